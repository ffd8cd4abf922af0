// bagsim run with a pneumatics section, end to end and short: the coarse pneumatic turn
// (scenarios/tests/turn-left-pneumatic-coarse.yaml) released, settled 0.15 s and turned for
// 0.15 s. The bags' and the network's gas masses agree to roundoff (one owner: the network's
// flows are given to the bags, never re-synchronised), the right side fills and the left
// vents, every new file has its columns and a row per output time, the events come in order
// and the verdict's statuses are among ok, warning, fail, n/a.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "ArrayRunTestUtil.h"

using namespace app::test;

TEST(ArrayPneumaticsRun, AShortTurnMovesGasThroughTheValvesAndWritesTheNewFiles) {
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-pneumatics-short";
    ASSERT_EQ(runScenario("turn-left-pneumatic-coarse.yaml", out,
                          "--set run.settle_time='0.15 s' --set run.duration='0.15 s' "
                          "--set output.every='50 ms'"),
              0);
    EXPECT_FALSE(std::filesystem::exists(out / "INCOMPLETE"));
    // One owner of the gas: the summary states the largest relative difference.
    std::ifstream summary(out / "summary.txt");
    std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
    const size_t at = text.find("gas masses of bag and network agree to ");
    ASSERT_NE(at, std::string::npos) << text;
    const double mismatch = std::stod(text.substr(at + 39));
    EXPECT_LT(mismatch, 1e-12);
    EXPECT_NE(text.find("support verdict (verdict.csv):"), std::string::npos);

    const Csv tilt = readCsv(out / "tilt.csv");
    const Csv body = readCsv(out / "body.csv");
    const Csv pneu = readCsv(out / "pneumatics.csv");
    const Csv events = readCsv(out / "events.csv");
    const Csv verdict = readCsv(out / "verdict.csv");
    const Csv bags = readCsv(out / "bags.csv");
    EXPECT_EQ(body.header, "time_s,com_x_mm,com_y_mm,com_z_mm");
    EXPECT_EQ(pneu.header, "time_s,bag,sensor_kPa,inflow_g_per_s,outflow_g_per_s");
    EXPECT_EQ(events.header, "time_s,event");
    EXPECT_EQ(verdict.header, "check,status,value,unit,detail");
    EXPECT_EQ(tilt.rows.size(), 7u);  // 0 to 0.3 s every 50 ms
    EXPECT_EQ(body.rows.size(), tilt.rows.size());
    // 34 bags in the network (18 a side, one of each not under him: 17 + 17), every frame.
    EXPECT_EQ(pneu.rows.size(), 34u * tilt.rows.size());
    // His centre of mass lies above the board, near the mid-line.
    for (const auto& r : body.rows) {
        EXPECT_GT(std::stod(r.at(3)), 150.0);
        EXPECT_LT(std::abs(std::stod(r.at(2))), 30.0);
    }
    // The events in order.
    std::vector<std::string> names;
    double last = -1.0;
    for (const auto& r : events.rows) {
        names.push_back(r.at(1));
        EXPECT_GE(std::stod(r.at(0)), last);
        last = std::stod(r.at(0));
    }
    ASSERT_GE(names.size(), 4u);
    EXPECT_EQ(names[0], "released onto the bags");
    EXPECT_EQ(names[1], "settle ended");
    EXPECT_EQ(names[2].rfind("turn started", 0), 0u) << names[2];
    EXPECT_EQ(names.back(), "run ended");
    // The right side (columns 4-6) filled, the left (0-2) vented, the middle column sealed;
    // in pneumatics.csv the right bags flowed in, the left out.
    const int mass = bags.column("mass_g"), bag = bags.column("bag");
    const double tEnd = std::stod(bags.rows.back().at(0));
    for (const auto& r : bags.rows) {
        if (std::stod(r.at(0)) < tEnd - 1e-9) continue;
        const int column = std::stoi(r.at(bag)) % 7;
        const double m = std::stod(r.at(mass));
        if (column >= 4) {
            EXPECT_GT(m, 4.501) << "bag " << r.at(bag);
        }
        if (column <= 2) {
            EXPECT_LT(m, 4.499) << "bag " << r.at(bag);
        }
        if (column == 3) {
            EXPECT_NEAR(m, 4.5, 1e-9) << "bag " << r.at(bag);
        }
    }
    for (const auto& r : pneu.rows) {
        if (std::stod(r.at(0)) < tEnd - 1e-9) continue;
        const int column = std::stoi(r.at(1)) % 7;
        EXPECT_GT(std::stod(r.at(column >= 4 ? 3 : 4)), 0.0) << "bag " << r.at(1);
    }
    const std::set<std::string> statuses = {"ok", "warning", "fail", "n/a"};
    std::set<std::string> checks;
    for (const auto& r : verdict.rows) {
        EXPECT_EQ(statuses.count(r.at(1)), 1u) << r.at(0);
        checks.insert(r.at(0));
    }
    for (const char* c :
         {"target tilt reached", "back to supine", "slid or rolled toward the edge",
          "contact lost at the array edge", "bag bottomed out", "fell through or off the bags"})
        EXPECT_EQ(checks.count(c), 1u) << c;
}
