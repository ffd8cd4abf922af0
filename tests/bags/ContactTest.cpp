// Rigid shapes (signed distance, closest point, normal, normal derivative) and the rigid contact
// term (penalty, friction, wrench, pressure). References: analytic geometry, central finite
// differences, dense sampling of the surface, and the penalty law p = pressurePenalty * overlap.

#include <bags/Contact.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "ContactTestUtil.h"

using bags::Mat3;
using bags::Vec3;
using bagstest::differenceContact;
using bagstest::DifferencedContact;
using bagstest::evaluate;
using bagstest::Evaluated;
using bagstest::finiteDifferences;

namespace {

Eigen::Isometry3d somePose() {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = (Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()) *
                  Eigen::AngleAxisd(-0.4, Vec3::UnitX()))
                     .toRotationMatrix();
    X.translation() = Vec3(0.05, -0.02, 0.3);
    return X;
}

/// Checks d, closest point and normal of a shape at a local point against given local values.
void expectLocal(const bags::RigidShape& s, const Vec3& p_S, double d, const Vec3& c_S,
                 const Vec3& n_S, double tol) {
    const Eigen::Isometry3d& X = s.getPose();
    Vec3 c, n;
    const double dd = s.calcSignedDistance(X * p_S, &c, &n);
    EXPECT_NEAR(dd, d, tol) << s.getName() << " at " << p_S.transpose();
    EXPECT_LT((X.inverse() * c - c_S).norm(), tol) << s.getName() << " at " << p_S.transpose();
    EXPECT_LT((X.linear().transpose() * n - n_S).norm(), tol)
        << s.getName() << " at " << p_S.transpose();
}

// The shapes every generic test runs on, in this order.
enum class Kind { Plane, SharpBox, RoundBox, Ellipsoid, Capsule };
const Vec3 kBoxHalf(0.1, 0.06, 0.04);
const double kBoxRadius = 0.015;
const Vec3 kSemiAxes(0.12, 0.08, 0.05);
const double kCapRadius = 0.04, kCapHalfLength = 0.09;

std::vector<std::unique_ptr<bags::RigidShape>> makeAllShapes() {
    std::vector<std::unique_ptr<bags::RigidShape>> v;
    v.push_back(bags::makePlane());
    v.push_back(bags::makeBox(kBoxHalf, 0.0));
    v.push_back(bags::makeBox(kBoxHalf, kBoxRadius));
    v.push_back(bags::makeEllipsoid(kSemiAxes));
    v.push_back(bags::makeCapsule(kCapRadius, kCapHalfLength));
    for (auto& s : v) s->setPose(somePose());
    return v;
}

Kind kindOf(size_t i) { return static_cast<Kind>(i); }

/// True if local point p lies 2 mm or more away from every place where the shape's normal or
/// its derivative jumps (box edges and inner ridges, region borders, the ellipsoid's inner
/// medial surface, the capsule axis), judged from the shape's definition alone.
bool isSmoothPoint(Kind kind, const Vec3& p) {
    const double m = 2e-3;
    auto ridgeFree = [&](const Vec3& q) {  // largest of q well separated from the next
        Vec3 s = q;
        std::sort(s.data(), s.data() + 3);
        return s[2] - s[1] > m;
    };
    switch (kind) {
        case Kind::Plane:
            return std::abs(p.z()) > m;
        case Kind::SharpBox: {
            const Vec3 q = p.cwiseAbs() - kBoxHalf;
            int out = 0;
            for (int i = 0; i < 3; ++i) {
                if (std::abs(q[i]) < m) return false;
                out += q[i] > 0;
            }
            return out == 1 || (out == 0 && ridgeFree(q));
        }
        case Kind::RoundBox: {
            const Vec3 q = p.cwiseAbs() - (kBoxHalf.array() - kBoxRadius).matrix();
            int out = 0;
            for (int i = 0; i < 3; ++i) {
                if (std::abs(q[i]) < m) return false;
                out += q[i] > 0;
            }
            if (out > 0) {
                const Vec3 w = q.cwiseMax(0.0);
                return std::abs(w.norm() - kBoxRadius) > m;
            }
            return ridgeFree(q) && q.maxCoeff() < -kBoxRadius - m;
        }
        case Kind::Ellipsoid: {
            const double g = p.cwiseQuotient(kSemiAxes).squaredNorm();
            return std::abs(g - 1.0) > 0.05 && (g > 1.0 || std::abs(p.z()) > 0.01);
        }
        case Kind::Capsule: {
            const double rho = p.head<2>().norm();
            const double dz = std::abs(p.z()) - kCapHalfLength;
            const double d = dz > 0 ? std::hypot(rho, dz) : rho;
            return rho > m && std::abs(dz) > m && std::abs(d - kCapRadius) > m;
        }
    }
    return false;
}

/// n random Ground points around shape number i where its normal field is smooth.
std::vector<Vec3> smoothPoints(const bags::RigidShape& s, Kind kind, int n, std::mt19937& rng) {
    std::uniform_real_distribution<double> U(-0.15, 0.15);
    std::vector<Vec3> pts;
    while (static_cast<int>(pts.size()) < n) {
        const Vec3 p_S(U(rng), U(rng), U(rng));
        if (isSmoothPoint(kind, p_S)) pts.push_back(s.getPose() * p_S);
    }
    return pts;
}

}  // namespace

TEST(RigidShapes, PlaneGivesHeightAboveFrameInPosedFrame) {
    auto s = bags::makePlane();
    s->setPose(somePose());
    // Reference: half-space z < 0 of the frame; exact up to round-off (1e-14 m).
    expectLocal(*s, Vec3(0.3, -0.2, 0.05), 0.05, Vec3(0.3, -0.2, 0), Vec3::UnitZ(), 1e-14);
    expectLocal(*s, Vec3(-1.0, 2.0, -0.01), -0.01, Vec3(-1.0, 2.0, 0), Vec3::UnitZ(), 1e-14);
    EXPECT_TRUE(s->calcNormalDerivative(s->getPose() * Vec3(1, 2, 3)).isZero(0.0));
}

