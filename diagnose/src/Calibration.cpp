// The "which" part of the diagnosis: each candidate effect calibrated with Ceres on the
// training tests (leave one gas mass out) and judged on the held-out test.
#include <diagnose/Diagnosis.h>

#include <ceres/ceres.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>

#include "Format.h"

namespace diagnose {

namespace {

using detail::fmt;
using detail::kNaN;

// Load tests at trial values, shared by every candidate and pair: keyed by the effects that
// change the bag and their scaled values, so that a pair whose other member changes only the
// instruments reuses the simulations of its member that changes the bag (and all folds share
// them).
class SimulationCache {
  public:
    bool find(const std::string& key, std::shared_ptr<const bags::LoadTestResult>& r) {
        std::lock_guard<std::mutex> lock(m_mutex);
        auto it = m_map.find(key);
        if (it == m_map.end()) return false;
        r = it->second;
        return true;
    }
    void put(const std::string& key, std::shared_ptr<const bags::LoadTestResult> r) {
        std::lock_guard<std::mutex> lock(m_mutex);
        m_map[key] = std::move(r);
    }

  private:
    std::mutex m_mutex;
    std::map<std::string, std::shared_ptr<const bags::LoadTestResult>> m_map;
};

// Simulated comparisons with one effect, or two at once, at trial parameter values (the
// effects' parameters in order, the first's then the second's).
class Evaluator {
  public:
    Evaluator(const MeasuredData& data, const bags::LoadTestOptions& base, const RigEffects& rig,
              const bags::LoadTestResult& baseResult, std::vector<const Effect*> effects,
              const Simulator& simulate, SimulationCache& cache)
        : m_data(data),
          m_base(base),
          m_rig(rig),
          m_baseResult(baseResult),
          m_effects(std::move(effects)),
          m_simulate(simulate),
          m_cache(cache) {
        for (const MeasuredTest& t : data.tests) m_readings.push_back(t.gasMass);
        for (const Effect* e : m_effects)
            for (const EffectParameter& p : e->parameters) m_parameters.push_back(&p);
    }

    int getParameterCount() const { return static_cast<int>(m_parameters.size()); }
    const EffectParameter& getParameter(int i) const { return *m_parameters[i]; }
    bool changesTheBag() const {
        for (const Effect* e : m_effects)
            if (e->changesTheBag) return true;
        return false;
    }

    /// x: scaled parameters, 1 + (v - lower) / (upper - lower) in [1, 2] (so Ceres' relative
    /// finite-difference step is a fixed share of the range).
    std::vector<double> toValues(const double* x) const {
        std::vector<double> v;
        for (size_t i = 0; i < m_parameters.size(); ++i) {
            const EffectParameter& p = *m_parameters[i];
            const double xi = std::clamp(x[i], 1.0, 2.0);
            v.push_back(p.lower + (xi - 1.0) * (p.upper - p.lower));
        }
        return v;
    }
    /// The scaled parameters of values [SI] (toValues' inverse), from parameter `from` on.
    std::vector<double> toScaled(const std::vector<double>& v, size_t from = 0) const {
        std::vector<double> x;
        for (size_t i = 0; i < v.size(); ++i) {
            const EffectParameter& p = *m_parameters[from + i];
            x.push_back(1.0 + (v[i] - p.lower) / (p.upper - p.lower));
        }
        return x;
    }

