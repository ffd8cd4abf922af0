// The which part on a measured stiffness curve: candidates read off the model's curve on
// grids, fitted leaving one gas mass out, ranked as the tests' candidates are.
#include <diagnose/Signatures.h>
#include <diagnose/StiffnessWhich.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "Format.h"

namespace diagnose {

namespace {

using detail::fmt;
using detail::kNaN;

// Points of the scan over a parameter's bounds before the golden-section refinement.
constexpr int kScanPoints = 401;

// The training masses' normalised residuals at `value`; false if the candidate gives no
// stiffness at one of them (the value cannot be read off the grid).
bool calcResiduals(const CurveCandidate& c, double value, const std::vector<double>& masses,
                   const std::vector<double>& measured, const std::vector<int>& train, double range,
                   std::vector<double>& r) {
    r.clear();
    for (int i : train) {
        const double k = predictStiffness(c, value, masses[i]);
        if (!std::isfinite(k)) return false;
        r.push_back((measured[i] - k) / range);
    }
    return true;
}

double calcCost(const CurveCandidate& c, double value, const std::vector<double>& masses,
                const std::vector<double>& measured, const std::vector<int>& train, double range) {
    std::vector<double> r;
    if (!calcResiduals(c, value, masses, measured, train, range, r)) return INFINITY;
    double s = 0.0;
    for (double v : r) s += v * v;
    return 0.5 * s;
}

struct CurveFit {
    double value = 0.0;
    double stdDev = kNaN;
};

// The least-squares value on the training masses: the best of a scan of the bounds, refined
// by golden section between its neighbours (the interpolated cost is piecewise smooth).
CurveFit fitCandidate(const CurveCandidate& c, const std::vector<double>& masses,
                      const std::vector<double>& measured, const std::vector<int>& train,
                      double range) {
    const EffectParameter& p = c.effect->parameters.front();
    const double lo = p.lower, hi = p.upper, h = (hi - lo) / (kScanPoints - 1);
    auto cost = [&](double v) { return calcCost(c, v, masses, measured, train, range); };
    int best = -1;
    double bestCost = INFINITY;
    // The model as it is (0) wins ties: an effect is not taken where it changes nothing.
    const int zero = lo <= 0.0 && hi >= 0.0 ? static_cast<int>(std::lround((0.0 - lo) / h)) : -1;
    for (int i = 0; i < kScanPoints; ++i) {
        const double v = i == zero ? 0.0 : lo + i * h;
        const double f = cost(v);
        if (f < bestCost || (f == bestCost && i == zero)) best = i, bestCost = f;
    }
    CurveFit fit;
    if (best < 0) {
        fit.value = zero >= 0 ? 0.0 : lo;
        return fit;
    }
    fit.value = best == zero ? 0.0 : lo + best * h;
    double a = std::max(lo, fit.value - h), b = std::min(hi, fit.value + h);
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = cost(x1), f2 = cost(x2);
    for (int it = 0; it < 60 && b - a > 1e-9 * (hi - lo); ++it) {
        if (f1 <= f2)
            b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = cost(x1);
        else
            a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = cost(x2);
    }
    // Taken only for a real gain: on a flat cost (the model as it is, exactly) roundoff would
    // move the value off the scan's point.
    const double xr = 0.5 * (a + b);
    if (cost(xr) < bestCost - 1e-12) fit.value = xr;

    // Gauss-Newton's variance, J^T J of the residuals by central difference, scaled by the
    // residuals' own variance (the weights are the range, not a noise).
    std::vector<double> r0, rp, rm;
    const double d = 1e-3 * (hi - lo);
    const double vp = std::min(hi, fit.value + d), vm = std::max(lo, fit.value - d);
    const int n = static_cast<int>(train.size());
    if (n > 1 && calcResiduals(c, fit.value, masses, measured, train, range, r0) &&
        calcResiduals(c, vp, masses, measured, train, range, rp) &&
        calcResiduals(c, vm, masses, measured, train, range, rm)) {
        double jj = 0.0, rr = 0.0;
        for (int i = 0; i < n; ++i) {
            const double j = (rp[i] - rm[i]) / (vp - vm);
            jj += j * j, rr += r0[i] * r0[i];
        }
        if (jj > 0.0) fit.stdDev = std::sqrt(rr / double(n - 1) / jj);
    }
    return fit;
}

// The gap over some masses: RMS of measured - simulated, less the validation uncertainty
// (squared, at least 0: beyond it), over the range.
double calcCurveGap(const std::vector<double>& errors, double range, double uncertainty) {
    if (errors.empty()) return 0.0;
    double s = 0.0;
    for (double e : errors) s += e * e;
    return std::sqrt(std::max(0.0, s / double(errors.size()) - uncertainty * uncertainty)) / range;
}

}  // namespace

double interpolateStiffness(const StiffnessTable& t, double m) {
    const auto& x = t.gasMass;
    if (x.empty() || !(m >= x.front() - 1e-12) || !(m <= x.back() + 1e-12)) return kNaN;
    size_t j = std::upper_bound(x.begin(), x.end(), m) - x.begin();
    if (j == 0) j = 1;
    if (j >= x.size()) j = x.size() - 1;
    if (x.size() == 1) return std::fabs(m - x[0]) <= 1e-12 ? t.stiffness[0] : kNaN;
    const double w = (m - x[j - 1]) / (x[j] - x[j - 1]);
    // A node itself needs only its own value.
    if (std::fabs(m - x[j - 1]) <= 1e-12) return t.stiffness[j - 1];
    if (std::fabs(m - x[j]) <= 1e-12) return t.stiffness[j];
    return (1.0 - w) * t.stiffness[j - 1] + w * t.stiffness[j];
}

double calcLeaveOneOutInterpolationError(const StiffnessTable& t) {
    double s = 0.0;
    int n = 0;
    for (size_t j = 1; j + 1 < t.gasMass.size(); ++j) {
        const double k0 = t.stiffness[j - 1], k1 = t.stiffness[j], k2 = t.stiffness[j + 1];
        if (!std::isfinite(k0) || !std::isfinite(k1) || !std::isfinite(k2)) continue;
        const double w = (t.gasMass[j] - t.gasMass[j - 1]) / (t.gasMass[j + 1] - t.gasMass[j - 1]);
        const double e = k1 - ((1.0 - w) * k0 + w * k2);
        s += e * e, ++n;
    }
    return n ? std::sqrt(s / n) : kNaN;
}

double predictStiffness(const CurveCandidate& c, double v, double m) {
    switch (c.action) {
        case CurveAction::MassOffset:
            return interpolateStiffness(c.tables.at(0), m - v);
        case CurveAction::MassScale:
            return interpolateStiffness(c.tables.at(0),
                                        m * (c.roomTemperature + v) / c.roomTemperature);
        case CurveAction::Series: {
            const double k = interpolateStiffness(c.tables.at(0), m);
            return k / (1.0 + v * k);
        }
        case CurveAction::Gain:
            return (1.0 + v) * interpolateStiffness(c.tables.at(0), m);
        case CurveAction::Grid: {
            const auto& x = c.values;
            if (x.empty() || !(v >= x.front() - 1e-12) || !(v <= x.back() + 1e-12)) return kNaN;
            size_t j = std::upper_bound(x.begin(), x.end(), v) - x.begin();
            if (x.size() == 1) return interpolateStiffness(c.tables[0], m);
            j = std::clamp<size_t>(j, 1, x.size() - 1);
            if (std::fabs(v - x[j - 1]) <= 1e-12) return interpolateStiffness(c.tables[j - 1], m);
            if (std::fabs(v - x[j]) <= 1e-12) return interpolateStiffness(c.tables[j], m);
            const double w = (v - x[j - 1]) / (x[j] - x[j - 1]);
            return (1.0 - w) * interpolateStiffness(c.tables[j - 1], m) +
                   w * interpolateStiffness(c.tables[j], m);
        }
    }
    return kNaN;
}

double calcInterpolationError(const CurveCandidate& c) {
    if (c.action == CurveAction::Series || c.action == CurveAction::Gain) return 0.0;
    if (c.action != CurveAction::Grid) return calcLeaveOneOutInterpolationError(c.tables.at(0));
    // Across the values at each mass of the first table.
    double worst = kNaN;
    if (c.tables.empty()) return worst;
    for (double m : c.tables[0].gasMass) {
        StiffnessTable across;
        for (size_t j = 0; j < c.values.size(); ++j) {
            across.gasMass.push_back(c.values[j]);
            across.stiffness.push_back(interpolateStiffness(c.tables[j], m));
        }
        const double e = calcLeaveOneOutInterpolationError(across);
        if (std::isfinite(e) && !(e <= worst)) worst = e;
    }
    return worst;
}

bool actsOnStiffnessCurve(const Effect& e, CurveAction& action, std::string& whyNot) {
    const std::string& n = e.name;
    if (n == "flowmeter-bias")
        action = CurveAction::MassOffset;
    else if (n == "gas-temperature")
        action = CurveAction::MassScale;
    else if (n == "bag-volume")
        action = CurveAction::Grid;
    else if (n == "machine-compliance" || n == "bed-compliance")
        action = CurveAction::Series;
    else if (n == "load-cell-gain")
        action = CurveAction::Gain;
    else {
        if (n == "pressure-sensor")
            whyNot = "it acts on the pressure channel only; a stiffness curve has none";
        else if (n == "viscoelasticity" || n == "leakage" || n == "heat-exchange")
            whyNot =
                "its signatures are over time (the loop, the rate, the pressure's fall); a "
                "loading-only stiffness at one rate holds none of them, and each trial value "
                "would be a full curve";
        else
            whyNot =
                "it changes the bag's response under the block in a way no grid of one "
                "curve re-reads: each trial value would be a full curve (not run on a "
                "stiffness curve)";
        return false;
    }
    return true;
}

std::vector<double> makeShiftMasses(const std::vector<double>& used, double step,
                                    double roomTemperature) {
    if (used.empty() || !(step > 0.0)) throw std::invalid_argument("no masses or no step");
    const Effect& fm = *findEffect("flowmeter-bias");
    const Effect& gt = *findEffect("gas-temperature");
    const double lo0 = *std::min_element(used.begin(), used.end());
    const double hi0 = *std::max_element(used.begin(), used.end());
    const double scaleLo = (roomTemperature + gt.parameters[0].lower) / roomTemperature;
    const double scaleHi = (roomTemperature + gt.parameters[0].upper) / roomTemperature;
    const double lo = std::min(lo0 - fm.parameters[0].upper, lo0 * scaleLo);
    const double hi = std::max(hi0 - fm.parameters[0].lower, hi0 * scaleHi);
    std::vector<double> m = used;
    // On multiples of the step, so that the grid does not move with the data's masses.
    for (long i = static_cast<long>(std::floor(lo / step + 1e-9));
         i <= static_cast<long>(std::ceil(hi / step - 1e-9)); ++i)
        if (i * step > 0.0) m.push_back(i * step);
    std::sort(m.begin(), m.end());
    std::vector<double> out;
    for (double x : m)
        if (out.empty() || x - out.back() > 1e-3 * step) out.push_back(x);
    return out;
}

StiffnessWhich calibrateStiffnessCandidates(const StiffnessComparison& cmp,
                                            const std::vector<CurveCandidate>& candidates,
                                            double validation, const std::string& validationWhat,
                                            const CalibrationOptions& o) {
    StiffnessWhich out;
    std::vector<double> measured, before;
    for (const StiffnessPoint& p : cmp.points)
        if (std::isfinite(p.simulated) && std::isfinite(p.measured)) {
            out.gasMasses.push_back(p.gasMass);
            measured.push_back(p.measured);
            before.push_back(p.simulated);
        }
    const int n = static_cast<int>(out.gasMasses.size());
    if (n < 3)
        throw std::invalid_argument(
            "the stiffness curve's which part needs three gas masses or more with both a "
            "measured and a simulated stiffness (one held out, a fit on two); there are " +
            std::to_string(n));
    out.range = *std::max_element(measured.begin(), measured.end()) -
                *std::min_element(measured.begin(), measured.end());
    if (!(out.range > 0.0))
        throw std::invalid_argument("the measured stiffness must vary to be compared");
    double s2 = 0.0;
    for (int i = 0; i < n; ++i) s2 += (measured[i] - before[i]) * (measured[i] - before[i]);
    out.rmse = std::sqrt(s2 / n);
    out.validation = validation;
    out.validationWhat = validationWhat;
    out.withinValidation = out.rmse <= kExplainedMultiple * validation;

    for (const CurveCandidate& c : candidates) {
        if (!c.effect || c.effect->parameters.size() != 1)
            throw std::invalid_argument("a stiffness curve's candidate has one parameter");
        out.interpolationErrors.push_back({c.effect->name, calcInterpolationError(c)});
        CandidateResult cr;
        cr.effect = c.effect->name;
        if (std::isfinite(out.interpolationErrors.back().second))
            cr.predictionUncertainty = out.interpolationErrors.back().second;
        cr.simulations = c.simulations;
        double sb = 0.0, sa = 0.0, seb = 0.0, sea = 0.0;
        std::vector<double> heldMeasured, heldAfter;
        for (int h = 0; h < n; ++h) {
            std::vector<int> train;
            for (int i = 0; i < n; ++i)
                if (i != h) train.push_back(i);
            const CurveFit fit = fitCandidate(c, out.gasMasses, measured, train, out.range);
            FoldResult f;
            f.heldOut = h;
            f.parameters = {fit.value};
            const double eb = measured[h] - before[h];
            const double after = predictStiffness(c, fit.value, out.gasMasses[h]);
            f.before = calcCurveGap({eb}, out.range, 0.0);
            f.excessBefore = calcCurveGap({eb}, out.range, validation);
            if (std::isfinite(after)) {
                f.after = calcCurveGap({measured[h] - after}, out.range, 0.0);
                f.excessAfter = calcCurveGap({measured[h] - after}, out.range, validation);
                heldMeasured.push_back(measured[h]);
                heldAfter.push_back(after);
            } else {
                f.after = f.excessAfter = INFINITY;  // the held-out mass off the candidate's grid
            }
            sb += f.before, sa += f.after, seb += f.excessBefore, sea += f.excessAfter;
            cr.folds.push_back(f);
        }
        std::vector<int> all(n);
        for (int i = 0; i < n; ++i) all[i] = i;
        const CurveFit full = fitCandidate(c, out.gasMasses, measured, all, out.range);
        cr.parameters = {full.value};
        cr.parameterStdDev = {full.stdDev};
        cr.heldoutBefore = sb / n, cr.heldoutAfter = sa / n;
        cr.shrink = cr.heldoutBefore > 0.0 ? 1.0 - cr.heldoutAfter / cr.heldoutBefore : 0.0;
        cr.excessBefore = seb / n, cr.excessAfter = sea / n;
        cr.excessShrink = cr.excessBefore > 0.0 ? 1.0 - cr.excessAfter / cr.excessBefore : 0.0;
        cr.score = cr.excessShrink - o.parameterPenalty * 1.0;
        cr.heldoutMetricsBefore = {calcPairedMetrics("stiffness", measured, before)};
        if (static_cast<int>(heldAfter.size()) == n)
            cr.heldoutMetricsAfter = {calcPairedMetrics("stiffness", heldMeasured, heldAfter)};
        out.which.candidates.push_back(cr);
    }
    // Candidates that are one transformation of the curve whatever the data.
    auto has = [&](const std::string& e) {
        for (const CurveCandidate& c : candidates)
            if (c.effect->name == e) return true;
        return false;
    };
    if (has("machine-compliance") && has("bed-compliance"))
        out.identical.push_back({{"machine-compliance", "bed-compliance"},
                                 "both a compliance in series with the block: k / (1 + c k)"});
    out.which.pairStageReason = "not run: a stiffness curve's candidates are fitted one at a time";
    const ChannelUncertainties uncertainties{{"stiffness", out.validation}};
    judgeCandidates(out.which, out.withinValidation,
                    "the stiffness's RMSE (" + fmt("%.3g N/mm", out.rmse * 1e-3) +
                        ") is within twice its validation uncertainty (" +
                        fmt("%.3g N/mm", validation * 1e-3) + ": " + validationWhat + ")",
                    uncertainties, o);
    // Every candidate acts at each mass through the mass only, so a scale of the gas mass is a
    // flowmeter gain: name it, since the library has no gain of the flowmeter to be confusable
    // with.
    if (has("gas-temperature"))
        out.identical.push_back({{"gas-temperature", "a flowmeter gain"},
                                 "isothermal gas acts through m T: a temperature offset dT is a "
                                 "gas-mass scale of dT / T, which a flowmeter reading its mass "
                                 "by a gain would make too (the library has no such gain)"});
    // A verdict at its parameter's bound explains what it does only as far as the bound lets
    // it: the data ask for more.
    if (!out.which.verdictEffects.empty()) {
        const CandidateResult& best = out.which.candidates.front();
        const EffectParameter& p = findEffect(best.effect)->parameters[0];
        const double v = best.parameters[0], tol = 1e-6 * (p.upper - p.lower);
        if (v <= p.lower + tol || v >= p.upper - tol)
            out.which.reason += "; fitted at its bound (" + p.name + " " +
                                fmt("%g", v / p.siPerUnit) + (p.unit.empty() ? "" : " " + p.unit) +
                                "): the data ask for more than its physical bounds allow";
    }
    for (const auto& [pair, why] : out.identical)
        if (out.which.verdict == pair.first || out.which.verdict == pair.second)
            out.which.reason += "; on a stiffness curve it is the same as " +
                                (out.which.verdict == pair.first ? pair.second : pair.first) +
                                " (" + why + ")";
    qualifyVerdict(out.which, uncertainties, getEffects());
    return out;
}

}  // namespace diagnose
