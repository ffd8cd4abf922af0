#include <io/MeasuredData.h>
#include <io/ResultFiles.h>

#include <io/Scenario.h>
#include <io/Units.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ChannelCsv.h"
#include "MeasuredManifest.h"

namespace io {

namespace fs = std::filesystem;

namespace {

using csv::fmt;
using csv::listUnits;
using csv::lower;
using csv::nextDataLine;
using csv::splitCsv;
using csv::splitHeader;
using csv::trim;

std::string formatMass(double kg) { return fmt("%.4g", kg * 1e3) + " g"; }

void readStiffnessChannel(const ScenarioNode& root, const fs::path& dir,
                          diagnose::MeasuredData& data);

}  // namespace

std::vector<std::vector<double>> readChannelCsv(const std::string& path,
                                                const std::string& shownName,
                                                const std::vector<ChannelColumn>& columns) {
    std::istringstream text(readInputFile(path, kMaxChannelBytes, "channel file"));
    auto fail = [&](int line, const std::string& msg) -> void {
        throw InputError(shownName, line, "", msg);
    };
    std::string expected;
    for (const ChannelColumn& c : columns)
        if (!c.optional)
            expected +=
                (expected.empty() ? "" : ",") + c.name +
                (c.dimension == Dimension::Dimensionless ? std::string()
                                                         : "_" + getUnits(c.dimension)[0].symbol);

    std::vector<int> index(columns.size(), -1);  // file column of each wanted column
    std::vector<double> factor(columns.size()), offset(columns.size());
    std::vector<std::string> header;
    std::vector<std::vector<double>> out(columns.size());
    int lineNo = 0, headerLine = 0, lastRowLine = 0;
    std::string t;
    std::vector<std::string> cells;
    while (nextDataLine(text, lineNo, t, cells)) {
        if (header.empty()) {
            header = cells;
            headerLine = lineNo;
            for (size_t w = 0; w < columns.size(); ++w) {
                const ChannelColumn& want = columns[w];
                for (size_t c = 0; c < cells.size(); ++c) {
                    const auto [name, unit] = splitHeader(cells[c]);
                    if (lower(name) != want.name) continue;
                    const std::string col =
                        "column " + std::to_string(c + 1) + " '" + cells[c] + "': ";
                    if (index[w] >= 0)
                        fail(lineNo, col + "a second '" + want.name +
                                         "' column (the first is column " +
                                         std::to_string(index[w] + 1) + "); keep one");
                    if (want.dimension == Dimension::Dimensionless) {
                        if (!unit.empty())
                            fail(lineNo,
                                 col + "a plain number takes no unit; valid: '" + want.name + "'");
                        index[w] = static_cast<int>(c), factor[w] = 1.0, offset[w] = 0.0;
                        continue;
                    }
                    if (unit.empty())
                        fail(lineNo, col + "no unit; write it in the header, e.g. " + want.name +
                                         "_" + getUnits(want.dimension)[0].symbol + " or \"" +
                                         want.name + " [" + getUnits(want.dimension)[0].symbol +
                                         "]\" (valid units: " + listUnits(want.dimension) + ")");
                    const UnitInfo* u = findUnit(unit);
                    if (!u || u->dimension != want.dimension)
                        fail(lineNo, col + "'" + unit + "' is not a unit of " +
                                         getDimensionName(want.dimension) +
                                         "; valid: " + listUnits(want.dimension));
                    index[w] = static_cast<int>(c);
                    factor[w] = u->factor;
                    offset[w] = u->offset;
                }
                if (index[w] < 0 && !want.optional)
                    fail(lineNo, "no '" + want.name + "' column in the header '" + t +
                                     "'; valid: a header with the columns " + expected +
                                     " (units may differ; other columns are ignored)");
            }
            continue;
        }
        if (cells.size() != header.size())
            fail(lineNo, "has " + std::to_string(cells.size()) + " cells; the header (line " +
                             std::to_string(headerLine) + ") has " + std::to_string(header.size()));
        for (size_t w = 0; w < columns.size(); ++w) {
            const int c = index[w];
            if (c < 0) continue;  // an optional column the file does not have
            const std::string& cell = cells[c];
            const std::string col = "column " + std::to_string(c + 1) + " '" + header[c] + "': ";
            char* end = nullptr;
            const double v = std::strtod(cell.c_str(), &end);
            if (cell.empty() || end != cell.c_str() + cell.size())
                fail(lineNo, col + "'" + cell + "' is not a number; valid: a finite number");
            if (!std::isfinite(v))
                fail(lineNo, col + "'" + cell + "' is not a finite number (" +
                                 (std::isnan(v) ? "NaN" : "infinite") +
                                 "); valid: a finite number (drop the row if the instrument "
                                 "had no reading)");
            const double si = factor[w] * v + offset[w];
            if (w == 0 && !out[0].empty() && !(si > out[0].back()))
                fail(lineNo, col + cell + " is not after the previous row's (line " +
                                 std::to_string(lastRowLine) + ") " +
                                 fmt("%.9g", (out[0].back() - offset[0]) / factor[0]) +
                                 "; valid: " + columns[0].name +
                                 " strictly increasing (sort the rows, drop repeated ones)");
            out[w].push_back(si);
        }
        lastRowLine = lineNo;
    }
    if (header.empty())
        fail(0, "no header line; valid: a header with the columns " + expected +
                    " then one row per sample");
    if (out[0].size() < 2)
        fail(0,
             "has " + std::to_string(out[0].size()) + " data row(s); valid: at least two samples");
    return out;
}

namespace manifest {

ScenarioFile readManifest(const std::string& folder) {
    const fs::path dir(folder);
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw InputError(folder, 0, "",
                         "is not a folder; give the measured-data folder holding " +
                             std::string(kMeasuredManifest) + " (docs/measured-data.md)");
    const fs::path manifest = dir / kMeasuredManifest;
    if (!fs::exists(manifest, ec))
        throw InputError(
            folder, 0, "",
            std::string("holds no ") + kMeasuredManifest +
                "; a measured-data folder needs this manifest (docs/measured-data.md)");
    const std::string mname = manifest.string();
    return ScenarioFile::parse(readInputFile(mname, kMaxScenarioBytes, "measured-data manifest"),
                               mname);
}

std::string readManifestScenario(const ScenarioNode& root, const std::string& folder,
                                 const std::string& what) {
    const std::string format = root.getString("format");
    if (format != kMeasuredFormat)
        root.fail("format", "\"" + format + "\" is not a format this bagsim reads; valid: \"" +
                                kMeasuredFormat + "\"");
    const std::string scen = root.getString("scenario");
    const fs::path sp = fs::path(scen).is_absolute() ? fs::path(scen) : fs::path(folder) / scen;
    std::error_code ec;
    if (!fs::is_regular_file(sp, ec))
        root.fail("scenario", "\"" + scen + "\": no such file (" + sp.string() +
                                  "); valid: " + what +
                                  " the data correspond to, relative to the folder or absolute");
    return sp.string();
}

}  // namespace manifest

diagnose::MeasuredData readMeasuredData(const std::string& folder) {
    const fs::path dir(folder);
    std::error_code ec;
    const ScenarioFile file = manifest::readManifest(folder);
    const ScenarioNode root = file.getRoot();
    root.checkKeys({"format", "scenario", "protocol"}, {"description", "tests", "stiffness"});
    if (!root.has("tests") && !root.has("stiffness"))
        root.fail(
            "lists no 'tests' and no 'stiffness'; valid: a 'tests' list (one entry per gas "
            "mass), a 'stiffness' curve file, or both (docs/measured-data.md)");
    diagnose::MeasuredData data;
    data.folder = folder;
    data.description = root.getString("description", "");
    data.scenarioFile = manifest::readManifestScenario(root, folder, "the scenario file");

    const ScenarioNode p = root.getSection("protocol");
    p.checkKeys({"block", "rate", "peak_force", "room_temperature"},
                {"gas_mass_uncertainty", "room_temperature_uncertainty"});
    diagnose::Protocol& pr = data.protocol;
    pr.blockSize = p.getQuantity("block", Dimension::Length);
    pr.rate = p.getQuantity("rate", Dimension::Velocity);
    pr.peakForce = p.getQuantity("peak_force", Dimension::Force);
    pr.roomTemperature = p.getQuantity("room_temperature", Dimension::Temperature);
    for (const auto& [key, v] : {std::pair<const char*, double>{"block", pr.blockSize},
                                 {"rate", pr.rate},
                                 {"peak_force", pr.peakForce},
                                 {"room_temperature", pr.roomTemperature}})
        if (!(v > 0.0)) p.fail(key, "must be greater than zero");
    if (p.has("room_temperature_uncertainty")) {
        // A temperature difference: K only (degC would be read as a temperature, 273.15 K on).
        const std::string key = "room_temperature_uncertainty";
        const std::string text = trim(p.getString(key));
        const std::string valid = "valid: 0 K to " + fmt("%g", kMaxRoomTemperatureUncertainty) +
                                  " K, a standard uncertainty in K (e.g. 0.5 K)";
        if (text.empty() || text.back() != 'K' || text.find("degC") != std::string::npos)
            p.fail(key, "\"" + text + "\" is not a temperature difference in K; " + valid);
        pr.roomTemperatureUncertainty = p.getQuantity(key, Dimension::Temperature);
        if (!(pr.roomTemperatureUncertainty >= 0.0) ||
            pr.roomTemperatureUncertainty > kMaxRoomTemperatureUncertainty)
            p.fail(key, "\"" + text + "\" is out of range; " + valid);
        pr.roomTemperatureUncertaintyStated = true;
    }
    // The flowmeter's stated standard uncertainty for every test (a test may state its own).
    const bool massUncertaintyForAll = p.has("gas_mass_uncertainty");
    const double massUncertaintyAll =
        massUncertaintyForAll ? p.getQuantity("gas_mass_uncertainty", Dimension::Mass) : 0.0;

    if (root.has("stiffness")) readStiffnessChannel(root, dir, data);
    if (!root.has("tests")) return data;
    const ScenarioNode tests = root.get("tests");
    const std::vector<ScenarioNode> entries = tests.getElements();
    if (entries.empty()) tests.fail("lists no test; valid: one entry per gas mass");
    // The bed gauge's channel: every test's or none (a rig has the gauge or not).
    int withBed = 0;
    for (const ScenarioNode& e : entries) withBed += e.has("bed") ? 1 : 0;
    for (const ScenarioNode& e : entries) {
        e.checkKeys({"gas_mass", "machine", "pressure", "flowmeter"},
                    {"gas_mass_uncertainty", "bed"});
        if (withBed > 0 && !e.has("bed"))
            e.fail("this test has no 'bed' channel while " + std::to_string(withBed) +
                   " other test(s) have one; valid: a bed gauge's file for "
                   "every test or for none (docs/measured-data.md)");
        diagnose::MeasuredTest t;
        t.gasMass = e.getQuantity("gas_mass", Dimension::Mass);
        if (!(t.gasMass > 0.0)) e.fail("gas_mass", "must be greater than zero");
        {
            // The test's own statement, else the protocol's; at most a share of its gas mass.
            const bool own = e.has("gas_mass_uncertainty");
            if (own || massUncertaintyForAll) {
                const ScenarioNode& at = own ? e : p;
                t.gasMassUncertainty = own ? e.getQuantity("gas_mass_uncertainty", Dimension::Mass)
                                           : massUncertaintyAll;
                t.gasMassUncertaintyStated = true;
                const double most = kMaxGasMassUncertaintyShare * t.gasMass;
                if (!(t.gasMassUncertainty >= 0.0) || t.gasMassUncertainty > most)
                    at.fail(
                        "gas_mass_uncertainty",
                        formatMass(t.gasMassUncertainty) + " is out of range" +
                            (own ? std::string() : " for the test of " + formatMass(t.gasMass)) +
                            "; valid: 0 g to " + fmt("%g", 100 * kMaxGasMassUncertaintyShare) +
                            " % of the test's gas mass (" + formatMass(most) +
                            "), a standard uncertainty of the flowmeter's reading");
            }
        }
        auto channelPath = [&](const char* key) {
            const std::string name = e.getString(key);
            const fs::path f = fs::path(name).is_absolute() ? fs::path(name) : dir / name;
            if (!fs::exists(f, ec))
                e.fail(key, "channel file \"" + name + "\" is missing (" + f.string() +
                                "); valid: a CSV file in the folder (docs/measured-data.md)");
            if (!fs::is_regular_file(f, ec))
                e.fail(key, "\"" + name + "\" is not a file (" + f.string() +
                                "); valid: a CSV file in the folder (docs/measured-data.md)");
            return f.string();
        };
        const std::string machine = channelPath("machine");
        const std::string pressure = channelPath("pressure");
        const std::string flow = channelPath("flowmeter");
        auto cols = readChannelCsv(machine, machine,
                                   {{"time", Dimension::Time},
                                    {"displacement", Dimension::Length},
                                    {"force", Dimension::Force}});
        t.time = cols[0];
        t.displacement = cols[1];
        t.force = cols[2];
        cols = readChannelCsv(pressure, pressure,
                              {{"time", Dimension::Time}, {"pressure", Dimension::Pressure}});
        t.pressure = {cols[0], cols[1]};
        cols = readChannelCsv(flow, flow, {{"time", Dimension::Time}, {"mass", Dimension::Mass}});
        t.flowmeter = {cols[0], cols[1]};
        if (e.has("bed")) {
            const std::string bed = channelPath("bed");
            cols =
                readChannelCsv(bed, bed, {{"time", Dimension::Time}, {"sink", Dimension::Length}});
            t.bed = {cols[0], cols[1]};
        }

        // Consistency of the channels with the manifest.
        double mean = 0.0;
        for (double m : t.flowmeter.value) mean += m;
        mean /= double(t.flowmeter.value.size());
        const double tol = std::max(kFlowmeterAbsTolerance, kFlowmeterRelTolerance * t.gasMass);
        if (std::fabs(mean - t.gasMass) > tol)
            e.fail("gas_mass", formatMass(t.gasMass) + " disagrees with its flowmeter file " +
                                   flow + ", which reads " + formatMass(mean) +
                                   " on average; valid: the flowmeter's reading within " +
                                   formatMass(tol) + " (the larger of 0.05 g and 2 %)");
        const double fmax = *std::max_element(t.force.begin(), t.force.end());
        if (std::fabs(fmax - pr.peakForce) > kPeakForceTolerance * pr.peakForce)
            p.fail("peak_force", fmt("%g N", pr.peakForce) + " disagrees with the machine file " +
                                     machine + ", whose force peaks at " + fmt("%.4g N", fmax) +
                                     "; valid: the peak force the tests were run to (within " +
                                     fmt("%g", 100 * kPeakForceTolerance) + " %)");
        data.tests.push_back(std::move(t));
    }
    return data;
}

namespace {

// The manifest's `stiffness` file: gas_mass, stiffness and an optional stage column.
void readStiffnessChannel(const ScenarioNode& root, const fs::path& dir,
                          diagnose::MeasuredData& data) {
    const std::string name = root.getString("stiffness");
    const fs::path f = fs::path(name).is_absolute() ? fs::path(name) : dir / name;
    std::error_code ec;
    if (!fs::exists(f, ec) || !fs::is_regular_file(f, ec))
        root.fail("stiffness", "stiffness file \"" + name + "\" is " +
                                   (fs::exists(f, ec) ? "not a file (" : "missing (") + f.string() +
                                   "); valid: a CSV file with the columns gas_mass_g, "
                                   "stiffness_N/mm and optionally stage (docs/measured-data.md)");
    data.stiffnessFile = f.string();
    const auto cols = readChannelCsv(data.stiffnessFile, data.stiffnessFile,
                                     {{"gas_mass", Dimension::Mass},
                                      {"stiffness", Dimension::Stiffness},
                                      {"stage", Dimension::Dimensionless, true}});
    diagnose::StiffnessChannel& k = data.stiffness;
    k.gasMass = cols[0];
    k.stiffness = cols[1];
    // The file's line of data row i (the reader skips comments and blank lines).
    auto rowLine = [&](size_t row) {
        std::istringstream text(
            readInputFile(data.stiffnessFile, kMaxChannelBytes, "channel file"));
        std::string line;
        int lineNo = 0;
        size_t seen = 0;
        while (std::getline(text, line)) {
            ++lineNo;
            const std::string t = trim(line);
            if (!t.empty() && t[0] != '#' && seen++ == row + 1) return lineNo;
        }
        return 0;
    };
    for (size_t i = 0; i < cols[0].size(); ++i) {
        if (!(k.gasMass[i] > 0.0) || !(k.stiffness[i] > 0.0))
            throw InputError(data.stiffnessFile, rowLine(i), "",
                             "gas mass " + formatMass(k.gasMass[i]) + ", stiffness " +
                                 fmt("%g N/mm", k.stiffness[i] * 1e-3) +
                                 "; valid: both greater than zero");
        if (cols[2].empty()) continue;
        const double s = cols[2][i];
        if (s != std::floor(s) || s < 0.0 || s > 3.0)
            throw InputError(data.stiffnessFile, rowLine(i), "",
                             "column 'stage': " + fmt("%g", s) +
                                 " is not a stage; valid: 1, 2, 3, or 0 (not stated)");
        k.stage.push_back(static_cast<int>(s));
    }
}

}  // namespace

ScenarioFile loadMeasuredScenarioFile(const diagnose::MeasuredData& data) {
    ScenarioFile file = ScenarioFile::load(data.scenarioFile);
    std::string masses = "[";
    for (size_t i = 0; i < data.tests.size(); ++i)
        masses += (i ? ", " : "") + fmt("%.9g", data.tests[i].gasMass * 1e3) + " g";
    if (data.tests.empty())  // a stiffness curve alone: its masses, let down from the largest
        for (size_t i = data.stiffness.gasMass.size(); i-- > 0;)
            masses += (masses.size() > 1 ? ", " : "") +
                      fmt("%.9g", data.stiffness.gasMass[i] * 1e3) + " g";
    masses += "]";
    const diagnose::Protocol& p = data.protocol;
    file.applyOverride("test.gas_masses", masses);
    file.applyOverride("test.block", fmt("%.9g", p.blockSize * 1e3) + " mm");
    file.applyOverride("test.rate", fmt("%.9g", p.rate * 6e4) + " mm/min");
    file.applyOverride("test.peak_force", fmt("%.9g", p.peakForce) + " N");
    file.applyOverride("gas.temperature", fmt("%.9g", p.roomTemperature) + " K");
    file.applyOverride("test.unload", "true");
    return file;
}

LoadTestScenario readMeasuredScenario(const diagnose::MeasuredData& data) {
    const ScenarioFile file = loadMeasuredScenarioFile(data);
    try {
        return readLoadTestScenario(file);
    } catch (const InputError& e) {
        // An error at a key the protocol set is the protocol's: say so at the manifest.
        static const std::vector<std::pair<std::string, std::string>> keys = {
            {"test.gas_masses", "tests"},
            {"test.block", "protocol.block"},
            {"test.rate", "protocol.rate"},
            {"test.peak_force", "protocol.peak_force"},
            {"gas.temperature", "protocol.room_temperature"},
            {"test.stiffness_range", "protocol.peak_force"},
            {"test.polynomial_order", "tests"}};
        const std::string manifest = (fs::path(data.folder) / kMeasuredManifest).string();
        for (const auto& [set, key] : keys)
            if (e.getWhere() == "--set " + set || e.getKey().rfind(set, 0) == 0) {
                const ScenarioFile m = ScenarioFile::load(manifest);
                const ScenarioNode root = m.getRoot();
                std::string section = key.substr(0, key.find('.'));
                if (section == "tests" && !root.has("tests")) section = "stiffness";
                int line = root.getLine(section);
                if (key.find('.') != std::string::npos)
                    line = root.getSection(section).getLine(key.substr(key.find('.') + 1));
                throw InputError(
                    manifest, line, key,
                    "the scenario " + data.scenarioFile +
                        " cannot run this protocol: " + e.getMessage() +
                        (e.getWhere().rfind("--set", 0) == 0
                             ? std::string()
                             : " (at " + e.getWhere() + ":" + std::to_string(e.getLine()) + ")"));
            }
        throw;
    }
}

std::vector<std::string> writeMeasuredData(const std::string& folder,
                                           const diagnose::MeasuredData& data,
                                           const std::string& scenarioText,
                                           const std::string& comment) {
    const fs::path dir(folder);
    std::vector<std::string> names;
    auto write = [&](const std::string& name, const std::string& text) {
        csv::writeFolderFile(dir, name, text, names);
    };
    write("scenario.yaml", scenarioText);
    std::ostringstream m;
    m << comment << "format: " << kMeasuredFormat << "\n"
      << "scenario: scenario.yaml\n";
    if (!data.description.empty()) m << "description: \"" << data.description << "\"\n";
    const diagnose::Protocol& p = data.protocol;
    m << "protocol:\n"
      << "  block: " << fmt("%.6g", p.blockSize * 1e3) << " mm\n"
      << "  rate: " << fmt("%.6g", p.rate * 6e4) << " mm/min\n"
      << "  peak_force: " << fmt("%.6g", p.peakForce) << " N\n"
      << "  room_temperature: " << fmt("%.6g", p.roomTemperature - 273.15) << " degC\n";
    if (p.roomTemperatureUncertaintyStated)
        m << "  room_temperature_uncertainty: " << fmt("%.6g", p.roomTemperatureUncertainty)
          << " K  # standard uncertainty\n";
    // One gas-mass uncertainty for all tests when they state the same, else each its own.
    bool sameMassUncertainty = !data.tests.empty();
    for (const diagnose::MeasuredTest& t : data.tests)
        sameMassUncertainty = sameMassUncertainty && t.gasMassUncertaintyStated &&
                              t.gasMassUncertainty == data.tests[0].gasMassUncertainty;
    if (sameMassUncertainty)
        m << "  gas_mass_uncertainty: " << fmt("%.6g", data.tests[0].gasMassUncertainty * 1e3)
          << " g  # standard uncertainty of the flowmeter's reading\n";
    m << "tests:\n";
    for (size_t i = 0; i < data.tests.size(); ++i) {
        const diagnose::MeasuredTest& t = data.tests[i];
        const std::string stem = "test" + std::to_string(i + 1);
        m << "  - gas_mass: " << fmt("%.4f", t.gasMass * 1e3) << " g  # flowmeter reading\n"
          << (t.gasMassUncertaintyStated && !sameMassUncertainty
                  ? "    gas_mass_uncertainty: " + fmt("%.6g", t.gasMassUncertainty * 1e3) + " g\n"
                  : std::string())
          << "    machine: " << stem << "-machine.csv\n"
          << "    pressure: " << stem << "-pressure.csv\n"
          << "    flowmeter: " << stem << "-flowmeter.csv\n"
          << (t.bed.empty() ? std::string() : "    bed: " + stem + "-bed.csv\n");
        std::ostringstream mc, pc, fc;
        mc << "time_s,displacement_mm,force_N\n";
        for (size_t k = 0; k < t.time.size(); ++k)
            mc << fmt("%.3f", t.time[k]) << "," << fmt("%.5f", t.displacement[k] * 1e3) << ","
               << fmt("%.5f", t.force[k]) << "\n";
        pc << "time_s,pressure_kPa\n";
        for (size_t k = 0; k < t.pressure.time.size(); ++k)
            pc << fmt("%.3f", t.pressure.time[k]) << "," << fmt("%.5f", t.pressure.value[k] * 1e-3)
               << "\n";
        fc << "time_s,mass_g\n";
        for (size_t k = 0; k < t.flowmeter.time.size(); ++k)
            fc << fmt("%.3f", t.flowmeter.time[k]) << "," << fmt("%.5f", t.flowmeter.value[k] * 1e3)
               << "\n";
        write(stem + "-machine.csv", mc.str());
        write(stem + "-pressure.csv", pc.str());
        write(stem + "-flowmeter.csv", fc.str());
        if (!t.bed.empty()) {
            std::ostringstream bc;
            bc << "time_s,sink_mm\n";
            for (size_t k = 0; k < t.bed.time.size(); ++k)
                bc << fmt("%.3f", t.bed.time[k]) << "," << fmt("%.5f", t.bed.value[k] * 1e3)
                   << "\n";
            write(stem + "-bed.csv", bc.str());
        }
    }
    write(kMeasuredManifest, m.str());
    return names;
}

std::string formatRigReadingsCsv(const bags::LoadTestResult& result,
                                 const diagnose::RigEffects& rig, double rate) {
    std::ostringstream os;
    os << kRigReadingsHeader << "\n";
    for (const bags::LoadCurve& c : result.curves) {
        const diagnose::MachineCurve mc = diagnose::calcMachineCurve(c, rig, rate);
        const std::vector<double> p = diagnose::applyPressureSensor(mc.time, mc.pressure, rig);
        // The gas mass as the flowmeter reads it.
        const std::string m = fmt("%.6g", (c.gasMass + rig.flowmeterOffset) * 1e3);
        for (size_t i = 0; i < mc.time.size(); ++i)
            os << m << "," << fmt("%.6g", mc.time[i]) << ","
               << fmt("%.6g", mc.displacement[i] * 1e3) << "," << fmt("%.6g", mc.force[i]) << ","
               << fmt("%.6g", p[i] * 1e-3) << "," << (mc.loading[i] ? "loading" : "unloading")
               << "\n";
    }
    return os.str();
}

}  // namespace io