TEST(RigidShapes, BoxGivesAnalyticDistanceOnFacesEdgesCornersAndInside) {
    const Vec3 h(0.1, 0.06, 0.04);
    auto box = bags::makeBox(h, 0.0);
    box->setPose(somePose());
    const double tol = 1e-14;  // closed-form references, round-off only
    // Face, edge and corner regions outside.
    expectLocal(*box, Vec3(0.02, 0.01, 0.07), 0.03, Vec3(0.02, 0.01, 0.04), Vec3::UnitZ(), tol);
    expectLocal(*box, Vec3(0.13, 0.0, 0.08), std::hypot(0.03, 0.04), Vec3(0.1, 0, 0.04),
                Vec3(0.6, 0, 0.8), tol);
    expectLocal(*box, Vec3(-0.12, -0.08, -0.06), std::sqrt(3 * 4e-4), Vec3(-0.1, -0.06, -0.04),
                -Vec3::Ones().normalized(), tol);
    // Inside: the face of least penetration (here -y, 0.01 deep).
    expectLocal(*box, Vec3(0.02, -0.05, 0.0), -0.01, Vec3(0.02, -0.06, 0.0), -Vec3::UnitY(), tol);

    const double r = 0.01;
    auto rbox = bags::makeBox(h, r);
    rbox->setPose(somePose());
    // Rounded edge: distance to the inner box edge minus r.
    const Vec3 innerEdge(0.09, 0.0, 0.03);
    const Vec3 p(0.12, 0.0, 0.07);
    const double dEdge = (p - innerEdge).norm();
    const Vec3 nEdge = (p - innerEdge) / dEdge;
    expectLocal(*rbox, p, dEdge - r, innerEdge + r * nEdge, nEdge, tol);
    // Inside the rounding shell of a corner (0 < d_inner < r): still negative distance.
    const Vec3 innerCorner(0.09, 0.05, 0.03);
    const Vec3 pc = innerCorner + 0.004 * Vec3(1, 2, 2) / 3.0;
    expectLocal(*rbox, pc, 0.004 - r, innerCorner + r * Vec3(1, 2, 2) / 3.0, Vec3(1, 2, 2) / 3.0,
                tol);
    // Face: unchanged by the rounding.
    expectLocal(*rbox, Vec3(0.0, 0.0, 0.05), 0.01, Vec3(0, 0, 0.04), Vec3::UnitZ(), tol);
    expectLocal(*rbox, Vec3(0.0, 0.0, 0.035), -0.005, Vec3(0, 0, 0.04), Vec3::UnitZ(), tol);
}

TEST(RigidShapes, CapsuleGivesAnalyticDistanceOnCylinderCapsAndAxis) {
    const double r = 0.04, L = 0.09;
    auto cap = bags::makeCapsule(r, L);
    cap->setPose(somePose());
    const double tol = 1e-14;  // closed form
    expectLocal(*cap, Vec3(0.03, 0.04, 0.05), 0.05 - r, Vec3(0.024, 0.032, 0.05), Vec3(0.6, 0.8, 0),
                tol);
    expectLocal(*cap, Vec3(0.0, 0.01, -0.02), 0.01 - r, Vec3(0, 0.04, -0.02), Vec3::UnitY(), tol);
    expectLocal(*cap, Vec3(0.0, 0.0, 0.2), 0.2 - L - r, Vec3(0, 0, L + r), Vec3::UnitZ(), tol);
    expectLocal(*cap, Vec3(0.0, 0.0, -0.1), 0.01 - r, Vec3(0, 0, -L - r), -Vec3::UnitZ(), tol);
}

TEST(RigidShapes, EllipsoidMatchesSphereAndAxisReferences) {
    auto sph = bags::makeEllipsoid(Vec3(0.1, 0.1, 0.1));
    sph->setPose(somePose());
    // Sphere: d = |p| - R (1e-13 m).
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-0.2, 0.2);
    for (int i = 0; i < 50; ++i) {
        const Vec3 p(U(rng), U(rng), U(rng));
        expectLocal(*sph, p, p.norm() - 0.1, 0.1 * p.normalized(), p.normalized(), 1e-13);
    }
    const Vec3 a(0.12, 0.08, 0.05);
    auto e = bags::makeEllipsoid(a);
    e->setPose(somePose());
    const double tol = 1e-13;
    // On the axes, outside: the axis tip.
    expectLocal(*e, Vec3(0.2, 0, 0), 0.08, Vec3(0.12, 0, 0), Vec3::UnitX(), tol);
    expectLocal(*e, Vec3(0, -0.1, 0), 0.02, Vec3(0, -0.08, 0), -Vec3::UnitY(), tol);
    expectLocal(*e, Vec3(0, 0, 0.3), 0.25, Vec3(0, 0, 0.05), Vec3::UnitZ(), tol);
    // On the short axis inside, and the centre: the short-axis tip.
    expectLocal(*e, Vec3(0, 0, -0.02), -0.03, Vec3(0, 0, -0.05), -Vec3::UnitZ(), tol);
    expectLocal(*e, Vec3(0, 0, 0), -0.05, Vec3(0, 0, 0.05), Vec3::UnitZ(), tol);
    // On the long axis inside, near the centre: the closest point leaves the axis plane,
    // x_c = a^2 x / (a^2 - c^2), z_c = c sqrt(1 - (x_c/a)^2) (the evolute branch).
    const double x = 0.01;
    const double xc = a.x() * a.x() * x / (a.x() * a.x() - a.z() * a.z());
    const double zc = a.z() * std::sqrt(1 - std::pow(xc / a.x(), 2));
    const Vec3 cRef(xc, 0, zc);
    // Two mirror closest points (+-z) tie exactly; round-off of the pose picks one.
    Vec3 c, nrm;
    const double d = e->calcSignedDistance(e->getPose() * Vec3(x, 0, 0), &c, &nrm);
    EXPECT_NEAR(d, -(cRef - Vec3(x, 0, 0)).norm(), tol);
    Vec3 cS = e->getPose().inverse() * c;
    cS.z() = std::abs(cS.z());
    EXPECT_LT((cS - cRef).norm(), tol);
}

TEST(RigidShapes, EllipsoidClosestPointIsOnSurfaceNormalAndGlobalEverywhere) {
    const Vec3 a(0.12, 0.08, 0.05);
    auto e = bags::makeEllipsoid(a);  // identity pose: the checks are in the shape frame
    // Reference: the global minimum of |p - s(theta, phi)| over the surface, from a coarse
    // 150 x 300 parameter grid whose 20 best samples are each refined by zooming grids
    // (8 levels, 21 x 21, step / 5 each): parameter error ~ 1e-8 rad, distance error < 1e-12 m.
    auto surf = [&](double th, double ph) {
        return Vec3(a.x() * std::sin(th) * std::cos(ph), a.y() * std::sin(th) * std::sin(ph),
                    a.z() * std::cos(th));
    };
    const int nt = 150, np = 300;
    const double dth = M_PI / nt, dph = 2 * M_PI / np;
    auto globalDistance = [&](const Vec3& p) {
        std::vector<std::pair<double, std::pair<double, double>>> coarse;
        for (int i = 0; i <= nt; ++i)
            for (int j = 0; j < np; ++j)
                coarse.push_back({(surf(i * dth, j * dph) - p).norm(), {i * dth, j * dph}});
        std::partial_sort(coarse.begin(), coarse.begin() + 20, coarse.end());
        double best = coarse[0].first;
        for (int c = 0; c < 20; ++c) {
            double th = coarse[c].second.first, ph = coarse[c].second.second;
            double st = dth, sp = dph, bc = coarse[c].first;
            for (int level = 0; level < 8; ++level) {
                double bth = th, bph = ph;
                for (int i = -10; i <= 10; ++i)
                    for (int j = -10; j <= 10; ++j) {
                        const double t = th + i * st / 5, f = ph + j * sp / 5;
                        const double dd = (surf(t, f) - p).norm();
                        if (dd < bc) {
                            bc = dd;
                            bth = t;
                            bph = f;
                        }
                    }
                th = bth;
                ph = bph;
                st /= 5;
                sp /= 5;
            }
            best = std::min(best, bc);
        }
        return best;
    };
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    std::vector<Vec3> pts;
    for (int i = 0; i < 40; ++i) pts.push_back(Vec3(U(rng), U(rng), U(rng)).cwiseProduct(a) * 1.6);
    // Near the axes and the axis planes (1e-9 m off), inside and outside.
    for (double f : {0.3, 0.9, 1.2}) {
        pts.push_back(Vec3(f * a.x(), 1e-9, -1e-9));
        pts.push_back(Vec3(1e-9, f * a.y(), 1e-9));
        pts.push_back(Vec3(-1e-9, 1e-9, f * a.z()));
        pts.push_back(Vec3(0.3 * f * a.x(), 0.2 * a.y(), 1e-9));
        pts.push_back(Vec3(0.1 * a.x(), 1e-9, 0.2 * f * a.z()));
    }
    double worst = 0.0;
    for (const Vec3& p : pts) {
        Vec3 c, n;
        const double d = e->calcSignedDistance(p, &c, &n);
        EXPECT_NEAR(c.cwiseQuotient(a).squaredNorm(), 1.0, 1e-12) << p.transpose();
        const Vec3 nSurf = c.cwiseQuotient(a.cwiseProduct(a)).normalized();
        EXPECT_LT((n - nSurf).norm(), 1e-12) << p.transpose();
        // p - c along the normal (1e-9 m of lateral offset)
        EXPECT_LT((p - c - (p - c).dot(n) * n).norm(), 1e-9) << p.transpose();
        const bool inside = p.cwiseQuotient(a).squaredNorm() < 1.0;
        EXPECT_EQ(d < 0, inside) << p.transpose();
        const double best = globalDistance(p);
        EXPECT_LE(std::abs(d), best + 1e-12) << p.transpose();
        EXPECT_GE(std::abs(d), best - 1e-10) << p.transpose();
        worst = std::max(worst, std::abs(std::abs(d) - best));
    }
    bagstest::recordFigure("ellipsoid_distance_vs_sampled_max_m", worst);
}

