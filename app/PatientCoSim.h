#pragma once
// Shared by bagsim synth-measurement and bagsim diagnose on a patient's data
// (docs/diagnosis.md#a-patient-on-the-array): the co-simulation of a patient-on-array scenario
// run into a folder and read back as channels, and the mat's sensels given body regions.
#include <diagnose/PatientDiagnosis.h>
#include <io/ArrayScenario.h>
#include <io/Scenario.h>

#include <string>
#include <vector>

namespace bagsim::app {

/// Runs `bagsim run` on the scenario's file with its overrides (`--set`) into `dir` (replaced),
/// as a child process (its output in `dir`.log), and reads back its channels
/// (io::readArrayRunChannels).
/// @throws Interrupted when interrupted; std::runtime_error when the run fails (naming the
/// folder, whose summary says why).
diagnose::PatientChannels runCoSimulation(const io::ScenarioFile& file, const std::string& dir);

/// The mat's sensels given the body region they lie under (docs/diagnosis.md#a-patient-on-the-array):
/// the regions that a supine patient lies on (those on his back: occiput, scapulae, spine,
/// elbows, sacrum, ischia, calves, heels), projected onto the bed from the standing reference
/// frame at his position (superior along +x, his right along +y); a sensel goes to the nearest
/// region centre within 1.5 times its radius, else to the segment whose centre of mass is
/// nearest within 0.3 m (named as regions.csv names nodes in no region: "thigh_r"), else to
/// "off the body". Other postures: one region, "whole mat".
diagnose::MatRegions makeMatRegions(const io::PatientOnArrayScenario& sc);

/// The macro step's text halved ("5 ms" for 10 ms), for a run at half the scenario's step.
std::string formatHalfMacroStep(const io::PatientOnArrayScenario& sc);

}  // namespace bagsim::app

namespace bagsim::app {

/// bagsim diagnose on a patient's measured data (the command's options).
struct PatientDiagnoseArgs {
    std::string measured, out, commandLine;
    bool force = false, whereOnly = false, quiet = false;
    std::vector<std::string> candidates;  ///< the patient's library's names; empty: instruments
    int windows = 3;                      ///< time windows (the folds)
};

/// Reads the data, runs the scenario (and at half its macro step), writes diagnosis.json,
/// residuals.csv and report.html into a.out with the co-simulations under a.out/runs/.
/// Returns 0 (the command's exceptions propagate to runCommandMain).
int runPatientDiagnosis(const PatientDiagnoseArgs& a);

}  // namespace bagsim::app
