#include <io/MeasuredData.h>
#include <io/PatientMeasuredData.h>

#include <bags/Units.h>
#include <io/InputError.h>
#include <io/Results.h>
#include <io/Scenario.h>
#include <io/Units.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>

#include "ChannelCsv.h"
#include "Hdf5.h"
#include "MeasuredManifest.h"
#include "ReportPage.h"

namespace io {

namespace fs = std::filesystem;

namespace {

using csv::fmt;
using csv::lower;
using csv::nextDataLine;
using csv::splitCsv;
using csv::splitHeader;
using csv::trim;

constexpr double kMmHg = bags::kPascalsPerMmHg;  // [Pa]
constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxMatSide = 1024;  // sensels along either side of a mat

// A number of a mat file's cell, or an InputError at its line and place.
double parseCell(const std::string& cell, const std::string& file, int line,
                 const std::string& where, const std::string& valid) {
    char* end = nullptr;
    const double v = std::strtod(cell.c_str(), &end);
    if (cell.empty() || end != cell.c_str() + cell.size())
        throw InputError(file, line, "",
                         where + ": '" + cell + "' is not a number; valid: " + valid);
    if (!std::isfinite(v))
        throw InputError(file, line, "",
                         where + ": '" + cell + "' is not a finite number (" +
                             (std::isnan(v) ? "NaN" : "infinite") + "); valid: " + valid);
    return v;
}

// The manifest's node at a dotted key of `channels`, `protocol` or `overrides`, of the root or
// (test >= 0) of the manifest's test (for errors found after the manifest was read: against the
// scenario).
[[noreturn]] void failAtManifest(const diagnose::PatientMeasurement& data, int test,
                                 const std::string& section, const std::string& key,
                                 const std::string& message) {
    const std::string manifest = (fs::path(data.folder) / kMeasuredManifest).string();
    const ScenarioFile m = ScenarioFile::parse(
        readInputFile(manifest, kMaxScenarioBytes, "measured-data manifest"), manifest);
    ScenarioNode owner = m.getRoot();
    if (test >= 0) owner = owner.get("tests").getElements().at(size_t(test));
    if (key.empty() || !owner.has(section) || !owner.getSection(section).has(key))
        owner.fail(section, message);
    owner.getSection(section).fail(key, message);
    throw InputError(manifest, 0, section + "." + key, message);  // not reached
}
[[noreturn]] void failAtManifest(const diagnose::PatientMeasurement& data,
                                 const std::string& section, const std::string& key,
                                 const std::string& message) {
    failAtManifest(data, -1, section, key, message);
}

}  // namespace

std::string readMeasuredKind(const std::string& folder) {
    const fs::path manifest = fs::path(folder) / kMeasuredManifest;
    std::error_code ec;
    if (!fs::is_regular_file(manifest, ec)) return "";
    try {
        const ScenarioFile f = ScenarioFile::parse(
            readInputFile(manifest.string(), kMaxScenarioBytes, "measured-data manifest"),
            manifest.string());
        const ScenarioNode root = f.getRoot();
        if (!root.has("protocol")) return "";
        const ScenarioNode p = root.getSection("protocol");
        return p.has("kind") ? p.getString("kind") : "";
    } catch (const InputError&) {
        return "";
    }
}

diagnose::MatFrames readMatFramesCsv(const std::string& path, const std::string& shownName) {
    std::istringstream text(readInputFile(path, kMaxMatBytes, "mat file"));
    const std::string layout =
        "the lines rows,R then columns,C then unit,U (docs/measured-data.md#the-pressure-mat)";
    diagnose::MatFrames m;
    double unitFactor = 0.0;
    std::string unitSymbol;
    int lineNo = 0, step = 0;  // step: 0 rows, 1 columns, 2 unit, 3 frames
    int row = 0, lastTimeLine = 0;
    std::vector<double> frame;
    auto fail = [&](int line, const std::string& msg) -> void {
        throw InputError(shownName, line, "", msg);
    };
    auto frameName = [&]() {
        return "frame " + std::to_string(m.time.size()) + " (time " + fmt("%g", m.time.back()) +
               " s)";
    };
    auto closeFrame = [&](int line) {
        if (m.time.empty()) return;
        if (row != m.rows)
            fail(line, frameName() + " (line " + std::to_string(lastTimeLine) + ") has " +
                           std::to_string(row) + " rows; valid: " + std::to_string(m.rows) +
                           " rows of " + std::to_string(m.columns) +
                           " pressures (the 'rows' line)");
        m.pressure.push_back(frame);
    };
    std::string t;
    std::vector<std::string> cells;
    while (nextDataLine(text, lineNo, t, cells)) {
        const std::string first = lower(cells[0]);
        if (step < 2) {
            const char* want = step == 0 ? "rows" : "columns";
            if (first != want || cells.size() != 2)
                fail(lineNo,
                     "'" + t + "' where the line " + want + ",N was expected; valid: " + layout);
            const double v = parseCell(cells[1], shownName, lineNo, std::string("'") + want + "'",
                                       "a whole number of sensels, 1 to 1024");
            if (v != std::floor(v) || v < 1 || v > kMaxMatSide)
                fail(lineNo, std::string("'") + want + "': " + cells[1] +
                                 " is not a number of sensels; valid: a whole number, 1 to 1024");
            (step == 0 ? m.rows : m.columns) = static_cast<int>(v);
            ++step;
            continue;
        }
        if (step == 2) {
            if (first != "unit" || cells.size() != 2)
                fail(lineNo, "'" + t + "' where the line unit,U was expected; valid: " + layout);
            const UnitInfo* u = findUnit(cells[1]);
            if (!u || u->dimension != Dimension::Pressure)
                fail(lineNo, "'unit': '" + cells[1] + "' is not a unit of a pressure; valid: " +
                                 csv::listUnits(Dimension::Pressure));
            unitFactor = u->factor;
            unitSymbol = u->symbol;
            ++step;
            continue;
        }
        const auto [name, unit] = splitHeader(cells[0]);
        if (lower(name) == "time") {
            if (cells.size() != 2)
                fail(lineNo, "a frame's time line has " + std::to_string(cells.size()) +
                                 " cells; valid: 2, e.g. time_s,0.5");
            const UnitInfo* u = findUnit(unit);
            if (!u || u->dimension != Dimension::Time)
                fail(lineNo, "'" + cells[0] + "': " +
                                 (unit.empty() ? std::string("no unit")
                                               : "'" + unit + "' is not a unit of a time") +
                                 "; valid: time_<unit>, e.g. time_s or \"time [ms]\" (units: " +
                                 csv::listUnits(Dimension::Time) + ")");
            closeFrame(lineNo);
            const double v =
                parseCell(cells[1], shownName, lineNo, "the frame's time", "a finite time");
            const double si = v * u->factor;
            if (!m.time.empty() && !(si > m.time.back()))
                fail(lineNo, "the frame's time " + cells[1] +
                                 " is not after the previous frame's (line " +
                                 std::to_string(lastTimeLine) + ") " +
                                 fmt("%.9g", m.time.back() / u->factor) +
                                 "; valid: frames in strictly increasing time");
            m.time.push_back(si);
            frame.assign(size_t(m.rows) * size_t(m.columns), 0.0);
            row = 0;
            lastTimeLine = lineNo;
            continue;
        }
        if (m.time.empty())
            fail(lineNo, "'" + t.substr(0, 40) + "' before the first frame's time line; valid: " +
                             "time_s,T then the frame's rows");
        if (row >= m.rows)
            fail(lineNo, frameName() + " (line " + std::to_string(lastTimeLine) + "): a row " +
                             std::to_string(row + 1) + " beyond the mat's " +
                             std::to_string(m.rows) + " rows; valid: " + std::to_string(m.rows) +
                             " rows, then the next frame's time line");
        if (int(cells.size()) != m.columns)
            fail(lineNo, frameName() + ", row " + std::to_string(row + 1) + ": has " +
                             std::to_string(cells.size()) + " cells; valid: " +
                             std::to_string(m.columns) + " pressures (the 'columns' line)");
        for (int c = 0; c < m.columns; ++c) {
            const double v = parseCell(
                cells[size_t(c)], shownName, lineNo,
                frameName() + ", row " + std::to_string(row + 1) + ", column " +
                    std::to_string(c + 1),
                "a finite pressure in " + unitSymbol + " (0 where the sensel reads nothing)");
            frame[size_t(row) * size_t(m.columns) + size_t(c)] = v * unitFactor;
        }
        ++row;
    }
    if (step < 3)
        fail(lineNo, "ends before its layout lines; valid: " + layout +
                         ", then frames (time_s,T and R rows of C pressures)");
    closeFrame(lineNo);
    if (m.time.size() < 2)
        fail(0, "has " + std::to_string(m.time.size()) + " frame(s); valid: at least two frames");
    return m;
}

namespace {

// The channels of one record: `owner`'s section `channels` (the manifest's root, or a test).
diagnose::PatientChannels readChannelsSection(const ScenarioNode& owner, const fs::path& dir) {
    std::error_code ec;
    const ScenarioNode ch = owner.getSection("channels");
    ch.checkKeys({}, {"mat", "tilt", "bag_pressures"});
    if (!ch.has("mat") && !ch.has("tilt"))
        owner.fail("channels",
                   "names no 'mat' and no 'tilt'; valid: a pressure mat's file, a tilt "
                   "sensor's file, or both (bag_pressures optional)");
    auto channelPath = [&](const ScenarioNode& node, const char* key) {
        const std::string name = node.getString(key);
        const fs::path f = fs::path(name).is_absolute() ? fs::path(name) : dir / name;
        if (!fs::is_regular_file(f, ec))
            node.fail(key, "channel file \"" + name + "\" is missing (" + f.string() +
                               "); valid: a CSV file in the folder (docs/measured-data.md)");
        return f.string();
    };
    diagnose::PatientChannels c;
    if (ch.has("mat")) {
        c.matFile = channelPath(ch, "mat");
        c.mat = readMatFramesCsv(c.matFile, c.matFile);
    }
    if (ch.has("tilt")) {
        c.tiltFile = channelPath(ch, "tilt");
        const auto cols = readChannelCsv(c.tiltFile, c.tiltFile,
                                         {{"time", Dimension::Time},
                                          {"pelvis_tilt", Dimension::Angle, true},
                                          {"thorax_tilt", Dimension::Angle, true}});
        if (cols[1].empty() && cols[2].empty())
            throw InputError(c.tiltFile, 0, "",
                             "no 'pelvis_tilt' and no 'thorax_tilt' column; valid: a header "
                             "time_s,pelvis_tilt_deg,thorax_tilt_deg (either tilt may be left "
                             "out; units may differ)");
        c.tilt.time = cols[0];
        c.tilt.pelvis = cols[1];
        c.tilt.thorax = cols[2];
    }
    if (ch.has("bag_pressures")) {
        const ScenarioNode list = ch.get("bag_pressures");
        std::set<int> seen;
        for (const ScenarioNode& e : list.getElements()) {
            e.checkKeys({"bag", "file"}, {});
            const double b = e.getNumber("bag");
            if (b != std::floor(b) || b < 0)
                e.fail("bag", fmt("%g", b) +
                                  " is not a bag; valid: the bag's index in the array "
                                  "(row x columns + column, from 0; bags.csv's 'bag')");
            if (!seen.insert(int(b)).second)
                e.fail("bag",
                       "bag " + fmt("%g", b) + " is listed twice; valid: one sensor file per bag");
            diagnose::BagPressureChannel s;
            s.bag = int(b);
            s.file = channelPath(e, "file");
            const auto cols = readChannelCsv(
                s.file, s.file, {{"time", Dimension::Time}, {"pressure", Dimension::Pressure}});
            s.pressure = {cols[0], cols[1]};
            c.bags.push_back(std::move(s));
        }
        std::sort(c.bags.begin(), c.bags.end(),
                  [](const auto& a, const auto& b) { return a.bag < b.bag; });
    }
    return c;
}

// A test's name: it names the test's co-simulations' folders, so a plain word.
bool isTestName(const std::string& n) {
    if (n.empty() || n.size() > 64 || n[0] == '.' || n[0] == '-') return false;
    return std::all_of(n.begin(), n.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '_';
    });
}

// The scenario keys a test may not change: the protocol's, every test's alike.
bool isProtocolKey(const std::string& k) {
    return k == "kind" || k == "run" || k == "run.settle_time" || k == "run.duration";
}

// Subjects: none, or one per test and at least two (the folds hold out one subject's tests).
void checkSubjects(const ScenarioNode& list, const std::vector<diagnose::PatientTest>& tests) {
    const std::vector<ScenarioNode> nodes = list.getElements();
    size_t named = 0, first = 0;
    for (size_t i = 0; i < tests.size(); ++i)
        if (!tests[i].subject.empty()) {
            if (!named) first = i;
            ++named;
        }
    if (!named) return;
    for (size_t i = 0; i < tests.size(); ++i)
        if (tests[i].subject.empty())
            nodes[i].fail("subject", "the test \"" + tests[i].name +
                                         "\" names no subject, the test \"" + tests[first].name +
                                         "\" (line " +
                                         std::to_string(nodes[first].getLine("subject")) +
                                         ") names \"" + tests[first].subject +
                                         "\"; valid: a subject for every test (the "
                                         "patient measured, e.g. subject: " +
                                         tests[first].subject +
                                         "), or for none (docs/measured-data.md#several-subjects)");
    for (size_t i = 1; i < tests.size(); ++i)
        if (tests[i].subject != tests[0].subject) return;
    nodes[0].fail("subject", "every test names the subject \"" + tests[0].subject +
                                 "\"; valid: at least two subjects (the diagnosis holds out one "
                                 "subject's tests at a time), or no 'subject' key at all");
}

std::vector<diagnose::PatientTest> readTestsSection(const ScenarioNode& root, const fs::path& dir) {
    const ScenarioNode list = root.get("tests");
    std::vector<diagnose::PatientTest> tests;
    std::map<std::string, int> names;  // name, line
    for (const ScenarioNode& t : list.getElements()) {
        t.checkKeys({"name", "channels"}, {"overrides", "subject"});
        diagnose::PatientTest test;
        test.name = t.getString("name");
        if (!isTestName(test.name))
            t.fail("name",
                   "\"" + test.name +
                       "\" is not a test's name; valid: 1-64 letters, digits, "
                       "'.', '-' and '_', not starting with '.' or '-' (it names the test's "
                       "co-simulations' folders), e.g. gas-4.0g");
        if (t.has("subject")) {
            test.subject = t.getString("subject");
            if (!isTestName(test.subject))
                t.fail("subject",
                       "\"" + test.subject +
                           "\" is not a subject's name; valid: 1-64 "
                           "letters, digits, '.', '-' and '_', not starting with '.' or '-' "
                           "(as a test's name), e.g. subject-2");
        }
        const auto [it, added] = names.emplace(test.name, t.getLine("name"));
        if (!added)
            t.fail("name", "the test \"" + test.name + "\" is named twice (first on line " +
                               std::to_string(it->second) + "); valid: one name per test");
        if (t.has("overrides")) {
            const ScenarioNode o = t.getSection("overrides");
            if (!o.isMap() && !o.isNull())
                t.fail("overrides",
                       "must be a section of scenario keys and values, e.g. "
                       "{array.gas_mass: 4.0 g}");
            for (auto kv = o.getYaml().begin(); o.isMap() && kv != o.getYaml().end(); ++kv) {
                const std::string key = kv->first.as<std::string>();
                if (isProtocolKey(key))
                    o.fail(key, "a test cannot change '" + key +
                                    "'; valid: any other scenario key "
                                    "(the protocol's settle_time and duration are every test's)");
                std::string value;
                if (kv->second.IsScalar()) {
                    value = kv->second.Scalar();
                } else {
                    YAML::Emitter e;
                    e << YAML::Flow << kv->second;
                    value = e.c_str();
                }
                test.overrides.emplace_back(key, value);
            }
        }
        test.channels = readChannelsSection(t, dir);
        tests.push_back(std::move(test));
    }
    if (tests.empty())
        root.fail("tests",
                  "is an empty list; valid: one entry per test, each with a name, its "
                  "overrides and its channels (docs/measured-data.md#several-tests)");
    checkSubjects(list, tests);
    return tests;
}

}  // namespace

