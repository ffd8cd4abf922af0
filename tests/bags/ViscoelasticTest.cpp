// The film's viscoelasticity (a Prony series on its stress, bags/Viscoelastic.h): the element's
// stress and tangent with history against finite differences, closed forms (step-strain
// relaxation, constant-rate ramp), the quasi-static and instantaneous limits on an inflated
// cushion, and the airbag: slow and fast presses, the hysteresis loop, g = 0 bit for bit, and
// its checkpoint.
#include "TestMeshes.h"

#include <bags/Airbag.h>
#include <bags/Geometry.h>
#include <bags/LoadTest.h>
#include <bags/Material.h>
#include <bags/MaterialFit.h>
#include <bags/EquilibriumSolver.h>
#include <bags/StVenantKirchhoff.h>
#include <bags/StateStream.h>
#include <bags/Viscoelastic.h>

#include <gtest/gtest.h>

#include <Eigen/SparseCore>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

using namespace bags;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

PronySeries makeProny(std::vector<PronyTerm> terms) {
    PronySeries p;
    p.terms = std::move(terms);
    return p;
}

std::shared_ptr<const MembraneMaterial> seedFilm() {
    return std::make_shared<WrinklingMaterial>(
        makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6), 1e-3);
}

EnergyAccumulator evaluate(const MembraneModel& m, const Eigen::Matrix3Xd& x, bool hessian) {
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    acc.wantHessian = hessian;
    m.addMembraneEnergy(x, acc);
    return acc;
}

Eigen::MatrixXd hessian(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    const int n = 3 * m.getMesh().getNumNodes();
    const EnergyAccumulator acc = evaluate(m, x, true);
    Eigen::SparseMatrix<double> H(n, n);
    H.setFromTriplets(acc.hess.begin(), acc.hess.end());
    return Eigen::MatrixXd(H);
}

// Uniform in-plane deformation of the flat patch: x = A X (A 3x3, z row zero).
Eigen::Matrix3Xd deform(const Mesh& mesh, double a11, double a22, double a12) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    A(0, 0) = a11;
    A(1, 1) = a22;
    A(0, 1) = a12;
    return A * mesh.X;
}

// One step of dt to x (no solve: the deformation is prescribed).
void step(MembraneModel& m, const Eigen::Matrix3Xd& x, double dt) {
    m.beginViscousStep(dt);
    m.endViscousStep(x);
}

}  // namespace

TEST(Prony, ValidatesItsTermsAndGivesTheStepScaleLimits) {
    EXPECT_NO_THROW(makeProny({{0.3, 10.0}, {0.2, 100.0}}).validate());
    EXPECT_THROW(makeProny({{-0.1, 10.0}}).validate(), std::invalid_argument);
    EXPECT_THROW(makeProny({{1.0, 10.0}}).validate(), std::invalid_argument);
    EXPECT_THROW(makeProny({{0.5, 10.0}, {0.5, 20.0}}).validate(), std::invalid_argument);
    EXPECT_THROW(makeProny({{0.1, 0.0}}).validate(), std::invalid_argument);
    EXPECT_THROW(makeProny({{0.1, 1e8}}).validate(), std::invalid_argument);
    EXPECT_THROW(makeProny({{0.1, std::nan("")}}).validate(), std::invalid_argument);
    EXPECT_FALSE(makeProny({{0.0, 10.0}}).isOn());
    const PronySeries p = makeProny({{0.3, 10.0}, {0.2, 100.0}});
    EXPECT_DOUBLE_EQ(p.getLongTermFraction(), 0.5);
    EXPECT_DOUBLE_EQ(p.calcStepScale(0.0), 2.0);   // 1 / g_inf: instantaneous
    EXPECT_DOUBLE_EQ(p.calcStepScale(kInf), 1.0);  // quasi-static: the long-term law
    EXPECT_NEAR(calcPronyPhi(1e-10), 1.0, 1e-10);
    EXPECT_NEAR(calcPronyPhi(2.0), (1 - std::exp(-2.0)) / 2.0, 1e-15);
}

