#pragma once
// What the HTML reports of a results folder share (report.html of a patient-on-array run,
// io/ArrayReport.h, and of a study, io/StudyReport.h): reading the folder's CSV files with
// located errors, the page's style sheet, status cells, a colour scale, and writing the page
// through a temporary file. The charts themselves are in SvgPlot.h.

#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace io::report {

/// A CSV file of a results folder: its header and rows, with the line of each row for messages.
struct CsvTable {
    std::string path;
    bool present = false;
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
    std::vector<int> lines;

    /// The column's index, -1 if the header has no such column.
    int find(const std::string& name) const;
    /// The cell as a number. @throws InputError (file, line, column) if it is not one.
    double number(size_t row, int column) const;
    const std::string& text(size_t row, int column) const { return rows[row].at(size_t(column)); }
};

/// A results file's whole text (no size limit: a long run's regions.csv is tens of MB).
/// @throws InputError if it is not a regular file or cannot be read.
std::string readWholeFile(const std::filesystem::path& p);
/// The file's text, "" if it does not exist.
std::string readTextIfPresent(const std::filesystem::path& p);

/// Reads a CSV file whose header holds `columns` (others may follow). Absent and `optional`:
/// present = false; absent otherwise: InputError with `missingHelp` (what the folder should
/// hold). A last line without its line break (a run killed while writing it) is skipped; any
/// other row must have the header's number of cells.
CsvTable readCsvTable(const std::filesystem::path& file, const std::vector<std::string>& columns,
                      bool optional, const std::string& missingHelp);

std::string lower(std::string s);
std::string join(const std::vector<std::string>& v, const char* sep = ",");

/// The style sheet of the pages (no fonts or images to fetch).
extern const char* const kCss;

/// A table cell for a status, coloured, with a symbol: ok; warning / partial; fail / failed;
/// anything else (n/a, not-run, interrupted) grey.
std::string formatStatusCell(const std::string& status);

/// A vertical colour scale (viridis from lo to hi) as its own <svg class='colourbar'>.
struct ColourBar {
    double lo = 0.0, hi = 1.0;
    std::string label;          ///< above the scale, with its unit: "pressure [mmHg]"
    std::string title;          ///< hover text
    bool saturatedTop = false;  ///< the top tick reads ">= hi"
    double ref = std::numeric_limits<double>::quiet_NaN();  ///< a marked value (e.g. 32 mmHg)
    std::string refLabel;
    /// Boxes under the scale: (fill colour, text), e.g. ("#fff", "below 0.5").
    std::vector<std::pair<std::string, std::string>> swatches;
    std::string note;     ///< a small line at the bottom ("" none)
    double height = 300;  ///< [px] of the scale itself
};
std::string drawColourBar(const ColourBar& bar);

/// Writes the page to `out` through a temporary file renamed into place, so a reader never
/// sees half a page. @throws std::runtime_error.
void writePageFile(const std::string& html, const std::filesystem::path& out);

}  // namespace io::report
