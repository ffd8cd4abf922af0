// The reduced bag (cosim::ReducedBag): the membrane-free limit against the closed form of a
// sphere pressed into a flat-topped gas bag, its analytic tangent against finite differences
// of its wrench, its pressure footprint against its force, gas flows, rollback and the
// envelope counter. The calibration here is synthetic (stated in each test); the shipped
// calibrations from FE runs are validated by bench_reduced_bag (docs/reduced-bag.md).
#include <bags/StateStream.h>
#include <cosim/PressureMat.h>
#include <cosim/ReducedBag.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

using namespace cosim;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Three masses: 3 g slack (gauge 0), 4 g at 10 kPa, 5 g at 20 kPa, volumes by the gas law; a
// top grid of `pitch` over 200 x 100 mm centred on the bag origin, height from top(x, y, m).
template <class Top>
std::shared_ptr<ReducedBagCalibration> makeCalibration(double pitch, Top top) {
    auto c = std::make_shared<ReducedBagCalibration>();
    c->masses = {3e-3, 4e-3, 5e-3};
    c->gaugePressures = {0.0, 10e3, 20e3};
    for (size_t i = 0; i < 3; ++i)
        c->volumes.push_back(c->masses[i] * c->gasConstant * c->temperature /
                             (c->gaugePressures[i] + c->ambientPressure));
    c->pitch = pitch;
    c->nx = int(std::lround(0.2 / pitch)) + 1;
    c->ny = int(std::lround(0.1 / pitch)) + 1;
    c->x0 = -0.1;
    c->y0 = -0.05;
    for (double m : c->masses) {
        Eigen::MatrixXd t(c->nx, c->ny);
        for (int ix = 0; ix < c->nx; ++ix)
            for (int iy = 0; iy < c->ny; ++iy)
                t(ix, iy) = top(c->x0 + ix * pitch, c->y0 + iy * pitch, m);
        c->top.push_back(t);
    }
    c->depths = {0.0, 0.01, 0.02, 0.04};
    c->pressureFactor = Eigen::MatrixXd::Ones(3, 4);
    c->volumeFactor = Eigen::MatrixXd::Ones(3, 4);
    return c;
}

ShapeState at(const Eigen::Vector3d& p, const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
    ShapeState s;
    s.X_GS.linear() = R;
    s.X_GS.translation() = p;
    return s;
}

Eigen::Matrix3d rotation(const Eigen::Vector3d& v) {
    return v.norm() > 0 ? Eigen::AngleAxisd(v.norm(), v.normalized()).toRotationMatrix()
                        : Eigen::Matrix3d::Identity();
}

// Central differences of a shape's wrench re-evaluated by advance() (rotation 1e-6 rad about
// Ground axes through its origin, translation 1e-7 m), the pose (p, R) given as state(p, R).
template <class State>
Mat6 finiteDifferenceTangent(ReducedBag& bag, const Eigen::Vector3d& p, const Eigen::Matrix3d& R,
                             State state) {
    Mat6 fd;
    for (int k = 0; k < 6; ++k) {
        const double h = k < 3 ? 1e-6 : 1e-7;
        Vec6 w[2];
        for (int sgn = 0; sgn < 2; ++sgn) {
            Eigen::Vector3d dth = Eigen::Vector3d::Zero(), du = Eigen::Vector3d::Zero();
            (k < 3 ? dth : du)[k % 3] = sgn ? -h : h;
            bag.setShapeState(0, state(p + du, rotation(dth) * R));
            EXPECT_TRUE(bag.advance(0.0).converged);
            w[sgn] = bag.calcWrench(0).asVector();
        }
        fd.col(k) = (w[0] - w[1]) / (2 * h);
    }
    return fd;
}

// The analytic tangent of shape 0 at its committed pose (p, R) against central differences:
// the largest entry's difference within `tolerance` of the largest entry (above 1).
void expectTangentMatchesFiniteDifferences(ReducedBag& bag, const Eigen::Vector3d& p,
                                           const Eigen::Matrix3d& R, double tolerance,
                                           const std::string& where) {
    bag.commit();
    const Mat6 T = bag.calcWrenchTangent(0);
    const Mat6 fd = finiteDifferenceTangent(
        bag, p, R, [](const Eigen::Vector3d& q, const Eigen::Matrix3d& Q) { return at(q, Q); });
    bag.rollback();
    const double scale = fd.cwiseAbs().maxCoeff();
    EXPECT_GT(scale, 1.0) << where;
    EXPECT_LT((T - fd).cwiseAbs().maxCoeff(), tolerance * scale) << where << "\nanalytic\n"
                                                                 << T << "\nfinite differences\n"
                                                                 << fd;
}

}  // namespace

