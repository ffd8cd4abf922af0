#pragma once
/// @file The table a study writes (docs/studies.md#outputs): study.csv and study.h5, a row per
/// case, its parameters (units in the header), its status, the reason it failed and the
/// outputs collected. A column whose every cell is a number (or empty) is numeric in study.h5;
/// others are strings.

#include <string>
#include <vector>

namespace io {

struct StudyTable {
    std::vector<std::string> header;             ///< column names, units in brackets
    std::vector<std::vector<std::string>> rows;  ///< cells as text, "" if none
    std::string status;       ///< "complete", "incomplete" (some cases not run) or "interrupted"
    std::string studyFile;    ///< as given
    std::string studyText;    ///< verbatim
    std::string baseText;     ///< the base scenario, verbatim
    std::string commandLine;  ///< for the record
};

/// Writes the table as CSV (RFC 4180 quoting where a cell needs it), through a temporary file
/// renamed into place so a reader never sees half a table. @throws std::runtime_error.
void writeStudyCsv(const StudyTable& table, const std::string& path);
/// Writes the table as HDF5: /table/<column index> datasets (attribute name), the status and
/// the study and base scenario texts as root attributes. @throws std::runtime_error.
void writeStudyH5(const StudyTable& table, const std::string& path);
/// Quotes a CSV cell if it holds a comma, a quote or a line break.
std::string quoteCsvCell(const std::string& cell);
/// Splits one CSV line into cells (quoted cells as quoteCsvCell() writes them).
std::vector<std::string> splitCsvLine(const std::string& line);

}  // namespace io
