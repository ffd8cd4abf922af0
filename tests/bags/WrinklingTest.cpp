// Tension-field (wrinkling) relaxation: states, derivatives, the free strip, slack energy and
// C1 continuity across the state boundaries.
#include "MaterialTestUtil.h"

#include <bags/Material.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <random>

namespace {

using bags::Mat2;
using bags::test::kC10;
using bags::test::kC20;
using bags::test::kC30;
using bags::test::makeC;
using bags::test::perturb;

/// S vs central differences of W, D vs central differences of S; tolerance 1e-6 relative
/// to the largest entry (h = 1e-7 keeps the stencil inside one state: the states used are at
/// least 1e-3 in stretch from a boundary).
void checkDerivatives(const bags::MembraneMaterial& mat, const Mat2& C) {
    Eigen::Vector3d S;
    Eigen::Matrix3d D;
    mat.calcEnergy(C, &S, &D);
    Eigen::Vector3d Sfd;
    Eigen::Matrix3d Dfd;
    bags::test::calcFiniteDifferenceDerivatives(mat, C, 1e-7, &Sfd, &Dfd);
    const double sScale = std::max(S.cwiseAbs().maxCoeff(), 1.0);
    const double dScale = D.cwiseAbs().maxCoeff();
    EXPECT_LE((S - Sfd).cwiseAbs().maxCoeff(), 1e-6 * sScale) << "S\n" << S << "\nFD\n" << Sfd;
    EXPECT_LE((D - Dfd).cwiseAbs().maxCoeff(), 1e-6 * dScale) << "D\n" << D << "\nFD\n" << Dfd;
    EXPECT_LE((D - D.transpose()).cwiseAbs().maxCoeff(), 1e-12 * dScale);
}

std::unique_ptr<bags::WrinklingMaterial> makeWrinklingYeoh(double residual) {
    return std::make_unique<bags::WrinklingMaterial>(bags::makeYeoh(kC10, kC20, kC30), residual);
}

}  // namespace

TEST(Wrinkling, StateFollowsPrincipalStretches) {
    const auto w = makeWrinklingYeoh(1e-3);
    EXPECT_EQ(w->calcState(makeC(1.2, 1.0, 0.3)), 0);   // taut: 1.0 >= 1.2^-1/2 = 0.913
    EXPECT_EQ(w->calcState(makeC(1.2, 0.9, 0.3)), 1);   // wrinkled: 0.9 < 0.913
    EXPECT_EQ(w->calcState(makeC(0.95, 0.9, 0.3)), 2);  // slack: lambda1 <= 1
    EXPECT_EQ(w->calcState(makeC(0.8, 1.3, 1.0)), 1);   // order of the stretches does not matter
    EXPECT_EQ(w->calcState(Mat2::Identity()), 2);
    double l1 = 0, l2 = 0;
    bags::WrinklingMaterial::calcPrincipalStretches(makeC(0.8, 1.3, 1.0), &l1, &l2);
    EXPECT_NEAR(l1, 1.3, 1e-14);  // sorted, and recovered from C to round-off
    EXPECT_NEAR(l2, 0.8, 1e-14);
}

TEST(Wrinkling, StressAndTangentMatchFiniteDifferencesInEveryState) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0), angle(0.0, M_PI);
    for (double residual : {0.0, 1e-3}) {
        std::vector<std::unique_ptr<bags::MembraneMaterial>> mats;
        mats.push_back(makeWrinklingYeoh(residual));
        mats.push_back(std::make_unique<bags::WrinklingMaterial>(
            bags::makeOgden({1.2e6, 0.3e6}, {7.5, -3.0}), residual));
        mats.push_back(std::make_unique<bags::WrinklingMaterial>(
            bags::makeMooneyRivlin(0.4e6, 0.1e6), residual));
        for (int trial = 0; trial < 10; ++trial) {
            // One state of each kind, each at least 1e-3 from a boundary.
            const double l1 = 1.02 + 0.4 * u(rng);
            const double nat = 1.0 / std::sqrt(l1);
            const Mat2 taut = makeC(l1, nat + 1e-3 + (l1 - nat - 1e-3) * u(rng), angle(rng));
            const Mat2 wrinkled = makeC(l1, 0.5 + (nat - 1e-3 - 0.5) * u(rng), angle(rng));
            const double s1 = 0.6 + 0.39 * u(rng);
            const Mat2 slack = makeC(s1, 0.5 + (s1 - 0.5) * u(rng), angle(rng));
            for (const auto& m : mats) {
                const auto& w = static_cast<const bags::WrinklingMaterial&>(*m);
                ASSERT_EQ(w.calcState(taut), 0);
                ASSERT_EQ(w.calcState(wrinkled), 1);
                ASSERT_EQ(w.calcState(slack), 2);
                SCOPED_TRACE(m->getName() + " residual " + std::to_string(residual));
                checkDerivatives(*m, taut);
                checkDerivatives(*m, wrinkled);
                checkDerivatives(*m, slack);
            }
        }
    }
}

