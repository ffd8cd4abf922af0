// The diagnosis (diagnose/Diagnosis.h) on a rig whose answers are known: a stand-in load test
// (linear curves whose stiffness and pressure grow with the gas mass, computed in microseconds)
// gives "measured" data with one effect on, and the diagnosis must find where the gap lies,
// which effect it is, and its parameters; the no-effect case must be called none and an effect
// outside the library unexplained.
#include <gtest/gtest.h>

#include <diagnose/Diagnosis.h>
#include <diagnose/Synthesis.h>

#include <bags/Material.h>

#include <algorithm>
#include <cmath>

namespace {

// The stand-in bag: force F = k(m) d with k = 2 N/mm + 2 N/mm per g above 3 g; gauge
// pressure p = p0(m) + F / (0.01 m^2) with p0 = 10 kPa per g above 3.5 g; m the gas mass at
// 23 degC that acts as the gas does (m T / 296.15 K).
bags::LoadTestResult simulateStandIn(const bags::LoadTestOptions& o) {
    bags::LoadTestResult r;
    for (double m : o.gasMasses) {
        bags::LoadCurve c;
        c.gasMass = m;
        // The gas acts through m T (ideal gas): the effective mass at 23 degC.
        const double me = m * o.gas.temperature / 296.15;
        const double k = 2000.0 + 2e6 * (me - 3e-3);
        const double p0 = 1e7 * (me - 3.5e-3);
        auto add = [&](double d, bool loading) {
            bags::LoadStep s;
            s.displacement = d;
            s.force = k * d;
            s.loading = loading;
            s.gaugePressure = {p0 + s.force / 0.01};
            s.volume = {3e-3};
            c.steps.push_back(s);
        };
        const double dPeak = o.peakForce / k;
        const int n = static_cast<int>(std::ceil(dPeak / o.displacementStep));
        for (int i = 0; i <= n; ++i) add(dPeak * i / n, true);
        for (int i = n - 1; i >= 0; --i) add(dPeak * i / n, false);
        r.curves.push_back(c);
    }
    return r;
}

struct Rig {
    bags::LoadTestOptions options;
    diagnose::Protocol protocol;
    Rig() {
        options.gasMasses = {4.5e-3, 4.25e-3, 4.0e-3};
        options.peakForce = 20.0;
        options.displacementStep = 0.5e-3;
        options.loadingRate = 10e-3 / 60;
        options.stiffnessFrom = 5.0;
        options.stiffnessTo = 15.0;
        options.gas.temperature = 296.15;
        // The stand-in ignores its film; the film-changing candidates need one to act on.
        options.material = bags::makeNeoHookean(1e6);
        protocol.rate = options.loadingRate;
        protocol.peakForce = options.peakForce;
        protocol.blockSize = 0.05;
        protocol.roomTemperature = 296.15;
    }
};

struct Diagnosed {
    diagnose::WhereReport where;
    diagnose::WhichReport which;
    std::vector<diagnose::TestComparison> tests;
};

// Measured data from the stand-in with `effect` on (a finer step as the model-form
// difference), then the diagnosis against the stand-in as the scenario gives it.
// Several effects at once: each name with its values.
using EffectValues = std::vector<std::pair<std::string, std::vector<double>>>;

// What the manifest states of the protocol's inputs (0: not stated).
struct Stated {
    double gasMass = 0.0;      ///< [kg] standard uncertainty of every test's gas mass
    double temperature = 0.0;  ///< [K] of the room temperature
};

// `bedGauge`: the rig has a gauge under the bed board (a fourth channel, the board's sink).
Diagnosed diagnoseStandIn(const EffectValues& effects, bool pairGate = true,
                          const Stated& stated = {}, bool bedGauge = false) {
    const diagnose::Simulator simulate = simulateStandIn;
    const Rig rig;
    bags::LoadTestOptions truth = rig.options;
    truth.displacementStep *= 0.5;
    diagnose::RigEffects rigTruth;
    for (const auto& [effect, values] : effects)
        diagnose::applyEffect(*diagnose::findEffect(effect), values, rig.options.gasMasses,
                              rigTruth, truth);
    diagnose::SynthesisOptions so;
    so.seed = 3;
    so.bedGauge = bedGauge;
    diagnose::MeasuredData data = diagnose::synthesizeMeasurement(
        simulate(truth).curves, rig.options.gasMasses, rigTruth, rig.protocol, so);

    for (diagnose::MeasuredTest& t : data.tests)
        t.gasMassUncertainty = stated.gasMass, t.gasMassUncertaintyStated = stated.gasMass > 0.0;
    data.protocol.roomTemperatureUncertainty = stated.temperature;
    data.protocol.roomTemperatureUncertaintyStated = stated.temperature > 0.0;

    Diagnosed d;
    const bags::LoadTestResult base = simulate(rig.options);
    const diagnose::RigEffects none;
    for (size_t i = 0; i < data.tests.size(); ++i)
        d.tests.push_back(diagnose::compareTest(data.tests[i], int(i), base.curves[i], none,
                                                rig.options.loadingRate));
    const std::vector<diagnose::InputRun> runs = diagnose::makeInputRuns(data, rig.options);
    std::vector<bags::LoadTestOptions> options;
    for (const diagnose::InputRun& r : runs) options.push_back(r.options);
    diagnose::addInputUncertainties(data, runs, diagnose::runLoadTests(options, simulate, 2), none,
                                    rig.options.loadingRate, d.tests);
    diagnose::WhereOptions wo;
    wo.loadFrom = 5.0;
    wo.loadTo = 15.0;
    d.where = diagnose::calcWhere(d.tests, wo);
    d.where.statedInputs = diagnose::describeInputs(data);
    diagnose::CalibrationOptions co;
    co.pairGate = pairGate;
    d.which = diagnose::calibrateCandidates(data, rig.options, none, base, d.tests, d.where,
                                            simulate, co);
    return d;
}

Diagnosed diagnoseStandIn(const std::string& effect, const std::vector<double>& values) {
    return diagnoseStandIn(effect.empty() ? EffectValues{} : EffectValues{{effect, values}});
}

const diagnose::CandidateResult& findCandidate(const diagnose::WhichReport& w,
                                               const std::string& name) {
    for (const auto& c : w.candidates)
        if (c.effect == name) return c;
    throw std::runtime_error("no candidate " + name);
}

const diagnose::Signature* findSignature(const diagnose::WhereReport& w, const std::string& ch,
                                         int test) {
    for (const auto& s : w.signatures)
        if (s.channel == ch && s.test == test) return &s;
    return nullptr;
}

}  // namespace

