#pragma once
/// @file bagsim run for the scenario kind patient-on-array (called from RunCommand.cpp), and
/// its checkpoints (bagsim run --resume; docs/output-layout.md#checkpoint).

#include <bags/StateStream.h>
#include <io/Scenario.h>

#include <cstdint>
#include <string>
#include <vector>

namespace bagsim::app {

/// How a patient-on-array run is run besides its scenario.
struct ArrayRunControl {
    bool force = false;  ///< write into a folder that is not empty
    bool quiet = false;
    std::string commandLine;
    /// A resumed run: the checkpoint read past its header (readCheckpointHeader()); the
    /// output folder is `out`, the folder of the run that wrote it. Null: a new run.
    bags::StateReader* resume = nullptr;
    /// A resumed run: the model its checkpoint's writer made (CheckpointHeader::model).
    std::string resumeModel;
    /// A run from a rest state (--from-rest): the rest state read past its header; the model
    /// built from the scenario takes the body's, the bags' and the coupling's state from it
    /// and runs on from the settle's end. `fromRestDir` names its folder (events, summary).
    bags::StateReader* fromRest = nullptr;
    std::string fromRestDir;
    /// A run from a rest state: the model the rest state's writer made (CheckpointHeader::
    /// model); its patient and array must be this build's.
    std::string fromRestModel;
    /// [s] simulated: the run stops there as on Ctrl-C, after the macro step that reaches it
    /// (--stop-after, for tests of --resume); negative: never.
    double stopAfter = -1.0;
};

/// Builds the patient on the airbag array, lowers him, lets him settle and runs the gas
/// schedule; streams regions.csv, bags.csv, tilt.csv, results.h5 (mat frames), results.xdmf
/// and summary.txt into the output folder, and a checkpoint every output.checkpoint_every.
/// Returns the exit status (0 done, 1 run failed, 2 bad input, 130/143 interrupted by
/// SIGINT/SIGTERM: needs the caller's InterruptGuard).
int runPatientOnArray(const io::ScenarioFile& file, const std::string& out,
                      const ArrayRunControl& control);

/// What a checkpoint says of the run that wrote it.
struct CheckpointHeader {
    std::string version;                 ///< bagsim's version that wrote it
    std::string scenarioFile;            ///< the scenario's path as given
    std::string scenarioText;            ///< its text verbatim
    std::vector<std::string> overrides;  ///< --set key=value, in order
    double time = 0.0;                   ///< [s] simulated, of the checkpoint
    /// The model the writing build made of the scenario, as its run header prints it (empty
    /// in checkpoints written before it was kept): a build that makes another is refused.
    std::string model;
};
/// A checkpoint file: this magic line, the length of the data that follows and its FNV-1a
/// hash (two little-endian uint64), then the data (header first).
inline constexpr const char* kCheckpointMagic = "bagsim checkpoint 1\n";
/// FNV-1a 64-bit hash of `data`: tells a damaged checkpoint from a sound one (also the key of
/// a cached stiffness curve of bagsim diagnose).
inline std::uint64_t calcCheckpointHash(const std::string& data) {
    std::uint64_t h = 14695981039346656037ull;
    for (unsigned char c : data) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}
/// A rest-state file: this magic line, then length, hash and data as a checkpoint's; the
/// data are a checkpoint header (the run that wrote it, the settle's end time), the model's
/// state (cosim::PatientOnArray::saveState) and an "end" tag.
inline constexpr const char* kRestStateMagic = "bagsim rest state 1\n";
/// "" when a run of scenario `run` may start from a rest state written by a run of scenario
/// `rest` (both with their overrides applied): every key must be the same except those that
/// act only after the settle or on the outputs (description, gas, control, pneumatics,
/// run.duration, mat, output). Else the first difference, as "bag.mesh_size: '25 mm' here,
/// '30 mm' in the rest state's scenario".
std::string describeRestDifference(const io::ScenarioFile& run, const io::ScenarioFile& rest);
/// Reads the header of a checkpoint (after the magic line).
/// @throws bags::StateError if it is not one.
CheckpointHeader readCheckpointHeader(bags::StateReader& r);

}  // namespace bagsim::app
