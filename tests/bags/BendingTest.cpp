// Bending of the membrane (DiscreteBending): the hinge angle's and the energy's derivatives
// against central finite differences, invariance under rigid motion and triangle orientation,
// zero energy and force in the reference configuration, the hinge rule at the double wedge's
// welds, the hook in MembraneModel, and the verification against the plate energy of a strip
// bent onto a cylinder (docs/verification.md).
#include "TestMeshes.h"

#include <bags/Bending.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/EquilibriumSolver.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <random>

using namespace bags;

namespace {

using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

constexpr double kD = 1.68e-4;  // [N m] the seed film's plate value

// A hinge on edge x0 = 0, x1 = (1,0,0), wing x2 in the x-y plane, wing x3 turned by `fold`
// about the edge; all four nodes jittered by up to 0.1.
void makeHinge(double fold, std::mt19937& rng, Vec3 x[4]) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    x[0] = Vec3(0, 0, 0);
    x[1] = Vec3(1.0, 0, 0);
    x[2] = Vec3(0.4, 0.8, 0.0);
    x[3] = Vec3(0.6, -0.9 * std::cos(fold), 0.9 * std::sin(fold));
    for (int k = 0; k < 4; ++k) x[k] += 0.1 * Vec3(u(rng), u(rng), u(rng));
}

double energyOf(const DiscreteBending& b, const Eigen::Matrix3Xd& x) { return b.calcEnergy(x); }

Eigen::VectorXd gradientOf(const DiscreteBending& b, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(static_cast<int>(x.cols()));
    acc.wantHessian = false;
    b.addEnergy(x, acc);
    return acc.grad;
}

Eigen::MatrixXd hessianOf(const DiscreteBending& b, const Eigen::Matrix3Xd& x) {
    const int n = static_cast<int>(3 * x.cols());
    EnergyAccumulator acc(static_cast<int>(x.cols()));
    b.addEnergy(x, acc);
    Eigen::SparseMatrix<double> H(n, n);
    H.setFromTriplets(acc.hess.begin(), acc.hess.end());
    return Eigen::MatrixXd(H);
}

// Gradient = FD(energy) and Hessian = FD(gradient), column by column, at x (scale: the
// largest entry of each).
void checkTangents(const DiscreteBending& b, const Eigen::Matrix3Xd& x, double tol) {
    const Eigen::VectorXd g = gradientOf(b, x);
    const Eigen::MatrixXd H = hessianOf(b, x);
    const double h = 1e-6 * (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).maxCoeff();
    Eigen::VectorXd gfd(g.size());
    Eigen::MatrixXd Hfd(H.rows(), H.cols());
    for (int k = 0; k < g.size(); ++k) {
        Eigen::Matrix3Xd xp = x, xm = x;
        xp.data()[k] += h;
        xm.data()[k] -= h;
        gfd(k) = (energyOf(b, xp) - energyOf(b, xm)) / (2 * h);
        Hfd.col(k) = (gradientOf(b, xp) - gradientOf(b, xm)) / (2 * h);
    }
    EXPECT_GT(g.norm(), 0.0);
    EXPECT_LT((g - gfd).cwiseAbs().maxCoeff(), tol * g.cwiseAbs().maxCoeff());
    EXPECT_LT((H - Hfd).cwiseAbs().maxCoeff(), tol * H.cwiseAbs().maxCoeff());
    EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
}

Eigen::Matrix3Xd perturbed(const Mesh& mesh, double amplitude, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3Xd x = mesh.X;
    for (int i = 0; i < x.cols(); ++i)
        for (int d = 0; d < 3; ++d) x(d, i) += amplitude * u(rng);
    return x;
}

// Flat strip [0, lx] x [0, ly] of nx x ny cells, each cut along its (0,0)-(1,1) diagonal (a
// regular three-direction grid: the two triangles at every edge form a parallelogram) or, if
// `alternate`, along alternating diagonals (the test patch's and the double wedge's pattern).
Mesh makeStrip(int nx, int ny, double lx, double ly, bool alternate = false) {
    return test::makeGrid(nx, ny, lx, ly, alternate);
}