TEST(Wrinkling, WrinkledTangentStaysFiniteNearUnstretchedState) {
    // Close to C = I the wrinkled tangent has w'(e1)/(e1 - e2) with both factors -> 0; it must
    // stay bounded by the taut tangent's scale (4 mu) and match finite differences.
    const auto w = makeWrinklingYeoh(0.0);
    const double mu = 2.0 * kC10;
    for (double eps : {1e-2, 1e-3, 1e-4}) {
        const Mat2 C = makeC(1.0 + eps, 1.0 - eps, 0.7);
        ASSERT_EQ(w->calcState(C), 1);
        Eigen::Matrix3d D;
        Eigen::Vector3d S;
        w->calcEnergy(C, &S, &D);
        EXPECT_LT(D.cwiseAbs().maxCoeff(), 4.0 * mu * 1.01);
        EXPECT_TRUE(D.allFinite());
    }
    checkDerivatives(*w, makeC(1.0 + 1e-3, 1.0 - 1e-3, 0.7));
}

TEST(Wrinkling, FreeStripCarriesNoTransverseStressAndTheUniaxialLoad) {
    // Reference: a strip stretched by l and free to contract (any lateral stretch below the
    // natural width l^-1/2) is in uniaxial tension: with residual 0, S22 = S12 = 0 exactly and
    // l S11 is the base's uniaxial nominal stress (Yeoh closed form). Tolerance 1e-9 relative.
    const auto w = makeWrinklingYeoh(0.0);
    for (double l : {1.05, 1.2, 1.5}) {
        const double x = l * l + 2.0 / l - 3.0;
        const double ref = 2.0 * (l - 1.0 / (l * l)) * (kC10 + 2.0 * kC20 * x + 3.0 * kC30 * x * x);
        for (double lateral : {0.5, 0.8, 0.99 / std::sqrt(l)}) {
            Mat2 C = Mat2::Zero();
            C(0, 0) = l * l;
            C(1, 1) = lateral * lateral;
            ASSERT_EQ(w->calcState(C), 1);
            Eigen::Vector3d S;
            w->calcEnergy(C, &S, nullptr);
            EXPECT_EQ(S(1), 0.0);
            EXPECT_EQ(S(2), 0.0);
            EXPECT_NEAR(l * S(0), ref, 1e-9 * ref);
        }
    }
    // Rotated strip: the stress is uniaxial along the stretch direction, sigma = S n n^T.
    const double l = 1.3, th = 0.6;
    Eigen::Vector3d S;
    w->calcEnergy(makeC(l, 0.7, th), &S, nullptr);
    Eigen::Matrix2d St;
    St << S(0), S(2), S(2), S(1);
    const Eigen::Vector2d n(std::cos(th), std::sin(th)), t(-std::sin(th), std::cos(th));
    EXPECT_NEAR(t.dot(St * t), 0.0, 1e-9 * S.norm());
    EXPECT_NEAR(n.dot(St * t), 0.0, 1e-9 * S.norm());
}

TEST(Wrinkling, SlackStateHasOnlyTheResidualEnergy) {
    // Reference: slack W = residual * W_base(C) (and its stress); zero with residual 0.
    const double residual = 1e-3;
    const auto w = makeWrinklingYeoh(residual);
    const auto w0 = makeWrinklingYeoh(0.0);
    const auto base = bags::makeYeoh(kC10, kC20, kC30);
    for (const Mat2& C : {makeC(0.9, 0.8, 0.2), makeC(0.99, 0.99, 0.0), makeC(0.7, 0.95, 1.1)}) {
        ASSERT_EQ(w->calcState(C), 2);
        Eigen::Vector3d S, Sb, S0;
        const double W = w->calcEnergy(C, &S, nullptr);
        const double Wb = base->calcEnergy(C, &Sb, nullptr);
        EXPECT_NEAR(W, residual * Wb, 1e-12 * std::abs(Wb));
        EXPECT_LT((S - residual * Sb).cwiseAbs().maxCoeff(), 1e-12 * Sb.norm());
        EXPECT_EQ(w0->calcEnergy(C, &S0, nullptr), 0.0);
        EXPECT_EQ(S0.norm(), 0.0);
    }
}

