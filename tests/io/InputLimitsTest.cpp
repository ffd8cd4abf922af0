// Inputs that would exhaust memory or time are refused before anything runs, with the file,
// line, key and the limit named: a mesh too fine for its airbag, too many gas masses or steps,
// a peak force far beyond what the bag can carry, and input files that are too large or are
// not regular files (a pipe would block the reader forever).
#include <bags/Geometry.h>
#include <gtest/gtest.h>
#include <io/LoadTestScenario.h>
#include <io/Scenario.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "InputErrorTestUtil.h"

using io::InputError;
using io::ScenarioFile;
using io::test::expectInputError;

namespace fs = std::filesystem;

namespace {

// A valid scenario (the seed's bag, 10 mm mesh by default); tests append or replace keys.
std::string makeScenario(const std::string& airbagExtra, const std::string& testExtra) {
    return "kind: seed-load-test\n"  // 1
           "airbag:\n"               // 2
           "  long_side: 350 mm\n"   // 3
           "  short_side: 200 mm\n"  // 4
           "  width: 100 mm\n"       // 5
           "  height: 150 mm\n" +    // 6
           airbagExtra +             // 7 (if any)
           "membrane: {model: neo-hookean, C10: 30 MPa, thickness: 0.2 mm}\n"
           "test:\n"
           "  polynomial_order: 1\n" +
           testExtra;
}

InputError errorFor(const std::string& text) {
    return expectInputError(
        [&] { io::readLoadTestScenario(ScenarioFile::parse(text, "limits.yaml")); });
}

fs::path makeTestDir(const std::string& name) {
    const fs::path p = fs::path(BAGSIM_BINARY_DIR) / "test-output" / "io" / name;
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
}

}  // namespace

TEST(InputLimits, NodeEstimateIsWithinTenPercentOfTheMesh) {
    bags::DoubleWedgeParams g;  // the seed's bag
    for (bags::MeshPattern pattern :
         {bags::MeshPattern::Legacy, bags::MeshPattern::Mirrored, bags::MeshPattern::Crossed})
        for (double h : {0.025, 0.010, 0.005, 0.0025}) {
            g.meshSize = h;
            g.pattern = pattern;
            const double mesh = bags::makeDoubleWedgeBag(g).getNumNodes();
            EXPECT_NEAR(io::estimateNumNodes(g) / mesh, 1.0, 0.10)
                << bags::getMeshPatternName(pattern) << ", mesh size " << h << " m";
        }
}

TEST(InputLimits, MeshTooFineForTheAirbagNamesTheLimitAndTheSmallestValidSize) {
    // 1 mm on the seed bag: about 150 000 nodes.
    const InputError e =
        errorFor(makeScenario("  mesh_size: 1 mm\n", "  gas_masses: [3 g, 2 g]\n"));
    EXPECT_EQ(e.getWhere(), "limits.yaml");
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "airbag.mesh_size");
    EXPECT_NE(e.getMessage().find("\"1 mm\" gives a mesh of about 150000 nodes"), std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("at most 60000"), std::string::npos) << e.what();
    EXPECT_NE(e.getMessage().find("valid: mesh_size at least 1.6 mm"), std::string::npos)
        << e.what();
    // Just above that size the scenario reads.
    EXPECT_NO_THROW(io::readLoadTestScenario(ScenarioFile::parse(
        makeScenario("  mesh_size: 1.6 mm\n", "  gas_masses: [3 g, 2 g]\n"), "ok.yaml")));
}

TEST(InputLimits, HugeAirbagAtTheDefaultMeshIsRefused) {
    const std::string text =
        "kind: seed-load-test\n"
        "airbag: {long_side: 5 m, short_side: 2 m, width: 3 m, height: 1.5 m}\n"
        "membrane: {model: neo-hookean, C10: 30 MPa, thickness: 0.2 mm}\n"
        "test: {gas_masses: [3 g, 2 g], polynomial_order: 1}\n";
    const InputError e = errorFor(text);
    EXPECT_EQ(e.getKey(), "airbag.mesh_size");
    EXPECT_EQ(e.getLine(), 2);
    EXPECT_NE(e.getMessage().find("the default 10 mm gives a mesh of about"), std::string::npos)
        << e.what();
}

