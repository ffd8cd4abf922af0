// bagsim diagnose: where the simulation of the seed's rig and measured data disagree, and
// which unmodelled effect of the library explains it (docs/diagnosis.md).
#include <bags/LoadTest.h>
#include <bagsim/Version.h>
#include <diagnose/Diagnosis.h>
#include <diagnose/Stiffness.h>
#include <io/DiagnosisJson.h>
#include <io/DiagnosisReport.h>
#include <io/InputError.h>
#include <io/LoadTestScenario.h>
#include <io/MeasuredData.h>
#include <io/PatientMeasuredData.h>
#include <io/Units.h>

#include <chrono>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "Commands.h"
#include "DiagnoseCurve.h"
#include "DiagnoseShared.h"
#include "Interrupt.h"
#include "PatientCoSim.h"

namespace bagsim::app {

namespace {

namespace fs = std::filesystem;

const char* kHelp =
    "usage: bagsim diagnose --measured DIR [--out DIR] [--force] [--where-only]\n"
    "           [--stop-if-within] [--candidates E1,E2,...] [--threads N] [--quiet]\n"
    "           [--curve-step MASS] [--curve-volumes N] [--cache DIR] [--mesh-check SIZE]\n"
    "\n"
    "Compares measured data of the seed's rig (docs/measured-data.md) with a simulation of the\n"
    "same protocol and says where they disagree: residuals per channel (force at the measured\n"
    "displacement, pressure as the sensor reads it, the flowmeter's mass, and a bed gauge's\n"
    "sink when the data have one) split by gas mass,\n"
    "loading or unloading and load range, each regime's share of the squared error, and the\n"
    "signatures bias, scale, lag (cross-correlation peak), hysteresis loop area and drift.\n"
    "Then, with two tests or more, which effect of the library explains the gap: each is\n"
    "calibrated (Ceres) on all tests but one and judged on the one left out, in turn; when\n"
    "the best leaves a channel beyond twice its validation uncertainty, the best two are\n"
    "fitted jointly with each other effect. The verdict names the effect, two effects\n"
    "('A + B': the pair explains at least half of what the single leaves), 'none' (the gap is\n"
    "within the validation uncertainty) or 'unexplained'. The validation uncertainty is the\n"
    "root sum square of the noise, the numerical uncertainty, a stated imperfection's spread\n"
    "and, when the manifest states them, the gas mass's and room temperature's standard\n"
    "uncertainties times their sensitivities (each simulated at +- its uncertainty).\n"
    "The numerical uncertainty is the difference from a run at half the displacement step;\n"
    "with --mesh-check, also from a run on a finer mesh (root sum square of the two).\n"
    "See docs/diagnosis.md.\n"
    "\n"
    "options:\n"
    "  --measured DIR      the measured-data folder (holds measured.yaml)\n"
    "  --out DIR           where to write diagnosis.json, residuals.csv and report.html\n"
    "                      (default: DIR/../<folder name>-diagnosis)\n"
    "  --force             replace this command's files in a folder that is not empty\n"
    "  --where-only        only where the gap lies (no calibration)\n"
    "  --stop-if-within    the rig's tests: when every channel is within twice its validation\n"
    "                      uncertainty, stop there (verdict none, no candidate fitted; by\n"
    "                      default they are fitted and ranked all the same)\n"
    "  --candidates LIST   effects to calibrate (default: the library, pressure-sensor,\n"
    "                      flowmeter-bias, gas-temperature, machine-compliance,\n"
    "                      block-friction, leakage, heat-exchange, bed-compliance,\n"
    "                      viscoelasticity, fabric-anisotropy, soft-tissue, bag-volume;\n"
    "                      load-cell-gain is kept out of it on purpose)\n"
    "  --threads N         simulations run at once (default 1)\n"
    "  --windows N         a patient's data: the time windows the folds leave out (default 3)\n"
    "  --curve-step MASS   a stiffness curve: the mass step of the model's dense curve that\n"
    "                      the gas-mass shifts re-read (default 0.125 g)\n"
    "  --curve-volumes N   a stiffness curve: bag-volume's grid over its bounds, odd, 3 to 41\n"
    "                      (default 9: every 0.0625)\n"
    "  --cache DIR         a stiffness curve: where the model's curves are kept and found\n"
    "                      again (default OUT/curve-cache)\n"
    "  --mesh-check SIZE   the tests' numerical uncertainty holds the mesh too: the\n"
    "                      protocol also on a mesh of SIZE (finer than the scenario's\n"
    "                      airbag.mesh_size, at least 5 mm), its difference added (one\n"
    "                      more simulation; the rig's tests only)\n"
    "  --quiet             print only the verdict\n"
    "\n"
    "A stiffness curve k(m) in the data (no tests needed): the model's curve at its masses\n"
    "beside it, then which effect explains the departure: the gas-mass shifts\n"
    "(flowmeter-bias, gas-temperature) re-read one dense curve of the model, bag-volume\n"
    "reads a grid of volumes, machine- and bed-compliance act in series; each fitted on all\n"
    "masses but one and judged on the one left out. The curves are cached (--cache).\n"
    "\n"
    "A patient's data (manifest protocol kind: patient-on-array) are compared with a\n"
    "co-simulation of their scenario: the mat by body region, the tilt, each bag's sensor,\n"
    "by time window; the candidates (default bag-pressure-sensor and mat-gain, those the data\n"
    "have channels for; also film-friction, gas-mass-bias, soft-tissue, each trial value a\n"
    "co-simulation) are fitted on all windows but one and judged on the one left out.\n"
    "\n"
    "exit status: 0 diagnosed, 1 a simulation failed, 2 bad input, 129/130/143 interrupted\n"
    "(SIGHUP, SIGINT, SIGTERM).\n";

struct Args {
    std::string measured, out, commandLine;
    bool force = false, whereOnly = false, quiet = false, stopIfWithin = false;
    std::vector<std::string> candidates;
    int threads = 1;
    int windows = 3;              ///< a patient's data: the time windows of the folds
    double curveStep = 0.125e-3;  ///< a stiffness curve: the dense curve's step [kg]
    int curveVolumes = 9;         ///< a stiffness curve: bag-volume's grid points
    std::string cache;            ///< a stiffness curve: the cache folder ("": OUT/curve-cache)
    std::string meshCheck;        ///< --mesh-check as given ("": the step's uncertainty only)
};

Args parseArgs(int argc, char** argv) {
    Args a;
    a.commandLine = "bagsim diagnose";
    for (int i = 0; i < argc; ++i) a.commandLine += std::string(" ") + argv[i];
    for (int i = 0; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&] { return takeOptionValue(argc, argv, i); };
        if (arg == "--measured")
            a.measured = value();
        else if (arg == "--out")
            a.out = value();
        else if (arg == "--force")
            a.force = true;
        else if (arg == "--where-only")
            a.whereOnly = true;
        else if (arg == "--stop-if-within")
            a.stopIfWithin = true;
        else if (arg == "--quiet" || arg == "-q")
            a.quiet = true;
        else if (arg == "--threads") {
            const std::string v = value();
            if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos ||
                std::stoi(v) < 1 || std::stoi(v) > 64)
                throw UsageError("--threads '" + v + "' is not valid; valid: 1 to 64");
            a.threads = std::stoi(v);
        } else if (arg == "--candidates") {
            std::istringstream is(value());
            std::string e;
            while (std::getline(is, e, ',')) a.candidates.push_back(e);
        } else if (arg == "--windows") {
            const std::string v = value();
            if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos ||
                std::stoi(v) < 2 || std::stoi(v) > 20)
                throw UsageError("--windows '" + v + "' is not valid; valid: 2 to 20");
            a.windows = std::stoi(v);
        } else if (arg == "--curve-step") {
            const std::string v = value();
            double m = 0.0;
            try {
                m = io::parseQuantity(v, io::Dimension::Mass);
            } catch (const std::exception&) {
                m = -1.0;
            }
            if (!(m >= 0.01e-3 && m <= 1e-3))
                throw UsageError("--curve-step '" + v +
                                 "' is not valid; valid: a mass with its unit from 0.01 g to 1 g "
                                 "(e.g. 0.125 g)");
            a.curveStep = m;
        } else if (arg == "--curve-volumes") {
            const std::string v = value();
            if (v.empty() || v.size() > 3 ||
                v.find_first_not_of("0123456789") != std::string::npos || std::stoi(v) < 3 ||
                std::stoi(v) > 41 || std::stoi(v) % 2 == 0)
                throw UsageError("--curve-volumes '" + v +
                                 "' is not valid; valid: an odd count from 3 to 41");
            a.curveVolumes = std::stoi(v);
        } else if (arg == "--cache") {
            a.cache = value();
        } else if (arg == "--mesh-check") {
            a.meshCheck = value();
        } else
            throw UsageError(
                "unknown option '" + arg +
                "'; valid: --measured, --out, --force, --where-only, --stop-if-within, "
                "--candidates, --threads, --windows, --curve-step, --curve-volumes, --cache, "
                "--mesh-check, --quiet, --help");
    }
    if (a.measured.empty()) throw UsageError("--measured DIR is required");
    if (a.out.empty()) {
        const fs::path m = fs::absolute(a.measured).lexically_normal();
        const fs::path dir = m.filename().empty() ? m.parent_path() : m;
        a.out = (dir.parent_path() / (dir.filename().string() + "-diagnosis")).string();
    }
    return a;
}

