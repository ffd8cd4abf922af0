// bagsim run on a patient-on-array scenario, end to end and short: the coarse supine scenario
// released and stepped for 0.1 s. Every file is written with its columns, the run is marked
// complete, and at every output time the regions' forces add up to the bags' (both the
// vertical force of the bags on him; reference: the coupling's link wrenches); the summary
// names the deepest segment between a film's nodes.
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ArrayRunTestUtil.h"

using namespace app::test;

TEST(ArrayRun, AShortCoarseRunWritesEveryFileAndTheRegionsAddUpToTheBags) {
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-short";
    ASSERT_EQ(runScenario("supine-on-array-coarse.yaml", out, "--set run.settle_time='0.1 s'"), 0);
    for (const char* f :
         {"regions.csv", "bags.csv", "tilt.csv", "results.h5", "results.xdmf", "summary.txt"})
        EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
    EXPECT_FALSE(std::filesystem::exists(out / "INCOMPLETE"));
    const Csv regions = readCsv(out / "regions.csv");
    const Csv bags = readCsv(out / "bags.csv");
    const Csv tilt = readCsv(out / "tilt.csv");
    EXPECT_EQ(regions.header,
              "time_s,region,ppi_mmHg,mean_mmHg,area_cm2,force_N,patch_peak_mmHg,immersion_mm,"
              "area_above_32_cm2");
    EXPECT_EQ(bags.header,
              "time_s,bag,mass_g,pressure_kPa,volume_l,force_N,overlap_mm,inner_height_mm");
    EXPECT_EQ(tilt.header, "time_s,pelvis_tilt_deg,thorax_tilt_deg");
    EXPECT_EQ(tilt.rows.size(), 11u);  // every 10 ms from 0 to 0.1 s
    // The verdict's texts whole, as the program writes them (the firm 4.5 g bags: the
    // 'inflation' row's warning, 150 characters; once cut at 63 by a second fmt() linked in).
    {
        std::ifstream in(out / "verdict.csv");
        std::ostringstream verdict;
        verdict << in.rdbuf();
        EXPECT_NE(verdict.str().find("published active air mattresses run their cells at "
                                     "1.6-4.0 kPa (docs/validation-interface-pressure.md): a "
                                     "firm setting, the peaks and immersion of this run are of "
                                     "it, not of a clinical setting"),
                  std::string::npos)
            << verdict.str();
    }
    const auto regionSum = sumPerTime(regions, "force_N");
    const auto bagSum = sumPerTime(bags, "force_N");
    ASSERT_GE(regionSum.size(), 2u);
    for (const auto& [t, f] : regionSum) {
        ASSERT_EQ(bagSum.count(t), 1u) << t;
        EXPECT_NEAR(f, bagSum.at(t), 1e-3 * bagSum.at(t) + 1e-3) << "at " << t << " s";
        EXPECT_GT(f, 0.0);
    }
    // Every region with contact has a patch peak (the mean over its best 20 cm2 disc), and
    // the report's region table shows it.
    const int ppi = regions.column("ppi_mmHg"), patch = regions.column("patch_peak_mmHg");
    for (const auto& r : regions.rows)
        if (std::stod(r.at(ppi)) > 0.0) EXPECT_GT(std::stod(r.at(patch)), 0.0) << r.at(1);
    // How deep he lies in the surface: a region with contact above 5 mmHg (its area) has
    // pushed the films down from their rest, by less than the 150 mm wedge; a bag he presses has
    // the air left under him (inner height) between the board and its top, an untouched bag
    // none (empty).
    const int area = regions.column("area_cm2"), immersion = regions.column("immersion_mm");
    // The area above 32 mmHg is part of the contact area, and where the peak is below 32 mmHg
    // there is none.
    const int risk = regions.column("area_above_32_cm2");
    int atRisk = 0;
    for (const auto& r : regions.rows) {
        EXPECT_LE(std::stod(r.at(risk)), std::stod(r.at(area)) + 1e-9) << r.at(1);
        if (std::stod(r.at(ppi)) <= 32.0) EXPECT_EQ(std::stod(r.at(risk)), 0.0) << r.at(1);
        atRisk += std::stod(r.at(risk)) > 0.0;
    }
    EXPECT_GT(atRisk, 0);  // landing on the 4.5 g wedges, some regions lie above 32 mmHg
    const int inner = bags.column("inner_height_mm"), bagForce = bags.column("force_N");
    int immersed = 0, pressed = 0, untouched = 0;
    for (const auto& r : regions.rows) {
        const double depth = std::stod(r.at(immersion));
        EXPECT_GE(depth, 0.0) << r.at(1);
        EXPECT_LT(depth, 150.0) << r.at(1);
        if (std::stod(r.at(area)) > 0.0 && r.at(0) == "0.1000") immersed += depth > 1.0;
    }
    for (const auto& r : bags.rows) {
        if (r.size() <= size_t(inner) ||
            r.at(inner).empty()) {  // (the split drops a last empty cell)
            EXPECT_LT(std::stod(r.at(bagForce)), 1.0) << "bag " << r.at(1) << " at " << r.at(0);
            ++untouched;
            continue;
        }
        const double h = std::stod(r.at(inner));
        EXPECT_GT(h, 0.0);
        EXPECT_LT(h, 160.0);
        ++pressed;
    }
    EXPECT_GT(immersed, 3);  // he has sunk into the bags under his trunk, thighs, head by 0.1 s
    EXPECT_GT(pressed, 0);
    EXPECT_GT(untouched, 0);  // at the release nothing presses
    // Every bag holds the scenario's 4.5 g (no gas command).
    const int mass = bags.column("mass_g");
    for (const auto& r : bags.rows) EXPECT_NEAR(std::stod(r.at(mass)), 4.5, 1e-6);
    // The summary says how deep a segment lies inside a film between its nodes, naming the
    // segment and the bag (on this 30 mm mesh a hand does).
    std::stringstream summary;
    summary << std::ifstream(out / "summary.txt").rdbuf();
    EXPECT_NE(summary.str().find("segments lie inside a film between its nodes by at most "),
              std::string::npos)
        << summary.str();

    // report.html is written at the end, complete; bagsim report remakes it in place, refuses
    // to replace another existing file without --force, and refuses a folder that is no result.
    std::stringstream page;
    page << std::ifstream(out / "report.html").rdbuf();
    EXPECT_NE(page.str().find("<h1>supine-on-array-coarse</h1>"), std::string::npos);
    EXPECT_EQ(page.str().find("INCOMPLETE RESULTS"), std::string::npos);
    EXPECT_NE(page.str().find("<th>highest patch peak</th>"), std::string::npos);
    EXPECT_NE(page.str().find("<th>deepest immersion</th>"), std::string::npos);
    EXPECT_NE(page.str().find("<th>largest area above 32 mmHg</th>"), std::string::npos);
    const std::string bagsim = std::string("\"") + BAGSIM_BINARY_DIR + "/bin/bagsim\" report ";
    auto run = [&](const std::string& args) {
        const int rc =
            std::system((bagsim + args + " > \"" + out.string() + ".report.log\" 2>&1").c_str());
        std::stringstream log;
        log << std::ifstream(out.string() + ".report.log").rdbuf();
        return std::make_pair(WEXITSTATUS(rc), log.str());
    };
    EXPECT_EQ(run("\"" + out.string() + "\"").first, 0);
    const std::filesystem::path other = out.string() + "-mine.html";
    { std::ofstream(other) << "mine\n"; }
    const auto refused = run("\"" + out.string() + "\" --out \"" + other.string() + "\"");
    EXPECT_EQ(refused.first, 2);
    EXPECT_NE(refused.second.find("mine.html: exists; pass --force to replace it"),
              std::string::npos)
        << refused.second;
    EXPECT_EQ(readCsv(other).header, "mine");
    EXPECT_EQ(run("\"" + out.string() + "\" --out \"" + other.string() + "\" --force").first, 0);
    EXPECT_NE(readCsv(other).header.find("<!DOCTYPE html>"), std::string::npos);
    const auto notResult = run("\"" + std::string(BAGSIM_SOURCE_DIR) + "/scenarios\"");
    EXPECT_EQ(notResult.first, 2);
    EXPECT_NE(
        notResult.second.find("scenarios: no results.h5: not the output folder of a bagsim run"),
        std::string::npos)
        << notResult.second;
}

TEST(ArrayRun, AnExistingOutputFolderIsNeverOverwrittenSilently) {
    const std::filesystem::path out =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "tests/app/array-existing";
    std::filesystem::remove_all(out);
    std::filesystem::create_directories(out);
    { std::ofstream(out / "regions.csv") << "keep\n"; }
    const std::string cmd = std::string("\"") + BAGSIM_BINARY_DIR + "/bin/bagsim\" run \"" +
                            BAGSIM_SOURCE_DIR +
                            "/scenarios/tests/supine-on-array-coarse.yaml\" --quiet --out \"" +
                            out.string() + "\" > /dev/null 2>&1";
    const int rc = std::system(cmd.c_str());
    EXPECT_EQ(WEXITSTATUS(rc), 2);
    EXPECT_EQ(readCsv(out / "regions.csv").header, "keep");
    EXPECT_FALSE(std::filesystem::exists(out / "INCOMPLETE"));
}
