#include <bags/Text.h>
#include <io/ArrayScenario.h>
#include <io/LoadTestScenario.h>
#include <io/PatientScenario.h>
#include <io/ResultFiles.h>
#include <io/StudyScenario.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <set>

namespace io {

namespace {

namespace fs = std::filesystem;

/// Largest number of cases a study may expand to: a grid that multiplies out past it is a
/// mistake, not a study this machine (or a cluster's allotment) would finish.
constexpr size_t kMaxCases = 100000;

/// A swept value as read: its --set text, its number and unit if it is a quantity.
struct Value {
    std::string text;
    double number = std::numeric_limits<double>::quiet_NaN();
    std::string unit;
    bool numeric = false;
    int line = 0;
};

std::string emitFlow(const YAML::Node& n) {
    if (n.IsScalar()) return n.Scalar();
    YAML::Emitter e;
    e << YAML::Flow << n;
    return e.c_str();
}

/// Splits "1e7 Pa/m" into 1e7 and "Pa/m"; false if the text is not a number with a known unit.
bool splitQuantity(const std::string& text, double* number, std::string* unit) {
    const std::string t = bags::trimBlanks(text);
    if (t.empty()) return false;
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || !std::isfinite(v)) return false;
    const std::string u = bags::trimBlanks(std::string(end));
    if (!u.empty() && !findUnit(u)) return false;
    *number = v;
    *unit = u;
    return true;
}

Value readValue(const ScenarioNode& n) {
    Value v;
    v.text = emitFlow(n.getYaml());
    v.line = n.getLine();
    // A quantity, or a list of one (a one-mass test.gas_masses) is a number in the table.
    YAML::Node scalar = n.getYaml();
    if (scalar.IsSequence() && scalar.size() == 1) scalar = scalar[0];
    if (scalar.IsScalar()) v.numeric = splitQuantity(scalar.Scalar(), &v.number, &v.unit);
    return v;
}

/// A set of rows over some parameters (a grid, a zip, random samples).
struct Block {
    std::vector<StudyParameter> parameters;
    std::vector<std::vector<Value>> rows;  ///< row -> value per parameter
};

void addParameter(Block& b, const ScenarioNode& section, const std::string& key,
                  std::set<std::string>& seen) {
    if (key.empty() || key.front() == '.' || key.back() == '.' ||
        key.find("..") != std::string::npos)
        section.fail(key, "a parameter is a scenario key path, e.g. contact.penalty");
    if (!seen.insert(key).second)
        section.fail(key, "is swept twice (or also fixed in 'set'); a key may appear once");
    StudyParameter p;
    p.key = key;
    p.line = section.getLine(key);
    p.path = section.getChildPath(key);
    b.parameters.push_back(p);
}

std::vector<std::string> getKeys(const ScenarioNode& section) {
    if (!section.isMap()) section.fail("must be a mapping of scenario keys to values");
    std::vector<std::string> keys;
    for (auto it = section.getYaml().begin(); it != section.getYaml().end(); ++it)
        keys.push_back(it->first.as<std::string>());
    return keys;
}

std::vector<Value> readList(const ScenarioNode& n) {
    if (!n.isSequence() || n.getElements().empty())
        n.fail("\"" + emitFlow(n.getYaml()) +
               "\": the values to sweep are a non-empty list, e.g. [1e7 Pa/m, 1e8 Pa/m] (a list "
               "value is itself a list: [[3.5 g], [3 g]])");
    std::vector<Value> values;
    for (const ScenarioNode& e : n.getElements()) values.push_back(readValue(e));
    return values;
}

Block readGrid(const ScenarioNode& grid, std::set<std::string>& seen) {
    Block b;
    b.rows.push_back({});
    for (const std::string& key : getKeys(grid)) {
        addParameter(b, grid, key, seen);
        const std::vector<Value> values = readList(grid.get(key));
        std::vector<std::vector<Value>> rows;
        for (const auto& row : b.rows)
            for (const Value& v : values) {
                rows.push_back(row);
                rows.back().push_back(v);
                if (rows.size() > kMaxCases)
                    grid.fail(key, "the grid has more than " + std::to_string(kMaxCases) +
                                       " cases; sweep fewer values");
            }
        b.rows = std::move(rows);
    }
    return b;
}

Block readZip(const ScenarioNode& zip, std::set<std::string>& seen) {
    Block b;
    size_t n = 0;
    std::string first;
    for (const std::string& key : getKeys(zip)) {
        addParameter(b, zip, key, seen);
        const std::vector<Value> values = readList(zip.get(key));
        if (b.rows.empty()) {
            n = values.size();
            first = key;
            b.rows.resize(n);
        } else if (values.size() != n) {
            zip.fail(key, "has " + std::to_string(values.size()) + " values and '" + first +
                              "' has " + std::to_string(n) +
                              "; zipped lists are taken together and need the same length");
        }
        for (size_t i = 0; i < n; ++i) b.rows[i].push_back(values[i]);
    }
    return b;
}

std::string formatSample(double v, const std::string& unit) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return unit.empty() ? std::string(buf) : std::string(buf) + " " + unit;
}