TEST(ReducedBag, ASpherePressedIntoAFlatTopCarriesGasPressureTimesItsContactArea) {
    // Reference (membrane-free limit, kappa = beta = 1): a sphere of radius R pressed delta
    // into a flat top displaces the cap volume pi delta^2 (3R - delta) / 3 and carries
    // P pi (2 R delta - delta^2), P from (P + p_amb)(V_free(P) - V_cap) = m R T. Tolerance 3 %
    // (a 1 mm grid, a normal depth in place of a vertical one, a 0.1 mm rim).
    auto cal = makeCalibration(1e-3, [](double, double, double) { return 0.1; });
    cal->rimWidth = 1e-4;
    ReducedBag bag(cal, Eigen::Isometry3d::Identity());
    const double R = 0.05, delta = 0.01;
    bag.addShape(bags::makeEllipsoid(Eigen::Vector3d::Constant(R)));
    bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, 1.0)));  // clear of the bag
    bag.setGasMass(4.5e-3);
    const double p0 = bag.getGaugePressure();
    bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, 0.1 + R - delta)));
    ASSERT_TRUE(bag.advance(0.0).converged);
    const double cap = kPi * delta * delta * (3 * R - delta) / 3;
    EXPECT_NEAR(bag.getOverlapVolume(0), cap, 0.03 * cap);
    const double P = bag.getGaugePressure();
    EXPECT_GT(P, p0);
    // The gas law with the model's own V_free (linear through the two taut states).
    const ReducedBagCalibration& c = *cal;
    const double slope =
        (c.volumes[2] - c.volumes[1]) / (c.gaugePressures[2] - c.gaugePressures[1]);
    const double vfree = c.volumes[1] + slope * (P - c.gaugePressures[1]);
    EXPECT_NEAR((P + c.ambientPressure) * (vfree - bag.getOverlapVolume(0)),
                4.5e-3 * c.gasConstant * c.temperature, 1e-9 * 382.5);
    const double F = P * kPi * (2 * R * delta - delta * delta);
    EXPECT_NEAR(bag.calcWrench(0).force.z(), F, 0.03 * F);
    EXPECT_NEAR(bag.calcWrench(0).force.x(), 0.0, 1e-3 * F);
    EXPECT_NEAR(bag.calcWrench(0).torque.norm(), 0.0, 1e-3 * F * R);
}

TEST(ReducedBag, TheTangentMatchesFiniteDifferencesOfTheWrench) {
    // Reference: central differences (rotation 1e-6 rad about Ground axes through the shape's
    // origin, translation 1e-7 m) of the wrench re-evaluated by advance(), the gas pressure
    // following. Tolerance 1e-4 of the largest entry. A curved top that sinks with mass,
    // factors that vary with depth and mass, a skirt, a tilted ellipsoid off centre 12 mm
    // deep; a second case, a lower top, presses it 45 mm, through the bed board (the film's
    // penalty); a third as the first with the other shape pressed into the same columns
    // (their common volume is displaced once: the union of their chords); a fourth as the
    // first with the panel coupling on (the ridge through the ellipsoid's contact, the
    // sphere's load moving its top by millimetres, through the gas pressure too).
    for (double depth : {0.012, 0.045, 0.0121, 0.0122}) {
        const bool share = depth == 0.0121, coupled = depth == 0.0122;
        const double h = depth < 0.02 ? 0.06 : 0.03;
        auto cal = makeCalibration(2e-3, [h](double x, double y, double m) {
            return h + 4.0 * (m - 3e-3) - 0.8 * x * x - 2.0 * y * y + 0.05 * x;
        });
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) {
                cal->pressureFactor(i, j) = 1.0 + 0.3 * j + 0.1 * i;
                cal->volumeFactor(i, j) = 1.2 - 0.1 * j + 0.05 * i;
            }
        cal->boardPenalty = 1e6;
        cal->skirt = 0.5;
        if (coupled) {
            cal->geometry.shortSide = 0.1505;  // the apex at x = 12.2 mm (bag frame)
            cal->panelSink = 3e-4, cal->panelLift = 2e-4, cal->panelBlend = 0.02;
        }
        ReducedBag bag(cal, Eigen::Isometry3d(Eigen::Translation3d(0.01, 0.0, 0.0)));
        const Eigen::Vector3d semi =
            depth < 0.02 ? Eigen::Vector3d(0.08, 0.05, 0.04) : Eigen::Vector3d(0.15, 0.10, 0.08);
        bag.addShape(bags::makeEllipsoid(semi));
        bag.addShape(bags::makeEllipsoid(Eigen::Vector3d::Constant(0.03)));  // another, fixed
        bag.setGasMass(4.4e-3);
        const Eigen::Matrix3d R0 = rotation(depth < 0.02 ? Eigen::Vector3d(0.3, -0.2, 0.4)
                                                         : Eigen::Vector3d(0.1, -0.05, 0.4));
        // Its height for that depth (bisection).
        Eigen::Vector3d p(0.02, -0.01, 0.0);
        bag.setShapeState(1, share ? at(Eigen::Vector3d(0.04, 0.0, h + 0.026))
                                   : at(Eigen::Vector3d(-0.06, 0.02, h + 0.025)));
        double lo = h, hi = h + 0.3;  // the centre at the top: deep in
        for (int it = 0; it < 50; ++it) {
            p.z() = 0.5 * (lo + hi);
            bag.setShapeState(0, at(p, R0));
            bag.advance(0.0);
            (bag.getDepth(0) > depth ? lo : hi) = p.z();
        }
        ASSERT_NEAR(bag.getDepth(0), depth, 1e-6);
        if (share) {  // the shapes do share columns: apart, the ellipsoid's own part grows
            const double shared = bag.getOverlapVolume(0);
            bag.setShapeState(1, at(Eigen::Vector3d(0.04, 0.0, 1.0)));
            bag.advance(0.0);
            EXPECT_GT(bag.getOverlapVolume(0), 1.05 * shared);
            bag.setShapeState(1, at(Eigen::Vector3d(0.04, 0.0, h + 0.026)));
            bag.advance(0.0);
            ASSERT_NEAR(bag.getOverlapVolume(0), shared, 1e-15);
            // and their films: some of the ellipsoid's samples share their column's film
            // with the sphere in part, so that the share's derivative is checked too
            int partial = 0;
            for (const ReducedBag::SampleForce& f : bag.getSampleForces(0))
                partial += f.film > 0.05 && f.film < 0.95;
            EXPECT_GE(partial, 2);
        }
        if (coupled) {  // the top moved under it by millimetres, up and down
            double up = 0.0, down = 0.0;
            for (const ReducedBag::SampleForce& f : bag.getSampleForces(0))
                up = std::max(up, f.shift), down = std::min(down, f.shift);
            EXPECT_GT(up, 1e-3);
            EXPECT_LT(down, -1e-3);
        }
        if (depth > 0.02) {  // its underside is below the board: the penalty acts
            ASSERT_LT(bag.getPressurePoints().row(2).minCoeff(), -1e-3);
        }
        expectTangentMatchesFiniteDifferences(bag, p, R0, 1e-4, "depth " + std::to_string(depth));
    }
}

