// The components' flow laws against their equations, their tangents against central
// differences, the sensor's lag against the exact first-order response, and the messages of
// bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "pneumatics/Components.h"

using namespace pneumatics;

namespace {

constexpr double kR = 8.314462618 / 0.029;  // [J/(kg K)] air

ValveSpec makeValve() {
    ValveSpec v;
    v.sonicConductance = 2.0e-8;
    v.criticalPressureRatio = 0.3;
    return v;
}

/// Checks dq/d(pa, Ta, pb, Tb) of `law` against central differences at (pa, Ta, pb, Tb).
void expectTangent(const std::function<Flow(double, double, double, double)>& law, double pa,
                   double Ta, double pb, double Tb, const std::string& where) {
    const Flow f = law(pa, Ta, pb, Tb);
    const double hp = 1e-3, hT = 1e-5;  // [Pa], [K]: far from any kink in these cases
    const double dpa =
        (law(pa + hp, Ta, pb, Tb).massFlow - law(pa - hp, Ta, pb, Tb).massFlow) / (2 * hp);
    const double dpb =
        (law(pa, Ta, pb + hp, Tb).massFlow - law(pa, Ta, pb - hp, Tb).massFlow) / (2 * hp);
    const double dTa =
        (law(pa, Ta + hT, pb, Tb).massFlow - law(pa, Ta - hT, pb, Tb).massFlow) / (2 * hT);
    const double dTb =
        (law(pa, Ta, pb, Tb + hT).massFlow - law(pa, Ta, pb, Tb - hT).massFlow) / (2 * hT);
    // Reference: the differences; tolerance 1e-6 of the largest pressure derivative (and of
    // q/T for the temperature ones), well above their truncation and roundoff error here.
    const double scaleP = std::max({std::abs(dpa), std::abs(dpb), 1e-30});
    const double scaleT = std::max(std::abs(f.massFlow) / Ta, 1e-30);
    EXPECT_NEAR(f.dpa, dpa, 1e-6 * scaleP) << where;
    EXPECT_NEAR(f.dpb, dpb, 1e-6 * scaleP) << where;
    EXPECT_NEAR(f.dTa, dTa, 1e-6 * scaleT) << where;
    EXPECT_NEAR(f.dTb, dTb, 1e-6 * scaleT) << where;
}

/// Expects `f` to throw std::invalid_argument whose message holds every one of `words`.
void expectInvalid(const std::function<void()>& f, std::initializer_list<const char*> words) {
    try {
        f();
        ADD_FAILURE() << "no exception; expected one naming " << *words.begin();
    } catch (const std::invalid_argument& e) {
        for (const char* w : words)
            EXPECT_NE(std::string(e.what()).find(w), std::string::npos)
                << "'" << w << "' missing from: " << e.what();
    }
}

}  // namespace

TEST(Valve, ChokedFlowIsIso6358SonicConductanceTimesUpstreamDensity) {
    const ValveSpec v = makeValve();
    const double p1 = 6e5, T1 = 310.0;
    // Reference: ISO 6358-1:2013, qm = C rho0 p1 sqrt(T0/T1) for p2/p1 <= b; roundoff only.
    const double q0 =
        v.sonicConductance * kIsoReferenceDensity * p1 * std::sqrt(kIsoReferenceTemperature / T1);
    for (double r : {0.0, 0.1, 0.2999}) {
        EXPECT_NEAR(calcValveFlow(v, 1.0, p1, T1, r * p1, 296.0).massFlow, q0, 1e-14 * q0);
    }
    // Subsonic: the elliptic law with m = 0.5.
    const double r = 0.8, u = (r - 0.3) / 0.7;
    EXPECT_NEAR(calcValveFlow(v, 1.0, p1, T1, r * p1, 296.0).massFlow, q0 * std::sqrt(1.0 - u * u),
                1e-14 * q0);
    // Half open: half the flow; closed: none; reversed ports: the same flow, negative.
    EXPECT_NEAR(calcValveFlow(v, 0.5, p1, T1, r * p1, 296.0).massFlow,
                0.5 * q0 * std::sqrt(1.0 - u * u), 1e-14 * q0);
    EXPECT_EQ(calcValveFlow(v, 0.0, p1, T1, r * p1, 296.0).massFlow, 0.0);
    EXPECT_NEAR(calcValveFlow(v, 1.0, r * p1, 296.0, p1, T1).massFlow, -q0 * std::sqrt(1.0 - u * u),
                1e-14 * q0);
}

