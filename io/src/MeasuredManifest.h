#pragma once
// Private to the io library: the head of a measured-data manifest, shared by the rig's reader
// (MeasuredData.cpp) and the patient's (PatientMeasuredData.cpp).
#include <io/Scenario.h>

#include <string>

namespace io::manifest {

/// The folder's measured.yaml, parsed. @throws InputError naming the folder when it is not a
/// folder or holds no manifest, or the manifest's own error.
ScenarioFile readManifest(const std::string& folder);

/// Checks the manifest's `format` and returns the path of its `scenario` (relative to the
/// folder or absolute), which must be a file; `what` names it in the message ("the scenario
/// file"). @throws InputError at the key.
std::string readManifestScenario(const ScenarioNode& root, const std::string& folder,
                                 const std::string& what);

}  // namespace io::manifest
