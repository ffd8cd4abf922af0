// Penalty contact of membrane nodes with a rigid shape, with regularised Coulomb friction.
//
// Normal law per node (g = signed distance, k = pressurePenalty * nodal reference area):
//   onsetGap = 0:  phi(g) = k g^2 / 2 for g < 0                (C1 energy)
//   onsetGap = w:  phi'' ramps linearly from 0 at g = w/2 to k at g = -w/2 (C2 energy, cubic
//                  in the ramp); below -w/2 the force is exactly k g, as without smoothing.
// Tissue layer (tissueThickness h > 0): the node's penetration -g is shared between the
//   layer's compression c and the penalty, in series: the penalty sees the gap g + c, and c
//   balances it, A sigma(c) = -phi'(g + c) (A the nodal reference area). The energy is
//   Phi(g) = phi(g + c) + A w(c), c minimising it: Phi' = phi'(g + c) (envelope theorem) and
//   Phi'' = phi'' A sigma' / (phi'' + A sigma'), the two springs in series.
// Friction, two laws (Options::frictionLaw), both with an anchor on the surface stored in the
// shape frame (it rides with the shape) and s = P (p - anchor), P = I - n n^T:
//   stick-slip:  an elastic stick spring k_t = stickStiffnessRatio * k to the anchor, capped at
//                mu * f_n (slip); the anchor keeps the spring's offset across commits.
//   regularised: f_t = -mu f_n s / sqrt(|s|^2 + r^2), r = v_s dt; the anchor is the contact
//                point at the last commit, so s is the slip over the step.

#include <bags/Contact.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace bags {

namespace {

/// Normal penalty potential phi(g) with its first and second derivatives; with a tissue
/// layer, the layer and the penalty in series.
struct NormalLaw {
    double k;
    double width;            // onsetGap [m]
    double area = 0.0;       // nodal reference area [m^2]
    double thickness = 0.0;  // tissue layer [m], 0: none
    double modulus = 0.0;    // [Pa]
    /// Returns false when the node is not in contact (phi = phi' = phi'' = 0).
    bool eval(double g, double& phi, double& dphi, double& ddphi) const {
        if (thickness <= 0.0) return evalPenalty(g, phi, dphi, ddphi);
        if (!evalPenalty(g, phi, dphi, ddphi)) return false;
        // r(c) = A sigma(c) + phi'(g + c) rises from phi'(g) <= 0 at c = 0 to A sigma > 0 where
        // the penalty lets go (c = activationDistance - g): safeguarded Newton in that bracket.
        double lo = 0.0, hi = activationDistance() - g, c = 0.0;
        TissueStress t;
        for (int it = 0; it < 100; ++it) {
            t = calcTissueStress(c, thickness, modulus);
            evalPenalty(g + c, phi, dphi, ddphi);
            const double r = area * t.sigma + dphi;
            if (r < 0.0)
                lo = c;
            else
                hi = c;
            const double dr = area * t.dsigma + ddphi;
            double next = c - r / dr;
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
            if (std::abs(next - c) <= 1e-14 * thickness || hi - lo <= 1e-14 * thickness) {
                c = next;
                break;
            }
            c = next;
        }
        t = calcTissueStress(c, thickness, modulus);
        evalPenalty(g + c, phi, dphi, ddphi);
        const double kl = area * t.dsigma;
        phi += area * t.energy;
        ddphi = ddphi > 0.0 ? ddphi * kl / (ddphi + kl) : 0.0;
        return true;
    }
    bool evalPenalty(double g, double& phi, double& dphi, double& ddphi) const {
        phi = dphi = ddphi = 0.0;
        if (width <= 0.0) {
            if (g >= 0.0) return false;
            phi = 0.5 * k * g * g;
            dphi = k * g;
            ddphi = k;
            return true;
        }
        const double half = 0.5 * width;
        if (g >= half) return false;
        const double u = half - g;
        if (u <= width) {
            phi = k * u * u * u / (6.0 * width);
            dphi = -k * u * u / (2.0 * width);
            ddphi = k * u / width;
        } else {
            phi = 0.5 * k * g * g + k * width * width / 24.0;
            dphi = k * g;
            ddphi = k;
        }
        return true;
    }
    double activationDistance() const { return width > 0.0 ? 0.5 * width : 0.0; }
};

/// One node's contribution.
struct NodeTerm {
    bool active = false;
    double energy = 0.0;
    Vec3 grad = Vec3::Zero();  // dE/dp = - force on the node
    Mat3 hess = Mat3::Zero();  // what Newton gets: symmetric, without the f_n coupling
    Mat3 full = Mat3::Zero();  // the exact d grad / dp (evalNode's `full` asked)
    Vec3 closest = Vec3::Zero();
    double normalForce = 0.0;  // f_n >= 0 [N]
};

}  // namespace