TEST(ReducedBag, ASmallSphereSunkPastItsWidestIsNeverPushedDown) {
    // Reference: the film can only meet a shape pressed in from above on its underside, so
    // the gas never pushes a shape down. A 40 mm sphere pressed through a flat top (kappa =
    // beta = 1) from touching until it lies wholly below: its vertical force >= 0 at every
    // 0.5 mm step, and between steps it changes by less than a tenth of P pi R^2 (no load
    // gained or lost at once as its widest passes the top). (A wholly sunk shape carries
    // nothing here: docs/reduced-bag.md#a-shape-sunk-past-its-widest.)
    // Its tangent, 4 mm and 12 mm past its widest (top samples fading by their upward
    // normals, column samples sliding along their columns), against central differences as
    // in TheTangentMatchesFiniteDifferencesOfTheWrench: within 5e-4 of the largest entry.
    // The centre lies off the grid's points: with a column exactly on the silhouette the
    // force has a kink there and no derivative.
    auto cal = makeCalibration(1e-3, [](double, double, double) { return 0.1; });
    ReducedBag bag(cal, Eigen::Isometry3d::Identity());
    const double R = 0.02;
    bag.addShape(bags::makeEllipsoid(Eigen::Vector3d::Constant(R)));
    bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, 1.0)));
    bag.setGasMass(4.5e-3);
    double last = 0.0, most = 0.0;
    for (double travel = 0.5e-3; travel <= 0.08 + 1e-12; travel += 0.5e-3) {
        const double zc = 0.1 + R - travel;  // its centre; its top 2R - travel above the top
        bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, zc)));
        ASSERT_TRUE(bag.advance(0.0).converged);
        const double F = bag.calcWrench(0).force.z();
        const double support = bag.getGaugePressure() * kPi * R * R;
        EXPECT_GE(F, 0.0) << "travel " << travel * 1e3 << " mm";
        EXPECT_LT(std::abs(F - last), 0.1 * support) << "travel " << travel * 1e3 << " mm";
        last = F, most = std::max(most, F);
    }
    EXPECT_GT(most, 0.3 * 19e3 * kPi * R * R);  // it did carry load on the way
    for (double zc : {0.1 - 0.2 * R, 0.1 - 0.6 * R}) {
        const Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
        const Eigen::Vector3d p(0.00313, -0.00171, zc);
        bag.setShapeState(0, at(p, R0));
        ASSERT_TRUE(bag.advance(0.0).converged);
        expectTangentMatchesFiniteDifferences(bag, p, R0, 5e-4,
                                              "centre at " + std::to_string(zc * 1e3) + " mm");
    }
}