// With history (a stretch, a hold, a release, a wrinkling shear) the step's energy is a
// potential in the end strain: the gradient matches central differences of the energy and the
// Hessian those of the gradient (1e-5 of their norms, as the elastic element's test), and the
// Hessian is symmetric (1e-12).
TEST(ViscoelasticElement, TangentMatchesFiniteDifferencesWithHistory) {
    MembraneModel model(test::makePatch(2, 0.1), seedFilm(), 0.2e-3);
    model.setProny(makeProny({{0.25, 5.0}, {0.15, 60.0}}));
    const Mesh& mesh = model.getMesh();
    step(model, deform(mesh, 1.04, 1.02, 0.0), 0.0);
    step(model, deform(mesh, 1.04, 1.02, 0.0), 3.0);
    step(model, deform(mesh, 1.06, 1.01, 0.01), 1.0);
    model.beginViscousStep(2.0);
    ASSERT_FALSE(model.isViscouslyRelaxed());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (double stretch : {1.03, 1.08, 0.97}) {  // taut, taut, partly wrinkled
        Eigen::Matrix3Xd x = deform(mesh, stretch, 1.0 + 0.5 * (stretch - 1.0), 0.0);
        for (int i = 0; i < x.cols(); ++i)
            for (int d = 0; d < 3; ++d) x(d, i) += 0.002 * u(rng);
        const Eigen::VectorXd g = evaluate(model, x, false).grad;
        const Eigen::MatrixXd H = hessian(model, x);
        const double h = 1e-7;
        Eigen::VectorXd gfd(g.size());
        Eigen::MatrixXd Hfd(H.rows(), H.cols());
        for (int k = 0; k < g.size(); ++k) {
            Eigen::Matrix3Xd xp = x, xm = x;
            xp.data()[k] += h;
            xm.data()[k] -= h;
            gfd(k) =
                (evaluate(model, xp, false).energy - evaluate(model, xm, false).energy) / (2 * h);
            Hfd.col(k) =
                (evaluate(model, xp, false).grad - evaluate(model, xm, false).grad) / (2 * h);
        }
        EXPECT_LT((g - gfd).norm(), 1e-5 * g.norm()) << "gradient vs FD at " << stretch;
        EXPECT_LT((H - Hfd).norm(), 1e-5 * H.norm()) << "Hessian vs FD at " << stretch;
        EXPECT_LT((H - H.transpose()).norm(), 1e-12 * H.norm()) << "symmetric at " << stretch;
        // The history matters: the elastic element's force differs.
        MembraneModel elastic(mesh, seedFilm(), 0.2e-3);
        EXPECT_GT((g - evaluate(elastic, x, false).grad).norm(), 1e-3 * g.norm());
    }
}

// g = 0 (or no terms) is the elastic element, bit for bit.
TEST(ViscoelasticElement, ZeroModuliGiveTheElasticElementBitForBit) {
    MembraneModel elastic(test::makePatch(3, 0.1), seedFilm(), 0.2e-3);
    MembraneModel zero(test::makePatch(3, 0.1), seedFilm(), 0.2e-3);
    zero.setProny(makeProny({{0.0, 10.0}}));
    EXPECT_FALSE(zero.hasProny());
    zero.beginViscousStep(1.0);
    const Eigen::Matrix3Xd x = deform(elastic.getMesh(), 1.05, 0.98, 0.02);
    const EnergyAccumulator a = evaluate(elastic, x, true), b = evaluate(zero, x, true);
    EXPECT_EQ(a.energy, b.energy);
    EXPECT_TRUE((a.grad.array() == b.grad.array()).all());
    ASSERT_EQ(a.hess.size(), b.hess.size());
    for (size_t i = 0; i < a.hess.size(); ++i) EXPECT_EQ(a.hess[i].value(), b.hess[i].value());
}

std::shared_ptr<const MembraneMaterial> linearFilm() {
    return std::make_shared<WrinklingMaterial>(makeStVenantKirchhoff(100e6, 0.3), 1e-3);
}

Mat2 calcC(const Eigen::Vector3d& a) {  // of deform(mesh, a(0), a(1), a(2))
    Mat2 C;
    C << a(0) * a(0), a(0) * a(2), a(0) * a(2), a(1) * a(1) + a(2) * a(2);
    return C;
}

