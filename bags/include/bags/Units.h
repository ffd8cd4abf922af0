#pragma once
/// @file The one non-SI unit the project's physics reads and reports in its own words:
/// interface pressure in millimetres of mercury, as clinicians and pressure mats give it.
/// Everything inside is SI; io/Units.h converts what users write at the boundary.

namespace bags {

/// [Pa] per mmHg: the conventional millimetre of mercury, 13.5951 g/cm^3 x 9.80665 m/s^2 x 1 mm.
inline constexpr double kPascalsPerMmHg = 133.322387415;

}  // namespace bags
