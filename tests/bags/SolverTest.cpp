// The model's total tangent (membrane + follower pressure + gas, including the dense rank-one
// gas term the solver adds by Sherman-Morrison-Woodbury) against finite differences, and the
// Newton solver's behaviour.
#include "TestMeshes.h"

#include <bags/Gas.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/EquilibriumSolver.h>

#include <gtest/gtest.h>

#include <Eigen/SparseCore>

#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <vector>

using namespace bags;

namespace {

Eigen::VectorXd totalGradient(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    acc.wantHessian = false;
    m.addEnergy(x, acc);
    return acc.grad;
}

// A wrinkling neo-Hookean box bag under 200 Pa with bending (1e-4 N m).
MembraneModel makeBendingBoxModel(const Mesh& mesh) {
    auto mat = std::make_shared<WrinklingMaterial>(makeNeoHookean(1e6), 1e-3);
    MembraneModel model(mesh, mat, 0.2e-3);
    model.setChamberPressure(0, 200.0);
    model.setBendingStiffness(1e-4);
    return model;
}

double totalEnergy(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    acc.wantHessian = false;
    m.addEnergy(x, acc);
    return acc.energy;
}

// Sparse tangent plus the rank-one gas terms -(dp/dV) g g^T, as the solver forms them.
Eigen::MatrixXd totalHessian(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    const int n = 3 * m.getMesh().getNumNodes();
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    m.addEnergy(x, acc);
    Eigen::SparseMatrix<double> H(n, n);
    H.setFromTriplets(acc.hess.begin(), acc.hess.end());
    Eigen::MatrixXd Hd(H);
    for (int g = 0; g < m.getNumGases(); ++g) {
        Eigen::VectorXd dV;
        const double V = m.calcGasVolume(g, x, &dV);
        Hd -= m.getGas(g).calcPressureDerivative(V) * dV * dV.transpose();
    }
    return Hd;
}

Eigen::Matrix3Xd perturbed(const Eigen::Matrix3Xd& x, double amplitude, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3Xd y = x;
    for (int i = 0; i < y.size(); ++i) y.data()[i] += amplitude * u(rng);
    return y;
}

MembraneModel makeGasSphere(double* V0) {
    Mesh mesh = makeSphere(0.05, 1);
    EXPECT_TRUE(test::fixSphereRigidModes(mesh));
    auto mat = std::make_shared<WrinklingMaterial>(makeYeoh(1e6, -1e4, 1e3), 1e-3);
    MembraneModel model(mesh, mat, 0.2e-3);
    *V0 = calcChamberVolume(mesh, 0, mesh.X);
    GasChamber gas(GasOptions(), 1.2 * GasOptions().getAmbientDensity() * *V0);
    gas.seal(*V0);
    model.addGas(gas, {0});
    return model;
}

}  // namespace

TEST(ModelTangent, GasAndFollowerPressureMatchFiniteDifferences) {
    double V0 = 0.0;
    const MembraneModel model = makeGasSphere(&V0);
    // 5 % stretched and 1 mm noise: taut, with some wrinkled elements.
    const Eigen::Matrix3Xd x = perturbed(1.05 * model.getMesh().X, 1e-3, 7);
    const Eigen::VectorXd g = totalGradient(model, x);
    const Eigen::MatrixXd H = totalHessian(model, x);
    const double h = 1e-7;
    Eigen::MatrixXd Hfd(H.rows(), H.cols());
    Eigen::VectorXd gfd(g.size());
    for (int k = 0; k < g.size(); ++k) {
        Eigen::Matrix3Xd xp = x, xm = x;
        xp.data()[k] += h;
        xm.data()[k] -= h;
        Hfd.col(k) = (totalGradient(model, xp) - totalGradient(model, xm)) / (2 * h);
        gfd(k) = (totalEnergy(model, xp) - totalEnergy(model, xm)) / (2 * h);
    }
    // Tolerances: central differences, 1e-5 relative (gas energy ~ p V is large, so the
    // energy difference loses more digits: 1e-4 there).
    EXPECT_LT((g - gfd).norm(), 1e-4 * g.norm());
    EXPECT_LT((H - Hfd).norm(), 1e-5 * H.norm());
}

