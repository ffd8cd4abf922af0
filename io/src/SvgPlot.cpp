#include "SvgPlot.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace io::svg {

std::string escape(const std::string& s) {
    std::string o;
    o.reserve(s.size());
    for (char c : s) {
        switch (c) {
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '&':
                o += "&amp;";
                break;
            case '\'':
                o += "&#39;";
                break;
            case '"':
                o += "&quot;";
                break;
            default:
                o += c;
        }
    }
    return o;
}

std::string num(double v, const char* f) {
    if (!std::isfinite(v)) return "-";
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

double calcRoundUp(double v) {
    if (!(v > 0.0) || !std::isfinite(v)) return 1.0;
    const double p = std::pow(10.0, std::floor(std::log10(v)));
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (m * p >= v * (1.0 - 1e-12)) return m * p;
    return 10.0 * p;
}

std::vector<double> calcTicks(double lo, double hi, int target) {
    if (!(hi > lo)) hi = lo + 1.0;
    const double step = calcRoundUp((hi - lo) / std::max(target, 1));
    std::vector<double> t;
    const double first = std::ceil(lo / step - 1e-9) * step;
    for (int k = 0; k < 100; ++k) {
        const double v = first + k * step;
        if (v > hi + 1e-9 * step) break;
        t.push_back(std::fabs(v) < 1e-12 * step ? 0.0 : v);
    }
    return t;
}

std::string formatTick(double v, double step) {
    int decimals = 0;
    for (double s = step; decimals < 6 && std::fabs(s - std::round(s)) > 1e-6 * step; s *= 10.0)
        ++decimals;
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", decimals, v);
    return b;
}

std::string getCategoryColour(int i) {
    static const char* const kColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                           "#E69F00", "#56B4E9", "#000000"};
    return kColours[((i % 7) + 7) % 7];
}

std::string getCategoryDash(int i) {
    static const char* const kDashes[] = {"", "6 3", "2 2", "8 3 2 3"};
    return kDashes[(std::max(i, 0) / 7) % 4];
}

std::string getViridis(double t) {
    // viridis (matplotlib) at 0, 0.1, ..., 1.
    static const int kStops[11][3] = {{68, 1, 84},    {72, 36, 117},  {65, 68, 135},
                                      {53, 95, 141},  {42, 120, 142}, {33, 145, 140},
                                      {34, 168, 132}, {68, 191, 112}, {122, 209, 81},
                                      {189, 223, 38}, {253, 231, 37}};
    if (!std::isfinite(t)) t = 0.0;
    t = std::clamp(t, 0.0, 1.0) * 10.0;
    const int i = std::min(int(t), 9);
    const double f = t - i;
    char b[8];
    int c[3];
    for (int k = 0; k < 3; ++k)
        c[k] = int(std::lround(kStops[i][k] + f * (kStops[i + 1][k] - kStops[i][k])));
    std::snprintf(b, sizeof b, "#%02x%02x%02x", c[0], c[1], c[2]);
    return b;
}

// Points of a line drawn at most (about): a chart is 500 px wide, so more add no detail.
constexpr size_t kMaxLinePoints = 1200;

