#include <io/InputError.h>
#include <io/StudyReport.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "Hdf5.h"
#include "ReportPage.h"
#include "SvgPlot.h"

namespace io {

namespace fs = std::filesystem;

namespace {

using report::CsvTable;
using svg::escape;
using svg::num;

const double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kStudyCsv = "study.csv";
constexpr const char* kStudyH5 = "study.h5";
constexpr const char* kStamp = ".bagsim-study";
constexpr const char* kMarker = "INCOMPLETE";
/// Lines in one chart before the cases are drawn as one cloud of points (a random sample).
constexpr size_t kMaxSeries = 14;
/// Load-displacement curves in one chart (one colour each).
constexpr size_t kCurvesPerChart = 7;
/// A map's colour scale spans at least this share of its mean: differences below about 1 %
/// do not look like contrasts.
constexpr double kMinMapSpan = 0.05;

bool parseNumber(const std::string& cell, double* v) {
    if (cell.empty()) return false;
    char* end = nullptr;
    *v = std::strtod(cell.c_str(), &end);
    return end == cell.c_str() + cell.size() && std::isfinite(*v);
}

// -------------------------------------------------------------------- names and units

/// The unit a results column's name ends in ("stiffness_N_per_mm" -> "N/mm"), "" if none.
std::pair<std::string, std::string> splitUnit(const std::string& column) {
    static const std::pair<const char*, const char*> kTails[] = {
        {"_N_per_mm", "N/mm"}, {"_g_per_s", "g/s"},  {"_kPa", "kPa"}, {"_mmHg", "mmHg"},
        {"_Pa", "Pa"},         {"_cm2", "cm\u00b2"}, {"_deg", "deg"}, {"_percent", "%"},
        {"_N", "N"},           {"_mm", "mm"},        {"_kg", "kg"},   {"_g", "g"},
        {"_s", "s"},           {"_m", "m"},          {"_l", "l"},     {"_J", "J"}};
    for (const auto& [tail, unit] : kTails) {
        const std::string t = tail;
        if (column.size() > t.size() && column.compare(column.size() - t.size(), t.size(), t) == 0)
            return {column.substr(0, column.size() - t.size()), unit};
    }
    return {column, ""};
}

std::string words(std::string s) {
    if (s == "r2") return "r\u00b2";
    std::replace(s.begin(), s.end(), '_', ' ');
    return s;
}

/// What a scenario key means, for axis labels (the key itself where none is known).
std::string describeKey(const std::string& key) {
    static const std::map<std::string, std::string> kNames = {
        {"test.gas_masses", "gas mass of the pressed bag"},
        {"airbag.neighbours.gas_mass", "neighbours' gas mass"},
        {"airbag.neighbours.layout", "neighbours"},
        {"airbag.neighbours.pressed", "pressed position [along, across]"},
        {"airbag.neighbours.gap", "gap between neighbours"},
        {"contact.penalty", "contact penalty"},
        {"airbag.mesh_size", "mesh size"},
        {"patient.mass", "patient's mass"},
        {"patient.height", "patient's height"}};
    const auto it = kNames.find(key);
    return it == kNames.end() ? key : it->second;
}

/// A short name for legends ("gas mass", "layout"): the known one, else the key's last part.
std::string shortKey(const std::string& key) {
    static const std::map<std::string, std::string> kNames = {
        {"test.gas_masses", "gas mass"},
        {"airbag.neighbours.gas_mass", "neighbours' gas mass"},
        {"airbag.neighbours.layout", "layout"},
        {"airbag.neighbours.pressed", "pressed"},
        {"contact.penalty", "penalty"}};
    const auto it = kNames.find(key);
    if (it != kNames.end()) return it->second;
    const auto dot = key.rfind('.');
    return dot == std::string::npos ? key : key.substr(dot + 1);
}

/// A number to 4 significant digits as a study file writes it ("3.5", "1e7", "2.5e-3").
std::string formatNumber(double v) {
    std::string t = num(v, "%.4g");
    const auto e = t.find('e');
    if (e == std::string::npos) return t;
    std::string mant = t.substr(0, e), exp = t.substr(e + 1);
    const bool negative = !exp.empty() && exp[0] == '-';
    if (!exp.empty() && (exp[0] == '+' || exp[0] == '-')) exp.erase(0, 1);
    while (exp.size() > 1 && exp[0] == '0') exp.erase(0, 1);
    return mant + "e" + (negative ? "-" : "") + exp;
}

bool endsWith(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// -------------------------------------------------------------------------- the folder

struct Parameter {
    std::string key, unit;
    int column = -1;
    bool numeric = true;
    std::vector<double> values;         ///< per row (NaN if not numeric)
    std::vector<std::string> distinct;  ///< cell texts in first-seen order
};

struct Output {
    std::string name;  ///< the table's column
    int column = -1;
    bool numeric = false;
    std::string label, unit;     ///< "stiffness (min)", "N/mm"
    std::vector<double> values;  ///< per row, NaN where empty
    std::string getAxis() const { return unit.empty() ? label : label + " [" + unit + "]"; }
};

struct Study {
    fs::path dir;
    CsvTable table;
    int caseColumn = -1, keyColumn = -1, statusColumn = -1, reasonColumn = -1, secondsColumn = -1;
    std::vector<Parameter> parameters;
    std::vector<Output> outputs;
    // study.h5
    bool haveH5 = false;
    std::string h5Problem, studyFile, studyText, baseText, commandLine, version, h5Status;
    std::string marker;  ///< INCOMPLETE's text
    // The study file's keys.
    std::string name, description, baseScenario, studyProblem;
    std::vector<std::pair<std::string, std::string>> sets;
    std::vector<std::string> outputSpecs;

    const std::string& status(size_t r) const { return table.text(r, statusColumn); }
    const std::string& reason(size_t r) const { return table.text(r, reasonColumn); }
    const std::string& key(size_t r) const { return table.text(r, keyColumn); }
    std::string caseNumber(size_t r) const { return table.text(r, caseColumn); }

    /// A parameter's value in a row, with its unit ("3.5 g", "pair", "[-1, 0]").
    std::string formatValue(size_t p, size_t r) const {
        const Parameter& q = parameters[p];
        if (q.numeric) return formatNumber(q.values[r]) + (q.unit.empty() ? "" : " " + q.unit);
        return table.text(r, q.column);
    }
    /// "gas mass=3.5 g, layout=pair" over the parameters not in `skip`.
    std::string describeRow(size_t r, const std::set<size_t>& skip = {}) const {
        std::string d;
        for (size_t p = 0; p < parameters.size(); ++p)
            if (!skip.count(p))
                d +=
                    (d.empty() ? "" : ", ") + shortKey(parameters[p].key) + "=" + formatValue(p, r);
        return d;
    }
};

Output makeOutput(const std::string& name, int column) {
    Output o;
    o.name = name;
    o.column = column;
    std::string base = name, per, perValue, reduce;
    if (const auto b = name.find('['); b != std::string::npos && name.back() == ']') {
        base = name.substr(0, b);
        const std::string inside = name.substr(b + 1, name.size() - b - 2);
        const auto eq = inside.find('=');
        per = inside.substr(0, eq);
        perValue = eq == std::string::npos ? "" : inside.substr(eq + 1);
        if (const auto c = base.rfind(':'); c != std::string::npos) {  // COLUMN:REDUCE[PER=V]
            reduce = base.substr(c + 1);
            base = base.substr(0, c);
        }
    } else if (const auto c = name.rfind(':'); c != std::string::npos) {
        base = name.substr(0, c);
        reduce = name.substr(c + 1);
    }
    const auto [stem, unit] = splitUnit(base);
    o.label = words(stem) + (reduce.empty() ? "" : " (" + reduce + ")");
    o.unit = unit;
    if (!per.empty()) {
        const auto [perStem, perUnit] = splitUnit(per);
        o.label +=
            " at " + words(perStem) + " " + perValue + (perUnit.empty() ? "" : " " + perUnit);
    }
    return o;
}

void readH5(Study& s) {
    const fs::path p = s.dir / kStudyH5;
    std::error_code ec;
    if (!fs::exists(p, ec)) return;
    try {
        h5::silenceErrors();
        h5::Handle file = h5::openFileReadOnly(p.string());
        auto str = [&](const char* key) {
            return h5::hasAttribute(file.get(), key) ? h5::readStringAttribute(file.get(), key)
                                                     : std::string();
        };
        s.studyFile = str("study_file");
        s.studyText = str("study_text");
        s.baseText = str("base_scenario_text");
        s.commandLine = str("command_line");
        s.version = str("version");
        s.h5Status = str("status");
        s.haveH5 = true;
    } catch (const std::exception& e) {
        s.h5Problem = e.what();
    }
}

void readStudyText(Study& s) {
    if (s.studyText.empty()) return;
    try {
        const YAML::Node root = YAML::Load(s.studyText);
        if (root["name"] && root["name"].IsScalar()) s.name = root["name"].Scalar();
        if (root["description"] && root["description"].IsScalar())
            s.description = root["description"].Scalar();
        if (root["scenario"] && root["scenario"].IsScalar())
            s.baseScenario = root["scenario"].Scalar();
        auto flow = [](const YAML::Node& n) {
            if (n.IsScalar()) return n.Scalar();
            YAML::Emitter e;
            e << YAML::Flow << n;
            return std::string(e.c_str());
        };
        if (root["set"] && root["set"].IsMap())
            for (const auto& kv : root["set"])
                s.sets.push_back({kv.first.Scalar(), flow(kv.second)});
        if (root["outputs"] && root["outputs"].IsSequence())
            for (const auto& o : root["outputs"]) s.outputSpecs.push_back(flow(o));
    } catch (const std::exception& e) {
        s.studyProblem = e.what();
    }
}

Study readStudy(const fs::path& dir) {
    Study s;
    s.dir = dir;
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw InputError(dir.string(), 0, "",
                         "is not a folder; give the folder bagsim study wrote (--out DIR)");
    if (!fs::exists(dir / kStudyCsv, ec))
        throw InputError(dir.string(), 0, "",
                         "a study's folder without study.csv: the study has not written its "
                         "table yet; run it (bagsim study STUDY.yaml --out " +
                             dir.string() + ") and the page is written at its end");
    s.table = report::readCsvTable(dir / kStudyCsv, {"case", "key", "status", "reason", "seconds"},
                                   false, "");
    const CsvTable& t = s.table;
    s.caseColumn = t.find("case");
    s.keyColumn = t.find("key");
    s.statusColumn = t.find("status");
    s.reasonColumn = t.find("reason");
    s.secondsColumn = t.find("seconds");
    if (!(s.keyColumn < s.statusColumn && s.statusColumn + 2 == s.secondsColumn))
        throw InputError(t.path, 1, "",
                         "the columns are not those of a study table: case, key, the "
                         "parameters, status, reason, seconds, the outputs (docs/studies.md)");
    for (int c = s.keyColumn + 1; c < s.statusColumn; ++c) {
        Parameter p;
        p.column = c;
        const std::string& h = t.header[size_t(c)];
        const auto b = h.rfind(" [");
        if (b != std::string::npos && h.back() == ']') {
            p.key = h.substr(0, b);
            p.unit = h.substr(b + 2, h.size() - b - 3);
        } else {
            p.key = h;
        }
        for (size_t r = 0; r < t.rows.size(); ++r) {
            double v = kNaN;
            if (!parseNumber(t.text(r, c), &v)) p.numeric = false;
            p.values.push_back(v);
            if (std::find(p.distinct.begin(), p.distinct.end(), t.text(r, c)) == p.distinct.end())
                p.distinct.push_back(t.text(r, c));
        }
        if (!p.numeric) std::fill(p.values.begin(), p.values.end(), kNaN);
        s.parameters.push_back(std::move(p));
    }
    for (int c = s.secondsColumn + 1; c < int(t.header.size()); ++c) {
        Output o = makeOutput(t.header[size_t(c)], c);
        bool any = false, allNumbers = true;
        for (size_t r = 0; r < t.rows.size(); ++r) {
            double v = kNaN;
            const std::string& cell = t.text(r, c);
            if (cell.empty()) {
                o.values.push_back(kNaN);
            } else if (parseNumber(cell, &v)) {
                o.values.push_back(v);
                any = true;
            } else {
                o.values.push_back(kNaN);
                allNumbers = false;
            }
        }
        o.numeric = any && allNumbers;
        s.outputs.push_back(std::move(o));
    }
    readH5(s);
    readStudyText(s);
    s.marker = report::readTextIfPresent(dir / kMarker);
    if (s.studyFile.empty()) {
        // The stamp names the study file of the last run into the folder.
        std::istringstream stamp(report::readTextIfPresent(dir / kStamp));
        for (std::string line; std::getline(stamp, line);)
            if (line.rfind("last study: ", 0) == 0) s.studyFile = line.substr(12);
    }
    if (s.name.empty() && !s.studyFile.empty()) s.name = fs::path(s.studyFile).stem().string();
    if (s.name.empty()) s.name = fs::absolute(dir).lexically_normal().filename().string();
    return s;
}

/// The numeric outputs to draw. A `per` output whose columns each case fills at most one of
/// (one gas mass per case: stiffness_N_per_mm[gas_mass_g=3.5], [=3], ...) is drawn as one
/// output, each case's own value, in place of its columns.
std::vector<Output> mergePerColumns(const Study& s) {
    std::vector<Output> out;
    std::map<std::string, std::vector<size_t>> family;  // base column -> its outputs
    for (size_t i = 0; i < s.outputs.size(); ++i) {
        const std::string& name = s.outputs[i].name;
        const auto b = name.find('[');
        if (s.outputs[i].numeric && b != std::string::npos && name.back() == ']')
            family[name.substr(0, b)].push_back(i);
    }
    std::set<size_t> done;
    for (size_t i = 0; i < s.outputs.size(); ++i) {
        if (done.count(i)) continue;
        const Output& o = s.outputs[i];
        const auto b = o.name.find('[');
        const auto f = b == std::string::npos ? family.end() : family.find(o.name.substr(0, b));
        bool merge = f != family.end() && f->second.size() >= 2;
        for (size_t r = 0; merge && r < s.table.rows.size(); ++r) {
            int filled = 0;
            for (size_t k : f->second) filled += std::isfinite(s.outputs[k].values[r]);
            merge = filled <= 1;
        }
        if (!merge) {
            out.push_back(o);
            continue;
        }
        const std::string inside = o.name.substr(b + 1, o.name.size() - b - 2);
        Output m = makeOutput(o.name.substr(0, b), o.column);
        m.label +=
            " (at the case's " + words(splitUnit(inside.substr(0, inside.find('='))).first) + ")";
        m.numeric = true;
        m.values.assign(s.table.rows.size(), kNaN);
        for (size_t k : f->second) {
            done.insert(k);
            for (size_t r = 0; r < m.values.size(); ++r)
                if (std::isfinite(s.outputs[k].values[r])) m.values[r] = s.outputs[k].values[r];
        }
        out.push_back(std::move(m));
    }
    return out;
}

// ------------------------------------------------------------------------------ charts

/// The rows grouped by the values of the parameters other than `skip`, in first-seen order.
struct Groups {
    std::vector<std::vector<size_t>> rows;  ///< per group, its rows
    std::vector<std::string> names;         ///< per group, "layout=pair, gas mass=3 g"
    std::vector<int> colour, dash;          ///< per group
};

Groups groupRows(const Study& s, const std::set<size_t>& skip) {
    Groups g;
    std::map<std::string, size_t> index;
    // Colours follow the first other parameter, dashes the rest, where there are two or more.
    std::vector<size_t> others;
    for (size_t p = 0; p < s.parameters.size(); ++p)
        if (!skip.count(p)) others.push_back(p);
    std::map<std::string, int> colourOf, dashOf;
    for (size_t r = 0; r < s.table.rows.size(); ++r) {
        const std::string name = s.describeRow(r, skip);
        auto it = index.find(name);
        if (it == index.end()) {
            it = index.emplace(name, g.rows.size()).first;
            g.rows.emplace_back();
            g.names.push_back(name);
            if (others.size() >= 2) {
                const std::string first = s.formatValue(others[0], r);
                std::set<size_t> rest = skip;
                rest.insert(others[0]);
                const std::string tail = s.describeRow(r, rest);
                colourOf.emplace(first, int(colourOf.size()));
                dashOf.emplace(tail, int(dashOf.size()));
                g.colour.push_back(colourOf[first]);
                g.dash.push_back(dashOf[tail]);
            } else {
                g.colour.push_back(int(g.rows.size()) - 1);
                g.dash.push_back(-1);
            }
        }
        g.rows[it->second].push_back(r);
    }
    return g;
}

std::string getDash(int i) {
    static const char* const kDashes[] = {"", "7 3", "2 3", "9 3 2 3", "1 5", "12 5"};
    return kDashes[std::max(i, 0) % 6];
}

/// The parameters other than p whose values go one to one with p's over the table (a zip of
/// two keys swept together: the fill at rest and the controller's setpoint): they do not
/// split p's lines, and p stands for them on its axis.
std::set<size_t> findPartners(const Study& s, size_t p) {
    std::set<size_t> out;
    for (size_t q = 0; q < s.parameters.size(); ++q) {
        if (q == p) continue;
        std::map<std::string, std::string> forward, backward;
        bool oneToOne = true;
        for (size_t r = 0; r < s.table.rows.size() && oneToOne; ++r) {
            const std::string a = s.formatValue(p, r), b = s.formatValue(q, r);
            const auto f = forward.emplace(a, b).first;
            const auto g = backward.emplace(b, a).first;
            oneToOne = f->second == b && g->second == a;
        }
        if (oneToOne) out.insert(q);
    }
    return out;
}

/// `y` (one value per row of the table, NaN where none) against parameter p: one line per
/// combination of the other parameters (those swept with p aside), each case a point on it.
std::string drawAgainst(const Study& s, size_t p, const std::vector<double>& y,
                        const std::string& yAxis, const std::string& titleIn,
                        const std::vector<svg::RefLine>& refLines = {}) {
    const Parameter& q = s.parameters[p];
    std::set<size_t> skip = findPartners(s, p);
    std::string title = titleIn;
    for (size_t k : skip) title += ", " + describeKey(s.parameters[k].key) + " with it";
    skip.insert(p);
    const Groups g = groupRows(s, skip);
    std::vector<svg::Series> series;
    const bool cloud = g.rows.size() > kMaxSeries;
    if (cloud) {
        svg::Series pts;
        pts.name = "each case";
        pts.colour = svg::getCategoryColour(0);
        pts.points = true;
        for (size_t r = 0; r < y.size(); ++r)
            if (std::isfinite(y[r])) pts.x.push_back(q.values[r]), pts.y.push_back(y[r]);
        series.push_back(pts);
    } else {
        for (size_t k = 0; k < g.rows.size(); ++k) {
            std::vector<std::pair<double, double>> xy;
            for (size_t r : g.rows[k])
                if (std::isfinite(y[r]) && std::isfinite(q.values[r]))
                    xy.push_back({q.values[r], y[r]});
            if (xy.empty()) continue;
            std::sort(xy.begin(), xy.end());
            svg::Series line, pts;
            line.name = g.names[k].empty() ? (g.rows.size() == 1 ? "" : "all") : g.names[k];
            line.colour = pts.colour = svg::getCategoryColour(g.colour[k]);
            line.dash = g.dash[k] >= 0 ? getDash(g.dash[k]) : svg::getCategoryDash(g.colour[k]);
            line.width = 1.8;
            for (const auto& [x, v] : xy) {
                line.x.push_back(x), line.y.push_back(v);
                pts.x.push_back(x), pts.y.push_back(v);
            }
            pts.points = true;
            series.push_back(line);
            series.push_back(pts);
        }
    }
    if (series.empty()) return "";
    double lo = INFINITY, hi = -INFINITY;
    for (double v : q.values)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    // Values of 1e5 and more (a contact penalty) in units of a power of ten: readable ticks.
    const double top = std::max(std::fabs(lo), std::fabs(hi));
    double scale = 1.0;
    if (top >= 1e5) {
        // The smallest value's power where all are positive (1e7 and 1e8: ticks 2, 4, ... 10).
        const double ref = lo > 0.0 ? lo : top;
        scale = std::pow(10.0, std::floor(std::log10(ref)));
        for (svg::Series& x : series)
            for (double& v : x.x) v /= scale;
        lo /= scale, hi /= scale;
    }
    svg::PlotOptions o;
    o.title = title;
    const std::string unit =
        (scale != 1.0 ? formatNumber(scale) + (q.unit.empty() ? "" : " ") : "") + q.unit;
    o.xLabel = describeKey(q.key) + (unit.empty() ? "" : " [" + unit + "]");
    o.yLabel = yAxis;
    o.refLines = refLines;
    // A little room either side of the first and last value, so their points show whole.
    const double pad = hi > lo ? 0.04 * (hi - lo) : std::max(std::fabs(lo) * 0.05, 1e-6);
    o.xMin = lo - pad;
    o.xMax = hi + pad;
    return svg::plot(o, series);
}

/// The numeric parameters that take two values or more: what the outputs are drawn against.
std::vector<size_t> findAxes(const Study& s) {
    std::vector<size_t> axes;
    for (size_t p = 0; p < s.parameters.size(); ++p) {
        if (!s.parameters[p].numeric || s.parameters[p].distinct.size() < 2) continue;
        // A parameter swept one to one with an axis already drawn is drawn on that axis.
        bool drawn = false;
        for (size_t q : findPartners(s, p))
            drawn = drawn || std::find(axes.begin(), axes.end(), q) != axes.end();
        if (!drawn) axes.push_back(p);
    }
    return axes;
}

// ----------------------------------------------------------------------- the block map

/// "[-1, 0]" as (along, across); false if the text is not two whole numbers in brackets.
bool parsePosition(const std::string& text, int* along, int* across) {
    int a = 0, c = 0;
    char close = 0;
    if (std::sscanf(text.c_str(), " [ %d , %d %c", &a, &c, &close) != 3 || close != ']')
        return false;
    *along = a, *across = c;
    return true;
}

/// One map: the 3 x 3 block seen from above, +x (along the bags' length) up, +y right; each
/// pressed position coloured by its value, the value written in it.
std::string drawMap(const Study& s, const Output& o, const std::vector<size_t>& rows,
                    size_t pressed, const report::ColourBar& scale, const std::string& caption) {
    const double cw = 92, ch = 74, left = 34, top = 28;
    const double W = left + 3 * cw + 10, H = top + 3 * ch + 40;
    std::map<std::pair<int, int>, size_t> at;
    for (size_t r : rows) {
        int a = 0, c = 0;
        if (parsePosition(s.table.text(r, s.parameters[pressed].column), &a, &c))
            at.emplace(std::make_pair(a, c), r);
    }
    std::ostringstream os;
    os << "<svg xmlns='http://www.w3.org/2000/svg' role='img' class='map' width='" << W
       << "' height='" << H << "' viewBox='0 0 " << W << " " << H
       << "' font-family='sans-serif' font-size='12'><title>" << escape(caption)
       << "</title><rect width='100%' height='100%' fill='#fff'/>"
       << "<text x='" << left + 1.5 * cw << "' y='16' text-anchor='middle' font-weight='bold'>"
       << escape(o.getAxis()) << "</text>";
    for (int i = 0; i < 3; ++i) {      // rows: along = +1 at the top
        for (int j = 0; j < 3; ++j) {  // columns: across = -1 on the left
            const int along = 1 - i, across = j - 1;
            const double x = left + j * cw, y = top + i * ch;
            const auto it = at.find({along, across});
            const std::string pos =
                "[" + std::to_string(along) + ", " + std::to_string(across) + "]";
            std::string fill = "#eeeeee", text = "not pressed", ink = "#666", hover;
            double v = kNaN;
            if (it != at.end()) {
                v = o.values[it->second];
                const std::string& st = s.status(it->second);
                if (std::isfinite(v)) {
                    const double t = (v - scale.lo) / (scale.hi - scale.lo);
                    fill = svg::getViridis(t);
                    ink = t < 0.55 ? "#fff" : "#000";
                    text = num(v, "%.4g");
                    hover = pos + ": " + text + (o.unit.empty() ? "" : " " + o.unit) + " (case " +
                            s.caseNumber(it->second) + ", " + st + ")";
                } else {
                    fill = st == "failed" ? "#f6d0d0" : "#eeeeee";
                    text = st.empty() ? "no value" : st;
                    hover = pos + ": case " + s.caseNumber(it->second) + " " + text;
                }
            } else {
                hover = pos + ": not pressed in this study";
            }
            os << "<g><title>" << escape(hover) << "</title><rect x='" << x << "' y='" << y
               << "' width='" << cw << "' height='" << ch << "' fill='" << fill
               << "' stroke='#fff' stroke-width='2'/><text x='" << x + cw / 2 << "' y='"
               << y + ch / 2 + (std::isfinite(v) ? 2 : 0) << "' text-anchor='middle' fill='" << ink
               << "'"
               << (std::isfinite(v) ? " font-size='15' font-weight='bold'" : " font-size='11'")
               << ">" << escape(text) << "</text><text x='" << x + cw / 2 << "' y='" << y + ch - 8
               << "' text-anchor='middle' font-size='10' fill='" << ink << "'>" << pos
               << "</text></g>";
        }
    }
    // Axes: along the bags' length (x) up the left side, across their width (y) underneath.
    os << "<text x='14' y='" << top + 1.5 * ch << "' transform='rotate(-90 14 " << top + 1.5 * ch
       << ")' text-anchor='middle' font-size='11'>along the bags (x) &#8594;</text><text x='"
       << left + 1.5 * cw << "' y='" << top + 3 * ch + 18
       << "' text-anchor='middle' font-size='11'>across the bags (y) &#8594;</text><text x='"
       << left + 1.5 * cw << "' y='" << top + 3 * ch + 34
       << "' text-anchor='middle' font-size='10' fill='#666'>[along, across]: the pressed "
          "bag's position</text></svg>";
    return os.str();
}

std::string formatSeconds(double t) {
    char b[32];
    const long n = long(t + 0.5);
    if (n >= 3600)
        std::snprintf(b, sizeof b, "%ld h %02ld min", n / 3600, n / 60 % 60);
    else if (n >= 60)
        std::snprintf(b, sizeof b, "%ld min %02ld s", n / 60, n % 60);
    else
        std::snprintf(b, sizeof b, "%.1f s", t);
    return b;
}

}  // namespace

bool isStudyFolder(const fs::path& dir) {
    std::error_code ec;
    return fs::is_directory(dir, ec) &&
           (fs::exists(dir / kStudyCsv, ec) || fs::exists(dir / kStamp, ec));
}

std::string formatStudyReportHtml(const fs::path& studyDir) {
    const Study s = readStudy(studyDir);
    const CsvTable& t = s.table;
    const size_t n = t.rows.size();
    std::map<std::string, int> count;
    for (size_t r = 0; r < n; ++r) ++count[s.status(r)];
    const int missing = count["not-run"] + count["interrupted"];
    const bool incomplete =
        missing > 0 || !s.marker.empty() || (!s.h5Status.empty() && s.h5Status != "complete");
    double seconds = 0.0;
    for (size_t r = 0; r < n; ++r) {
        double v = 0.0;
        if (parseNumber(t.text(r, s.secondsColumn), &v)) seconds += v;
    }

    std::ostringstream os;
    os << "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><meta name='viewport' "
          "content='width=device-width, initial-scale=1'><title>bagsim study report: "
       << escape(s.name) << "</title><style>" << report::kCss
       << ".maps{display:flex;flex-wrap:wrap;gap:1.2em;align-items:flex-start}"
          ".maps figure{display:flex;gap:0.4em;align-items:flex-start;flex-wrap:wrap;"
          "max-width:470px}.maps figcaption{flex-basis:100%;max-width:440px}"
          "</style></head><body>";
    os << "<h1>" << escape(s.name) << "</h1><p class='muted'>A study of " << n << " case"
       << (n == 1 ? "" : "s") << (s.baseScenario.empty() ? "" : " of " + escape(s.baseScenario))
       << ", run by bagsim" << (s.version.empty() ? "" : " " + escape(s.version))
       << ". Report made from the folder <code>" << escape(s.dir.string()) << "</code>.</p>";
    const std::string rerun = "bagsim study " + (s.studyFile.empty() ? "STUDY.yaml" : s.studyFile) +
                              " --out " + s.dir.string();
    if (incomplete) {
        os << "<div class='banner' id='incomplete'><b>INCOMPLETE STUDY</b>: " << missing << " of "
           << n << " cases have no result";
        if (missing > 0)
            os << " (" << count["not-run"] << " not run, " << count["interrupted"]
               << " interrupted)";
        os << "; the status of the table is <b>"
           << escape(s.h5Status.empty() ? (missing ? "incomplete" : "unknown") : s.h5Status)
           << "</b>. The charts and maps below show only the cases done. Run the same study "
              "into this folder again to finish it (the cases done are kept): <code>"
           << escape(rerun) << "</code></div>";
    }
    os << "<p>" << count["ok"] << " ok, " << count["partial"] << " partial, " << count["failed"]
       << " failed, " << count["not-run"] << " not run, " << count["interrupted"]
       << " interrupted; the cases' runs took " << formatSeconds(seconds)
       << " in all (summed).</p>";

    // The cases without a full result, first: what a reader must know before the charts.
    if (count["ok"] < int(n)) {
        os << "<h2 id='problems'>Cases missing, failed or partial</h2><table id='problem-cases'>"
              "<tr><th>case</th><th>parameters</th><th>status</th><th>reason</th></tr>";
        for (size_t r = 0; r < n; ++r) {
            if (s.status(r) == "ok") continue;
            std::string why = s.reason(r);
            if (why.empty() && s.status(r) == "not-run")
                why = "not started before the study stopped";
            if (why.empty() && s.status(r) == "interrupted")
                why = "stopped by the interrupt; its partial results are in its folder";
            os << "<tr><td class='n'>" << escape(s.caseNumber(r)) << "</td><td>"
               << escape(s.describeRow(r)) << "</td>" << report::formatStatusCell(s.status(r))
               << "<td>" << escape(why) << "</td></tr>";
        }
        os << "</table>";
    }

    // The study.
    os << "<h2>Study</h2><table id='study'>";
    auto row = [&](const std::string& k, const std::string& v) {
        if (!v.empty()) os << "<tr><th>" << k << "</th><td>" << escape(v) << "</td></tr>";
    };
    row("description", s.description);
    row("study file", s.studyFile);
    row("base scenario", s.baseScenario);
    {
        std::string sets;
        for (const auto& [k, v] : s.sets) sets += (sets.empty() ? "" : "; ") + k + ": " + v;
        row("set in every case", sets);
    }
    for (const Parameter& p : s.parameters) {
        std::string values;
        for (const std::string& v : p.distinct) {
            double x = 0.0;
            values +=
                (values.empty() ? "" : ", ") +
                (parseNumber(v, &x) ? formatNumber(x) + (p.unit.empty() ? "" : " " + p.unit) : v);
        }
        row("swept: " + escape(p.key), values + " (" + std::to_string(p.distinct.size()) +
                                           " value" + (p.distinct.size() == 1 ? "" : "s") + ")");
    }
    row("outputs", report::join(s.outputSpecs, "; "));
    row("status", s.h5Status);
    row("command", s.commandLine);
    os << "</table>";
    if (!s.haveH5)
        os << "<p class='muted'>No study.h5 in this folder"
           << (s.h5Problem.empty() ? "" : " that could be read (" + escape(s.h5Problem) + ")")
           << ": the study writes it at its end, with the text of the study file and of the "
              "base scenario; the parameters and outputs above come from study.csv.</p>";
    if (!s.studyProblem.empty())
        os << "<p class='muted'>The study file's text could not be read for its keys ("
           << escape(s.studyProblem) << "); it follows as written.</p>";
    if (!s.studyText.empty())
        os << "<details><summary>Study file as run</summary><pre>" << escape(s.studyText)
           << "</pre></details>";
    if (!s.baseText.empty())
        os << "<details><summary>Base scenario as run</summary><pre>" << escape(s.baseText)
           << "</pre></details>";

    // The table of cases.
    os << "<h2>Cases</h2><p>One row per case, in the study's order (as study.csv). Each case's "
          "run is in <code>cases/KEY/</code>, what it printed in <code>cases/KEY.log</code>.</p>"
          "<table id='cases'><tr>";
    for (int c = 0; c < int(t.header.size()); ++c)
        if (c != s.keyColumn) os << "<th>" << escape(t.header[size_t(c)]) << "</th>";
    os << "<th>key</th></tr>";
    for (size_t r = 0; r < n; ++r) {
        os << "<tr>";
        for (int c = 0; c < int(t.header.size()); ++c) {
            if (c == s.keyColumn) continue;
            const std::string& cell = t.text(r, c);
            double v = 0.0;
            if (c == s.statusColumn)
                os << report::formatStatusCell(cell);
            else if (parseNumber(cell, &v))
                os << "<td class='n'>" << escape(cell) << "</td>";
            else
                os << "<td>" << escape(cell) << "</td>";
        }
        os << "<td><code>" << escape(s.key(r)) << "</code></td></tr>";
    }
    os << "</table>";

    // Outputs against each swept parameter.
    const std::vector<size_t> axes = findAxes(s);
    const std::vector<Output> merged = mergePerColumns(s);
    std::vector<const Output*> numeric;
    for (const Output& o : merged)
        if (o.numeric) numeric.push_back(&o);
    os << "<h2 id='curves'>Outputs against the parameters</h2>";
    if (axes.empty() || numeric.empty()) {
        os << "<p class='muted'>"
           << (numeric.empty() ? "No numeric output in the table yet."
                               : "No parameter with numbers takes two values or more: nothing "
                                 "to draw against.")
           << "</p>";
    } else {
        os << "<p>Each output of the cases against each swept parameter with numbers; one line "
              "per combination of the other parameters (colour: the first of them, dashes: the "
              "rest), each case a dot. Cases without a value (failed, not run) are left out.</p>"
              "<div class='plots'>";
        for (size_t p : axes)
            for (const Output* o : numeric)
                os << drawAgainst(s, p, o->values, o->getAxis(),
                                  o->label + " against " + describeKey(s.parameters[p].key));
        os << "</div>";
    }

    // The block map: an output over the pressed position.
    size_t pressed = s.parameters.size();
    for (size_t p = 0; p < s.parameters.size(); ++p)
        if (endsWith(s.parameters[p].key, "neighbours.pressed")) pressed = p;
    if (pressed < s.parameters.size() && !numeric.empty()) {
        os << "<h2 id='maps'>Map over the block</h2><p>The 3 x 3 block of bags seen from above, "
              "the bags' long side (x) upwards: each cell is the value when the bag at that "
              "position is pressed (<code>airbag.neighbours.pressed: [along, across]</code>), "
              "one map per combination of the other parameters. Each map has its own colour "
              "scale (viridis, at least "
           << num(kMinMapSpan * 100, "%.0f")
           << " % of its mean wide, so that differences of a few tenths of a percent do not "
              "look like contrasts); the value is written in each cell. Grey: a position this "
              "study did not press (the block is mirror-symmetric across y, "
              "docs/array-coupling.md), red: a case that failed.</p>";
        const Groups g = groupRows(s, {pressed});
        for (const Output* o : numeric) {
            os << "<h3>" << escape(o->label)
               << (o->unit.empty() ? "" : " [" + escape(o->unit) + "]")
               << "</h3><div class='maps'>";
            for (size_t k = 0; k < g.rows.size(); ++k) {
                double lo = INFINITY, hi = -INFINITY;
                for (size_t r : g.rows[k])
                    if (std::isfinite(o->values[r]))
                        lo = std::min(lo, o->values[r]), hi = std::max(hi, o->values[r]);
                if (!std::isfinite(lo)) continue;
                const double mid = 0.5 * (lo + hi);
                const double span = std::max({hi - lo, kMinMapSpan * std::fabs(mid), 1e-12});
                const double step = svg::calcRoundUp(span / 5);
                report::ColourBar bar;
                bar.lo = std::floor((mid - 0.5 * span) / step + 1e-9) * step;
                bar.hi = std::ceil((mid + 0.5 * span) / step - 1e-9) * step;
                if (!(bar.hi > bar.lo)) bar.hi = bar.lo + step;
                bar.label = o->getAxis();
                bar.title = "colour scale: " + o->getAxis();
                bar.height = 200;
                bar.swatches = {{"#eeeeee", "not pressed"}, {"#f6d0d0", "failed"}};
                const std::string where = g.names[k].empty() ? "" : g.names[k];
                const std::string caption =
                    o->label + (where.empty() ? "" : ", " + where) + ": " + num(lo, "%.4g") +
                    " to " + num(hi, "%.4g") + (o->unit.empty() ? "" : " " + o->unit) +
                    (std::fabs(mid) > 0
                         ? " (spread " + num(100 * (hi - lo) / std::fabs(mid), "%.2g") +
                               " % of the mean)"
                         : "");
                os << "<figure>" << drawMap(s, *o, g.rows[k], pressed, bar, caption)
                   << report::drawColourBar(bar) << "<figcaption>" << escape(caption)
                   << "</figcaption></figure>";
            }
            os << "</div>";
        }
    }

    // The neighbours' effect: each case against the bag alone with the same other values.
    size_t layout = s.parameters.size();
    for (size_t p = 0; p < s.parameters.size(); ++p) {
        const Parameter& q = s.parameters[p];
        if (endsWith(q.key, "neighbours.layout") && q.distinct.size() >= 2 &&
            std::find(q.distinct.begin(), q.distinct.end(), "none") != q.distinct.end())
            layout = p;
    }
    if (layout < s.parameters.size()) {
        std::vector<const Output*> stiff;
        for (const Output* o : numeric)
            if (o->name.rfind("stiffness", 0) == 0) stiff.push_back(o);
        std::map<std::string, size_t> alone;  // the other parameters' values -> row alone
        const int lc = s.parameters[layout].column;
        for (size_t r = 0; r < n; ++r)
            if (t.text(r, lc) == "none") alone.emplace(s.describeRow(r, {layout}), r);
        std::vector<size_t> others;
        for (size_t p : axes)
            if (p != layout) others.push_back(p);
        if (!stiff.empty() && !others.empty()) {
            os << "<h2 id='neighbours'>What the neighbours change</h2><p>Each case's stiffness "
                  "against the bag alone (<code>layout: none</code>) with the same other "
                  "parameters, in percent: +10 % is a bag 10 % stiffer among its neighbours. "
                  "For the bag alone the neighbours' gas mass is unused.</p><div class='plots'>";
            for (const Output* o : stiff) {
                std::vector<double> change(n, kNaN);
                for (size_t r = 0; r < n; ++r) {
                    if (t.text(r, lc) == "none") continue;
                    const auto it = alone.find(s.describeRow(r, {layout}));
                    if (it == alone.end()) continue;
                    const double ref = o->values[it->second];
                    if (std::isfinite(ref) && ref != 0.0 && std::isfinite(o->values[r]))
                        change[r] = 100.0 * (o->values[r] / ref - 1.0);
                }
                for (size_t p : others)
                    os << drawAgainst(
                        s, p, change, "change against the bag alone [%]",
                        o->label + " among neighbours against " + describeKey(s.parameters[p].key),
                        {{0.0, "alone", "#999"}});
            }
            os << "</div>";
        }
    }

    // Load-displacement curves of the cases.
    {
        struct Curve {
            size_t row;
            std::vector<svg::Series> parts;  ///< one per gas mass
        };
        std::vector<Curve> curves;
        std::vector<std::string> unreadable;
        bool severalMasses = false;
        for (size_t r = 0; r < n; ++r) {
            const fs::path file = s.dir / "cases" / s.key(r) / "load_displacement.csv";
            std::error_code ec;
            if (s.key(r).empty() || !fs::exists(file, ec)) continue;
            try {
                const CsvTable ld =
                    report::readCsvTable(file, {"displacement_mm", "force_N"}, true, "");
                const int di = ld.find("displacement_mm"), fi = ld.find("force_N"),
                          mi = ld.find("gas_mass_g");
                Curve c{r, {}};
                std::map<std::string, size_t> part;
                for (size_t i = 0; i < ld.rows.size(); ++i) {
                    const std::string m = mi >= 0 ? ld.text(i, mi) : "";
                    auto it = part.find(m);
                    if (it == part.end()) {
                        it = part.emplace(m, c.parts.size()).first;
                        c.parts.emplace_back();
                    }
                    c.parts[it->second].x.push_back(ld.number(i, di));
                    c.parts[it->second].y.push_back(ld.number(i, fi));
                }
                if (c.parts.empty()) continue;
                severalMasses |= c.parts.size() > 1;
                curves.push_back(std::move(c));
            } catch (const std::exception& e) {
                unreadable.push_back(e.what());
            }
        }
        if (!curves.empty() || !unreadable.empty()) {
            os << "<h2 id='load-displacement'>Load-displacement curves</h2><p>The force on the "
                  "block against its displacement, from each case's "
                  "<code>load_displacement.csv</code> (loading, then unloading where the case "
                  "unloads), "
               << kCurvesPerChart << " cases to a chart"
               << (severalMasses ? "; a case with several gas masses draws each (dashes for "
                                   "the later ones)"
                                 : "")
               << ". A case that failed shows what it wrote before it stopped.</p>"
                  "<div class='plots'>";
            for (size_t first = 0; first < curves.size(); first += kCurvesPerChart) {
                std::vector<svg::Series> series;
                const size_t last = std::min(curves.size(), first + kCurvesPerChart);
                for (size_t k = first; k < last; ++k) {
                    const size_t r = curves[k].row;
                    for (size_t m = 0; m < curves[k].parts.size(); ++m) {
                        svg::Series line = curves[k].parts[m];
                        line.colour = svg::getCategoryColour(int(k - first));
                        line.dash = getDash(int(m));
                        line.width = 1.5;
                        if (m == 0)
                            line.name = "case " + s.caseNumber(r) +
                                        (s.parameters.empty() ? "" : ": " + s.describeRow(r)) +
                                        (s.status(r) == "ok" ? "" : " (" + s.status(r) + ")");
                        series.push_back(std::move(line));
                    }
                }
                svg::PlotOptions o;
                o.title = "Force against displacement, cases " + s.caseNumber(curves[first].row) +
                          " to " + s.caseNumber(curves[last - 1].row);
                if (last - first == 1)
                    o.title = "Force against displacement, case " + s.caseNumber(curves[first].row);
                o.xLabel = "displacement of the block [mm]";
                o.yLabel = "force [N]";
                o.xMin = 0.0;
                o.yMin = 0.0;
                os << svg::plot(o, series);
            }
            os << "</div>";
            for (const std::string& u : unreadable)
                os << "<p class='muted'>Left out: " << escape(u) << "</p>";
        }
    }

    if (!s.marker.empty()) os << "<h2>INCOMPLETE marker</h2><pre>" << escape(s.marker) << "</pre>";
    os << "<p class='muted'>Units as in study.csv: a parameter's unit in brackets after its "
          "key, an output's in its column name (N/mm: newtons per millimetre of block travel; "
          "g: grams of gas; kPa: gauge pressure). How to read this page: docs/studies.md of "
          "bagsim.</p></body></html>\n";
    return os.str();
}

void writeStudyReport(const fs::path& studyDir, const fs::path& out) {
    report::writePageFile(formatStudyReportHtml(studyDir), out);
}

}  // namespace io