void RigidContact::Options::validate() const {
    if (!(pressurePenalty > 0.0) || !std::isfinite(pressurePenalty))
        throw std::invalid_argument("RigidContact option pressurePenalty must be > 0 [Pa/m], got " +
                                    std::to_string(pressurePenalty));
    if (!(friction >= 0.0) || !std::isfinite(friction))
        throw std::invalid_argument("RigidContact option friction must be >= 0, got " +
                                    std::to_string(friction));
    if (!(slipVelocity > 0.0) || !std::isfinite(slipVelocity))
        throw std::invalid_argument("RigidContact option slipVelocity must be > 0 [m/s], got " +
                                    std::to_string(slipVelocity));
    if (!(stickStiffnessRatio > 0.0) || !std::isfinite(stickStiffnessRatio))
        throw std::invalid_argument("RigidContact option stickStiffnessRatio must be > 0, got " +
                                    std::to_string(stickStiffnessRatio));
    if (!(onsetGap >= 0.0) || !std::isfinite(onsetGap))
        throw std::invalid_argument("RigidContact option onsetGap must be >= 0 [m], got " +
                                    std::to_string(onsetGap));
    if (!(tissueThickness >= 0.0) || !std::isfinite(tissueThickness))
        throw std::invalid_argument("RigidContact option tissueThickness must be >= 0 [m], got " +
                                    std::to_string(tissueThickness));
    if (tissueThickness > 0.0 ? !(tissueModulus > 0.0) || !std::isfinite(tissueModulus)
                              : tissueModulus != 0.0)
        throw std::invalid_argument(
            "RigidContact options tissueThickness and tissueModulus go together: both > 0 "
            "(a layer) or both 0 (none), got " +
            std::to_string(tissueThickness) + " m and " + std::to_string(tissueModulus) + " Pa");
    if (minNodesForThreads < 1)
        throw std::invalid_argument("RigidContact option minNodesForThreads must be >= 1, got " +
                                    std::to_string(minNodesForThreads));
}

TissueStress calcTissueStress(double c, double h, double E) {
    TissueStress t;
    const double cm = (1.0 - kTissueMinStretch) * h;  // where the linear continuation starts
    const double l = 1.0 - std::min(c, cm) / h;
    t.sigma = E / 3.0 * (1.0 / (l * l) - l);
    t.dsigma = E / (3.0 * h) * (2.0 / (l * l * l) + 1.0);
    t.energy = E * h / 6.0 * (l * l + 2.0 / l - 3.0);
    if (c > cm) {
        const double e = c - cm;
        t.energy += t.sigma * e + 0.5 * t.dsigma * e * e;
        t.sigma += t.dsigma * e;
    }
    return t;
}

struct RigidContact::Impl {
    Options opt;
    const RigidShape* shape = nullptr;
    int numNodes = 0;            // nodes of the mesh
    std::vector<int> nodes;      // contact set
    std::vector<double> area;    // nodal reference area [m^2] per contact node
    std::vector<Vec3> anchor_S;  // friction anchor on the surface, shape frame
    std::vector<char> hasAnchor;
    double slipLength = RigidContact::kMinSlipLength;  // [m] r = v_s dt of the regularised law
    bool frictionSuppressed = false;  // setFrictionSuppressed(): evaluate as frictionless

    NormalLaw law(int j) const {
        return NormalLaw{opt.pressurePenalty * area[j], opt.onsetGap, area[j], opt.tissueThickness,
                         opt.tissueModulus};
    }

    /// Fast rejection of nodes certainly out of reach of the shape.
    bool isFar(const Vec3& p) const {
        return shape->calcDistanceLowerBound(p) >= 0.5 * opt.onsetGap;
    }

