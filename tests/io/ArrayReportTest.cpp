// report.html of a patient-on-array run (io/ArrayReport.h), made from a synthetic results
// folder written through the run's own writer: its parts (scenario, verdict, mat pictures at
// the key moments with their peaks, time plots, events), an interrupted run's banner, a folder
// without the optional files, nothing fetched from a network, and the located errors for
// folders that are not such results. (tests/io/ReportBrowserTest.cpp renders it in Chromium.)
#include <gtest/gtest.h>
#include <hdf5.h>
#include <io/ArrayReport.h>
#include <io/InputError.h>

#include <regex>
#include <sstream>

#include "SyntheticArrayRun.h"

#include "ReportTestUtil.h"

namespace fs = std::filesystem;

namespace {

fs::path makeDir(const std::string& name) { return io::test::makeReportTestDir(name); }

int count(const std::string& s, const std::string& what) {
    return io::test::countOccurrences(s, what);
}

std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

std::string errorOf(const fs::path& dir) {
    return io::test::reportErrorOf([](const fs::path& d) { return io::formatArrayReportHtml(d); },
                                   dir);
}

}  // namespace

TEST(ArrayReport, ShowsTheScenarioVerdictKeyMomentsAndCurvesOfACompleteRun) {
    const fs::path dir = makeDir("report-complete");
    const io::test::SyntheticRun run = io::test::writeSyntheticRun(dir, true);
    const std::string html = io::formatArrayReportHtml(dir);
    EXPECT_NE(html.find("<h1>synthetic-turn</h1>"), std::string::npos);
    EXPECT_NE(html.find("a synthetic turn to 25 deg and back"), std::string::npos);
    EXPECT_NE(html.find("male, 1.75 m, 75.0 kg, supine"), std::string::npos);
    EXPECT_NE(html.find("2 rows x 3 columns of airbags, 4.50 g of gas each"), std::string::npos);
    EXPECT_NE(html.find("# --set run.settle_time=1.5 s"), std::string::npos);
    EXPECT_EQ(html.find("INCOMPLETE RESULTS"), std::string::npos);
    // The verdict, a colour and a word per status.
    EXPECT_NE(html.find("1 ok, 1 warning, 1 failed"), std::string::npos);
    EXPECT_NE(html.find("<td class='fail'>&#10008; fail</td>"), std::string::npos);
    EXPECT_NE(html.find("bag 0 under the sacrum, 2.1 s to 3.4 s"), std::string::npos);
    // Key moments: the settle's end from events.csv, half the largest tilt, the largest, the end;
    // each picture's peak is the frame's highest sensel.
    auto frameOf = [&](double t) { return size_t(std::lround(t / 0.1)); };
    const std::vector<std::pair<std::string, double>> moments = {{"A. supine at 1.50 s", 1.5},
                                                                 {"B. mid-turn at 2.50 s", 2.5},
                                                                 {"C. turned at 3.50 s", 3.5},
                                                                 {"D. back at 6.00 s", 6.0}};
    for (const auto& [caption, t] : moments) {
        const size_t at = html.find("<b>" + caption + "</b>");
        ASSERT_NE(at, std::string::npos) << caption;
        const std::string peak = "peak <b>" + fmt("%.0f", run.matPeak[frameOf(t)]) + " mmHg</b>";
        EXPECT_EQ(html.find(peak, at), html.find("peak <b>", at)) << caption << ": " << peak;
    }
    EXPECT_EQ(count(html, "class='mat'"), 4);
    EXPECT_EQ(count(html, "class='colourbar'"), 1);
    // Time plots: tilt, centre of mass, bags, pneumatics, one per region; events listed.
    for (const char* title :
         {"Tilt (positive: onto his left side)", "Bag gauge pressure", "Gas in each bag",
          "Pressure sensors", "Net gas flow into each bag", "Centre of mass across the bed",
          "sacrum: highest", "heel_l: highest", "target tilt reached"})
        EXPECT_NE(html.find(title), std::string::npos) << title;
    EXPECT_NE(html.find("column 0 (his left)"), std::string::npos);
    // The charts are drawn on their data's range: the centre of mass moves 37.5 mm to his left.
    const size_t com = html.find("<title>Centre of mass across the bed");
    ASSERT_NE(com, std::string::npos);
    const std::string comChart = html.substr(com, html.find("</svg>", com) - com);
    EXPECT_NE(comChart.find(">-40</text>"), std::string::npos);
    EXPECT_NE(comChart.find(">0</text>"), std::string::npos);
    EXPECT_NE(html.find("synthetic summary"), std::string::npos);
    // Self-contained: nothing to fetch.
    EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*['"]?\s*(https?:)?//)")));
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_EQ(html.find("<link"), std::string::npos);
    EXPECT_EQ(html.find("url(http"), std::string::npos);
    EXPECT_EQ(html.find("@import"), std::string::npos);
}

TEST(ArrayReport, AnInterruptedRunSaysSoAtTheTopAndKeepsWhatWasWritten) {
    const fs::path dir = makeDir("report-interrupted");
    io::test::writeSyntheticRun(dir, false, 2.3);
    const std::string html = io::formatArrayReportHtml(dir);
    const size_t banner = html.find("INCOMPLETE RESULTS");
    ASSERT_NE(banner, std::string::npos);
    EXPECT_LT(banner, html.find("<h2>Scenario"));
    EXPECT_NE(html.find("status <b>interrupted</b>"), std::string::npos);
    EXPECT_NE(html.find("stops at 2.30 s of the 6.00 s planned"), std::string::npos);
    // Without events.csv the settle's end comes from the scenario (1.5 s); the turn had not
    // come back, so the last picture is the end, not "back".
    EXPECT_NE(html.find("<b>A. supine at 1.50 s</b>"), std::string::npos);
    EXPECT_NE(html.find("C. turned at 2.30 s"), std::string::npos);
    EXPECT_EQ(html.find("back at"), std::string::npos);
    EXPECT_NE(html.find("No verdict.csv in this folder"), std::string::npos);
}

TEST(ArrayReport, RunWithoutTurnShowsTheSettleAndTheEnd) {
    const fs::path dir = makeDir("report-no-turn");
    io::test::writeSyntheticRun(dir, false, 1.4);
    const std::string html = io::formatArrayReportHtml(dir);
    // Stopped before the settle ended: the first picture says so.
    EXPECT_NE(
        html.find(
            "A. supine at 1.40 s</b> (the last output (the run stopped before the settle ended))"),
        std::string::npos);
    EXPECT_EQ(count(html, "class='mat'"), 1);
}

TEST(ArrayReport, WriteReplacesThePageThroughATemporaryFile) {
    const fs::path dir = makeDir("report-write");
    io::test::writeSyntheticRun(dir, true);
    { std::ofstream(dir / "report.html") << "old"; }
    io::writeArrayReport(dir, dir / "report.html");
    std::ifstream in(dir / "report.html");
    std::string first;
    std::getline(in, first);
    EXPECT_EQ(first.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_FALSE(fs::exists(dir / "report.html.tmp"));
}

TEST(ArrayReport, AFolderThatIsNotAPatientOnArrayResultGetsALocatedError) {
    const fs::path dir = makeDir("report-not-a-result");
    EXPECT_NE(errorOf(dir).find("is not a folder"), std::string::npos) << errorOf(dir);
    fs::create_directories(dir);
    EXPECT_NE(
        errorOf(dir).find(
            "report-not-a-result: no results.h5: not the output folder of a bagsim run, nor a "
            "study's folder (no study.csv)"),
        std::string::npos)
        << errorOf(dir);
    // results.h5 of another kind of run.
    {
        const hid_t f =
            H5Fcreate((dir / "results.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
        const hid_t g = H5Gcreate2(f, "meta", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        const hid_t type = H5Tcopy(H5T_C_S1);
        H5Tset_size(type, 14);
        const hid_t space = H5Screate(H5S_SCALAR);
        const hid_t a = H5Acreate2(g, "kind", type, space, H5P_DEFAULT, H5P_DEFAULT);
        H5Awrite(a, type, "seed-load-test");
        H5Aclose(a), H5Sclose(space), H5Tclose(type), H5Gclose(g), H5Fclose(f);
    }
    EXPECT_NE(errorOf(dir).find("results.h5: is the result of a 'seed-load-test' run; bagsim "
                                "report reads the results of kind patient-on-array"),
              std::string::npos)
        << errorOf(dir);
    { std::ofstream(dir / "results.h5") << "not hdf5"; }
    EXPECT_NE(errorOf(dir).find("results.h5: not an HDF5 file (or it cannot be read)"),
              std::string::npos)
        << errorOf(dir);

    // A result with a file missing, a wrong header, a bad number.
    const fs::path run = makeDir("report-broken");
    io::test::writeSyntheticRun(run, false);
    fs::remove(run / "tilt.csv");
    EXPECT_NE(errorOf(run).find("tilt.csv: missing: a patient-on-array results folder holds"),
              std::string::npos)
        << errorOf(run);
    { std::ofstream(run / "tilt.csv") << "time,pelvis\n0,0\n"; }
    EXPECT_NE(errorOf(run).find("tilt.csv:1: the header 'time,pelvis' has no column 'time_s'; "
                                "expected time_s,pelvis_tilt_deg,thorax_tilt_deg"),
              std::string::npos)
        << errorOf(run);
    {
        std::ofstream(run / "tilt.csv")
            << "time_s,pelvis_tilt_deg,thorax_tilt_deg\n0,0,0\n0.1,x,0\n";
    }
    EXPECT_NE(errorOf(run).find("tilt.csv:3: column 2 'pelvis_tilt_deg': 'x' is not a number"),
              std::string::npos)
        << errorOf(run);
}

TEST(ArrayReport, ARunStoppedBeforeItsFirstOutputStillGetsAPageThatSaysSo) {
    const fs::path dir = makeDir("report-empty");
    io::test::writeSyntheticRun(dir, false, -1.0);  // interrupted before the first frame
    const std::string html = io::formatArrayReportHtml(dir);
    EXPECT_NE(html.find("INCOMPLETE RESULTS"), std::string::npos);
    EXPECT_NE(
        html.find("The run wrote nothing before it stopped, at the start of the 6.00 s planned"),
        std::string::npos);
    EXPECT_NE(html.find("No pressure-mat frames in results.h5."), std::string::npos);
    EXPECT_EQ(count(html, "class='mat'"), 0);
}
