// The Simbody model: mass properties, conservation in free flight, postures, support forces.
#include <body/BodyModel.h>
#include <body/SupportContact.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

body::PatientSpec makeSpec(body::Sex sex, double h, double m) {
    body::PatientSpec s;
    s.sex = sex;
    s.height = h;
    s.mass = m;
    return s;
}

}  // namespace

TEST(BodyModel, SimbodyBodiesCarryTheTableMassProperties) {
    for (body::Sex sex : {body::Sex::Female, body::Sex::Male}) {
        const body::DeLevaReference ref = body::getDeLevaReference(sex);
        body::BodyModel model(makeSpec(sex, ref.stature, ref.mass));
        EXPECT_NEAR(model.calcTotalMass(), ref.mass, 1e-12 * ref.mass);
        for (int i = 0; i < body::kSegmentCount; ++i) {
            const body::Segment seg = static_cast<body::Segment>(i);
            const body::SegmentParameters& p = model.getAnthropometry().get(seg);
            const SimTK::MassProperties mp = model.getMobilizedBody(seg).getDefaultMassProperties();
            EXPECT_NEAR(mp.getMass(), p.mass, 1e-12);
            EXPECT_NEAR((mp.getMassCenter() - p.p_BC).norm(), 0.0, 1e-14);
            const SimTK::Inertia I_C = mp.calcCentralInertia();
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(I_C.getMoments()[k], p.inertiaC[k], 1e-12);
            EXPECT_NEAR(I_C.getProducts().norm(), 0.0, 1e-12);
        }
    }
}

TEST(BodyModel, FreeFallingSpinningBodyConservesEnergyAndMomentum) {
    // Undamped passive joints (their elastic torques derive from a potential), gravity, no
    // support: total energy and the angular momentum about the centre of mass are constant,
    // the linear momentum grows as m g t.
    body::BodyModelOptions opt;
    opt.jointDampingScale = 0;
    body::BodyModel model(makeSpec(body::Sex::Male, 1.741, 73.0), opt);
    SimTK::State state = model.updSystem().realizeTopology();
    model.setPosture(state, body::Posture::SideLeft90, {0, 0}, 0, 1.0);
    // Spin: rigid rotation about the CoM plus a translation.
    model.getSystem().realize(state, SimTK::Stage::Position);
    const SimTK::Vec3 com = model.getMatter().calcSystemMassCenterLocationInGround(state);
    const SimTK::Vec3 w(1.0, 2.0, 0.5), v0(0.3, -0.2, 1.5);
    const SimTK::MobilizedBody& root = model.getMobilizedBody(body::Segment::LowerTrunk);
    const SimTK::Vec3 r = root.getBodyOriginLocation(state) - com;
    root.setUToFitAngularVelocity(state, w);
    root.setUToFitLinearVelocity(state, v0 + w % r);
    model.getSystem().realize(state, SimTK::Stage::Velocity);
    const double m = model.calcTotalMass();
    const double E0 = model.getSystem().calcEnergy(state);
    const SimTK::SpatialVec M0 = model.getMatter().calcSystemCentralMomentum(state);
    SimTK::RungeKuttaMersonIntegrator integ(model.getSystem());
    integ.setAccuracy(1e-9);
    SimTK::TimeStepper ts(model.getSystem(), integ);
    ts.initialize(state);
    ts.stepTo(2.0);
    const SimTK::State& s = integ.getState();
    model.getSystem().realize(s, SimTK::Stage::Velocity);
    const double E1 = model.getSystem().calcEnergy(s);
    const SimTK::SpatialVec M1 = model.getMatter().calcSystemCentralMomentum(s);
    const double KE0 = model.getMatter().calcKineticEnergy(state);
    std::printf(
        "free fall 2 s: |dE|/KE0 = %.2e, |dH|/|H| = %.2e, |dp - m g t|/|p| = %.2e, "
        "steps %d\n",
        std::abs(E1 - E0) / KE0, (M1[0] - M0[0]).norm() / M0[0].norm(),
        (M1[1] - M0[1] - SimTK::Vec3(0, 0, -m * 9.80665 * 2.0)).norm() /
            (M0[1] + SimTK::Vec3(0, 0, -m * 9.80665 * 2.0)).norm(),
        integ.getNumStepsTaken());
    // Energy: drift below 1e-6 of the initial kinetic energy (integrator accuracy 1e-9).
    EXPECT_NEAR(E1, E0, 1e-6 * KE0);
    // Central angular momentum: constant to 1e-6 of its size.
    EXPECT_NEAR((M1[0] - M0[0]).norm(), 0.0, 1e-6 * M0[0].norm());
    // Linear momentum: p0 - m g t z (relative 1e-9).
    const SimTK::Vec3 p1 = M0[1] + SimTK::Vec3(0, 0, -m * 9.80665 * 2.0);
    EXPECT_NEAR((M1[1] - p1).norm(), 0.0, 1e-9 * p1.norm());
    // The joints did move (the test is not of a rigid body).
    double maxAngle = 0;
    for (const body::JointSpec& j : model.getJoints())
        maxAngle = std::max(maxAngle, (~model.getMobilizedBody(j.parent).getBodyRotation(s) *
                                       model.getMobilizedBody(j.child).getBodyRotation(s))
                                          .convertRotationToAngleAxis()[0]);
    EXPECT_GT(maxAngle, 0.1);
}