void printWhere(const diagnose::WhereReport& w, std::ostream& out) {
    out << "where: gap " << fmt("%.4f", w.gap) << " (" << diagnose::describeGap(w) << ")"
        << (w.withinValidation ? ", within the validation uncertainty" : "") << "\n";
    out << "  channel   RMSE        range       noise       numerical   input       gas mass    "
           "room temp.  validation  share of gap\n";
    for (const auto& c : w.channels) {
        const auto kind = diagnose::getChannelKind(c.channel);
        const double u = diagnose::getChannelUnitScale(kind);
        const std::string un = " " + diagnose::getChannelUnit(kind);
        char line[300];
        std::snprintf(
            line, sizeof line,
            "  %-8s  %-10s  %-10s  %-10s  %-10s  %-10s  %-10s  %-10s  %-10s  %s\n",
            c.channel.c_str(), (fmt("%.4g", c.rmse / u) + un).c_str(),
            (fmt("%.4g", c.range / u) + un).c_str(), (fmt("%.3g", c.noise / u) + un).c_str(),
            (fmt("%.3g", c.numerical / u) + un).c_str(), (fmt("%.3g", c.input / u) + un).c_str(),
            (fmt("%.3g", c.inputGasMass / u) + un).c_str(),
            (fmt("%.3g", c.inputTemperature / u) + un).c_str(),
            (fmt("%.3g", c.validation / u) + un).c_str(),
            c.channel == "mass" ? "(consistency only)"
                                : (fmt("%.0f", 100 * c.shareOfGap) + " %").c_str());
        out << line;
    }
    out << "  (input: a stated imperfection's spread; gas mass, room temp.: the protocol's stated "
           "standard uncertainties by their sensitivities; validation: the root sum square)\n";
    for (const auto& s : w.statedInputs)
        out << "  stated "
            << (s.input == diagnose::ProtocolInput::GasMass ? "gas mass" : "room temperature")
            << " uncertainty: " << io::formatStatedInput(s) << "\n";
    out << "  largest shares of squared error (per channel and split):\n";
    for (const auto& r : w.regimes)
        if (r.regime != "all" && r.channel != "mass" && r.share >= 0.5)
            out << "    " << r.channel << ", " << r.regime << ": " << fmt("%.0f", 100 * r.share)
                << " %\n";
    out << "  signatures per test (bias, scale, lag, loop area measured / simulated):\n";
    for (const auto& s : w.signatures) {
        if (s.channel == "mass") continue;
        const auto kind = diagnose::getChannelKind(s.channel);
        const double u = diagnose::getChannelUnitScale(kind);
        const std::string un = diagnose::getChannelUnit(kind);
        out << "    " << s.channel << " " << fmt("%.2f g", s.gasMass * 1e3) << ": bias "
            << fmt("%+.3g ", s.bias / u) << un << ", scale " << fmt("%+.3f", s.scale) << ", lag "
            << fmt("%.2f s", s.lag) << ", loop " << fmt("%.3g", s.loopAreaMeasured / u * 1e3)
            << " / " << fmt("%.3g", s.loopAreaSimulated / u * 1e3) << " " << un << " mm\n";
    }
}

