#pragma once
/// @file The which part of the diagnosis on a measured stiffness curve k(m)
/// (docs/diagnosis.md#which-on-a-stiffness-curve): which effect of the library explains the
/// departure of the model's curve from the measured one, judged on gas masses held out of the
/// fit.
///
/// A full curve of the seed's bag takes minutes, so the candidates are not fitted by running
/// the model per trial value. Each is read off the model's curve run on a grid, once:
/// - a shift of the gas mass (flowmeter-bias: the bag holds the reading less an offset;
///   gas-temperature: isothermal gas acts through m T, a scale of the mass) re-reads ONE dense
///   curve of the model at other masses;
/// - bag-volume runs the model at the curve's masses for a few volumes;
/// - a compliance in series with the block (machine-compliance, bed-compliance) and the load
///   cell's gain act on the model's stiffness directly, k / (1 + c k) and (1 + g) k.
/// The grids' stiffness is interpolated linearly (in the mass, or in the volume at each mass).
///
/// Order of use: the caller runs the model (the curve at the measured masses, and each
/// candidate's grid: makeShiftMasses() says the dense curve's masses), builds a CurveCandidate
/// per effect, then calibrateStiffnessCandidates() fits each by leaving one gas mass out in
/// turn and ranks them with the tests' rule (judgeCandidates).

#include <diagnose/Diagnosis.h>
#include <diagnose/Effects.h>
#include <diagnose/Stiffness.h>

#include <string>
#include <vector>

namespace diagnose {

/// The model's stiffness at some gas masses (one let-down of one bag).
struct StiffnessTable {
    std::vector<double> gasMass;    ///< [kg] strictly increasing
    std::vector<double> stiffness;  ///< [N/m]; NaN where the curve gives none
};

/// Linear interpolation of the table at `gasMass` [kg]; NaN outside the table or next to a
/// mass without a stiffness.
double interpolateStiffness(const StiffnessTable& table, double gasMass);

/// RMS over the table's interior masses of the error of interpolating each from its two
/// neighbours with it left out [N/m] (the spacing doubled there: an upper bound of the
/// interpolation's own error); NaN with fewer than three usable masses.
double calcLeaveOneOutInterpolationError(const StiffnessTable& table);

/// How a candidate acts on a stiffness curve.
enum class CurveAction {
    MassOffset,  ///< the bag holds m - offset (flowmeter-bias): the dense curve re-read
    MassScale,   ///< the gas acts as m (T + offset) / T (gas-temperature, isothermal)
    Grid,        ///< a grid of the parameter, each a curve at the measured masses (bag-volume)
    Series,      ///< a compliance c in series with the block: k / (1 + c k)
    Gain         ///< the load cell reads (1 + g) times the force: (1 + g) k
};

/// One candidate effect made ready to act on a stiffness curve.
struct CurveCandidate {
    const Effect* effect = nullptr;  ///< one parameter
    CurveAction action = CurveAction::Series;
    /// MassOffset, MassScale: the dense curve; Grid: one table per value of `values`; Series,
    /// Gain: the model's curve at the measured masses.
    std::vector<StiffnessTable> tables;
    std::vector<double> values;    ///< Grid: the parameter's values [SI], increasing
    double roomTemperature = 0.0;  ///< MassScale: the gas temperature of the protocol [K]
    int simulations = 0;           ///< load tests its grid ran (not those found cached)
};

/// The model's stiffness with the candidate's parameter at `value` [SI], at `gasMass` [kg]
/// as the flowmeter read it; NaN where its grid gives none.
double predictStiffness(const CurveCandidate& candidate, double value, double gasMass);

/// The candidate's interpolation error [N/m]: the largest of its tables' (Grid: at each
/// measured mass, across the values); 0 for Series and Gain (no interpolation); NaN if none.
double calcInterpolationError(const CurveCandidate& candidate);

/// How an effect of the library acts on a stiffness curve: false, with why, for those that
/// do not (no channel of theirs, or a response that needs a full curve per trial value).
bool actsOnStiffnessCurve(const Effect& effect, CurveAction& action, std::string& whyNot);

/// The dense curve's masses [kg], increasing: every `step` from below the least used mass by
/// the widest shift the candidates reach (flowmeter-bias's offset bound, gas-temperature's
/// scale bound at `roomTemperature`) to above the largest by it, with the used masses
/// themselves added.
std::vector<double> makeShiftMasses(const std::vector<double>& usedMasses, double step,
                                    double roomTemperature);

/// An effect found not to act on the curve, and why.
struct NotApplicable {
    std::string effect;
    std::string why;
};

/// What the which part on a stiffness curve found; `which` is the tests' report (ranked
/// candidates with folds and held-out gaps, confusable, verdict), its pair stage not run.
struct StiffnessWhich {
    WhichReport which;
    std::vector<double> gasMasses;  ///< [kg] the masses used: measured and simulated both
    double range = 0.0;             ///< measured max - min over them [N/m] (normalises the gap)
    double rmse = 0.0;              ///< of measured - simulated over them [N/m]
    /// The stiffness channel's validation uncertainty [N/m] (the caller's: the spread of the
    /// model's own curve between two let-down histories), and what it is.
    double validation = 0.0;
    std::string validationWhat;
    bool withinValidation = false;  ///< rmse within twice the validation uncertainty
    std::vector<NotApplicable> notApplicable;
    /// Per candidate in the order given: its interpolation error [N/m] (calcInterpolationError).
    std::vector<std::pair<std::string, double>> interpolationErrors;
    /// Pairs of candidates that act on a stiffness curve as the same transformation, with why
    /// (the confusable rule may not name them when neither explains the gap).
    std::vector<std::pair<std::pair<std::string, std::string>, std::string>> identical;
};

/// Fits each candidate on the curve's masses leaving one out in turn (a scan of the
/// parameter's bounds, then a golden-section refinement; its standard deviation by
/// Gauss-Newton on the residuals' own variance) and judges it on the mass held out, as the
/// tests' which part does (gap = |measured - simulated| / range, beyond the validation
/// uncertainty; shrink; score less the penalty per parameter; verdict by judgeCandidates).
/// `validation` [N/m] as in StiffnessWhich.
/// @throws std::invalid_argument with fewer than three masses with both stiffnesses.
StiffnessWhich calibrateStiffnessCandidates(const StiffnessComparison& comparison,
                                            const std::vector<CurveCandidate>& candidates,
                                            double validation, const std::string& validationWhat,
                                            const CalibrationOptions& options);

}  // namespace diagnose