TEST(RigidShapes, DistanceLowerBoundNeverExceedsDistance) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(-0.4, 0.4);
    for (auto& s : makeAllShapes()) {
        int tight = 0;
        for (int i = 0; i < 2000; ++i) {
            const Vec3 p = s->getPose() * Vec3(U(rng), U(rng), U(rng));
            const double d = s->calcSignedDistance(p, nullptr, nullptr);
            const double lb = s->calcDistanceLowerBound(p);
            EXPECT_LE(lb, d + 1e-15) << s->getName() << " at " << p.transpose();
            tight += lb > d - 0.05;
        }
        EXPECT_GT(tight, 200) << s->getName();  // and is useful: within 5 cm of d often
    }
}

TEST(RigidShapes, NoPointBeyondTheLowerBoundReachHasABoundWithinIt) {
    // getLowerBoundReach(t) is what lets the reduced bag skip its grid's far columns without
    // asking the shape: every point whose lower bound is at most t lies within it of the
    // frame origin. Checked at random points for bounds below, at and above zero; and the
    // reach is finite (so that something is skipped) for every shape but the plane.
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> U(-0.5, 0.5);
    for (auto& s : makeAllShapes()) {
        const Vec3 o = s->getPose().translation();
        for (double t : {-0.02, 0.0, 0.03, 0.1}) {
            const double reach = s->getLowerBoundReach(t);
            EXPECT_EQ(std::isfinite(reach), s->getName() != "plane") << s->getName();
            int within = 0;
            for (int i = 0; i < 4000; ++i) {
                const Vec3 p = s->getPose() * Vec3(U(rng), U(rng), U(rng));
                if (s->calcDistanceLowerBound(p) > t) continue;
                ++within;
                EXPECT_LE((p - o).norm(), reach + 1e-12) << s->getName() << " t " << t;
            }
            if (t >= 0.0 && s->getName() != "plane") EXPECT_GT(within, 0) << s->getName();
        }
    }
}

TEST(RigidShapes, NormalIsGradientOfSignedDistance) {
    std::mt19937 rng(11);
    double worst = 0.0;
    auto shapes = makeAllShapes();
    for (size_t k = 0; k < shapes.size(); ++k) {
        const auto& s = shapes[k];
        for (const Vec3& p : smoothPoints(*s, kindOf(k), 30, rng)) {
            Vec3 n;
            s->calcSignedDistance(p, nullptr, &n);
            Vec3 g;
            const double h = 1e-7;  // central differences: error ~ h^2 |d'''| + eps/h ~ 1e-9
            for (int i = 0; i < 3; ++i) {
                Vec3 dp = Vec3::Zero();
                dp[i] = h;
                g[i] = (s->calcSignedDistance(p + dp, nullptr, nullptr) -
                        s->calcSignedDistance(p - dp, nullptr, nullptr)) /
                       (2 * h);
            }
            EXPECT_LT((g - n).norm(), 1e-7) << s->getName() << " at " << p.transpose();
            EXPECT_NEAR(n.norm(), 1.0, 1e-14);
            worst = std::max(worst, (g - n).norm());
        }
    }
    bagstest::recordFigure("normal_vs_fd_gradient_max", worst);
}

TEST(RigidShapes, NormalDerivativeMatchesFiniteDifferences) {
    std::mt19937 rng(13);
    double worst = 0.0;
    auto shapes = makeAllShapes();
    for (size_t k = 0; k < shapes.size(); ++k) {
        const auto& s = shapes[k];
        for (const Vec3& p : smoothPoints(*s, kindOf(k), 30, rng)) {
            const Mat3 dn = s->calcNormalDerivative(p);
            Mat3 fd;
            const double h = 1e-6;
            for (int i = 0; i < 3; ++i) {
                Vec3 dp = Vec3::Zero(), np, nm;
                dp[i] = h;
                s->calcSignedDistance(p + dp, nullptr, &np);
                s->calcSignedDistance(p - dp, nullptr, &nm);
                fd.col(i) = (np - nm) / (2 * h);
            }
            // Curvatures here are up to ~1/(5 mm); FD error ~ h^2 k^3 + eps/h ~ 1e-6 relative.
            EXPECT_LT((dn - fd).norm(), 1e-5 * (1.0 + fd.norm()))
                << s->getName() << " at " << p.transpose() << "\n"
                << dn << "\n"
                << fd;
            EXPECT_LT((dn - dn.transpose()).norm(), 1e-9 * (1.0 + dn.norm()));
            worst = std::max(worst, (dn - fd).norm() / (1.0 + fd.norm()));
        }
    }
    bagstest::recordFigure("dndp_vs_fd_rel_max", worst);
}

namespace {

/// Contact nodes placed at given penetrations below random surface points of the shape.
Eigen::Matrix3Xd placeNodes(const bags::RigidShape& s, Kind kind, const bags::Mesh& mesh,
                            const std::vector<double>& gaps, std::mt19937& rng) {
    const auto pts = smoothPoints(s, kind, mesh.getNumNodes(), rng);
    Eigen::Matrix3Xd x(3, mesh.getNumNodes());
    for (int i = 0; i < mesh.getNumNodes(); ++i) {
        Vec3 c, n;
        s.calcSignedDistance(pts[i], &c, &n);
        x.col(i) = c + gaps[i % gaps.size()] * n;
    }
    return x;
}

std::vector<int> allNodes(const bags::Mesh& m) {
    std::vector<int> v(m.getNumNodes());
    for (int i = 0; i < m.getNumNodes(); ++i) v[i] = i;
    return v;
}

}  // namespace

