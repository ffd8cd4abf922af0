#pragma once
/// @file printf-style formatting of one number into a string of whatever length it takes
/// (the commands' messages, summaries and verdict texts).

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace bagsim::app {

/// `f` (a printf format with one double conversion: f, e, g or a) applied to `v`, never
/// truncated. Any other conversion (%d, %ld of an integer passed as a double) would print
/// garbage, so it throws std::logic_error: format integers with std::to_string.
inline std::string fmt(const char* f, double v) {
    for (const char* c = f; *c; ++c) {
        if (*c != '%') continue;
        if (c[1] == '%') {
            ++c;
            continue;
        }
        const char* e = c + 1;
        while (*e && std::string("-+ #0123456789.").find(*e) != std::string::npos) ++e;
        if (*e == 'l' && (e[1] == 'f' || e[1] == 'e' || e[1] == 'g')) ++e;  // %lf is %f
        if (!*e || std::string("feEgGaA").find(*e) == std::string::npos)
            throw std::logic_error(std::string("fmt: '") + f +
                                   "' is not a format of one double (use std::to_string for an "
                                   "integer)");
        c = e;
    }
    const int n = std::max(std::snprintf(nullptr, 0, f, v), 0);
    std::string s(size_t(n) + 1, '\0');
    std::snprintf(s.data(), s.size(), f, v);
    s.resize(size_t(n));
    return s;
}

}  // namespace bagsim::app
