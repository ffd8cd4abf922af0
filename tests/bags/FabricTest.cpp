// Fabric anisotropy (bags::FabricMaterial, docs/materials.md#fabric-anisotropy): the woven
// film's warp and weft yarns on the tension-field matrix. Stress and tangent against finite
// differences (taut, wrinkled, slack; yarns stretched and compressed), the element's tangent,
// closed forms of a single element stretched along the warp, the weft and the bias, the warp
// directions of the double wedge's panels, and the isotropic film unchanged when it is off.
#include <bags/Airbag.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/MaterialFit.h>
#include <bags/EquilibriumSolver.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <cmath>
#include <random>

#include "MaterialTestUtil.h"
#include "TestMeshes.h"

using namespace bags;
using bags::test::kC10;
using bags::test::kC20;
using bags::test::kC30;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kE = 6.0 * kC10;  // the seed film's small-strain Young's modulus 3 mu [Pa]

FabricAnisotropy makeYarns(double warp, double weft, double angle) {
    FabricAnisotropy y;
    y.warpModulus = warp;
    y.weftModulus = weft;
    y.angle = angle;
    return y;
}

// The element's material: the tension field on the seed's Yeoh, yarns added.
std::unique_ptr<MembraneMaterial> makeFabric(double warp, double weft, double angle) {
    const FabricMaterial base(makeYeoh(kC10, kC20, kC30), makeYarns(warp, weft, angle));
    return makeRelaxedMaterial(base, 1e-3);
}

// The yarn's Green strain along unit (cos t, sin t) at C.
double yarnStrain(const Mat2& C, double t) {
    const Eigen::Vector2d a(std::cos(t), std::sin(t));
    return 0.5 * (a.dot(C * a) - 1.0);
}

// S = S_matrix + k <E_a> a a^T per family, from the formula (not through FabricMaterial).
Eigen::Vector3d expectedStress(const MembraneMaterial& matrix, const Mat2& C, double kw, double kf,
                               double angle) {
    Eigen::Vector3d S;
    matrix.calcEnergy(C, &S, nullptr);
    for (int f = 0; f < 2; ++f) {
        const double t = angle + f * 0.5 * kPi, k = f == 0 ? kw : kf;
        const double E = std::max(yarnStrain(C, t), 0.0);
        const double c = std::cos(t), s = std::sin(t);
        S += k * E * Eigen::Vector3d(c * c, s * s, c * s);
    }
    return S;
}

// Expects a and b to give the same W, S and D at C, bit for bit.
void expectSameBits(const MembraneMaterial& a, const MembraneMaterial& b, const Mat2& C) {
    Eigen::Vector3d Sa, Sb;
    Eigen::Matrix3d Da, Db;
    EXPECT_EQ(a.calcEnergy(C, &Sa, &Da), b.calcEnergy(C, &Sb, &Db));
    EXPECT_EQ(Sa, Sb);
    EXPECT_EQ(Da, Db);
}

}  // namespace

