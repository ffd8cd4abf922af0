// The "which" part of the diagnosis: each candidate effect calibrated with Ceres on the
// training tests (leave one gas mass out) and judged on the held-out test.
#include <diagnose/Diagnosis.h>

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>

#include "Format.h"

namespace diagnose {

namespace {

using detail::fmt;
using detail::kNaN;

// Simulated comparisons of one effect at trial parameter values, with the load tests of
// effects that change the bag cached by parameter value (shared by all folds).
class Evaluator {
  public:
    Evaluator(const MeasuredData& data, const bags::LoadTestOptions& base, const RigEffects& rig,
              const bags::LoadTestResult& baseResult, const Effect& effect,
              const Simulator& simulate)
        : m_data(data), m_base(base), m_rig(rig), m_baseResult(baseResult), m_effect(effect),
          m_simulate(simulate) {
        for (const MeasuredTest& t : data.tests) m_readings.push_back(t.gasMass);
    }

    /// x: scaled parameters, 1 + (v - lower) / (upper - lower) in [1, 2] (so Ceres' relative
    /// finite-difference step is a fixed share of the range).
    std::vector<double> toValues(const double* x) const {
        std::vector<double> v;
        for (size_t i = 0; i < m_effect.parameters.size(); ++i) {
            const EffectParameter& p = m_effect.parameters[i];
            const double xi = std::clamp(x[i], 1.0, 2.0);
            v.push_back(p.lower + (xi - 1.0) * (p.upper - p.lower));
        }
        return v;
    }

    /// The comparisons of all tests at scaled parameters x; false if the simulation failed.
    bool compare(const double* x, std::vector<TestComparison>& out) {
        const std::vector<double> v = toValues(x);
        RigEffects rig = m_rig;
        bags::LoadTestOptions o = m_base;
        applyEffect(m_effect, v, m_readings, rig, o);
        std::shared_ptr<const bags::LoadTestResult> r;
        if (m_effect.changesTheBag) {
            r = simulate(x, o);
            if (!r) return false;
        }
        const bags::LoadTestResult& res = r ? *r : m_baseResult;
        out.clear();
        for (size_t i = 0; i < m_data.tests.size(); ++i)
            out.push_back(compareTest(m_data.tests[i], int(i), res.curves[i], rig, o.loadingRate));
        return true;
    }

    /// Runs (or finds) the load test at these parameters; null if it failed.
    std::shared_ptr<const bags::LoadTestResult> simulate(const double* x,
                                                         const bags::LoadTestOptions& o) {
        std::vector<long> key;
        for (size_t i = 0; i < m_effect.parameters.size(); ++i)
            key.push_back(std::lround(x[i] * 1e6));
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            auto it = m_cache.find(key);
            if (it != m_cache.end()) return it->second;
        }
        std::shared_ptr<const bags::LoadTestResult> r;
        try {
            r = std::make_shared<bags::LoadTestResult>(m_simulate(o));
        } catch (const bags::NumericalError&) {
            r = nullptr;  // this trial value cannot be simulated: the fit steps back
        }
        std::lock_guard<std::mutex> lock(m_mutex);
        ++m_simulations;
        m_cache[key] = r;
        return r;
    }

    int getSimulations() const { return m_simulations; }
    const Effect& getEffect() const { return m_effect; }

