// The airbag module: its call protocol (inflate, shapes, gas, advance, commit, rollback,
// snapshots), the wrench tangent against finite differences of re-solved equilibria, the
// imperfection, and results that do not depend on the number of threads.
#include <bags/Airbag.h>
#include <bags/MaterialFit.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

using namespace bags;

namespace {

AirbagSpec coarseSpec(double meshSize = 0.020) {
    AirbagSpec s;
    s.geometry.meshSize = meshSize;
    s.material = makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    return s;
}

Eigen::Isometry3d translation(const Vec3& p) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = p;
    return X;
}

// A rigid ellipsoid above the apex ridge of the inflated bag (frictionless unless the
// contact options say otherwise), parked clear.
struct PressedBag {
    std::unique_ptr<Airbag> bag;
    int shape = -1;
    Vec3 centre;
    double top = 0.0;
    Vec3 semi{0.04, 0.03, 0.02};
    explicit PressedBag(const AirbagSpec& spec, double mass = 4.5e-3,
                        const RigidContact::Options& contact = RigidContact::Options()) {
        bag = std::make_unique<Airbag>(spec);
        const Mesh& mesh = bag->getMesh();
        int apex = 0;
        mesh.X.row(2).maxCoeff(&apex);
        std::shared_ptr<RigidShape> e(makeEllipsoid(semi));
        e->setPose(translation(Vec3(mesh.X(0, apex), 0.0, 0.5)));
        shape = bag->addShape(e, contact);
        bag->inflate(mass);
        top = bag->getPositions().row(2).maxCoeff();
        centre = Vec3(mesh.X(0, apex), 0.0, top + semi.z());
    }
    // Presses the ellipsoid `depth` [m] into the bag, slightly tilted and off centre.
    Eigen::Isometry3d pose(double depth) const {
        Eigen::Isometry3d X = translation(centre + Vec3(0.004, -0.003, -depth));
        X.linear() = Eigen::AngleAxisd(0.05, Vec3(1, 1, 0).normalized()).toRotationMatrix();
        return X;
    }
};

}  // namespace