TEST(Fabric, StressAndTangentMatchFiniteDifferencesTautWrinkledAndSlack) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int seen[3] = {0, 0, 0};
    int yarnsStretched = 0, yarnsCompressed = 0;
    for (int i = 0; i < 60; ++i) {
        const double angle = (u(rng) - 0.5) * kPi;
        const auto mat = makeFabric(kE * 3.0 * u(rng), kE * 3.0 * u(rng), angle);
        const auto* fabric = dynamic_cast<const FabricMaterial*>(mat.get());
        ASSERT_NE(fabric, nullptr);
        const auto& matrix = dynamic_cast<const WrinklingMaterial&>(fabric->getMatrix());
        // Principal stretches 0.9-1.1 and 0.8-1.1 at any angle: taut, wrinkled and slack.
        const Mat2 C = test::makeC(0.9 + 0.2 * u(rng), 0.8 + 0.3 * u(rng), kPi * u(rng));
        const double Ew = yarnStrain(C, angle), Ef = yarnStrain(C, angle + 0.5 * kPi);
        if (std::abs(Ew) < 1e-4 || std::abs(Ef) < 1e-4) continue;  // off the yarns' kink
        ++seen[matrix.calcState(C)];
        yarnsStretched += (Ew > 0) + (Ef > 0);
        yarnsCompressed += (Ew < 0) + (Ef < 0);
        Eigen::Vector3d S, Sfd;
        Eigen::Matrix3d D, Dfd;
        mat->calcEnergy(C, &S, &D);
        test::calcFiniteDifferenceDerivatives(*mat, C, 1e-7, &Sfd, &Dfd);
        const double scale = std::max(S.cwiseAbs().maxCoeff(), 1e3);
        EXPECT_LT((S - Sfd).cwiseAbs().maxCoeff(), 1e-6 * scale) << "state " << i;
        EXPECT_LT((D - Dfd).cwiseAbs().maxCoeff(), 1e-6 * D.cwiseAbs().maxCoeff()) << i;
        EXPECT_LT((D - D.transpose()).norm(), 1e-12 * D.norm());
        // Both parts carry no compression: less the residual term (1e-3 of the base's stress,
        // kept so that slack states stay solvable), the stress is positive semidefinite.
        Eigen::Vector3d Sr;
        matrix.getResidualMaterial().calcEnergy(C, &Sr, nullptr);
        const Eigen::Vector3d St = S - matrix.getResidual() * Sr;
        Mat2 Sm;
        Sm << St(0), St(2), St(2), St(1);
        const double smallest = Eigen::SelfAdjointEigenSolver<Mat2>(Sm).eigenvalues()(0);
        EXPECT_GT(smallest, -1e-9 * std::max(St.norm(), 1.0)) << "state " << i;
    }
    EXPECT_GT(seen[0], 3);
    EXPECT_GT(seen[1], 3);
    EXPECT_GT(seen[2], 3);
    EXPECT_GT(yarnsStretched, 10);
    EXPECT_GT(yarnsCompressed, 10);
}

TEST(Fabric, CompressedYarnsCarryNothing) {
    // Squeezed along both yarns (0.98, 0.97 in the warp frame): the fabric is the matrix.
    const auto fabric = makeFabric(2.0 * kE, 1.0 * kE, 0.0);
    const WrinklingMaterial matrix(makeYeoh(kC10, kC20, kC30), 1e-3);
    expectSameBits(*fabric, matrix, test::makeC(0.98, 0.97, 0.0));
}

