#pragma once
/// @file The output of `bagsim diagnose` on a patient's data (docs/diagnosis.md#a-patient-on-the-array):
/// diagnosis.json (the where report with the channels' units, the regimes by body region, bag
/// and time window, the signatures; the candidates ranked with their held-out gaps and folds;
/// the verdict), residuals.csv (one row per compared sample) and report.html (a self-contained
/// page: the verdict, the where tables, the candidates, and over time the mat's total force
/// on the compared sensels, the tilt and each bag's pressure, measured beside the model as it is
/// and with the best candidate). Values in the units the keys name (mmHg, deg, kPa, s).

#include <diagnose/PatientDiagnosis.h>
#include <io/DiagnosisJson.h>

#include <string>
#include <vector>

namespace io {

/// diagnosis.json; `which` may be null (--where-only); `folds` the time windows [s] and
/// whether the folds were tests or subjects (`fold_kind`, `tests`, `subjects`, `test_subjects`,
/// each fold's `held_out_test`, or `held_out_subject` and its `held_out_tests`, by name).
std::string formatPatientDiagnosisJson(const DiagnosisInfo& info,
                                       const diagnose::PatientComparison& c,
                                       const diagnose::WhereReport& where,
                                       const diagnose::WhichReport* which,
                                       const diagnose::PatientFolds& folds);

/// residuals.csv ([subject,][test,] first when the tests name subjects, when several tests): channel,unit,part,time_s,sensel_row,sensel_column,measured,simulated,residual
/// (the sensel's row and column from 1 for the mat, empty otherwise); `matColumns` the mat's.
std::string formatPatientResidualsCsv(const diagnose::PatientComparison& c, int matColumns);

/// report.html; `fitted` the comparison with the best candidate at its fit on all windows (null:
/// none).
std::string formatPatientDiagnosisReportHtml(const DiagnosisInfo& info,
                                             const diagnose::PatientComparison& c,
                                             const diagnose::WhereReport& where,
                                             const diagnose::WhichReport* which,
                                             const diagnose::PatientComparison* fitted);

}  // namespace io
