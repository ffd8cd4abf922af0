// bagsim study: runs every case of a study (docs/studies.md) and writes its table. Exit status:
// 0 every case ok, 3 the table is complete but some cases failed or are partial, 1 the table
// could not be written, 2 bad input, 130/143 interrupted (what is done is kept).
#include <bagsim/Version.h>
#include <io/InputError.h>
#include <io/StudyScenario.h>
#include <study/StudyRunner.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "Commands.h"
#include "Interrupt.h"
#include "Report.h"

namespace bagsim::app {

namespace {

const char* kHelp =
    "usage: bagsim study STUDY.yaml [--out DIR] [--jobs N] [--retry-failed] [--quiet]\n"
    "       mpirun -n RANKS bagsim study STUDY.yaml --out DIR   (a build with BAGSIM_MPI=ON)\n"
    "\n"
    "Runs every case of a study: its base scenario with the swept keys set per case (grids,\n"
    "zipped lists, random samples), each case a `bagsim run` of its own in DIR/cases/, several\n"
    "at once, and writes one table with a row per case: the parameters, the status, the reason\n"
    "a case failed, the outputs collected. A failed case does not stop the others. Run the same\n"
    "study into the same folder again and the cases done are skipped (keyed by their\n"
    "parameters and the base scenario). Study keys: docs/studies.md.\n"
    "\n"
    "options:\n"
    "  --out DIR        the study's folder (default: out/<study name>); a folder that is not\n"
    "                   empty and not a study's is refused and left alone\n"
    "  --jobs N         cases at once on this machine (default: its cores); each case runs\n"
    "                   single-threaded when N > 1\n"
    "  --retry-failed   run the cases that failed in an earlier run again\n"
    "  --quiet          no progress line, only the summary\n"
    "  -h, --help       this text\n"
    "\n"
    "outputs: DIR/study.csv (rewritten after every case), DIR/study.h5 and DIR/report.html\n"
    "(the curves and maps as pictures, docs/studies.md#the-report) at the end,\n"
    "DIR/cases/<key>/ (each case's run), DIR/cases/<key>.log (what it printed). While cases are\n"
    "missing from the table, DIR/INCOMPLETE says so. Ctrl-C (SIGINT) or SIGTERM stops the\n"
    "running cases, keeps every case done and writes the table marked interrupted.\n"
    "\n"
    "exit status: 0 every case ok, 3 some case failed or is partial (see its row), 1 the table\n"
    "could not be written, 2 bad input, 130 interrupted by SIGINT, 143 by SIGTERM, 129 by\n"
    "SIGHUP.\n";

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct Args {
    std::string study, out;
    int jobs = 0;
    bool retryFailed = false, quiet = false, help = false;
    std::string commandLine;
};

/// Splits "--name=value" into ("--name", "value"); other words come back whole.
std::pair<std::string, std::string> splitOption(const std::string& word) {
    const auto eq = word.find('=');
    if (word.rfind("--", 0) != 0 || eq == std::string::npos) return {word, ""};
    return {word.substr(0, eq), word.substr(eq + 1)};
}

int parseJobs(const std::string& v) {
    char* end = nullptr;
    const long n = std::strtol(v.c_str(), &end, 10);
    if (end == v.c_str() || *end || n < 1 || n > 1024)
        throw UsageError("--jobs '" + v + "': a whole number of cases at once, 1 to 1024");
    return int(n);
}

Args parseArgs(int argc, char** argv) {
    Args a;
    const std::vector<std::string> words(argv, argv + argc);
    a.commandLine = "bagsim study";
    for (const std::string& w : words) a.commandLine += " " + w;
    for (size_t i = 0; i < words.size(); ++i) {
        auto [name, inlineValue] = splitOption(words[i]);
        const bool takesValue = name == "--out" || name == "--jobs" || name == "-j";
        const bool inlined = words[i].size() > name.size();  // --out=VALUE, VALUE maybe empty
        std::string v = inlineValue;
        if (takesValue && !inlined) {
            if (i + 1 == words.size()) throw UsageError(name + " needs a value");
            v = words[++i];
        }
        if (name == "--out" && v.empty())
            throw UsageError(
                "--out needs a folder, not an empty path (without --out the study "
                "goes to out/NAME)");
        if (name == "--out")
            a.out = v;
        else if (name == "--jobs" || name == "-j")
            a.jobs = parseJobs(v);
        else if (name == "-h" || name == "--help")
            a.help = true;
        else if (name == "--retry-failed")
            a.retryFailed = true;
        else if (name == "--quiet" || name == "-q")
            a.quiet = true;
        else if (name.size() > 1 && name[0] == '-')
            throw UsageError("unknown option '" + words[i] +
                             "'; valid: --out DIR, --jobs N, --retry-failed, --quiet, --help");
        else if (!a.study.empty())
            throw UsageError("one study at a time ('" + a.study + "' and '" + words[i] + "')");
        else
            a.study = name;
    }
    if (!a.help && a.study.empty())
        throw UsageError("which study? e.g. bagsim study scenarios/seed-mass-study.yaml");
    return a;
}

std::string formatDuration(double s) {
    char buf[32];
    const long t = long(s + 0.5);
    if (t >= 3600)
        std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else
        std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
    return buf;
}

/// Only rank 0 of an MPI job speaks (every rank reads the study and would print the same).
bool isSilentRank() {
    const char* r = std::getenv("OMPI_COMM_WORLD_RANK");
    if (!r) r = std::getenv("PMIX_RANK");
    return r && std::atoi(r) != 0;
}

}  // namespace

int runStudyCommand(int argc, char** argv) {
    Args args;
    try {
        args = parseArgs(argc, argv);
    } catch (const UsageError& e) {
        std::cerr << "bagsim study: " << e.what() << " (see bagsim study --help)\n";
        return 2;
    }
    if (args.help) {
        std::cout << kHelp;
        return 0;
    }
    const bool silent = isSilentRank();
    const InterruptGuard interruptGuard;

    io::StudyScenario sc;
    try {
        const io::ScenarioFile file = io::ScenarioFile::load(args.study);
        if (!io::isStudyFile(file))
            throw io::InputError(args.study, file.getRoot().getLine("kind"), "kind",
                                 "a study file has kind: study; run a scenario with bagsim run");
        sc = io::readStudyScenario(file);
    } catch (const io::InputError& e) {
        if (!silent) std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    }

    study::Options o;
    o.outDir =
        args.out.empty() ? std::filesystem::path("out") / sc.name : std::filesystem::path(args.out);
    std::error_code ec;
    // Each case is this same program, `bagsim run`.
    o.program = std::filesystem::read_symlink("/proc/self/exe", ec).string();
    if (ec) {
        std::cerr << "bagsim: study failed: cannot find this program's path: " << ec.message()
                  << "\n";
        return 1;
    }
    o.jobs = args.jobs > 0 ? args.jobs : std::max(1u, std::thread::hardware_concurrency());
    o.retryFailed = args.retryFailed;
    o.commandLine = args.commandLine;
    o.isInterrupted = [] { return getInterruptSignal() != 0; };
    const bool tty = isatty(STDERR_FILENO) != 0;
    o.onStart = [&](int todo, int skipped, int ranks) {
        if (args.quiet) return;
        std::cerr << "bagsim " << bagsim::kVersion << " study: " << args.study << " (" << sc.name
                  << "), base scenario " << sc.baseScenario << "\n  " << sc.cases.size()
                  << " cases, " << sc.parameters.size() << " parameters; " << skipped
                  << " done before (skipped), " << todo << " to run, " << o.jobs << " at once"
                  << (ranks > 1 ? " per rank on " + std::to_string(ranks) + " MPI ranks" : "")
                  << "\n  writing to " << o.outDir.string()
                  << "/ (Ctrl-C stops and keeps what is done)\n";
    };
    o.onProgress = [&](const study::Progress& p) {
        if (args.quiet) return;
        char line[256];
        std::snprintf(line, sizeof line, "[%d/%d] %d failed, %d running; elapsed %s, remaining %s",
                      p.finished, p.total, p.failed, p.running, formatDuration(p.elapsed).c_str(),
                      p.remaining < 0 ? "?" : ("~" + formatDuration(p.remaining)).c_str());
        if (tty) std::cerr << "\r\033[K";
        std::cerr << "  " << p.lastCase << ": " << p.lastStatus << "\n  " << line;
        if (!tty) std::cerr << "\n";
        std::cerr.flush();
    };

    study::Summary sum;
    try {
        sum = study::runStudy(sc, o);
    } catch (const io::InputError& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "bagsim: study failed: " << e.what() << "\n";
        return 1;
    }
    if (!sum.isRoot) return sum.interrupted ? getInterruptExitCode(getInterruptSignal()) : 0;
    if (!args.quiet && tty) std::cerr << "\n";
    const std::string dir = o.outDir.string();
    // The page is a view of the table: made from the folder, also when cases are missing.
    const bool report = writeStudyReportAfterRun(o.outDir);
    std::cout << "study " << sc.name << ": " << sum.total << " cases: " << sum.ok << " ok, "
              << sum.partial << " partial, " << sum.failed << " failed, " << sum.notRun
              << " not run (" << sum.skipped << " done before this run); "
              << formatDuration(sum.seconds) << " elapsed\n"
              << "table: " << dir << "/study.csv and " << dir << "/study.h5 (status "
              << sum.table.status << ")\n";
    if (report) std::cout << "report: " << dir << "/report.html\n";
    if (sum.interrupted) {
        const int sig = getInterruptSignal();
        std::cerr << "bagsim: study " << Interrupted(sig).what()
                  << "; the cases done are kept; run "
                  << "it again into " << dir << "/ to finish it (marked INCOMPLETE)\n";
        return getInterruptExitCode(sig);
    }
    return sum.failed + sum.partial > 0 ? 3 : 0;
}

}  // namespace bagsim::app
