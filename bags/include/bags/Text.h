#pragma once
/// @file Small text helpers shared by the readers of tables and scenarios.

#include <string>

namespace bags {

/// s without leading and trailing blanks (space, tab, carriage return, newline).
inline std::string trimBlanks(const std::string& s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return "";
    const auto e = s.find_last_not_of(" \t\r\n");
    return s.substr(b, e - b + 1);
}

}  // namespace bags
