#pragma once
/// @file report.html at the end of a patient-on-array run or of a study (ReportCommand.cpp).

#include <filesystem>

namespace bagsim::app {

/// Writes dir/report.html from the folder's files once the run has closed them (complete,
/// failed or interrupted: the page then says it is incomplete). Never throws: a page that
/// cannot be made is a warning, the results stay as they are.
void writeReportAfterRun(const std::filesystem::path& dir, bool quiet);

/// Writes dir/report.html from a study's folder once the study has written its table
/// (complete, or incomplete: the page then says which cases are missing). Never throws: a
/// page that cannot be made is a warning. @return true if written.
bool writeStudyReportAfterRun(const std::filesystem::path& dir);

}  // namespace bagsim::app
