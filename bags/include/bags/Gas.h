#pragma once
/// @file Ideal gas in an airbag chamber: uniform pressure, fixed mass, isothermal, adiabatic
/// or polytropic; chambers joined by orifices.
///
/// Absolute pressure p, gauge pressure p - pAmbient. The gas enters the bag's potential energy
/// as -G(V), with dG/dV = p(V) - pAmbient (the work the gas does against the atmosphere), so
/// the bag's equilibrium has the follower pressure load and the gas stiffness
/// -(dp/dV) g g^T, g = dV/dx, comes out as the Hessian of -G.

#include <bags/StateStream.h>

#include <string>

namespace bags {

/// Universal gas constant [J/(mol K)].
inline constexpr double kGasConstant = 8.314462618;

struct GasOptions {
    enum class Process { Isothermal, Adiabatic, Polytropic };
    double molarMass = 0.029;        ///< [kg/mol] (air)
    double temperature = 296.15;     ///< [K] gas and room temperature (23 degC)
    double ambientPressure = 1.0e5;  ///< [Pa] absolute
    Process process = Process::Isothermal;
    double polytropicIndex = 1.4;  ///< n in p V^n = const (Adiabatic uses gamma = 1.4)
    double gamma = 1.4;            ///< heat capacity ratio of the gas
    /// Leakage through seams and valves [kg/(s Pa)]: the gas flows out at this conductance
    /// times its gauge pressure (laminar; in at a gauge pressure below zero). Per bag, shared
    /// among its gas bodies by volume. 0: sealed. docs/diagnosis.md#leakage.
    double leakConductance = 0.0;
    /// Heat exchange with the room through the film [s]: > 0 makes the gas's temperature a
    /// state that compresses adiabatically (gamma) and relaxes to `temperature` (the room)
    /// with this time constant (Newton cooling, tau = m c_v / (h A)); 0: the process as
    /// chosen. Not with process polytropic. docs/diagnosis.md#heat-exchange.
    double heatTimeConstant = 0.0;
    /// Largest leak conductance accepted [kg/(s Pa)]: 1 mg/(s kPa), about a 0.2 mm hole at a
    /// few kPa (a 3.5 L bag then loses its gauge pressure with a time constant of 40 s).
    static constexpr double kMaxLeakConductance = 1e-9;
    static constexpr double kMaxHeatTimeConstant = 3600.0;  ///< [s]
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
    double calcPressure(double volume) const;            ///< absolute [Pa]
    double calcGaugePressure(double volume) const;       ///< [Pa]
    double calcPressureDerivative(double volume) const;  ///< dp/dV [Pa/m^3]
    /// G(V) with dG/dV = p(V) - pAmbient [J] (defined up to a constant).
    double calcWorkPotential(double volume) const;
    /// Temperature [K] at volume V (varies in adiabatic/polytropic processes).
    double calcTemperature(double volume) const;
    /// Mass [kg] (negative: lost) that leaks through a conductance C [kg/(s Pa)] during dt [s]
    /// at the held volume V [m^3], the gas keeping its temperature at V: the gauge pressure
    /// (m - m0) R T / V, m0 = pAmbient V / (R T), decays as exp(-t / tau), tau = V / (R T C),
    /// so dm = -(m - m0) (1 - exp(-dt / tau)) exactly. Does not change the gas.
    double calcLeakTransfer(double volume, double dt, double conductance) const;
    /// Reseals the gas so that its temperature at volume V [m^3] is T [K] (mass kept; the
    /// process's exponent kept: an adiabat through (V, T)).
    void setTemperature(double temperature, double volume);
    /// The heat exchange over a step of dt [s] (options' heatTimeConstant tau > 0, room
    /// temperature Tr = options' temperature): the temperature [K] at the step's end when the
    /// gas goes from (V0, T0) to V1 along a volume exponential in time,
    ///   dT/dt = -(gamma - 1) T dlnV/dt - (T - Tr) / tau,
    /// integrated exactly: T1 = T0 e^-x + Tr (dt / tau) (1 - e^-x) / x with
    /// x = (gamma - 1) ln(V1 / V0) + dt / tau. dt = 0: the adiabat T0 (V0 / V1)^(gamma - 1);
    /// V1 = V0: Newton cooling Tr + (T0 - Tr) e^(-dt / tau).
    double calcHeatStepTemperature(double V0, double T0, double V1, double dt) const;
    /// Adds dm [kg] (negative: removes) at volume V [m^3] without changing the gas's
    /// temperature at that volume: p(V) scales by (m + dm) / m. Exact for an isothermal gas;
    /// for adiabatic and polytropic gases it neglects the heat carried by the flow.
    void transferMass(double dm, double volume);
    const GasOptions& getOptions() const { return m_options; }
    /// The state (mass and reference state) into a checkpoint, bit for bit, and back.
    void saveState(StateWriter& w) const {
        w.pod(m_mass);
        w.pod(m_exponent);
        w.pod(m_pRef);
        w.pod(m_VRef);
    }
    void loadState(StateReader& r) {
        r.pod(m_mass);
        r.pod(m_exponent);
        r.pod(m_pRef);
        r.pod(m_VRef);
    }

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
    double diameter = 4.0e-3;            ///< [m] of the equivalent round opening
    double dischargeCoefficient = 0.62;  ///< Cd (sharp-edged orifice: about 0.6)
    double laminarPressure = 1.0;        ///< [Pa] dpLam, where the law turns linear
    void validate() const;               ///< throws std::invalid_argument naming the option
    double getArea() const;              ///< [m^2]
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
