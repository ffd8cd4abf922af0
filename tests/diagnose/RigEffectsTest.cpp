// The rig's effects (diagnose/RigEffects.h) against their analytic answers: a first-order
// sensor on a ramp and a step, the offset, the compliance in series, the flowmeter's bias.
// The fabric-anisotropy candidate applied to the film; the bag-volume candidate's similar bag
// and its fill mass.
#include <gtest/gtest.h>

#include <diagnose/Effects.h>
#include <diagnose/RigEffects.h>

#include <bags/Airbag.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/MaterialFit.h>
#include <bags/SeedReading.h>

#include <cmath>
#include <cstdio>
#include <vector>

using diagnose::RigEffects;

TEST(PressureSensor, LagsARampByItsTimeConstant) {
    // p = a t from rest: y = a (t - tau (1 - exp(-t / tau))), exact at any sampling.
    RigEffects rig;
    rig.pressureLag = 2.0;
    const double a = 50.0;  // [Pa/s]
    std::vector<double> t, p;
    for (double ti = 0.0; ti <= 30.0; ti += 1.7) t.push_back(ti), p.push_back(a * ti);
    const std::vector<double> y = diagnose::applyPressureSensor(t, p, rig);
    for (size_t i = 0; i < t.size(); ++i)
        EXPECT_NEAR(y[i], a * (t[i] - 2.0 * (1.0 - std::exp(-t[i] / 2.0))), 1e-9) << t[i];
}

TEST(PressureSensor, FollowsAFastRiseExponentiallyAndAddsItsOffset) {
    // A rise over 1 ms, then constant: after it the reading approaches p1 as exp(-t / tau).
    RigEffects rig;
    rig.pressureLag = 3.0;
    rig.pressureOffset = 150.0;
    const std::vector<double> t = {0.0, 1e-3, 3.0, 6.0};
    const std::vector<double> p = {0.0, 1000.0, 1000.0, 1000.0};
    const std::vector<double> y = diagnose::applyPressureSensor(t, p, rig);
    EXPECT_NEAR(y[0], 150.0, 1e-12);
    EXPECT_NEAR(y[2], 150.0 + 1000.0 * (1.0 - std::exp(-1.0)), 0.5);
    EXPECT_NEAR(y[3], 150.0 + 1000.0 * (1.0 - std::exp(-2.0)), 0.5);
}

TEST(PressureSensor, WithoutLagReadsThePressurePlusOffset) {
    RigEffects rig;
    rig.pressureOffset = -80.0;
    const std::vector<double> y = diagnose::applyPressureSensor({0, 1, 2}, {10, 300, 20}, rig);
    EXPECT_DOUBLE_EQ(y[1], 220.0);
    EXPECT_DOUBLE_EQ(y[2], -60.0);
}

TEST(MachineCurve, ComplianceAddsForceOverStiffnessAndTheCrossheadSetsTheTime) {
    bags::LoadCurve c;
    const double d[] = {0.0, 1e-3, 2e-3, 1e-3}, f[] = {0.0, 1.0, 3.0, 0.5};
    for (int i = 0; i < 4; ++i) {
        bags::LoadStep s;
        s.displacement = d[i];
        s.force = f[i];
        s.loading = i < 3;
        s.gaugePressure = {100.0 * i, 100.0 * i};
        s.volume = {1e-3, 3e-3};
        c.steps.push_back(s);
    }
    RigEffects rig;
    rig.machineCompliance = 0.5e-3;  // 2 N/mm
    const double rate = 1e-3 / 6.0;  // 10 mm/min
    const diagnose::MachineCurve m = diagnose::calcMachineCurve(c, rig, rate);
    EXPECT_NEAR(m.displacement[2], 2e-3 + 1.5e-3, 1e-15);
    EXPECT_NEAR(m.displacement[3], 1e-3 + 0.25e-3, 1e-15);
    // Crosshead path 0 -> 1.5 -> 3.5 -> 1.25 mm at 10 mm/min: 9, 12 and 13.5 s.
    EXPECT_NEAR(m.time[1], 9.0, 1e-9);
    EXPECT_NEAR(m.time[3], 9.0 + 12.0 + 13.5, 1e-9);
    EXPECT_NEAR(m.pressure[2], 200.0, 1e-12);
    EXPECT_EQ(m.loading[3], 0);
}

