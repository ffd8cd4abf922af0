#include <io/Scenario.h>
#include <bags/Text.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace io {

struct ScenarioFile::Source {
    std::string fileName;
    std::string text;
    std::vector<std::string> overrides;     ///< "key=value" as given
    std::set<std::string> overriddenPaths;  ///< dotted paths replaced by --set
};

namespace {

using bags::trimBlanks;

std::string joinQuoted(const std::vector<std::string>& words) {
    std::string out;
    for (const std::string& w : words) {
        if (!out.empty()) out += ", ";
        out += w;
    }
    return out;
}

std::vector<std::string> splitPath(const std::string& path) {
    std::vector<std::string> parts;
    std::string part;
    std::istringstream in(path);
    while (std::getline(in, part, '.')) parts.push_back(part);
    return parts;
}

int toLine(const YAML::Mark& m) { return m.line >= 0 ? m.line + 1 : 0; }

std::string sectionName(const std::string& path) {
    return path.empty() ? "the scenario's top level" : "section '" + path + "'";
}

}  // namespace

int calcEditDistance(const std::string& a, const std::string& b) {
    std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = static_cast<int>(j);
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = static_cast<int>(i);
        for (size_t j = 1; j <= b.size(); ++j) {
            const int subst = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, subst});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::string findClosest(const std::string& word, const std::vector<std::string>& candidates) {
    // Case differences count as small: compare lower-case first, then exact distance.
    auto lower = [](std::string s) {
        for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return s;
    };
    std::string best;
    int bestDistance = 1 << 30;
    for (const std::string& c : candidates) {
        const int d =
            2 * calcEditDistance(lower(word), lower(c)) + (lower(word) == lower(c) ? 1 : 0);
        if (d < bestDistance) {
            bestDistance = d;
            best = c;
        }
    }
    const int limit = std::max(2, static_cast<int>(word.size()) / 3);
    if (best.empty() || bestDistance / 2 > limit) return "";
    return best;
}

std::string readInputFile(const std::string& path, std::uintmax_t maxBytes,
                          const std::string& what) {
    namespace fs = std::filesystem;
    auto formatSize = [](std::uintmax_t bytes) {
        char buf[48];
        if (bytes >= 1024 * 1024)
            std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
        else
            std::snprintf(buf, sizeof buf, "%.0f kiB", std::ceil(double(bytes) / 1024.0));
        return std::string(buf);
    };
    const std::string limit = "a " + what + " may be at most " + formatSize(maxBytes);
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status))
        throw InputError(path, 0, "",
                         "cannot read the " + what + " (" +
                             (ec ? ec.message() : std::string("no such file")) + ")");
    if (fs::is_directory(status)) throw InputError(path, 0, "", "is a folder; give a " + what);
    // A pipe or a device would block the program or never end: only files on disk are read.
    if (!fs::is_regular_file(status))
        throw InputError(path, 0, "",
                         "is not a regular file (a pipe, socket or device); give the " + what +
                             " as a file on disk");
    const std::uintmax_t size = fs::file_size(path, ec);
    if (!ec && size > maxBytes)
        throw InputError(path, 0, "",
                         "is " + std::to_string(size) + " bytes; " + limit + " (" +
                             std::to_string(maxBytes) + " bytes)");
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        const std::string reason = std::strerror(errno);
        throw InputError(path, 0, "", "cannot read the " + what + " (" + reason + ")");
    }
    // Read at most one byte past the limit, so a file that grows while read still ends; the
    // buffer starts at the file's size (not the limit: a 256 MiB limit would cost its zeroing).
    const size_t limitBytes = static_cast<size_t>(maxBytes) + 1;
    std::string text(ec ? limitBytes : std::min(limitBytes, static_cast<size_t>(size) + 1), '\0');
    in.read(&text[0], static_cast<std::streamsize>(text.size()));
    size_t got = static_cast<size_t>(in.gcount());
    while (got == text.size() && text.size() < limitBytes) {  // it grew: read on
        text.resize(std::min(limitBytes, 2 * text.size()));
        in.read(&text[got], static_cast<std::streamsize>(text.size() - got));
        got += static_cast<size_t>(in.gcount());
    }
    text.resize(got);
    if (text.size() > maxBytes)
        throw InputError(path, 0, "", "grew past the limit while read; " + limit);
    return text;
}

// ---------------------------------------------------------------------------------------------
// ScenarioFile

