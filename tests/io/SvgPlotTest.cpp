// The reports' SVG charts (io/src/SvgPlot.h): round ticks, and a long line thinned to about
// 1200 points without losing its peak.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "../../io/src/SvgPlot.h"

using namespace io::svg;

TEST(SvgPlot, TicksAreRoundAndCoverTheRange) {
    EXPECT_EQ(calcTicks(0.0, 7.3, 4), (std::vector<double>{0, 2, 4, 6}));
    const std::vector<double> t = calcTicks(-0.37, 0.12, 5), want = {-0.3, -0.2, -0.1, 0, 0.1};
    ASSERT_EQ(t.size(), want.size());
    for (size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(t[i], want[i], 1e-12);
    EXPECT_DOUBLE_EQ(calcRoundUp(56.0), 100.0);
    EXPECT_DOUBLE_EQ(calcRoundUp(0.21), 0.25);
    EXPECT_EQ(formatTick(2.5, 0.5), "2.5");
    EXPECT_EQ(formatTick(40.0, 20.0), "40");
}

TEST(SvgPlot, ALongLineIsThinnedButKeepsItsPeak) {
    Series s;
    s.colour = "#000";
    for (int i = 0; i < 20000; ++i) {
        s.x.push_back(0.01 * i);
        s.y.push_back(i == 12345 ? 100.0 : std::sin(0.01 * i));
    }
    PlotOptions o;
    o.yMin = 0.0;
    o.yMax = 100.0;
    const std::string svg = plot(o, {s});
    std::smatch m;
    ASSERT_TRUE(std::regex_search(svg, m, std::regex("points='([^']*)'")));
    const std::string pts = m[1];
    const long n = std::count(pts.begin(), pts.end(), ',');
    EXPECT_LE(n, 1300);
    EXPECT_GE(n, 1000);
    // The spike (y = 100) is at the plot's top edge, 30 px from the top (no markers).
    EXPECT_NE(pts.find(",30.0 "), std::string::npos) << "the peak was thinned away";
    // A short line keeps every point.
    s.x.resize(50);
    s.y.resize(50);
    const std::string small = plot(o, {s});
    ASSERT_TRUE(std::regex_search(small, m, std::regex("points='([^']*)'")));
    EXPECT_EQ(std::count(m[1].first, m[1].second, ','), 50);
}