TEST(BodyModel, PosturesPlaceTheBodyOnTheBed) {
    body::BodyModel model(makeSpec(body::Sex::Female, 1.62, 58.0));
    SimTK::State state = model.updSystem().realizeTopology();
    const double deg = SimTK::Pi / 180;
    struct Case {
        body::Posture posture;
        double rightUp;  // z-component of the pelvis' right axis: sin(turn), + is right side up
    };
    for (const Case& c :
         {Case{body::Posture::Supine, 0.0}, Case{body::Posture::TiltLeft30, 0.5},
          Case{body::Posture::TiltRight30, -0.5}, Case{body::Posture::SideLeft90, 1.0},
          Case{body::Posture::SideRight90, -1.0}}) {
        model.setPosture(state, c.posture, {0.3, -0.1}, 30 * deg);
        SCOPED_TRACE(body::getPostureName(c.posture));
        EXPECT_NEAR(model.calcLowestPointHeight(state), 0.0, 1e-12);
        const SimTK::Transform& X =
            model.getMobilizedBody(body::Segment::LowerTrunk).getBodyTransform(state);
        EXPECT_NEAR(X.p()[0], 0.3, 1e-15);
        EXPECT_NEAR(X.p()[1], -0.1, 1e-15);
        EXPECT_NEAR(X.R().asMat33()(2, 2), c.rightUp, 1e-12);  // body Z in Ground, z component
        EXPECT_NEAR(X.R().asMat33()(0, 1), 1.0, 1e-12);        // superior axis along +x: head to +x
        // Supine: anterior up; lateral postures: the head still towards +x.
    }
    // Head of bed raised by 30 deg: trunk pitched up, thighs flat.
    model.setPosture(state, body::Posture::HeadOfBedRaised, {0, 0}, 30 * deg);
    const SimTK::Rotation& Rut =
        model.getMobilizedBody(body::Segment::UpperTrunk).getBodyRotation(state);
    const SimTK::Rotation& Rth =
        model.getMobilizedBody(body::Segment::ThighR).getBodyRotation(state);
    EXPECT_NEAR(Rut.asMat33()(2, 1), std::sin(30 * deg), 1e-12);  // superior axis rises 30 deg
    EXPECT_NEAR(Rth.asMat33()(2, 1), 0.0, 1e-12);                 // thigh axis horizontal
    EXPECT_NEAR(model.calcLowestPointHeight(state), 0.0, 1e-12);
}

TEST(BodyModel, RegionsFindTheirLandmarks) {
    body::BodyModel model(makeSpec(body::Sex::Male, 1.741, 73.0));
    const auto& regions = model.getRegions();
    auto idOf = [&](const std::string& n) {
        for (std::size_t i = 0; i < regions.size(); ++i)
            if (regions[i].name == n) return static_cast<int>(i);
        return -2;
    };
    const body::ContactShape& head = model.getContactShape(body::Segment::Head);
    // The back of the head (support point towards -X) is the occiput.
    EXPECT_EQ(model.findRegion(body::Segment::Head,
                               head.calcSupportPoint(SimTK::Vec3(-1, 0.2, 0) / std::sqrt(1.04))),
              idOf("occiput"));
    const body::ContactShape& foot = model.getContactShape(body::Segment::FootL);
    EXPECT_EQ(model.findRegion(body::Segment::FootL, foot.calcSupportPoint(SimTK::Vec3(-1, 0, 0))),
              idOf("heel_l"));
    const body::ContactShape& thigh = model.getContactShape(body::Segment::ThighR);
    EXPECT_EQ(model.findRegion(body::Segment::ThighR, thigh.calcSupportPoint(SimTK::Vec3(0, 0, 1))),
              idOf("trochanter_r"));
    const body::ContactShape& pelvis = model.getContactShape(body::Segment::LowerTrunk);
    EXPECT_EQ(
        model.findRegion(body::Segment::LowerTrunk, pelvis.calcSupportPoint(SimTK::Vec3(-1, 0, 0))),
        idOf("sacrum"));
    // The front of the abdomen is in no region.
    const body::ContactShape& belly = model.getContactShape(body::Segment::MiddleTrunk);
    EXPECT_EQ(
        model.findRegion(body::Segment::MiddleTrunk, belly.calcSupportPoint(SimTK::Vec3(1, 0, 0))),
        -1);
}

