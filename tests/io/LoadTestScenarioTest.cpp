// The seed-load-test scenario: scenarios/seed-load-test.yaml maps onto bags::LoadTestOptions in
// SI, and bad input (missing or misspelt keys, wrong units, negative masses, impossible
// geometry) is an InputError at the right line and key.
#include <gtest/gtest.h>
#include "InputErrorTestUtil.h"

#include <io/LoadTestScenario.h>

#include <cmath>
#include <functional>
#include <string>

using io::InputError;
using io::ScenarioFile;

namespace {

using io::test::expectInputError;

// A valid scenario; tests edit one line of it. Lines counted from 1.
const std::string kBase =
    "kind: seed-load-test\n"                 // 1
    "airbag:\n"                              // 2
    "  long_side: 350 mm\n"                  // 3
    "  short_side: 200 mm\n"                 // 4
    "  width: 100 mm\n"                      // 5
    "  height: 150 mm\n"                     // 6
    "membrane:\n"                            // 7
    "  model: yeoh\n"                        // 8
    "  C10: 31.587917 MPa\n"                 // 9
    "  C20: -0.76582566 MPa\n"               // 10
    "  C30: -3.06587618 MPa\n"               // 11
    "  thickness: 0.2 mm\n"                  // 12
    "test:\n"                                // 13
    "  gas_masses: [3.5 g, 2.5 g, 1.5 g]\n"  // 14
    "  polynomial_order: 2\n";               // 15

std::string replaceLine(const std::string& text, int line, const std::string& with) {
    size_t begin = 0;
    for (int i = 1; i < line; ++i) begin = text.find('\n', begin) + 1;
    const size_t end = text.find('\n', begin);
    return text.substr(0, begin) + with + text.substr(end);
}

InputError errorFor(const std::string& text) {
    return expectInputError(
        [&] { io::readLoadTestScenario(ScenarioFile::parse(text, "bad.yaml")); });
}

}  // namespace

TEST(LoadTestScenario, SeedScenarioMapsToOptionsInSi) {
    const ScenarioFile f =
        ScenarioFile::load(std::string(BAGSIM_SOURCE_DIR) + "/scenarios/seed-load-test.yaml");
    EXPECT_EQ(io::readScenarioKind(f), "seed-load-test");
    const io::LoadTestScenario sc = io::readLoadTestScenario(f);
    const bags::LoadTestOptions& o = sc.options;
    EXPECT_EQ(sc.name, "seed-load-test");
    // Reference: the seed's values (issue 2) in SI; conversions are exact up to round-off.
    const double tol = 1e-12;
    EXPECT_NEAR(o.geometry.longSide, 0.350, tol);
    EXPECT_NEAR(o.geometry.shortSide, 0.200, tol);
    EXPECT_NEAR(o.geometry.width, 0.100, tol);
    EXPECT_NEAR(o.geometry.height, 0.150, tol);
    EXPECT_GT(o.geometry.meshSize, 0.0);
    EXPECT_TRUE(o.geometry.diaphragm);
    ASSERT_TRUE(o.material);
    EXPECT_EQ(o.material->getName(), "yeoh");
    // Yeoh small-strain shear modulus is 2 C10 (W = C10 (I1 - 3) + ...): 63.175834 MPa.
    EXPECT_NEAR(o.material->getInitialShearModulus(), 2.0 * 31.587917e6, 1.0);
    EXPECT_NEAR(o.thickness, 0.2e-3, tol);
    EXPECT_NEAR(o.density, 1150.0, tol);
    EXPECT_NEAR(o.wrinklingResidual, 1e-3, tol);
    EXPECT_NEAR(o.gas.molarMass, 0.029, tol);
    EXPECT_NEAR(o.gas.temperature, 296.15, 1e-9);
    EXPECT_NEAR(o.gas.ambientPressure, 1e5, 1e-6);
    EXPECT_EQ(o.gas.process, bags::GasOptions::Process::Isothermal);
    ASSERT_EQ(o.gasMasses.size(), 11u);  // 3.5 g to 1.0 g in 0.25 g steps
    for (size_t i = 0; i < 11; ++i) EXPECT_NEAR(o.gasMasses[i], 3.5e-3 - 0.25e-3 * i, 1e-15);
    EXPECT_NEAR(o.blockSize, 0.050, tol);
    EXPECT_NEAR(o.loadingRate, 10e-3 / 60.0, 1e-15);
    EXPECT_NEAR(o.peakForce, 50.0, tol);
    EXPECT_TRUE(o.unload);
    EXPECT_NEAR(o.stiffnessFrom, 10.0, tol);
    EXPECT_NEAR(o.stiffnessTo, 35.0, tol);
    EXPECT_EQ(o.polynomialOrder, 5);
    EXPECT_NEAR(o.blockContact.pressurePenalty, 1e8, 1e-2);
    EXPECT_NEAR(o.floorContact.pressurePenalty, 1e8, 1e-2);
    EXPECT_TRUE(o.selfContact);
    EXPECT_EQ(sc.output.frameEvery, 5);
    EXPECT_NO_THROW(o.validate());
}

TEST(LoadTestScenario, MeshSizeCanBeOverridden) {
    ScenarioFile f =
        ScenarioFile::load(std::string(BAGSIM_SOURCE_DIR) + "/scenarios/seed-load-test.yaml");
    f.applyOverride("airbag.mesh_size=5 mm");
    EXPECT_NEAR(io::readLoadTestScenario(f).options.geometry.meshSize, 5e-3, 1e-15);
}