ScenarioFile ScenarioFile::load(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw InputError(path, 0, "",
                         "is a folder; give a scenario file (e.g. "
                         "scenarios/seed-load-test.yaml)");
    return parse(readInputFile(path, kMaxScenarioBytes, "scenario file"), path);
}

ScenarioFile ScenarioFile::parse(const std::string& text, const std::string& name) {
    ScenarioFile file;
    file.m_source = std::make_shared<Source>();
    file.m_source->fileName = name;
    file.m_source->text = text;
    try {
        const std::vector<YAML::Node> documents = YAML::LoadAll(text);
        if (documents.size() > 1)
            throw InputError(name, toLine(documents[1].Mark()), "",
                             "a second YAML document (after '---'): a scenario is one document; "
                             "put each scenario in a file of its own");
        file.m_root = documents.empty() ? YAML::Node() : documents.front();
    } catch (const YAML::ParserException& e) {
        throw InputError(name, toLine(e.mark), "", "not valid YAML: " + e.msg);
    }
    if (!file.m_root || file.m_root.IsNull()) {
        file.m_root = YAML::Node(YAML::NodeType::Map);
    } else if (!file.m_root.IsMap()) {
        throw InputError(name, toLine(file.m_root.Mark()), "",
                         "a scenario is a set of 'key: value' lines (a YAML mapping), starting "
                         "with 'kind:'");
    }
    return file;
}

void ScenarioFile::applyOverride(const std::string& keyPath, const std::string& value) {
    const std::string where = "--set " + keyPath;
    const std::vector<std::string> parts = splitPath(keyPath);
    if (keyPath.empty() ||
        std::any_of(parts.begin(), parts.end(), [](const std::string& p) { return p.empty(); }))
        throw InputError(where, 0, "",
                         "the key path must be section.key, e.g. airbag.mesh_size=\"5 mm\"");
    YAML::Node valueNode;
    try {
        valueNode = YAML::Load(value);
    } catch (const YAML::ParserException&) {
        valueNode = YAML::Node(value);
    }
    YAML::Node cur;
    cur.reset(m_root);
    std::string path;
    for (size_t i = 0; i + 1 < parts.size(); ++i) {
        path += (path.empty() ? "" : ".") + parts[i];
        YAML::Node child;
        bool found = false;
        for (auto it = cur.begin(); it != cur.end(); ++it) {
            if (it->first.IsScalar() && it->first.Scalar() == parts[i]) {
                child.reset(it->second);
                found = true;
                break;
            }
        }
        if (!found || child.IsNull()) {
            cur[parts[i]] = YAML::Node(YAML::NodeType::Map);
            child.reset(cur[parts[i]]);
        } else if (!child.IsMap()) {
            throw InputError(where, 0, path,
                             "is not a section, so it has no key '" + parts[i + 1] + "'");
        }
        cur.reset(child);
    }
    cur[parts.back()] = valueNode;
    m_source->overrides.push_back(keyPath + "=" + value);
    m_source->overriddenPaths.insert(keyPath);
}

void ScenarioFile::applyOverride(const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos)
        throw InputError("--set " + assignment, 0, "",
                         "expected KEY=VALUE, e.g. --set airbag.mesh_size=\"5 mm\"");
    applyOverride(trimBlanks(assignment.substr(0, eq)), trimBlanks(assignment.substr(eq + 1)));
}

ScenarioFile::ScenarioFile(const ScenarioFile& other)
    : m_source(other.m_source ? std::make_shared<Source>(*other.m_source) : nullptr),
      m_root(YAML::Clone(other.m_root)) {}

ScenarioFile& ScenarioFile::operator=(const ScenarioFile& other) {
    if (this != &other) {
        ScenarioFile copy(other);
        *this = std::move(copy);
    }
    return *this;
}

ScenarioFile::~ScenarioFile() = default;

const std::string& ScenarioFile::getFileName() const { return m_source->fileName; }
const std::string& ScenarioFile::getText() const { return m_source->text; }
const std::vector<std::string>& ScenarioFile::getOverrides() const { return m_source->overrides; }

std::string ScenarioFile::getStem() const {
    return std::filesystem::path(m_source->fileName).stem().string();
}

ScenarioNode ScenarioFile::getRoot() const {
    return ScenarioNode(m_source, m_root, "", m_root.Mark());
}

// ---------------------------------------------------------------------------------------------
// ScenarioNode

ScenarioNode::ScenarioNode(std::shared_ptr<const ScenarioFile::Source> source, YAML::Node node,
                           std::string path, YAML::Mark keyMark)
    : m_source(std::move(source)), m_node(node), m_path(std::move(path)), m_keyMark(keyMark) {}