namespace {

/// The frictionless contact's gradient and Hessian against central differences on every shape,
/// onset 0 and 1 mm, nodes at the given gaps (tolerances 1e-6 / 1e-5 relative: FD truncation
/// and round-off ~ 1e-7); `options` gives the rest of the law. Each case's gradient must
/// exceed minGrad [N] (the contact really active); `perCase` runs on each case's contact and x.
/// Returns the largest relative errors (gradient, Hessian).
std::pair<double, double> checkContactDerivatives(
    const bags::RigidContact::Options& options, const std::vector<double>& gaps, std::mt19937& rng,
    double minGrad,
    const std::function<void(const bags::RigidShape&, double, const Eigen::Matrix3Xd&,
                             const bags::RigidContact&)>& perCase = {}) {
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    double gradErr = 0.0, hessErr = 0.0;
    for (double onset : {0.0, 1e-3}) {
        auto shapes = makeAllShapes();
        for (size_t k = 0; k < shapes.size(); ++k) {
            const auto& s = shapes[k];
            bags::RigidContact::Options o = options;
            o.onsetGap = onset;
            bags::RigidContact contact(mesh, allNodes(mesh), *s, o);
            EXPECT_TRUE(contact.isConservative());
            const Eigen::Matrix3Xd x = placeNodes(*s, kindOf(k), mesh, gaps, rng);
            const DifferencedContact dc = differenceContact(contact, x, 1e-8);
            const Evaluated& ev = dc.ev;
            const Eigen::VectorXd& gFd = dc.gradFd;
            const Eigen::MatrixXd& hFd = dc.hessFd;
            EXPECT_LT((ev.grad - gFd).norm(), 1e-6 * ev.grad.norm()) << s->getName() << onset;
            EXPECT_LT((ev.hess - hFd).norm(), 1e-5 * ev.hess.norm()) << s->getName() << onset;
            EXPECT_GT(ev.grad.norm(), minGrad) << s->getName();
            gradErr = std::max(gradErr, (ev.grad - gFd).norm() / ev.grad.norm());
            hessErr = std::max(hessErr, (ev.hess - hFd).norm() / ev.hess.norm());
            if (perCase) perCase(*s, onset, x, contact);
        }
    }
    return {gradErr, hessErr};
}

}  // namespace

TEST(RigidContact, GradientAndHessianMatchFiniteDifferencesWithoutFriction) {
    std::mt19937 rng(17);
    // Forces ~ 1-20 N, stiffness ~ 1e3 N/m.
    const auto err = checkContactDerivatives(
        bags::RigidContact::Options(),
        {-2e-3, -5e-4, -1e-4, -1e-3, 3e-3, -3e-4, 1e-4, -6e-4, -1.5e-3}, rng, 0.1);
    bagstest::recordFigure("rigid_grad_fd_rel_err", err.first);
    bagstest::recordFigure("rigid_hess_fd_rel_err", err.second);
}

TEST(RigidContact, SmoothOnsetIsC2AndExactBeyondHalfWidth) {
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    bags::RigidContact::Options o;
    o.onsetGap = 1e-3;
    bags::RigidContact contact(mesh, {4}, *plane, o);  // centre node, area 1e-4 m^2
    const double k = o.pressurePenalty * 1e-4;
    auto fz = [&](double z) {
        Eigen::Matrix3Xd x = mesh.X;
        x(2, 4) = z;
        bags::EnergyAccumulator acc(mesh.getNumNodes());
        contact.addEnergy(x, acc);
        Eigen::SparseMatrix<double> H(27, 27);
        H.setFromTriplets(acc.hess.begin(), acc.hess.end());
        return std::make_pair(-acc.grad[14], H.coeff(14, 14));
    };
    // Force and stiffness continuous at the ramp ends: across +-1e-12 m the force may change
    // by at most k * 2e-12 = 2e-9 N, the stiffness by 1e-6 k (a jump would be O(k)).
    for (double z : {5e-4, -5e-4}) {
        const auto a = fz(z + 1e-12), b = fz(z - 1e-12);
        EXPECT_NEAR(a.first, b.first, 3e-9);
        EXPECT_NEAR(a.second, b.second, 1e-6 * k);
    }
    EXPECT_EQ(fz(6e-4).first, 0.0);
    // Beyond -w/2 the pressure is exactly pressurePenalty * penetration (1e-12 relative).
    const double pen = 2e-3;
    EXPECT_NEAR(fz(-pen).first, k * pen, 1e-12 * k * pen);
    EXPECT_NEAR(fz(-pen).second, k, 1e-9 * k);
}

TEST(RigidContact, FlatPatchOnPlaneCarriesPenaltyTimesPenetration) {
    const double s = 0.005, pen = 1e-3;
    const bags::Mesh mesh = bagstest::makeGridMesh(11, 7, s, Vec3(-0.02, 0.01, 0.0));
    auto plane = bags::makePlane();
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(0, 0, pen);  // plane raised by pen: uniform penetration
    plane->setPose(X);
    bags::RigidContact::Options o;
    bags::RigidContact contact(mesh, allNodes(mesh), *plane, o);
    const Eigen::VectorXd p = contact.calcNodalPressure(mesh.X);
    // Reference: p = pressurePenalty * penetration = 1e7 * 1e-3 = 10 kPa at every node (1e-9).
    for (int i = 0; i < mesh.getNumNodes(); ++i) EXPECT_NEAR(p[i], 1e4, 1e-9 * 1e4);
    Vec3 F, T;
    contact.calcWrenchOnShape(mesh.X, &F, &T);
    const double area = 10 * s * 6 * s;
    // Total force = pressure * area, pushing the plane down (relative 1e-12).
    EXPECT_NEAR(F.z(), -1e4 * area, 1e-12 * 1e4 * area);
    EXPECT_NEAR(F.head<2>().norm(), 0.0, 1e-12);
    EXPECT_EQ(contact.getNumActive(mesh.X), mesh.getNumNodes());
}

