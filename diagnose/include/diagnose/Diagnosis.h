#pragma once
/// @file The diagnosis of the sim-to-real gap on the seed's rig (docs/diagnosis.md).
///
/// Where: compareTest() puts a simulated curve beside a measured test, channel by channel, at
/// the measured samples (the machine's force at the measured displacement on the same branch;
/// the pressure sensor's reading at its sample times, the bag's pressure taken at the machine's
/// displacement then); calcWhere() splits the residuals by regime (gas mass, loading or
/// unloading, load range, third of the test's time), gives each regime's share of the squared
/// error and the signatures
/// (bias, scale, lag by cross-correlation, hysteresis loop area, drift).
///
/// Which: calibrateCandidates() fits each effect of the library (Effects.h) on the training
/// tests, leaving one gas mass out in turn, and ranks the effects by how much they shrink the
/// gap beyond the validation uncertainty on the held-out test, with a penalty per parameter;
/// then, when the best leaves a channel beyond twice its validation uncertainty, fits the best
/// few jointly with each other candidate (the pair stage); the verdict names one effect, two,
/// `none` or `unexplained`.

#include <diagnose/Effects.h>
#include <diagnose/MeasuredData.h>
#include <diagnose/RigEffects.h>

#include <bags/LoadTest.h>

#include <array>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace diagnose {

/// The channels compared (the flowmeter's is a consistency check, not part of the gap; the
/// bed gauge's only when the data have it).
enum class ChannelKind { Force, Pressure, Mass, Bed };
std::string getChannelName(ChannelKind c);  ///< "force", "pressure", "mass", "bed"
/// The kind of a channel named by getChannelName: "force", "pressure", "bed", else Mass.
ChannelKind getChannelKind(const std::string& name);
std::string getChannelUnit(ChannelKind c);  ///< "N", "kPa", "g", "mm" (how it is reported)
double getChannelUnitScale(ChannelKind c);  ///< SI per reported unit

/// One channel of one test at the measured samples, measured beside simulated.
struct ChannelComparison {
    ChannelKind kind = ChannelKind::Force;
    std::vector<double> time;          ///< [s] the channel's sample times
    std::vector<double> displacement;  ///< [m] the machine's displacement at those times
    std::vector<double> force;         ///< [N] the measured force at those times (load range)
    std::vector<char> loading;         ///< 1 before the largest displacement
    std::vector<double> measured, simulated;  ///< SI
};

struct TestComparison {
    int test = 0;                             ///< index in MeasuredData::tests
    double gasMass = 0.0;                     ///< [kg] as the flowmeter read it
    std::vector<ChannelComparison> channels;  ///< force, pressure, mass[, bed]
    /// RMS of (simulated - simulated at half the step) per channel [SI], when given: the
    /// numerical uncertainty (0 if not estimated); with a finer mesh's run (diagnose
    /// --mesh-check) the root sum square of that and numericalUncertaintyMesh.
    std::vector<double> numericalUncertainty;
    /// RMS of (simulated - simulated on the finer mesh) per channel [SI]: the mesh's part of
    /// numericalUncertainty (empty or 0 if not estimated).
    std::vector<double> numericalUncertaintyMesh;
    /// RMS over other bags of the population (imperfection seeds) of (simulated - theirs) per
    /// channel [SI]: the input uncertainty of a stated imperfection (0 if not estimated).
    std::vector<double> inputUncertainty;
    /// The input uncertainty of the protocol's stated gas mass and room temperature per channel
    /// [SI]: RMS over the channel's samples of |dS/dx| u_x, the sensitivity by central
    /// difference (calcSensitivityUncertainty); 0 where not stated.
    std::vector<double> inputUncertaintyGasMass, inputUncertaintyTemperature;
};

/// The protocol's own inputs whose stated standard uncertainty enters the validation
/// uncertainty by its sensitivity coefficient (ASME V&V 20): the flowmeter's gas mass of each
/// test and the room (gas) temperature.
enum class ProtocolInput { GasMass, RoomTemperature };
std::string getProtocolInputName(ProtocolInput input);  ///< "gas_mass", "room_temperature"

