// Rigid analytic shapes for membrane contact: plane, (rounded) box, ellipsoid, capsule.
//
// Each shape evaluates its geometry in its own frame S (signed distance, closest point, outward
// normal and the normal's gradient d n / d p); the base class maps Ground points into S and the
// results back. The normal returned is the gradient of the signed distance wherever that is
// differentiable, so d n / d p is the (symmetric) Hessian of the distance.

#include <bags/Contact.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace bags {

void RigidShape::calcContactGeometry(const Vec3& p_G, double* distance, Vec3* closest_G,
                                     Vec3* normal_G, Mat3* dndp_G) const {
    const double d = calcSignedDistance(p_G, closest_G, normal_G);
    if (distance) *distance = d;
    if (dndp_G) *dndp_G = calcNormalDerivative(p_G);
}

double RigidShape::getBoundingRadius() const { return std::numeric_limits<double>::infinity(); }

double RigidShape::getLowerBoundReach(double t) const {
    // |p - o| - R <= t holds inside R + t.
    const double R = getBoundingRadius();
    return std::isfinite(R) ? std::max(0.0, R + t) : std::numeric_limits<double>::infinity();
}

double RigidShape::calcDistanceLowerBound(const Vec3& p_G) const {
    const double R = getBoundingRadius();
    if (!std::isfinite(R)) return calcSignedDistance(p_G, nullptr, nullptr);
    return (p_G - m_X_GS.translation()).norm() - R;
}

double LocalRigidShape::calcSignedDistance(const Vec3& p_G, Vec3* closest_G, Vec3* normal_G) const {
    double d;
    calcContactGeometry(p_G, &d, closest_G, normal_G, nullptr);
    return d;
}

Mat3 LocalRigidShape::calcNormalDerivative(const Vec3& p_G) const {
    Mat3 dn;
    calcContactGeometry(p_G, nullptr, nullptr, nullptr, &dn);
    return dn;
}

void LocalRigidShape::calcContactGeometry(const Vec3& p_G, double* distance, Vec3* closest_G,
                                          Vec3* normal_G, Mat3* dndp_G) const {
    const Mat3& R = m_X_GS.linear();
    const Vec3 p_S = R.transpose() * (p_G - m_X_GS.translation());
    double d;
    Vec3 c_S, n_S;
    Mat3 dn_S;
    evalLocal(p_S, d, c_S, n_S, dndp_G ? &dn_S : nullptr);
    if (distance) *distance = d;
    if (closest_G) *closest_G = m_X_GS * c_S;
    if (normal_G) *normal_G = R * n_S;
    if (dndp_G) *dndp_G = R * dn_S * R.transpose();
}

namespace {

class Plane final : public LocalRigidShape {
  public:
    std::string getName() const override { return "plane"; }
    double calcDistanceLowerBound(const Vec3& p_G) const override {
        return m_X_GS.linear().col(2).dot(p_G - m_X_GS.translation());
    }

  protected:
    void evalLocal(const Vec3& p, double& d, Vec3& c, Vec3& n, Mat3* dn) const override {
        d = p.z();
        c = Vec3(p.x(), p.y(), 0.0);
        n = Vec3::UnitZ();
        if (dn) dn->setZero();
    }
};

inline double signOf(double v) { return v < 0.0 ? -1.0 : 1.0; }

/// Box = inner box (half extents h - r) Minkowski sphere of radius r; exact signed distance.
class Box final : public LocalRigidShape {
  public:
    Box(const Vec3& h, double r) : m_h(h), m_r(r), m_inner(h.array() - r) {}
    std::string getName() const override { return "box"; }
    double getBoundingRadius() const override { return m_h.norm(); }
    /// The rounded box lies inside the sharp one, whose distance is at least max |p_i| - h_i.
    double calcDistanceLowerBound(const Vec3& p_G) const override {
        const Vec3 p = m_X_GS.linear().transpose() * (p_G - m_X_GS.translation());
        return (p.cwiseAbs() - m_h).maxCoeff();
    }
    /// max |p_i| - h_i <= t puts p in the box of half extents h + t.
    double getLowerBoundReach(double t) const override {
        return (m_h.array() + t).max(0.0).matrix().norm();
    }