TEST(Solver, NewtonConvergesQuadraticallyNearEquilibrium) {
    double V0 = 0.0;
    const MembraneModel model = makeGasSphere(&V0);
    // Solve once (from the reference shape, with the pseudo-transient start), then perturb
    // by 0.1 mm and re-solve: a full Newton with the exact tangent needs only a few steps.
    Eigen::Matrix3Xd x = model.getMesh().X;
    Mesh m = model.getMesh();
    SolverOptions so;
    SolveSummary s1 = solveEquilibrium(model, x, so);
    ASSERT_TRUE(s1.converged) << s1.residualNorm;
    Eigen::Matrix3Xd y = perturbed(x, 1e-4, 3);
    std::vector<double> r;  // the residual at each Newton iteration [N]
    so.monitor = [&r](int, double residual, double, double) { r.push_back(residual); };
    SolveSummary s2 = solveEquilibrium(model, y, so);
    ASSERT_TRUE(s2.converged);
    EXPECT_LE(s2.iterations, 8);
    // The rate: near the solution each step squares the error (the forcing term tightens with
    // the residual, so the inexact solve keeps the order). Over the last three residuals above
    // the round-off floor the estimated order log(r2/r1) / log(r1/r0) is at least 1.5, and the
    // last step gains at least two digits.
    std::vector<double> q;
    for (double v : r)
        if (v > 1e-10) q.push_back(v);
    ASSERT_GE(q.size(), 3u) << "too few iterations to see the rate";
    const size_t n = q.size();
    const double order = std::log(q[n - 1] / q[n - 2]) / std::log(q[n - 2] / q[n - 3]);
    std::ostringstream trace;
    for (double v : r) trace << v << " ";
    EXPECT_GE(order, 1.5) << "residuals: " << trace.str();
    EXPECT_LT(q[n - 1] / q[n - 2], 1e-2) << "residuals: " << trace.str();
    // The perturbed start returns to the same volume (unique equilibrium of the gas sphere).
    EXPECT_NEAR(calcChamberVolume(m, 0, y), calcChamberVolume(m, 0, x), 1e-9 * V0);
}

TEST(Solver, FixedDofsDoNotMove) {
    Mesh mesh = makeBoxBag(0.1, 0.1, 0.05, 0.02, true);
    ASSERT_FALSE(mesh.supportNodes.empty());
    auto mat = std::make_shared<WrinklingMaterial>(makeNeoHookean(1e6), 1e-3);
    MembraneModel model(mesh, mat, 0.2e-3);
    model.setChamberPressure(0, 200.0);
    Eigen::Matrix3Xd x = mesh.X;
    const SolveSummary s = solveEquilibrium(model, x, SolverOptions());
    EXPECT_TRUE(s.converged);
    for (int n : mesh.supportNodes) EXPECT_EQ((x.col(n) - mesh.X.col(n)).norm(), 0.0);
    EXPECT_GT(calcChamberVolume(mesh, 0, x), calcChamberVolume(mesh, 0, mesh.X));
}

TEST(Solver, RejectsBadOptionsAndNonFiniteStart) {
    SolverOptions so;
    so.maxIterations = 0;
    EXPECT_THROW(so.validate(), std::invalid_argument);
    Mesh mesh = makeBoxBag(0.1, 0.1, 0.05, 0.05, true);
    MembraneModel model(mesh, std::shared_ptr<MembraneMaterial>(makeNeoHookean(1e6)), 0.2e-3);
    Eigen::Matrix3Xd x = mesh.X;
    x(0, 0) = std::nan("");
    EXPECT_THROW(solveEquilibrium(model, x, SolverOptions()), NumericalError);
}

TEST(Solver, BendingTangentIsSolvedThroughItsSparsifiedFactorisation) {
    // With bending the solver factors the tangent without the couplings between nodes that
    // share no triangle and solves the whole tangent by CG with it: the same equilibrium as
    // the direct solve of the whole tangent (to the solve tolerance), reached with CG
    // iterations that the direct path does not take.
    const Mesh mesh = makeBoxBag(0.1, 0.1, 0.05, 0.02, true);
    const MembraneModel model = makeBendingBoxModel(mesh);
    auto solve = [&](bool sparsify, SolveSummary* s) {
        SolverOptions o;
        o.sparsifyWideCouplings = sparsify;
        o.reuseFactorization = false;  // every direction from a fresh factorisation
        Eigen::Matrix3Xd x = mesh.X;
        *s = solveEquilibrium(model, x, o);
        return x;
    };
    SolveSummary direct, sparse;
    const Eigen::Matrix3Xd xd = solve(false, &direct), xs = solve(true, &sparse);
    ASSERT_TRUE(direct.converged);
    ASSERT_TRUE(sparse.converged);
    // The direct path takes CG iterations only where its factorisation needed a raised
    // diagonal (an indefinite tangent on the way); the sparsified path on every direction.
    EXPECT_LT(direct.krylovIterations, sparse.krylovIterations);
    EXPECT_GT(sparse.krylovIterations, sparse.factorizations);
    EXPECT_LT((xd - xs).cwiseAbs().maxCoeff(), 1e-6);  // [m]
}