void printStiffness(const diagnose::StiffnessComparison& k, std::ostream& out) {
    out << "stiffness: measured k(m) beside the simulated one (N/mm over the load range)\n"
        << "  gas mass   measured   simulated   difference   stage stated / simulated\n";
    for (const auto& p : k.points) {
        char line[200];
        std::snprintf(
            line, sizeof line, "  %-9s  %-9s  %-10s  %-11s  %s / %s%s\n",
            fmt("%.3g g", p.gasMass * 1e3).c_str(), fmt("%.3f", p.measured * 1e-3).c_str(),
            std::isfinite(p.simulated) ? fmt("%.3f", p.simulated * 1e-3).c_str() : "none",
            std::isfinite(p.simulated) ? fmt("%+.3f", (p.measured - p.simulated) * 1e-3).c_str()
                                       : "-",
            p.measuredStage ? std::to_string(p.measuredStage).c_str() : "-",
            p.simulatedStage ? std::to_string(p.simulatedStage).c_str() : "-",
            p.note.empty() ? "" : ("  (" + p.note + ")").c_str());
        out << line;
    }
    for (const auto& r : k.regimes)
        out << "  " << r.regime << ": " << r.points << (r.points == 1 ? " mass" : " masses")
            << ", RMSE " << fmt("%.3g", r.rmse * 1e-3) << " N/mm, bias (measured - simulated) "
            << fmt("%+.3g", r.bias * 1e-3) << " N/mm, " << fmt("%.0f %%", 100 * r.relative)
            << " of the measured, share " << fmt("%.0f %%", 100 * r.share) << "\n";
    out << "  scale: measured = (1 " << fmt("%+.3f", k.scale)
        << ") x simulated; least stiffness at " << fmt("%.3g g", k.leastMeasured * 1e3)
        << " measured, "
        << (std::isfinite(k.leastSimulated) ? fmt("%.3g g", k.leastSimulated * 1e3) : "none")
        << " simulated; stages agree at " << k.stagesAgreeing << " of " << k.stagesCompared
        << " masses; " << k.missing << " without a simulated stiffness\n";
}