TEST(Diagnosis, NoEffectIsCalledNone) {
    const Diagnosed d = diagnoseStandIn("", {});
    EXPECT_TRUE(d.where.withinValidation);
    EXPECT_EQ(d.which.verdict, "none") << d.which.reason;
    // The noise is estimated from the data as stated (0.01 N); the residual adds the
    // displacement's 0.002 mm noise through the stiffness (4-5 N/mm): about 0.014 N.
    EXPECT_NEAR(d.where.channels[0].noise, 0.01, 0.0015);
    EXPECT_NEAR(d.where.channels[0].rmse, 0.014, 0.003);
}

TEST(Diagnosis, PressureSensorLagAndOffsetAreFoundWhereAndWhich) {
    const Diagnosed d = diagnoseStandIn("pressure-sensor", {3.0, 200.0});
    // Where: the pressure channel carries the gap, with a bias near the offset and a lag near
    // the time constant (a first-order lag delays a ramp by its time constant).
    EXPECT_GT(d.where.channels[1].shareOfGap, 0.9);
    const diagnose::Signature* s = findSignature(d.where, "pressure", 0);
    ASSERT_NE(s, nullptr);
    EXPECT_NEAR(s->lag, 3.0, 0.5);
    EXPECT_GT(s->bias, 100.0);
    // The lag opens a loop in pressure against displacement that the model has not.
    EXPECT_LT(s->loopAreaMeasured, 0.0);
    EXPECT_LT(std::fabs(s->loopAreaSimulated), 0.05 * std::fabs(s->loopAreaMeasured));
    // Which: named, and its parameters found.
    EXPECT_EQ(d.which.verdict, "pressure-sensor") << d.which.reason;
    const diagnose::CandidateResult& c = findCandidate(d.which, "pressure-sensor");
    EXPECT_NEAR(c.parameters[0], 3.0, 0.2);
    EXPECT_NEAR(c.parameters[1], 200.0, 10.0);
    EXPECT_GT(c.shrink, 0.7);
    // How far, over every test when held out: the pressure's error falls to about the noise
    // (5 Pa stated); the area metric is never above the RMSE (sorted pairs are the closest).
    ASSERT_EQ(c.heldoutMetricsAfter.size(), 2u);
    const diagnose::GapMetrics &p0 = c.heldoutMetricsBefore[1], &p1 = c.heldoutMetricsAfter[1];
    EXPECT_EQ(p0.channel, "pressure");
    EXPECT_GT(p0.rmse, 100.0);
    EXPECT_LT(p1.rmse, 10.0);
    EXPECT_LT(p1.maxError, p0.maxError);
    EXPECT_LE(p0.areaMetric, p0.rmse);
    EXPECT_LE(p1.areaMetric, p1.rmse);
    EXPECT_NEAR(p0.meanError, -200.0, 30.0);  // S - D: the sensor reads 200 Pa high
}

TEST(Diagnosis, FlowmeterBiasIsFoundWithItsOffset) {
    const Diagnosed d = diagnoseStandIn("flowmeter-bias", {0.1e-3});
    EXPECT_EQ(d.which.verdict, "flowmeter-bias") << d.which.reason;
    const diagnose::CandidateResult& c = findCandidate(d.which, "flowmeter-bias");
    EXPECT_NEAR(c.parameters[0], 0.1e-3, 0.01e-3);
    EXPECT_GT(c.shrink, 0.7);
    EXPECT_GT(c.simulations, 0);
}

TEST(Diagnosis, MachineComplianceIsFoundInTheForceChannel) {
    // Without a gauge under the bed board the machine's compliance and the bed's are one spring
    // in series with the block: the verdict names both and the gauge that would part them.
    const Diagnosed d = diagnoseStandIn("machine-compliance", {0.5e-3});
    EXPECT_GT(d.where.channels[0].shareOfGap, 0.5);
    EXPECT_EQ(d.which.verdict, "machine-compliance or bed-compliance") << d.which.reason;
    ASSERT_EQ(d.which.verdictEffects.size(), 1u);
    EXPECT_EQ(d.which.verdictEffects[0], "machine-compliance");
    EXPECT_EQ(d.which.rivals, std::vector<std::string>{"bed-compliance"});
    EXPECT_EQ(d.which.explained, "fully") << d.which.reason;
    EXPECT_LE(d.which.residualRatio, diagnose::kExplainedMultiple);
    EXPECT_NE(d.which.tellApart.find("a gauge under the bed board"), std::string::npos)
        << d.which.tellApart;
    // Their fits are the same spring: no channel of these tests tells them apart.
    EXPECT_NE(d.which.tellApart.find("no channel of these tests tells them apart"),
              std::string::npos)
        << d.which.tellApart;
    EXPECT_EQ(d.which.reason.rfind("explained by machine-compliance or bed-compliance", 0), 0u)
        << d.which.reason;
    EXPECT_NEAR(findCandidate(d.which, "machine-compliance").parameters[0], 0.5e-3, 0.05e-3);
}

