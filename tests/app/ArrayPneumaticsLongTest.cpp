// bagsim run of the coarse pneumatic turn in full (label manual: about 15-30 minutes on the
// shared machine): settled 1.5 s, turned by the valves to a pelvis tilt of 12 deg onto his
// left side (what these wedges reach; 30 deg is beyond them: docs/pneumatics.md), held 0.5 s,
// and brought back to the initial masses. Bag and network masses agree to roundoff over the
// whole run; the events run through the whole sequence; the target is reached, he comes back
// near level (pelvis within 5 deg at the end) and stays on the middle of the array (his
// centre of mass within one column pitch of where it was, the verdict's travel check ok).
#include <cmath>
#include <filesystem>
#include <fstream>

#include "ArrayRunTestUtil.h"

using namespace app::test;

TEST(ArrayPneumaticsRun, TheCoarseTurnRunsItsSequenceAndComesBack) {
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-pneumatics-turn";
    ASSERT_EQ(runScenario("turn-left-pneumatic-coarse.yaml", out), 0);
    std::ifstream summary(out / "summary.txt");
    std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
    const size_t at = text.find("gas masses of bag and network agree to ");
    ASSERT_NE(at, std::string::npos) << text;
    EXPECT_LT(std::stod(text.substr(at + 39)), 1e-12);
    const size_t turned = text.find("the turn ended at pelvis tilt ");
    ASSERT_NE(turned, std::string::npos) << text;
    EXPECT_GT(std::stod(text.substr(turned + 30)), 11.9);  // degrees onto his left side
    const Csv events = readCsv(out / "events.csv");
    bool reached = false, gaveUp = false, hold = false, back = false;
    for (const auto& r : events.rows) {
        reached = reached || r.at(1).rfind("target tilt reached", 0) == 0;
        gaveUp = gaveUp || r.at(1).rfind("target tilt not reached", 0) == 0;
        hold = hold || r.at(1) == "hold ended";
        back = back || r.at(1).rfind("back to supine", 0) == 0;
    }
    EXPECT_TRUE(reached);
    EXPECT_FALSE(gaveUp);
    EXPECT_TRUE(hold);
    EXPECT_TRUE(back);
    const Csv verdict = readCsv(out / "verdict.csv");
    for (const auto& r : verdict.rows) {
        if (r.at(0) == "target tilt reached") {
            EXPECT_EQ(r.at(1), "ok");
        }
        if (r.at(0) == "back to supine") {
            EXPECT_EQ(r.at(1), "ok");
        }
        if (r.at(0) == "slid or rolled toward the edge") {
            EXPECT_EQ(r.at(1), "ok") << r.at(4);
        }
        if (r.at(0) == "fell through or off the bags") {
            EXPECT_EQ(r.at(1), "ok") << r.at(4);
        }
    }
    // Back near level at the end.
    const Csv tilt = readCsv(out / "tilt.csv");
    ASSERT_FALSE(tilt.rows.empty());
    EXPECT_LT(std::abs(std::stod(tilt.rows.back().at(1))), 5.0);
}
