#pragma once
/// @file The `patient:` section of a scenario (sex, height, mass, posture, position,
/// head_of_bed_angle) read into body::PatientSpec, and the scenario kind patient-on-support
/// (the patient settled on a rigid flat support). Units are converted to SI; every value is
/// checked and an error names the file, line, key and what is valid; nothing is clamped.
/// Keys, units and ranges: docs/scenario-reference.md.

#include <body/PatientSpec.h>
#include <body/SettleOnSupport.h>
#include <io/Scenario.h>

#include <string>

namespace io {

/// The scenario kind that settles a patient on a rigid flat support.
inline constexpr const char* kPatientOnSupportKind = "patient-on-support";

/// A scenario of kind patient-on-support, ready to run.
struct PatientOnSupportScenario {
    std::string name;         ///< 'name' key, else the file name without extension
    std::string description;  ///< 'description' key (free text), may be empty
    body::PatientSpec patient;
    body::SettleOptions settle;  ///< 'support' section and 'settle_time'
};

/// Reads a `patient:` section (`section` is that mapping) and validates it
/// (body::PatientSpec::validate(); its errors are reported at the key concerned).
/// @throws InputError on a missing, misspelt or invalid key or value.
body::PatientSpec readPatientSection(const ScenarioNode& section);

/// Checks a scenario's name (it names the output folder): letters, digits, '.', '_', '-'.
/// @throws InputError at the root's 'name' key.
void checkScenarioName(const ScenarioNode& root, const std::string& name);

/// Reads a flat support's friction law from section `s`: keys prefix + "friction_law"
/// (`regularised` or `stick-slip`, `defaultLaw` when absent), prefix + "slip_velocity" (the
/// regularised law's only) and prefix + "stick_distance" (the stick-slip law's only) into `o`;
/// the other law's key is refused at its line. Ranges are the caller's to check.
void readSupportFriction(const ScenarioNode& s, const std::string& prefix,
                         const std::string& defaultLaw, body::PlaneSupportOptions& o);

/// Reads the `patient:` section at the top of any scenario. @throws InputError, also if the
/// scenario has no patient section.
body::PatientSpec readScenarioPatient(const ScenarioFile& file);

/// Reads a patient-on-support scenario (kind, name, description, patient, support,
/// settle_time). @throws InputError on any missing, misspelt or invalid key or value.
PatientOnSupportScenario readPatientOnSupportScenario(const ScenarioFile& file);

}  // namespace io