TEST(Fabric, ElementTangentMatchesFiniteDifferencesTautAndWrinkled) {
    // The membrane elements with the fabric (warp rotated 30 degrees off the panel's x), on a
    // patch stretched along x and, for the wrinkled case, squeezed across.
    for (int wrinkled = 0; wrinkled < 2; ++wrinkled) {
        std::shared_ptr<const MembraneMaterial> mat = makeFabric(2.0 * kE, 0.7 * kE, kPi / 6);
        MembraneModel model(test::makePatch(2, 0.1), mat, 0.2e-3);
        std::mt19937 rng(3 + wrinkled);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        Eigen::Matrix3Xd x = model.getMesh().X;
        x.row(0) *= 1.04;
        x.row(1) *= wrinkled ? 0.9 : 1.02;
        for (int i = 0; i < x.cols(); ++i)
            for (int d = 0; d < 3; ++d) x(d, i) += 0.0003 * u(rng);
        const auto states = model.calcWrinkleStates(x);
        int nWrinkled = 0;
        for (int s : states) nWrinkled += s == 1;
        if (wrinkled)
            EXPECT_GT(nWrinkled, 0);
        else
            EXPECT_EQ(nWrinkled, 0);
        auto eval = [&](const Eigen::Matrix3Xd& y, bool hess) {
            EnergyAccumulator acc(model.getMesh().getNumNodes());
            acc.wantHessian = hess;
            model.addMembraneEnergy(y, acc);
            return acc;
        };
        const EnergyAccumulator a = eval(x, true);
        const int n = static_cast<int>(a.grad.size());
        Eigen::SparseMatrix<double> Hs(n, n);
        Hs.setFromTriplets(a.hess.begin(), a.hess.end());
        const Eigen::MatrixXd H(Hs);
        Eigen::VectorXd gfd(n);
        Eigen::MatrixXd Hfd(n, n);
        const double h = 1e-8;
        for (int k = 0; k < n; ++k) {
            Eigen::Matrix3Xd xp = x, xm = x;
            xp.data()[k] += h;
            xm.data()[k] -= h;
            const EnergyAccumulator p = eval(xp, false), m = eval(xm, false);
            gfd(k) = (p.energy - m.energy) / (2 * h);
            Hfd.col(k) = (p.grad - m.grad) / (2 * h);
        }
        EXPECT_LT((a.grad - gfd).norm(), 1e-5 * a.grad.norm()) << "wrinkled " << wrinkled;
        EXPECT_LT((H - Hfd).norm(), 1e-5 * H.norm()) << "wrinkled " << wrinkled;
        EXPECT_LT((H - H.transpose()).norm(), 1e-12 * H.norm());
    }
}

TEST(Fabric, SingleElementBiaxialStretchAlongWarpWeftAndBiasGivesTheClosedForm) {
    // One triangle in the x-y plane, warp reference along x: stretched to (l1 along x, l2 along
    // y), the element's stress is S_matrix + k_w <E_w> a a^T + k_f <E_f> b b^T with the warp a
    // at the angle given: 0 (stretch along the warp), 90 degrees (along the weft), 45 (bias).
    Mesh mesh;
    mesh.X.resize(3, 3);
    mesh.X << 0.0, 0.1, 0.03, 0.0, 0.01, 0.08, 0.0, 0.0, 0.0;
    mesh.tris.resize(3, 1);
    mesh.tris << 0, 1, 2;
    mesh.triPanel = {0};
    mesh.panelNames = {"sheet"};
    const double kw = 2.0 * kE, kf = 0.5 * kE;
    const WrinklingMaterial matrix(makeYeoh(kC10, kC20, kC30), 1e-3);
    for (double angleDeg : {0.0, 90.0, 45.0, -30.0}) {
        const double angle = angleDeg * kPi / 180.0;
        std::shared_ptr<const MembraneMaterial> mat = makeFabric(kw, kf, angle);
        MembraneModel model(mesh, mat, 0.2e-3);
        const std::vector<Vec3> warp = model.calcWarpDirections();
        EXPECT_LT((warp[0] - Vec3::UnitX()).norm(), 1e-15);
        for (const auto& l :
             {std::pair<double, double>{1.03, 1.01}, std::pair<double, double>{1.05, 0.99},
              std::pair<double, double>{1.02, 1.04}}) {
            Eigen::Matrix3Xd x = mesh.X;
            x.row(0) *= l.first;
            x.row(1) *= l.second;
            const Eigen::Vector3d S = model.calcElementStress(x, 0);
            Mat2 C = Mat2::Zero();
            C(0, 0) = l.first * l.first;
            C(1, 1) = l.second * l.second;
            const Eigen::Vector3d expected = expectedStress(matrix, C, kw, kf, angle);
            EXPECT_LT((S - expected).norm(), 1e-9 * expected.norm())
                << "angle " << angleDeg << " stretch " << l.first << " x " << l.second;
        }
    }
}