diagnose::PatientMeasurement readPatientMeasuredData(const std::string& folder) {
    const fs::path dir(folder);
    const ScenarioFile file = manifest::readManifest(folder);
    const ScenarioNode root = file.getRoot();
    root.checkKeys({"format", "scenario", "protocol"}, {"description", "channels", "tests"});
    diagnose::PatientMeasurement data;
    data.folder = folder;
    data.description = root.getString("description", "");
    data.scenarioFile =
        manifest::readManifestScenario(root, folder, "the patient-on-array scenario");

    const ScenarioNode p = root.getSection("protocol");
    p.checkKeys({"kind"}, {"settle_time", "duration"});
    p.getChoice("kind", {kPatientMeasuredKind});
    for (const char* key : {"settle_time", "duration"}) {
        if (!p.has(key)) continue;
        const double v = p.getQuantity(key, Dimension::Time);
        if (!(v >= 0.0)) p.fail(key, "must be zero or more");
        (std::string(key) == "duration" ? data.protocol.duration : data.protocol.settleTime) = v;
    }
    if (root.has("channels") && root.has("tests"))
        root.fail("tests",
                  "the manifest has both 'channels' and 'tests'; valid: 'channels' for one "
                  "record, or 'tests' (a list, each test with its own channels)");
    if (!root.has("channels") && !root.has("tests"))
        root.fail("channels",
                  "the manifest has neither 'channels' nor 'tests'; valid: 'channels' "
                  "for one record, or 'tests', a list of records each with its "
                  "'name', 'overrides' and 'channels' (docs/measured-data.md)");
    if (root.has("channels"))
        data.channels = readChannelsSection(root, dir);
    else
        data.tests = readTestsSection(root, dir);
    return data;
}

