#include <bags/Units.h>
#include <cosim/ArrayReadings.h>
#include <io/ArrayReport.h>
#include <io/InputError.h>
#include <io/Results.h>
#include <io/Scenario.h>
#include <io/StudyTable.h>
#include <io/Units.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "Hdf5.h"
#include "ReportPage.h"
#include "SvgPlot.h"

namespace io {

namespace fs = std::filesystem;

namespace {

constexpr double kMmHg = bags::kPascalsPerMmHg;                  // [Pa]
constexpr double kThresholdMmHg = cosim::kRiskPressure / kMmHg;  // capillary closing, 32 mmHg
// The colour scale's top [mmHg] at most: as a clinical mat's display, it resolves the range
// around 32 mmHg; higher sensels take the top colour (the captions give the true peaks).
constexpr double kScaleCapMmHg = 100.0;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

using svg::escape;
using svg::num;

using report::lower;

// ------------------------------------------------------------------------------- the files

using Table = report::CsvTable;

/// Reads a CSV file of the run's folder (report::readCsvTable()).
Table readTable(const fs::path& dir, const std::string& name,
                const std::vector<std::string>& columns, bool optional) {
    return report::readCsvTable(dir / name, columns, optional,
                                "a patient-on-array results folder holds regions.csv, bags.csv, "
                                "tilt.csv and results.h5 (docs/output-layout.md#patient-on-array)");
}

std::string readText(const fs::path& p) { return report::readTextIfPresent(p); }

/// What the page is made of.
struct Run {
    fs::path dir;
    // results.h5 /meta
    std::string kind, status, message, scenarioText, scenarioFile, commandLine, version, started,
        finished;
    std::vector<std::string> overrides;
    std::string marker;  ///< INCOMPLETE's text ("" if absent)
    // The scenario, as far as it could be read.
    std::string name, description, patient, array, schedule, scenarioProblem;
    double settle = kNaN, duration = kNaN;
    int columns = 0;
    // The pressure mat.
    int matRows = 0, matColumns = 0;
    double originX = 0, originY = 0, sizeX = 0, sizeY = 0;
    std::vector<double> matTime;  ///< [s] per frame
    int matFrames = 0;            ///< frames with both a time and a pressure
    /// Per frame: the highest sensel [mmHg] and the area of sensels above 32 mmHg [cm^2]
    /// (read in blocks of frames, so a long run's mat is never in memory at once).
    std::vector<double> matPeak, matAbove;
    std::map<int, std::vector<double>> keyFrames;  ///< frame -> [Pa] columns x rows
    Table regions, bags, tilt, verdict, events, body, pneumatics;
    std::string summary;