TEST(RigidContact, FrictionIsLinearInStickCappedInSlipAndAnchorsFollowCommit) {
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    bags::RigidContact::Options o;
    o.friction = 0.3;
    bags::RigidContact contact(mesh, {4}, *plane, o);
    EXPECT_FALSE(contact.isConservative());
    const double k = 1e7 * 1e-4;  // [N/m] centre node area 1e-4 m^2
    const double fn = k * 1e-3;   // 1 mm penetration: 1 N
    const double cap = 0.3 * fn;
    auto forceAt = [&](double ux, double uy) {
        Eigen::Matrix3Xd x = mesh.X;
        x.col(4) = Vec3(ux, uy, -1e-3);
        bags::EnergyAccumulator acc(mesh.getNumNodes());
        contact.addEnergy(x, acc);
        return Vec3(-acc.grad.segment<3>(12));
    };
    auto commitAt = [&](double ux, double uy, double z = -1e-3) {
        Eigen::Matrix3Xd x = mesh.X;
        x.col(4) = Vec3(ux, uy, z);
        contact.commitStep(x);
    };
    // Pressed: no anchor yet, no tangential force.
    EXPECT_EQ(forceAt(0.01, 0.01).head<2>().norm(), 0.0);
    commitAt(0.01, 0.01);  // anchor at (10, 10) mm
    // Stick: f_t = -k_t u, linear (1e-12 relative).
    for (double u : {0.05e-3, 0.1e-3, 0.2e-3}) {
        const Vec3 f = forceAt(0.01 + u, 0.01);
        EXPECT_NEAR(f.x(), -k * u, 1e-12 * k * u);
        EXPECT_NEAR(f.z(), fn, 1e-12);
    }
    // Slip: |f_t| = mu f_n, opposite to the drag (1e-12 N).
    const Vec3 fs = forceAt(0.01 + 0.8e-3, 0.01 + 0.6e-3);
    EXPECT_NEAR(fs.head<2>().norm(), cap, 1e-12);
    EXPECT_NEAR(fs.x() / fs.y(), 0.8 / 0.6, 1e-12);
    EXPECT_LT(fs.x(), 0.0);
    // Commit in slip: the anchor follows so that the stored offset carries exactly the cap.
    commitAt(0.011, 0.01);
    EXPECT_NEAR(forceAt(0.011, 0.01).x(), -cap, 1e-12);
    // Stepping back 0.1 mm unloads elastically: f = -(0.3 mm - 0.1 mm) k (stick again).
    EXPECT_NEAR(forceAt(0.0109, 0.01).x(), -k * 0.2e-3, 1e-12);
    // The anchor is stored in the shape frame: sliding the plane by +0.3 mm under the node
    // drags the anchor to the node and the force vanishes.
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(0.3e-3, 0, 0);
    plane->setPose(X);
    EXPECT_NEAR(forceAt(0.011, 0.01).x(), 0.0, 1e-12);
    // Lifted off and committed: anchor released; pressed again elsewhere: no tangential force.
    commitAt(0.011, 0.01, 1e-3);
    EXPECT_EQ(forceAt(0.02, 0.0).head<2>().norm(), 0.0);
}

TEST(RigidContact, RestoredHistoryUndoesCommitsOfAnAbandonedStep) {
    // A step that committed trial states and was then abandoned must leave the friction anchors
    // as they were: the restored contact gives the same forces as one that never saw the trial
    // (exactly: the same stored numbers).
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    bags::RigidContact::Options o;
    o.friction = 0.3;
    bags::RigidContact contact(mesh, {4}, *plane, o);
    auto at = [&](double ux) {
        Eigen::Matrix3Xd x = mesh.X;
        x.col(4) = Vec3(ux, 0.0, -1e-3);
        return x;
    };
    auto forceX = [&](double ux) {
        bags::EnergyAccumulator acc(mesh.getNumNodes());
        contact.addEnergy(at(ux), acc);
        return -acc.grad(12);
    };
    contact.commitStep(at(0.01));  // anchor at 10 mm
    const bags::RigidContact::History h = contact.getHistory();
    const double before = forceX(0.0101);
    contact.commitStep(at(0.012));                       // trial: slips 2 mm, anchor dragged along
    EXPECT_GT(std::abs(forceX(0.0101) - before), 1e-3);  // the trial moved the anchor
    contact.setHistory(h);
    EXPECT_EQ(forceX(0.0101), before);
    contact.commitStep(at(0.015));  // a second trial, restored again
    contact.setHistory(h);
    EXPECT_EQ(forceX(0.0101), before);
    // A history of another contact set is refused.
    bags::RigidContact other(mesh, {3, 4}, *plane, o);
    EXPECT_THROW(other.setHistory(h), std::invalid_argument);
}

TEST(RigidContact, StickTangentMatchesFiniteDifferencesOnPlane) {
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    plane->setPose(somePose());
    bags::RigidContact::Options o;
    o.friction = 0.5;
    o.stickStiffnessRatio = 0.5;
    bags::RigidContact contact(mesh, allNodes(mesh), *plane, o);
    Eigen::Matrix3Xd x0(3, mesh.getNumNodes());
    for (int i = 0; i < mesh.getNumNodes(); ++i)
        x0.col(i) = plane->getPose() * Vec3(0.01 * i, 0.005 * i, -1e-3);
    contact.commitStep(x0);
    Eigen::Matrix3Xd x = x0;
    for (int i = 0; i < mesh.getNumNodes(); ++i)  // small drags: all stick
        x.col(i) += plane->getPose().linear() * Vec3(1e-4 * std::sin(i), 1e-4 * std::cos(i), 0);
    const DifferencedContact dc = differenceContact(contact, x, 1e-8);
    const Evaluated& ev = dc.ev;
    const Eigen::VectorXd& gFd = dc.gradFd;
    const Eigen::MatrixXd& hFd = dc.hessFd;
    // In stick the friction term is an energy: exact on a plane (FD error ~ 1e-7 relative).
    EXPECT_LT((ev.grad - gFd).norm(), 1e-6 * ev.grad.norm());
    EXPECT_LT((ev.hess - hFd).norm(), 1e-5 * ev.hess.norm());
    bagstest::recordFigure("stick_grad_fd_rel_err", (ev.grad - gFd).norm() / ev.grad.norm());
    bagstest::recordFigure("stick_hess_fd_rel_err", (ev.hess - hFd).norm() / ev.hess.norm());
}

TEST(RigidContact, SlipTangentIsExactForTangentialMotionOnPlane) {
    // In slip the only term left out of the tangent couples the friction force to normal motion
    // (d f_n / d g); on a plane, tangential motion keeps g, so those columns must match FD.
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    bags::RigidContact::Options o;
    o.friction = 0.3;
    bags::RigidContact contact(mesh, {4}, *plane, o);
    Eigen::Matrix3Xd x = mesh.X;
    x(2, 4) = -1e-3;
    contact.commitStep(x);
    x(0, 4) += 0.8e-3;  // slip: k_t u = 0.8 N > mu f_n = 0.3 N
    x(1, 4) += 0.5e-3;
    const DifferencedContact dc = differenceContact(contact, x, 1e-9);
    const Evaluated& ev = dc.ev;
    const Eigen::MatrixXd& hFd = dc.hessFd;
    const Eigen::Matrix<double, 3, 2> h = ev.hess.block<3, 2>(12, 12);
    const Eigen::Matrix<double, 3, 2> f = hFd.block<3, 2>(12, 12);
    // Tangent of the capped force ~ mu f_n / |d_t| ~ 320 N/m; FD error ~ 1e-6 relative.
    EXPECT_LT((h - f).norm(), 1e-5 * f.norm());
    EXPECT_GT(f.norm(), 100.0);
    EXPECT_NEAR(Vec3(-ev.grad.segment<3>(12)).head<2>().norm(), 0.3 * 1.0, 1e-12);
}