Block readRandom(const ScenarioNode& random, std::set<std::string>& seen) {
    random.checkKeys({"samples", "values"}, {"seed"});
    const int samples = random.getInteger("samples", 0);
    if (samples < 1 || samples > int(kMaxCases))
        random.fail("samples", "\"" + std::to_string(samples) +
                                   "\": the number of random cases is 1 to " +
                                   std::to_string(kMaxCases));
    const int seed = random.getInteger("seed", 1);
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    Block b;
    b.rows.resize(samples);
    const ScenarioNode values = random.getSection("values");
    for (const std::string& key : getKeys(values)) {
        addParameter(b, values, key, seen);
        const ScenarioNode spec = values.get(key);
        if (!spec.isMap())
            spec.fail(
                "a random parameter is {uniform: [LOW, HIGH]} or {normal: [MEAN, SD]} "
                "with optional within: [LOW, HIGH]");
        spec.checkKeys({}, {"uniform", "normal", "within"});
        const bool uniform = spec.has("uniform");
        if (uniform == spec.has("normal"))
            spec.fail("give one of uniform: [LOW, HIGH] or normal: [MEAN, SD]");
        std::string unit;
        bool unitSet = false;
        auto pair = [&](const std::string& k, const char* a, const char* bname) {
            const ScenarioNode n = spec.get(k);
            const std::vector<ScenarioNode> e =
                n.isSequence() ? n.getElements() : std::vector<ScenarioNode>{};
            if (e.size() != 2)
                n.fail("\"" + emitFlow(n.getYaml()) + "\": two values, [" + a + ", " + bname +
                       "], with the same unit, e.g. [140 mm, 160 mm]");
            double v[2];
            for (int i = 0; i < 2; ++i) {
                std::string u;
                if (!e[i].isScalar() || !splitQuantity(e[i].asString(), &v[i], &u))
                    e[i].fail("\"" + emitFlow(e[i].getYaml()) +
                              "\" is not a number with a unit, e.g. 140 mm");
                if (!unitSet) {
                    unit = u;
                    unitSet = true;
                } else if (u != unit) {
                    e[i].fail("\"" + e[i].asString() +
                              "\": every number of a random parameter "
                              "takes the same unit ('" +
                              unit + "' here)");
                }
            }
            return std::pair<double, double>(v[0], v[1]);
        };
        const auto ab =
            pair(uniform ? "uniform" : "normal", uniform ? "LOW" : "MEAN", uniform ? "HIGH" : "SD");
        double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
        if (spec.has("within")) std::tie(lo, hi) = pair("within", "LOW", "HIGH");
        if (uniform) {
            lo = std::max(lo, ab.first);
            hi = std::min(hi, ab.second);
        }
        if (!(lo < hi) || (!uniform && !(ab.second > 0)))
            spec.fail(uniform ? "LOW must be less than HIGH (within the 'within' bounds)"
                              : "SD must be greater than zero and LOW less than HIGH");
        const int line = values.getLine(key);
        for (int i = 0; i < samples; ++i) {
            double x;
            if (uniform) {
                x = lo + (hi - lo) * std::generate_canonical<double, 53>(rng);
            } else {
                // A normal truncated to the bounds: drawn again until inside them.
                std::normal_distribution<double> normal(ab.first, ab.second);
                int tries = 0;
                do {
                    x = normal(rng);
                } while ((x < lo || x > hi) && ++tries < 10000);
                if (x < lo || x > hi)
                    spec.fail("within",
                              "the bounds hold almost none of the normal "
                              "distribution; widen them or move the mean");
            }
            Value v;
            v.text = formatSample(x, unit);
            splitQuantity(v.text, &v.number, &v.unit);  // the rounded value, as run
            v.numeric = true;
            v.line = line;
            b.rows[i].push_back(v);
        }
    }
    return b;
}

