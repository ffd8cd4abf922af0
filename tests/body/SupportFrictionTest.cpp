// The support's friction laws (body/SupportContact.h) against Coulomb's: the patient lying on
// the plane under a uniform horizontal body force g_x per unit mass besides gravity (the plane
// tilted by atan(g_x / g), seen from the plane). Below mu g the stick-slip law holds him where
// he lies and the regularised law lets him creep at about v_s g_x / (mu g); above it both
// slide with the acceleration g_x - mu N / M (N the plane's normal force, M his mass).
#include <body/BodyModel.h>
#include <body/SupportContact.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

constexpr double kG = 9.80665;

struct Slide {
    double drift = 0;              // centre-of-mass travel along x over the last `window` [m]
    double acceleration = 0;       // mean centre-of-mass acceleration along x over it [m/s^2]
    double coulomb = 0;            // g_x - mu N / M at the end [m/s^2]
    std::array<int, 2> sliding{};  // stick-slip patches sliding, in contact (end)
    int steps = 0;                 // integrator steps taken
};

Slide run(body::SupportFrictionLaw law, double gx, double settle, double window) {
    body::BodyModel model(body::PatientSpec{});
    body::PlaneSupportOptions o;
    o.frictionLaw = law;
    const body::PlaneSupport& support = body::addPlaneSupport(model, o);
    SimTK::Force::Gravity(model.updForces(), model.getSystem().getMatterSubsystem(),
                          SimTK::UnitVec3(1, 0, 0), gx);
    SimTK::State state = model.updSystem().realizeTopology();
    model.setPosture(state);
    SimTK::RungeKuttaMersonIntegrator integ(model.getSystem());
    integ.setAccuracy(1e-4);
    SimTK::TimeStepper ts(model.getSystem(), integ);
    ts.initialize(state);
    const SimTK::SimbodyMatterSubsystem& matter = model.getSystem().getMatterSubsystem();
    ts.stepTo(settle);
    SimTK::State a = integ.getState();
    model.getSystem().realize(a, SimTK::Stage::Velocity);
    const SimTK::Vec3 p1 = matter.calcSystemMassCenterLocationInGround(a);
    const SimTK::Vec3 v1 = matter.calcSystemMassCenterVelocityInGround(a);
    ts.stepTo(settle + window);
    SimTK::State b = integ.getState();
    model.getSystem().realize(b, SimTK::Stage::Dynamics);
    const SimTK::Vec3 p2 = matter.calcSystemMassCenterLocationInGround(b);
    const SimTK::Vec3 v2 = matter.calcSystemMassCenterVelocityInGround(b);
    Slide r;
    r.drift = p2[0] - p1[0];
    r.acceleration = (v2[0] - v1[0]) / window;
    const double M = model.calcTotalMass();
    r.coulomb = gx - o.friction * support.calcSupportLoad(b).force[2] / M;
    r.sliding = support.countSlidingPatches(b);
    r.steps = integ.getNumStepsTaken();
    return r;
}

}  // namespace

// Held at 0.3 g (half of mu g): the stick-slip law does not creep; the regularised law
// creeps at about v_s g_x / (mu g) = 2 mm/s x 0.5 = 1 mm/s (the test asserts > 0.3 mm/s, so
// that a creep would be seen).
TEST(PlaneSupportFriction, TheStickSlipLawHoldsAPatientBelowCoulombsLimitWithoutCreep) {
    const Slide stick = run(body::SupportFrictionLaw::StickSlip, 0.3 * kG, 1.0, 1.0);
    const Slide reg = run(body::SupportFrictionLaw::Regularised, 0.3 * kG, 1.0, 1.0);
    std::printf(
        "drift over 1 s: stick-slip %.4f mm (%d steps, %d of %d patches sliding), "
        "regularised %.4f mm (%d steps)\n",
        1e3 * stick.drift, stick.steps, stick.sliding[0], stick.sliding[1], 1e3 * reg.drift,
        reg.steps);
    EXPECT_LT(std::abs(stick.drift), 2e-5);              // 0.02 mm: held
    EXPECT_GT(reg.drift, 3e-4);                          // the regularised law's creep
    EXPECT_GT(stick.sliding[1], 100);                    // he lies on the plane
    EXPECT_LT(stick.sliding[0], stick.sliding[1] / 20);  // next to nothing slides
    // The stick spring is softer in the body's velocity than the regularised damper: fewer
    // steps for the same accuracy.
    EXPECT_LT(stick.steps, reg.steps);
}

