// A Yeoh fit with C30 < 0 continued linearly in I1 beyond its stable range (makeStableYeoh).
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
    for (const Mat2& C : {makeC(1.2, 1.2, 0.0), makeC(1.4, 1.0 / std::sqrt(1.4), 0.3),
                          makeC(1.1, 0.98, 0.7)}) {
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
        if (std::abs(C(0, 0) - 1.2848 * 1.2848) > 1e-9)
            EXPECT_LT((D - Dfd).cwiseAbs().maxCoeff(), 1e-6 * D.cwiseAbs().maxCoeff());
    }
}
