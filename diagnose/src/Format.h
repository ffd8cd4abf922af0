#pragma once
// Private to the diagnose library's sources: what Diagnosis.cpp and Calibration.cpp both use.
#include <cstdio>
#include <limits>
#include <string>

namespace diagnose::detail {

inline const double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One number formatted with the printf format `f` (e.g. "%.4g").
inline std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

}  // namespace diagnose::detail