  protected:
    void evalLocal(const Vec3& p, double& d, Vec3& c, Vec3& n, Mat3* dn) const override {
        const Vec3 q = p.cwiseAbs() - m_inner;  // > 0 where p lies beyond the inner box
        int iMax;
        const double qMax = q.maxCoeff(&iMax);
        if (qMax > 0.0) {
            // Outside the inner box: the normal points from its closest point to p.
            Vec3 w = Vec3::Zero();
            Mat3 D = Mat3::Zero();
            for (int i = 0; i < 3; ++i)
                if (q[i] > 0.0) {
                    w[i] = signOf(p[i]) * q[i];
                    D(i, i) = 1.0;
                }
            const double len = w.norm();
            n = w / len;
            d = len - m_r;
            c = p - d * n;
            if (dn) *dn = (D - n * n.transpose()) / len;
        } else {
            // Inside: the face of least penetration.
            n = Vec3::Zero();
            n[iMax] = signOf(p[iMax]);
            d = qMax - m_r;
            c = p;
            c[iMax] = n[iMax] * m_h[iMax];
            if (dn) dn->setZero();
        }
    }

  private:
    Vec3 m_h;
    double m_r;
    Vec3 m_inner;
};

/// Capsule: points within r of the segment z in [-L, L].
class Capsule final : public LocalRigidShape {
  public:
    Capsule(double r, double L) : m_r(r), m_L(L) {}
    std::string getName() const override { return "capsule"; }
    double getBoundingRadius() const override { return m_L + m_r; }

  protected:
    void evalLocal(const Vec3& p, double& d, Vec3& c, Vec3& n, Mat3* dn) const override {
        const double zc = std::clamp(p.z(), -m_L, m_L);
        const Vec3 q(p.x(), p.y(), p.z() - zc);
        const double len = q.norm();
        if (len > 0.0)
            n = q / len;
        else
            n = Vec3::UnitX();  // on the axis: any radial direction is closest
        d = len - m_r;
        c = Vec3(0.0, 0.0, zc) + m_r * n;
        if (dn) {
            if (len > 0.0) {
                Mat3 D = Mat3::Identity();
                if (std::abs(p.z()) <= m_L) D(2, 2) = 0.0;
                *dn = (D - n * n.transpose()) / len;
            } else {
                dn->setZero();
            }
        }
    }

  private:
    double m_r;
    double m_L;
};

/// Ellipsoid sum (x_i / a_i)^2 = 1. The closest point x of p solves the Lagrange condition
/// p - x = t A x, A = diag(1/a_i^2): x_i = a_i^2 p_i / (t + a_i^2). With k the shortest axis
/// and s = t + a_k^2 > 0 the constraint reads q(s) = |a_i y_i / (s + a_i^2 - a_k^2)| = 1 (y = |p|
/// in the first octant); h(s) = 1/q(s) - 1 is a power mean of order -2 of linear functions,
/// hence concave and increasing, so Newton from a point left of the root converges
/// monotonically (and in one step when one axis dominates, as near an axis). Working in s keeps
/// full relative precision of s + d_k near the pole, where points approach the short axis.
class Ellipsoid final : public LocalRigidShape {
  public:
    explicit Ellipsoid(const Vec3& a) : m_a(a) {
        m_a.minCoeff(&m_k);
        for (int i = 0; i < 3; ++i) m_dd[i] = m_a[i] * m_a[i] - m_a[m_k] * m_a[m_k];
        m_dd[m_k] = 0.0;
    }
    std::string getName() const override { return "ellipsoid"; }
    double getBoundingRadius() const override { return m_a.maxCoeff(); }
    /// p / a maps the surface to the unit sphere and shrinks lengths by at most 1 / a_min, so
    /// d >= a_min (rho - 1) outside (rho = |p / a|); inside, the surface point on the ray from
    /// the centre is within a_max (1 - rho).
    double calcDistanceLowerBound(const Vec3& p_G) const override {
        const Vec3 p = m_X_GS.linear().transpose() * (p_G - m_X_GS.translation());
        const double rho = p.cwiseQuotient(m_a).norm();
        return (rho >= 1.0 ? m_a[m_k] : m_a.maxCoeff()) * (rho - 1.0);
    }
    /// |p| <= a_max rho, and the bound at most t >= 0 means rho <= 1 + t / a_min.
    double getLowerBoundReach(double t) const override {
        return m_a.maxCoeff() * std::max(1.0, 1.0 + t / m_a[m_k]);
    }

