// Benchmark of the patient on the airbag array (issue 10, Speed): a patient-on-array scenario
// run as `bagsim run` runs it (the same reader, model and time loop, no output files), timed
// per window of simulated time, with where the wall time went. Not a test: run by hand, see
// docs/performance.md.
//
//   build/bin/bench_cosim SCENARIO.yaml [--set KEY=VALUE ...] [--window S] [--bags N]
//                         [--warm-start 0|1] [--trace 1]
//
// --set takes the scenario keys as `bagsim run` does (short runs: run.settle_time,
// run.duration; scaling: bag.mesh_size, coupling.macro_step, coupling.threads, array.columns,
// bag.self_contact). --window is the simulated time per printed row (default 0.1 s);
// --bags N prints the N dearest bags (default 5); --warm-start 0|1 sets
// bags::AirbagSpec::warmStart (not a scenario key); --trace 1 prints every macro step. The settle is 0 to run.settle_time, the
// turn (the scenario's gas commands) from there to the end.
#include <cosim/ArrayReadings.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

// CPU time of the process, every thread [s].
double cpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::string loadAverage() {
    std::ifstream f("/proc/loadavg");
    std::string a, b, c;
    f >> a >> b >> c;
    return a + " " + b + " " + c;
}

// What a stretch of the run cost, from the coupling's profile and the wall clock.
struct Window {
    double t0 = 0.0, t1 = 0.0, wall = 0.0, cpu = 0.0;
    cosim::CouplingProfile p;
};

// The difference of two cumulative profiles (b after a).
cosim::CouplingProfile minus(const cosim::CouplingProfile& b, const cosim::CouplingProfile& a) {
    cosim::CouplingProfile d = b;
    d.steps -= a.steps;
    d.passes -= a.passes;
    d.bodySeconds -= a.bodySeconds;
    d.bagsSeconds -= a.bagsSeconds;
    d.bagBusySeconds -= a.bagBusySeconds;
    d.tangentSeconds -= a.tangentSeconds;
    d.advances -= a.advances;
    d.tangentRefreshes -= a.tangentRefreshes;
    d.skipped -= a.skipped;
    d.idleAdvances -= a.idleAdvances;
    d.solverIterations -= a.solverIterations;
    for (size_t i = 0; i < a.participantSeconds.size() && i < d.participantSeconds.size(); ++i) {
        d.participantSeconds[i] -= a.participantSeconds[i];
        d.participantIterations[i] -= a.participantIterations[i];
    }
    return d;
}

void printHeader() {
    std::printf("%-13s %8s %9s %8s %6s %7s %7s %6s %6s %6s %6s %6s %6s %6s %6s %6s %8s %7s %7s\n",
                "window [s]", "wall [s]", "wall/sim", "cpu/sim", "steps", "passes", "N/step",
                "body%", "bags%", "tang%", "T/step", "rest%", "wait%", "skip%", "idle%", "N/adv",
                "F/W-1 %", "pelvis", "thorax");
}