TEST(Solver, InexactNewtonReachesTheSameEquilibriumWithFewerKrylovIterations) {
    // CG to the forcing term 0.1 (tighter near convergence) against CG to 1e-4 of each
    // Newton residual: the same equilibrium within the solve tolerance (1e-3 N), fewer CG
    // iterations. Bending makes the sparsified path take CG on every direction.
    const Mesh mesh = makeBoxBag(0.1, 0.1, 0.05, 0.02, true);
    const MembraneModel model = makeBendingBoxModel(mesh);
    // From the inflated equilibrium moved by a smooth bump (the tangent definite on the way).
    Eigen::Matrix3Xd start = mesh.X;
    ASSERT_TRUE(solveEquilibrium(model, start, SolverOptions()).converged);
    const Vec3 c = start.rowwise().mean();
    std::vector<char> fixed(mesh.getNumNodes(), 0);
    for (int n : mesh.supportNodes) fixed[n] = 1;
    for (int i = 0; i < mesh.getNumNodes(); ++i)
        if (!fixed[i])
            start.col(i) +=
                2e-3 * std::exp(-(start.col(i) - c).squaredNorm() / 1e-3) * Vec3(0.3, -0.2, 1.0);
    auto solve = [&](double forcing, SolveSummary* s) {
        SolverOptions o;
        o.forcingTerm = forcing;
        o.absoluteTolerance = 1e-3;  // [N] as a bag's force tolerance, well above roundoff
        Eigen::Matrix3Xd x = start;
        *s = solveEquilibrium(model, x, o);
        return x;
    };
    SolveSummary tight, inexact;
    const Eigen::Matrix3Xd xt = solve(1e-4, &tight), xi = solve(0.1, &inexact);
    ASSERT_TRUE(tight.converged);
    ASSERT_TRUE(inexact.converged);
    EXPECT_LT(inexact.krylovIterations, tight.krylovIterations);
    EXPECT_LT((xt - xi).cwiseAbs().maxCoeff(), 1e-6);  // [m]
    std::printf("CG iterations: forcing 0.1 %d (%d Newton), 1e-4 %d (%d Newton)\n",
                inexact.krylovIterations, inexact.iterations, tight.krylovIterations,
                tight.iterations);
}

TEST(Solver, StabilisationSpringsAreWeightedPerNode) {
    // E = sum_i k A_i w_i |x_i - a_i|^2 / 2: nodes of weight 0 hold nothing, and the gradient
    // is k A_i w_i (x_i - a_i) (checked against central differences, 1e-6 relative).
    Mesh mesh = makeBoxBag(0.1, 0.1, 0.05, 0.05, true);
    MembraneModel model(mesh, std::shared_ptr<MembraneMaterial>(makeNeoHookean(1e6)), 0.2e-3);
    const double k = 1e5;
    const Eigen::Matrix3Xd anchor = mesh.X;
    std::vector<double> w(mesh.getNumNodes());
    for (int i = 0; i < mesh.getNumNodes(); ++i) w[i] = (i % 3 == 0) ? 0.0 : 0.5 * (i % 2 + 1);
    model.setStabilization(k, anchor, w);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1e-3, 1e-3);
    Eigen::Matrix3Xd x = anchor;
    for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
    const Eigen::VectorXd A = mesh.calcNodalAreas();
    double expected = 0.0;
    for (int i = 0; i < mesh.getNumNodes(); ++i)
        expected += 0.5 * k * A(i) * w[i] * (x.col(i) - anchor.col(i)).squaredNorm();
    EXPECT_NEAR(model.calcStabilizationEnergy(x), expected, 1e-12 * expected);
    // The model's gradient with and without the springs differs by the springs' gradient.
    auto grad = [&](const Eigen::Matrix3Xd& at) {
        EnergyAccumulator acc(mesh.getNumNodes());
        acc.wantHessian = false;
        model.addEnergy(at, acc);
        return Eigen::VectorXd(acc.grad);
    };
    const Eigen::VectorXd g = grad(x);
    model.setStabilization(0.0, anchor);
    const Eigen::VectorXd g0 = grad(x);
    model.setStabilization(k, anchor, w);
    for (int i = 0; i < mesh.getNumNodes(); ++i) {
        const Vec3 springs = (g - g0).segment<3>(3 * i);
        const Vec3 want = k * A(i) * w[i] * (x.col(i) - anchor.col(i));
        EXPECT_LE((springs - want).norm(), 1e-9 * (want.norm() + 1e-9)) << "node " << i;
    }
    // Central differences of the energy along a random direction.
    Eigen::Matrix3Xd dir(3, mesh.getNumNodes());
    for (int i = 0; i < dir.size(); ++i) dir.data()[i] = u(rng) * 1e3;
    const double h = 1e-7;
    const double fd =
        (model.calcStabilizationEnergy(x + h * dir) - model.calcStabilizationEnergy(x - h * dir)) /
        (2.0 * h);
    const double an = (g - g0).dot(Eigen::Map<const Eigen::VectorXd>(dir.data(), dir.size()));
    EXPECT_NEAR(fd, an, 1e-6 * std::abs(an));
    EXPECT_THROW(model.setStabilization(k, anchor, std::vector<double>(3, 1.0)),
                 std::invalid_argument);
}
