// The shipped pneumatic scenarios (and scripts/demo's turn-quick) end to end at a coarse setting (30 mm meshes, settled 0.1 s,
// run 0.1 s, frictionless: about 15-35 s each on the shared machine, where the turns' friction
// of 0.4 took the first one to 140 s): each runs to the end, its controller
// acts at the end of the settle (events.csv), and the gas moves the way it should: the turn's
// inflated side gains and its vented side loses, the alternating cycle's odd rows gain while
// its even rows lose; the three builds are the ones asked for (summary.txt); the turns' zones
// are held as he lands (the centre column vented back to the setpoint, events.csv).
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>

#include "ArrayRunTestUtil.h"

using namespace app::test;

namespace {

struct Case {
    const char* scenario;
    const char* firstEvent;  // the controller's first event starts with this
    const char* patient;     // in summary.txt ("" : not checked)
    // An event the zones' hold must make as he lands ("" : not checked): the centre column's
    // bags, pressed above the setpoint's band, are vented by the turn controller's hold.
    const char* held;
    // which bags gain (+1) and lose (-1) by the end, by row and column
    int (*side)(int row, int column);
};

// gtest names the case by its scenario (not its bytes).
void PrintTo(const Case& c, std::ostream* os) { *os << c.scenario; }

// The turns' zones are held at the setpoint from his release (control.pressure).
constexpr const char* kCentreHeld = "zone held: channel 'centre' venting";

int rightGains(int, int c) { return c >= 4 ? 1 : c <= 2 ? -1 : 0; }
int leftGains(int, int c) { return c <= 2 ? 1 : c >= 4 ? -1 : 0; }
int oddRowsGain(int r, int) { return r % 2 ? 1 : -1; }

int runShipped(const std::string& scenario, const std::filesystem::path& out) {
    std::filesystem::remove_all(out);
    const std::string cmd = std::string("\"") + BAGSIM_BINARY_DIR + "/bin/bagsim\" run \"" +
                            BAGSIM_SOURCE_DIR + "/scenarios/" + scenario + ".yaml\" --out \"" +
                            out.string() +
                            "\" --quiet --set bag.mesh_size='30 mm' --set run.settle_time='0.1 s' "
                            "--set run.duration='0.1 s' --set output.every='50 ms' "
                            "--set bag.body_friction=0 > \"" +
                            out.string() + ".log\" 2>&1";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

class ShippedScenario : public testing::TestWithParam<Case> {};

}  // namespace

TEST_P(ShippedScenario, RunsCoarseAndMovesTheGasTheWayItShould) {
    const Case c = GetParam();
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/shipped" / c.scenario;
    std::filesystem::create_directories(out.parent_path());
    ASSERT_EQ(runShipped(c.scenario, out), 0) << "see " << out.string() << ".log";
    EXPECT_FALSE(std::filesystem::exists(out / "INCOMPLETE"));
    const Csv events = readCsv(out / "events.csv");
    bool acted = false;
    for (const auto& r : events.rows) acted = acted || r.at(1).rfind(c.firstEvent, 0) == 0;
    EXPECT_TRUE(acted) << c.firstEvent;
    if (*c.held) {
        bool held = false;
        for (const auto& r : events.rows) held = held || r.at(1).rfind(c.held, 0) == 0;
        EXPECT_TRUE(held) << c.held;
    }
    if (*c.patient) {
        std::ifstream summary(out / "summary.txt");
        std::string text((std::istreambuf_iterator<char>(summary)),
                         std::istreambuf_iterator<char>());
        EXPECT_NE(text.find(c.patient), std::string::npos) << text;
    }
    // The gas a side holds (its bags share their air through their line, so a pressed bag
    // may give some to the others of its side): the filled side gains, the vented side loses
    // from what it was filled with; a bag in no channel keeps its fill.
    const Csv bags = readCsv(out / "bags.csv");
    const int mass = bags.column("mass_g"), bag = bags.column("bag");
    const double tEnd = std::stod(bags.rows.back().at(0));
    std::map<int, double> fill;  // each bag's gas at the first output
    for (const auto& r : bags.rows) fill.emplace(std::stoi(r.at(bag)), std::stod(r.at(mass)));
    double gained = 0.0, lost = 0.0;
    int moved = 0;
    for (const auto& r : bags.rows) {
        if (std::stod(r.at(0)) < tEnd - 1e-9) continue;
        const int b = std::stoi(r.at(bag));
        const int way = c.side(b / 7, b % 7);
        const double dm = std::stod(r.at(mass)) - fill.at(b);
        if (way > 0) gained += dm;
        if (way < 0) lost -= dm;
        // (way 0: the centre column, held at the setpoint as he lands: it vents.)
        moved += way != 0;
    }
    EXPECT_GT(gained, 0.01);
    EXPECT_GT(lost, 0.01);
    EXPECT_GE(moved, 30);
}

INSTANTIATE_TEST_SUITE_P(
    Pneumatic, ShippedScenario,
    testing::Values(Case{"turn-left-pneumatic", "turn started", "", kCentreHeld, rightGains},
                    Case{"turn-right-pneumatic", "turn started", "", kCentreHeld, leftGains},
                    Case{"turn-quick", "turn started", "", kCentreHeld, rightGains},
                    Case{"alternating-pressure", "schedule: channel 'odd-rows' inflate open", "",
                         "", oddRowsGain},
                    Case{"turn-left-pneumatic-small-woman", "turn started",
                         "small light woman (1.55 m, 50 kg", kCentreHeld, rightGains},
                    Case{"turn-left-pneumatic-tall-man", "turn started",
                         "tall heavy man (1.90 m, 110 kg", kCentreHeld, rightGains},
                    Case{"turn-left-pneumatic-high-bmi", "turn started",
                         "high-BMI patient (1.65 m, 120 kg", kCentreHeld, rightGains}),
    [](const testing::TestParamInfo<Case>& i) {
        std::string n = i.param.scenario;
        for (char& ch : n)
            if (ch == '-') ch = '_';
        return n;
    });