TEST(LoadTestScenario, MeshPatternKeyChoosesTheTriangulation) {
    using bags::MeshPattern;
    const auto patternOf = [](const std::string& text) {
        return io::readLoadTestScenario(ScenarioFile::parse(text, "m.yaml"))
            .options.geometry.pattern;
    };
    EXPECT_EQ(patternOf(kBase), MeshPattern::Legacy);  // unstated: the mesh of before
    // The seed's scenario states the crossed pattern.
    EXPECT_EQ(io::readLoadTestScenario(ScenarioFile::load(std::string(BAGSIM_SOURCE_DIR) +
                                                          "/scenarios/seed-load-test.yaml"))
                  .options.geometry.pattern,
              MeshPattern::Crossed);
    EXPECT_EQ(patternOf(replaceLine(kBase, 6, "  height: 150 mm\n  mesh_pattern: legacy")),
              MeshPattern::Legacy);
    EXPECT_EQ(patternOf(replaceLine(kBase, 6, "  height: 150 mm\n  mesh_pattern: mirrored")),
              MeshPattern::Mirrored);
    EXPECT_EQ(patternOf(replaceLine(kBase, 6, "  height: 150 mm\n  mesh_pattern: crossed")),
              MeshPattern::Crossed);
    const InputError e =
        errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  mesh_pattern: diagonal"));
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "airbag.mesh_pattern");
    for (const char* valid : {"legacy", "mirrored", "crossed"})
        EXPECT_NE(std::string(e.what()).find(valid), std::string::npos) << e.what();
}

TEST(LoadTestScenario, BaseScenarioIsValidAndUsesDefaults) {
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(kBase, "b.yaml"));
    const bags::LoadTestOptions defaults;
    EXPECT_EQ(sc.name, "b");
    EXPECT_EQ(sc.options.gasMasses.size(), 3u);
    EXPECT_EQ(sc.options.peakForce, defaults.peakForce);
    EXPECT_EQ(sc.options.geometry.meshSize, defaults.geometry.meshSize);
    EXPECT_EQ(sc.options.gas.temperature, defaults.gas.temperature);
    EXPECT_EQ(sc.options.blockContact.friction, defaults.blockContact.friction);
    EXPECT_EQ(sc.options.stabilization, defaults.stabilization);
    const io::LoadTestScenario sc2 = io::readLoadTestScenario(ScenarioFile::parse(
        kBase + "solver: {stabilization: 2 kPa/m, max_iterations: 30}\n", "s.yaml"));
    EXPECT_DOUBLE_EQ(sc2.options.stabilization, 2000.0);  // 2 kPa/m = 2000 Pa/m
    EXPECT_EQ(sc2.options.solver.maxIterations, 30);
    EXPECT_EQ(sc.options.residualTolerance, defaults.residualTolerance);
    const io::LoadTestScenario sc3 = io::readLoadTestScenario(
        ScenarioFile::parse(kBase + "solver: {residual_tolerance: 0}\n", "r.yaml"));
    EXPECT_EQ(sc3.options.residualTolerance, 0.0);
    // A tolerance of more than 5 % of the peak force is refused, naming the key.
    const InputError e = errorFor(kBase + "solver:\n  residual_tolerance: 0.2\n");
    EXPECT_EQ(e.getKey(), "solver.residual_tolerance");
    EXPECT_NE(std::string(e.what()).find("fraction of the peak force"), std::string::npos)
        << e.what();
    // The damper: off by default, a stiffness per area with its unit, never negative.
    EXPECT_EQ(sc.options.damping, 0.0);
    const io::LoadTestScenario sc4 = io::readLoadTestScenario(
        ScenarioFile::parse(kBase + "solver: {damping: 100 kPa/m}\n", "d.yaml"));
    EXPECT_DOUBLE_EQ(sc4.options.damping, 1e5);
    const InputError ed = errorFor(kBase + "solver:\n  damping: -1 Pa/m\n");
    EXPECT_EQ(ed.getKey(), "solver.damping");
    EXPECT_NE(std::string(ed.what()).find("Pa/m"), std::string::npos) << ed.what();
}

TEST(LoadTestScenario, OrificeAndExtrapolationKeys) {
    // connection: orifice with its opening; the yeoh is continued beyond its stable range
    // unless extrapolation: polynomial.
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 6,
                    "  height: 150 mm\n  connection: orifice\n  orifice_diameter: 3 mm\n"
                    "  discharge_coefficient: 0.7"),
        "o.yaml"));
    EXPECT_EQ(sc.options.connection, bags::LoadTestOptions::Connection::Orifice);
    EXPECT_NEAR(sc.options.orifice.diameter, 3e-3, 1e-15);
    EXPECT_NEAR(sc.options.orifice.dischargeCoefficient, 0.7, 1e-15);
    EXPECT_EQ(io::readLoadTestScenario(ScenarioFile::parse(kBase, "b.yaml")).options.connection,
              bags::LoadTestOptions::Connection::Open);
    // Equibiaxial stretch 2: the polynomial's energy is negative (C30 < 0), the continued
    // one positive.
    bags::Mat2 C = bags::Mat2::Identity() * 4.0;
    const auto linear = io::readLoadTestScenario(ScenarioFile::parse(kBase, "b.yaml"));
    EXPECT_GT(linear.options.material->calcEnergy(C, nullptr, nullptr), 0.0);
    const auto poly = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 12, "  thickness: 0.2 mm\n  extrapolation: polynomial"), "p.yaml"));
    EXPECT_LT(poly.options.material->calcEnergy(C, nullptr, nullptr), 0.0);

    // Errors name the line, the key and what is valid.
    const InputError e =
        errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  orifice_diameter: 3 mm"));
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "airbag.orifice_diameter");
    EXPECT_NE(std::string(e.what()).find("only applies to connection: orifice"), std::string::npos)
        << e.what();
    const InputError e2 = errorFor(
        replaceLine(kBase, 6, "  height: 150 mm\n  diaphragm: false\n  connection: orifice"));
    EXPECT_EQ(e2.getKey(), "airbag.connection");
    EXPECT_NE(std::string(e2.what()).find("diaphragm: true"), std::string::npos) << e2.what();
    const InputError e3 = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  connection: valve"));
    EXPECT_EQ(e3.getLine(), 7);
    EXPECT_NE(std::string(e3.what()).find("open"), std::string::npos) << e3.what();
    const InputError e4 = errorFor(
        replaceLine(kBase, 6, "  height: 150 mm\n  connection: orifice\n  orifice_diameter: 0 mm"));
    EXPECT_EQ(e4.getKey(), "airbag.orifice_diameter");
    const InputError e5 = errorFor(
        replaceLine(replaceLine(kBase, 8, "  model: neo-hookean"), 10, "  extrapolation: linear"));
    EXPECT_EQ(e5.getKey(), "membrane.extrapolation");
}

