// Units at the boundary: every unit the scenario reader takes converts to SI, a bare number
// where a unit is needed and a unit of the wrong kind are errors that list the valid units.
#include <gtest/gtest.h>
#include <io/Units.h>

#include <cmath>
#include <string>

using io::Dimension;
using io::parseQuantity;

namespace {

// Relative tolerance of a conversion: exact factors, so round-off only.
constexpr double kRel = 1e-14;

void expectSi(const std::string& text, Dimension d, double expected) {
    SCOPED_TRACE(text);
    EXPECT_NEAR(parseQuantity(text, d), expected, kRel * std::fabs(expected) + 1e-300);
}

std::string errorOf(const std::string& text, Dimension d) {
    try {
        parseQuantity(text, d);
    } catch (const io::UnitError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Units, ConvertsTheBriefsExamplesToSi) {
    // Reference: definitions of the units (1 mm = 1e-3 m, 1 degC = K - 273.15, ...).
    expectSi("350 mm", Dimension::Length, 0.350);
    expectSi("3.5 g", Dimension::Mass, 3.5e-3);
    expectSi("10 mm/min", Dimension::Velocity, 10e-3 / 60.0);
    expectSi("0.1 MPa", Dimension::Pressure, 1e5);
    expectSi("23 degC", Dimension::Temperature, 296.15);
    expectSi("296.15 K", Dimension::Temperature, 296.15);
    expectSi("50 N", Dimension::Force, 50.0);
    expectSi("5 kPa", Dimension::Pressure, 5e3);
    expectSi("0.2 mm", Dimension::Length, 0.2e-3);
    expectSi("1150 kg/m^3", Dimension::Density, 1150.0);
    expectSi("29 g/mol", Dimension::MolarMass, 0.029);
    expectSi("1e7 Pa/m", Dimension::StiffnessPerArea, 1e7);
    expectSi("30 deg", Dimension::Angle, M_PI / 6.0);
    expectSi("20 1/s", Dimension::Rate, 20.0);
    expectSi("20/s", Dimension::Rate, 20.0);
    expectSi("60 1/min", Dimension::Rate, 1.0);
    expectSi("0.15 us", Dimension::Time, 0.15e-6);
}

TEST(Units, ConvertsEveryListedUnitByItsFactor) {
    // Reference: each unit's definition; 2.5 of it must be 2.5 * factor + offset in SI.
    const Dimension all[] = {Dimension::Length,   Dimension::Mass,      Dimension::Force,
                             Dimension::Pressure, Dimension::Velocity,  Dimension::Temperature,
                             Dimension::Density,  Dimension::MolarMass, Dimension::Time,
                             Dimension::Angle,    Dimension::Stiffness, Dimension::StiffnessPerArea,
                             Dimension::Moment};
    int count = 0;
    for (Dimension d : all) {
        ASSERT_FALSE(io::getUnits(d).empty());
        for (const io::UnitInfo& u : io::getUnits(d)) {
            expectSi("2.5 " + u.symbol, d, 2.5 * u.factor + u.offset);
            expectSi("2.5" + u.symbol, d, 2.5 * u.factor + u.offset);  // no space
            ++count;
        }
    }
    EXPECT_GE(count, 40);
    // Independent spot checks of the factors themselves (definitions).
    expectSi("1 mmHg", Dimension::Pressure, 133.322387415);
    expectSi("1 bar", Dimension::Pressure, 1e5);
    expectSi("1 g/cm^3", Dimension::Density, 1000.0);
    expectSi("2 min", Dimension::Time, 120.0);
    expectSi("1 h", Dimension::Time, 3600.0);
    expectSi("5 N/mm", Dimension::Stiffness, 5000.0);
    expectSi("1 kPa/mm", Dimension::StiffnessPerArea, 1e6);
    expectSi("0.168 N mm", Dimension::Moment, 1.68e-4);
    expectSi("1.68e-4 N m", Dimension::Moment, 1.68e-4);
    expectSi("1 rad", Dimension::Angle, 1.0);
    expectSi("-0.76582566 MPa", Dimension::Pressure, -0.76582566e6);
    expectSi("+3 mm", Dimension::Length, 3e-3);
    expectSi("  7 cm  ", Dimension::Length, 0.07);
    expectSi("0 degC", Dimension::Temperature, 273.15);
    expectSi("-40 degC", Dimension::Temperature, 233.15);
    expectSi("23 °C", Dimension::Temperature, 296.15);
}

TEST(Units, AcceptsBareNumbersOnlyWhenDimensionless) {
    EXPECT_DOUBLE_EQ(parseQuantity("0.3", Dimension::Dimensionless), 0.3);
    EXPECT_DOUBLE_EQ(parseQuantity("1e-3", Dimension::Dimensionless), 1e-3);
    const std::string e = errorOf("0.3 mm", Dimension::Dimensionless);
    EXPECT_NE(e.find("takes no unit"), std::string::npos) << e;
}

TEST(Units, RejectsBareNumberWhereUnitIsNeeded) {
    const std::string e = errorOf("350", Dimension::Length);
    EXPECT_NE(e.find("has no unit"), std::string::npos) << e;
    EXPECT_NE(e.find("mm, cm, m"), std::string::npos) << e;   // lists the valid units
    EXPECT_NE(e.find("\"350 mm\""), std::string::npos) << e;  // and an example
    // Zero too: "0" without a unit is still ambiguous for a temperature.
    EXPECT_FALSE(errorOf("0", Dimension::Temperature).empty());
}

TEST(Units, RejectsWrongDimensionListingValidUnits) {
    const std::string e = errorOf("3.5 kg/m", Dimension::Mass);
    EXPECT_NE(e.find("is not a mass"), std::string::npos) << e;
    EXPECT_NE(e.find("g, kg, mg"), std::string::npos) << e;
    EXPECT_NE(e.find("\"3.5 g\""), std::string::npos) << e;

    const std::string e2 = errorOf("23 mm", Dimension::Temperature);
    EXPECT_NE(e2.find("is not a temperature ('mm' is a length)"), std::string::npos) << e2;
    EXPECT_NE(e2.find("degC, K"), std::string::npos) << e2;

    // Case matters: "MPA" is not a unit, "mn" neither.
    EXPECT_FALSE(errorOf("1 MPA", Dimension::Pressure).empty());
    EXPECT_FALSE(errorOf("1 mn", Dimension::Force).empty());
}

TEST(Units, RejectsMalformedNumbers) {
    EXPECT_NE(errorOf("mm", Dimension::Length).find("does not start with a number"),
              std::string::npos);
    EXPECT_NE(errorOf("", Dimension::Length).find("empty"), std::string::npos);
    EXPECT_NE(errorOf("inf mm", Dimension::Length).find("finite"), std::string::npos);
    EXPECT_FALSE(errorOf("nan", Dimension::Dimensionless).empty());
    EXPECT_FALSE(errorOf("3,5 g", Dimension::Mass).empty());  // decimal comma
}

TEST(Units, FormatsForOutput) {
    EXPECT_EQ(io::formatQuantity(0.0035, "g", 2), "3.50 g");
    EXPECT_EQ(io::formatQuantity(296.15, "degC", 1), "23.0 degC");
    EXPECT_EQ(io::formatSignificant(0.0123, "mm"), "12.3 mm");
    EXPECT_EQ(io::formatSignificant(5123.0, "kPa"), "5.12 kPa");
    EXPECT_EQ(io::formatSignificant(0.35, "mm"), "350 mm");
    EXPECT_DOUBLE_EQ(io::toUnit(0.0035, "g"), 3.5);
    EXPECT_DOUBLE_EQ(io::fromUnit(23.0, "degC"), 296.15);
    EXPECT_THROW(io::toUnit(1.0, "furlong"), io::UnitError);
}
