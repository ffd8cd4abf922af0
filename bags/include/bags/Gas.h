#pragma once
/// @file Ideal gas in an airbag chamber: uniform pressure, fixed mass, isothermal, adiabatic
/// or polytropic; chambers joined by orifices.
///
/// Absolute pressure p, gauge pressure p - pAmbient. The gas enters the bag's potential energy
/// as -G(V), with dG/dV = p(V) - pAmbient (the work the gas does against the atmosphere), so
/// the bag's equilibrium has the follower pressure load and the gas stiffness
/// -(dp/dV) g g^T, g = dV/dx, comes out as the Hessian of -G.

#include <string>

namespace bags {

/// Universal gas constant [J/(mol K)].
inline constexpr double kGasConstant = 8.314462618;

struct GasOptions {
    enum class Process { Isothermal, Adiabatic, Polytropic };
    double molarMass = 0.029;         ///< [kg/mol] (air)
    double temperature = 296.15;      ///< [K] gas and room temperature (23 degC)
    double ambientPressure = 1.0e5;   ///< [Pa] absolute
    Process process = Process::Isothermal;
    double polytropicIndex = 1.4;     ///< n in p V^n = const (Adiabatic uses gamma = 1.4)
    double gamma = 1.4;               ///< heat capacity ratio of the gas
    /// Throws std::invalid_argument naming the option and the valid range.
    void validate() const;
    double getSpecificGasConstant() const { return kGasConstant / molarMass; }  ///< [J/(kg K)]
    double getAmbientDensity() const;  ///< [kg/m^3] at ambient pressure and temperature
};

std::string toString(GasOptions::Process p);

/// The gas of one sealed chamber (or of several chambers that share their air through open
/// connections). State: mass m [kg] and a reference state (pRef, VRef) set when the gas is
/// sealed at temperature T; isothermal: p V = m R T; polytropic: p V^n = pRef VRef^n.
class GasChamber {
public:
    GasChamber() = default;
    GasChamber(const GasOptions& options, double mass);
    /// Seals the gas at volume V [m^3] and the options' temperature: pRef = m R T / V.
    void seal(double volume);
    double getMass() const { return m_mass; }
    /// Changes the mass at fixed temperature (inflation, deflation), reseals at volume V.
    void setMass(double mass, double volume);
    double calcPressure(double volume) const;      ///< absolute [Pa]
    double calcGaugePressure(double volume) const; ///< [Pa]
    double calcPressureDerivative(double volume) const;  ///< dp/dV [Pa/m^3]
    /// G(V) with dG/dV = p(V) - pAmbient [J] (defined up to a constant).
    double calcWorkPotential(double volume) const;
    /// Temperature [K] at volume V (varies in adiabatic/polytropic processes).
    double calcTemperature(double volume) const;
    const GasOptions& getOptions() const { return m_options; }
private:
    GasOptions m_options;
    double m_mass = 0.0;
    double m_exponent = 1.0;  ///< 1 isothermal, gamma adiabatic, n polytropic
    double m_pRef = 0.0;
    double m_VRef = 0.0;
};

}  // namespace bags