TEST(Fabric, FreeStripAlongWarpAndWeftGivesTheMatrixPlusTheYarn) {
    // A strip stretched to l along a yarn with its sides free: the lateral stretch is the
    // matrix's natural width l^-1/2 (the cross yarn is compressed, carries nothing), and the
    // nominal stress is P = P_yeoh(l) + k l (l^2 - 1)/2.
    const double kw = 2.0 * kE, kf = 0.5 * kE;
    const auto fabric = makeFabric(kw, kf, 0.0);
    const auto yeoh = makeYeoh(kC10, kC20, kC30);
    for (int along = 0; along < 2; ++along) {  // 0 warp (element x), 1 weft (element y)
        for (double l : {1.005, 1.02, 1.05, 1.1}) {
            // Lateral stress S_t(lt) = 0 by bisection: tension at lt = 1, none below l^-1/2.
            auto lateral = [&](double lt) {
                Mat2 C = Mat2::Zero();
                C(along, along) = l * l;
                C(1 - along, 1 - along) = lt * lt;
                Eigen::Vector3d S;
                fabric->calcEnergy(C, &S, nullptr);
                return std::make_pair(S(1 - along), S(along));
            };
            double lo = 0.9 / std::sqrt(l), hi = 1.0;
            for (int it = 0; it < 200; ++it) {
                const double mid = 0.5 * (lo + hi);
                (lateral(mid).first > 1e-3 * kE * 1e-6 ? hi : lo) = mid;
            }
            const double k = along == 0 ? kw : kf;
            const double P = l * lateral(hi).second;
            // The matrix with its residual term (1e-3 of the base, also free at the natural width).
            const double expected =
                (1.0 + 1e-3) * yeoh->calcUniaxialNominalStress(l) + k * l * (l * l - 1) / 2;
            EXPECT_NEAR(hi, 1.0 / std::sqrt(l), 1e-6) << "along " << along << " l " << l;
            EXPECT_NEAR(P, expected, 2e-6 * expected) << "along " << along << " l " << l;
        }
    }
}

TEST(Fabric, WarpFollowsTheLongSideInEachPanelOfTheDoubleWedge) {
    DoubleWedgeParams p;
    p.meshSize = 0.05;
    const Mesh mesh = makeDoubleWedgeBag(p);
    std::shared_ptr<const MembraneMaterial> mat = makeFabric(kE, kE, 0.0);
    MembraneModel model(mesh, mat, 0.2e-3);
    const std::vector<Vec3> warp = model.calcWarpDirections();
    const double ax = p.calcApexX();
    const Vec3 steep = Vec3(ax, 0, p.height).normalized();
    const Vec3 gentle = Vec3(p.longSide - ax, 0, -p.height).normalized();
    int checked = 0;
    for (int e = 0; e < mesh.getNumTris(); ++e) {
        const std::string& panel = mesh.panelNames[mesh.triPanel[e]];
        const Vec3 w = warp[e];
        EXPECT_NEAR(w.norm(), 1.0, 1e-12);
        Vec3 expected;
        if (panel.find("diaphragm") != std::string::npos || panel.find("wall") != std::string::npos)
            expected = Vec3::UnitZ();  // the internal wall is across x: its warp is vertical
        else if (std::abs(w.z()) < 1e-12)
            expected = Vec3::UnitX();  // base and side profiles
        else
            expected = std::abs(w.dot(steep)) > std::abs(w.dot(gentle)) ? steep : gentle;
        EXPECT_NEAR(std::abs(w.dot(expected)), 1.0, 1e-12) << panel << " triangle " << e;
        ++checked;
    }
    EXPECT_EQ(checked, mesh.getNumTris());
}