TEST(RigidContact, FullFrictionTangentMatchesFiniteDifferencesForBothLawsOnEveryShape) {
    // calcNodeTangents() is the exact derivative of each node's force law, the coupling of the
    // friction force to the normal force (mu t (d f_n/dp)^T) and the curvature terms included.
    // Nodes pressed 0.5-2 mm at smooth points of every shape, anchored, then dragged along the
    // surface by 5 um to 1 mm: with the regularised law (slip length v_s dt = 20 um) from the
    // viscous range to full sliding, with the stick-slip law (stick up to mu f_n / k_t = 0.25-
    // 1 mm) in stick and in slip. Against central differences of the gradient (step 1 nm):
    // per node block, relative to the block (FD error ~ (h / 5 um)^2 ~ 1e-7).
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    std::mt19937 rng(29);
    const std::vector<double> gaps = {-2e-3,   -5e-4, -1e-3, -1.5e-3, -7e-4,
                                      -1.2e-3, -8e-4, -2e-3, -6e-4};
    const std::vector<double> drags = {5e-6, 2e-5, 1e-4, 1e-3, 3e-5, 4e-4, 8e-6, 2e-4, 6e-5};
    double worst = 0.0, coupling = 0.0;
    for (auto law : {bags::RigidContact::FrictionLaw::Regularised,
                     bags::RigidContact::FrictionLaw::StickSlip}) {
        auto shapes = makeAllShapes();
        for (size_t k = 0; k < shapes.size(); ++k) {
            const auto& s = shapes[k];
            bags::RigidContact::Options o;
            o.friction = 0.5;
            o.frictionLaw = law;
            bags::RigidContact contact(mesh, allNodes(mesh), *s, o);
            const Eigen::Matrix3Xd x0 = placeNodes(*s, kindOf(k), mesh, gaps, rng);
            contact.commitStep(x0);       // anchors where the nodes touch
            contact.beginStep(x0, 0.01);  // a 10 ms step: slip length 20 um
            Eigen::Matrix3Xd x = x0;
            std::uniform_real_distribution<double> angle(0.0, 6.283);
            for (int i = 0; i < mesh.getNumNodes(); ++i) {
                Vec3 n;
                s->calcSignedDistance(x0.col(i), nullptr, &n);
                const Vec3 a = n.unitOrthogonal(), b = n.cross(a);
                const double th = angle(rng);
                x.col(i) += drags[i] * (std::cos(th) * a + std::sin(th) * b);
            }
            auto add = [&](const Eigen::Matrix3Xd& xx, bags::EnergyAccumulator& acc) {
                contact.addEnergy(xx, acc);
            };
            Eigen::VectorXd gFd;
            Eigen::MatrixXd hFd;
            finiteDifferences(add, x, 1e-9, gFd, hFd);
            const std::vector<Mat3> T = contact.calcNodeTangents(x);
            ASSERT_EQ(T.size(), static_cast<size_t>(mesh.getNumNodes()));
            for (int i = 0; i < mesh.getNumNodes(); ++i) {
                const Mat3 f = hFd.block<3, 3>(3 * i, 3 * i);
                const double err = (T[i] - f).norm() / f.norm();
                EXPECT_LT(err, 1e-5)
                    << s->getName() << " node " << i << " drag " << drags[i]
                    << (law == bags::RigidContact::FrictionLaw::Regularised ? " regularised"
                                                                            : " stick-slip")
                    << "\nexact\n"
                    << T[i] << "\nFD\n"
                    << f;
                worst = std::max(worst, err);
                // The f_n coupling: its size against the block's (leaving it out fails).
                Vec3 nn;
                s->calcSignedDistance(x.col(i), nullptr, &nn);
                coupling = std::max(coupling, (f * nn - (nn.dot(f * nn)) * nn).norm() / f.norm());
            }
        }
    }
    EXPECT_GT(coupling, 0.1);  // the friction force does follow the normal force
    bagstest::recordFigure("friction_full_tangent_fd_rel_err", worst);
}

TEST(RigidContact, RegularisedFrictionIsViscousBelowTheSlipVelocityAndCoulombAbove) {
    // One node pressed 1 mm into a plane (f_n = 1 N), mu = 0.3, v_s = 2 mm/s; the plane slides
    // under the held node at v over a step dt, so the node slips by -v dt on it. The law:
    // f_t = mu f_n v / sqrt(v^2 + v_s^2) against the slip: viscous, slope mu f_n / v_s, well
    // below v_s (v = 0.01 v_s: 0.99995 of the slope), mu f_n well above it (v = 20 v_s:
    // 0.99875 mu f_n; v = 100 v_s: 0.99995). The same v over a step 10 times shorter gives the
    // same force (a rate law, not a slip-length law).
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    bags::RigidContact::Options o;
    o.friction = 0.3;
    o.frictionLaw = bags::RigidContact::FrictionLaw::Regularised;
    o.slipVelocity = 2e-3;
    bags::RigidContact contact(mesh, {4}, *plane, o);
    const double fn = 1e7 * 1e-4 * 1e-3, muN = 0.3 * fn, vs = 2e-3;
    Eigen::Matrix3Xd x = mesh.X;
    x.col(4) = Vec3(0.01, 0.01, -1e-3);
    auto forceX = [&]() {
        bags::EnergyAccumulator acc(mesh.getNumNodes());
        contact.addEnergy(x, acc);
        EXPECT_NEAR(-acc.grad(14), fn, 1e-12);
        EXPECT_NEAR(acc.grad(13), 0.0, 1e-12);
        return -acc.grad(12);
    };
    auto drag = [&](double v, double dt) {  // the plane moves by -v dt under the node
        plane->setPose(Eigen::Isometry3d::Identity());
        contact.commitStep(x);  // touched: anchored
        contact.beginStep(x, dt);
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = Vec3(-v * dt, 0.0, 0.0);
        plane->setPose(X);
        return forceX();  // the node slipped +v dt on the plane: the force points back, -x
    };
    for (double dt : {0.01, 0.001}) {
        for (double v : {0.01 * vs, 0.1 * vs, vs, 20.0 * vs, 100.0 * vs}) {
            const double f = drag(v, dt);
            const double exact = -muN * v / std::sqrt(v * v + vs * vs);
            EXPECT_NEAR(f, exact, 1e-12 * muN) << "v " << v << " dt " << dt;
            if (v <= 0.01 * vs) {  // viscous
                EXPECT_NEAR(f / v, -muN / vs, 1e-4 * muN / vs);
            }
            if (v >= 20.0 * vs) {  // Coulomb
                EXPECT_NEAR(f, -muN, 2e-3 * muN);
            }
            if (v >= 100.0 * vs) {
                EXPECT_NEAR(f, -muN, 1e-4 * muN);
            }
        }
    }
    // The committed state keeps its step's force until the next step begins; that step's
    // slip starts from zero; a restored history brings back the step's slip length.
    const double f = drag(vs, 0.01);
    const bags::RigidContact::History h = contact.getHistory();
    contact.commitStep(x);
    EXPECT_EQ(forceX(), f);
    contact.beginStep(x, 0.001);
    EXPECT_NEAR(forceX(), 0.0, 1e-9 * muN);
    contact.setHistory(h);
    EXPECT_EQ(forceX(), f);
    // No time (a quasi-static ramp): Coulomb's rate-independent limit, mu f_n at 1 um of slip
    // (slip length 10 nm: 0.99995).
    plane->setPose(Eigen::Isometry3d::Identity());
    contact.beginStep(x, 0.0);
    x(0, 4) += 1e-6;
    EXPECT_NEAR(forceX(), -muN, 1e-4 * muN);
    EXPECT_THROW(contact.beginStep(x, -1.0), std::invalid_argument);
    o.slipVelocity = 0.0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
}

