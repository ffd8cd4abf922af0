// bagsim run: reads a scenario, runs it, streams the results into the output folder and
// prints progress and a summary. Exit status: 0 complete, 1 the run failed (numerical or I/O),
// 2 bad input (scenario, options, output folder), 3 partial (a curve stopped on a numerical
// failure, relaxed bags kept steps unrelaxed, or the coupling kept steps without a fixed
// point), 130 interrupted by SIGINT (Ctrl-C), 143 by
// SIGTERM (docs/output-layout.md).
#include <algorithm>
#include <bags/LoadTest.h>
#include <bags/Polynomial.h>
#include <bags/SeedReading.h>
#include <bagsim/Version.h>
#include <io/InputError.h>
#include <io/LoadTestScenario.h>
#include <io/MeasuredData.h>
#include <io/Results.h>
#include <io/Scenario.h>
#include <io/Units.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "Commands.h"
#include "Format.h"
#include "Interrupt.h"
#include "ArrayRun.h"
#include "PatientRun.h"

namespace bagsim::app {

namespace {

const char* kHelp =
    "usage: bagsim run SCENARIO.yaml [--out DIR] [--force] [--set KEY=VALUE]...\n"
    "       bagsim run --resume DIR\n"
    "       bagsim run SCENARIO.yaml --from-rest DIR [--out DIR2] [--set KEY=VALUE]...\n"
    "\n"
    "Runs a scenario and writes its results into an output folder. The scenario kind\n"
    "seed-load-test is the seed study's test rig: one airbag inflated to each gas mass, pressed\n"
    "by a rigid block to a peak force and released; it prints the stiffness per gas mass and the\n"
    "k(m) fit next to the seed's. The kind patient-on-support settles the scenario's patient on\n"
    "a rigid flat support and writes region_loads.csv and summary.txt (share of the weight per\n"
    "body region). The kind patient-on-array lowers the patient onto an array of airbags, lets\n"
    "him settle and runs the scenario's gas schedule (the co-simulation); it writes regions.csv,\n"
    "bags.csv, tilt.csv and the pressure mat's frames in results.h5 (docs/cosim.md).\n"
    "Scenario keys: docs/scenario-reference.md.\n"
    "\n"
    "options:\n"
    "  --out DIR          output folder (default: out/<scenario name>)\n"
    "  --force            write into DIR even if it is not empty (its result files are replaced)\n"
    "  --set KEY=VALUE    override a scenario value, e.g. --set airbag.mesh_size=\"5 mm\"\n"
    "                     (repeatable; VALUE is YAML: --set test.gas_masses=\"[3 g, 2 g]\")\n"
    "  --quiet            no progress, only the summary\n"
    "  --resume DIR       continue the interrupted patient-on-array run in DIR from its last\n"
    "                     checkpoint (output.checkpoint_every, 1 s simulated by default), with\n"
    "                     the scenario stored there; its files are cut back to the checkpoint\n"
    "                     and continued, to the same results as a run never stopped\n"
    "  --from-rest DIR    patient-on-array: start at the end of the settle from the rest state\n"
    "                     (rest-state.bin) that the run in DIR wrote when its settle ended,\n"
    "                     instead of releasing the patient again; the scenario must be that\n"
    "                     run's but for description, gas, control, pneumatics, run.duration,\n"
    "                     mat and output (docs/output-layout.md#rest-state)\n"
    "  --stop-after TIME  patient-on-array: stop as Ctrl-C would once the simulated time\n"
    "                     reaches TIME (e.g. \"0.3 s\"; for tests of --resume)\n"
    "  -h, --help         this text\n"
    "\n"
    "outputs (docs/output-layout.md): results.h5, results.xdmf (open in ParaView),\n"
    "load_displacement.csv, stiffness.csv. While the run writes, the folder holds a file\n"
    "INCOMPLETE; it is removed only when the run finishes with every curve at its peak force\n"
    "or bottomed out. Ctrl-C (SIGINT) or SIGTERM stops the run within a solver iteration and\n"
    "keeps what was computed, marked INCOMPLETE.\n"
    "\n"
    "exit status: 0 complete, 1 run failed (results so far kept, marked INCOMPLETE), 2 bad\n"
    "input, 3 partial (a curve stopped on a numerical failure or outside the model's\n"
    "envelope, a film beyond its law's fitted range, relaxed bags kept steps unrelaxed, or\n"
    "the coupling kept steps without a fixed point; all results written,\n"
    "marked INCOMPLETE), 130 interrupted by SIGINT, 143 by SIGTERM, 129 by SIGHUP.\n";

/// Bad command-line usage: exit status 2.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct Args {
    std::string scenario;
    std::string out;
    bool force = false;
    bool quiet = false;
    bool help = false;
    std::string resume;     // --resume DIR
    std::string fromRest;   // --from-rest DIR
    std::string stopAfter;  // --stop-after TIME, as written
    std::vector<std::string> sets;
    std::string commandLine;
};

Args parseArgs(int argc, char** argv) {
    Args a;
    a.commandLine = "bagsim run";
    for (int i = 0; i < argc; ++i) a.commandLine += std::string(" ") + argv[i];
    for (int i = 0; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&](const std::string& name) -> std::string {
            const std::string prefix = name + "=";
            if (arg.rfind(prefix, 0) == 0) return arg.substr(prefix.size());
            if (i + 1 >= argc) throw UsageError(name + " needs a value");
            return argv[++i];
        };
        if (arg == "-h" || arg == "--help") {
            a.help = true;
        } else if (arg == "--force") {
            a.force = true;
        } else if (arg == "--quiet" || arg == "-q") {
            a.quiet = true;
        } else if (arg == "--out" || arg.rfind("--out=", 0) == 0) {
            a.out = value("--out");
            if (a.out.empty())
                throw UsageError(
                    "--out needs a folder, not an empty path (without --out the "
                    "results go to out/NAME)");
        } else if (arg == "--set" || arg.rfind("--set=", 0) == 0) {
            const std::string set = value("--set");
            // One value a key: a second would silently win.
            auto keyOf = [](const std::string& s) {
                std::string k = s.substr(0, s.find('='));
                k.erase(0, k.find_first_not_of(" \t"));
                k.erase(k.find_last_not_of(" \t") + 1);
                return k;
            };
            for (const std::string& earlier : a.sets)
                if (set.find('=') != std::string::npos && keyOf(earlier) == keyOf(set))
                    throw UsageError("--set " + keyOf(set) + " is given twice ('" + earlier +
                                     "' and '" + set + "'); give each key once");
            a.sets.push_back(set);
        } else if (arg == "--resume" || arg.rfind("--resume=", 0) == 0) {
            a.resume = value("--resume");
        } else if (arg == "--from-rest" || arg.rfind("--from-rest=", 0) == 0) {
            a.fromRest = value("--from-rest");
        } else if (arg == "--stop-after" || arg.rfind("--stop-after=", 0) == 0) {
            a.stopAfter = value("--stop-after");
        } else if (arg.rfind("-", 0) == 0 && arg.size() > 1) {
            throw UsageError("unknown option '" + arg +
                             "'; valid: --out DIR, --force, --set KEY=VALUE, --quiet, "
                             "--resume DIR, --from-rest DIR, --stop-after TIME, --help");
        } else if (a.scenario.empty()) {
            a.scenario = arg;
        } else {
            throw UsageError("one scenario at a time ('" + a.scenario + "' and '" + arg + "')");
        }
    }
    if (!a.resume.empty()) {
        if (a.force)
            throw UsageError(
                "--resume continues the run in its folder; --force does not go with it");
        if (!a.out.empty() && std::filesystem::path(a.out).lexically_normal() !=
                                  std::filesystem::path(a.resume).lexically_normal())
            throw UsageError("--resume " + a.resume + " writes into that folder; --out " + a.out +
                             " does not go with it");
    }
    if (!a.fromRest.empty()) {
        if (!a.resume.empty())
            throw UsageError(
                "--resume continues a run with its own start; --from-rest does not go "
                "with it");
        if (!a.out.empty() && std::filesystem::path(a.out).lexically_normal() ==
                                  std::filesystem::path(a.fromRest).lexically_normal())
            throw UsageError("--out " + a.out +
                             " is the folder of the rest state; a run from "
                             "rest writes into a folder of its own");
    }
    if (!a.help && a.scenario.empty() && a.resume.empty())
        throw UsageError(
            "which scenario? e.g. bagsim run "
            "scenarios/seed-load-test.yaml");
    return a;
}