/// The product of the blocks: every row of the first with every row of the next, in order.
void combine(StudyScenario& s, const std::vector<Block>& blocks, const ScenarioNode& where) {
    std::vector<std::vector<Value>> rows{{}};
    for (const Block& b : blocks) {
        s.parameters.insert(s.parameters.end(), b.parameters.begin(), b.parameters.end());
        std::vector<std::vector<Value>> next;
        for (const auto& r : rows)
            for (const auto& br : b.rows) {
                next.push_back(r);
                next.back().insert(next.back().end(), br.begin(), br.end());
                if (next.size() > kMaxCases)
                    where.fail("the sweep has more than " + std::to_string(kMaxCases) +
                               " cases; sweep fewer values");
            }
        rows = std::move(next);
    }
    // The column's unit: the first value's; other units of the same kind are converted.
    for (size_t p = 0; p < s.parameters.size(); ++p) {
        bool numeric = true;
        std::string unit;
        for (size_t r = 0; r < rows.size(); ++r) {
            const Value& v = rows[r][p];
            if (!v.numeric) numeric = false;
            if (r == 0) unit = v.unit;
            if (v.numeric && v.unit != unit) {
                const UnitInfo* a = findUnit(v.unit);
                const UnitInfo* b = findUnit(unit);
                if (!a || !b || a->dimension != b->dimension) numeric = false;
            }
        }
        s.parameters[p].unit = numeric ? unit : "";
        for (auto& row : rows) {
            Value& v = row[p];
            if (!numeric)
                v.number = std::numeric_limits<double>::quiet_NaN();
            else if (v.unit != unit)
                v.number = toUnit(fromUnit(v.number, v.unit), unit);
        }
    }
    for (const auto& row : rows) {
        StudyCase c;
        for (const Value& v : row) {
            c.values.push_back(v.text);
            c.numbers.push_back(v.number);
            c.lines.push_back(v.line);
        }
        s.cases.push_back(std::move(c));
    }
}

// The output's file and columns are ones a run of `kind` writes (io/ResultFiles.h): refused
// here, before any case runs, rather than found missing after each.
void checkOutputAgainstKind(const ScenarioNode& o, const StudyOutput& out,
                            const std::string& kind) {
    const std::vector<ResultCsv> files = getResultCsvs(kind);
    if (files.empty()) return;
    std::string names;
    for (const ResultCsv& f : files) names += std::string(names.empty() ? "" : ", ") + f.file;
    for (const ResultCsv& f : files) {
        if (out.file != f.file) continue;
        const std::vector<std::string> columns = splitResultHeader(f.header);
        std::string list;
        for (const std::string& c : columns) list += (list.empty() ? "" : ", ") + c;
        for (const char* key : {"column", "per"}) {
            const std::string& c = std::string(key) == "column" ? out.column : out.per;
            if (c.empty() || std::find(columns.begin(), columns.end(), c) != columns.end())
                continue;
            o.fail(key, "\"" + c + "\": " + out.file + " has no such column; its columns: " + list);
        }
        return;
    }
    o.fail("file", "\"" + out.file + "\" is not a file a " + kind + " run writes; valid: " + names);
}