TEST(RigidContact, WrenchIsReactionOfNodalForcesAndMatchesEnergyRate) {
    const bags::Mesh mesh = bagstest::makeGridMesh(4, 4, 0.01, Vec3::Zero());
    std::mt19937 rng(23);
    auto shapes = makeAllShapes();
    for (size_t k = 0; k < shapes.size(); ++k) {
        const auto& s = shapes[k];
        bags::RigidContact contact(mesh, allNodes(mesh), *s, bags::RigidContact::Options());
        const Eigen::Matrix3Xd x =
            placeNodes(*s, kindOf(k), mesh, {-1e-3, -2e-4, -5e-4, 1e-3}, rng);
        bags::EnergyAccumulator acc(mesh.getNumNodes());
        contact.addEnergy(x, acc);
        Vec3 F, T;
        contact.calcWrenchOnShape(x, &F, &T);
        // Action-reaction: force on the shape = - sum of the nodal contact forces (1e-12 N).
        Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
        const Vec3 o = s->getPose().translation();
        for (int i = 0; i < mesh.getNumNodes(); ++i) {
            sum += acc.grad.segment<3>(3 * i);
            torque += (x.col(i) - o).cross(Vec3(acc.grad.segment<3>(3 * i)));
        }
        EXPECT_LT((F - sum).norm(), 1e-12 * (1 + F.norm())) << s->getName();
        EXPECT_LT((T - torque).norm(), 1e-12 * (1 + T.norm())) << s->getName();
        // Generalised force on the shape = - dE/d(pose): translate and rotate the shape by
        // +-h and difference the energy (central FD, 1e-6 relative).
        const Eigen::Isometry3d X0 = s->getPose();
        auto energyAt = [&](const Eigen::Isometry3d& X) {
            s->setPose(X);
            bags::EnergyAccumulator a(mesh.getNumNodes());
            a.wantGradient = a.wantHessian = false;
            contact.addEnergy(x, a);
            return a.energy;
        };
        const double h = 1e-7;
        for (int i = 0; i < 3; ++i) {
            Eigen::Isometry3d Xp = X0, Xm = X0;
            Xp.translation()[i] += h;
            Xm.translation()[i] -= h;
            const double dEdu = (energyAt(Xp) - energyAt(Xm)) / (2 * h);
            EXPECT_NEAR(-dEdu, F[i], 1e-6 * F.norm() + 1e-9) << s->getName();
            const Mat3 Rp = Eigen::AngleAxisd(h, Vec3::Unit(i)).toRotationMatrix();
            Xp = X0;
            Xm = X0;
            Xp.linear() = Rp * X0.linear();
            Xm.linear() = Rp.transpose() * X0.linear();
            const double dEdth = (energyAt(Xp) - energyAt(Xm)) / (2 * h);
            EXPECT_NEAR(-dEdth, T[i], 1e-6 * T.norm() + 1e-9) << s->getName();
        }
        s->setPose(X0);
        EXPECT_GT(F.norm(), 0.1) << s->getName();
    }
}

TEST(RigidContact, ThreadedEvaluationMatchesSerial) {
    const bags::Mesh mesh = bagstest::makeGridMesh(80, 80, 0.004, Vec3(-0.16, -0.16, 0.0));
    auto e = bags::makeEllipsoid(Vec3(0.2, 0.15, 0.08));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(0, 0, 0.075);  // 5 mm into the grid
    e->setPose(X);
    bags::RigidContact::Options serial, threaded;
    serial.minNodesForThreads = 1 << 30;
    threaded.minNodesForThreads = 1;
    threaded.friction = serial.friction = 0.2;
    bags::RigidContact a(mesh, allNodes(mesh), *e, serial), b(mesh, allNodes(mesh), *e, threaded);
    Eigen::Matrix3Xd x = mesh.X;
    a.commitStep(x);
    b.commitStep(x);
    x.row(0).array() += 2e-4;
    bags::EnergyAccumulator ea(mesh.getNumNodes()), eb(mesh.getNumNodes());
    a.addEnergy(x, ea);
    b.addEnergy(x, eb);
    // Same per-node arithmetic, same summation order: identical results.
    EXPECT_EQ(ea.energy, eb.energy);
    EXPECT_EQ((ea.grad - eb.grad).norm(), 0.0);
    ASSERT_EQ(ea.hess.size(), eb.hess.size());
    for (size_t i = 0; i < ea.hess.size(); ++i) {
        EXPECT_EQ(ea.hess[i].row(), eb.hess[i].row());
        EXPECT_EQ(ea.hess[i].col(), eb.hess[i].col());
        EXPECT_EQ(ea.hess[i].value(), eb.hess[i].value());
    }
    EXPECT_GT(a.getNumActive(x), 100);
}

