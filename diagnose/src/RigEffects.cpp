#include <diagnose/RigEffects.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace diagnose {

namespace {

void require(bool ok, const char* name, double value, const std::string& valid) {
    if (ok) return;
    std::ostringstream s;
    s << "rig effect '" << name << "' = " << value << " is invalid; " << valid;
    throw std::invalid_argument(s.str());
}

double calcMeanPressure(const bags::LoadStep& s) {
    // Volume-weighted mean over the chambers (as load_displacement.csv writes it).
    double pv = 0.0, v = 0.0;
    for (size_t c = 0; c < s.gaugePressure.size(); ++c) {
        const double vc = c < s.volume.size() ? s.volume[c] : 1.0;
        pv += s.gaugePressure[c] * vc;
        v += vc;
    }
    return v > 0.0 ? pv / v : 0.0;
}

}  // namespace

bool RigEffects::isNone() const {
    return pressureLag == 0.0 && pressureOffset == 0.0 && flowmeterOffset == 0.0 &&
           machineCompliance == 0.0 && loadCellGain == 0.0 && bedCompliance == 0.0;
}

void RigEffects::validate() const {
    require(pressureLag >= 0.0 && pressureLag <= kMaxPressureLag, "pressureLag", pressureLag,
            "use 0 to 30 s");
    require(std::fabs(pressureOffset) <= kMaxPressureOffset, "pressureOffset", pressureOffset,
            "use -5 to 5 kPa");
    require(std::fabs(flowmeterOffset) <= kMaxFlowmeterOffset, "flowmeterOffset", flowmeterOffset,
            "use -0.25 to 0.25 g");
    require(machineCompliance >= 0.0 && machineCompliance <= kMaxMachineCompliance,
            "machineCompliance", machineCompliance,
            "use 0 (a rigid rig) to 2 mm/N (a rig stiffness of at least 0.5 N/mm)");
    require(bedCompliance >= 0.0 && bedCompliance <= kMaxBedCompliance, "bedCompliance",
            bedCompliance,
            "use 0 (a rigid bed board) to 2 mm/N (a bed stiffness of at least 0.5 N/mm)");
    require(std::fabs(loadCellGain) <= kMaxLoadCellGain, "loadCellGain", loadCellGain,
            "use -0.2 to 0.2 (the load cell reads the force times 1 + gain)");
}

std::vector<double> calcBagGasMasses(const std::vector<double>& readings, const RigEffects& rig) {
    std::vector<double> m;
    for (double r : readings) {
        const double mb = r - rig.flowmeterOffset;
        if (!(mb > 0.0)) {
            std::ostringstream s;
            s << "rig effect 'flowmeterOffset' = " << rig.flowmeterOffset * 1e3
              << " g leaves no gas in the bag for the reading " << r * 1e3
              << " g; valid: an offset below the smallest reading";
            throw std::invalid_argument(s.str());
        }
        m.push_back(mb);
    }
    return m;
}

MachineCurve calcMachineCurve(const bags::LoadCurve& curve, const RigEffects& rig, double rate) {
    MachineCurve mc;
    double t = 0.0;
    for (size_t i = 0; i < curve.steps.size(); ++i) {
        const bags::LoadStep& s = curve.steps[i];
        // The bed sinks under the bed's force, which is the block's (quasi-static; the bag's
        // own weight was on it before contact): the crosshead follows the bag down.
        const double d = s.displacement + s.force * (rig.machineCompliance + rig.bedCompliance);
        if (i > 0) t += std::fabs(d - mc.displacement.back()) / rate;
        mc.time.push_back(t);
        mc.displacement.push_back(d);
        mc.force.push_back(s.force * (1.0 + rig.loadCellGain));
        mc.pressure.push_back(calcMeanPressure(s));
        mc.bedSink.push_back(s.force * rig.bedCompliance);
        mc.loading.push_back(s.loading ? 1 : 0);
    }
    return mc;
}

std::vector<double> applyPressureSensor(const std::vector<double>& t, const std::vector<double>& p,
                                        const RigEffects& rig) {
    std::vector<double> y(p.size());
    if (p.empty()) return y;
    y[0] = p[0];
    const double tau = rig.pressureLag;
    for (size_t i = 1; i < p.size(); ++i) {
        const double h = t[i] - t[i - 1];
        if (tau <= 0.0 || h <= 0.0) {
            y[i] = tau <= 0.0 ? p[i] : y[i - 1];
            continue;
        }
        // y' = (u - y) / tau with u linear over the interval (slope a): exact step.
        const double a = (p[i] - p[i - 1]) / h;
        const double e = std::exp(-h / tau);
        y[i] = p[i] - a * tau + (y[i - 1] - p[i - 1] + a * tau) * e;
    }
    for (double& v : y) v += rig.pressureOffset;
    return y;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double xq) {
    const size_t n = x.size();
    if (n == 1) return y[0];
    size_t i = std::upper_bound(x.begin(), x.end(), xq) - x.begin();
    i = std::clamp<size_t>(i, 1, n - 1);
    const double dx = x[i] - x[i - 1];
    if (!(dx > 0.0)) return y[i];
    return y[i - 1] + (y[i] - y[i - 1]) * (xq - x[i - 1]) / dx;
}

}  // namespace diagnose