// The flat mesh rolled onto a cylinder of radius R whose axis lies in the plane at angle beta
// to x (isometric: the arc length across the axis is kept).
Eigen::Matrix3Xd rollOntoCylinder(const Mesh& mesh, double R, double beta) {
    const Vec3 across(-std::sin(beta), std::cos(beta), 0.0);  // bending direction
    Eigen::Matrix3Xd x = mesh.X;
    for (int i = 0; i < x.cols(); ++i) {
        const double s = mesh.X.col(i).dot(across);
        x.col(i) += (R * std::sin(s / R) - s) * across + Vec3(0, 0, R * (1 - std::cos(s / R)));
    }
    return x;
}

}  // namespace

TEST(HingeAngle, GradientAndHessianMatchFiniteDifferences) {
    // Near flat (1e-3 rad), moderate, strongly folded both ways (+-2.6 rad); |theta| < pi.
    std::mt19937 rng(7);
    for (double fold : {1e-3, 0.3, -0.8, 1.5, 2.6, -2.6}) {
        Vec3 x[4];
        makeHinge(fold, rng, x);
        Vec12 g;
        Mat12 H;
        const double theta = calcHingeAngle(x[0], x[1], x[2], x[3], &g, &H);
        EXPECT_LT(std::abs(theta), M_PI);
        const double h = 1e-6;
        for (int k = 0; k < 12; ++k) {
            Vec3 p[4] = {x[0], x[1], x[2], x[3]}, m[4] = {x[0], x[1], x[2], x[3]};
            p[k / 3](k % 3) += h;
            m[k / 3](k % 3) -= h;
            Vec12 gp, gm;
            const double tp = calcHingeAngle(p[0], p[1], p[2], p[3], &gp);
            const double tm = calcHingeAngle(m[0], m[1], m[2], m[3], &gm);
            EXPECT_NEAR(g(k), (tp - tm) / (2 * h), 1e-8) << "fold " << fold << " dof " << k;
            for (int j = 0; j < 12; ++j)
                EXPECT_NEAR(H(j, k), (gp(j) - gm(j)) / (2 * h), 1e-7)
                    << "fold " << fold << " (" << j << "," << k << ")";
        }
    }
}

TEST(HingeAngle, SignAndValueOfAKnownFold) {
    // Wing x3 lifted by 30 degrees along its normal (x3 - x0) x (x1 - x0) = +z: theta = -30 deg.
    const double phi = M_PI / 6;
    const Vec3 x0(0, 0, 0), x1(1, 0, 0), x2(0.5, 1, 0), x3(0.5, -std::cos(phi), std::sin(phi));
    EXPECT_NEAR(calcHingeAngle(x0, x1, x2, x3), -phi, 1e-14);
    EXPECT_NEAR(calcHingeAngle(x0, x1, x2, Vec3(0.5, -std::cos(phi), -std::sin(phi))), phi, 1e-14);
    // Symmetric in the two triangles (consistently oriented).
    EXPECT_NEAR(calcHingeAngle(x1, x0, x3, x2), -phi, 1e-14);
}

TEST(DiscreteBending, TangentsMatchFiniteDifferencesOnPerturbedPatch) {
    const Mesh mesh = test::makePatch(4, 0.1);
    BendingOptions o;
    o.stiffness = kD;
    const DiscreteBending b(mesh, o);
    EXPECT_EQ(b.getNumHinges(), 40);  // 3 n^2 - 2 n interior edges of an n x n patch
    checkTangents(b, perturbed(mesh, 0.002, 1), 1e-6);  // near flat
    checkTangents(b, perturbed(mesh, 0.02, 2), 1e-6);   // strongly folded (hinges up to ~2 rad)
    Eigen::Matrix3Xd x = rollOntoCylinder(mesh, 0.03, 0.4);  // rolled 190 degrees, perturbed
    x += perturbed(mesh, 0.002, 3) - mesh.X;
    checkTangents(b, x, 1e-6);
    o.poisson = 0.0;
    checkTangents(DiscreteBending(mesh, o), perturbed(mesh, 0.01, 4), 1e-6);
}