TEST(LoadTestScenario, MisspeltKeyIsNamedWithSuggestion) {
    const InputError e = errorFor(replaceLine(kBase, 6, "  hieght: 150 mm"));
    EXPECT_EQ(e.getLine(), 6);
    EXPECT_EQ(e.getKey(), "airbag.hieght");
    EXPECT_NE(std::string(e.what()).find("did you mean 'height'?"), std::string::npos) << e.what();
    const InputError e2 = errorFor(replaceLine(kBase, 9, "  c10: 31.587917 MPa"));
    EXPECT_EQ(e2.getLine(), 9);
    EXPECT_NE(std::string(e2.what()).find("did you mean 'C10'?"), std::string::npos) << e2.what();
    const InputError e3 = errorFor(replaceLine(kBase, 13, "tset:"));
    EXPECT_EQ(e3.getLine(), 13);
    EXPECT_NE(std::string(e3.what()).find("did you mean 'test'?"), std::string::npos) << e3.what();
}

TEST(LoadTestScenario, MissingKeysListWhatIsRequired) {
    const InputError e = errorFor(replaceLine(kBase, 5, "  # no width"));
    EXPECT_EQ(e.getLine(), 2);
    EXPECT_NE(std::string(e.what()).find("missing required key 'width' in section 'airbag'"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("long_side, short_side, width, height"),
              std::string::npos);
    const InputError e2 = errorFor(replaceLine(kBase, 11, "  # no C30"));
    EXPECT_NE(std::string(e2.what()).find("'C30'"), std::string::npos) << e2.what();
    EXPECT_NE(std::string(e2.what()).find("the yeoh model takes C10, C20, C30"), std::string::npos);
    const InputError e3 = errorFor(replaceLine(kBase, 1, "# no kind"));
    EXPECT_NE(std::string(e3.what()).find("missing required key 'kind'"), std::string::npos)
        << e3.what();
}

TEST(LoadTestScenario, WrongUnitAndNegativeMassAreLocated) {
    const InputError e = errorFor(replaceLine(kBase, 14, "  gas_masses: [3.5 g, 2.5 kg/m]"));
    EXPECT_EQ(e.getLine(), 14);
    EXPECT_EQ(e.getKey(), "test.gas_masses[1]");
    EXPECT_NE(std::string(e.what()).find("is not a mass"), std::string::npos) << e.what();
    const InputError e2 = errorFor(replaceLine(kBase, 14, "  gas_masses: [3.5 g, -1 g, 2 g]"));
    EXPECT_EQ(e2.getLine(), 14);
    EXPECT_NE(std::string(e2.what()).find("greater than zero"), std::string::npos) << e2.what();
    const InputError e3 = errorFor(replaceLine(kBase, 12, "  thickness: 0.2"));
    EXPECT_EQ(e3.getLine(), 12);
    EXPECT_NE(std::string(e3.what()).find("has no unit"), std::string::npos) << e3.what();
}

TEST(LoadTestScenario, GasMassRangeExpandsAndMustDivide) {
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 14, "  gas_masses: {from: 1.0 g, to: 2.0 g, step: 0.5 g}"), "r.yaml"));
    ASSERT_EQ(sc.options.gasMasses.size(), 3u);
    EXPECT_NEAR(sc.options.gasMasses[2], 2e-3, 1e-15);
    const InputError e =
        errorFor(replaceLine(kBase, 14, "  gas_masses: {from: 3.5 g, to: 1.0 g, step: 0.3 g}"));
    EXPECT_EQ(e.getKey(), "test.gas_masses.step");
    EXPECT_NE(std::string(e.what()).find("does not divide"), std::string::npos) << e.what();
}

TEST(LoadTestScenario, ImpossibleGeometryIsRejected) {
    // Steep side shorter than the height: no triangle.
    const InputError e = errorFor(replaceLine(kBase, 4, "  short_side: 100 mm"));
    EXPECT_EQ(e.getLine(), 6);
    EXPECT_EQ(e.getKey(), "airbag.height");
    EXPECT_NE(std::string(e.what()).find("must be less than short_side (100 mm)"),
              std::string::npos)
        << e.what();
    // Apex beyond the base: caught by DoubleWedgeParams::validate(), mapped to long_side.
    const InputError e2 = errorFor(replaceLine(kBase, 3, "  long_side: 120 mm"));
    EXPECT_EQ(e2.getKey(), "airbag.long_side") << e2.what();
    EXPECT_EQ(e2.getLine(), 3);
    // Mesh too coarse for the width.
    std::string t = kBase;
    t.insert(t.find("membrane:"), "  mesh_size: 80 mm\n");
    const InputError e3 = errorFor(t);
    EXPECT_EQ(e3.getKey(), "airbag.mesh_size");
    EXPECT_EQ(e3.getLine(), 7);
}

