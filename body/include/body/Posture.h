#pragma once
/// @file Lying postures of the patient and how they are set in a Simbody state.
///
/// Ground frame: z up, the bed surface is the plane z = 0, the patient's head points to +x.
/// Supine: the patient's anterior axis is +z, superior +x, and their right side +y.
/// A tilt or side-lying "left" turns the patient onto their left side (left side down).

#include <string>

namespace body {

/// The lying postures a scenario can ask for.
enum class Posture {
    Supine,           ///< on the back, arms alongside the trunk, legs straight
    TiltLeft30,       ///< supine turned 30 deg onto the left side
    TiltRight30,      ///< supine turned 30 deg onto the right side
    SideLeft90,       ///< lying on the left side, lower arm forward, hips and knees a little flexed
    SideRight90,      ///< lying on the right side
    HeadOfBedRaised,  ///< supine with the trunk raised by the head-of-bed angle, legs flat
};

/// Scenario spelling of a posture: "supine", "tilt-left-30", "tilt-right-30",
/// "side-left-90", "side-right-90", "head-of-bed-raised".
const char* getPostureName(Posture posture);
/// All valid spellings, comma-separated (for error messages).
const char* getPostureNames();
/// Parses a posture name. @throws std::invalid_argument naming the valid values.
Posture parsePosture(const std::string& name);

}  // namespace body
