#pragma once
/// @file bagsim run for the scenario kind patient-on-support (called from RunCommand.cpp).

#include <io/Scenario.h>

#include <string>

namespace bagsim::app {

/// Settles the scenario's patient on the rigid flat support, prints the support force against
/// the body weight and the share per region, writes region_loads.csv and summary.txt into the
/// output folder. Returns the exit status (0 done, 1 run failed, 2 bad input, 130/143
/// interrupted by SIGINT/SIGTERM: needs the caller's InterruptGuard).
int runPatientOnSupport(const io::ScenarioFile& file, const std::string& out, bool force,
                        bool quiet);

}  // namespace bagsim::app
