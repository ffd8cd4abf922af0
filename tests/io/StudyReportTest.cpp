// report.html of a study (io/StudyReport.h), made from synthetic study folders written through
// the study's own table writers: the table of cases, the outputs against each parameter, the
// map over a block's pressed positions with its colour scale and unit, the change against the
// bag alone, the load-displacement curves, the cases missing or failed, nothing fetched from a
// network, and the located errors for folders that are not a study's.
// (tests/io/ReportBrowserTest.cpp renders the page in Chromium.)
#include <gtest/gtest.h>
#include <io/InputError.h>
#include <io/StudyReport.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "SyntheticStudy.h"

#include "ReportTestUtil.h"

namespace fs = std::filesystem;

namespace {

fs::path makeDir(const std::string& name) { return io::test::makeReportTestDir(name); }

int count(const std::string& s, const std::string& what) {
    return io::test::countOccurrences(s, what);
}

/// The text of the element that opens with `open` up to its closing `close`.
std::string section(const std::string& html, const std::string& open, const std::string& close) {
    const size_t a = html.find(open);
    if (a == std::string::npos) return "";
    const size_t b = html.find(close, a);
    return html.substr(a, b == std::string::npos ? std::string::npos : b - a);
}

std::string errorOf(const fs::path& dir) {
    return io::test::reportErrorOf([](const fs::path& d) { return io::formatStudyReportHtml(d); },
                                   dir);
}

}  // namespace