TEST(Flowmeter, OffsetIsTakenFromTheReadings) {
    RigEffects rig;
    rig.flowmeterOffset = 0.1e-3;
    const std::vector<double> m = diagnose::calcBagGasMasses({3.5e-3, 1.0e-3}, rig);
    EXPECT_NEAR(m[0], 3.4e-3, 1e-15);
    EXPECT_NEAR(m[1], 0.9e-3, 1e-15);
    rig.flowmeterOffset = 0.2e-3;
    EXPECT_THROW(diagnose::calcBagGasMasses({0.15e-3}, rig), std::invalid_argument);
}

TEST(RigEffects, ValidateNamesTheParameterAndRange) {
    RigEffects rig;
    rig.pressureLag = 40.0;
    try {
        rig.validate();
        FAIL() << "no error";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'pressureLag' = 40 is invalid; use 0 to 30 s"),
                  std::string::npos)
            << e.what();
    }
}

TEST(MachineCurve, TheLoadCellGainScalesTheForceReadOnly) {
    bags::LoadCurve c;
    for (int i = 0; i < 3; ++i) {
        bags::LoadStep s;
        s.displacement = 1e-3 * i;
        s.force = 2.0 * i;
        s.gaugePressure = {100.0};
        c.steps.push_back(s);
    }
    RigEffects rig;
    rig.loadCellGain = 0.1;
    rig.machineCompliance = 1e-3;
    const diagnose::MachineCurve m = diagnose::calcMachineCurve(c, rig, 1e-3);
    EXPECT_NEAR(m.force[2], 4.4, 1e-12);
    // The crosshead follows the true force through the compliance, not the reading.
    EXPECT_NEAR(m.displacement[2], 2e-3 + 4.0 * 1e-3, 1e-15);
}

// The bed board on a spring: the bag rides down on it as a rigid body (the bed carries the
// block's force; the airbag's translation invariance is checked in tests/bags/AirbagTest.cpp),
// so the crosshead travels the block's travel into the bag plus force times the bed's
// compliance, in series with the machine's: exactly what a machine compliance of the sum gives
// (tolerance: roundoff). The pressure at a sample is the bag's, unchanged: the two effects are
// confusable on the rig's channels.
TEST(MachineCurve, TheBedsComplianceAddsInSeriesWithTheMachines) {
    bags::LoadCurve c;
    for (int i = 0; i < 4; ++i) {
        bags::LoadStep s;
        s.displacement = 1e-3 * i;
        s.force = 2.0 * i * i;
        s.gaugePressure = {100.0 * i};
        c.steps.push_back(s);
    }
    RigEffects bed, machine;
    bed.bedCompliance = 0.3e-3;
    bed.machineCompliance = 0.2e-3;
    machine.machineCompliance = 0.5e-3;
    const diagnose::MachineCurve a = diagnose::calcMachineCurve(c, bed, 1e-3);
    const diagnose::MachineCurve b = diagnose::calcMachineCurve(c, machine, 1e-3);
    for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(a.displacement[i], 1e-3 * i + 2.0 * i * i * 0.5e-3, 1e-15);
        EXPECT_NEAR(a.displacement[i], b.displacement[i], 1e-15);
        EXPECT_NEAR(a.time[i], b.time[i], 1e-12);
        EXPECT_EQ(a.pressure[i], b.pressure[i]);
    }
    EXPECT_FALSE(bed.isNone());
    RigEffects bad;
    bad.bedCompliance = 3e-3;
    EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The fabric's yarns as a candidate: the film becomes the matrix of a balanced weave whose