namespace {

// A record's channels against the scenario it is simulated with (test >= 0: the manifest's test).
void checkAgainstScenario(const diagnose::PatientMeasurement& data, int test,
                          const diagnose::PatientChannels& c, const PatientOnArrayScenario& sc) {
    if (!c.mat.empty() && (c.mat.rows != sc.mat.rows || c.mat.columns != sc.mat.columns))
        failAtManifest(data, test, "channels", "mat",
                       "the mat file " + c.matFile + " has " + std::to_string(c.mat.rows) + " x " +
                           std::to_string(c.mat.columns) + " sensels, the scenario's mat " +
                           std::to_string(sc.mat.rows) + " x " + std::to_string(sc.mat.columns) +
                           "; valid: the scenario's mat section (rows, columns) of the mat the "
                           "data were recorded with");
    const int nbags = sc.options.layout.rows * sc.options.layout.columns;
    for (const diagnose::BagPressureChannel& b : c.bags)
        if (b.bag >= nbags)
            failAtManifest(data, test, "channels", "bag_pressures",
                           "bag " + std::to_string(b.bag) + " (" + b.file +
                               ") is not in the array of " + std::to_string(nbags) +
                               " bags; valid: 0 to " + std::to_string(nbags - 1));
    const double end = sc.getEndTime() + 1e-9;
    auto checkSpan = [&](const std::vector<double>& t, const std::string& key,
                         const std::string& f) {
        if (t.empty()) return;
        if (t.front() < -1e-9 || t.back() > end)
            failAtManifest(data, test, "channels", key,
                           f + " runs from " + fmt("%g", t.front()) + " s to " +
                               fmt("%g", t.back()) +
                               " s; valid: samples from the release (0 s) to the run's end, " +
                               fmt("%g s", sc.getEndTime()) +
                               " (run.settle_time + run.duration, with the protocol's)");
    };
    checkSpan(c.mat.time, "mat", c.matFile);
    checkSpan(c.tilt.time, "tilt", c.tiltFile);
    for (const diagnose::BagPressureChannel& b : c.bags)
        checkSpan(b.pressure.time, "bag_pressures", b.file);
}

}  // namespace

