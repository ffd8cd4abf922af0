#pragma once
/// @file A measured stiffness curve k(m) beside the simulated one (docs/diagnosis.md): per gas
/// mass the measured and simulated stiffness over the load range and their stages; where the
/// difference lies (by the stage the measurement states), its bias and scale, and where each
/// curve has its least stiffness (the turn from the seed's stage 1-2 to stage 3).

#include <diagnose/MeasuredData.h>

#include <bags/LoadTest.h>

#include <string>
#include <vector>

namespace diagnose {

struct StiffnessPoint {
    double gasMass = 0.0;    ///< [kg]
    double measured = 0.0;   ///< [N/m]
    double simulated = 0.0;  ///< [N/m]; NaN when the simulated curve gives none
    int measuredStage = 0;   ///< as the data state it (0: not stated)
    int simulatedStage = 0;  ///< the simulation's stage rule (docs/seed-load-test.md), 0: none
    std::string note;        ///< why there is no simulated stiffness (empty otherwise)
};

/// The stiffness residuals over the masses of one stated stage (or "all").
struct StiffnessRegime {
    std::string regime;     ///< "all", "stage 1", "stage 2", "stage 3", "stage not stated"
    int points = 0;         ///< masses with both values
    double rmse = 0.0;      ///< [N/m]
    double bias = 0.0;      ///< mean of measured - simulated [N/m]
    double relative = 0.0;  ///< RMS of (measured - simulated) / measured [-]
    double share = 0.0;     ///< of the squared error over all masses (0-1)
};

struct StiffnessComparison {
    std::vector<StiffnessPoint> points;    ///< by increasing gas mass
    std::vector<StiffnessRegime> regimes;  ///< "all" first, then by stated stage
    /// measured = (1 + scale) x simulated, least squares through the origin [-]
    double scale = 0.0;
    /// Masses whose simulated curve gives no stiffness (stopped, never spanned the range).
    int missing = 0;
    /// The stated stage agrees with the simulated one, of the masses where both are known.
    int stagesAgreeing = 0, stagesCompared = 0;
    /// The gas mass of least stiffness [kg], measured and simulated (NaN if none).
    double leastMeasured = 0.0, leastSimulated = 0.0;
};

/// Compares the measured stiffness curve with the simulated load test `sim`, whose curves were
/// run at the channel's gas masses (in any order: matched by mass within 1e-9 kg).
/// @throws std::invalid_argument when a measured mass has no simulated curve.
StiffnessComparison compareStiffness(const StiffnessChannel& measured,
                                     const bags::LoadTestResult& sim);

}  // namespace diagnose
