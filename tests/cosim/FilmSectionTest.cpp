// One section of a bag's film (cosim::FilmSection, docs/reduced-bag.md#a-film-section): its
// energy's gradient and Hessian against finite differences; a free film against the
// closed-form arc of Laplace's law; the contact pressure of a flat plate (the gas pressure)
// and of a wrapped cylinder (the gas pressure plus the tension over its radius).
#include <cosim/FilmSection.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace cosim;

namespace {

// A disc of radius r centred at c as a signed distance.
FilmSection::Obstacle disc(const Eigen::Vector2d& c, double r) {
    return [c, r](const Eigen::Vector2d& p, Eigen::Vector2d* n, Eigen::Matrix2d* dndp) {
        const Eigen::Vector2d d = p - c;
        const double l = d.norm();
        if (n) *n = d / l;
        if (dndp) *dndp = (Eigen::Matrix2d::Identity() - d * d.transpose() / (l * l)) / l;
        return l - r;
    };
}

// The half plane z >= h (a flat plate from above) as a signed distance.
FilmSection::Obstacle plate(double h) {
    return [h](const Eigen::Vector2d& p, Eigen::Vector2d* n, Eigen::Matrix2d* dndp) {
        if (n) *n = Eigen::Vector2d(0.0, -1.0);
        if (dndp) dndp->setZero();
        return h - p.y();
    };
}

FilmSectionSpec spec(int segments) {
    FilmSectionSpec s;
    s.a = Eigen::Vector2d(-0.05, 0.0);
    s.b = Eigen::Vector2d(0.05, 0.0);
    s.restLength = 0.2;
    s.stiffness = 2e4;
    s.segments = segments;
    return s;
}

}  // namespace

TEST(FilmSection, TheGradientAndHessianMatchFiniteDifferencesOfTheEnergy) {
    // Reference: central differences of the energy (step 1e-7 m) and of the gradient, at a
    // shape pressed by a disc and through the board. Tolerance 1e-6 of the largest entry.
    FilmSectionSpec s = spec(24);
    s.contactPenalty = 1e6;  // (a soft contact: its terms comparable with the film's)
    FilmSection film(s);
    film.addObstacle(disc(Eigen::Vector2d(0.01, 0.09), 0.03));
    Eigen::VectorXd q = film.getFreeCoordinates();
    for (int i = 0; i < q.size(); ++i) q[i] += 2e-3 * std::sin(1.7 * i);
    q[1] = -0.002;  // the first free node below the board
    const double P = 8e3;
    Eigen::VectorXd g;
    Eigen::MatrixXd H;
    film.calcEnergy(q, P, &g, &H);
    const double h = 1e-7;
    Eigen::VectorXd gfd(q.size());
    Eigen::MatrixXd Hfd(q.size(), q.size());
    int inside = 0;
    for (int i = 0; i < q.size(); ++i) {
        Eigen::VectorXd qp = q, qm = q, gp, gm;
        qp[i] += h;
        qm[i] -= h;
        gfd[i] =
            (film.calcEnergy(qp, P, &gp, nullptr) - film.calcEnergy(qm, P, &gm, nullptr)) / (2 * h);
        Hfd.col(i) = (gp - gm) / (2 * h);
    }
    for (int i = 1; i < q.size(); i += 2) inside += q[i] < 0.0;
    EXPECT_GE(inside, 1);  // the board acts
    EXPECT_LT((g - gfd).cwiseAbs().maxCoeff(), 1e-6 * g.cwiseAbs().maxCoeff());
    EXPECT_LT((H - Hfd).cwiseAbs().maxCoeff(), 1e-6 * H.cwiseAbs().maxCoeff());
}