PatientMeasuredScenario readPatientMeasuredScenario(const diagnose::PatientMeasurement& data) {
    ScenarioFile file = ScenarioFile::load(data.scenarioFile);
    const std::string kind = file.getRoot().getString("kind", "");
    if (kind != kPatientOnArrayKind)
        failAtManifest(data, "scenario", "",
                       "the scenario " + data.scenarioFile + " is of kind '" + kind +
                           "'; valid: a patient-on-array scenario (docs/scenario-reference.md)");
    const diagnose::PatientProtocol& pr = data.protocol;
    if (pr.settleTime >= 0.0)
        file.applyOverride("run.settle_time", fmt("%.9g", pr.settleTime) + " s");
    if (pr.duration >= 0.0) file.applyOverride("run.duration", fmt("%.9g", pr.duration) + " s");
    PatientOnArrayScenario sc;
    try {
        sc = readPatientOnArrayScenario(file);
    } catch (const InputError& e) {
        for (const char* key : {"settle_time", "duration"})
            if (e.getWhere() == std::string("--set run.") + key)
                failAtManifest(data, "protocol", key,
                               "the scenario " + data.scenarioFile +
                                   " cannot run this protocol: " + e.getMessage());
        throw;
    }
    PatientMeasuredScenario out{file, sc, {}};
    if (data.tests.empty()) {
        checkAgainstScenario(data, -1, data.channels, sc);
        return out;
    }
    for (size_t i = 0; i < data.tests.size(); ++i) {
        const diagnose::PatientTest& t = data.tests[i];
        PatientMeasuredTestScenario ts{t.name, file, {}};
        try {
            for (const auto& [k, v] : t.overrides) ts.file.applyOverride(k, v);
            ts.scenario = readPatientOnArrayScenario(ts.file);
        } catch (const InputError& e) {
            for (const auto& [k, v] : t.overrides)
                if (e.getWhere() == "--set " + k)
                    failAtManifest(data, int(i), "overrides", k,
                                   "the test \"" + t.name + "\": " + e.getMessage());
            throw;
        }
        checkAgainstScenario(data, int(i), t.channels, ts.scenario);
        out.tests.push_back(std::move(ts));
    }
    return out;
}