// N/step: the bags' Newton iterations per macro step (all bags, all passes); wait%: share of the threads' time in the bags' sections spent waiting for another thread;
// skip%: share of the bags' steps skipped (coupling.skip_travel); idle%: share of the bag
// advances that took no Newton iteration (untouched, or already in balance); N/adv: Newton iterations per
// advance that solved; tang%: share of the threads' time in the tangents; T/step: bags
// whose tangents were computed per step.
void printRow(const char* label, const Window& w, double force, double weight, double pelvis,
              double thorax) {
    const cosim::CouplingProfile& p = w.p;
    const double sim = w.t1 - w.t0;
    const double rest = w.wall - p.bodySeconds - p.bagsSeconds;
    const double threadTime = p.threads * p.bagsSeconds;
    const long solved = p.advances - p.idleAdvances;
    std::printf(
        "%-13s %8.2f %9.1f %8.1f %6d %7.2f %7.1f %6.1f %6.1f %6.1f %6.1f %6.1f %6.1f %6.1f %6.1f "
        "%6.2f %+8.3f %+7.2f "
        "%+7.2f\n",
        label, w.wall, sim > 0 ? w.wall / sim : 0.0, sim > 0 ? w.cpu / sim : 0.0, p.steps,
        p.steps ? double(p.passes) / p.steps : 0.0,
        p.steps ? double(p.solverIterations) / p.steps : 0.0, 100.0 * p.bodySeconds / w.wall,
        100.0 * p.bagsSeconds / w.wall, 100.0 * p.tangentSeconds / std::max(1e-12, threadTime),
        p.steps ? double(p.tangentRefreshes) / p.steps : 0.0, 100.0 * rest / w.wall,
        threadTime > 0 ? 100.0 * (threadTime - p.bagBusySeconds) / threadTime : 0.0,
        p.advances + p.skipped ? 100.0 * p.skipped / (p.advances + p.skipped) : 0.0,
        p.advances ? 100.0 * p.idleAdvances / p.advances : 0.0,
        solved ? double(p.solverIterations) / solved : 0.0, 100.0 * (force - weight) / weight,
        pelvis * kDeg, thorax * kDeg);
    std::fflush(stdout);
}

