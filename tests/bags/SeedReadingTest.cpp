// The seed's bag read from its words (bags/SeedReading.h, docs/geometry.md): which sizes each
// scaling multiplies, the first guess, and the search hitting a target fill mass on the coarse
// 20 mm rig.
#include <gtest/gtest.h>

#include <bags/MaterialFit.h>
#include <bags/SeedReading.h>

#include <cmath>

namespace {

bags::LoadTestOptions makeCoarseSeedRig() {
    bags::LoadTestOptions o;  // the seed scenario's settings
    o.geometry.meshSize = 0.020;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    return o;
}

}  // namespace

TEST(SeedReading, ScalingsMultiplyTheSizesTheyName) {
    const bags::DoubleWedgeParams p;  // 350/200/100/150 mm
    const double s = 0.9;
    const bags::DoubleWedgeParams a = bags::scaleDoubleWedge(p, bags::FillScaling::Profile, s);
    EXPECT_DOUBLE_EQ(a.longSide, 0.315);
    EXPECT_DOUBLE_EQ(a.shortSide, 0.180);
    EXPECT_DOUBLE_EQ(a.height, 0.135);
    EXPECT_DOUBLE_EQ(a.width, 0.100);
    EXPECT_DOUBLE_EQ(a.meshSize, p.meshSize);
    EXPECT_NEAR(a.calcFlatVolume(), s * s * p.calcFlatVolume(), 1e-15);
    const bags::DoubleWedgeParams b = bags::scaleDoubleWedge(p, bags::FillScaling::Uniform, s);
    EXPECT_DOUBLE_EQ(b.width, 0.090);
    EXPECT_NEAR(b.calcFlatVolume(), s * s * s * p.calcFlatVolume(), 1e-15);
    const bags::DoubleWedgeParams c = bags::scaleDoubleWedge(p, bags::FillScaling::Height, s);
    EXPECT_DOUBLE_EQ(c.longSide, 0.350);
    EXPECT_DOUBLE_EQ(c.width, 0.100);
    EXPECT_DOUBLE_EQ(c.height, 0.135);
    EXPECT_NEAR(c.calcFlatVolume(), s * p.calcFlatVolume(), 1e-15);
    for (auto sc :
         {bags::FillScaling::Profile, bags::FillScaling::Uniform, bags::FillScaling::Height}) {
        // The first guess follows the flat volume: V ~ s^q.
        const bags::LoadTestOptions rig = makeCoarseSeedRig();
        const double q = bags::getFillScalingExponent(sc);
        const double s0 = bags::estimateFillScale(rig, 2.8e-3, sc);
        const double flat = rig.gas.getAmbientDensity() * 1.18 * p.calcFlatVolume();
        EXPECT_NEAR(std::pow(s0, q) * flat, 2.8e-3, 1e-12) << bags::getFillScalingName(sc);
    }
    bags::FillMassOptions bad;
    bad.probeLow = 0.9;
    EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// 20 mm mesh: each measurement is one inflation to two taut probe states (seconds).
TEST(SeedReading, SearchHitsTheTargetFillMass) {
    const bags::LoadTestOptions rig = makeCoarseSeedRig();
    const double target = 2.8e-3;
    const bags::FillScaleResult r = bags::findFillScale(rig, target, bags::FillScaling::Profile);
    // Within the search's tolerance, 0.005 g, of the target, in at most three measurements
    // (the first guess, then the s^2 law; measured: see docs/geometry.md).
    EXPECT_NEAR(r.measurement.fillMass, target, 0.005e-3);
    EXPECT_LE(r.scales.size(), 3u);
    EXPECT_EQ(r.scales.back(), r.scale);
    // The geometry is the profile scaled by s, the width kept.
    EXPECT_DOUBLE_EQ(r.geometry.longSide, 0.350 * r.scale);
    EXPECT_DOUBLE_EQ(r.geometry.width, 0.100);
    EXPECT_GT(r.scale, 0.8);
    EXPECT_LT(r.scale, 0.95);
    // The probe states are taut, the heavier one at the higher pressure.
    EXPECT_GT(r.measurement.probePressure[1], 500.0);
    EXPECT_GT(r.measurement.probePressure[0], r.measurement.probePressure[1]);
    // Extrapolating the pressure in the mass instead of the volume in the pressure gives the
    // same fill mass to within 0.05 g (both use the same two states).
    EXPECT_NEAR(r.measurement.fillMassFromPressure, r.measurement.fillMass, 0.05e-3);
    // A second measurement of the found geometry repeats the first.
    bags::LoadTestOptions o = rig;
    o.geometry = r.geometry;
    const bags::FillMassMeasurement m = bags::measureFillMass(o, target);
    EXPECT_NEAR(m.fillMass, r.measurement.fillMass, 1e-9);
}
