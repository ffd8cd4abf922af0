#include "DiagnoseCurve.h"

#include <bags/LoadTest.h>
#include <bagsim/Version.h>
#include <diagnose/Diagnosis.h>
#include <diagnose/Effects.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "ArrayRun.h"
#include "DiagnoseShared.h"
#include "Interrupt.h"

namespace bagsim::app {

namespace {

namespace fs = std::filesystem;

// One curve of the model to run or find in the cache: an effect at a value (or the model as it
// is, "model"), at some masses let down from the largest.
struct CurveRun {
    std::string effect;
    double value = 0.0;
    bags::LoadTestOptions options;
    fs::path file;  // in the cache
};

std::string readText(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// The cache file of a curve: named by the effect, its value and a hash of everything the curve
// depends on (the program's version, the scenario's text, the protocol as applied, the masses).
fs::path makeCacheFile(const fs::path& dir, const diagnose::MeasuredData& data,
                       const std::string& effect, double value, const bags::LoadTestOptions& o) {
    std::ostringstream key;
    key.precision(17);
    key << "bagsim " << bagsim::kVersion << "\n"
        << readText(data.scenarioFile) << "\n"
        << effect << "=" << value << " block " << o.blockSize << " rate " << o.loadingRate
        << " peak " << o.peakForce << " T " << o.gas.temperature << " range " << o.stiffnessFrom
        << "-" << o.stiffnessTo << " step " << o.displacementStep << " unload " << o.unload
        << " masses";
    for (double m : o.gasMasses) key << " " << m;
    char name[160];
    std::snprintf(name, sizeof name, "%s_%+.6g_%016llx.csv", effect.c_str(), value,
                  static_cast<unsigned long long>(calcCheckpointHash(key.str())));
    return dir / name;
}

// The curves' stiffness and stage as the cache keeps them (what the which part reads).
void writeCache(const fs::path& file, const bags::LoadTestResult& r) {
    std::ostringstream s;
    s.precision(17);
    s << "gas_mass_kg,stiffness_N_per_m,stage,failed,note\n";
    for (const bags::LoadCurve& c : r.curves) {
        std::string note = c.failure;
        std::replace(note.begin(), note.end(), '\n', ' ');
        s << c.gasMass << "," << c.stiffness << "," << c.stage << "," << (c.failed ? 1 : 0) << ","
          << note << "\n";
    }
    fs::create_directories(file.parent_path());
    writeOutputFile(file.parent_path(), file.filename().string(), s.str());
}

bool readCache(const fs::path& file, bags::LoadTestResult& r) {
    std::ifstream in(file);
    std::string line;
    if (!in || !std::getline(in, line) || line != "gas_mass_kg,stiffness_N_per_m,stage,failed,note")
        return false;
    r.curves.clear();
    while (std::getline(in, line)) {
        std::istringstream row(line);
        std::string m, k, stage, failed, note;
        if (!std::getline(row, m, ',') || !std::getline(row, k, ',') ||
            !std::getline(row, stage, ',') || !std::getline(row, failed, ','))
            return false;
        std::getline(row, note);
        bags::LoadCurve c;
        try {
            c.gasMass = std::stod(m);
            c.stiffness = k == "nan" || k == "-nan" ? NAN : std::stod(k);
            c.stage = std::stoi(stage);
            c.failed = failed == "1";
        } catch (const std::exception&) {
            return false;  // a damaged cache file is run again
        }
        c.failure = note;
        r.curves.push_back(c);
    }
    return true;
}

// Runs the curves not in the cache, `threads` at a time, each written to the cache as it ends
// (an interrupt keeps those done). A curve that cannot start is kept as failed at every mass.
std::vector<bags::LoadTestResult> runCurves(const std::vector<CurveRun>& runs,
                                            const CurveRunOptions& o, int& ran) {
    std::vector<bags::LoadTestResult> out(runs.size());
    std::vector<bags::LoadTestOptions> todo;
    std::vector<size_t> which;
    for (size_t i = 0; i < runs.size(); ++i)
        if (!readCache(runs[i].file, out[i])) todo.push_back(runs[i].options), which.push_back(i);
    if (todo.empty()) return out;
    std::mutex printing;
    const auto start = std::chrono::steady_clock::now();
    int done = 0;
    auto simulate = [&](const bags::LoadTestOptions& opt) {
        const size_t i = which[static_cast<size_t>(&opt - todo.data())];  // opt is todo's
        bags::LoadTestResult r;
        try {
            r = bags::runLoadTest(opt);
        } catch (const bags::NumericalError& e) {
            if (getInterruptSignal()) throw Interrupted(getInterruptSignal());
            for (double m : opt.gasMasses) {
                bags::LoadCurve c;
                c.gasMass = m, c.failed = true, c.failure = e.what(), c.stiffness = NAN;
                r.curves.push_back(c);
            }
        }
        writeCache(runs[i].file, r);
        std::lock_guard<std::mutex> lock(printing);
        ++done;
        if (!o.quiet)
            std::cerr << "  curve " << done << " of " << todo.size() << " done: " << runs[i].effect
                      << " " << fmt("%g", runs[i].value) << ", " << opt.gasMasses.size()
                      << " masses ("
                      << fmt("%.0f s",
                             std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
                                 .count())
                      << ")\n";
        return r;
    };
    const std::vector<bags::LoadTestResult> results =
        diagnose::runLoadTests(todo, simulate, o.threads);
    for (size_t k = 0; k < which.size(); ++k) out[which[k]] = results[k];
    ran += static_cast<int>(todo.size());
    return out;
}

// The stiffness of a run's curves by increasing mass (NaN where a curve gives none, as
// diagnose::compareStiffness reads it).
diagnose::StiffnessTable makeTable(const bags::LoadTestResult& r) {
    std::vector<std::pair<double, double>> v;
    for (const bags::LoadCurve& c : r.curves)
        v.push_back({c.gasMass, c.stage > 0 && c.stiffness > 0.0 && !c.failed ? c.stiffness : NAN});
    std::sort(v.begin(), v.end());
    diagnose::StiffnessTable t;
    for (const auto& [m, k] : v) t.gasMass.push_back(m), t.stiffness.push_back(k);
    return t;
}

bags::LoadTestOptions makeCurveOptions(const io::LoadTestScenario& sc, std::vector<double> masses) {
    bags::LoadTestOptions o = sc.options;
    std::sort(masses.rbegin(), masses.rend());  // let down from the largest, as the seed's test
    o.gasMasses = masses;
    o.unload = false;
    return o;
}

}  // namespace

bags::LoadTestResult runModelCurve(const diagnose::MeasuredData& data,
                                   const io::LoadTestScenario& sc, const CurveRunOptions& o,
                                   int& runs) {
    CurveRun r;
    r.effect = "model";
    r.options = makeCurveOptions(sc, data.stiffness.gasMass);
    r.file = makeCacheFile(o.cache, data, r.effect, 0.0, r.options);
    CurveRunOptions one = o;
    one.threads = 1;
    return runCurves({r}, one, runs).front();
}

diagnose::StiffnessWhich runCurveWhich(const diagnose::MeasuredData& data,
                                       const io::LoadTestScenario& sc,
                                       const bags::LoadTestResult& model,
                                       const diagnose::StiffnessComparison& cmp,
                                       const CurveRunOptions& o, int& ran) {
    std::vector<double> used;  // the masses with a measured and a simulated stiffness
    for (const diagnose::StiffnessPoint& p : cmp.points)
        if (std::isfinite(p.simulated)) used.push_back(p.gasMass);
    const double room = sc.options.gas.temperature;

    // The candidates and how each acts on the curve.
    std::vector<diagnose::CurveCandidate> candidates;
    std::vector<diagnose::NotApplicable> notApplicable;
    for (const diagnose::Effect& e : diagnose::getEffects()) {
        if (o.candidates.empty()
                ? !e.inLibrary
                : std::find(o.candidates.begin(), o.candidates.end(), e.name) == o.candidates.end())
            continue;
        diagnose::CurveCandidate c;
        c.effect = &e;
        c.roomTemperature = room;
        std::string why;
        if (diagnose::actsOnStiffnessCurve(e, c.action, why))
            candidates.push_back(c);
        else
            notApplicable.push_back({e.name, why});
    }
    if (used.size() < 3)
        throw std::invalid_argument(
            "the stiffness curve's which part needs three gas masses or more where the model "
            "gives a stiffness; it gives one at " +
            std::to_string(used.size()));

    // The runs: the dense curve (two let-downs, every other mass each, so that two can run at
    // once whatever --threads says), and bag-volume's grid at the used masses.
    std::vector<CurveRun> runs;
    bool shifts = false, volume = false;
    for (const auto& c : candidates) {
        shifts = shifts || c.action == diagnose::CurveAction::MassOffset ||
                 c.action == diagnose::CurveAction::MassScale;
        volume = volume || c.action == diagnose::CurveAction::Grid;
    }
    if (shifts) {
        std::vector<double> dense = diagnose::makeShiftMasses(used, o.shiftStep, room);
        std::sort(dense.rbegin(), dense.rend());
        for (int chain = 0; chain < 2; ++chain) {
            std::vector<double> m;
            for (size_t i = chain; i < dense.size(); i += 2) m.push_back(dense[i]);
            CurveRun r;
            r.effect = "dense" + std::to_string(chain + 1);
            r.options = makeCurveOptions(sc, m);
            r.file = makeCacheFile(o.cache, data, r.effect, 0.0, r.options);
            runs.push_back(r);
        }
    }
    std::vector<double> volumes;
    // The model's own curve serves as bag-volume 0 when the used masses are the first it let
    // down to (the same history).
    std::vector<double> usedDown(used.rbegin(), used.rend());
    bool modelIsZero = model.curves.size() >= usedDown.size();
    for (size_t k = 0; modelIsZero && k < usedDown.size(); ++k)
        modelIsZero = std::fabs(model.curves[k].gasMass - usedDown[k]) < 1e-12;
    const diagnose::Effect& bagVolume = *diagnose::findEffect("bag-volume");
    if (volume) {
        const diagnose::EffectParameter& p = bagVolume.parameters[0];
        for (int j = 0; j < o.volumePoints; ++j) {
            double v = p.lower + (p.upper - p.lower) * j / double(o.volumePoints - 1);
            if (std::fabs(v) < 1e-12) v = 0.0;
            volumes.push_back(v);
            if (v == 0.0 && modelIsZero) continue;
            CurveRun r;
            r.effect = "bag-volume";
            r.value = v;
            r.options = makeCurveOptions(sc, used);
            diagnose::RigEffects rig = sc.rig;
            diagnose::applyEffect(bagVolume, {v}, used, rig, r.options);
            r.file = makeCacheFile(o.cache, data, r.effect, v, r.options);
            runs.push_back(r);
        }
    }
    const std::vector<bags::LoadTestResult> results = runCurves(runs, o, ran);

    // The dense curve: both let-downs together; against the model's curve at the used masses,
    // the spread of the model's own stiffness between two histories.
    diagnose::StiffnessTable dense;
    double validation = 0.0;
    std::string what = "not estimated (no dense curve run: no gas-mass shift among the candidates)";
    if (shifts) {
        bags::LoadTestResult both = results[0];
        both.curves.insert(both.curves.end(), results[1].curves.begin(), results[1].curves.end());
        dense = makeTable(both);
        double s2 = 0.0;
        int n = 0;
        for (const diagnose::StiffnessPoint& p : cmp.points) {
            const double d = diagnose::interpolateStiffness(dense, p.gasMass);
            if (std::isfinite(d) && std::isfinite(p.simulated))
                s2 += (d - p.simulated) * (d - p.simulated), ++n;
        }
        validation = n ? std::sqrt(s2 / n) : 0.0;
        what =
            "the model's stiffness let down through the dense curve's masses against its "
            "curve at the measured masses: RMS over " +
            std::to_string(n) + " masses";
    }
    const diagnose::StiffnessTable modelTable = makeTable(model);
    size_t next = shifts ? 2 : 0;
    for (diagnose::CurveCandidate& c : candidates) {
        switch (c.action) {
            case diagnose::CurveAction::MassOffset:
            case diagnose::CurveAction::MassScale:
                c.tables = {dense};
                c.simulations = 2;
                break;
            case diagnose::CurveAction::Grid:
                c.values = volumes;
                for (double v : volumes) {
                    if (v == 0.0 && modelIsZero)
                        c.tables.push_back(modelTable);
                    else
                        c.tables.push_back(makeTable(results[next++])), ++c.simulations;
                }
                break;
            default:
                c.tables = {modelTable};
        }
    }
    diagnose::CalibrationOptions co;
    diagnose::StiffnessWhich w =
        diagnose::calibrateStiffnessCandidates(cmp, candidates, validation, what, co);
    w.notApplicable = notApplicable;
    return w;
}

void printCurveWhich(const diagnose::StiffnessWhich& w, std::ostream& out) {
    out << "which (stiffness curve): candidates ranked by the shrink of the held-out gap beyond "
           "the validation uncertainty (leave one gas mass out of "
        << w.gasMasses.size() << "), less 0.05 per parameter; validation uncertainty "
        << fmt("%.3g N/mm", w.validation * 1e-3) << " (" << w.validationWhat << "):\n";
    for (const auto& c : w.which.candidates) {
        const diagnose::EffectParameter& p = diagnose::findEffect(c.effect)->parameters[0];
        double interp = NAN;
        for (const auto& [e, v] : w.interpolationErrors)
            if (e == c.effect) interp = v;
        out << "  " << c.effect << ": shrink " << fmt("%.1f %%", 100 * c.excessShrink)
            << " beyond the uncertainty (" << fmt("%.4f", c.excessBefore) << " -> "
            << fmt("%.4f", c.excessAfter) << "), " << fmt("%.1f %%", 100 * c.shrink)
            << " of the whole gap, score " << fmt("%.3f", c.score) << "; " << p.name << " "
            << fmt("%.4g", c.parameters[0] / p.siPerUnit)
            << (std::isfinite(c.parameterStdDev[0])
                    ? " +- " + fmt("%.2g", c.parameterStdDev[0] / p.siPerUnit)
                    : std::string())
            << (p.unit.empty() ? "" : " " + p.unit) << " (fitted on all masses); per fold:";
        for (const auto& f : c.folds) out << " " << fmt("%.4g", f.parameters[0] / p.siPerUnit);
        out << "; interpolation error " << fmt("%.3g N/mm", interp * 1e-3) << "\n";
        if (!c.heldoutMetricsAfter.empty())
            out << "    held out: RMSE " << fmt("%.3g", c.heldoutMetricsBefore[0].rmse * 1e-3)
                << " -> " << fmt("%.3g N/mm", c.heldoutMetricsAfter[0].rmse * 1e-3) << ", largest "
                << fmt("%.3g", c.heldoutMetricsBefore[0].maxError * 1e-3) << " -> "
                << fmt("%.3g N/mm", c.heldoutMetricsAfter[0].maxError * 1e-3) << "\n";
        else
            out << "    held out: a mass off the candidate's grid\n";
    }
    for (const auto& p : w.which.confusable)
        out << "  confusable on these data: " << p.first << " and " << p.second << "\n";
    for (const auto& [pair, why] : w.identical)
        out << "  the same on a stiffness curve: " << pair.first << " and " << pair.second << " ("
            << why << ")\n";
    for (const auto& n : w.notApplicable)
        out << "  not applicable: " << n.effect << " (" << n.why << ")\n";
}

}  // namespace bagsim::app