TEST(Fabric, OffIsTheIsotropicFilmAndTheFrameDoesNotMatterToIt) {
    // makeRelaxedMaterial of an isotropic base is the tension-field material as before.
    const auto yeoh = makeYeoh(kC10, kC20, kC30);
    const auto relaxed = makeRelaxedMaterial(*yeoh, 1e-3);
    const WrinklingMaterial before(yeoh->clone(), 1e-3);
    expectSameBits(*relaxed, before, test::makeC(1.03, 0.99, 0.4));
    EXPECT_TRUE(relaxed->isIsotropic());
    // Zero moduli in the warp-aligned frames: the same energy and forces as the isotropic film
    // in the edge frames, to roundoff (the isotropic film's energy does not depend on its frame).
    DoubleWedgeParams p;
    p.meshSize = 0.05;
    const Mesh mesh = makeDoubleWedgeBag(p);
    MembraneModel iso(mesh, std::shared_ptr<const MembraneMaterial>(relaxed->clone()), 0.2e-3);
    MembraneModel zero(mesh, makeFabric(0.0, 0.0, 0.3), 0.2e-3);
    Eigen::Matrix3Xd x = mesh.X;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < x.cols(); ++i)
        for (int d = 0; d < 3; ++d) x(d, i) = 1.02 * x(d, i) + 0.002 * u(rng);
    EnergyAccumulator a(mesh.getNumNodes()), b(mesh.getNumNodes());
    a.wantHessian = b.wantHessian = false;
    iso.addMembraneEnergy(x, a);
    zero.addMembraneEnergy(x, b);
    EXPECT_NEAR(a.energy, b.energy, 1e-10 * std::abs(a.energy));
    EXPECT_LT((a.grad - b.grad).norm(), 1e-8 * a.grad.norm());
}

TEST(Fabric, InvalidYarnsAreRefusedNamingTheMember) {
    auto refuse = [](const FabricAnisotropy& y, const std::string& what) {
        try {
            FabricMaterial f(makeNeoHookean(1e6), y);
            ADD_FAILURE() << "accepted " << what;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    refuse(makeYarns(-1.0, 0.0, 0.0), "warpModulus");
    refuse(makeYarns(0.0, 3e10, 0.0), "weftModulus");
    refuse(makeYarns(1e6, 1e6, 2.0), "angle");
    refuse(makeYarns(std::nan(""), 1e6, 0.0), "warpModulus");
}

TEST(Fabric, TheAirbagsFilmTakesTheYarnsAlongItsOwnFrame) {
    // The tiny rig's bag (25 mm mesh) inflated to 4.5 g: yarns of 3 mu each way hold it
    // smaller at a higher pressure than the isotropic film; turned 90 degrees about the
    // vertical (X_GB), the warp turns with it and the bag is the same; rotated cluster copies
    // of an anisotropic bag are refused.
    AirbagSpec iso;
    iso.geometry.meshSize = 0.025;
    iso.material = makeStableYeoh(kC10, kC20, kC30);
    iso.forceTolerance = 1e-6;  // the turned bag is solved from turned states: to roundoff
    AirbagSpec yarns = iso;
    yarns.material =
        std::make_shared<FabricMaterial>(iso.material->clone(), makeYarns(kE, kE, 0.0));
    AirbagSpec turned = yarns;
    turned.X_GB = Eigen::Isometry3d(Eigen::AngleAxisd(0.5 * kPi, Vec3::UnitZ()));
    auto inflated = [](const AirbagSpec& spec) {
        Airbag bag(spec);
        bag.inflate(4.5e-3);
        return bag.getChamberState(0);
    };
    const ChamberState a = inflated(iso), b = inflated(yarns), c = inflated(turned);
    EXPECT_GT(b.gaugePressure, 1.02 * a.gaugePressure);
    EXPECT_LT(b.volume, a.volume);
    EXPECT_NEAR(c.gaugePressure, b.gaugePressure, 1e-5 * b.gaugePressure);
    EXPECT_NEAR(c.volume, b.volume, 1e-6 * b.volume);
    AirbagSpec cluster = yarns;
    cluster.cluster = {Eigen::Isometry3d::Identity(), turned.X_GB};
    try {
        Airbag bag(cluster);
        ADD_FAILURE() << "a rotated copy of an anisotropic bag accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("cluster"), std::string::npos) << e.what();
    }
}
