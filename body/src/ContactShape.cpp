// Analytic queries on ellipsoids and round cones (see ContactShape.h).
#include "body/ContactShape.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace body {
namespace {

// Points on the unit sphere, nearly uniform (Fibonacci lattice), each standing for 4 pi / n sr.
std::vector<SimTK::Vec3> calcFibonacciSphere(int n) {
    std::vector<SimTK::Vec3> u(n);
    const double golden = SimTK::Pi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < n; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / n;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden * k;
        u[k] = SimTK::Vec3(r * std::cos(phi), r * std::sin(phi), z);
    }
    return u;
}

// Closest point on the ellipsoid sum (x_i/a_i)^2 = 1 to y (all y_i >= 0), after Eberly
// ("Distance from a point to an ellipse, an ellipsoid, or a hyperellipsoid", 2013): the closest
// point is x_i = a_i^2 y_i / (a_i^2 + t) with t the root of
// F(t) = sum (a_i y_i / (a_i^2 + t))^2 - 1, which is convex and decreasing on (-a_min^2, inf);
// Newton's method started left of the root converges monotonically.
SimTK::Vec3 calcEllipsoidClosestPositive(const SimTK::Vec3& a, SimTK::Vec3 y, bool outside) {
    int iMin = 0;
    for (int i = 1; i < 3; ++i)
        if (a[i] < a[iMin]) iMin = i;
    const double amin2 = a[iMin] * a[iMin];
    // A point exactly on the plane of the smallest axis is moved off it by a negligible amount
    // so the bracket below exists (the medial surface of the ellipsoid).
    y[iMin] = std::max(y[iMin], 1e-12 * a[iMin]);
    double t = outside ? 0.0 : -amin2 + a[iMin] * y[iMin];
    for (int it = 0; it < 100; ++it) {
        double F = -1, dF = 0;
        for (int i = 0; i < 3; ++i) {
            const double d = a[i] * a[i] + t;
            const double r = a[i] * y[i] / d;
            F += r * r;
            dF -= 2 * r * r / d;
        }
        if (!(dF < 0)) break;
        const double step = F / dF;
        t -= step;
        if (std::abs(step) <= 1e-15 * (std::abs(t) + amin2)) break;
    }
    SimTK::Vec3 x;
    for (int i = 0; i < 3; ++i) x[i] = a[i] * a[i] * y[i] / (a[i] * a[i] + t);
    return x;
}

}  // namespace

ContactShape ContactShape::makeEllipsoid(const SimTK::Vec3& semiAxes, const SimTK::Vec3& p_BS,
                                         const SimTK::Rotation& R_BS) {
    for (int i = 0; i < 3; ++i)
        if (!(semiAxes[i] > 0) || !std::isfinite(semiAxes[i]))
            throw std::invalid_argument("ContactShape: ellipsoid semi-axes must be positive");
    ContactShape s;
    s.m_kind = Kind::Ellipsoid;
    s.m_semiAxes = semiAxes;
    s.m_X_BS = SimTK::Transform(R_BS, p_BS);
    s.updateBounds();
    return s;
}

ContactShape ContactShape::makeRoundCone(const SimTK::Vec3& pA, double rA, const SimTK::Vec3& pB,
                                         double rB) {
    if (!(rA > 0) || !(rB > 0))
        throw std::invalid_argument("ContactShape: round cone radii must be positive");
    if (!((pB - pA).norm() > std::abs(rA - rB)))
        throw std::invalid_argument(
            "ContactShape: round cone needs |pB - pA| > |rA - rB| (one sphere inside the other)");
    ContactShape s;
    s.m_kind = Kind::RoundCone;
    s.m_pA = pA;
    s.m_pB = pB;
    s.m_rA = rA;
    s.m_rB = rB;
    s.updateBounds();
    return s;
}

void ContactShape::updateBounds() {
    if (m_kind == Kind::Ellipsoid) {
        m_boundCentre = m_X_BS.p();
        m_boundRadius = std::max(m_semiAxes[0], std::max(m_semiAxes[1], m_semiAxes[2]));
    } else {
        m_boundCentre = 0.5 * (m_pA + m_pB);
        m_boundRadius = 0.5 * (m_pB - m_pA).norm() + std::max(m_rA, m_rB);
    }
}

