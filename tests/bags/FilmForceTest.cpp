// The explicit step's force kernel (bags/FilmForce.h) against the general path
// (MembraneModel::addEnergy without its Hessian): the same gradient and energy to roundoff
// for every term and every law it evaluates, and the same bits on any number of threads.
//
// Tolerance: 1e-12 of the largest nodal force of the general path's parts (the membrane with
// its bending, and the loads: gas, pressures, gravity, contacts), taken apart because at an
// equilibrium their sum is small where each part is not. The two paths sum in other orders
// (elements per node, hinges by their stiffness rows, the hinge angle's change rotated by the
// rest angle), so they agree to about 1e-15 of it, not bit for bit.
#include <bags/Bending.h>
#include <bags/Contact.h>
#include <bags/Dynamics.h>
#include <bags/FilmForce.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/StVenantKirchhoff.h>
#include <bags/Viscoelastic.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>

namespace bags {
namespace {

constexpr double kTolerance = 1e-12;

// The reference stretched by `stretch` about its centroid, every node moved by up to
// `amplitude` [m] at random in each direction: taut, wrinkled and slack elements side by side.
Eigen::Matrix3Xd shuffle(const Mesh& mesh, double stretch, double amplitude, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Vec3 centre = mesh.X.rowwise().mean();
    Eigen::Matrix3Xd x = mesh.X;
    for (int i = 0; i < x.cols(); ++i) {
        x.col(i) = centre + stretch * (Vec3(mesh.X.col(i)) - centre);
        for (int d = 0; d < 3; ++d) x(d, i) += amplitude * u(rng);
    }
    return x;
}

struct Comparison {
    double gradient = 0.0;  // largest difference over the largest part's force
    double energy = 0.0;    // difference over the sum of the parts' magnitudes
};

Comparison compare(const MembraneModel& model, const Eigen::Matrix3Xd& x) {
    const int nn = model.getMesh().getNumNodes();
    EnergyAccumulator general(nn), film(nn), loads(nn);
    general.wantHessian = film.wantHessian = loads.wantHessian = false;
    model.addEnergy(x, general);
    model.addMembraneEnergy(x, film);
    model.addLoadEnergy(x, loads);
    const double scale =
        std::max(film.grad.lpNorm<Eigen::Infinity>(), loads.grad.lpNorm<Eigen::Infinity>());
    const FilmForce kernel(model);
    EnergyAccumulator fast(nn);
    kernel.addGradient(x, fast, true);
    EnergyAccumulator fastNoEnergy(nn);
    kernel.addGradient(x, fastNoEnergy, false);
    EXPECT_TRUE(std::isnan(fastNoEnergy.energy));
    EXPECT_EQ(fastNoEnergy.grad, fast.grad);  // the energy changes nothing of the force
    Comparison c;
    c.gradient = (fast.grad - general.grad).lpNorm<Eigen::Infinity>() / scale;
    c.energy =
        std::abs(fast.energy - general.energy) / (std::abs(film.energy) + std::abs(loads.energy));
    return c;
}

std::string format(double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.3g", v);
    return s;
}

std::vector<int> countStates(const MembraneModel& model, const Eigen::Matrix3Xd& x) {
    std::vector<int> n(3, 0);
    for (int s : model.calcWrinkleStates(x)) ++n[s];
    return n;
}

std::shared_ptr<const MembraneMaterial> seedFilm() {
    return makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
}

TEST(FilmForce, EqualsTheGeneralGradientOnAShuffledBagWithTensionFieldBendingGasAndContact) {
    // The double wedge at 25 mm (two chambers: the diaphragm's triangles bound both, one gas
    // fills them), its seed film under the tension field, plate bending (the seams' rest
    // angles), gravity, a box pressed 3 mm into its top, self contact.
    DoubleWedgeParams p;
    p.meshSize = 0.025;
    const Mesh mesh = makeDoubleWedgeBag(p);
    MembraneModel model(mesh, std::make_shared<WrinklingMaterial>(seedFilm()->clone(), 1e-3),
                        0.2e-3);
    model.setBendingStiffness(calcPlateBendingStiffness(*seedFilm(), 0.2e-3));
    model.setGravity(1150.0, Vec3(0.0, 0.0, -9.81));
    double V0 = 0.0;
    for (int c = 0; c < static_cast<int>(mesh.chambers.size()); ++c)
        V0 += calcChamberVolume(mesh, c, mesh.X);
    GasChamber gas(GasOptions(), 1.1 * GasOptions().getAmbientDensity() * V0);
    gas.seal(V0);
    model.addGas(gas, {0, 1});
    const Eigen::Matrix3Xd x = shuffle(mesh, 1.02, 1.5e-3, 7);
    std::shared_ptr<RigidShape> box(makeBox(Vec3(0.04, 0.04, 0.01)));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(p.calcApexX(), 0.0, x.row(2).maxCoeff() + 0.01 - 0.003);
    box->setPose(X);
    std::vector<int> nodes(mesh.getNumNodes());
    for (size_t i = 0; i < nodes.size(); ++i) nodes[i] = static_cast<int>(i);
    auto contact = std::make_shared<RigidContact>(mesh, nodes, *box, RigidContact::Options());
    model.addRigidContact(contact);
    auto self = std::make_shared<SelfContact>(mesh, SelfContact::Options());
    self->updateCandidates(x);
    model.setSelfContact(self);
    ASSERT_GT(contact->getNumActive(x), 0);
    const std::vector<int> states = countStates(model, x);
    ASSERT_GT(states[0], 0);  // taut
    ASSERT_GT(states[1], 0);  // wrinkled
    ASSERT_GT(states[2], 0);  // slack
    EXPECT_TRUE(FilmForce(model).isLawInline());
    const Comparison c = compare(model, x);
    RecordProperty("gradient", format(c.gradient));
    RecordProperty("energy", format(c.energy));
    EXPECT_LT(c.gradient, kTolerance);
    EXPECT_LT(c.energy, kTolerance);
}

TEST(FilmForce, EqualsTheGeneralGradientOnACushionInSelfContact) {
    // Two sheets welded at their rim, 0.5 mm apart (inside the self contact's 1 mm), a plain
    // neo-Hookean film (no tension field), a prescribed pressure.
    const Mesh mesh = makeSquareCushion(0.1, 8, 0.5e-3);
    MembraneModel model(mesh, makeNeoHookean(1e6), 0.2e-3);
    model.setBendingStiffness(1e-5);
    model.setChamberPressure(0, 2e3);
    const Eigen::Matrix3Xd x = shuffle(mesh, 1.01, 0.1e-3, 11);
    auto self = std::make_shared<SelfContact>(mesh, SelfContact::Options());
    self->updateCandidates(x);
    model.setSelfContact(self);
    ASSERT_GT(self->getNumActive(x), 0);
    EXPECT_TRUE(FilmForce(model).isLawInline());
    const Comparison c = compare(model, x);
    EXPECT_LT(c.gradient, kTolerance);
    EXPECT_LT(c.energy, kTolerance);
}

TEST(FilmForce, EqualsTheGeneralGradientForEveryLawWithAndWithoutPronyBranches) {
    // The double wedge shuffled (the states of every regime), one gas, no bending: each law
    // alone, under the tension field (with the base's and with its own residual law), with
    // fabric yarns, with a continuation limit a stretched element passes, and two the kernel
    // does not run inline (Ogden, St. Venant-Kirchhoff: the virtual call).
    DoubleWedgeParams p;
    p.meshSize = 0.025;
    const Mesh mesh = makeDoubleWedgeBag(p);
    const Eigen::Matrix3Xd x = shuffle(mesh, 1.06, 1.5e-3, 3);
    FabricAnisotropy yarns;
    yarns.warpModulus = 2e7;
    yarns.weftModulus = 1e7;
    yarns.angle = 0.3;
    struct Case {
        const char* name;
        std::shared_ptr<const MembraneMaterial> material;
        bool inlineLaw;
    };
    const std::vector<Case> cases = {
        {"neo-Hooke", makeNeoHookean(5e6), true},
        {"Mooney-Rivlin", makeMooneyRivlin(4e6, 1e6), true},
        {"Yeoh", seedFilm(), true},
        {"Yeoh beyond its limit", makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6, 0.01), true},
        {"tension field (Yeoh)", std::make_shared<WrinklingMaterial>(seedFilm()->clone(), 1e-3),
         true},
        {"tension field, no residual",
         std::make_shared<WrinklingMaterial>(seedFilm()->clone(), 0.0), true},
        {"tension field, own residual",
         std::make_shared<WrinklingMaterial>(makeMooneyRivlin(4e6, 1e6), 1e-3, makeNeoHookean(5e6)),
         true},
        {"fabric on the tension field",
         makeRelaxedMaterial(FabricMaterial(seedFilm()->clone(), yarns), 1e-3), true},
        {"fabric on neo-Hooke", std::make_shared<FabricMaterial>(makeNeoHookean(5e6), yarns), true},
        {"tension field (Ogden)",
         std::make_shared<WrinklingMaterial>(makeOgden({5e6, 1e5}, {2.0, -2.0}), 1e-3), false},
        {"St. Venant-Kirchhoff", makeStVenantKirchhoff(3e7, 0.4), false},
    };
    PronySeries prony;
    prony.terms = {{0.3, 0.01}, {0.2, 1.0}};
    for (const Case& k : cases) {
        for (const bool viscous : {false, true}) {
            SCOPED_TRACE(std::string(k.name) + (viscous ? " with Prony branches" : ""));
            MembraneModel model(mesh, k.material, 0.2e-3);
            double V0 = 0.0;
            for (int c = 0; c < static_cast<int>(mesh.chambers.size()); ++c)
                V0 += calcChamberVolume(mesh, c, mesh.X);
            GasChamber gas(GasOptions(), GasOptions().getAmbientDensity() * V0);
            gas.seal(V0);
            model.addGas(gas, {0, 1});
            if (viscous) {
                // Branches strained by a first step to a nearby state, then the next step's
                // potential: the branch strains' offsets are not zero.
                model.setProny(prony);
                model.beginViscousStep(0.005);
                model.endViscousStep(shuffle(mesh, 1.03, 1e-3, 5));
                model.beginViscousStep(0.002);
                ASSERT_FALSE(model.isViscouslyRelaxed());
            }
            EXPECT_EQ(FilmForce(model).isLawInline(), k.inlineLaw);
            const Comparison c = compare(model, x);
            RecordProperty(std::string(k.name) + (viscous ? " prony" : ""),
                           format(c.gradient) + " " + format(c.energy));
            EXPECT_LT(c.gradient, kTolerance);
            EXPECT_LT(c.energy, kTolerance);
        }
    }
}

TEST(FilmForce, GivesTheSameBitsOnOneAndTwoThreads) {
    DoubleWedgeParams p;
    p.meshSize = 0.02;
    const Mesh mesh = makeDoubleWedgeBag(p);
    MembraneModel model(mesh, std::make_shared<WrinklingMaterial>(seedFilm()->clone(), 1e-3),
                        0.2e-3);
    model.setBendingStiffness(calcPlateBendingStiffness(*seedFilm(), 0.2e-3));
    model.setChamberPressure(0, 3e3);
    model.setChamberPressure(1, 2e3);
    model.setElementChunks(8);
    const Eigen::Matrix3Xd x = shuffle(mesh, 1.02, 1.5e-3, 13);
    const int nn = mesh.getNumNodes();
    model.setNumThreads(1);
    const FilmForce one(model);
    ASSERT_EQ(one.getNumThreads(), 1);
    EnergyAccumulator a(nn), b(nn);
    one.addGradient(x, a, true);
    model.setNumThreads(2);
    const FilmForce two(model);
    ASSERT_EQ(two.getNumThreads(), 2);
    two.addGradient(x, b, true);
    EXPECT_EQ(a.grad, b.grad);
    EXPECT_EQ(a.energy, b.energy);
    // And the step itself (FilmDynamics runs the kernel).
    DynamicOptions o;
    o.massScale = 1000.0;
    o.damping = 20.0;
    Eigen::Matrix3Xd x1 = x, x2 = x, v1 = Eigen::Matrix3Xd::Zero(3, nn), v2 = v1;
    model.setNumThreads(1);
    {
        const FilmDynamics film(model, 1150.0, o, 0.0);
        for (int k = 0; k < 5; ++k) film.step(x1, v1, 1e-5, a);
    }
    model.setNumThreads(2);
    {
        const FilmDynamics film(model, 1150.0, o, 0.0);
        for (int k = 0; k < 5; ++k) film.step(x2, v2, 1e-5, b);
    }
    EXPECT_EQ(x1, x2);
    EXPECT_EQ(v1, v2);
    EXPECT_NE(x1, x);  // it moved
}

TEST(FilmForce, Atan2IsStdAtan2WithinTwoUlpInEveryQuadrant) {
    // Reference: std::atan2 (correctly rounded or nearly); tolerance 2 ulp of the angle, over
    // random directions at scales from 1e-6 to 1e6, every octant's border, and small angles.
    std::mt19937 rng(17);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> logScale(-6.0, 6.0);
    auto check = [](double y, double x) {
        const double ref = std::atan2(y, x), got = calcAtan2(y, x);
        EXPECT_LE(std::abs(got - ref), 2.0 * std::numeric_limits<double>::epsilon() * std::abs(ref))
            << "y " << y << " x " << x << " atan2 " << ref << " got " << got;
    };
    for (int k = 0; k < 200000; ++k) {
        const double s = std::pow(10.0, logScale(rng));
        check(s * n(rng), s * n(rng));
        check(1e-9 * n(rng), 1.0 + 0.1 * n(rng));  // a hinge near its rest angle
    }
    for (const double t : {0.0, 0.3, 0.66, 0.6600000000000001, 1.0, 2.414213562373095, 2.5, 1e8})
        for (const double sy : {1.0, -1.0})
            for (const double sx : {1.0, -1.0}) {
                check(sy * t, sx * 1.0);
                check(sy * 1.0, sx * t);
            }
    EXPECT_EQ(calcAtan2(0.0, 0.0), 0.0);
}

TEST(FilmForce, ReportsACollapsedElementAndAVanishedGas) {
    DoubleWedgeParams p;
    p.meshSize = 0.025;
    const Mesh mesh = makeDoubleWedgeBag(p);
    MembraneModel model(mesh, std::make_shared<WrinklingMaterial>(seedFilm()->clone(), 1e-3),
                        0.2e-3);
    double V0 = 0.0;
    for (int c = 0; c < static_cast<int>(mesh.chambers.size()); ++c)
        V0 += calcChamberVolume(mesh, c, mesh.X);
    GasChamber gas(GasOptions(), GasOptions().getAmbientDensity() * V0);
    gas.seal(V0);
    model.addGas(gas, {0, 1});
    const FilmForce kernel(model);
    Eigen::Matrix3Xd x = mesh.X;
    const int e = 5;
    x.col(mesh.tris(2, e)) = x.col(mesh.tris(1, e));  // element 5 collapsed onto an edge
    EnergyAccumulator acc(mesh.getNumNodes());
    try {
        kernel.addGradient(x, acc);
        ADD_FAILURE() << "no error for a collapsed element";
    } catch (const NumericalError& err) {
        EXPECT_LE(err.getElement(), e);
        EXPECT_GE(err.getElement(), 0);
    }
    // Mirrored (z -> -z): every element as it was, the volume negative.
    Eigen::Matrix3Xd mirrored = mesh.X;
    mirrored.row(2) *= -1.0;
    try {
        kernel.addGradient(mirrored, acc);
        ADD_FAILURE() << "no error for a negative gas volume";
    } catch (const NumericalError& err) {
        EXPECT_NE(std::string(err.what()).find("gas volume"), std::string::npos) << err.what();
    }
}

}  // namespace
}  // namespace bags
