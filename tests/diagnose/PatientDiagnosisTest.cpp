// The patient's diagnosis on a stand-in run (no co-simulation): a mat of 4 x 3 sensels whose
// load changes over 3 s, a tilt, two bags whose pressure rises and falls. Synthetic data with an
// instrument effect are made from it (synthesizePatientChannels) and diagnosed against it:
// the where stage splits the residuals by region, bag and time window (shares adding up), the
// which stage names the effect put in and brings its parameters back, and names none without
// one; the effects that change the response say which scenario keys they set.
// With several tests the comparisons are joined (each sample tagged with its test), the folds
// are the tests, and an effect on the response is run in every test at its stated gas mass.
// With subjects (tests that name the patient measured) the folds hold out all tests of one
// subject; the where stage splits by subject; each test's mat regions are its own patient's.
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
    return [](const std::vector<std::pair<std::string, std::string>>&,
              const std::string&) -> PatientChannels {
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
    d.which = calibratePatientCandidates(measured, run, d.comparison, d.where, makeRegions(),
                                         kEdges, 4.5e-3, noSimulation(), {});
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
    ASSERT_EQ(m.mat.time.size(), 31u);    // 0 to 3 s every 0.1 s
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

// ------------------------------------------------------------------ leave one test out

namespace {

// A stand-in test: the run with its bags' pressures raised by `lift` [Pa] (another condition).
PatientChannels makeTestRun(double lift) {
    PatientChannels r = makeRun();
    for (BagPressureChannel& b : r.bags)
        for (double& p : b.pressure.value) p += lift;
    return r;
}

}  // namespace

TEST(PatientDiagnosis, JoinedTestsKeepTheirSamplesApart) {
    PatientSynthesisOptions so;
    so.matInterval = 0.5;
    std::vector<PatientComparison> parts;
    for (double lift : {0.0, 3e3}) {
        const PatientChannels run = makeTestRun(lift);
        parts.push_back(
            comparePatient(synthesizePatientChannels(run, {}, so), run, {}, makeRegions()));
    }
    parts[1].channels.back().partNames = {"bag 8",
                                          "bag 3"};  // the same bags named in another order
    for (int& p : parts[1].channels.back().part) p = 1 - p;
    const PatientComparison j = joinPatientComparisons(parts, {"a", "b"});
    ASSERT_EQ(j.tests.size(), 2u);
    const PatientChannelComparison* bags = j.find("bag-pressure");
    ASSERT_TRUE(bags);
    EXPECT_EQ(bags->partNames, (std::vector<std::string>{"bag 3", "bag 8"}));
    EXPECT_EQ(bags->time.size(), 2 * parts[0].find("bag-pressure")->time.size());
    // A sample of test b keeps its bag's name and its test.
    const size_t i = parts[0].find("bag-pressure")->time.size();
    EXPECT_EQ(bags->getTest(i), 1);
    EXPECT_EQ(bags->partNames[size_t(bags->part[i])],
              parts[1].channels.back().partNames[size_t(parts[1].channels.back().part[0])]);
    // The series (noise, signatures) are per test and part: 2 tests x 2 bags.
    EXPECT_EQ(bags->partSeries().size(), 4u);
    PatientFolds folds;
    folds.windowEdges = kEdges;
    folds.tests = 2;
    EXPECT_EQ(folds.getCount(), 2);
    EXPECT_EQ(folds.findFold(*bags, i), 1);
    EXPECT_EQ(folds.findFold(*bags, 0), 0);
    // The where stage splits by test and gives each test its own signatures.
    const WhereReport w = calcPatientWhere(j, {}, kEdges, 2.0);
    int byTest = 0, signed_b = 0;
    for (const RegimeStats& r : w.regimes) byTest += r.regime.rfind("test ", 0) == 0;
    for (const Signature& s : w.signatures) signed_b += s.part.rfind("test b", 0) == 0;
    EXPECT_EQ(byTest, 2 * int(j.channels.size()));
    EXPECT_EQ(signed_b, int(j.channels.size()) + 1);  // mat, two tilts, two bags
}

TEST(PatientDiagnosis, LeavesOneTestOutForAnInstrumentEffect) {
    PatientInstruments inst;
    inst.bagSensorLag = 0.3;
    inst.bagSensorOffset = 400.0;
    std::vector<PatientTestCase> tests;
    for (double lift : {0.0, 2e3, 4e3}) {
        PatientTestCase t;
        t.name = "lift-" + std::to_string(int(lift));
        t.baseline = makeTestRun(lift);
        PatientSynthesisOptions so;
        so.matInterval = 0.05;
        so.seed = uint64_t(lift) + 1;
        t.measured = synthesizePatientChannels(t.baseline, inst, so);
        t.statedGasMass = 4.5e-3;
        tests.push_back(t);
    }
    const std::vector<PatientComparison> parts = comparePatientTests(tests, makeRegions());
    const PatientComparison base =
        joinPatientComparisons(parts, {tests[0].name, tests[1].name, tests[2].name});
    const WhereReport where = calcPatientWhere(base, {}, kEdges, 2.0);
    PatientFolds folds;
    folds.windowEdges = kEdges;
    folds.tests = 3;
    const WhichReport which = calibratePatientCandidates(
        tests, where, makeRegions(), folds,
        [](int, const std::vector<std::pair<std::string, std::string>>&,
           const std::string&) -> PatientChannels {
            throw std::logic_error("an instrument effect needs no co-simulation");
        },
        {});
    EXPECT_EQ(which.verdict, "bag-pressure-sensor") << which.reason;
    const CandidateResult& c = which.candidates.front();
    ASSERT_EQ(c.folds.size(), 3u);  // one per test, not per time window
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(c.folds[size_t(k)].heldOut, k);
        EXPECT_NEAR(c.folds[size_t(k)].parameters[0], 0.3, 0.03);
        EXPECT_NEAR(c.folds[size_t(k)].parameters[1], 400.0, 20.0);
        EXPECT_LT(c.folds[size_t(k)].excessAfter, 0.2 * c.folds[size_t(k)].excessBefore);
    }
}

