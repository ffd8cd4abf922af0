#include <io/InputError.h>

namespace io {

namespace {

std::string buildWhat(const std::string& where, int line, const std::string& key,
                      const std::string& message) {
    std::string out;
    if (!where.empty()) {
        out += where;
        if (line > 0) out += ":" + std::to_string(line);
        out += ": ";
    }
    if (!key.empty()) out += "key '" + key + "': ";
    return out + message;
}

}  // namespace

InputError::InputError(const std::string& where, int line, const std::string& key,
                       const std::string& message)
    : std::runtime_error(buildWhat(where, line, key, message)),
      m_where(where),
      m_line(line),
      m_key(key),
      m_message(message) {}

}  // namespace io
