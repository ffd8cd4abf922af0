#pragma once
/// @file bagsim run for the scenario kind patient-on-array (called from RunCommand.cpp).

#include <io/Scenario.h>

#include <string>

namespace bagsim::app {

/// Builds the patient on the airbag array, lowers him, lets him settle and runs the gas
/// schedule; streams regions.csv, bags.csv, tilt.csv, results.h5 (mat frames), results.xdmf
/// and summary.txt into the output folder. Returns the exit status (0 done, 1 run failed,
/// 2 bad input, 130/143 interrupted by SIGINT/SIGTERM: needs the caller's InterruptGuard).
int runPatientOnArray(const io::ScenarioFile& file, const std::string& out, bool force, bool quiet,
                      const std::string& commandLine);

}  // namespace bagsim::app