std::vector<StudyOutput> readOutputs(const ScenarioNode& root, const std::string& kind) {
    std::vector<StudyOutput> outputs;
    if (!root.has("outputs")) {
        if (kind == "seed-load-test")
            return {{"stiffness.csv", "stiffness_N_per_mm", "gas_mass_g", "", 0}};
        if (kind == "patient-on-support")
            return {{"region_loads.csv", "share_percent", "region", "", 0}};
        root.fail("outputs", "a study of kind " + kind +
                                 " names its outputs, e.g. outputs: [{file: regions.csv, "
                                 "column: patch_peak_mmHg, per: region, reduce: last}]");
    }
    const ScenarioNode list = root.get("outputs");
    if (!list.isSequence() || list.getElements().empty())
        list.fail(
            "a list of outputs, e.g. [{file: stiffness.csv, column: stiffness_N_per_mm, "
            "per: gas_mass_g}]");
    std::set<std::string> names;
    for (const ScenarioNode& o : list.getElements()) {
        o.checkKeys({"file", "column"}, {"per", "reduce"});
        StudyOutput out;
        out.file = o.getString("file");
        out.column = o.getString("column");
        out.line = o.getLine();
        if (out.file.empty() || out.file.find('/') != std::string::npos ||
            out.file.find("..") != std::string::npos || fs::path(out.file).extension() != ".csv")
            o.fail("file", "\"" + out.file +
                               "\": a CSV file the run writes in its folder, e.g. stiffness.csv");
        out.per = o.getString("per", "");
        // With per: no reduce, one value per row (each row its own value of `per`), or the
        // reduction over the rows of each value (a time series: last, the value at the end).
        out.reduce = o.has("per") && !o.has("reduce")
                         ? ""
                         : o.getChoice("reduce", {"first", "last", "min", "max", "mean"}, "first");
        checkOutputAgainstKind(o, out, kind);
        const std::string name = out.file + ":" + out.column + ":" + out.per + ":" + out.reduce;
        if (!names.insert(name).second) o.fail("this output is listed twice");
        outputs.push_back(out);
    }
    return outputs;
}

/// Runs the base scenario's reader on one case; a refused value is reported at its line in
/// the study file.
void checkCase(const StudyScenario& s, size_t index, const std::string& basePath,
               const ScenarioNode& setSection) {
    const StudyCase& c = s.cases[index];
    ScenarioFile f = ScenarioFile::parse(s.baseText, basePath);
    // The files only some runs of a kind write (io::ResultFiles' `when`): pneumatics.csv with a
    // pneumatics section, rig_readings.csv with a rig section.
    bool pneumatics = true, rig = true;
    try {
        for (const std::string& o : getCaseOverrides(s, c)) f.applyOverride(o);
        if (s.baseKind == "seed-load-test")
            rig = !readLoadTestScenario(f).rig.isNone();
        else if (s.baseKind == "patient-on-support")
            readPatientOnSupportScenario(f);
        else if (s.baseKind == "patient-on-array")
            pneumatics = readPatientOnArrayScenario(f).hasPneumatics;
    } catch (const InputError& e) {
        const std::string prefix = "--set ";
        if (e.getWhere().rfind(prefix, 0) != 0) throw;
        const std::string key = e.getWhere().substr(prefix.size());
        const std::string detail =
            (e.getKey().empty() ? "" : "key '" + e.getKey() + "': ") + e.getMessage();
        for (size_t p = 0; p < s.parameters.size(); ++p)
            if (s.parameters[p].key == key)
                throw InputError(s.studyFile, c.lines[p], s.parameters[p].path,
                                 "case " + std::to_string(index + 1) + " sets " + key + " = " +
                                     c.values[p] + ", which " + s.baseScenario +
                                     " refuses: " + detail);
        if (setSection.has(key))
            throw InputError(s.studyFile, setSection.getLine(key), setSection.getChildPath(key),
                             s.baseScenario + " refuses it: " + detail);
        throw InputError(s.studyFile, 0, key, detail);
    }
    for (const StudyOutput& o : s.outputs) {
        const bool missing =
            (o.file == "pneumatics.csv" && !pneumatics) || (o.file == "rig_readings.csv" && !rig);
        if (missing)
            throw InputError(s.studyFile, o.line, "outputs",
                             o.file + " is written only by a run with a " +
                                 (o.file == "pneumatics.csv" ? "pneumatics" : "rig") +
                                 " section, and case " + std::to_string(index + 1) + " of " +
                                 s.baseScenario + " has none; valid: an output its runs write");
    }
}

}  // namespace

