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
    require(gamma > 1.0 && gamma <= 5.0 / 3.0, "gamma", gamma,
            "use 1 < gamma <= 5/3 (air: 1.4)");
}

double GasOptions::getAmbientDensity() const {
    return ambientPressure / (getSpecificGasConstant() * temperature);
}

std::string toString(GasOptions::Process p) {
    switch (p) {
        case GasOptions::Process::Isothermal: return "isothermal";
        case GasOptions::Process::Adiabatic: return "adiabatic";
        case GasOptions::Process::Polytropic: return "polytropic";
    }
    return "unknown";
}

GasChamber::GasChamber(const GasOptions& options, double mass) : m_options(options), m_mass(mass) {
    options.validate();
    if (!(mass > 0.0)) throw std::invalid_argument("gas mass must be positive");
    switch (options.process) {
        case GasOptions::Process::Isothermal: m_exponent = 1.0; break;
        case GasOptions::Process::Adiabatic: m_exponent = options.gamma; break;
        case GasOptions::Process::Polytropic: m_exponent = options.polytropicIndex; break;
    }
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
    const double g = m_exponent == 1.0 ? c * std::log(V / m_VRef)
                                       : c * (std::pow(V, 1.0 - m_exponent) -
                                              std::pow(m_VRef, 1.0 - m_exponent)) /
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