// A sheet stretched at once (a step of no time) and held relaxes as the Prony series:
// S(t) / S(0) = G(t) = g_inf + sum g_i exp(-t / tau_i). For a linear film (St. Venant-
// Kirchhoff under the tension field, taut) exactly: 1e-12, in steps of any length (the
// exponential integrator is exact while the strain is held); equibiaxial, planar and sheared
// stretches, each stress component. Long after, the long-term stress S(0) g_inf. The seed's
// Yeoh at 1 % equibiaxial strain follows G(t) to 1 % of S(0) (the branches' law is nonlinear:
// G holds to first order in their strain).
TEST(Viscoelastic, StepStrainRelaxesAsThePronySeries) {
    const PronySeries prony = makeProny({{0.3, 4.0}, {0.2, 50.0}});
    struct Case {
        std::shared_ptr<const MembraneMaterial> film;
        Eigen::Vector3d stretch;
        double tolerance;
    };
    for (const Case& c : {Case{linearFilm(), Eigen::Vector3d(1.05, 1.05, 0.0), 1e-12},
                          Case{linearFilm(), Eigen::Vector3d(1.08, 1.0, 0.0), 1e-12},
                          Case{linearFilm(), Eigen::Vector3d(1.04, 1.02, 0.03), 1e-12},
                          Case{seedFilm(), Eigen::Vector3d(1.01, 1.01, 0.0), 1e-2}}) {
        MembraneModel model(test::makePatch(2, 0.1), c.film, 0.2e-3);
        model.setProny(prony);
        const Eigen::Vector3d& a = c.stretch;
        const Eigen::Matrix3Xd x = deform(model.getMesh(), a(0), a(1), a(2));
        step(model, x, 0.0);
        const Eigen::Vector3d S0 = model.calcElementStress(x, 0);
        ASSERT_GT(S0(0), 1e5);
        double t = 0.0;
        for (double dt : {0.5, 0.5, 1.0, 3.0, 7.0, 20.0, 40.0, 100.0}) {
            step(model, x, dt);
            t += dt;
            const Eigen::Vector3d S = model.calcElementStress(x, 0);
            const double G = prony.calcRelaxation(t);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(S(k), G * S0(k), c.tolerance * S0.norm()) << "t = " << t << " s";
        }
        step(model, x, 1e6);
        Eigen::Vector3d SL;
        model.getMaterial().calcEnergy(calcC(a), &SL, nullptr);
        EXPECT_NEAR((model.calcElementStress(x, 0) - SL).norm(), 0.0, 1e-9 * SL.norm());
        EXPECT_NEAR((S0 * prony.getLongTermFraction() - SL).norm(), 0.0, c.tolerance * SL.norm());
    }
}

// A constant Green-strain rate (E11 = r t, E22 = 0) against the closed form of the Maxwell
// branches: q_i(t) = r tau_i (1 - exp(-t / tau_i)), S = S_L(E) + sum k_i S_L(I + 2 q_i).
// The exponential integrator is exact for a strain linear in time, whatever the law: 1e-12 of
// S at steps of 0.7-5 s. For the linear film this is the convolution of the Prony series,
// S(t) = D r [t + sum k_i tau_i (1 - exp(-t / tau_i))] (checked too); for the seed's Yeoh it is
// the branches' own law.
TEST(Viscoelastic, ConstantStrainRateRampMatchesTheClosedForm) {
    const PronySeries prony = makeProny({{0.3, 4.0}, {0.2, 50.0}});
    const double ginf = prony.getLongTermFraction();
    for (const auto& film : {linearFilm(), seedFilm()}) {
        MembraneModel model(test::makePatch(2, 0.1), film, 0.2e-3);
        model.setProny(prony);
        const double r = 2e-3;  // [1/s]
        double t = 0.0;
        for (double dt : {0.7, 0.7, 2.0, 5.0, 5.0, 1.0, 3.0}) {
            t += dt;
            const Eigen::Matrix3Xd x =
                deform(model.getMesh(), std::sqrt(1.0 + 2.0 * r * t), 1.0, 0.0);
            step(model, x, dt);
            Eigen::Vector3d expected;
            film->calcEnergy((Mat2() << 1.0 + 2.0 * r * t, 0, 0, 1).finished(), &expected, nullptr);
            for (const PronyTerm& p : prony.terms) {
                const double q = r * p.tau * (1.0 - std::exp(-t / p.tau));
                Eigen::Vector3d Sb;
                film->calcEnergy((Mat2() << 1.0 + 2.0 * q, 0, 0, 1).finished(), &Sb, nullptr);
                expected += p.g / ginf * Sb;
            }
            const Eigen::Vector3d S = model.calcElementStress(x, 0);
            EXPECT_LT((S - expected).norm(), 1e-12 * expected.norm()) << "t = " << t;
            if (film == linearFilm() || film->getName() == linearFilm()->getName()) {
                // The Prony convolution of the linear film: (D E)_11 per E11 = Ebar / (1 - nu^2)
                // (1.001: the tension field's residual).
                double factor = t;
                for (const PronyTerm& p : prony.terms)
                    factor += p.g / ginf * p.tau * (1.0 - std::exp(-t / p.tau));
                const double D11 = 1.001 * 100e6 / (1.0 - 0.3 * 0.3);
                EXPECT_NEAR(S(0), D11 * r * factor, 1e-12 * D11 * r * factor);
            }
        }
    }
}