TEST(LoadTestScenario, MaterialModelsAndTheirConstants) {
    const std::string neo = replaceLine(
        replaceLine(replaceLine(replaceLine(kBase, 8, "  model: neo-hookean"), 10, "  #"), 11,
                    "  #"),
        9, "  C10: 1 MPa");
    EXPECT_EQ(
        io::readLoadTestScenario(ScenarioFile::parse(neo, "n.yaml")).options.material->getName(),
        "neo-hookean");
    // A constant of another model.
    const InputError e = errorFor(replaceLine(kBase, 8, "  model: neo-hookean"));
    EXPECT_EQ(e.getLine(), 10);
    EXPECT_NE(std::string(e.what()).find("is not a constant of this material"), std::string::npos);
    const InputError e2 = errorFor(replaceLine(kBase, 8, "  model: yeo"));
    EXPECT_NE(std::string(e2.what()).find("did you mean 'yeoh'?"), std::string::npos) << e2.what();
    // Ogden with lists.
    std::string ogden = replaceLine(kBase, 8, "  model: ogden");
    ogden = replaceLine(ogden, 9, "  mu: [1 MPa, 0.1 MPa]");
    ogden = replaceLine(ogden, 10, "  alpha: [2, -2]");
    ogden = replaceLine(ogden, 11, "  #");
    EXPECT_EQ(
        io::readLoadTestScenario(ScenarioFile::parse(ogden, "o.yaml")).options.material->getName(),
        "ogden");
    const InputError e3 = errorFor(replaceLine(ogden, 10, "  alpha: [2]"));
    EXPECT_EQ(e3.getKey(), "membrane.alpha");
}

TEST(LoadTestScenario, RangesAreCheckedWithTheKeysLine) {
    EXPECT_EQ(errorFor(replaceLine(kBase, 15, "  polynomial_order: 3")).getKey(),
              "test.polynomial_order");  // 3 masses allow at most order 2
    const InputError e = errorFor(kBase + "gas: {temperature: -300 degC}\n");
    EXPECT_EQ(e.getKey(), "gas.temperature");
    EXPECT_EQ(e.getLine(), 16);
    // A gas a film bag cannot hold (it ran to 'complete' at 5000 K): refused, with the range.
    for (const char* t : {"5000 K", "150 degC", "-60 degC"}) {
        const InputError hot = errorFor(kBase + "gas: {temperature: " + t + "}\n");
        EXPECT_EQ(hot.getKey(), "gas.temperature") << t;
        EXPECT_NE(std::string(hot.what()).find("must be in [223.15 K, 373.15 K]"),
                  std::string::npos)
            << hot.what();
    }
    for (const char* t : {"23 degC", "40 degC", "0 degC"})
        EXPECT_NO_THROW(io::readLoadTestScenario(
            ScenarioFile::parse(kBase + "gas: {temperature: " + t + "}\n", "t.yaml")))
            << t;
    // More gas than the bag can hold (ten atmospheres in its unstretched 2.625 L: 34 g).
    const std::string masses = "gas_masses: [";
    std::string heavy = kBase;
    heavy.replace(heavy.find(masses), masses.size(), masses + "80 g, ");
    const InputError gas = errorFor(heavy);
    EXPECT_EQ(gas.getKey(), "test.gas_masses");
    EXPECT_NE(std::string(gas.what()).find("80 g is more gas than this bag can hold"),
              std::string::npos)
        << gas.what();
    EXPECT_NE(std::string(gas.what()).find("valid: at most 34"), std::string::npos) << gas.what();
    const InputError e2 = errorFor(kBase + "contact: {block: {friction: -0.1}}\n");
    EXPECT_EQ(e2.getKey(), "contact.block.friction");
    const InputError e3 = errorFor(kBase + "  stiffness_range: [10 N, 60 N]\n");
    EXPECT_EQ(e3.getKey(), "test.stiffness_range");
    EXPECT_EQ(e3.getLine(), 16);
    const InputError e4 = errorFor(kBase + "  block: 400 mm\n");  // LoadTestOptions::validate
    EXPECT_EQ(e4.getKey(), "test.block") << e4.what();
}

TEST(LoadTestScenario, ContactSubsectionsOverrideSharedKeys) {
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        kBase +
            "contact: {penalty: 2e7 Pa/m, friction: 0.3, floor: {friction: 0.5}, self: false}\n",
        "c.yaml"));
    EXPECT_DOUBLE_EQ(sc.options.blockContact.pressurePenalty, 2e7);
    EXPECT_DOUBLE_EQ(sc.options.floorContact.pressurePenalty, 2e7);
    EXPECT_DOUBLE_EQ(sc.options.blockContact.friction, 0.3);
    EXPECT_DOUBLE_EQ(sc.options.floorContact.friction, 0.5);
    EXPECT_FALSE(sc.options.selfContact);
}

// A layer on the block (soft tissue, a pad): both keys, in range, on the block only.
TEST(LoadTestScenario, TheBlockTakesATissueLayerWithItsThicknessAndModulus) {
    const io::LoadTestScenario none =
        io::readLoadTestScenario(ScenarioFile::parse(kBase, "c.yaml"));
    EXPECT_FALSE(none.options.blockContact.hasTissue());
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        kBase + "contact: {block: {tissue: {thickness: 15 mm, modulus: 50 kPa}}}\n", "c.yaml"));
    EXPECT_DOUBLE_EQ(sc.options.blockContact.tissueThickness, 0.015);
    EXPECT_DOUBLE_EQ(sc.options.blockContact.tissueModulus, 5e4);
    EXPECT_FALSE(sc.options.floorContact.hasTissue());
    const InputError e = errorFor(kBase + "contact: {block: {tissue: {thickness: 15 mm}}}\n");
    EXPECT_EQ(e.getKey(), "contact.block.tissue") << e.what();
    EXPECT_NE(std::string(e.what()).find("modulus"), std::string::npos) << e.what();
    EXPECT_EQ(e.getLine(), 16);
    const InputError e2 =
        errorFor(kBase + "contact: {block: {tissue: {thickness: 0.3 m, modulus: 50 kPa}}}\n");
    EXPECT_EQ(e2.getKey(), "contact.block.tissue.thickness");
    EXPECT_NE(std::string(e2.what()).find("5-40 mm"), std::string::npos) << e2.what();
    const InputError e3 =
        errorFor(kBase + "contact: {block: {tissue: {thickness: 15 mm, modulus: -5 kPa}}}\n");
    EXPECT_EQ(e3.getKey(), "contact.block.tissue.modulus");
    // The bed board is bare: a layer there is an unknown key.
    const InputError e4 =
        errorFor(kBase + "contact: {floor: {tissue: {thickness: 15 mm, modulus: 50 kPa}}}\n");
    EXPECT_EQ(e4.getKey(), "contact.floor.tissue") << e4.what();
}

