#pragma once
/// @file report.html at the end of a patient-on-array run (ReportCommand.cpp).

#include <filesystem>

namespace bagsim::app {

/// Writes dir/report.html from the folder's files once the run has closed them (complete,
/// failed or interrupted: the page then says it is incomplete). Never throws: a page that
/// cannot be made is a warning, the results stay as they are.
void writeReportAfterRun(const std::filesystem::path& dir, bool quiet);

}  // namespace bagsim::app