std::string ScenarioNode::getChildPath(const std::string& key) const {
    return m_path.empty() ? key : m_path + "." + key;
}

std::string ScenarioNode::getWhere(const std::string& path) const {
    // An override of a key or of any section containing it moves the error to the command line.
    for (const std::string& o : m_source->overriddenPaths)
        if (path == o || path.rfind(o + ".", 0) == 0 || path.rfind(o + "[", 0) == 0)
            return "--set " + o;
    return m_source->fileName;
}

int ScenarioNode::getLine() const {
    if (getWhere(m_path) != m_source->fileName) return 0;
    return toLine(m_keyMark);
}

int ScenarioNode::getLine(const std::string& key) const {
    YAML::Node value;
    YAML::Mark mark;
    if (findEntry(key, &value, &mark)) {
        if (getWhere(getChildPath(key)) != m_source->fileName) return 0;
        return toLine(mark);
    }
    return getLine();
}

bool ScenarioNode::findEntry(const std::string& key, YAML::Node* value, YAML::Mark* keyMark) const {
    if (!m_node.IsMap()) return false;
    for (auto it = m_node.begin(); it != m_node.end(); ++it) {
        if (it->first.IsScalar() && it->first.Scalar() == key) {
            value->reset(it->second);
            *keyMark = it->first.Mark();
            if (keyMark->line < 0) *keyMark = it->second.Mark();
            return true;
        }
    }
    return false;
}

void ScenarioNode::fail(const std::string& message) const {
    throw InputError(getWhere(m_path), getLine(), m_path, message);
}

void ScenarioNode::fail(const std::string& key, const std::string& message) const {
    const std::string path = getChildPath(key);
    throw InputError(getWhere(path), getLine(key), path, message);
}

std::string ScenarioNode::getValueText() const {
    if (m_node.IsScalar()) return "\"" + m_node.Scalar() + "\"";
    if (m_node.IsSequence()) return "a list";
    if (m_node.IsMap()) return "a section";
    return "an empty value";
}

void ScenarioNode::checkKeys(const std::vector<std::string>& required,
                             const std::vector<std::string>& optional) const {
    std::vector<std::string> valid = required;
    valid.insert(valid.end(), optional.begin(), optional.end());
    if (!isNull() && !m_node.IsMap())
        fail("is " + getValueText() + " but must be a section with the keys " + joinQuoted(valid));
    std::vector<std::pair<std::string, int>> seen;  // key, line
    if (m_node.IsMap()) {
        for (auto it = m_node.begin(); it != m_node.end(); ++it) {
            const std::string key = it->first.IsScalar() ? it->first.Scalar() : "";
            const std::string path = getChildPath(key);
            const int line = getWhere(path) == m_source->fileName ? toLine(it->first.Mark()) : 0;
            if (!it->first.IsScalar())
                throw InputError(getWhere(m_path), toLine(it->first.Mark()), m_path,
                                 "a key must be a plain word; valid keys: " + joinQuoted(valid));
            if (std::find(valid.begin(), valid.end(), key) == valid.end()) {
                const std::string closest = findClosest(key, valid);
                std::string msg = "unknown key in " + sectionName(m_path) + ";";
                if (!closest.empty()) msg += " did you mean '" + closest + "'?";
                msg += " valid keys: " + joinQuoted(valid);
                throw InputError(getWhere(path), line, path, msg);
            }
            for (const auto& [k, l] : seen)
                if (k == key)
                    throw InputError(
                        getWhere(path), line, path,
                        "appears twice in " + sectionName(m_path) +
                            (l > 0 ? " (first at line " + std::to_string(l) + ")" : "") +
                            "; keep one");
            seen.emplace_back(key, line);
        }
    }
    std::vector<std::string> missing;
    for (const std::string& r : required)
        if (!has(r)) missing.push_back(r);
    if (!missing.empty()) {
        std::string msg = (missing.size() == 1 ? "missing required key '" + missing[0] + "'"
                                               : "missing required keys " + joinQuoted(missing));
        msg += " in " + sectionName(m_path) + "; it requires " + joinQuoted(required);
        if (!optional.empty()) msg += " (optional: " + joinQuoted(optional) + ")";
        if (m_path.empty()) throw InputError(m_source->fileName, 0, "", msg);
        fail(msg);
    }
}

bool ScenarioNode::has(const std::string& key) const {
    YAML::Node value;
    YAML::Mark mark;
    return findEntry(key, &value, &mark);
}