/// One extra simulation of the protocol for the sensitivity to a stated input: every test's
/// gas mass shifted by its own stated uncertainty (sign +1 or -1) at once, or the room
/// temperature by its.
struct InputRun {
    ProtocolInput input = ProtocolInput::GasMass;
    int sign = 1;
    bags::LoadTestOptions options;
};

/// The runs the stated inputs of `data` need (none for an input not stated, or stated as 0):
/// for each stated input, `base` at + and - its standard uncertainty.
std::vector<InputRun> makeInputRuns(const MeasuredData& data, const bags::LoadTestOptions& base);

/// |dS/dx| u_x per sample by central difference, (S(x + u) - S(x - u)) / 2, from the
/// comparisons of the runs at + and - (the same test, the same rig), RMS over each channel's
/// samples [SI].
std::vector<double> calcSensitivityUncertainty(const TestComparison& plus,
                                               const TestComparison& minus);

/// Root sum square of independent inputs' terms, channel by channel [SI]:
/// sqrt(sum_i term_i^2). (The RMS over samples of sqrt(sum_i (dS/dx_i u_i)^2) is this of the
/// inputs' RMS terms.)
std::vector<double> combineInputUncertainties(const std::vector<std::vector<double>>& terms);

/// Runs the load tests at once, `threads` at a time; rethrows the first failure (by index).
std::vector<bags::LoadTestResult> runLoadTests(
    const std::vector<bags::LoadTestOptions>& runs,
    const std::function<bags::LoadTestResult(const bags::LoadTestOptions&)>& simulate, int threads);

/// Sets each test's inputUncertaintyGasMass and inputUncertaintyTemperature from the runs of
/// makeInputRuns (`results` in the same order), the instruments reading them with `rig`.
void addInputUncertainties(const MeasuredData& data, const std::vector<InputRun>& runs,
                           const std::vector<bags::LoadTestResult>& results, const RigEffects& rig,
                           double rate, std::vector<TestComparison>& tests);

/// RMS per channel of the difference between two comparisons' simulated values at the same
/// measured samples [SI].
std::vector<double> calcSimulatedRmsDifference(const TestComparison& a, const TestComparison& b);

/// Puts the simulated curve `sim` (run at the test's gas mass) beside the measured test, the
/// instruments reading it with `rig`; `rate` is the crosshead speed [m/s].
TestComparison compareTest(const MeasuredTest& test, int index, const bags::LoadCurve& sim,
                           const RigEffects& rig, double rate);

/// Statistics of a channel's residuals (measured - simulated) over one regime.
struct RegimeStats {
    std::string channel;  ///< "force"
    std::string regime;   ///< "all", "gas mass 3.50 g", "loading", "load 10-35 N",
                          ///< "time first third", ...
    int samples = 0;
    double rmse = 0.0;      ///< [SI]
    double bias = 0.0;      ///< mean residual [SI]
    double maxError = 0.0;  ///< largest |residual| [SI]
    double share = 0.0;     ///< of the channel's squared error (0-1)
};

/// Signatures of a channel's residuals over one test (or all, test = -1).
struct Signature {
    std::string channel;
    int test = -1;
    double gasMass = 0.0;           ///< [kg] (0 for all)
    double bias = 0.0;              ///< mean residual [SI]
    double scale = 0.0;             ///< measured = a + (1 + scale) simulated, least squares [-]
    double lag = 0.0;               ///< [s] cross-correlation peak: measured behind simulated > 0
    double lagCorrelation = 0.0;    ///< the correlation at that peak (-1 to 1)
    double loopAreaMeasured = 0.0;  ///< hysteresis loop area, channel x displacement [SI m]
    double loopAreaSimulated = 0.0;
    double drift = 0.0;  ///< slope of the residual over time [SI/s]
    /// What the signature is of within its channel ("bag 17", "test gas-4.0g, bag 17"); "" all
    /// (the rig's: `test` and `gasMass` say it).
    std::string part;
};

