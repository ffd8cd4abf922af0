#pragma once
/// @file Reading a study file (kind: study, docs/studies.md): a base scenario, the scenario keys
/// to sweep (grids, zipped lists, seeded random samples) and the outputs to collect from each
/// case's run. readStudyScenario() expands the sweep into its cases and checks every case
/// against the base scenario's own reader, so a bad value is reported before anything runs,
/// located in the study file (file, line, key, what is valid).

#include <io/Scenario.h>

#include <cstdint>
#include <string>
#include <vector>

namespace io {

/// One swept scenario key: a column of the study table.
struct StudyParameter {
    std::string key;   ///< dotted scenario key, as given to --set ("contact.penalty")
    std::string unit;  ///< unit of the column's numbers ("Pa/m"), "" if plain or not numeric
    int line = 0;      ///< line of the key in the study file
    std::string path;  ///< key path in the study file ("parameters.grid.contact.penalty")
};

/// One case: a value per parameter, in the order of StudyScenario::parameters.
struct StudyCase {
    std::vector<std::string> values;  ///< YAML text passed to --set ("1e7 Pa/m", "[3 g]")
    std::vector<double> numbers;      ///< value in the parameter's unit, NaN if not a number
    std::vector<int> lines;           ///< line of each value in the study file
};

/// One output to collect from a case's folder: a column of a CSV file the run writes.
struct StudyOutput {
    std::string file;    ///< CSV file in the run's folder ("stiffness.csv")
    std::string column;  ///< its column ("stiffness_N_per_mm")
    std::string per;     ///< if set: one table column per value of this column
    /// first, last, min, max or mean of the column (with `per`: over the rows of each value;
    /// "" with `per`: one row per value, a value on two rows is an error)
    std::string reduce;
    int line = 0;  ///< line of the output in the study file
};

/// A study, its sweep expanded.
struct StudyScenario {
    std::string name;          ///< study file stem, or `name`
    std::string description;   ///< free text
    std::string studyFile;     ///< as given
    std::string studyText;     ///< verbatim
    std::string baseScenario;  ///< path of the base scenario (relative to the study file's folder)
    std::string baseText;      ///< its text verbatim
    std::string baseKind;      ///< its kind ("seed-load-test", ...)
    std::vector<std::string> fixedSets;  ///< the `set` section, "key=value", for every case
    std::vector<StudyParameter> parameters;
    std::vector<StudyCase> cases;
    std::vector<StudyOutput> outputs;
};

/// Reads a study file (already loaded), expands its cases and checks each against the base
/// scenario's reader. @throws InputError naming the study file's line and key for any mistake,
/// including a swept value the base scenario's reader refuses.
StudyScenario readStudyScenario(const ScenarioFile& file);

/// True if the file's top-level `kind` is "study".
bool isStudyFile(const ScenarioFile& file);

/// The --set assignments of one case: the fixed ones, then the case's parameters.
std::vector<std::string> getCaseOverrides(const StudyScenario& s, const StudyCase& c);

/// A case's key: 16 hex digits hashing the base scenario's text and the case's overrides. The
/// same parameters against the same base scenario give the same key, run after run.
std::string getCaseKey(const StudyScenario& s, const StudyCase& c);

}  // namespace io