TEST(DiscreteBending, TangentsMatchFiniteDifferencesOnDoubleWedgeSeams) {
    // Seams with their 3D rest angles and the welds where three sheets meet.
    DoubleWedgeParams p;
    p.meshSize = 0.04;
    const Mesh mesh = makeDoubleWedgeBag(p);
    BendingOptions o;
    o.stiffness = kD;
    const DiscreteBending b(mesh, o);
    checkTangents(b, perturbed(mesh, 0.004, 5), 1e-6);
}

TEST(DiscreteBending, ZeroEnergyAndForceInReferenceConfiguration) {
    DoubleWedgeParams p;
    p.meshSize = 0.02;
    const Mesh wedge = makeDoubleWedgeBag(p);
    for (const Mesh& mesh : {test::makePatch(6, 0.1), wedge, makeSphere(0.1, 2)}) {
        BendingOptions o;
        o.stiffness = kD;
        const DiscreteBending b(mesh, o);
        EnergyAccumulator acc(mesh.getNumNodes());
        b.addEnergy(mesh.X, acc);
        EXPECT_EQ(acc.energy, 0.0);
        EXPECT_LT(acc.grad.cwiseAbs().maxCoeff(), 1e-18);
        // Moved rigidly, still stress free.
        const Eigen::Matrix3d Q =
            Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
        const Eigen::Matrix3Xd y = (Q * mesh.X).colwise() + Vec3(0.3, -0.2, 1.0);
        EXPECT_LT(b.calcEnergy(y), 1e-24);
    }
}

TEST(DiscreteBending, InvariantUnderRigidMotion) {
    const Mesh mesh = test::makePatch(5, 0.1);
    BendingOptions o;
    o.stiffness = kD;
    const DiscreteBending b(mesh, o);
    const Eigen::Matrix3Xd x = perturbed(mesh, 0.01, 11);
    const Eigen::Matrix3d Q =
        Eigen::AngleAxisd(2.1, Vec3(-1, 0.5, 2).normalized()).toRotationMatrix();
    const Eigen::Matrix3Xd y = (Q * x).colwise() + Vec3(1.0, 2.0, -3.0);
    const double E = b.calcEnergy(x);
    EXPECT_GT(E, 0.0);
    EXPECT_NEAR(b.calcEnergy(y), E, 1e-12 * E);
    // Forces turn with the body; they have no net force or moment.
    const Eigen::VectorXd gx = gradientOf(b, x), gy = gradientOf(b, y);
    const Eigen::Map<const Eigen::Matrix3Xd> fx(gx.data(), 3, x.cols()), fy(gy.data(), 3, x.cols());
    EXPECT_LT((Q * fx - fy).cwiseAbs().maxCoeff(), 1e-10 * fx.cwiseAbs().maxCoeff());
    Vec3 moment = Vec3::Zero();
    for (int i = 0; i < x.cols(); ++i) moment += x.col(i).cross(fx.col(i));
    EXPECT_LT(fx.rowwise().sum().norm(), 1e-12 * fx.cwiseAbs().maxCoeff());
    EXPECT_LT(moment.norm(), 1e-12 * fx.cwiseAbs().maxCoeff());
    // The Hessian has the six rigid modes in its null space.
    const Eigen::MatrixXd H = hessianOf(b, x);
    for (int mode = 0; mode < 6; ++mode) {
        Eigen::Matrix3Xd v(3, x.cols());
        for (int i = 0; i < x.cols(); ++i)
            v.col(i) = mode < 3 ? Vec3::Unit(mode) : Vec3(Vec3::Unit(mode - 3).cross(x.col(i)));
        const Eigen::Map<const Eigen::VectorXd> vv(v.data(), v.size());
        // A rotation mode is in the null space of H only at equilibrium; in general H v equals
        // the gradient's turn, -(mode axis) x f per node.
        Eigen::VectorXd expected = Eigen::VectorXd::Zero(vv.size());
        if (mode >= 3)
            for (int i = 0; i < x.cols(); ++i)
                expected.segment<3>(3 * i) = Vec3::Unit(mode - 3).cross(fx.col(i));
        EXPECT_LT((H * vv - expected).cwiseAbs().maxCoeff(), 1e-8 * H.cwiseAbs().maxCoeff())
            << "mode " << mode;
    }
}

