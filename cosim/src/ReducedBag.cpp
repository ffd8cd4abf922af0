#include "cosim/ReducedBag.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace cosim {

namespace {

constexpr double kMinSlope = 0.3;      // least -n_z a contact's area is divided by
constexpr double kColumnOnset = 0.01;  // [m] depth over which the column is blended in
constexpr double kSlackWidth = 100.0;  // [Pa] width of the smooth turn from slack to taut
// A chord's end on a surface within this of vertical (|n . e|) moves too fast along its
// column to carry a derivative; its share of the volume's tangent is left out.
constexpr double kGrazing = 1e-3;

// A point nearing a shape's medial axis (deep inside a limb) has a closest surface point that
// jumps from side to side; its share fades out within kAxisFade of the axis, 1 / |dn/dp|.
constexpr double kAxisFade = 0.005;  // [m]

double smoothstep(double u, double* du);
double calcUpFade(double nz, double* dNz);
double calcColumnShare(double nz, double phi, double* dNz, double* dDepth);

double calcAxisFade(const Eigen::Matrix3d& dndp) {
    const double k = dndp.norm();
    return k * kAxisFade < 1e-12 ? 1.0 : smoothstep(1.0 / (k * kAxisFade) - 1.0, nullptr);
}

// The column sample's share b of a top point whose column has a chord (n_z its normal's up
// component, phi its signed distance): up(n_z) = smoothstep over n_z from -0.45 to -0.15 times
// the onset over the first kColumnOnset of depth -phi; 0 outside the shape. dNz, dDepth: its
// derivatives in n_z and in -phi.
double calcColumnShare(double nz, double phi, double* dNz, double* dDepth) {
    double dUp = 0.0, dOnset = 0.0;
    const double up = smoothstep((nz + 0.45) / 0.3, &dUp);
    const double onset = phi < 0.0 ? smoothstep(-phi / kColumnOnset, &dOnset) : 0.0;
    if (dNz) *dNz = dUp / 0.3 * onset;
    if (dDepth) *dDepth = up * dOnset / kColumnOnset;
    return up * onset;
}

// The share a top sample keeps where the shape's closest surface faces up (n_z the normal's
// up component): it fades out over n_z from -0.15 to +0.15, inside the shape and outside
// alike (continuous where the top point crosses the surface). dNz: its derivative.
double calcUpFade(double nz, double* dNz) {
    double du = 0.0;
    const double f = smoothstep((0.15 - nz) / 0.3, &du);
    if (dNz) *dNz = -du / 0.3;
    return f;
}

// The axis fade's gradient in Ground at p (where it is neither 0 nor 1), by central
// differences of the shape's normal derivative over 1e-6 m: the fade follows how fast the
// normal turns, whose own derivative the shapes do not give.
Eigen::Vector3d calcAxisFadeGradient(const bags::RigidShape& shape, const Eigen::Vector3d& p) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    const double f = calcAxisFade(shape.calcNormalDerivative(p));
    if (f <= 0.0 || f >= 1.0) return g;
    constexpr double h = 1e-6;
    for (int i = 0; i < 3; ++i) {
        Eigen::Vector3d dp = Eigen::Vector3d::Zero();
        dp[i] = h;
        g[i] = (calcAxisFade(shape.calcNormalDerivative(p + dp)) -
                calcAxisFade(shape.calcNormalDerivative(p - dp))) /
               (2.0 * h);
    }
    return g;
}

double smoothstep(double u, double* du) {
    if (u <= 0.0 || u >= 1.0) {
        if (du) *du = 0.0;
        return u <= 0.0 ? 0.0 : 1.0;
    }
    if (du) *du = 6.0 * u * (1.0 - u);
    return u * u * (3.0 - 2.0 * u);
}

Eigen::Matrix3d cross(const Vec3& v) {
    Eigen::Matrix3d m;
    m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    return m;
}

void fail(const std::string& what) {
    throw std::invalid_argument("reduced bag calibration: " + what);
}

}  // namespace

void ReducedBagCalibration::validate() const {
    geometry.validate();
    const size_t n = masses.size();
    if (n < 2) fail("needs at least 2 gas masses, has " + std::to_string(n));
    if (gaugePressures.size() != n || volumes.size() != n || top.size() != n)
        fail("the unloaded states and top heights need one entry per mass");
    for (size_t i = 0; i < n; ++i) {
        if (!(masses[i] > 0.0) || (i && !(masses[i] > masses[i - 1])))
            fail("masses must be positive and ascending");
        if (!(volumes[i] > 0.0) || !std::isfinite(gaugePressures[i]))
            fail("unloaded volume and pressure must be finite, volume positive");
        if (top[i].rows() != nx || top[i].cols() != ny)
            fail("top height " + std::to_string(i) + " is not nx x ny");
    }
    if (nx < 2 || ny < 2 || !(pitch > 0.0)) fail("the grid needs nx, ny >= 2 and pitch > 0");
    if (depths.size() < 2 || depths.front() != 0.0) fail("depths must start at 0, at least 2");
    for (size_t j = 1; j < depths.size(); ++j)
        if (!(depths[j] > depths[j - 1])) fail("depths must be ascending");
    for (const Eigen::MatrixXd* t : {&pressureFactor, &volumeFactor})
        if (t->rows() != int(n) || t->cols() != int(depths.size()) || !t->allFinite() ||
            !(t->minCoeff() > 0.0))
            fail("factor tables must be masses x depths, finite and positive");
    if (!(gasConstant > 0.0) || !(temperature > 0.0) || !(ambientPressure > 0.0))
        fail("gas constant, temperature and ambient pressure must be positive");
    if (!(boardPenalty > 0.0) || !(rimWidth > 0.0) || !(skirt >= 0.0) || !(skirt <= 10.0))
        fail("board penalty and rim width must be > 0, skirt in [0, 10]");
    if (!(depthMax > 0.0) || !(radiusMin > 0.0) || !(radiusMax >= radiusMin) || !(tiltMax > 0.0))
        fail("envelope: depth, radii and tilt must be positive, radii ordered");
    if (!(panelSink >= 0.0 && panelSink < 1e-3) || !(panelLift >= 0.0 && panelLift < 1e-3) ||
        !(panelBlend > 0.0 && panelBlend < geometry.longSide))
        fail(
            "panel coupling: sink and lift must be in [0, 1e-3) m/N, the blend in (0, the long "
            "side)");
}

void ReducedBagFriction::validate() const {
    if (!(coefficient >= 0.0 && coefficient <= 2.0))
        throw std::invalid_argument("reduced bag friction: coefficient must be in [0, 2]");
    if (coefficient == 0.0) return;
    if (!(stickDistance > 0.0 && stickDistance <= 0.1))
        throw std::invalid_argument(
            "reduced bag friction: stickDistance must be in (0, 0.1] m with friction on");
    if (!(dampingTime >= 0.0 && dampingTime <= 1.0))
        throw std::invalid_argument("reduced bag friction: dampingTime must be in [0, 1] s");
}

ReducedBag::ReducedBag(std::shared_ptr<const ReducedBagCalibration> calibration,
                       const Eigen::Isometry3d& X_GB)
    : m_cal(std::move(calibration)), m_X_GB(X_GB), m_X_BG(X_GB.inverse()) {
    if (!m_cal) throw std::invalid_argument("ReducedBag: no calibration");
    m_cal->validate();
    const ReducedBagCalibration& c = *m_cal;
    for (int iy = 0; iy < c.ny; ++iy)
        for (int ix = 0; ix < c.nx; ++ix) {
            bool ok = true;
            for (const Eigen::MatrixXd& t : c.top) ok = ok && std::isfinite(t(ix, iy));
            if (ok) m_gridIndex.push_back(ix + c.nx * iy);
        }
    // The coupling's panels: steep below the apex's x, blended across the ridge.
    const double apex = c.geometry.calcApexX();
    for (int g : m_gridIndex) {
        const double x = c.x0 + c.pitch * (g % c.nx);
        m_steep.push_back(smoothstep((apex + c.panelBlend - x) / (2.0 * c.panelBlend), nullptr));
    }
    // The taut unloaded states give V_free(P) (the slack ones carry no pressure).
    for (size_t i = 0; i < c.masses.size(); ++i)
        if (c.gaugePressures[i] > 200.0 &&
            (m_pVfree.empty() || c.gaugePressures[i] > m_pVfree.back())) {
            m_pVfree.push_back(c.gaugePressures[i]);
            m_Vfree.push_back(c.volumes[i]);
        }
    if (m_pVfree.size() < 2)
        throw std::invalid_argument(
            "reduced bag calibration: needs at least 2 taut unloaded states (above 200 Pa)");
    for (size_t i = 0; i < c.masses.size() && m_tautMass == 0.0; ++i)
        if (c.gaugePressures[i] > 200.0) m_tautMass = c.masses[i];
    setGasMass(c.masses.front());
}

