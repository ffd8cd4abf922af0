// The patient's diagnosis on a stand-in run (no co-simulation): a mat of 4 x 3 sensels whose
// load changes over 3 s, a tilt, two bags whose pressure rises and falls. Synthetic data with an
// instrument effect are made from it (synthesizePatientChannels) and diagnosed against it:
// the where stage splits the residuals by region, bag and time window (shares adding up), the
// which stage names the effect put in and brings its parameters back, and names none without
// one; the effects that change the response say which scenario keys they set.
#include <gtest/gtest.h>

#include <diagnose/PatientDiagnosis.h>

#include <cmath>
#include <map>
#include <stdexcept>

using namespace diagnose;

namespace {

constexpr double kMmHg = 133.322387415;

// The stand-in run: outputs every 10 ms over 3 s.
PatientChannels makeRun() {
    PatientChannels r;
    r.mat.rows = 4, r.mat.columns = 3;
    for (int k = 0; k <= 300; ++k) {
        const double t = 0.01 * k;
        r.mat.time.push_back(t);
        std::vector<double> f(12, 0.0);
        for (int s = 0; s < 12; ++s)
            if (s % 4 != 3) f[size_t(s)] = (20.0 + 5.0 * s + 10.0 * std::sin(2.0 * t + s)) * kMmHg;
        r.mat.pressure.push_back(f);
        r.tilt.time.push_back(t);
        r.tilt.pelvis.push_back(0.1 * std::sin(1.5 * t));
        r.tilt.thorax.push_back(0.05 * std::sin(1.5 * t + 0.3));
    }
    for (int b : {3, 8}) {
        BagPressureChannel c;
        c.bag = b;
        for (int k = 0; k <= 300; ++k) {
            const double t = 0.01 * k;
            c.pressure.time.push_back(t);
            c.pressure.value.push_back(20e3 + 2e3 * std::sin(3.0 * t + b) + 500.0 * t);
        }
        r.bags.push_back(c);
    }
    return r;
}

MatRegions makeRegions() {
    MatRegions m;
    m.names = {"heels", "sacrum"};
    m.sensel = {0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1};
    return m;
}

const std::vector<double> kEdges = {0.0, 1.0, 2.0, 3.0 + 1e-9};

PatientSimulator noSimulation() {
    return [](const std::vector<std::pair<std::string, std::string>>&, const std::string&) -> PatientChannels {
        throw std::logic_error("an instrument effect needs no co-simulation");
    };
}

struct Diagnosed {
    PatientComparison comparison;
    WhereReport where;
    WhichReport which;
};

// Synthetic data of the run with these instruments, diagnosed against the run itself (a
// numerical uncertainty of zero: the model-form difference is the co-simulation's, not here).
Diagnosed diagnoseSynthetic(const PatientInstruments& inst, std::uint64_t seed = 1) {
    const PatientChannels run = makeRun();
    PatientSynthesisOptions so;
    so.seed = seed;
    so.matInterval = 0.05;
    const PatientChannels measured = synthesizePatientChannels(run, inst, so);
    Diagnosed d;
    d.comparison = comparePatient(measured, run, {}, makeRegions());
    d.where = calcPatientWhere(d.comparison, {}, kEdges, 2.0);
    d.which = calibratePatientCandidates(measured, run, d.comparison, d.where, makeRegions(), kEdges,
                                         4.5e-3, noSimulation(), {});
    return d;
}

}  // namespace

TEST(PatientDiagnosis, SynthesisSamplesTheInstrumentsWithNoise) {
    const PatientChannels run = makeRun();
    PatientInstruments inst;
    inst.bagSensorOffset = 300.0;
    inst.matGain = 0.1;
    PatientSynthesisOptions so;
    so.matNoise = so.tiltNoise = so.pressureNoise = 0.0;
    const PatientChannels m = synthesizePatientChannels(run, inst, so);
    ASSERT_EQ(m.mat.time.size(), 31u);  // 0 to 3 s every 0.1 s
    ASSERT_EQ(m.tilt.time.size(), 151u);  // every 0.02 s
    EXPECT_NEAR(m.mat.pressure[10][1], 1.1 * run.mat.pressure[100][1], 1e-9);
    EXPECT_EQ(m.mat.pressure[10][3], 0.0);  // a sensel that reads nothing stays 0
    ASSERT_EQ(m.bags.size(), 2u);
    EXPECT_NEAR(m.bags[1].pressure.value[50], run.bags[1].pressure.value[100] + 300.0, 1e-9);
    // With noise: a loaded sensel's reading scatters by the noise, an empty one stays 0.
    so.matNoise = 0.5 * kMmHg;
    const PatientChannels n = synthesizePatientChannels(run, {}, so);
    double s2 = 0.0;
    for (size_t f = 0; f < n.mat.time.size(); ++f) {
        s2 += std::pow(n.mat.pressure[f][0] - run.mat.pressure[10 * f][0], 2);
        EXPECT_EQ(n.mat.pressure[f][7], 0.0);
    }
    EXPECT_NEAR(std::sqrt(s2 / double(n.mat.time.size())), 0.5 * kMmHg, 0.2 * kMmHg);
}

