// bagsim report DIR [--out FILE] [--force]: (re)writes report.html from the results folder
// of a patient-on-array run (io/ArrayReport.h; docs/reading-the-report.md) or from a study's
// folder (io/StudyReport.h; docs/studies.md#the-report).
#include <io/ArrayReport.h>
#include <io/InputError.h>
#include <io/StudyReport.h>

#include <filesystem>
#include <iostream>
#include <string>

#include "Commands.h"
#include "Report.h"

namespace bagsim::app {

namespace fs = std::filesystem;

namespace {

const char* kHelp =
    "usage: bagsim report DIR [--out FILE] [--force]\n"
    "\n"
    "Writes report.html, one self-contained page (no network needed), from DIR:\n"
    "- the results folder of a patient-on-array run: the scenario, the verdict, pressure-mat\n"
    "  images at key moments with a colour scale in mmHg, the peak pressure per body region,\n"
    "  tilt, bag pressures and gas over time (docs/reading-the-report.md);\n"
    "- a study's folder (bagsim study --out DIR, it holds study.csv): the study, the table of\n"
    "  cases, the outputs against each parameter, the map of a block's pressed positions, the\n"
    "  cases' load-displacement curves, the cases missing or failed (docs/studies.md).\n"
    "bagsim run and bagsim study write it at their end (also after a failure or Ctrl-C, marked\n"
    "incomplete); this command remakes it, e.g. for the folder of an older run.\n"
    "\n"
    "options:\n"
    "  --out FILE   where to write the page (default: DIR/report.html, which is replaced)\n"
    "  --force      replace FILE if it exists (DIR/report.html needs no --force)\n"
    "  -h, --help   this text\n"
    "\n"
    "exit status: 0 written, 1 it could not be written, 2 bad usage, a folder that is neither\n"
    "a patient-on-array result nor a study's, or an existing FILE without --force.\n";

}  // namespace

int runReportCommand(int argc, char** argv) {
    std::string dir, out;
    bool force = false;
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-h" || a == "--help") {
            std::cout << kHelp;
            return 0;
        } else if (a == "--force") {
            force = true;
        } else if (a == "--out" || a.rfind("--out=", 0) == 0) {
            if (a == "--out" && i + 1 >= argc) {
                std::cerr << "bagsim report: --out needs a file name\n";
                return 2;
            }
            out = a == "--out" ? argv[++i] : a.substr(6);
            if (out.empty()) {
                std::cerr << "bagsim report: --out needs a file name, not an empty one\n";
                return 2;
            }
        } else if (a.rfind("-", 0) == 0 && a.size() > 1) {
            std::cerr << "bagsim report: unknown option '" << a
                      << "'; valid: --out FILE, --force, --help\n";
            return 2;
        } else if (dir.empty()) {
            dir = a;
        } else {
            std::cerr << "bagsim report: one results folder at a time ('" << dir << "' and '" << a
                      << "')\n";
            return 2;
        }
    }
    if (dir.empty()) {
        std::cerr << "bagsim report: which folder? e.g. bagsim report out/turn-left (a run) or "
                     "bagsim report out/array-stiffness-map (a study)\n";
        return 2;
    }
    const fs::path own = fs::path(dir) / io::kReportHtml;
    const fs::path target = out.empty() ? own : fs::path(out);
    std::error_code ec;
    if (fs::is_directory(target, ec)) {
        std::cerr << "bagsim: error: " << target.string()
                  << ": is a folder; --out names the page's file, e.g. --out turn.html\n";
        return 2;
    }
    const bool isOwn =
        fs::exists(target, ec) && fs::exists(own, ec) && fs::equivalent(target, own, ec);
    if (fs::exists(target, ec) && !isOwn && !force) {
        std::cerr << "bagsim: error: " << target.string()
                  << ": exists; pass --force to replace it, or choose another --out\n";
        return 2;
    }
    try {
        if (io::isStudyFolder(dir))
            io::writeStudyReport(dir, target);
        else
            io::writeArrayReport(dir, target);
    } catch (const io::InputError& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 1;
    }
    std::cout << "report: " << target.string() << "\n";
    return 0;
}

bool writeStudyReportAfterRun(const fs::path& dir) {
    try {
        io::writeStudyReport(dir, dir / io::kReportHtml);
        return true;
    } catch (const std::exception& e) {
        std::cerr << "bagsim: warning: report.html not written (" << e.what()
                  << "); the table is kept; bagsim report " << dir.string() << " remakes it\n";
        return false;
    }
}

void writeReportAfterRun(const fs::path& dir, bool quiet) {
    try {
        io::writeArrayReport(dir, dir / io::kReportHtml);
        if (!quiet) std::cerr << "  report: " << (dir / io::kReportHtml).string() << "\n";
    } catch (const std::exception& e) {
        // The results are written; the page is a view of them and can be remade.
        std::cerr << "bagsim: warning: report.html not written (" << e.what()
                  << "); the results are kept; bagsim report " << dir.string() << " remakes it\n";
    }
}

}  // namespace bagsim::app
