#pragma once
/// @file The reduced bag's calibration file (cosim::ReducedBagCalibration) as text: written by
/// the calibration (bench_reduced_bag calibrate), read for `bag: {model: reduced}`. Line
/// format and every record: docs/reduced-bag.md#calibration. SI units throughout.

#include <cosim/PatientOnArray.h>
#include <cosim/ReducedBag.h>
#include <io/Scenario.h>

#include <memory>
#include <string>

namespace io {

/// Reads and checks a calibration file. @throws InputError naming the file, line and record
/// (a missing file, an unknown or misspelt record, a bad number, tables that do not fit).
std::shared_ptr<const cosim::ReducedBagCalibration> readReducedBagCalibration(
    const std::string& path);

/// The `bag` section's keys `model` (finite-element, the default, or reduced) and
/// `calibration` (a file relative to the scenario's folder `fileName` is in): sets
/// options.model and options.reduced. @throws InputError at the key: an unknown model, a
/// missing or unreadable file, a calibration of another bag or mesh (bag.reading, mesh_size).
void readReducedBagKeys(const ScenarioNode& bag, cosim::PatientOnArrayOptions& options,
                        const std::string& fileName);

/// Writes a calibration (full precision). @throws std::runtime_error if it cannot be written.
void writeReducedBagCalibration(const std::string& path, const cosim::ReducedBagCalibration& c);

}  // namespace io