TEST(ReducedBag, TwoShapesInOnePlaceCarryWhatOneCarriesAloneAndAShallowSkirtYieldsItsFilm) {
    // The film over a column touches one surface (docs/reduced-bag.md#shapes-that-reach-the-same-film).
    // Reference: two copies of one tilted ellipsoid in the same pose displace its volume once
    // and take half of each column's film each, so together they carry the single shape's
    // wrench and the gas its pressure (1e-9 relative). Without the share the film would be
    // counted twice.
    auto cal = makeCalibration(
        2e-3, [](double x, double y, double) { return 0.06 - 0.8 * x * x - 2.0 * y * y; });
    cal->skirt = 1.0;
    const Eigen::Vector3d semi(0.08, 0.05, 0.04);
    const ShapeState pose = at(Eigen::Vector3d(0.01, -0.005, 0.06 + 0.04 - 0.012),
                               rotation(Eigen::Vector3d(0.2, -0.1, 0.3)));
    ReducedBag one(cal, Eigen::Isometry3d::Identity()), two(cal, Eigen::Isometry3d::Identity());
    one.addShape(bags::makeEllipsoid(semi));
    two.addShape(bags::makeEllipsoid(semi));
    two.addShape(bags::makeEllipsoid(semi));
    for (auto [b, shapes] : {std::pair{&one, 1}, std::pair{&two, 2}}) {
        b->setGasMass(4.4e-3);
        for (int s = 0; s < shapes; ++s) b->setShapeState(s, pose);
        ASSERT_TRUE(b->advance(0.0).converged);
    }
    const ShapeWrench w = one.calcWrench(0);
    ASSERT_GT(w.force.norm(), 1.0);
    EXPECT_NEAR(two.getGaugePressure(), one.getGaugePressure(), 1e-9 * one.getGaugePressure());
    const Eigen::Vector3d f = two.calcWrench(0).force + two.calcWrench(1).force;
    const Eigen::Vector3d t = two.calcWrench(0).torque + two.calcWrench(1).torque;
    EXPECT_LT((f - w.force).norm(), 1e-9 * w.force.norm());
    EXPECT_LT((t - w.torque).norm(), 1e-9 * w.force.norm() * 0.1);
    EXPECT_LT((two.calcWrench(0).force - 0.5 * w.force).norm(), 1e-9 * w.force.norm());
    // A small shape just touching the top inside the first's contact, where the first lies
    // deeper, yields the film there to it.
    ReducedBag beside(cal, Eigen::Isometry3d::Identity());
    beside.addShape(bags::makeEllipsoid(semi));
    beside.addShape(bags::makeEllipsoid(Eigen::Vector3d::Constant(0.03)));
    beside.setGasMass(4.4e-3);
    beside.setShapeState(0, pose);
    beside.setShapeState(1, at(Eigen::Vector3d(0.03, 0.0, 0.06 + 0.03 - 0.002)));
    ASSERT_TRUE(beside.advance(0.0).converged);
    int yielded = 0;
    for (const ReducedBag::SampleForce& sf : beside.getSampleForces(1)) yielded += sf.film < 0.05;
    EXPECT_GE(yielded, 1);
}

TEST(ReducedBag, ThePressureFootprintCarriesTheContactForce) {
    // Reference: the wrench. Sum over the footprint of p A along the shape's inward normal is
    // the force (1e-12 relative), its vertical part the region loads' force. A pressure mat
    // over the bag reads sum p A (1e-12): the normal forces, which add up to more than |F|
    // on a curved patch (they partly cancel), and to |F| under a flat face (1e-9).
    auto cal = makeCalibration(
        2e-3, [](double x, double y, double) { return 0.08 - 0.5 * x * x - 1.0 * y * y; });
    ReducedBag bag(cal, Eigen::Isometry3d(Eigen::Translation3d(0.3, -0.2, 0.0)));
    std::shared_ptr<bags::RigidShape> shape = bags::makeEllipsoid(Eigen::Vector3d(0.2, 0.12, 0.1));
    bag.addShape(shape);
    bag.setGasMass(4.0e-3);
    bag.setShapeState(0, at(Eigen::Vector3d(0.31, -0.2, 0.08 + 0.1 - 0.01),
                            rotation(Eigen::Vector3d(0.1, 0.05, 0.3))));
    ASSERT_TRUE(bag.advance(0.0).converged);
    const Eigen::VectorXd p = bag.calcContactPressure(0);
    const Eigen::VectorXd A = bag.getPressureAreas();
    const Eigen::Matrix3Xd& x = bag.getPressurePoints();
    Eigen::Vector3d F = Eigen::Vector3d::Zero();
    for (int i = 0; i < p.size(); ++i) {
        if (!(p[i] > 0.0)) continue;
        Eigen::Vector3d n;
        EXPECT_NEAR(shape->calcSignedDistance(x.col(i), nullptr, &n), 0.0, 1e-9);
        F += p[i] * A[i] * -n;
    }
    const Eigen::Vector3d W = bag.calcWrench(0).force;
    ASSERT_GT(W.z(), 50.0);
    EXPECT_NEAR((F - W).norm(), 0.0, 1e-12 * W.norm());
    PressureMatOptions o;
    o.rows = 20, o.columns = 10;
    o.origin = Eigen::Vector2d(0.15, -0.3);
    o.size = Eigen::Vector2d(0.3, 0.2);
    PressureMat mat(o);
    mat.addNodalPressures(x, p, A);
    EXPECT_NEAR(mat.getOffMatForce(), 0.0, 1e-12);
    EXPECT_NEAR(mat.calcTotalForce(), p.dot(A), 1e-12 * p.dot(A));
    EXPECT_GT(mat.calcTotalForce(), W.norm());
    // A box's flat face, level, 0.5 mm into a flat top: every point's force is vertical (its
    // sides lie 1 mm from the nearest grid points, so the face is their closest surface).
    auto flatTop = makeCalibration(2e-3, [](double, double, double) { return 0.08; });
    ReducedBag flat(flatTop, Eigen::Isometry3d(Eigen::Translation3d(0.3, -0.2, 0.0)));
    flat.addShape(bags::makeBox(Eigen::Vector3d(0.051, 0.031, 0.02), 1e-4));
    flat.setGasMass(4.0e-3);
    flat.setShapeState(0, at(Eigen::Vector3d(0.3, -0.2, 0.08 + 0.02 - 0.0005)));
    ASSERT_TRUE(flat.advance(0.0).converged);
    const Eigen::VectorXd pf = flat.calcContactPressure(0);
    mat.clear();
    mat.addNodalPressures(flat.getPressurePoints(), pf, flat.getPressureAreas());
    const Eigen::Vector3d Wf = flat.calcWrench(0).force;
    ASSERT_GT(Wf.z(), 5.0);
    EXPECT_NEAR(mat.calcTotalForce(), Wf.z(), 1e-9 * Wf.z());
}

