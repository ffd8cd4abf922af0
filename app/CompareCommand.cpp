// bagsim compare REFERENCE RUN: a patient-on-array run against a reference run of the same
// scenario, on the reduced bag's targets (io/RunComparison.h;
// docs/reduced-bag.md#checking-a-run-against-a-reference).
#include <io/InputError.h>
#include <io/RunComparison.h>
#include <io/Units.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include <unistd.h>

#include "Commands.h"

namespace bagsim::app {

namespace fs = std::filesystem;

namespace {

const char* kHelp =
    "usage: bagsim compare REFERENCE RUN [options]\n"
    "\n"
    "Compares the results folder RUN of a patient-on-array run with the folder REFERENCE of a\n"
    "run of the same scenario (e.g. reduced bags against finite-element bags, or a coarse mesh\n"
    "against a fine one): the pelvis's and thorax's tilt at every output row both have (the\n"
    "largest difference, its rms, the rows within the tilt tolerance) and each body region's\n"
    "patch peak pressure (20 cm^2) at the output times, for the regions the reference loads\n"
    "(the mean and rms of run / reference - 1, the regions within the peak tolerance; a region\n"
    "the run does not load then counts as -100 %). Its last line says whether the run meets\n"
    "both tolerances everywhere, or that the comparison is not whole (an unfinished folder,\n"
    "rows or moments one run lacks, no region judged): "
    "docs/reduced-bag.md#checking-a-run-against-a-reference.\n"
    "\n"
    "options:\n"
    "  --from TIME            compare rows from this time on, e.g. '1.5 s' (default 0 s)\n"
    "  --times T1,T2,...      the region moments, e.g. '1.5 s,3 s,4.5 s' (default: every\n"
    "                         output time both runs have, from --from on)\n"
    "  --min-force F          judge a region where the reference carries at least F\n"
    "                         (default 10 N)\n"
    "  --tilt-tolerance A     default 2 deg\n"
    "  --peak-tolerance R     relative, e.g. 15% or 0.15 (default 15%)\n"
    "  --detail               print every region at every moment\n"
    "  --csv FILE             write every judged region-moment as CSV (not over an existing\n"
    "                         file without --force)\n"
    "  --force                replace an existing --csv FILE\n"
    "  -h, --help             this text\n"
    "\n"
    "exit status: 0 compared (whatever the result), 1 the CSV could not be written, 2 bad\n"
    "usage or a folder without tilt.csv and regions.csv (with patch_peak_mmHg).\n";

int usageError(const std::string& what) {
    std::cerr << "bagsim compare: " << what << " (bagsim compare --help)\n";
    return 2;
}

}  // namespace

int runCompareCommand(int argc, char** argv) {
    std::vector<std::string> dirs;
    io::RunComparisonOptions opt;
    std::string csv;
    bool detail = false, force = false;
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
        try {
            if (a == "-h" || a == "--help") {
                std::cout << kHelp;
                return 0;
            } else if (a == "--detail") {
                detail = true;
            } else if (a == "--force") {
                force = true;
            } else if (a == "--from" || a == "--times" || a == "--min-force" ||
                       a == "--tilt-tolerance" || a == "--peak-tolerance" || a == "--csv") {
                const char* v = value();
                if (!v) return usageError(a + " needs a value");
                const std::string s = v;
                if (a == "--from") {
                    opt.from = io::parseQuantity(s, io::Dimension::Time);
                } else if (a == "--times") {
                    std::stringstream in(s);
                    std::string item;
                    while (std::getline(in, item, ','))
                        opt.times.push_back(io::parseQuantity(item, io::Dimension::Time));
                } else if (a == "--min-force") {
                    opt.minForce = io::parseQuantity(s, io::Dimension::Force);
                } else if (a == "--tilt-tolerance") {
                    opt.tiltTolerance = io::parseQuantity(s, io::Dimension::Angle);
                } else if (a == "--peak-tolerance") {
                    std::string n = s;
                    const bool percent = !n.empty() && n.back() == '%';
                    if (percent) n.pop_back();
                    const std::string valid =
                        "; valid: a percentage (15%) or a fraction "
                        "below 1 (0.15), more than 0";
                    try {
                        opt.peakTolerance = io::parseQuantity(n, io::Dimension::Dimensionless) *
                                            (percent ? 0.01 : 1.0);
                    } catch (const io::UnitError&) {
                        return usageError("--peak-tolerance '" + s + "' is not a number" + valid);
                    }
                    if (!(opt.peakTolerance > 0.0) || (!percent && opt.peakTolerance >= 1.0))
                        return usageError("--peak-tolerance '" + s + "'" + valid +
                                          (!percent && opt.peakTolerance >= 1.0
                                               ? " (did you mean " + n + "%?)"
                                               : ""));
                } else {
                    csv = s;
                }
            } else if (a.rfind("-", 0) == 0 && a.size() > 1) {
                return usageError("unknown option '" + a +
                                  "'; valid: --from, --times, --min-force, --tilt-tolerance, "
                                  "--peak-tolerance, --detail, --csv, --force, --help");
            } else {
                dirs.push_back(a);
            }
        } catch (const io::UnitError& e) {
            return usageError(a + ": " + e.what());
        }
    }
    if (dirs.size() != 2)
        return usageError(
            "give two results folders, the reference first, e.g. bagsim compare "
            "out/turn-fe out/turn-reduced");
    if (!(opt.tiltTolerance > 0.0)) return usageError("--tilt-tolerance must be positive");
    // Times are matched to 0.1 ms: a run's output times lie between 0 and a day or so.
    for (double t : opt.times)
        if (!(t >= 0.0 && t <= 1e6))
            return usageError("--times: " + std::to_string(t) +
                              " s is not a run's output time; "
                              "valid: 0 s to 1e6 s");
    if (!(opt.from >= 0.0 && opt.from <= 1e6))
        return usageError("--from must lie between 0 s and 1e6 s");
    std::error_code ec;
    if (!csv.empty() && fs::exists(csv, ec) && !force)
        return usageError(csv + ": exists; pass --force to replace it, or choose another --csv");
    io::RunComparison c;
    try {
        c = io::compareRuns(dirs[0], dirs[1], opt);
    } catch (const io::InputError& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    }
    std::cout << io::formatRunComparison(c, detail);
    if (!csv.empty()) {
        // Written beside it under a name of this process's own, then renamed over it.
        const fs::path tmp = csv + ".bagsim-" + std::to_string(::getpid()) + ".tmp";
        {
            std::ofstream o(tmp);
            o << io::formatRegionPeaksCsv(c);
            if (!o) {
                std::cerr << "bagsim: error: " << csv << ": cannot be written\n";
                fs::remove(tmp, ec);
                return 1;
            }
        }
        fs::rename(tmp, csv, ec);
        if (ec) {
            std::cerr << "bagsim: error: " << csv << ": cannot be written (" << ec.message()
                      << ")\n";
            std::error_code ignored;
            fs::remove(tmp, ignored);
            return 1;
        }
        std::cout << "region peaks: " << csv << "\n";
    }
    return 0;
}

}  // namespace bagsim::app