ScenarioNode ScenarioNode::get(const std::string& key) const {
    YAML::Node value;
    YAML::Mark mark;
    if (!findEntry(key, &value, &mark))
        fail(key, "missing in " + sectionName(m_path) + "; it is required");
    return ScenarioNode(m_source, value, getChildPath(key), mark);
}

ScenarioNode ScenarioNode::getSection(const std::string& key, bool required) const {
    YAML::Node value;
    YAML::Mark mark;
    if (!findEntry(key, &value, &mark)) {
        if (required) fail(key, "missing section in " + sectionName(m_path) + "; it is required");
        return ScenarioNode(m_source, YAML::Node(YAML::NodeType::Map), getChildPath(key),
                            m_keyMark);
    }
    ScenarioNode child(m_source, value, getChildPath(key), mark);
    if (!child.isNull() && !child.isMap())
        child.fail("is " + child.getValueText() + " but must be a section of 'key: value' lines");
    return child;
}

std::vector<ScenarioNode> ScenarioNode::getElements() const {
    if (!m_node.IsSequence()) fail("is " + getValueText() + " but must be a list, e.g. [a, b]");
    std::vector<ScenarioNode> out;
    int i = 0;
    for (auto it = m_node.begin(); it != m_node.end(); ++it, ++i) {
        YAML::Mark mark = it->Mark();
        if (mark.line < 0) mark = m_keyMark;
        out.emplace_back(m_source, *it, m_path + "[" + std::to_string(i) + "]", mark);
    }
    return out;
}

double ScenarioNode::asQuantity(Dimension d) const {
    if (!m_node.IsScalar())
        fail("is " + getValueText() + " but must be " + getDimensionName(d) + " (e.g. \"" +
             getExample(d) + "\")");
    try {
        return parseQuantity(m_node.Scalar(), d);
    } catch (const UnitError& e) {
        fail(e.what());
    }
}

double ScenarioNode::asNumber() const { return asQuantity(Dimension::Dimensionless); }

int ScenarioNode::asInteger() const {
    const double v = asNumber();
    if (v != std::floor(v) || std::fabs(v) > 1e9) fail(getValueText() + " must be a whole number");
    return static_cast<int>(v);
}

bool ScenarioNode::asBool() const {
    if (m_node.IsScalar()) {
        std::string s = m_node.Scalar();
        for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (s == "true" || s == "yes" || s == "on") return true;
        if (s == "false" || s == "no" || s == "off") return false;
    }
    fail("is " + getValueText() + " but must be true or false");
}

std::string ScenarioNode::asString() const {
    if (!m_node.IsScalar()) fail("is " + getValueText() + " but must be a single word or text");
    return m_node.Scalar();
}

std::string ScenarioNode::asChoice(const std::vector<std::string>& choices) const {
    const std::string s = asString();
    if (std::find(choices.begin(), choices.end(), s) != choices.end()) return s;
    const std::string closest = findClosest(s, choices);
    fail(getValueText() + " is not valid;" +
         (closest.empty() ? std::string() : " did you mean '" + closest + "'?") +
         " valid values: " + joinQuoted(choices));
}

double ScenarioNode::getQuantity(const std::string& key, Dimension d) const {
    return get(key).asQuantity(d);
}

double ScenarioNode::getQuantity(const std::string& key, Dimension d, double defaultSi) const {
    return has(key) ? get(key).asQuantity(d) : defaultSi;
}

double ScenarioNode::getNumber(const std::string& key) const { return get(key).asNumber(); }

double ScenarioNode::getNumber(const std::string& key, double defaultValue) const {
    return has(key) ? get(key).asNumber() : defaultValue;
}

int ScenarioNode::getInteger(const std::string& key, int defaultValue) const {
    return has(key) ? get(key).asInteger() : defaultValue;
}

bool ScenarioNode::getBool(const std::string& key, bool defaultValue) const {
    return has(key) ? get(key).asBool() : defaultValue;
}

std::string ScenarioNode::getString(const std::string& key) const { return get(key).asString(); }

std::string ScenarioNode::getString(const std::string& key, const std::string& defaultValue) const {
    return has(key) ? get(key).asString() : defaultValue;
}

std::string ScenarioNode::getChoice(const std::string& key,
                                    const std::vector<std::string>& choices) const {
    return get(key).asChoice(choices);
}

std::string ScenarioNode::getChoice(const std::string& key, const std::vector<std::string>& choices,
                                    const std::string& defaultValue) const {
    return has(key) ? get(key).asChoice(choices) : defaultValue;
}

}  // namespace io
