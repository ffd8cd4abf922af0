// bagsim run of the coarse pneumatic turn in full (label long: minutes to tens of minutes on
// the shared machine): settled 1.5 s, turned by the valves to a pelvis tilt of 30 deg onto his
// left side, held 0.5 s, and brought back to the initial masses; bag and network masses agree
// to roundoff over the whole run, and the verdict says the target tilt was reached.
#include <filesystem>
#include <fstream>

#include "ArrayRunTestUtil.h"

using namespace app::test;

TEST(ArrayPneumaticsRun, TheCoarseTurnReachesThirtyDegreesAndComesBack) {
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-pneumatics-turn";
    ASSERT_EQ(runScenario("turn-left-pneumatic-coarse.yaml", out), 0);
    std::ifstream summary(out / "summary.txt");
    std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
    const size_t at = text.find("gas masses of bag and network agree to ");
    ASSERT_NE(at, std::string::npos) << text;
    EXPECT_LT(std::stod(text.substr(at + 39)), 1e-12);
    const Csv verdict = readCsv(out / "verdict.csv");
    bool reached = false;
    for (const auto& r : verdict.rows)
        if (r.at(0) == "target tilt reached") reached = r.at(1) == "ok";
    EXPECT_TRUE(reached);
    const Csv events = readCsv(out / "events.csv");
    bool hold = false;
    for (const auto& r : events.rows) hold = hold || r.at(1) == "hold ended";
    EXPECT_TRUE(hold);
}