TEST(Diagnosis, WithABedGaugeTheMachinesComplianceIsNamedAlone) {
    const Diagnosed d =
        diagnoseStandIn(EffectValues{{"machine-compliance", {0.5e-3}}}, true, {}, true);
    EXPECT_EQ(d.which.verdict, "machine-compliance") << d.which.reason;
    EXPECT_TRUE(d.which.rivals.empty());
    EXPECT_EQ(d.which.explained, "fully") << d.which.reason;
}

TEST(Diagnosis, ALoadCellGainOutsideTheLibraryIsUnexplained) {
    // The load cell reads 10 % high: no effect of the library makes the force alone larger
    // while the pressure stays.
    const Diagnosed d = diagnoseStandIn("load-cell-gain", {0.10});
    EXPECT_FALSE(d.where.withinValidation);
    const diagnose::Signature* s = findSignature(d.where, "force", 0);
    ASSERT_NE(s, nullptr);
    EXPECT_NEAR(s->scale, 0.10, 0.01);
    EXPECT_EQ(d.which.verdict, "unexplained") << d.which.reason;
}

TEST(Diagnosis, RegimeSharesAddUpPerSplit) {
    const Diagnosed d = diagnoseStandIn("pressure-sensor", {3.0, 200.0});
    for (const std::string ch : {"force", "pressure"}) {
        double branches = 0.0, masses = 0.0, loads = 0.0, thirds = 0.0;
        for (const auto& r : d.where.regimes) {
            if (r.channel != ch) continue;
            if (r.regime.rfind("time ", 0) == 0) thirds += r.share;
            if (r.regime == "loading" || r.regime == "unloading") branches += r.share;
            if (r.regime.rfind("gas mass", 0) == 0) masses += r.share;
            if (r.regime.rfind("load ", 0) == 0) loads += r.share;
        }
        EXPECT_NEAR(branches, 1.0, 1e-12) << ch;
        EXPECT_NEAR(masses, 1.0, 1e-12) << ch;
        EXPECT_NEAR(loads, 1.0, 1e-12) << ch;
        EXPECT_NEAR(thirds, 1.0, 1e-12) << ch;
    }
}

TEST(Diagnosis, AWarmerGasIsToldFromAFlowmeterBiasByWhatTheBiasLeaves) {
    // A gas 5 K warmer acts as 1.7 % more gas: a flowmeter offset of 0.07-0.08 g mimics it
    // over these masses, and shrinks the held-out gap about as much (within 0.1). But held out,
    // the offset leaves a channel beyond twice its validation uncertainty where the warmer gas
    // leaves none: the data tell them apart, and the verdict names the gas alone.
    const Diagnosed d = diagnoseStandIn("gas-temperature", {5.0});
    const diagnose::CandidateResult& gas = findCandidate(d.which, "gas-temperature");
    const diagnose::CandidateResult& bias = findCandidate(d.which, "flowmeter-bias");
    EXPECT_LT(std::fabs(gas.excessShrink - bias.excessShrink), diagnose::kRivalMargin);
    diagnose::ChannelUncertainties u;
    for (const auto& c : d.where.channels) u[c.channel] = c.validation;
    u.erase("mass");
    EXPECT_LE(diagnose::calcResidualRatio(gas, u), diagnose::kExplainedMultiple);
    EXPECT_GT(diagnose::calcResidualRatio(bias, u), diagnose::kExplainedMultiple);
    EXPECT_TRUE(d.which.confusable.empty()) << d.which.reason;
    EXPECT_EQ(d.which.verdict, "gas-temperature") << d.which.reason;
    EXPECT_EQ(d.which.explained, "fully") << d.which.reason;
    EXPECT_NEAR(gas.parameters[0], 5.0, 0.5);
}

TEST(Diagnosis, TheLoadCellGainIsNotACandidateUnlessNamed) {
    for (const auto& c : diagnoseStandIn("load-cell-gain", {0.1}).which.candidates)
        EXPECT_NE(c.effect, "load-cell-gain");
}

TEST(Diagnosis, ASmallLagIsJudgedOnTheGapBeyondTheUncertainty) {
    // Lag 1 s, offset 30 Pa: the pressure's error is a few times its noise. The whole gap also
    // holds the force's noise, which no effect explains; the shrink that decides is the one
    // beyond the validation uncertainty.
    const Diagnosed d = diagnoseStandIn("pressure-sensor", {1.0, 30.0});
    EXPECT_EQ(d.which.verdict, "pressure-sensor") << d.which.reason;
    const diagnose::CandidateResult& c = findCandidate(d.which, "pressure-sensor");
    EXPECT_GT(c.excessShrink, 0.9);
    EXPECT_LT(c.shrink, c.excessShrink);
    EXPECT_NEAR(c.parameters[0], 1.0, 0.2);
}

