#pragma once
/// @file Measured data made from a simulation (issue 12's withheld-effect checks): the
/// instruments of the seed's rig sample a truth run's curves at a fixed interval, with the
/// rig's effects (RigEffects) and Gaussian sensor noise. The app runs the truth simulation
/// (`bagsim synth-measurement`, docs/diagnosis.md); this turns its curves into channels.

#include <diagnose/MeasuredData.h>
#include <diagnose/RigEffects.h>

#include <bags/LoadTest.h>

#include <cstdint>
#include <vector>

namespace diagnose {

struct SynthesisOptions {
    double sampleInterval = 0.5;      ///< [s] every instrument samples at this interval
    double displacementNoise = 2e-6;  ///< standard deviation [m]
    double forceNoise = 0.01;         ///< [N]
    double pressureNoise = 5.0;       ///< [Pa]
    double massNoise = 2e-6;          ///< [kg]
    /// The rig has a bed gauge: each test gets the bed board's sink as a channel (a dial gauge
    /// or displacement transducer under the board, against the floor).
    bool bedGauge = false;
    double bedNoise = 2e-6;  ///< the bed gauge's [m]
    std::uint64_t seed = 1;  ///< of the noise (the same seed gives the same data)
    /// @throws std::invalid_argument naming the option and what would be valid.
    void validate() const;
};

/// Samples each truth curve as the instruments read it. `readings` are the gas masses the
/// flowmeter reads, one per curve (the protocol's values, written in the manifest); the
/// curves were run at the masses the bag holds. The protocol is copied into the result.
/// @throws std::invalid_argument if a curve has fewer than two steps.
MeasuredData synthesizeMeasurement(const std::vector<bags::LoadCurve>& truth,
                                   const std::vector<double>& readings, const RigEffects& rig,
                                   const Protocol& protocol, const SynthesisOptions& options);

}  // namespace diagnose
