#pragma once
/// @file Measured data of a patient on the airbag array as a folder
/// (docs/measured-data.md#a-patient-on-the-array): the manifest measured.yaml with
/// `protocol.kind: patient-on-array` (the scenario it corresponds to, what the protocol changes
/// in it, the channel files), a pressure mat's frames (mat CSV export: a block of rows x
/// columns per frame), a tilt sensor's time/pelvis/thorax angle, and optional per-bag pressure
/// sensors (time/gauge pressure, as the rig's pressure sensor). Also the channels of a
/// patient-on-array run's folder, read back alike (readArrayRunChannels).
///
/// Order: readMeasuredKind(folder) tells a patient's folder from the rig's; then
/// readPatientMeasuredData(folder), then readPatientMeasuredScenario(data) for the scenario
/// with the protocol applied. Every problem is one io::InputError naming the file, the line
/// (for a CSV: the row's line), the key, row or column, and what would be valid.

#include <diagnose/PatientData.h>
#include <io/ArrayScenario.h>
#include <io/Scenario.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace io {

/// The manifest's protocol kind of a patient's measured data.
inline constexpr const char* kPatientMeasuredKind = "patient-on-array";
/// Largest mat file read [bytes]: 256 MiB, a 64 x 32 mat exported at 1 Hz for about six
/// hours, or at 10 Hz for half an hour.
inline constexpr std::uintmax_t kMaxMatBytes = 256ull * 1024 * 1024;

/// The manifest's protocol kind: "" for the rig's data (no `protocol.kind`), else its value
/// ("patient-on-array"). A folder without a manifest, or a manifest that is not YAML, gives ""
/// (the rig's reader then says what is wrong).
std::string readMeasuredKind(const std::string& folder);

/// Reads a pressure mat's CSV export: '#' comment lines and blank lines are skipped; then the
/// lines `rows,R`, `columns,C` and `unit,U` (a pressure unit: mmHg, kPa, Pa, ...), in this
/// order; then frames, each a line `time_<unit>,T` (time_s, "time [ms]") followed by R lines
/// of C pressures, the sensels of one row (row 1 at the foot end, column 1 at y < 0).
/// Checks: R, C whole numbers 1-1024; the unit; every cell a finite number; each frame R rows
/// of C cells; times strictly increasing; at least two frames.
/// @param shownName the file as named in messages
/// @throws InputError naming the file, the line, the frame, row and column, what is valid.
diagnose::MatFrames readMatFramesCsv(const std::string& path, const std::string& shownName);

/// Reads a patient's measured-data folder (the manifest's keys, the channel files: at least a
/// mat or a tilt sensor; each tilt file with a pelvis_tilt or thorax_tilt column or both).
/// @throws InputError (missing manifest, key or file; bad units; NaN; unsorted time; a bag
/// listed twice; a test without a subject where another names one; a single subject).
diagnose::PatientMeasurement readPatientMeasuredData(const std::string& folder);

/// One test's scenario: the data's with the protocol and the test's overrides applied.
struct PatientMeasuredTestScenario {
    std::string name;                 ///< the test's
    ScenarioFile file;                ///< the protocol and the test's overrides as overrides
    PatientOnArrayScenario scenario;  ///< read and checked
};

/// A patient's data's scenario, ready to run.
struct PatientMeasuredScenario {
    ScenarioFile file;                ///< the scenario's text and the protocol as overrides
    PatientOnArrayScenario scenario;  ///< read and checked
    /// Per test of the manifest's `tests` (empty for one record): its own scenario.
    std::vector<PatientMeasuredTestScenario> tests;
};
/// The scenario of a patient's data with the protocol applied (run.settle_time, run.duration
/// replaced), ready to run, and checked against the data: a patient-on-array scenario; its
/// mat of the data's rows x columns; each bag sensor's bag in the array; every channel's
/// samples within the run (release to settle + duration). With tests, each test's scenario
/// (the protocol's, then its overrides) is read and checked against its channels.
/// @throws InputError at the manifest's key (a test's: tests[i].overrides.KEY,
/// tests[i].channels.KEY) or the scenario's own error.
PatientMeasuredScenario readPatientMeasuredScenario(const diagnose::PatientMeasurement& data);

/// Writes a patient's measured-data folder (which must exist): measured.yaml, scenario.yaml
/// (the scenario text given), mat.csv (pressures in mmHg), tilt.csv (deg) and per bag sensor
/// bag<N>-pressure.csv (kPa); with tests, the manifest's `tests` list (with each test's
/// subject when it has one) and each test's files
/// prefixed with its name (<name>-mat.csv, ...). `comment` goes at the top of the manifest.
/// Returns the names.
std::vector<std::string> writePatientMeasuredData(const std::string& folder,
                                                  const diagnose::PatientMeasurement& data,
                                                  const std::string& scenarioText,
                                                  const std::string& comment);

/// The channels of a patient-on-array run's output folder (docs/output-layout.md): the mat's
/// frames from results.h5 /mat, tilt.csv (pelvis and thorax), and bags.csv's gauge pressure
/// per bag (the bag's true pressure, not a sensor's reading).
/// @throws InputError naming the folder or file when it is not such a run's output.
diagnose::PatientChannels readArrayRunChannels(const std::filesystem::path& runDir);

}  // namespace io
