#include <bags/Bending.h>

#include <bags/Material.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace bags {

namespace {

using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

Mat3 skew(const Vec3& v) {
    Mat3 s;
    s << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
    return s;
}

}  // namespace

double calcPlateBendingStiffness(double youngsModulus, double poisson, double thickness) {
    if (!(youngsModulus > 0.0) || !(poisson >= 0.0 && poisson < 1.0) || !(thickness > 0.0)) {
        std::ostringstream s;
        s << "calcPlateBendingStiffness: need E > 0, 0 <= nu < 1, t > 0 (got E = " << youngsModulus
          << " Pa, nu = " << poisson << ", t = " << thickness << " m)";
        throw std::invalid_argument(s.str());
    }
    return youngsModulus * thickness * thickness * thickness / (12.0 * (1.0 - poisson * poisson));
}

double calcPlateBendingStiffness(const MembraneMaterial& material, double thickness) {
    return calcPlateBendingStiffness(3.0 * material.getInitialShearModulus(), 0.5, thickness);
}

namespace {

// The hinge angle's derivatives (12: x0, x1, x2, x3) from the edge e = x1 - x0, the wings
// a = x2 - x0 and b = x3 - x0 and the wing normals NA = e x a, NB = b x e; grad and hess may
// each be null.
void calcHingeDerivatives(const Vec3& e, const Vec3& a, const Vec3& b, const Vec3& NA,
                          const Vec3& NB, Vec12* grad, Mat12* hess) {
    // Moving a wing along its normal by dz turns the hinge by -dz / (wing height); the edge
    // nodes take the share that keeps the gradient free of rigid translations and rotations.
    const double L2 = e.squaredNorm(), L = std::sqrt(L2);
    const double NA2 = NA.squaredNorm(), NB2 = NB.squaredNorm();
    const Vec3 uA = NA / NA2, uB = NB / NB2;
    const Vec3 g2 = -L * uA, g3 = -L * uB;
    const double alpha2 = a.dot(e) / L2, alpha3 = b.dot(e) / L2;
    if (grad)
        *grad << -(1.0 - alpha2) * g2 - (1.0 - alpha3) * g3, -alpha2 * g2 - alpha3 * g3, g2, g3;
    if (!hess) return;

    // The Hessian as the Jacobian of the gradient above, one 3x3 block per node (column k:
    // d/dx_k). With s(v) the cross-product matrix, d(NA) = s(e) da - s(a) de and
    // d(NB) = s(b) de - s(e) db; d(N / |N|^2) = P dN with P = (I - 2 n n^T) / |N|^2.
    // Column blocks 1-3 from their formulas, block 0 from translation invariance (each row's
    // column blocks sum to zero).
    const Vec3 nA = NA / std::sqrt(NA2), nB = NB / std::sqrt(NB2);
    const Mat3 PA = (Mat3::Identity() - 2.0 * nA * nA.transpose()) / NA2;
    const Mat3 PB = (Mat3::Identity() - 2.0 * nB * nB.transpose()) / NB2;
    const Mat3 se = skew(e);
    const Mat3 LPAse = L * (PA * se).eval(), LPBse = L * (PB * se).eval();
    // d g2 / dx_k and d g3 / dx_k (g2 = -L uA: dL = e^T de / L).
    Mat3 Jg2[4], Jg3[4];
    Jg2[1] = -(uA / L) * e.transpose() + L * (PA * skew(a)).eval();
    Jg2[2] = -LPAse;
    Jg2[3].setZero();
    Jg3[1] = -(uB / L) * e.transpose() - L * (PB * skew(b)).eval();
    Jg3[2].setZero();
    Jg3[3] = LPBse;
    Jg2[0] = -(Jg2[1] + Jg2[2]);
    Jg3[0] = -(Jg3[1] + Jg3[3]);
    // d alpha2 / dx_k and d alpha3 / dx_k (alpha2 = a.e / L2).
    Vec3 ja2[4], ja3[4];
    ja2[1] = (a - 2.0 * alpha2 * e) / L2;
    ja2[2] = e / L2;
    ja2[3].setZero();
    ja3[1] = (b - 2.0 * alpha3 * e) / L2;
    ja3[2].setZero();
    ja3[3] = e / L2;
    ja2[0] = -(ja2[1] + ja2[2]);
    ja3[0] = -(ja3[1] + ja3[3]);
    Mat12 H;
    for (int k = 0; k < 4; ++k) {
        const Mat3 t = g2 * ja2[k].transpose() + g3 * ja3[k].transpose();
        H.block<3, 3>(0, 3 * k) = t - (1.0 - alpha2) * Jg2[k] - (1.0 - alpha3) * Jg3[k];
        H.block<3, 3>(3, 3 * k) = -t - alpha2 * Jg2[k] - alpha3 * Jg3[k];
        H.block<3, 3>(6, 3 * k) = Jg2[k];
        H.block<3, 3>(9, 3 * k) = Jg3[k];
    }
    *hess = 0.5 * (H + H.transpose());  // symmetric in exact arithmetic; this evens roundoff
}

}  // namespace

