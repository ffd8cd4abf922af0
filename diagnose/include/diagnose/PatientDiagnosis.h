#pragma once
/// @file The diagnosis of the sim-to-real gap for a patient on the airbag array
/// (docs/diagnosis.md#a-patient-on-the-array): the patient's library of unmodelled effects,
/// synthetic measured data from a truth run, and the where and which stages on the mat, tilt
/// and bag pressure channels.
///
/// Order: a run's channels (io::readArrayRunChannels) go through readPatientInstruments() (what
/// the instruments read of them) and synthesizePatientChannels() (sampled, noisy) to make
/// synthetic data; comparePatient() puts a simulated run beside measured data at the measured
/// samples; calcPatientWhere() splits the residuals (by body region of the mat, by bag, by time
/// window) with the rig's statistics and signatures (Signatures.h); calibratePatientCandidates()
/// fits each candidate on all time windows but one and judges it on the one left out, with the
/// rig's scoring rule (CalibrationOptions' penalty and threshold).

#include <bags/Units.h>
#include <diagnose/Diagnosis.h>
#include <diagnose/Effects.h>
#include <diagnose/PatientData.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace diagnose {

// ------------------------------------------------------------------------- the effects

/// The instruments' own errors on the ward (no re-run of the co-simulation).
struct PatientInstruments {
    double bagSensorLag = 0.0;     ///< the bags' pressure sensors' first-order lag [s]
    double bagSensorOffset = 0.0;  ///< their zero offset [Pa]
    double matGain = 0.0;          ///< the mat reads the pressure times 1 + this [-]
    static constexpr double kMaxBagSensorLag = 2.0;     ///< [s] tubing and filter
    static constexpr double kMaxBagSensorOffset = 5e3;  ///< [Pa] either sign
    static constexpr double kMaxMatGain = 0.3;          ///< either sign: a mat's drift
};

/// The patient's library, in order: bag-pressure-sensor (lag, offset), mat-gain (gain) change
/// only what the instruments read; film-friction (friction: bag.body_friction), gas-mass-bias
/// (offset: the bags hold the stated array.gas_mass plus this) and soft-tissue (thickness,
/// modulus: bag.body_tissue) change the patient's response (changesTheBag: a co-simulation per
/// trial value).
const std::vector<Effect>& getPatientEffects();
const Effect* findPatientEffect(const std::string& name);
std::string listPatientEffectNames();

/// The instruments with an instrument effect applied (values [SI], one per parameter).
/// @throws std::invalid_argument outside the bounds.
void applyPatientInstrumentEffect(const Effect& effect, const std::vector<double>& values,
                                  PatientInstruments& instruments);
/// The scenario overrides (key, value text with units) that switch on an effect that changes the
/// patient's response; `statedGasMass` [kg] is the scenario's array.gas_mass.
/// @throws std::invalid_argument outside the bounds.
std::vector<std::pair<std::string, std::string>> getPatientEffectOverrides(
    const Effect& effect, const std::vector<double>& values, double statedGasMass);

/// What the instruments read of a run's channels at its own samples: the bags' sensors with
/// their lag and offset (applyPressureSensor), the mat times 1 + gain.
PatientChannels readPatientInstruments(const PatientChannels& run, const PatientInstruments& inst);

// ------------------------------------------------------------------------- synthesis

struct PatientSynthesisOptions {
    double sampleInterval = 0.02;  ///< [s] tilt and bag sensors sample at this interval
    double matInterval = 0.1;      ///< [s] the mat's frame interval
    double matNoise = 0.5 * bags::kPascalsPerMmHg;            ///< [Pa] per loaded sensel (0.5 mmHg)
    double tiltNoise = 0.1 * 3.14159265358979323846 / 180.0;  ///< [rad] (0.1 deg)
    double pressureNoise = 50.0;                              ///< [Pa] the bags' sensors (0.05 kPa)
    std::uint64_t seed = 1;
    /// @throws std::invalid_argument naming the option and what would be valid.
    void validate() const;
};

/// The instruments' readings (readPatientInstruments) sampled at the options' intervals from
/// the first time on, by linear interpolation between the run's outputs, with Gaussian noise
/// (a sensel that reads nothing stays 0, and none reads below 0: a mat reads no tension).
PatientChannels synthesizePatientChannels(const PatientChannels& run,
                                          const PatientInstruments& inst,
                                          const PatientSynthesisOptions& options);

