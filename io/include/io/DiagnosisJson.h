#pragma once
/// @file diagnosis.json and residuals.csv of `bagsim diagnose` (docs/diagnosis.md#output):
/// the where report (channels, regimes, signatures) and, when run, the which report
/// (candidates ranked, held-out gap before and after, shrink, verdict). Values are in the
/// units the keys or a "unit" field name (N, kPa, g, s, mm), never bare SI.

#include <diagnose/Diagnosis.h>

#include <string>
#include <vector>

namespace io {

struct DiagnosisInfo {
    std::string measuredFolder;
    std::string scenarioFile;
    std::string program;      ///< "bagsim 0.1.0"
    std::string commandLine;
    int simulations = 0;      ///< load tests run in all
    double seconds = 0.0;     ///< wall time
};

/// The whole diagnosis as JSON text; `which` may be null (part 2 not run).
std::string formatDiagnosisJson(const DiagnosisInfo& info, const diagnose::WhereReport& where,
                                const diagnose::WhichReport* which);

/// One row per compared sample: test,gas_mass_g,channel,unit,time_s,displacement_mm,branch,
/// measured,simulated,residual (channel values in the channel's unit).
std::string formatResidualsCsv(const std::vector<diagnose::TestComparison>& tests);

}  // namespace io