TEST(ReducedBag, TheSampleForcesAndTheFootprintAddUpToTheWrench) {
    // Reference: the wrench. getSampleForces() (the diagnostics' split of the wrench by
    // sample) adds up to its force and its torque about the shape's origin (1e-12 relative),
    // with each kind of sample present: inside the shape, the skirt outside it, column samples
    // (a capsule sunk below the top) and the bed board's term (an ellipsoid pressed through
    // it).
    auto cal = makeCalibration(
        2e-3, [](double x, double y, double) { return 0.05 - 0.5 * x * x - 1.0 * y * y; });
    cal->skirt = 0.5;
    cal->boardPenalty = 1e6;
    ReducedBag bag(cal, Eigen::Isometry3d(Eigen::Translation3d(0.3, -0.2, 0.0)));
    bag.addShape(bags::makeEllipsoid(Eigen::Vector3d(0.08, 0.05, 0.04)));
    bag.addShape(bags::makeCapsule(0.012, 0.03));
    bag.setGasMass(4.0e-3);
    bag.setShapeState(
        0, at(Eigen::Vector3d(0.27, -0.2, 0.035), rotation(Eigen::Vector3d(0.1, -0.2, 0.3))));
    bag.setShapeState(1, at(Eigen::Vector3d(0.36, -0.2, 0.042),  // along x
                            rotation(Eigen::Vector3d(0.0, 0.5 * kPi, 0.0))));
    ASSERT_TRUE(bag.advance(0.0).converged);
    int skirt = 0, column = 0, board = 0;
    for (int s = 0; s < 2; ++s) {
        const ShapeWrench W = bag.calcWrench(s);
        const Eigen::Vector3d o =
            s == 0 ? Eigen::Vector3d(0.27, -0.2, 0.035) : Eigen::Vector3d(0.36, -0.2, 0.042);
        Eigen::Vector3d F = Eigen::Vector3d::Zero(), M = Eigen::Vector3d::Zero();
        for (const ReducedBag::SampleForce& f : bag.getSampleForces(s)) {
            F += f.force;
            M += (f.c - o).cross(f.force);
            skirt += f.delta < 0.0 && f.gasPressure > 0.0;
            column += f.column;
            board += f.boardPressure > 0.0;
        }
        ASSERT_GT(W.force.norm(), 1.0);
        EXPECT_NEAR((F - W.force).norm(), 0.0, 1e-12 * W.force.norm()) << "shape " << s;
        EXPECT_NEAR((M - W.torque).norm(), 0.0, 1e-12 * (W.torque.norm() + 1.0)) << "shape " << s;
    }
    EXPECT_GT(skirt, 0);
    EXPECT_GT(column, 0);
    EXPECT_GT(board, 0);
    // The footprint carries the same force in this scene too (column samples beside their
    // top samples, two shapes over some of the same grid points, the board's term): each
    // shape's pressure on the points, over their areas, along its inward normal there, as
    // the region loads and the pressure mat read it (cosim::calcRegionLoads). Tolerance
    // 1e-9 (the normal found again at each contact point).
    const Eigen::VectorXd A = bag.getPressureAreas();
    const Eigen::Matrix3Xd& x = bag.getPressurePoints();
    for (int s = 0; s < 2; ++s) {
        const Eigen::VectorXd p = bag.calcContactPressure(s);
        ASSERT_EQ(p.size(), x.cols());
        auto probe = s == 0 ? bags::makeEllipsoid(Eigen::Vector3d(0.08, 0.05, 0.04))
                            : bags::makeCapsule(0.012, 0.03);
        probe->setPose(s == 0 ? at(Eigen::Vector3d(0.27, -0.2, 0.035),
                                   rotation(Eigen::Vector3d(0.1, -0.2, 0.3)))
                                    .X_GS
                              : at(Eigen::Vector3d(0.36, -0.2, 0.042),
                                   rotation(Eigen::Vector3d(0.0, 0.5 * kPi, 0.0)))
                                    .X_GS);
        Eigen::Vector3d F = Eigen::Vector3d::Zero();
        for (int i = 0; i < p.size(); ++i) {
            if (p[i] == 0.0) continue;
            Eigen::Vector3d n;
            probe->calcSignedDistance(x.col(i), nullptr, &n);
            F += p[i] * A[i] * -n;
        }
        const Eigen::Vector3d W = bag.calcWrench(s).force;
        EXPECT_NEAR((F - W).norm(), 0.0, 1e-9 * W.norm()) << "shape " << s;
    }
}

