// The Yeoh of makeStableYeoh: continued linearly in I1 beyond its stable range when its energy
// is unbounded below (C30 < 0, or C30 == 0 and C20 < 0), the plain polynomial otherwise.
#include "MaterialTestUtil.h"

#include <bags/MaterialFit.h>

#include <gtest/gtest.h>

#include <cmath>

using bags::Mat2;
using bags::test::kC10;
using bags::test::kC20;
using bags::test::kC30;
using bags::test::makeC;

TEST(StableYeoh, LimitIsTheEquibiaxialStabilityLimitOfTheSeedConstants) {
    // Reference: the seed's Yeoh loses stability first on the equibiaxial path, at stretch
    // 1.2856 (peak of the equibiaxial nominal stress, docs/materials.md); I1 - 3 there is
    // 2 l^2 + l^-4 - 3 = 0.6719. The scan finds the last stable stretch to 1e-3, which moves
    // I1 - 3 by at most 4e-3.
    EXPECT_NEAR(bags::calcYeohStableLimit(kC10, kC20, kC30), 0.6719, 4e-3);
    // A Yeoh with non-negative C20, C30 is stable throughout: no limit.
    EXPECT_TRUE(std::isinf(bags::calcYeohStableLimit(1e6, 1e4, 1e3)));
}

TEST(StableYeoh, EqualsThePolynomialInsideAndStaysBoundedOutside) {
    const auto raw = bags::makeYeoh(kC10, kC20, kC30);
    const auto stable = bags::makeStableYeoh(kC10, kC20, kC30);
    // Inside the stable range (equibiaxial 1.2, uniaxial 1.4, a sheared state) the two agree
    // exactly (the same code path).
    for (const Mat2& C :
         {makeC(1.2, 1.2, 0.0), makeC(1.4, 1.0 / std::sqrt(1.4), 0.3), makeC(1.1, 0.98, 0.7)}) {
        Eigen::Vector3d S1, S2;
        EXPECT_EQ(raw->calcEnergy(C, &S1, nullptr), stable->calcEnergy(C, &S2, nullptr));
        EXPECT_EQ(S1, S2);
    }
    // Far outside (equibiaxial stretch 2.5): the polynomial's energy has turned negative, the
    // continued one keeps rising with the stretch.
    EXPECT_LT(raw->calcEnergy(makeC(2.5, 2.5, 0.0), nullptr, nullptr), 0.0);
    double prev = 0.0;
    for (double l = 1.0; l <= 3.0; l += 0.05) {
        const double W = stable->calcEnergy(makeC(l, l, 0.0), nullptr, nullptr);
        EXPECT_GE(W, prev) << "stretch " << l;
        prev = W;
    }
    // The continued material is stable on all three paths up to stretch 3.
    EXPECT_NEAR(bags::calcStabilityRange(*stable).getStable(), 3.0, 1e-9);
}

TEST(StableYeoh, StressAndTangentMatchFiniteDifferencesBeyondTheLimit) {
    // States past the limit (I1 - 3 from 0.9 to 5) and one straddling it; tolerance as the
    // other material checks: 1e-6 of the largest entry.
    const auto stable = bags::makeStableYeoh(kC10, kC20, kC30);
    for (const Mat2& C : {makeC(1.35, 1.3, 0.2), makeC(2.0, 0.8, 1.1), makeC(1.7, 1.7, 0.0),
                          makeC(1.2848, 1.2848, 0.4)}) {
        Eigen::Vector3d S, Sfd;
        Eigen::Matrix3d D, Dfd;
        stable->calcEnergy(C, &S, &D);
        bags::test::calcFiniteDifferenceDerivatives(*stable, C, 1e-6, &Sfd, &Dfd);
        EXPECT_LT((S - Sfd).cwiseAbs().maxCoeff(), 1e-6 * S.cwiseAbs().maxCoeff());
        // Straddling the limit D jumps (W11 from negative to 0); skip D there.
        if (std::abs(C(0, 0) - 1.2848 * 1.2848) > 1e-9) {
            EXPECT_LT((D - Dfd).cwiseAbs().maxCoeff(), 1e-6 * D.cwiseAbs().maxCoeff());
        }
    }
}

TEST(StableYeoh, BoundedEnergyKeepsThePolynomialBeyondAnUnstableBand) {
    // C20 < 0 < C30: unstable in a middle band (first instability at I1 - 3 = 0.405), stable
    // and stiffening again beyond it, and the energy is bounded below (C30 > 0). The continued
    // material would give a uniaxial nominal stress at stretch 3 about 5 times too small.
    const double C10 = 0.5e6, C20 = -0.2e6, C30 = 0.03e6;
    const double limit = bags::calcYeohStableLimit(C10, C20, C30);
    ASSERT_TRUE(std::isfinite(limit));  // the band exists, so the test is meaningful
    const auto raw = bags::makeYeoh(C10, C20, C30);
    const auto continued = bags::makeYeoh(C10, C20, C30, limit);
    const auto stable = bags::makeStableYeoh(C10, C20, C30);
    // Reference: the plain polynomial; the same code path, so exactly equal.
    EXPECT_EQ(stable->calcUniaxialNominalStress(3.0), raw->calcUniaxialNominalStress(3.0));
    // Reference: the continuation from the band differs by far more than any rounding (> 2x).
    EXPECT_GT(raw->calcUniaxialNominalStress(3.0), 2.0 * continued->calcUniaxialNominalStress(3.0));
    // C30 = 0 with C20 >= 0 is bounded too: the polynomial at a large stretch.
    const auto quad = bags::makeStableYeoh(1e6, 1e4, 0.0);
    EXPECT_EQ(quad->calcUniaxialNominalStress(5.0),
              bags::makeYeoh(1e6, 1e4, 0.0)->calcUniaxialNominalStress(5.0));
}

