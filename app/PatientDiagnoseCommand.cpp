// bagsim diagnose on a patient's measured data (docs/diagnosis.md#a-patient-on-the-array):
// the co-simulation of the data's scenario beside the mat, the tilt sensor and the bags'
// pressure sensors; where the gap lies (by channel, body region, bag, time window) and which
// effect of the patient's library explains it, judged on time windows, tests or subjects held out
// in turn.
#include <bagsim/Version.h>
#include <diagnose/PatientDiagnosis.h>
#include <io/PatientDiagnosisReport.h>
#include <io/PatientMeasuredData.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "DiagnoseShared.h"
#include "Interrupt.h"
#include "PatientCoSim.h"

namespace bagsim::app {

namespace {

namespace fs = std::filesystem;

// The time windows (of the where stage, and of the folds for one record): `n` equal parts of
// the span of the measured records.
std::vector<double> makeWindowEdges(const std::vector<diagnose::PatientTestCase>& tests, int n) {
    double lo = INFINITY, hi = -INFINITY;
    auto span = [&](const std::vector<double>& t) {
        if (t.empty()) return;
        lo = std::min(lo, t.front());
        hi = std::max(hi, t.back());
    };
    for (const diagnose::PatientTestCase& tc : tests) {
        const diagnose::PatientChannels& c = tc.measured;
        span(c.mat.time);
        span(c.tilt.time);
        for (const auto& b : c.bags) span(b.pressure.time);
    }
    std::vector<double> e;
    for (int k = 0; k <= n; ++k) e.push_back(lo + (hi - lo) * double(k) / double(n));
    e.back() = hi + 1e-9;  // the last sample inside the last window
    return e;
}

void printWhere(const diagnose::PatientComparison& c, const diagnose::WhereReport& w,
                std::ostream& out) {
    out << "where: gap " << fmt("%.4f", w.gap)
        << " (RMS over the channels of RMSE / measured range)"
        << (w.withinValidation ? ", within the validation uncertainty" : "") << "\n";
    for (const auto& ch : w.channels) {
        const diagnose::PatientChannelComparison* cc = c.find(ch.channel);
        const double u = cc ? cc->unitScale : 1.0;
        const std::string un = cc ? " " + cc->unit : "";
        out << "  " << ch.channel << ": RMSE " << fmt("%.4g", ch.rmse / u) << un << " over "
            << (cc ? cc->time.size() : 0) << " samples, range " << fmt("%.4g", ch.range / u) << un
            << ", noise " << fmt("%.3g", ch.noise / u) << un << ", numerical "
            << fmt("%.3g", ch.numerical / u) << un << ", share of gap "
            << fmt("%.0f %%", 100 * ch.shareOfGap) << "\n";
    }
    out << "  largest shares of a channel's squared error (by region, bag, time window, test, "
           "subject):\n";
    for (const auto& r : w.regimes)
        if (r.regime != "all" && r.share >= 0.25)
            out << "    " << r.channel << ", " << r.regime << ": " << fmt("%.0f %%", 100 * r.share)
                << " (bias "
                << fmt("%+.3g", r.bias / (c.find(r.channel) ? c.find(r.channel)->unitScale : 1.0))
                << ")\n";
    out << "  signatures (bias, scale, lag):\n";
    for (const auto& s : w.signatures) {
        const diagnose::PatientChannelComparison* cc = c.find(s.channel);
        const std::string part = s.part.empty() ? "" : " " + s.part;
        out << "    " << s.channel << part << ": bias "
            << fmt("%+.3g", s.bias / (cc ? cc->unitScale : 1.0)) << (cc ? " " + cc->unit : "")
            << ", scale " << fmt("%+.3f", s.scale) << ", lag " << fmt("%.3f s", s.lag) << "\n";
    }
}

}  // namespace

int runPatientDiagnosis(const PatientDiagnoseArgs& a) {
    const auto start = std::chrono::steady_clock::now();
    const diagnose::PatientMeasurement data = io::readPatientMeasuredData(a.measured);
    const io::PatientMeasuredScenario ms = io::readPatientMeasuredScenario(data);
    for (const std::string& n : a.candidates)
        if (!diagnose::findPatientEffect(n))
            throw UsageError("--candidates: '" + n +
                             "' is not an effect of the patient's library; valid: " +
                             diagnose::listPatientEffectNames());
    if (a.windows < 2 && !a.whereOnly) throw UsageError("--windows must be 2 or more (the folds)");
    const fs::path out(a.out);
    claimOutputFolder(out, a.force, {"diagnosis.json", "residuals.csv", "report.html"});
    std::error_code ec;
    fs::remove_all(out / "runs", ec);
    const fs::path runs = out / "runs";
    if (!a.quiet)
        std::cerr << "bagsim diagnose: a patient's data in " << a.measured << " against "
                  << data.scenarioFile << " (co-simulations in " << runs.string() << "/)\n";
    const diagnose::MatRegions regions = makeMatRegions(ms.scenario);
    int simulations = 0;
    auto simulate = [&](const io::ScenarioFile& f, const std::string& label) {
        if (!a.quiet) std::cerr << "  co-simulation: " << label << "\n";
        ++simulations;
        return runCoSimulation(f, (runs / label).string());
    };
    // The tests (one record: one test without a name); each test's co-simulations in
    // runs/<test>/ (one record: runs/).
    struct TestRun {
        std::string name, dir;  // dir: "" or "<test>/"
        io::ScenarioFile file;
        double gasMass = 0.0;
    };
    std::vector<TestRun> testRuns;
    std::vector<diagnose::PatientTestCase> cases;
    if (data.tests.empty()) {
        testRuns.push_back({"", "", ms.file, ms.scenario.options.layout.gasMass});
        cases.push_back({"", data.channels, {}, ms.scenario.options.layout.gasMass, "", {}});
    } else {
        for (size_t t = 0; t < data.tests.size(); ++t) {
            const io::PatientMeasuredTestScenario& ts = ms.tests[t];
            testRuns.push_back(
                {ts.name, ts.name + "/", ts.file, ts.scenario.options.layout.gasMass});
            // Each test's mat regions under its own patient (subjects differ in build).
            cases.push_back({ts.name,
                             data.tests[t].channels,
                             {},
                             ts.scenario.options.layout.gasMass,
                             data.tests[t].subject,
                             makeMatRegions(ts.scenario)});
        }
    }
    std::vector<std::string> names, subjects;
    for (const TestRun& t : testRuns) names.push_back(t.name);
    for (const diagnose::PatientTestCase& c : cases) subjects.push_back(c.subject);
    auto regionsOf = [&](size_t t) -> const diagnose::MatRegions& {
        return cases[t].regions.names.empty() ? regions : cases[t].regions;
    };
    std::vector<diagnose::PatientComparison> halfParts;
    for (size_t t = 0; t < testRuns.size(); ++t) {
        cases[t].baseline = simulate(testRuns[t].file, testRuns[t].dir + "model");
        // The numerical uncertainty: the same scenario at half the macro step.
        io::ScenarioFile halfFile = testRuns[t].file;
        halfFile.applyOverride("coupling.macro_step", formatHalfMacroStep(ms.scenario));
        const diagnose::PatientChannels half =
            simulate(halfFile, testRuns[t].dir + "half-macro-step");
        const diagnose::PatientComparison basePart =
            diagnose::comparePatient(cases[t].measured, cases[t].baseline, {}, regionsOf(t));
        halfParts.push_back(
            diagnose::comparePatient(cases[t].measured, half, {}, regionsOf(t), &basePart));
    }
    const std::vector<diagnose::PatientComparison> baseParts =
        diagnose::comparePatientTests(cases, regions);
    const diagnose::PatientComparison base =
        diagnose::joinPatientComparisons(baseParts, names, subjects);
    if (base.channels.empty())
        throw io::InputError(a.measured, 0, "",
                             "no channel of the data has a simulated counterpart");
    const diagnose::PatientComparison half =
        diagnose::joinPatientComparisons(halfParts, names, subjects);
    diagnose::PatientFolds folds;
    folds.windowEdges = makeWindowEdges(cases, std::max(2, a.windows));
    folds.tests = int(cases.size());
    folds.subjects = base.subjects;  // the reader asks for a subject in every test, and two or more
    folds.testSubject = base.testSubject;
    const std::vector<double>& edges = folds.windowEdges;
    diagnose::WhereReport where;
    try {
        where = diagnose::calcPatientWhere(
            base, diagnose::calcPatientSimulatedDifference(base, half), edges, 2.0);
    } catch (const std::domain_error& e) {  // a non-finite residual: the data's sample
        throw io::InputError(a.measured, 0, "", e.what());
    }
    if (!a.quiet) printWhere(base, where, std::cout);

    std::unique_ptr<diagnose::WhichReport> which;
    std::unique_ptr<diagnose::PatientComparison> fitted;
    if (!a.whereOnly) {
        diagnose::PatientCalibrationOptions co;
        co.candidates = a.candidates;
        which = std::make_unique<diagnose::WhichReport>(diagnose::calibratePatientCandidates(
            cases, where, regions, folds,
            [&](int t, const std::vector<std::pair<std::string, std::string>>& overrides,
                const std::string& label) {
                io::ScenarioFile f = testRuns[size_t(t)].file;
                for (const auto& [k, v] : overrides) f.applyOverride(k, v);
                return simulate(f, testRuns[size_t(t)].dir + label);
            },
            co));
        if (!which->candidates.empty()) {
            const diagnose::CandidateResult& b = which->candidates.front();
            const diagnose::Effect* e = diagnose::findPatientEffect(b.effect);
            if (!e->changesTheBag) {
                diagnose::PatientInstruments inst;
                diagnose::applyPatientInstrumentEffect(*e, b.parameters, inst);
                std::vector<diagnose::PatientComparison> parts;
                for (size_t t = 0; t < cases.size(); ++t)
                    parts.push_back(diagnose::comparePatient(cases[t].measured, cases[t].baseline,
                                                             inst, regionsOf(t), &baseParts[t]));
                fitted = std::make_unique<diagnose::PatientComparison>(
                    diagnose::joinPatientComparisons(parts, names, subjects));
            }
        }
        if (!a.quiet) {
            std::cout << "which: candidates ranked by the shrink of the held-out gap beyond the "
                         "validation uncertainty (leave one "
                      << (folds.isBySubject() ? "subject"
                          : folds.isByTest()  ? "test"
                                              : "time window")
                      << " out of " << folds.getCount() << "), less "
                      << fmt("%g", co.parameterPenalty) << " per parameter:\n";
            for (const auto& c : which->candidates) {
                const diagnose::Effect* e = diagnose::findPatientEffect(c.effect);
                std::cout << "  " << c.effect << ": shrink " << fmt("%.1f %%", 100 * c.excessShrink)
                          << " beyond the uncertainty (" << fmt("%.4f", c.excessBefore) << " -> "
                          << fmt("%.4f", c.excessAfter) << "), score " << fmt("%.3f", c.score);
                for (size_t k = 0; k < c.parameters.size(); ++k)
                    std::cout << "; " << e->parameters[k].name << " "
                              << fmt("%.4g", c.parameters[k] / e->parameters[k].siPerUnit)
                              << (e->parameters[k].unit.empty() ? "" : " " + e->parameters[k].unit);
                std::cout << "\n";
                for (size_t k = 0; k < c.heldoutMetricsBefore.size(); ++k) {
                    const auto& m0 = c.heldoutMetricsBefore[k];
                    const auto& m1 = c.heldoutMetricsAfter[k];
                    const diagnose::PatientChannelComparison* cc = base.find(m0.channel);
                    const double u = cc ? cc->unitScale : 1.0;
                    std::cout << "    held out, " << m0.channel << ": RMSE "
                              << fmt("%.4g", m0.rmse / u) << " -> " << fmt("%.4g", m1.rmse / u)
                              << " " << (cc ? cc->unit : "") << ", area metric "
                              << fmt("%.4g", m0.areaMetric / u) << " -> "
                              << fmt("%.4g", m1.areaMetric / u) << "\n";
                }
            }
            for (const auto& p : which->confusable)
                std::cout << "  confusable on these data: " << p.first << " and " << p.second
                          << "\n";
        }
    }
    io::DiagnosisInfo info;
    info.measuredFolder = a.measured;
    info.scenarioFile = data.scenarioFile;
    info.program = std::string("bagsim ") + bagsim::kVersion;
    info.commandLine = a.commandLine;
    info.simulations = simulations;
    info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    writeOutputFile(out, "residuals.csv",
                    io::formatPatientResidualsCsv(base, ms.scenario.mat.columns));
    writeOutputFile(
        out, "report.html",
        io::formatPatientDiagnosisReportHtml(info, base, where, which.get(), fitted.get()));
    writeOutputFile(out, "diagnosis.json",
                    io::formatPatientDiagnosisJson(info, base, where, which.get(), folds));
    if (which)
        std::cout << "verdict: " << diagnose::describeVerdict(*which) << " (" << which->reason
                  << ")\n";
    else
        std::cout << "verdict: not run (--where-only)\n";
    std::cout << "diagnosis in " << out.string()
              << "/: diagnosis.json, residuals.csv, report.html (" << simulations
              << " co-simulations, " << fmt("%.1f", info.seconds) << " s)\n";
    return 0;
}

}  // namespace bagsim::app