TEST(PatientDiagnosis, WhereSplitsByRegionBagAndWindow) {
    PatientInstruments inst;
    inst.bagSensorOffset = 1000.0;
    const Diagnosed d = diagnoseSynthetic(inst);
    ASSERT_EQ(d.where.channels.size(), 4u);
    EXPECT_EQ(d.where.channels[0].channel, "mat");
    EXPECT_EQ(d.where.channels[3].channel, "bag-pressure");
    EXPECT_NEAR(d.where.channels[3].rmse, 1000.0, 20.0);
    EXPECT_FALSE(d.where.withinValidation);
    // Per channel, the parts' shares and the windows' shares each add up to 1.
    std::map<std::string, double> parts, windows;
    for (const RegimeStats& r : d.where.regimes) {
        if (r.regime == "all") continue;
        (r.regime.rfind("time ", 0) == 0 ? windows : parts)[r.channel] += r.share;
    }
    EXPECT_NEAR(parts["mat"], 1.0, 1e-12);
    EXPECT_NEAR(parts["bag-pressure"], 1.0, 1e-12);
    for (const auto& [c, s] : windows) EXPECT_NEAR(s, 1.0, 1e-12) << c;
    // Each bag's signature carries the offset as its bias.
    int bags = 0;
    for (const Signature& s : d.where.signatures)
        if (s.channel == "bag-pressure") {
            ++bags;
            EXPECT_NEAR(s.bias, 1000.0, 20.0);
        }
    EXPECT_EQ(bags, 2);
}

TEST(PatientDiagnosis, FindsTheBagSensorsLagAndOffset) {
    PatientInstruments inst;
    inst.bagSensorLag = 0.3;
    inst.bagSensorOffset = 400.0;
    const Diagnosed d = diagnoseSynthetic(inst);
    EXPECT_EQ(d.which.verdict, "bag-pressure-sensor") << d.which.reason;
    const CandidateResult& c = d.which.candidates.front();
    ASSERT_EQ(c.effect, "bag-pressure-sensor");
    EXPECT_NEAR(c.parameters[0], 0.3, 0.03);
    EXPECT_NEAR(c.parameters[1], 400.0, 20.0);
    EXPECT_GT(c.excessShrink, 0.9);
    ASSERT_EQ(c.folds.size(), 3u);
    for (const FoldResult& f : c.folds) EXPECT_LT(f.excessAfter, 0.2 * f.excessBefore);
    EXPECT_EQ(c.simulations, 0);
}

TEST(PatientDiagnosis, FindsTheMatsGain) {
    PatientInstruments inst;
    inst.matGain = 0.15;
    const Diagnosed d = diagnoseSynthetic(inst);
    EXPECT_EQ(d.which.verdict, "mat-gain") << d.which.reason;
    EXPECT_NEAR(d.which.candidates.front().parameters[0], 0.15, 0.01);
}

TEST(PatientDiagnosis, NoEffectIsNone) {
    const Diagnosed d = diagnoseSynthetic({}, 2);
    EXPECT_TRUE(d.where.withinValidation);
    EXPECT_EQ(d.which.verdict, "none");
    for (const CandidateResult& c : d.which.candidates) EXPECT_LE(c.score, 0.0) << c.effect;
}

TEST(PatientDiagnosis, EffectsOnTheResponseSetScenarioKeys) {
    const Effect* f = findPatientEffect("film-friction");
    ASSERT_TRUE(f && f->changesTheBag);
    EXPECT_EQ(getPatientEffectOverrides(*f, {0.4}, 4.5e-3).at(0),
              std::make_pair(std::string("bag.body_friction"), std::string("0.4")));
    const Effect* g = findPatientEffect("gas-mass-bias");
    EXPECT_EQ(getPatientEffectOverrides(*g, {0.2e-3}, 4.5e-3).at(0).second, "4.7 g");
    const Effect* t = findPatientEffect("soft-tissue");
    EXPECT_EQ(getPatientEffectOverrides(*t, {20e-3, 30e3}, 4.5e-3).at(0).second,
              "{thickness: 20 mm, modulus: 30 kPa}");
    EXPECT_TRUE(getPatientEffectOverrides(*t, {0.0, 30e3}, 4.5e-3).empty());  // no layer
    EXPECT_THROW(getPatientEffectOverrides(*f, {1.5}, 4.5e-3), std::invalid_argument);
    PatientInstruments inst;
    EXPECT_THROW(applyPatientInstrumentEffect(*findPatientEffect("mat-gain"), {0.5}, inst),
                 std::invalid_argument);
    EXPECT_EQ(listPatientEffectNames(),
              "bag-pressure-sensor, mat-gain, film-friction, gas-mass-bias, soft-tissue");
}
