#pragma once
/// @file printf-style formatting of one number into a string of whatever length it takes
/// (the commands' messages, summaries and verdict texts).

#include <algorithm>
#include <cstdio>
#include <string>

namespace bagsim::app {

/// `f` (a printf format with one double conversion) applied to `v`, never truncated.
inline std::string fmt(const char* f, double v) {
    const int n = std::max(std::snprintf(nullptr, 0, f, v), 0);
    std::string s(size_t(n) + 1, '\0');
    std::snprintf(s.data(), s.size(), f, v);
    s.resize(size_t(n));
    return s;
}

}  // namespace bagsim::app
