#pragma once
/// @file diagnosis.json and residuals.csv of `bagsim diagnose` (docs/diagnosis.md#output):
/// the where report (channels, regimes, signatures) and, when run, the which report
/// (candidates ranked, held-out gap before and after, shrink, verdict). Values are in the
/// units the keys or a "unit" field name (N, kPa, g, s, mm), never bare SI.

#include <diagnose/Diagnosis.h>
#include <diagnose/Stiffness.h>
#include <diagnose/StiffnessWhich.h>

#include <string>
#include <vector>

namespace io {

struct DiagnosisInfo {
    std::string measuredFolder;
    std::string scenarioFile;
    std::string program;  ///< "bagsim 0.1.0"
    std::string commandLine;
    int simulations = 0;   ///< load tests run in all
    double seconds = 0.0;  ///< wall time
};

/// The whole diagnosis as JSON text; `which` may be null (part 2 not run); `stiffness`, when
/// given, the measured stiffness curve beside the simulated one (key `stiffness`), and
/// `curveWhich` the which part on it (key `stiffness_which`; `curveNotRun` says why when it
/// did not run); a `where` without channels (no tests, a stiffness curve alone) is written as
/// null, and the verdict is then the curve's.
std::string formatDiagnosisJson(const DiagnosisInfo& info, const diagnose::WhereReport& where,
                                const diagnose::WhichReport* which,
                                const diagnose::StiffnessComparison* stiffness = nullptr,
                                const diagnose::StiffnessWhich* curveWhich = nullptr,
                                const std::string& curveNotRun = "");

/// A stated input uncertainty as the outputs say it: "0.05 g (every test)", "0.05 g, 0.04 g,
/// not stated (per test)", "0.5 K", or "not stated".
std::string formatStatedInput(const diagnose::WhereReport::StatedInput& stated);

/// One row per compared sample: test,gas_mass_g,channel,unit,time_s,displacement_mm,branch,
/// measured,simulated,residual (channel values in the channel's unit).
std::string formatResidualsCsv(const std::vector<diagnose::TestComparison>& tests);

/// One row per gas mass: gas_mass_g,measured_N_per_mm,simulated_N_per_mm,difference_N_per_mm,
/// measured_stage,simulated_stage,note (no simulated stiffness: empty cells and the reason).
std::string formatStiffnessCsv(const diagnose::StiffnessComparison& stiffness);

}  // namespace io