TEST(ReducedBag, GasFlowsReachTheirTargetRollBackAndTheEnvelopeCountsExits) {
    // Reference: m(t) of the stated flow and target (exact); a rollback restores the
    // committed mass; a mass beyond the calibration's 3-5 g is counted.
    auto cal = makeCalibration(5e-3, [](double, double, double) { return 0.1; });
    ReducedBag bag(cal, Eigen::Isometry3d::Identity());
    bag.setGasMass(4.0e-3);
    bag.setTargetMass(4.6e-3, 1e-3);
    ASSERT_TRUE(bag.advance(0.5).converged);
    EXPECT_NEAR(bag.getGasMass(), 4.5e-3, 1e-15);
    EXPECT_NEAR(bag.getChamberState(0).volume * (bag.getGaugePressure() + cal->ambientPressure),
                4.5e-3 * cal->gasConstant * cal->temperature, 1e-9);
    bag.rollback();
    EXPECT_NEAR(bag.getGasMass(), 4.0e-3, 1e-15);
    ASSERT_TRUE(bag.advance(1.0).converged);
    EXPECT_NEAR(bag.getGasMass(), 4.6e-3, 1e-15);
    bag.commit();
    EXPECT_EQ(bag.getEnvelopeCounts().total(), 0);
    bag.setMassFlow(1e-3);
    ASSERT_TRUE(bag.advance(1.0).converged);  // 5.6 g: beyond 5 g
    bag.commit();
    EXPECT_EQ(bag.getEnvelopeCounts().mass, 1);
    EXPECT_NEAR(bag.getEnvelopeCounts().worstMass, 5.6e-3, 1e-15);
    // Slack below the fill mass: no gauge pressure (the smooth turn to taut is 100 Pa wide).
    bag.setGasMass(3.0e-3);
    EXPECT_LT(bag.getGaugePressure(), 1.0);
}

TEST(ReducedBag, ASlackBagPressedByALongShapeStaysAtAmbientUntilItsShapeFillsTheTautBagsDeficit) {
    // Reference (kappa = beta = 1): below its fill mass the film hangs slack under the taut
    // bag's top (here 20 mm lower at 3 g than the flat top at 100 mm of the taut 4 and 5 g).
    // A capsule of radius R lying along the bag, its axis R - delta above the taut top, takes
    // the circular segment A(delta) = R^2 acos(1 - delta / R) - (R - delta) sqrt(2 R delta -
    // delta^2) out of each column's length L of the taut bag. The gas stays at ambient
    // pressure while L A < V_free(0) - m R T / p_amb (90 mL here: delta 10.6 mm), and then
    // follows (P + p_amb)(V_free(P) - L A) = m R T. Tolerances: the gauge pressure below 1 Pa
    // at delta 6 mm (the slack turn is 100 Pa wide, its argument here below -15); the overlap
    // volume within 1 % of L A at 25 mm (a 1 mm grid); the gas law to 1e-9 relative.
    auto cal = makeCalibration(1e-3, [](double, double, double m) {
        return m < 3.5e-3 ? 0.08 : 0.1;  // the 3 g top sags
    });
    cal->rimWidth = 1e-4;
    ReducedBag bag(cal, Eigen::Isometry3d::Identity());
    const double R = 0.05, L = cal->nx * cal->pitch, m = 3e-3;
    const Eigen::Matrix3d along = rotation(Eigen::Vector3d(0.0, kPi / 2, 0.0));  // axis on x
    bag.addShape(bags::makeCapsule(R, 0.15));
    bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, 1.0), along));
    bag.setGasMass(m);
    const ReducedBagCalibration& c = *cal;
    const double slope =
        (c.volumes[2] - c.volumes[1]) / (c.gaugePressures[2] - c.gaugePressures[1]);
    auto vfree = [&](double P) { return c.volumes[1] + slope * (P - c.gaugePressures[1]); };
    const double mrt = m * c.gasConstant * c.temperature;
    ASSERT_NEAR(vfree(0.0) - mrt / c.ambientPressure, 90e-6, 1e-6);
    auto segment = [R](double d) {
        return R * R * std::acos(1.0 - d / R) - (R - d) * std::sqrt(2 * R * d - d * d);
    };
    // 6 mm: the shape takes 39 mL of the 90 mL the taut bag has to spare.
    bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, 0.1 + R - 0.006), along));
    ASSERT_TRUE(bag.advance(0.0).converged);
    EXPECT_NEAR(bag.getOverlapVolume(0), L * segment(0.006), 0.02 * L * segment(0.006));
    EXPECT_LT(bag.getGaugePressure(), 1.0);
    // 25 mm: 236 mL, the gas is compressed.
    bag.setShapeState(0, at(Eigen::Vector3d(0.0, 0.0, 0.1 + R - 0.025), along));
    ASSERT_TRUE(bag.advance(0.0).converged);
    const double V = bag.getOverlapVolume(0), P = bag.getGaugePressure();
    EXPECT_NEAR(V, L * segment(0.025), 0.01 * L * segment(0.025));
    EXPECT_GT(P, 3e3);
    EXPECT_NEAR((P + c.ambientPressure) * (vfree(P) - V), mrt, 1e-9 * mrt);
}

