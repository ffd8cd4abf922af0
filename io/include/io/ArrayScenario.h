#pragma once
/// @file The scenario kind patient-on-array: the patient (the `patient:` section of
/// PatientScenario.h) lying on an array of the seed's double-wedge airbags, coupled through
/// cosim::PatientOnArray; released above the bags, settling, then the gas of bags or groups
/// changed over time. Sections: patient, bag, array, gas, coupling, run, mat, output. Units
/// are converted to SI; every value is checked, and an error names the file, line, key and
/// what is valid (overlapping bags, a patient off the array, an unknown group included).
/// Keys, units and ranges: docs/scenario-reference.md#kind-patient-on-array.

#include <body/PatientSpec.h>
#include <cosim/ArrayPneumatics.h>
#include <cosim/GasSchedule.h>
#include <cosim/PneumaticControl.h>
#include <cosim/PatientOnArray.h>
#include <cosim/PressureMat.h>
#include <io/Scenario.h>

#include <memory>
#include <string>
#include <vector>

namespace io {

inline constexpr const char* kPatientOnArrayKind = "patient-on-array";

/// Most bags in an array: each is a membrane model of its own (a 30 mm mesh about 170
/// nodes, a 10 mm mesh about 1500); 400 bags is a whole bed of 20 mm cells many times over.
inline constexpr int kMaxArrayBags = 400;
/// The pressure mat's frames a run may write into results.h5 (frames x rows x columns doubles):
/// 4 GiB, hundreds of times a 30 s turn's (600 frames of 64 x 32 sensels: 10 MB).
inline constexpr double kMaxMatFrameBytes = 4.0 * 1024 * 1024 * 1024;

/// A gas command as written, for the summary ("right: target 5.5 g at 0.05 g/s from 0 s").
struct GasCommandText {
    std::string who;   ///< "group 'right'" or "bags 3, 4"
    std::string what;  ///< "target 5.5 g at 0.05 g/s" or "flow -0.02 g/s"
    double at = 0.0;   ///< [s] after the settle
};

/// A scenario of kind patient-on-array, ready to run.
struct PatientOnArrayScenario {
    std::string name;         ///< 'name' key, else the file name without extension
    std::string description;  ///< 'description' key (free text), may be empty
    body::PatientSpec patient;
    std::string bagReading;  ///< bag.reading: "literal" or "fill-2.8g"
    cosim::PatientOnArrayOptions options;
    /// The gas commands, bag indices into the array, times from the release (the scenario
    /// writes them from the end of the settle; settleTime is added).
    cosim::GasSchedule gas;
    std::vector<GasCommandText> gasText;  ///< the same, as written
    double settleTime = 1.5;              ///< [s] run.settle_time: release to the schedule's 0
    double duration = 0.0;                ///< [s] run.duration: after the settle
    double outputInterval = 0.05;         ///< [s] output.every
    /// [s] output.checkpoint_every: simulated time between checkpoints (bagsim run --resume);
    /// 0: none.
    double checkpointInterval = 1.0;
    cosim::PressureMatOptions mat;  ///< mat section (default: 64 x 32 over the array)
    /// pneumatics section: the air hardware (absent: the gas list sets the bags' flows).
    bool hasPneumatics = false;
    cosim::ArrayPneumaticsSpec pneumatics;
    /// control section (with pneumatics): the controller, its times from the release; null:
    /// every valve stays closed. controlText says what it does, for the summary.
    std::shared_ptr<cosim::PneumaticController> controller;
    /// [Pa gauge] the pressure the array (or a group) was filled to at rest when it was set
    /// `from-body` (cosim::calcCellPressureForBody), else 0.
    double fillFromBody = 0.0;
    std::string controlKind;  ///< "schedule", "target-mass", "target-pressure", "turn" or ""
    std::vector<std::string> controlText;
    double targetTilt = 0.0;  ///< [rad] the turn's target pelvis tilt (0: no turn)
    double getEndTime() const { return settleTime + duration; }  ///< [s] from the release
};

/// Reads a patient-on-array scenario and checks it, the array against the bag (no overlap)
/// and the patient against the array (a bag under every segment).
/// @throws InputError on any missing, misspelt or invalid key or value.
PatientOnArrayScenario readPatientOnArrayScenario(const ScenarioFile& file);

}  // namespace io
