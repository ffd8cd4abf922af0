#pragma once
// Helpers for the end-to-end tests of `bagsim run` on patient-on-array scenarios: run the
// program on a scenario of scenarios/tests/ and read back the CSV files it wrote.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace app::test {

/// A CSV file: its header line and its rows split at commas.
struct Csv {
    std::string header;
    std::vector<std::vector<std::string>> rows;
    /// Column index of a header name (-1 if absent).
    int column(const std::string& name) const {
        std::stringstream s(header);
        std::string cell;
        for (int i = 0; std::getline(s, cell, ','); ++i)
            if (cell == name) return i;
        return -1;
    }
};

/// Reads a CSV file; with skipComments, lines starting with '#' (a reference file's notes)
/// are left out.
inline Csv readCsv(const std::filesystem::path& path, bool skipComments = false) {
    Csv c;
    std::ifstream in(path);
    while (std::getline(in, c.header) && skipComments && c.header.rfind('#', 0) == 0) {
    }
    for (std::string line; std::getline(in, line);) {
        if (skipComments && line.rfind('#', 0) == 0) continue;
        std::vector<std::string> cells;
        std::stringstream s(line);
        for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
        c.rows.push_back(cells);
    }
    return c;
}

/// Runs `bagsim run scenarios/tests/<scenario> --out <out> --quiet <extra>` with the output
/// folder removed first; returns the exit status.
inline int runScenario(const std::string& scenario, const std::filesystem::path& out,
                       const std::string& extra = "") {
    std::filesystem::remove_all(out);
    const std::string cmd = std::string("\"") + BAGSIM_BINARY_DIR + "/bin/bagsim\" run \"" +
                            BAGSIM_SOURCE_DIR + "/scenarios/tests/" + scenario + "\" --out \"" +
                            out.string() + "\" --quiet " + extra + " > \"" + out.string() +
                            ".log\" 2>&1";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// Sum of a column per distinct time (column time_s), in time order.
inline std::map<double, double> sumPerTime(const Csv& c, const std::string& name) {
    std::map<double, double> sum;
    const int t = c.column("time_s"), v = c.column(name);
    for (const auto& r : c.rows) sum[std::stod(r.at(t))] += std::stod(r.at(v));
    return sum;
}

}  // namespace app::test
