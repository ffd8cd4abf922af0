#pragma once
/// @file Lays a patient on the rigid flat support (PlaneSupport) and lets them settle under
/// gravity: the model is built from a PatientSpec, placed in its posture just above the plane
/// and integrated for a settle time. The report gives the support force against the body
/// weight, the share of the weight under each named region and how still the body is at the
/// end. Used by the scenario kind patient-on-support (docs/scenario-reference.md).

#include <functional>
#include <string>
#include <vector>

#include "body/PatientSpec.h"
#include "body/SupportContact.h"

namespace body {

/// How the settle is run.
struct SettleOptions {
    PlaneSupportOptions support;  ///< the flat support
    double settleTime = 2.0;      ///< simulated time [s], > 0 and at most 60
    double accuracy = 1e-4;       ///< integrator relative accuracy [-], in (0, 0.1]
    /// If set, called with the simulated time [s] every 0.1 s of it; may throw to stop the
    /// settle (the exception leaves settleOnSupport()). For a program's Ctrl-C.
    std::function<void(double time)> monitor;
    /// @throws std::invalid_argument naming the option and what is valid.
    void validate() const;
};

/// What the support carries once the patient has settled.
struct SettleReport {
    double mass = 0;                       ///< total body mass [kg]
    double weight = 0;                     ///< m g with the model's gravity [N]
    SupportLoad load;                      ///< support force, per region and segment, at the end
    std::vector<std::string> regionNames;  ///< names of load.regionForce's entries
    double drift = 0;          ///< horizontal motion of the pelvis over the last 0.5 s [m]
    double maxSpeed = 0;       ///< largest segment-origin speed at the end [m/s]
    double simulatedTime = 0;  ///< [s]
    double wallSeconds = 0;    ///< wall-clock time of the integration [s]
    int steps = 0;             ///< integrator steps taken
};

/// Builds the patient, lays them on the flat support and integrates for options.settleTime.
/// @throws std::invalid_argument if spec or options are invalid.
SettleReport settleOnSupport(const PatientSpec& spec, const SettleOptions& options = {});

}  // namespace body