TEST(Airbag, ProtocolInflatesPressesCommitsAndRollsBack) {
    PressedBag p(coarseSpec());
    Airbag& bag = *p.bag;
    EXPECT_NEAR(bag.getTotalGasMass(), 4.5e-3, 1e-12);
    ASSERT_EQ(bag.getNumChambers(), 2);
    const ChamberState c0 = bag.getChamberState(0);
    EXPECT_GT(c0.gaugePressure, 1000.0);
    EXPECT_NEAR(bag.getChamberState(0).mass + bag.getChamberState(1).mass, 4.5e-3, 1e-12);
    EXPECT_EQ(bag.calcShapeWrench(p.shape).force.norm(), 0.0);  // parked clear

    const Eigen::Matrix3Xd x0 = bag.getPositions();
    bag.setShapePose(p.shape, p.pose(0.010));
    const AdvanceSummary a = bag.advance(60.0);
    ASSERT_TRUE(a.converged);
    EXPECT_GE(a.substeps, 1);
    EXPECT_DOUBLE_EQ(bag.getTime(), 60.0);
    const Wrench w = bag.calcShapeWrench(p.shape);
    EXPECT_GT(w.force.z(), 1.0);  // the bag pushes the shape up
    EXPECT_GT(bag.calcShapeContactPressure(p.shape).maxCoeff(), 0.0);
    // The base is bonded to the bed board: no free node reaches it here.
    EXPECT_EQ(bag.calcBedForce().norm(), 0.0);
    const Eigen::Matrix3Xd x1 = bag.getPositions();

    // Not committed: rollback returns to the inflated state, bit for bit.
    bag.rollback();
    EXPECT_EQ((bag.getPositions() - x0).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(bag.getTime(), 0.0);
    EXPECT_EQ(bag.calcShapeWrench(p.shape).force.norm(), 0.0);
    // The same step again reaches the same state within the solve's tolerance (the
    // factorisation that preconditions the solve is the first attempt's, so the iterates
    // differ; whole runs are bit-identical, see below): the wrench within the bag's force
    // tolerance (0.05 N), the nodes within 0.1 mm (measured 11 um).
    bag.setShapePose(p.shape, p.pose(0.010));
    ASSERT_TRUE(bag.advance(60.0).converged);
    EXPECT_LT((bag.getPositions() - x1).cwiseAbs().maxCoeff(), 1e-4);
    EXPECT_LT((bag.calcShapeWrench(p.shape).force - w.force).norm(), bag.getSpec().forceTolerance);
    const Eigen::Matrix3Xd x1b = bag.getPositions();
    bag.commit();
    const auto checkpoint = bag.getSnapshot();
    // A deeper press, then back to the checkpoint.
    bag.setShapePose(p.shape, p.pose(0.020));
    ASSERT_TRUE(bag.advance(60.0).converged);
    EXPECT_GT(bag.calcShapeWrench(p.shape).force.z(), w.force.z());
    bag.commit();
    bag.setSnapshot(checkpoint);
    EXPECT_EQ((bag.getPositions() - x1b).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_DOUBLE_EQ(bag.getTime(), 60.0);
    EXPECT_LT((bag.calcShapeWrench(p.shape).force - w.force).norm(), bag.getSpec().forceTolerance);
}

TEST(Airbag, GasFlowsInAndOutOverTheStepAndStopsAtTheTarget) {
    PressedBag p(coarseSpec());
    Airbag& bag = *p.bag;
    const double p0 = bag.getChamberState(0).gaugePressure;
    bag.setMassFlow(-1e-5);  // 0.01 g/s out
    ASSERT_TRUE(bag.advance(20.0).converged);
    EXPECT_NEAR(bag.getTotalGasMass(), 4.5e-3 - 2e-4, 1e-12);
    EXPECT_LT(bag.getChamberState(0).gaugePressure, p0);
    bag.commit();
    bag.setTargetMass(4.4e-3, 1e-5);  // in again, but only up to 4.4 g
    ASSERT_TRUE(bag.advance(30.0).converged);
    EXPECT_NEAR(bag.getTotalGasMass(), 4.4e-3, 1e-12);
    bag.commit();
    ASSERT_TRUE(bag.advance(30.0).converged);  // target reached: no more flow
    EXPECT_NEAR(bag.getTotalGasMass(), 4.4e-3, 1e-12);
    bag.changeGasMass(4.0e-3);  // a quasi-static let-down, committed
    EXPECT_NEAR(bag.getTotalGasMass(), 4.0e-3, 1e-12);
    // A shape that moves without touching, no gas moving: nothing is solved, the state stands.
    const Eigen::Matrix3Xd x = bag.getPositions();
    bag.setMassFlow(0.0);
    bag.setShapePose(p.shape, translation(p.centre + Vec3(0.02, 0.0, 0.1)));
    const AdvanceSummary idle = bag.advance(10.0);
    EXPECT_TRUE(idle.converged);
    EXPECT_EQ(idle.newtonIterations, 0);
    EXPECT_EQ((bag.getPositions() - x).cwiseAbs().maxCoeff(), 0.0);
}

namespace {

// The wrench tangent of the pressed ellipsoid against central differences of the wrench over
// equilibria re-solved at perturbed poses (tight tolerances); returns the worst block error
// relative to the block's largest entry, and checks it against `tolerance`. Pressed and
// committed, every node in contact holds a friction anchor where it touches (friction acts
// from the step after first touch); a committed `sideways` move then loads the stick springs
// (slipping where they reach mu f_n). `tissue` (thickness [m], modulus [Pa]) puts a compliant
// layer on the ellipsoid.
// The ellipsoid pressed 12 mm into a bag solved tightly (for finite differences), committed;
// then moved `sideways` and committed again (the friction anchors set where it first touched).
std::unique_ptr<PressedBag> pressTightly(double friction, const Vec3& sideways,
                                         const std::pair<double, double>& tissue = {0.0, 0.0}) {
    AirbagSpec spec = coarseSpec();
    spec.forceTolerance = 1e-7;
    spec.solver.absoluteTolerance = 1e-9;
    spec.solver.relativeTolerance = 1e-12;
    spec.selfContact = false;
    RigidContact::Options contact;
    contact.friction = friction;
    contact.tissueThickness = tissue.first;
    contact.tissueModulus = tissue.second;
    auto p = std::make_unique<PressedBag>(spec, 4.5e-3, contact);
    Airbag& bag = *p->bag;
    Eigen::Isometry3d X = p->pose(0.012);
    bag.setShapePose(p->shape, X);
    EXPECT_TRUE(bag.advance(0.0).converged);
    bag.commit();
    if (sideways.norm() > 0.0) {
        X.translation() += sideways;
        bag.setShapePose(p->shape, X);
        EXPECT_TRUE(bag.advance(0.0).converged);
        bag.commit();
    }
    return p;
}

double checkWrenchTangent(double friction, const Vec3& sideways, double tolerance,
                          Eigen::Matrix<double, 6, 6>* tangent,
                          const std::pair<double, double>& tissue = {0.0, 0.0}) {
    const std::unique_ptr<PressedBag> pressed = pressTightly(friction, sideways, tissue);
    PressedBag& p = *pressed;
    Airbag& bag = *p.bag;
    const Eigen::Matrix<double, 6, 6> T = bag.calcShapeWrenchTangent(p.shape);
    const Eigen::Isometry3d X0 = bag.getShapePose(p.shape);
    Eigen::Matrix<double, 6, 6> fd;
    for (int j = 0; j < 6; ++j) {
        const double h = j < 3 ? 2e-4 : 2e-5;  // [rad], [m]
        Eigen::Matrix<double, 6, 1> w[2];
        for (int side = 0; side < 2; ++side) {
            const double sgn = side == 0 ? 1.0 : -1.0;
            Eigen::Isometry3d X = X0;
            if (j < 3) {
                X.linear() =
                    Eigen::AngleAxisd(sgn * h, Vec3::Unit(j)).toRotationMatrix() * X0.linear();
            } else {
                X.translation() += sgn * h * Vec3::Unit(j - 3);
            }
            bag.setShapePose(p.shape, X);
            EXPECT_TRUE(bag.advance(0.0).converged);
            const Wrench wr = bag.calcShapeWrench(p.shape);
            w[side] << wr.torque, wr.force;
            bag.rollback();
        }
        fd.col(j) = (w[0] - w[1]) / (2.0 * h);
    }
    double worst = 0.0;
    for (int bi = 0; bi < 2; ++bi)
        for (int bj = 0; bj < 2; ++bj) {
            const Eigen::Matrix3d a = T.block<3, 3>(3 * bi, 3 * bj);
            const Eigen::Matrix3d b = fd.block<3, 3>(3 * bi, 3 * bj);
            const double scale = b.cwiseAbs().maxCoeff();
            worst = std::max(worst, (a - b).cwiseAbs().maxCoeff() / scale);
            EXPECT_LT((a - b).cwiseAbs().maxCoeff(), tolerance * scale)
                << "friction " << friction << ", block " << bi << "," << bj << "\ntangent\n"
                << a << "\nfinite differences\n"
                << b;
        }
    if (tangent) *tangent = T;
    return worst;
}

}  // namespace

TEST(Airbag, WrenchTangentMatchesFiniteDifferencesOfReSolvedEquilibria) {
    // Tolerance: 1e-4 of the largest entry of each block (rows torque / force, columns
    // rotation / translation; measured 9e-7): the finite differences carry the solve
    // tolerance and the contact's active-set changes.
    Eigen::Matrix<double, 6, 6> T;
    const double worst = checkWrenchTangent(0.0, Vec3::Zero(), 1e-4, &T);
    RecordProperty("worst_block_error", std::to_string(worst));
    std::printf(
        "wrench tangent against finite differences: worst block error %.2e of the "
        "block's largest entry; d(force z)/d(z) = %.1f N/m\n",
        worst, T(5, 5));
    // The vertical stiffness the shape feels is positive and well below the contact penalty
    // over the contact patch (the bag, not the penalty, governs it).
    EXPECT_LT(T(5, 5), 0.0);  // pushing down (+z translation raises it; force falls)
}

TEST(Airbag, WrenchTangentWithATissueLayerMatchesFiniteDifferencesOfReSolvedEquilibria) {
    // A 10 mm layer of 200 kPa on the ellipsoid (RigidContact::Options::tissueThickness): the
    // tangent the body gets carries the layer in series with the bag, frictionless and stuck
    // with friction 0.5; tolerances as without the layer. The layer softens what the shape
    // feels: its vertical stiffness is below the bare shape's. Measured: worst block errors
    // 9.0e-7 (frictionless) and 1.4e-7 (stuck); vertical stiffness 5509 N/m against 6257 N/m.
    Eigen::Matrix<double, 6, 6> bare, T, Tf;
    checkWrenchTangent(0.0, Vec3::Zero(), 1e-4, &bare);
    const double plain = checkWrenchTangent(0.0, Vec3::Zero(), 1e-4, &T, {0.010, 2e5});
    const double stick = checkWrenchTangent(0.5, Vec3::Zero(), 1e-5, &Tf, {0.010, 2e5});
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2e / %.2e", plain, stick);
    RecordProperty("worst_block_error_plain_stick", buf);
    RecordProperty("vertical_stiffness_bare", std::to_string(-bare(5, 5)));
    RecordProperty("vertical_stiffness_layer", std::to_string(-T(5, 5)));
    EXPECT_LT(T(5, 5), 0.0);
    EXPECT_GT(T(5, 5), bare(5, 5));
}

TEST(Airbag, WrenchTangentWithFrictionMatchesFiniteDifferencesOfReSolvedEquilibria) {
    // The same check with Coulomb friction 0.5 between shape and film: the wrench carries the
    // stick springs' tangential forces, and the tangent their dependence on the pose (the
    // anchors ride with the shape), on the nodes' positions (dW/dx, its own derivative: the
    // friction force is a law, not a potential's gradient) and on the film's re-equilibrium.
    // Without friction a sideways move of the shape is resisted only through the curved
    // surface; with it the film holds on, so d(force x)/d(x) is about 100 times larger.
    //  - Pressed (every node in contact stuck): tolerance 1e-5 of each block's largest entry
    //    (measured 3.2e-7).
    //  - Then pushed 0.5 mm sideways, part of the patch slipping: the bag's tangent stiffness
    //    is symmetric, so it leaves out a slipping node's -mu (d f_n / d g) t n^T and the
    //    stretched springs' unsymmetric part. Tolerance 1e-2 (measured 2.0e-3).
    Eigen::Matrix<double, 6, 6> T0, T, Ts;
    checkWrenchTangent(0.0, Vec3::Zero(), 1e-4, &T0);
    const double stick = checkWrenchTangent(0.5, Vec3::Zero(), 1e-5, &T);
    const double slip = checkWrenchTangent(0.5, Vec3(0.0005, 0.0003, 0.0), 1e-2, &Ts);
    RecordProperty("worst_block_error_stick", std::to_string(stick));
    RecordProperty("worst_block_error_slip", std::to_string(slip));
    std::printf(
        "wrench tangent with friction 0.5 against finite differences: worst block error "
        "%.2e stuck, %.2e partly slipping; d(force x)/d(x) = %.1f N/m stuck, %.1f N/m "
        "slipping (frictionless %.1f N/m)\n",
        stick, slip, T(3, 3), Ts(3, 3), T0(3, 3));
    EXPECT_LT(T(3, 3), 20.0 * T0(3, 3));  // both negative: friction resists the sideways move
}

TEST(Airbag, TheLinearisationWithoutFrictionLeavesTheStickSpringsOutAndTheStateAsItWas) {
    // calcShapeWrenchTangents(..., withoutFriction): the tangent of the same state with the
    // shape's contact taken frictionless, for the tangent-implicit coupling with body friction
    // (docs/cosim.md#friction-and-the-tangent-schemes). References:
    //  - friction 0: it is the tangent itself, bit for bit;
    //  - friction 0.5, pressed (stuck) and pushed 0.5 mm sideways (partly slipping): it is the
    //    frictionless bag's tangent (checked against finite differences above) of a state a
    //    little apart (the film held by friction): within 5 % of each block's largest entry
    //    (measured 8.7e-10 stuck, 1.9e-2 partly slipping), while the tangent with friction is
    //    about 100 times stiffer sideways (-12 440 against -101 N/m stuck);
    //  - the call leaves the bag as it was: the wrench and the tangent with friction after it
    //    are those before it, bit for bit.
    Eigen::Matrix<double, 6, 6> T0;
    {
        const std::unique_ptr<PressedBag> p = pressTightly(0.0, Vec3::Zero());
        T0 = p->bag->calcShapeWrenchTangent(p->shape);
        bool held = true;
        const Eigen::Matrix<double, 6, 6> T0n =
            p->bag->calcShapeWrenchTangents({p->shape}, &held, true).front();
        EXPECT_FALSE(held);
        EXPECT_EQ((T0n - T0).cwiseAbs().maxCoeff(), 0.0);
        EXPECT_EQ((p->bag->calcShapeWrenchLinearisation({p->shape}, true).pose.at(0) - T0)
                      .cwiseAbs()
                      .maxCoeff(),
                  0.0);
    }
    for (const Vec3& sideways : {Vec3::Zero().eval(), Vec3(0.0005, 0.0003, 0.0)}) {
        const std::unique_ptr<PressedBag> p = pressTightly(0.5, sideways);
        Airbag& bag = *p->bag;
        const Wrench w = bag.calcShapeWrench(p->shape);
        const Eigen::Matrix<double, 6, 6> T = bag.calcShapeWrenchTangent(p->shape);
        bool held = true;
        const Eigen::Matrix<double, 6, 6> Tn =
            bag.calcShapeWrenchTangents({p->shape}, &held, true).front();
        EXPECT_FALSE(held);
        const Airbag::WrenchLinearisation lin = bag.calcShapeWrenchLinearisation({p->shape}, true);
        EXPECT_EQ((lin.pose.at(0) - Tn).cwiseAbs().maxCoeff(), 0.0);
        double worst = 0.0;
        for (int bi = 0; bi < 2; ++bi)
            for (int bj = 0; bj < 2; ++bj) {
                const Eigen::Matrix3d a = Tn.block<3, 3>(3 * bi, 3 * bj);
                const Eigen::Matrix3d b = T0.block<3, 3>(3 * bi, 3 * bj);
                worst = std::max(worst, (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff());
            }
        std::printf(
            "friction 0.5, sideways %.1f mm: the tangent without friction against the "
            "frictionless bag's: worst block error %.2e; d(force x)/d(x) = %.1f N/m "
            "without friction, %.1f N/m with it, %.1f N/m frictionless\n",
            1e3 * sideways.norm(), worst, Tn(3, 3), T(3, 3), T0(3, 3));
        EXPECT_LT(worst, 5e-2);
        EXPECT_GT(T(3, 3) / Tn(3, 3), 20.0);  // both negative
        const Wrench after = bag.calcShapeWrench(p->shape);
        EXPECT_EQ((after.force - w.force).norm(), 0.0);
        EXPECT_EQ((after.torque - w.torque).norm(), 0.0);
        EXPECT_EQ((bag.calcShapeWrenchTangent(p->shape) - T).cwiseAbs().maxCoeff(), 0.0);
    }
}

namespace {

// The pressed ellipsoid's wrench derivative by the bag's gas mass against central differences
// of equilibria re-solved with gas let in and out over a step (the flow path advance() takes),
// the shape held; returns the error relative to the derivative's largest entry.
double checkGasDerivative(double friction, const Vec3& sideways,
                          Eigen::Matrix<double, 6, 1>* dWdm) {
    const std::unique_ptr<PressedBag> pressed = pressTightly(friction, sideways);
    PressedBag& p = *pressed;
    Airbag& bag = *p.bag;
    const Airbag::WrenchLinearisation lin = bag.calcShapeWrenchLinearisation({p.shape});
    EXPECT_FALSE(lin.filmHeld);
    EXPECT_EQ(lin.gas.at(0).cols(), 1);
    // The pose tangent is calcShapeWrenchTangent()'s, bit for bit (one solve, its columns
    // independent).
    EXPECT_EQ((lin.pose.at(0) - bag.calcShapeWrenchTangent(p.shape)).cwiseAbs().maxCoeff(), 0.0);
    const double h = 1e-6, dt = 1.0;  // [kg] 1 mg, 0.02 % of the gas (at 20 mg the contact
                                      // patch changes and the differences err by 2e-3); [s]
    Eigen::Matrix<double, 6, 1> w[2];
    for (int side = 0; side < 2; ++side) {
        bag.setMassFlow((side == 0 ? h : -h) / dt);
        EXPECT_NEAR(bag.calcGasInflow(0, dt), side == 0 ? h : -h, 1e-18);
        EXPECT_TRUE(bag.advance(dt).converged);
        const Wrench wr = bag.calcShapeWrench(p.shape);
        w[side] << wr.torque, wr.force;
        bag.rollback();
    }
    bag.setMassFlow(0.0);
    const Eigen::Matrix<double, 6, 1> fd = (w[0] - w[1]) / (2.0 * h);
    *dWdm = lin.gas.at(0).col(0);
    std::printf(
        "d force / d gas mass, friction %.1f: (%.3f, %.3f, %.3f) N/g, finite differences "
        "(%.3f, %.3f, %.3f) N/g\n",
        friction, 1e-3 * (*dWdm)(3), 1e-3 * (*dWdm)(4), 1e-3 * (*dWdm)(5), 1e-3 * fd(3),
        1e-3 * fd(4), 1e-3 * fd(5));
    return (*dWdm - fd).cwiseAbs().maxCoeff() / fd.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(Airbag, WrenchGasDerivativeMatchesFiniteDifferencesOfReSolvedEquilibria) {
    // d wrench / d m (the gas let in, shared by volume between the chambers, the shape held)
    // against central differences over +-1 mg let in over a step. Tolerance 1e-5 of the
    // largest entry, frictionless and stuck under friction 0.5 (measured 3e-8 and 1e-7: the
    // solve tolerance); partly slipping 5e-3 (measured 7.5e-4: as for the pose tangent, the
    // slipping nodes' unsymmetric part is left out of the bag's tangent). More gas lifts the
    // pressed shape: d(force z)/dm > 0 (31.8 N/g frictionless).
    Eigen::Matrix<double, 6, 1> d0, d1, d2;
    const double e0 = checkGasDerivative(0.0, Vec3::Zero(), &d0);
    const double e1 = checkGasDerivative(0.5, Vec3::Zero(), &d1);
    const double e2 = checkGasDerivative(0.5, Vec3(0.0005, 0.0003, 0.0), &d2);
    std::printf(
        "gas derivative against finite differences: %.2e frictionless, %.2e stuck, %.2e "
        "partly slipping\n",
        e0, e1, e2);
    EXPECT_LT(e0, 1e-5);
    EXPECT_LT(e1, 1e-5);
    EXPECT_LT(e2, 5e-3);
    EXPECT_GT(d0(5), 0.0);
}

TEST(Airbag, GasInflowIsTheFlowOverTheStepUpToTheTarget) {
    PressedBag p(coarseSpec());
    Airbag& bag = *p.bag;
    EXPECT_EQ(bag.calcGasInflow(0, 1.0), 0.0);  // no flow set
    bag.setMassFlow(-1e-5);
    EXPECT_DOUBLE_EQ(bag.calcGasInflow(0, 2.0), -2e-5);
    bag.setTargetMass(4.6e-3, 1e-5);  // 0.1 g to go at 0.01 g/s
    EXPECT_DOUBLE_EQ(bag.calcGasInflow(0, 3.0), 3e-5);
    EXPECT_NEAR(bag.calcGasInflow(0, 30.0), 1e-4, 1e-15);  // what is left to the target
    bag.setTargetMass(4.0e-3, 1e-5);                       // out, toward a lower target
    EXPECT_DOUBLE_EQ(bag.calcGasInflow(0, 3.0), -3e-5);
    EXPECT_THROW(bag.calcGasInflow(1, 1.0), std::out_of_range);
}

// A bag on a bed board that has sunk by delta (a bed on a spring under load) is the same bag
// moved down as a rigid body: pressed to the same depth below its own top it pushes back with
// the same force and holds the same pressure (gravity is uniform). This is what lets the rig
// take the bed's compliance as crosshead travel (diagnose::RigEffects::bedCompliance).
// Tolerance 1e-6 of the force: the two solves start from translated states.
TEST(Airbag, ABagOnASunkBedBoardIsTheSameBagMovedDown) {
    AirbagSpec low = coarseSpec();
    low.forceTolerance = 1e-6;
    AirbagSpec high = low;
    low.X_GB = translation(Vec3(0.0, 0.0, -0.004));  // the board 4 mm lower
    PressedBag a(high), b(low);
    EXPECT_NEAR(b.top, a.top - 0.004, 1e-9);
    a.bag->setShapePose(a.shape, a.pose(0.010));
    b.bag->setShapePose(b.shape, b.pose(0.010));
    ASSERT_TRUE(a.bag->advance(1.0).converged);
    ASSERT_TRUE(b.bag->advance(1.0).converged);
    const double fa = a.bag->calcShapeWrench(a.shape).force.z();
    EXPECT_GT(fa, 1.0);
    EXPECT_NEAR(b.bag->calcShapeWrench(b.shape).force.z(), fa, 1e-6 * fa);
    EXPECT_NEAR(b.bag->getChamberState(0).gaugePressure, a.bag->getChamberState(0).gaugePressure,
                1e-6 * a.bag->getChamberState(0).gaugePressure);
}

TEST(Airbag, ImperfectionIsSmoothDeterministicAndOfTheStatedAmplitude) {
    DoubleWedgeParams g;
    g.meshSize = 0.010;
    const Mesh perfect = makeDoubleWedgeBag(g);
    Imperfection imp;
    imp.amplitude = 0.5e-3;
    imp.seed = 7;
    Mesh a = perfect, b = perfect, c = perfect;
    applyImperfection(a, imp);
    applyImperfection(b, imp);
    imp.seed = 8;
    applyImperfection(c, imp);
    EXPECT_EQ((a.X - b.X).cwiseAbs().maxCoeff(), 0.0);   // same seed, same bits
    EXPECT_GT((a.X - c.X).cwiseAbs().maxCoeff(), 1e-4);  // another seed, another bag
    const Eigen::VectorXd d = (a.X - perfect.X).colwise().norm();
    EXPECT_NEAR(d.maxCoeff(), 0.5e-3, 1e-12);                 // the stated amplitude
    for (int n : perfect.supportNodes) EXPECT_EQ(d(n), 0.0);  // bonded nodes stay
    // Smooth: neighbouring free nodes (one element apart) differ on average by far less than
    // the amplitude (a node-by-node random offset would give about a third of it; the bonded
    // base holds its nodes, so the row above it may step off).
    std::vector<char> support(perfect.getNumNodes(), 0);
    for (int n : perfect.supportNodes) support[n] = 1;
    double jump = 0.0;
    int edges = 0;
    for (int e = 0; e < a.getNumTris(); ++e)
        for (int k = 0; k < 3; ++k) {
            const int i = a.tris(k, e), j = a.tris((k + 1) % 3, e);
            if (support[i] || support[j]) continue;
            jump += std::abs(d(i) - d(j));
            ++edges;
        }
    EXPECT_LT(jump / edges, 0.15 * imp.amplitude);  // measured 0.11
    a.validate();                                   // still a valid closed bag
}

TEST(Airbag, ResultsAreBitIdenticalOnOneAndTwoThreads) {
    // 6 mm: over 4000 triangles, so the element loop is cut into chunks and runs on a team.
    auto run = [](int threads) {
        AirbagSpec spec = coarseSpec(0.006);
        spec.threads = threads;
        spec.imperfection.amplitude = 0.3e-3;
        PressedBag p(spec);
        p.bag->setShapePose(p.shape, p.pose(0.008));
        EXPECT_TRUE(p.bag->advance(48.0).converged);
        return std::make_pair(Eigen::Matrix3Xd(p.bag->getPositions()),
                              p.bag->calcShapeWrench(p.shape).force);
    };
    const auto one = run(1), two = run(2), again = run(2);
    EXPECT_GT(one.first.cols(), 3000);
    EXPECT_EQ((one.first - two.first).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((two.first - again.first).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(one.second, two.second);
}

TEST(Airbag, DampedStepsRelaxOnTautFilmAndReportTheDampersWorkOnSlackFilm) {
    // Taut bag (4.5 g): the damped solve is easy, so the damper-free equilibrium is taken:
    // no damper work, the wrench of the undamped bag within the force tolerance (0.05 N).
    auto press = [](double mass, double damping, double depth) {
        AirbagSpec spec = coarseSpec();
        spec.damping = damping;
        PressedBag p(spec, mass);
        p.bag->setShapePose(p.shape, p.pose(depth));
        const AdvanceSummary a = p.bag->advance(60.0);
        EXPECT_TRUE(a.converged);
        return std::make_tuple(a, p.bag->calcShapeWrench(p.shape).force, std::move(p.bag));
    };
    const auto [tautDamped, fTautDamped, b0] = press(4.5e-3, 1e5, 0.006);
    const auto [taut, fTaut, b1] = press(4.5e-3, 0.0, 0.006);
    EXPECT_EQ(tautDamped.stabilizationEnergy, 0.0);
    EXPECT_LT((fTautDamped - fTaut).norm(), b0->getSpec().forceTolerance);
    EXPECT_GT(fTaut.z(), 1.0);
    // Slack bag (2.0 g; this coarse literal bag is just full at about 3.6 g) pressed 20 mm in
    // one step: the damped solve is not easy; the dampers are re-anchored until the force they
    // hold is within the force tolerance, and their work on the way is reported.
    const auto [slackDamped, fSlack, b2] = press(2.0e-3, 1e5, 0.020);
    std::printf(
        "slack press: damper work %.3g J, shape work about %.3g J, residual %.3g N, "
        "%d iterations\n",
        slackDamped.stabilizationEnergy, 0.5 * fSlack.z() * 0.020, slackDamped.residual,
        slackDamped.newtonIterations);
    EXPECT_GT(slackDamped.stabilizationEnergy, 0.0);
    EXPECT_LE(slackDamped.residual, b2->getSpec().forceTolerance);
}

TEST(Airbag, TheTangentsOfSeveralShapesAtOnceAreEachShapesOwn) {
    // calcShapeWrenchTangents() factors the bag's tangent once for every pressing shape; each
    // block must equal the shape's tangent computed alone (itself checked against finite
    // differences above), to roundoff (1e-9 of the block's largest entry). A second
    // ellipsoid presses 35 mm beside the first; a third hangs clear of the bag and gets zero.
    AirbagSpec spec = coarseSpec();
    spec.selfContact = false;
    PressedBag p(spec);
    Airbag& bag = *p.bag;
    std::shared_ptr<RigidShape> e2(makeEllipsoid(p.semi)), e3(makeEllipsoid(p.semi));
    e2->setPose(translation(p.centre + Vec3(0.0, 0.0, 0.3)));
    e3->setPose(translation(p.centre + Vec3(0.0, 0.0, 0.3)));
    const int s2 = bag.addShape(e2, RigidContact::Options());
    const int s3 = bag.addShape(e3, RigidContact::Options());
    bag.setShapePose(p.shape, p.pose(0.010));
    Eigen::Isometry3d X2 = p.pose(0.015);
    X2.translation().y() += 0.035;
    bag.setShapePose(s2, X2);
    ASSERT_TRUE(bag.advance(0.0).converged);
    bag.commit();
    ASSERT_GT(bag.calcShapeWrench(s2).force.z(), 1.0);  // both press (measured 10.3, 37.1 N)
    const auto all = bag.calcShapeWrenchTangents({p.shape, s2, s3});
    ASSERT_EQ(all.size(), 3u);
    for (int k = 0; k < 2; ++k) {
        const Eigen::Matrix<double, 6, 6> alone = bag.calcShapeWrenchTangent(k == 0 ? p.shape : s2);
        const double scale = alone.cwiseAbs().maxCoeff();
        ASSERT_GT(scale, 0.0);
        EXPECT_LT((all[k] - alone).cwiseAbs().maxCoeff(), 1e-9 * scale) << "shape " << k;
    }
    EXPECT_EQ(all[2].cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(bag.calcShapeWrenchTangent(s3).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Airbag, ARepeatedAdvanceStartsWhereTheLastEndedAndFindsTheSameEquilibrium) {
    // An implicit coupling advances a bag again from the same commit to poses that differ by
    // its correction. With the warm start the second solve starts where the first ended: at
    // most as many Newton iterations as from the commit, and the same equilibrium (the
    // wrench within 1e-3 of itself; both solves are converged to the force tolerance).
    double force[2];
    int iterations[2];
    for (int warm = 0; warm < 2; ++warm) {
        AirbagSpec spec = coarseSpec();
        spec.warmStart = warm == 1;
        PressedBag p(spec);
        Airbag& bag = *p.bag;
        bag.setShapePose(p.shape, p.pose(0.010));
        ASSERT_TRUE(bag.advance(0.01).converged);
        bag.commit();
        bag.setShapePose(p.shape, p.pose(0.012));
        ASSERT_TRUE(bag.advance(0.01).converged);
        bag.setShapePose(p.shape, p.pose(0.01205));  // the next pass: 50 um further
        const AdvanceSummary again = bag.advance(0.01);
        ASSERT_TRUE(again.converged);
        iterations[warm] = again.newtonIterations;
        force[warm] = bag.calcShapeWrench(p.shape).force.z();
    }
    std::printf("second pass: %d Newton iterations from the commit, %d warm; force %.6f / %.6f N\n",
                iterations[0], iterations[1], force[0], force[1]);
    EXPECT_LE(iterations[1], iterations[0]);
    EXPECT_LT(iterations[1], iterations[0]);
    EXPECT_NEAR(force[1], force[0], 1e-3 * std::abs(force[0]));
}

TEST(Airbag, TheGasIsStillUnlessAFlowIsSetOrATargetIsNotReached) {
    PressedBag p(coarseSpec(0.03));
    Airbag& bag = *p.bag;
    EXPECT_TRUE(bag.isGasStill());
    bag.setMassFlow(1e-5);
    EXPECT_FALSE(bag.isGasStill());
    bag.setTargetMass(bag.getTotalGasMass(), 1e-5);  // already there
    EXPECT_TRUE(bag.isGasStill());
    bag.setTargetMass(bag.getTotalGasMass() + 1e-4, 1e-5);
    EXPECT_FALSE(bag.isGasStill());
}

namespace {
// A flat plate (200 x 200 mm, larger than the bag's top) pressed 5 mm onto the coarse wedge
// inflated to 4.5 g, then pushed along the bag's length in 16 committed steps of 0.5 mm, each
// advanced over stepTime [s]; the plate's force after each step.
void pushPlate(const RigidContact::Options& o, double stepTime, std::vector<Vec3>* forces) {
    AirbagSpec spec = coarseSpec();
    spec.selfContact = false;
    Airbag bag(spec);
    const Mesh& mesh = bag.getMesh();
    int apex = 0;
    mesh.X.row(2).maxCoeff(&apex);
    std::shared_ptr<RigidShape> plate(makeBox(Vec3(0.1, 0.1, 0.01), 0.002));
    plate->setPose(translation(Vec3(mesh.X(0, apex), 0.0, 0.5)));
    const int s = bag.addShape(plate, o);
    bag.inflate(4.5e-3);
    const double top = bag.getPositions().row(2).maxCoeff();
    Vec3 c(mesh.X(0, apex), 0.0, top + 0.01 - 0.005);
    bag.setShapePose(s, translation(c));
    ASSERT_TRUE(bag.advance(0.0).converged);
    bag.commit();
    for (int k = 1; k <= 16; ++k) {
        bag.setShapePose(s, translation(c + Vec3(0.0005 * k, 0.0, 0.0)));
        ASSERT_TRUE(bag.advance(stepTime).converged) << "push step " << k;
        bag.commit();
        forces->push_back(bag.calcShapeWrench(s).force);
    }
}
}  // namespace

TEST(Airbag, AShapePushedSidewaysOnTheFilmSticksThenSlipsAtMuTimesTheNormalForce) {
    // A flat plate (200 x 200 mm, larger than the bag's top, so its rounded edges never touch
    // the film and every contact normal is vertical) pressed 5 mm onto the inflated wedge,
    // then pushed along the bag's length in committed steps of 0.5 mm. Coulomb's law on every
    // node gives |F_horizontal| <= mu F_vertical at every step (within 1e-6 of the normal force,
    // the roundoff of the sums): at first the film sticks and the force grows with the push
    // (below 0.9 mu F_v after the first step), then the nodes slip and it levels at mu F_v
    // (within 2 %). Without friction the plate feels no horizontal force, and friction 0
    // gives the default options' wrench bit for bit.
    auto run = [](double mu, bool defaultOptions, std::vector<Vec3>* forces) {
        RigidContact::Options o;
        if (!defaultOptions) o.friction = mu;
        pushPlate(o, 0.0, forces);
    };
    const double mu = 0.4;
    std::vector<Vec3> none, zero, rough;
    run(0.0, true, &none);
    run(0.0, false, &zero);
    run(mu, false, &rough);
    ASSERT_EQ(none.size(), 16u);
    ASSERT_EQ(zero.size(), 16u);
    ASSERT_EQ(rough.size(), 16u);
    for (size_t k = 0; k < none.size(); ++k) {
        EXPECT_EQ(none[k], zero[k]) << "step " << k;
        EXPECT_LT(none[k].head<2>().norm(), 1e-9 * none[k].z()) << "step " << k;
    }
    double ratioFirst = 0.0, ratioLast = 0.0;
    for (size_t k = 0; k < rough.size(); ++k) {
        const double fh = rough[k].head<2>().norm(), fv = rough[k].z();
        ASSERT_GT(fv, 1.0);
        EXPECT_LE(fh, mu * fv * (1.0 + 1e-6)) << "step " << k;
        EXPECT_LT(rough[k].x(), 0.0) << "step " << k;  // the film holds the plate back
        if (k == 0) ratioFirst = fh / fv;
        ratioLast = fh / fv;
        std::printf("push %4.1f mm: F_h %7.3f N, F_v %7.3f N, F_h / F_v %.4f\n", 0.5 * (k + 1), fh,
                    fv, fh / fv);
    }
    EXPECT_LT(ratioFirst, 0.9 * mu);
    EXPECT_GT(ratioLast, 0.98 * mu);
}

TEST(Airbag, APlateDraggedOverTheFilmFeelsTheRegularisedLawsForceAtItsSpeed) {
    // The plate of the test above, 5 mm into the inflated wedge, dragged along the bag's length
    // in 16 steps of 0.5 mm with the regularised law (mu 0.4, v_s = 2 mm/s). Each node's force
    // is mu f_n v / sqrt(v^2 + v_s^2) at its slip speed v on the plate, which is at most the
    // plate's speed V once the film is not moving forward faster than the plate, so
    // |F_h| <= mu F_v V / sqrt(V^2 + v_s^2) at every step (1e-6 of F_v for roundoff). Fast
    // (V = 50 mm/s, 10 ms a step): the film soon holds still under the sliding plate and the
    // force levels at mu F_v (0.9992 of it at V). Slow (V = 0.05 mm/s, 10 s a step): viscous,
    // the bound 0.025 mu F_v. Both reach their bound after 8 mm (within 0.5 %; measured: to
    // 4 digits from 4.5 and 1 mm on).
    auto run = [](double stepTime, std::vector<Vec3>* forces) {
        RigidContact::Options o;
        o.friction = 0.4;
        o.frictionLaw = RigidContact::FrictionLaw::Regularised;
        o.slipVelocity = 2e-3;
        pushPlate(o, stepTime, forces);
    };
    const double mu = 0.4, vs = 2e-3;
    for (double stepTime : {0.01, 10.0}) {
        std::vector<Vec3> f;
        run(stepTime, &f);
        ASSERT_EQ(f.size(), 16u);
        const double V = 0.0005 / stepTime, bound = mu * V / std::sqrt(V * V + vs * vs);
        double ratio = 0.0;
        for (size_t k = 0; k < f.size(); ++k) {
            const double fh = f[k].head<2>().norm(), fv = f[k].z();
            ASSERT_GT(fv, 1.0);
            EXPECT_LE(fh, bound * fv + 1e-6 * fv) << "step " << k << ", V " << V;
            EXPECT_LT(f[k].x(), 0.0) << "step " << k;  // the film holds the plate back
            ratio = fh / fv;
            std::printf(
                "V %.3g mm/s, drag %4.1f mm: F_h %7.4f N, F_v %7.3f N, F_h / (mu F_v) "
                "%.4f (bound %.4f)\n",
                1e3 * V, 0.5 * (k + 1), fh, fv, fh / (mu * fv), bound / mu);
        }
        EXPECT_GT(ratio, 0.995 * bound) << "V " << V;  // measured: equal to 4 digits
    }
}

TEST(Airbag, ACheckpointCarriesTheRegularisedFrictionsSlipOfTheStep) {
    // The regularised law's committed force depends on where the step started (the anchors)
    // and on its slip length v_s dt; a bag loaded from a checkpoint gives the writer's wrench
    // and continues to the same bits. A bag with the stick-slip law does not read it.
    RigidContact::Options contact;
    contact.friction = 0.4;
    contact.frictionLaw = RigidContact::FrictionLaw::Regularised;
    // The reader's own last step is of another length: its slip length must come from the file.
    auto make = [&](const RigidContact::Options& o, double dt) {
        auto p = std::make_unique<PressedBag>(coarseSpec(), 4.5e-3, o);
        p->bag->setShapePose(p->shape, p->pose(0.006));
        EXPECT_TRUE(p->bag->advance(dt).converged);
        p->bag->commit();
        return p;
    };
    auto slide = [](PressedBag& p, int k) {
        Eigen::Isometry3d X = p.pose(0.006);
        X.translation().y() += 0.0005 * k;
        p.bag->setShapePose(p.shape, X);
        EXPECT_TRUE(p.bag->advance(0.01).converged);
        p.bag->commit();
        return p.bag->calcShapeWrench(p.shape).force;
    };
    auto a = make(contact, 0.01);
    slide(*a, 1);
    const Vec3 fa = slide(*a, 2);
    EXPECT_GT(std::abs(fa.y()), 0.05 * fa.z());  // friction acts
    a->bag->resetCaches();  // the solver's caches shape the roundoff; a loaded bag has none
    StateWriter w;
    a->bag->saveState(w);
    const Vec3 na = slide(*a, 3);
    auto b = make(contact, 0.05);
    StateReader r(w.getData());
    b->bag->loadState(r);
    EXPECT_EQ(b->bag->calcShapeWrench(b->shape).force, fa);
    EXPECT_EQ(slide(*b, 3), na);
    auto c = make(RigidContact::Options{}, 0.01);
    StateReader rc(w.getData());
    EXPECT_THROW(c->bag->loadState(rc), StateError);
}

TEST(Airbag, ARepeatedAdvanceThatNeedsTheSpringsAnswersTheSamePosesTheSameWay) {
    // An implicit coupling advances a bag again and again from one commit, and converges only
    // if the bag answers the same poses the same way. A slack bag (2.0 g; the coarse literal
    // bag fills at about 3.6 g) with friction 0.4 on the film, pressed 20 mm and then pushed
    // 5 mm deeper and 10 mm sideways in one step, cannot reach the tight force tolerance of the
    // patient runs (0.1 mN): the step is accepted held by the stabilisation springs, which
    // are anchored where Newton starts. Warm-started from the last pass's end, each repeat
    // relaxed further (measured before this was fixed: the wrench moved by 79 mN on the
    // second pass and 86 mN on the third, the residual 28, 1.1 and 2.5 mN), so the coupling
    // chased a moving answer. A warm start that does not end on an equilibrium
    // is solved again from the first pass's start: the repeats give the first pass's wrench.
    AirbagSpec spec = coarseSpec(0.030);
    spec.forceTolerance = 1e-4;
    RigidContact::Options contact;
    contact.friction = 0.4;
    PressedBag p(spec, 2.0e-3, contact);
    Airbag& bag = *p.bag;
    bag.setShapePose(p.shape, p.pose(0.020));
    ASSERT_TRUE(bag.advance(0.01).converged);
    bag.commit();
    Eigen::Isometry3d X = p.pose(0.025);
    X.translation().y() += 0.010;
    bag.setShapePose(p.shape, X);
    const AdvanceSummary first = bag.advance(0.01);
    ASSERT_TRUE(first.converged);
    ASSERT_GT(first.stabilizationEnergy, 0.0);              // held by the springs
    ASSERT_GT(first.residual, 10.0 * spec.forceTolerance);  // not an equilibrium
    const Vec3 f1 = bag.calcShapeWrench(p.shape).force;
    for (int pass = 2; pass <= 3; ++pass) {
        const AdvanceSummary again = bag.advance(0.01);
        ASSERT_TRUE(again.converged);
        const Vec3 f = bag.calcShapeWrench(p.shape).force;
        std::printf("pass %d: residual %.3g N (first %.3g N), force moved %.3g N of %.4f N\n", pass,
                    again.residual, first.residual, (f - f1).norm(), f1.norm());
        EXPECT_LT((f - f1).norm(), spec.forceTolerance) << "pass " << pass;
    }
}

// The film's use of its material's fitted range (Airbag::calcFittedRangeUse): the seed's film
// at its 4.5 g works far inside the Yeoh fit's stable range (the seed's bag works at a few per
// cent of strain; the fit is the polynomial up to I1 - 3 = 0.669, docs/materials.md); ten
// times that gas stretches it beyond (the array run then fails its 'film within its fitted
// range' row and ends partial); a law with no fitted limit (neo-Hookean) reports 0.
TEST(AirbagEnvelope, TheFilmsUseOfItsFittedRangeIsSmallWhenFilledAndAboveOneWhenOverfilled) {
    EXPECT_NEAR(calcFittedRangeLimit(*makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6)),
                0.669, 0.005);
    AirbagSpec spec = coarseSpec(0.03);
    spec.selfContact = false;
    Airbag filled(spec);
    filled.inflate(4.5e-3);
    double stretch = 0.0;
    const double use = filled.calcFittedRangeUse(&stretch);
    EXPECT_GT(use, 0.0);
    EXPECT_LT(use, 0.2);
    EXPECT_GT(stretch, 1.0);
    EXPECT_LT(stretch, 1.1);
    Airbag over(spec);
    over.inflate(45e-3);
    const double overUse = over.calcFittedRangeUse(&stretch);
    EXPECT_GT(overUse, 1.0);
    EXPECT_GT(stretch, 1.5);
    spec.material = makeNeoHookean(10e6);
    Airbag plain(spec);
    plain.inflate(4.5e-3);
    EXPECT_EQ(plain.calcFittedRangeUse(), 0.0);
}