TEST(Wrinkling, EnergyIsC1AcrossTautWrinkledAndWrinkledSlackBoundaries) {
    // Reference: Pipkin's relaxed energy is C1 (sigma2 = 0 at the natural width; w'(1) = 0 at
    // lambda1 = 1). Across a boundary at distance +-d, W and S may differ by O(d) only:
    // with d = 1e-7 the jump in S must be below 1e-5 of |S| (a jump in the stress itself would
    // be O(1)). D is allowed to jump.
    const auto w = makeWrinklingYeoh(0.0);
    const double d = 1e-7;
    for (double l1 : {1.05, 1.3, 1.5}) {
        const double nat = 1.0 / std::sqrt(l1);
        const Mat2 Ct = makeC(l1, nat + d, 0.4), Cw = makeC(l1, nat - d, 0.4);
        ASSERT_EQ(w->calcState(Ct), 0);
        ASSERT_EQ(w->calcState(Cw), 1);
        Eigen::Vector3d St, Sw;
        const double Wt = w->calcEnergy(Ct, &St, nullptr);
        const double Ww = w->calcEnergy(Cw, &Sw, nullptr);
        EXPECT_NEAR(Wt, Ww, 1e-5 * Wt);
        EXPECT_LT((St - Sw).norm(), 1e-5 * St.norm()) << "l1 " << l1;
    }
    // Wrinkled/slack: around lambda1 = 1 both W and S tend to zero.
    const Mat2 Cw = makeC(1.0 + d, 0.8, 0.4), Cs = makeC(1.0 - d, 0.8, 0.4);
    ASSERT_EQ(w->calcState(Cw), 1);
    ASSERT_EQ(w->calcState(Cs), 2);
    Eigen::Vector3d Sw, Ss;
    w->calcEnergy(Cw, &Sw, nullptr);
    w->calcEnergy(Cs, &Ss, nullptr);
    EXPECT_LT((Sw - Ss).norm(), 1e-5 * 2.0 * kC10);  // |S| ~ 6 mu d here
}

TEST(Wrinkling, YeohResidualLosesConvexityInStrongBiaxialCompressionNeoHookeanDoesNot) {
    // The seed's Yeoh (C30 < 0) has dW/dI1 < 0 for I1 - 3 > 1.77; equibiaxial compression to
    // lambda = 0.6 gives I1 = 0.72 + 1/0.1296 = 8.44, so residual * W_yeoh has a negative
    // tangent eigenvalue there, while a neo-Hookean residual of the same mu stays positive.
    const Mat2 C = 0.36 * Mat2::Identity();
    const auto wy = makeWrinklingYeoh(1e-3);
    const bags::WrinklingMaterial wn(bags::makeYeoh(kC10, kC20, kC30), 1e-3,
                                     bags::makeNeoHookean(kC10));
    ASSERT_EQ(wy->calcState(C), 2);
    Eigen::Matrix3d Dy, Dn;
    Eigen::Vector3d S;
    wy->calcEnergy(C, &S, &Dy);
    wn.calcEnergy(C, &S, &Dn);
    EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Dy).eigenvalues()(0), 0.0);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Dn).eigenvalues()(0), 0.0);
    checkDerivatives(wn, makeC(0.8, 0.7, 0.3));
    EXPECT_NEAR(wn.getInitialShearModulus(), 2.0 * kC10 * (1.0 + 1e-3), 1e-6);
}

TEST(Wrinkling, CloneKeepsBaseResidualAndResidualMaterial) {
    const bags::WrinklingMaterial wn(bags::makeYeoh(kC10, kC20, kC30), 2e-3,
                                     bags::makeNeoHookean(kC10));
    const auto c = wn.clone();
    const Mat2 C = 0.5 * Mat2::Identity();
    EXPECT_EQ(c->calcEnergy(C, nullptr, nullptr), wn.calcEnergy(C, nullptr, nullptr));
    EXPECT_EQ(c->getName(), "tension-field(yeoh)");
    EXPECT_THROW(bags::WrinklingMaterial(bags::makeNeoHookean(1e6), -1.0), std::invalid_argument);
}