TEST(FilmSection, AFreeFilmIsTheArcOfLaplacesLaw) {
    // Reference: a film of rest length L0 and stiffness EA between anchors c apart under gauge
    // pressure P is a circular arc of radius R with T = P R (Laplace) and length
    // L = L0 (1 + T / EA) = 2 R theta, sin(theta) = c / (2 R) (theta > pi / 2 here: the arc
    // is more than a half circle). R by bisection; area R^2 (theta - sin theta cos theta) +
    // ... Tolerance 2e-4 relative on the tension, the length and the area with 400 segments.
    const FilmSectionSpec s = spec(400);
    const double P = 1e4, c = 0.1;
    auto lengthMiss = [&](double R) {
        const double theta = M_PI - std::asin(c / (2 * R));  // the major arc
        return 2 * R * theta - s.restLength * (1 + P * R / s.stiffness);
    };
    double lo = 0.05, hi = 0.1;
    ASSERT_LT(lengthMiss(lo), 0.0);
    ASSERT_GT(lengthMiss(hi), 0.0);
    for (int it = 0; it < 200; ++it) {
        const double R = 0.5 * (lo + hi);
        (lengthMiss(R) < 0.0 ? lo : hi) = R;
    }
    const double R = 0.5 * (lo + hi), theta = M_PI - std::asin(c / (2 * R));
    const double T = P * R, L = 2 * R * theta;
    // the circular segment's area: R^2 (2 theta - sin(2 theta)) / 2
    const double A = 0.5 * R * R * (2 * theta - std::sin(2 * theta));
    FilmSection film(s);
    film.solve(P);
    const Eigen::VectorXd tension = film.calcTensions();
    EXPECT_NEAR(tension.minCoeff() / T, 1.0, 2e-4);
    EXPECT_NEAR(tension.maxCoeff() / T, 1.0, 2e-4);
    EXPECT_NEAR(film.calcLength() / L, 1.0, 2e-4);
    EXPECT_NEAR(film.calcArea() / A, 1.0, 2e-4);
    EXPECT_EQ(film.calcContactPressures().maxCoeff(), 0.0);
}

TEST(FilmSection, AFlatPlatePressesWithTheGasPressureAndAWrappedCylinderWithTensionOverRadius) {
    // Reference: where the film lies on a flat face its curvature is zero and its contact
    // pressure is the gas pressure P; where it wraps a cylinder of radius rho from below it
    // is P + T / rho (T the film's tension there). Tolerance 1 % at the nodes well inside the
    // contact (20 nodes, 10 mm, from its edges: the penalty's edge layer is sqrt(T / k) =
    // 1.7 mm thick), 400 segments, penalty 1e8 Pa/m; the plate 20 mm below the free film's
    // top, the cylinder (radius 40 mm) 30 mm.
    const double P = 1e4;
    {
        FilmSection film(spec(400));
        film.solve(P);
        const double top = film.getNodes().row(1).maxCoeff();
        FilmSection pressed(spec(400));
        pressed.addObstacle(plate(top - 0.02));
        pressed.solve(P);
        const Eigen::VectorXd q = pressed.calcContactPressures();
        int on = 0;
        for (int i = 20; i + 20 < q.size(); ++i)
            if (q[i - 20] > 0.0 && q[i + 20] > 0.0) {
                EXPECT_NEAR(q[i] / P, 1.0, 0.01) << "node " << i;
                ++on;
            }
        EXPECT_GE(on, 20);
    }
    {
        const double rho = 0.04;
        FilmSection film(spec(400));
        film.solve(P);
        const double top = film.getNodes().row(1).maxCoeff();
        FilmSection wrapped(spec(400));
        wrapped.addObstacle(disc(Eigen::Vector2d(0.0, top + rho - 0.03), rho));
        wrapped.solve(P);
        const Eigen::VectorXd q = wrapped.calcContactPressures(), T = wrapped.calcTensions();
        int on = 0;
        for (int i = 20; i + 20 < q.size(); ++i)
            if (q[i - 20] > 0.0 && q[i + 20] > 0.0) {
                const double expected = P + 0.5 * (T[i - 1] + T[i]) / rho;
                EXPECT_NEAR(q[i] / expected, 1.0, 0.01) << "node " << i;
                ++on;
            }
        EXPECT_GE(on, 20);
        // and it presses harder than the gas: by a factor 1 + T / (P rho), about 1.7 here
        EXPECT_GT(q.maxCoeff(), 1.5 * P);
    }
}