TEST(LoadTestScenario, FitMaterialFormPointsToTheMembraneSection) {
    const InputError e = errorFor(kBase + "material: {model: yeoh, C10: \"31.6 MPa\"}\n");
    EXPECT_EQ(e.getLine(), 16);
    EXPECT_NE(std::string(e.what()).find("go in the membrane section"), std::string::npos);
}

TEST(LoadTestScenario, UnknownKindListsValidKinds) {
    const InputError e = expectInputError(
        [] { io::readScenarioKind(ScenarioFile::parse("kind: seed-load-tset\n", "k.yaml")); });
    EXPECT_EQ(e.getLine(), 1);
    EXPECT_NE(std::string(e.what()).find("did you mean 'seed-load-test'?"), std::string::npos);
}

// The seed's bag read from its words (docs/geometry.md): the default scenario sizes its bag to
// a fill mass of 2.8 g; the literal reading keeps today's sizes unscaled; the band's ends
// differ from the default in the fill mass only.
TEST(LoadTestScenario, SeedReadingsDifferOnlyInTheFillMass) {
    auto read = [](const std::string& file) {
        return io::readLoadTestScenario(
            ScenarioFile::load(std::string(BAGSIM_SOURCE_DIR) + "/scenarios/" + file));
    };
    const io::LoadTestScenario literal = read("seed-load-test-literal.yaml");
    const io::LoadTestScenario words = read("seed-load-test.yaml");
    EXPECT_EQ(literal.name, "seed-load-test-literal");
    EXPECT_EQ(literal.fillMass, 0.0);  // no scaling: the sizes as written
    EXPECT_NEAR(words.fillMass, 2.8e-3, 1e-15);
    EXPECT_EQ(words.fillScaling, bags::FillScaling::Profile);
    auto expectSameRig = [](const io::LoadTestScenario& a, const io::LoadTestScenario& b) {
        const bags::LoadTestOptions &x = a.options, &y = b.options;
        EXPECT_EQ(x.geometry.longSide, y.geometry.longSide);
        EXPECT_EQ(x.geometry.shortSide, y.geometry.shortSide);
        EXPECT_EQ(x.geometry.width, y.geometry.width);
        EXPECT_EQ(x.geometry.height, y.geometry.height);
        EXPECT_EQ(x.geometry.meshSize, y.geometry.meshSize);
        EXPECT_EQ(x.geometry.pattern, y.geometry.pattern);
        EXPECT_EQ(x.geometry.diaphragm, y.geometry.diaphragm);
        EXPECT_EQ(x.geometry.bondBase, y.geometry.bondBase);
        EXPECT_EQ(x.material->getName(), y.material->getName());
        EXPECT_EQ(x.material->getInitialShearModulus(), y.material->getInitialShearModulus());
        EXPECT_EQ(x.thickness, y.thickness);
        EXPECT_EQ(x.density, y.density);
        EXPECT_EQ(x.wrinklingResidual, y.wrinklingResidual);
        EXPECT_EQ(x.gas.molarMass, y.gas.molarMass);
        EXPECT_EQ(x.gas.temperature, y.gas.temperature);
        EXPECT_EQ(x.gas.ambientPressure, y.gas.ambientPressure);
        EXPECT_EQ(x.gas.process, y.gas.process);
        EXPECT_EQ(x.connection, y.connection);
        EXPECT_EQ(x.gasMasses, y.gasMasses);
        EXPECT_EQ(x.blockSize, y.blockSize);
        EXPECT_EQ(x.loadingRate, y.loadingRate);
        EXPECT_EQ(x.peakForce, y.peakForce);
        EXPECT_EQ(x.unload, y.unload);
        EXPECT_EQ(x.stiffnessFrom, y.stiffnessFrom);
        EXPECT_EQ(x.stiffnessTo, y.stiffnessTo);
        EXPECT_EQ(x.polynomialOrder, y.polynomialOrder);
        EXPECT_EQ(x.blockContact.pressurePenalty, y.blockContact.pressurePenalty);
        EXPECT_EQ(x.blockContact.friction, y.blockContact.friction);
        EXPECT_EQ(x.selfContact, y.selfContact);
        EXPECT_EQ(a.output.frameEvery, b.output.frameEvery);
    };
    expectSameRig(literal, words);
    for (const char* end : {"2.7", "2.9"}) {
        const io::LoadTestScenario band =
            read(std::string("seed-load-test-fill-") + end + "g.yaml");
        EXPECT_NEAR(band.fillMass, std::stod(end) * 1e-3, 1e-15) << end;
        EXPECT_EQ(band.fillScaling, bags::FillScaling::Profile);
        expectSameRig(band, words);
    }
    // The band's ends also as an override of the default scenario.
    ScenarioFile f =
        ScenarioFile::load(std::string(BAGSIM_SOURCE_DIR) + "/scenarios/seed-load-test.yaml");
    f.applyOverride("airbag.fill_mass=2.9 g");
    EXPECT_NEAR(io::readLoadTestScenario(f).fillMass, 2.9e-3, 1e-15);
}

