#pragma once
/// @file report.html of a patient-on-array run (docs/reading-the-report.md): one
/// self-contained page (inline SVG and CSS, no scripts, fonts or links to fetch) made from the
/// files of a results folder, so it can be remade from any folder, old or interrupted:
/// results.h5 (/meta, /mat), regions.csv, bags.csv, tilt.csv, summary.txt and INCOMPLETE,
/// and, where present, verdict.csv, events.csv, body.csv and pneumatics.csv (a folder
/// without them gets a page without their sections).
///
/// The page: the scenario (name, description, patient, array; its text in a collapsible
/// block), a banner when the run is incomplete, the verdict, pressure-mat images at key
/// moments (after the settle, mid-turn, largest tilt, end) on one colour scale in mmHg, the
/// per-region peak pressure over time, tilt, bag pressures and masses (and pneumatics and
/// the centre of mass when written) over time, with the key moments and events marked.

#include <filesystem>
#include <string>

namespace io {

inline constexpr const char* kReportHtml = "report.html";

/// Reads the results folder and returns the page.
/// @throws InputError naming the folder or file (and line) when the folder is not the output
///   of a patient-on-array run (no results.h5, another kind, a CSV without its header) or a
///   file cannot be read; a last CSV line cut short by a killed run is skipped.
std::string formatArrayReportHtml(const std::filesystem::path& runDir);

/// formatArrayReportHtml() written to `out` through a temporary file renamed into place, so a
/// reader never sees half a page. @throws InputError as above, std::runtime_error on I/O.
void writeArrayReport(const std::filesystem::path& runDir, const std::filesystem::path& out);

}  // namespace io