namespace {

// One record's channel files, named with `prefix` ("" or "<test>-"), and its `channels` section
// of the manifest indented by `indent`.
void writeChannels(const fs::path& dir, const std::string& prefix,
                   const diagnose::PatientChannels& c, const std::string& indent,
                   std::ostringstream& m, std::vector<std::string>& names) {
    m << indent << "channels:\n";
    if (!c.mat.empty()) {
        std::ostringstream o;
        o << "# pressure mat export: " << c.mat.rows
          << " rows along the bed (row 1 at the foot end) x " << c.mat.columns
          << " columns across (column 1 at his left)\n"
          << "rows," << c.mat.rows << "\ncolumns," << c.mat.columns << "\nunit,mmHg\n";
        for (size_t f = 0; f < c.mat.time.size(); ++f) {
            o << "time_s," << fmt("%.4f", c.mat.time[f]) << "\n";
            for (int r = 0; r < c.mat.rows; ++r) {
                for (int k = 0; k < c.mat.columns; ++k)
                    o << (k ? "," : "")
                      << fmt("%.2f",
                             c.mat.pressure[f][size_t(r) * size_t(c.mat.columns) + size_t(k)] /
                                 kMmHg);
                o << "\n";
            }
        }
        csv::writeFolderFile(dir, prefix + "mat.csv", o.str(), names);
        m << indent << "  mat: " << prefix << "mat.csv\n";
    }
    if (!c.tilt.empty()) {
        std::ostringstream o;
        const bool pel = !c.tilt.pelvis.empty(), tho = !c.tilt.thorax.empty();
        o << "time_s" << (pel ? ",pelvis_tilt_deg" : "") << (tho ? ",thorax_tilt_deg" : "") << "\n";
        for (size_t k = 0; k < c.tilt.time.size(); ++k) {
            o << fmt("%.4f", c.tilt.time[k]);
            if (pel) o << "," << fmt("%.4f", c.tilt.pelvis[k] * 180.0 / kPi);
            if (tho) o << "," << fmt("%.4f", c.tilt.thorax[k] * 180.0 / kPi);
            o << "\n";
        }
        csv::writeFolderFile(dir, prefix + "tilt.csv", o.str(), names);
        m << indent << "  tilt: " << prefix << "tilt.csv\n";
    }
    if (!c.bags.empty()) m << indent << "  bag_pressures:\n";
    for (const diagnose::BagPressureChannel& b : c.bags) {
        const std::string name = prefix + "bag" + std::to_string(b.bag) + "-pressure.csv";
        std::ostringstream o;
        o << "time_s,pressure_kPa\n";
        for (size_t k = 0; k < b.pressure.time.size(); ++k)
            o << fmt("%.4f", b.pressure.time[k]) << "," << fmt("%.5f", b.pressure.value[k] * 1e-3)
              << "\n";
        csv::writeFolderFile(dir, name, o.str(), names);
        m << indent << "    - {bag: " << b.bag << ", file: " << name << "}\n";
    }
}

}  // namespace

