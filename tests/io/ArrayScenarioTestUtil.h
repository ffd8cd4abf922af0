#pragma once
// Test helpers shared by the patient-on-array scenario tests: read a scenario text, or expect
// it to fail with a located InputError.
#include <io/ArrayScenario.h>

#include <string>

#include "InputErrorTestUtil.h"

namespace io::test {

/// The patient-on-array scenario of `text`, read as file "a.yaml".
inline PatientOnArrayScenario read(const std::string& text) {
    return readPatientOnArrayScenario(ScenarioFile::parse(text, "a.yaml"));
}

/// The InputError reading `text` must raise.
inline InputError readError(const std::string& text) {
    return expectInputError([&] { read(text); });
}

}  // namespace io::test