TEST(InputLimits, TooManyGasMassesAreRefused) {
    std::string list = "  gas_masses: [";
    for (int i = 0; i < io::kMaxGasMasses + 1; ++i) list += (i ? ", " : "") + std::string("3 g");
    list += "]\n";
    InputError e = errorFor(makeScenario("", list));
    EXPECT_EQ(e.getKey(), "test.gas_masses");
    EXPECT_EQ(e.getLine(), 10);
    EXPECT_NE(e.getMessage().find("lists 201 gas masses; at most 200"), std::string::npos)
        << e.what();

    e = errorFor(makeScenario("", "  gas_masses: {from: 3.5 g, to: 1 g, step: 0.01 g}\n"));
    EXPECT_EQ(e.getKey(), "test.gas_masses.step");
    EXPECT_NE(e.getMessage().find("\"0.01 g\" gives 251 gas masses; at most 200"),
              std::string::npos)
        << e.what();
}

TEST(InputLimits, TooManyStepsPerBranchAreRefused) {
    // 150 mm in 0.01 mm steps: 15 000 steps.
    const InputError e =
        errorFor(makeScenario("", "  gas_masses: [3 g, 2 g]\n  displacement_step: 0.01 mm\n"));
    EXPECT_EQ(e.getKey(), "test.displacement_step");
    EXPECT_EQ(e.getLine(), 11);
    EXPECT_NE(e.getMessage().find("needs about 15000 steps"), std::string::npos) << e.what();
    EXPECT_NE(e.getMessage().find("valid: at least 0.03 mm"), std::string::npos) << e.what();
}

TEST(InputLimits, PeakForceFarBeyondWhatTheBagCarriesIsRefused) {
    // 3.5 g squeezed under the 50 mm block reaches about 32 kPa: about 1.1 kN over the base.
    bags::LoadTestOptions o;
    o.gasMasses = {3.5e-3, 2e-3};
    EXPECT_NEAR(io::estimateForceCapacity(o), 1110.0, 20.0);

    const InputError e =
        errorFor(makeScenario("", "  gas_masses: [3.5 g, 2 g]\n  peak_force: 1e6 N\n"));
    EXPECT_EQ(e.getKey(), "test.peak_force");
    EXPECT_EQ(e.getLine(), 11);
    EXPECT_NE(e.getMessage().find("\"1e6 N\" is far beyond what this bag can carry"),
              std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("valid: at most 11"), std::string::npos) << e.what();
    // The seed's 50 N, and a large but conceivable 2 kN, read.
    EXPECT_NO_THROW(io::readLoadTestScenario(ScenarioFile::parse(
        makeScenario("", "  gas_masses: [3.5 g, 2 g]\n  peak_force: 2 kN\n"), "ok.yaml")));
    // A bag at ambient pressure (1 g never pressurises here) may still be loaded up to one
    // atmosphere over its base (3.5 kN): it bottoms out, a physical outcome.
    EXPECT_NO_THROW(io::readLoadTestScenario(ScenarioFile::parse(
        makeScenario("", "  gas_masses: [1 g]\n  peak_force: 50 N\n"), "slack.yaml")));
}

TEST(InputLimits, ScenarioFileMustBeARegularFileOfAtMostOneMebibyte) {
    const fs::path dir = makeTestDir("limits");
    // Too large: refused before parsing, with the limit.
    const fs::path big = dir / "big.yaml";
    {
        std::ofstream out(big);
        out << "kind: seed-load-test\n# " << std::string(io::kMaxScenarioBytes, 'x') << "\n";
    }
    InputError e = expectInputError([&] { ScenarioFile::load(big.string()); });
    EXPECT_EQ(e.getWhere(), big.string());
    EXPECT_NE(e.getMessage().find("bytes; a scenario file may be at most 1.0 MiB (1048576 bytes)"),
              std::string::npos)
        << e.what();
    // A pipe would block the reader: refused without opening it.
    const fs::path fifo = dir / "pipe.yaml";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    e = expectInputError([&] { ScenarioFile::load(fifo.string()); });
    EXPECT_NE(e.getMessage().find("is not a regular file (a pipe, socket or device)"),
              std::string::npos)
        << e.what();
    e = expectInputError([&] { ScenarioFile::load("/dev/zero"); });
    EXPECT_NE(e.getMessage().find("is not a regular file"), std::string::npos) << e.what();
    e = expectInputError([&] { ScenarioFile::load((dir / "missing.yaml").string()); });
    EXPECT_NE(e.getMessage().find("cannot read the scenario file (No such file"), std::string::npos)
        << e.what();
    // The limit itself is inclusive.
    const fs::path edge = dir / "edge.txt";
    {
        std::ofstream out(edge);
        out << std::string(1000, 'y');
    }
    EXPECT_EQ(io::readInputFile(edge.string(), 1000, "test file").size(), 1000u);
    e = expectInputError([&] { io::readInputFile(edge.string(), 999, "test file"); });
    EXPECT_NE(e.getMessage().find("is 1000 bytes; a test file may be at most 1 kiB (999 bytes)"),
              std::string::npos)
        << e.what();
}