std::vector<std::string> writePatientMeasuredData(const std::string& folder,
                                                  const diagnose::PatientMeasurement& data,
                                                  const std::string& scenarioText,
                                                  const std::string& comment) {
    const fs::path dir(folder);
    std::vector<std::string> names;
    csv::writeFolderFile(dir, "scenario.yaml", scenarioText, names);
    std::ostringstream m;
    m << comment << "format: " << kMeasuredFormat << "\n"
      << "scenario: scenario.yaml\n";
    if (!data.description.empty()) m << "description: \"" << data.description << "\"\n";
    m << "protocol:\n  kind: " << kPatientMeasuredKind << "\n";
    if (data.protocol.settleTime >= 0.0)
        m << "  settle_time: " << fmt("%.9g", data.protocol.settleTime) << " s\n";
    if (data.protocol.duration >= 0.0)
        m << "  duration: " << fmt("%.9g", data.protocol.duration) << " s\n";
    if (data.tests.empty()) {
        writeChannels(dir, "", data.channels, "", m, names);
    } else {
        m << "tests:\n";
        for (const diagnose::PatientTest& t : data.tests) {
            m << "  - name: " << t.name << "\n";
            if (!t.subject.empty()) m << "    subject: " << t.subject << "\n";
            if (!t.overrides.empty()) {
                m << "    overrides:\n";
                for (const auto& [k, v] : t.overrides) m << "      " << k << ": " << v << "\n";
            }
            writeChannels(dir, t.name + "-", t.channels, "    ", m, names);
        }
    }
    csv::writeFolderFile(dir, kMeasuredManifest, m.str(), names);
    return names;
}

