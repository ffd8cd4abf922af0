// Synthetic measured data (diagnose/Synthesis.h): without noise the instruments sample the
// truth curve exactly (with the rig's effects); with noise the scatter has the stated size and
// the same seed gives the same data.
#include <gtest/gtest.h>

#include <diagnose/Synthesis.h>

#include <cmath>

namespace {

// A linear curve: loading to 3 mm at 1 N/mm and 1 kPa/mm, then back to 1 mm.
bags::LoadCurve makeCurve(double gasMass) {
    bags::LoadCurve c;
    c.gasMass = gasMass;
    const double d[] = {0.0, 1e-3, 2e-3, 3e-3, 2e-3, 1e-3};
    for (int i = 0; i < 6; ++i) {
        bags::LoadStep s;
        s.displacement = d[i];
        s.force = d[i] * 1e3;
        s.loading = i <= 3;
        s.gaugePressure = {d[i] * 1e6};
        s.volume = {1e-3};
        c.steps.push_back(s);
    }
    return c;
}

diagnose::Protocol makeProtocol() {
    diagnose::Protocol p;
    p.rate = 1e-3 / 6.0;  // 10 mm/min: 6 s per mm
    p.peakForce = 3.0;
    p.blockSize = 0.05;
    p.roomTemperature = 296.15;
    return p;
}

}  // namespace

TEST(Synthesis, NoiseFreeSamplesAreTheTruthWithTheRigsEffects) {
    diagnose::SynthesisOptions o;
    o.displacementNoise = o.forceNoise = o.pressureNoise = o.massNoise = 0.0;
    o.sampleInterval = 1.5;
    diagnose::RigEffects rig;
    rig.machineCompliance = 1e-3;  // 1 mm/N: the crosshead travels twice the block's travel
    rig.flowmeterOffset = 0.1e-3;
    const diagnose::MeasuredData d =
        diagnose::synthesizeMeasurement({makeCurve(3.4e-3)}, {3.5e-3}, rig, makeProtocol(), o);
    ASSERT_EQ(d.tests.size(), 1u);
    const diagnose::MeasuredTest& t = d.tests[0];
    // Crosshead path 0 -> 6 mm -> 2 mm: 36 s + 24 s, samples every 1.5 s.
    ASSERT_EQ(t.time.size(), 41u);
    EXPECT_NEAR(t.time.back(), 60.0, 1e-9);
    EXPECT_NEAR(t.displacement[24], 6e-3, 1e-12);  // at 36 s, the turning point
    EXPECT_NEAR(t.force[24], 3.0, 1e-9);
    EXPECT_NEAR(t.force[12], 1.5, 1e-9);  // 18 s: 3 mm crosshead, 1.5 mm block
    EXPECT_NEAR(t.pressure.value[12], 1500.0, 1e-6);
    EXPECT_NEAR(t.flowmeter.value[5], 3.5e-3, 1e-15);  // it reads the bag's 3.4 g + 0.1 g
    EXPECT_DOUBLE_EQ(t.gasMass, 3.5e-3);
}

TEST(Synthesis, NoiseHasItsStatedSizeAndTheSeedRepeatsIt) {
    diagnose::SynthesisOptions o;
    o.forceNoise = 0.05;
    o.sampleInterval = 0.01;
    o.seed = 7;
    const diagnose::RigEffects rig;
    const auto a =
        diagnose::synthesizeMeasurement({makeCurve(3e-3)}, {3e-3}, rig, makeProtocol(), o);
    const auto b =
        diagnose::synthesizeMeasurement({makeCurve(3e-3)}, {3e-3}, rig, makeProtocol(), o);
    const diagnose::MeasuredTest& t = a.tests[0];
    double sum2 = 0.0;
    for (size_t i = 0; i < t.time.size(); ++i) {
        // The truth force at the sample: block travel = crosshead travel here (rigid rig).
        const double truth = t.time[i] <= 18.0 ? t.time[i] / 6.0 : 3.0 - (t.time[i] - 18.0) / 6.0;
        sum2 += std::pow(t.force[i] - truth, 2);
    }
    const double sd = std::sqrt(sum2 / double(t.time.size()));
    EXPECT_NEAR(sd, 0.05, 0.004) << t.time.size() << " samples";  // 3000 samples: 1.3 % s.e.
    EXPECT_EQ(a.tests[0].force, b.tests[0].force);
    o.seed = 8;
    const auto c =
        diagnose::synthesizeMeasurement({makeCurve(3e-3)}, {3e-3}, rig, makeProtocol(), o);
    EXPECT_NE(a.tests[0].force, c.tests[0].force);
}