TEST(Diagnosis, TwoEffectsAtOnceAreBothNamed) {
    // The pressure sensor (lag 3 s, offset 200 Pa) and the machine's compliance (0.5 mm/N): the
    // compliance carries the force's gap, which the sensor cannot touch, so one at a time only
    // the compliance is found; the pair stage fits the two together and names both.
    const Diagnosed d = diagnoseStandIn(
        EffectValues{{"pressure-sensor", {3.0, 200.0}}, {"machine-compliance", {0.5e-3}}});
    EXPECT_EQ(d.which.candidates.front().effect, "machine-compliance");
    EXPECT_TRUE(d.which.pairStageRan) << d.which.pairStageReason;
    ASSERT_GE(d.which.pairChosen, 0) << d.which.reason;
    const diagnose::PairResult& p = d.which.pairs[d.which.pairChosen];
    EXPECT_TRUE(p.refined && p.accepted);
    ASSERT_EQ(d.which.verdictEffects.size(), 2u) << d.which.verdict;
    // Without a bed gauge the bed's compliance with the sensor is the same pair: named with it.
    EXPECT_EQ(d.which.verdict,
              "machine-compliance + pressure-sensor or bed-compliance + pressure-sensor");
    EXPECT_NE(d.which.tellApart.find("bed-compliance: a gauge under the bed board"),
              std::string::npos)
        << d.which.tellApart;
    EXPECT_EQ(d.which.tellApart.find("pressure-sensor:"), std::string::npos) << d.which.tellApart;
    EXPECT_EQ(d.which.verdictEffects[0], "machine-compliance");
    EXPECT_EQ(d.which.verdictEffects[1], "pressure-sensor");
    // Both parameter sets come back: compliance, then lag and offset.
    ASSERT_EQ(p.result.parameters.size(), 3u);
    EXPECT_NEAR(p.result.parameters[0], 0.5e-3, 0.05e-3);
    EXPECT_NEAR(p.result.parameters[1], 3.0, 0.3);
    EXPECT_NEAR(p.result.parameters[2], 200.0, 20.0);
    EXPECT_EQ(p.result.parameterStdDev.size(), 3u);
    EXPECT_EQ(p.result.folds.size(), 3u);
    // The pair explains what the compliance leaves, beyond the threshold and the penalty.
    EXPECT_EQ(p.against, "machine-compliance");
    EXPECT_GT(p.shrinkOverSingle, 0.5 + p.extraPenalty);
    EXPECT_NEAR(p.extraPenalty, 0.1, 1e-12);  // two parameters added
    EXPECT_LT(p.result.excessAfter, d.which.candidates.front().excessAfter);
    // The bed's compliance is the machine's on these channels: its pair with the sensor is
    // named confusable with the one named.
    const std::pair<std::string, std::string> twin = {"machine-compliance + pressure-sensor",
                                                      "bed-compliance + pressure-sensor"};
    EXPECT_NE(std::find(d.which.confusablePairs.begin(), d.which.confusablePairs.end(), twin),
              d.which.confusablePairs.end());
}

TEST(Diagnosis, ASingleEffectGetsNoSecond) {
    for (const auto& [effect, values] : EffectValues{{"pressure-sensor", {3.0, 200.0}},
                                                     {"flowmeter-bias", {0.1e-3}},
                                                     {"machine-compliance", {0.5e-3}},
                                                     {"pressure-sensor", {1.0, 30.0}}}) {
        // The pair stage stops at its gate: the single leaves every channel within twice its
        // validation uncertainty. Without the gate, pairs are tried, and none is accepted.
        const Diagnosed d = diagnoseStandIn(effect, values);
        EXPECT_FALSE(d.which.pairStageRan) << effect << ": " << d.which.pairStageReason;
        const Diagnosed u = diagnoseStandIn(EffectValues{{effect, values}}, false);
        EXPECT_TRUE(u.which.pairStageRan) << effect;
        EXPECT_FALSE(u.which.pairs.empty()) << effect;
        EXPECT_EQ(u.which.pairChosen, -1) << effect << ": " << u.which.reason;
        EXPECT_EQ(u.which.verdict, d.which.verdict);
        EXPECT_EQ(d.which.pairChosen, -1) << effect << ": " << d.which.reason;
        ASSERT_EQ(d.which.verdictEffects.size(), 1u) << effect << ": " << d.which.verdict;
        EXPECT_EQ(d.which.verdict.rfind(d.which.verdictEffects[0], 0), 0u) << d.which.verdict;
        for (const auto& p : d.which.pairs) EXPECT_FALSE(p.accepted) << effect << ": " << p.why;
    }
}

TEST(Diagnosis, NoEffectTriesNoPair) {
    const Diagnosed d = diagnoseStandIn("", {});
    EXPECT_FALSE(d.which.pairStageRan);
    EXPECT_TRUE(d.which.pairs.empty());
    EXPECT_TRUE(d.which.verdictEffects.empty());
    EXPECT_EQ(d.which.pairSimulations, 0);
}

TEST(Diagnosis, AnEffectOutsideTheLibraryIsNotExplainedByAPair) {
    const Diagnosed d = diagnoseStandIn("load-cell-gain", {0.10});
    EXPECT_TRUE(d.which.pairStageRan) << d.which.pairStageReason;
    EXPECT_FALSE(d.which.pairs.empty());
    EXPECT_EQ(d.which.pairChosen, -1) << d.which.reason;
    EXPECT_TRUE(d.which.verdictEffects.empty());
}

// ------------------------------------------------------------- the protocol's input uncertainty