// Pushed at 0.9 g (1.5 mu g) he slides: acceleration g_x - mu N / M = 0.3 g, within 1 %.
TEST(PlaneSupportFriction, BothLawsSlideAtCoulombsLimitAboveIt) {
    for (const body::SupportFrictionLaw law :
         {body::SupportFrictionLaw::StickSlip, body::SupportFrictionLaw::Regularised}) {
        const Slide r = run(law, 0.9 * kG, 0.6, 0.4);
        std::printf(
            "%s: acceleration %.4f m/s^2, Coulomb %.4f m/s^2, %d of %d patches "
            "sliding\n",
            law == body::SupportFrictionLaw::StickSlip ? "stick-slip" : "regularised",
            r.acceleration, r.coulomb, r.sliding[0], r.sliding[1]);
        EXPECT_NEAR(r.acceleration, r.coulomb, 0.01 * r.coulomb);
        if (law == body::SupportFrictionLaw::StickSlip) {
            EXPECT_EQ(r.sliding[0], r.sliding[1]);
        }
    }
}

// The anchors go out of a state and back in (checkpoints): the forces at the state are the
// same; a wrong size is refused.
TEST(PlaneSupportFriction, TheAnchorsRoundTripThroughAState) {
    body::BodyModel model(body::PatientSpec{});
    body::PlaneSupportOptions o;
    o.frictionLaw = body::SupportFrictionLaw::StickSlip;
    const body::PlaneSupport& support = body::addPlaneSupport(model, o);
    SimTK::Force::Gravity(model.updForces(), model.getSystem().getMatterSubsystem(),
                          SimTK::UnitVec3(0, 1, 0), 0.2 * kG);
    SimTK::State state = model.updSystem().realizeTopology();
    model.setPosture(state);
    SimTK::RungeKuttaMersonIntegrator integ(model.getSystem());
    SimTK::TimeStepper ts(model.getSystem(), integ);
    ts.initialize(state);
    ts.stepTo(0.5);
    SimTK::State s = integ.getState();
    const std::vector<double> anchors = support.getAnchors(s);
    ASSERT_EQ(anchors.size() % 3, 0u);
    EXPECT_GT(anchors.size() / 3, 100u);  // the patches he lies on
    for (std::size_t i = 3; i < anchors.size(); i += 3) EXPECT_GT(anchors[i], anchors[i - 3]);
    model.getSystem().realize(s, SimTK::Stage::Dynamics);
    const SimTK::Vec3 f = support.calcSupportLoad(s).force;
    SimTK::State t = model.getSystem().getDefaultState();
    t.updQ() = s.getQ();
    t.updU() = s.getU();
    t.setTime(s.getTime());
    support.setAnchors(t, anchors);
    model.getSystem().realize(t, SimTK::Stage::Dynamics);
    const SimTK::Vec3 g = support.calcSupportLoad(t).force;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(f[k], g[k]) << k;
    EXPECT_GT(std::abs(f[1]), 0.1 * kG * model.calcTotalMass());  // the friction holds him
    EXPECT_THROW(support.setAnchors(t, {1.0, 2.0}), std::invalid_argument);
    EXPECT_THROW(support.setAnchors(t, {double(support.getPatchCount()), 0.0, 0.0}),
                 std::invalid_argument);
    EXPECT_THROW(support.setAnchors(t, {5.0, 0.0, 0.0, 5.0, 0.0, 0.0}), std::invalid_argument);
}