SurfaceQuery ContactShape::calcSurfaceQuery(const SimTK::Vec3& p_B) const {
    SurfaceQuery q;
    if (m_kind == Kind::Ellipsoid) {
        const SimTK::Vec3 p = ~m_X_BS * p_B;  // shape frame
        const SimTK::Vec3& a = m_semiAxes;
        double f0 = -1;
        for (int i = 0; i < 3; ++i) f0 += (p[i] / a[i]) * (p[i] / a[i]);
        SimTK::Vec3 x;
        if (a[0] == a[1] && a[1] == a[2]) {  // sphere
            const double r = p.norm();
            x = r > 0 ? SimTK::Vec3(p * (a[0] / r)) : SimTK::Vec3(0, 0, a[0]);
        } else {
            const SimTK::Vec3 y(std::abs(p[0]), std::abs(p[1]), std::abs(p[2]));
            x = calcEllipsoidClosestPositive(a, y, f0 > 0);
            for (int i = 0; i < 3; ++i)
                if (p[i] < 0) x[i] = -x[i];
        }
        SimTK::Vec3 n(x[0] / (a[0] * a[0]), x[1] / (a[1] * a[1]), x[2] / (a[2] * a[2]));
        n /= n.norm();
        const double dist = (p - x).norm();
        q.distance = f0 > 0 ? dist : -dist;
        q.closestPoint = m_X_BS * x;
        q.normal = m_X_BS.R() * n;
        return q;
    }
    // Round cone, worked in the plane of the axis and the query point.
    const SimTK::Vec3 axis = m_pB - m_pA;
    const double h = axis.norm();
    const SimTK::Vec3 e = axis / h;
    const SimTK::Vec3 v = p_B - m_pA;
    const double y = ~v * e;
    SimTK::Vec3 w = v - y * e;
    const double x = w.norm();
    const SimTK::Vec3 er =
        x > 1e-14 * h ? SimTK::Vec3(w / x) : SimTK::Vec3(SimTK::UnitVec3(e).perp());
    const double sinA = (m_rA - m_rB) / h;
    const double cosA = std::sqrt(1 - sinA * sinA);
    const double s = -x * sinA + y * cosA;  // position along the tangent line
    auto sphere = [&](const SimTK::Vec3& c, double r) {
        const SimTK::Vec3 d = p_B - c;
        const double dn = d.norm();
        const SimTK::Vec3 n = dn > 0 ? SimTK::Vec3(d / dn) : SimTK::Vec3(cosA * er + sinA * e);
        q.distance = dn - r;
        q.normal = n;
        q.closestPoint = c + r * n;
    };
    if (s < 0) {
        sphere(m_pA, m_rA);
    } else if (s > h * cosA) {
        sphere(m_pB, m_rB);
    } else {
        const SimTK::Vec3 n = cosA * er + sinA * e;
        q.distance = x * cosA + y * sinA - m_rA;
        q.normal = n;
        q.closestPoint = p_B - q.distance * n;
    }
    return q;
}

SimTK::Vec3 ContactShape::calcSupportPoint(const SimTK::Vec3& d_B) const {
    if (m_kind == Kind::Ellipsoid) {
        const SimTK::Vec3 u = ~m_X_BS.R() * d_B;
        const SimTK::Vec3& a = m_semiAxes;
        const SimTK::Vec3 a2u(a[0] * a[0] * u[0], a[1] * a[1] * u[1], a[2] * a[2] * u[2]);
        const double den = std::sqrt(~u * a2u);
        return m_X_BS * SimTK::Vec3(a2u / den);
    }
    const double hA = ~m_pA * d_B + m_rA, hB = ~m_pB * d_B + m_rB;
    return hA >= hB ? SimTK::Vec3(m_pA + m_rA * d_B) : SimTK::Vec3(m_pB + m_rB * d_B);
}

double ContactShape::calcSurfaceArea() const {
    if (m_kind == Kind::Ellipsoid) {
        const double p = 1.6075;
        const double a = std::pow(m_semiAxes[0], p), b = std::pow(m_semiAxes[1], p),
                     c = std::pow(m_semiAxes[2], p);
        return 4 * SimTK::Pi * std::pow((a * b + a * c + b * c) / 3, 1 / p);
    }
    const double h = (m_pB - m_pA).norm();
    const double sinA = (m_rA - m_rB) / h, cosA = std::sqrt(1 - sinA * sinA);
    const double capA = 2 * SimTK::Pi * m_rA * m_rA * (1 + sinA);
    const double capB = 2 * SimTK::Pi * m_rB * m_rB * (1 - sinA);
    const double side = SimTK::Pi * (m_rA + m_rB) * cosA * h * cosA;
    return capA + capB + side;
}

