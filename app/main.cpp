// bagsim: simulator of airbag nursing mattresses. Dispatches to the subcommands.
#include "Commands.h"

#include <bagsim/Version.h>

#include <cstring>
#include <iostream>
#include <string>

namespace {

const char* kUsage =
    "usage: bagsim <command> [options]\n"
    "\n"
    "Simulates airbag nursing mattresses: membrane-and-gas airbags under a rigid-segment patient.\n"
    "\n"
    "commands:\n"
    "  run SCENARIO.yaml [--out DIR]   run a scenario (e.g. scenarios/seed-load-test.yaml)\n"
    "  body --sex S --height H --mass M  print the patient's segment table\n"
    "  fit-material TENSILE.csv --model M  fit a membrane material to a uniaxial tensile test\n"
    "  synth-measurement --scenario S --effect E --out DIR --label-out FILE\n"
    "                                  measured data from a truth run with an effect on\n"
    "  diagnose --measured DIR         where simulation and measured data disagree, and why\n"
    "  study STUDY.yaml [--out DIR]    run every case of a study into one table\n"
    "  report DIR [--out FILE]         (re)write report.html of a patient-on-array run or a study\n"
    "  compare REFERENCE RUN           a run's tilt and region peaks against a reference run\n"
    "\n"
    "  bagsim <command> --help   says what a command does and its options\n"
    "  bagsim --version          prints the version\n";

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
        !std::strcmp(argv[1], "help")) {
        std::cout << kUsage;
        return argc < 2 ? 2 : 0;
    }
    const std::string cmd = argv[1];
    if (cmd == "--version") {
        std::cout << "bagsim " << bagsim::kVersion << "\n";
        return 0;
    }
    if (cmd == "run") return bagsim::app::runRunCommand(argc - 2, argv + 2);
    if (cmd == "body") return bagsim::app::runBodyCommand(argc - 2, argv + 2);
    if (cmd == "fit-material") return bagsim::app::runFitMaterialCommand(argc - 2, argv + 2);
    if (cmd == "synth-measurement")
        return bagsim::app::runSynthMeasurementCommand(argc - 2, argv + 2);
    if (cmd == "diagnose") return bagsim::app::runDiagnoseCommand(argc - 2, argv + 2);
    if (cmd == "study") return bagsim::app::runStudyCommand(argc - 2, argv + 2);
    if (cmd == "report") return bagsim::app::runReportCommand(argc - 2, argv + 2);
    if (cmd == "compare") return bagsim::app::runCompareCommand(argc - 2, argv + 2);
    std::cerr << "bagsim: unknown command '" << cmd
              << "'; valid commands: run, body, fit-material, synth-measurement, diagnose, study, "
                 "report, compare (see bagsim --help)\n";
    return 2;
}