TEST(PlaneSupport, NormalForceIsMinusEnergyGradient) {
    // With no velocity, the support's vertical force equals -dV/dz of its elastic energy when
    // the whole body is lowered (central differences, h = 1e-7 m; V is piecewise quadratic).
    body::BodyModel model(makeSpec(body::Sex::Male, 1.741, 73.0));
    const body::PlaneSupport& support = body::addPlaneSupport(model);
    SimTK::State state = model.updSystem().realizeTopology();
    const double h = 1e-7;
    auto energyAt = [&](double z) {
        model.setPosture(state, body::Posture::Supine, {0, 0}, 0, z);
        model.getSystem().realize(state, SimTK::Stage::Velocity);
        return support.calcPotentialEnergy(state);
    };
    const double z = -0.006;  // lowest point 6 mm into the support
    const double dV = (energyAt(z + h) - energyAt(z - h)) / (2 * h);
    energyAt(z);
    const body::SupportLoad load = support.calcSupportLoad(state);
    EXPECT_GT(load.force[2], 50.0);  // several segments in contact
    EXPECT_NEAR(load.force[2], -dV, 1e-5 * load.force[2]);
    // No sliding velocity: no friction.
    EXPECT_NEAR(std::hypot(load.force[0], load.force[1]), 0.0, 1e-9);
    double sum = load.otherForce;
    for (double f : load.regionForce) sum += f;
    EXPECT_NEAR(sum, load.force[2], 1e-9 * load.force[2]);  // every patch is counted once
}

TEST(PlaneSupport, TurnedPosturesLoadTheLowerSide) {
    // Static check of postures and regions: lower the body into the support (no dynamics)
    // and see which regions touch. On the side the shoulder is wider than the hips (0.45 vs
    // 0.39 m) so the trochanter needs 40 mm; a real patient's spine bends until both touch.
    body::BodyModel model(makeSpec(body::Sex::Male, 1.75, 80.0));
    const body::PlaneSupport& support = body::addPlaneSupport(model);
    SimTK::State state = model.updSystem().realizeTopology();
    const auto& regions = model.getRegions();
    auto force = [&](const body::SupportLoad& load, const std::string& name) {
        for (std::size_t i = 0; i < regions.size(); ++i)
            if (regions[i].name == name) return load.regionForce[i];
        return -1.0;
    };
    model.setPosture(state, body::Posture::SideLeft90, {0, 0}, 0, -0.04);
    model.getSystem().realize(state, SimTK::Stage::Velocity);
    body::SupportLoad side = support.calcSupportLoad(state);
    EXPECT_GT(force(side, "trochanter_l"), 1.0);
    EXPECT_GT(force(side, "shoulder_l"), 10.0);
    EXPECT_EQ(force(side, "sacrum"), 0.0);
    EXPECT_EQ(force(side, "trochanter_r"), 0.0);
    EXPECT_EQ(force(side, "occiput"), 0.0);
    model.setPosture(state, body::Posture::TiltRight30, {0, 0}, 0, -0.03);
    model.getSystem().realize(state, SimTK::Stage::Velocity);
    body::SupportLoad tilt = support.calcSupportLoad(state);
    EXPECT_GE(force(tilt, "scapula_r"), force(tilt, "scapula_l"));
    EXPECT_EQ(force(tilt, "ischium_l"), 0.0);
    EXPECT_GT(force(tilt, "ischium_r") + force(tilt, "trochanter_r"), 10.0);
    EXPECT_EQ(force(tilt, "trochanter_l"), 0.0);
}
