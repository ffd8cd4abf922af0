#include <bags/Gas.h>
#include <bags/Types.h>

#include <gtest/gtest.h>

#include <cmath>

using bags::GasChamber;
using bags::GasOptions;

namespace {
GasOptions air(GasOptions::Process p) {
    GasOptions o;  // M = 29 g/mol, 23 degC, 0.1 MPa ambient
    o.process = p;
    return o;
}
}  // namespace

TEST(Gas, IdealGasLawHoldsWhenIsothermal) {
    // Reference: p V = m R T / M exactly (R = 8.314462618 J/(mol K)); tolerance 1e-12 relative.
    GasChamber g(air(GasOptions::Process::Isothermal), 3.5e-3);
    g.seal(2.8e-3);
    for (double V : {1.0e-3, 2.8e-3, 4.0e-3}) {
        const double expected = 3.5e-3 * 8.314462618 / 0.029 * 296.15 / V;
        EXPECT_NEAR(g.calcPressure(V), expected, 1e-12 * expected);
        EXPECT_NEAR(g.calcTemperature(V), 296.15, 1e-9);
    }
}

TEST(Gas, AmbientDensityMatchesIdealGas) {
    // rho = p M / (R T) = 1e5 * 0.029 / (8.314462618 * 296.15) = 1.17777 kg/m^3 (1e-4 rel).
    EXPECT_NEAR(GasOptions().getAmbientDensity(), 1.17777, 1.2e-4);
}

TEST(Gas, AdiabaticKeepsPVGammaConstant) {
    // Reference: p V^1.4 = const; tolerance 1e-12 relative.
    GasChamber g(air(GasOptions::Process::Adiabatic), 3.0e-3);
    g.seal(2.5e-3);
    const double c = g.calcPressure(2.5e-3) * std::pow(2.5e-3, 1.4);
    for (double V : {1.5e-3, 2.0e-3, 3.5e-3})
        EXPECT_NEAR(g.calcPressure(V) * std::pow(V, 1.4), c, 1e-12 * c);
    // Compression heats the gas: T2/T1 = (V1/V2)^(gamma-1).
    EXPECT_NEAR(g.calcTemperature(1.5e-3), 296.15 * std::pow(2.5 / 1.5, 0.4), 1e-9);
}

TEST(Gas, DerivativesMatchFiniteDifferences) {
    for (auto p : {GasOptions::Process::Isothermal, GasOptions::Process::Adiabatic,
                   GasOptions::Process::Polytropic}) {
        GasOptions o = air(p);
        o.polytropicIndex = 1.2;
        GasChamber g(o, 2.0e-3);
        g.seal(2.0e-3);
        const double V = 1.7e-3, h = 1e-9;
        // dG/dV = p - pAmbient; dp/dV; central differences, 1e-6 relative.
        const double dG = (g.calcWorkPotential(V + h) - g.calcWorkPotential(V - h)) / (2 * h);
        EXPECT_NEAR(dG, g.calcGaugePressure(V), 1e-6 * g.calcPressure(V)) << bags::toString(p);
        const double dp = (g.calcPressure(V + h) - g.calcPressure(V - h)) / (2 * h);
        EXPECT_NEAR(dp, g.calcPressureDerivative(V), 1e-6 * std::abs(dp)) << bags::toString(p);
    }
}

TEST(Gas, SetMassReseals) {
    GasChamber g(air(GasOptions::Process::Isothermal), 3.5e-3);
    g.seal(3.0e-3);
    g.setMass(2.5e-3, 3.0e-3);
    EXPECT_NEAR(g.calcPressure(3.0e-3), 2.5e-3 * 8.314462618 / 0.029 * 296.15 / 3.0e-3, 1e-6);
}

TEST(Gas, RejectsBadOptions) {
    GasOptions o;
    o.temperature = -3.0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    EXPECT_THROW(GasChamber(GasOptions(), -1.0), std::invalid_argument);
    GasChamber g(GasOptions(), 1e-3);
    EXPECT_THROW(g.calcPressure(1e-3), std::logic_error);  // not sealed
    g.seal(1e-3);
    EXPECT_THROW(g.calcPressure(-1e-3), bags::NumericalError);
}