TEST(LoadTestScenario, FillMassKeys) {
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: 2.8 g\n  fill_scaling: uniform"),
        "f.yaml"));
    EXPECT_NEAR(sc.fillMass, 2.8e-3, 1e-15);
    EXPECT_EQ(sc.fillScaling, bags::FillScaling::Uniform);
    EXPECT_NEAR(sc.options.geometry.longSide, 0.350, 1e-15);  // scaled only before the run
    const io::LoadTestScenario sc2 = io::readLoadTestScenario(
        ScenarioFile::parse(replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: 3 g"), "f.yaml"));
    EXPECT_EQ(sc2.fillScaling, bags::FillScaling::Profile);  // the default

    const InputError e = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: -2.8 g"));
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "airbag.fill_mass");
    EXPECT_NE(std::string(e.what()).find("must be > 0 g"), std::string::npos) << e.what();
    const InputError e2 = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: 2.8 mm"));
    EXPECT_EQ(e2.getKey(), "airbag.fill_mass");
    // A fill mass that would shrink or blow up the bag beyond 0.5-1.5 times its sizes.
    const InputError e3 = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: 0.5 g"));
    EXPECT_EQ(e3.getKey(), "airbag.fill_mass");
    EXPECT_NE(std::string(e3.what()).find("would scale the profile by about 0.37"),
              std::string::npos)
        << e3.what();
    const InputError e4 = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: 20 g"));
    EXPECT_EQ(e4.getKey(), "airbag.fill_mass");
    const InputError e5 = errorFor(
        replaceLine(kBase, 6, "  height: 150 mm\n  fill_mass: 2.8 g\n  fill_scaling: sideways"));
    EXPECT_EQ(e5.getLine(), 8);
    EXPECT_EQ(e5.getKey(), "airbag.fill_scaling");
    EXPECT_NE(std::string(e5.what()).find("profile"), std::string::npos) << e5.what();
    const InputError e6 =
        errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  fill_scaling: profile"));
    EXPECT_EQ(e6.getKey(), "airbag.fill_scaling");
    EXPECT_NE(std::string(e6.what()).find("only applies with fill_mass"), std::string::npos)
        << e6.what();
    // The mesh must still fit the scaled bag: 45 mm is more than half the 82 mm height that
    // 2.0 g gives with the height scaling.
    const InputError e7 = errorFor(replaceLine(
        kBase, 6,
        "  height: 150 mm\n  mesh_size: 45 mm\n  fill_mass: 2.0 g\n  fill_scaling: height"));
    EXPECT_EQ(e7.getKey(), "airbag.mesh_size");
}

// airbag.volume_change: the bag's volume and fill mass relative to its sizes' reading, a
// similar bag (docs/diagnosis.md#bag-volume); applied after a fill mass's sizing
// (io::applyBagSizing), the sizes as written kept until then; out of range or scaling the mesh
// beyond 50 mm, a located error naming the valid range.
TEST(LoadTestScenario, VolumeChangeKey) {
    io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 6, "  height: 150 mm\n  volume_change: -0.1"), "v.yaml"));
    EXPECT_DOUBLE_EQ(sc.volumeChange, -0.1);
    EXPECT_EQ(sc.options.bagScale, 1.0);  // applied before the run
    const bags::DoubleWedgeParams g0 = sc.options.geometry;
    io::applyBagSizing(sc);
    EXPECT_EQ(sc.volumeChange, 0.0);
    EXPECT_NEAR(std::pow(sc.options.bagScale, 3), 0.9, 1e-14);
    EXPECT_EQ(sc.options.geometry.longSide, g0.longSide);
    EXPECT_NEAR(sc.options.getBagGeometry().calcFlatVolume(), 0.9 * g0.calcFlatVolume(), 1e-15);
    io::applyBagSizing(sc);  // a second call changes nothing
    EXPECT_NEAR(std::pow(sc.options.bagScale, 3), 0.9, 1e-14);
    // Absent: 0, the bag as written.
    io::LoadTestScenario none = io::readLoadTestScenario(ScenarioFile::parse(kBase, "n.yaml"));
    EXPECT_EQ(none.volumeChange, 0.0);
    io::applyBagSizing(none);
    EXPECT_EQ(none.options.bagScale, 1.0);

    const InputError e = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  volume_change: 0.3"));
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "airbag.volume_change");
    EXPECT_NE(std::string(e.what()).find("must be in [-0.25, 0.25]"), std::string::npos)
        << e.what();
    const InputError e2 = errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  volume_change: 5 %"));
    EXPECT_EQ(e2.getKey(), "airbag.volume_change");
    const InputError e3 = errorFor(
        replaceLine(kBase, 6, "  height: 150 mm\n  mesh_size: 49 mm\n  volume_change: 0.2"));
    EXPECT_EQ(e3.getLine(), 8);
    EXPECT_EQ(e3.getKey(), "airbag.volume_change");
    EXPECT_NE(std::string(e3.what()).find("beyond 50 mm"), std::string::npos) << e3.what();
}