// warp and weft moduli are the ratio times 3 mu; a ratio of 0 leaves the film as it was (the
// same material, bit for bit); outside its bounds it is refused naming the bounds.
TEST(Effects, FabricAnisotropyAddsBalancedYarnsAndZeroLeavesTheFilm) {
    const diagnose::Effect* effect = diagnose::findEffect("fabric-anisotropy");
    ASSERT_NE(effect, nullptr);
    EXPECT_TRUE(effect->changesTheBag);
    EXPECT_TRUE(effect->inLibrary);
    bags::LoadTestOptions o;
    o.material = bags::makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    diagnose::RigEffects rig;
    bags::LoadTestOptions on = o;
    diagnose::applyEffect(*effect, {0.5}, {}, rig, on);
    const auto* fabric = dynamic_cast<const bags::FabricMaterial*>(on.material.get());
    ASSERT_NE(fabric, nullptr);
    EXPECT_DOUBLE_EQ(fabric->getYarns().warpModulus, 0.5 * 6.0 * 31.587917e6);
    EXPECT_EQ(fabric->getYarns().weftModulus, fabric->getYarns().warpModulus);
    EXPECT_EQ(fabric->getYarns().angle, 0.0);
    // Applied again (a trial value on a fabric film): the yarns are replaced, not stacked.
    diagnose::applyEffect(*effect, {0.25}, {}, rig, on);
    fabric = dynamic_cast<const bags::FabricMaterial*>(on.material.get());
    ASSERT_NE(fabric, nullptr);
    EXPECT_DOUBLE_EQ(fabric->getYarns().warpModulus, 0.25 * 6.0 * 31.587917e6);
    EXPECT_TRUE(fabric->getMatrix().isIsotropic());
    bags::LoadTestOptions off = o;
    diagnose::applyEffect(*effect, {0.0}, {}, rig, off);
    ASSERT_TRUE(off.material->isIsotropic());
    bags::Mat2 C;
    C << 1.04, 0.01, 0.01, 0.99;
    Eigen::Vector3d S0, S1;
    Eigen::Matrix3d D0, D1;
    EXPECT_EQ(off.material->calcEnergy(C, &S0, &D0), o.material->calcEnergy(C, &S1, &D1));
    EXPECT_EQ(S0, S1);
    EXPECT_EQ(D0, D1);
    bags::LoadTestOptions noFilm;
    EXPECT_THROW(diagnose::applyEffect(*effect, {0.5}, {}, rig, noFilm), std::invalid_argument);
    try {
        diagnose::applyEffect(*effect, {3.5}, {}, rig, on);
        ADD_FAILURE() << "a ratio of 3.5 accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("valid: 0 to 3"), std::string::npos) << e.what();
    }
}