double calcHingeAngle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, Vec12* grad,
                      Mat12* hess) {
    const Vec3 e = x1 - x0, a = x2 - x0, b = x3 - x0;
    const Vec3 NA = e.cross(a), NB = b.cross(e);
    const Vec3 nA = NA / std::sqrt(NA.squaredNorm()), nB = NB / std::sqrt(NB.squaredNorm());
    const double theta = std::atan2(nA.cross(nB).dot(e) / std::sqrt(e.squaredNorm()), nA.dot(nB));
    if (grad || hess) calcHingeDerivatives(e, a, b, NA, NB, grad, hess);
    return theta;
}

void BendingOptions::validate() const {
    auto fail = [](const char* name, double v, const char* valid) {
        std::ostringstream s;
        s << "bending option '" << name << "' = " << v << " is invalid; " << valid;
        throw std::invalid_argument(s.str());
    };
    if (!(stiffness >= 0.0 && std::isfinite(stiffness)))
        fail("stiffness", stiffness, "use >= 0 N m (0: no bending)");
    if (!(poisson >= 0.0 && poisson <= 0.5)) fail("poisson", poisson, "use 0 <= nu <= 0.5");
}

DiscreteBending::DiscreteBending(const Mesh& mesh, const BendingOptions& options)
    : m_options(options), m_numNodes(mesh.getNumNodes()) {
    options.validate();
    const int nt = mesh.getNumTris();
    // Edges as (low node, high node, triangle, local edge i = opposite vertex i), sorted: the
    // hinges come out in one fixed order.
    struct EdgeUse {
        int lo, hi, tri, local;
    };
    std::vector<EdgeUse> uses;
    uses.reserve(3 * nt);
    for (int t = 0; t < nt; ++t)
        for (int i = 0; i < 3; ++i) {
            const int p = mesh.tris((i + 1) % 3, t), q = mesh.tris((i + 2) % 3, t);
            uses.push_back({std::min(p, q), std::max(p, q), t, i});
        }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& u, const EdgeUse& v) {
        return std::tie(u.lo, u.hi, u.tri, u.local) < std::tie(v.lo, v.hi, v.tri, v.local);
    });

    // Per triangle: hinge and sign of each edge.
    std::vector<std::array<int, 3>> triHinge(nt, {-1, -1, -1});
    std::vector<std::array<double, 3>> triSign(nt, {0.0, 0.0, 0.0});
    auto addHinge = [&](const EdgeUse& A, const EdgeUse& B) {
        Hinge h;
        const int x0 = mesh.tris((A.local + 1) % 3, A.tri),
                  x1 = mesh.tris((A.local + 2) % 3, A.tri);
        h.nodes = {x0, x1, mesh.tris(A.local, A.tri), mesh.tris(B.local, B.tri)};
        h.restAngle = calcHingeAngle(mesh.X.col(h.nodes[0]), mesh.X.col(h.nodes[1]),
                                     mesh.X.col(h.nodes[2]), mesh.X.col(h.nodes[3]));
        const int id = static_cast<int>(m_hinges.size());
        m_hinges.push_back(h);
        triHinge[A.tri][A.local] = id;
        triSign[A.tri][A.local] = 1.0;
        // B oriented consistently with A runs the edge x1 -> x0; otherwise its normal is the
        // opposite of the hinge's, and so is the curvature it sees.
        const bool consistent = mesh.tris((B.local + 1) % 3, B.tri) == x1;
        triHinge[B.tri][B.local] = id;
        triSign[B.tri][B.local] = consistent ? 1.0 : -1.0;
    };
    for (size_t s = 0; s < uses.size();) {
        size_t f = s;
        while (f < uses.size() && uses[f].lo == uses[s].lo && uses[f].hi == uses[s].hi) ++f;
        const size_t count = f - s;
        if (count == 2) {
            const bool seam = mesh.triPanel[uses[s].tri] != mesh.triPanel[uses[s + 1].tri];
            if (!seam || options.seamsBend) addHinge(uses[s], uses[s + 1]);
        } else if (count > 2) {
            for (size_t i = s; i < f; ++i) {
                const int panel = mesh.triPanel[uses[i].tri];
                std::vector<size_t> same;
                for (size_t j = s; j < f; ++j)
                    if (mesh.triPanel[uses[j].tri] == panel) same.push_back(j);
                if (same.size() == 2 && same[0] == i) addHinge(uses[same[0]], uses[same[1]]);
            }
        }
        s = f;
    }

    // Plates: the constant hinge-angle form of each triangle with a hinge.
    const double D = options.stiffness, nu = options.poisson;
    for (int t = 0; t < nt; ++t) {
        const std::array<int, 3>& hs = triHinge[t];
        if (hs[0] < 0 && hs[1] < 0 && hs[2] < 0) continue;
        Vec3 edge[3];
        for (int i = 0; i < 3; ++i)
            edge[i] = mesh.X.col(mesh.tris((i + 2) % 3, t)) - mesh.X.col(mesh.tris((i + 1) % 3, t));
        const double area = 0.5 * edge[1].cross(edge[2]).norm();
        if (!(area > 0.0))
            throw std::invalid_argument("DiscreteBending: degenerate reference triangle " +
                                        std::to_string(t));
        Plate p;
        p.hinges = hs;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                if (hs[i] < 0 || hs[j] < 0) {
                    p.M(i, j) = 0.0;
                    continue;
                }
                // A D a_i a_j [nu + (1 - nu) (n_i . n_j)^2], a_i = |e_i| / (2 A).
                const double li = edge[i].norm(), lj = edge[j].norm();
                const double c = edge[i].dot(edge[j]) / (li * lj);
                p.M(i, j) = D * li * lj / (4.0 * area) * (nu + (1.0 - nu) * c * c) * triSign[t][i] *
                            triSign[t][j];
            }
        p.numNodes = 0;
        for (int i = 0; i < 3; ++i) {
            p.local[i] = {-1, -1, -1, -1};
            if (hs[i] < 0) continue;
            for (int k = 0; k < 4; ++k) {
                const int n = m_hinges[hs[i]].nodes[k];
                int l = 0;
                while (l < p.numNodes && p.nodes[l] != n) ++l;
                if (l == p.numNodes) p.nodes[p.numNodes++] = n;
                p.local[i][k] = l;
            }
        }
        m_plates.push_back(p);
    }

    // The Hessian's block pattern: every node pair of a plate (a hinge's pairs are among its
    // plates'), sorted, and each plate's slots in it.
    for (const Plate& p : m_plates)
        for (int a = 0; a < p.numNodes; ++a)
            for (int b = 0; b < p.numNodes; ++b) m_blocks.emplace_back(p.nodes[a], p.nodes[b]);
    std::sort(m_blocks.begin(), m_blocks.end());
    m_blocks.erase(std::unique(m_blocks.begin(), m_blocks.end()), m_blocks.end());
    auto findSlot = [&](int a, int b) {
        const auto it = std::lower_bound(m_blocks.begin(), m_blocks.end(), std::make_pair(a, b));
        return static_cast<int>(it - m_blocks.begin());
    };
    for (Plate& p : m_plates) {
        p.slots.fill(-1);
        for (int a = 0; a < p.numNodes; ++a)
            for (int b = 0; b < p.numNodes; ++b)
                p.slots[6 * a + b] = findSlot(p.nodes[a], p.nodes[b]);
    }
    // Each hinge's angle-curvature term goes with its first plate (every hinge has one: the
    // triangles of its edge are plates).
    std::vector<char> owned(m_hinges.size(), 0);
    for (Plate& p : m_plates)
        for (int i = 0; i < 3; ++i) {
            p.ownsHinge[i] = p.hinges[i] >= 0 && !owned[p.hinges[i]];
            if (p.ownsHinge[i]) owned[p.hinges[i]] = 1;
        }
}