TEST(DiscreteBending, IndependentOfTriangleOrientation) {
    // Flipping triangles (some hinges then join inconsistently oriented triangles) changes
    // nothing: the curvature each triangle sees turns with its normal.
    const Mesh mesh = test::makePatch(4, 0.1);
    Mesh flipped = mesh;
    for (int t = 0; t < flipped.getNumTris(); t += 3)
        std::swap(flipped.tris(1, t), flipped.tris(2, t));
    BendingOptions o;
    o.stiffness = kD;
    const DiscreteBending a(mesh, o), b(flipped, o);
    const Eigen::Matrix3Xd x = perturbed(mesh, 0.01, 21);
    EXPECT_NEAR(b.calcEnergy(x), a.calcEnergy(x), 1e-12 * a.calcEnergy(x));
    EXPECT_LT((gradientOf(b, x) - gradientOf(a, x)).cwiseAbs().maxCoeff(),
              1e-10 * gradientOf(a, x).cwiseAbs().maxCoeff());
}

TEST(DiscreteBending, HingesAtWeldsFollowThePanelRule) {
    DoubleWedgeParams p;
    p.meshSize = 0.02;
    const Mesh mesh = makeDoubleWedgeBag(p);
    BendingOptions o;
    o.stiffness = kD;
    const DiscreteBending withSeams(mesh, o);
    o.seamsBend = false;
    const DiscreteBending noSeams(mesh, o);
    // Count the edges by the number of their triangles and the panels there.
    std::map<std::pair<int, int>, std::vector<int>> edges;
    for (int t = 0; t < mesh.getNumTris(); ++t)
        for (int i = 0; i < 3; ++i) {
            const int a = mesh.tris(i, t), b = mesh.tris((i + 1) % 3, t);
            edges[{std::min(a, b), std::max(a, b)}].push_back(mesh.triPanel[t]);
        }
    int manifold = 0, seams = 0, weldHinges = 0;
    for (const auto& [e, panels] : edges) {
        if (panels.size() == 2) {
            ++manifold;
            if (panels[0] != panels[1]) ++seams;
        } else if (panels.size() > 2) {
            for (int panel : std::set<int>(panels.begin(), panels.end()))
                if (std::count(panels.begin(), panels.end(), panel) == 2) ++weldHinges;
        }
    }
    EXPECT_GT(seams, 0);
    EXPECT_GT(weldHinges, 0);
    EXPECT_EQ(withSeams.getNumHinges(), manifold + weldHinges);
    EXPECT_EQ(noSeams.getNumHinges(), manifold - seams + weldHinges);
    // A seam's rest angle is its angle in X.
    double largest = 0.0;
    for (int h = 0; h < withSeams.getNumHinges(); ++h)
        largest = std::max(largest, std::abs(withSeams.getRestAngle(h)));
    // The largest is where the gentle side meets the base: pi minus the gentle side's slope.
    const double slope = std::atan2(p.height, p.longSide - p.calcApexX());
    EXPECT_NEAR(largest, M_PI - slope, 1e-9);
}

TEST(DiscreteBending, PlateStiffnessOfTheSeedFilm) {
    // D = E t^3 / (12 (1 - nu^2)), E = 6 C10 = 189.5 MPa, t = 0.2 mm, nu = 0.5: 1.6846e-4 N m.
    const double C10 = 31.587917e6, t = 0.2e-3;
    const double D = 6 * C10 * t * t * t / (12 * 0.75);
    EXPECT_NEAR(D, 1.6846e-4, 1e-8);
    EXPECT_NEAR(calcPlateBendingStiffness(6 * C10, 0.5, t), D, 1e-15);
    const auto yeoh = makeYeoh(C10, -0.76582566e6, -3.06587618e6);
    EXPECT_NEAR(calcPlateBendingStiffness(*yeoh, t), D, 1e-15);
    EXPECT_THROW(calcPlateBendingStiffness(-1.0, 0.3, t), std::invalid_argument);
    EXPECT_THROW(calcPlateBendingStiffness(1e6, 1.0, t), std::invalid_argument);
}