double ContactShape::calcVolume() const {
    if (m_kind == Kind::Ellipsoid)
        return 4.0 / 3.0 * SimTK::Pi * m_semiAxes[0] * m_semiAxes[1] * m_semiAxes[2];
    const double h = (m_pB - m_pA).norm();
    const double sinA = (m_rA - m_rB) / h, cosA = std::sqrt(1 - sinA * sinA);
    const double hA = m_rA * (1 + sinA), hB = m_rB * (1 - sinA);
    const double capA = SimTK::Pi * hA * hA * (3 * m_rA - hA) / 3;
    const double capB = SimTK::Pi * hB * hB * (3 * m_rB - hB) / 3;
    const double R1 = m_rA * cosA, R2 = m_rB * cosA, len = h * cosA * cosA;
    return capA + capB + SimTK::Pi * len * (R1 * R1 + R1 * R2 + R2 * R2) / 3;
}

std::vector<SurfaceSample> ContactShape::calcSurfaceSamples(double spacing) const {
    std::vector<SurfaceSample> out;
    const double ds2 = spacing * spacing;
    if (m_kind == Kind::Ellipsoid) {
        const SimTK::Vec3& a = m_semiAxes;
        const int n = std::max(24, static_cast<int>(std::ceil(calcSurfaceArea() / ds2)));
        const double dOmega = 4 * SimTK::Pi / n;
        const double abc = a[0] * a[1] * a[2];
        for (const SimTK::Vec3& u : calcFibonacciSphere(n)) {
            // Nanson: the map x = A u takes the sphere's area element dOmega to
            // det(A) |A^-1 u| dOmega, with normal along A^-1 u.
            SimTK::Vec3 m(u[0] / a[0], u[1] / a[1], u[2] / a[2]);
            const double mn = m.norm();
            SurfaceSample s;
            s.p_B = m_X_BS * SimTK::Vec3(a[0] * u[0], a[1] * u[1], a[2] * u[2]);
            s.n_B = m_X_BS.R() * SimTK::Vec3(m / mn);
            s.area = abc * mn * dOmega;
            out.push_back(s);
        }
        return out;
    }
    const SimTK::Vec3 axis = m_pB - m_pA;
    const double h = axis.norm();
    const SimTK::Vec3 e = axis / h;
    const SimTK::UnitVec3 e1 = SimTK::UnitVec3(e).perp();
    const SimTK::Vec3 e2 = e % SimTK::Vec3(e1);
    const double sinA = (m_rA - m_rB) / h, cosA = std::sqrt(1 - sinA * sinA);
    auto addCap = [&](const SimTK::Vec3& c, double r, bool lower) {
        const int n = std::max(24, static_cast<int>(std::ceil(4 * SimTK::Pi * r * r / ds2)));
        const double dA = 4 * SimTK::Pi * r * r / n;
        for (const SimTK::Vec3& u0 : calcFibonacciSphere(n)) {
            const SimTK::Vec3 u = u0[0] * SimTK::Vec3(e1) + u0[1] * e2 + u0[2] * e;
            const double ue = ~u * e;
            if (lower ? (ue < sinA) : (ue > sinA)) out.push_back({c + r * u, u, dA});
        }
    };
    addCap(m_pA, m_rA, true);
    addCap(m_pB, m_rB, false);
    const double slant = h * cosA;
    const double R1 = m_rA * cosA, R2 = m_rB * cosA;
    const int nAlong = std::max(1, static_cast<int>(std::ceil(slant / spacing)));
    const int nAround =
        std::max(12, static_cast<int>(std::ceil(2 * SimTK::Pi * std::max(R1, R2) / spacing)));
    for (int i = 0; i < nAlong; ++i) {
        const double t = (i + 0.5) / nAlong;
        const double r = m_rA + (m_rB - m_rA) * t;
        const double rho = r * cosA;
        const double y = t * h + r * sinA;
        const double dA = 2 * SimTK::Pi * rho * slant / (nAlong * nAround);
        for (int j = 0; j < nAround; ++j) {
            const double phi = 2 * SimTK::Pi * (j + 0.5 * (i % 2)) / nAround;
            const SimTK::Vec3 er = std::cos(phi) * SimTK::Vec3(e1) + std::sin(phi) * e2;
            out.push_back({m_pA + y * e + rho * er, cosA * er + sinA * e, dA});
        }
    }
    return out;
}

}  // namespace body