namespace {

// An ellipsoid pressed `depth` into a bag of the calibration (bisection on its height between
// 30 mm below the given point and 100 mm above it; further down it sinks below the top), with
// friction; the pose is committed (the film takes hold: the anchor at the pressure centroid).
Eigen::Vector3d pressWithFriction(ReducedBag& bag, double depth, const Eigen::Matrix3d& R,
                                  Eigen::Vector3d p) {
    double lo = p.z() - 0.03, hi = p.z() + 0.1;  // from deep in to clear above
    for (int it = 0; it < 60; ++it) {
        p.z() = 0.5 * (lo + hi);
        bag.setShapeState(0, at(p, R));
        bag.advance(0.0);
        (bag.getDepth(0) > depth ? lo : hi) = p.z();
    }
    bag.commit();
    return p;
}

ReducedBagFriction friction(double mu, double d, double tau) {
    ReducedBagFriction f;
    f.coefficient = mu;
    f.stickDistance = d;
    f.dampingTime = tau;
    return f;
}

}  // namespace

TEST(ReducedBag, FrictionSticksAsASpringUpToItsStickDistanceThenSlidesAtTheCoulombLimit) {
    // Reference: the law itself with the normal force N = |F_n| of the same state: a shape
    // translated by u along the flat top (tangential to its contact force) after the film took
    // hold carries f = -mu N u / d while |u| <= d, and mu N against the slide beyond it
    // (1e-12 relative). After a committed slide the anchor has followed (|s| = d): the same
    // pose gives the same force, and moving back by d frees it (1e-9 of mu N).
    auto cal = makeCalibration(2e-3, [](double, double, double) { return 0.06; });
    ReducedBag bag(cal, Eigen::Isometry3d::Identity());
    bag.addShape(bags::makeEllipsoid(Eigen::Vector3d(0.08, 0.05, 0.04)));
    bag.setGasMass(4.4e-3);
    const double mu = 0.4, d = 5e-3;
    bag.setFriction(friction(mu, d, 0.0));
    const Eigen::Vector3d p0 =
        pressWithFriction(bag, 0.012, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 0.09));
    EXPECT_EQ(bag.getFrictionForce(0).norm(), 0.0);  // anchored where it stands
    for (double travel : {1e-3, 3e-3, 12e-3}) {
        bag.setShapeState(0, at(p0 + Eigen::Vector3d(travel, 0.0, 0.0)));
        ASSERT_TRUE(bag.advance(0.0).converged);
        const Eigen::Vector3d f = bag.getFrictionForce(0);
        const Eigen::Vector3d Fn = bag.calcWrench(0).force - f;
        const double N = Fn.norm();
        EXPECT_GT(N, 10.0);
        EXPECT_LT(std::abs(Fn.x()), 1e-9 * N);  // symmetric: the normal force is vertical
        const double expected = travel <= d ? mu * N * travel / d : mu * N;
        EXPECT_NEAR(f.x(), -expected, 1e-12 * N) << "travel " << travel;
        EXPECT_NEAR(f.y(), 0.0, 1e-12 * N);
        EXPECT_EQ(bag.isSliding(0), travel > d);
    }
    // Slid 12 mm: committed, the anchor follows.
    bag.commit();
    const double slid = bag.getFrictionForce(0).x();
    ASSERT_TRUE(bag.advance(0.0).converged);
    EXPECT_NEAR(bag.getFrictionForce(0).x(), slid, 1e-9 * std::abs(slid));
    bag.setShapeState(0, at(p0 + Eigen::Vector3d(12e-3 - d, 0.0, 0.0)));
    ASSERT_TRUE(bag.advance(0.0).converged);
    EXPECT_LT(bag.getFrictionForce(0).norm(), 1e-9 * std::abs(slid));
    // A step rolled back leaves the committed anchor: the slid pose's force again.
    bag.rollback();
    EXPECT_NEAR(bag.getFrictionForce(0).x(), slid, 1e-9 * std::abs(slid));
    // Frictionless (the default) gives the normal force alone.
    bag.setFriction(ReducedBagFriction{});
    EXPECT_EQ(bag.getFrictionForce(0).norm(), 0.0);
}

