#pragma once
/// @file The one exception type for mistakes a user can make in a scenario or on the command
/// line. Its message names where (file and line, or the --set option), which key, the value
/// and what would be valid, e.g.
///   scenarios/x.yaml:12: key 'gas.temperature': "23" has no unit; a temperature needs one of
///   K, degC (e.g. "23 degC")

#include <stdexcept>
#include <string>

namespace io {

class InputError : public std::runtime_error {
  public:
    /// @param where file name, or "--set KEY" for a command-line override, or "" if unknown
    /// @param line 1-based line in that file, 0 if unknown
    /// @param key dotted key path ("gas.temperature"), "" for the file as a whole
    /// @param message what is wrong and what would be valid
    InputError(const std::string& where, int line, const std::string& key,
               const std::string& message);

    const std::string& getWhere() const { return m_where; }      ///< file or "--set KEY"
    int getLine() const { return m_line; }                       ///< 1-based, 0 if unknown
    const std::string& getKey() const { return m_key; }          ///< dotted key path
    const std::string& getMessage() const { return m_message; }  ///< without the location

  private:
    std::string m_where;
    int m_line;
    std::string m_key;
    std::string m_message;
};

}  // namespace io
