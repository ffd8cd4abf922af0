#pragma once
/// @file report.html of `bagsim diagnose` (docs/diagnosis.md#output): a self-contained page
/// (inline SVG, no scripts) with the verdict, the where tables, and per test the measured
/// force against displacement and pressure against time beside the simulation before and
/// after the best candidate, and the residuals.

#include <diagnose/Diagnosis.h>
#include <io/DiagnosisJson.h>

#include <string>
#include <vector>

namespace io {

/// The page; `which` may be null (then only the model as it is is drawn).
std::string formatDiagnosisReportHtml(const DiagnosisInfo& info,
                                      const std::vector<diagnose::TestComparison>& tests,
                                      const diagnose::WhereReport& where,
                                      const diagnose::WhichReport* which);

}  // namespace io