int ReducedBag::addShape(std::shared_ptr<bags::RigidShape> shape) {
    if (!shape) throw std::invalid_argument("ReducedBag::addShape: null shape");
    m_poses.push_back(shape->getPose());
    m_committedPoses.push_back(shape->getPose());
    m_velocities.push_back(Vec6::Zero());
    m_committedVelocities.push_back(Vec6::Zero());
    m_anchors.emplace_back();
    m_shapes.push_back(std::move(shape));
    m_results.emplace_back();
    evaluate();
    return int(m_shapes.size()) - 1;
}

void ReducedBag::setGasMass(double mass) {
    if (!(mass > 0.0)) throw std::invalid_argument("ReducedBag::setGasMass: mass must be > 0");
    m_cur.mass = mass;
    m_cur.flow = 0.0;
    m_cur.target = -1.0;
    evaluate();
    commit();
}

void ReducedBag::setFriction(const ReducedBagFriction& friction) {
    friction.validate();
    m_friction = friction;
    for (Anchor& a : m_anchors) a = Anchor{};
    evaluate();
}

void ReducedBag::setShapeState(int shape, const ShapeState& state) {
    m_poses.at(shape) = state.X_GS;
    m_velocities.at(shape) << state.w_GS, state.v_GS;
}

ParticipantStep ReducedBag::advance(double dt) {
    State s = m_committed;
    if (s.target >= 0.0) {
        const double step = std::abs(s.rate) * dt;
        s.mass = s.mass < s.target ? std::min(s.target, s.mass + step)
                                   : std::max(s.target, s.mass - step);
    } else {
        s.mass = std::max(1e-9, s.mass + s.flow * dt);
    }
    s.time += dt;
    m_cur = s;
    evaluate();
    ParticipantStep r;
    r.converged = std::isfinite(m_cur.pressure);
    r.solverIterations = 1;
    if (!r.converged) rollback();
    return r;
}

void ReducedBag::commit() {
    m_committed = m_cur;
    m_committedPoses = m_poses;
    m_committedVelocities = m_velocities;
    updateAnchors();
    checkEnvelope();
}

void ReducedBag::rollback() {
    m_cur = m_committed;
    m_poses = m_committedPoses;
    m_velocities = m_committedVelocities;
    evaluate();
}

void ReducedBag::addFriction(size_t s) {
    ShapeResult& r = m_results[s];
    r.normalForce = r.wrench.force;
    const Anchor& anchor = m_anchors[s];
    const double mu = m_friction.coefficient, N = r.normalForce.norm();
    if (!(mu > 0.0 && anchor.on && r.load > 0.0 && N > 0.0)) return;
    const Eigen::Isometry3d& X = m_poses[s];
    const Vec3 rp = X.linear() * anchor.onShape;
    const Vec3 vp = m_velocities[s].tail<3>() + m_velocities[s].head<3>().cross(rp);
    const Vec3 n = r.normalForce / N;
    r.anchored = true;
    r.point = X.translation() + rp;
    r.raw = r.point - anchor.inGround + m_friction.dampingTime * vp;
    r.slip = r.raw - n * n.dot(r.raw);
    const double ns = r.slip.norm();
    r.sliding = ns > m_friction.stickDistance;
    r.frictionForce = -mu * N / std::max(ns, m_friction.stickDistance) * r.slip;
    r.wrench.force += r.frictionForce;
    r.wrench.torque += rp.cross(r.frictionForce);
}

void ReducedBag::updateAnchors() {
    // The anchor follows a slide (return mapping: |s| = d, the force unchanged), then the
    // spring moves to the pressure centroid keeping its tangential stretch: a shape rolling
    // on the film without slipping is not held back.
    for (size_t s = 0; s < m_shapes.size(); ++s) {
        const ShapeResult& r = m_results[s];
        Anchor& a = m_anchors[s];
        if (!(m_friction.coefficient > 0.0 && r.load > 0.0 && r.normalForce.norm() > 0.0)) {
            a = Anchor{};
            continue;
        }
        Vec3 keep = Vec3::Zero();
        if (r.anchored) {
            const Vec3 n = r.normalForce.normalized();
            const Vec3 u = r.point - a.inGround;
            keep = u - n * n.dot(u);
            const double ns = r.slip.norm();
            if (ns > m_friction.stickDistance)
                keep -= (ns - m_friction.stickDistance) / ns * r.slip;
        }
        a.on = true;
        a.onShape = m_poses[s].linear().transpose() * (r.centroid - m_poses[s].translation());
        a.inGround = r.centroid - keep;
    }
}

void ReducedBag::setMassFlow(double massFlow) {
    m_committed.flow = m_cur.flow = massFlow;
    m_committed.target = m_cur.target = -1.0;
}

void ReducedBag::setTargetMass(double mass, double rate) {
    m_committed.target = m_cur.target = mass;
    m_committed.rate = m_cur.rate = rate;
}

double ReducedBag::calcWeight(double delta, double depth, double* dDelta, double* dDepth) const {
    // w = smoothstep(u), u = (delta + s) / (s + eps), s = skirt x depth: 0 at the skirt's
    // edge, 1 from eps inside the shape.
    const double eps = m_cal->rimWidth, lambda = m_cal->skirt, s = lambda * depth;
    const double u = (delta + s) / (s + eps);
    double dw = 0.0;
    const double w = smoothstep(u, &dw);
    if (dDelta) *dDelta = dw / (s + eps);
    if (dDepth)
        *dDepth = dw * (lambda / (s + eps) - (delta + s) * lambda / ((s + eps) * (s + eps)));
    return w;
}

double ReducedBag::interpolateTop(int point, double mass) const {
    const ReducedBagCalibration& c = *m_cal;
    const int g = m_gridIndex[point], ix = g % c.nx, iy = g / c.nx;
    const std::vector<double>& m = c.masses;
    mass = std::max(mass, m_tautMass);  // a slack bag: the taut bag's top
    if (mass <= m.front()) return c.top.front()(ix, iy);
    if (mass >= m.back()) return c.top.back()(ix, iy);
    const size_t k = size_t(std::upper_bound(m.begin(), m.end(), mass) - m.begin()) - 1;
    const double u = (mass - m[k]) / (m[k + 1] - m[k]);
    return (1.0 - u) * c.top[k](ix, iy) + u * c.top[k + 1](ix, iy);
}

bool ReducedBag::findChord(const bags::RigidShape& shape, const Vec3& t, Chord& ch) const {
    const Vec3 e = m_X_GB.linear().col(2);  // the bag's up
    const double boardZ = e.dot(m_X_GB.translation());
    auto height = [&](const Vec3& p) { return e.dot(p) - boardZ; };
    auto phiAt = [&](const Vec3& p) { return shape.calcSignedDistance(p, nullptr, nullptr); };
    // Where the line down from p0 (phi f0 there, not 0) crosses the surface: sphere steps
    // (never past the surface) to within 1e-6 m, a bracket by doubling steps, then the
    // Illinois method to 1e-13 m. False if the board comes first or, from outside, the line
    // passes the shape.
    auto cross = [&](const Vec3& p0, double f0, Vec3& at, Vec3& n) {
        const bool outside = f0 > 0.0;
        const double h0 = height(p0);
        double s = 0.0, f = f0;
        for (int it = 0; it < 400 && std::abs(f) > 1e-6; ++it) {
            const double next = s + std::abs(f);
            if (next > h0) return false;
            const double fn = phiAt(p0 - next * e);
            if (outside && fn > f - 1e-12) return false;  // passing by
            s = next, f = fn;
        }
        if (f == 0.0 || (f > 0.0) != outside) {  // a sphere step landed on the surface
            at = p0 - s * e;
            shape.calcSignedDistance(at, nullptr, &n);
            return true;
        }
        double sa = s, fa = f, ds = 2.0 * std::abs(f) + 1e-9, sb = s, fb = f;
        for (int it = 0;; ++it) {
            sb = sa + ds;
            if (sb > h0 || it > 60) return false;
            fb = phiAt(p0 - sb * e);
            if ((fb > 0.0) != (fa > 0.0)) break;
            if (outside && fb > fa) return false;  // grazing past
            sa = sb, fa = fb, ds *= 2.0;
        }
        int side = 0;
        for (int it = 0; it < 200 && sb - sa > 1e-13; ++it) {
            const double sc = (sa * fb - sb * fa) / (fb - fa);
            const double fc = phiAt(p0 - sc * e);
            if (fc == 0.0) {
                sa = sb = sc;
                break;
            }
            if ((fc > 0.0) == (fb > 0.0)) {
                sb = sc, fb = fc;
                if (side == -1) fa *= 0.5;
                side = -1;
            } else {
                sa = sc, fa = fc;
                if (side == 1) fb *= 0.5;
                side = 1;
            }
        }
        at = p0 - 0.5 * (sa + sb) * e;
        shape.calcSignedDistance(at, nullptr, &n);
        return true;
    };
    ch = Chord{};
    const double phi = phiAt(t);
    ch.topInside = phi < 0.0;
    Vec3 p = t;
    double inside = phi;
    if (!ch.topInside) {
        if (!cross(t, phi, ch.hi, ch.nhi)) return false;
        // The lower end from just inside the upper one.
        p = ch.hi - 1e-9 * e;
        inside = phiAt(p);
        if (!(inside < 0.0)) return false;
    } else {
        ch.hi = t;
    }
    ch.onBoard = !cross(p, inside, ch.lo, ch.nlo);
    if (ch.onBoard) {
        ch.lo = p - height(p) * e;
        ch.nlo = -e;
    }
    ch.length = height(ch.hi) - height(ch.lo);
    return ch.length > 0.0;
}