struct ChannelSummary {
    std::string channel;
    double rmse = 0.0;  ///< [SI]
    /// Measured max - min [SI] (normalises the gap); for the bed gauge the crosshead's
    /// travel (the bed's sink is judged against how far the block went: a rigid bed's
    /// channel spans its noise only).
    double range = 0.0;
    double noise = 0.0;          ///< sensor noise from the data (median second difference) [SI]
    double numerical = 0.0;      ///< numerical uncertainty [SI] (0 if not estimated)
    double numericalMesh = 0.0;  ///< the mesh's part of `numerical` [SI] (0 if not estimated)
    double input = 0.0;          ///< input uncertainty (the imperfection's spread) [SI]
    /// Input uncertainty of the protocol's stated gas mass and room temperature [SI]: over the
    /// channel's samples of all tests, the RMS of |dS/dx| u_x (0 where not stated).
    double inputGasMass = 0.0, inputTemperature = 0.0;
    /// ASME V&V 20 validation uncertainty [SI]: the root sum square of noise, numerical,
    /// input, inputGasMass and inputTemperature.
    double validation = 0.0;
    double shareOfGap = 0.0;  ///< of the normalised squared error over force, pressure, bed
};

struct WhereReport {
    std::vector<ChannelSummary> channels;
    std::vector<RegimeStats> regimes;
    std::vector<Signature> signatures;
    /// The gap: RMS over force and pressure (and the bed gauge) of rmse / range [-].
    double gap = 0.0;
    /// True when every channel's RMSE is within twice its validation uncertainty.
    bool withinValidation = false;
    /// What the protocol states of its inputs' standard uncertainties (for the report: an
    /// input not stated adds nothing and is said so); set by the caller (describeInputs).
    struct StatedInput {
        ProtocolInput input = ProtocolInput::GasMass;
        bool stated = false;         ///< by every test (the gas mass) or the protocol
        std::vector<double> values;  ///< [SI] per test (the gas mass) or one (temperature)
    };
    std::vector<StatedInput> statedInputs;
};

/// The protocol's stated input uncertainties of `data` (gas mass: stated when any test states
/// it, the values per test, 0 where a test states none; room temperature: one value).
std::vector<WhereReport::StatedInput> describeInputs(const MeasuredData& data);

struct WhereOptions {
    double loadFrom = 10.0;  ///< [N] load range split (the scenario's stiffness range)
    double loadTo = 35.0;
    double maxLag = 30.0;  ///< [s] cross-correlation search window
};

WhereReport calcWhere(const std::vector<TestComparison>& tests, const WhereOptions& options);

/// What a where report's gap is, for readers: "RMS over force and pressure of RMSE / measured
/// range", with the bed gauge when the data have it.
std::string describeGap(const WhereReport& where);

/// The scales gaps are measured with, per channel kind of the gap (force, pressure, bed) [SI]:
/// the range its RMSE is divided by and its validation uncertainty (WhereReport's, pooled
/// over the tests), and each test's own validation uncertainty.
struct GapScale {
    struct Scale {
        double range = 0.0, uncertainty = 0.0;
    };
    Scale force, pressure, bed;
    /// Per test (its index, TestComparison::test): the validation uncertainty of force,
    /// pressure and bed [SI], the channel's noise with the test's own numerical and input
    /// uncertainties (root sum square). A test not listed takes the pooled one.
    std::map<int, std::array<double, 3>> testUncertainty;
    const Scale& get(ChannelKind kind) const;  ///< the mass's is all 0
    Scale& get(ChannelKind kind);              ///< @throws std::invalid_argument for the mass
    double getRange(ChannelKind kind) const { return get(kind).range; }
    double getUncertainty(ChannelKind kind) const { return get(kind).uncertainty; }
    /// The test's own (else the pooled) validation uncertainty of a channel kind [SI].
    double getUncertainty(ChannelKind kind, int test) const;
};
/// The ranges and validation uncertainties of a where report's channels and, with the
/// comparisons it was made of (their numerical and input uncertainties filled), each test's
/// own: the step's error differs between the tests (a stiffer bag's force more), and a
/// pooled uncertainty leaves a floor in the tests where it is larger.
GapScale makeGapScale(const WhereReport& where, const std::vector<TestComparison>& tests = {});