TEST(LoadTestScenario, BendingStiffnessKey) {
    // Absent or `plate`: the film's plate value E t^3 / (12 (1 - nu^2)) with E = 6 C10 and
    // nu = 0.5: 6 * 31.587917 MPa * (0.2 mm)^3 / 9 = 1.68469e-4 N m; a moment in N m or N mm;
    // 0 switches bending off.
    const double plate = 6 * 31.587917e6 * 8e-12 / 9;
    const auto base = io::readLoadTestScenario(ScenarioFile::parse(kBase, "b.yaml"));
    EXPECT_NEAR(base.options.bendingStiffness, plate, 1e-12 * plate);
    auto read = [](const std::string& value) {
        return io::readLoadTestScenario(ScenarioFile::parse(replaceLine(kBase, 12,
                                                                        "  thickness: 0.2 mm\n"
                                                                        "  bending_stiffness: " +
                                                                            value),
                                                            "k.yaml"))
            .options.bendingStiffness;
    };
    EXPECT_NEAR(read("plate"), plate, 1e-12 * plate);
    EXPECT_EQ(read("0"), 0.0);
    EXPECT_NEAR(read("1.7e-4 N m"), 1.7e-4, 1e-18);
    EXPECT_NEAR(read("0.05 N mm"), 5e-5, 1e-18);
    // A wrong unit, a bare number and a negative value are errors at the key's line.
    for (const char* bad : {"0.17 N/mm", "1.7e-4", "-1e-4 N m", "2 N m", "stiff"}) {
        const InputError e = errorFor(replaceLine(
            kBase, 12, std::string("  thickness: 0.2 mm\n  bending_stiffness: ") + bad));
        EXPECT_EQ(e.getLine(), 13) << bad;
        EXPECT_EQ(e.getKey(), "membrane.bending_stiffness") << bad;
    }
    const InputError e =
        errorFor(replaceLine(kBase, 12, "  thickness: 0.2 mm\n  bending_stiffness: 0.17 N/mm"));
    EXPECT_NE(std::string(e.what()).find("is not a moment"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("N m"), std::string::npos) << e.what();
}

TEST(LoadTestScenario, ImperfectionAndEnsembleKeys) {
    const auto read = [](const std::string& text) {
        return io::readLoadTestScenario(ScenarioFile::parse(text, "i.yaml")).options;
    };
    const std::string withImperfection = replaceLine(
        kBase, 6, "  height: 150 mm\n  imperfection:\n    amplitude: 0.5 mm\n    seed: 4");
    const bags::LoadTestOptions o = read(withImperfection);
    EXPECT_DOUBLE_EQ(o.imperfection.amplitude, 0.5e-3);
    EXPECT_EQ(o.imperfection.seed, 4u);
    EXPECT_EQ(read(kBase).imperfection.amplitude, 0.0);  // absent: the perfect bag
    EXPECT_EQ(read(kBase).ensemble, 1);
    // The ensemble: test.ensemble bags, each with its own seed.
    const bags::LoadTestOptions e = read(withImperfection + "  ensemble: 5\n");
    EXPECT_EQ(e.ensemble, 5);
    // Errors at the key's line: a missing unit, too large, a negative seed, an unknown key,
    // an ensemble out of range or without an imperfection.
    struct Bad {
        std::string text;
        int line;
        std::string key;
    };
    const std::vector<Bad> bad = {
        {replaceLine(kBase, 6, "  height: 150 mm\n  imperfection:\n    amplitude: 0.5"), 8,
         "airbag.imperfection.amplitude"},
        {replaceLine(kBase, 6, "  height: 150 mm\n  imperfection:\n    amplitude: 20 mm"), 8,
         "airbag.imperfection.amplitude"},
        {replaceLine(kBase, 6,
                     "  height: 150 mm\n  imperfection:\n    amplitude: 1 mm\n    seed: -2"),
         9, "airbag.imperfection.seed"},
        {replaceLine(kBase, 6, "  height: 150 mm\n  imperfection:\n    amplitud: 1 mm"), 8,
         "airbag.imperfection.amplitud"},
        {withImperfection + "  ensemble: 100\n", 19, "test.ensemble"},
        {kBase + "  ensemble: 3\n", 16, "test.ensemble"},
    };
    for (const Bad& b : bad) {
        const InputError err = errorFor(b.text);
        EXPECT_EQ(err.getLine(), b.line) << b.text << "\n" << err.what();
        EXPECT_EQ(err.getKey(), b.key) << err.what();
    }
}

TEST(LoadTestScenario, NeighboursKeysAndTheirErrors) {
    // The pressed bag among neighbours (docs/array-coupling.md): layout, gap, gas mass.
    const io::LoadTestScenario sc = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 6,
                    "  height: 150 mm\n  neighbours: {layout: row3, gap: 4 mm, gas_mass: 3.0 g}"),
        "n.yaml"));
    EXPECT_EQ(sc.options.neighbours, bags::LoadTestOptions::Neighbours::Row3);
    EXPECT_NEAR(sc.options.neighbourGap, 4e-3, 1e-15);
    EXPECT_NEAR(sc.options.neighbourGasMass, 3e-3, 1e-15);
    const auto base = io::readLoadTestScenario(ScenarioFile::parse(kBase, "b.yaml"));
    EXPECT_EQ(base.options.neighbours, bags::LoadTestOptions::Neighbours::None);
    EXPECT_EQ(base.options.neighbourGasMass, 0.0);  // the pressed bag's own at each curve
    EXPECT_FALSE(sc.options.neighbourSharedAir);    // each bag its own air by default
    const io::LoadTestScenario shared = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 6, "  height: 150 mm\n  neighbours: {layout: pair, shared_air: true}"),
        "s.yaml"));
    EXPECT_TRUE(shared.options.neighbourSharedAir);
    EXPECT_TRUE(bags::makeAirbagSpec(shared.options).sharedAir);
    EXPECT_FALSE(bags::makeAirbagSpec(sc.options).sharedAir);
    const InputError es = errorFor(replaceLine(
        kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: pair\n    shared_air: perhaps"));
    EXPECT_EQ(es.getKey(), "airbag.neighbours.shared_air");
    EXPECT_EQ(es.getLine(), 9);

    // Where in a 3 x 3 block the pressed bag stands.
    const io::LoadTestScenario corner = io::readLoadTestScenario(ScenarioFile::parse(
        replaceLine(kBase, 6,
                    "  height: 150 mm\n  neighbours: {layout: block3x3, pressed: [1, -1]}"),
        "c.yaml"));
    EXPECT_EQ(corner.options.neighbourPressed[0], 1);
    EXPECT_EQ(corner.options.neighbourPressed[1], -1);
    EXPECT_EQ(base.options.neighbourPressed[0], 0);
    const InputError ep = errorFor(replaceLine(
        kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: block3x3\n    pressed: [2, 0]"));
    EXPECT_EQ(ep.getKey(), "airbag.neighbours.pressed");
    EXPECT_EQ(ep.getLine(), 9);
    EXPECT_NE(std::string(ep.what()).find("-1, 0 or 1"), std::string::npos) << ep.what();
    const InputError ep2 = errorFor(replaceLine(
        kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: row3\n    pressed: [0, 1]"));
    EXPECT_NE(std::string(ep2.what()).find("block3x3"), std::string::npos) << ep2.what();

    // Errors name the line, the key and what is valid.
    const InputError e = errorFor(replaceLine(
        kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: pair\n    gap: 120 mm"));
    EXPECT_EQ(e.getLine(), 9);
    EXPECT_EQ(e.getKey(), "airbag.neighbours.gap");
    EXPECT_NE(std::string(e.what()).find("100 mm"), std::string::npos) << e.what();
    const InputError e2 =
        errorFor(replaceLine(kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: hexagon"));
    EXPECT_EQ(e2.getLine(), 8);
    EXPECT_NE(std::string(e2.what()).find("row3"), std::string::npos) << e2.what();
    const InputError e3 = errorFor(replaceLine(
        kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: pair\n    gas_mass: -1 g"));
    EXPECT_EQ(e3.getKey(), "airbag.neighbours.gas_mass");
    const InputError e4 = errorFor(replaceLine(
        kBase, 6, "  height: 150 mm\n  neighbours:\n    layout: pair\n    pitch: 110 mm"));
    EXPECT_EQ(e4.getLine(), 9);
    const InputError e5 =
        errorFor(replaceLine(kBase, 6,
                             "  height: 150 mm\n  diaphragm: true\n  connection: orifice\n"
                             "  neighbours: {layout: pair}"));
    EXPECT_EQ(e5.getKey(), "airbag.connection");
}

TEST(LoadTestScenario, DynamicSteppingKeysMapToTheDynamicTest) {
    const std::string text = kBase +
                             "solver:\n"                        // 16
                             "  stepping: dynamic\n"            // 17
                             "  dynamic:\n"                     // 18
                             "    block_speed: 10 mm/s\n"       // 19
                             "    mass_scale: 500\n"            // 20
                             "    damping: 30 1/s\n"            // 21
                             "    record_every: 0.5 mm\n"       // 22
                             "    ramp: 1 mm\n"                 // 23
                             "    kinetic_share_limit: 0.02\n"  // 24
                             "    max_halvings: 1\n";           // 25
    const bags::LoadTestOptions o =
        io::readLoadTestScenario(ScenarioFile::parse(text, "d.yaml")).options;
    EXPECT_EQ(o.stepping, bags::AirbagSpec::Stepping::Dynamic);
    EXPECT_DOUBLE_EQ(o.dynamic.blockSpeed, 0.01);
    EXPECT_DOUBLE_EQ(o.dynamic.massScale, 500.0);
    EXPECT_DOUBLE_EQ(o.dynamic.damping, 30.0);
    EXPECT_DOUBLE_EQ(o.dynamic.recordEvery, 0.5e-3);
    EXPECT_DOUBLE_EQ(o.dynamic.rampTravel, 1e-3);
    EXPECT_DOUBLE_EQ(o.dynamic.kineticShareLimit, 0.02);
    EXPECT_EQ(o.dynamic.maxHalvings, 1);
    // The bag's own options: the pace carried into the test's time (10 mm/min).
    const bags::DynamicOptions d = bags::calcLoadTestDynamics(o, 0.01);
    const double r = 0.01 / (10e-3 / 60.0);
    EXPECT_NEAR(d.massScale, 500.0 * r * r, 1e-9 * d.massScale);
    EXPECT_NEAR(d.damping, 30.0 / r, 1e-12);
    // The default stays quasi-static.
    EXPECT_EQ(io::readLoadTestScenario(ScenarioFile::parse(kBase, "q.yaml")).options.stepping,
              bags::AirbagSpec::Stepping::QuasiStatic);
}

TEST(LoadTestScenario, DynamicKeysAreCheckedAndLocated) {
    // Settings of the dynamic test without the dynamic stepping: refused where they stand.
    const InputError e = errorFor(kBase + "solver:\n  dynamic: {block_speed: 10 mm/s}\n");
    EXPECT_EQ(e.getLine(), 17);
    EXPECT_NE(std::string(e.what()).find("stepping: dynamic"), std::string::npos) << e.what();
    // An unknown stepping names the valid ones.
    const InputError e2 = errorFor(kBase + "solver:\n  stepping: explicit\n");
    EXPECT_EQ(e2.getLine(), 17);
    EXPECT_NE(std::string(e2.what()).find("quasi-static"), std::string::npos) << e2.what();
    // A damping is a rate: a unit of time alone is refused.
    const InputError e3 =
        errorFor(kBase + "solver:\n  stepping: dynamic\n  dynamic: {damping: 20 s}\n");
    EXPECT_EQ(e3.getKey(), "solver.dynamic.damping");
    EXPECT_NE(std::string(e3.what()).find("1/s"), std::string::npos) << e3.what();
    // A mass scale below 1 would make the film lighter than it is.
    const InputError e4 =
        errorFor(kBase + "solver:\n  stepping: dynamic\n  dynamic: {mass_scale: 0.5}\n");
    EXPECT_EQ(e4.getKey(), "solver.dynamic.mass_scale");
}

TEST(LoadTestScenario, ANameOfDotsIsNotAnOutputFolderOfItsOwn) {
    // name: ".." made the default output folder out/.., the folder bagsim was started in: the
    // run wrote its files there. Refused, as is a name with a slash.
    for (const char* name : {"\"..\"", "\".\"", "\"...\""}) {
        const InputError e = errorFor("name: " + std::string(name) + "\n" + kBase);
        EXPECT_EQ(e.getKey(), "name") << name;
        EXPECT_NE(std::string(e.what()).find("which is not a folder of its own"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(errorFor("name: ../up\n" + kBase).getKey(), "name");
    EXPECT_NO_THROW(
        io::readLoadTestScenario(ScenarioFile::parse("name: a.b-c_1\n" + kBase, "n.yaml")));
}