double ReducedBag::calcFreeVolume(double P, double* dVdP) const {
    const std::vector<double>& p = m_pVfree;
    size_t k = 0;
    if (P >= p.back())
        k = p.size() - 2;
    else if (P > p.front())
        k = size_t(std::upper_bound(p.begin(), p.end(), P) - p.begin()) - 1;
    const double slope = (m_Vfree[k + 1] - m_Vfree[k]) / (p[k + 1] - p[k]);
    if (dVdP) *dVdP = slope;
    return m_Vfree[k] + slope * (P - p[k]);
}

double ReducedBag::lookup(const Eigen::MatrixXd& table, double mass, double depth,
                          double* dDepth) const {
    const ReducedBagCalibration& c = *m_cal;
    auto bracket = [](const std::vector<double>& v, double x, size_t& k, double& u) {
        if (x <= v.front()) {
            k = 0, u = 0.0;
        } else if (x >= v.back()) {
            k = v.size() - 2, u = 1.0;
        } else {
            k = size_t(std::upper_bound(v.begin(), v.end(), x) - v.begin()) - 1;
            u = (x - v[k]) / (v[k + 1] - v[k]);
        }
    };
    size_t i, j;
    double um, ud;
    bracket(c.masses, mass, i, um);
    bracket(c.depths, depth, j, ud);
    auto row = [&](size_t r) {
        return std::pair<double, double>{(1 - ud) * table(r, j) + ud * table(r, j + 1),
                                         table(r, j + 1) - table(r, j)};
    };
    const auto a = row(i), b = row(i + 1);
    const bool inside = depth > c.depths.front() && depth < c.depths.back();
    if (dDepth)
        *dDepth =
            inside ? ((1 - um) * a.second + um * b.second) / (c.depths[j + 1] - c.depths[j]) : 0.0;
    return (1 - um) * a.first + um * b.first;
}

double ReducedBag::solvePressure(double displaced, double* dPdV) const {
    const ReducedBagCalibration& c = *m_cal;
    const double pa = c.ambientPressure, mrt = m_cur.mass * c.gasConstant * c.temperature;
    auto f = [&](double P, double* dfdP) {
        double dV = 0.0;
        const double V = calcFreeVolume(P, &dV) - displaced;
        if (dfdP) *dfdP = V + (P + pa) * dV;
        return (P + pa) * V - mrt;
    };
    // The root P_raw of f (negative where the gas fits slack at ambient pressure, V_free then
    // extended below its first taut state), bracketed, then the gauge pressure
    // P = w ln(1 + exp(P_raw / w)): 0 in the slack bag, P_raw in the taut one, smooth
    // between (w = kSlackWidth).
    double lo = -0.5 * pa, hi = std::max(1e3, m_committed.pressure);
    while (f(lo, nullptr) > 0.0 && lo > -0.99 * pa) lo = 0.5 * (lo - pa);
    while (f(hi, nullptr) < 0.0) {
        lo = hi;
        hi *= 2.0;
        if (hi > 1e8) return std::numeric_limits<double>::quiet_NaN();
    }
    double P = hi;
    for (int it = 0; it < 100; ++it) {
        double d = 0.0;
        const double v = f(P, &d);
        if (v > 0.0)
            hi = P;
        else
            lo = P;
        double next = d > 0.0 ? P - v / d : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::abs(next - P) < 1e-10 * pa) {
            P = next;
            break;
        }
        P = next;
    }
    double d = 0.0;
    f(P, &d);
    const double u = P / kSlackWidth;
    const double sig = u > 0.0 ? 1.0 / (1.0 + std::exp(-u)) : std::exp(u) / (1.0 + std::exp(u));
    if (dPdV) *dPdV = sig * (P + pa) / d;
    return u > 30.0 ? P : kSlackWidth * std::log1p(std::exp(u));
}