int run(const Args& a) {
    if (io::readMeasuredKind(a.measured) != "") {
        if (!a.meshCheck.empty())
            throw UsageError(
                "--mesh-check is for the rig's tests; a patient's numerical "
                "uncertainty is its run at half the macro step");
        if (a.stopIfWithin)
            throw UsageError(
                "--stop-if-within is for the rig's tests; a patient's diagnosis "
                "fits its candidates (or use --where-only)");
        PatientDiagnoseArgs p;
        p.measured = a.measured, p.out = a.out, p.commandLine = a.commandLine;
        p.force = a.force, p.whereOnly = a.whereOnly, p.quiet = a.quiet;
        p.candidates = a.candidates, p.windows = a.windows;
        return runPatientDiagnosis(p);
    }
    for (const std::string& e : a.candidates)
        if (!diagnose::findEffect(e))
            throw UsageError("--candidates: '" + e + "' is not an effect of the library; valid: " +
                             diagnose::listEffectNames());
    const auto start = std::chrono::steady_clock::now();
    const diagnose::MeasuredData data = io::readMeasuredData(a.measured);
    io::LoadTestScenario sc = io::readMeasuredScenario(data);
    const double writtenMesh = sc.options.geometry.meshSize;  // airbag.mesh_size as read
    const double meshCheck = parseFinerMesh("--mesh-check", a.meshCheck, writtenMesh);
    if (meshCheck > 0.0 && data.tests.empty())
        throw UsageError("--mesh-check is for the rig's tests; " + a.measured +
                         " holds a stiffness curve only");
    const fs::path out(a.out);
    claimOutputFolder(out, a.force,
                      {"diagnosis.json", "residuals.csv", "report.html", "stiffness.csv"});
    if (!a.quiet)
        std::cerr << "bagsim diagnose: " << data.tests.size() << " tests"
                  << (data.stiffness.empty() ? "" : " and a stiffness curve") << " in "
                  << a.measured << " against " << data.scenarioFile << "\n";

    sc.options.solver.monitor = [](int, double, double, double) { throwIfInterrupted(); };
    prepareGeometry(sc);
    int simulations = 0;
    auto simulate = [&](const bags::LoadTestOptions& o) {
        bags::LoadTestResult r = bags::runLoadTest(o);
        for (const bags::LoadCurve& c : r.curves)
            if (c.failed)
                throw bags::NumericalError("the curve at " + io::formatQuantity(c.gasMass, "g", 3) +
                                           " stopped: " + c.failure);
        return r;
    };
    io::DiagnosisInfo info;
    info.measuredFolder = a.measured;
    info.scenarioFile = data.scenarioFile;
    info.program = std::string("bagsim ") + bagsim::kVersion;
    info.commandLine = a.commandLine;
    auto write = [&](const std::string& name, const std::string& text) {
        writeOutputFile(out, name, text);
    };
    // A measured stiffness curve: its masses in turn, let down from the largest as in the
    // seed's test, loading only. A curve that stops or gives no stiffness is a finding, not a
    // failure of the diagnosis.
    std::unique_ptr<diagnose::StiffnessComparison> stiffness;
    std::unique_ptr<diagnose::StiffnessWhich> curveWhich;
    std::string curveNotRun;
    if (!data.stiffness.empty()) {
        CurveRunOptions co;
        co.cache = a.cache.empty() ? out / "curve-cache" : fs::path(a.cache);
        co.threads = a.threads;
        co.shiftStep = a.curveStep;
        co.volumePoints = a.curveVolumes;
        co.candidates = a.candidates;
        co.quiet = a.quiet;
        int runs = 0;
        const bags::LoadTestResult model = runModelCurve(data, sc, co, runs);
        stiffness = std::make_unique<diagnose::StiffnessComparison>(
            diagnose::compareStiffness(data.stiffness, model));
        if (!a.quiet) printStiffness(*stiffness, std::cout);
        write("stiffness.csv", io::formatStiffnessCsv(*stiffness));
        if (!a.whereOnly) {
            try {
                curveWhich = std::make_unique<diagnose::StiffnessWhich>(
                    runCurveWhich(data, sc, model, *stiffness, co, runs));
                if (!a.quiet) printCurveWhich(*curveWhich, std::cout);
            } catch (const std::invalid_argument& e) {
                curveNotRun = e.what();
            }
        }
        simulations += runs;
    }
    if (data.tests.empty()) {
        info.simulations = simulations;
        info.seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        write("diagnosis.json", io::formatDiagnosisJson(info, {}, nullptr, stiffness.get(),
                                                        curveWhich.get(), curveNotRun));
        if (curveWhich)
            std::cout << "verdict: " << diagnose::describeVerdict(curveWhich->which) << " ("
                      << curveWhich->which.reason << ")\n";
        else
            std::cout << "verdict: not run ("
                      << (a.whereOnly ? std::string("--where-only") : curveNotRun) << ")\n";
        std::cout << "diagnosis in " << out.string() << "/: diagnosis.json, stiffness.csv ("
                  << simulations << (simulations == 1 ? " simulation, " : " simulations, ")
                  << fmt("%.1f", info.seconds) << " s)\n";
        return 0;
    }
    // The protocol as stated, then the runs its uncertainties need, all at once (--threads):
    // the numerical uncertainty (the same protocol at half the displacement step); the input
    // uncertainty of a stated imperfection (other bags of its population: the next kPopulation
    // imperfection seeds, as the ensemble of a run would make them); the protocol's stated
    // gas mass and room temperature, each at + and - its standard uncertainty (sensitivity
    // coefficients by central difference).
    constexpr int kPopulation = 3;
    std::vector<bags::LoadTestOptions> runs = {sc.options, sc.options};
    runs[1].displacementStep *= 0.5;
    if (meshCheck > 0.0) {  // --mesh-check: the same protocol on the finer mesh
        runs.push_back(sc.options);
        applyFinerMesh("--mesh-check", a.meshCheck, meshCheck, writtenMesh, runs.back());
    }
    const size_t firstPopulationRun = runs.size();
    if (sc.options.imperfection.amplitude > 0.0)
        for (int k = 1; k <= kPopulation; ++k) {
            runs.push_back(sc.options);
            runs.back().imperfection.seed += static_cast<std::uint64_t>(k);
        }
    const size_t firstInputRun = runs.size();
    const std::vector<diagnose::InputRun> inputRuns = diagnose::makeInputRuns(data, sc.options);
    for (const diagnose::InputRun& r : inputRuns) runs.push_back(r.options);
    if (!a.quiet)  // on the seed's bag these take minutes: say what runs before it does
        std::cout << "where: " << runs.size() << " load tests (the scenario, at half its step"
                  << (meshCheck > 0.0 ? ", on the finer mesh" : "")
                  << (firstInputRun > firstPopulationRun
                          ? ", " + std::to_string(firstInputRun - firstPopulationRun) +
                                " bags of the imperfection's population"
                          : std::string())
                  << (inputRuns.empty()
                          ? ""
                          : ", " + std::to_string(inputRuns.size()) + " for the stated inputs")
                  << "), " << a.threads << " at a time ..." << std::endl;
    std::vector<bags::LoadTestResult> results = diagnose::runLoadTests(runs, simulate, a.threads);
    simulations += static_cast<int>(runs.size());
    const bags::LoadTestResult base = std::move(results[0]);
    const bags::LoadTestResult& fine = results[1];
    const bags::LoadTestResult* finerMesh = meshCheck > 0.0 ? &results[2] : nullptr;
    const std::vector<bags::LoadTestResult> population(results.begin() + firstPopulationRun,
                                                       results.begin() + firstInputRun);
    const std::vector<bags::LoadTestResult> inputResults(results.begin() + firstInputRun,
                                                         results.end());

    std::vector<diagnose::TestComparison> tests;
    for (size_t i = 0; i < data.tests.size(); ++i) {
        diagnose::TestComparison t = diagnose::compareTest(data.tests[i], int(i), base.curves[i],
                                                           sc.rig, sc.options.loadingRate);
        const diagnose::TestComparison f = diagnose::compareTest(
            data.tests[i], int(i), fine.curves[i], sc.rig, sc.options.loadingRate);
        t.numericalUncertainty = diagnose::calcSimulatedRmsDifference(t, f);
        if (finerMesh) {  // the mesh's part beside the step's (root sum square)
            const std::vector<double> dm = diagnose::calcSimulatedRmsDifference(
                t, diagnose::compareTest(data.tests[i], int(i), finerMesh->curves[i], sc.rig,
                                         sc.options.loadingRate));
            for (size_t c = 0; c < dm.size(); ++c)
                t.numericalUncertainty[c] = std::hypot(t.numericalUncertainty[c], dm[c]);
            t.numericalUncertaintyMesh = dm;
        }
        std::vector<double> sum2(t.channels.size(), 0.0);
        for (const bags::LoadTestResult& p : population) {
            const std::vector<double> d = diagnose::calcSimulatedRmsDifference(
                t, diagnose::compareTest(data.tests[i], int(i), p.curves[i], sc.rig,
                                         sc.options.loadingRate));
            for (size_t c = 0; c < d.size(); ++c) sum2[c] += d[c] * d[c];
        }
        for (size_t c = 0; c < sum2.size(); ++c)
            t.inputUncertainty[c] =
                population.empty() ? 0.0 : std::sqrt(sum2[c] / double(population.size()));
        tests.push_back(std::move(t));
    }
    diagnose::addInputUncertainties(data, inputRuns, inputResults, sc.rig, sc.options.loadingRate,
                                    tests);
    diagnose::WhereOptions wo;
    wo.loadFrom = sc.options.stiffnessFrom;
    wo.loadTo = sc.options.stiffnessTo;
    diagnose::WhereReport where;
    try {
        where = diagnose::calcWhere(tests, wo);
    } catch (const std::domain_error& e) {  // a non-finite residual: the data's sample
        throw io::InputError(a.measured, 0, "", e.what());
    }
    where.statedInputs = diagnose::describeInputs(data);
    if (!a.quiet) printWhere(where, std::cout);

    std::unique_ptr<diagnose::WhichReport> which;
    if (!a.whereOnly && data.tests.size() >= 2 && a.stopIfWithin && where.withinValidation) {
        // The verdict is `none` whatever the candidates would do (diagnose::judgeCandidates):
        // --stop-if-within spares their fits.
        which = std::make_unique<diagnose::WhichReport>();
        which->verdict = "none";
        which->reason =
            "every channel's RMSE is within twice its validation uncertainty "
            "(sensor noise, numerical and input uncertainty); no candidate fitted "
            "(--stop-if-within)";
        which->pairStageReason =
            "not run: every channel is within twice its validation uncertainty";
        if (!a.quiet) std::cout << "which: no candidate fitted (--stop-if-within)\n";
    } else if (!a.whereOnly && data.tests.size() >= 2) {
        diagnose::CalibrationOptions co;
        co.candidates = a.candidates;
        co.threads = a.threads;
        // The which stage runs minutes to an hour: a line as each candidate and pair starts.
        const auto whichStart = std::chrono::steady_clock::now();
        if (!a.quiet)
            co.progress = [whichStart](const std::string& what, int number, int count) {
                const double s =
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - whichStart)
                        .count();
                std::cout << "which: " << number << " of " << count << ", " << what << " ("
                          << fmt("%.0f s", s) << " so far)" << std::endl;
            };
        auto counted = [&](const bags::LoadTestOptions& o) {
            bags::LoadTestOptions m = o;
            m.solver.monitor = [](int, double, double, double) { throwIfInterrupted(); };
            try {
                return simulate(m);
            } catch (const bags::NumericalError&) {
                // A signal seen inside a solve may arrive wrapped as its numerical error: the
                // calibration must stop, not take it for a trial value that cannot be solved.
                if (getInterruptSignal()) throw Interrupted(getInterruptSignal());
                throw;
            }
        };
        which = std::make_unique<diagnose::WhichReport>(diagnose::calibrateCandidates(
            data, sc.options, sc.rig, base, tests, where, counted, co));
        for (const auto& c : which->candidates) simulations += c.simulations;
        simulations += which->pairSimulations;
        if (!a.quiet) {
            std::cout << "which: candidates ranked by the shrink of the held-out gap beyond the "
                         "validation uncertainty (leave one gas mass out), less "
                      << fmt("%g", co.parameterPenalty) << " per parameter:\n";
            for (const auto& c : which->candidates) {
                const diagnose::Effect* e = diagnose::findEffect(c.effect);
                std::cout << "  " << c.effect << ": shrink " << fmt("%.1f %%", 100 * c.excessShrink)
                          << " beyond the uncertainty (" << fmt("%.4f", c.excessBefore) << " -> "
                          << fmt("%.4f", c.excessAfter) << "), " << fmt("%.1f %%", 100 * c.shrink)
                          << " of the whole gap (" << fmt("%.4f", c.heldoutBefore) << " -> "
                          << fmt("%.4f", c.heldoutAfter) << "), score " << fmt("%.3f", c.score);
                for (size_t k = 0; k < c.parameters.size(); ++k)
                    std::cout << "; " << e->parameters[k].name << " "
                              << fmt("%.4g", c.parameters[k] / e->parameters[k].siPerUnit)
                              << (std::isfinite(c.parameterStdDev[k])
                                      ? " +- " + fmt("%.2g", c.parameterStdDev[k] /
                                                                 e->parameters[k].siPerUnit)
                                      : std::string())
                              << (e->parameters[k].unit.empty() ? "" : " " + e->parameters[k].unit);
                std::cout << "\n";
            }
            if (!which->candidates.empty()) {
                // How far: the best candidate over every test when held out.
                const diagnose::CandidateResult& b = which->candidates.front();
                std::cout << "how far (" << b.effect
                          << ", every test when held out; before -> after):\n";
                for (size_t k = 0;
                     k < b.heldoutMetricsBefore.size() && k < b.heldoutMetricsAfter.size(); ++k) {
                    const auto& m0 = b.heldoutMetricsBefore[k];
                    const auto& m1 = b.heldoutMetricsAfter[k];
                    const auto kind = diagnose::getChannelKind(m0.channel);
                    const double u = diagnose::getChannelUnitScale(kind);
                    const std::string un = " " + diagnose::getChannelUnit(kind);
                    double uval = 0.0;
                    for (const auto& ch : where.channels)
                        if (ch.channel == m0.channel) uval = ch.validation;
                    std::cout << "  " << m0.channel << ": RMSE " << fmt("%.4g", m0.rmse / u)
                              << " -> " << fmt("%.4g", m1.rmse / u) << un << ", largest "
                              << fmt("%.4g", m0.maxError / u) << " -> "
                              << fmt("%.4g", m1.maxError / u) << un << ", area metric "
                              << fmt("%.4g", m0.areaMetric / u) << " -> "
                              << fmt("%.4g", m1.areaMetric / u) << un << "; validation uncertainty "
                              << fmt("%.3g", uval / u) << un << "\n";
                }
            }
            for (const auto& p : which->confusable)
                std::cout << "  confusable on these data: " << p.first << " and " << p.second
                          << "\n";
            std::cout << "pairs: " << which->pairStageReason << "\n";
            for (const auto& p : which->pairs)
                if (p.refined)
                    std::cout << "  " << p.result.effect << ": shrink "
                              << fmt("%.1f %%", 100 * p.result.excessShrink)
                              << " beyond the uncertainty, score " << fmt("%.3f", p.result.score)
                              << "; " << p.why << (p.accepted ? ": accepted" : ": not accepted")
                              << "\n";
                else
                    std::cout << "  " << p.first << " + " << p.second << ": screened (cost "
                              << fmt("%.4g", p.screenCost) << ")\n";
            for (const auto& p : which->confusablePairs)
                std::cout << "  confusable on these data: " << p.first << " and " << p.second
                          << "\n";
        }
    }

    info.simulations = simulations;
    info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write("residuals.csv", io::formatResidualsCsv(tests));
    write("report.html", io::formatDiagnosisReportHtml(info, tests, where, which.get()));
    write("diagnosis.json", io::formatDiagnosisJson(info, where, which.get(), stiffness.get(),
                                                    curveWhich.get(), curveNotRun));
    if (which)
        std::cout << "verdict: " << diagnose::describeVerdict(*which) << " (" << which->reason
                  << ")\n";
    else
        std::cout << "verdict: not run ("
                  << (a.whereOnly ? "--where-only" : "one test: no test to hold out") << ")\n";
    std::cout << "diagnosis in " << out.string()
              << "/: diagnosis.json, residuals.csv, report.html (" << simulations
              << " simulations, " << fmt("%.1f", info.seconds) << " s)\n";
    return 0;
}

}  // namespace

int runDiagnoseCommand(int argc, char** argv) {
    return runCommandMain("bagsim diagnose", kHelp, argc, argv,
                          [](int n, char** v) { return run(parseArgs(n, v)); });
}

}  // namespace bagsim::app