TEST(RigidContact, OptionsValidateRejectsBadValues) {
    bags::RigidContact::Options o;
    EXPECT_NO_THROW(o.validate());
    o.pressurePenalty = 0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.friction = -0.1;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.stickStiffnessRatio = 0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.onsetGap = -1e-3;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    EXPECT_THROW(bags::makeBox(Vec3(0.1, 0.05, 0.02), 0.02), std::invalid_argument);
    EXPECT_THROW(bags::makeEllipsoid(Vec3(0.1, 0.0, 0.02)), std::invalid_argument);
    const bags::Mesh mesh = bagstest::makeGridMesh(2, 2, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    EXPECT_THROW(bags::RigidContact(mesh, {0, 4}, *plane, bags::RigidContact::Options()),
                 std::invalid_argument);
}

// ------------------------------------------------------------------------------ tissue layer

TEST(TissueLayer, StressIsTheEnergysSlopeAndStiffnessIsItsC1Derivative) {
    const double h = 0.015, E = 5e4, d = 1e-8;
    // Through the neo-Hookean range and past the linear continuation at 80 % compression.
    for (double c : {1e-4, 2e-3, 6e-3, 1.1e-2, 0.8 * h - 1e-6, 0.8 * h + 1e-6, 1.4e-2, 2e-2}) {
        const bags::TissueStress t = bags::calcTissueStress(c, h, E);
        const bags::TissueStress p = bags::calcTissueStress(c + d, h, E);
        const bags::TissueStress m = bags::calcTissueStress(c - d, h, E);
        const double w = 2 * d;
        // Central differences, 1e-6 relative to the larger of the values (truncation ~ 1e-10).
        EXPECT_NEAR((p.energy - m.energy) / w, t.sigma, 1e-6 * (t.sigma + E * 1e-3)) << c;
        EXPECT_NEAR((p.sigma - m.sigma) / w, t.dsigma, 1e-5 * t.dsigma) << c;
    }
    // At no compression: no stress, the Winkler stiffness E / h.
    EXPECT_EQ(bags::calcTissueStress(0.0, h, E).sigma, 0.0);
    EXPECT_NEAR(bags::calcTissueStress(0.0, h, E).dsigma, E / h, 1e-12 * E / h);
    // Continuous in value and slope where the continuation starts (C1: the energy is C2).
    const double cm = (1 - bags::kTissueMinStretch) * h;
    const bags::TissueStress a = bags::calcTissueStress(cm - 1e-12, h, E);
    const bags::TissueStress b = bags::calcTissueStress(cm + 1e-12, h, E);
    EXPECT_NEAR(a.sigma, b.sigma, 1e-6 * a.sigma);
    EXPECT_NEAR(a.dsigma, b.dsigma, 1e-6 * a.dsigma);
}

TEST(TissueLayer, GradientAndHessianMatchFiniteDifferencesOnEveryShape) {
    std::mt19937 rng(29);
    bags::RigidContact::Options o;
    o.tissueThickness = 0.015;
    o.tissueModulus = 5e4;
    // The layer softens the contact: less pressure than the bare penalty's at every node.
    auto softer = [](const bags::RigidShape& s, double onset, const Eigen::Matrix3Xd& x,
                     const bags::RigidContact& contact) {
        bags::RigidContact::Options bare;
        bare.onsetGap = onset;
        const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
        bags::RigidContact rigid(mesh, allNodes(mesh), s, bare);
        const Eigen::VectorXd pl = contact.calcNodalPressure(x);
        const Eigen::VectorXd pr = rigid.calcNodalPressure(x);
        for (int i = 0; i < x.cols(); ++i) EXPECT_LE(pl[i], pr[i]) << s.getName() << " " << i;
    };
    // Overlaps through small strain, the stiffening range, the continuation past 80 % of the
    // 15 mm layer (12 mm) and out of contact; forces ~ 0.05-3 N, stiffness ~ 1e2-1e3 N/m.
    const auto err = checkContactDerivatives(
        o, {-5e-4, -3e-3, -8e-3, -1.3e-2, 2e-3, -1e-4, -1.6e-2, 4e-4, -6e-3}, rng, 0.05, softer);
    bagstest::recordFigure("tissue_grad_fd_rel_err", err.first);
    bagstest::recordFigure("tissue_hess_fd_rel_err", err.second);
}

TEST(TissueLayer, WrenchTangentsMatchFiniteDifferencesWithFriction) {
    // The node derivative of the wrench (the body's tangent) and the stick tangent with a layer.
    const bags::Mesh mesh = bagstest::makeGridMesh(3, 3, 0.01, Vec3::Zero());
    auto plane = bags::makePlane();
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Vec3(0, 0, 4e-3);  // 4 mm into a 10 mm layer
    plane->setPose(X);
    bags::RigidContact::Options o;
    o.friction = 0.5;
    o.tissueThickness = 0.01;
    o.tissueModulus = 3e4;
    bags::RigidContact contact(mesh, allNodes(mesh), *plane, o);
    Eigen::Matrix3Xd x = mesh.X;
    contact.commitStep(x);     // anchors where the nodes touch
    x.row(0).array() += 1e-6;  // a small tangential offset: stick
    const DifferencedContact dc = differenceContact(contact, x, 1e-9);
    const Evaluated& ev = dc.ev;
    const Eigen::MatrixXd& hFd = dc.hessFd;
    EXPECT_LT((ev.hess - hFd).norm(), 1e-5 * ev.hess.norm());
    // The wrench's node derivative is -(d grad / d x) summed into force and torque rows.
    const Eigen::MatrixXd D = contact.calcWrenchNodeDerivative(x);
    Eigen::MatrixXd Dfd(6, 3 * mesh.getNumNodes());
    for (int c = 0; c < 3 * mesh.getNumNodes(); ++c) {
        Eigen::Matrix3Xd xp = x, xm = x;
        xp(c % 3, c / 3) += 1e-8;
        xm(c % 3, c / 3) -= 1e-8;
        Vec3 Fp, Tp, Fm, Tm;
        contact.calcWrenchOnShape(xp, &Fp, &Tp);
        contact.calcWrenchOnShape(xm, &Fm, &Tm);
        Dfd.col(c) << (Tp - Tm) / 2e-8, (Fp - Fm) / 2e-8;
    }
    EXPECT_LT((D - Dfd).norm(), 1e-5 * D.norm());
    EXPECT_GT(D.norm(), 10.0);
    bagstest::recordFigure("tissue_stick_hess_fd_rel_err", (ev.hess - hFd).norm() / ev.hess.norm());
    bagstest::recordFigure("tissue_wrench_node_derivative_rel_err", (D - Dfd).norm() / D.norm());
}

TEST(TissueLayer, FlatPunchCompressesTheLayerByForceTimesThicknessOverModulusTimesArea) {
    // A flat rigid punch (the plane) with a layer pressed uniformly into a flat patch: every
    // node carries the same pressure p = F / A; the penalty takes p / pressurePenalty of the
    // penetration, the layer the rest, c = delta - p / pressurePenalty. Reference: the
    // neo-Hookean law's inverse (1e-9), and at small strain the Winkler layer c = F h / (E A).
    const double s = 0.005, h = 0.015, E = 5e4;
    const bags::Mesh mesh = bagstest::makeGridMesh(11, 7, s, Vec3(-0.02, 0.01, 0.0));
    const double area = 10 * s * 6 * s;
    auto plane = bags::makePlane();
    bags::RigidContact::Options o;
    o.tissueThickness = h;
    o.tissueModulus = E;
    bags::RigidContact contact(mesh, allNodes(mesh), *plane, o);
    for (double delta : {2e-4, 1e-3, 5e-3}) {
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = Vec3(0, 0, delta);
        plane->setPose(X);
        Vec3 F, T;
        contact.calcWrenchOnShape(mesh.X, &F, &T);
        const double p = -F.z() / area;
        const Eigen::VectorXd pn = contact.calcNodalPressure(mesh.X);
        for (int i = 0; i < mesh.getNumNodes(); ++i) EXPECT_NEAR(pn[i], p, 1e-9 * p);
        const double c = delta - p / o.pressurePenalty;
        const double l = 1 - c / h;
        EXPECT_NEAR(E / 3 * (1 / (l * l) - l), p, 1e-9 * p) << delta;
        // Winkler: c = F h / (E A), to the law's first nonlinear term (relative c / h: the
        // Winkler value is 1 + 1.07 c / h of it at 5 % strain, 1 + 1.43 c / h at 23 %).
        const double winkler = -F.z() * h / (E * area);
        EXPECT_NEAR(c, winkler, 1.5 * (c / h) * c) << delta;
        if (delta == 2e-4) {
            EXPECT_NEAR(c, winkler, 0.015 * c);  // 1 % strain: within 1.5 %
        }
    }
}