// Soft tissue as a candidate: a layer on the block (its thickness and modulus), the bed board
// left bare; a thickness of 0 is no layer; outside the bounds (0-40 mm, 10-200 kPa) it is
// refused naming them.
TEST(Effects, SoftTissuePutsALayerOnTheBlockOnly) {
    const diagnose::Effect* effect = diagnose::findEffect("soft-tissue");
    ASSERT_NE(effect, nullptr);
    EXPECT_TRUE(effect->changesTheBag);
    EXPECT_TRUE(effect->inLibrary);
    ASSERT_EQ(effect->parameters.size(), 2u);
    bags::LoadTestOptions o;
    diagnose::RigEffects rig;
    diagnose::applyEffect(*effect, {0.015, 50e3}, {}, rig, o);
    EXPECT_EQ(o.blockContact.tissueThickness, 0.015);
    EXPECT_EQ(o.blockContact.tissueModulus, 50e3);
    EXPECT_FALSE(o.floorContact.hasTissue());
    EXPECT_NO_THROW(o.blockContact.validate());
    EXPECT_TRUE(rig.isNone());
    try {
        diagnose::applyEffect(*effect, {0.015, 300e3}, {}, rig, o);
        ADD_FAILURE() << "300 kPa accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("valid: 10 to 200 kPa"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(diagnose::applyEffect(*effect, {0.045, 50e3}, {}, rig, o), std::invalid_argument);
    // A thickness of 0 is no layer: the candidate contains the model as it is.
    diagnose::applyEffect(*effect, {0.0, 50e3}, {}, rig, o);
    EXPECT_FALSE(o.blockContact.hasTissue());
    EXPECT_EQ(o.blockContact.tissueModulus, 0.0);
    EXPECT_NO_THROW(o.blockContact.validate());
}

// The bag's volume as a candidate: a geometrically similar bag, the mesh built from the
// scenario's sizes with every node times cbrt(1 + volume) (the same triangles: a mesh built
// anew from scaled sizes flips diagonals of the side panels on round-off ties, at a third of
// the values on the tiny rig's 25 mm mesh), so its flat volume is exactly 1 + volume times the
// scenario's; applied twice the scales multiply; outside the bounds (-0.25 to 0.25) it is
// refused naming them.
TEST(Effects, BagVolumeScalesTheBagSimilarly) {
    const diagnose::Effect* effect = diagnose::findEffect("bag-volume");
    ASSERT_NE(effect, nullptr);
    EXPECT_TRUE(effect->changesTheBag);
    EXPECT_TRUE(effect->inLibrary);
    ASSERT_EQ(effect->parameters.size(), 1u);
    bags::LoadTestOptions o;
    o.geometry.meshSize = 0.025;  // the tiny rig's
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.gasMasses = {4e-3};
    const bags::DoubleWedgeParams g0 = o.geometry;
    const bags::Mesh m0 = bags::makeDoubleWedgeBag(g0);
    diagnose::RigEffects rig;
    for (double v : {-0.25, -0.15, 0.01, 0.02, 0.1, 0.25}) {
        bags::LoadTestOptions on = o;
        diagnose::applyEffect(*effect, {v}, {}, rig, on);
        const double s = std::cbrt(1.0 + v);
        EXPECT_NEAR(on.bagScale, s, 1e-15) << v;
        EXPECT_EQ(on.geometry.longSide, g0.longSide);  // the sizes the mesh is built from
        const bags::DoubleWedgeParams g = on.getBagGeometry();
        EXPECT_NEAR(g.calcFlatVolume(), (1.0 + v) * g0.calcFlatVolume(), 1e-15) << v;
        EXPECT_NEAR(g.width, s * g0.width, 1e-15) << v;
        EXPECT_NEAR(g.meshSize, s * g0.meshSize, 1e-15) << v;
        EXPECT_NO_THROW(on.validate()) << v;
        // The bag the load test builds: the same mesh, every node scaled.
        const bags::AirbagSpec spec = bags::makeAirbagSpec(on);
        ASSERT_EQ(spec.mesh.tris, m0.tris) << v;
        EXPECT_LT((spec.mesh.X - s * m0.X).cwiseAbs().maxCoeff(), 1e-15) << v;
        EXPECT_EQ(spec.solver.maxStep, g.meshSize);
    }
    EXPECT_TRUE(rig.isNone());
    bags::LoadTestOptions twice = o;
    diagnose::applyEffect(*effect, {0.1}, {}, rig, twice);
    diagnose::applyEffect(*effect, {-0.1}, {}, rig, twice);
    EXPECT_NEAR(std::pow(twice.bagScale, 3), 1.1 * 0.9, 1e-14);
    bags::LoadTestOptions same = o;
    diagnose::applyEffect(*effect, {0.0}, {}, rig, same);
    EXPECT_EQ(same.bagScale, 1.0);
    EXPECT_EQ(bags::makeAirbagSpec(same).mesh.getNumNodes(), 0);  // built from the geometry
    try {
        diagnose::applyEffect(*effect, {0.3}, {}, rig, same);
        ADD_FAILURE() << "a volume change of 0.3 accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("valid: -0.25 to 0.25"), std::string::npos)
            << e.what();
    }
    // A bag whose mesh size would pass 50 mm once scaled is refused, not built.
    bags::LoadTestOptions coarse = o;
    coarse.geometry.meshSize = 0.049;
    EXPECT_THROW(diagnose::applyEffect(*effect, {0.25}, {}, rig, coarse), std::invalid_argument);
}

// What the parameter says, measured: the fill mass (the gas that just fills the inflated bag,
// bags::measureFillMass) moves by the factor 1 + volume. Exact for the flat panels; the
// inflated bag departs from similarity by its film's strain at the probes' 1-4 kPa (the strain
// at a pressure grows with the size) and its weight. Tolerance 0.5 % of the fill mass (measured
// on the tiny rig's 25 mm bag at -0.15 and +0.1: see docs/diagnosis.md#bag-volume).
TEST(Effects, BagVolumeMovesTheFillMassAsStated) {
    const diagnose::Effect* effect = diagnose::findEffect("bag-volume");
    ASSERT_NE(effect, nullptr);
    bags::LoadTestOptions o;  // the tiny rig's bag and film
    o.geometry.meshSize = 0.025;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    const double m0 = bags::measureFillMass(o, 3.6e-3).fillMass;
    EXPECT_GT(m0, 3.3e-3);
    EXPECT_LT(m0, 3.9e-3);
    diagnose::RigEffects rig;
    for (double v : {-0.15, 0.1}) {
        bags::LoadTestOptions on = o;
        diagnose::applyEffect(*effect, {v}, {}, rig, on);
        const double m1 = bags::measureFillMass(on, (1.0 + v) * m0).fillMass;
        EXPECT_NEAR(m1 / m0, 1.0 + v, 0.005 * (1.0 + v)) << v << ": " << m1 / m0;
        std::printf("bag-volume %+.2f: fill mass %.4f g -> %.4f g (ratio %.5f)\n", v, m0 * 1e3,
                    m1 * 1e3, m1 / m0);
    }
}

// The film's stiffness misstated (its thickness or its modulus): the membrane's thickness, and
// so every membrane force, times 1 + change; the sheet's weight (density x thickness) and its
// bending stiffness as stated; no instrument touched; outside -40 % to +40 % refused naming the
// bounds.
TEST(Effects, FilmStiffnessScalesTheMembraneNotItsWeight) {
    const diagnose::Effect* effect = diagnose::findEffect("film-stiffness");
    ASSERT_NE(effect, nullptr);
    EXPECT_TRUE(effect->changesTheBag);
    EXPECT_TRUE(effect->inLibrary);
    EXPECT_FALSE(effect->isolatedBy.empty());
    ASSERT_EQ(effect->parameters.size(), 1u);
    bags::LoadTestOptions o;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.bendingStiffness = 2e-4;
    o.gasMasses = {4e-3};
    diagnose::RigEffects rig;
    for (double c : {-0.4, -0.15, 0.1, 0.4}) {
        bags::LoadTestOptions on = o;
        diagnose::applyEffect(*effect, {c}, {}, rig, on);
        EXPECT_NEAR(on.thickness, (1.0 + c) * o.thickness, 1e-18) << c;
        EXPECT_NEAR(on.density * on.thickness, o.density * o.thickness, 1e-12) << c;
        EXPECT_EQ(on.bendingStiffness, o.bendingStiffness);
        EXPECT_EQ(on.material, o.material);
        const bags::AirbagSpec spec = bags::makeAirbagSpec(on);
        EXPECT_NEAR(spec.thickness, (1.0 + c) * o.thickness, 1e-18) << c;
    }
    EXPECT_TRUE(rig.isNone());
    bags::LoadTestOptions none = o;
    diagnose::applyEffect(*effect, {0.0}, {}, rig, none);
    EXPECT_EQ(none.thickness, o.thickness);
    EXPECT_EQ(none.density, o.density);
    try {
        bags::LoadTestOptions bad = o;
        diagnose::applyEffect(*effect, {0.5}, {}, rig, bad);
        FAIL() << "a change of 50 % was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("valid: -0.4 to 0.4"), std::string::npos) << e.what();
    }
}