/// The gap (as WhereReport::gap) over some tests only, with the given channel ranges [SI] so
/// that gaps of different subsets are comparable: RMS over the channel kinds the tests have.
/// With `beyondUncertainty`, the gap beyond the validation uncertainties: each channel's
/// squared RMSE less its squared uncertainty (each test's own, GapScale::testUncertainty,
/// weighted by its samples; at least 0), what noise and numerics cannot explain.
double calcGap(const std::vector<TestComparison>& tests, const std::vector<int>& which,
               const GapScale& scale, bool beyondUncertainty = false);

// ------------------------------------------------------------------------------------ which

/// Runs the load test (the app supplies it: bags::runLoadTest with its interrupt checks).
using Simulator = std::function<bags::LoadTestResult(const bags::LoadTestOptions&)>;

struct CalibrationOptions {
    int gridPoints = 7;              ///< coarse scan per parameter before Ceres refines
    int maxIterations = 10;          ///< Ceres iterations per fold
    double parameterPenalty = 0.05;  ///< subtracted from the shrink per parameter [-]
    /// An effect is named when its held-out shrink (less the penalty) is at least this.
    double explainThreshold = 0.5;
    std::vector<std::string> candidates;  ///< effect names; empty: the library (Effect::inLibrary)
    int threads = 1;                      ///< simulations run at once
    /// The pair stage (docs/diagnosis.md#two-effects-at-once): the best singles taken as a
    /// pair's first member, and how many of the pairs screened are fitted in full.
    bool pairs = true;
    /// False: the pair stage runs whenever the gap is beyond the uncertainty, even when the best
    /// single leaves every channel within twice its validation uncertainty (checks of the rule
    /// that accepts a pair).
    bool pairGate = true;
    int pairFirstMembers = 2;
    int pairsRefined = 3;
    /// Called before each candidate, and each pair the pair stage screens and fits, is
    /// calibrated: what it is ("gas-temperature", "pair machine-compliance + pressure-sensor"),
    /// its number from 1 and how many there are in that stage (a progress line; may be empty).
    std::function<void(const std::string& what, int number, int count)> progress;
};

struct FoldResult {
    int heldOut = 0;                               ///< test index
    std::vector<double> parameters;                ///< calibrated on the others [SI]
    double before = 0.0, after = 0.0;              ///< held-out gap without and with the effect [-]
    double excessBefore = 0.0, excessAfter = 0.0;  ///< the same beyond the uncertainty [-]
};

/// How far a channel's simulation is from the measurement over some samples: ASME V&V 20's
/// comparison error E = S - D summarised, and the area validation metric.
struct GapMetrics {
    std::string channel;
    int samples = 0;
    double rmse = 0.0;       ///< RMS of E [SI]
    double meanError = 0.0;  ///< mean of E = S - D [SI]
    double maxError = 0.0;   ///< largest |E| [SI]
    /// Area between the empirical CDFs of the measured and the simulated values (Ferson,
    /// Oberkampf and Ginzburg 2008): the Wasserstein-1 distance of the two samples [SI].
    double areaMetric = 0.0;
};

/// The metrics of the force and pressure channels of `tests` (all samples).
std::vector<GapMetrics> calcGapMetrics(const std::vector<TestComparison>& tests);