TEST(Valve, FlowIsContinuousAtTheCriticalAndTheLaminarRatio) {
    const ValveSpec v = makeValve();
    const double p1 = 2e5;
    for (double r : {v.criticalPressureRatio, v.laminarPressureRatio}) {
        const double below = calcValveFlow(v, 1.0, p1, 296.0, p1 * r * (1 - 1e-14), 296.0).massFlow;
        const double above = calcValveFlow(v, 1.0, p1, 296.0, p1 * r * (1 + 1e-14), 296.0).massFlow;
        EXPECT_NEAR(below, above, 1e-9 * below) << "r = " << r;
    }
    EXPECT_EQ(calcValveFlow(v, 1.0, p1, 296.0, p1, 296.0).massFlow, 0.0);
}

TEST(Valve, TangentMatchesCentralDifferencesInEveryRegime) {
    for (double m : {0.5, 0.7}) {
        ValveSpec v = makeValve();
        v.subsonicIndex = m;
        auto law = [&](double pa, double Ta, double pb, double Tb) {
            return calcValveFlow(v, 0.7, pa, Ta, pb, Tb);
        };
        // choked, subsonic, laminar end, and each of them reversed
        for (double r : {0.2, 0.6, 0.95, 0.9995}) {
            const std::string where = "m " + std::to_string(m) + " r " + std::to_string(r);
            expectTangent(law, 5e5, 320.0, r * 5e5, 290.0, where);
            expectTangent(law, r * 5e5, 290.0, 5e5, 320.0, where + " reversed");
        }
    }
}

TEST(Pump, FlowFollowsItsCurveAndNeverRunsBackwards) {
    PumpSpec p;
    p.pressureRise = {0.0, 10e3, 30e3};
    p.massFlow = {2e-4, 1.5e-4, 0.0};
    p.validate();
    EXPECT_DOUBLE_EQ(calcPumpFlow(p, 1.0, 1e5, 1e5 + 5e3).massFlow, 1.75e-4);
    EXPECT_DOUBLE_EQ(calcPumpFlow(p, 1.0, 1e5, 1e5 + 20e3).massFlow, 0.75e-4);
    EXPECT_DOUBLE_EQ(calcPumpFlow(p, 0.5, 1e5, 1e5 + 20e3).massFlow, 0.375e-4);
    EXPECT_DOUBLE_EQ(calcPumpFlow(p, 1.0, 1e5, 0.9e5).massFlow, 2e-4);  // below the curve
    EXPECT_EQ(calcPumpFlow(p, 1.0, 1e5, 1e5 + 40e3).massFlow, 0.0);     // past shut-off
    EXPECT_EQ(calcPumpFlow(p, 0.0, 1e5, 1e5 + 5e3).massFlow, 0.0);      // off
    auto law = [&](double pa, double Ta, double pb, double Tb) {
        return calcPumpFlow(p, 0.8, pa, pb);
    };
    for (double rise : {3e3, 17e3}) expectTangent(law, 1e5, 296.0, 1e5 + rise, 296.0, "pump");
}

TEST(Orifice, IsBagsOrificeLawWithTheUpstreamDensityAndItsTangent) {
    bags::OrificeOptions o;
    o.diameter = 2e-3;
    const double pa = 1.1e5, Ta = 300.0, pb = 1.05e5, Tb = 290.0;
    const double rhoA = pa / (kR * Ta);
    // Reference: bags::calcOrificeMassFlow itself (this law wraps it): equal to roundoff.
    EXPECT_DOUBLE_EQ(calcOrificeFlow(o, kR, pa, Ta, pb, Tb).massFlow,
                     bags::calcOrificeMassFlow(o, pa, pb, rhoA));
    auto law = [&](double pa, double Ta, double pb, double Tb) {
        return calcOrificeFlow(o, kR, pa, Ta, pb, Tb);
    };
    for (double dp : {5e3, 3.0, 0.2, -0.7, -4e3})
        expectTangent(law, 1e5 + dp, 300.0, 1e5, 290.0, "orifice dp " + std::to_string(dp));
}