TEST(PatientDiagnosis, LeavesOneTestOutRunningAResponseEffectInEveryTest) {
    // The gas mass's effect on the stand-in: every bag 20 kPa per gram above the stated mass.
    // Two tests at 4.0 and 5.0 g; the bags hold 0.2 g more than stated in both.
    const double perKg = 20e3 / 1e-3;
    const std::vector<double> stated = {4.0e-3, 5.0e-3};
    std::vector<PatientTestCase> tests;
    for (size_t t = 0; t < stated.size(); ++t) {
        PatientTestCase c;
        c.name = t ? "gas-5.0g" : "gas-4.0g";
        c.baseline = makeTestRun(0.0);
        PatientSynthesisOptions so;
        so.matInterval = 0.05;
        so.seed = t + 1;
        c.measured = synthesizePatientChannels(makeTestRun(perKg * 0.2e-3), {}, so);
        c.statedGasMass = stated[t];
        tests.push_back(c);
    }
    std::vector<std::pair<int, std::string>> calls;  // test, its array.gas_mass
    const PatientTestSimulator simulate =
        [&](int t, const std::vector<std::pair<std::string, std::string>>& ov, const std::string&) {
            EXPECT_EQ(ov.size(), 1u);
            EXPECT_EQ(ov.at(0).first, "array.gas_mass");
            calls.push_back({t, ov.at(0).second});
            const double mass = std::stod(ov.at(0).second) * 1e-3;  // "4.25 g"
            return makeTestRun(perKg * (mass - stated[size_t(t)]));
        };
    const std::vector<PatientComparison> parts = comparePatientTests(tests, makeRegions());
    const PatientComparison base = joinPatientComparisons(parts, {tests[0].name, tests[1].name});
    const WhereReport where = calcPatientWhere(base, {}, kEdges, 2.0);
    PatientFolds folds;
    folds.windowEdges = kEdges;
    folds.tests = 2;
    PatientCalibrationOptions o;
    o.candidates = {"gas-mass-bias"};
    const WhichReport which =
        calibratePatientCandidates(tests, where, makeRegions(), folds, simulate, o);
    EXPECT_EQ(which.verdict, "gas-mass-bias") << which.reason;
    const CandidateResult& c = which.candidates.front();
    EXPECT_NEAR(c.parameters[0], 0.2e-3, 0.01e-3);
    ASSERT_EQ(c.folds.size(), 2u);
    // Each trial value ran in both tests, at the test's stated mass plus the offset.
    EXPECT_EQ(c.simulations, int(calls.size()));
    EXPECT_EQ(calls.size() % 2, 0u);
    bool sawGrid = false;
    for (size_t k = 0; k + 1 < calls.size(); k += 2) {
        EXPECT_EQ(calls[k].first, 0);
        EXPECT_EQ(calls[k + 1].first, 1);
        const double a = std::stod(calls[k].second), b = std::stod(calls[k + 1].second);
        EXPECT_NEAR(b - a, 1.0, 1e-9) << calls[k].second << " " << calls[k + 1].second;
        sawGrid |= calls[k].second == "4.25 g" && calls[k + 1].second == "5.25 g";
    }
    EXPECT_TRUE(sawGrid);
}

