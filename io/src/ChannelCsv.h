#pragma once
// Private to the io library: what the measured-data readers and writers share (the rig's,
// MeasuredData.cpp, and the patient's, PatientMeasuredData.cpp): splitting a CSV line, a
// header cell's name and unit, the units of a dimension for messages, and writing a folder's
// file through a temporary one.
#include <io/Units.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace io::csv {

inline std::string trim(const std::string& s) {
    const size_t b = s.find_first_not_of(" \t\r\"");
    if (b == std::string::npos) return "";
    const size_t e = s.find_last_not_of(" \t\r\"");
    return s.substr(b, e - b + 1);
}

inline std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

/// The cells of a line split at commas, each trimmed of blanks and quotes.
inline std::vector<std::string> splitCsv(const std::string& line) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream is(line);
    while (std::getline(is, cell, ',')) cells.push_back(trim(cell));
    if (!line.empty() && line.back() == ',') cells.push_back("");
    return cells;
}

/// Reads the next line of `in` that holds data, skipping blank lines and '#' comments (an
/// instrument's preamble) and dropping a trailing CR: its trimmed text and its cells; lineNo
/// counts every line read (1-based). False at the end of the stream.
inline bool nextDataLine(std::istream& in, int& lineNo, std::string& trimmed,
                         std::vector<std::string>& cells) {
    std::string line;
    while (std::getline(in, line)) {
        ++lineNo;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        trimmed = trim(line);
        if (trimmed.empty() || trimmed[0] == '#') continue;
        cells = splitCsv(line);
        return true;
    }
    return false;
}

/// "force_N" / "force [N]" / "force (N)" -> {"force", "N"}; no unit -> {name, ""}.
inline std::pair<std::string, std::string> splitHeader(const std::string& h) {
    for (const char open : {'[', '('}) {
        const size_t p = h.find(open);
        if (p != std::string::npos) {
            const char close = open == '[' ? ']' : ')';
            const size_t q = h.find(close, p);
            return {trim(h.substr(0, p)),
                    trim(h.substr(p + 1, q == std::string::npos ? q : q - p - 1))};
        }
    }
    const size_t u = h.rfind('_');  // the unit follows the last '_': gas_mass_g
    if (u == std::string::npos) return {trim(h), ""};
    return {trim(h.substr(0, u)), trim(h.substr(u + 1))};
}

/// "kPa, Pa, MPa, ..." for messages.
inline std::string listUnits(Dimension d) {
    std::string s;
    for (const UnitInfo& u : getUnits(d)) s += (s.empty() ? "" : ", ") + u.symbol;
    return s;
}

inline std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

/// Writes `name` into `dir` through a temporary file renamed into place; appends the name to
/// `names`. @throws std::runtime_error if it cannot be written.
inline void writeFolderFile(const std::filesystem::path& dir, const std::string& name,
                            const std::string& text, std::vector<std::string>& names) {
    const std::filesystem::path f = dir / name;
    const std::filesystem::path tmp = dir / (name + ".tmp");
    {
        std::ofstream o(tmp);
        o << text;
        if (!o.flush()) throw std::runtime_error(f.string() + ": write failed");
    }
    std::filesystem::rename(tmp, f);
    names.push_back(name);
}

}  // namespace io::csv