std::string formatPolynomial(const std::vector<double>& c) {
    std::string s;
    const int n = static_cast<int>(c.size()) - 1;
    for (int i = 0; i <= n; ++i) {
        const int power = n - i;
        std::string term = fmt("%.4g", std::fabs(c[i]));
        if (power >= 1) term += " m";
        if (power >= 2) term += "^" + std::to_string(power);
        s += (i == 0 ? (c[i] < 0 ? "-" : "") : (c[i] < 0 ? " - " : " + ")) + term;
    }
    return s;
}

// Progress of the run as the observer sees it, one line per finished curve.
class Progress {
  public:
    Progress(const bags::LoadTestOptions& o, bool quiet)
        : m_options(o), m_quiet(quiet), m_tty(isatty(STDERR_FILENO) != 0) {}

    void onStep(const bags::LoadStep& s, const Eigen::Matrix3Xd& x) {
        if (s.curve != m_curve) {
            if (m_curve >= 0) printCurve();
            m_curve = s.curve;
            m_steps = 0;
            m_peakForce = 0.0;
            m_peakDisplacement = 0.0;
            m_pressure0 = calcPressure(s);
            m_height0 = x.row(2).maxCoeff();
            m_curveStart = std::chrono::steady_clock::now();
            m_curveSteps.clear();
        }
        ++m_steps;
        m_curveSteps.push_back(s);
        if (s.force > m_peakForce) {
            m_peakForce = s.force;
            m_peakDisplacement = s.displacement;
        }
        if (m_tty && !m_quiet) {
            const auto now = std::chrono::steady_clock::now();
            if (std::chrono::duration<double>(now - m_lastLive).count() > 0.2) {
                m_lastLive = now;
                std::fprintf(stderr, "\r\033[K  %s  step %d %s: F = %.1f N, d = %.1f mm",
                             io::formatQuantity(m_options.gasMasses[s.curve], "g", 2).c_str(),
                             s.step, s.loading ? "loading" : "unloading", s.force,
                             s.displacement * 1e3);
                std::fflush(stderr);
            }
        }
    }

