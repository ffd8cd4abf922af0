// io::compareRuns (bagsim compare): a run's tilt and region patch peaks against a reference's,
// on small hand-made results folders whose figures are worked out by hand below.
#include <io/RunComparison.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "InputErrorTestUtil.h"

namespace {

namespace fs = std::filesystem;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kMmHg = 133.322387415;

fs::path makeRun(const std::string& name, const std::string& tilt, const std::string& regions) {
    const fs::path d = fs::temp_directory_path() / ("bagsim-run-comparison-" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    std::ofstream(d / "tilt.csv") << "time_s,pelvis_tilt_deg,thorax_tilt_deg\n" << tilt;
    std::ofstream(d / "regions.csv")
        << "time_s,region,ppi_mmHg,mean_mmHg,area_cm2,force_N,patch_peak_mmHg\n"
        << regions;
    return d;
}

const char* kRefTilt = "0.0000,0,0\n0.1000,1.0,2.0\n0.2000,3.0,4.0\n0.3000,5.0,6.0\n";
const char* kRefRegions =
    "0.1000,heel_r,0,0,0,20.0,100.0\n0.1000,head,0,0,0,30.0,50.0\n0.1000,hand_l,0,0,0,5.0,80.0\n"
    "0.2000,heel_r,0,0,0,20.0,100.0\n0.2000,head,0,0,0,30.0,50.0\n";

TEST(RunComparison, TiltAndRegionPeaksAreJudgedAsWorkedOutByHand) {
    const fs::path ref = makeRun("ref", kRefTilt, kRefRegions);
    // The run lacks the 0.3 s row; pelvis differences 0, +1, +2.5 deg; thorax 0, -0.5, 0 deg.
    // Regions: at 0.1 s heel +10 %, head -20 % (hand_l below 10 N in the reference: not
    // judged); at 0.2 s the heel +30 %, the head not loaded by the run (-100 %).
    const fs::path run = makeRun("run", "0.0000,0,0\n0.1000,2.0,1.5\n0.2000,5.5,4.0\n",
                                 "0.1000,heel_r,0,0,0,1,110.0\n0.1000,head,0,0,0,1,40.0\n"
                                 "0.1000,hand_l,0,0,0,1,1.0\n0.2000,heel_r,0,0,0,1,130.0\n");
    io::RunComparisonOptions opt;
    opt.from = 0.05;
    const io::RunComparison c = io::compareRuns(ref, run, opt);
    EXPECT_EQ(c.referenceTiltRows, 3);
    EXPECT_EQ(c.tiltRows, 2);
    EXPECT_DOUBLE_EQ(c.firstTime, 0.1);
    EXPECT_DOUBLE_EQ(c.lastTime, 0.2);
    EXPECT_NEAR(c.pelvis.largest, 2.5 * kDeg, 1e-12);
    EXPECT_DOUBLE_EQ(c.pelvis.largestTime, 0.2);
    EXPECT_NEAR(c.pelvis.rms, std::sqrt((1.0 + 6.25) / 2) * kDeg, 1e-12);
    EXPECT_NEAR(c.thorax.largest, -0.5 * kDeg, 1e-12);
    EXPECT_NEAR(c.thorax.rms, std::sqrt(0.25 / 2) * kDeg, 1e-12);
    EXPECT_EQ(c.tiltRowsWithin, 1);  // 0.2 s: the pelvis 2.5 deg off
    // The turn alone, less each run's own tilt at 0.1 s (run 2.0 / 1.5, reference 1.0 / 2.0):
    // pelvis differences 0, +1.5 deg; thorax 0, +0.5 deg.
    EXPECT_NEAR(c.pelvisSinceFirst.largest, 1.5 * kDeg, 1e-12);
    EXPECT_DOUBLE_EQ(c.pelvisSinceFirst.largestTime, 0.2);
    EXPECT_NEAR(c.pelvisSinceFirst.rms, std::sqrt(2.25 / 2) * kDeg, 1e-12);
    EXPECT_NEAR(c.thoraxSinceFirst.largest, 0.5 * kDeg, 1e-12);
    EXPECT_NEAR(c.thoraxSinceFirst.rms, std::sqrt(0.25 / 2) * kDeg, 1e-12);
    EXPECT_EQ(c.tiltRowsWithinSinceFirst, 2);
    ASSERT_EQ(c.peaks.size(), 4u);
    ASSERT_EQ(c.moments.size(), 2u);
    EXPECT_EQ(c.moments[0].regions, 2);
    EXPECT_NEAR(c.moments[0].mean, (0.1 - 0.2) / 2, 1e-12);
    EXPECT_NEAR(c.moments[0].rms, std::sqrt((0.01 + 0.04) / 2), 1e-12);
    EXPECT_EQ(c.moments[0].within, 1);
    EXPECT_NEAR(c.moments[1].mean, (0.3 - 1.0) / 2, 1e-12);
    EXPECT_EQ(c.moments[1].within, 0);
    EXPECT_EQ(c.overall.regions, 4);
    EXPECT_NEAR(c.overall.rms, std::sqrt((0.01 + 0.04 + 0.09 + 1.0) / 4), 1e-12);
    EXPECT_EQ(c.overall.within, 1);
    EXPECT_NEAR(c.peaks[0].reference, 50.0 * kMmHg, 1e-9);  // head, by name within a moment
    EXPECT_FALSE(c.meetsTargets());
    // Asked-for moments: 0.3 s is not in the run's regions.csv.
    opt.times = {0.2, 0.3};
    const io::RunComparison d = io::compareRuns(ref, run, opt);
    EXPECT_EQ(d.overall.regions, 2);
    ASSERT_EQ(d.missingTimes.size(), 1u);
    EXPECT_DOUBLE_EQ(d.missingTimes[0], 0.3);
    const std::string text = io::formatRunComparison(d, true);
    EXPECT_NE(text.find("0.3 s: not an output time of both runs (their tilt.csv)"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("misses the targets"), std::string::npos);
    EXPECT_NE(io::formatRegionPeaksCsv(d).find("0.2000,heel_r,20.000,100.000,130.000,30.00,0\n"),
              std::string::npos);
    EXPECT_EQ(text.find("incomplete run"), std::string::npos);
    // An unfinished run (its INCOMPLETE marker) is compared as far as it went but its last
    // row (0.2 s: it may be half-written), and said so.
    std::ofstream(run / "INCOMPLETE") << "This folder's results are incomplete.\nstatus: running\n";
    opt.times.clear();
    const io::RunComparison e = io::compareRuns(ref, run, opt);
    EXPECT_EQ(e.runIncomplete, "running");
    EXPECT_EQ(e.referenceIncomplete, "");
    EXPECT_EQ(e.tiltRows, 1);
    EXPECT_EQ(e.overall.regions, 2);
    EXPECT_NE(io::formatRunComparison(e, false).find(
                  "NOTE: the run is an incomplete run (its INCOMPLETE marker: status running)"),
              std::string::npos);
}

TEST(RunComparison, APartialComparisonIsNotJudgedAsMeetingTheTargets) {
    const fs::path ref = makeRun("whole-ref", kRefTilt, kRefRegions);
    // A run equal to the reference as far as it went, stopped after 0.1 s.
    const fs::path cut = makeRun("cut", "0.0000,0,0\n0.1000,1.0,2.0\n",
                                 "0.1000,heel_r,0,0,0,20.0,100.0\n0.1000,head,0,0,0,30.0,50.0\n");
    const io::RunComparison c = io::compareRuns(ref, cut, io::RunComparisonOptions());
    EXPECT_EQ(c.tiltRowsWithin, c.tiltRows);
    EXPECT_EQ(c.overall.within, c.overall.regions);
    EXPECT_FALSE(c.meetsTargets());
    ASSERT_EQ(c.whyNotJudged().size(), 1u);
    EXPECT_EQ(c.whyNotJudged()[0], "the run lacks 2 of the reference's 4 tilt rows");
    EXPECT_NE(io::formatRunComparison(c, false).find("not judged: within the targets where "
                                                     "compared, but the run lacks 2"),
              std::string::npos);
    // The same run unfinished: also not judged, even where its rows are whole.
    std::ofstream(cut / "INCOMPLETE") << "status: running\n";
    EXPECT_FALSE(io::compareRuns(ref, cut, io::RunComparisonOptions()).meetsTargets());
    // A run that loads no region at 0.2 s (lifted off): its tilt row is there, its regions.csv
    // has none; the reference's loaded regions count -100 % then, not skipped.
    const fs::path lifted = makeRun(
        "lifted", kRefTilt, "0.1000,heel_r,0,0,0,20.0,100.0\n0.1000,head,0,0,0,30.0,50.0\n");
    const io::RunComparison d = io::compareRuns(ref, lifted, io::RunComparisonOptions());
    ASSERT_EQ(d.moments.size(), 2u);
    EXPECT_EQ(d.moments[1].regions, 2);
    EXPECT_NEAR(d.moments[1].mean, -1.0, 1e-12);
    EXPECT_EQ(d.overall.within, 2);
    EXPECT_FALSE(d.meetsTargets());
    // Nothing judged (the reference loads no region of 10 N): not judged either.
    const fs::path light = makeRun("light", kRefTilt, "0.1000,hand_l,0,0,0,5.0,80.0\n");
    const io::RunComparison e = io::compareRuns(light, light, io::RunComparisonOptions());
    EXPECT_FALSE(e.meetsTargets());
    EXPECT_EQ(e.whyNotJudged().back(), "no region was judged");
    // Repeated and unsorted moments are judged once each, in time order.
    io::RunComparisonOptions opt;
    opt.times = {0.2, 0.1, 0.2};
    const io::RunComparison f = io::compareRuns(ref, ref, opt);
    ASSERT_EQ(f.moments.size(), 2u);
    EXPECT_DOUBLE_EQ(f.moments[0].time, 0.1);
    EXPECT_EQ(f.overall.regions, 4);
}

TEST(RunComparison, ARunAgainstItselfMeetsTheTargets) {
    const fs::path ref = makeRun("self", kRefTilt, kRefRegions);
    const io::RunComparison c = io::compareRuns(ref, ref, io::RunComparisonOptions());
    EXPECT_EQ(c.tiltRows, 4);
    EXPECT_EQ(c.tiltRowsWithin, 4);
    EXPECT_EQ(c.overall.regions, 4);
    EXPECT_EQ(c.overall.within, 4);
    EXPECT_TRUE(c.meetsTargets());
}

TEST(RunComparison, BadFoldersAreNamedWithFileLineAndColumn) {
    const fs::path ref = makeRun("bad-ref", kRefTilt, kRefRegions);
    // regions.csv of a run before the patch peak was written.
    const fs::path old = makeRun("old", kRefTilt, "");
    std::ofstream(old / "regions.csv") << "time_s,region,ppi_mmHg,mean_mmHg,area_cm2,force_N\n";
    io::InputError e =
        io::test::expectInputError([&] { io::compareRuns(ref, old, io::RunComparisonOptions()); });
    EXPECT_NE(e.getWhere().find("regions.csv"), std::string::npos);
    EXPECT_NE(e.getMessage().find("no column 'patch_peak_mmHg'"), std::string::npos)
        << e.getMessage();
    // A cell that is not a number: its line and column.
    const fs::path nan = makeRun("nan", "0.0000,0,0\n0.1000,abc,0\n", kRefRegions);
    e = io::test::expectInputError([&] { io::compareRuns(ref, nan, io::RunComparisonOptions()); });
    EXPECT_NE(e.getWhere().find("tilt.csv"), std::string::npos);
    EXPECT_EQ(e.getLine(), 3);
    // No row in common.
    const fs::path later = makeRun("later", "5.0000,0,0\n", kRefRegions);
    e = io::test::expectInputError(
        [&] { io::compareRuns(ref, later, io::RunComparisonOptions()); });
    EXPECT_NE(e.getMessage().find("no row at a time of"), std::string::npos) << e.getMessage();
    // Not a folder.
    e = io::test::expectInputError(
        [&] { io::compareRuns(ref, ref / "nowhere", io::RunComparisonOptions()); });
    EXPECT_NE(e.getMessage().find("is not a folder"), std::string::npos);
}

}  // namespace