bool isStudyFile(const ScenarioFile& file) {
    const YAML::Node& k = file.getRoot().getYaml()["kind"];
    return k && k.IsScalar() && k.Scalar() == "study";
}

StudyScenario readStudyScenario(const ScenarioFile& file) {
    const ScenarioNode root = file.getRoot();
    root.checkKeys({"kind", "scenario", "parameters"}, {"name", "description", "set", "outputs"});
    root.getChoice("kind", {"study"});
    StudyScenario s;
    s.studyFile = file.getFileName();
    s.studyText = file.getText();
    s.name = root.getString("name", file.getStem());
    checkScenarioName(root, s.name);
    s.description = root.getString("description", "");

    // The base scenario, relative to the study file.
    const std::string base = root.getString("scenario");
    const fs::path basePath = fs::path(file.getFileName()).parent_path() / base;
    s.baseScenario = basePath.lexically_normal().string();
    ScenarioFile baseFile;
    try {
        baseFile = ScenarioFile::load(s.baseScenario);
        s.baseKind = readScenarioKind(baseFile);
    } catch (const InputError& e) {
        root.fail("scenario", "\"" + base + "\" (relative to the study file): " + e.what());
    }
    if (isStudyFile(baseFile)) root.fail("scenario", "the base scenario cannot be a study");
    s.baseText = baseFile.getText();

    std::set<std::string> seen;
    const ScenarioNode setSection = root.getSection("set", false);
    if (!setSection.isNull())
        for (const std::string& key : getKeys(setSection)) {
            seen.insert(key);
            s.fixedSets.push_back(key + "=" + emitFlow(setSection.get(key).getYaml()));
        }

    const ScenarioNode params = root.getSection("parameters");
    params.checkKeys({}, {"grid", "zip", "random"});
    std::vector<Block> blocks;
    if (params.has("grid")) blocks.push_back(readGrid(params.getSection("grid"), seen));
    if (params.has("zip")) blocks.push_back(readZip(params.getSection("zip"), seen));
    if (params.has("random")) blocks.push_back(readRandom(params.getSection("random"), seen));
    if (blocks.empty() || seen.size() == s.fixedSets.size())
        params.fail(
            "sweeps nothing; give grid: {KEY: [VALUES]}, zip: {KEY: [VALUES]} or "
            "random: {samples: N, values: {KEY: {uniform: [LOW, HIGH]}}}");
    combine(s, blocks, params);
    s.outputs = readOutputs(root, s.baseKind);

    for (size_t i = 0; i < s.cases.size(); ++i) checkCase(s, i, s.baseScenario, setSection);
    return s;
}

std::vector<std::string> getCaseOverrides(const StudyScenario& s, const StudyCase& c) {
    std::vector<std::string> o = s.fixedSets;
    for (size_t p = 0; p < s.parameters.size(); ++p)
        o.push_back(s.parameters[p].key + "=" + c.values[p]);
    return o;
}

std::string getCaseKey(const StudyScenario& s, const StudyCase& c) {
    // FNV-1a, 64 bits: stable across runs, machines and compilers (std::hash is not).
    std::uint64_t h = 1469598103934665603ull;
    auto add = [&](const std::string& text) {
        for (unsigned char ch : text) {
            h ^= ch;
            h *= 1099511628211ull;
        }
        h ^= 0xff;  // separator
        h *= 1099511628211ull;
    };
    add(s.baseText);
    for (const std::string& o : getCaseOverrides(s, c)) add(o);
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

}  // namespace io
