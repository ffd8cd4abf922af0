#include <io/Units.h>
#include <bags/Text.h>
#include <bags/Units.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace io {

namespace {

// Every unit the scenario reader accepts, preferred unit of each dimension first.
const std::vector<UnitInfo>& getUnitTable() {
    using D = Dimension;
    static const std::vector<UnitInfo> table = {
        {"mm", D::Length, 1e-3},
        {"cm", D::Length, 1e-2},
        {"m", D::Length, 1.0},
        {"um", D::Length, 1e-6},

        {"g", D::Mass, 1e-3},
        {"kg", D::Mass, 1.0},
        {"mg", D::Mass, 1e-6},

        {"N", D::Force, 1.0},
        {"kN", D::Force, 1e3},
        {"mN", D::Force, 1e-3},

        {"kPa", D::Pressure, 1e3},
        {"Pa", D::Pressure, 1.0},
        {"MPa", D::Pressure, 1e6},
        {"GPa", D::Pressure, 1e9},
        {"hPa", D::Pressure, 1e2},
        {"bar", D::Pressure, 1e5},
        {"mbar", D::Pressure, 1e2},
        {"mmHg", D::Pressure, bags::kPascalsPerMmHg},  // conventional millimetre of mercury

        {"mm/min", D::Velocity, 1e-3 / 60.0},
        {"mm/s", D::Velocity, 1e-3},
        {"cm/s", D::Velocity, 1e-2},
        {"m/s", D::Velocity, 1.0},
        {"m/min", D::Velocity, 1.0 / 60.0},

        {"degC", D::Temperature, 1.0, 273.15},
        {"K", D::Temperature, 1.0},

        {"kg/m^3", D::Density, 1.0},
        {"kg/m3", D::Density, 1.0},
        {"g/cm^3", D::Density, 1e3},
        {"g/cm3", D::Density, 1e3},

        {"g/mol", D::MolarMass, 1e-3},
        {"kg/mol", D::MolarMass, 1.0},

        {"s", D::Time, 1.0},
        {"ms", D::Time, 1e-3},
        {"us", D::Time, 1e-6},
        {"min", D::Time, 60.0},
        {"h", D::Time, 3600.0},

        {"deg", D::Angle, M_PI / 180.0},
        {"rad", D::Angle, 1.0},

        {"N/mm", D::Stiffness, 1e3},
        {"N/m", D::Stiffness, 1.0},
        {"kN/m", D::Stiffness, 1e3},

        {"Pa/m", D::StiffnessPerArea, 1.0},
        {"kPa/mm", D::StiffnessPerArea, 1e6},
        {"kPa/m", D::StiffnessPerArea, 1e3},
        {"MPa/m", D::StiffnessPerArea, 1e6},
        {"N/mm^3", D::StiffnessPerArea, 1e9},
        {"N/m^3", D::StiffnessPerArea, 1.0},

        {"N m", D::Moment, 1.0},
        {"N*m", D::Moment, 1.0},
        {"N mm", D::Moment, 1e-3},
        {"mN m", D::Moment, 1e-3},

        {"g/s", D::MassFlow, 1e-3},
        {"g/min", D::MassFlow, 1e-3 / 60.0},
        {"mg/s", D::MassFlow, 1e-6},
        {"kg/s", D::MassFlow, 1.0},

        {"mg/(s kPa)", D::LeakConductance, 1e-9},
        {"mg/s/kPa", D::LeakConductance, 1e-9},
        {"g/(s kPa)", D::LeakConductance, 1e-6},
        {"kg/(s Pa)", D::LeakConductance, 1.0},
        {"1/s", D::Rate, 1.0},
        {"/s", D::Rate, 1.0},
        {"1/min", D::Rate, 1.0 / 60.0},

        {"mL", D::Volume, 1e-6},
        {"L", D::Volume, 1e-3},
        {"cm^3", D::Volume, 1e-6},
        {"m^3", D::Volume, 1.0},

        {"cm^2", D::Area, 1e-4},
        {"mm^2", D::Area, 1e-6},
        {"m^2", D::Area, 1.0},

        // ISO 6358: 1 dm^3/(s bar) = 1e-3 m^3 / (s 1e5 Pa) = 1e-8 m^3/(s Pa).
        {"dm^3/(s bar)", D::SonicConductance, 1e-8},
        {"L/(s bar)", D::SonicConductance, 1e-8},
        {"m^3/(s Pa)", D::SonicConductance, 1.0},
    };
    return table;
}

using bags::trimBlanks;

std::string quote(const std::string& s) { return "\"" + s + "\""; }

std::string listUnits(Dimension d) {
    std::string out;
    for (const UnitInfo& u : getUnits(d)) {
        if (!out.empty()) out += ", ";
        out += u.symbol;
    }
    return out;
}

// "a length needs one of mm, cm, m, um (e.g. "350 mm")"
std::string describeValid(Dimension d) {
    if (d == Dimension::Dimensionless) return "a plain number is expected (e.g. \"0.3\")";
    return "use " + listUnits(d) + " (e.g. " + quote(getExample(d)) + ")";
}

}  // namespace