    /// The node's term at p; `full` also gives the exact, unsymmetric tangent out.full.
    void evalNode(int j, const Vec3& p, bool wantHess, NodeTerm& out, bool full = false) const {
        out.active = false;
        wantHess = wantHess || full;
        if (area[j] <= 0.0 || isFar(p)) return;
        const NormalLaw nl = law(j);
        double g;
        Vec3 c, n;
        Mat3 dn;
        shape->calcContactGeometry(p, &g, &c, &n, wantHess ? &dn : nullptr);
        double phi, dphi, ddphi;
        if (!nl.eval(g, phi, dphi, ddphi)) return;
        out.active = true;
        out.closest = c;
        out.normalForce = -dphi;
        out.energy = phi;
        out.grad = dphi * n;
        if (wantHess) out.hess = ddphi * n * n.transpose() + dphi * dn;
        if (full) out.full = out.hess;
        if (!(opt.friction > 0.0 && hasAnchor[j]) || frictionSuppressed) return;
        const Vec3 a_G = shape->getPose() * anchor_S[j];
        const Mat3 P = Mat3::Identity() - n * n.transpose();
        const Vec3 q = p - a_G;
        const Vec3 d_t = P * q;
        const double cap = opt.friction * out.normalForce;
        // d(P q)/dp = P - (n.q) dn/dp - n d_t^T dn/dp (n^T dn/dp = 0): the projection turns with
        // the normal on a curved shape. Newton gets its last term symmetrised; at d_t = 0 (a
        // node where its anchor was set) that is exact.
        Mat3 ddt, ddtSym;
        if (wantHess) {
            const Mat3 cn = n * (d_t.transpose() * dn);
            ddt = P - n.dot(q) * dn - cn;
            ddtSym = P - n.dot(q) * dn - 0.5 * (cn + cn.transpose());
        }
        // The friction force's dependence on f_n: d(mu f_n)/dp = -mu phi'' n, entering as
        // (dE_t/d cap) (d cap/dp)^T; unsymmetric, so only in the exact tangent.
        const Vec3 dcap = -opt.friction * ddphi * n;
        if (opt.frictionLaw == FrictionLaw::Regularised) {
            const double r = slipLength;
            const double rho = std::sqrt(d_t.squaredNorm() + r * r);
            out.energy += cap * (rho - r);  // the frozen-f_n potential (a convex function of s)
            out.grad += (cap / rho) * d_t;
            if (wantHess) {
                // d(s / rho)/ds = (I - s s^T / rho^2) / rho: stiffness cap r^2 / rho^3 along s.
                const Mat3 W = (Mat3::Identity() - d_t * d_t.transpose() / (rho * rho)) / rho;
                out.hess += cap * 0.5 * (W * ddtSym + (W * ddtSym).transpose());
                if (full) out.full += cap * W * ddt + (d_t / rho) * dcap.transpose();
            }
            return;
        }
        const double r = d_t.norm();
        const double kt = opt.stickStiffnessRatio * nl.k;
        if (kt * r <= cap) {  // stick: an elastic spring to the anchor
            out.energy += 0.5 * kt * r * r;
            out.grad += kt * d_t;
            if (wantHess) out.hess += kt * ddtSym;
            if (full) out.full += kt * ddt;
        } else {  // slip: force mu f_n against the offset; Newton's tangent drops its f_n coupling
            const Vec3 t = d_t / r;
            out.energy += cap * (r - 0.5 * cap / kt);
            out.grad += cap * t;
            if (wantHess) out.hess += (cap / r) * (P - t * t.transpose());
            if (full) {
                const Mat3 W = (Mat3::Identity() - t * t.transpose()) / r;
                out.full += cap * W * ddt + t * dcap.transpose();
            }
        }
    }
};

RigidContact::RigidContact(const Mesh& mesh, std::vector<int> nodes, const RigidShape& shape,
                           const Options& options)
    : m_impl(std::make_shared<Impl>()) {
    options.validate();
    Impl& m = *m_impl;
    m.opt = options;
    m.shape = &shape;
    m.numNodes = mesh.getNumNodes();
    const Eigen::VectorXd A = mesh.calcNodalAreas();
    for (int v : nodes)
        if (v < 0 || v >= m.numNodes)
            throw std::invalid_argument("RigidContact: node " + std::to_string(v) +
                                        " is not in the mesh (0.." +
                                        std::to_string(m.numNodes - 1) + ")");
    m.nodes = std::move(nodes);
    m.area.resize(m.nodes.size());
    for (size_t j = 0; j < m.nodes.size(); ++j) m.area[j] = A[m.nodes[j]];
    m.anchor_S.assign(m.nodes.size(), Vec3::Zero());
    m.hasAnchor.assign(m.nodes.size(), 0);
}

