// bagsim run --resume with neighbouring bags grouped into modules (array.neighbour_contact,
// docs/cosim.md#contact-between-neighbouring-bags): the coarse settle stopped as by Ctrl-C and
// resumed from its checkpoint writes every CSV file byte for byte as the run never stopped.
// Label long: the modules of seven coarse bags take minutes to inflate on the shared machine.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

const std::string kBagsim = std::string("\"") + BAGSIM_BINARY_DIR + "/bin/bagsim\"";
const std::string kScenarios = std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/";

int runBagsim(const std::string& args, const fs::path& log) {
    const std::string cmd = kBagsim + " run " + args + " > \"" + log.string() + "\" 2>&1";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string readFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string readLog(const fs::path& p) { return readFile(p); }

void expectSameCsvFiles(const fs::path& whole, const fs::path& resumed) {
    int compared = 0;
    for (const auto& e : fs::directory_iterator(whole)) {
        if (e.path().extension() != ".csv") continue;
        EXPECT_EQ(readFile(e.path()), readFile(resumed / e.path().filename()))
            << e.path().filename();
        ++compared;
    }
    EXPECT_GE(compared, 7);
}

}  // namespace

TEST(Resume, NeighbourModulesStoppedAndResumedEndByteIdentical) {
    // The coarse settle with neighbouring bags grouped into modules (array.neighbour_contact):
    // the checkpoint holds the modules; resumed, every CSV file
    // (bags.csv's overlap_mm included) is the never-stopped run's, byte for byte.
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "tests/app/resume/neighbours";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string scenario = "\"" + kScenarios + "supine-on-array-coarse.yaml\"";
    const std::string sets =
        " --set array.neighbour_contact=true --set run.settle_time='0.06 s'"
        " --set output.checkpoint_every='0.03 s' --quiet";
    ASSERT_EQ(runBagsim(scenario + " --out \"" + (dir / "whole").string() + "\"" + sets,
                        dir / "whole.log"),
              0)
        << readLog(dir / "whole.log");
    const fs::path out = dir / "stopped";
    ASSERT_EQ(
        runBagsim(scenario + " --out \"" + out.string() + "\"" + sets + " --stop-after '0.04 s'",
                  dir / "stopped.log"),
        130)
        << readLog(dir / "stopped.log");
    ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
    ASSERT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "resumed.log"), 0)
        << readLog(dir / "resumed.log");
    EXPECT_FALSE(fs::exists(out / "INCOMPLETE"));
    expectSameCsvFiles(dir / "whole", out);
}