// The branches are films under the tension field too: a stretched and held sheet compressed
// at once carries no compression (its stress stays within the residual's 1e-3 of the
// stretched sheet's), where a Prony series added to the stress would push with k S_L.
TEST(Viscoelastic, CompressedBranchesWrinkleInsteadOfPushing) {
    MembraneModel model(test::makePatch(2, 0.1), seedFilm(), 0.2e-3);
    model.setProny(makeProny({{0.3, 10.0}}));
    const Eigen::Matrix3Xd stretched = deform(model.getMesh(), 1.03, 1.03, 0.0);
    step(model, stretched, 0.0);
    step(model, stretched, 5.0);
    const double S1 = model.calcElementStress(stretched, 0).norm();
    EXPECT_FALSE(model.isViscouslyRelaxed());
    const Eigen::Matrix3Xd compressed = deform(model.getMesh(), 0.99, 0.99, 0.0);
    step(model, compressed, 0.0);
    const Eigen::Vector3d S = model.calcElementStress(compressed, 0);
    EXPECT_LT(S.norm(), 2e-3 * S1);
}

namespace {

// The square cushion of the verification set (two sheets welded at the rim, St. Venant-
// Kirchhoff under the tension field), coarse, inflated by a prescribed pressure from flat in
// steps of dt; returns the chamber volume after each step (and the centre's rise at the end).
struct Cushion {
    Mesh mesh;
    std::vector<double> volumes;
    double rise = 0.0;
};

Cushion pressCushion(double youngsModulus, const PronySeries* prony,
                     const std::vector<double>& pressures, double dt) {
    Cushion c;
    c.mesh = makeSquareCushion(0.4, 8, 1e-3);
    const Vec3 centre = c.mesh.X.rowwise().mean();
    int top = -1;
    for (int i = 0; i < c.mesh.getNumNodes(); ++i) {
        const Vec3 p = c.mesh.X.col(i) - centre;
        if (std::abs(p.x()) < 1e-9) c.mesh.fixedDofs.push_back(3 * i + 0);
        if (std::abs(p.y()) < 1e-9) c.mesh.fixedDofs.push_back(3 * i + 1);
        if (std::abs(p.z()) < 1e-9) c.mesh.fixedDofs.push_back(3 * i + 2);
        if (std::abs(p.x()) < 1e-9 && std::abs(p.y()) < 1e-9 && p.z() > 0) top = i;
    }
    MembraneModel model(
        c.mesh,
        std::make_shared<WrinklingMaterial>(makeStVenantKirchhoff(youngsModulus, 0.4), 1e-3),
        0.6e-3);
    if (prony) model.setProny(*prony);
    Eigen::Matrix3Xd x = c.mesh.X;
    SolverOptions so;
    so.relativeTolerance = 1e-11;
    so.maxIterations = 200;
    for (double p : pressures) {
        model.setChamberPressure(0, p);
        model.beginViscousStep(dt);
        const SolveSummary sum = solveEquilibrium(model, x, so);
        EXPECT_TRUE(sum.converged) << "p = " << p << " residual " << sum.residualNorm;
        model.endViscousStep(x);
        c.volumes.push_back(calcChamberVolume(c.mesh, 0, x));
    }
    c.rise = x(2, top) - c.mesh.X(2, top);
    return c;
}

}  // namespace