TEST(StableYeoh, UnboundedEnergyWithLimitBeyondStretch3IsStillContinued) {
    // C30 < 0 so small that the scan to stretch 3 sees no instability: W -> -infinity anyway.
    const double C10 = 1e6, C20 = 0.0, C30 = -100.0;
    // Root of dW/dI1 = C10 + 3 C30 x^2: x0 = sqrt(C10 / (3 |C30|)) = 57.735.
    const double x0 = std::sqrt(C10 / (3.0 * -C30));
    const double limit = bags::calcYeohStableLimit(C10, C20, C30);
    ASSERT_TRUE(std::isfinite(limit));
    EXPECT_GT(limit, 15.0);  // beyond stretch 3 on every path (equibiaxial: I1 - 3 = 15.01)
    EXPECT_LT(limit, x0);    // stability is lost before dW/dI1 = 0
    const auto raw = bags::makeYeoh(C10, C20, C30);
    const auto stable = bags::makeStableYeoh(C10, C20, C30);
    const auto eqW = [](const bags::MembraneMaterial& m, double l) {
        return m.calcEnergy(makeC(l, l, 0.0), nullptr, nullptr);
    };
    // The polynomial falls without bound (-7.0e7 at equibiaxial stretch 8).
    EXPECT_LT(eqW(*raw, 8.0), 0.0);
    // Energy at the limit: the polynomial at I1 - 3 = limit.
    const double Wc = C10 * limit + C20 * limit * limit + C30 * limit * limit * limit;
    // Beyond the limit W rises (dW/dI1 > 0 there); tolerance: rounding of W, 1e-12 relative.
    const double W8 = eqW(*stable, 8.0), W20 = eqW(*stable, 20.0);
    EXPECT_GT(W8, Wc - 1e-12 * std::abs(Wc));
    EXPECT_GT(W20, W8);
    EXPECT_GT(eqW(*stable, 100.0), W20);
    // Stable on all three paths up to stretch 8 (scan step 1e-2).
    EXPECT_NEAR(bags::calcStabilityRange(*stable, 8.0, 1e-2).getStable(), 8.0, 1e-9);
}

TEST(StableYeoh, C30ZeroWithNegativeC20IsContinued) {
    // W = C10 x + C20 x^2 with C20 < 0 is unbounded below too; dW/dI1 = 0 at x0 = -C10 / (2 C20).
    const double C10 = 1e6, C20 = -1e3, x0 = -C10 / (2.0 * C20);  // x0 = 500
    const double limit = bags::calcYeohStableLimit(C10, C20, 0.0);
    ASSERT_TRUE(std::isfinite(limit));
    EXPECT_LT(limit, x0);
    const auto stable = bags::makeStableYeoh(C10, C20, 0.0);
    const double Wc = C10 * limit + C20 * limit * limit;
    // Tolerance: rounding of W, 1e-12 relative. Equibiaxial stretch 30: I1 - 3 = 1797 > x0.
    EXPECT_GT(stable->calcEnergy(makeC(30.0, 30.0, 0.0), nullptr, nullptr),
              Wc - 1e-12 * std::abs(Wc));
}

TEST(StableYeoh, SeedLimitAndContinuationAreUnchanged) {
    // Reference: the value before the bounded/unbounded split (0.669215, docs/materials.md
    // "x_c = 0.669"); the seed's scan to stretch 3 is unchanged, so it is pinned to 1e-6.
    const double limit = bags::calcYeohStableLimit(kC10, kC20, kC30);
    EXPECT_NEAR(limit, 0.669215, 1e-6);
    // The seed (C30 < 0) is still continued from that limit: bit for bit the same material
    // as makeYeoh with it, also beyond the limit (equibiaxial 2.0, I1 - 3 = 5.06).
    const auto stable = bags::makeStableYeoh(kC10, kC20, kC30);
    const auto explicitLimit = bags::makeYeoh(kC10, kC20, kC30, limit);
    for (const Mat2& C : {makeC(2.0, 2.0, 0.0), makeC(1.1, 1.0, 0.2)}) {
        Eigen::Vector3d S1, S2;
        EXPECT_EQ(stable->calcEnergy(C, &S1, nullptr), explicitLimit->calcEnergy(C, &S2, nullptr));
        EXPECT_EQ(S1, S2);
    }
}
