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

// ------------------------------------------------------------------------------ orifice

TEST(Orifice, FlowFollowsTheOrificeLawAndItsDerivative) {
    bags::OrificeOptions o;  // 4 mm, Cd 0.62, dpLam 1 Pa
    const double rho = 1.2, A = 0.25 * 3.14159265358979 * 4e-3 * 4e-3;
    // Far above dpLam: Cd A sqrt(2 rho dp); the regularisation changes it by
    // (1 + (dpLam/dp)^2)^(-1/4) - 1 = -2.5e-7 at 1 kPa; tolerance 1e-6 relative.
    const double dp = 1000.0, expected = 0.62 * A * std::sqrt(2 * rho * dp);
    EXPECT_NEAR(bags::calcOrificeMassFlow(o, 1e5 + dp, 1e5, rho), expected, 1e-6 * expected);
    // Reverse flow is the mirror image.
    EXPECT_NEAR(bags::calcOrificeMassFlow(o, 1e5, 1e5 + dp, rho), -expected, 1e-6 * expected);
    // Well below dpLam the law is linear: Cd A sqrt(2 rho) dp / sqrt(dpLam) (1e-6 relative).
    const double small = 1e-4, lin = 0.62 * A * std::sqrt(2 * rho) * small;
    EXPECT_NEAR(bags::calcOrificeMassFlow(o, 1e5 + small, 1e5, rho), lin, 1e-6 * lin);
    // Derivative against central differences (1e-6 relative) across the laminar knee.
    for (double d : {-300.0, -1.0, 0.0, 0.3, 2.0, 5000.0}) {
        double g = 0.0;
        bags::calcOrificeMassFlow(o, 1e5 + d, 1e5, rho, &g);
        const double h = 1e-4 * std::max(1.0, std::abs(d));
        const double fd = (bags::calcOrificeMassFlow(o, 1e5 + d + h, 1e5, rho) -
                           bags::calcOrificeMassFlow(o, 1e5 + d - h, 1e5, rho)) /
                          (2 * h);
        EXPECT_NEAR(g, fd, 1e-6 * std::abs(fd)) << "dp = " << d;
    }
}

namespace {
// Two rigid chambers joined by an orifice, integrated with calcOrificeTransfer at step dt.
// Returns the pressure difference [Pa] after time t.
double blowDown(double dt, double t, double* massDrift = nullptr) {
    GasOptions air;
    bags::OrificeOptions o;
    o.diameter = 1e-3;
    o.laminarPressure = 1e-3;
    const double Va = 1.0e-3, Vb = 2.0e-3;
    const double rho = air.getAmbientDensity();
    GasChamber a(air, rho * 1.03 * Va), b(air, rho * Vb);  // 3 kPa over ambient in a
    a.seal(Va);
    b.seal(Vb);
    const double m0 = a.getMass() + b.getMass();
    const int n = static_cast<int>(std::lround(t / dt));
    for (int i = 0; i < n; ++i) {
        const double dm = bags::calcOrificeTransfer(o, a, Va, b, Vb, dt);
        a.transferMass(-dm, Va);
        b.transferMass(dm, Vb);
    }
    if (massDrift) *massDrift = a.getMass() + b.getMass() - m0;
    return a.calcPressure(Va) - b.calcPressure(Vb);
}
}  // namespace

TEST(Orifice, RigidChambersEqualiseAsTheAnalyticBlowDown) {
    // Reference: with fixed volumes and isothermal gas, d(dp)/dt = -k sqrt(dp),
    // k = Cd A sqrt(2 rho) R T (1/Va + 1/Vb), so sqrt(dp) = sqrt(dp0) - k t / 2 (upstream
    // density taken constant: it changes by < 3 % over the run, which bounds the reference's
    // own error; tolerance 2 % of dp0 at the half-way time).
    GasOptions air;
    const double R = air.getSpecificGasConstant(), T = air.temperature;
    const double rho = air.getAmbientDensity() * 1.02;  // mean upstream density
    const double A = 0.25 * 3.14159265358979 * 1e-6;
    const double k = 0.62 * A * std::sqrt(2 * rho) * R * T * (1 / 1.0e-3 + 1 / 2.0e-3);
    const double dp0 = 0.03 * air.ambientPressure;
    const double tEnd = 2 * std::sqrt(dp0) / k;  // analytic time to equalise
    const double tHalf = 0.5 * tEnd;
    const double exact = std::pow(std::sqrt(dp0) - 0.5 * k * tHalf, 2);  // dp0 / 4
    double drift = 0.0;
    const double fine = blowDown(tEnd / 4000, tHalf, &drift);
    EXPECT_NEAR(fine, exact, 0.02 * dp0);
    // Mass is conserved to round-off (1e-15 kg of 3.5e-3 kg).
    EXPECT_NEAR(drift, 0.0, 1e-15);
    // Backward Euler converges at first order: halving dt halves the error (ratio 1.7-2.3),
    // measured against a 64x finer run.
    const double ref = blowDown(tEnd / 256000, tHalf);
    const double e1 = std::abs(blowDown(tEnd / 1000, tHalf) - ref);
    const double e2 = std::abs(blowDown(tEnd / 2000, tHalf) - ref);
    EXPECT_GT(e1 / e2, 1.7);
    EXPECT_LT(e1 / e2, 2.3);
    // Any step is stable: one step of 100 equalisation times lands close to equal pressures
    // without overshoot (backward Euler leaves sqrt(dp) = sqrt(dp0) / 200, dp = dp0 / 40000).
    const double big = blowDown(100 * tEnd, 100 * tEnd);
    EXPECT_GE(big, 0.0);
    EXPECT_LT(big, 1.1 * dp0 / 40000);
}

TEST(Orifice, RejectsBadOptions) {
    bags::OrificeOptions o;
    o.diameter = 0.0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = bags::OrificeOptions();
    o.dischargeCoefficient = 1.5;
    EXPECT_THROW(o.validate(), std::invalid_argument);
}