    void finish() {
        if (m_curve >= 0) printCurve();
        m_curve = -1;
    }

  private:
    static double calcPressure(const bags::LoadStep& s) {
        double sum = 0.0;
        for (double p : s.gaugePressure) sum += p;
        return s.gaugePressure.empty() ? 0.0 : sum / double(s.gaugePressure.size());
    }

    void printCurve() {
        if (m_quiet) return;
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - m_curveStart).count();
        // The library's stiffness rule, applied to the steps seen so far.
        std::string k = "k n/a";
        const double slope =
            bags::calcRangeStiffness(m_curveSteps, m_options.stiffnessFrom, m_options.stiffnessTo)
                .slope;
        if (std::isfinite(slope)) k = fmt("k = %.3f N/mm", 1e-3 * slope);
        if (m_tty) std::fprintf(stderr, "\r\033[K");
        std::fprintf(stderr,
                     "  curve %d/%zu  %s: p = %.2f kPa, top %.1f mm before loading; %d steps, "
                     "peak %.1f N at %.1f mm, %s; %.1f s\n",
                     m_curve + 1, m_options.gasMasses.size(),
                     io::formatQuantity(m_options.gasMasses[m_curve], "g", 2).c_str(),
                     m_pressure0 * 1e-3, m_height0 * 1e3, m_steps, m_peakForce,
                     m_peakDisplacement * 1e3, k.c_str(), secs);
    }

    const bags::LoadTestOptions& m_options;
    bool m_quiet;
    bool m_tty;
    int m_curve = -1;
    int m_steps = 0;
    double m_peakForce = 0.0, m_peakDisplacement = 0.0;
    double m_pressure0 = 0.0, m_height0 = 0.0;
    std::vector<bags::LoadStep> m_curveSteps;  ///< steps of the current curve
    std::chrono::steady_clock::time_point m_curveStart, m_lastLive;
};