struct CandidateResult {
    std::string effect;
    std::vector<double> parameters;       ///< calibrated on all tests [SI]
    std::vector<double> parameterStdDev;  ///< from Ceres' covariance (NaN if unavailable)
    std::vector<FoldResult> folds;
    double heldoutBefore = 0.0;  ///< mean over folds [-]
    double heldoutAfter = 0.0;
    double shrink = 0.0;  ///< 1 - after / before [-]
    /// The held-out gap beyond the validation uncertainty (calcGap), mean over folds, and its
    /// shrink: the part of the gap an effect must explain.
    double excessBefore = 0.0, excessAfter = 0.0;
    double excessShrink = 0.0;
    double score = 0.0;   ///< excessShrink - penalty x parameters
    int simulations = 0;  ///< load tests run for this candidate
    /// Over every test when held out (each with its fold's parameters), per channel: without
    /// and with the effect.
    std::vector<GapMetrics> heldoutMetricsBefore, heldoutMetricsAfter;
    /// Every test compared with the effect at the parameters fitted on all tests (for the
    /// report's before/after curves); empty if that simulation failed.
    std::vector<TestComparison> fitted;
    /// [SI] the candidate's own numerical error of prediction (a stiffness curve's grid
    /// interpolation; 0 where it is simulated), added in quadrature to each channel's validation
    /// uncertainty when what it leaves is judged (calcResidualRatio).
    double predictionUncertainty = 0.0;
};

/// Two effects fitted at once (both parameter sets), as a single candidate is: its
/// CandidateResult's effect is "first + second", its parameters the first's then the second's.
struct PairResult {
    std::string first, second;  ///< the first is one of the best singles
    /// Screen: the least-squares cost on all tests with the first at its single fit and the
    /// second scanned (the cheap look that chooses which pairs are fitted in full).
    double screenCost = 0.0;
    std::vector<double> screenParameters;  ///< where that cost was found [SI]
    bool refined = false;    ///< fitted in full (folds and all tests); else screened only
    CandidateResult result;  ///< when refined
    /// Against the single it is judged by (the one of the best single, the first and the
    /// second that leaves least to gain): the held-out gap beyond the uncertainty that single
    /// leaves, the share of it the pair removes, the penalty for the parameters the pair adds,
    /// and their difference (gain); accepted when the gain and the pair's own score both reach
    /// the threshold of a single.
    std::string against;
    double singleExcessAfter = 0.0;
    double shrinkOverSingle = 0.0;
    double extraPenalty = 0.0;
    double gain = 0.0;
    bool accepted = false;
    std::string why;  ///< one sentence
};

struct WhichReport {
    std::vector<CandidateResult> candidates;  ///< ranked, best first
    /// The pair stage: whether it ran and why (not), the pairs tried (refined first, by gain;
    /// then the screened), the one named (the accepted pair of largest gain: index into pairs,
    /// -1 if none), the load tests the stage ran.
    bool pairStageRan = false;
    std::string pairStageReason;
    std::vector<PairResult> pairs;
    int pairChosen = -1;
    int pairSimulations = 0;  ///< load tests the pair stage ran (screen and fits)
    /// The effects the verdict names: none for `none` and `unexplained`, one, or two.
    std::vector<std::string> verdictEffects;
    std::string verdict;  ///< an effect name, "none" or "unexplained"
    std::string reason;   ///< one sentence
    /// Pairs of effects whose scores are both above the threshold and whose shrinks beyond the
    /// uncertainty are within 0.1 of each other: these data do not tell them apart.
    std::vector<std::pair<std::string, std::string>> confusable;
    /// Accepted pairs (as "first + second") whose gains are within 0.1 of the named pair's.
    std::vector<std::pair<std::string, std::string>> confusablePairs;

    // What the verdict can and cannot say (qualifyVerdict; docs/diagnosis.md#what-a-verdict-says).
    /// "fully" when, held out, the verdict's effects bring every channel within
    /// kExplainedMultiple times its validation uncertainty; "partly" when a channel stays
    /// beyond it (or its held-out residual could not be measured); "" when the verdict names
    /// no effect.
    std::string explained;
    /// The largest held-out RMSE with the verdict's effects over its channel's validation
    /// uncertainty, and that channel (NaN and "" when not measured).
    double residualRatio = std::numeric_limits<double>::quiet_NaN();
    std::string residualChannel;
    /// Explanations these data do not tell from the named one (singles, or pairs as
    /// "first + second"): the verdict names them with it, "A or B". `verdictEffects` are the
    /// best explanation's effects, the one fitted in the report's curves.
    std::vector<std::string> rivals;
    /// With rivals: the measurement that would tell them apart (each differing effect's
    /// Effect::isolatedBy) and, on the rig, where their fits differ most on these tests.
    std::string tellApart;
};

