#pragma once
// Inline SVG charts for the HTML reports (report.html of bagsim diagnose and of a
// patient-on-array run): line and point series on axes with round-numbered ticks, a grid, axis
// labels with units, a legend under the chart, vertical markers (moments, events), shaded
// bands and horizontal reference lines. Colours: the Okabe-Ito palette, which readers with a
// colour-vision deficiency can tell apart, with dash patterns past its size; viridis for
// colour scales (perceptually uniform, readable in grey and with any colour-vision deficiency).
// Self-contained: no scripts, no fonts, no external references.

#include <limits>
#include <string>
#include <vector>

namespace io::svg {

/// Escapes text for HTML and SVG content and attribute values (&, <, >, ', ").
std::string escape(const std::string& text);
/// printf-formats a number; "-" for NaN or infinity.
std::string num(double v, const char* format = "%.4g");

/// One curve of a chart.
struct Series {
    std::string name;          ///< legend text ("" leaves it out of the legend)
    std::string colour;        ///< CSS colour
    std::vector<double> x, y;  ///< NaN in y breaks the line; a line of more than ~1200
                               ///< points is thinned to each bucket's lowest and highest
    bool points = false;       ///< markers instead of a line (at most ~400 drawn)
    std::string dash = "";     ///< stroke-dasharray ("" solid)
    double width = 1.6;        ///< line width [px]
};

/// A vertical line at x with a short label at its top and a longer hover text.
struct Marker {
    double x = 0.0;
    std::string label;  ///< drawn ("A", "3")
    std::string title;  ///< shown on hover (SVG <title>)
    std::string colour = "#555";
    int row = 0;  ///< label row above the plot (0 top, 1 below it): keeps two kinds apart
};

/// A horizontal reference line (e.g. 32 mmHg), kept inside the y range.
struct RefLine {
    double y = 0.0;
    std::string label;
    std::string colour = "#b00";
};

/// A shaded x interval (e.g. the settle).
struct Band {
    double x0 = 0.0, x1 = 0.0;
    std::string label;
};

struct PlotOptions {
    std::string title, xLabel, yLabel;  ///< labels carry their unit: "time [s]"
    double width = 560, height = 300;   ///< [px] of the plot without its legend
    double xMin = std::numeric_limits<double>::quiet_NaN();  ///< NaN: from the data
    double xMax = std::numeric_limits<double>::quiet_NaN();
    double yMin = std::numeric_limits<double>::quiet_NaN();
    double yMax = std::numeric_limits<double>::quiet_NaN();
    std::vector<Marker> markers;
    std::vector<RefLine> refLines;
    std::vector<Band> bands;
    std::string id;  ///< id attribute of the <svg> ("" none)
};

/// One chart as an <svg> element (with width, height and viewBox; scales down with CSS).
std::string plot(const PlotOptions& options, const std::vector<Series>& series);

/// Round tick values covering [lo, hi] with about `target` intervals (steps 1, 2, 2.5, 5 x 10^k).
std::vector<double> calcTicks(double lo, double hi, int target);
/// The smallest round number (1, 2, 2.5, 5 x 10^k) at or above v (> 0).
double calcRoundUp(double v);
/// Formats a tick value with as many decimals as the tick step needs.
std::string formatTick(double v, double step);

/// The i-th colour of the Okabe-Ito palette (cycles over 7, yellow left out: too light).
std::string getCategoryColour(int i);
/// A dash pattern for the i-th series once colours repeat ("" for the first 7).
std::string getCategoryDash(int i);
/// viridis at t in [0, 1] as "#rrggbb".
std::string getViridis(double t);

}  // namespace io::svg
