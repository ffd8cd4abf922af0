// The film in time (bags/Dynamics.h) and the Airbag's dynamic stepping: the integrator's
// physics (energy, momentum, stable step), velocities through snapshots, checkpoints and
// rollback, bit-identity over threads, a sleeping bag, and the dynamic load test against the
// quasi-static one on a coarse rig. docs/solver.md#the-film-in-time.
#include <bags/Airbag.h>
#include <bags/Dynamics.h>
#include <bags/Geometry.h>
#include <bags/LoadTest.h>
#include <bags/Material.h>
#include <bags/StateStream.h>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

namespace bags {
namespace {

// A free sphere (r 50 mm, no fixed dofs, no gravity) of a Yeoh film 0.2 mm thick, its gas
// sealed at the reference volume at `overPressure` times the ambient density: away from
// equilibrium, so that it breathes when let go.
std::shared_ptr<const MembraneMaterial> sphereFilm() { return makeYeoh(1e6, -1e4, 1e3); }

MembraneModel makeFreeSphere(double overPressure, int refinements = 2) {
    Mesh mesh = makeSphere(0.05, refinements);
    auto mat = std::make_shared<WrinklingMaterial>(sphereFilm()->clone(), 1e-3);
    MembraneModel model(mesh, mat, 0.2e-3);
    const double V0 = calcChamberVolume(mesh, 0, mesh.X);
    GasChamber gas(GasOptions(), overPressure * GasOptions().getAmbientDensity() * V0);
    gas.seal(V0);
    model.addGas(gas, {0});
    return model;
}

double totalEnergy(const MembraneModel& model, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(static_cast<int>(x.cols()));
    acc.wantGradient = acc.wantHessian = false;
    model.addEnergy(x, acc);
    return acc.energy;
}

// Undamped central differences over `steps` steps of `fraction` x the stable step from the
// sphere's reference at rest; the largest departure of the energy (potential at x_n plus the
// kinetic energy of the mean of the half-step velocities around it) from its start, over the
// largest kinetic energy, and (*blewUp) whether the state left every bound.
double energyDrift(const MembraneModel& model, double fraction, int steps, bool* blewUp) {
    DynamicOptions o;
    o.stepFraction = 1.0;
    const FilmDynamics film(model, 1150.0, o, 0.0, sphereFilm());
    Eigen::Matrix3Xd x = model.getMesh().X;
    const double h = fraction * film.calcStableStep(x);
    Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Zero(3, x.cols());
    EnergyAccumulator acc;
    const double E0 = totalEnergy(model, x);
    double drift = 0.0, keMax = 0.0;
    *blewUp = false;
    for (int n = 0; n < steps; ++n) {
        const Eigen::Matrix3Xd vOld = v;
        const double potential = totalEnergy(model, x);  // at x_n, before the step moves it
        try {
            film.step(x, v, h, acc);
        } catch (const NumericalError&) {
            *blewUp = true;
            return drift / keMax;
        }
        const double ke = film.calcKineticEnergy(0.5 * (vOld + v));
        keMax = std::max(keMax, ke);
        const double E = potential + ke;
        if (!std::isfinite(E) || !x.allFinite() || std::abs(E - E0) > 10.0 * keMax + 1.0) {
            *blewUp = true;
            return drift / keMax;
        }
        if (n > 0) drift = std::max(drift, std::abs(E - E0));
    }
    return drift / keMax;
}

TEST(FilmDynamics, UndampedStepKeepsTheEnergyOfAFreeBreathingSphere) {
    // The sphere at 1.2 times the ambient gas density breathes about its inflated shape,
    // every mode of the film excited. The symplectic step keeps the energy within an
    // oscillation of order h^2, without drift (reference: E constant). Measured, largest
    // departure over the largest kinetic energy: 6.8 % at half the stable step (4000 steps),
    // 1.3 % at a quarter, 0.21 % at an eighth. Tolerances: 10 % at half the step, and at
    // least second order (each halving at most a quarter of the departure).
    const MembraneModel model = makeFreeSphere(1.2);
    bool blewUp = false;
    const double half = energyDrift(model, 0.5, 4000, &blewUp);
    ASSERT_FALSE(blewUp);
    const double quarter = energyDrift(model, 0.25, 8000, &blewUp);
    ASSERT_FALSE(blewUp);
    const double eighth = energyDrift(model, 0.125, 16000, &blewUp);
    ASSERT_FALSE(blewUp);
    RecordProperty("half", std::to_string(half));
    RecordProperty("quarter", std::to_string(quarter));
    RecordProperty("eighth", std::to_string(eighth));
    EXPECT_LT(half, 0.10);
    EXPECT_LT(quarter, 0.25 * half);
    EXPECT_LT(eighth, 0.25 * quarter);
}

TEST(FilmDynamics, StableStepEstimateLiesBelowTheStepThatBlowsUp) {
    // The estimate (Gershgorin's bound on the largest eigenvalue of M^-1 K) must be safe
    // (the undamped step of the estimate itself runs) and not wastefully small: the step that
    // blows up within 3000 steps lies between 1 and 4 times it (measured: 1.25 times).
    const MembraneModel model = makeFreeSphere(1.2);
    bool blewUp = false;
    energyDrift(model, 1.0, 3000, &blewUp);
    EXPECT_FALSE(blewUp) << "the estimated stable step itself blew up";
    double blowUp = 0.0;
    for (double f : {1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0}) {
        energyDrift(model, f, 3000, &blewUp);
        if (blewUp) {
            blowUp = f;
            break;
        }
    }
    RecordProperty("blow_up_over_estimate", std::to_string(blowUp));
    ASSERT_GT(blowUp, 0.0) << "no step up to 6 times the estimate blew up";
    EXPECT_LE(blowUp, 4.0);
}

TEST(FilmDynamics, MomentumOfASphereHitByABlockIsTheBlocksImpulse) {
    // A sphere at ambient pressure at rest, hit by a box moving at 2 m/s along -z: membrane
    // and gas forces sum to zero over a closed film, so the film's momentum changes by the
    // contact's impulse alone, sum h F(x_n), to roundoff (reference: Newton's third law;
    // tolerance 1e-10 of the impulse).
    MembraneModel model = makeFreeSphere(1.0);
    std::shared_ptr<RigidShape> box(makeBox(Vec3(0.03, 0.03, 0.01)));
    std::vector<int> nodes(model.getMesh().getNumNodes());
    for (size_t i = 0; i < nodes.size(); ++i) nodes[i] = static_cast<int>(i);
    RigidContact::Options co;
    co.pressurePenalty = 1e6;
    auto contact = std::make_shared<RigidContact>(model.getMesh(), nodes, *box, co);
    model.addRigidContact(contact);
    DynamicOptions o;
    const FilmDynamics film(model, 1150.0, o, co.pressurePenalty);
    Eigen::Matrix3Xd x = model.getMesh().X;
    Eigen::Matrix3Xd v = Eigen::Matrix3Xd::Zero(3, x.cols());
    const double h = 0.5 * film.calcStableStep(x);
    auto pose = [&](double t) {
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = Vec3(0.0, 0.0, 0.05 + 0.01 - 0.002 - 2.0 * t);  // 2 mm in at t = 0
        return X;
    };
    Vec3 impulse = Vec3::Zero();
    EnergyAccumulator acc;
    const int steps = 2000;
    for (int n = 0; n < steps; ++n) {
        box->setPose(pose(n * h));
        Vec3 F, M;
        contact->calcWrenchOnShape(x, &F, &M);
        impulse -= h * F;  // the force on the film
        film.step(x, v, h, acc);
    }
    Vec3 P = Vec3::Zero();
    const Eigen::VectorXd& m = film.getDofMass();
    for (int i = 0; i < x.cols(); ++i) P += m(3 * i) * v.col(i);
    ASSERT_GT(impulse.norm(), 1e-6);
    EXPECT_LT((P - impulse).norm(), 1e-10 * impulse.norm())
        << "P " << P.transpose() << " impulse " << impulse.transpose();
    EXPECT_LT(impulse.z(), 0.0);  // pushed down
}

// --- the Airbag's dynamic stepping

AirbagSpec makeDynamicSpec(int threads = 1) {
    AirbagSpec s;
    s.geometry.meshSize = 0.025;
    s.material = makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    s.stepping = AirbagSpec::Stepping::Dynamic;
    s.dynamics.massScale = 1000.0;
    s.dynamics.damping = 20.0;
    s.threads = threads;
    return s;
}

struct PressedBag {
    Airbag bag;
    int block = 0;
    double top = 0.0;
    explicit PressedBag(const AirbagSpec& spec) : bag(spec) {
        std::shared_ptr<RigidShape> box(makeBox(Vec3(0.025, 0.025, 0.01), 1e-3));
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = Vec3(0.0, 0.0, 0.5);
        box->setPose(X);
        block = bag.addShape(box, RigidContact::Options());
        bag.inflate(4.5e-3);
        int apex = 0;
        bag.getMesh().X.row(2).maxCoeff(&apex);
        centre = bag.getMesh().X(0, apex);
        // The top of the inflated bag under the block's footprint.
        const Eigen::Matrix3Xd& x = bag.getPositions();
        top = -1.0;
        for (int i = 0; i < x.cols(); ++i)
            if (std::abs(x(0, i) - centre) <= 0.025 && std::abs(x(1, i)) <= 0.025)
                top = std::max(top, x(2, i));
    }
    double centre = 0.0;
    Eigen::Isometry3d at(double depth) const {
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = Vec3(centre, 0.0, top + 0.01 - depth);
        return X;
    }
    // Presses `depth` over dt, commits if asked.
    AdvanceSummary press(double depth, double dt, bool commit) {
        bag.setShapePose(block, at(depth));
        const AdvanceSummary s = bag.advance(dt);
        if (commit) bag.commit();
        return s;
    }
};

TEST(AirbagDynamics, VelocitiesLiveInSnapshotsCheckpointsAndRollback) {
    PressedBag p(makeDynamicSpec());
    ASSERT_TRUE(p.press(0.002, 0.01, true).converged);
    const AdvanceSummary s = p.press(0.004, 0.01, false);
    ASSERT_TRUE(s.converged);
    EXPECT_GT(s.substeps, 1);
    EXPECT_GT(s.kineticEnergy, 0.0);
    const Eigen::Matrix3Xd xA = p.bag.getPositions();
    const double keA = p.bag.calcKineticEnergy();
    EXPECT_EQ(keA, s.kineticEnergy);
    // The same step again from the commit (a coupling's next pass): the same bits.
    p.bag.rollback();
    ASSERT_TRUE(p.press(0.004, 0.01, false).converged);
    EXPECT_EQ(p.bag.getPositions(), xA);
    EXPECT_EQ(p.bag.calcKineticEnergy(), keA);
    // A snapshot keeps the velocity: the step after it is the same from the snapshot.
    p.bag.commit();
    const auto snap = p.bag.getSnapshot();
    ASSERT_TRUE(p.press(0.006, 0.01, false).converged);
    const Eigen::Matrix3Xd xB = p.bag.getPositions();
    p.bag.setSnapshot(snap);
    EXPECT_EQ(p.bag.calcKineticEnergy(), keA);
    ASSERT_TRUE(p.press(0.006, 0.01, false).converged);
    EXPECT_EQ(p.bag.getPositions(), xB);
    // A checkpoint of the committed state, loaded into a new bag: the same next step.
    p.bag.setSnapshot(snap);
    StateWriter w;
    p.bag.saveState(w);
    PressedBag q(makeDynamicSpec());
    StateReader r(w.getData());
    q.bag.loadState(r);
    EXPECT_EQ(q.bag.calcKineticEnergy(), keA);
    q.top = p.top;
    q.centre = p.centre;
    ASSERT_TRUE(q.press(0.006, 0.01, false).converged);
    EXPECT_EQ(q.bag.getPositions(), xB);
}

TEST(AirbagDynamics, OneAndTwoThreadsGiveTheSameBits) {
    PressedBag one(makeDynamicSpec(1)), two(makeDynamicSpec(2));
    for (int k = 1; k <= 3; ++k) {
        ASSERT_TRUE(one.press(0.002 * k, 0.01, true).converged);
        ASSERT_TRUE(two.press(0.002 * k, 0.01, true).converged);
    }
    EXPECT_EQ(one.bag.getPositions(), two.bag.getPositions());
    EXPECT_EQ(one.bag.calcShapeWrench(one.block).force, two.bag.calcShapeWrench(two.block).force);
}

TEST(AirbagDynamics, AnUntouchedStillBagSleepsAndAPressWakesIt) {
    PressedBag p(makeDynamicSpec());
    const Eigen::Matrix3Xd x0 = p.bag.getPositions();
    // The block well clear: nothing is integrated, nothing moves.
    const AdvanceSummary idle = p.press(-0.05, 1.0, true);
    ASSERT_TRUE(idle.converged);
    EXPECT_EQ(idle.substeps, 0);
    EXPECT_EQ(p.bag.getPositions(), x0);
    // Pressed: it wakes and moves.
    const AdvanceSummary pressed = p.press(0.003, 0.01, true);
    ASSERT_TRUE(pressed.converged);
    EXPECT_GT(pressed.substeps, 0);
    EXPECT_GT(p.bag.calcShapeWrench(p.block).force.z(), 0.5);
}

TEST(AirbagDynamics, PressedAndHeldTheBagComesToTheQuasiStaticForce) {
    // Pressed 5 mm and held, the damped film settles: its block force comes to the
    // quasi-static bag's at the same pose (reference: the equilibrium; tolerance 2 % of it).
    AirbagSpec qs = makeDynamicSpec();
    qs.stepping = AirbagSpec::Stepping::QuasiStatic;
    PressedBag statics(qs), dynamic(makeDynamicSpec());
    ASSERT_TRUE(statics.press(0.005, 0.05, true).converged);
    const double F = statics.bag.calcShapeWrench(statics.block).force.z();
    ASSERT_GT(F, 2.0);
    ASSERT_TRUE(dynamic.press(0.005, 0.05, true).converged);
    for (int k = 0; k < 20; ++k) ASSERT_TRUE(dynamic.press(0.005, 0.05, true).converged);
    const double Fd = dynamic.bag.calcShapeWrench(dynamic.block).force.z();
    RecordProperty("quasi_static_N", std::to_string(F));
    RecordProperty("dynamic_N", std::to_string(Fd));
    EXPECT_NEAR(Fd, F, 0.02 * F);
}

// --- the relaxed stepping: the quasi-static equilibrium by dynamic relaxation

AirbagSpec makeRelaxedSpec(double massScale = 1000.0) {
    AirbagSpec s = makeDynamicSpec();
    s.stepping = AirbagSpec::Stepping::Relaxed;
    s.dynamics.massScale = massScale;
    s.dynamics.damping = 20.0 * std::sqrt(1000.0 / massScale);  // the same in its own time
    s.forceTolerance = 1e-3;
    s.dynamics.newtonFirst = false;          // the relaxation itself on trial,
    s.dynamics.quasiStaticFallback = false;  // and what it leaves short kept as it is
    return s;
}

TEST(AirbagRelaxed, EachStepEndsOnTheQuasiStaticEquilibrium) {
    // Pressed to 6 mm in steps of 0.5 mm (10 ms each), the relaxed bag's block force at every
    // other step is the quasi-static bag's at the same pose (reference: Newton's equilibrium
    // to its tolerance, 1 mN; tolerance 0.5 % of the force: both within 1 mN of their
    // equilibria), each step within the force tolerance and ending at rest.
    // (Brought 2 mm deep in one step the two differ several times over: Newton's jump leaves
    // the film's nodes at the block's edge inside it, pushed out through its side face; the
    // relaxation moves the block in at its pace and the film stays under it.)
    AirbagSpec qsSpec = makeRelaxedSpec();
    qsSpec.stepping = AirbagSpec::Stepping::QuasiStatic;
    PressedBag statics(qsSpec), relaxed(makeRelaxedSpec());
    for (int k = 0; k <= 12; ++k) {
        ASSERT_TRUE(statics.press(0.0005 * k, 0.01, true).converged);
        const AdvanceSummary s = relaxed.press(0.0005 * k, 0.01, true);
        ASSERT_TRUE(s.converged);
        EXPECT_FALSE(s.unrelaxed) << "step " << k << " residual " << s.residual << " N";
        EXPECT_LE(s.residual, 1e-3);
        EXPECT_EQ(relaxed.bag.calcKineticEnergy(), 0.0);  // an equilibrium ends at rest
        if (k < 4 || k % 4 != 0) continue;
        const double F = statics.bag.calcShapeWrench(statics.block).force.z();
        const double Fr = relaxed.bag.calcShapeWrench(relaxed.block).force.z();
        ASSERT_GT(F, 0.5);
        EXPECT_NEAR(Fr, F, 0.005 * F) << "at " << 0.5 * k << " mm";
        RecordProperty("at_" + std::to_string(k / 2) + "_mm_N",
                       std::to_string(F) + " vs " + std::to_string(Fr));
    }
}

TEST(AirbagRelaxed, NewtonFirstTakesTheTautStepsAsTheQuasiStaticStepping) {
    // With Newton tried first (the default), a taut bag pressed in 1 mm steps never needs the
    // relaxation: every step is Newton's, the quasi-static stepping's force (reference; the
    // two differ by the roundoff of the element chunks the film in time is summed in, which
    // Newton's tolerance of 1 mN carries: tolerance 0.1 %).
    AirbagSpec qsSpec = makeRelaxedSpec(), hybrid = makeRelaxedSpec();
    qsSpec.stepping = AirbagSpec::Stepping::QuasiStatic;
    hybrid.dynamics.newtonFirst = true;
    PressedBag statics(qsSpec), relaxed(hybrid);
    for (int k = 0; k <= 4; ++k) {
        ASSERT_TRUE(statics.press(0.001 * k, 0.01, true).converged);
        const AdvanceSummary s = relaxed.press(0.001 * k, 0.01, true);
        ASSERT_TRUE(s.converged);
        EXPECT_FALSE(s.unrelaxed);
        EXPECT_EQ(s.substep, 0.0) << "step " << k << ": relaxed, not Newton's";
        const double F = statics.bag.calcShapeWrench(statics.block).force.z();
        EXPECT_NEAR(relaxed.bag.calcShapeWrench(relaxed.block).force.z(), F,
                    1e-3 * std::abs(F) + 1e-6)
            << "step " << k;
    }
}

TEST(AirbagRelaxed, WhatTouchesTheBagFeelsNoneOfTheFilmsScaledInertia) {
    // The film at mass scales 1000 and 1e5 (its inertia 100 times larger; the damping scaled
    // with the root, the same in its own time): after a quick press the block feels the same
    // force to the tolerance's share (reference: the equilibrium, which has no mass in it;
    // tolerance 0.5 %). The dynamic stepping's force after the same press depends on it.
    PressedBag light(makeRelaxedSpec(1000.0)), heavy(makeRelaxedSpec(1e5));
    ASSERT_TRUE(light.press(0.001, 0.05, true).converged);
    ASSERT_TRUE(heavy.press(0.001, 0.05, true).converged);
    ASSERT_TRUE(light.press(0.005, 0.002, true).converged);
    ASSERT_TRUE(heavy.press(0.005, 0.002, true).converged);
    const double Fl = light.bag.calcShapeWrench(light.block).force.z();
    const double Fh = heavy.bag.calcShapeWrench(heavy.block).force.z();
    EXPECT_NEAR(Fh, Fl, 0.005 * Fl);
    AirbagSpec d1 = makeDynamicSpec(), d2 = makeDynamicSpec();
    d2.dynamics.massScale = 1e5;
    PressedBag dyn1(d1), dyn2(d2);
    ASSERT_TRUE(dyn1.press(0.001, 0.05, true).converged);
    ASSERT_TRUE(dyn2.press(0.001, 0.05, true).converged);
    ASSERT_TRUE(dyn1.press(0.005, 0.002, true).converged);
    ASSERT_TRUE(dyn2.press(0.005, 0.002, true).converged);
    EXPECT_GT(std::abs(dyn2.bag.calcShapeWrench(dyn2.block).force.z() -
                       dyn1.bag.calcShapeWrench(dyn1.block).force.z()),
              0.05 * Fl);
}

TEST(AirbagRelaxed, AStepWhoseSubstepsRanOutIsKeptMarkedAndRepeatsExactly) {
    // 20 sub-steps cannot relax a 5 mm press: the step is kept as it stands, marked, its
    // pseudo-velocity kept; the same step again from the commit gives the same bits, and the
    // next steps go on relaxing from there until the force tolerance is met.
    AirbagSpec spec = makeRelaxedSpec();
    spec.dynamics.relaxSubsteps = 20;
    spec.dynamics.newtonPolish = 0;  // no Newton from where the sub-steps ran out
    PressedBag p(spec);
    const AdvanceSummary s = p.press(0.005, 0.01, false);
    ASSERT_TRUE(s.converged);
    EXPECT_TRUE(s.unrelaxed);
    EXPECT_GT(s.residual, 1e-3);
    EXPECT_GE(s.substeps, 20);
    const Eigen::Matrix3Xd x = p.bag.getPositions();
    p.bag.rollback();
    const AdvanceSummary again = p.press(0.005, 0.01, true);
    EXPECT_EQ(p.bag.getPositions(), x);
    EXPECT_EQ(again.residual, s.residual);
    bool relaxed = false;
    for (int k = 0; k < 400 && !relaxed; ++k) relaxed = !p.press(0.005, 0.01, true).unrelaxed;
    EXPECT_TRUE(relaxed);
}

TEST(AirbagRelaxed, NewtonPolishesARelaxationThatRanOut) {
    // The 5 mm press above, its 20 sub-steps run out, polished by Newton from where they
    // stopped (the default, at most 30 iterations): the step is relaxed, at rest, within the
    // force tolerance, and its block force is the relaxation's own equilibrium (reference: the
    // same press relaxed to the tolerance without Newton, 4000 sub-steps; tolerance 0.5 % of
    // the force, both within 1 mN of their equilibria).
    AirbagSpec polished = makeRelaxedSpec(), slow = makeRelaxedSpec();
    polished.dynamics.relaxSubsteps = 20;
    slow.dynamics.newtonPolish = 0;
    PressedBag p(polished), r(slow);
    const AdvanceSummary s = p.press(0.005, 0.01, true);
    const AdvanceSummary t = r.press(0.005, 0.01, true);
    ASSERT_TRUE(s.converged);
    ASSERT_TRUE(t.converged);
    ASSERT_FALSE(t.unrelaxed);
    EXPECT_FALSE(s.unrelaxed);
    EXPECT_LE(s.residual, polished.forceTolerance);
    EXPECT_GT(s.newtonIterations, 0);
    EXPECT_LT(s.substeps, t.substeps);
    EXPECT_EQ(p.bag.calcKineticEnergy(), 0.0);
    const double F = r.bag.calcShapeWrench(r.block).force.z();
    ASSERT_GT(F, 0.5);
    EXPECT_NEAR(p.bag.calcShapeWrench(p.block).force.z(), F, 0.005 * F);
    RecordProperty("substeps", std::to_string(s.substeps) + " + " +
                                   std::to_string(s.newtonIterations) + " Newton vs " +
                                   std::to_string(t.substeps));
}

TEST(AirbagRelaxed, TheQuasiStaticSteppingTakesAStepTheRelaxationLeftShort) {
    // The 5 mm press whose 20 sub-steps run out, with no polish: with the fallback (the
    // default) the quasi-static stepping takes the step from the commit and its equilibrium is
    // kept, at rest, within the force tolerance, not marked; its block force is the
    // quasi-static bag's for the same press (reference; tolerance 0.1 %: the element chunks'
    // roundoff, carried by Newton's 1 mN tolerance). Without it the step is kept unrelaxed.
    AirbagSpec spec = makeRelaxedSpec(), qsSpec = makeRelaxedSpec();
    spec.dynamics.relaxSubsteps = 20;
    spec.dynamics.newtonPolish = 0;
    AirbagSpec without = spec;
    spec.dynamics.quasiStaticFallback = true;
    qsSpec.stepping = AirbagSpec::Stepping::QuasiStatic;
    PressedBag p(spec), q(qsSpec), u(without);
    const AdvanceSummary s = p.press(0.005, 0.01, true);
    ASSERT_TRUE(q.press(0.005, 0.01, true).converged);
    ASSERT_TRUE(s.converged);
    EXPECT_FALSE(s.unrelaxed);
    EXPECT_LE(s.residual, spec.forceTolerance);
    EXPECT_GE(s.substeps, 20);  // the relaxation's sub-steps counted with the fallback's
    EXPECT_EQ(p.bag.calcKineticEnergy(), 0.0);
    const double F = q.bag.calcShapeWrench(q.block).force.z();
    ASSERT_GT(F, 0.5);
    EXPECT_NEAR(p.bag.calcShapeWrench(p.block).force.z(), F, 1e-3 * F);
    EXPECT_TRUE(u.press(0.005, 0.01, true).unrelaxed);
}

TEST(AirbagRelaxed, ASlackBagPressedDeepNeverStopsTheRun) {
    // 1.0 g in the 25 mm bag (its fill mass about 3.6 g): slack, folding. Pressed 40 mm in
    // 4 mm steps of 10 ms with at most 1000 relaxation sub-steps a step, every step is
    // accepted; the ones whose sub-steps ran out are marked, their residual stated (measured
    // 0.10-0.23 N against the 0.01 N asked for; asserted below 0.5 N), and the block's force
    // grows with the press. Held there, the next steps relax it to the tolerance.
    AirbagSpec spec = makeRelaxedSpec();
    spec.forceTolerance = 0.01;
    spec.dynamics.relaxSubsteps = 1000;
    Airbag bag(spec);
    std::shared_ptr<RigidShape> box(makeBox(Vec3(0.05, 0.05, 0.01), 1e-3));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(0.0, 0.0, 0.5);
    box->setPose(X);
    const int block = bag.addShape(box, RigidContact::Options());
    bag.inflate(1.0e-3);
    int apex = 0;
    const double top = bag.getPositions().row(2).maxCoeff(&apex);
    const double centre = bag.getPositions()(0, apex);
    int unrelaxed = 0;
    double F2 = 0.0;
    for (int k = 1; k <= 10; ++k) {
        X.translation() = Vec3(centre, 0.0, top + 0.01 - 0.004 * k);
        bag.setShapePose(block, X);
        const AdvanceSummary s = bag.advance(0.01);
        ASSERT_TRUE(s.converged) << "step " << k;
        EXPECT_LT(s.residual, 0.5) << "step " << k;
        EXPECT_EQ(s.unrelaxed, s.residual > spec.forceTolerance) << "step " << k;
        unrelaxed += s.unrelaxed;
        bag.commit();
        if (k == 2) F2 = bag.calcShapeWrench(block).force.z();
    }
    RecordProperty("unrelaxed_steps", unrelaxed);
    const double F = bag.calcShapeWrench(block).force.z();
    RecordProperty("force_at_40_mm_N", std::to_string(F));
    EXPECT_GT(F2, 0.0);
    EXPECT_GT(F, 2.0 * F2);
    int held = 0;
    bool relaxed = false;
    while (!relaxed && held < 30) {
        const AdvanceSummary s = bag.advance(0.01);
        ASSERT_TRUE(s.converged);
        bag.commit();
        relaxed = !s.unrelaxed;
        ++held;
    }
    RecordProperty("held_steps_to_relax", held);
    EXPECT_TRUE(relaxed);
}

}  // namespace
}  // namespace bags

