#include <bags/Gas.h>
#include <bags/Types.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bags {

namespace {
constexpr double kPi = 3.14159265358979323846;
void require(bool ok, const char* option, double value, const char* valid) {
    if (ok) return;
    std::ostringstream s;
    s << "gas option '" << option << "' = " << value << " is invalid; " << valid;
    throw std::invalid_argument(s.str());
}
}  // namespace

void GasOptions::validate() const {
    require(molarMass > 0.0 && molarMass < 1.0, "molarMass", molarMass,
            "use a positive molar mass in kg/mol (air: 0.029)");
    require(temperature > 0.0, "temperature", temperature, "use an absolute temperature > 0 K");
    require(ambientPressure > 0.0, "ambientPressure", ambientPressure,
            "use a positive absolute pressure in Pa (sea level: 1.01325e5)");
    require(polytropicIndex >= 1.0 && polytropicIndex <= 2.0, "polytropicIndex", polytropicIndex,
            "use 1 <= n <= 2 (1 isothermal, 1.4 adiabatic air)");
    require(gamma > 1.0 && gamma <= 5.0 / 3.0, "gamma", gamma, "use 1 < gamma <= 5/3 (air: 1.4)");
    require(leakConductance >= 0.0 && leakConductance <= kMaxLeakConductance, "leakConductance",
            leakConductance, "use 0 (sealed) to 1e-9 kg/(s Pa) (1 mg/(s kPa))");
    require(heatTimeConstant >= 0.0 && heatTimeConstant <= kMaxHeatTimeConstant, "heatTimeConstant",
            heatTimeConstant,
            "use 0 (the process as chosen) to 3600 s (the film's thermal time constant)");
    if (heatTimeConstant > 0.0 && process == Process::Polytropic)
        throw std::invalid_argument(
            "gas option 'heatTimeConstant' makes the gas adiabatic with heat exchange; it does "
            "not combine with process polytropic (use isothermal or adiabatic)");
}

double GasOptions::getAmbientDensity() const {
    return ambientPressure / (getSpecificGasConstant() * temperature);
}

std::string toString(GasOptions::Process p) {
    switch (p) {
        case GasOptions::Process::Isothermal:
            return "isothermal";
        case GasOptions::Process::Adiabatic:
            return "adiabatic";
        case GasOptions::Process::Polytropic:
            return "polytropic";
    }
    return "unknown";
}

GasChamber::GasChamber(const GasOptions& options, double mass) : m_options(options), m_mass(mass) {
    options.validate();
    if (!(mass > 0.0)) throw std::invalid_argument("gas mass must be positive");
    switch (options.process) {
        case GasOptions::Process::Isothermal:
            m_exponent = 1.0;
            break;
        case GasOptions::Process::Adiabatic:
            m_exponent = options.gamma;
            break;
        case GasOptions::Process::Polytropic:
            m_exponent = options.polytropicIndex;
            break;
    }
    // With heat exchange the gas compresses adiabatically between its relaxations.
    if (options.heatTimeConstant > 0.0) m_exponent = options.gamma;
}

void GasChamber::seal(double volume) {
    if (!(volume > 0.0)) throw NumericalError("cannot seal gas at a non-positive volume");
    m_VRef = volume;
    m_pRef = m_mass * m_options.getSpecificGasConstant() * m_options.temperature / volume;
}

void GasChamber::setMass(double mass, double volume) {
    if (!(mass > 0.0)) throw std::invalid_argument("gas mass must be positive");
    m_mass = mass;
    seal(volume);
}

double GasChamber::calcPressure(double V) const {
    if (m_VRef <= 0.0) throw std::logic_error("GasChamber used before seal()");
    if (!(V > 0.0)) throw NumericalError("gas volume is not positive");
    return m_exponent == 1.0 ? m_pRef * m_VRef / V : m_pRef * std::pow(m_VRef / V, m_exponent);
}

double GasChamber::calcGaugePressure(double V) const {
    return calcPressure(V) - m_options.ambientPressure;
}

double GasChamber::calcPressureDerivative(double V) const {
    return -m_exponent * calcPressure(V) / V;
}

double GasChamber::calcWorkPotential(double V) const {
    const double c = m_pRef * std::pow(m_VRef, m_exponent);  // p V^n
    const double g =
        m_exponent == 1.0
            ? c * std::log(V / m_VRef)
            : c * (std::pow(V, 1.0 - m_exponent) - std::pow(m_VRef, 1.0 - m_exponent)) /
                  (1.0 - m_exponent);
    return g - m_options.ambientPressure * (V - m_VRef);
}

double GasChamber::calcTemperature(double V) const {
    return calcPressure(V) * V / (m_mass * m_options.getSpecificGasConstant());
}

void GasChamber::transferMass(double dm, double volume) {
    if (m_VRef <= 0.0) throw std::logic_error("GasChamber used before seal()");
    const double m = m_mass + dm;
    if (!(m > 0.0)) throw NumericalError("gas mass would become non-positive in a transfer");
    m_pRef *= m / m_mass;
    m_mass = m;
    (void)volume;  // p(V) scales by the same factor at every volume
}