diagnose::PatientChannels readArrayRunChannels(const fs::path& runDir) {
    diagnose::PatientChannels out;
    const fs::path h5path = runDir / kResultsH5;
    std::error_code ec;
    if (!fs::exists(h5path, ec))
        throw InputError(runDir.string(), 0, "",
                         "no results.h5: not the output folder of a patient-on-array run");
    try {
        h5::Handle file = h5::openFileReadOnly(h5path.string());
        if (!h5::hasLink(file.get(), "mat"))
            throw InputError(h5path.string(), 0, "", "has no /mat: not a patient-on-array run's");
        h5::Handle mat = h5::openGroup(file.get(), "mat");
        diagnose::MatFrames& m = out.mat;
        m.rows = int(h5::readDoubleAttribute(mat.get(), "rows").at(0));
        m.columns = int(h5::readDoubleAttribute(mat.get(), "columns").at(0));
        std::vector<hsize_t> dims;
        m.time = h5::readDataset(mat.get(), "time", dims);
        const std::vector<double> p = h5::readDataset(mat.get(), "pressure", dims);
        if (dims.size() != 3 || dims[1] != hsize_t(m.columns) || dims[2] != hsize_t(m.rows))
            throw InputError(h5path.string(), 0, "",
                             "/mat/pressure is not frames x columns x rows of the mat's sensels");
        const size_t frames = std::min<size_t>(m.time.size(), size_t(dims[0]));
        m.time.resize(frames);
        const size_t per = size_t(m.rows) * size_t(m.columns);
        for (size_t f = 0; f < frames; ++f) {
            std::vector<double> frame(per);
            // results.h5 stores pressure[f][c][r]; ours is [r * columns + c].
            for (int c = 0; c < m.columns; ++c)
                for (int r = 0; r < m.rows; ++r)
                    frame[size_t(r) * size_t(m.columns) + size_t(c)] =
                        p[f * per + size_t(c) * size_t(m.rows) + size_t(r)];
            m.pressure.push_back(std::move(frame));
        }
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(h5path.string(), 0, "", e.what());
    }
    const std::string help =
        "a patient-on-array results folder holds results.h5, tilt.csv and "
        "bags.csv (docs/output-layout.md#patient-on-array)";
    const report::CsvTable tilt = report::readCsvTable(
        runDir / "tilt.csv", {"time_s", "pelvis_tilt_deg", "thorax_tilt_deg"}, false, help);
    for (size_t r = 0; r < tilt.rows.size(); ++r) {
        const double t = tilt.number(r, 0);
        if (!out.tilt.time.empty() && !(t > out.tilt.time.back())) continue;  // a repeated time
        out.tilt.time.push_back(t);
        out.tilt.pelvis.push_back(tilt.number(r, 1) * kPi / 180.0);
        out.tilt.thorax.push_back(tilt.number(r, 2) * kPi / 180.0);
    }
    const report::CsvTable bags = report::readCsvTable(
        runDir / "bags.csv", {"time_s", "bag", "mass_g", "pressure_kPa"}, false, help);
    std::map<int, diagnose::BagPressureChannel> byBag;
    for (size_t r = 0; r < bags.rows.size(); ++r) {
        const int b = int(bags.number(r, 1));
        diagnose::BagPressureChannel& ch = byBag[b];
        ch.bag = b;
        const double t = bags.number(r, 0);
        if (!ch.pressure.time.empty() && !(t > ch.pressure.time.back())) continue;
        ch.pressure.time.push_back(t);
        ch.pressure.value.push_back(bags.number(r, 3) * 1e3);
    }
    for (auto& [b, ch] : byBag) out.bags.push_back(std::move(ch));
    return out;
}

}  // namespace io