void printSummary(const bags::LoadTestResult& r, const bags::LoadTestOptions& o) {
    std::ostream& out = std::cout;
    out << "\nstiffness over " << fmt("%g", o.stiffnessFrom) << "-" << fmt("%g", o.stiffnessTo)
        << " N (slope of force vs displacement on loading):\n";
    out << "  gas [g]  height [mm]  p0 [kPa]  V0 [mL]  steps  peak  k [N/mm]      r2  stage"
           "  stabilised\n";
    for (const bags::LoadCurve& c : r.curves) {
        char line[200];
        std::snprintf(line, sizeof line,
                      "  %7.3f  %11.1f  %8.2f  %7.0f  %5zu  %4s  %8.3f  %6.4f  %5d  %3d steps, "
                      "%.1f %% of work\n",
                      c.gasMass * 1e3, c.unloadedHeight * 1e3, c.inflatedGaugePressure * 1e-3,
                      c.inflatedVolume * 1e6, c.steps.size(), c.reachedPeak ? "yes" : "no",
                      c.stiffness * 1e-3, c.r2, c.stage, c.stabilizedSteps,
                      100.0 * c.stabilizationShare);
        out << line;
    }
    if (o.stepping == bags::AirbagSpec::Stepping::Dynamic) {
        out << "  (stabilised: none in the dynamic test; its film in time, docs/solver.md)\n";
        out << "dynamic film (the block's pace, and the largest share of its work the film's "
               "kinetic\n"
               "energy reached; limit "
            << fmt("%g", 100.0 * o.dynamic.kineticShareLimit) << " %):\n";
        for (const bags::LoadCurve& c : r.curves)
            out << "  " << io::formatQuantity(c.gasMass, "g", 2) << ": "
                << fmt("%g mm/s", c.blockSpeed * 1e3) << ", kinetic "
                << fmt("%.2f %%", 100.0 * c.kineticShare)
                << (c.quasiStatic ? "" : "  NOT QUASI-STATIC") << "\n";
    } else {
        out << "  (stabilised: steps accepted with the stabilisation springs, and the largest "
               "share of\n"
               "   the block's work they held; docs/solver.md)\n";
    }
    for (const bags::LoadCurve& c : r.curves)
        if (!c.failure.empty())
            out << "  " << io::formatQuantity(c.gasMass, "g", 2)
                << (io::isCurveFailed(c) ? " FAILED: " : " stopped early: ") << c.failure << "\n";
    for (const bags::LoadCurve& c : r.curves)
        if (c.snaps > 0)
            out << "  " << io::formatQuantity(c.gasMass, "g", 2) << ": " << c.snaps
                << (c.snaps == 1 ? " snap" : " snaps") << " stepped over ("
                << fmt("%.1f mm", c.snapTravel * 1e3)
                << " of block travel without points where no nearby equilibrium was found: a "
                   "fold snapping, or a step the solver could not take; docs/solver.md)\n";

    const std::vector<double> seed = bags::getSeedStiffnessPolynomial();
    out << "\nk(m) [N/mm], m [g]:\n";
    out << "  seed:  k = " << formatPolynomial(seed) << "\n";
    if (r.kFit.empty()) {
        int finite = 0;
        for (const bags::LoadCurve& c : r.curves) finite += std::isfinite(c.stiffness) ? 1 : 0;
        out << "  bagsim: no fit (" << finite << " curve(s) have a stiffness; a fit of order "
            << o.polynomialOrder << " needs " << o.polynomialOrder + 1 << ")\n";
        return;
    }
    out << "  bagsim: k = " << formatPolynomial(r.kFit) << "\n";
    {
        int finite = 0;
        double lo = 1e9, hi = -1e9;
        for (const bags::LoadCurve& c : r.curves)
            if (std::isfinite(c.stiffness)) {
                ++finite;
                lo = std::min(lo, c.gasMass * 1e3);
                hi = std::max(hi, c.gasMass * 1e3);
            }
        if (finite == o.polynomialOrder + 1)
            out << "  note: " << finite << " curves have a stiffness, so the order-"
                << o.polynomialOrder << " fit passes through them exactly; it is not a fit\n";
        if (lo > 1.0 + 1e-9 || hi < 3.5 - 1e-9)
            out << "  note: stiffness known from " << fmt("%.2f", lo) << " to " << fmt("%.2f", hi)
                << " g only; outside that the polynomial is an extrapolation\n";
    }
    // Both fits on a fine grid over the seed's range, 1.0-3.5 g.
    const int n = 251;
    double maxDiff = 0.0, sumSq = 0.0, maxAt = 1.0;
    for (int i = 0; i < n; ++i) {
        const double m = 1.0 + 2.5 * i / (n - 1);
        const double d = bags::evalPolynomial(r.kFit, m) - bags::evalPolynomial(seed, m);
        sumSq += d * d;
        if (std::fabs(d) > std::fabs(maxDiff)) {
            maxDiff = d;
            maxAt = m;
        }
    }
    out << "  m [g]   bagsim   seed   difference\n";
    for (double m = 1.0; m <= 3.5 + 1e-9; m += 0.5) {
        const double kb = bags::evalPolynomial(r.kFit, m), ks = bags::evalPolynomial(seed, m);
        char line[96];
        std::snprintf(line, sizeof line, "  %5.2f  %7.3f  %5.3f  %+8.3f\n", m, kb, ks, kb - ks);
        out << line;
    }
    out << "  difference bagsim - seed over 1.0-3.5 g: max |d| = "
        << fmt("%.3f", std::fabs(maxDiff)) << " N/mm (" << fmt("%+.3f", maxDiff) << " at "
        << fmt("%.2f", maxAt) << " g), RMS " << fmt("%.3f", std::sqrt(sumSq / n)) << " N/mm\n";
}

}  // namespace

// The first line where two texts differ, as "line N: 'a' here, 'b' there".
std::string describeFirstDifference(const std::string& here, const std::string& there) {
    std::istringstream a(here), b(there);
    std::string la, lb;
    for (int line = 1;; ++line) {
        const bool ha = bool(std::getline(a, la)), hb = bool(std::getline(b, lb));
        if (!ha && !hb) return "they differ in their line ends";
        if (!ha) la = "(end of file)";
        if (!hb) lb = "(end of file)";
        if (!ha || !hb || la != lb)
            return "line " + std::to_string(line) + ": '" + la.substr(0, 80) + "' given, '" +
                   lb.substr(0, 80) + "' in the checkpoint";
    }
}

std::string joinOverrides(const std::vector<std::string>& sets) {
    if (sets.empty()) return "none";
    std::string s;
    for (const std::string& o : sets) s += (s.empty() ? "" : ", ") + std::string("--set ") + o;
    return s;
}