// ------------------------------------------------------------------ leave one subject out

namespace {

// Four tests of three subjects: a (two tests), b, c; each subject's bags lifted by its own
// amount (another build), a's second test a little more (another condition).
struct SubjectCase {
    std::string test, subject;
    double lift;
};
const std::vector<SubjectCase> kSubjectCases = {
    {"a-1", "a", 0.0}, {"b-1", "b", 2e3}, {"a-2", "a", 1e3}, {"c-1", "c", 4e3}};

// The regions of a taller patient: his sacrum over the mat's first half.
MatRegions makeTallRegions() {
    MatRegions m;
    m.names = {"heels", "sacrum"};
    m.sensel = {1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0};
    return m;
}

std::vector<PatientTestCase> makeSubjectTests(const PatientInstruments& inst) {
    std::vector<PatientTestCase> tests;
    for (size_t k = 0; k < kSubjectCases.size(); ++k) {
        PatientTestCase t;
        t.name = kSubjectCases[k].test;
        t.subject = kSubjectCases[k].subject;
        t.baseline = makeTestRun(kSubjectCases[k].lift);
        PatientSynthesisOptions so;
        so.matInterval = 0.05;
        so.seed = k + 1;
        t.measured = synthesizePatientChannels(t.baseline, inst, so);
        t.statedGasMass = 4.5e-3;
        if (t.subject == "b") t.regions = makeTallRegions();
        tests.push_back(t);
    }
    return tests;
}

std::vector<std::string> getNames(const std::vector<PatientTestCase>& tests, bool subjects) {
    std::vector<std::string> out;
    for (const PatientTestCase& t : tests) out.push_back(subjects ? t.subject : t.name);
    return out;
}

PatientFolds makeSubjectFolds(const PatientComparison& base) {
    PatientFolds folds;
    folds.windowEdges = kEdges;
    folds.tests = int(base.tests.size());
    folds.subjects = base.subjects;
    folds.testSubject = base.testSubject;
    return folds;
}

}  // namespace

