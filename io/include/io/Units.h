#pragma once
/// @file Physical quantities at the program's boundary. Scenario values carry units
/// ("350 mm", "3.5 g", "10 mm/min", "23 degC"); parseQuantity() turns them into SI numbers for
/// the libraries, which work in SI only. A bare number where a unit is needed is an error, and
/// so is a unit of the wrong kind; both errors list the units that would be valid.
/// formatQuantity() goes the other way for printed output ("3.50 g").

#include <stdexcept>
#include <string>
#include <vector>

namespace io {

/// The kind of a quantity; each has an SI unit that parseQuantity() returns.
enum class Dimension {
    Dimensionless,     ///< plain number, takes no unit
    Length,            ///< [m]
    Mass,              ///< [kg]
    Force,             ///< [N]
    Pressure,          ///< [Pa] (also stress, material constants)
    Velocity,          ///< [m/s]
    Temperature,       ///< [K] (absolute; degC is shifted by 273.15)
    Density,           ///< [kg/m^3]
    MolarMass,         ///< [kg/mol]
    Time,              ///< [s]
    Angle,             ///< [rad]
    Stiffness,         ///< force per length [N/m]
    StiffnessPerArea,  ///< pressure per length, e.g. a contact penalty [Pa/m]
    Moment,            ///< force times length, e.g. a plate's bending stiffness [N m]
    MassFlow,          ///< mass per time, e.g. a bag's gas flow [kg/s]
    Volume,            ///< [m^3] e.g. a manifold
    Area,              ///< [m^2]
    SonicConductance,  ///< ISO 6358 sonic conductance C [m^3/(s Pa)]
    LeakConductance,   ///< mass flow per gauge pressure, e.g. a bag's seams [kg/(s Pa)]
    Rate,              ///< per time, e.g. a damping coefficient [1/s]
};

/// A unit the parser knows: value_SI = factor * value + offset.
struct UnitInfo {
    std::string symbol;  ///< as written, e.g. "mm/min"
    Dimension dimension;
    double factor;        ///< SI per unit
    double offset = 0.0;  ///< SI offset (degC only)
};

/// Raised by parseQuantity() when the text is not a valid quantity of the wanted kind; the
/// message says what would be valid. The scenario reader adds file, line and key to it.
class UnitError : public std::invalid_argument {
  public:
    using std::invalid_argument::invalid_argument;
};

/// All units of a dimension, preferred first (for error messages and docs).
std::vector<UnitInfo> getUnits(Dimension d);
/// Name of a dimension as used in messages ("a length", "a pressure").
std::string getDimensionName(Dimension d);
/// SI unit symbol of a dimension ("m", "Pa", "" for Dimensionless).
std::string getSiUnit(Dimension d);
/// An example value in the preferred unit, e.g. "350 mm".
std::string getExample(Dimension d);

/// Parses "<number> [unit]" (space optional, e.g. "350 mm", "1e7 Pa/m", "-0.77 MPa") into SI.
/// @throws UnitError for a missing unit (unless Dimensionless), an unknown unit, a unit of
///   another dimension, a unit on a dimensionless value, or a malformed or non-finite number.
double parseQuantity(const std::string& text, Dimension d);

/// Looks up a unit symbol; nullptr if unknown.
const UnitInfo* findUnit(const std::string& symbol);

/// Converts an SI value to the given unit (e.g. toUnit(0.0035, "g") == 3.5).
/// @throws UnitError if the unit is unknown.
double toUnit(double valueSi, const std::string& unit);
/// Converts a value in the given unit to SI (e.g. fromUnit(23, "degC") == 296.15).
double fromUnit(double value, const std::string& unit);

/// Formats an SI value in the given unit with `decimals` digits after the point:
/// formatQuantity(0.0035, "g", 2) == "3.50 g".
std::string formatQuantity(double valueSi, const std::string& unit, int decimals);
/// Like formatQuantity() with three significant digits: 0.0123 m in "mm" -> "12.3 mm".
std::string formatSignificant(double valueSi, const std::string& unit, int digits = 3);

}  // namespace io