// The cushion inflated from its stress-free flat sheets: in steps of no time it is the elastic
// cushion of the instantaneous modulus (E / g_inf), infinitely slowly the elastic cushion of
// the long-term modulus (to 1e-6 and 1e-9 of the volume: the solves' tolerance), and a pressure
// cycle at the relaxation time's pace leaves a loop: over the cycle the pressure does positive
// work, the energy the film dissipated (at least 1 % of the work of the loading branch), and the
// cushion ends larger than it started (the overstress still relaxing).
TEST(Viscoelastic, CushionIsInstantaneousWhenFastElasticWhenSlowAndDissipatesInACycle) {
    const PronySeries prony = makeProny({{0.4, 10.0}});
    const double E = 588e6 * 0.1, ginf = prony.getLongTermFraction();
    std::vector<double> up;
    for (int i = 1; i <= 8; ++i) up.push_back(250.0 * i);
    const Cushion fast = pressCushion(E, &prony, up, 0.0);
    const Cushion slow = pressCushion(E, &prony, up, kInf);
    const Cushion instantaneous = pressCushion(E / ginf, nullptr, up, 0.0);
    const Cushion longTerm = pressCushion(E, nullptr, up, 0.0);
    EXPECT_NEAR(fast.volumes.back(), instantaneous.volumes.back(),
                1e-6 * instantaneous.volumes.back());
    EXPECT_NEAR(slow.volumes.back(), longTerm.volumes.back(), 1e-9 * longTerm.volumes.back());
    EXPECT_LT(fast.volumes.back(), slow.volumes.back() - 1e-3 * slow.volumes.back());
    // A cycle: up and down in steps of 2 s (relaxation time 10 s).
    std::vector<double> cycle = up;
    for (int i = 7; i >= 0; --i) cycle.push_back(250.0 * i);
    const Cushion c = pressCushion(E, &prony, cycle, 2.0);
    double work = 0.0, loading = 0.0;  // trapezoidal int p dV
    for (size_t i = 1; i < cycle.size(); ++i) {
        const double dW = 0.5 * (cycle[i] + cycle[i - 1]) * (c.volumes[i] - c.volumes[i - 1]);
        work += dW;
        if (i < up.size()) loading += dW;
    }
    EXPECT_GT(work, 0.01 * loading) << "loop " << work << " J of " << loading << " J";
}

namespace {

// The seed's tiny taut rig as an Airbag: the 25 mm bag at 4.5 g, a 50 mm block over its top.
struct Rig {
    std::unique_ptr<Airbag> bag;
    int block = 0;
    double top = 0.0;
    Vec3 centre = Vec3::Zero();
};

LoadTestOptions rigOptions() {
    LoadTestOptions o;
    o.geometry.meshSize = 0.025;
    o.material = makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.gasMasses = {4.5e-3};
    return o;
}

Eigen::Isometry3d blockPose(const Vec3& centre, double bottom) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(centre.x(), centre.y(), bottom + 0.01);
    return X;
}

Rig makeRig(const PronySeries& prony) {
    LoadTestOptions o = rigOptions();
    o.prony = prony;
    Rig r;
    r.bag = std::make_unique<Airbag>(makeAirbagSpec(o));
    const Mesh& mesh = r.bag->getMesh();
    int top = 0;
    for (int i = 0; i < mesh.getNumNodes(); ++i)
        if (mesh.X(2, i) > mesh.X(2, top)) top = i;
    r.centre = Vec3(mesh.X(0, top), 0.0, 0.0);
    auto shape = std::shared_ptr<RigidShape>(makeBox(Vec3(0.025, 0.025, 0.01), 1e-3));
    shape->setPose(blockPose(r.centre, mesh.X.row(2).maxCoeff() + 0.2));
    r.block = r.bag->addShape(shape, o.blockContact);
    r.bag->inflate(o.gasMasses.front());
    const Eigen::Matrix3Xd& x = r.bag->getPositions();
    r.top = -kInf;
    for (int i = 0; i < x.cols(); ++i)
        if (std::abs(x(0, i) - r.centre.x()) <= 0.025 && std::abs(x(1, i)) <= 0.025)
            r.top = std::max(r.top, x(2, i));
    return r;
}

// Presses the block `depths` [m] in turn, each step taking dt [s]; the force after each.
std::vector<double> press(Rig& r, const std::vector<double>& depths, double dt) {
    std::vector<double> f;
    for (double d : depths) {
        r.bag->setShapePose(r.block, blockPose(r.centre, r.top - d));
        const AdvanceSummary s = r.bag->advance(dt, 6);
        EXPECT_TRUE(s.converged) << "depth " << d * 1e3 << " mm";
        r.bag->commit();
        f.push_back(r.bag->calcShapeWrench(r.block).force.z());
    }
    return f;
}

std::vector<double> depthsDownAndUp() {
    std::vector<double> d;
    for (int i = 1; i <= 16; ++i) d.push_back(0.5e-3 * i);
    for (int i = 15; i >= 1; --i) d.push_back(0.5e-3 * i);
    return d;
}

}  // namespace