// Reads a checkpoint or rest-state file (`magic`, length, hash, then a checkpoint header and
// the state), checking all of it before anything is touched: into *payload the data after
// the hash, *header and *scenario (the stored scenario with its overrides). False with the
// reason in *why. `what` names the file's kind, `cannot` what follows from a bad one, `older`
// what to do with another version's.
bool readStateFile(const std::filesystem::path& path, const std::string& magic,
                   const std::string& what, const std::string& cannot, const std::string& older,
                   std::string* payload, CheckpointHeader* header, io::ScenarioFile* scenario,
                   std::string* why) {
    std::string data;
    {
        std::ifstream in(path, std::ios::binary);
        std::ostringstream s;
        s << in.rdbuf();
        data = s.str();
    }
    if (data.compare(0, magic.size(), magic) != 0) {
        *why = path.string() + " is not a bagsim " + what + " (or of another format)";
        return false;
    }
    std::uint64_t length = 0, hash = 0;
    if (data.size() >= magic.size() + 16) {
        bags::StateReader head(data.substr(magic.size(), 16));
        length = head.pod<std::uint64_t>();
        hash = head.pod<std::uint64_t>();
    }
    const size_t have = data.size() < magic.size() + 16 ? 0 : data.size() - magic.size() - 16;
    if (data.size() < magic.size() + 16 || have != length) {
        *why = path.string() + " is cut short (" + std::to_string(have) + " of " +
               std::to_string(length) + " bytes of state); " + cannot;
        return false;
    }
    *payload = data.substr(magic.size() + 16);
    bags::StateReader reader(*payload);
    try {
        *header = readCheckpointHeader(reader);
    } catch (const bags::StateError& e) {
        *why = path.string() + ": " + e.what();
        return false;
    }
    if (header->version != bagsim::kVersion) {
        *why = "its " + what + " was written by bagsim " + header->version + ", this is bagsim " +
               bagsim::kVersion + "; " + older + " " + header->version +
               ", or run the scenario again";
        return false;
    }
    if (calcCheckpointHash(*payload) != hash) {
        *why = path.string() + " is damaged (its data do not match their checksum); " + cannot;
        return false;
    }
    try {
        *scenario = io::ScenarioFile::parse(header->scenarioText, header->scenarioFile);
        for (const std::string& o : header->overrides) scenario->applyOverride(o);
        if (io::readScenarioKind(*scenario) != "patient-on-array") {
            *why = "its " + what + " is not of a patient-on-array run";
            return false;
        }
    } catch (const io::InputError& e) {
        *why = "the scenario stored in its " + what + ": " + e.what();
        return false;
    }
    return true;
}

// bagsim run --resume DIR: the checkpoint's scenario, checked against what was given.
int runResume(const Args& args, const std::string& stopAfterText) {
    const std::filesystem::path dir(args.resume);
    const std::filesystem::path cp = dir / io::kCheckpointFile;
    auto refuse = [&](const std::string& why) {
        std::cerr << "bagsim: error: cannot resume " << dir.string() << ": " << why << "\n";
        return 2;
    };
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        return refuse("no such folder; --resume takes the output folder of an interrupted run");
    const bool incomplete = std::filesystem::exists(dir / io::OutputDir::kMarkerName, ec);
    if (!std::filesystem::exists(cp, ec)) {
        if (!incomplete && std::filesystem::exists(dir / io::kResultsH5, ec))
            return refuse("the run there finished (no INCOMPLETE marker); nothing to resume");
        return refuse("it holds no checkpoint (" + std::string(io::kCheckpointFile) +
                      "): only patient-on-array runs write one, every output.checkpoint_every of "
                      "simulated time (1 s by default, 0 s: none); a run stopped before its first "
                      "checkpoint must be run again");
    }
    if (!incomplete)
        return refuse("the run there finished (no INCOMPLETE marker); nothing to resume");
    std::string payload, why;
    CheckpointHeader header;
    io::ScenarioFile file;
    if (!readStateFile(cp, kCheckpointMagic, "checkpoint", "its run cannot be resumed",
                       "resume it with bagsim", &payload, &header, &file, &why))
        return refuse(why);
    // The checkpoint must be this folder's run: its scenario and overrides are the ones the
    // folder's results.h5 records (a checkpoint copied from another run of the same scenario
    // would continue that run into these files).
    try {
        const io::RunInfo folder = io::readRunInfo(dir.string());
        if (folder.scenarioText != header.scenarioText)
            return refuse(
                "its checkpoint was written by another run than the one whose results "
                "are there (the scenario differs: " +
                describeFirstDifference(folder.scenarioText, header.scenarioText) +
                "); the folder is left as it was");
        if (folder.overrides != header.overrides)
            return refuse(
                "its checkpoint was written by another run than the one whose results "
                "are there (overrides " +
                joinOverrides(header.overrides) + " in the checkpoint, " +
                joinOverrides(folder.overrides) + " in results.h5); the folder is left as it was");
    } catch (const std::exception& e) {
        return refuse(std::string("its results.h5 cannot be read (") + e.what() +
                      "), so the checkpoint cannot be checked against the run there; the folder "
                      "is left as it was");
    }
    bags::StateReader reader(payload);
    readCheckpointHeader(reader);  // read above; the model's state follows
    if (!args.scenario.empty()) {
        // A scenario given with --resume must be the one the run was started with.
        io::ScenarioFile given;
        try {
            given = io::ScenarioFile::load(args.scenario);
        } catch (const io::InputError& e) {
            std::cerr << "bagsim: error: " << e.what() << "\n";
            return 2;
        }
        if (given.getText() != header.scenarioText)
            return refuse(args.scenario + " is not the scenario the run was started with (" +
                          describeFirstDifference(given.getText(), header.scenarioText) +
                          "); --resume continues that run with its own scenario (give the "
                          "folder alone), or run " +
                          args.scenario + " into a new folder");
    }
    if ((!args.scenario.empty() || !args.sets.empty()) && args.sets != header.overrides)
        return refuse("the overrides differ from the run's (" + joinOverrides(args.sets) +
                      " given, " + joinOverrides(header.overrides) +
                      " in the checkpoint); give the folder alone");
    ArrayRunControl control;
    control.quiet = args.quiet;
    control.commandLine = args.commandLine;
    control.resume = &reader;
    control.resumeModel = header.model;
    if (!stopAfterText.empty())
        control.stopAfter = io::parseQuantity(stopAfterText, io::Dimension::Time);
    if (!args.quiet)
        std::cerr << "bagsim: resuming " << dir.string() << " at " << header.time
                  << " s (its last checkpoint) with its scenario " << header.scenarioFile
                  << (header.overrides.empty() ? "" : " and " + joinOverrides(header.overrides))
                  << "\n";
    return runPatientOnArray(file, dir.string(), control);
}