TEST(MembraneModel, BendingStiffnessAddsTheBendingEnergy) {
    const Mesh mesh = test::makePatch(4, 0.1);
    MembraneModel model(mesh, std::shared_ptr<const MembraneMaterial>(makeNeoHookean(1e6)), 2e-4);
    EXPECT_EQ(model.getBendingStiffness(), 0.0);
    const Eigen::Matrix3Xd x = perturbed(mesh, 0.005, 31);
    EnergyAccumulator plain(mesh.getNumNodes()), bent(mesh.getNumNodes());
    model.addMembraneEnergy(x, plain);
    model.setBendingStiffness(kD);
    EXPECT_EQ(model.getBendingStiffness(), kD);
    model.addMembraneEnergy(x, bent);
    BendingOptions o;
    o.stiffness = kD;
    const DiscreteBending b(mesh, o);
    EXPECT_NEAR(bent.energy - plain.energy, b.calcEnergy(x), 1e-12 * bent.energy);
    EXPECT_LT((bent.grad - plain.grad - gradientOf(b, x)).cwiseAbs().maxCoeff(),
              1e-10 * bent.grad.cwiseAbs().maxCoeff());
    EXPECT_THROW(model.setBendingStiffness(-1.0), std::invalid_argument);
    model.setBendingStiffness(0.0);
    EXPECT_EQ(model.getBendingStiffness(), 0.0);
}

// VERIFICATION. A flat 100 mm x 50 mm strip rolled onto a cylinder of radius R = 50 mm
// (isometric): the plate energy is D / (2 R^2) per area. Axis along the grid's y lines: each
// triangle's curvature is exact (its one folded hinge turns by exactly h / R) and the only
// error is the band of half a column along the two free edges across the bend, whose
// triangles see no hinge: E / E_exact = 1 - h / L to roundoff (tolerance 1e-10).
// Oblique axis (30 degrees to the grid), regular grid: the error falls as O(h) (the free-edge
// band), measured orders 0.90-0.99; tolerance |E / E_exact - 1| < 1.5 h / L at every mesh and
// an observed order > 0.8 between the two finest meshes (figures in docs/verification.md).
TEST(DiscreteBendingVerification, StripRolledOntoCylinderConvergesToPlateEnergy) {
    const double L = 0.1, W = 0.05, R = 0.05;
    const double exactPerArea = kD / (2 * R * R);
    BendingOptions o;
    o.stiffness = kD;
    for (int nx : {8, 16, 32, 64}) {
        const Mesh mesh = makeStrip(nx, nx / 2, L, W);
        const DiscreteBending b(mesh, o);
        const double ratio =
            b.calcEnergy(rollOntoCylinder(mesh, R, M_PI / 2)) / (exactPerArea * L * W);
        EXPECT_NEAR(ratio, 1.0 - 1.0 / nx, 1e-10) << "nx " << nx;
        std::printf("aligned  h = %6.3f mm: E/E_exact = %.6f\n", 1e3 * L / nx, ratio);
    }
    for (bool alternate : {false, true}) {
        double previous = 0.0;
        for (int nx : {8, 16, 32, 64, 128}) {
            const Mesh mesh = makeStrip(nx, nx / 2, L, W, alternate);
            const DiscreteBending b(mesh, o);
            const double ratio = b.calcEnergy(rollOntoCylinder(mesh, R, M_PI / 2 + M_PI / 6)) /
                                 (exactPerArea * L * W);
            const double error = std::abs(ratio - 1.0);
            const double order = previous > 0.0 ? std::log2(previous / error) : 0.0;
            std::printf("oblique %s h = %6.3f mm: E/E_exact = %.6f, error %.2e, order %.2f\n",
                        alternate ? "alternating" : "regular    ", 1e3 * L / nx, ratio, error,
                        order);
            if (!alternate) {
                EXPECT_LT(error, 1.5 / nx) << "nx " << nx;
                if (nx == 128) {
                    EXPECT_GT(order, 0.8);
                }
            }
            // Known defect, pinned: where the two triangles of a hinge are mirror images
            // (alternating diagonals) the averaged mid-edge slopes miss the triangles'
            // interpolation error and an oblique bend converges to 1.55 E_exact.
            if (alternate && nx == 128) {
                EXPECT_NEAR(ratio, 1.553, 0.01);
            }
            previous = error;
        }
    }
}
