#include "cosim/BodyShapes.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cosim {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

class RoundCone : public bags::LocalRigidShape {
  public:
    RoundCone(const Vec3& pA, double rA, const Vec3& pB, double rB)
        : m_pA(pA), m_pB(pB), m_rA(rA), m_rB(rB) {
        const double h = (pB - pA).norm();
        if (!(rA > 0.0 && rB > 0.0 && h > std::abs(rA - rB))) {
            std::ostringstream s;
            s << "makeRoundCone: radii " << rA << " m, " << rB << " m and centres " << h
              << " m apart; valid: positive radii and centres further apart than the radii "
                 "differ";
            throw std::invalid_argument(s.str());
        }
        m_h = h;
        m_e = (pB - pA) / h;
        m_sin = (rA - rB) / h;
        m_cos = std::sqrt(1.0 - m_sin * m_sin);
        m_bound = std::max(m_pA.norm() + m_rA, m_pB.norm() + m_rB);
    }
    double getBoundingRadius() const override { return m_bound; }
    /// The round cone lies inside the capsule of radius max(rA, rB) about the segment AB, so
    /// its signed distance is at least the capsule's, |p - closest point of AB| - max(rA, rB)
    /// (outside: the capsule is nearer; inside: the cone's surface is nearer than the
    /// capsule's). Tighter than the bounding sphere for a long limb.
    double calcDistanceLowerBound(const Vec3& p_G) const override {
        const Vec3 p = m_X_GS.linear().transpose() * (p_G - m_X_GS.translation());
        const double y = std::clamp((p - m_pA).dot(m_e), 0.0, m_h);
        return (p - m_pA - y * m_e).norm() - std::max(m_rA, m_rB);
    }
    /// The capsule's bound at most t: within max(rA, rB) + t of the segment AB.
    double getLowerBoundReach(double t) const override {
        return std::max(m_pA.norm(), m_pB.norm()) + std::max(0.0, std::max(m_rA, m_rB) + t);
    }
    std::string getName() const override { return "round-cone"; }

  protected:
    void evalLocal(const Vec3& p, double& d, Vec3& c, Vec3& n, Mat3* dnOut) const override {
        const Vec3 v = p - m_pA;
        const double y = v.dot(m_e);
        const Vec3 w = v - y * m_e;
        const double x = w.norm();
        // Off the axis er is the radial direction; on it any perpendicular will do (the
        // distance is the same; the normal's derivative is undefined there and left zero).
        Vec3 er;
        if (x > 1e-14 * m_h) {
            er = w / x;
        } else {
            er = m_e.unitOrthogonal();
        }
        const double s = -x * m_sin + y * m_cos;  // along the tangent line
        if (dnOut) dnOut->setZero();
        auto sphere = [&](const Vec3& centre, double r) {
            const Vec3 q = p - centre;
            const double len = q.norm();
            n = len > 0.0 ? Vec3(q / len) : Vec3(m_cos * er + m_sin * m_e);
            d = len - r;
            c = centre + r * n;
            if (dnOut && len > 0.0) *dnOut = (Mat3::Identity() - n * n.transpose()) / len;
        };
        if (s < 0.0) {
            sphere(m_pA, m_rA);
        } else if (s > m_h * m_cos) {
            sphere(m_pB, m_rB);
        } else {
            n = m_cos * er + m_sin * m_e;
            d = x * m_cos + y * m_sin - m_rA;
            c = p - d * n;
            if (dnOut && x > 1e-14 * m_h)
                *dnOut =
                    m_cos * (Mat3::Identity() - m_e * m_e.transpose() - er * er.transpose()) / x;
        }
    }

  private:
    Vec3 m_pA, m_pB, m_e;
    double m_rA, m_rB, m_h = 0.0, m_sin = 0.0, m_cos = 1.0, m_bound = 0.0;
};

Vec3 toEigen(const SimTK::Vec3& v) { return Vec3(v[0], v[1], v[2]); }

}  // namespace

std::unique_ptr<bags::RigidShape> makeRoundCone(const Vec3& pA, double rA, const Vec3& pB,
                                                double rB) {
    return std::make_unique<RoundCone>(pA, rA, pB, rB);
}

BagShapeOfBody makeBagShape(const body::ContactShape& s) {
    BagShapeOfBody out;
    if (s.getKind() == body::ContactShape::Kind::Ellipsoid) {
        out.shape = bags::makeEllipsoid(toEigen(s.getSemiAxes()));
        out.X_BS = s.getEllipsoidPose();
    } else {
        out.shape = makeRoundCone(toEigen(s.getPointA()), s.getRadiusA(), toEigen(s.getPointB()),
                                  s.getRadiusB());
        out.X_BS = SimTK::Transform();
    }
    return out;
}

}  // namespace cosim