  private:
    const MeasuredData& m_data;
    const bags::LoadTestOptions& m_base;
    RigEffects m_rig;
    const bags::LoadTestResult& m_baseResult;
    const Effect& m_effect;
    const Simulator& m_simulate;
    std::vector<double> m_readings;
    std::mutex m_mutex;
    std::map<std::vector<long>, std::shared_ptr<const bags::LoadTestResult>> m_cache;
    int m_simulations = 0;
};

// Which samples of each training test enter the fit: at most kMaxSamples per channel,
// evenly spaced, each channel of each test weighted equally.
constexpr size_t kMaxSamples = 120;

struct SampleSet {
    std::vector<int> tests;
    std::vector<std::vector<std::vector<size_t>>> index;  // [test][channel] -> samples
    int count = 0;
};

SampleSet makeSamples(const std::vector<TestComparison>& baseline, const std::vector<int>& tests) {
    SampleSet s;
    s.tests = tests;
    for (int t : tests) {
        std::vector<std::vector<size_t>> chans;
        for (const ChannelComparison& ch : baseline[t].channels) {
            std::vector<size_t> idx;
            if (ch.kind != ChannelKind::Mass) {
                const size_t n = ch.measured.size();
                const size_t step = std::max<size_t>(1, (n + kMaxSamples - 1) / kMaxSamples);
                for (size_t i = 0; i < n; i += step) idx.push_back(i);
            }
            s.count += static_cast<int>(idx.size());
            chans.push_back(idx);
        }
        s.index.push_back(chans);
    }
    return s;
}

// Normalised residuals of the sample set.
void fillResiduals(const std::vector<TestComparison>& c, const SampleSet& s, double forceRange,
                   double pressureRange, double* r) {
    int k = 0;
    for (size_t ti = 0; ti < s.tests.size(); ++ti) {
        const TestComparison& t = c[s.tests[ti]];
        for (size_t ch = 0; ch < t.channels.size(); ++ch) {
            const auto& idx = s.index[ti][ch];
            if (idx.empty()) continue;
            const ChannelComparison& cc = t.channels[ch];
            const double range = cc.kind == ChannelKind::Force ? forceRange : pressureRange;
            const double w = 1.0 / (range * std::sqrt(double(idx.size())));
            for (size_t i : idx) r[k++] = w * (cc.measured[i] - cc.simulated[i]);
        }
    }
}

struct Residual {
    Evaluator* eval;
    const SampleSet* samples;
    double forceRange, pressureRange;
    bool operator()(double const* const* x, double* r) const {
        std::vector<TestComparison> c;
        if (!eval->compare(x[0], c)) return false;
        fillResiduals(c, *samples, forceRange, pressureRange, r);
        return true;
    }
};

double calcCost(Evaluator& e, const double* x, const SampleSet& s, double fr, double pr) {
    std::vector<TestComparison> c;
    if (!e.compare(x, c)) return INFINITY;
    std::vector<double> r(s.count);
    fillResiduals(c, s, fr, pr, r.data());
    double sum = 0.0;
    for (double v : r) sum += v * v;
    return 0.5 * sum;
}

struct Fit {
    std::vector<double> x;      // scaled
    std::vector<double> sdX;    // scaled standard deviations (NaN if unknown)
    double cost = INFINITY;
};

// The grid's points (scaled), the tensor product of gridPoints per parameter.
std::vector<std::vector<double>> makeGrid(int params, int points) {
    std::vector<std::vector<double>> g = {{}};
    for (int p = 0; p < params; ++p) {
        std::vector<std::vector<double>> next;
        for (const auto& v : g)
            for (int i = 0; i < points; ++i) {
                auto w = v;
                w.push_back(1.0 + double(i) / double(points - 1));
                next.push_back(w);
            }
        g = next;
    }
    return g;
}

Fit calibrate(Evaluator& e, const std::vector<TestComparison>& baseline,
              const std::vector<int>& train, double fr, double pr, const CalibrationOptions& o,
              bool covariance) {
    const SampleSet s = makeSamples(baseline, train);
    const int np = static_cast<int>(e.getEffect().parameters.size());
    // Coarse scan (its simulations in parallel), then Ceres from the best point.
    const std::vector<std::vector<double>> grid = makeGrid(np, o.gridPoints);
    std::vector<double> costs(grid.size(), INFINITY);
    if (e.getEffect().changesTheBag) {
        std::vector<std::string> errors(grid.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(o.threads)
        for (int i = 0; i < static_cast<int>(grid.size()); ++i) {
            try {
                costs[i] = calcCost(e, grid[i].data(), s, fr, pr);
            } catch (const std::exception& ex) {
                errors[i] = ex.what();
            }
        }
        for (const std::string& err : errors)
            if (!err.empty()) throw std::runtime_error(err);  // e.g. an interrupt
    } else {
        for (size_t i = 0; i < grid.size(); ++i) costs[i] = calcCost(e, grid[i].data(), s, fr, pr);
    }
    const size_t best = std::min_element(costs.begin(), costs.end()) - costs.begin();
    Fit fit;
    fit.x = grid[best];
    fit.sdX.assign(np, kNaN);
    if (!std::isfinite(costs[best])) return fit;

    ceres::Problem problem;
    ceres::NumericDiffOptions nd;
    nd.relative_step_size = 0.01;
    auto* cf = new ceres::DynamicNumericDiffCostFunction<Residual, ceres::CENTRAL>(
        new Residual{&e, &s, fr, pr}, ceres::TAKE_OWNERSHIP, nd);
    cf->AddParameterBlock(np);
    cf->SetNumResiduals(s.count);
    problem.AddResidualBlock(cf, nullptr, fit.x.data());
    for (int i = 0; i < np; ++i) {
        problem.SetParameterLowerBound(fit.x.data(), i, 1.0);
        problem.SetParameterUpperBound(fit.x.data(), i, 2.0);
    }
    ceres::Solver::Options so;
    so.max_num_iterations = o.maxIterations;
    so.linear_solver_type = ceres::DENSE_QR;
    so.function_tolerance = 1e-4;
    so.parameter_tolerance = 1e-4;
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    fit.cost = summary.final_cost;
    if (!(fit.cost <= costs[best])) {
        fit.x = grid[best];
        fit.cost = costs[best];
    }
    if (covariance && s.count > np) {
        // Parameter uncertainty: (J^T J)^-1 scaled by the residual variance s^2 = 2 cost /
        // (n - p) (the residuals' own scatter, since the weights are ranges, not noise).
        ceres::Covariance::Options co;
        ceres::Covariance cov(co);
        std::vector<std::pair<const double*, const double*>> blocks = {{fit.x.data(), fit.x.data()}};
        if (cov.Compute(blocks, &problem)) {
            std::vector<double> c(np * np);
            cov.GetCovarianceBlock(fit.x.data(), fit.x.data(), c.data());
            const double s2 = 2.0 * fit.cost / double(s.count - np);
            for (int i = 0; i < np; ++i) fit.sdX[i] = std::sqrt(std::max(0.0, c[i * np + i] * s2));
        }
    }
    return fit;
}

}  // namespace

WhichReport calibrateCandidates(const MeasuredData& data, const bags::LoadTestOptions& base,
                                const RigEffects& baseRig, const bags::LoadTestResult& baseResult,
                                const std::vector<TestComparison>& baseline,
                                const WhereReport& where, const Simulator& simulate,
                                const CalibrationOptions& o) {
    const int n = static_cast<int>(data.tests.size());
    if (n < 2) throw std::invalid_argument("the calibration needs two tests or more (one held out)");
    double fr = 0.0, pr = 0.0, fu = 0.0, pu = 0.0;
    for (const ChannelSummary& c : where.channels) {
        if (c.channel == "force") fr = c.range, fu = c.validation;
        if (c.channel == "pressure") pr = c.range, pu = c.validation;
    }
    if (!(fr > 0.0) || !(pr > 0.0))
        throw std::invalid_argument("the measured force and pressure must vary to be compared");

    WhichReport report;
    for (const Effect& effect : getEffects()) {
        if (o.candidates.empty() ? !effect.inLibrary
                                 : std::find(o.candidates.begin(), o.candidates.end(),
                                             effect.name) == o.candidates.end())
            continue;
        Evaluator e(data, base, baseRig, baseResult, effect, simulate);
        CandidateResult cr;
        cr.effect = effect.name;
        double sumBefore = 0.0, sumAfter = 0.0, sumExcessBefore = 0.0, sumExcessAfter = 0.0;
        std::vector<TestComparison> heldAfter;  // each test as held out, with its fold's fit
        for (int h = 0; h < n; ++h) {
            std::vector<int> train;
            for (int i = 0; i < n; ++i)
                if (i != h) train.push_back(i);
            const Fit fit = calibrate(e, baseline, train, fr, pr, o, false);
            FoldResult f;
            f.heldOut = h;
            f.parameters = e.toValues(fit.x.data());
            f.before = calcGap(baseline, {h}, fr, pr);
            f.excessBefore = calcGap(baseline, {h}, fr, pr, fu, pu);
            std::vector<TestComparison> c;
            if (e.compare(fit.x.data(), c)) {
                f.after = calcGap(c, {h}, fr, pr);
                f.excessAfter = calcGap(c, {h}, fr, pr, fu, pu);
                heldAfter.push_back(c[h]);
            } else {
                f.after = f.excessAfter = INFINITY;
            }
            sumBefore += f.before;
            sumAfter += f.after;
            sumExcessBefore += f.excessBefore;
            sumExcessAfter += f.excessAfter;
            cr.folds.push_back(f);
        }
        std::vector<int> all(n);
        for (int i = 0; i < n; ++i) all[i] = i;
        const Fit full = calibrate(e, baseline, all, fr, pr, o, true);
        cr.parameters = e.toValues(full.x.data());
        if (!e.compare(full.x.data(), cr.fitted)) cr.fitted.clear();
        for (size_t i = 0; i < effect.parameters.size(); ++i)
            cr.parameterStdDev.push_back(full.sdX[i] *
                                         (effect.parameters[i].upper - effect.parameters[i].lower));
        cr.heldoutBefore = sumBefore / n;
        cr.heldoutAfter = sumAfter / n;
        cr.shrink = cr.heldoutBefore > 0.0 ? 1.0 - cr.heldoutAfter / cr.heldoutBefore : 0.0;
        cr.excessBefore = sumExcessBefore / n;
        cr.excessAfter = sumExcessAfter / n;
        cr.excessShrink = cr.excessBefore > 0.0 ? 1.0 - cr.excessAfter / cr.excessBefore : 0.0;
        cr.score = cr.excessShrink - o.parameterPenalty * double(effect.parameters.size());
        cr.simulations = e.getSimulations();
        cr.heldoutMetricsBefore = calcGapMetrics(baseline);
        if (static_cast<int>(heldAfter.size()) == n) cr.heldoutMetricsAfter = calcGapMetrics(heldAfter);
        report.candidates.push_back(cr);
    }
    std::stable_sort(report.candidates.begin(), report.candidates.end(),
                     [](const CandidateResult& a, const CandidateResult& b) {
                         return a.score > b.score;
                     });
    for (size_t i = 0; i < report.candidates.size(); ++i)
        for (size_t j = i + 1; j < report.candidates.size(); ++j) {
            const CandidateResult &a = report.candidates[i], &b = report.candidates[j];
            if (a.score >= o.explainThreshold && b.score >= o.explainThreshold &&
                std::fabs(a.excessShrink - b.excessShrink) < 0.1)
                report.confusable.push_back({a.effect, b.effect});
        }

    const CandidateResult* best = report.candidates.empty() ? nullptr : &report.candidates[0];
    if (where.withinValidation) {
        report.verdict = "none";
        report.reason = "every channel's RMSE is within twice its validation uncertainty "
                        "(sensor noise, numerical and input uncertainty)";
    } else if (best && best->score >= o.explainThreshold) {
        report.verdict = best->effect;
        report.reason = "it shrinks the held-out gap beyond the validation uncertainty by " +
                        fmt("%.0f", 100 * best->excessShrink) + " % (from " +
                        fmt("%.4f", best->excessBefore) + " to " + fmt("%.4f", best->excessAfter) +
                        "; the whole gap by " + fmt("%.0f", 100 * best->shrink) + " %, from " +
                        fmt("%.4f", best->heldoutBefore) + " to " + fmt("%.4f", best->heldoutAfter) + ")";
        // The effects these data cannot tell from the one named.
        std::string others;
        for (const auto& [a, b] : report.confusable)
            if (a == best->effect || b == best->effect)
                others += (others.empty() ? "" : ", ") + (a == best->effect ? b : a);
        if (!others.empty()) report.reason += "; confusable with " + others + " on these data";
    } else {
        report.verdict = "unexplained";
        report.reason = "no candidate shrinks the held-out gap beyond the validation "
                        "uncertainty by " +
                        fmt("%.0f", 100 * o.explainThreshold) + " % after its parameter penalty" +
                        (best ? " (best: " + best->effect + ", " +
                                    fmt("%.0f", 100 * best->excessShrink) + " %)"
                              : std::string());
    }
    return report;
}

}  // namespace diagnose
