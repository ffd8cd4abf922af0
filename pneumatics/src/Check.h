#pragma once
/// @file The parameter check every pneumatics validate() uses.

#include <string>

namespace pneumatics {

/// @throws std::invalid_argument "<owner>: '<parameter>' = <value> <unit> is invalid; valid:
/// <valid>" unless ok.
void checkParameter(bool ok, const std::string& owner, const char* parameter, double value,
                    const char* unit, const char* valid);

}  // namespace pneumatics