void ReducedBag::evaluate() {
    const ReducedBagCalibration& c = *m_cal;
    const int n = int(m_gridIndex.size());
    const double a = c.pitch * c.pitch;
    // The unloaded top at this mass, in Ground.
    // (xyB: the columns' place in the bag's plane; topHeight: the highest top above the board)
    const Eigen::Isometry3d& X_BG = m_X_BG;
    const Eigen::Matrix3Xd top = calcTop();
    Eigen::Matrix2Xd xyB(2, n);
    Eigen::VectorXd heightB(n);  // each column's top above the board
    for (int i = 0; i < n; ++i) {
        const Vec3 tB = X_BG * Vec3(top.col(i));
        xyB.col(i) = tB.head<2>();
        heightB[i] = tB.z();
    }
    const double topHeight = n > 0 ? std::max(0.0, heightB.maxCoeff()) : 0.0;
    m_displaced = 0.0;
    for (size_t s = 0; s < m_shapes.size(); ++s) {
        bags::RigidShape& shape = *m_shapes[s];
        shape.setPose(m_poses[s]);
        ShapeResult& r = m_results[s];
        r = ShapeResult{};
        // The shape's chords first: per column the stretch of it below the top and above the
        // board (its volume in the column, and where the film meets its underside). A column
        // whose midpoint is further from the shape than half its height misses.
        std::vector<int> chordAt(n, -1);
        const Vec3 oB = X_BG * m_poses[s].translation();
        std::vector<double> across2(n);
        for (int i = 0; i < n; ++i) across2[i] = (xyB.col(i) - oB.head<2>()).squaredNorm();
        const double reachColumn = shape.getLowerBoundReach(0.5 * topHeight + 1e-5);
        for (int i = 0; i < n; ++i) {
            if (across2[i] > reachColumn * reachColumn) continue;
            const double hcol = heightB[i];
            const Vec3 mid = top.col(i) - 0.5 * hcol * m_X_GB.linear().col(2);
            if (shape.calcDistanceLowerBound(mid) > 0.5 * hcol + 1e-6) continue;
            Chord ch;
            if (findChord(shape, top.col(i), ch)) {
                ch.point = i;
                chordAt[size_t(i)] = int(r.chords.size());
                r.chords.push_back(ch);
            }
        }
        // Two passes over the grid: first the points the shape may overlap (its distance
        // bound below 0) and the columns it lies in below the top (sunk), which give the
        // depth d_s; then the skirt's, within skirt x d_s of it. The samples are kept in the
        // grid's order, as one pass would give them.
        const Vec3 e = m_X_GB.linear().col(2);
        std::vector<Sample> found, rim;
        auto sample = [&](int i, std::vector<Sample>& out) {
            Sample smp;
            double phi = 0.0;
            smp.point = i;
            smp.t = top.col(i);
            shape.calcContactGeometry(smp.t, &phi, &smp.c, &smp.n, &smp.dndp);
            smp.delta = smp.delta0 = -phi;
            smp.topDelta = smp.delta, smp.topN = smp.n;
            // Where the shape's closest surface faces sideways or up (it lies below the
            // unloaded top), the film meets its underside: down the column to where it
            // leaves the shape (the chord's lower end), and the point that far inside along
            // the normal there. Blended in over -n_z from 0.45 to 0.15 and over the first
            // kColumnOnset of depth (continuous in the pose).
            const int k = chordAt[size_t(i)];
            const double b = k >= 0 ? calcColumnShare(smp.n.z(), phi, nullptr, nullptr) : 0.0;
            if (b > 0.0) {
                const Chord& ch = r.chords[size_t(k)];
                // The underside: the chord's lower end, or through the board (the chord stops
                // there) down to where the column leaves the shape, for the board's penalty.
                Vec3 lo = ch.lo;
                if (ch.onBoard) {
                    double d = shape.calcSignedDistance(lo, nullptr, nullptr);
                    for (int it = 0; it < 40 && d < -1e-7; ++it) {
                        lo += d * e;
                        d = shape.calcSignedDistance(lo, nullptr, nullptr);
                    }
                }
                Vec3 nrm, cp;
                Eigen::Matrix3d curv;
                double on = 0.0;
                shape.calcContactGeometry(lo, &on, &cp, &nrm, &curv);
                // At most half the surface's least curvature radius there (1 / |dn/dp|): a
                // long column through a sunk limb would otherwise put the point past its
                // axis, where its closest surface is the upper side and the film's pressure
                // would push the limb down.
                const double column = e.dot(smp.t - lo);
                const double kc = curv.norm();
                const double inward =
                    std::min(column * std::max(-nrm.z(), kMinSlope), kc > 1e-12 ? 0.5 / kc : 1e300);
                Sample col = smp;
                // The film's contact is the underside point itself, pressed along its normal
                // by that depth. (Not the closest surface of the inward point: in a thin shape,
                // a hand, that point passes the middle and its closest surface is the upper
                // side, whose pressure would push the shape down.)
                col.t = lo - inward * nrm;
                col.column = column;
                col.c = lo, col.n = nrm;
                col.delta = col.delta0 = inward;
                // The surface's curvature there, which also gives the axis fade: the point
                // lies at most half the least curvature radius inside, so the fade is the
                // shape's (a thin limb's), not the point's depth.
                col.dndp = curv;
                col.blend = b * calcAxisFade(curv);
                if (col.blend > 0.0) out.push_back(col);
                smp.blend = 1.0 - b;
            }
            smp.blend *= calcAxisFade(smp.dndp);
            // Where the shape's closest surface faces up, the top point is not film wrapping
            // the shape, and the gas there would press it down: above a sunk shape, or inside
            // one sunk past its widest by its upper side, it fades out over n_z from -0.15
            // to +0.15.
            smp.blend *= calcUpFade(smp.n.z(), nullptr);
            if (smp.blend > 0.0) out.push_back(smp);
        };
        // A column further across from the shape's origin (in the bag's plane) than the
        // shape's lower-bound reach for t has a bound above t at every height: skipped
        // without asking the shape (the same samples, fewer queries). kUnasked: above 0, not
        // yet asked.
        constexpr double kUnasked = std::numeric_limits<double>::infinity();
        std::vector<double> bound(n, kUnasked);
        const double reach0 = shape.getLowerBoundReach(0.0);
        for (int i = 0; i < n; ++i) {
            if (across2[i] <= reach0 * reach0) bound[i] = shape.calcDistanceLowerBound(top.col(i));
            if (bound[i] <= 0.0) sample(i, found);
        }
        // The depth: the mean of delta weighted by a delta over the overlap (smooth in the
        // pose).
        double s1 = 0.0, s2 = 0.0;
        for (const Sample& smp : found)
            if (smp.delta > 0.0) {
                s1 += a * smp.blend * smp.delta;
                s2 += a * smp.blend * smp.delta * smp.delta;
            }
        r.depthSum1 = r.depth0Sum1 = s1, r.depthSum2 = r.depth0Sum2 = s2;
        r.depth = r.depth0 = s1 > 0.0 ? s2 / s1 : 0.0;
        // The skirt: points outside the shape, within skirt x depth of it, touch it too.
        const double skirt = c.skirt * r.depth;
        if (r.depth > 0.0) {
            const double reachSkirt = shape.getLowerBoundReach(skirt);
            for (int i = 0; i < n; ++i) {
                if (bound[i] <= 0.0 || across2[i] > reachSkirt * reachSkirt) continue;
                if (bound[i] == kUnasked) bound[i] = shape.calcDistanceLowerBound(top.col(i));
                if (bound[i] < skirt) sample(i, rim);
            }
            // Merge the two passes in grid order (each is ascending in the point).
            size_t ia = 0, ib = 0;
            while (ia < found.size() || ib < rim.size()) {
                const bool takeA =
                    ib == rim.size() || (ia < found.size() && found[ia].point < rim[ib].point);
                const Sample& smp = takeA ? found[ia++] : rim[ib++];
                if (smp.delta > -skirt) r.samples.push_back(smp);
            }
        }
        findDeepestAndArea(r);
    }
    // The columns' overlap: per column the union of the shapes' chords, shared among them in
    // proportion to their lengths (V_s = sum a length U / S), so that where shapes overlap
    // each other their common volume is displaced once.
    {
        std::vector<std::vector<std::pair<int, int>>> at(n);  // point -> (shape, chord)
        for (size_t s = 0; s < m_shapes.size(); ++s)
            for (size_t k = 0; k < m_results[s].chords.size(); ++k)
                at[m_results[s].chords[k].point].emplace_back(int(s), int(k));
        std::vector<double> beta(m_shapes.size());
        for (size_t s = 0; s < m_shapes.size(); ++s)
            beta[s] = lookup(c.volumeFactor, m_cur.mass, m_results[s].depth, nullptr);
        const Vec3 e = m_X_GB.linear().col(2);
        for (int i = 0; i < n; ++i) {
            if (at[i].size() < 2) continue;
            std::vector<Chord*> ch;
            for (const auto& [s, k] : at[i]) ch.push_back(&m_results[size_t(s)].chords[size_t(k)]);
            std::vector<int> order(ch.size());
            for (size_t k = 0; k < ch.size(); ++k) order[k] = int(k);
            std::sort(order.begin(), order.end(),
                      [&](int u, int v) { return e.dot(ch[u]->lo) < e.dot(ch[v]->lo); });
            double U = 0.0, S = 0.0, B = 0.0;
            for (size_t k = 0; k < ch.size(); ++k) {
                S += ch[k]->length;
                B += beta[size_t(at[i][k].first)] * ch[k]->length;
                ch[k]->hiBounds = ch[k]->loBounds = false;
            }
            // merged runs of intervals, sorted by their lower ends
            for (size_t k = 0; k < order.size();) {
                Chord* bottom = ch[order[k]];
                Chord* topc = bottom;
                double hiz = e.dot(bottom->hi);
                size_t j = k + 1;
                for (; j < order.size() && e.dot(ch[order[j]]->lo) <= hiz; ++j)
                    if (e.dot(ch[order[j]]->hi) > hiz) {
                        topc = ch[order[j]];
                        hiz = e.dot(topc->hi);
                    }
                bottom->loBounds = true;
                topc->hiBounds = true;
                U += hiz - e.dot(bottom->lo);
                k = j;
            }
            for (Chord* c2 : ch) c2->share = U / S, c2->sum = S, c2->betaSum = B;
        }
        for (size_t s = 0; s < m_shapes.size(); ++s) {
            ShapeResult& r = m_results[s];
            for (Chord& ch : r.chords) {
                if (ch.sum == 0.0) ch.sum = ch.length, ch.betaSum = beta[s] * ch.length;
                r.volume += a * ch.length * ch.share;
            }
            m_displaced += beta[s] * r.volume;
        }
    }
    shareFilm(top);
    m_cur.pressure = solvePressure(m_displaced, &m_dPdV);
    coupleThePanels();
    const double P = m_cur.pressure;
    for (size_t s = 0; s < m_shapes.size(); ++s) {
        ShapeResult& r = m_results[s];
        const double kappa = lookup(c.pressureFactor, m_cur.mass, r.depth, nullptr);
        const Vec3 o = m_poses[s].translation();
        ShapeWrench w;
        for (const Sample& smp : r.samples) {
            const double q = kappa * P * calcWeight(smp.delta, r.depth, nullptr, nullptr) +
                             calcBoardPressure(smp.c);
            const double g = std::max(-smp.n.z(), kMinSlope);
            const double ab = smp.blend * smp.film * a;
            const Vec3 f = ab * q / g * -smp.n;
            w.force += f;
            w.torque += (smp.c - o).cross(f);
            r.load += ab * q / g;
            r.centroid += ab * q / g * smp.c;
        }
        r.wrench = w;
        if (r.load > 0.0) r.centroid /= r.load;
        addFriction(s);
    }
    buildFootprint(top);
}