// ------------------------------------------------------------------------- where

/// The regions of the mat: per sensel (r * columns + c) the index of its region in `names`.
struct MatRegions {
    std::vector<std::string> names;
    std::vector<int> sensel;
};

/// One channel of the patient compared at the measured samples.
struct PatientChannelComparison {
    std::string name;        ///< "mat", "pelvis-tilt", "thorax-tilt", "bag-pressure"
    std::string unit;        ///< how it is reported: "mmHg", "deg", "kPa"
    double unitScale = 1.0;  ///< SI per reported unit
    std::vector<double> time, measured, simulated;  ///< SI
    std::vector<int> part;  ///< per sample: the mat's region or the bag (index into partNames)
    std::vector<std::string> partNames;  ///< "sacrum", "bag 17"; empty for the tilt
    /// The mat's samples: frame of the measured mat and sensel (to re-evaluate them alike).
    std::vector<int> frame, sensel;
    /// Per sample: its test (index into PatientComparison::tests); empty for one record.
    std::vector<int> test;
    /// Per part (the mat: per sensel) and test, its samples in time order (for the series'
    /// signatures and noise).
    std::vector<std::vector<size_t>> partSeries() const;
    int getTest(size_t sample) const { return test.empty() ? 0 : test[sample]; }
};

struct PatientComparison {
    std::vector<PatientChannelComparison> channels;
    /// The tests' names when several tests are joined (joinPatientComparisons); empty for one
    /// record.
    std::vector<std::string> tests;
    /// The subjects' names (in the order they first appear) when the joined tests name them;
    /// empty otherwise.
    std::vector<std::string> subjects;
    /// Per test: its subject (index into subjects); empty without subjects.
    std::vector<int> testSubject;
    const PatientChannelComparison* find(const std::string& name) const;
};

/// Several tests' comparisons as one: each channel's samples test after test, each tagged with
/// its test; the parts (bags, the mat's regions) merged by name. One comparison is returned as
/// it is. `subjects` (per test its subject's name; empty: none) fills subjects and testSubject.
PatientComparison joinPatientComparisons(const std::vector<PatientComparison>& parts,
                                         const std::vector<std::string>& names,
                                         const std::vector<std::string>& subjects = {});

/// What the folds of the which stage leave out: the time windows of one record, or (several
/// tests) whole tests, or (tests that name their subjects) all tests of one subject, each in
/// turn.
struct PatientFolds {
    std::vector<double> windowEdges;    ///< [s] the time windows' bounds (also the where stage's)
    int tests = 1;                      ///< more than one: the folds are the tests (or subjects)
    std::vector<std::string> subjects;  ///< not empty: the folds are these subjects
    std::vector<int> testSubject;       ///< per test: its subject (index into subjects)
    bool isBySubject() const { return !subjects.empty(); }
    bool isByTest() const { return tests > 1 && !isBySubject(); }
    int getCount() const {
        return isBySubject() ? int(subjects.size())
               : isByTest()  ? tests
                             : int(windowEdges.size()) - 1;
    }
    /// "subject", "test" or "time-window" (diagnosis.json's fold_kind).
    const char* getKind() const {
        return isBySubject() ? "subject" : isByTest() ? "test" : "time-window";
    }
    /// The fold a sample of the channel belongs to.
    int findFold(const PatientChannelComparison& c, size_t sample) const;
    /// The tests (indices) of a fold: its subject's, or the one test; empty for a time window.
    std::vector<int> getFoldTests(int fold) const;
};

/// The simulated run (its true values; the instruments read it with `inst`) beside the measured
/// data at the measured samples. The mat is compared at the sensels and frames where either
/// reads a pressure, or, given `like`, at the same samples as that comparison's mat.
PatientComparison comparePatient(const PatientChannels& measured, const PatientChannels& run,
                                 const PatientInstruments& inst, const MatRegions& regions,
                                 const PatientComparison* like = nullptr);

/// RMS per channel of the difference between two comparisons' simulated values [SI] (the
/// numerical uncertainty, from a run at half the macro step), in `a`'s channel order.
std::vector<double> calcPatientSimulatedDifference(const PatientComparison& a,
                                                   const PatientComparison& b);

/// Where the gap lies: per channel RMSE, range, noise (second differences of each part's
/// series), the numerical uncertainty given, their validation uncertainty; the gap (RMS over
/// channels of RMSE / range) and each channel's share; regimes: by region (mat) or bag, and by
/// time window (the windows' bounds given); signatures per channel and part.
WhereReport calcPatientWhere(const PatientComparison& c, const std::vector<double>& numerical,
                             const std::vector<double>& windowEdges, double maxLag);