// bagsim run SCENARIO --from-rest DIR: the rest state in DIR, checked against the scenario.
int runFromRest(const Args& args, const io::ScenarioFile& file, ArrayRunControl control) {
    const std::filesystem::path dir(args.fromRest);
    const std::filesystem::path path = dir / io::kRestStateFile;
    auto refuse = [&](const std::string& why) {
        std::cerr << "bagsim: error: cannot start from the rest state in " << dir.string() << ": "
                  << why << "\n";
        return 2;
    };
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        return refuse(
            "no such folder; --from-rest takes the output folder of a patient-on-array "
            "run whose settle ended");
    if (!std::filesystem::exists(path, ec))
        return refuse("it holds no rest state (" + std::string(io::kRestStateFile) +
                      "): a patient-on-array run writes one when its settle ends (run.settle_time "
                      "> 0); a run stopped before that has none");
    std::string payload, why;
    CheckpointHeader header;
    io::ScenarioFile rest;
    if (!readStateFile(path, kRestStateMagic, "rest state", "it cannot be started from",
                       "start from it with bagsim", &payload, &header, &rest, &why))
        return refuse(why);
    const std::string diff = describeRestDifference(file, rest);
    if (!diff.empty())
        return refuse(args.scenario + " is not the scenario of the run that wrote it (" + diff +
                      "); only description, gas, control, pneumatics, run.duration, mat and "
                      "output may differ");
    bags::StateReader reader(payload);
    readCheckpointHeader(reader);  // read above; the model's state follows
    control.fromRest = &reader;
    control.fromRestDir = dir.string();
    control.fromRestModel = header.model;
    return runPatientOnArray(file, args.out, control);
}