void ReducedBag::shareFilm(const Eigen::Matrix3Xd& top) {
    // The film over a column touches one surface. Where several shapes reach a grid point
    // (segments overlap at the joints; one shape's skirt reaches into another's contact),
    // the one whose surface lies deepest under the top point takes it: shape s takes
    // exp(delta_s / w) / sum_r exp(delta_r / w) of the column's film, delta the top point's
    // depth in each shape, w the rim width, so that the wrench stays continuous in the poses.
    // Alone at a point a shape keeps all of it (the calibration's single shapes are unchanged).
    const int n = int(top.cols());
    const double w = m_cal->rimWidth;
    constexpr double kNone = -std::numeric_limits<double>::infinity();
    std::vector<int> count(n, 0), last(n, -1);
    std::vector<double> deepest(n, kNone), sum(n, 0.0);
    for (size_t s = 0; s < m_results.size(); ++s)
        for (const Sample& smp : m_results[s].samples) {
            const int i = smp.point;
            if (last[i] == int(s)) continue;  // a shape's samples at a point are adjacent
            last[i] = int(s);
            ++count[i];
            deepest[i] = std::max(deepest[i], smp.topDelta);
        }
    std::fill(last.begin(), last.end(), -1);
    for (size_t s = 0; s < m_results.size(); ++s)
        for (const Sample& smp : m_results[s].samples) {
            const int i = smp.point;
            if (count[i] < 2 || last[i] == int(s)) continue;
            last[i] = int(s);
            sum[i] += std::exp((smp.topDelta - deepest[i]) / w);
        }
    for (size_t s = 0; s < m_results.size(); ++s) {
        const Vec3 o = m_poses[s].translation();
        for (Sample& smp : m_results[s].samples) {
            const int i = smp.point;
            if (count[i] < 2) continue;
            smp.film = std::exp((smp.topDelta - deepest[i]) / w) / sum[i];
            // d delta_top = n . (theta x (t - o) + u) at the fixed top point t
            const Vec3 t = top.col(i);
            Eigen::Matrix<double, 1, 6> dDelta;
            dDelta << ((t - o).cross(smp.topN)).transpose(), smp.topN.transpose();
            smp.dFilm = smp.film * (1.0 - smp.film) / w * dDelta;
        }
    }
}

void ReducedBag::coupleThePanels() {
    // A load on one panel sinks that panel's top beyond the contact and lifts the other's
    // (the FE bag's film keeps its length; docs/reduced-bag.md#a-load-on-one-panel-lifts-the-
    // other). Each shape sees the top moved by the other shapes' gas loads under the unloaded
    // top (its own is in the calibration's single shapes), so at its sample i the top rises by
    //   shift_i = st_i (-sink L_st + lift L_ge) + (1 - st_i) (lift L_st - sink L_ge),
    // st_i the point's steep share and L the others' loads per panel; its depth there becomes
    // delta0 - (n.e) shift. The loads are kappa P w times the film's area, so d shift / dP =
    // shift / P with the poses held.
    // (Off, each sample keeps delta = delta0 and no shift, as sampled.)
    const ReducedBagCalibration& c = *m_cal;
    const double a = c.pitch * c.pitch, P = m_cur.pressure;
    if (!((c.panelSink > 0.0 || c.panelLift > 0.0) && m_results.size() > 1 && P > 0.0)) return;
    std::array<double, 2> total{};
    for (ShapeResult& r : m_results) {
        const double kappa = lookup(c.pressureFactor, m_cur.mass, r.depth, nullptr);
        for (const Sample& smp : r.samples) {
            const double q = smp.blend * smp.film * a * kappa * P *
                             calcWeight(smp.delta, r.depth, nullptr, nullptr);
            r.panelLoad[0] += q * m_steep[smp.point];
            r.panelLoad[1] += q * (1.0 - m_steep[smp.point]);
        }
        for (int k = 0; k < 2; ++k) total[k] += r.panelLoad[k];
    }
    const Vec3 e = m_X_GB.linear().col(2);
    for (ShapeResult& r : m_results) {
        const double Ls = total[0] - r.panelLoad[0], Lg = total[1] - r.panelLoad[1];
        double s1 = 0.0, s2 = 0.0;
        for (Sample& smp : r.samples) {
            const double st = m_steep[smp.point];
            smp.shift = st * (-c.panelSink * Ls + c.panelLift * Lg) +
                        (1.0 - st) * (c.panelLift * Ls - c.panelSink * Lg);
            smp.dShift = smp.shift / P;
            smp.delta = smp.delta0 - smp.n.dot(e) * smp.shift;
            if (smp.delta > 0.0) {
                s1 += a * smp.blend * smp.delta;
                s2 += a * smp.blend * smp.delta * smp.delta;
            }
        }
        r.depthSum1 = s1, r.depthSum2 = s2;
        r.depth = s1 > 0.0 ? s2 / s1 : 0.0;
        findDeepestAndArea(r);
    }
}

void ReducedBag::findDeepestAndArea(ShapeResult& r) const {
    const double a = m_cal->pitch * m_cal->pitch;
    r.deepest = -1, r.area = 0.0;
    for (size_t k = 0; k < r.samples.size(); ++k) {
        const Sample& smp = r.samples[k];
        if (r.deepest < 0 || smp.delta > r.samples[r.deepest].delta) r.deepest = int(k);
        r.area += a * smp.blend * calcWeight(smp.delta, r.depth, nullptr, nullptr);
    }
}

double ReducedBag::calcBoardPressure(const Vec3& p) const {
    return m_cal->boardPenalty * std::max(0.0, -(m_X_BG * p).z());
}

Vec3 ReducedBag::calcTopPoint(int point) const {
    const ReducedBagCalibration& c = *m_cal;
    const int g = m_gridIndex[point];
    return m_X_GB * Vec3(c.x0 + c.pitch * (g % c.nx), c.y0 + c.pitch * (g / c.nx),
                         interpolateTop(point, m_cur.mass));
}

Eigen::Matrix3Xd ReducedBag::calcTop() const {
    const int n = int(m_gridIndex.size());
    Eigen::Matrix3Xd top(3, n);
    for (int i = 0; i < n; ++i) top.col(i) = calcTopPoint(i);
    return top;
}

void ReducedBag::buildFootprint(const Eigen::Matrix3Xd& top) {
    // The grid's tops first (no pressure: where nothing presses), then one point per sample
    // of each shape, at its contact point over its area a / g, so that each shape's pressures
    // on them give its wrench exactly (docs/reduced-bag.md#the-pressure-footprint).
    const double a = m_cal->pitch * m_cal->pitch;
    const int n = int(top.cols());
    int total = n;
    m_slotStart.assign(m_results.size(), 0);
    for (size_t s = 0; s < m_results.size(); ++s) {
        m_slotStart[s] = total;
        total += int(m_results[s].samples.size());
    }
    m_points.resize(3, total);
    m_areas.resize(total);
    m_points.leftCols(n) = top;
    m_areas.head(n).setConstant(a);
    for (size_t s = 0; s < m_results.size(); ++s)
        for (size_t k = 0; k < m_results[s].samples.size(); ++k) {
            const Sample& smp = m_results[s].samples[k];
            m_points.col(m_slotStart[s] + int(k)) = smp.c;
            m_areas[m_slotStart[s] + int(k)] = a / std::max(-smp.n.z(), kMinSlope);
        }
}

ShapeWrench ReducedBag::calcWrench(int shape) const { return m_results.at(shape).wrench; }

std::vector<ReducedBag::SampleForce> ReducedBag::getSampleForces(int shape) const {
    const ReducedBagCalibration& c = *m_cal;
    const ShapeResult& r = m_results.at(shape);
    const double a = c.pitch * c.pitch;
    const double kappa = lookup(c.pressureFactor, m_cur.mass, r.depth, nullptr);
    std::vector<SampleForce> out;
    for (const Sample& smp : r.samples) {
        SampleForce f;
        f.point = smp.point;
        f.column = smp.column > 0.0;
        f.delta = smp.delta, f.blend = smp.blend, f.film = smp.film, f.c = smp.c, f.n = smp.n;
        f.shift = smp.shift;
        f.gasPressure = kappa * m_cur.pressure * calcWeight(smp.delta, r.depth, nullptr, nullptr);
        f.boardPressure = calcBoardPressure(smp.c);
        const double gs = std::max(-smp.n.z(), kMinSlope);
        f.force = smp.blend * smp.film * a * (f.gasPressure + f.boardPressure) / gs * -smp.n;
        out.push_back(f);
    }
    return out;
}