// --- the dynamic load test

namespace bags {
namespace {

// The coarse rig (literal sizes, 25 mm mesh) at a taut 4.5 g, pressed to 20 N.
LoadTestOptions coarseTautRig() {
    LoadTestOptions o;
    o.geometry.meshSize = 0.025;
    o.material = makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.gasMasses = {4.5e-3};
    o.peakForce = 20.0;
    o.displacementStep = 0.25e-3;  // the quasi-static test: several steps in the range too
    o.stiffnessFrom = 5.0;
    o.stiffnessTo = 15.0;
    o.polynomialOrder = 1;
    o.unload = false;
    return o;
}

// The same rig, dynamic, at `speed` [m/s] with up to `halvings` halvings of the pace.
LoadTestOptions coarseDynamicRig(double speed, int halvings) {
    LoadTestOptions o = coarseTautRig();
    o.stepping = AirbagSpec::Stepping::Dynamic;
    o.dynamic.blockSpeed = speed;
    o.dynamic.maxHalvings = halvings;
    return o;
}

TEST(LoadTestDynamics, TautCurveAgreesWithTheQuasiStaticOne) {
    // Reference: the quasi-static test's stiffness over 5-15 N on the taut coarse rig;
    // tolerance 3 % (the agreement target where the quasi-static solver converges).
    LoadTestOptions o = coarseTautRig();
    const LoadTestResult qs = runLoadTest(o);
    o.stepping = AirbagSpec::Stepping::Dynamic;
    const LoadTestResult dyn = runLoadTest(o);
    ASSERT_TRUE(qs.curves[0].reachedPeak);
    ASSERT_TRUE(dyn.curves[0].reachedPeak);
    const LoadCurve& c = dyn.curves[0];
    RecordProperty("k_quasi_static", std::to_string(qs.curves[0].stiffness));
    RecordProperty("k_dynamic", std::to_string(c.stiffness));
    EXPECT_NEAR(c.stiffness, qs.curves[0].stiffness, 0.03 * qs.curves[0].stiffness);
    EXPECT_TRUE(c.quasiStatic);
    EXPECT_LE(c.kineticShare, o.dynamic.kineticShareLimit);
    EXPECT_GT(c.blockSpeed, 0.0);
    EXPECT_TRUE(c.failure.empty()) << c.failure;
    int substeps = 0;
    for (const LoadStep& s : c.steps) substeps += s.substeps;
    EXPECT_GT(substeps, 0);
    EXPECT_EQ(c.steps.front().displacement, 0.0);
}

TEST(LoadTestDynamics, AHurriedBlockIsMarkedNotQuasiStatic) {
    // 1 m/s with the film's real mass scaled 1000 times and no slowing down allowed: the film's
    // kinetic energy is far more than 1 % of the block's work, and the curve says so.
    LoadTestOptions o = coarseDynamicRig(1.0, 0);
    o.dynamic.damping = 0.0;
    o.dynamic.rampTravel = 0.0;
    const LoadTestResult r = runLoadTest(o);
    const LoadCurve& c = r.curves[0];
    EXPECT_FALSE(c.quasiStatic);
    EXPECT_GT(c.kineticShare, o.dynamic.kineticShareLimit);
    EXPECT_NE(c.failure.find("not quasi-static"), std::string::npos) << c.failure;
}

TEST(LoadTestDynamics, TheObserverSeesOnlyTheLoadingThatWasKept) {
    // A loading run again at half the speed (a share limit the first pace breaks) reaches the
    // observer once, its steps numbered from 0 in order.
    LoadTestOptions o = coarseDynamicRig(0.2, 3);
    o.dynamic.kineticShareLimit = 0.02;
    std::vector<int> seen;
    const LoadTestResult r = runLoadTest(
        o,
        [&](const LoadStep& s, const Mesh&, const Eigen::Matrix3Xd&) { seen.push_back(s.step); });
    ASSERT_EQ(seen.size(), r.curves[0].steps.size());
    for (size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], static_cast<int>(i));
    EXPECT_LT(r.curves[0].blockSpeed, 0.2);  // it slowed down
}

}  // namespace
}  // namespace bags
