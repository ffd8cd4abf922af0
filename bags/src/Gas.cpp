#include <bags/Gas.h>
#include <bags/Types.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bags {

namespace {
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

}  // namespace bags
