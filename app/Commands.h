#pragma once
/// @file The subcommands of the bagsim program. Each takes the arguments after its name and
/// returns the process exit code (0 ok, 1 run failed, 2 bad input or usage; bagsim run also 3
/// partial and 130/143 interrupted, docs/output-layout.md#exit-status-and-status).

namespace bagsim::app {

int runRunCommand(int argc, char** argv);   ///< bagsim run SCENARIO.yaml [--out DIR]
int runBodyCommand(int argc, char** argv);  ///< bagsim body --sex ... --height ... --mass ...
int runFitMaterialCommand(int argc, char** argv);  ///< bagsim fit-material TENSILE.csv --model ...
int runSynthMeasurementCommand(int argc, char** argv);  ///< bagsim synth-measurement --scenario ...
int runDiagnoseCommand(int argc, char** argv);          ///< bagsim diagnose --measured DIR
int runStudyCommand(int argc, char** argv);             ///< bagsim study STUDY.yaml [--out DIR]
int runReportCommand(int argc, char** argv);            ///< bagsim report DIR [--out FILE]
int runCompareCommand(int argc, char** argv);           ///< bagsim compare REFERENCE RUN

}  // namespace bagsim::app
