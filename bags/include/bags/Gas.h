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
    /// Adds dm [kg] (negative: removes) at volume V [m^3] without changing the gas's
    /// temperature at that volume: p(V) scales by (m + dm) / m. Exact for an isothermal gas;
    /// for adiabatic and polytropic gases it neglects the heat carried by the flow.
    void transferMass(double dm, double volume);
    const GasOptions& getOptions() const { return m_options; }
private:
    GasOptions m_options;
    double m_mass = 0.0;
    double m_exponent = 1.0;  ///< 1 isothermal, gamma adiabatic, n polytropic
    double m_pRef = 0.0;
    double m_VRef = 0.0;
};

/// A flow restriction between two gas bodies (the double wedge's intermediate connection, a
/// valve port): mass flow driven by the pressure difference,
///   mdot = Cd A sqrt(2 rho_up) dp / (dp^2 + dpLam^2)^(1/4)   (from the higher pressure),
/// the incompressible orifice law Cd A sqrt(2 rho dp) for |dp| >> dpLam and a linear (laminar)
/// law for |dp| << dpLam, which keeps the flow smooth where the pressures equalise. rho_up is
/// the upstream gas density. Valid while dp is a few percent of the absolute pressure (the
/// compressible expansion factor then stays above 0.98); choked flow is not modelled.
struct OrificeOptions {
    double diameter = 4.0e-3;          ///< [m] of the equivalent round opening
    double dischargeCoefficient = 0.62;///< Cd (sharp-edged orifice: about 0.6)
    double laminarPressure = 1.0;      ///< [Pa] dpLam, where the law turns linear
    void validate() const;             ///< throws std::invalid_argument naming the option
    double getArea() const;            ///< [m^2]
};

/// Mass flow [kg/s] from gas a to gas b through an orifice for absolute pressures pa, pb [Pa]
/// and the upstream density rhoUp [kg/m^3]; dmdotdp (optional) is d(mdot)/d(pa - pb) at fixed
/// density [kg/(s Pa)].
double calcOrificeMassFlow(const OrificeOptions& o, double pa, double pb, double rhoUp,
                           double* dmdotdp = nullptr);

/// Mass [kg] that flows from gas a (at volume Va) to gas b (at Vb) through the orifice during
/// dt [s] with both volumes held fixed, by backward Euler: dm = dt mdot(pa(ma - dm),
/// pb(mb + dm)). The root is unique and lies between 0 and the transfer that equalises the
/// pressures, so any dt is stable. Does not change the gases.
double calcOrificeTransfer(const OrificeOptions& o, const GasChamber& a, double Va,
                           const GasChamber& b, double Vb, double dt);

}  // namespace bags