TEST(PatientDiagnosis, JoinedTestsKnowTheirSubjects) {
    const std::vector<PatientTestCase> tests = makeSubjectTests({});
    const std::vector<PatientComparison> parts = comparePatientTests(tests, makeRegions());
    const PatientComparison j =
        joinPatientComparisons(parts, getNames(tests, false), getNames(tests, true));
    EXPECT_EQ(j.subjects,
              (std::vector<std::string>{"a", "b", "c"}));  // in the order they first appear
    EXPECT_EQ(j.testSubject, (std::vector<int>{0, 1, 0, 2}));
    // Without subjects the joined tests have none.
    const PatientComparison n = joinPatientComparisons(parts, getNames(tests, false));
    EXPECT_TRUE(n.subjects.empty());
    EXPECT_TRUE(n.testSubject.empty());
    // The folds: one per subject; a's fold holds out both of its tests.
    const PatientFolds folds = makeSubjectFolds(j);
    EXPECT_TRUE(folds.isBySubject());
    EXPECT_FALSE(folds.isByTest());
    EXPECT_STREQ(folds.getKind(), "subject");
    EXPECT_EQ(folds.getCount(), 3);
    EXPECT_EQ(folds.getFoldTests(0), (std::vector<int>{0, 2}));
    EXPECT_EQ(folds.getFoldTests(2), (std::vector<int>{3}));
    const PatientChannelComparison* bags = j.find("bag-pressure");
    ASSERT_TRUE(bags);
    for (size_t i = 0; i < bags->time.size(); ++i)
        EXPECT_EQ(folds.findFold(*bags, i), j.testSubject[size_t(bags->getTest(i))]);
    // Each test's mat on its own patient's regions: b's first sensel under his sacrum.
    const PatientChannelComparison* mat = parts[1].find("mat");
    ASSERT_TRUE(mat);
    EXPECT_EQ(mat->partNames[size_t(mat->part[0])], mat->sensel[0] < 6 ? "sacrum" : "heels");
    const PatientChannelComparison* matA = parts[0].find("mat");
    EXPECT_EQ(matA->partNames[size_t(matA->part[0])], matA->sensel[0] < 6 ? "heels" : "sacrum");
    // The where stage: a regime per subject, and per test (a has two tests); signatures per test
    // named with the subject.
    const WhereReport w = calcPatientWhere(j, {}, kEdges, 2.0);
    int bySubject = 0, byTest = 0, named = 0;
    for (const RegimeStats& r : w.regimes) {
        const bool subject = r.regime.rfind("subject ", 0) == 0;
        const bool test = r.regime.find(", test ") != std::string::npos;  // "subject a, test a-1"
        bySubject += subject && !test;
        byTest += subject && test;
    }
    for (const Signature& sg : w.signatures) named += sg.part.rfind("subject a, test a-2", 0) == 0;
    EXPECT_EQ(bySubject, 3 * int(j.channels.size()));
    EXPECT_EQ(byTest, 4 * int(j.channels.size()));
    EXPECT_EQ(named, int(j.channels.size()) + 1);  // mat, two tilts, two bags
}

TEST(PatientDiagnosis, LeavesOneSubjectOutForAnInstrumentEffect) {
    PatientInstruments inst;
    inst.bagSensorLag = 0.3;
    inst.bagSensorOffset = 400.0;
    const std::vector<PatientTestCase> tests = makeSubjectTests(inst);
    const std::vector<PatientComparison> parts = comparePatientTests(tests, makeRegions());
    const PatientComparison base =
        joinPatientComparisons(parts, getNames(tests, false), getNames(tests, true));
    const WhereReport where = calcPatientWhere(base, {}, kEdges, 2.0);
    const PatientFolds folds = makeSubjectFolds(base);
    const PatientTestSimulator none = [](int,
                                         const std::vector<std::pair<std::string, std::string>>&,
                                         const std::string&) -> PatientChannels {
        throw std::logic_error("an instrument effect needs no co-simulation");
    };
    const WhichReport which =
        calibratePatientCandidates(tests, where, makeRegions(), folds, none, {});
    EXPECT_EQ(which.verdict, "bag-pressure-sensor") << which.reason;
    const CandidateResult& c = which.candidates.front();
    ASSERT_EQ(c.folds.size(), 3u);  // one per subject, not per test (4) or time window
    for (int k = 0; k < 3; ++k) {
        const FoldResult& f = c.folds[size_t(k)];
        EXPECT_EQ(f.heldOut, k);
        EXPECT_NEAR(f.parameters[0], 0.3, 0.03);
        EXPECT_NEAR(f.parameters[1], 400.0, 20.0);
        EXPECT_LT(f.excessAfter, 0.2 * f.excessBefore);
        // The fold's gap is over its subject's tests.
        EXPECT_NEAR(f.before, calcPatientGap(base, where, folds, {k}, false), 1e-12);
    }
    // The held-out samples are every sample once (each subject held out once).
    size_t samples = 0;
    for (const PatientChannelComparison& ch : base.channels) samples += ch.time.size();
    size_t held = 0;
    for (const GapMetrics& m : c.heldoutMetricsBefore) held += size_t(m.samples);
    EXPECT_EQ(held, samples);
    // Folds that do not match the tests are refused.
    PatientFolds bad = folds;
    bad.testSubject.pop_back();
    EXPECT_THROW(calibratePatientCandidates(tests, where, makeRegions(), bad, none, {}),
                 std::invalid_argument);
}