/// A named effect explains the gap when, held out, it brings every channel within this many
/// times the channel's validation uncertainty: the rule that calls data `none` (calcWhere's
/// withinValidation, the stiffness curve's, the patient's, the pair stage's gate), applied to
/// what the effect leaves.
inline constexpr double kExplainedMultiple = 2.0;
/// Two candidates are rivals (confusable) when the better one reaches the threshold, their
/// shrinks of the held-out gap beyond the uncertainty are within this, and both explain alike
/// (both fully or both partly, by kExplainedMultiple).
inline constexpr double kRivalMargin = 0.1;

/// The validation uncertainty per channel name [SI] that a verdict is judged against.
using ChannelUncertainties = std::map<std::string, double>;

/// The largest held-out RMSE of a candidate's channels over their validation uncertainty (with
/// its own predictionUncertainty; NaN when none of its channels can be judged; infinity for a
/// residual that is not a finite number), and that channel.
double calcResidualRatio(const CandidateResult& c, const ChannelUncertainties& validation,
                         std::string* channel = nullptr);

/// The confusable pairs among ranked candidates: the better of the two scores at least
/// `threshold`, their shrinks beyond the uncertainty are within kRivalMargin, and, held out,
/// both bring every channel within kExplainedMultiple times its validation uncertainty or
/// neither does (a candidate that leaves a residual the other does not is told apart by these
/// data).
std::vector<std::pair<std::string, std::string>> findConfusable(
    const std::vector<CandidateResult>& candidates, double threshold,
    const ChannelUncertainties& validation);

/// Qualifies a verdict that names effects (a single or a pair; nothing for `none` or
/// `unexplained`): `explained` and the residual ratio from the named candidate's held-out
/// metrics against `validation` (the validation uncertainty per channel name [SI]; channels
/// not listed are not judged); the rivals (the single's confusable, the pair's confusable
/// pairs) named in the verdict as "A or B"; what tells them apart from `library`'s
/// isolatedBy. The reason starts with what the verdict can say ("partly explained by A or B:
/// ...").
void qualifyVerdict(WhichReport& report, const ChannelUncertainties& validation,
                    const std::vector<Effect>& library);

/// The verdict as one line: "pressure-sensor", "A or B, partly explained", "none".
std::string describeVerdict(const WhichReport& report);

/// Ranks the candidates by score, names the confusable pairs (findConfusable, judged against
/// `validation`) and gives the verdict: `none` when `withinValidation` (with `noneReason`), the
/// best effect when its score reaches the threshold, else `unexplained`. Shared by the tests'
/// and the stiffness curve's which part; qualifyVerdict then says what the verdict can say.
void judgeCandidates(WhichReport& report, bool withinValidation, const std::string& noneReason,
                     const ChannelUncertainties& validation, const CalibrationOptions& options);

/// The effects `report.confusable` pairs with `effect`, joined by ", " ("" if none).
std::string listConfusableWith(const WhichReport& report, const std::string& effect);

/// Calibrates each candidate with leave-one-test-out folds (needs two tests or more).
/// `base` are the options the diagnosis simulates (the protocol applied; the flowmeter's
/// readings are the tests' gas masses), `baseRig` the scenario's rig effects, `baseResult` the load test
/// simulated with them (reused by effects that change only the instruments), `baseline` its
/// comparisons (for the gap before), `where` their report (verdict `none` when within the
/// validation uncertainty).
WhichReport calibrateCandidates(const MeasuredData& data, const bags::LoadTestOptions& base,
                                const RigEffects& baseRig, const bags::LoadTestResult& baseResult,
                                const std::vector<TestComparison>& baseline,
                                const WhereReport& where, const Simulator& simulate,
                                const CalibrationOptions& options);

}  // namespace diagnose