TEST(StudyReport, AMapStudyShowsItsTableCurvesMapsAndLoadDisplacementCurves) {
    const fs::path dir = makeDir("study-report-map");
    io::test::writeSyntheticMapStudy(dir, false);
    ASSERT_TRUE(io::isStudyFolder(dir));
    const std::string html = io::formatStudyReportHtml(dir);

    EXPECT_NE(html.find("<h1>array-stiffness-map</h1>"), std::string::npos);
    EXPECT_NE(html.find("stiffness map of a synthetic 3 x 3 block"), std::string::npos);
    EXPECT_NE(html.find("airbag.neighbours.layout: block3x3"), std::string::npos);
    EXPECT_EQ(html.find("INCOMPLETE STUDY"), std::string::npos);
    EXPECT_NE(html.find("11 ok, 0 partial, 1 failed, 0 not run"), std::string::npos);

    // The table: a row per case, with its status and outputs.
    const std::string cases = section(html, "<table id='cases'>", "</table>");
    EXPECT_EQ(count(cases, "<tr>"), 13);
    EXPECT_EQ(count(cases, "&#10004; ok"), 11);
    EXPECT_EQ(count(cases, "&#10008; failed"), 1);
    EXPECT_NE(cases.find("<th>test.gas_masses [g]</th>"), std::string::npos);
    EXPECT_NE(cases.find("<td>[1, 1]</td>"), std::string::npos);
    EXPECT_NE(
        cases.find(io::test::formatSyntheticNumber(io::test::getSyntheticMapStiffness(0, 3.5))),
        std::string::npos);
    // The failed case is named with its reason above the table.
    const std::string problems = section(html, "<table id='problem-cases'>", "</table>");
    EXPECT_EQ(count(problems, "<tr>"), 2);
    EXPECT_NE(problems.find("no convergence while inflating the airbag"), std::string::npos);
    EXPECT_NE(problems.find("pressed=[1, 1], gas mass=3 g"), std::string::npos);

    // Curves: the three outputs against the gas mass, one line per pressed position.
    EXPECT_NE(html.find("stiffness against gas mass of the pressed bag"), std::string::npos);
    EXPECT_NE(html.find("gas mass of the pressed bag [g]"), std::string::npos);
    EXPECT_NE(html.find("stiffness [N/mm]"), std::string::npos);
    EXPECT_NE(html.find("pressure [kPa]"), std::string::npos);
    EXPECT_NE(html.find("pressed=[0, 1]"), std::string::npos);  // a legend entry

    // Maps: per output, one per gas mass, each with its colour scale; the value in each cell.
    EXPECT_EQ(count(html, "class='map'"), 6);
    EXPECT_EQ(count(html, "class='colourbar'"), 6);
    const std::string map = section(html,
                                    "<svg xmlns='http://www.w3.org/2000/svg' role='img' "
                                    "class='map'",
                                    "</svg>");
    EXPECT_NE(map.find(">stiffness [N/mm]</text>"), std::string::npos);
    EXPECT_NE(map.find(">3.617</text>"), std::string::npos) << map;  // 3.553 x 1.018
    EXPECT_NE(map.find(">3.553</text>"), std::string::npos);
    EXPECT_EQ(count(map, ">not pressed</text>"), 3);  // across = -1
    EXPECT_NE(map.find("[0, 0]: 3.617 N/mm (case 3, ok)"), std::string::npos);
    // The failed case's cell at 3.0 g says so.
    EXPECT_NE(html.find("[1, 1]: case 12 failed"), std::string::npos);
    EXPECT_NE(html.find("3.553 to 3.617 N/mm (spread 1.8 % of the mean)"), std::string::npos);

    // Load-displacement: 11 cases with a curve, 7 to a chart.
    EXPECT_NE(html.find("Force against displacement, cases 1 to 7"), std::string::npos);
    EXPECT_NE(html.find("Force against displacement, cases 8 to 11"), std::string::npos);
    EXPECT_NE(html.find("displacement of the block [mm]"), std::string::npos);

    // Every picture: 3 curves, 6 maps and their 6 scales, 2 load-displacement charts.
    EXPECT_EQ(count(html, "<svg "), 17);
    // Self-contained.
    EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*['"]?\s*(https?:)?//)")));
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_EQ(html.find("<link"), std::string::npos);
}

TEST(StudyReport, AnIncompleteStudySaysWhichCasesAreMissingAtTheTop) {
    const fs::path dir = makeDir("study-report-incomplete");
    io::test::writeSyntheticMapStudy(dir, true);
    const std::string html = io::formatStudyReportHtml(dir);
    const size_t banner = html.find(
        "<b>INCOMPLETE STUDY</b>: 1 of 12 cases have no result "
        "(1 not run, 0 interrupted)");
    ASSERT_NE(banner, std::string::npos);
    EXPECT_LT(banner, html.find("<h2>Study"));
    EXPECT_NE(html.find("bagsim study scenarios/array-stiffness-map.yaml --out " + dir.string()),
              std::string::npos);
    const std::string problems = section(html, "<table id='problem-cases'>", "</table>");
    EXPECT_EQ(count(problems, "<tr>"), 3);
    EXPECT_NE(problems.find("<td class='na'>not-run</td>"), std::string::npos);
    EXPECT_NE(problems.find("not started before the study stopped"), std::string::npos);
    EXPECT_NE(html.find("<h2>INCOMPLETE marker</h2>"), std::string::npos);
    // The map at 3.5 g has no value at [1, 1].
    EXPECT_NE(html.find("[1, 1]: case 11 not-run"), std::string::npos);
}

TEST(StudyReport, ACouplingStudyShowsTheChangeAgainstTheBagAlone) {
    const fs::path dir = makeDir("study-report-coupling");
    io::test::writeSyntheticCouplingStudy(dir);
    const std::string html = io::formatStudyReportHtml(dir);
    EXPECT_EQ(count(html, "class='map'"), 0);
    EXPECT_NE(html.find("stiffness against gas mass of the pressed bag"), std::string::npos);
    EXPECT_NE(html.find("stiffness against neighbours&#39; gas mass"), std::string::npos);
    const std::string neighbours = section(html, "<h2 id='neighbours'>", "</div>");
    ASSERT_FALSE(neighbours.empty());
    EXPECT_NE(neighbours.find("stiffness among neighbours against gas mass of the pressed bag"),
              std::string::npos);
    EXPECT_NE(neighbours.find("change against the bag alone [%]"), std::string::npos);
    // The legend names layout and the other mass; the bag alone draws no line of its own.
    EXPECT_NE(neighbours.find("layout=row3, neighbours&#39; gas mass=3.5 g"), std::string::npos);
    EXPECT_EQ(neighbours.find("layout=none"), std::string::npos);
    // Outputs x parameters: 2 x 2 curves, 2 charts of the change (one output), no curves of
    // load and displacement (the synthetic cases wrote none).
    EXPECT_EQ(count(html, "<svg "), 6);
    EXPECT_EQ(html.find("id='load-displacement'"), std::string::npos);
}

TEST(StudyReport, AFolderThatIsNotAStudysGetsALocatedError) {
    const fs::path dir = makeDir("study-report-not-a-study");
    EXPECT_FALSE(io::isStudyFolder(dir));
    EXPECT_NE(errorOf(dir).find("is not a folder"), std::string::npos) << errorOf(dir);
    fs::create_directories(dir);
    EXPECT_FALSE(io::isStudyFolder(dir));
    // The runner's stamp, no table yet.
    std::ofstream(dir / ".bagsim-study") << "last study: x.yaml\n";
    EXPECT_TRUE(io::isStudyFolder(dir));
    EXPECT_NE(errorOf(dir).find("a study's folder without study.csv"), std::string::npos)
        << errorOf(dir);
    // A study.csv that is not a study's table.
    std::ofstream(dir / "study.csv") << "case,status\n1,ok\n";
    EXPECT_NE(errorOf(dir).find("study.csv:1: the header 'case,status' has no column 'key'"),
              std::string::npos)
        << errorOf(dir);
    std::ofstream(dir / "study.csv") << "case,key,status,x,reason,seconds\n1,k,ok,2,,1\n";
    EXPECT_NE(errorOf(dir).find("study.csv:1: the columns are not those of a study table"),
              std::string::npos)
        << errorOf(dir);
    std::ofstream(dir / "study.csv") << "case,key,p,status,reason,seconds\n1,k,2,ok,,1,9\n";
    EXPECT_NE(errorOf(dir).find("study.csv:2: 7 cells; the header has 6"), std::string::npos)
        << errorOf(dir);
}

TEST(StudyReport, WriteReplacesThePageThroughATemporaryFile) {
    const fs::path dir = makeDir("study-report-write");
    io::test::writeSyntheticCouplingStudy(dir);
    std::ofstream(dir / "report.html") << "old page";
    io::writeStudyReport(dir, dir / "report.html");
    std::ifstream in(dir / "report.html");
    std::stringstream s;
    s << in.rdbuf();
    EXPECT_EQ(s.str().rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(s.str().find("<table id='cases'>"), std::string::npos);
    EXPECT_EQ(s.str().find("old page"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir / "report.html.tmp"));
}

TEST(StudyReport, AStiffnessPerGasMassWithOneMassPerCaseIsDrawnAsOneOutput) {
    // As scenarios/seed-mass-study.yaml: each case fills the one column of its own gas mass.
    const fs::path dir = makeDir("study-report-per");
    io::StudyTable t;
    t.header = {"case",
                "key",
                "test.gas_masses [g]",
                "contact.penalty [Pa/m]",
                "status",
                "reason",
                "seconds",
                "stiffness_N_per_mm[gas_mass_g=3.5]",
                "stiffness_N_per_mm[gas_mass_g=3]",
                "stiffness_N_per_mm[gas_mass_g=2.5]"};
    int n = 0;
    const double masses[] = {3.5, 3.0, 2.5};
    for (int m = 0; m < 3; ++m)
        for (double penalty : {1e7, 1e8}) {
            ++n;
            std::vector<std::string> row = {std::to_string(n),
                                            "k" + std::to_string(n),
                                            io::test::formatSyntheticNumber(masses[m]),
                                            io::test::formatSyntheticNumber(penalty),
                                            "ok",
                                            "",
                                            "5.0",
                                            "",
                                            "",
                                            ""};
            row[size_t(7 + m)] = io::test::formatSyntheticNumber(1.0 + m + penalty * 1e-8);
            t.rows.push_back(row);
        }
    t.status = "complete";
    t.studyText = "kind: study\nscenario: seed-load-test.yaml\n";
    io::test::writeSyntheticStudyFiles(dir, t, "scenarios/seed-mass-study.yaml");
    const std::string html = io::formatStudyReportHtml(dir);
    EXPECT_NE(html.find("<title>stiffness (at the case&#39;s gas mass) against gas mass of the "
                        "pressed bag</title>"),
              std::string::npos);
    EXPECT_NE(html.find("<title>stiffness (at the case&#39;s gas mass) against contact "
                        "penalty</title>"),
              std::string::npos);
    EXPECT_EQ(html.find("stiffness at gas mass 3.5 g against"), std::string::npos);
    // 1e7 and 1e8 Pa/m on the axis in units of 1e7 Pa/m; the legend as the study file writes.
    EXPECT_NE(html.find(">contact penalty [1e7 Pa/m]</text>"), std::string::npos);
    EXPECT_NE(html.find(">penalty=1e8 Pa/m</text>"), std::string::npos);
    EXPECT_EQ(count(html, "<svg "), 2);
    // The table keeps the columns as study.csv has them.
    EXPECT_NE(html.find("<th>stiffness_N_per_mm[gas_mass_g=2.5]</th>"), std::string::npos);
}
