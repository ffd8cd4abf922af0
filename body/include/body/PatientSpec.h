#pragma once
/// @file The `patient:` section of a scenario as a plain struct. The YAML reading lives in io;
/// this is what it fills in, and validate() is where the patient's own rules are checked.

#include <array>
#include <string>

#include "body/Anthropometry.h"
#include "body/Posture.h"

namespace body {

/// Who lies on the bed and how.
struct PatientSpec {
    Sex sex = Sex::Male;                         ///< selects the de Leva table
    double height = 1.75;                        ///< stature [m], 1.4 to 2.1
    double mass = 75.0;                          ///< body mass [kg]; the BMI must be 14 to 50
    Posture posture = Posture::Supine;           ///< lying posture
    std::array<double, 2> position{{0.0, 0.0}};  ///< (x, y) on the bed of the mid-hip point [m]
    double headOfBedAngle =
        30.0 * 3.14159265358979323846 / 180.0;  ///< for HeadOfBedRaised [rad], 0 to 80 deg

    /// Body-mass index mass / height^2 [kg/m^2].
    double getBmi() const { return mass / (height * height); }
    /// Body surface area [m^2] by Mosteller's formula, sqrt(height [cm] x mass [kg] / 3600)
    /// (Mosteller 1987, N Engl J Med 317:1098).
    double getBodySurfaceArea() const;
    /// Checks the ranges the model is valid for.
    /// @throws std::invalid_argument naming the key, the value and what is valid; nothing is
    /// clamped.
    void validate() const;
};

/// Parses "female"/"male" (also "f"/"m", any case). @throws std::invalid_argument.
Sex parseSex(const std::string& name);

}  // namespace body