Eigen::VectorXd ReducedBag::calcContactPressure(int shape) const {
    const ReducedBagCalibration& c = *m_cal;
    const ShapeResult& r = m_results.at(shape);
    Eigen::VectorXd p = Eigen::VectorXd::Zero(m_points.cols());
    const double kappa = lookup(c.pressureFactor, m_cur.mass, r.depth, nullptr);
    // Each sample's own point (buildFootprint): its whole pressure, gas and board, times its
    // blend, as in the wrench.
    for (size_t k = 0; k < r.samples.size(); ++k) {
        const Sample& smp = r.samples[k];
        p[m_slotStart.at(size_t(shape)) + int(k)] =
            smp.blend * smp.film *
            (kappa * m_cur.pressure * calcWeight(smp.delta, r.depth, nullptr, nullptr) +
             calcBoardPressure(smp.c));
    }
    return p;
}

Mat6 ReducedBag::calcWrenchTangent(int shape) const {
    // Analytic derivative of calcWrench() (docs/reduced-bag.md#the-tangent): a pose change
    // xi = (theta, u) moves the shape's material at a fixed Ground point t by
    // v = u + theta x r (r = t - o), so d delta = n.v, dn = theta x n - (dn/dp) v, and the gas
    // pressure follows the displaced volume, dP = dP/dV_d d V_d.
    const ReducedBagCalibration& c = *m_cal;
    const ShapeResult& r = m_results.at(shape);
    const Vec3 o = m_poses.at(shape).translation();
    const double a = c.pitch * c.pitch, P = m_cur.pressure;
    const Eigen::Matrix3d R_BG = m_X_GB.linear().transpose();
    using Row6 = Eigen::Matrix<double, 1, 6>;
    using Mat36 = Eigen::Matrix<double, 3, 6>;
    auto jacobian = [&](const Vec3& t) {  // v = J xi
        Mat36 J;
        J << -cross(t - o), Eigen::Matrix3d::Identity();
        return J;
    };
    Mat36 Jtheta = Mat36::Zero(), Ju = Mat36::Zero();
    Jtheta.leftCols<3>().setIdentity();
    Ju.rightCols<3>().setIdentity();

    double dKappa = 0.0, dBeta = 0.0;
    const double kappa = lookup(c.pressureFactor, m_cur.mass, r.depth, &dKappa);
    const double beta = lookup(c.volumeFactor, m_cur.mass, r.depth0, &dBeta);
    // The depth s2 / s1 over delta > 0 (the blend b held), of the given depths' derivatives.
    // (the blends' derivatives, dBlend, below)
    std::vector<Row6> dBlend(r.samples.size(), Row6::Zero());
    auto calcDepthDerivative = [&](double s1, double s2, auto deltaOf, auto dDeltaOf) {
        Row6 dDepth = Row6::Zero();
        for (size_t k = 0; k < r.samples.size(); ++k) {
            const Sample& smp = r.samples[k];
            const double d = deltaOf(smp);
            if (d > 0.0)
                dDepth += a *
                          ((2.0 * d * s1 - s2) * smp.blend * dDeltaOf(smp) +
                           (d * d * s1 - d * s2) * dBlend[k]) /
                          (s1 * s1);
        }
        return dDepth;
    };
    // How each sample moves with the pose. A top sample's point t is fixed in Ground: the
    // material there moves by v = J(t) xi, so d delta0 = n.v, dn = theta x n - (dn/dp) v and
    // its contact point c = t + delta0 n. A column sample sits where the fixed column leaves
    // the shape's underside (c, the film's contact): that point slides along the column by
    // dz = n.v / n.e (v = J(c) xi), dn = theta x n + (dn/dp) (e dz - v) there, and its depth
    // is the column's length L times max(-n_z, kMinSlope) (dL = -dz), or half the surface's
    // least curvature radius where that is smaller (held).
    const Vec3 e = m_X_GB.linear().col(2);
    struct Motion {
        Row6 dDelta0;
        Mat36 dn, dc;
    };
    std::vector<Motion> motion(r.samples.size());
    for (size_t k = 0; k < r.samples.size(); ++k) {
        const Sample& smp = r.samples[k];
        Motion& m = motion[k];
        if (smp.column > 0.0) {
            const Mat36 J = jacobian(smp.c);
            const double ne = smp.n.dot(e);
            const Row6 dz =
                std::abs(ne) > kGrazing ? Row6(smp.n.transpose() * J / ne) : Row6::Zero();
            m.dc = e * dz;
            m.dn = -cross(smp.n) * Jtheta + smp.dndp * (m.dc - J);
            const double curvature = smp.dndp.norm();
            double slope = -smp.n.z();
            Row6 dSlope = -m.dn.row(2);
            if (slope < kMinSlope) slope = kMinSlope, dSlope.setZero();
            const bool capped = curvature > 1e-12 && smp.column * slope > 0.5 / curvature;
            m.dDelta0 = capped ? Row6::Zero() : Row6(-dz * slope + smp.column * dSlope);
        } else {
            const Mat36 J = jacobian(smp.t);
            m.dDelta0 = smp.n.transpose() * J;
            m.dn = -cross(smp.n) * Jtheta - smp.dndp * J;
            m.dc = smp.n * m.dDelta0 + smp.delta0 * m.dn;
        }
    }
    auto indexOf = [&](const Sample& smp) { return size_t(&smp - r.samples.data()); };
    std::vector<int> chordOf(size_t(m_gridIndex.size()), -1);  // grid point -> its chord
    for (size_t k = 0; k < r.chords.size(); ++k) chordOf[size_t(r.chords[k].point)] = int(k);
    // A sample's blend (evaluate()): with n and phi the top point's normal and signed
    // distance, b = calcColumnShare(n_z, phi) where its column has a chord; a column sample
    // has b times its axis fade, a top sample (1 - b) times the fade of an upward normal and
    // its own axis fade. A top sample is the top point's own geometry (phi = -n.(c - t)); a
    // column sample asks the shape for it.
    {
        const bags::RigidShape& body = *m_shapes.at(size_t(shape));
        for (size_t k = 0; k < r.samples.size(); ++k) {
            const Sample& smp = r.samples[k];
            const Vec3 t = smp.column > 0.0 ? calcTopPoint(smp.point) : smp.t;
            double phi = 0.0;
            Vec3 nTop = smp.n;
            Eigen::Matrix3d dndpTop = smp.dndp;
            if (smp.column > 0.0) {
                Vec3 cp;
                body.calcContactGeometry(t, &phi, &cp, &nTop, &dndpTop);
            } else {
                phi = -nTop.dot(smp.c - t);
            }
            const Mat36 J = jacobian(t);
            const Row6 dnz = (-cross(nTop) * Jtheta - dndpTop * J).row(2);
            const Row6 dDepthTop = nTop.transpose() * J;  // d(-phi)
            double dbNz = 0.0, dbDepth = 0.0;
            const double b = chordOf[size_t(smp.point)] >= 0
                                 ? calcColumnShare(nTop.z(), phi, &dbNz, &dbDepth)
                                 : 0.0;
            const Row6 db = dbNz * dnz + dbDepth * dDepthTop;
            // (the axis fade moves with the material past the point: at a fixed point by
            // -v, at a column's underside by dc - v)
            if (smp.column > 0.0) {
                if (b > 0.0) {
                    const Mat36 rel = motion[k].dc - jacobian(smp.c);
                    const double axis = calcAxisFade(smp.dndp);
                    dBlend[k] = axis * db + b * calcAxisFadeGradient(body, smp.c).transpose() * rel;
                }
            } else {
                double dFade = 0.0;
                const double fade = calcUpFade(nTop.z(), &dFade);
                dBlend[k] = calcAxisFade(smp.dndp) * (-db * fade + (1.0 - b) * dFade * dnz) -
                            (1.0 - b) * fade * calcAxisFadeGradient(body, t).transpose() * J;
            }
        }
    }
    // Under the unloaded top (the displaced volume's beta reads it).
    const Row6 dDepth0 = calcDepthDerivative(
        r.depth0Sum1, r.depth0Sum2, [](const Sample& smp) { return smp.delta0; },
        [&](const Sample& smp) -> Row6 { return motion[indexOf(smp)].dDelta0; });
    // V_s = sum a (z_hi - z_lo) over the chords: a surface end moves along the fixed column by
    // dz = n.v / n.e (e up); the top point and the board stay.
    // Where other shapes share a column, this shape's pose changes every sharer's part
    // beta_r length_r U / S: d(sum_r beta_r a length_r U / S) = a (beta w dl + B / S (dU - w
    // dl)), w = U / S, B = sum_r beta_r length_r, dU from this chord's ends that bound the
    // union. That is the displaced volume's change, dVd; alone in a column it is beta a dl.
    Row6 dVd = Row6::Zero();
    for (const Chord& ch : r.chords) {
        Row6 dHi = Row6::Zero(), dLo = Row6::Zero();
        if (!ch.topInside && std::abs(ch.nhi.dot(e)) > kGrazing)
            dHi = 1.0 / ch.nhi.dot(e) * ch.nhi.transpose() * jacobian(ch.hi);
        if (!ch.onBoard && std::abs(ch.nlo.dot(e)) > kGrazing)
            dLo = 1.0 / ch.nlo.dot(e) * ch.nlo.transpose() * jacobian(ch.lo);
        const Row6 dl = dHi - dLo;
        const Row6 dU = (ch.hiBounds ? dHi : Row6::Zero()) - (ch.loBounds ? dLo : Row6::Zero());
        dVd += a * (beta * ch.share * dl + ch.betaSum / ch.sum * (dU - ch.share * dl));
    }
    const Row6 dP = m_dPdV * (dVd + r.volume * dBeta * dDepth0);
    // Under the top the other shapes' loads moved (the panel coupling): delta = delta0 - (n.e)
    // shift, the shift following the gas pressure (their poses held).
    auto dDeltaOf = [&](const Sample& smp) -> Row6 {
        const Motion& m = motion[indexOf(smp)];
        Row6 d = m.dDelta0;
        if (smp.shift != 0.0 || smp.dShift != 0.0)
            d -= smp.shift * (e.transpose() * m.dn) + smp.n.dot(e) * smp.dShift * dP;
        return d;
    };
    const Row6 dDepth = calcDepthDerivative(
        r.depthSum1, r.depthSum2, [](const Sample& smp) { return smp.delta; }, dDeltaOf);
    const Row6 dK = dKappa * dDepth;

    Mat6 T = Mat6::Zero();
    for (const Sample& smp : r.samples) {
        const Motion& m = motion[indexOf(smp)];
        const Row6 dDelta = dDeltaOf(smp);
        const Mat36& dn = m.dn;
        const Mat36& dc = m.dc;
        double dwDelta = 0.0, dwDepth = 0.0;
        const double w = calcWeight(smp.delta, r.depth, &dwDelta, &dwDepth);
        Row6 dq = kappa * w * dP + P * w * dK + kappa * P * (dwDelta * dDelta + dwDepth * dDepth);
        double q = kappa * P * w;
        const Vec3 cB = R_BG * (smp.c - m_X_GB.translation());
        if (cB.z() < 0.0) {
            q += -c.boardPenalty * cB.z();
            dq += -c.boardPenalty * (R_BG.row(2) * dc);
        }
        double g = -smp.n.z();
        Row6 dg = -dn.row(2);
        if (g < kMinSlope) {
            g = kMinSlope;
            dg.setZero();
        }
        const double ab = a * smp.blend * smp.film;
        const Vec3 f = ab * q / g * -smp.n;
        // (the film's share moves with this shape's depth at the top point, the others held)
        const Mat36 df = -ab * (smp.n * (dq / g - q / (g * g) * dg) + q / g * dn) -
                         a * smp.blend * q / g * smp.n * smp.dFilm -
                         a * smp.film * q / g * smp.n * dBlend[indexOf(smp)];
        T.bottomRows<3>() += df;
        T.topRows<3>() += -cross(f) * (dc - Ju) + cross(smp.c - o) * df;
    }
    if (r.anchored) {
        // The friction force f = -mu N s / max(|s|, d), s = P (u + tau v), P = I - n n^T,
        // n = F_n / N: through the spring point p (dp = J(p) xi; its velocity w x (p - o)
        // turns with the shape) and through F_n, whose derivative is the rows above.
        const double mu = m_friction.coefficient, d = m_friction.stickDistance;
        const Mat36 Jp = jacobian(r.point);
        const Vec3 w = m_velocities.at(shape).head<3>();
        const Mat36 dRaw = Jp + m_friction.dampingTime * cross(w) * (Jp - Ju);
        const Mat36 dF = T.bottomRows<3>();
        const double N = r.normalForce.norm();
        const Vec3 n = r.normalForce / N;
        const Eigen::Matrix3d Pn = Eigen::Matrix3d::Identity() - n * n.transpose();
        const Row6 dN = n.transpose() * dF;
        const Mat36 dn = Pn * dF / N;
        const Mat36 dS = Pn * dRaw - dn * n.dot(r.raw) - n * (r.raw.transpose() * dn);
        Mat36 df;
        if (!r.sliding) {
            df = -(mu / d) * (r.slip * dN + N * dS);
        } else {
            const double ns = r.slip.norm();
            const Vec3 sh = r.slip / ns;
            df =
                -mu * (sh * dN + N / ns * (Eigen::Matrix3d::Identity() - sh * sh.transpose()) * dS);
        }
        const Vec3& f = r.frictionForce;
        T.bottomRows<3>() += df;
        T.topRows<3>() += -cross(f) * (Jp - Ju) + cross(r.point - o) * df;
    }
    return T;
}

