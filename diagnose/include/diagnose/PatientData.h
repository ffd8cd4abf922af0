#pragma once
/// @file Measured data of a patient on the airbag array (docs/measured-data.md#a-patient-on-the-array)
/// as the ward's instruments record it, in SI: a pressure mat's frames (rows x columns of
/// sensel pressure per time), a tilt sensor's pelvis and/or thorax angle over time, and
/// optionally the bags' own pressure sensors. The same structure holds the channels of a
/// simulated run (io::readArrayRunChannels), so the two are compared alike. The folder format
/// and its reader are io::readPatientMeasuredData; this is the plain data the diagnosis works on.

#include <diagnose/MeasuredData.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace diagnose {

/// A pressure mat's frames: sensel (r, c) of frame f at pressure[f][r * columns + c] [Pa];
/// row r along the bed (row 0 at the foot end, the mat's origin), column c across it
/// (column 0 at y < 0: a supine patient's left side). cosim::PressureMat's layout.
struct MatFrames {
    int rows = 0, columns = 0;
    std::vector<double> time;                   ///< [s] from the release, strictly increasing
    std::vector<std::vector<double>> pressure;  ///< per frame, rows x columns [Pa]
    bool empty() const { return time.empty(); }
};

/// A tilt sensor (or the model's tilt): the pelvis' and the thorax' anterior axis from
/// vertical, seen along the bed; positive turned onto his left side (cosim::calcSegmentTilt).
struct TiltChannel {
    std::vector<double> time;    ///< [s] from the release
    std::vector<double> pelvis;  ///< [rad]; empty when not recorded
    std::vector<double> thorax;  ///< [rad]; empty when not recorded
    bool empty() const { return time.empty(); }
};

/// One bag's pressure sensor: gauge pressure over time.
struct BagPressureChannel {
    int bag = 0;       ///< array index (bags.csv's `bag`)
    Channel pressure;  ///< [s], [Pa] gauge
    std::string file;  ///< as named in messages (measured data), "" for a simulation
};

/// What the data's protocol changes in the scenario before it is simulated (negative: the
/// scenario's own value).
struct PatientProtocol {
    double settleTime = -1.0;  ///< [s] run.settle_time
    double duration = -1.0;    ///< [s] run.duration
};

/// The channels of one recording of a patient on the array, measured or simulated. Time 0 is
/// the release of the patient onto the bags (the run's time_s).
struct PatientChannels {
    MatFrames mat;
    TiltChannel tilt;
    std::vector<BagPressureChannel> bags;  ///< sorted by bag index
    std::string matFile, tiltFile;         ///< as named in messages ("" for a simulation)
};

/// One test of a patient's data: a record under its own condition of the scenario (another gas
/// mass, another setting), the manifest's `tests:` list.
struct PatientTest {
    std::string name;  ///< the lab's name ("gas-4.0g"): letters, digits, '.', '-', '_'
    /// The patient measured (the manifest's optional `subject`, a name as the test's): "" when
    /// the data name no subject, else every test names one and there are at least two.
    std::string subject;
    /// The scenario keys this test changes: (dotted key, value text with units), as `--set`.
    std::vector<std::pair<std::string, std::string>> overrides;
    PatientChannels channels;
};

/// A measured-data folder of a patient (manifest `protocol.kind: patient-on-array`): one record
/// (`channels`) or several tests (`tests`, each with its channels; then `channels` is empty).
struct PatientMeasurement {
    std::string folder;        ///< where it was read from
    std::string scenarioFile;  ///< the patient-on-array scenario it corresponds to
    std::string description;
    PatientProtocol protocol;
    PatientChannels channels;        ///< the single record's (empty when `tests` is not)
    std::vector<PatientTest> tests;  ///< the manifest's tests, in its order; empty: one record
    /// The subjects the tests name, in the order they first appear; empty when none.
    std::vector<std::string> getSubjects() const {
        std::vector<std::string> out;
        for (const PatientTest& t : tests)
            if (!t.subject.empty() && std::find(out.begin(), out.end(), t.subject) == out.end())
                out.push_back(t.subject);
        return out;
    }
};

}  // namespace diagnose
