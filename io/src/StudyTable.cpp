#include <bagsim/Version.h>
#include <io/StudyTable.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "Hdf5.h"

namespace io {

namespace {

bool isNumber(const std::string& s, double* v) {
    if (s.empty()) {
        *v = std::nan("");
        return true;
    }
    char* end = nullptr;
    *v = std::strtod(s.c_str(), &end);
    return end != s.c_str() && *end == '\0';
}

}  // namespace

std::string quoteCsvCell(const std::string& cell) {
    if (cell.find_first_of(",\"\n\r") == std::string::npos) return cell;
    std::string q = "\"";
    for (char c : cell) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
    return q + "\"";
}

std::vector<std::string> splitCsvLine(const std::string& line) {
    std::vector<std::string> cells(1);
    bool quoted = false;
    for (size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
                cells.back() += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                cells.back() += c;
            }
        } else if (c == '"') {
            quoted = true;
        } else if (c == ',') {
            cells.emplace_back();
        } else if (c != '\r') {
            cells.back() += c;
        }
    }
    return cells;
}

void writeStudyCsv(const StudyTable& t, const std::string& path) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::trunc);
        auto line = [&](const std::vector<std::string>& cells) {
            for (size_t i = 0; i < cells.size(); ++i)
                out << (i ? "," : "") << quoteCsvCell(cells[i]);
            out << "\n";
        };
        line(t.header);
        for (const auto& r : t.rows) line(r);
        out.flush();
        if (!out) throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(errno));
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw std::runtime_error("cannot write " + path + ": " + ec.message());
}

void writeStudyH5(const StudyTable& t, const std::string& path) {
    h5::silenceErrors();
    const std::string tmp = path + ".tmp";
    {
        h5::Handle file = h5::createFile(tmp);
        h5::setAttribute(file.get(), "format", std::string("bagsim-study 1"));
        h5::setAttribute(file.get(), "version", std::string(bagsim::kVersion));
        h5::setAttribute(file.get(), "status", t.status);
        h5::setAttribute(file.get(), "study_file", t.studyFile);
        h5::setAttribute(file.get(), "study_text", t.studyText);
        h5::setAttribute(file.get(), "base_scenario_text", t.baseText);
        h5::setAttribute(file.get(), "command_line", t.commandLine);
        h5::Handle table = h5::createGroup(file.get(), "table");
        h5::setAttribute(table.get(), "columns", t.header);
        const hsize_t n = t.rows.size();
        for (size_t c = 0; c < t.header.size(); ++c) {
            std::vector<double> numbers(n);
            bool numeric = true;
            for (size_t r = 0; r < n && numeric; ++r)
                numeric = isNumber(c < t.rows[r].size() ? t.rows[r][c] : "", &numbers[r]);
            char name[24];
            std::snprintf(name, sizeof name, "%03zu", c);
            if (numeric) {
                h5::writeDataset(table.get(), name, {n}, numbers.data(), "");
            } else {
                // Variable-length UTF-8 strings, one per row.
                std::vector<const char*> cells(n);
                for (size_t r = 0; r < n; ++r)
                    cells[r] = c < t.rows[r].size() ? t.rows[r][c].c_str() : "";
                h5::Handle type(h5::check(H5Tcopy(H5T_C_S1), "string type"));
                h5::check(H5Tset_size(type.get(), H5T_VARIABLE), "string type");
                h5::check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string type");
                const hsize_t dims[1] = {n};
                h5::Handle space(h5::check(H5Screate_simple(1, dims, nullptr), "dataspace"));
                h5::Handle ds(h5::check(H5Dcreate2(table.get(), name, type.get(), space.get(),
                                                   H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                                        "dataset " + std::string(name)));
                if (n > 0)
                    h5::check(
                        H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, cells.data()),
                        "dataset " + std::string(name));
                h5::setAttribute(ds.get(), "name", t.header[c]);
                continue;
            }
            h5::Handle ds(h5::check(H5Dopen2(table.get(), name, H5P_DEFAULT), name));
            h5::setAttribute(ds.get(), "name", t.header[c]);
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw std::runtime_error("cannot write " + path + ": " + ec.message());
}

}  // namespace io