std::vector<UnitInfo> getUnits(Dimension d) {
    std::vector<UnitInfo> out;
    for (const UnitInfo& u : getUnitTable())
        if (u.dimension == d) out.push_back(u);
    return out;
}

std::string getDimensionName(Dimension d) {
    switch (d) {
        case Dimension::Dimensionless:
            return "a plain number";
        case Dimension::Length:
            return "a length";
        case Dimension::Mass:
            return "a mass";
        case Dimension::Force:
            return "a force";
        case Dimension::Pressure:
            return "a pressure";
        case Dimension::Velocity:
            return "a velocity";
        case Dimension::Temperature:
            return "a temperature";
        case Dimension::Density:
            return "a density";
        case Dimension::MolarMass:
            return "a molar mass";
        case Dimension::Time:
            return "a time";
        case Dimension::Angle:
            return "an angle";
        case Dimension::Stiffness:
            return "a stiffness (force per length)";
        case Dimension::StiffnessPerArea:
            return "a pressure per length";
        case Dimension::Moment:
            return "a moment (force times length)";
        case Dimension::MassFlow:
            return "a mass flow";
        case Dimension::Rate:
            return "a rate (per time)";
        case Dimension::Volume:
            return "a volume";
        case Dimension::Area:
            return "an area";
        case Dimension::SonicConductance:
            return "a sonic conductance (ISO 6358)";
        case Dimension::LeakConductance:
            return "a leak conductance (mass flow per gauge pressure)";
    }
    return "a quantity";
}

std::string getSiUnit(Dimension d) {
    switch (d) {
        case Dimension::Dimensionless:
            return "";
        case Dimension::Length:
            return "m";
        case Dimension::Mass:
            return "kg";
        case Dimension::Force:
            return "N";
        case Dimension::Pressure:
            return "Pa";
        case Dimension::Velocity:
            return "m/s";
        case Dimension::Temperature:
            return "K";
        case Dimension::Density:
            return "kg/m^3";
        case Dimension::MolarMass:
            return "kg/mol";
        case Dimension::Time:
            return "s";
        case Dimension::Angle:
            return "rad";
        case Dimension::Stiffness:
            return "N/m";
        case Dimension::StiffnessPerArea:
            return "Pa/m";
        case Dimension::Moment:
            return "N m";
        case Dimension::MassFlow:
            return "kg/s";
        case Dimension::Rate:
            return "1/s";
        case Dimension::Volume:
            return "m^3";
        case Dimension::Area:
            return "m^2";
        case Dimension::SonicConductance:
            return "m^3/(s Pa)";
        case Dimension::LeakConductance:
            return "kg/(s Pa)";
    }
    return "";
}