bags::ChamberState ReducedBag::getChamberState(int chamber) const {
    if (chamber != 0) throw std::out_of_range("ReducedBag: one chamber (0)");
    const ReducedBagCalibration& c = *m_cal;
    bags::ChamberState s;
    s.gaugePressure = m_cur.pressure;
    s.mass = m_cur.mass;
    s.volume = m_cur.mass * c.gasConstant * c.temperature / (m_cur.pressure + c.ambientPressure);
    return s;
}

double ReducedBag::calcPotentialEnergy() const {
    // The isothermal gas's work potential -G(V), G = m R T ln V - p_amb V, and the board's
    // penalty energy under the pressed film.
    const ReducedBagCalibration& c = *m_cal;
    const double mrt = m_cur.mass * c.gasConstant * c.temperature;
    const double V = mrt / (m_cur.pressure + c.ambientPressure);
    double e = -(mrt * std::log(V) - c.ambientPressure * V);
    const double a = c.pitch * c.pitch;
    for (const ShapeResult& r : m_results)
        for (const Sample& smp : r.samples) {
            const double z = (m_X_BG * smp.c).z();
            if (z < 0.0) e += 0.5 * c.boardPenalty * a * smp.film * z * z;
        }
    return e;
}

double ReducedBag::getOverlapVolume(int shape) const { return m_results.at(shape).volume; }
double ReducedBag::getDepth(int shape) const { return m_results.at(shape).depth; }
double ReducedBag::getContactArea(int shape) const { return m_results.at(shape).area; }

void ReducedBag::checkEnvelope() {
    const ReducedBagCalibration& c = *m_cal;
    EnvelopeCounts& e = m_envelope;
    ++e.steps;
    const double m = m_cur.mass;
    const double tol = 1e-9;
    if (m < c.masses.front() * (1 - tol) || m > c.masses.back() * (1 + tol)) {
        ++e.mass;
        const double mid = 0.5 * (c.masses.front() + c.masses.back());
        if (e.worstMass == 0.0 || std::abs(m - mid) > std::abs(e.worstMass - mid)) e.worstMass = m;
    }
    bool depth = false, radius = false, tilt = false;
    for (const ShapeResult& r : m_results) {
        if (r.deepest < 0) continue;
        const Sample& d = r.samples[r.deepest];
        if (r.depth > c.depthMax) {
            depth = true;
            e.worstDepth = std::max(e.worstDepth, r.depth);
        }
        // The shape's least curvature radius at its deepest point: 1 / the largest
        // eigenvalue of dn/dp (symmetric part) at the point delta inside, plus delta.
        const Eigen::Matrix3d D = 0.5 * (d.dndp + d.dndp.transpose());
        const double kmax =
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(D).eigenvalues().maxCoeff();
        const double rad =
            kmax > 1e-9 ? 1.0 / kmax + d.delta : std::numeric_limits<double>::infinity();
        if (rad < c.radiusMin * 0.999 || rad > c.radiusMax * 1.001) {
            radius = true;
            if (e.worstRadius == 0.0 || std::abs(std::log(rad / c.radiusMin)) >
                                            std::abs(std::log(e.worstRadius / c.radiusMin)))
                e.worstRadius = rad;
        }
        const Vec3 nB = m_X_GB.linear().transpose() * d.n;
        const double angle = std::acos(std::clamp(-nB.z(), -1.0, 1.0));
        if (angle > c.tiltMax) {
            tilt = true;
            e.worstTilt = std::max(e.worstTilt, angle);
        }
    }
    e.depth += depth;
    e.radius += radius;
    e.tilt += tilt;
}