double DiscreteBending::calcEnergy(const Eigen::Matrix3Xd& x) const {
    EnergyAccumulator acc;
    acc.wantGradient = acc.wantHessian = false;
    addEnergy(x, acc);
    return acc.energy;
}

void DiscreteBending::addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    addEnergy(x, acc, 1);
}

std::vector<Triplet> DiscreteBending::calcHingeStiffness() const {
    std::vector<Triplet> K;
    for (const Plate& p : m_plates)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (p.hinges[i] >= 0 && p.hinges[j] >= 0)
                    K.emplace_back(p.hinges[i], p.hinges[j], p.M(i, j));
    return K;
}

void DiscreteBending::addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc,
                                int threads) const {
    if (m_options.stiffness == 0.0 || m_hinges.empty()) return;
    const bool wantG = acc.wantGradient, wantH = acc.wantHessian, wantD = wantG || wantH;
    const int nh = getNumHinges();

    // Pass 1, hinges: angle change from rest and its gradient, each hinge on its own (any
    // thread, the same bits); a collapsed wing is recorded, the lowest hinge reported. The
    // scratch is kept per thread from call to call (an explicit step calls this every
    // sub-step).
    thread_local std::vector<double> dtheta, moment;
    thread_local std::vector<Vec12> grad;
    dtheta.resize(nh);
    grad.resize(wantD ? nh : 0);
    int collapsed = nh;
#ifdef _OPENMP
    const int nthreads = threads > 0 ? threads : omp_get_max_threads();
#else
    const int nthreads = 1;
    (void)threads;
#endif
    double* dth = dtheta.data();
    Vec12* gr = grad.data();
#pragma omp parallel for schedule(static) num_threads(nthreads) if (nthreads > 1 && nh > 512) \
    reduction(min                                                                             \
              : collapsed)
    for (int h = 0; h < nh; ++h) {
        const std::array<int, 4>& n = m_hinges[h].nodes;
        const Vec3 x0 = x.col(n[0]), x1 = x.col(n[1]), x2 = x.col(n[2]), x3 = x.col(n[3]);
        const double wingA = (x1 - x0).cross(x2 - x0).squaredNorm();
        const double wingB = (x3 - x0).cross(x1 - x0).squaredNorm();
        if (!(wingA > 0.0 && wingB > 0.0 && std::isfinite(wingA + wingB))) {
            collapsed = std::min(collapsed, h);
            dth[h] = 0.0;
            continue;
        }
        // The change from rest, on the branch nearest to it: a seam with a large rest angle
        // (the gentle side meets the base at 2.5 rad) may fold through +-pi continuously.
        double d = calcHingeAngle(x0, x1, x2, x3, wantD ? &gr[h] : nullptr) - m_hinges[h].restAngle;
        if (d > M_PI) d -= 2.0 * M_PI;
        if (d <= -M_PI) d += 2.0 * M_PI;
        dth[h] = d;
    }
    if (collapsed < nh) {
        acc.energy = std::numeric_limits<double>::infinity();
        if (wantD)
            throw NumericalError("bending hinge " + std::to_string(collapsed) +
                                 " has a collapsed triangle");
        return;
    }

    // Pass 2, plates: energy and the moment dE/dtheta of each hinge.
    double energy = 0.0;
    moment.assign(wantD ? nh : 0, 0.0);
    for (const Plate& p : m_plates) {
        Vec3 d;
        for (int i = 0; i < 3; ++i) d(i) = p.hinges[i] >= 0 ? dtheta[p.hinges[i]] : 0.0;
        const Vec3 Md = p.M * d;
        energy += 0.5 * d.dot(Md);
        if (!wantD) continue;
        for (int i = 0; i < 3; ++i)
            if (p.hinges[i] >= 0) moment[p.hinges[i]] += Md(i);
    }
    acc.energy += energy;
    if (!wantD) return;

    // Pass 3, hinges: forces moment * grad theta.
    if (wantG)
        for (int h = 0; h < nh; ++h)
            for (int k = 0; k < 4; ++k)
                acc.grad.segment<3>(3 * m_hinges[h].nodes[k]) +=
                    moment[h] * grad[h].segment<3>(3 * k);
    if (!wantH) return;

    // Pass 4, plates: the Hessian's Gauss-Newton part sum_ij M_ij grad_i grad_j^T and, for the
    // hinges the plate owns, the angle-curvature part moment * d2theta, gathered on the plate's
    // nodes before they go to the node-pair blocks.
    std::vector<Mat3> blocks(m_blocks.size(), Mat3::Zero());
    for (const Plate& p : m_plates) {
        Eigen::Matrix<double, 3, 18> G = Eigen::Matrix<double, 3, 18>::Zero();
        for (int i = 0; i < 3; ++i) {
            if (p.hinges[i] < 0) continue;
            const Vec12& g = grad[p.hinges[i]];
            for (int k = 0; k < 4; ++k) G.block<1, 3>(i, 3 * p.local[i][k]) += g.segment<3>(3 * k);
        }
        // K = G^T M G node block by node block (K_ab = G_a^T (M G)_b; K_ba = K_ab^T).
        const Eigen::Matrix<double, 3, 18> MG = p.M.lazyProduct(G);
        Mat3 K[36];
        for (int a = 0; a < p.numNodes; ++a)
            for (int b = a; b < p.numNodes; ++b) {
                K[6 * a + b] =
                    G.middleCols<3>(3 * a).transpose().lazyProduct(MG.middleCols<3>(3 * b));
                if (b != a) K[6 * b + a] = K[6 * a + b].transpose();
            }
        for (int i = 0; i < 3; ++i) {
            if (!p.ownsHinge[i]) continue;
            const int h = p.hinges[i];
            const std::array<int, 4>& n = m_hinges[h].nodes;
            const Vec3 x0 = x.col(n[0]);
            const Vec3 e = x.col(n[1]) - x0, a = x.col(n[2]) - x0, b = x.col(n[3]) - x0;
            Mat12 H;
            calcHingeDerivatives(e, a, b, e.cross(a), b.cross(e), nullptr, &H);
            for (int k = 0; k < 4; ++k)
                for (int l = 0; l < 4; ++l)
                    K[6 * p.local[i][k] + p.local[i][l]] += moment[h] * H.block<3, 3>(3 * k, 3 * l);
        }
        for (int a = 0; a < p.numNodes; ++a)
            for (int b = 0; b < p.numNodes; ++b) blocks[p.slots[6 * a + b]] += K[6 * a + b];
    }
    // Every entry of every block, zeros too: the same triplet sequence every call.
    acc.hess.reserve(acc.hess.size() + 9 * m_blocks.size());
    for (size_t s = 0; s < m_blocks.size(); ++s) {
        const int a = m_blocks[s].first, b = m_blocks[s].second;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                acc.hess.emplace_back(3 * a + i, 3 * b + j, blocks[s](i, j));
    }
}

}  // namespace bags