TEST(InputUncertainty, SensitivityTermsAreHalfTheCentralDifferenceCombinedByRootSumSquare) {
    // By hand: S(x + u) = 1, 2, 3 and S(x - u) = 0, 1, 1 at three samples: |dS/dx| u = 0.5, 0.5,
    // 1, RMS sqrt(1.5 / 3) = sqrt(0.5). With a second input of 0.3: sqrt(0.5 + 0.09).
    diagnose::TestComparison plus, minus;
    for (diagnose::TestComparison* t : {&plus, &minus}) t->channels.resize(1);
    plus.channels[0].simulated = {1.0, 2.0, 3.0};
    minus.channels[0].simulated = {0.0, 1.0, 1.0};
    const std::vector<double> u = diagnose::calcSensitivityUncertainty(plus, minus);
    ASSERT_EQ(u.size(), 1u);
    EXPECT_NEAR(u[0], std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(u[0], diagnose::calcSensitivityUncertainty(minus, plus)[0], 1e-15);
    const std::vector<double> c = diagnose::combineInputUncertainties({u, {0.3}});
    EXPECT_NEAR(c[0], std::sqrt(0.59), 1e-15);
}

TEST(InputUncertainty, TheChannelsTermIsTheRmsOverAllItsSamplesAndEntersTheValidationByRss) {
    // Two tests of a channel with 3 and 1 samples, terms 0.2 and 0.6: over the channel's
    // samples sqrt((3 x 0.04 + 1 x 0.36) / 4) = sqrt(0.12); beside a numerical uncertainty of
    // 0.1 and a room temperature term of 0.05 the validation uncertainty is their root sum
    // square with the noise (0: the measured values lie on a line).
    std::vector<diagnose::TestComparison> tests(2);
    for (int i = 0; i < 2; ++i) {
        diagnose::TestComparison& t = tests[i];
        t.test = i;
        t.gasMass = 4e-3;
        diagnose::ChannelComparison ch;
        ch.kind = diagnose::ChannelKind::Pressure;
        const int n = i == 0 ? 3 : 1;
        for (int k = 0; k < n; ++k) {
            ch.time.push_back(k);
            ch.displacement.push_back(1e-3 * k);
            ch.force.push_back(k);
            ch.loading.push_back(1);
            ch.measured.push_back(100.0 * k);
            ch.simulated.push_back(100.0 * k);
        }
        t.channels = {ch};
        t.numericalUncertainty = {0.1};
        t.inputUncertainty = {0.0};
        t.inputUncertaintyGasMass = {i == 0 ? 0.2 : 0.6};
        t.inputUncertaintyTemperature = {0.05};
    }
    const diagnose::WhereReport w = diagnose::calcWhere(tests, diagnose::WhereOptions());
    ASSERT_EQ(w.channels.size(), 1u);
    const diagnose::ChannelSummary& c = w.channels[0];
    EXPECT_NEAR(c.inputGasMass, std::sqrt(0.12), 1e-12);
    EXPECT_NEAR(c.inputTemperature, 0.05, 1e-12);
    EXPECT_NEAR(c.validation, std::sqrt(c.noise * c.noise + 0.01 + 0.12 + 0.0025), 1e-12);
}

namespace {

// The stand-in's closed form of |dS/dm| u at each sample of a test's channel: at a fixed
// displacement d, F = k(m) d and p = p0(m) + F / 0.01 m^2, so dF/dm = 2e6 d and
// dp/dm = 1e7 + 2e8 d (both linear in m: the central difference is exact); the force is 0
// where the measured displacement is not positive. RMS over the channel's samples of all tests.
double calcStandInMassTerm(const std::vector<diagnose::TestComparison>& tests,
                           diagnose::ChannelKind kind, const std::vector<double>& u) {
    double s = 0.0;
    long n = 0;
    for (const diagnose::TestComparison& t : tests)
        for (const diagnose::ChannelComparison& ch : t.channels) {
            if (ch.kind != kind) continue;
            for (double d : ch.displacement) {
                const double dSdm = kind == diagnose::ChannelKind::Force ? (d > 0.0 ? 2e6 * d : 0.0)
                                                                         : 1e7 + 2e8 * d;
                s += std::pow(dSdm * u[t.test], 2);
                ++n;
            }
        }
    return std::sqrt(s / double(n));
}

}  // namespace

TEST(InputUncertainty, AStatedGasMassUncertaintyGivesTheStandInsClosedForm) {
    const double u = 0.02e-3;
    const Diagnosed d = diagnoseStandIn({}, true, {u, 0.0});
    const Diagnosed plain = diagnoseStandIn({}, true, {});
    for (int c : {0, 1}) {
        const auto kind = c == 0 ? diagnose::ChannelKind::Force : diagnose::ChannelKind::Pressure;
        const diagnose::ChannelSummary& s = d.where.channels[c];
        const double expected = calcStandInMassTerm(d.tests, kind, {u, u, u});
        // 1e-6: the force's samples at the first contact, where the noise puts the measured
        // displacement about 0 (the simulated force is clipped at 0 on one side only).
        EXPECT_NEAR(s.inputGasMass, expected, 1e-6 * expected) << s.channel;
        EXPECT_EQ(s.inputTemperature, 0.0);
        // The validation uncertainty grows by root sum square; the RMSE does not change.
        const diagnose::ChannelSummary& p = plain.where.channels[c];
        EXPECT_EQ(p.inputGasMass, 0.0);
        EXPECT_NEAR(s.validation * s.validation, p.validation * p.validation + expected * expected,
                    1e-9 * s.validation * s.validation);
        EXPECT_EQ(s.rmse, p.rmse);
    }
    EXPECT_NEAR(d.where.channels[2].inputGasMass, u, 1e-15);  // the flowmeter reads the mass
    ASSERT_EQ(d.where.statedInputs.size(), 2u);
    EXPECT_TRUE(d.where.statedInputs[0].stated);
    EXPECT_FALSE(d.where.statedInputs[1].stated);
    EXPECT_FALSE(plain.where.statedInputs[0].stated);
}

TEST(InputUncertainty, AStatedRoomTemperatureUncertaintyActsAsTheGasMassTimesItsShare) {
    // The stand-in's gas acts through m T: u_T acts as a mass uncertainty of m u_T / T.
    const double uT = 0.5;
    const Diagnosed d = diagnoseStandIn({}, true, {0.0, uT});
    const std::vector<double> masses = {4.5e-3, 4.25e-3, 4.0e-3};
    std::vector<double> um;
    for (double m : masses) um.push_back(m * uT / 296.15);
    for (int c : {0, 1}) {
        const auto kind = c == 0 ? diagnose::ChannelKind::Force : diagnose::ChannelKind::Pressure;
        const double expected = calcStandInMassTerm(d.tests, kind, um);
        EXPECT_NEAR(d.where.channels[c].inputTemperature, expected, 1e-6 * expected);
        EXPECT_EQ(d.where.channels[c].inputGasMass, 0.0);
    }
    EXPECT_TRUE(d.where.statedInputs[1].stated);
}

TEST(InputUncertainty, AFlowmeterBiasWithinTheStatedUncertaintyIsNone) {
    // A bias of 0.03 g: found without a statement; with a stated standard uncertainty of
    // 0.05 g the data are within twice the validation uncertainty, and called none.
    const Diagnosed found = diagnoseStandIn({{"flowmeter-bias", {0.03e-3}}});
    EXPECT_FALSE(found.where.withinValidation);
    EXPECT_EQ(found.which.verdict, "flowmeter-bias") << found.which.reason;
    const Diagnosed within = diagnoseStandIn({{"flowmeter-bias", {0.03e-3}}}, true, {0.05e-3, 0.0});
    EXPECT_TRUE(within.where.withinValidation);
    EXPECT_EQ(within.which.verdict, "none") << within.which.reason;
}

TEST(InputUncertainty, NothingStatedRunsNothing) {
    diagnose::MeasuredData data;
    data.tests.resize(2);
    bags::LoadTestOptions o;
    o.gasMasses = {4e-3, 3e-3};
    EXPECT_TRUE(diagnose::makeInputRuns(data, o).empty());
    data.tests[1].gasMassUncertainty = 0.01e-3;  // one test states it: the other is not moved
    data.protocol.roomTemperatureUncertainty = 1.0;
    const std::vector<diagnose::InputRun> runs = diagnose::makeInputRuns(data, o);
    ASSERT_EQ(runs.size(), 4u);
    EXPECT_EQ(runs[0].input, diagnose::ProtocolInput::GasMass);
    EXPECT_EQ(runs[0].options.gasMasses, (std::vector<double>{4e-3, 3.01e-3}));
    EXPECT_EQ(runs[1].options.gasMasses, (std::vector<double>{4e-3, 2.99e-3}));
    EXPECT_EQ(runs[2].input, diagnose::ProtocolInput::RoomTemperature);
    EXPECT_DOUBLE_EQ(runs[2].options.gas.temperature, o.gas.temperature + 1.0);
    EXPECT_DOUBLE_EQ(runs[3].options.gas.temperature, o.gas.temperature - 1.0);
}

TEST(Diagnosis, TheBedGaugeTellsTheBedsComplianceFromTheMachines) {
    // Without a gauge under the bed board, the bed's compliance and the machine's give the
    // same channels: the two fit alike and are named confusable.
    const Diagnosed blind = diagnoseStandIn(EffectValues{{"bed-compliance", {0.5e-3}}});
    const std::pair<std::string, std::string> pair = {"machine-compliance", "bed-compliance"};
    const std::pair<std::string, std::string> riap = {pair.second, pair.first};
    auto named = [&](const diagnose::WhichReport& w) {
        return std::find(w.confusable.begin(), w.confusable.end(), pair) != w.confusable.end() ||
               std::find(w.confusable.begin(), w.confusable.end(), riap) != w.confusable.end();
    };
    EXPECT_TRUE(named(blind.which)) << blind.which.reason;
    EXPECT_NEAR(findCandidate(blind.which, "machine-compliance").excessShrink,
                findCandidate(blind.which, "bed-compliance").excessShrink, 1e-6);

    // With it, the board's sink is a fourth channel: only the bed's compliance explains it.
    for (const std::string truth : {"bed-compliance", "machine-compliance"}) {
        const Diagnosed d = diagnoseStandIn(EffectValues{{truth, {0.5e-3}}}, true, {}, true);
        ASSERT_EQ(d.tests[0].channels.size(), 4u);
        EXPECT_EQ(d.tests[0].channels[3].kind, diagnose::ChannelKind::Bed);
        ASSERT_EQ(d.where.channels.size(), 4u);
        const diagnose::ChannelSummary& bed = d.where.channels[3];
        EXPECT_EQ(bed.channel, "bed");
        // Its error is judged against the crosshead's travel (a rigid bed's channel spans
        // only its noise): 20 N at 4-5 N/mm and 0.5 mm/N, 14-15 mm.
        EXPECT_GT(bed.range, 10e-3);
        EXPECT_EQ(d.which.verdict, truth) << d.which.reason;
        EXPECT_FALSE(named(d.which)) << d.which.reason;
        EXPECT_NEAR(findCandidate(d.which, truth).parameters[0], 0.5e-3, 0.05e-3);
        const std::string other =
            truth == "bed-compliance" ? "machine-compliance" : "bed-compliance";
        EXPECT_LT(findCandidate(d.which, other).excessShrink,
                  findCandidate(d.which, truth).excessShrink - 0.2)
            << d.which.reason;
        if (truth == "bed-compliance") {
            // The bed carries a share of the gap (the board sinks 10 mm at 20 N, and the
            // model's board does not), the force most of it (its curve is 3 times as soft).
            EXPECT_GT(bed.shareOfGap, 0.05);
            EXPECT_GT(d.where.channels[0].shareOfGap, bed.shareOfGap);
            // Held out, the bed's channel is a third metric beside force and pressure.
            const diagnose::CandidateResult& c = findCandidate(d.which, truth);
            ASSERT_EQ(c.heldoutMetricsAfter.size(), 3u);
            EXPECT_EQ(c.heldoutMetricsAfter[2].channel, "bed");
            EXPECT_LT(c.heldoutMetricsAfter[2].rmse, 0.1 * c.heldoutMetricsBefore[2].rmse);
        } else {
            EXPECT_LT(bed.rmse, 2.0 * bed.validation);  // the board stays: the gauge reads noise
        }
    }
}

TEST(GapScale, EachChannelKindHasItsScaleAndTheMassNone) {
    diagnose::GapScale g;
    g.pressure = {10.0, 5.0};
    g.bed = {30.0, 0.002};
    EXPECT_EQ(g.getRange(diagnose::ChannelKind::Pressure), 10.0);
    EXPECT_EQ(g.getUncertainty(diagnose::ChannelKind::Bed), 0.002);
    const diagnose::GapScale& c = g;
    EXPECT_EQ(c.getRange(diagnose::ChannelKind::Mass), 0.0);
    EXPECT_THROW(g.get(diagnose::ChannelKind::Mass), std::invalid_argument);
}

TEST(GapScale, EachTestIsJudgedBeyondItsOwnUncertainty) {
    // Two tests whose force residual is exactly their own numerical error: 0.04 N in the
    // first (a stiff bag, a large step error), 0.01 N in the second; no noise, no pressure
    // error. Pooled, the uncertainty is their RMS (0.0292 N), below the first's error: a
    // floor of 0.0274 N that no model removes. Each beyond its own: nothing left.
    std::vector<diagnose::TestComparison> tests(2);
    const double err[2] = {0.04, 0.01};
    for (int t = 0; t < 2; ++t) {
        tests[t].test = t;
        diagnose::ChannelComparison f, p;
        f.kind = diagnose::ChannelKind::Force;
        p.kind = diagnose::ChannelKind::Pressure;
        for (int i = 0; i < 10; ++i) {
            f.measured.push_back(1.0 + err[t] * (i % 2 ? 1.0 : -1.0));
            f.simulated.push_back(1.0);
            p.measured.push_back(1000.0);
            p.simulated.push_back(1000.0);
        }
        tests[t].channels = {f, p};
        tests[t].numericalUncertainty = {err[t], 0.0};
        tests[t].inputUncertainty = {0.0, 0.0};
    }
    diagnose::WhereReport w;
    w.channels.resize(2);
    w.channels[0].channel = "force";
    w.channels[0].range = 20.0;
    w.channels[0].validation = std::sqrt(0.5 * (0.04 * 0.04 + 0.01 * 0.01));
    w.channels[1].channel = "pressure";
    w.channels[1].range = 1e4;
    const diagnose::GapScale pooled = diagnose::makeGapScale(w);
    const diagnose::GapScale own = diagnose::makeGapScale(w, tests);
    EXPECT_NEAR(own.getUncertainty(diagnose::ChannelKind::Force, 0), 0.04, 1e-15);
    EXPECT_NEAR(own.getUncertainty(diagnose::ChannelKind::Force, 1), 0.01, 1e-15);
    EXPECT_EQ(own.getUncertainty(diagnose::ChannelKind::Force, 7), w.channels[0].validation);
    // The first test alone: pooled, sqrt(0.04^2 - 0.0292^2) / 20 N over two channel kinds.
    const double floor = std::sqrt(0.04 * 0.04 - 0.5 * (0.04 * 0.04 + 0.01 * 0.01)) / 20.0;
    EXPECT_NEAR(diagnose::calcGap(tests, {0}, pooled, true), floor / std::sqrt(2.0), 1e-12);
    // (the square root of a roundoff-sized difference: 1e-9 against the floor's 1e-3)
    EXPECT_NEAR(diagnose::calcGap(tests, {0}, own, true), 0.0, 1e-9);
    EXPECT_NEAR(diagnose::calcGap(tests, {0, 1}, own, true), 0.0, 1e-9);
    // Without the uncertainty the gap is the same either way.
    EXPECT_DOUBLE_EQ(diagnose::calcGap(tests, {0}, own), diagnose::calcGap(tests, {0}, pooled));
}

TEST(Where, AFlatChannelHasNoShareAndShiftsNoOther) {
    // Force with an error, pressure flat (its range 0: not in the gap), a bed gauge with an
    // error: the shares go to force and bed, in their places.
    diagnose::TestComparison t;
    t.test = 0;
    for (diagnose::ChannelKind k : {diagnose::ChannelKind::Force, diagnose::ChannelKind::Pressure,
                                    diagnose::ChannelKind::Mass, diagnose::ChannelKind::Bed}) {
        diagnose::ChannelComparison c;
        c.kind = k;
        for (int i = 0; i < 5; ++i) {
            c.time.push_back(i);
            c.displacement.push_back(1e-3 * i);
            c.force.push_back(i);
            c.loading.push_back(1);
            const bool flat =
                k == diagnose::ChannelKind::Pressure || k == diagnose::ChannelKind::Mass;
            c.measured.push_back(flat ? 1.0 : 0.1 * i);
            c.simulated.push_back(flat ? 1.0
                                       : 0.1 * i + (k == diagnose::ChannelKind::Bed ? 1e-4 : 0.01));
        }
        t.channels.push_back(c);
    }
    const diagnose::WhereReport w = diagnose::calcWhere({t}, {});
    ASSERT_EQ(w.channels.size(), 4u);
    EXPECT_EQ(w.channels[1].shareOfGap, 0.0);
    EXPECT_EQ(w.channels[2].shareOfGap, 0.0);
    EXPECT_NEAR(w.channels[0].shareOfGap + w.channels[3].shareOfGap, 1.0, 1e-12);
    // force: 0.01 over a range of 0.4; bed: 0.1 mm over the travel of 4 mm: the same share.
    EXPECT_NEAR(w.channels[0].shareOfGap, 0.5, 1e-9);
    EXPECT_NEAR(w.gap, 0.025, 1e-9);  // two channels in the gap, each 0.025
    // Tests with other channels are refused.
    diagnose::TestComparison u = t;
    u.test = 1;
    u.channels.pop_back();
    EXPECT_THROW(diagnose::calcWhere({t, u}, {}), std::invalid_argument);
}

TEST(Where, AResidualThatIsNotAFiniteNumberGivesNoVerdict) {
    // One absurd sample (1e200 N squares to infinity): the RMSE and the noise were infinite,
    // infinity > 2 x infinity is false, and the verdict read "within the validation
    // uncertainty". Now calcWhere refuses, naming the channel, the test, the time and the
    // sample (the command turns it into a bad-input error on the measured data, exit 2).
    diagnose::TestComparison t;
    t.test = 2;
    diagnose::ChannelComparison c;
    c.kind = diagnose::ChannelKind::Force;
    for (int i = 0; i < 6; ++i) {
        c.time.push_back(0.5 * i);
        c.displacement.push_back(1e-3 * i);
        c.force.push_back(i);
        c.loading.push_back(1);
        c.measured.push_back(i == 4 ? 1e200 : 0.1 * i);
        c.simulated.push_back(0.1 * i);
    }
    t.channels.push_back(c);
    try {
        diagnose::calcWhere({t}, {});
        ADD_FAILURE() << "no error for a sample of 1e200 N";
    } catch (const std::domain_error& e) {
        EXPECT_NE(std::string(e.what()).find("the force residual is not a finite number: test 3 "
                                             "at 2 s has a sample of 1e+200"),
                  std::string::npos)
            << e.what();
    }
    t.channels[0].measured[4] = 0.4;  // the same data without it: a verdict
    EXPECT_NO_THROW(diagnose::calcWhere({t}, {}));
}

TEST(Diagnosis, AnEffectThatLeavesAResidualIsNamedAsPartlyExplaining) {
    // The pressure sensor's lag and offset, and a load cell reading 5 % high (outside the
    // library). The sensor alone explains too little of the whole gap; the pair stage adds the
    // flowmeter's bias, which mimics part of the gain. Held out, the force stays 7 times its
    // validation uncertainty: whatever is named explains only a part, and the verdict says so.
    const Diagnosed d = diagnoseStandIn(
        EffectValues{{"pressure-sensor", {3.0, 200.0}}, {"load-cell-gain", {0.05}}});
    ASSERT_FALSE(d.which.verdictEffects.empty()) << d.which.reason;
    EXPECT_NE(
        std::find(d.which.verdictEffects.begin(), d.which.verdictEffects.end(), "pressure-sensor"),
        d.which.verdictEffects.end())
        << d.which.verdict;
    EXPECT_EQ(d.which.explained, "partly") << d.which.reason;
    EXPECT_EQ(d.which.residualChannel, "force");
    EXPECT_GT(d.which.residualRatio, 2.0 * diagnose::kExplainedMultiple);
    EXPECT_EQ(d.which.reason.rfind("partly explained by " + d.which.verdict + ": held out, ", 0),
              0u)
        << d.which.reason;
    EXPECT_NE(d.which.reason.find("leaves the force at "), std::string::npos);
    EXPECT_NE(d.which.reason.find("a residual remains that it does not explain"),
              std::string::npos);
    EXPECT_EQ(diagnose::describeVerdict(d.which), d.which.verdict + ", partly explained");
    // Alone, the sensor explains everything.
    const Diagnosed alone = diagnoseStandIn("pressure-sensor", {3.0, 200.0});
    EXPECT_EQ(alone.which.explained, "fully") << alone.which.reason;
    EXPECT_EQ(diagnose::describeVerdict(alone.which), "pressure-sensor");
}

TEST(Diagnosis, NoneAndUnexplainedAreNotQualified) {
    for (const Diagnosed& d : {diagnoseStandIn("", {}), diagnoseStandIn("load-cell-gain", {0.1})}) {
        EXPECT_TRUE(d.which.explained.empty()) << d.which.verdict;
        EXPECT_TRUE(d.which.rivals.empty());
        EXPECT_TRUE(std::isnan(d.which.residualRatio));
    }
}

TEST(Diagnosis, ConfusableCandidatesMustExplainAlike) {
    // findConfusable on made-up candidates, the validation uncertainty 1 N on the force.
    auto make = [](const std::string& name, double shrink, double rmse) {
        diagnose::CandidateResult c;
        c.effect = name;
        c.excessShrink = shrink;
        c.score = shrink - 0.05;
        diagnose::GapMetrics m;
        m.channel = "force";
        m.rmse = rmse;
        c.heldoutMetricsAfter = {m};
        return c;
    };
    const diagnose::ChannelUncertainties u{{"force", 1.0}};
    using Pairs = std::vector<std::pair<std::string, std::string>>;
    // Both within twice the uncertainty, shrinks 0.05 apart: rivals.
    EXPECT_EQ(diagnose::findConfusable({make("a", 0.95, 1.5), make("b", 0.90, 1.9)}, 0.5, u),
              (Pairs{{"a", "b"}}));
    // The same shrinks, but b leaves 2.5 times the uncertainty: told apart.
    EXPECT_TRUE(
        diagnose::findConfusable({make("a", 0.95, 1.5), make("b", 0.90, 2.5)}, 0.5, u).empty());
    // Both beyond (both partly): rivals.
    EXPECT_EQ(diagnose::findConfusable({make("a", 0.70, 3.0), make("b", 0.65, 4.0)}, 0.5, u),
              (Pairs{{"a", "b"}}));
    // Shrinks 0.15 apart: told apart.
    EXPECT_TRUE(
        diagnose::findConfusable({make("a", 0.95, 1.5), make("b", 0.80, 1.9)}, 0.5, u).empty());
    // The better just passes the threshold, the other just misses it: rivals all the same.
    EXPECT_EQ(diagnose::findConfusable({make("a", 0.56, 3.0), make("b", 0.50, 3.0)}, 0.5, u),
              (Pairs{{"a", "b"}}));
    // Neither explains: no pair.
    EXPECT_TRUE(
        diagnose::findConfusable({make("a", 0.40, 3.0), make("b", 0.38, 3.0)}, 0.5, u).empty());
    // A candidate's own prediction error widens its scale: 2.5 N over hypot(1, 1) is within.
    diagnose::CandidateResult b = make("b", 0.90, 2.5);
    b.predictionUncertainty = 1.0;
    EXPECT_EQ(diagnose::findConfusable({make("a", 0.95, 1.5), b}, 0.5, u), (Pairs{{"a", "b"}}));
}