TEST(ReducedBag, TheTangentWithFrictionMatchesFiniteDifferencesOfTheWrench) {
    // Reference: central differences of the wrench re-evaluated by advance() (the committed
    // anchor held; rotation 1e-6 rad, translation 1e-7 m), tolerance 1e-4 of the largest
    // entry. The curved top and factors of the frictionless tangent test; the shape tilted
    // and moving (the stick spring's damping), anchored 12 mm deep, then moved 2 mm (the
    // film sticks) and 9 mm (it slides) along and across the bag with a turn.
    for (double travel : {2e-3, 9e-3}) {
        auto cal = makeCalibration(2e-3, [](double x, double y, double m) {
            return 0.06 + 4.0 * (m - 3e-3) - 0.8 * x * x - 2.0 * y * y + 0.05 * x;
        });
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) {
                cal->pressureFactor(i, j) = 1.0 + 0.3 * j + 0.1 * i;
                cal->volumeFactor(i, j) = 1.2 - 0.1 * j + 0.05 * i;
            }
        cal->skirt = 0.5;
        ReducedBag bag(cal, Eigen::Isometry3d(Eigen::Translation3d(0.01, 0.0, 0.0)));
        bag.addShape(bags::makeEllipsoid(Eigen::Vector3d(0.08, 0.05, 0.04)));
        bag.setGasMass(4.4e-3);
        bag.setFriction(friction(0.4, 5e-3, 0.02));
        const Eigen::Matrix3d R0 = rotation(Eigen::Vector3d(0.3, -0.2, 0.4));
        const Eigen::Vector3d p0 =
            pressWithFriction(bag, 0.012, R0, Eigen::Vector3d(0.02, -0.01, 0.1));
        const Eigen::Vector3d p = p0 + travel * Eigen::Vector3d(0.8, 0.6, 0.0);
        const Eigen::Matrix3d R = rotation(Eigen::Vector3d(0.0, 0.0, 0.02)) * R0;
        auto moving = [](ShapeState s) {
            s.w_GS = Eigen::Vector3d(0.1, -0.2, 0.3);
            s.v_GS = Eigen::Vector3d(0.01, -0.02, 0.005);
            return s;
        };
        bag.setShapeState(0, moving(at(p, R)));
        ASSERT_TRUE(bag.advance(0.0).converged);
        ASSERT_EQ(bag.isSliding(0), travel > 5e-3);
        ASSERT_GT(bag.getFrictionForce(0).norm(), 1.0);
        const Mat6 T = bag.calcWrenchTangent(0);
        const Mat6 fd = finiteDifferenceTangent(
            bag, p, R,
            [&](const Eigen::Vector3d& q, const Eigen::Matrix3d& Q) { return moving(at(q, Q)); });
        const double scale = fd.cwiseAbs().maxCoeff();
        EXPECT_LT((T - fd).cwiseAbs().maxCoeff(), 1e-4 * scale)
            << "travel " << travel << "\nanalytic\n"
            << T << "\nfinite differences\n"
            << fd;
    }
}

TEST(ReducedBag, ItsStateWithFrictionAnchorsRoundTripsThroughACheckpoint) {
    // Reference: the bag that was not saved. A bag loaded from another's saved state gives the
    // same wrench, bit for bit, at the next pose (the anchors and velocities came along).
    auto cal = makeCalibration(2e-3, [](double, double, double) { return 0.06; });
    auto make = [&] {
        auto b = std::make_unique<ReducedBag>(cal, Eigen::Isometry3d::Identity());
        b->addShape(bags::makeEllipsoid(Eigen::Vector3d(0.08, 0.05, 0.04)));
        b->setGasMass(4.4e-3);
        b->setFriction(friction(0.4, 5e-3, 0.02));
        return b;
    };
    auto a = make();
    const Eigen::Vector3d p0 =
        pressWithFriction(*a, 0.012, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 0.09));
    ShapeState s = at(p0 + Eigen::Vector3d(7e-3, 1e-3, 0.0));
    s.v_GS = Eigen::Vector3d(0.01, 0.0, 0.0);
    a->setShapeState(0, s);
    a->advance(0.01);
    a->commit();
    bags::StateWriter w;
    a->saveState(w);
    auto b = make();
    bags::StateReader r(w.getData());
    b->loadState(r);
    s = at(p0 + Eigen::Vector3d(9e-3, 2e-3, 0.0));
    for (ReducedBag* bag : {a.get(), b.get()}) {
        bag->setShapeState(0, s);
        ASSERT_TRUE(bag->advance(0.01).converged);
    }
    EXPECT_GT(a->getFrictionForce(0).norm(), 1.0);
    EXPECT_EQ(a->calcWrench(0).asVector(), b->calcWrench(0).asVector());
}