    /// The comparisons of all tests at scaled parameters x; false if the simulation failed.
    bool compare(const double* x, std::vector<TestComparison>& out) {
        const std::vector<double> v = toValues(x);
        RigEffects rig = m_rig;
        bags::LoadTestOptions o = m_base;
        size_t k = 0;
        for (const Effect* e : m_effects) {
            const size_t np = e->parameters.size();
            applyEffect(*e, std::vector<double>(v.begin() + k, v.begin() + k + np), m_readings, rig,
                        o);
            k += np;
        }
        std::shared_ptr<const bags::LoadTestResult> r;
        if (changesTheBag()) {
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
        // Only the effects that change the bag make the simulation.
        std::string key;
        size_t k = 0;
        for (const Effect* e : m_effects) {
            if (e->changesTheBag) {
                key += e->name + ":";
                for (size_t i = 0; i < e->parameters.size(); ++i)
                    key += std::to_string(std::lround(x[k + i] * 1e6)) + ",";
                key += "|";
            }
            k += e->parameters.size();
        }
        std::shared_ptr<const bags::LoadTestResult> r;
        if (m_cache.find(key, r)) return r;
        try {
            r = std::make_shared<bags::LoadTestResult>(m_simulate(o));
        } catch (const bags::NumericalError&) {
            r = nullptr;  // this trial value cannot be simulated: the fit steps back
        }
        m_simulations.fetch_add(1);
        m_cache.put(key, r);
        return r;
    }

    int getSimulations() const { return m_simulations.load(); }

  private:
    const MeasuredData& m_data;
    const bags::LoadTestOptions& m_base;
    RigEffects m_rig;
    const bags::LoadTestResult& m_baseResult;
    std::vector<const Effect*> m_effects;
    std::vector<const EffectParameter*> m_parameters;
    const Simulator& m_simulate;
    SimulationCache& m_cache;
    std::vector<double> m_readings;
    std::atomic<int> m_simulations{0};
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
void fillResiduals(const std::vector<TestComparison>& c, const SampleSet& s, const GapScale& g,
                   double* r) {
    int k = 0;
    for (size_t ti = 0; ti < s.tests.size(); ++ti) {
        const TestComparison& t = c[s.tests[ti]];
        for (size_t ch = 0; ch < t.channels.size(); ++ch) {
            const auto& idx = s.index[ti][ch];
            if (idx.empty()) continue;
            const ChannelComparison& cc = t.channels[ch];
            const double range = g.getRange(cc.kind);
            if (!(range > 0.0)) {  // a flat channel is not fitted (as it is not in the gap)
                for (size_t i = 0; i < idx.size(); ++i) r[k++] = 0.0;
                continue;
            }
            const double w = 1.0 / (range * std::sqrt(double(idx.size())));
            for (size_t i : idx) r[k++] = w * (cc.measured[i] - cc.simulated[i]);
        }
    }
}

struct Residual {
    Evaluator* eval;
    const SampleSet* samples;
    GapScale scale;
    bool operator()(double const* const* x, double* r) const {
        std::vector<TestComparison> c;
        if (!eval->compare(x[0], c)) return false;
        fillResiduals(c, *samples, scale, r);
        return true;
    }
};

// The residuals and their central-difference Jacobian, as Ceres' numeric differentiation
// (ceres::CENTRAL) makes them, to the bit: the step max(sqrt(eps), relative x |x_j|), the
// column (r(x + h e_j) - r(x - h e_j)) (1 / h / 2). Its 2 p + 1 evaluations run `threads` at
// a time when the effects change the bag (each a load test); the fit is the same at any
// number of threads.
class ParallelCentralCost : public ceres::CostFunction {
  public:
    ParallelCentralCost(Evaluator& e, const SampleSet& s, const GapScale& g, int threads,
                        double relativeStep)
        : m_residual{&e, &s, g},
          m_threads(e.changesTheBag() ? std::max(1, threads) : 1),
          m_relativeStep(relativeStep) {
        mutable_parameter_block_sizes()->push_back(e.getParameterCount());
        set_num_residuals(s.count);
    }

    bool Evaluate(double const* const* parameters, double* residuals,
                  double** jacobians) const override {
        const int np = parameter_block_sizes()[0], nr = num_residuals();
        const double* x = parameters[0];
        if (!jacobians || !jacobians[0]) return evaluateAt(x, residuals);
        // Evaluation k: 0 at x, 2 j + 1 at x + h_j e_j, 2 j + 2 at x - h_j e_j.
        const int n = 2 * np + 1;
        std::vector<std::vector<double>> r(n, std::vector<double>(nr));
        std::vector<double> h(np);
        for (int j = 0; j < np; ++j)
            h[j] = std::max(std::sqrt(std::numeric_limits<double>::epsilon()),
                            std::abs(x[j]) * m_relativeStep);
        std::vector<char> ok(n, 0);
        std::vector<std::string> errors(n);
#pragma omp parallel for schedule(dynamic, 1) num_threads(m_threads)
        for (int k = 0; k < n; ++k) {
            try {
                std::vector<double> xk(x, x + np);
                if (k > 0) xk[(k - 1) / 2] += (k % 2 ? 1.0 : -1.0) * h[(k - 1) / 2];
                ok[k] = evaluateAt(xk.data(), r[k].data());
            } catch (const std::exception& ex) {
                errors[k] = ex.what();
            }
        }
        for (const std::string& err : errors)
            if (!err.empty()) throw std::runtime_error(err);  // e.g. an interrupt
        if (!ok[0]) return false;
        std::copy(r[0].begin(), r[0].end(), residuals);
        for (int j = 0; j < np; ++j) {
            if (!ok[2 * j + 1] || !ok[2 * j + 2]) return false;
            const double scale = 1.0 / h[j] / 2;
            for (int i = 0; i < nr; ++i)  // row-major, as Ceres stores a block's Jacobian
                jacobians[0][i * np + j] = (r[2 * j + 1][i] - r[2 * j + 2][i]) * scale;
        }
        return true;
    }

  private:
    bool evaluateAt(const double* x, double* r) const {
        const double* p[1] = {x};
        return m_residual(p, r);
    }
    Residual m_residual;
    int m_threads;
    double m_relativeStep;
};

double calcCost(Evaluator& e, const double* x, const SampleSet& s, const GapScale& g) {
    std::vector<TestComparison> c;
    if (!e.compare(x, c)) return INFINITY;
    std::vector<double> r(s.count);
    fillResiduals(c, s, g, r.data());
    double sum = 0.0;
    for (double v : r) sum += v * v;
    return 0.5 * sum;
}

struct Fit {
    std::vector<double> x;    // scaled
    std::vector<double> sdX;  // scaled standard deviations (NaN if unknown)
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

// The least-squares cost at each of the points (scaled), their simulations run at once when
// the effects change the bag.
std::vector<double> calcScanCosts(Evaluator& e, const std::vector<std::vector<double>>& points,
                                  const SampleSet& s, const GapScale& g,
                                  const CalibrationOptions& o) {
    std::vector<double> costs(points.size(), INFINITY);
    if (e.changesTheBag()) {
        std::vector<std::string> errors(points.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(o.threads)
        for (int i = 0; i < static_cast<int>(points.size()); ++i) {
            try {
                costs[i] = calcCost(e, points[i].data(), s, g);
            } catch (const std::exception& ex) {
                errors[i] = ex.what();
            }
        }
        for (const std::string& err : errors)
            if (!err.empty()) throw std::runtime_error(err);  // e.g. an interrupt
    } else {
        for (size_t i = 0; i < points.size(); ++i) costs[i] = calcCost(e, points[i].data(), s, g);
    }
    return costs;
}

// Fits the parameters on the training tests: the best of the start points (scaled; empty:
// the coarse grid of gridPoints per parameter), then Ceres from there.
Fit calibrate(Evaluator& e, const std::vector<TestComparison>& baseline,
              const std::vector<int>& train, const GapScale& g, const CalibrationOptions& o,
              bool covariance, const std::vector<std::vector<double>>& starts = {}) {
    const SampleSet s = makeSamples(baseline, train);
    const int np = e.getParameterCount();
    const std::vector<std::vector<double>> grid =
        starts.empty() ? makeGrid(np, o.gridPoints) : starts;
    const std::vector<double> costs = calcScanCosts(e, grid, s, g, o);
    const size_t best = std::min_element(costs.begin(), costs.end()) - costs.begin();
    Fit fit;
    fit.x = grid[best];
    fit.sdX.assign(np, kNaN);
    if (!std::isfinite(costs[best])) return fit;

    ceres::Problem problem;
    auto* cf = new ParallelCentralCost(e, s, g, o.threads, 0.01);
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
        std::vector<std::pair<const double*, const double*>> blocks = {
            {fit.x.data(), fit.x.data()}};
        if (cov.Compute(blocks, &problem)) {
            std::vector<double> c(np * np);
            cov.GetCovarianceBlock(fit.x.data(), fit.x.data(), c.data());
            const double s2 = 2.0 * fit.cost / double(s.count - np);
            for (int i = 0; i < np; ++i) fit.sdX[i] = std::sqrt(std::max(0.0, c[i * np + i] * s2));
        }
    }
    return fit;
}

// Fits the evaluator's parameters with leave-one-test-out folds and on all tests, and measures
// the held-out gap before and after. `starts(h)`: the scan's start points for the fit without
// test h (h = -1: all tests); empty, the coarse grid.
CandidateResult calibrateCandidate(
    Evaluator& e, const std::string& name, int n, const std::vector<TestComparison>& baseline,
    const GapScale& g, const CalibrationOptions& o,
    const std::function<std::vector<std::vector<double>>(int)>& starts) {
    CandidateResult cr;
    cr.effect = name;
    double sumBefore = 0.0, sumAfter = 0.0, sumExcessBefore = 0.0, sumExcessAfter = 0.0;
    std::vector<TestComparison> heldAfter;  // each test as held out, with its fold's fit
    for (int h = 0; h < n; ++h) {
        std::vector<int> train;
        for (int i = 0; i < n; ++i)
            if (i != h) train.push_back(i);
        const Fit fit = calibrate(e, baseline, train, g, o, false, starts(h));
        FoldResult f;
        f.heldOut = h;
        f.parameters = e.toValues(fit.x.data());
        f.before = calcGap(baseline, {h}, g);
        f.excessBefore = calcGap(baseline, {h}, g, true);
        std::vector<TestComparison> c;
        if (e.compare(fit.x.data(), c)) {
            f.after = calcGap(c, {h}, g);
            f.excessAfter = calcGap(c, {h}, g, true);
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
    const Fit full = calibrate(e, baseline, all, g, o, true, starts(-1));
    cr.parameters = e.toValues(full.x.data());
    if (!e.compare(full.x.data(), cr.fitted)) cr.fitted.clear();
    const int np = e.getParameterCount();
    for (int i = 0; i < np; ++i)
        cr.parameterStdDev.push_back(full.sdX[i] *
                                     (e.getParameter(i).upper - e.getParameter(i).lower));
    cr.heldoutBefore = sumBefore / n;
    cr.heldoutAfter = sumAfter / n;
    cr.shrink = cr.heldoutBefore > 0.0 ? 1.0 - cr.heldoutAfter / cr.heldoutBefore : 0.0;
    cr.excessBefore = sumExcessBefore / n;
    cr.excessAfter = sumExcessAfter / n;
    cr.excessShrink = cr.excessBefore > 0.0 ? 1.0 - cr.excessAfter / cr.excessBefore : 0.0;
    cr.score = cr.excessShrink - o.parameterPenalty * double(np);
    cr.simulations = e.getSimulations();
    cr.heldoutMetricsBefore = calcGapMetrics(baseline);
    if (static_cast<int>(heldAfter.size()) == n) cr.heldoutMetricsAfter = calcGapMetrics(heldAfter);
    return cr;
}

const CandidateResult* findSingle(const WhichReport& r, const std::string& name) {
    for (const CandidateResult& c : r.candidates)
        if (c.effect == name) return &c;
    return nullptr;
}

bool areConfusable(const WhichReport& r, const std::string& a, const std::string& b) {
    for (const auto& [x, y] : r.confusable)
        if ((x == a && y == b) || (x == b && y == a)) return true;
    return false;
}

// The points a pair's scan starts from: the first member at its single fit (`first`, SI) with
// the second over its coarse grid, and with the second at its own single fit.
std::vector<std::vector<double>> makePairStarts(const Evaluator& e,
                                                const std::vector<double>& first,
                                                const std::vector<double>& second, int gridPoints) {
    const std::vector<double> x1 = e.toScaled(first);
    std::vector<std::vector<double>> starts;
    auto add = [&](const std::vector<double>& x2) {
        std::vector<double> x = x1;
        x.insert(x.end(), x2.begin(), x2.end());
        starts.push_back(x);
    };
    for (const std::vector<double>& x2 : makeGrid(static_cast<int>(second.size()), gridPoints))
        add(x2);
    add(e.toScaled(second, first.size()));
    return starts;
}

// Judges a fitted pair against the singles it must beat (the best single, and each member
// alone): the share of the held-out gap beyond the uncertainty that single leaves which the
// pair removes, less the penalty per parameter the pair adds; the least of these is its gain.
void calcPairGain(PairResult& p, const WhichReport& r, const CalibrationOptions& o) {
    const CandidateResult& pair = p.result;
    p.gain = INFINITY;
    for (const CandidateResult* s :
         {&r.candidates.front(), findSingle(r, p.first), findSingle(r, p.second)}) {
        if (!s) continue;
        const double extra =
            o.parameterPenalty *
            std::max<double>(0.0, double(pair.parameters.size()) - double(s->parameters.size()));
        const double shrink = s->excessAfter > 0.0 && std::isfinite(pair.excessAfter)
                                  ? 1.0 - pair.excessAfter / s->excessAfter
                                  : -INFINITY;
        if (shrink - extra < p.gain) {
            p.gain = shrink - extra;
            p.against = s->effect;
            p.singleExcessAfter = s->excessAfter;
            p.shrinkOverSingle = shrink;
            p.extraPenalty = extra;
        }
    }
    const bool gains = p.gain >= o.explainThreshold, explains = pair.score >= o.explainThreshold;
    p.accepted = gains && explains;
    p.why = "removes " + fmt("%.0f", 100 * p.shrinkOverSingle) +
            " % of the held-out gap beyond "
            "the uncertainty that " +
            p.against + " alone leaves (" + fmt("%.4f", p.singleExcessAfter) + " -> " +
            fmt("%.4f", pair.excessAfter) + "), less " + fmt("%.2f", p.extraPenalty) +
            " for the parameters it adds: " + fmt("%.3f", p.gain) + (gains ? " >= " : " < ") +
            fmt("%g", o.explainThreshold) + "; its own score " + fmt("%.3f", pair.score) +
            (explains ? " >= " : " < ") + fmt("%g", o.explainThreshold);
}

// The pair stage (docs/diagnosis.md#two-effects-at-once): when the best single leaves a channel
// beyond twice its validation uncertainty held out, the best singles are each fitted jointly
// with every other candidate (screened cheaply first, the best few fitted in full), and a pair
// is named when it explains at least the threshold's share of what the singles leave.
void calibratePairs(WhichReport& report, const MeasuredData& data,
                    const bags::LoadTestOptions& base, const RigEffects& baseRig,
                    const bags::LoadTestResult& baseResult,
                    const std::vector<TestComparison>& baseline, const WhereReport& where,
                    const Simulator& simulate, const CalibrationOptions& o, SimulationCache& cache,
                    const GapScale& g) {
    const int n = static_cast<int>(data.tests.size());
    if (!o.pairs) {
        report.pairStageReason = "not run: switched off";
        return;
    }
    if (where.withinValidation) {
        report.pairStageReason =
            "not run: every channel is within twice its validation uncertainty";
        return;
    }
    if (report.candidates.size() < 2) {
        report.pairStageReason = "not run: fewer than two candidates";
        return;
    }
    const CandidateResult& best = report.candidates.front();
    std::string left;
    for (const GapMetrics& m : best.heldoutMetricsAfter) {
        double u = 0.0;
        for (const ChannelSummary& c : where.channels)
            if (c.channel == m.channel) u = c.validation;
        if (m.rmse > kExplainedMultiple * u)
            left += (left.empty() ? "" : ", ") + m.channel + " RMSE " +
                    fmt("%.4g", m.rmse / getChannelUnitScale(getChannelKind(m.channel))) + " " +
                    getChannelUnit(getChannelKind(m.channel)) + " > twice " +
                    fmt("%.3g", u / getChannelUnitScale(getChannelKind(m.channel)));
    }
    if (best.heldoutMetricsAfter.empty()) left = "a fold of " + best.effect + " failed";
    if (left.empty() && o.pairGate) {
        report.pairStageReason = "not run: " + best.effect +
                                 " leaves every channel within twice its "
                                 "validation uncertainty, held out";
        return;
    }
    report.pairStageRan = true;
    report.pairStageReason = left.empty() ? "run without its gate"
                                          : "run: " + best.effect + " leaves, held out, " + left;

    // The pairs: each of the best singles with every other candidate, but not with one it is
    // confusable with (on these data the two are one effect).
    std::vector<std::unique_ptr<Evaluator>> evaluators;
    const int firsts =
        std::min<int>(o.pairFirstMembers, static_cast<int>(report.candidates.size()));
    for (int f = 0; f < firsts; ++f) {
        const CandidateResult& a = report.candidates[f];
        if (!(a.excessShrink > 0.0)) continue;
        for (const CandidateResult& b : report.candidates) {
            if (b.effect == a.effect || areConfusable(report, a.effect, b.effect)) continue;
            bool listed = false;
            for (const PairResult& p : report.pairs)
                listed = listed || (p.first == b.effect && p.second == a.effect);
            if (listed) continue;
            PairResult p;
            p.first = a.effect;
            p.second = b.effect;
            evaluators.push_back(std::make_unique<Evaluator>(
                data, base, baseRig, baseResult,
                std::vector<const Effect*>{findEffect(a.effect), findEffect(b.effect)}, simulate,
                cache));
            // Screen on all tests: the first at its single fit, the second scanned.
            Evaluator& e = *evaluators.back();
            std::vector<int> all(n);
            for (int i = 0; i < n; ++i) all[i] = i;
            const std::vector<std::vector<double>> starts =
                makePairStarts(e, a.parameters, b.parameters, o.gridPoints);
            const std::vector<double> costs =
                calcScanCosts(e, starts, makeSamples(baseline, all), g, o);
            const size_t k = std::min_element(costs.begin(), costs.end()) - costs.begin();
            p.screenCost = costs[k];
            p.screenParameters = e.toValues(starts[k].data());
            p.why = "screened out: its cost on all tests at the scan's best is not among the " +
                    std::to_string(o.pairsRefined) + " lowest";
            report.pairs.push_back(p);
        }
    }
    // The pairs whose screen fits best are fitted in full, as a single is.
    std::vector<size_t> order(report.pairs.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
        return report.pairs[x].screenCost < report.pairs[y].screenCost;
    });
    const int refined = std::min<int>(o.pairsRefined, static_cast<int>(order.size()));
    for (size_t r = 0; r < order.size() && static_cast<int>(r) < o.pairsRefined; ++r) {
        PairResult& p = report.pairs[order[r]];
        if (!std::isfinite(p.screenCost)) continue;
        if (o.progress)
            o.progress("pair " + p.first + " + " + p.second + " (fitted in full)",
                       static_cast<int>(r) + 1, refined);
        const CandidateResult& a = *findSingle(report, p.first);
        const CandidateResult& b = *findSingle(report, p.second);
        Evaluator& e = *evaluators[order[r]];
        p.result = calibrateCandidate(e, p.first + " + " + p.second, n, baseline, g, o, [&](int h) {
            return h < 0 ? makePairStarts(e, a.parameters, b.parameters, o.gridPoints)
                         : makePairStarts(e, a.folds[h].parameters, b.folds[h].parameters,
                                          o.gridPoints);
        });
        p.refined = true;
        calcPairGain(p, report, o);
    }
    for (size_t i = 0; i < report.pairs.size(); ++i) {
        report.pairs[i].result.simulations = evaluators[i]->getSimulations();
        report.pairSimulations += evaluators[i]->getSimulations();
    }
    // Refined pairs first, by gain; then the screened, by their screen's cost.
    std::stable_sort(report.pairs.begin(), report.pairs.end(),
                     [](const PairResult& x, const PairResult& y) {
                         if (x.refined != y.refined) return x.refined;
                         return x.refined ? x.gain > y.gain : x.screenCost < y.screenCost;
                     });
    // The pair named: the accepted one with the largest gain (the first, as they are sorted).
    for (size_t i = 0; i < report.pairs.size() && report.pairChosen < 0; ++i)
        if (report.pairs[i].accepted) report.pairChosen = static_cast<int>(i);
}

// Where, on these tests, the named single's fit and each rival's (both fitted on all tests)
// differ most against the channel's validation uncertainty: a channel they differ in by more than
// twice it would tell them apart if measured again with less noise; less, and only another
// measurement can (appended to the verdict's tellApart and reason).
void addWhereFitsDiffer(WhichReport& r, const GapScale& g) {
    if (r.rivals.empty() || r.verdictEffects.size() != 1) return;
    const CandidateResult* named = findSingle(r, r.verdictEffects.front());
    if (!named || named->fitted.empty()) return;
    std::string text;
    for (const std::string& rival : r.rivals) {
        const CandidateResult* other = findSingle(r, rival);
        if (!other || other->fitted.size() != named->fitted.size()) continue;
        double most = -1.0;
        std::string where;
        for (size_t t = 0; t < named->fitted.size(); ++t) {
            const TestComparison& a = named->fitted[t];
            const std::vector<double> d = calcSimulatedRmsDifference(a, other->fitted[t]);
            for (size_t c = 0; c < d.size() && c < a.channels.size(); ++c) {
                const ChannelKind kind = a.channels[c].kind;
                if (kind == ChannelKind::Mass) continue;
                const double u = g.getUncertainty(kind, a.test);
                if (!(u > 0.0) || !(d[c] / u > most)) continue;
                most = d[c] / u;
                where = "the " + getChannelName(kind) + " of the " + fmt("%.3g", a.gasMass * 1e3) +
                        " g test";
            }
        }
        if (most < 0.0) continue;
        text += (text.empty() ? "" : "; ") + named->effect + " and " + rival +
                " fitted on all tests differ most in " + where + ", by " + fmt("%.2g", most) +
                " times its validation uncertainty" +
                (most > kExplainedMultiple ? "" : " (no channel of these tests tells them apart)");
    }
    if (text.empty()) return;
    r.tellApart += (r.tellApart.empty() ? "" : "; ") + text;
    r.reason += "; " + text;
}

}  // namespace

std::string listConfusableWith(const WhichReport& report, const std::string& effect) {
    std::string others;
    for (const auto& [a, b] : report.confusable)
        if (a == effect || b == effect)
            others += (others.empty() ? "" : ", ") + (a == effect ? b : a);
    return others;
}

void judgeCandidates(WhichReport& report, bool withinValidation, const std::string& noneReason,
                     const ChannelUncertainties& validation, const CalibrationOptions& o) {
    std::stable_sort(
        report.candidates.begin(), report.candidates.end(),
        [](const CandidateResult& a, const CandidateResult& b) { return a.score > b.score; });
    report.confusable = findConfusable(report.candidates, o.explainThreshold, validation);
    const CandidateResult* best = report.candidates.empty() ? nullptr : &report.candidates[0];
    report.verdictEffects.clear();
    if (withinValidation) {
        report.verdict = "none";
        report.reason = noneReason;
    } else if (best && best->score >= o.explainThreshold) {
        report.verdict = best->effect;
        report.verdictEffects = {best->effect};
        report.reason = "it shrinks the held-out gap beyond the validation uncertainty by " +
                        fmt("%.0f", 100 * best->excessShrink) + " % (from " +
                        fmt("%.4f", best->excessBefore) + " to " + fmt("%.4f", best->excessAfter) +
                        "; the whole gap by " + fmt("%.0f", 100 * best->shrink) + " %, from " +
                        fmt("%.4f", best->heldoutBefore) + " to " +
                        fmt("%.4f", best->heldoutAfter) + ")";
    } else {
        report.verdict = "unexplained";
        report.reason =
            "no candidate shrinks the held-out gap beyond the validation "
            "uncertainty by " +
            fmt("%.0f", 100 * o.explainThreshold) + " % after its parameter penalty" +
            (best ? " (best: " + best->effect + ", " + fmt("%.0f", 100 * best->excessShrink) + " %)"
                  : std::string());
    }
}

WhichReport calibrateCandidates(const MeasuredData& data, const bags::LoadTestOptions& base,
                                const RigEffects& baseRig, const bags::LoadTestResult& baseResult,
                                const std::vector<TestComparison>& baseline,
                                const WhereReport& where, const Simulator& simulate,
                                const CalibrationOptions& o) {
    const int n = static_cast<int>(data.tests.size());
    if (n < 2)
        throw std::invalid_argument("the calibration needs two tests or more (one held out)");
    const GapScale g = makeGapScale(where, baseline);
    if (!(g.force.range > 0.0) || !(g.pressure.range > 0.0))
        throw std::invalid_argument("the measured force and pressure must vary to be compared");

    SimulationCache cache;
    WhichReport report;
    std::vector<const Effect*> chosen;
    for (const Effect& effect : getEffects())
        if (o.candidates.empty() ? effect.inLibrary
                                 : std::find(o.candidates.begin(), o.candidates.end(),
                                             effect.name) != o.candidates.end())
            chosen.push_back(&effect);
    for (const Effect* candidate : chosen) {
        const Effect& effect = *candidate;
        if (o.progress)
            o.progress(effect.name, static_cast<int>(report.candidates.size()) + 1,
                       static_cast<int>(chosen.size()));
        Evaluator e(data, base, baseRig, baseResult, {&effect}, simulate, cache);
        report.candidates.push_back(calibrateCandidate(e, effect.name, n, baseline, g, o, [](int) {
            return std::vector<std::vector<double>>();
        }));
    }
    ChannelUncertainties validation;
    for (const ChannelSummary& c : where.channels)
        if (c.channel != getChannelName(ChannelKind::Mass)) validation[c.channel] = c.validation;
    judgeCandidates(report, where.withinValidation,
                    "every channel's RMSE is within twice its validation uncertainty "
                    "(sensor noise, numerical and input uncertainty)",
                    validation, o);

    calibratePairs(report, data, base, baseRig, baseResult, baseline, where, simulate, o, cache, g);
    if (report.pairChosen >= 0) {
        const PairResult& p = report.pairs[report.pairChosen];
        const std::string single = report.verdict;
        report.verdict = p.first + " + " + p.second;
        report.verdictEffects = {p.first, p.second};
        report.reason =
            "the two at once shrink the held-out gap beyond the validation uncertainty by " +
            fmt("%.0f", 100 * p.result.excessShrink) + " % (from " +
            fmt("%.4f", p.result.excessBefore) + " to " + fmt("%.4f", p.result.excessAfter) +
            "; the whole gap by " + fmt("%.0f", 100 * p.result.shrink) + " %); the pair " + p.why +
            " (the single stage's verdict: " + single + ")";
        for (const std::string& m : {p.first, p.second}) {
            const std::string others = listConfusableWith(report, m);
            if (!others.empty())
                report.reason += "; " + m + " confusable with " + others + " on these data";
        }
        // Other accepted pairs that explain about as much: these data do not tell them apart.
        std::string others;
        for (size_t i = 0; i < report.pairs.size(); ++i)
            if (static_cast<int>(i) != report.pairChosen && report.pairs[i].accepted &&
                std::fabs(report.pairs[i].gain - p.gain) < 0.1) {
                others += (others.empty() ? "" : ", ") + report.pairs[i].result.effect;
                report.confusablePairs.push_back({p.result.effect, report.pairs[i].result.effect});
            }
        if (!others.empty())
            report.reason += "; the pair is confusable with " + others + " on these data";
    } else if (report.pairStageRan) {
        report.reason += "; no pair of effects explains what is left (the pair stage names none)";
    }
    qualifyVerdict(report, validation, getEffects());
    addWhereFitsDiffer(report, g);
    return report;
}

}  // namespace diagnose