    int getFrames() const { return matFrames; }
    /// Sensel (r, c) of a frame loaded by loadFrames() [Pa].
    double at(int f, int r, int c) const {
        return keyFrames.at(f)[size_t(c) * size_t(matRows) + size_t(r)];
    }
    /// Reads these frames' sensels from results.h5 /mat/pressure.
    void loadFrames(const std::vector<int>& frames) {
        h5::Handle file = h5::openFileReadOnly((dir / kResultsH5).string());
        h5::Handle mat = h5::openGroup(file.get(), "mat");
        std::vector<hsize_t> dims;
        for (int f : frames)
            if (!keyFrames.count(f))
                keyFrames[f] = h5::readDatasetRows(mat.get(), "pressure", hsize_t(f), 1, dims);
    }
};

void readMeta(Run& run) {
    const fs::path h5path = run.dir / kResultsH5;
    std::error_code ec;
    if (!fs::exists(h5path, ec))
        throw InputError(run.dir.string(), 0, "",
                         "no results.h5: not the output folder of a bagsim run, nor a study's "
                         "folder (no study.csv); give the folder a patient-on-array run wrote "
                         "(it holds results.h5, regions.csv, bags.csv, tilt.csv) or one that "
                         "bagsim study wrote (it holds study.csv)");
    h5::Handle file;
    try {
        file = h5::openFileReadOnly(h5path.string());
    } catch (const std::exception& e) {
        throw InputError(h5path.string(), 0, "", e.what());
    }
    try {
        if (!h5::hasLink(file.get(), "meta"))
            throw InputError(h5path.string(), 0, "", "has no /meta group: not written by bagsim");
        h5::Handle meta = h5::openGroup(file.get(), "meta");
        auto str = [&](const char* key) {
            return h5::hasAttribute(meta.get(), key) ? h5::readStringAttribute(meta.get(), key)
                                                     : std::string();
        };
        run.kind = str("kind");
        if (run.kind != "patient-on-array")
            throw InputError(h5path.string(), 0, "",
                             "is the result of a '" + run.kind +
                                 "' run; bagsim report reads the results of kind "
                                 "patient-on-array");
        run.status = str("status");
        run.message = str("message");
        run.scenarioText = str("scenario");
        run.scenarioFile = str("scenario_file");
        run.commandLine = str("command_line");
        run.version = str("version");
        run.started = str("started");
        run.finished = str("finished");
        const std::string o = str("overrides");
        std::istringstream os(o);
        for (std::string line; std::getline(os, line);)
            if (!line.empty()) run.overrides.push_back(line);
        if (h5::hasLink(file.get(), "mat")) {
            h5::Handle mat = h5::openGroup(file.get(), "mat");
            run.matRows = int(h5::readDoubleAttribute(mat.get(), "rows").at(0));
            run.matColumns = int(h5::readDoubleAttribute(mat.get(), "columns").at(0));
            const std::vector<double> origin = h5::readDoubleAttribute(mat.get(), "origin");
            const std::vector<double> size = h5::readDoubleAttribute(mat.get(), "size");
            run.originX = origin.at(0), run.originY = origin.at(1);
            run.sizeX = size.at(0), run.sizeY = size.at(1);
            std::vector<hsize_t> dims;
            run.matTime = h5::readDataset(mat.get(), "time", dims);
            h5::readDatasetRows(mat.get(), "pressure", 0, 0, dims);
            if (dims.size() != 3 || dims[1] != hsize_t(run.matColumns) ||
                dims[2] != hsize_t(run.matRows))
                throw InputError(h5path.string(), 0, "",
                                 "/mat/pressure is not frames x columns x rows of the mat's " +
                                     std::to_string(run.matRows) + " x " +
                                     std::to_string(run.matColumns) + " sensels");
            run.matFrames = int(std::min<hsize_t>(run.matTime.size(), dims[0]));
            const size_t per = size_t(run.matRows) * size_t(run.matColumns);
            const double sensel = run.sizeX / run.matRows * run.sizeY / run.matColumns;  // [m^2]
            constexpr int kBlock = 256;  // frames read at once (4 MB of a 64 x 32 mat)
            for (int first = 0; first < run.matFrames; first += kBlock) {
                const std::vector<double> p =
                    h5::readDatasetRows(mat.get(), "pressure", hsize_t(first), kBlock, dims);
                for (int f = first; f < run.matFrames && f < first + kBlock; ++f) {
                    double peak = 0.0, above = 0.0;
                    for (size_t k = 0; k < per; ++k) {
                        const double v = p[size_t(f - first) * per + k] / kMmHg;
                        peak = std::max(peak, v);
                        if (v > kThresholdMmHg) above += sensel * 1e4;
                    }
                    run.matPeak.push_back(peak);
                    run.matAbove.push_back(above);
                }
            }
        }
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(h5path.string(), 0, "", e.what());
    }
}

// The scenario's keys the page shows, read from /meta's text and overrides; a scenario this
// cannot read (an older or newer format) leaves them out and says so.
void readScenario(Run& run) {
    try {
        ScenarioFile file = ScenarioFile::parse(run.scenarioText, run.scenarioFile);
        for (const std::string& o : run.overrides) file.applyOverride(o);
        const ScenarioNode root = file.getRoot();
        run.name = root.getString("name", file.getStem());
        run.description = root.getString("description", "");
        if (root.has("patient")) {
            const ScenarioNode p = root.getSection("patient");
            run.patient =
                p.getString("sex", "") + ", " +
                formatSignificant(p.getQuantity("height", Dimension::Length, kNaN), "m", 3) + ", " +
                formatSignificant(p.getQuantity("mass", Dimension::Mass, kNaN), "kg", 3) + ", " +
                p.getString("posture", "supine");
        }
        if (root.has("array")) {
            const ScenarioNode a = root.getSection("array");
            const int rows = a.getInteger("rows", 0);
            run.columns = a.getInteger("columns", 0);
            run.array =
                std::to_string(rows) + " rows x " + std::to_string(run.columns) +
                " columns of airbags, " +
                formatSignificant(a.getQuantity("gas_mass", Dimension::Mass, kNaN), "g", 3) +
                " of gas each";
            if (a.has("groups"))
                for (const ScenarioNode& g : a.get("groups").getElements())
                    if (g.has("gas_mass"))
                        run.array +=
                            ", group " + g.getString("name", "?") + " " +
                            formatSignificant(g.getQuantity("gas_mass", Dimension::Mass), "g", 3);
        }
        const ScenarioNode r = root.getSection("run", false);
        run.settle = r.getQuantity("settle_time", Dimension::Time, 1.5);
        run.duration = r.getQuantity("duration", Dimension::Time, 0.0);
        run.schedule = "released and left to settle for " + formatSignificant(run.settle, "s", 3) +
                       ", then " + formatSignificant(run.duration, "s", 3) + " of the gas schedule";
    } catch (const std::exception& e) {
        run.scenarioProblem = e.what();
    }
}

Run readRun(const fs::path& dir) {
    Run run;
    run.dir = dir;
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw InputError(dir.string(), 0, "",
                         "is not a folder; give the output folder of a patient-on-array run "
                         "(bagsim run --out DIR)");
    readMeta(run);
    readScenario(run);
    if (run.name.empty()) run.name = dir.filename().string();
    run.regions =
        readTable(dir, "regions.csv",
                  {"time_s", "region", "ppi_mmHg", "mean_mmHg", "area_cm2", "force_N"}, false);
    run.bags = readTable(dir, "bags.csv",
                         {"time_s", "bag", "mass_g", "pressure_kPa", "volume_l", "force_N"}, false);
    run.tilt = readTable(dir, "tilt.csv", {"time_s", "pelvis_tilt_deg", "thorax_tilt_deg"}, false);
    run.verdict =
        readTable(dir, "verdict.csv", {"check", "status", "value", "unit", "detail"}, true);
    run.events = readTable(dir, "events.csv", {"time_s", "event"}, true);
    run.body = readTable(dir, "body.csv", {"time_s", "com_x_mm", "com_y_mm", "com_z_mm"}, true);
    run.pneumatics =
        readTable(dir, "pneumatics.csv",
                  {"time_s", "bag", "sensor_kPa", "inflow_g_per_s", "outflow_g_per_s"}, true);
    run.summary = readText(dir / "summary.txt");
    run.marker = readText(dir / OutputDir::kMarkerName);
    return run;
}

// -------------------------------------------------------------------------- key moments

struct Moment {
    std::string letter, name, why;
    double time = 0.0;
    int frame = -1;  ///< mat frame (-1: none)
};

/// The index of the value nearest v in ascending times t (-1 if empty).
int findNearest(const std::vector<double>& t, double v) {
    if (t.empty()) return -1;
    const size_t i = size_t(std::lower_bound(t.begin(), t.end(), v) - t.begin());
    if (i == 0) return 0;
    if (i == t.size()) return int(t.size()) - 1;
    return std::fabs(t[i] - v) < std::fabs(t[i - 1] - v) ? int(i) : int(i) - 1;
}

struct Event {
    double time;
    std::string text;
};

std::vector<Event> getEvents(const Run& run) {
    std::vector<Event> e;
    if (!run.events.present) return e;
    const int t = run.events.find("time_s"), x = run.events.find("event");
    for (size_t i = 0; i < run.events.rows.size(); ++i)
        e.push_back({run.events.number(i, t), run.events.text(i, x)});
    return e;
}

/// The end of the settle: an event that names it, else the scenario's settle_time.
double getSettleEnd(const Run& run, const std::vector<Event>& events) {
    for (const Event& e : events)
        if (lower(e.text).find("settle") != std::string::npos) return e.time;
    return run.settle;
}

std::vector<Moment> pickMoments(const Run& run, const std::vector<Event>& events,
                                const std::vector<double>& t, const std::vector<double>& tilt,
                                const std::vector<double>& matPeak) {
    std::vector<Moment> m;
    if (t.empty()) return m;
    const double settle = getSettleEnd(run, events);
    const int a = std::isfinite(settle) ? findNearest(t, std::min(settle, t.back())) : 0;
    const double ref = tilt[size_t(a)];
    int iMax = a;
    for (size_t i = size_t(a); i < t.size(); ++i)
        if (std::fabs(tilt[i] - ref) > std::fabs(tilt[size_t(iMax)] - ref)) iMax = int(i);
    const double excursion = tilt[size_t(iMax)] - ref;
    const int last = int(t.size()) - 1;
    const std::string settled = std::isfinite(settle) && t.back() >= settle - 1e-9
                                    ? "the end of the settle"
                                    : "the last output (the run stopped before the settle ended)";
    if (std::fabs(excursion) >= 3.0) {
        int mid = a;
        for (int i = a; i <= iMax; ++i)
            if (std::fabs(tilt[size_t(i)] - ref) >= 0.5 * std::fabs(excursion)) {
                mid = i;
                break;
            }
        const double endTurn = std::fabs(tilt[size_t(last)] - ref);
        m.push_back({"A", "supine", settled, t[size_t(a)]});
        m.push_back({"B", "mid-turn", "half the largest tilt first reached", t[size_t(mid)]});
        m.push_back({"C", "turned", "the largest tilt", t[size_t(iMax)]});
        if (last != iMax)
            m.push_back(
                {"D", endTurn < 0.5 * std::fabs(excursion) ? "back" : "end",
                 "the last output" +
                     std::string(endTurn < 0.5 * std::fabs(excursion) ? "" : " (still turned)"),
                 t[size_t(last)]});
    } else {
        m.push_back({"A", "supine", settled, t[size_t(a)]});
        int peak = -1;
        for (size_t i = 0; i < matPeak.size(); ++i)
            if (peak < 0 || matPeak[i] > matPeak[size_t(peak)]) peak = int(i);
        if (peak >= 0) {
            const int p = findNearest(t, run.matTime[size_t(peak)]);
            const int fa = findNearest(run.matTime, t[size_t(a)]);
            if (p != a && p != last && fa >= 0 &&
                matPeak[size_t(peak)] > 1.05 * matPeak[size_t(fa)])
                m.push_back(
                    {"B", "highest peak", "the highest sensel pressure of the run", t[size_t(p)]});
        }
        if (last != a)
            m.push_back(
                {std::string(1, char('A' + m.size())), "end", "the last output", t[size_t(last)]});
    }
    std::stable_sort(m.begin(), m.end(),
                     [](const Moment& p, const Moment& q) { return p.time < q.time; });
    for (size_t i = 0; i < m.size(); ++i) {
        m[i].letter = std::string(1, char('A' + i));
        m[i].frame = findNearest(run.matTime, m[i].time);
    }
    return m;
}

// ------------------------------------------------------------------------------- drawing

/// One frame of the mat, seen from above: head at the top, his right on the left.
std::string drawMat(const Run& run, int f, double scaleMax, const std::string& caption) {
    const double s = std::min(400.0 / run.sizeX, 300.0 / run.sizeY);  // [px/m]
    const double w = run.sizeY * s, h = run.sizeX * s, top = 22, side = 16;
    const double cw = w / run.matColumns, ch = h / run.matRows;
    const double W = w + 2 * side, H = h + top + 22;
    std::ostringstream os;
    os << "<svg xmlns='http://www.w3.org/2000/svg' role='img' class='mat' width='" << num(W, "%.0f")
       << "' height='" << num(H, "%.0f") << "' viewBox='0 0 " << num(W, "%.1f") << " "
       << num(H, "%.1f") << "' font-family='sans-serif' font-size='11'><title>" << escape(caption)
       << "</title><text x='" << num(W / 2, "%.1f")
       << "' y='14' text-anchor='middle'>head</text><text x='" << num(W / 2, "%.1f") << "' y='"
       << num(H - 6, "%.1f") << "' text-anchor='middle'>feet</text><text x='" << side << "' y='"
       << num(H - 6, "%.1f") << "' font-size='10'>R</text><text x='" << num(W - side, "%.1f")
       << "' y='" << num(H - 6, "%.1f") << "' text-anchor='end' font-size='10'>L</text><rect x='"
       << side << "' y='" << top << "' width='" << num(w, "%.1f") << "' height='" << num(h, "%.1f")
       << "' fill='#fff' stroke='#999'/><g shape-rendering='crispEdges'>";
    int pr = -1, pc = -1;
    double peak = 0.0;
    for (int c = 0; c < run.matColumns; ++c)
        for (int r = 0; r < run.matRows; ++r) {
            const double p = run.at(f, r, c) / kMmHg;
            if (p > peak) peak = p, pr = r, pc = c;
            if (!(p >= 0.5)) continue;  // white: no contact
            os << "<rect x='" << num(side + (run.matColumns - 1 - c) * cw, "%.1f") << "' y='"
               << num(top + (run.matRows - 1 - r) * ch, "%.1f") << "' width='"
               << num(cw + 0.3, "%.1f") << "' height='" << num(ch + 0.3, "%.1f") << "' fill='"
               << svg::getViridis(p / scaleMax) << "'/>";
        }
    os << "</g>";
    if (pr >= 0) {  // the peak sensel: a ring readable on any colour
        const double cx = side + (run.matColumns - 0.5 - pc) * cw,
                     cy = top + (run.matRows - 0.5 - pr) * ch;
        const double rad = std::max(cw, ch) * 0.5 + 5;
        os << "<circle cx='" << num(cx, "%.1f") << "' cy='" << num(cy, "%.1f") << "' r='"
           << num(rad, "%.1f") << "' fill='none' stroke='#000' stroke-width='3'/><circle cx='"
           << num(cx, "%.1f") << "' cy='" << num(cy, "%.1f") << "' r='" << num(rad, "%.1f")
           << "' fill='none' stroke='#fff' stroke-width='1.2'/>";
    }
    return os.str() + "</svg>";
}

/// The colour scale of the mat images [mmHg], with the 32 mmHg reference.
std::string drawColourBar(double scaleMax, bool saturated) {
    report::ColourBar b;
    b.lo = 0.0;
    b.hi = scaleMax;
    b.label = "pressure [mmHg]";
    b.title = "colour scale: contact pressure in mmHg";
    b.saturatedTop = saturated;
    b.ref = kThresholdMmHg;
    b.refLabel = "32";
    b.swatches = {{"#fff", "below 0.5"}};
    b.note = "ring: the peak sensel";
    return report::drawColourBar(b);
}

/// Per time, the values of a column for each key (region, bag) of a long-format table.
struct Curves {
    std::vector<std::string> keys;  ///< in first-seen order
    std::map<std::string, svg::Series> byKey;
};

Curves collect(const Table& t, const std::string& keyColumn, const std::string& valueColumn,
               double scale = 1.0) {
    Curves c;
    const int ti = t.find("time_s"), ki = t.find(keyColumn), vi = t.find(valueColumn);
    for (size_t r = 0; r < t.rows.size(); ++r) {
        const std::string& k = t.text(r, ki);
        auto it = c.byKey.find(k);
        if (it == c.byKey.end()) {
            c.keys.push_back(k);
            it = c.byKey.emplace(k, svg::Series{}).first;
        }
        it->second.x.push_back(t.number(r, ti));
        it->second.y.push_back(t.number(r, vi) * scale);
    }
    return c;
}

std::string formatTime(double t) { return num(t, "%.2f") + " s"; }

struct PageContext {
    std::vector<svg::Marker> markers;
    std::vector<svg::Band> bands;
    double tEnd = kNaN;
};

svg::PlotOptions timePlot(const PageContext& ctx, const std::string& title,
                          const std::string& yLabel) {
    svg::PlotOptions o;
    o.title = title;
    o.xLabel = "time since the release [s]";
    o.yLabel = yLabel;
    o.markers = ctx.markers;
    o.bands = ctx.bands;
    o.xMin = 0.0;
    if (std::isfinite(ctx.tEnd) && ctx.tEnd > 0) o.xMax = ctx.tEnd;
    return o;
}

/// Bags coloured by their column (side of the bed), one legend entry per column.
std::vector<svg::Series> bagSeries(const Run& run, Curves c) {
    std::vector<svg::Series> out;
    std::set<int> named;
    std::vector<std::pair<int, std::string>> order;
    for (const std::string& k : c.keys) order.push_back({std::atoi(k.c_str()), k});
    std::sort(order.begin(), order.end());
    for (const auto& [bag, key] : order) {
        svg::Series s = c.byKey[key];
        const int group = run.columns > 0 ? bag % run.columns : bag;
        s.colour = svg::getCategoryColour(group);
        s.dash = svg::getCategoryDash(group);
        s.width = 1.2;
        if (named.insert(group).second) {
            if (run.columns > 0) {
                s.name = "column " + std::to_string(group);
                if (group == 0) s.name += " (his left)";
                if (group == run.columns - 1 && group > 0) s.name += " (his right)";
            } else {
                s.name = "bag " + key;
            }
        }
        out.push_back(std::move(s));
    }
    return out;
}

using report::kCss;

/// A verdict value to 4 significant digits when it is a number, as written otherwise.
std::string formatValue(const std::string& cell) {
    char* end = nullptr;
    const double v = std::strtod(cell.c_str(), &end);
    if (cell.empty() || end != cell.c_str() + cell.size() || !std::isfinite(v)) return escape(cell);
    return num(v, "%.4g");
}

std::string statusCell(const std::string& status) { return report::formatStatusCell(status); }

}  // namespace

std::string formatArrayReportHtml(const fs::path& runDir) {
    Run run = readRun(runDir);
    const std::vector<Event> events = getEvents(run);
    const bool incomplete = !run.marker.empty() || run.status != "complete";

    // Tilt (the time base of the key moments).
    std::vector<double> t, pelvis, thorax, tiltMean;
    {
        const int ti = run.tilt.find("time_s"), pi = run.tilt.find("pelvis_tilt_deg"),
                  hi = run.tilt.find("thorax_tilt_deg");
        for (size_t r = 0; r < run.tilt.rows.size(); ++r) {
            t.push_back(run.tilt.number(r, ti));
            pelvis.push_back(run.tilt.number(r, pi));
            thorax.push_back(run.tilt.number(r, hi));
            tiltMean.push_back(0.5 * (pelvis.back() + thorax.back()));
        }
    }
    const int frames = run.getFrames();
    const std::vector<double>& matPeak = run.matPeak;    // [mmHg]
    const std::vector<double>& matAbove = run.matAbove;  // [cm^2] of sensels above 32 mmHg
    std::vector<Moment> moments = pickMoments(run, events, t, tiltMean, matPeak);
    if (t.empty() && frames > 0)  // no tilt rows yet: the last frame alone
        moments.push_back(
            {"A", "end", "the last output", run.matTime[size_t(frames - 1)], frames - 1});

    {
        std::vector<int> keys;
        for (const Moment& m : moments)
            if (m.frame >= 0) keys.push_back(m.frame);
        try {
            run.loadFrames(keys);
        } catch (const std::exception& e) {
            throw InputError((run.dir / kResultsH5).string(), 0, "", e.what());
        }
    }
    PageContext ctx;
    ctx.tEnd = t.empty() ? (frames ? run.matTime[size_t(frames - 1)] : kNaN) : t.back();
    for (const Moment& m : moments)
        ctx.markers.push_back(
            {m.time, m.letter, m.letter + ": " + m.name + " at " + formatTime(m.time), "#222"});
    for (size_t i = 0; i < events.size(); ++i)
        ctx.markers.push_back(
            {events[i].time, std::to_string(i + 1),
             std::to_string(i + 1) + ": " + events[i].text + " at " + formatTime(events[i].time),
             "#0072B2", 1});
    const double settle = getSettleEnd(run, events);
    if (std::isfinite(settle) && settle > 0) ctx.bands.push_back({0.0, settle, "settle"});

    std::ostringstream os;
    os << "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><meta name='viewport' "
          "content='width=device-width, initial-scale=1'><title>bagsim report: "
       << escape(run.name) << "</title><style>" << kCss << "</style></head><body>";
    os << "<h1>" << escape(run.name) << "</h1><p class='muted'>Patient on an airbag array, "
       << "simulated by bagsim " << escape(run.version) << (run.started.empty() ? "" : ", started ")
       << escape(run.started) << ". Report made from the folder <code>" << escape(run.dir.string())
       << "</code>.</p>";
    if (incomplete) {
        os << "<div class='banner' id='incomplete'><b>INCOMPLETE RESULTS</b>: this run did not "
              "finish (status <b>"
           << escape(run.status.empty() ? "unknown" : run.status) << "</b>). "
           << escape(run.message.empty() ? "" : run.message + ". ")
           << (std::isfinite(ctx.tEnd)
                   ? "Everything below stops at " + formatTime(ctx.tEnd)
                   : std::string("The run wrote nothing before it stopped, at"));
        if (std::isfinite(run.settle) && std::isfinite(run.duration))
            os << (std::isfinite(ctx.tEnd) ? " of the " : " the start of the ")
               << formatTime(run.settle + run.duration) << " planned";
        os << "; do not read it as the outcome of the whole scenario.</div>";
    }

    // The scenario.
    os << "<h2>Scenario</h2><table>";
    auto row = [&](const std::string& k, const std::string& v) {
        if (!v.empty()) os << "<tr><th>" << k << "</th><td>" << escape(v) << "</td></tr>";
    };
    row("description", run.description);
    row("patient", run.patient);
    row("array", run.array);
    row("run", run.schedule);
    row("status", run.status + (run.finished.empty() ? "" : " (ended " + run.finished + ")"));
    row("scenario file", run.scenarioFile);
    row("command", run.commandLine);
    os << "</table>";
    if (!run.scenarioProblem.empty())
        os << "<p class='muted'>The scenario text could not be read for its keys ("
           << escape(run.scenarioProblem) << "); its text follows as written.</p>";
    os << "<details><summary>Scenario file as run</summary><pre>" << escape(run.scenarioText);
    for (const std::string& o : run.overrides) os << "\n# --set " << escape(o);
    os << "</pre></details>";

    // The verdict.
    os << "<h2>Verdict</h2>";
    if (run.verdict.present) {
        const Table& v = run.verdict;
        const int ci = v.find("check"), si = v.find("status"), vi = v.find("value"),
                  ui = v.find("unit"), di = v.find("detail");
        std::map<std::string, int> count;
        for (size_t r = 0; r < v.rows.size(); ++r) ++count[lower(v.text(r, si))];
        os << "<p>" << count["ok"] << " ok, " << count["warning"] << " warning"
           << (count["warning"] == 1 ? "" : "s") << ", " << count["fail"] << " failed"
           << (incomplete ? " (on the part of the run that was computed)" : "")
           << ".</p><table id='verdict'><tr><th>check</th><th>status</th><th>value</th>"
              "<th>detail</th></tr>";
        // Problems first (fail, warning, ok, n/a), each group in the file's order.
        auto rank = [&](size_t r) {
            const std::string x = lower(v.text(r, si));
            return x == "fail" ? 0 : x == "warning" ? 1 : x == "ok" ? 2 : 3;
        };
        std::vector<size_t> order(v.rows.size());
        for (size_t r = 0; r < order.size(); ++r) order[r] = r;
        std::stable_sort(order.begin(), order.end(),
                         [&](size_t a, size_t b) { return rank(a) < rank(b); });
        for (size_t r : order)
            os << "<tr><td>" << escape(v.text(r, ci)) << "</td>" << statusCell(v.text(r, si))
               << "<td class='n'>" << formatValue(v.text(r, vi))
               << (v.text(r, ui).empty() ? "" : " " + escape(v.text(r, ui))) << "</td><td>"
               << escape(v.text(r, di)) << "</td></tr>";
        os << "</table>";
    } else {
        os << "<p class='muted'>No verdict.csv in this folder (a run made before the verdict "
              "was written, or one that stopped before it).</p>";
    }

    // The pressure mat at the key moments.
    os << "<h2>Pressure under him at key moments</h2>";
    if (frames == 0 || moments.empty()) {
        os << "<p class='muted'>No pressure-mat frames in results.h5.</p>";
    } else {
        double top = 0.0;
        for (const Moment& m : moments) top = std::max(top, matPeak[size_t(m.frame)]);
        const double scaleMax =
            std::clamp(10.0 * std::ceil(top / 10.0), 40.0, kScaleCapMmHg);         // [mmHg]
        const double cell = run.sizeX / run.matRows * run.sizeY / run.matColumns;  // [m^2]
        os << "<p>The virtual pressure mat (" << run.matRows << " x " << run.matColumns
           << " sensels of " << num(run.sizeX / run.matRows * 1e3, "%.0f") << " x "
           << num(run.sizeY / run.matColumns * 1e3, "%.0f")
           << " mm) seen from above, head at the top: his right side on the left. One colour "
              "scale for all pictures; white is no contact; the black mark on the scale is "
              "32 mmHg, the usual reference for pressure-ulcer risk.</p><div class='mats'>";
        for (const Moment& m : moments) {
            const int f = m.frame;
            int above = 0;
            for (int c = 0; c < run.matColumns; ++c)
                for (int r = 0; r < run.matRows; ++r)
                    above += run.at(f, r, c) / kMmHg > kThresholdMmHg;
            const std::string caption =
                m.letter + ". " + m.name + " at " + formatTime(run.matTime[size_t(f)]);
            os << "<figure>" << drawMat(run, f, scaleMax, caption) << "<figcaption><b>"
               << escape(caption) << "</b> (" << escape(m.why) << ")<br>peak <b>"
               << num(matPeak[size_t(f)], "%.0f") << " mmHg</b>; "
               << num(above * cell * 1e4, "%.0f") << " cm&#178; above 32 mmHg";
            const int ti = findNearest(t, m.time);
            if (ti >= 0)
                os << "; tilt pelvis " << num(pelvis[size_t(ti)], "%+.1f") << "&#176;, thorax "
                   << num(thorax[size_t(ti)], "%+.1f") << "&#176;";
            os << "</figcaption></figure>";
        }
        os << "<figure>" << drawColourBar(scaleMax, top > scaleMax) << "</figure></div>";
        if (top > scaleMax)
            os << "<p class='muted'>Sensels above " << num(scaleMax, "%.0f")
               << " mmHg take the top colour; the captions give each picture's true peak.</p>";
    }

    // Time plots.
    os << "<h2>Over time</h2><p>Shaded: the settle. Letters mark the key moments above";
    if (!events.empty()) os << ", numbers the events listed below";
    os << ". Hover a mark for its time.</p><div class='plots'>";
    {
        svg::PlotOptions o = timePlot(ctx, "Tilt (positive: onto his left side)", "tilt [deg]");
        o.refLines.push_back({0.0, "", "#999"});
        os << svg::plot(o, {{"pelvis", svg::getCategoryColour(0), t, pelvis},
                            {"thorax", svg::getCategoryColour(1), t, thorax, false, "6 3"}});
    }
    if (frames > 0) {
        const std::vector<double> mt(run.matTime.begin(), run.matTime.begin() + frames);
        svg::PlotOptions o = timePlot(ctx, "Pressure mat: highest sensel", "pressure [mmHg]");
        o.yMin = 0.0;
        o.refLines.push_back({kThresholdMmHg, "32 mmHg", "#b00"});
        os << svg::plot(o, {{"highest sensel", svg::getCategoryColour(0), mt, matPeak}});
        svg::PlotOptions a = timePlot(ctx, "Pressure mat: area above 32 mmHg", "area [cm\u00b2]");
        a.yMin = 0.0;
        os << svg::plot(a, {{"sensels above 32 mmHg", svg::getCategoryColour(1), mt, matAbove}});
    }
    if (run.body.present && !run.body.rows.empty()) {
        const Table& b = run.body;
        std::vector<double> bt, y, z;
        for (size_t r = 0; r < b.rows.size(); ++r) {
            bt.push_back(b.number(r, b.find("time_s")));
            y.push_back(b.number(r, b.find("com_y_mm")));
            z.push_back(b.number(r, b.find("com_z_mm")));
        }
        os << svg::plot(
            timePlot(ctx, "Centre of mass across the bed (+: towards his right)", "y [mm]"),
            {{"across (y)", svg::getCategoryColour(0), bt, y}});
        os << svg::plot(timePlot(ctx, "Centre of mass height above the bed board", "z [mm]"),
                        {{"height (z)", svg::getCategoryColour(2), bt, z}});
    }
    os << svg::plot(timePlot(ctx, "Bag gauge pressure", "pressure [kPa]"),
                    bagSeries(run, collect(run.bags, "bag", "pressure_kPa")));
    os << svg::plot(timePlot(ctx, "Gas in each bag", "gas mass [g]"),
                    bagSeries(run, collect(run.bags, "bag", "mass_g")));
    os << svg::plot(timePlot(ctx, "Force of each bag on him", "force [N]"),
                    bagSeries(run, collect(run.bags, "bag", "force_N")));
    if (run.pneumatics.present && !run.pneumatics.rows.empty()) {
        os << svg::plot(timePlot(ctx, "Pressure sensors", "sensor reading [kPa]"),
                        bagSeries(run, collect(run.pneumatics, "bag", "sensor_kPa")));
        Curves in = collect(run.pneumatics, "bag", "inflow_g_per_s");
        const Curves out = collect(run.pneumatics, "bag", "outflow_g_per_s");
        for (auto& [k, s] : in.byKey)
            for (size_t i = 0; i < s.y.size() && i < out.byKey.at(k).y.size(); ++i)
                s.y[i] -= out.byKey.at(k).y[i];
        os << svg::plot(timePlot(ctx, "Net gas flow into each bag (in - out)", "flow [g/s]"),
                        bagSeries(run, in));
    }
    os << "</div>";

    // Regions: one small chart each, on one scale, the most loaded first.
    os << "<h2>Peak pressure per body region</h2>";
    {
        const Curves ppi = collect(run.regions, "region", "ppi_mmHg");
        const Curves area = collect(run.regions, "region", "area_cm2");
        const Curves force = collect(run.regions, "region", "force_N");
        // The patch peak (regions.csv of runs before it was written has no such column).
        const bool hasPatch = run.regions.find("patch_peak_mmHg") >= 0;
        const Curves patch =
            hasPatch ? collect(run.regions, "region", "patch_peak_mmHg") : Curves{};
        // The immersion (likewise absent from older runs' regions.csv; empty with reduced
        // bags, which have no film to measure it on).
        const int immersionColumn = run.regions.find("immersion_mm");
        bool hasImmersion = immersionColumn >= 0;
        for (size_t r = 0; hasImmersion && r < run.regions.rows.size(); ++r)
            hasImmersion = !run.regions.text(r, immersionColumn).empty();
        const Curves immersion =
            hasImmersion ? collect(run.regions, "region", "immersion_mm") : Curves{};
        const bool hasRisk = run.regions.find("area_above_32_cm2") >= 0;
        const Curves risk =
            hasRisk ? collect(run.regions, "region", "area_above_32_cm2") : Curves{};
        struct R {
            std::string name;
            double max, at, area, force, patch, immersion, risk;
        };
        std::vector<R> rs;
        double top = kThresholdMmHg;
        for (const std::string& k : ppi.keys) {
            const svg::Series& s = ppi.byKey.at(k);
            const size_t i = size_t(std::max_element(s.y.begin(), s.y.end()) - s.y.begin());
            const auto& a = area.byKey.at(k).y;
            const auto& f = force.byKey.at(k).y;
            double pp = 0.0, deepest = 0.0, atRisk = 0.0;
            if (hasPatch)
                for (double v : patch.byKey.at(k).y) pp = std::max(pp, v);
            if (hasImmersion)
                for (double v : immersion.byKey.at(k).y) deepest = std::max(deepest, v);
            if (hasRisk)
                for (double v : risk.byKey.at(k).y) atRisk = std::max(atRisk, v);
            rs.push_back({k, s.y[i], s.x[i], *std::max_element(a.begin(), a.end()),
                          *std::max_element(f.begin(), f.end()), pp, deepest, atRisk});
            top = std::max(top, s.y[i]);
        }
        std::sort(rs.begin(), rs.end(), [](const R& a, const R& b) { return a.max > b.max; });
        if (rs.empty()) {
            os << "<p class='muted'>No region touched the bags in the rows written.</p>";
        } else {
            os << "<p>The highest nodal contact pressure (PPI) in each region that touched the "
                  "bags, on one scale; dashed: 32 mmHg. A region with no row at a time had no "
                  "contact then."
               << (hasPatch ? " The patch peak is the highest mean pressure over a disc of "
                              "20 cm&#178; of the region: unlike the nodal PPI it does not "
                              "depend on the bags' mesh."
                            : "")
               << (hasImmersion ? " The immersion is the most the region pushed a point of "
                                  "the films down from where it stood before he lay on them."
                                : "")
               << "</p><table><tr><th>region</th><th>highest PPI</th><th>at</th>"
               << (hasPatch ? "<th>highest patch peak</th>" : "")
               << "<th>largest contact area</th><th>largest force</th>"
               << (hasRisk ? "<th>largest area above 32 mmHg</th>" : "")
               << (hasImmersion ? "<th>deepest immersion</th>" : "") << "</tr>";
            for (const R& r : rs) {
                os << "<tr><td>" << escape(r.name) << "</td><td class='n'>" << num(r.max, "%.1f")
                   << " mmHg</td><td class='n'>" << formatTime(r.at) << "</td><td class='n'>";
                if (hasPatch) os << num(r.patch, "%.1f") << " mmHg</td><td class='n'>";
                os << num(r.area, "%.1f") << " cm&#178;</td><td class='n'>" << num(r.force, "%.1f")
                   << " N</td>";
                if (hasRisk) os << "<td class='n'>" << num(r.risk, "%.1f") << " cm&#178;</td>";
                if (hasImmersion) os << "<td class='n'>" << num(r.immersion, "%.1f") << " mm</td>";
                os << "</tr>";
            }
            os << "</table><div class='plots'>";
            const double yMax = svg::calcRoundUp(top * 1.05);
            for (const R& r : rs) {
                svg::PlotOptions o = timePlot(
                    ctx, r.name + ": highest " + num(r.max, "%.0f") + " mmHg", "PPI [mmHg]");
                o.width = 300;
                o.height = 200;
                o.yMin = 0;
                o.yMax = yMax;
                o.refLines.push_back({kThresholdMmHg, "32", "#b00"});
                svg::Series s = ppi.byKey.at(r.name);
                // Break the line where the region had no contact (no row at an output time).
                svg::Series g;
                g.colour = svg::getCategoryColour(0);
                for (size_t i = 0; i < s.x.size(); ++i) {
                    if (i > 0 && !t.empty()) {
                        const int a = findNearest(t, s.x[i - 1]), b = findNearest(t, s.x[i]);
                        if (b - a > 1) g.x.push_back(kNaN), g.y.push_back(kNaN);
                    }
                    g.x.push_back(s.x[i]);
                    g.y.push_back(s.y[i]);
                }
                os << svg::plot(o, {g});
            }
            os << "</div>";
        }
    }

    if (!events.empty()) {
        os << "<h2>Events</h2><table><tr><th>#</th><th>time</th><th>event</th></tr>";
        for (size_t i = 0; i < events.size(); ++i)
            os << "<tr><td class='n'>" << i + 1 << "</td><td class='n'>"
               << formatTime(events[i].time) << "</td><td>" << escape(events[i].text)
               << "</td></tr>";
        os << "</table>";
    }
    if (!run.summary.empty()) os << "<h2>Summary</h2><pre>" << escape(run.summary) << "</pre>";
    if (!run.marker.empty())
        os << "<h2>INCOMPLETE marker</h2><pre>" << escape(run.marker) << "</pre>";
    os << "<p class='muted'>Units: pressures on the skin in mmHg (1 mmHg = 133.3 Pa), bag "
          "pressures in kPa gauge, gas in g, times in s from the release of the patient above "
          "the bags. How to read this page: docs/reading-the-report.md of bagsim.</p>"
       << "</body></html>\n";
    return os.str();
}

void writeArrayReport(const fs::path& runDir, const fs::path& out) {
    report::writePageFile(formatArrayReportHtml(runDir), out);
}

}  // namespace io