void RigidContact::addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    const Impl& m = *m_impl;
    if (x.cols() != m.numNodes)
        throw std::invalid_argument("RigidContact::addEnergy: x has " + std::to_string(x.cols()) +
                                    " nodes, the mesh " + std::to_string(m.numNodes));
    const int n = static_cast<int>(m.nodes.size());
    const bool wantGrad = acc.wantGradient;
    const bool wantHess = acc.wantHessian;
    auto scatter = [&](int j, const NodeTerm& t) {
        if (!t.active) return;
        const int v = m.nodes[j];
        acc.energy += t.energy;
        if (wantGrad) acc.addGrad(v, t.grad);
        if (wantHess) acc.addHessBlock(v, v, t.hess);
    };
    if (n >= m.opt.minNodesForThreads && omp_get_max_threads() > 1) {
        // Evaluate in parallel into one buffer, then add serially (acc is not thread-safe).
        std::vector<NodeTerm> terms(n);
#pragma omp parallel for schedule(static)
        for (int j = 0; j < n; ++j) m.evalNode(j, x.col(m.nodes[j]), wantHess, terms[j]);
        for (int j = 0; j < n; ++j) scatter(j, terms[j]);
    } else {
        NodeTerm t;
        for (int j = 0; j < n; ++j) {
            m.evalNode(j, x.col(m.nodes[j]), wantHess, t);
            scatter(j, t);
        }
    }
}

bool RigidContact::isConservative() const {
    return m_impl->opt.friction == 0.0 || m_impl->frictionSuppressed;
}

void RigidContact::setFrictionSuppressed(bool on) const { m_impl->frictionSuppressed = on; }

void RigidContact::beginStep(const Eigen::Matrix3Xd& x, double dt) {
    Impl& m = *m_impl;
    if (!(dt >= 0.0) || !std::isfinite(dt))
        throw std::invalid_argument("RigidContact::beginStep: dt must be >= 0 [s], got " +
                                    std::to_string(dt));
    if (m.opt.friction == 0.0 || m.opt.frictionLaw != FrictionLaw::Regularised) return;
    m.slipLength = std::max(m.opt.slipVelocity * dt, kMinSlipLength);
    const Eigen::Isometry3d X_SG = m.shape->getPose().inverse();
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        if (!m.hasAnchor[j]) continue;
        Vec3 c;
        m.shape->calcSignedDistance(x.col(m.nodes[j]), &c, nullptr);
        m.anchor_S[j] = X_SG * c;
    }
}

std::vector<Mat3> RigidContact::calcNodeTangents(const Eigen::Matrix3Xd& x) const {
    const Impl& m = *m_impl;
    std::vector<Mat3> out(m.nodes.size(), Mat3::Zero());
    NodeTerm t;
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        m.evalNode(static_cast<int>(j), x.col(m.nodes[j]), true, t, true);
        if (t.active) out[j] = t.full;
    }
    return out;
}

RigidContact::History RigidContact::getHistory() const {
    return History{m_impl->anchor_S, m_impl->hasAnchor, m_impl->slipLength};
}

void RigidContact::setHistory(const History& h) {
    if (h.anchor_S.size() != m_impl->anchor_S.size() ||
        h.hasAnchor.size() != m_impl->hasAnchor.size())
        throw std::invalid_argument("RigidContact::setHistory: history of another contact set");
    m_impl->anchor_S = h.anchor_S;
    m_impl->hasAnchor = h.hasAnchor;
    m_impl->slipLength = h.slipLength;
}