int runRunCommand(int argc, char** argv) {
    Args args;
    try {
        args = parseArgs(argc, argv);
    } catch (const UsageError& e) {
        std::cerr << "bagsim run: " << e.what() << " (see bagsim run --help)\n";
        return 2;
    }
    if (args.help) {
        std::cout << kHelp;
        return 0;
    }

    // SIGINT and SIGTERM from here on only set a flag that the runs check where they can stop
    // and keep their results.
    const InterruptGuard interruptGuard;

    double stopAfter = -1.0;
    if (!args.stopAfter.empty()) {
        try {
            stopAfter = io::parseQuantity(args.stopAfter, io::Dimension::Time);
        } catch (const std::exception& e) {
            std::cerr << "bagsim run: --stop-after '" << args.stopAfter << "': " << e.what()
                      << "; valid: a simulated time, e.g. \"0.3 s\" (see bagsim run --help)\n";
            return 2;
        }
        if (!(stopAfter >= 0.0)) {
            std::cerr << "bagsim run: --stop-after '" << args.stopAfter
                      << "': valid: a simulated time >= 0 s\n";
            return 2;
        }
    }
    if (!args.resume.empty()) return runResume(args, args.stopAfter);

    // Input: everything that can be wrong with the scenario is found before any output exists.
    io::ScenarioFile file;
    io::LoadTestScenario sc;
    std::filesystem::path outPath;
    std::unique_ptr<io::OutputDir> outDir;
    try {
        file = io::ScenarioFile::load(args.scenario);
        for (const std::string& s : args.sets) file.applyOverride(s);
        const std::string kind = io::readScenarioKind(file);
        if (!args.fromRest.empty() && kind != "patient-on-array")
            throw io::InputError(args.scenario, 0, "kind",
                                 "--from-rest is for patient-on-array runs only");
        if (stopAfter >= 0.0 && kind != "patient-on-array")
            throw io::InputError(args.scenario, 0, "kind",
                                 "--stop-after is for patient-on-array runs only");
        if (kind == "patient-on-support")
            return runPatientOnSupport(file, args.out, args.force, args.quiet);
        if (kind == "patient-on-array") {
            ArrayRunControl control;
            control.force = args.force;
            control.quiet = args.quiet;
            control.commandLine = args.commandLine;
            control.stopAfter = stopAfter;
            if (!args.fromRest.empty()) return runFromRest(args, file, control);
            return runPatientOnArray(file, args.out, control);
        }
        sc = io::readLoadTestScenario(file);
        outPath = args.out.empty() ? std::filesystem::path("out") / sc.name
                                   : std::filesystem::path(args.out);
        outDir = std::make_unique<io::OutputDir>(outPath, args.force);
    } catch (const io::InputError& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    }

    bags::LoadTestOptions& o = sc.options;
    // Ctrl-C is noticed within one Newton iteration, not only between load steps (inflating
    // and letting gas out take many iterations before the first step of a curve).
    o.solver.monitor = [](int, double, double, double) { throwIfInterrupted(); };
    if (!args.quiet) {
        std::cerr << "bagsim " << bagsim::kVersion << ": " << args.scenario << " (" << sc.name
                  << ")\n"
                  << "  airbag " << io::formatSignificant(o.geometry.longSide, "mm") << " x "
                  << io::formatSignificant(o.geometry.width, "mm") << ", height "
                  << io::formatSignificant(o.geometry.height, "mm") << ", mesh "
                  << io::formatSignificant(o.geometry.meshSize, "mm") << " ("
                  << bags::getMeshPatternName(o.geometry.pattern) << "); " << o.material->getName()
                  << " membrane " << io::formatSignificant(o.thickness, "mm") << "\n"
                  << "  " << o.gasMasses.size() << " gas masses from "
                  << io::formatQuantity(o.gasMasses.front(), "g", 2) << " to "
                  << io::formatQuantity(o.gasMasses.back(), "g", 2) << "; block "
                  << io::formatSignificant(o.blockSize, "mm") << " at "
                  << io::formatSignificant(o.loadingRate, "mm/min") << " to "
                  << io::formatSignificant(o.peakForce, "N") << "\n"
                  << "  writing to " << outPath.string() << "/ (Ctrl-C stops and keeps what "
                  << "was computed)\n";
    }

    io::RunInfo info{args.scenario, file.getText(), file.getOverrides(), args.commandLine};
    io::LoadTestWriter::Options wo;
    wo.frameEvery = sc.output.frameEvery;
    std::unique_ptr<io::LoadTestWriter> writer;
    try {
        writer = std::make_unique<io::LoadTestWriter>(*outDir, info, o, wo);
    } catch (const std::exception& e) {
        std::cerr << "bagsim: error: cannot write the results: " << e.what() << "\n";
        outDir->setStatus("failed", e.what());
        return 1;
    }

    Progress progress(o, args.quiet);
    int lastCurve = 0, lastStep = -1;
    auto observer = [&](const bags::LoadStep& s, const bags::Mesh& mesh,
                        const Eigen::Matrix3Xd& x) {
        writer->addStep(s, mesh, x);
        progress.onStep(s, x);
        lastCurve = s.curve;
        lastStep = s.step;
        throwIfInterrupted();
    };

    bags::LoadTestResult result;
    std::string status;
    auto where = [&] {
        return lastStep < 0 ? std::string("before the first step")
                            : "after step " + std::to_string(lastStep) + " of curve " +
                                  std::to_string(lastCurve + 1) + " (" +
                                  io::formatQuantity(o.gasMasses[lastCurve], "g", 2) + ")";
    };
    auto stopInterrupted = [&](int signal) {
        progress.finish();
        const std::string msg = Interrupted(signal).what() + std::string(" ") + where();
        writer->fail("interrupted", msg);
        std::cerr << "bagsim: " << msg << "; partial results kept in " << outPath.string()
                  << "/ (marked INCOMPLETE)\n";
        return getInterruptExitCode(signal);
    };
    try {
        if (sc.fillMass > 0.0 || sc.volumeChange != 0.0) {
            // airbag.fill_mass: the sizes as written are scaled until that mass just fills the
            // inflated bag (a few inflations; docs/geometry.md); airbag.volume_change then
            // scales the bag's volume (a similar bag). The sizes used are printed.
            const double fillMass = sc.fillMass, volumeChange = sc.volumeChange;
            if (!args.quiet && fillMass > 0.0)
                std::cerr << "  sizing the airbag (" << bags::getFillScalingName(sc.fillScaling)
                          << " scale) to a fill mass of " << io::formatQuantity(fillMass, "g", 3)
                          << "\n";
            const bags::FillScaleResult fs = io::applyBagSizing(sc);  // o is sc.options
            if (fillMass > 0.0)
                std::cout << "airbag sized to a fill mass of "
                          << io::formatQuantity(fillMass, "g", 3) << " ("
                          << bags::getFillScalingName(sc.fillScaling) << " scale "
                          << fmt("%.4f", fs.scale) << ", measured "
                          << io::formatQuantity(fs.measurement.fillMass, "g", 3) << ")";
            else
                std::cout << "airbag as written";
            if (volumeChange != 0.0)
                std::cout << ", volume changed by " << fmt("%+.4g", volumeChange * 100.0)
                          << " % (every size and the mesh size times "
                          << fmt("%.4f", std::cbrt(1.0 + volumeChange)) << ")";
            const bags::DoubleWedgeParams g = o.getBagGeometry();
            std::cout << ": long side " << fmt("%.1f mm", g.longSide * 1e3) << ", short side "
                      << fmt("%.1f mm", g.shortSide * 1e3) << ", width "
                      << fmt("%.1f mm", g.width * 1e3) << ", height "
                      << fmt("%.1f mm", g.height * 1e3) << ", mesh size "
                      << fmt("%.2f mm", g.meshSize * 1e3) << "\n";
        }
        result = bags::runLoadTest(o, observer);
        progress.finish();
        if (!sc.rig.isNone()) {
            // The rig section: what the instruments read of the curves (docs/scenario-reference.md#rig).
            std::ofstream rig(outDir->getFile(io::kRigReadingsCsv));
            rig << io::formatRigReadingsCsv(result, sc.rig, o.loadingRate);
            if (!rig.flush())
                throw std::runtime_error("cannot write " +
                                         outDir->getFile(io::kRigReadingsCsv).string());
        }
        status = writer->finish(result);
    } catch (const Interrupted& e) {
        return stopInterrupted(e.signal);
    } catch (const bags::NumericalError& e) {
        // A signal seen by a solve the library wraps (a bag of an ensemble run in a thread)
        // arrives as its error: still an interrupt.
        if (getInterruptSignal()) return stopInterrupted(getInterruptSignal());
        progress.finish();
        std::string msg = std::string("numerical failure: ") + e.what();
        if (e.getTime() >= 0) msg += fmt("; time %.4g s", e.getTime());
        if (e.getStep() >= 0) msg += "; step " + std::to_string(e.getStep());
        if (e.getElement() >= 0) msg += "; element " + std::to_string(e.getElement());
        msg += " (" + where() + ")";
        writer->fail("failed", msg);
        std::cerr << "bagsim: run failed: " << msg << "\n  partial results kept in "
                  << outPath.string() << "/ (marked INCOMPLETE)\n";
        return 1;
    } catch (const std::exception& e) {
        if (getInterruptSignal()) return stopInterrupted(getInterruptSignal());
        progress.finish();
        const std::string msg = std::string(e.what()) + " (" + where() + ")";
        writer->fail("failed", msg);
        std::cerr << "bagsim: run failed: " << msg << "\n  partial results kept in "
                  << outPath.string() << "/ (marked INCOMPLETE)\n";
        return 1;
    }

    printSummary(result, o);
    const std::string dir = outPath.string();
    std::cout
        << "\nsolved in " << fmt("%.1f", result.seconds) << " s; " << writer->getNumSteps()
        << " steps, " << writer->getNumFrames() << " frames saved\n"
        << "results in " << dir << "/:\n"
        << "  " << io::kResultsH5 << "             all curves, mesh and frames "
        << "(docs/output-layout.md)\n"
        << "  " << io::kResultsXdmf << "           open in ParaView: the deforming membrane\n"
        << "  " << io::kLoadDisplacementCsv << "  gas_mass_g,displacement_mm,force_N,"
        << "pressure_kPa,branch\n"
        << "  " << io::kStiffnessCsv
        << "          gas_mass_g,stiffness_N_per_mm,k_min_N_per_mm,k_max_N_per_mm,r2,stage,end\n";
    if (!sc.rig.isNone())
        std::cout << "  " << io::kRigReadingsCsv
                  << "       the instruments' readings with the scenario's rig effects\n";
    if (std::filesystem::exists(outPath /
                                io::kKOfMYaml))  // written by finish() when it has a branch
        std::cout << "  " << io::kKOfMYaml
                  << "            k(m) and its inverse for a target-mass controller\n";
    if (status == "partial") {
        // Every gas mass was run, but a curve's branch ends where a step could not be solved:
        // its stiffness and the k(m) fit may rest on part of a curve.
        int failed = 0;
        for (const bags::LoadCurve& c : result.curves) failed += io::isCurveFailed(c) ? 1 : 0;
        std::cerr << "bagsim: run partial: " << failed << " of " << result.curves.size()
                  << " curves stopped on a numerical failure or outside the model's envelope "
                     "(listed as FAILED above); results kept in "
                  << dir << "/ (marked INCOMPLETE, status partial)\n";
        return 3;
    }
    return 0;
}

}  // namespace bagsim::app
