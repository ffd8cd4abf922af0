#pragma once
/// @file The seed study's load test as a scenario file (kind: seed-load-test): reads the
/// sections airbag, membrane, gas, test, contact, solver and output into
/// bags::LoadTestOptions, converting units to SI and checking every value, so that an error
/// names the file, line and key. Every key, unit, default and valid range is listed in
/// docs/scenario-reference.md.

#include <bags/LoadTest.h>
#include <io/Scenario.h>

#include <string>
#include <vector>

namespace io {

/// What is written besides the curves.
struct OutputOptions {
    /// Save the membrane's nodal positions every this many steps (and at the first and last
    /// step of each loading and unloading branch); 0 saves no frames.
    int frameEvery = 5;
};

/// A scenario of kind seed-load-test, ready to run.
struct LoadTestScenario {
    std::string name;         ///< 'name' key, else the file name without extension
    std::string description;  ///< 'description' key (free text), may be empty
    bags::LoadTestOptions options;
    OutputOptions output;
};

/// The scenario kinds `bagsim run` knows.
std::vector<std::string> getScenarioKinds();

/// The scenario's 'kind' (checked against getScenarioKinds()). @throws InputError.
std::string readScenarioKind(const ScenarioFile& file);

/// Reads a seed-load-test scenario and validates the options (LoadTestOptions::validate()
/// and the material's own checks; their std::invalid_argument becomes an InputError at the
/// key concerned). @throws InputError on any missing, misspelt or invalid key or value.
LoadTestScenario readLoadTestScenario(const ScenarioFile& file);

}  // namespace io