int usage() {
    std::fprintf(stderr,
                 "usage: bench_cosim SCENARIO.yaml [--set KEY=VALUE ...] [--window S] "
                 "[--bags N] [--warm-start 0|1] [--trace 1]\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) return usage();
    std::string path;
    std::vector<std::string> sets;
    double window = 0.1;
    int topBags = 5;
    int warmStart = -1;  // -1: as bags::AirbagSpec has it
    bool trace = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--set" && i + 1 < argc) {
            sets.push_back(argv[++i]);
        } else if (a == "--window" && i + 1 < argc) {
            window = std::atof(argv[++i]);
        } else if (a == "--warm-start" && i + 1 < argc) {
            warmStart = std::atoi(argv[++i]);
        } else if (a == "--trace" && i + 1 < argc) {
            trace = std::atoi(argv[++i]) != 0;
        } else if (a == "--bags" && i + 1 < argc) {
            topBags = std::atoi(argv[++i]);
        } else if (a.rfind("--", 0) == 0 || !path.empty()) {
            return usage();
        } else {
            path = a;
        }
    }
    if (path.empty() || !(window > 0.0)) return usage();

    io::PatientOnArrayScenario sc;
    try {
        io::ScenarioFile file = io::ScenarioFile::load(path);
        for (const std::string& s : sets) file.applyOverride(s);
        sc = io::readPatientOnArrayScenario(file);
        if (warmStart >= 0) sc.options.bag.warmStart = warmStart != 0;
    } catch (const io::InputError& e) {
        std::fprintf(stderr, "bench_cosim: %s\n", e.what());
        return 2;
    }
    // This loop is a copy of bagsim run's without the pneumatic network and its controller:
    // timing such a scenario here would leave out the flows between its bags (which, with the
    // films' friction, cost 4 times the rest on the clinical turns: docs/performance.md).
    if (sc.hasPneumatics) {
        std::fprintf(stderr,
                     "bench_cosim: %s has a pneumatics section, which this bench does not run "
                     "(its bags' flows and controller would be left out of the figures); time it "
                     "with bagsim run (summary.txt gives the wall-clock), or remove the "
                     "pneumatics and control sections\n",
                     path.c_str());
        return 2;
    }
    const cosim::PatientOnArrayOptions& o = sc.options;
    std::printf("bench_cosim %s", path.c_str());
    for (const std::string& s : sets) std::printf(" --set %s", s.c_str());
    std::printf(
        "\n  %d x %d bags, mesh %.0f mm, self-contact %s, warm start %s, %s/%s, macro step %.1f ms,"
        " threads %d;"
        " settle %g s, turn %g s\n  load average at start: %s\n",
        o.layout.rows, o.layout.columns, o.bag.geometry.meshSize * 1e3,
        o.bag.selfContact ? "on" : "off", o.bag.warmStart ? "on" : "off",
        cosim::toString(o.coupling.scheme).c_str(),
        cosim::toString(o.coupling.acceleration).c_str(), o.coupling.macroStep * 1e3,
        o.coupling.threads, sc.settleTime, sc.duration, loadAverage().c_str());
    if (o.coupling.adaptive)
        std::printf(
            "  adaptive macro step: %.2f to %.1f ms, accuracy %g x the tolerance, %d passes aimed "
            "at\n",
            o.coupling.minMacroStep * 1e3, o.coupling.maxMacroStep * 1e3, o.coupling.stepAccuracy,
            o.coupling.targetPasses);

    const double tBuild = now();
    cosim::PatientOnArray poa(sc.patient, sc.options);
    const double buildWall = now() - tBuild;
    const int np = int(poa.getBagIndices().size());
    int nodes = 0;
    for (int i = 0; i < np; ++i) nodes += int(poa.getBag(i).getPressurePoints().cols());
    std::printf("  built in %.2f s: %d bags under him (%d nodes each on average), %zu pairs\n",
                buildWall, np, np ? nodes / np : 0, poa.getPairs().size());
    std::vector<cosim::Bag*> bags(size_t(o.layout.rows) * o.layout.columns, nullptr);
    for (int i = 0; i < np; ++i) bags[poa.getBagIndices()[i]] = &poa.updBag(i);

    cosim::Coupling& coupling = poa.updCoupling();
    coupling.resetProfile();
    const double end = sc.getEndTime();
    const double weight = poa.getWeight();
    printHeader();
    Window phase[2];  // settle, turn
    phase[0].t0 = 0.0;
    phase[1].t0 = sc.settleTime;
    Window current;
    cosim::CouplingProfile atWindow = coupling.getProfile(), atPhase = atWindow;
    double wallWindow = now(), wallPhase = wallWindow;
    double cpuWindow = cpuSeconds(), cpuPhase = cpuWindow;
    int ph = 0;
    auto tilt = [&](body::Segment s) { return cosim::calcSegmentTilt(poa, s); };
    auto close = [&](Window& w, double t0, double wallStart, double cpuStart,
                     const cosim::CouplingProfile& at) {
        w.t0 = t0;
        w.cpu = cpuSeconds() - cpuStart;
        w.t1 = poa.getTime();
        w.wall = now() - wallStart;
        w.p = minus(coupling.getProfile(), at);
    };
    double windowStart = 0.0;
    int redone = 0, cuts = 0;
    double smallest = INFINITY, largest = 0.0;
    try {
        while (poa.getTime() < end - 1e-9) {
            const double t = poa.getTime() + 1e-9;
            sc.gas.apply(t, bags);
            // As bagsim run steps: ended early at a gas command's start, the settle's end and
            // the end (not at output times: bench_cosim writes none).
            double limit = std::min(end, sc.gas.findNextChange(t));
            if (t < sc.settleTime) limit = std::min(limit, sc.settleTime);
            const cosim::StepSummary st = poa.stepUntil(limit);
            const double tn = poa.getTime();
            redone += st.redone;
            cuts += st.cuts;
            smallest = std::min(smallest, st.macroStep);
            largest = std::max(largest, st.macroStep);
            if (trace)
                std::printf(
                    "step %.4f s dt %.2f ms passes %d cuts %d redone %d mismatch %.3g N of "
                    "%.4g N, first pass %.3g N (tolerance %.3g N), %d Newton, F/W %+.4f %%, "
                    "travel %.3g mm\n",
                    tn, 1e3 * st.macroStep, st.iterations, st.cuts, st.redone, st.residual,
                    st.wrenchNorm, st.firstResidual, st.tolerance, st.bagIterations,
                    100.0 * (poa.calcBagForce() - weight) / weight, 1e3 * st.shapeTravel);
            if (trace && st.firstWorstLink >= 0) {
                // Where the step's miss was: the link (segment on bag) worst at the first and
                // the last pass.
                auto name = [&](int link) {
                    if (size_t(link) >= poa.getPairs().size())
                        return "link " + std::to_string(link);
                    const cosim::ShapeBagPair& pr = poa.getPairs()[size_t(link)];
                    return std::string(body::getSegmentName(body::Segment(pr.shape))) + " on bag " +
                           std::to_string(pr.bag);
                };
                std::printf("     worst link: first pass %s (%.3g N), last pass %s (%.3g N)\n",
                            name(st.firstWorstLink).c_str(), st.firstWorstMiss,
                            name(st.lastWorstLink).c_str(), st.lastWorstMiss);
            }
            const bool phaseEnd = (ph == 0 && tn >= sc.settleTime - 1e-9) || tn >= end - 1e-9;
            if (tn >= windowStart + window - 1e-9 || phaseEnd) {
                close(current, windowStart, wallWindow, cpuWindow, atWindow);
                char label[32];
                std::snprintf(label, sizeof label, "%.2f-%.2f", current.t0, current.t1);
                printRow(label, current, poa.calcBagForce(), weight,
                         tilt(body::Segment::LowerTrunk), tilt(body::Segment::UpperTrunk));
                windowStart = tn;
                wallWindow = now();
                cpuWindow = cpuSeconds();
                atWindow = coupling.getProfile();
            }
            if (phaseEnd && ph == 0) {
                close(phase[0], 0.0, wallPhase, cpuPhase, atPhase);
                ph = 1;
                wallPhase = now();
                cpuPhase = cpuSeconds();
                atPhase = coupling.getProfile();
            }
        }
    } catch (const std::exception& e) {
        std::printf("bench_cosim: the run failed at %.4f s: %s\n", poa.getTime(), e.what());
        return 1;
    }
    if (ph == 1 && sc.duration > 0.0) close(phase[1], sc.settleTime, wallPhase, cpuPhase, atPhase);
    const double pelvis = tilt(body::Segment::LowerTrunk), thorax = tilt(body::Segment::UpperTrunk);
    std::printf("phases:\n");
    printHeader();
    printRow("settle", phase[0], poa.calcBagForce(), weight, pelvis, thorax);
    if (sc.duration > 0.0) printRow("turn", phase[1], poa.calcBagForce(), weight, pelvis, thorax);

    // The dearest bags over the whole run, and how evenly the bags' time could be shared.
    const cosim::CouplingProfile all = coupling.getProfile();
    std::vector<int> order(all.participantSeconds.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return all.participantSeconds[a] > all.participantSeconds[b]; });
    const double busy = all.bagBusySeconds;
    std::printf("bags: %.2f s busy over %.2f s of their sections on %d threads", busy,
                all.bagsSeconds, all.threads);
    if (!order.empty())
        std::printf(" (the dearest bag %.1f %% of the busy time)",
                    100.0 * all.participantSeconds[order[0]] / std::max(1e-12, busy));
    std::printf("\n");
    for (int k = 0; k < topBags && k < int(order.size()); ++k) {
        const int i = order[k];
        // A participant is one bag, or with array.neighbour_contact a module of bags.
        std::string arrayBags;
        for (int b : poa.getModules()[size_t(i)])
            arrayBags +=
                (arrayBags.empty() ? "" : " ") + std::to_string(poa.getBagIndices()[size_t(b)]);
        std::printf("  participant %3d (array %s): %7.2f s, %6ld Newton iterations\n", i,
                    arrayBags.c_str(), all.participantSeconds[i], all.participantIterations[i]);
    }
    std::printf(
        "steps: %d committed (%.2f to %.2f ms), %d redone for accuracy, %d cut on failure\n",
        coupling.getNumSteps(), 1e3 * smallest, 1e3 * largest, redone, cuts);
    std::printf("  the bags carry %.2f N of his %.2f N (%+.3f %%); load average at end: %s\n",
                poa.calcBagForce(), weight, 100.0 * (poa.calcBagForce() - weight) / weight,
                loadAverage().c_str());
    return 0;
}
