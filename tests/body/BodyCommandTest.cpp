// `bagsim body`: exit codes, messages, and the CSV carrying the same numbers as the table. The
// program is built with this test (tests/body/CMakeLists.txt): its absence is a failure.
#include <body/Anthropometry.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace {

const std::string kBagsim = std::string(BAGSIM_BINARY_DIR) + "/bin/bagsim";

// Runs bagsim with arguments; returns the exit code and fills out with stdout + stderr.
int run(const std::string& args, std::string& out) {
    FILE* pipe = popen((kBagsim + " " + args + " 2>&1").c_str(), "r");
    if (!pipe) return -1;
    char buf[4096];
    out.clear();
    while (fgets(buf, sizeof buf, pipe)) out += buf;
    const int status = pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool haveBagsim() { return std::ifstream(kBagsim).good(); }

}  // namespace

TEST(BodyCommand, PrintsTableAndCsvWithTheSameMasses) {
    ASSERT_TRUE(haveBagsim()) << "bagsim not built at " << kBagsim;
    std::string table, csv;
    ASSERT_EQ(run("body --sex female --height 1.62 --mass 58", table), 0) << table;
    ASSERT_EQ(run("body --sex female --height 1.62 --mass 58 --format csv", csv), 0) << csv;
    const body::Anthropometry a = body::calcAnthropometry(body::Sex::Female, 1.62, 58.0);
    std::istringstream rows(csv);
    std::string line;
    std::getline(rows, line);
    EXPECT_EQ(line.rfind("segment,mass_kg,", 0), 0u) << line;
    int n = 0;
    double total = 0;
    while (std::getline(rows, line)) {
        const std::string name = line.substr(0, line.find(','));
        const double mass = std::stod(line.substr(line.find(',') + 1));
        EXPECT_NEAR(mass, a.segments[n].mass, 1e-5 * a.segments[n].mass) << name;
        EXPECT_EQ(name, body::getSegmentName(a.segments[n].segment));
        // The table row of the same segment shows the same mass to 3 decimals.
        char expect[64];
        std::snprintf(expect, sizeof expect, "%-13s %8.3f", name.c_str(), a.segments[n].mass);
        EXPECT_NE(table.find(expect), std::string::npos) << expect;
        total += mass;
        ++n;
    }
    EXPECT_EQ(n, body::kSegmentCount);
    EXPECT_NEAR(total, 58.0, 1e-4);  // CSV prints 6 significant digits
    EXPECT_NE(table.find("total           58.000"), std::string::npos);
}

TEST(BodyCommand, RefusesBadInputNamingTheFlag) {
    ASSERT_TRUE(haveBagsim()) << "bagsim not built at " << kBagsim;
    std::string out;
    EXPECT_EQ(run("body --sex male --height 2.3 --mass 80", out), 2);
    EXPECT_NE(out.find("--height"), std::string::npos) << out;
    EXPECT_NE(out.find("1.4-2.1"), std::string::npos) << out;
    EXPECT_EQ(run("body --sex male --height 1.8 --mass 200", out), 2);
    EXPECT_NE(out.find("--mass"), std::string::npos) << out;
    EXPECT_NE(out.find("BMI"), std::string::npos) << out;
    EXPECT_EQ(run("body --sex other --height 1.8 --mass 80", out), 2);
    EXPECT_NE(out.find("female or male"), std::string::npos) << out;
    EXPECT_EQ(run("body --sex male --height 1.8", out), 2);
    EXPECT_NE(out.find("--mass is required"), std::string::npos) << out;
    EXPECT_EQ(run("body --sex male --height 1.8 --mass 80 --format xml", out), 2);
    EXPECT_NE(out.find("table or csv"), std::string::npos) << out;
    EXPECT_EQ(run("body --help", out), 0);
    EXPECT_NE(out.find("usage: bagsim body"), std::string::npos);
}
