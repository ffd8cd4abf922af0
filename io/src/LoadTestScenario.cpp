#include <io/LoadTestScenario.h>
#include <io/PatientScenario.h>

#include <bags/Bending.h>
#include <bags/MaterialFit.h>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace io {

namespace {

using D = Dimension;

const char* kKind = "seed-load-test";

// The value as written (for messages), or "" if the key is absent.
std::string getRaw(const ScenarioNode& s, const std::string& key) {
    if (!s.has(key)) return "";
    const YAML::Node n = s.get(key).getYaml();
    return n.IsScalar() ? n.Scalar() : "";
}

std::string shown(const ScenarioNode& s, const std::string& key) {
    const std::string raw = getRaw(s, key);
    return raw.empty() ? "the value" : "\"" + raw + "\"";
}

std::string fmt(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

// Three significant digits, without an exponent below 1e6 ("28600", "32.1").
std::string fmt3(double v) {
    if (!(v != 0.0) || !std::isfinite(v)) return fmt(v);
    const double scale = std::pow(10.0, std::floor(std::log10(std::fabs(v))) - 2);
    return fmt(std::round(v / scale) * scale);
}

// Checks lo < v (or lo <= v) and v < hi (or v <= hi); values are SI, shown in `unit`.
void checkRange(const ScenarioNode& s, const std::string& key, double v, double lo, bool loIncl,
                double hi, bool hiIncl, const std::string& unit, const std::string& why = "") {
    const bool okLo = loIncl ? v >= lo : v > lo;
    const bool okHi = hiIncl ? v <= hi : v < hi;
    if (okLo && okHi && std::isfinite(v)) return;
    auto show = [&](double x) { return unit.empty() ? fmt(x) : fmt(toUnit(x, unit)) + " " + unit; };
    std::string range;
    if (std::isinf(hi))
        range = std::string("must be ") + (loIncl ? ">= " : "> ") + show(lo);
    else
        range = "must be in " + std::string(loIncl ? "[" : "(") + show(lo) + ", " + show(hi) +
                (hiIncl ? "]" : ")");
    s.fail(key, shown(s, key) + " " + range + (why.empty() ? "" : " (" + why + ")"));
}

const double kInf = INFINITY;

// Turns a library's std::invalid_argument into an InputError at the key it names. The
// libraries name options by their C++ member (peakForce) and the scenario by its key
// (test.peak_force); both spellings are looked for, longest first.
struct KeyAlias {
    const char* token;
    const char* section;
    const char* key;
};

const std::vector<KeyAlias>& getAliases() {
    static const std::vector<KeyAlias> aliases = {
        {"longSide", "airbag", "long_side"},
        {"long_side", "airbag", "long_side"},
        {"shortSide", "airbag", "short_side"},
        {"short_side", "airbag", "short_side"},
        {"meshSize", "airbag", "mesh_size"},
        {"mesh_size", "airbag", "mesh_size"},
        {"height", "airbag", "height"},
        {"width", "airbag", "width"},
        {"wrinklingResidual", "membrane", "wrinkling_residual"},
        {"wrinkling_residual", "membrane", "wrinkling_residual"},
        {"bendingStiffness", "membrane", "bending_stiffness"},
        {"'prony'", "membrane", "prony"},
        {"ensemble", "test", "ensemble"},
        {"imperfection.amplitude", "airbag", "imperfection"},
        {"bending_stiffness", "membrane", "bending_stiffness"},
        {"thickness", "membrane", "thickness"},
        {"density", "membrane", "density"},
        {"C10", "membrane", "C10"},
        {"C01", "membrane", "C01"},
        {"C20", "membrane", "C20"},
        {"C30", "membrane", "C30"},
        {"alpha", "membrane", "alpha"},
        {"mu", "membrane", "mu"},
        {"molarMass", "gas", "molar_mass"},
        {"molar_mass", "gas", "molar_mass"},
        {"ambientPressure", "gas", "ambient_pressure"},
        {"ambient_pressure", "gas", "ambient_pressure"},
        {"temperature", "gas", "temperature"},
        {"polytropicIndex", "gas", "polytropic_index"},
        {"polytropic_index", "gas", "polytropic_index"},
        {"gamma", "gas", "gamma"},
        {"gasMasses", "test", "gas_masses"},
        {"gas_masses", "test", "gas_masses"},
        {"gas mass", "test", "gas_masses"},
        {"blockSize", "test", "block"},
        {"loadingRate", "test", "rate"},
        {"peakForce", "test", "peak_force"},
        {"peak_force", "test", "peak_force"},
        {"displacementStep", "test", "displacement_step"},
        {"stiffnessFrom", "test", "stiffness_range"},
        {"stiffnessTo", "test", "stiffness_range"},
        {"polynomialOrder", "test", "polynomial_order"},
        {"pressurePenalty", "contact", "penalty"},
        {"stickStiffnessRatio", "contact", "stick_ratio"},
        {"onsetGap", "contact", "onset_gap"},
        {"friction", "contact", "friction"},
        {"relativeTolerance", "solver", "relative_tolerance"},
        {"absoluteTolerance", "solver", "absolute_tolerance"},
        {"maxIterations", "solver", "max_iterations"},
        {"pseudoTransientShift", "solver", "pseudo_transient_shift"},
        {"stabilization", "solver", "stabilization"},
        {"damping", "solver", "damping"},
        {"residualTolerance", "solver", "residual_tolerance"},
        {"neighbourGap", "airbag", "neighbours"},
        {"neighbourGasMass", "airbag", "neighbours"},
        {"neighbourSharedAir", "airbag", "neighbours"},
        {"neighbours", "airbag", "neighbours"},
    };
    return aliases;
}

// `node` is the scenario's root or one of its sections; the error goes to the key the message
// names if that key is in `node` (or, from the root, in the section named), else to `node`.
[[noreturn]] void failFromLibrary(const ScenarioNode& node, const std::string& message) {
    const std::string path = node.getPath();
    const std::string top = path.substr(0, path.find('.'));
    const KeyAlias* best = nullptr;
    size_t bestPos = std::string::npos;
    for (const KeyAlias& a : getAliases()) {
        if (!path.empty() && top != a.section) continue;
        const size_t pos = message.find(a.token);
        // The earliest mention wins (messages name the option first); ties go to the longer token.
        if (pos != std::string::npos &&
            (pos < bestPos ||
             (pos == bestPos && std::string(a.token).size() > std::string(best->token).size()))) {
            best = &a;
            bestPos = pos;
        }
    }
    const std::string text = "invalid: " + message;
    if (best) {
        if (!path.empty()) node.fail(best->key, text);
        if (node.has(best->section)) node.getSection(best->section).fail(best->key, text);
    }
    node.fail(text);
}

// ----------------------------------------------------------------------------------- airbag

void readAirbag(const ScenarioNode& s, bags::LoadTestOptions& o) {
    bags::DoubleWedgeParams& g = o.geometry;
    s.checkKeys({"long_side", "short_side", "width", "height"},
                {"mesh_size", "mesh_pattern", "diaphragm", "bond_base", "connection",
                 "orifice_diameter", "discharge_coefficient", "fill_mass", "fill_scaling",
                 "volume_change", "imperfection", "neighbours"});
    g.longSide = s.getQuantity("long_side", D::Length);
    g.shortSide = s.getQuantity("short_side", D::Length);
    g.width = s.getQuantity("width", D::Length);
    g.height = s.getQuantity("height", D::Length);
    g.meshSize = s.getQuantity("mesh_size", D::Length, g.meshSize);
    {
        // Unstated, the library's default (legacy, the mesh of every result before the key);
        // the seed's scenarios state crossed (docs/seed-load-test.md, "Mesh convergence and
        // the mesh pattern").
        const std::string pattern = s.getChoice("mesh_pattern", {"legacy", "mirrored", "crossed"},
                                                bags::getMeshPatternName(g.pattern));
        g.pattern = pattern == "mirrored"  ? bags::MeshPattern::Mirrored
                    : pattern == "crossed" ? bags::MeshPattern::Crossed
                                           : bags::MeshPattern::Legacy;
    }
    g.diaphragm = s.getBool("diaphragm", g.diaphragm);
    g.bondBase = s.getBool("bond_base", g.bondBase);
    checkRange(s, "long_side", g.longSide, 0, false, kInf, false, "mm");
    checkRange(s, "short_side", g.shortSide, 0, false, kInf, false, "mm");
    checkRange(s, "width", g.width, 0, false, kInf, false, "mm");
    checkRange(s, "height", g.height, 0, false, kInf, false, "mm");
    if (!(g.height < g.shortSide))
        s.fail("height", shown(s, "height") + " must be less than short_side (" +
                             getRaw(s, "short_side") +
                             "): the steep side rises from the base to the apex");
    const double smallest = std::min({g.longSide, g.shortSide, g.width, g.height});
    checkRange(s, "mesh_size", g.meshSize, 1e-3, true, std::min(0.05, 0.5 * smallest), true, "mm",
               "at least 1 mm; at most 50 mm and half the smallest dimension");
    // The rest (the apex above the base) is checked by DoubleWedgeParams::validate().

    // How the two wedge chambers share their air.
    const std::string connection = s.getChoice("connection", {"open", "orifice"}, "open");
    o.connection = connection == "orifice" ? bags::LoadTestOptions::Connection::Orifice
                                           : bags::LoadTestOptions::Connection::Open;
    for (const char* key : {"orifice_diameter", "discharge_coefficient"})
        if (s.has(key) && connection != "orifice")
            s.fail(key, std::string("only applies to connection: orifice (connection is ") +
                            connection + ")");
    if (connection == "orifice" && !g.diaphragm)
        s.fail("connection",
               "orifice needs two chambers: set diaphragm: true, or use "
               "connection: open");
    o.orifice.diameter = s.getQuantity("orifice_diameter", D::Length, o.orifice.diameter);
    o.orifice.dischargeCoefficient =
        s.getNumber("discharge_coefficient", o.orifice.dischargeCoefficient);
    checkRange(s, "orifice_diameter", o.orifice.diameter, 0, false, std::min(g.width, g.height),
               false, "mm", "greater than zero and smaller than the diaphragm");
    checkRange(s, "discharge_coefficient", o.orifice.dischargeCoefficient, 0, false, 1, true, "",
               "0 < Cd <= 1 (sharp-edged orifice: about 0.6)");

    // A stated imperfection: smooth random offsets of the panels along their normals.
    if (s.has("imperfection")) {
        const ScenarioNode imp = s.getSection("imperfection");
        imp.checkKeys({"amplitude"}, {"seed"});
        o.imperfection.amplitude = imp.getQuantity("amplitude", D::Length);
        checkRange(imp, "amplitude", o.imperfection.amplitude, 0, true, 0.01, true, "mm",
                   "0 (the perfect bag) to 10 mm, e.g. 0.5 mm");
        const int seed = imp.getInteger("seed", 1);
        if (seed < 0) imp.fail("seed", std::to_string(seed) + " must be a whole number >= 0");
        o.imperfection.seed = static_cast<std::uint64_t>(seed);
    }

    // The pressed bag among neighbours of the same bag (docs/array-coupling.md).
    if (s.has("neighbours")) {
        const ScenarioNode nb = s.getSection("neighbours");
        nb.checkKeys({"layout"}, {"gap", "gas_mass", "pressed", "shared_air"});
        using N = bags::LoadTestOptions::Neighbours;
        const std::string layout = nb.getChoice("layout", {"none", "pair", "row3", "block3x3"});
        o.neighbours = layout == "pair"       ? N::Pair
                       : layout == "row3"     ? N::Row3
                       : layout == "block3x3" ? N::Block3x3
                                              : N::None;
        // With layout none, gap and gas_mass are read and checked but unused, so a study can
        // sweep the layout with them set for every case.
        o.neighbourGap = nb.getQuantity("gap", D::Length, o.neighbourGap);
        checkRange(nb, "gap", o.neighbourGap, 0, false, 0.1, false, "mm",
                   "between the facing flat panels of neighbouring bags, e.g. 5 mm");
        if (nb.has("gas_mass")) {
            o.neighbourGasMass = nb.getQuantity("gas_mass", D::Mass);
            checkRange(nb, "gas_mass", o.neighbourGasMass, 0, false, 0.1, false, "g",
                       "every neighbour's gas mass; leave it out for the pressed bag's own");
        }
        if (nb.has("pressed")) {
            const ScenarioNode pr = nb.get("pressed");
            const std::vector<ScenarioNode> e =
                pr.isSequence() ? pr.getElements() : std::vector<ScenarioNode>();
            const char* valid =
                "two whole numbers [along, across], each -1, 0 or 1: where in the 3 x 3 block "
                "the pressed bag stands ([0, 0] the middle, [1, 1] the corner at +x +y)";
            if (e.size() != 2) nb.fail("pressed", std::string("must be ") + valid);
            for (int k = 0; k < 2; ++k) {
                const int v = e[k].asInteger();
                if (v < -1 || v > 1) nb.fail("pressed", std::string("must be ") + valid);
                o.neighbourPressed[k] = v;
            }
            if (o.neighbours != N::Block3x3 && o.neighbourPressed != std::array<int, 2>{0, 0})
                nb.fail("pressed",
                        "needs layout: block3x3 (the other layouts press their "
                        "middle bag); use [0, 0] or leave it out");
        }
        // With layout none there is no neighbour to share air with: read, checked, unused.
        o.neighbourSharedAir = nb.getBool("shared_air", false);
        if (o.neighbours != N::None && connection == "orifice")
            s.fail("connection",
                   "orifice is not supported with neighbours (one gas body per "
                   "bag); use connection: open");
    }
}

// The seed's bag read from its words (docs/geometry.md): airbag.fill_mass scales the sizes
// as written so that this gas mass just fills the inflated bag; the scale itself is found
// before the run (bags::findFillScale), here only the keys and a first guess are checked.
void readFillMass(const ScenarioNode& s, LoadTestScenario& sc) {
    // airbag.volume_change: the bag's volume (and fill mass) relative to the sizes as written
    // or as the fill mass scales them; a similar bag, every size and the mesh size times
    // cbrt(1 + change) (bags::scaleBagVolume), applied after the fill mass's sizing.
    if (s.has("volume_change")) {
        sc.volumeChange = s.getNumber("volume_change");
        checkRange(s, "volume_change", sc.volumeChange, -bags::kMaxVolumeChange, true,
                   bags::kMaxVolumeChange, true, "",
                   "the bag's volume and fill mass relative to its sizes' reading: +0.05 a bag "
                   "5 % larger, every size times the cube root of 1 + change");
        const double s1 = std::cbrt(1.0 + sc.volumeChange);
        const bags::DoubleWedgeParams& g = sc.options.geometry;
        if (g.meshSize * s1 > 0.05)
            s.fail("volume_change", shown(s, "volume_change") + " would scale the mesh size (" +
                                        fmt(toUnit(g.meshSize, "mm")) +
                                        " mm) beyond 50 mm; valid: a mesh_size of at most " +
                                        fmt(std::floor(toUnit(0.05 / s1, "mm") * 10) / 10) +
                                        " mm with this change");
    }
    const std::string scaling =
        s.getChoice("fill_scaling", {"profile", "uniform", "height"}, "profile");
    if (!s.has("fill_mass")) {
        if (s.has("fill_scaling"))
            s.fail("fill_scaling",
                   "only applies with fill_mass (the gas mass that just fills "
                   "the inflated bag, e.g. fill_mass: 2.8 g)");
        return;
    }
    sc.fillScaling = scaling == "uniform"  ? bags::FillScaling::Uniform
                     : scaling == "height" ? bags::FillScaling::Height
                                           : bags::FillScaling::Profile;
    sc.fillMass = s.getQuantity("fill_mass", D::Mass);
    checkRange(s, "fill_mass", sc.fillMass, 0, false, kInf, false, "g",
               "the gas mass that just fills the inflated bag at ambient pressure");
    // The first guess (flat volume times the seed reading's bulge) must leave a bag of
    // sensible proportions: the search moves the scale by a few per cent from it.
    const double s0 = bags::estimateFillScale(sc.options, sc.fillMass, sc.fillScaling);
    const double lo = 0.5, hi = 1.5;
    if (!(s0 >= lo && s0 <= hi)) {
        auto massAt = [&](double f) {
            return fmt(std::round(toUnit(sc.fillMass *
                                             std::pow(f / s0,
                                                      bags::getFillScalingExponent(sc.fillScaling)),
                                         "g") *
                                  100) /
                       100) +
                   " g";
        };
        s.fail("fill_mass", shown(s, "fill_mass") + " would scale the " + scaling + " by about " +
                                fmt(std::round(s0 * 100) / 100) + "; valid: a scale from " +
                                fmt(lo) + " to " + fmt(hi) + ", i.e. a fill mass from about " +
                                massAt(lo) + " to " + massAt(hi) + " for these sizes");
    }
    const bags::DoubleWedgeParams g =
        bags::scaleDoubleWedge(sc.options.geometry, sc.fillScaling, s0);
    const double smallest = std::min({g.longSide, g.shortSide, g.width, g.height});
    if (g.meshSize > 0.5 * smallest)
        s.fail("mesh_size", shown(s, "mesh_size") +
                                " must be at most half the smallest "
                                "dimension of the scaled airbag (about " +
                                fmt(std::round(toUnit(0.5 * smallest, "mm"))) + " mm)");
}

// --------------------------------------------------------------------------------- membrane

struct ModelInfo {
    std::string name;
    std::vector<std::string> constants;
};

const std::vector<ModelInfo>& getModels() {
    static const std::vector<ModelInfo> models = {
        {"yeoh", {"C10", "C20", "C30"}},
        {"neo-hookean", {"C10"}},
        {"mooney-rivlin", {"C10", "C01"}},
        {"ogden", {"mu", "alpha"}},
    };
    return models;
}

// membrane.prony: [{g: 0.1, tau: 20 s}, ...], the film's viscoelasticity
// (docs/materials.md#viscoelasticity): each term located when it is wrong.
bags::PronySeries readProny(const ScenarioNode& s) {
    const ScenarioNode list = s.get("prony");
    const std::vector<ScenarioNode> terms = list.getElements();
    const std::string example = "e.g. prony: [{g: 0.1, tau: 20 s}]";
    if (static_cast<int>(terms.size()) > bags::PronySeries::kMaxTerms)
        s.fail("prony", "has " + std::to_string(terms.size()) + " terms; use 1 to " +
                            std::to_string(bags::PronySeries::kMaxTerms) + " (" + example + ")");
    bags::PronySeries p;
    double sum = 0.0;
    for (const ScenarioNode& t : terms) {
        t.checkKeys({"g", "tau"}, {});
        bags::PronyTerm term;
        term.g = t.getNumber("g");
        term.tau = t.getQuantity("tau", D::Time);
        checkRange(t, "g", term.g, 0, true, 1, false, "",
                   "the term's relative modulus (of the instantaneous modulus)");
        checkRange(t, "tau", term.tau, bags::PronySeries::kMinTau, true, bags::PronySeries::kMaxTau,
                   true, "s", "the term's relaxation time");
        sum += term.g;
        if (!(sum <= bags::PronySeries::kMaxSum))
            t.fail("g", "brings the sum of the relative moduli to " + fmt(sum) +
                            "; the sum must be at most " + fmt(bags::PronySeries::kMaxSum) +
                            " (the long-term modulus 1 - sum g stays positive)");
        p.terms.push_back(term);
    }
    return p;
}

// membrane.anisotropy: {warp: 95 MPa, weft: 60 MPa, angle: 0 deg}, the woven fabric's yarns
// (docs/materials.md#fabric-anisotropy).
bags::FabricAnisotropy readAnisotropy(const ScenarioNode& s) {
    const ScenarioNode a = s.getSection("anisotropy");
    a.checkKeys({"warp", "weft"}, {"angle"});
    bags::FabricAnisotropy y;
    y.warpModulus = a.getQuantity("warp", D::Pressure);
    y.weftModulus = a.getQuantity("weft", D::Pressure);
    y.angle = a.getQuantity("angle", D::Angle, 0.0);
    const std::string why = "the yarns' tangent modulus in Green strain; 0: none";
    checkRange(a, "warp", y.warpModulus, 0, true, bags::FabricAnisotropy::kMaxModulus, true, "MPa",
               why);
    checkRange(a, "weft", y.weftModulus, 0, true, bags::FabricAnisotropy::kMaxModulus, true, "MPa",
               why);
    checkRange(a, "angle", y.angle, -0.5 * M_PI, true, 0.5 * M_PI, true, "deg",
               "the warp's angle from its panel's reference direction");
    return y;
}

void readMembrane(const ScenarioNode& s, bags::LoadTestOptions& o) {
    std::vector<std::string> allConstants;
    std::vector<std::string> modelNames;
    for (const ModelInfo& m : getModels()) {
        modelNames.push_back(m.name);
        for (const std::string& c : m.constants)
            if (std::find(allConstants.begin(), allConstants.end(), c) == allConstants.end())
                allConstants.push_back(c);
    }
    std::vector<std::string> optional = allConstants;
    optional.insert(optional.end(), {"density", "wrinkling_residual", "extrapolation",
                                     "bending_stiffness", "prony", "anisotropy"});
    s.checkKeys({"model", "thickness"}, optional);
    const std::string model = s.getChoice("model", modelNames);
    // Beyond the stable range a Yeoh continues linearly in I1 (default) or as its polynomial.
    const std::string extrapolation =
        s.getChoice("extrapolation", {"linear", "polynomial"}, "linear");
    if (s.has("extrapolation") && model != "yeoh")
        s.fail("extrapolation", "only applies to model: yeoh (model is " + model + ")");
    const ModelInfo& info = *std::find_if(getModels().begin(), getModels().end(),
                                          [&](const ModelInfo& m) { return m.name == model; });
    auto describe = [&] {
        std::string list;
        for (const std::string& c : info.constants) list += (list.empty() ? "" : ", ") + c;
        return "the " + model + " model takes " + list;
    };
    for (const std::string& c : allConstants) {
        const bool mine =
            std::find(info.constants.begin(), info.constants.end(), c) != info.constants.end();
        if (!mine && s.has(c)) s.fail(c, "is not a constant of this material; " + describe());
        if (mine && !s.has(c))
            s.fail("missing the material constant '" + c + "'; " + describe() +
                   " (e.g. C10: 31.6 MPa; bagsim fit-material writes them)");
    }

    try {
        if (model == "yeoh") {
            const double C10 = s.getQuantity("C10", D::Pressure);
            const double C20 = s.getQuantity("C20", D::Pressure);
            const double C30 = s.getQuantity("C30", D::Pressure);
            o.material = extrapolation == "polynomial" ? bags::makeYeoh(C10, C20, C30)
                                                       : bags::makeStableYeoh(C10, C20, C30);
        } else if (model == "neo-hookean") {
            o.material = bags::makeNeoHookean(s.getQuantity("C10", D::Pressure));
        } else if (model == "mooney-rivlin") {
            o.material = bags::makeMooneyRivlin(s.getQuantity("C10", D::Pressure),
                                                s.getQuantity("C01", D::Pressure));
        } else {
            const std::vector<ScenarioNode> mu = s.get("mu").getElements();
            const std::vector<ScenarioNode> alpha = s.get("alpha").getElements();
            if (mu.empty() || mu.size() > 6)
                s.fail("mu", "must list 1 to 6 moduli, e.g. [0.5 MPa, 0.01 MPa]");
            if (alpha.size() != mu.size())
                s.fail("alpha", "must list as many exponents as mu has moduli (" +
                                    std::to_string(mu.size()) + ")");
            std::vector<double> muSi, alphaSi;
            for (const ScenarioNode& n : mu) muSi.push_back(n.asQuantity(D::Pressure));
            for (const ScenarioNode& n : alpha) {
                alphaSi.push_back(n.asNumber());
                if (alphaSi.back() == 0.0) n.fail("an Ogden exponent must not be zero");
            }
            o.material = bags::makeOgden(muSi, alphaSi);
        }
    } catch (const std::invalid_argument& e) {
        const std::string msg = e.what();
        for (const std::string& c : info.constants)
            if (msg.find(c) != std::string::npos) s.fail(c, "invalid: " + msg);
        s.fail("model", "invalid material constants: " + msg);
    }
    if (o.material && !(o.material->getInitialShearModulus() > 0.0))
        s.fail(info.constants.front(), "these constants give a small-strain shear modulus of " +
                                           fmt(o.material->getInitialShearModulus() / 1e6) +
                                           " MPa; a membrane material needs a positive one");

    o.thickness = s.getQuantity("thickness", D::Length);
    o.density = s.getQuantity("density", D::Density, o.density);
    o.wrinklingResidual = s.getNumber("wrinkling_residual", o.wrinklingResidual);
    checkRange(s, "thickness", o.thickness, 0, false, 0.01, true, "mm");
    checkRange(s, "density", o.density, 0, true, kInf, false, "kg/m^3");
    checkRange(s, "wrinkling_residual", o.wrinklingResidual, 0, false, 0.1, false, "");
    if (s.has("prony")) o.prony = readProny(s);
    if (s.has("anisotropy")) {
        const bags::FabricAnisotropy yarns = readAnisotropy(s);
        if (yarns.isOn())  // both moduli 0: the isotropic film, as without the key
            o.material = std::make_shared<bags::FabricMaterial>(o.material->clone(), yarns);
    }
    // The film's bending stiffness: the plate value also when the key is absent.
    o.bendingStiffness = readBendingStiffness(s, "bending_stiffness", *o.material, o.thickness);
}

// -------------------------------------------------------------------------------------- gas

void readGas(const ScenarioNode& s, bags::GasOptions& g) {
    s.checkKeys({}, {"molar_mass", "temperature", "ambient_pressure", "process", "polytropic_index",
                     "gamma", "leak_conductance", "heat_time_constant"});
    g.molarMass = s.getQuantity("molar_mass", D::MolarMass, g.molarMass);
    g.temperature = s.getQuantity("temperature", D::Temperature, g.temperature);
    g.ambientPressure = s.getQuantity("ambient_pressure", D::Pressure, g.ambientPressure);
    const std::string process =
        s.getChoice("process", {"isothermal", "adiabatic", "polytropic"}, "isothermal");
    g.process = process == "isothermal"  ? bags::GasOptions::Process::Isothermal
                : process == "adiabatic" ? bags::GasOptions::Process::Adiabatic
                                         : bags::GasOptions::Process::Polytropic;
    if (s.has("polytropic_index") && process != "polytropic")
        s.fail("polytropic_index",
               "only applies to process: polytropic (process is " + process + ")");
    g.polytropicIndex = s.getNumber("polytropic_index", g.polytropicIndex);
    g.gamma = s.getNumber("gamma", g.gamma);
    checkRange(s, "molar_mass", g.molarMass, 0, false, kInf, false, "g/mol");
    // A film bag's air: the film's law was fitted at room temperature, and polyurethane and
    // PVC films soften well below 100 degC; a gas far outside is not a bag this model describes.
    checkRange(s, "temperature", g.temperature, 223.15, true, 373.15, true, "K",
               "-50 to 100 degC: the air of a film bag, whose law was fitted at room temperature");
    checkRange(s, "ambient_pressure", g.ambientPressure, 0, false, kInf, false, "kPa",
               "absolute pressure");
    checkRange(s, "polytropic_index", g.polytropicIndex, 1, true, kInf, false, "");
    checkRange(s, "gamma", g.gamma, 1, false, kInf, false, "");
    // Unmodelled effects a scenario can switch on (docs/diagnosis.md#the-library-of-unmodelled-effects).
    g.leakConductance = s.getQuantity("leak_conductance", D::LeakConductance, 0.0);
    checkRange(s, "leak_conductance", g.leakConductance, 0, true,
               bags::GasOptions::kMaxLeakConductance, true, "mg/(s kPa)",
               "the mass flow out through seams and valves per gauge pressure; 0: sealed");
    g.heatTimeConstant = s.getQuantity("heat_time_constant", D::Time, 0.0);
    checkRange(s, "heat_time_constant", g.heatTimeConstant, 0, true,
               bags::GasOptions::kMaxHeatTimeConstant, true, "s",
               "the film's thermal time constant (adiabatic gas relaxing to the room); 0: the "
               "process as chosen");
    if (g.heatTimeConstant > 0.0 && process == "polytropic")
        s.fail("heat_time_constant",
               "makes the gas adiabatic with heat exchange; it does not combine with process: "
               "polytropic (use isothermal or adiabatic)");
    try {
        g.validate();
    } catch (const std::invalid_argument& e) {
        failFromLibrary(s, e.what());
    }
}

// ------------------------------------------------------------------------------------- test

std::vector<double> readGasMasses(const ScenarioNode& s) {
    const ScenarioNode n = s.get("gas_masses");
    std::vector<double> masses;
    if (n.isSequence()) {
        for (const ScenarioNode& e : n.getElements()) {
            const double m = e.asQuantity(D::Mass);
            if (!(m > 0)) e.fail("\"" + e.asString() + "\": a gas mass must be greater than zero");
            masses.push_back(m);
        }
    } else if (n.isMap()) {
        n.checkKeys({"from", "to", "step"}, {});
        const double from = n.getQuantity("from", D::Mass);
        const double to = n.getQuantity("to", D::Mass);
        const double step = n.getQuantity("step", D::Mass);
        checkRange(n, "from", from, 0, false, kInf, false, "g", "a gas mass");
        checkRange(n, "to", to, 0, false, kInf, false, "g", "a gas mass");
        checkRange(n, "step", step, 0, false, kInf, false, "g");
        const double count = std::fabs(from - to) / step;
        const long steps = std::lround(count);
        if (std::fabs(count - steps) > 1e-6 * std::max(1.0, count))
            n.fail("step", "\"" + getRaw(n, "step") + "\" does not divide the range from " +
                               getRaw(n, "from") + " to " + getRaw(n, "to") +
                               " into whole steps; pick a step that does (e.g. 0.25 g)");
        if (steps + 1 > kMaxGasMasses)
            n.fail("step", "\"" + getRaw(n, "step") + "\" gives " + std::to_string(steps + 1) +
                               " gas masses; at most " + std::to_string(kMaxGasMasses) +
                               " are allowed (a curve takes minutes); use a larger step");
        for (long i = 0; i <= steps; ++i)
            masses.push_back(steps == 0 ? from : from + (to - from) * double(i) / double(steps));
    } else {
        n.fail(
            "must be a list of masses, e.g. [3.5 g, 3.0 g], or a range "
            "{from: 3.5 g, to: 1.0 g, step: 0.25 g}");
    }
    if (masses.empty()) n.fail("lists no gas mass; give at least one, e.g. [3.5 g]");
    if (static_cast<int>(masses.size()) > kMaxGasMasses)
        n.fail("lists " + std::to_string(masses.size()) + " gas masses; at most " +
               std::to_string(kMaxGasMasses) + " are allowed (a curve takes minutes)");
    return masses;
}

void readTest(const ScenarioNode& s, bags::LoadTestOptions& o) {
    s.checkKeys({"gas_masses"},
                {"block", "rate", "peak_force", "unload", "displacement_step", "stiffness_range",
                 "polynomial_order", "gravity", "ensemble", "step_over_snaps"});
    o.gasMasses = readGasMasses(s);
    o.blockSize = s.getQuantity("block", D::Length, o.blockSize);
    o.loadingRate = s.getQuantity("rate", D::Velocity, o.loadingRate);
    o.peakForce = s.getQuantity("peak_force", D::Force, o.peakForce);
    o.unload = s.getBool("unload", o.unload);
    o.displacementStep = s.getQuantity("displacement_step", D::Length, o.displacementStep);
    o.polynomialOrder = s.getInteger("polynomial_order", o.polynomialOrder);
    o.gravity = s.getBool("gravity", o.gravity);
    o.ensemble = s.getInteger("ensemble", o.ensemble);
    o.stepOverSnaps = s.getBool("step_over_snaps", o.stepOverSnaps);
    if (o.ensemble < 1 || o.ensemble > 64)
        s.fail("ensemble",
               std::to_string(o.ensemble) + " must be from 1 (one bag) to 64 imperfection seeds");
    checkRange(s, "block", o.blockSize, 0, false, o.geometry.longSide, true, "mm",
               "at most the airbag's long side");
    checkRange(s, "rate", o.loadingRate, 0, false, kInf, false, "mm/min");
    checkRange(s, "peak_force", o.peakForce, 0, false, kInf, false, "N");
    checkRange(s, "displacement_step", o.displacementStep, 0, false, kInf, false, "mm");
    if (s.has("stiffness_range")) {
        const ScenarioNode r = s.get("stiffness_range");
        const std::vector<ScenarioNode> ends = r.getElements();
        if (ends.size() != 2) r.fail("must be two forces [from, to], e.g. [10 N, 35 N]");
        o.stiffnessFrom = ends[0].asQuantity(D::Force);
        o.stiffnessTo = ends[1].asQuantity(D::Force);
    }
    if (!(o.stiffnessFrom >= 0.0 && o.stiffnessFrom < o.stiffnessTo &&
          o.stiffnessTo <= o.peakForce))
        s.fail("stiffness_range", "[" + fmt(o.stiffnessFrom) + " N, " + fmt(o.stiffnessTo) +
                                      " N] must satisfy 0 <= from < to <= peak_force (" +
                                      fmt(o.peakForce) + " N)");
    const int masses = static_cast<int>(o.gasMasses.size());
    if (o.polynomialOrder < 1 || o.polynomialOrder > 8 ||
        (masses > 1 && o.polynomialOrder >= masses))
        s.fail("polynomial_order", std::to_string(o.polynomialOrder) +
                                       " must be in [1, 8] and less than the "
                                       "number of gas masses (" +
                                       std::to_string(masses) + ") for a least-squares fit");
}

// ---------------------------------------------------------------------------------- contact

const std::vector<std::string> kContactKeys = {"penalty", "friction", "stick_ratio", "onset_gap"};

void readContactKeys(const ScenarioNode& s, bags::RigidContact::Options& c) {
    c.pressurePenalty = s.getQuantity("penalty", D::StiffnessPerArea, c.pressurePenalty);
    c.friction = s.getNumber("friction", c.friction);
    c.stickStiffnessRatio = s.getNumber("stick_ratio", c.stickStiffnessRatio);
    c.onsetGap = s.getQuantity("onset_gap", D::Length, c.onsetGap);
    checkRange(s, "penalty", c.pressurePenalty, 0, false, kInf, false, "Pa/m");
    checkRange(s, "friction", c.friction, 0, true, kInf, false, "");
    checkRange(s, "stick_ratio", c.stickStiffnessRatio, 0, false, kInf, false, "");
    checkRange(s, "onset_gap", c.onsetGap, 0, true, kInf, false, "mm");
    try {
        c.validate();
    } catch (const std::invalid_argument& e) {
        failFromLibrary(s, e.what());
    }
}

void readContact(const ScenarioNode& s, bags::LoadTestOptions& o) {
    std::vector<std::string> keys = kContactKeys;
    keys.insert(keys.end(), {"block", "floor", "self"});
    s.checkKeys({}, keys);
    // Keys at the top of the section apply to both shapes; block/floor subsections override.
    readContactKeys(s, o.blockContact);
    readContactKeys(s, o.floorContact);
    for (const char* shape : {"block", "floor"}) {
        const ScenarioNode sub = s.getSection(shape, false);
        const bool block = std::string(shape) == "block";
        // A layer on the block (a pad on the indenter, soft tissue); the bed board is bare.
        std::vector<std::string> subKeys = kContactKeys;
        if (block) subKeys.push_back("tissue");
        sub.checkKeys({}, subKeys);
        readContactKeys(sub, block ? o.blockContact : o.floorContact);
        if (block && sub.has("tissue")) readTissueLayer(sub.getSection("tissue"), o.blockContact);
    }
    o.selfContact = s.getBool("self", o.selfContact);
}

// ----------------------------------------------------------------------------------- solver

// solver.dynamic: the dynamic test's pace, mass scale, damping and checks
// (bags::LoadTestOptions::Dynamic).
void readDynamic(const ScenarioNode& s, bags::LoadTestOptions::Dynamic& d) {
    s.checkKeys({}, {"block_speed", "mass_scale", "damping", "step_fraction", "record_every",
                     "ramp", "kinetic_share_limit", "max_halvings"});
    d.blockSpeed = s.getQuantity("block_speed", D::Velocity, d.blockSpeed);
    checkRange(s, "block_speed", d.blockSpeed, 0, false, 1.0, true, "m/s",
               "the pace the film is integrated at, e.g. 20 mm/s");
    d.massScale = s.getNumber("mass_scale", d.massScale);
    checkRange(s, "mass_scale", d.massScale, 1, true, 1e6, true, "", "e.g. 1000");
    d.damping = s.getQuantity("damping", D::Rate, d.damping);
    checkRange(s, "damping", d.damping, 0, true, 1e4, true, "1/s", "e.g. 20 1/s");
    d.stepFraction = s.getNumber("step_fraction", d.stepFraction);
    checkRange(s, "step_fraction", d.stepFraction, 0, false, 1, true, "",
               "a fraction of the stable step, e.g. 0.5");
    d.recordEvery = s.getQuantity("record_every", D::Length, d.recordEvery);
    checkRange(s, "record_every", d.recordEvery, 0, false, 0.02, true, "m", "e.g. 0.25 mm");
    d.rampTravel = s.getQuantity("ramp", D::Length, d.rampTravel);
    checkRange(s, "ramp", d.rampTravel, 0, true, 0.02, true, "m",
               "the travel over which the block comes up to speed, e.g. 2 mm");
    d.kineticShareLimit = s.getNumber("kinetic_share_limit", d.kineticShareLimit);
    checkRange(s, "kinetic_share_limit", d.kineticShareLimit, 0, false, 1, false, "",
               "a fraction of the block's work, e.g. 0.01");
    d.maxHalvings = s.getInteger("max_halvings", d.maxHalvings);
    checkRange(s, "max_halvings", d.maxHalvings, 0, true, 6, true, "");
}

void readSolver(const ScenarioNode& s, bags::LoadTestOptions& lo) {
    bags::SolverOptions& o = lo.solver;
    double& stabilization = lo.stabilization;
    double& damping = lo.damping;
    double& residualTolerance = lo.residualTolerance;
    s.checkKeys(
        {}, {"relative_tolerance", "absolute_tolerance", "max_iterations", "pseudo_transient_shift",
             "stabilization", "damping", "residual_tolerance", "stepping", "dynamic"});
    lo.stepping = readStepping(s, lo.stepping);
    if (s.has("dynamic")) readDynamic(s.getSection("dynamic"), lo.dynamic);
    o.relativeTolerance = s.getNumber("relative_tolerance", o.relativeTolerance);
    o.absoluteTolerance = s.getQuantity("absolute_tolerance", D::Force, o.absoluteTolerance);
    o.maxIterations = s.getInteger("max_iterations", o.maxIterations);
    o.pseudoTransientShift = s.getNumber("pseudo_transient_shift", o.pseudoTransientShift);
    checkRange(s, "relative_tolerance", o.relativeTolerance, 0, false, 1, false, "");
    checkRange(s, "absolute_tolerance", o.absoluteTolerance, 0, false, kInf, false, "N");
    checkRange(s, "max_iterations", o.maxIterations, 1, true, 100000, true, "");
    checkRange(s, "pseudo_transient_shift", o.pseudoTransientShift, 0, true, kInf, false, "");
    stabilization = s.getQuantity("stabilization", D::StiffnessPerArea, stabilization);
    checkRange(s, "stabilization", stabilization, 0, true, kInf, false, "Pa/m", "0 disables it");
    damping = s.getQuantity("damping", D::StiffnessPerArea, damping);
    checkRange(s, "damping", damping, 0, true, kInf, false, "Pa/m", "0: no damper");
    residualTolerance = s.getNumber("residual_tolerance", residualTolerance);
    checkRange(s, "residual_tolerance", residualTolerance, 0, true, 0.05, true, "",
               "a fraction of the peak force; 0 leaves the absolute and relative tolerances");
    try {
        o.validate();
    } catch (const std::invalid_argument& e) {
        failFromLibrary(s, e.what());
    }
}

// The rig's effects the airbag model leaves out (docs/scenario-reference.md#rig).
void readRig(const ScenarioNode& s, diagnose::RigEffects& r) {
    s.checkKeys({}, {"pressure_sensor", "flowmeter", "machine_stiffness", "bed_stiffness",
                     "load_cell_gain"});
    const ScenarioNode ps = s.getSection("pressure_sensor", false);
    ps.checkKeys({}, {"lag", "offset"});
    r.pressureLag = ps.getQuantity("lag", D::Time, 0.0);
    r.pressureOffset = ps.getQuantity("offset", D::Pressure, 0.0);
    checkRange(ps, "lag", r.pressureLag, 0, true, diagnose::RigEffects::kMaxPressureLag, true, "s",
               "the sensor's first-order time constant; 0: no lag");
    checkRange(ps, "offset", r.pressureOffset, -diagnose::RigEffects::kMaxPressureOffset, true,
               diagnose::RigEffects::kMaxPressureOffset, true, "kPa",
               "what the sensor reads at zero gauge pressure");
    const ScenarioNode fm = s.getSection("flowmeter", false);
    fm.checkKeys({}, {"offset"});
    r.flowmeterOffset = fm.getQuantity("offset", D::Mass, 0.0);
    checkRange(fm, "offset", r.flowmeterOffset, -diagnose::RigEffects::kMaxFlowmeterOffset, true,
               diagnose::RigEffects::kMaxFlowmeterOffset, true, "g",
               "the flowmeter reads the bag's gas mass plus this");
    if (s.has("machine_stiffness")) {
        const double k = s.getQuantity("machine_stiffness", D::Stiffness);
        checkRange(s, "machine_stiffness", k, 1.0 / diagnose::RigEffects::kMaxMachineCompliance,
                   true, kInf, false, "N/mm", "the testing machine in series with the block");
        r.machineCompliance = 1.0 / k;
    }
    if (s.has("bed_stiffness")) {
        const double k = s.getQuantity("bed_stiffness", D::Stiffness);
        checkRange(s, "bed_stiffness", k, 1.0 / diagnose::RigEffects::kMaxBedCompliance, true, kInf,
                   false, "N/mm", "the spring under the bed board, in series with the bag");
        r.bedCompliance = 1.0 / k;
    }
    r.loadCellGain = s.getNumber("load_cell_gain", 0.0);
    checkRange(s, "load_cell_gain", r.loadCellGain, -diagnose::RigEffects::kMaxLoadCellGain, true,
               diagnose::RigEffects::kMaxLoadCellGain, true, "",
               "the load cell reads the force times 1 + gain");
}

void readOutput(const ScenarioNode& s, OutputOptions& o) {
    s.checkKeys({}, {"frame_every"});
    o.frameEvery = s.getInteger("frame_every", o.frameEvery);
    checkRange(s, "frame_every", o.frameEvery, 0, true, kInf, false, "", "0 saves no frames");
}

// The limits of LoadTestScenario.h, checked once the options are valid.
void checkLimits(const ScenarioNode& root, const bags::LoadTestOptions& o) {
    const ScenarioNode airbag = root.getSection("airbag");
    const double nodes = estimateNumNodes(o.geometry);
    if (nodes > kMaxMeshNodes) {
        // Nodes go as 1 / h^2: the smallest mesh size within the limit.
        const double hMin = o.geometry.meshSize * std::sqrt(nodes / kMaxMeshNodes);
        const std::string given =
            airbag.has("mesh_size")
                ? shown(airbag, "mesh_size")
                : "the default " + fmt(toUnit(o.geometry.meshSize, "mm")) + " mm";
        airbag.fail("mesh_size",
                    given + " gives a mesh of about " + fmt(std::round(nodes / 1000) * 1000) +
                        " nodes for this airbag; at most " + std::to_string(kMaxMeshNodes) +
                        " are allowed (about 2 GB and hours per curve); valid: mesh_size at "
                        "least " +
                        fmt(std::ceil(toUnit(hMin, "mm") * 10 - 1e-9) / 10) +
                        " mm for this airbag, or a smaller airbag");
    }

    const ScenarioNode test = root.getSection("test");
    // A gas mass no film bag can hold (ten atmospheres in its unstretched volume).
    const double mostGas = calcMostPlausibleGasMass(o.geometry, o.gas);
    for (double m : o.gasMasses)
        if (m > mostGas) test.fail("gas_masses", describeTooMuchGas(m, mostGas));
    const double steps = o.geometry.height / o.displacementStep;
    if (steps > kMaxStepsPerBranch)
        test.fail(
            "displacement_step",
            (test.has("displacement_step") ? shown(test, "displacement_step")
                                           : std::string("the default")) +
                " needs about " + fmt(std::round(steps)) +
                " steps to cross the airbag's height; at most " +
                std::to_string(kMaxStepsPerBranch) + " per branch are allowed; valid: at least " +
                fmt(std::ceil(toUnit(o.geometry.height / kMaxStepsPerBranch, "mm") * 1000 - 1e-9) /
                    1000) +
                " mm");

    const double capacity = estimateForceCapacity(o);
    const double area = o.geometry.longSide * o.geometry.width;
    // A bag at ambient pressure may still carry something: never refuse below the force of
    // one atmosphere over the base.
    const double limit = std::max(kPeakForceFactor * capacity, o.gas.ambientPressure * area);
    if (o.peakForce > limit) {
        const double mMax = *std::max_element(o.gasMasses.begin(), o.gasMasses.end());
        test.fail(
            "peak_force",
            shown(test, "peak_force") + " is far beyond what this bag can carry: over the " +
                fmt(toUnit(o.geometry.longSide, "mm")) + " mm x " +
                fmt(toUnit(o.geometry.width, "mm")) + " mm base it needs a gauge pressure of " +
                fmt3(toUnit(o.peakForce / area, "kPa")) + " kPa, while " + fmt(toUnit(mMax, "g")) +
                " g of gas squeezed under the " + fmt(toUnit(o.blockSize, "mm")) +
                " mm block reaches about " + fmt3(toUnit(capacity / area, "kPa")) + " kPa (" +
                fmt3(capacity) + " N); valid: at most " + fmt(std::floor(limit)) + " N (" +
                fmt(kPeakForceFactor) + " times that, or one atmosphere over the base)");
    }
}

}  // namespace

double readBendingStiffness(const ScenarioNode& s, const std::string& key,
                            const bags::MembraneMaterial& material, double thickness) {
    const std::string raw = getRaw(s, key);
    if (raw.empty() || raw == "plate") return bags::calcPlateBendingStiffness(material, thickness);
    if (raw == "0") return 0.0;
    const double stiffness = s.getQuantity(key, D::Moment);
    checkRange(s, key, stiffness, 0, true, 1.0, false, "N m",
               "or plate: the film's plate value; 0 switches bending off");
    return stiffness;
}

void readTissueLayer(const ScenarioNode& s, bags::RigidContact::Options& c) {
    s.checkKeys({"thickness", "modulus"}, {});
    c.tissueThickness = s.getQuantity("thickness", D::Length);
    c.tissueModulus = s.getQuantity("modulus", D::Pressure);
    checkRange(s, "thickness", c.tissueThickness, kMinTissueThickness, true, kMaxTissueThickness,
               true, "mm", "soft tissue over bone is about 5-40 mm");
    checkRange(s, "modulus", c.tissueModulus, kMinTissueModulus, true, kMaxTissueModulus, true,
               "kPa", "soft tissue's effective compressive modulus is about 10-200 kPa");
    try {
        c.validate();
    } catch (const std::invalid_argument& e) {
        failFromLibrary(s, e.what());
    }
}

double estimateNumNodes(const bags::DoubleWedgeParams& g) {
    const double ax = g.calcApexX();
    const double gentle = std::hypot(g.longSide - ax, g.height);
    // Two side profiles, the base, both sloped sides and the internal wall.
    double area = g.longSide * g.height + g.width * (g.longSide + g.shortSide + gentle);
    if (g.diaphragm) area += g.width * g.height;
    // An equilateral mesh of edge h has one node per sqrt(3)/2 h^2; the builder's triangles
    // are a little larger (0.87 fits the seed bag from 25 mm to 2.5 mm).
    double nodes = 0.87 * area / (0.5 * std::sqrt(3.0) * g.meshSize * g.meshSize);
    // The crossed pattern adds a node at the centre of each cell of about h x h of the
    // structured panels (base, sloped sides, internal wall).
    if (g.pattern == bags::MeshPattern::Crossed)
        nodes += (area - g.longSide * g.height) / (g.meshSize * g.meshSize);
    return nodes;
}

double estimateForceCapacity(const bags::LoadTestOptions& o) {
    const bags::DoubleWedgeParams& g = o.geometry;
    const double v0 = g.calcFlatVolume();
    const double footprint = std::min(o.blockSize * o.blockSize, g.longSide * g.width);
    const double v1 = v0 - footprint * g.height;
    if (!(v1 > 0.05 * v0)) return INFINITY;
    double mMax = 0.0;
    for (double m : o.gasMasses) mMax = std::max(mMax, m);
    const double n = o.gas.process == bags::GasOptions::Process::Isothermal ? 1.0
                     : o.gas.process == bags::GasOptions::Process::Adiabatic
                         ? o.gas.gamma
                         : o.gas.polytropicIndex;
    const double p0 = mMax * o.gas.getSpecificGasConstant() * o.gas.temperature / v0;
    const double p1 = p0 * std::pow(v0 / v1, n);
    return std::max(0.0, p1 - o.gas.ambientPressure) * g.longSide * g.width;
}

double calcMostPlausibleGasMass(const bags::DoubleWedgeParams& g, const bags::GasOptions& gas) {
    return (gas.ambientPressure + 1e6) * g.calcFlatVolume() /
           (gas.getSpecificGasConstant() * gas.temperature);
}

std::string describeTooMuchGas(double mass, double most) {
    return fmt(toUnit(mass, "g")) +
           " g is more gas than this bag can hold: it would fill its "
           "unstretched volume at over 1 MPa gauge (a film bag bursts far below; the seed's is "
           "at about 20 kPa with 4.5 g); valid: at most " +
           fmt(std::floor(toUnit(most, "g") * 10) / 10) + " g";
}

std::vector<std::string> getScenarioKinds() {
    return {kKind, "patient-on-support", "patient-on-array"};
}

std::string readScenarioKind(const ScenarioFile& file) {
    const ScenarioNode root = file.getRoot();
    if (!root.has("kind"))
        root.fail("missing required key 'kind' at the top of the scenario; valid kinds: " +
                  std::string(kKind) + ", patient-on-support, patient-on-array");
    return root.getChoice("kind", getScenarioKinds());
}

bags::FillScaleResult applyBagSizing(LoadTestScenario& sc) {
    bags::FillScaleResult fs;
    fs.geometry = sc.options.geometry;
    if (sc.fillMass > 0.0) {
        fs = bags::findFillScale(sc.options, sc.fillMass, sc.fillScaling);
        sc.options.geometry = fs.geometry;
        sc.fillMass = 0.0;
    }
    if (sc.volumeChange != 0.0) {
        bags::changeBagVolume(sc.options, sc.volumeChange);
        sc.volumeChange = 0.0;
    }
    return fs;
}

LoadTestScenario readLoadTestScenario(const ScenarioFile& file) {
    const ScenarioNode root = file.getRoot();
    // bagsim fit-material prints "material: {model: ..., C10: ...}": its keys belong here.
    if (root.has("material"))
        root.fail("material",
                  "the material's model and constants go in the membrane section, "
                  "beside the thickness: membrane: {model: yeoh, C10: 31.6 MPa, "
                  "C20: ..., C30: ..., thickness: 0.2 mm}");
    root.checkKeys({"kind", "airbag", "membrane", "test"},
                   {"name", "description", "gas", "contact", "solver", "output", "rig"});
    root.getChoice("kind", {kKind});

    LoadTestScenario sc;
    sc.name = root.getString("name", file.getStem());
    checkScenarioName(root, sc.name);
    sc.description = root.getString("description", "");

    bags::LoadTestOptions& o = sc.options;
    readAirbag(root.getSection("airbag"), o);
    readMembrane(root.getSection("membrane"), o);
    readGas(root.getSection("gas", false), o.gas);
    readFillMass(root.getSection("airbag"), sc);
    readTest(root.getSection("test"), o);
    readContact(root.getSection("contact", false), o);
    readSolver(root.getSection("solver", false), o);
    readOutput(root.getSection("output", false), sc.output);
    readRig(root.getSection("rig", false), sc.rig);
    if (sc.rig.flowmeterOffset != 0.0) {
        // test.gas_masses are the flowmeter's readings: the bag holds them less its offset.
        try {
            o.gasMasses = diagnose::calcBagGasMasses(o.gasMasses, sc.rig);
        } catch (const std::invalid_argument& e) {
            root.getSection("rig").getSection("flowmeter").fail("offset", e.what());
        }
    }

    // The libraries' own checks (impossible geometry and the like) as located errors.
    try {
        o.geometry.validate();
    } catch (const std::invalid_argument& e) {
        failFromLibrary(root.getSection("airbag"), e.what());
    }
    try {
        o.validate();
    } catch (const std::invalid_argument& e) {
        failFromLibrary(root, e.what());
    }
    checkLimits(root, o);
    return sc;
}

bags::AirbagSpec::Stepping readStepping(const ScenarioNode& s, bags::AirbagSpec::Stepping current) {
    using S = bags::AirbagSpec::Stepping;
    if (s.has("stepping")) {
        const std::string c = s.getChoice("stepping", {"quasi-static", "dynamic", "relaxed"});
        current = c == "dynamic" ? S::Dynamic : c == "relaxed" ? S::Relaxed : S::QuasiStatic;
    }
    if (s.has("dynamic") && current == S::QuasiStatic)
        s.fail("dynamic",
               "these settings of the film in time need 'stepping: dynamic' or "
               "'stepping: relaxed' beside them");
    return current;
}

}  // namespace io