double GasChamber::calcLeakTransfer(double V, double dt, double C) const {
    if (!(dt >= 0.0) || !(C >= 0.0)) throw std::invalid_argument("leak needs dt >= 0 and C >= 0");
    if (dt == 0.0 || C == 0.0) return 0.0;
    const double RT = m_options.getSpecificGasConstant() * calcTemperature(V);
    const double m0 = m_options.ambientPressure * V / RT;  // the mass at zero gauge pressure
    const double tau = V / (RT * C);
    return -(m_mass - m0) * -std::expm1(-dt / tau);
}

void GasChamber::setTemperature(double T, double V) {
    if (!(T > 0.0) || !(V > 0.0)) throw NumericalError("gas temperature or volume not positive");
    m_VRef = V;
    m_pRef = m_mass * m_options.getSpecificGasConstant() * T / V;
}

double GasChamber::calcHeatStepTemperature(double V0, double T0, double V1, double dt) const {
    const double tau = m_options.heatTimeConstant;
    const double a = (m_options.gamma - 1.0) * std::log(V1 / V0);
    if (!(tau > 0.0) || dt <= 0.0) return T0 * std::exp(-a);
    const double r = dt / tau;
    const double x = a + r;
    // (1 - e^-x) / x, smooth through x = 0
    const double phi = std::abs(x) < 1e-8 ? 1.0 - 0.5 * x : -std::expm1(-x) / x;
    return T0 * std::exp(-x) + m_options.temperature * r * phi;
}

void OrificeOptions::validate() const {
    require(diameter > 0.0 && diameter < 1.0, "diameter", diameter,
            "use 0 < diameter < 1 m (e.g. 4 mm)");
    require(dischargeCoefficient > 0.0 && dischargeCoefficient <= 1.0, "dischargeCoefficient",
            dischargeCoefficient, "use 0 < Cd <= 1 (sharp-edged orifice: 0.6)");
    require(laminarPressure > 0.0 && laminarPressure < 1e4, "laminarPressure", laminarPressure,
            "use 0 < dpLam < 10 kPa (e.g. 1 Pa)");
}

double OrificeOptions::getArea() const { return 0.25 * kPi * diameter * diameter; }

double calcOrificeMassFlow(const OrificeOptions& o, double pa, double pb, double rhoUp,
                           double* dmdotdp) {
    const double dp = pa - pb;
    const double L2 = o.laminarPressure * o.laminarPressure;
    const double q = dp * dp + L2;
    const double c = o.dischargeCoefficient * o.getArea() * std::sqrt(2.0 * rhoUp);
    const double root = std::pow(q, 0.25);
    // d/ddp [dp q^-1/4] = q^-1/4 - dp^2 / 2 q^-5/4 = q^-5/4 (dp^2 / 2 + L2)
    if (dmdotdp) *dmdotdp = c * (0.5 * dp * dp + L2) / (q * root);
    return c * dp / root;
}

double calcOrificeTransfer(const OrificeOptions& o, const GasChamber& a, double Va,
                           const GasChamber& b, double Vb, double dt) {
    o.validate();
    if (!(dt >= 0.0)) throw std::invalid_argument("orifice transfer needs dt >= 0");
    const double pa0 = a.calcPressure(Va), pb0 = b.calcPressure(Vb);
    if (dt == 0.0 || pa0 == pb0) return 0.0;
    const double ma = a.getMass(), mb = b.getMass();
    // At fixed volumes each pressure is proportional to its mass (transferMass keeps T).
    auto pressures = [&](double dm, double* pa, double* pb) {
        *pa = pa0 * (ma - dm) / ma;
        *pb = pb0 * (mb + dm) / mb;
    };
    // dm that equalises the pressures: pa0 (ma - dm)/ma = pb0 (mb + dm)/mb.
    const double dmEq = (pa0 - pb0) / (pa0 / ma + pb0 / mb);
    auto residual = [&](double dm, double* dRdm) {
        double pa, pb;
        pressures(dm, &pa, &pb);
        const double rhoUp = pa >= pb ? (ma - dm) / Va : (mb + dm) / Vb;
        double g = 0.0;
        const double mdot = calcOrificeMassFlow(o, pa, pb, rhoUp, &g);
        if (dRdm) *dRdm = 1.0 + dt * g * (pa0 / ma + pb0 / mb);  // density change neglected
        return dm - dt * mdot;
    };
    // R(0) = -dt mdot(0) and R(dmEq) = dmEq have opposite signs: safeguarded Newton.
    double lo = std::min(0.0, dmEq), hi = std::max(0.0, dmEq);
    double dm = 0.0;
    for (int it = 0; it < 100; ++it) {
        double dR = 0.0;
        const double R = residual(dm, &dR);
        if (std::abs(R) <= 1e-14 * std::abs(dmEq)) break;
        (R > 0.0 ? hi : lo) = dm;  // R increases with dm
        double next = dm - R / dR;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (next == dm) break;
        dm = next;
    }
    return dm;
}

}  // namespace bags
