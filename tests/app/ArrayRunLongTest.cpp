// bagsim run on the coarse variants of the shipped patient-on-array scenarios, end to end
// (label long: minutes each on the shared 2-core machine).
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "ArrayRunTestUtil.h"

using namespace app::test;

namespace {

const double kWeight = 75.0 * 9.80665;  // [N] the scenarios' 75 kg man

// Mean of a per-time series over the times in [from, to].
double meanOver(const std::map<double, double>& s, double from, double to) {
    double sum = 0.0;
    int n = 0;
    for (const auto& [t, v] : s)
        if (t >= from - 1e-9 && t <= to + 1e-9) {
            sum += v;
            ++n;
        }
    return n ? sum / n : NAN;
}

}  // namespace

TEST(ArrayRunLong, TheCoarseSupineManSettlesAndTheBagsCarryHisWeight) {
    // Reference: his weight m g. Over the last 0.3 s of the settle the bags' vertical force
    // (bags.csv) averages it within 0.5 % (the check); at every output time the
    // regions' forces (regions.csv) add up to the bags' within 0.1 %; he stays supine (pelvis
    // and thorax within 5 deg of level).
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-supine";
    ASSERT_EQ(runScenario("supine-on-array-coarse.yaml", out), 0);
    const Csv bags = readCsv(out / "bags.csv");
    const Csv regions = readCsv(out / "regions.csv");
    const auto bagSum = sumPerTime(bags, "force_N");
    const double end = bagSum.rbegin()->first;
    const double carried = meanOver(bagSum, end - 0.3, end);
    std::printf("bags carry %.3f N of %.3f N on average over the last 0.3 s (%+.3f %%)\n", carried,
                kWeight, 100.0 * (carried - kWeight) / kWeight);
    EXPECT_NEAR(carried, kWeight, 0.005 * kWeight);
    for (const auto& [t, f] : sumPerTime(regions, "force_N"))
        EXPECT_NEAR(f, bagSum.at(t), 1e-3 * bagSum.at(t) + 1e-3) << "at " << t << " s";
    const Csv tilt = readCsv(out / "tilt.csv");
    for (int c : {1, 2}) EXPECT_LT(std::abs(std::stod(tilt.rows.back().at(c))), 5.0);
}

TEST(ArrayRunLong, TheCoarseTurnTiltsHimOntoHisLeftSide) {
    // The bags under his right side (y > 0) filled, those under his left let down, over 3 s
    // after a 1.5 s settle. Reference: the tilt's sign convention (positive: onto his left
    // side, cosim::calcSegmentTilt, tested on the body's tilt-left-30 posture). His pelvis and
    // thorax turn left by more than 2 deg from where the settle left them; the bags reach their
    // target masses.
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-turn";
    ASSERT_EQ(runScenario("turn-left-coarse.yaml", out), 0);
    const Csv tilt = readCsv(out / "tilt.csv");
    double pelvis0 = NAN, thorax0 = NAN;
    for (const auto& r : tilt.rows)
        if (std::abs(std::stod(r.at(0)) - 1.5) < 1e-6) {
            pelvis0 = std::stod(r.at(1));
            thorax0 = std::stod(r.at(2));
        }
    ASSERT_TRUE(std::isfinite(pelvis0));
    const double pelvis = std::stod(tilt.rows.back().at(1)),
                 thorax = std::stod(tilt.rows.back().at(2));
    std::printf("tilt after the settle: pelvis %+.2f deg, thorax %+.2f deg; after the turn: "
                "pelvis %+.2f deg, thorax %+.2f deg\n",
                pelvis0, thorax0, pelvis, thorax);
    EXPECT_GT(pelvis - pelvis0, 2.0);
    EXPECT_GT(thorax - thorax0, 2.0);
    const Csv bags = readCsv(out / "bags.csv");
    const double last = std::stod(bags.rows.back().at(0));
    double lo = 1e9, hi = 0.0;
    for (const auto& r : bags.rows)
        if (std::stod(r.at(0)) == last) {
            lo = std::min(lo, std::stod(r.at(2)));
            hi = std::max(hi, std::stod(r.at(2)));
        }
    EXPECT_NEAR(lo, 3.0, 1e-3);
    EXPECT_NEAR(hi, 6.0, 1e-3);
}