TEST(PatientDiagnosis, LeavesOneSubjectOutRunningAResponseEffectInEveryTest) {
    // The gas mass on the stand-in (20 kPa per gram): every test's bags hold 0.2 g more than its
    // stated mass (a at 4.0 and 5.0 g, b at 4.5 g, c at 4.0 g).
    const double perKg = 20e3 / 1e-3;
    const std::vector<double> stated = {4.0e-3, 4.5e-3, 5.0e-3, 4.0e-3};
    std::vector<PatientTestCase> tests;
    for (size_t k = 0; k < kSubjectCases.size(); ++k) {
        PatientTestCase c;
        c.name = kSubjectCases[k].test;
        c.subject = kSubjectCases[k].subject;
        c.baseline = makeTestRun(kSubjectCases[k].lift);
        PatientSynthesisOptions so;
        so.matInterval = 0.05;
        so.seed = k + 1;
        c.measured =
            synthesizePatientChannels(makeTestRun(kSubjectCases[k].lift + perKg * 0.2e-3), {}, so);
        c.statedGasMass = stated[k];
        tests.push_back(c);
    }
    std::vector<int> calls(tests.size(), 0);
    const PatientTestSimulator simulate =
        [&](int t, const std::vector<std::pair<std::string, std::string>>& ov, const std::string&) {
            EXPECT_EQ(ov.at(0).first, "array.gas_mass");
            ++calls.at(size_t(t));
            const double mass = std::stod(ov.at(0).second) * 1e-3;
            return makeTestRun(kSubjectCases[size_t(t)].lift + perKg * (mass - stated[size_t(t)]));
        };
    const std::vector<PatientComparison> parts = comparePatientTests(tests, makeRegions());
    const PatientComparison base =
        joinPatientComparisons(parts, getNames(tests, false), getNames(tests, true));
    const WhereReport where = calcPatientWhere(base, {}, kEdges, 2.0);
    PatientCalibrationOptions o;
    o.candidates = {"gas-mass-bias"};
    const WhichReport which = calibratePatientCandidates(tests, where, makeRegions(),
                                                         makeSubjectFolds(base), simulate, o);
    EXPECT_EQ(which.verdict, "gas-mass-bias") << which.reason;
    const CandidateResult& c = which.candidates.front();
    ASSERT_EQ(c.folds.size(), 3u);
    for (const FoldResult& f : c.folds) EXPECT_NEAR(f.parameters[0], 0.2e-3, 0.01e-3) << f.heldOut;
    EXPECT_NEAR(c.parameters[0], 0.2e-3, 0.01e-3);
    // Every trial value ran in every test (the co-simulations are shared by the folds).
    for (size_t t = 1; t < calls.size(); ++t) EXPECT_EQ(calls[t], calls[0]) << t;
    EXPECT_GT(calls[0], 0);
    EXPECT_EQ(c.simulations, calls[0] * int(calls.size()));
}
