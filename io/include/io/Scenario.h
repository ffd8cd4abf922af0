#pragma once
/// @file Reading scenario files (YAML) with errors that say where: a thin layer over yaml-cpp
/// that remembers the file name and each key's line, so every mistake becomes an io::InputError
/// naming file, line, key, value and what would be valid.
///
/// Order of use: ScenarioFile::load() (YAML syntax errors become InputError here), then
/// applyOverride() for each command-line "--set key=value", then getRoot() and, per section,
/// checkKeys() followed by the typed getters. checkKeys() rejects unknown keys (suggesting the
/// closest valid one) before the getters report missing ones, so a misspelt key is named as
/// such rather than as a missing one.

#include <io/InputError.h>
#include <io/Units.h>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace io {

/// Levenshtein edit distance between two strings (case-sensitive).
int calcEditDistance(const std::string& a, const std::string& b);
/// The candidate closest to `word` by edit distance if it is close enough to be a plausible
/// misspelling (at most 2 edits, or a third of the word's length), else "".
std::string findClosest(const std::string& word, const std::vector<std::string>& candidates);

/// Largest scenario file read [bytes], 1 MiB: a scenario is a page of keys (the seed's is
/// 3 kB). A larger file is the wrong file, and yaml-cpp's tree of it would take on the order of
/// a hundred times its size in memory.
inline constexpr std::uintmax_t kMaxScenarioBytes = 1024 * 1024;

/// Reads a whole input file as text. Refuses, before opening it, what is not a regular file (a
/// folder; a pipe or a device, which would block or never end) and a file larger than
/// `maxBytes`; a file that grows past the limit while read is refused too.
/// @param what what the file is, for the messages ("scenario file", "tensile data file")
/// @throws InputError naming the file, what is wrong and the limit.
std::string readInputFile(const std::string& path, std::uintmax_t maxBytes,
                          const std::string& what);

class ScenarioNode;

/// One scenario: its file name, its text verbatim and its YAML tree (with overrides applied).
class ScenarioFile {
  public:
    /// Reads and parses a file. @throws InputError if it cannot be read, is not a regular file,
    /// is larger than kMaxScenarioBytes or is not valid YAML (with the line of the syntax
    /// error), or if its top level is not a mapping.
    static ScenarioFile load(const std::string& path);
    /// Parses text as if read from a file called `name` (for tests and generated scenarios).
    static ScenarioFile parse(const std::string& text, const std::string& name);

    /// A copy is a scenario of its own: overrides applied to it leave the original as it was
    /// (and the original's later overrides leave the copy).
    ScenarioFile() = default;  ///< empty until assigned a loaded or parsed one
    ScenarioFile(const ScenarioFile& other);
    ScenarioFile& operator=(const ScenarioFile& other);
    ScenarioFile(ScenarioFile&&) noexcept = default;
    ScenarioFile& operator=(ScenarioFile&&) noexcept = default;
    ~ScenarioFile();

    /// Replaces (or adds) the value at a dotted key path, e.g. ("airbag.mesh_size", "5 mm").
    /// The value is parsed as YAML, so "[3.5 g, 2 g]" is a list. Errors about that key then
    /// point at "--set KEY" instead of a line of the file.
    /// @throws InputError if the path runs through a value that is not a section.
    void applyOverride(const std::string& keyPath, const std::string& value);
    /// Parses "key.path=value" (as given to --set) and applies it.
    void applyOverride(const std::string& assignment);

    const std::string& getFileName() const;  ///< as given to load()/parse()
    const std::string& getText() const;      ///< file text verbatim (without overrides)
    /// The overrides applied, as "key=value" in the order given.
    const std::vector<std::string>& getOverrides() const;
    /// The file name without directories and extension ("seed-load-test").
    std::string getStem() const;
    ScenarioNode getRoot() const;

    struct Source;  ///< shared by all nodes of one file (name, overridden paths)

  private:
    std::shared_ptr<Source> m_source;
    YAML::Node m_root;
};

/// A node of a scenario tree with its dotted key path and its file, for located errors.
/// Getters with a default return it when the key is absent; those without throw InputError
/// when it is. Quantities are returned in SI.
class ScenarioNode {
  public:
    ScenarioNode(std::shared_ptr<const ScenarioFile::Source> source, YAML::Node node,
                 std::string path, YAML::Mark keyMark);

    const std::string& getPath() const { return m_path; }  ///< "" for the root, else "a.b"
    /// Dotted path of a child key ("gas" + "mass" -> "gas.mass").
    std::string getChildPath(const std::string& key) const;
    /// 1-based line of this node's key (or value), 0 if unknown.
    int getLine() const;
    /// 1-based line of a child key, or of this section if the key is absent.
    int getLine(const std::string& key) const;

    bool isMap() const { return m_node.IsMap(); }
    bool isSequence() const { return m_node.IsSequence(); }
    bool isScalar() const { return m_node.IsScalar(); }
    bool isNull() const { return !m_node || m_node.IsNull(); }
    const YAML::Node& getYaml() const { return m_node; }

    /// Checks this is a mapping whose keys are all among `required` and `optional`, with no key
    /// twice, and that every required key is present.
    /// @throws InputError naming an unknown key and the closest valid one, or listing the
    ///   required keys of this section that are missing.
    void checkKeys(const std::vector<std::string>& required,
                   const std::vector<std::string>& optional) const;
    /// True if the key is present (even with an empty value).
    bool has(const std::string& key) const;
    /// The child node at `key`. @throws InputError if absent.
    ScenarioNode get(const std::string& key) const;
    /// A child section (a mapping); absent keys give an empty section when optional.
    ScenarioNode getSection(const std::string& key, bool required = true) const;
    /// Elements of a sequence node. @throws InputError if this is not a sequence.
    std::vector<ScenarioNode> getElements() const;

    // Scalars of this node.
    double asQuantity(Dimension d) const;  ///< SI value
    double asNumber() const;               ///< plain number
    int asInteger() const;
    bool asBool() const;  ///< true/false (yes/no, on/off accepted)
    std::string asString() const;
    /// One of `choices` (exact match); the error lists them and suggests the closest.
    std::string asChoice(const std::vector<std::string>& choices) const;

    // Scalars of a child key, required or with a default (SI for quantities).
    double getQuantity(const std::string& key, Dimension d) const;
    double getQuantity(const std::string& key, Dimension d, double defaultSi) const;
    double getNumber(const std::string& key) const;
    double getNumber(const std::string& key, double defaultValue) const;
    int getInteger(const std::string& key, int defaultValue) const;
    bool getBool(const std::string& key, bool defaultValue) const;
    std::string getString(const std::string& key) const;
    std::string getString(const std::string& key, const std::string& defaultValue) const;
    std::string getChoice(const std::string& key, const std::vector<std::string>& choices) const;
    std::string getChoice(const std::string& key, const std::vector<std::string>& choices,
                          const std::string& defaultValue) const;

    /// Throws an InputError located at this node, with its key path.
    [[noreturn]] void fail(const std::string& message) const;
    /// Throws an InputError located at the child key (or at this section if it is absent).
    [[noreturn]] void fail(const std::string& key, const std::string& message) const;

  private:
    /// Finds a child entry; false if absent. Sets the key's mark and the value.
    bool findEntry(const std::string& key, YAML::Node* value, YAML::Mark* keyMark) const;
    std::string getWhere(const std::string& path) const;
    std::string getValueText() const;

    std::shared_ptr<const ScenarioFile::Source> m_source;
    YAML::Node m_node;
    std::string m_path;
    YAML::Mark m_keyMark;  ///< where this node's key is (or the value, for list elements)
};

}  // namespace io