std::string getExample(Dimension d) {
    switch (d) {
        case Dimension::Dimensionless:
            return "0.3";
        case Dimension::Length:
            return "350 mm";
        case Dimension::Mass:
            return "3.5 g";
        case Dimension::Force:
            return "50 N";
        case Dimension::Pressure:
            return "5 kPa";
        case Dimension::Velocity:
            return "10 mm/min";
        case Dimension::Temperature:
            return "23 degC";
        case Dimension::Density:
            return "1150 kg/m^3";
        case Dimension::MolarMass:
            return "29 g/mol";
        case Dimension::Time:
            return "60 s";
        case Dimension::Angle:
            return "30 deg";
        case Dimension::Stiffness:
            return "5 N/mm";
        case Dimension::StiffnessPerArea:
            return "1e7 Pa/m";
        case Dimension::Moment:
            return "1.7e-4 N m";
        case Dimension::MassFlow:
            return "0.05 g/s";
        case Dimension::Rate:
            return "20 1/s";
        case Dimension::Volume:
            return "20 mL";
        case Dimension::Area:
            return "100 cm^2";
        case Dimension::SonicConductance:
            return "0.3 dm^3/(s bar)";
        case Dimension::LeakConductance:
            return "0.05 mg/(s kPa)";
    }
    return "";
}

const UnitInfo* findUnit(const std::string& symbol) {
    for (const UnitInfo& u : getUnitTable())
        if (u.symbol == symbol) return &u;
    return nullptr;
}

double parseQuantity(const std::string& text, Dimension d) {
    const std::string s = trimBlanks(text);
    if (s.empty()) throw UnitError("empty value; " + describeValid(d));
    // The number: from_chars is locale independent; it does not take a leading '+'.
    const char* begin = s.data();
    const char* end = s.data() + s.size();
    if (*begin == '+') ++begin;
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(begin, end, value);
    if (ec != std::errc() || ptr == begin)
        throw UnitError(quote(s) + " does not start with a number; " + describeValid(d));
    if (!std::isfinite(value)) throw UnitError(quote(s) + " is not a finite number");
    const std::string unit = trimBlanks(std::string(ptr, end));

    if (d == Dimension::Dimensionless) {
        if (!unit.empty())
            throw UnitError(quote(s) + " takes no unit; write a plain number (e.g. \"" +
                            std::string(begin, ptr) + "\")");
        return value;
    }
    if (unit.empty())
        throw UnitError(quote(s) + " has no unit; " + getDimensionName(d) + " needs one of " +
                        listUnits(d) + " (e.g. " + quote(getExample(d)) + ")");
    const UnitInfo* u = findUnit(unit == "°C" ? "degC" : unit == "°" ? "deg" : unit);
    if (!u)
        throw UnitError(quote(s) + " is not " + getDimensionName(d) + " (unknown unit '" + unit +
                        "'); " + describeValid(d));
    if (u->dimension != d)
        throw UnitError(quote(s) + " is not " + getDimensionName(d) + " ('" + unit + "' is " +
                        getDimensionName(u->dimension) + "); " + describeValid(d));
    return u->factor * value + u->offset;
}

double toUnit(double valueSi, const std::string& unit) {
    const UnitInfo* u = findUnit(unit);
    if (!u) throw UnitError("unknown unit '" + unit + "'");
    return (valueSi - u->offset) / u->factor;
}

double fromUnit(double value, const std::string& unit) {
    const UnitInfo* u = findUnit(unit);
    if (!u) throw UnitError("unknown unit '" + unit + "'");
    return u->factor * value + u->offset;
}

std::string formatQuantity(double valueSi, const std::string& unit, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f %s", decimals < 0 ? 0 : decimals, toUnit(valueSi, unit),
                  unit.c_str());
    return buf;
}

std::string formatSignificant(double valueSi, const std::string& unit, int digits) {
    const double v = toUnit(valueSi, unit);
    int decimals = 0;
    if (v != 0.0 && std::isfinite(v))
        decimals = digits - 1 - static_cast<int>(std::floor(std::log10(std::fabs(v))));
    else
        decimals = digits - 1;
    if (decimals < 0) decimals = 0;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f %s", decimals, v, unit.c_str());
    return buf;
}

}  // namespace io