std::string plot(const PlotOptions& o, const std::vector<Series>& series) {
    const double W = o.width, H = o.height, L = 64, R = 14, T = o.markers.empty() ? 30 : 48, B = 44;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const Series& s : series)
        for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
            if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
            x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
            y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
        }
    if (!std::isfinite(x0)) x0 = 0.0, x1 = 1.0, y0 = 0.0, y1 = 1.0;
    for (const RefLine& r : o.refLines) y0 = std::min(y0, r.y), y1 = std::max(y1, r.y);
    if (std::isfinite(o.xMin)) x0 = o.xMin;
    if (std::isfinite(o.xMax)) x1 = o.xMax;
    if (!(x1 > x0)) x1 = x0 + 1.0;
    // y: widened to round ticks unless given.
    if (!(y1 > y0)) {
        const double d = std::max(std::fabs(y0) * 0.05, 1e-3);
        y0 -= d, y1 += d;
    }
    const std::vector<double> yt0 = calcTicks(y0, y1, 5);
    const double ystep = yt0.size() > 1 ? yt0[1] - yt0[0] : 1.0;
    if (!std::isfinite(o.yMin))
        y0 = std::floor(y0 / ystep + 1e-9) * ystep;
    else
        y0 = o.yMin;
    if (!std::isfinite(o.yMax))
        y1 = std::ceil(y1 / ystep - 1e-9) * ystep;
    else
        y1 = o.yMax;
    if (!(y1 > y0)) y1 = y0 + ystep;
    const double pw = W - L - R, ph = H - T - B;
    auto X = [&](double v) { return L + (v - x0) / (x1 - x0) * pw; };
    auto Y = [&](double v) { return T + ph - (v - y0) / (y1 - y0) * ph; };
    auto P = [](double v) { return num(v, "%.1f"); };

    // Legend rows under the plot.
    struct Entry {
        const Series* s;
        double w;
    };
    std::vector<std::vector<Entry>> rows(1);
    double rowW = 0.0;
    for (const Series& s : series) {
        if (s.name.empty()) continue;
        const double w = 34 + 6.6 * s.name.size() + 14;
        if (rowW + w > W - L && !rows.back().empty()) rows.emplace_back(), rowW = 0.0;
        rows.back().push_back({&s, w});
        rowW += w;
    }
    if (rows.back().empty()) rows.pop_back();
    const double totalH = H + 18.0 * rows.size();

    std::ostringstream os;
    os << "<svg xmlns='http://www.w3.org/2000/svg' role='img' width='" << W << "' height='"
       << totalH << "' viewBox='0 0 " << W << " " << totalH << "'"
       << (o.id.empty() ? "" : " id='" + escape(o.id) + "'")
       << " font-family='sans-serif' font-size='12'><title>" << escape(o.title) << "</title>"
       << "<rect width='100%' height='100%' fill='#fff'/>"
       << "<text x='" << L << "' y='17' font-size='14' font-weight='bold'>" << escape(o.title)
       << "</text>";
    for (const Band& b : o.bands) {
        const double a = X(std::clamp(b.x0, x0, x1)), c = X(std::clamp(b.x1, x0, x1));
        if (c - a < 0.5) continue;
        os << "<rect x='" << P(a) << "' y='" << T << "' width='" << P(c - a) << "' height='" << ph
           << "' fill='#eee'/><text x='" << P((a + c) / 2) << "' y='" << T + ph - 6
           << "' text-anchor='middle' fill='#777' font-size='11'>" << escape(b.label) << "</text>";
    }
    // Grid and ticks.
    const std::vector<double> xt = calcTicks(x0, x1, std::max(2, int(pw / 80)));
    const std::vector<double> yt = calcTicks(y0, y1, std::max(2, int(ph / 45)));
    const double xs = xt.size() > 1 ? xt[1] - xt[0] : 1.0, ys = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
    for (double v : xt)
        os << "<line x1='" << P(X(v)) << "' x2='" << P(X(v)) << "' y1='" << T << "' y2='" << T + ph
           << "' stroke='#e4e4e4'/><text x='" << P(X(v)) << "' y='" << T + ph + 15
           << "' text-anchor='middle'>" << formatTick(v, xs) << "</text>";
    for (double v : yt)
        os << "<line x1='" << L << "' x2='" << L + pw << "' y1='" << P(Y(v)) << "' y2='" << P(Y(v))
           << "' stroke='#e4e4e4'/><text x='" << L - 5 << "' y='" << P(Y(v) + 4)
           << "' text-anchor='end'>" << formatTick(v, ys) << "</text>";
    os << "<rect x='" << L << "' y='" << T << "' width='" << pw << "' height='" << ph
       << "' fill='none' stroke='#888'/>"
       << "<text x='" << L + pw / 2 << "' y='" << H - 8 << "' text-anchor='middle'>"
       << escape(o.xLabel) << "</text><text x='15' y='" << T + ph / 2
       << "' transform='rotate(-90 15 " << T + ph / 2 << ")' text-anchor='middle'>"
       << escape(o.yLabel) << "</text>";
    for (const RefLine& r : o.refLines) {
        if (r.y < y0 || r.y > y1) continue;
        os << "<line x1='" << L << "' x2='" << L + pw << "' y1='" << P(Y(r.y)) << "' y2='"
           << P(Y(r.y)) << "' stroke='" << r.colour << "' stroke-dasharray='5 4'/><text x='"
           << L + pw - 4 << "' y='" << P(Y(r.y) - 4) << "' text-anchor='end' fill='" << r.colour
           << "' font-size='11'>" << escape(r.label) << "</text>";
    }
    // Series, clipped to the plot area.
    static std::atomic<int> clipCount{0};  // ids unique within a page
    const std::string clip = "clip" + std::to_string(++clipCount);
    os << "<clipPath id='" << clip << "'><rect x='" << L << "' y='" << T << "' width='" << pw
       << "' height='" << ph << "'/></clipPath><g clip-path='url(#" << clip << ")'>";
    for (const Series& s : series) {
        const size_t n = std::min(s.x.size(), s.y.size());
        if (s.points) {
            const size_t step = std::max<size_t>(1, n / 400);  // at most ~400 markers
            for (size_t i = 0; i < n; i += step)
                if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
                    os << "<circle cx='" << P(X(s.x[i])) << "' cy='" << P(Y(s.y[i]))
                       << "' r='2' fill='" << s.colour << "'/>";
            continue;
        }
        std::string pts;
        auto flush = [&] {
            if (!pts.empty())
                os << "<polyline fill='none' stroke-linejoin='round' stroke-width='" << s.width
                   << "' stroke='" << s.colour << "'"
                   << (s.dash.empty() ? "" : " stroke-dasharray='" + s.dash + "'") << " points='"
                   << pts << "'/>";
            pts.clear();
        };
        // A long line keeps, per bucket of points, its lowest and highest (in order): about
        // kMaxLinePoints drawn, and no peak lost to the thinning.
        const size_t bucket =
            n > kMaxLinePoints ? (2 * n + kMaxLinePoints - 1) / kMaxLinePoints : 1;
        auto emit = [&](size_t lo, size_t hi) {
            if (lo == n) return;
            const size_t a = std::min(lo, hi), b = std::max(lo, hi);
            pts += P(X(s.x[a])) + "," + P(Y(s.y[a])) + " ";
            if (b != a) pts += P(X(s.x[b])) + "," + P(Y(s.y[b])) + " ";
        };
        for (size_t b0 = 0; b0 < n; b0 += bucket) {
            size_t lo = n, hi = n;
            for (size_t i = b0; i < std::min(n, b0 + bucket); ++i) {
                if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
                    emit(lo, hi);
                    lo = hi = n;
                    flush();
                    continue;
                }
                if (lo == n || s.y[i] < s.y[lo]) lo = i;
                if (hi == n || s.y[i] > s.y[hi]) hi = i;
            }
            emit(lo, hi);
        }
        flush();
    }
    os << "</g>";
    // Markers of one row closer than a label's width share one label ("2,3") and hover text.
    std::vector<Marker> merged;
    for (const Marker& m : o.markers) {
        if (m.x < x0 || m.x > x1) continue;
        Marker* near = nullptr;
        for (Marker& k : merged)
            if (k.row == m.row && std::fabs(X(k.x) - X(m.x)) < 7.0 * (k.label.size() + 1))
                near = &k;
        if (near) {
            near->label += "," + m.label;
            near->title += "\n" + m.title;
        } else {
            merged.push_back(m);
        }
    }
    for (const Marker& m : merged) {
        const double ly = T - 17 + 12 * std::clamp(m.row, 0, 1);
        os << "<g><title>" << escape(m.title) << "</title><line x1='" << P(X(m.x)) << "' x2='"
           << P(X(m.x)) << "' y1='" << ly + 2 << "' y2='" << T + ph << "' stroke='" << m.colour
           << "' stroke-dasharray='3 3'/><text x='" << P(X(m.x)) << "' y='" << ly
           << "' text-anchor='middle' font-size='11' font-weight='bold' fill='" << m.colour << "'>"
           << escape(m.label) << "</text></g>";
    }
    double ly = H + 4;
    for (const auto& row : rows) {
        double lx = L;
        for (const Entry& e : row) {
            const Series& s = *e.s;
            if (s.points)
                os << "<circle cx='" << P(lx + 13) << "' cy='" << P(ly + 6) << "' r='3' fill='"
                   << s.colour << "'/>";
            else
                os << "<line x1='" << P(lx) << "' x2='" << P(lx + 26) << "' y1='" << P(ly + 6)
                   << "' y2='" << P(ly + 6) << "' stroke-width='2.5' stroke='" << s.colour << "'"
                   << (s.dash.empty() ? "" : " stroke-dasharray='" + s.dash + "'") << "/>";
            os << "<text x='" << P(lx + 32) << "' y='" << P(ly + 10) << "'>" << escape(s.name)
               << "</text>";
            lx += e.w;
        }
        ly += 18;
    }
    return os.str() + "</svg>";
}

}  // namespace io::svg