/// The gap over the samples whose time lies in the given windows (indices into the windows
/// that windowEdges bound); beyond the channels' validation uncertainties (as calcGap), except
/// that a channel whose RMSE over the record is within twice its validation uncertainty counts
/// only what goes beyond twice it.
double calcPatientGap(const PatientComparison& c, const WhereReport& where,
                      const std::vector<double>& windowEdges, const std::vector<int>& windows,
                      bool beyondUncertainty);
/// The same over the samples of the given folds (time windows, or tests).
double calcPatientGap(const PatientComparison& c, const WhereReport& where,
                      const PatientFolds& folds, const std::vector<int>& selected,
                      bool beyondUncertainty);

// ------------------------------------------------------------------------- which

/// Simulates the scenario with these overrides (an effect that changes the patient's response)
/// and returns the run's channels; the app supplies it (a co-simulation).
using PatientSimulator = std::function<PatientChannels(
    const std::vector<std::pair<std::string, std::string>>& overrides, const std::string& label)>;

struct PatientCalibrationOptions {
    double parameterPenalty = 0.05;  ///< as CalibrationOptions
    double explainThreshold = 0.5;
    std::vector<std::string> candidates;  ///< names; empty: the instrument effects the data have
    /// Per parameter, for effects that re-run the co-simulation (one parameter: then one more
    /// run at the vertex of a parabola through the best point and its neighbours).
    int gridPoints = 5;
    double maxLag = 2.0;  ///< [s]
};

/// One test of a patient's data as the which stage uses it.
struct PatientTestCase {
    std::string name;  ///< "" for one record
    PatientChannels measured;
    PatientChannels baseline;    ///< the model's run of the test's scenario
    double statedGasMass = 0.0;  ///< [kg] the test's array.gas_mass
    std::string subject;         ///< the patient measured ("" when the data name none)
    /// The mat's regions under this test's patient (a subject's own build); empty: the regions
    /// the caller gives for every test.
    MatRegions regions;
};

/// Simulates test `test`'s scenario with these overrides (applied after the test's own) and
/// returns the run's channels; the app supplies it (a co-simulation).
using PatientTestSimulator = std::function<PatientChannels(
    int test, const std::vector<std::pair<std::string, std::string>>& overrides,
    const std::string& label)>;

/// Each test's comparison of its baseline (the model as it is) with what was measured, on the
/// test's own regions when it has them, else on `regions`.
std::vector<PatientComparison> comparePatientTests(const std::vector<PatientTestCase>& tests,
                                                   const MatRegions& regions);

/// Calibrates each candidate on all folds but one and judges it on the one left out, in turn:
/// the folds are the subjects when the tests name them (all tests of one subject left out), the
/// tests when there are several (an effect that changes the response is simulated in every test
/// at each trial value, with the test's stated gas mass), else the time windows of the one
/// record. The fit, the score and the verdict as below.
WhichReport calibratePatientCandidates(const std::vector<PatientTestCase>& tests,
                                       const WhereReport& where, const MatRegions& regions,
                                       const PatientFolds& folds,
                                       const PatientTestSimulator& simulate,
                                       const PatientCalibrationOptions& options);

/// Calibrates each candidate with leave-one-window-out folds (the windows bounded by
/// windowEdges, at least two) and ranks them by the rig's score (the held-out shrink of the gap
/// beyond the validation uncertainty less the penalty per parameter); the verdict as the
/// rig's single stage (none, an effect, unexplained; confusable within 0.1). Instrument effects
/// re-read the baseline run (least squares of the channels' residuals over their ranges on a
/// grid of 11 values per parameter refined coordinate by coordinate by golden section); effects
/// that change the response are scanned over gridPoints values per parameter, each a run
/// (cached: the folds share them), and a one-parameter effect refined by a parabola.
WhichReport calibratePatientCandidates(const PatientChannels& measured,
                                       const PatientChannels& baseline,
                                       const PatientComparison& baseComparison,
                                       const WhereReport& where, const MatRegions& regions,
                                       const std::vector<double>& windowEdges, double statedGasMass,
                                       const PatientSimulator& simulate,
                                       const PatientCalibrationOptions& options);

}  // namespace diagnose