TEST(Sensor, LagIsTheExactFirstOrderResponseToAStepAndARamp) {
    const double tau = 0.05;
    // Step from 0 to 1 at t = 0, taken in steps of 7 ms: y = 1 - exp(-t/tau).
    double y = 0.0;
    for (int k = 1; k <= 50; ++k) {
        y = calcFirstOrderLag(y, 1.0, 1.0, 0.007, tau);
        // Reference: the exact solution; tolerance roundoff over 50 steps.
        EXPECT_NEAR(y, 1.0 - std::exp(-0.007 * k / tau), 1e-14);
    }
    // Ramp u = 2 t from y(0) = 0.3: y = u - 2 tau + (0.3 + 2 tau) exp(-t/tau).
    y = 0.3;
    for (int k = 1; k <= 50; ++k) {
        const double t0 = 0.003 * (k - 1), t1 = 0.003 * k;
        y = calcFirstOrderLag(y, 2 * t0, 2 * t1, 0.003, tau);
        EXPECT_NEAR(y, 2 * t1 - 2 * tau + (0.3 + 2 * tau) * std::exp(-t1 / tau), 1e-14);
    }
    EXPECT_EQ(calcFirstOrderLag(0.3, 1.0, 2.0, 0.01, 0.0), 2.0);  // no lag
}

TEST(Parameters, BadOnesThrowNamingParameterUnitAndValidRange) {
    ValveSpec v;
    v.sonicConductance = -1e-8;
    expectInvalid([&] { v.validate("supply valve"); },
                  {"supply valve", "sonicConductance", "m^3/(s Pa)", "C > 0"});
    v = ValveSpec();
    for (double b : {-0.1, 1.0, 1.5}) {
        v.criticalPressureRatio = b;
        expectInvalid([&] { v.validate(); }, {"criticalPressureRatio", "0 <= b < 1"});
    }
    v = ValveSpec();
    v.subsonicIndex = 0.0;
    expectInvalid([&] { v.validate(); }, {"subsonicIndex", "0 < m <= 1"});
    v = ValveSpec();
    v.laminarPressureRatio = 0.4;
    expectInvalid([&] { v.validate(); }, {"laminarPressureRatio", "b < rLam < 1"});
    v = ValveSpec();
    v.openingTime = -0.01;
    expectInvalid([&] { v.validate(); }, {"openingTime", " s", ">= 0 s"});

    PumpSpec p;
    p.pressureRise = {0.0, 10e3};
    p.massFlow = {1e-4, 2e-4};
    expectInvalid([&] { p.validate("pump"); }, {"massFlow[1]", "kg/s", "non-increasing"});
    p.massFlow = {1e-4, 1e-5};
    expectInvalid([&] { p.validate(); }, {"massFlow[last]", "kg/s", "shut-off"});
    p.pressureRise = {0.0, 0.0};
    p.massFlow = {1e-4, 0.0};
    expectInvalid([&] { p.validate(); }, {"pressureRise[1]", "Pa", "strictly increasing"});
    p.pressureRise = {-5.0, 10.0};
    expectInvalid([&] { p.validate(); }, {"pressureRise[0]", "Pa", ">= 0 Pa"});

    SensorSpec s;
    s.timeConstant = -1.0;
    expectInvalid([&] { s.validate("bag 3 sensor"); }, {"bag 3 sensor", "timeConstant", " s"});
    s = SensorSpec();
    s.noiseStdDev = -2.0;
    expectInvalid([&] { s.validate(); }, {"noiseStdDev", "Pa", ">= 0 Pa"});
}