void RigidContact::commitStep(const Eigen::Matrix3Xd& x) {
    Impl& m = *m_impl;
    if (m.opt.friction == 0.0) return;
    const Eigen::Isometry3d X_SG = m.shape->getPose().inverse();
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        const Vec3 p = x.col(m.nodes[j]);
        double g;
        Vec3 c, n;
        m.shape->calcContactGeometry(p, &g, &c, &n, nullptr);
        double phi, dphi, ddphi;
        if (m.area[j] <= 0.0 || !m.law(static_cast<int>(j)).eval(g, phi, dphi, ddphi)) {
            m.hasAnchor[j] = 0;  // released: the next touch starts a fresh anchor
            continue;
        }
        if (!m.hasAnchor[j]) {
            m.anchor_S[j] = X_SG * c;
            m.hasAnchor[j] = 1;
            continue;
        }
        // Regularised: the anchor stays at the step's start until beginStep().
        if (m.opt.frictionLaw == FrictionLaw::Regularised) continue;
        const Vec3 a_G = m.shape->getPose() * m.anchor_S[j];
        const Vec3 dt = (Mat3::Identity() - n * n.transpose()) * (p - a_G);
        const double r = dt.norm();
        const double kt = m.opt.stickStiffnessRatio * m.opt.pressurePenalty * m.area[j];
        const double cap = -m.opt.friction * dphi;
        if (kt * r > cap) {
            // Slipped: move the anchor so that the stored elastic offset carries the capped force.
            Vec3 aNew = c - (cap / kt) * (dt / r);
            Vec3 aOnSurface;
            m.shape->calcSignedDistance(aNew, &aOnSurface, nullptr);
            m.anchor_S[j] = X_SG * aOnSurface;
        }
    }
}

void RigidContact::calcWrenchOnShape(const Eigen::Matrix3Xd& x, Vec3* force, Vec3* torque) const {
    const Impl& m = *m_impl;
    Vec3 F = Vec3::Zero(), T = Vec3::Zero();
    const Vec3 o = m.shape->getPose().translation();
    NodeTerm t;
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        m.evalNode(static_cast<int>(j), x.col(m.nodes[j]), false, t);
        if (!t.active) continue;
        // The node pushes the shape with -(force on node) = dE/dp, applied at the contact point.
        F += t.grad;
        T += (t.closest - o).cross(t.grad);
    }
    if (force) *force = F;
    if (torque) *torque = T;
}

Eigen::MatrixXd RigidContact::calcWrenchNodeDerivative(const Eigen::Matrix3Xd& x) const {
    const Impl& m = *m_impl;
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(6, 3 * m.numNodes);
    const Vec3 o = m.shape->getPose().translation();
    const double h = 1e-7;  // [m]
    NodeTerm t;
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        const Vec3 p = x.col(m.nodes[j]);
        m.evalNode(static_cast<int>(j), p, false, t);
        if (!t.active) continue;
        for (int k = 0; k < 3; ++k) {
            Eigen::Matrix<double, 6, 1> w[2];
            for (int side = 0; side < 2; ++side) {
                Vec3 q = p;
                q[k] += side == 0 ? h : -h;
                m.evalNode(static_cast<int>(j), q, false, t);
                w[side].setZero();
                if (t.active) w[side] << (t.closest - o).cross(t.grad), t.grad;
            }
            D.col(3 * m.nodes[j] + k) = (w[0] - w[1]) / (2.0 * h);
        }
    }
    return D;
}

Eigen::VectorXd RigidContact::calcNodalPressure(const Eigen::Matrix3Xd& x) const {
    const Impl& m = *m_impl;
    Eigen::VectorXd p = Eigen::VectorXd::Zero(m.numNodes);
    NodeTerm t;
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        m.evalNode(static_cast<int>(j), x.col(m.nodes[j]), false, t);
        if (t.active) p[m.nodes[j]] += t.normalForce / m.area[j];
    }
    return p;
}

int RigidContact::getNumActive(const Eigen::Matrix3Xd& x) const {
    const Impl& m = *m_impl;
    int count = 0;
    NodeTerm t;
    for (size_t j = 0; j < m.nodes.size(); ++j) {
        m.evalNode(static_cast<int>(j), x.col(m.nodes[j]), false, t);
        if (t.active) ++count;
    }
    return count;
}

const std::vector<int>& RigidContact::getNodes() const { return m_impl->nodes; }

const RigidShape& RigidContact::getShape() const { return *m_impl->shape; }

const RigidContact::Options& RigidContact::getOptions() const { return m_impl->opt; }

}  // namespace bags
