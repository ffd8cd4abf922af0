#pragma once
/// @file Effects of the seed's rig that the airbag model leaves out, as model extensions a
/// scenario can switch on (section `rig`, docs/scenario-reference.md#rig) and the diagnosis can
/// calibrate (docs/diagnosis.md):
///   - the pressure sensor's lag (first order: tubing and filter) and zero offset;
///   - the flowmeter's gas-mass bias (it reads the bag's gas mass plus an offset);
///   - the compliance of the testing machine and bed board, in series with the bag (the
///     crosshead travels the block's travel plus force times compliance);
///   - the bed board's compliance: the board under the bag on a spring, which sinks by the
///     bed's force times its compliance (counted from first contact: the bag's own weight
///     rests on it before). The bag then moves down with the board as a rigid body, so the
///     crosshead travels the block's travel into the bag plus the force times the compliance,
///     and the bag's state (its pressure) at a crosshead travel is what the machine's
///     compliance gives: the two are confusable on the rig's data;
///   - the load cell's gain error (it reads the force times 1 + gain).
///
/// Order of use: RigEffects::validate(); calcBagGasMasses() turns the masses a protocol lists
/// (flowmeter readings) into the masses the bag holds, for bags::runLoadTest; then, per
/// simulated curve, calcMachineCurve() gives what the testing machine records and
/// applyPressureSensor() what the pressure sensor reads.

#include <bags/LoadTest.h>

#include <string>
#include <vector>

namespace diagnose {

struct RigEffects {
    double pressureLag = 0.0;        ///< pressure sensor's first-order time constant [s]
    double pressureOffset = 0.0;     ///< pressure sensor reads gauge pressure + this [Pa]
    double flowmeterOffset = 0.0;    ///< flowmeter reads the bag's gas mass + this [kg]
    double machineCompliance = 0.0;  ///< testing machine and bed board in series [m/N]
    double loadCellGain = 0.0;       ///< the load cell reads the force times 1 + this [-]
    double bedCompliance = 0.0;      ///< the bed board's spring under the bag [m/N]

    /// Physical bounds of each parameter (also the calibration's bounds).
    static constexpr double kMaxPressureLag = 30.0;       ///< [s]
    static constexpr double kMaxPressureOffset = 5000.0;  ///< [Pa] either sign
    /// [kg] either sign: about 6 % of the taut rig's 4 g, several times a thermal mass
    /// flowmeter's stated accuracy (1-2 % of reading)
    static constexpr double kMaxFlowmeterOffset = 0.25e-3;
    static constexpr double kMaxMachineCompliance = 2.0e-3;  ///< [m/N] (0.5 N/mm rig)
    static constexpr double kMaxLoadCellGain = 0.2;          ///< [-] either sign
    static constexpr double kMaxBedCompliance = 2.0e-3;      ///< [m/N] (0.5 N/mm bed)

    /// True when every effect is off (the model as it was).
    bool isNone() const;
    /// @throws std::invalid_argument naming the parameter, its value and the valid range.
    void validate() const;
};

/// Gas masses the bag holds [kg] for the flowmeter readings a protocol lists [kg].
/// @throws std::invalid_argument if a mass would be zero or negative.
std::vector<double> calcBagGasMasses(const std::vector<double>& readings, const RigEffects& rig);

/// A simulated curve as the testing machine records it, at the simulation's steps.
struct MachineCurve {
    std::vector<double> time;          ///< [s] crosshead path / rate, from first contact
    std::vector<double> displacement;  ///< crosshead travel [m] (block travel + F (c + c_bed))
    std::vector<double> force;         ///< as the load cell reads it [N]
    std::vector<double> pressure;      ///< true gauge pressure of the bag [Pa] (chamber mean)
    std::vector<double> bedSink;       ///< the bed board's sink [m] (force times c_bed)
    std::vector<char> loading;         ///< 1 on the loading branch
};

/// What the testing machine records of a simulated curve (with the rig's and the bed's
/// compliance and the load cell's gain); `rate` is the crosshead speed [m/s].
MachineCurve calcMachineCurve(const bags::LoadCurve& curve, const RigEffects& rig, double rate);

/// Pressure sensor readings [Pa] of a gauge pressure p [Pa] given at increasing times t [s]:
/// first-order lag (exact for p linear between samples; the sensor at rest at p[0] before)
/// plus the offset.
std::vector<double> applyPressureSensor(const std::vector<double>& t, const std::vector<double>& p,
                                        const RigEffects& rig);

/// Linear interpolation of y(x) at xq on increasing x; beyond the ends the first or last
/// segment is extended. Needs at least one point.
double interpolate(const std::vector<double>& x, const std::vector<double>& y, double xq);

}  // namespace diagnose
