#pragma once
// Helpers shared by the report tests (a run's and a study's report.html).
#include <io/InputError.h>

#include <filesystem>
#include <string>

namespace io::test {

/// An empty folder for a test's output under the build tree (its parent made; itself removed).
inline std::filesystem::path makeReportTestDir(const std::string& name) {
    const std::filesystem::path p =
        std::filesystem::path(BAGSIM_BINARY_DIR) / "test-output" / "io" / name;
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p.parent_path());
    return p;
}

/// How often `what` occurs in `s` (overlapping occurrences counted).
inline int countOccurrences(const std::string& s, const std::string& what) {
    int n = 0;
    for (size_t i = s.find(what); i != std::string::npos; i = s.find(what, i + 1)) ++n;
    return n;
}

/// The message of the InputError that `format(dir)` throws, or "(no error)".
template <class Format>
std::string reportErrorOf(const Format& format, const std::filesystem::path& dir) {
    try {
        format(dir);
    } catch (const io::InputError& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace io::test
