#pragma once
/// @file report.html of a study (docs/studies.md#the-report): one self-contained page (inline
/// SVG and CSS, no scripts, fonts or links to fetch) made from the files of a study's folder,
/// so it can be remade from any study folder, finished or not: study.csv (required), study.h5
/// (the study file's and the base scenario's text), INCOMPLETE, and each case's
/// cases/<key>/load_displacement.csv where the case's run wrote one.
///
/// The page: a banner when cases are missing, the cases that failed or are partial with their
/// reasons, the study (file, base scenario, the overrides of every case, the swept parameters,
/// the outputs collected; the texts in collapsible blocks), the table of cases, per swept
/// numeric parameter each numeric output plotted against it (one line per combination of the
/// other parameters), a map of each output over the pressed position of a block of bags
/// (airbag.neighbours.pressed) with its colour scale and unit, the change of the stiffness
/// against the bag alone where airbag.neighbours.layout sweeps `none` with others, and the
/// load-displacement curves of the cases.

#include <filesystem>
#include <string>

namespace io {

/// True if the folder is a study's: it holds study.csv or the study runner's stamp.
bool isStudyFolder(const std::filesystem::path& dir);

/// Reads the study folder and returns the page.
/// @throws InputError naming the folder or file (and line) when the folder is not a study's or
///   holds no study.csv yet, when study.csv lacks the columns a study table has, or when a file
///   cannot be read; a case's load_displacement.csv that cannot be read is left out and named.
std::string formatStudyReportHtml(const std::filesystem::path& studyDir);

/// formatStudyReportHtml() written to `out` through a temporary file renamed into place.
/// @throws InputError as above, std::runtime_error on I/O.
void writeStudyReport(const std::filesystem::path& studyDir, const std::filesystem::path& out);

}  // namespace io