  protected:
    void evalLocal(const Vec3& p, double& d, Vec3& c, Vec3& n, Mat3* dn) const override {
        const Vec3 y = p.cwiseAbs();
        const Vec3& a = m_a;
        Vec3 x;
        bool poleActive = false;
        for (int i = 0; i < 3; ++i)
            if (m_dd[i] == 0.0 && y[i] > 0.0) poleActive = true;
        double F0 = -1.0;  // q(0)^2 - 1 when no term has a pole at s = 0
        if (!poleActive)
            for (int i = 0; i < 3; ++i)
                if (m_dd[i] > 0.0) F0 += std::pow(a[i] * y[i] / m_dd[i], 2);
        double s = 0.0;
        if (!poleActive && F0 <= 0.0) {
            // p lies in the short-axis "slab" of the medial surface: the closest point leaves
            // the plane y_k = 0 (t = -a_k^2).
            bool first = true;
            for (int i = 0; i < 3; ++i) {
                if (m_dd[i] > 0.0) {
                    x[i] = a[i] * a[i] * y[i] / m_dd[i];
                } else {
                    x[i] = first ? a[i] * std::sqrt(-F0) : 0.0;
                    first = false;
                }
            }
        } else {
            for (int i = 0; i < 3; ++i)
                if (y[i] > 0.0) s = std::max(s, a[i] * y[i] - m_dd[i]);  // one term alone = 1
            for (int it = 0; it < 100; ++it) {
                double S = 0.0, S1 = 0.0;
                for (int i = 0; i < 3; ++i) {
                    if (y[i] == 0.0) continue;
                    const double den = s + m_dd[i];
                    const double v = a[i] * y[i] / den;
                    S += v * v;
                    S1 += v * v / den;
                }
                const double q = std::sqrt(S);
                const double h = 1.0 / q - 1.0;
                if (h >= 0.0) break;
                const double ds = -h * q * q * q / S1;
                if (!(ds > std::numeric_limits<double>::epsilon() * s)) break;
                s += ds;
            }
            for (int i = 0; i < 3; ++i)
                x[i] = y[i] == 0.0 ? 0.0 : a[i] * a[i] * y[i] / (s + m_dd[i]);
        }
        for (int i = 0; i < 3; ++i) c[i] = p[i] < 0.0 ? -x[i] : x[i];
        const Vec3 m = c.cwiseQuotient(a.cwiseProduct(a));  // A c, along the outward normal
        const double mLen = m.norm();
        n = m / mLen;
        const double g = p.cwiseQuotient(a).squaredNorm() - 1.0;
        d = (g < 0.0 ? -1.0 : 1.0) * (p - c).norm();
        if (dn) {
            // dx/dp from (I + tA) dx = dp - A x dt and x^T A dx = 0; dn/dx = (I - n n^T) A / |Ax|.
            const double sMin = 1e-14 * a.squaredNorm();
            Vec3 Minv;
            for (int i = 0; i < 3; ++i) Minv[i] = a[i] * a[i] / std::max(s + m_dd[i], sMin);
            const Vec3 Mm = Minv.cwiseProduct(m);
            const Mat3 dxdp = Mat3(Minv.asDiagonal()) - Mm * Mm.transpose() / m.dot(Mm);
            const Vec3 Adiag = a.cwiseProduct(a).cwiseInverse();
            const Mat3 P = Mat3::Identity() - n * n.transpose();
            const Mat3 J = P * Adiag.asDiagonal() * dxdp / mLen;
            *dn = 0.5 * (J + J.transpose());
        }
    }

  private:
    Vec3 m_a;
    Vec3 m_dd;  // a_i^2 - a_k^2
    int m_k = 0;
};

void requirePositive(double v, const char* what) {
    if (!(v > 0.0) || !std::isfinite(v))
        throw std::invalid_argument(std::string(what) + " must be positive and finite, got " +
                                    std::to_string(v));
}

}  // namespace

std::unique_ptr<RigidShape> makePlane() { return std::make_unique<Plane>(); }

std::unique_ptr<RigidShape> makeBox(const Vec3& halfExtents, double edgeRadius) {
    for (int i = 0; i < 3; ++i) requirePositive(halfExtents[i], "makeBox: half extent");
    if (!(edgeRadius >= 0.0) || !(edgeRadius < halfExtents.minCoeff()))
        throw std::invalid_argument("makeBox: edge radius must lie in [0, smallest half extent " +
                                    std::to_string(halfExtents.minCoeff()) + "), got " +
                                    std::to_string(edgeRadius));
    return std::make_unique<Box>(halfExtents, edgeRadius);
}

std::unique_ptr<RigidShape> makeEllipsoid(const Vec3& semiAxes) {
    for (int i = 0; i < 3; ++i) requirePositive(semiAxes[i], "makeEllipsoid: semi-axis");
    return std::make_unique<Ellipsoid>(semiAxes);
}

std::unique_ptr<RigidShape> makeCapsule(double radius, double halfLength) {
    requirePositive(radius, "makeCapsule: radius");
    if (!(halfLength >= 0.0) || !std::isfinite(halfLength))
        throw std::invalid_argument("makeCapsule: half length must be >= 0, got " +
                                    std::to_string(halfLength));
    return std::make_unique<Capsule>(radius, halfLength);
}

}  // namespace bags
