#include <diagnose/Stiffness.h>

#include <cmath>
#include <stdexcept>

#include "Format.h"

namespace diagnose {

using detail::fmt;
using detail::kNaN;

StiffnessComparison compareStiffness(const StiffnessChannel& measured,
                                     const bags::LoadTestResult& sim) {
    StiffnessComparison out;
    for (size_t i = 0; i < measured.gasMass.size(); ++i) {
        const bags::LoadCurve* curve = nullptr;
        for (const bags::LoadCurve& c : sim.curves)
            if (std::fabs(c.gasMass - measured.gasMass[i]) < 1e-9) curve = &c;
        if (!curve)
            throw std::invalid_argument("no simulated curve at " +
                                        fmt("%.4g g", measured.gasMass[i] * 1e3));
        StiffnessPoint p;
        p.gasMass = measured.gasMass[i];
        p.measured = measured.stiffness[i];
        p.measuredStage = measured.stage.empty() ? 0 : measured.stage[i];
        p.simulatedStage = curve->stage;
        const bool has = curve->stage > 0 && curve->stiffness > 0.0 && !curve->failed;
        p.simulated = has ? curve->stiffness : kNaN;
        if (!has) {
            p.note = !curve->failure.empty() ? curve->failure
                                             : "the curve gives no stiffness over the load range";
            ++out.missing;
        }
        out.points.push_back(p);
    }

    // Least squares measured = (1 + scale) simulated; the regimes by stated stage.
    double sxy = 0.0, sxx = 0.0, total2 = 0.0;
    for (const StiffnessPoint& p : out.points)
        if (std::isfinite(p.simulated)) {
            sxy += p.measured * p.simulated, sxx += p.simulated * p.simulated;
            total2 += (p.measured - p.simulated) * (p.measured - p.simulated);
        }
    out.scale = sxx > 0.0 ? sxy / sxx - 1.0 : kNaN;
    auto regime = [&](const std::string& name, int stage) {
        StiffnessRegime r;
        r.regime = name;
        double s2 = 0.0, rel2 = 0.0, sum = 0.0;
        for (const StiffnessPoint& p : out.points) {
            if (!std::isfinite(p.simulated) || (stage >= 0 && p.measuredStage != stage)) continue;
            const double e = p.measured - p.simulated;
            ++r.points, s2 += e * e, sum += e, rel2 += (e / p.measured) * (e / p.measured);
        }
        if (r.points == 0) return;
        r.rmse = std::sqrt(s2 / r.points);
        r.bias = sum / r.points;
        r.relative = std::sqrt(rel2 / r.points);
        r.share = total2 > 0.0 ? s2 / total2 : 0.0;
        out.regimes.push_back(r);
    };
    regime("all", -1);
    for (int s = 1; s <= 3; ++s) regime("stage " + std::to_string(s), s);
    if (!measured.stage.empty()) regime("stage not stated", 0);

    out.leastMeasured = out.leastSimulated = kNaN;
    double kMinM = kNaN, kMinS = kNaN;
    for (const StiffnessPoint& p : out.points) {
        if (!(p.measured >= kMinM)) kMinM = p.measured, out.leastMeasured = p.gasMass;
        if (std::isfinite(p.simulated) && !(p.simulated >= kMinS))
            kMinS = p.simulated, out.leastSimulated = p.gasMass;
        if (p.measuredStage > 0 && p.simulatedStage > 0) {
            ++out.stagesCompared;
            if (p.measuredStage == p.simulatedStage) ++out.stagesAgreeing;
        }
    }
    return out;
}

}  // namespace diagnose
