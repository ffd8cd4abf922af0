#pragma once
/// @file The flow laws of the pneumatic components: solenoid valves and vents after ISO 6358-1,
/// a pump given by its flow against back-pressure curve, and the orifice between chambers or
/// bags (bags' own law, bags::calcOrificeMassFlow, reused). Each law returns the mass flow
/// from port a to port b [kg/s] (negative: from b to a) and its partial derivatives with
/// respect to the absolute pressures [Pa] and temperatures [K] at both ports, the tangent the
/// network's implicit step needs.
///
/// SI throughout. Parameters are plain structs with defaults and a validate() that throws
/// std::invalid_argument naming the parameter, its unit and the valid range.

#include <bags/Gas.h>

#include <string>
#include <vector>

namespace pneumatics {

/// ISO 8778 standard reference atmosphere, the state at which ISO 6358 conductances are given.
inline constexpr double kIsoReferenceTemperature = 293.15;  ///< T0 [K]
inline constexpr double kIsoReferenceDensity = 1.185;       ///< rho0 [kg/m^3] (100 kPa, 65 % RH)

/// A mass flow from port a to port b and its tangent.
struct Flow {
    double massFlow = 0.0;  ///< [kg/s] from a to b (negative: from b to a)
    double dpa = 0.0;       ///< d(massFlow)/d(pa) [kg/(s Pa)]
    double dTa = 0.0;       ///< d(massFlow)/d(Ta) [kg/(s K)]
    double dpb = 0.0;       ///< d(massFlow)/d(pb) [kg/(s Pa)]
    double dTb = 0.0;       ///< d(massFlow)/d(Tb) [kg/(s K)]
};

/// A solenoid valve (or a fixed restriction: a vent) after ISO 6358-1:2013. With p1, T1 the
/// upstream and p2 the downstream absolute pressure, r = p2/p1 and s the opening (0 closed,
/// 1 open):
///   choked,    r <= b:  qm = s C rho0 p1 sqrt(T0/T1)
///   subsonic,  b < r:   qm = s C rho0 p1 sqrt(T0/T1) [1 - ((r - b)/(1 - b))^2]^m
/// Near r = 1 the subsonic law has an infinite slope dqm/dp2; above r = rLam
/// (laminarPressureRatio) the flow is taken linear in (1 - r) from its value at rLam to zero,
/// which keeps the tangent finite for the implicit step (as Simscape's laminar region does).
struct ValveSpec {
    double sonicConductance = 1.0e-8;     ///< C [m^3/(s Pa)] (1e-8 = 1 dm^3/(s bar))
    double criticalPressureRatio = 0.5;   ///< b [-], in [0, 1)
    double subsonicIndex = 0.5;           ///< m [-], in (0, 1] (0.5: the elliptic law of ISO 6358)
    double laminarPressureRatio = 0.999;  ///< rLam [-], in (b, 1)
    double openingTime = 0.0;  ///< [s] from closed to open (and back), linear; 0: at once
    /// @throws std::invalid_argument naming the parameter, its unit and the valid range.
    void validate(const std::string& name = "valve") const;
};

/// ISO 6358 mass flow from a to b with the valve opened to the fraction `opening` in [0, 1].
Flow calcValveFlow(const ValveSpec& v, double opening, double pa, double Ta, double pb, double Tb);

/// A pump: mass flow [kg/s] against the pressure rise p_out - p_in [Pa], piecewise linear
/// through the given points. The first point holds below its pressure rise; the last point
/// is the shut-off pressure (flow 0); above it no flow (a check valve: never backwards).
struct PumpSpec {
    std::vector<double> pressureRise;  ///< [Pa] strictly increasing, the first >= 0
    std::vector<double> massFlow;      ///< [kg/s] >= 0, non-increasing, the last 0
    /// @throws std::invalid_argument naming the parameter, its unit and the valid range.
    void validate(const std::string& name = "pump") const;
};

/// Pump flow from inlet a to outlet b; `speed` in [0, 1] scales the curve's flow (0: off).
/// The gas leaves at the inlet's temperature (an aftercooled pump), so the flow does not
/// depend on temperature.
Flow calcPumpFlow(const PumpSpec& p, double speed, double pa, double pb);

/// Orifice between chambers or between bags that share air: bags::calcOrificeMassFlow (the
/// incompressible orifice law with its laminar rounding) with the upstream density from the
/// upstream port's p/(R T), and the density's share of the tangent added.
/// @param R specific gas constant [J/(kg K)]
Flow calcOrificeFlow(const bags::OrificeOptions& o, double R, double pa, double Ta, double pb,
                     double Tb);

/// A pressure sensor on one gas volume: reads the gauge pressure p - pAmbient through a
/// first-order lag, plus an offset and Gaussian noise drawn from its own seeded generator.
struct SensorSpec {
    double timeConstant = 0.0;    ///< [s] of the first-order lag, >= 0 (0: no lag)
    double offset = 0.0;          ///< [Pa] added to every reading
    double noiseStdDev = 0.0;     ///< [Pa] standard deviation of the Gaussian noise, >= 0
    unsigned long long seed = 1;  ///< of the noise generator
    /// @throws std::invalid_argument naming the parameter, its unit and the valid range.
    void validate(const std::string& name = "sensor") const;
};

/// The exact first-order response y(t0 + h) of tau y' = u - y to an input that varies
/// linearly from u0 to u1 over [t0, t0 + h] (first-order hold), from y0. tau = 0: y = u1.
double calcFirstOrderLag(double y0, double u0, double u1, double h, double tau);

}  // namespace pneumatics