namespace {

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, f, a, b, c);
    return buf;
}

std::string describeReason(int reason, const EnvelopeCounts& e, const ReducedBagCalibration& c) {
    const double deg = 180.0 / 3.14159265358979323846;
    switch (reason) {
        case 0:
            return fmt("gas mass %.2f g (calibrated %.2f to %.2f g)", e.worstMass * 1e3,
                       c.masses.front() * 1e3, c.masses.back() * 1e3);
        case 1:
            return fmt("depth %.1f mm (calibrated to %.1f mm)", e.worstDepth * 1e3,
                       c.depthMax * 1e3);
        case 2:
            return fmt("shape curvature radius %.0f mm (calibrated %.0f to %.0f mm)",
                       e.worstRadius * 1e3, c.radiusMin * 1e3, c.radiusMax * 1e3);
        default:
            return fmt("contact normal %.0f deg from vertical (calibrated to %.0f deg)",
                       e.worstTilt * deg, c.tiltMax * deg);
    }
}

}  // namespace

std::string describeNewEnvelopeExits(const EnvelopeCounts& now, const EnvelopeCounts& before,
                                     const ReducedBagCalibration& c) {
    const int n[4] = {now.mass, now.depth, now.radius, now.tilt};
    const int b[4] = {before.mass, before.depth, before.radius, before.tilt};
    std::string s;
    for (int k = 0; k < 4; ++k)
        if (n[k] > 0 && b[k] == 0) s += (s.empty() ? "" : "; ") + describeReason(k, now, c);
    return s.empty() ? s
                     : "a reduced bag left its calibration's validity envelope: " + s +
                           " (counted in the summary; docs/reduced-bag.md#validity)";
}

std::string describeEnvelopeCounts(const EnvelopeCounts& e, const ReducedBagCalibration& c) {
    if (e.total() == 0)
        return "reduced bags: all " + std::to_string(e.steps) +
               " bag-steps inside the calibration's validity envelope";
    std::string s = "reduced bags: outside the calibration's validity envelope in";
    const int n[4] = {e.mass, e.depth, e.radius, e.tilt};
    bool first = true;
    for (int k = 0; k < 4; ++k)
        if (n[k] > 0) {
            s += (first ? " " : ", ") + std::to_string(n[k]) + " of " + std::to_string(e.steps) +
                 " bag-steps by " + describeReason(k, e, c);
            first = false;
        }
    return s;
}

namespace {

template <class V>
void saveFixed(bags::StateWriter& w, const V& v) {
    for (Eigen::Index i = 0; i < v.size(); ++i) w.pod(v.data()[i]);
}
template <class V>
void loadFixed(bags::StateReader& r, V& v) {
    for (Eigen::Index i = 0; i < v.size(); ++i) r.pod(v.data()[i]);
}

}  // namespace

void ReducedBag::saveState(bags::StateWriter& w) const {
    w.tag("reduced bag 5");
    for (const State* s : {&m_cur, &m_committed}) {
        w.pod(s->mass), w.pod(s->pressure), w.pod(s->time);
        w.pod(s->flow), w.pod(s->target), w.pod(s->rate);
    }
    w.pod(std::uint64_t(m_poses.size()));
    for (const Eigen::Isometry3d& X : m_poses) w.pose(X);
    for (const Eigen::Isometry3d& X : m_committedPoses) w.pose(X);
    for (const Vec6& v : m_velocities) saveFixed(w, v);
    for (const Vec6& v : m_committedVelocities) saveFixed(w, v);
    for (const Anchor& a : m_anchors)
        w.pod(a.on), saveFixed(w, a.onShape), saveFixed(w, a.inGround);
    for (const ShapeResult& res : m_results) {
        w.pod(std::uint64_t(res.samples.size()));
        for (const Sample& smp : res.samples) {
            w.pod(smp.point), w.pod(smp.delta), w.pod(smp.blend);
            w.pod(smp.film),
                saveFixed(w, smp.dFilm);  // (topDelta, topN: inputs of evaluate's share)
            saveFixed(w, smp.t), saveFixed(w, smp.c), saveFixed(w, smp.n), saveFixed(w, smp.dndp);
        }
        w.pod(std::uint64_t(res.chords.size()));
        for (const Chord& ch : res.chords) {
            w.pod(ch.point), w.pod(ch.topInside), w.pod(ch.onBoard), w.pod(ch.length);
            w.pod(ch.share), w.pod(ch.sum), w.pod(ch.betaSum), w.pod(ch.hiBounds),
                w.pod(ch.loBounds);
            saveFixed(w, ch.hi), saveFixed(w, ch.nhi), saveFixed(w, ch.lo), saveFixed(w, ch.nlo);
        }
        w.pod(res.volume), w.pod(res.depth), w.pod(res.area);
        w.pod(res.depthSum1), w.pod(res.depthSum2), w.pod(res.deepest);
        saveFixed(w, res.wrench.torque), saveFixed(w, res.wrench.force);
        saveFixed(w, res.normalForce), saveFixed(w, res.point), saveFixed(w, res.raw);
        saveFixed(w, res.slip), saveFixed(w, res.frictionForce), saveFixed(w, res.centroid);
        w.pod(res.load), w.pod(res.anchored), w.pod(res.sliding);
    }
    w.pod(m_displaced), w.pod(m_dPdV);
    w.pod(m_envelope);
}

void ReducedBag::loadState(bags::StateReader& r) {
    r.tag("reduced bag 5");
    for (State* s : {&m_cur, &m_committed}) {
        r.pod(s->mass), r.pod(s->pressure), r.pod(s->time);
        r.pod(s->flow), r.pod(s->target), r.pod(s->rate);
    }
    const auto n = r.pod<std::uint64_t>();
    if (n != m_poses.size())
        bags::StateReader::mismatch("shapes of a reduced bag", n, m_poses.size());
    for (Eigen::Isometry3d& X : m_poses) X = r.pose();
    for (Eigen::Isometry3d& X : m_committedPoses) X = r.pose();
    for (Vec6& v : m_velocities) loadFixed(r, v);
    for (Vec6& v : m_committedVelocities) loadFixed(r, v);
    for (Anchor& a : m_anchors) r.pod(a.on), loadFixed(r, a.onShape), loadFixed(r, a.inGround);
    for (ShapeResult& res : m_results) {
        res.samples.resize(r.pod<std::uint64_t>());
        for (Sample& smp : res.samples) {
            r.pod(smp.point), r.pod(smp.delta), r.pod(smp.blend);
            r.pod(smp.film), loadFixed(r, smp.dFilm);
            loadFixed(r, smp.t), loadFixed(r, smp.c), loadFixed(r, smp.n), loadFixed(r, smp.dndp);
        }
        res.chords.resize(r.pod<std::uint64_t>());
        for (Chord& ch : res.chords) {
            r.pod(ch.point), r.pod(ch.topInside), r.pod(ch.onBoard), r.pod(ch.length);
            r.pod(ch.share), r.pod(ch.sum), r.pod(ch.betaSum), r.pod(ch.hiBounds),
                r.pod(ch.loBounds);
            loadFixed(r, ch.hi), loadFixed(r, ch.nhi), loadFixed(r, ch.lo), loadFixed(r, ch.nlo);
        }
        r.pod(res.volume), r.pod(res.depth), r.pod(res.area);
        r.pod(res.depthSum1), r.pod(res.depthSum2), r.pod(res.deepest);
        loadFixed(r, res.wrench.torque), loadFixed(r, res.wrench.force);
        loadFixed(r, res.normalForce), loadFixed(r, res.point), loadFixed(r, res.raw);
        loadFixed(r, res.slip), loadFixed(r, res.frictionForce), loadFixed(r, res.centroid);
        r.pod(res.load), r.pod(res.anchored), r.pod(res.sliding);
    }
    r.pod(m_displaced), r.pod(m_dPdV);
    r.pod(m_envelope);
    for (size_t s = 0; s < m_shapes.size(); ++s) m_shapes[s]->setPose(m_poses[s]);
    // A column sample's point lies off its top point; its column reaches down to c.
    const Eigen::Matrix3Xd top = calcTop();
    const Vec3 e = m_X_GB.linear().col(2);
    for (ShapeResult& res : m_results)
        for (Sample& smp : res.samples)
            if ((smp.t - top.col(smp.point)).norm() > 1e-12)
                smp.column = e.dot(top.col(smp.point) - smp.c);
    buildFootprint(top);
}

}  // namespace cosim
