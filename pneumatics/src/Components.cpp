#include "pneumatics/Components.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "Check.h"

namespace pneumatics {

void checkParameter(bool ok, const std::string& owner, const char* parameter, double value,
                    const char* unit, const char* valid) {
    if (ok) return;
    std::ostringstream s;
    s << owner << ": '" << parameter << "' = " << value << " " << unit
      << " is invalid; valid: " << valid;
    throw std::invalid_argument(s.str());
}

void ValveSpec::validate(const std::string& name) const {
    const double C = sonicConductance, b = criticalPressureRatio;
    checkParameter(std::isfinite(C) && C > 0.0, name, "sonicConductance", C, "m^3/(s Pa)",
                   "C > 0 m^3/(s Pa) (1e-8 m^3/(s Pa) = 1 dm^3/(s bar))");
    checkParameter(b >= 0.0 && b < 1.0, name, "criticalPressureRatio", b, "(-)",
                   "0 <= b < 1 (air through a valve: about 0.2-0.5)");
    checkParameter(subsonicIndex > 0.0 && subsonicIndex <= 1.0, name, "subsonicIndex",
                   subsonicIndex, "(-)", "0 < m <= 1 (ISO 6358: 0.5)");
    checkParameter(laminarPressureRatio > b && laminarPressureRatio < 1.0, name,
                   "laminarPressureRatio", laminarPressureRatio, "(-)",
                   "b < rLam < 1 (default 0.999)");
    checkParameter(openingTime >= 0.0 && std::isfinite(openingTime), name, "openingTime",
                   openingTime, "s", "openingTime >= 0 s (0: opens at once)");
}

namespace {
/// phi(r) and dphi/dr of the ISO 6358 law with the laminar end, for 0 < r <= 1.
void calcFlowFunction(const ValveSpec& v, double r, double* phi, double* dphi) {
    const double b = v.criticalPressureRatio, m = v.subsonicIndex, rL = v.laminarPressureRatio;
    if (r <= b) {
        *phi = 1.0;
        *dphi = 0.0;
        return;
    }
    auto subsonic = [&](double x, double* d) {
        const double u = (x - b) / (1.0 - b), w = 1.0 - u * u;
        const double f = std::pow(w, m);
        if (d) *d = m * f / w * (-2.0 * u / (1.0 - b));
        return f;
    };
    if (r < rL) {
        *phi = subsonic(r, dphi);
        return;
    }
    const double phiL = subsonic(rL, nullptr);
    *phi = phiL * (1.0 - r) / (1.0 - rL);
    *dphi = -phiL / (1.0 - rL);
}

/// Flow from the upstream port 1 to the downstream port 2, p1 >= p2 (T2 does not enter).
void calcValveFlowDownstream(const ValveSpec& v, double s, double p1, double T1, double p2,
                             double* q, double* dp1, double* dT1, double* dp2) {
    const double base = s * v.sonicConductance * kIsoReferenceDensity *
                        std::sqrt(kIsoReferenceTemperature / T1);  // qm per unit p1 phi
    const double r = p2 / p1;
    double phi = 0.0, dphi = 0.0;
    calcFlowFunction(v, r, &phi, &dphi);
    *q = base * p1 * phi;
    *dp1 = base * (phi - r * dphi);
    *dp2 = base * dphi;
    *dT1 = -0.5 * *q / T1;
}
}  // namespace

Flow calcValveFlow(const ValveSpec& v, double opening, double pa, double Ta, double pb, double Tb) {
    Flow f;
    if (opening <= 0.0) return f;
    if (pa >= pb) {
        calcValveFlowDownstream(v, opening, pa, Ta, pb, &f.massFlow, &f.dpa, &f.dTa, &f.dpb);
    } else {
        calcValveFlowDownstream(v, opening, pb, Tb, pa, &f.massFlow, &f.dpb, &f.dTb, &f.dpa);
        f.massFlow = -f.massFlow;
        f.dpa = -f.dpa;
        f.dpb = -f.dpb;
        f.dTb = -f.dTb;
    }
    return f;
}

void PumpSpec::validate(const std::string& name) const {
    const size_t n = pressureRise.size();
    checkParameter(n >= 2 && massFlow.size() == n, name, "points", double(n), "(count)",
                   "at least 2 points, as many pressure rises as mass flows");
    checkParameter(pressureRise[0] >= 0.0, name, "pressureRise[0]", pressureRise[0], "Pa",
                   "the first pressure rise >= 0 Pa");
    for (size_t i = 0; i < n; ++i) {
        const std::string at = "[" + std::to_string(i) + "]";
        checkParameter(std::isfinite(massFlow[i]) && massFlow[i] >= 0.0, name,
                       ("massFlow" + at).c_str(), massFlow[i], "kg/s", "mass flow >= 0 kg/s");
        if (i == 0) continue;
        checkParameter(pressureRise[i] > pressureRise[i - 1] && std::isfinite(pressureRise[i]),
                       name, ("pressureRise" + at).c_str(), pressureRise[i], "Pa",
                       "pressure rises strictly increasing");
        checkParameter(massFlow[i] <= massFlow[i - 1], name, ("massFlow" + at).c_str(), massFlow[i],
                       "kg/s", "mass flows non-increasing with the pressure rise");
    }
    checkParameter(massFlow[n - 1] == 0.0, name, "massFlow[last]", massFlow[n - 1], "kg/s",
                   "0 kg/s: the last point is the shut-off pressure");
}

Flow calcPumpFlow(const PumpSpec& p, double speed, double pa, double pb) {
    Flow f;
    if (speed <= 0.0) return f;
    const std::vector<double>& x = p.pressureRise;
    const std::vector<double>& y = p.massFlow;
    const double dp = pb - pa;
    if (dp <= x.front()) {
        f.massFlow = speed * y.front();
        return f;
    }
    if (dp >= x.back()) return f;
    size_t k = 1;
    while (x[k] < dp) ++k;
    const double slope = (y[k] - y[k - 1]) / (x[k] - x[k - 1]);
    f.massFlow = speed * (y[k - 1] + slope * (dp - x[k - 1]));
    f.dpb = speed * slope;
    f.dpa = -speed * slope;
    return f;
}

Flow calcOrificeFlow(const bags::OrificeOptions& o, double R, double pa, double Ta, double pb,
                     double Tb) {
    Flow f;
    const bool aUp = pa >= pb;
    const double pUp = aUp ? pa : pb, TUp = aUp ? Ta : Tb;
    double g = 0.0;  // d(massFlow)/d(pa - pb) at fixed density
    f.massFlow = bags::calcOrificeMassFlow(o, pa, pb, pUp / (R * TUp), &g);
    // massFlow grows as sqrt(rhoUp) = sqrt(pUp / (R TUp)).
    const double dUp = 0.5 * f.massFlow / pUp, dTUp = -0.5 * f.massFlow / TUp;
    f.dpa = g + (aUp ? dUp : 0.0);
    f.dpb = -g + (aUp ? 0.0 : dUp);
    (aUp ? f.dTa : f.dTb) = dTUp;
    return f;
}

void SensorSpec::validate(const std::string& name) const {
    checkParameter(timeConstant >= 0.0 && std::isfinite(timeConstant), name, "timeConstant",
                   timeConstant, "s", "timeConstant >= 0 s (0: no lag)");
    checkParameter(std::isfinite(offset), name, "offset", offset, "Pa", "a finite offset in Pa");
    checkParameter(noiseStdDev >= 0.0 && std::isfinite(noiseStdDev), name, "noiseStdDev",
                   noiseStdDev, "Pa", "noiseStdDev >= 0 Pa");
}

double calcFirstOrderLag(double y0, double u0, double u1, double h, double tau) {
    if (tau <= 0.0) return u1;
    if (h <= 0.0) return y0;
    // u(t) = u0 + s t: y(t) = u(t) - s tau + (y0 - u0 + s tau) exp(-t / tau).
    const double s = (u1 - u0) / h;
    return u1 - s * tau + (y0 - u0 + s * tau) * std::exp(-h / tau);
}

}  // namespace pneumatics