// The rig's bag pressed 8 mm and released, 1 mm a step, relaxation time 10 s, g 0.4:
// - pressed infinitely slowly (steps of 1e9 s) it gives the elastic bag's forces (to 1e-3 N,
//   within the bag's force tolerance of the solve);
// - pressed fast (steps of 1 us) it is stiffer: the force at 8 mm higher by at least 2 %;
// - at the relaxation time's pace (steps of 2 s) the unloading branch lies below the loading
//   one: the loop's area (the work the block does over the cycle) is positive;
// - g = 0 gives the elastic bag's forces bit for bit.
TEST(ViscoelasticAirbag, SlowPressIsElasticFastPressIsStifferAndACycleDissipates) {
    const std::vector<double> depths = depthsDownAndUp();
    Rig elasticRig = makeRig(PronySeries());
    const std::vector<double> elastic = press(elasticRig, depths, 2.0);
    const PronySeries prony = makeProny({{0.4, 10.0}});
    Rig slowRig = makeRig(prony);
    const std::vector<double> slow = press(slowRig, depths, 1e9);
    Rig fastRig = makeRig(prony);
    const std::vector<double> fast = press(fastRig, depths, 1e-6);
    Rig paceRig = makeRig(prony);
    const std::vector<double> paced = press(paceRig, depths, 2.0);
    Rig zeroRig = makeRig(makeProny({{0.0, 10.0}}));
    const std::vector<double> zero = press(zeroRig, depths, 2.0);
    ASSERT_GT(elastic[15], 5.0);
    double loop = 0.0, elasticLoop = 0.0;
    for (size_t i = 0; i < depths.size(); ++i) {
        EXPECT_NEAR(slow[i], elastic[i], 1e-3) << "depth " << depths[i] * 1e3 << " mm";
        EXPECT_EQ(zero[i], elastic[i]);
        if (i > 0) {
            loop += 0.5 * (paced[i] + paced[i - 1]) * (depths[i] - depths[i - 1]);
            elasticLoop += 0.5 * (elastic[i] + elastic[i - 1]) * (depths[i] - depths[i - 1]);
        }
    }
    EXPECT_GT(fast[15], 1.02 * elastic[15]);
    // Unloading below loading at the same depth, by more than the solves' tolerance.
    for (int k = 1; k <= 15; ++k) EXPECT_LT(paced[15 + k], paced[15 - k] - 0.01) << k;
    EXPECT_GT(loop, 0.0);
    EXPECT_GT(loop, 20.0 * std::abs(elasticLoop));
}

// The internal variables are part of the bag's state: a rollback restores them, and a
// checkpoint (saveState / loadState) carries them, so that a bag loaded from one continues to
// the same bits as the bag that wrote it.
TEST(ViscoelasticAirbag, RollbackAndCheckpointCarryTheInternalVariables) {
    const PronySeries prony = makeProny({{0.4, 10.0}});
    const std::vector<double> first = {2e-3, 4e-3, 6e-3}, then = {5e-3, 3e-3};
    Rig a = makeRig(prony);
    press(a, first, 1.0);
    a.bag->resetCaches();
    StateWriter w;
    a.bag->saveState(w);
    const std::vector<double> afterA = press(a, then, 1.0);
    // Rolled back: from 5 mm a step of another length and depth, then the step to 3 mm again
    // from the commit (the predictor's increment is forgotten: the same state to the solve's
    // force tolerance, not to the bit).
    Rig a2 = makeRig(prony);
    press(a2, first, 1.0);
    press(a2, {then[0]}, 1.0);
    a2.bag->setShapePose(a2.block, blockPose(a2.centre, a2.top - 4e-3));
    ASSERT_TRUE(a2.bag->advance(30.0, 6).converged);
    a2.bag->rollback();
    a2.bag->setShapePose(a2.block, blockPose(a2.centre, a2.top - then[1]));
    ASSERT_TRUE(a2.bag->advance(1.0, 6).converged);
    EXPECT_NEAR(a2.bag->calcShapeWrench(a2.block).force.z(), afterA.back(), 2e-3);
    Rig b = makeRig(prony);
    StateReader r(w.getData());
    b.bag->loadState(r);
    const std::vector<double> afterB = press(b, then, 1.0);
    for (size_t i = 0; i < then.size(); ++i) EXPECT_EQ(afterB[i], afterA[i]);
    // A bag without the Prony terms does not read a checkpoint of one that has them.
    Rig c = makeRig(PronySeries());
    StateReader rc(w.getData());
    EXPECT_THROW(c.bag->loadState(rc), StateError);
}
