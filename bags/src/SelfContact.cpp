// Self contact of a membrane: node-to-triangle penalty with a thickness offset.
//
// Pairs: a node v and a triangle T that contains neither v nor a neighbour of v. Distance d_T:
//   - projection of v inside T ("interior"): d = D = s * (v - x0) . n_T, the plane distance
//     signed by the side s the node was on when the pair was found (so a node pushed through
//     the sheet within a step is pushed back, not further through);
//   - otherwise r = |v - q|, the distance to the closest point q on an edge or vertex of T, if
//     D >= 0; behind the sheet (D < 0) d = r + 2 D^3 / r^2, which equals D where q reaches the
//     triangle's boundary (r = -D) and r on the plane D = 0, with matching gradients: d is C1
//     over the whole space (C2 across D = 0), not only on the node's own side.
// The facets a node sees on one side of its own surface form a group; the group's distance
// is the softmax-weighted mean
//     d_w = sum_i w_i d_i,   w_i = exp(-beta d_i) / sum_j exp(-beta d_j),  beta = sharpness / h,
// a smooth stand-in for min_i d_i (a hard min makes the energy kinked where the nearest facet
// changes, and Newton stalls there). d_w = LSE-min + entropy / beta: the log-sum-exp soft-min
// -(1/beta) log sum exp(-beta d_i) alone is biased low by (log n) / beta for n equidistant
// facets (a node over a shared vertex of 6 facets of a flat sheet: 0.09 h at sharpness 20),
// the entropy term removes that bias exactly, so a node over a shared edge or vertex of a
// flat sheet sees the true distance (not double counted). min d_i <= d_w, and for two facets
// d_w - min d_i <= 0.28 / beta (0.014 h at sharpness 20).
// Energy 0.5 k (h - d_w)^2 for d_w < h with k = pressurePenalty * A_v / 2: every pair of sheets
// is seen twice (nodes of A against triangles of B and the reverse), so two parallel sheets at
// gap g < h press on each other with pressurePenalty * (h - g), the same law as rigid contact.
// Facets with beta (d_i - min d) > 40 (weight < 4e-18) are dropped from the sums.

#include <bags/Contact.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace bags {

namespace {

using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

inline Mat3 skew(const Vec3& a) {
    Mat3 S;
    S << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
    return S;
}

/// Where the closest point of a triangle to p lies.
enum class Region { Interior, Vertex0, Vertex1, Vertex2, Edge01, Edge12, Edge20 };

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5).
Region closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& q) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        q = a;
        return Region::Vertex0;
    }
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) {
        q = b;
        return Region::Vertex1;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        q = a + d1 / (d1 - d3) * ab;
        return Region::Edge01;
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) {
        q = c;
        return Region::Vertex2;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        q = a + d2 / (d2 - d6) * ac;
        return Region::Edge20;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        q = b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
        return Region::Edge12;
    }
    const double denom = 1.0 / (va + vb + vc);
    q = a + ab * (vb * denom) + ac * (vc * denom);
    return Region::Interior;
}

/// Plane distance D = (p - x0) . n / |n|, n = (x1 - x0) x (x2 - x0), with its exact gradient and
/// Hessian w.r.t. (p, x0, x1, x2). Derived in (r, e1, e2) = (p - x0, x1 - x0, x2 - x0).
void planeDistanceDerivatives(const Vec3& p, const Vec3& x0, const Vec3& x1, const Vec3& x2,
                              Vec12& g, Mat12& H) {
    const Vec3 r = p - x0, e1 = x1 - x0, e2 = x2 - x0;
    const Vec3 nv = e1.cross(e2);
    const double l = nv.norm();
    const Vec3 n = nv / l;
    const double D = r.dot(n);
    const Mat3 P = Mat3::Identity() - n * n.transpose();
    const Vec3 rt = P * r;
    // Hessian of f(n) = r.n/|n| w.r.t. the unnormalised normal.
    const Mat3 F = (-(n * rt.transpose() + rt * n.transpose()) - D * P) / (l * l);
    const Mat3 S1 = skew(e1), S2 = skew(e2);
    Eigen::Matrix<double, 9, 1> g9;
    g9 << n, e2.cross(rt) / l, rt.cross(e1) / l;
    Eigen::Matrix<double, 9, 9> H9 = Eigen::Matrix<double, 9, 9>::Zero();
    const Mat3 Hr1 = -P * S2 / l, Hr2 = P * S1 / l;
    const Mat3 H11 = S2.transpose() * F * S2;
    const Mat3 H22 = S1.transpose() * F * S1;
    const Mat3 H12 = S2 * F * S1 - skew(rt / l);
    H9.block<3, 3>(0, 3) = Hr1;
    H9.block<3, 3>(3, 0) = Hr1.transpose();
    H9.block<3, 3>(0, 6) = Hr2;
    H9.block<3, 3>(6, 0) = Hr2.transpose();
    H9.block<3, 3>(3, 3) = H11;
    H9.block<3, 3>(6, 6) = H22;
    H9.block<3, 3>(3, 6) = H12;
    H9.block<3, 3>(6, 3) = H12.transpose();
    // (r, e1, e2) = J (p, x0, x1, x2)
    Eigen::Matrix<double, 9, 12> J = Eigen::Matrix<double, 9, 12>::Zero();
    const Mat3 I = Mat3::Identity();
    J.block<3, 3>(0, 0) = I;
    J.block<3, 3>(0, 3) = -I;
    J.block<3, 3>(3, 3) = -I;
    J.block<3, 3>(3, 6) = I;
    J.block<3, 3>(6, 3) = -I;
    J.block<3, 3>(6, 9) = I;
    g = J.transpose() * g9;
    H = J.transpose() * H9 * J;
}

/// Distance |p - (a + t (b - a))| to a segment at its interior closest point, with gradient and
/// Hessian w.r.t. (p, a, b) (t eliminated: H = B^T B - m m^T / |e|^2 for Phi = |w|^2 / 2).
void segmentDistanceDerivatives(const Vec3& p, const Vec3& a, const Vec3& b,
                                Eigen::Matrix<double, 9, 1>& g, Eigen::Matrix<double, 9, 9>& H,
                                double& d) {
    const Vec3 e = b - a;
    const double ee = e.squaredNorm();
    const double t = (p - a).dot(e) / ee;
    const Vec3 w = p - a - t * e;
    d = w.norm();
    const Eigen::Vector3d coef(1.0, -(1.0 - t), -t);
    Eigen::Matrix<double, 9, 1> gPhi, m;
    gPhi << w, -(1.0 - t) * w, -t * w;
    m << -e, w + (1.0 - t) * e, -w + t * e;
    Eigen::Matrix<double, 9, 9> HPhi;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            HPhi.block<3, 3>(3 * i, 3 * j) = coef[i] * coef[j] * Mat3::Identity();
    HPhi -= m * m.transpose() / ee;
    g = gPhi / d;
    H = HPhi / d - gPhi * gPhi.transpose() / (d * d * d);
}

/// Contact distance of node p to triangle (x0, x1, x2) for a pair on side `side` (see the top
/// of the file) and, if g is given, its gradient and Hessian w.r.t. (p, x0, x1, x2). A node on
/// an edge or vertex itself (r = 0, derivative undefined) gets zero derivatives.
double facetDistance(const Vec3& p, const Vec3& x0, const Vec3& x1, const Vec3& x2, int side,
                     Vec12* g, Mat12* H) {
    Vec3 q;
    const Region region = closestPointOnTriangle(p, x0, x1, x2, q);
    const Vec3 nv = (x1 - x0).cross(x2 - x0);
    const double D = side * (p - x0).dot(nv) / nv.norm();
    if (region == Region::Interior) {
        if (g) {
            planeDistanceDerivatives(p, x0, x1, x2, *g, *H);
            *g *= side;
            *H *= side;
        }
        return D;
    }
    const double r = (p - q).norm();
    const bool behind = D < 0.0 && r > 0.0;
    const double d = behind ? r + 2.0 * D * D * D / (r * r) : r;
    if (!g) return d;
    g->setZero();
    H->setZero();
    const double scale = (x1 - x0).norm() + (x2 - x0).norm();
    if (!(r > 1e-14 * scale)) return d;
    int a = -1, b = -1;
    switch (region) {
        case Region::Vertex0:
            a = 0;
            break;
        case Region::Vertex1:
            a = 1;
            break;
        case Region::Vertex2:
            a = 2;
            break;
        case Region::Edge01:
            a = 0;
            b = 1;
            break;
        case Region::Edge12:
            a = 1;
            b = 2;
            break;
        case Region::Edge20:
            a = 2;
            b = 0;
            break;
        default:
            break;
    }
    const Vec3 xs[3] = {x0, x1, x2};
    if (b < 0) {
        const Vec3 u = (p - xs[a]) / r;
        const Mat3 Hu = (Mat3::Identity() - u * u.transpose()) / r;
        g->segment<3>(0) = u;
        g->segment<3>(3 * (1 + a)) = -u;
        H->block<3, 3>(0, 0) = Hu;
        H->block<3, 3>(3 * (1 + a), 3 * (1 + a)) = Hu;
        H->block<3, 3>(0, 3 * (1 + a)) = -Hu;
        H->block<3, 3>(3 * (1 + a), 0) = -Hu;
    } else {
        Eigen::Matrix<double, 9, 1> g9;
        Eigen::Matrix<double, 9, 9> H9;
        double dd;
        segmentDistanceDerivatives(p, xs[a], xs[b], g9, H9, dd);
        const int slot[3] = {0, 1 + a, 1 + b};
        for (int i = 0; i < 3; ++i) {
            g->segment<3>(3 * slot[i]) = g9.segment<3>(3 * i);
            for (int j = 0; j < 3; ++j)
                H->block<3, 3>(3 * slot[i], 3 * slot[j]) = H9.block<3, 3>(3 * i, 3 * j);
        }
    }
    if (behind) {
        // d = f(D, r) = r + 2 D^3 / r^2 with u = D / r: chain rule through D and r.
        Vec12 gD;
        Mat12 HD;
        planeDistanceDerivatives(p, x0, x1, x2, gD, HD);
        gD *= side;
        HD *= side;
        const double u = D / r;
        const double fD = 6.0 * u * u, fr = 1.0 - 4.0 * u * u * u;
        const double fDD = 12.0 * u / r, fDr = -12.0 * u * u / r, frr = 12.0 * u * u * u / r;
        const Vec12 gr = *g;
        *H = fr * *H + fD * HD + fDD * gD * gD.transpose() +
             fDr * (gD * gr.transpose() + gr * gD.transpose()) + frr * gr * gr.transpose();
        *g = fr * gr + fD * gD;
    }
    return d;
}

/// One facet of a (node, side) group with its distance and softmax weight.
struct Term {
    int cand;
    double d;
    double w;
};

struct Candidate {
    int node;
    int tri;
    signed char side;   // side of the triangle plane the node was on when found
    signed char group;  // which side of the node's own surface the triangle lies on
};

inline std::uint64_t cellHash(std::int64_t i, std::int64_t j, std::int64_t k) {
    return static_cast<std::uint64_t>(i) * 73856093ULL ^
           static_cast<std::uint64_t>(j) * 19349663ULL ^
           static_cast<std::uint64_t>(k) * 83492791ULL;
}

}  // namespace

void SelfContact::Options::validate() const {
    if (!(pressurePenalty > 0.0) || !std::isfinite(pressurePenalty))
        throw std::invalid_argument("SelfContact option pressurePenalty must be > 0 [Pa/m], got " +
                                    std::to_string(pressurePenalty));
    if (!(thickness > 0.0) || !std::isfinite(thickness))
        throw std::invalid_argument("SelfContact option thickness must be > 0 [m], got " +
                                    std::to_string(thickness));
    if (!(candidateMargin >= 0.0) || !std::isfinite(candidateMargin))
        throw std::invalid_argument("SelfContact option candidateMargin must be >= 0 [m], got " +
                                    std::to_string(candidateMargin));
    if (!(softMinSharpness > 0.0) || !std::isfinite(softMinSharpness))
        throw std::invalid_argument(
            "SelfContact option softMinSharpness must be finite and > 0 (beta * thickness; "
            "20 is the default), got " +
            std::to_string(softMinSharpness));
}

struct SelfContact::Impl {
    Options opt;
    int numNodes = 0;
    Eigen::Matrix3Xi tris;
    std::vector<double> k;           // penalty stiffness per node [N/m]
    std::vector<int> nbrStart, nbr;  // node neighbours (CSR)
    std::vector<Candidate> cands;    // sorted by (node, group, tri)
    Eigen::Matrix3Xd xUpdate;        // positions at the last updateCandidates()
    bool updated = false;

    size_t maxGroup = 0;  // longest (node, group) run of cands

    /// Calls f(begin, end) for each (node, group) run [begin, end) of cands.
    template <class F>
    void forEachGroup(F&& f) const {
        size_t i = 0;
        while (i < cands.size()) {
            size_t j = i + 1;
            while (j < cands.size() && cands[j].node == cands[i].node &&
                   cands[j].group == cands[i].group)
                ++j;
            f(i, j);
            i = j;
        }
    }

    /// Soft-min distance d_w of the run [i, j) at x (see the top of the file). Writes the
    /// facets that keep a weight into terms (capacity >= j - i), their count into n. Returns
    /// +infinity (n = 0) when no facet is nearer than the thickness, so d_w >= h anyway.
    double calcGroupDistance(const Eigen::Matrix3Xd& x, size_t i, size_t j, Term* terms,
                             int& n) const {
        const double h = opt.thickness, beta = opt.softMinSharpness / h;
        const Vec3 p = x.col(cands[i].node);
        double dMin = std::numeric_limits<double>::infinity();
        n = 0;
        for (size_t c = i; c < j; ++c) {
            const int t = cands[c].tri;
            const double d = facetDistance(p, x.col(tris(0, t)), x.col(tris(1, t)),
                                           x.col(tris(2, t)), cands[c].side, nullptr, nullptr);
            terms[n++] = Term{static_cast<int>(c), d, 0.0};
            dMin = std::min(dMin, d);
        }
        n = 0;
        if (!(dMin < h)) return std::numeric_limits<double>::infinity();
        double sumW = 0.0;
        const int total = static_cast<int>(j - i);
        for (int c = 0; c < total; ++c) {
            const double e = beta * (terms[c].d - dMin);  // >= 0: max-shift, no overflow
            if (e > kWeightCut) continue;
            terms[n] = terms[c];
            terms[n].w = std::exp(-e);
            sumW += terms[n].w;
            ++n;
        }
        double dw = 0.0;
        for (int c = 0; c < n; ++c) {
            terms[c].w /= sumW;
            dw += terms[c].w * terms[c].d;
        }
        return dw;
    }
    static constexpr double kWeightCut = 40.0;  // drop facets with weight < exp(-40)
};

SelfContact::SelfContact(const Mesh& mesh, const Options& options)
    : m_impl(std::make_shared<Impl>()) {
    options.validate();
    Impl& m = *m_impl;
    m.opt = options;
    m.numNodes = mesh.getNumNodes();
    m.tris = mesh.tris;
    const int nt = mesh.getNumTris();
    for (int t = 0; t < nt; ++t)
        for (int a = 0; a < 3; ++a)
            if (m.tris(a, t) < 0 || m.tris(a, t) >= m.numNodes)
                throw std::invalid_argument("SelfContact: triangle " + std::to_string(t) +
                                            " has node " + std::to_string(m.tris(a, t)) +
                                            " outside the mesh");
    const Eigen::VectorXd area = mesh.calcNodalAreas();
    m.k.resize(m.numNodes);
    for (int v = 0; v < m.numNodes; ++v) m.k[v] = 0.5 * options.pressurePenalty * area[v];
    const std::vector<std::vector<int>> nb = mesh.calcNodeNeighbours();
    m.nbrStart.assign(1, 0);
    for (int v = 0; v < m.numNodes; ++v) {
        m.nbr.insert(m.nbr.end(), nb[v].begin(), nb[v].end());
        m.nbrStart.push_back(static_cast<int>(m.nbr.size()));
    }
}

void SelfContact::updateCandidates(const Eigen::Matrix3Xd& x) {
    Impl& m = *m_impl;
    if (x.cols() != m.numNodes)
        throw std::invalid_argument("SelfContact::updateCandidates: x has " +
                                    std::to_string(x.cols()) + " nodes, the mesh " +
                                    std::to_string(m.numNodes));
    const int nt = static_cast<int>(m.tris.cols());
    const double reach = m.opt.thickness + m.opt.candidateMargin;
    // Keep the side of pairs that persist, so a node that went through a sheet in the last step
    // is still pushed back to where it came from.
    std::vector<Candidate> old = std::move(m.cands);
    std::sort(old.begin(), old.end(), [](const Candidate& a, const Candidate& b) {
        return a.node != b.node ? a.node < b.node : a.tri < b.tri;
    });
    m.cands.clear();

    // Expanded triangle AABBs and the cell size.
    std::vector<Eigen::Array3d> lo(nt), hi(nt);
    double meanExtent = 0.0;
    for (int t = 0; t < nt; ++t) {
        const Vec3 a = x.col(m.tris(0, t)), b = x.col(m.tris(1, t)), c = x.col(m.tris(2, t));
        lo[t] = a.array().min(b.array()).min(c.array()) - reach;
        hi[t] = a.array().max(b.array()).max(c.array()) + reach;
        meanExtent += (hi[t] - lo[t]).maxCoeff();
    }
    if (nt == 0) {
        m.xUpdate = x;
        m.updated = true;
        return;
    }
    meanExtent /= nt;
    const double cell = std::max(meanExtent, 1e-9);
    auto cellOf = [&](double v) { return static_cast<std::int64_t>(std::floor(v / cell)); };

    // Spatial hash (Teschner et al. 2003): bucket -> triangles whose box overlaps a cell there.
    size_t tableSize = 1024;
    while (tableSize < 2 * static_cast<size_t>(nt)) tableSize *= 2;
    std::vector<int> count(tableSize + 1, 0);
    auto forCells = [&](int t, auto&& f) {
        for (std::int64_t i = cellOf(lo[t][0]); i <= cellOf(hi[t][0]); ++i)
            for (std::int64_t j = cellOf(lo[t][1]); j <= cellOf(hi[t][1]); ++j)
                for (std::int64_t kk = cellOf(lo[t][2]); kk <= cellOf(hi[t][2]); ++kk)
                    f(cellHash(i, j, kk) & (tableSize - 1));
    };
    for (int t = 0; t < nt; ++t) forCells(t, [&](std::uint64_t b) { ++count[b + 1]; });
    for (size_t b = 0; b < tableSize; ++b) count[b + 1] += count[b];
    std::vector<int> entries(count[tableSize]);
    std::vector<int> fill(count.begin(), count.end() - 1);
    for (int t = 0; t < nt; ++t) forCells(t, [&](std::uint64_t b) { entries[fill[b]++] = t; });

    // Vertex normals (area weighted) decide on which side of its own sheet a triangle lies.
    Eigen::Matrix3Xd vn = Eigen::Matrix3Xd::Zero(3, m.numNodes);
    for (int t = 0; t < nt; ++t) {
        const Vec3 n = (x.col(m.tris(1, t)) - x.col(m.tris(0, t)))
                           .cross(x.col(m.tris(2, t)) - x.col(m.tris(0, t)));
        for (int a = 0; a < 3; ++a) vn.col(m.tris(a, t)) += n;
    }

    std::vector<int> seen(nt, -1), nbrMark(m.numNodes, -1);
    for (int v = 0; v < m.numNodes; ++v) {
        if (m.k[v] <= 0.0) continue;
        const Vec3 p = x.col(v);
        for (int q = m.nbrStart[v]; q < m.nbrStart[v + 1]; ++q) nbrMark[m.nbr[q]] = v;
        nbrMark[v] = v;
        const std::uint64_t b =
            cellHash(cellOf(p.x()), cellOf(p.y()), cellOf(p.z())) & (tableSize - 1);
        const size_t first = m.cands.size();
        for (int e = count[b]; e < count[b + 1]; ++e) {
            const int t = entries[e];
            if (seen[t] == v) continue;
            seen[t] = v;
            if ((p.array() < lo[t]).any() || (p.array() > hi[t]).any()) continue;
            const int i0 = m.tris(0, t), i1 = m.tris(1, t), i2 = m.tris(2, t);
            if (nbrMark[i0] == v || nbrMark[i1] == v || nbrMark[i2] == v) continue;
            Vec3 q;
            const Vec3 x0 = x.col(i0), x1 = x.col(i1), x2 = x.col(i2);
            closestPointOnTriangle(p, x0, x1, x2, q);
            if ((p - q).norm() >= reach) continue;
            Candidate c;
            c.node = v;
            c.tri = t;
            const auto it = std::lower_bound(
                old.begin(), old.end(), std::make_pair(v, t),
                [](const Candidate& a, const std::pair<int, int>& key) {
                    return a.node != key.first ? a.node < key.first : a.tri < key.second;
                });
            if (it != old.end() && it->node == v && it->tri == t)
                c.side = it->side;
            else
                c.side = (p - x0).dot((x1 - x0).cross(x2 - x0)) < 0.0 ? -1 : 1;
            c.group = (q - p).dot(vn.col(v)) < 0.0 ? 0 : 1;
            m.cands.push_back(c);
        }
        std::sort(m.cands.begin() + first, m.cands.end(),
                  [](const Candidate& a, const Candidate& b) {
                      return a.group != b.group ? a.group < b.group : a.tri < b.tri;
                  });
    }
    m.maxGroup = 0;
    m.forEachGroup([&](size_t i, size_t j) { m.maxGroup = std::max(m.maxGroup, j - i); });
    m.xUpdate = x;
    m.updated = true;
}

void SelfContact::addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    const Impl& m = *m_impl;
    if (x.cols() != m.numNodes)
        throw std::invalid_argument("SelfContact::addEnergy: x has " + std::to_string(x.cols()) +
                                    " nodes, the mesh " + std::to_string(m.numNodes));
    const double h = m.opt.thickness, beta = m.opt.softMinSharpness / h;
    const bool derivs = acc.wantGradient || acc.wantHessian;
    // Scratch sized once per call to the largest group (no allocation per node): the group's
    // facets, its distinct nodes, the vectors u, v below and the group's dense Hessian.
    const int maxGroup = static_cast<int>(m.maxGroup);
    const int maxLocal = 1 + 3 * maxGroup;
    std::vector<Term> terms(m.maxGroup);
    std::vector<int> local(derivs ? maxLocal : 0);
    std::vector<double> cw(derivs ? maxGroup : 0);
    Eigen::MatrixXd Hloc;
    Eigen::VectorXd u, v;
    if (acc.wantHessian) {
        Hloc.resize(3 * maxLocal, 3 * maxLocal);
        u.resize(3 * maxLocal);
        v.resize(3 * maxLocal);
    }
    Vec12 gd;
    Mat12 Hd;
    m.forEachGroup([&](size_t i, size_t j) {
        int n = 0;
        const double dw = m.calcGroupDistance(x, i, j, terms.data(), n);
        if (!(dw < h)) return;
        const int node = m.cands[i].node;
        const double k = m.k[node];
        const double gap = h - dw;
        acc.energy += 0.5 * k * gap * gap;
        if (!derivs) return;
        // d_w = sum w_i d_i: grad = G = sum c_i g_i with c_i = w_i (1 - beta (d_i - d_w));
        // Hessian = sum c_i H_i - beta [sum a_i g_i g_i^T - G gbar^T - gbar G^T] with
        // a_i = w_i (2 - beta (d_i - d_w)), gbar = sum w_i g_i.
        // E = k (h - d_w)^2 / 2: dE = -k gap G; d2E = k G G^T - k gap d2(d_w), i.e.
        // d2E = sum_i (-k gap c_i) H_i + sum_ij M_ij g_i g_j^T with
        // M_ij = k c_i c_j + k gap beta (delta_ij a_i - c_i w_j - w_i c_j), assembled as
        // k u u^T - k gap beta (u v^T + v u^T) + sum_i k gap beta a_i g_i g_i^T with
        // u = G = sum c_i g_i, v = gbar = sum w_i g_i over the group's distinct nodes.
        const Vec3 p = x.col(node);
        int numLocal = 1;
        local[0] = node;
        for (int a = 0; a < n; ++a) {  // the group's distinct nodes
            const int tri = m.cands[terms[a].cand].tri;
            for (int q = 0; q < 3; ++q) {
                int l = 0;
                while (l < numLocal && local[l] != m.tris(q, tri)) ++l;
                if (l == numLocal) local[numLocal++] = m.tris(q, tri);
            }
        }
        if (acc.wantHessian) {
            Hloc.topLeftCorner(3 * numLocal, 3 * numLocal).setZero();
            u.head(3 * numLocal).setZero();
            v.head(3 * numLocal).setZero();
        }
        for (int a = 0; a < n; ++a) {
            const Candidate& c = m.cands[terms[a].cand];
            int ids[4] = {node, m.tris(0, c.tri), m.tris(1, c.tri), m.tris(2, c.tri)};
            int slot[4] = {0, 0, 0, 0};
            for (int q = 1; q < 4; ++q)
                while (local[slot[q]] != ids[q]) ++slot[q];
            facetDistance(p, x.col(ids[1]), x.col(ids[2]), x.col(ids[3]), c.side, &gd, &Hd);
            const double delta = terms[a].d - dw;
            cw[a] = terms[a].w * (1.0 - beta * delta);
            if (acc.wantGradient)
                for (int q = 0; q < 4; ++q)
                    acc.addGrad(ids[q], -k * gap * cw[a] * gd.segment<3>(3 * q));
            if (acc.wantHessian) {
                const double aa = terms[a].w * (2.0 - beta * delta);
                const Mat12 Hf = k * gap * (beta * aa * gd * gd.transpose() - cw[a] * Hd);
                for (int q = 0; q < 4; ++q) {
                    u.segment<3>(3 * slot[q]) += cw[a] * gd.segment<3>(3 * q);
                    v.segment<3>(3 * slot[q]) += terms[a].w * gd.segment<3>(3 * q);
                    for (int r = 0; r < 4; ++r)
                        Hloc.block<3, 3>(3 * slot[q], 3 * slot[r]) += Hf.block<3, 3>(3 * q, 3 * r);
                }
            }
        }
        if (!acc.wantHessian) return;
        const int dim = 3 * numLocal;
        const auto uu = u.head(dim), vv = v.head(dim);
        Hloc.topLeftCorner(dim, dim).noalias() +=
            k * uu * uu.transpose() - k * gap * beta * (uu * vv.transpose() + vv * uu.transpose());
        for (int q = 0; q < numLocal; ++q)
            for (int r = 0; r < numLocal; ++r)
                acc.addHessBlock(local[q], local[r], Hloc.block<3, 3>(3 * q, 3 * r));
    });
}

int SelfContact::getNumActive(const Eigen::Matrix3Xd& x) const {
    const Impl& m = *m_impl;
    std::vector<Term> terms(m.maxGroup);
    int count = 0;
    int lastNode = -1;
    m.forEachGroup([&](size_t i, size_t j) {
        int n = 0;
        if (!(m.calcGroupDistance(x, i, j, terms.data(), n) < m.opt.thickness)) return;
        if (m.cands[i].node != lastNode) ++count;
        lastNode = m.cands[i].node;
    });
    return count;
}

bool SelfContact::isCandidateListValid(const Eigen::Matrix3Xd& x) const {
    const Impl& m = *m_impl;
    if (!m.updated || x.cols() != m.xUpdate.cols()) return false;
    if (x.cols() == 0) return true;
    const double lim = 0.5 * m.opt.candidateMargin;
    return (x - m.xUpdate).colwise().squaredNorm().maxCoeff() <= lim * lim;
}

std::vector<std::pair<int, int>> SelfContact::getCandidatePairs() const {
    std::vector<std::pair<int, int>> out;
    out.reserve(m_impl->cands.size());
    for (const Candidate& c : m_impl->cands) out.emplace_back(c.node, c.tri);
    std::sort(out.begin(), out.end());
    return out;
}

void SelfContact::saveState(StateWriter& w) const {
    const Impl& m = *m_impl;
    w.tag("self contact");
    w.pod(m.numNodes);
    w.pod(std::uint64_t(m.cands.size()));
    for (const Candidate& c : m.cands) w.pod(c.node), w.pod(c.tri), w.pod(c.side), w.pod(c.group);
    w.mat(m.xUpdate);
    w.pod(m.updated);
}

void SelfContact::loadState(StateReader& r) {
    Impl& m = *m_impl;
    r.tag("self contact");
    const int n = r.pod<int>();
    if (n != m.numNodes) StateReader::mismatch("nodes of the self-contact mesh", n, m.numNodes);
    m.cands.resize(r.pod<std::uint64_t>());
    const int nt = static_cast<int>(m.tris.cols());
    for (Candidate& c : m.cands) {
        r.pod(c.node), r.pod(c.tri), r.pod(c.side), r.pod(c.group);
        if (c.node < 0 || c.node >= m.numNodes || c.tri < 0 || c.tri >= nt)
            throw StateError("checkpoint: a self-contact pair outside the mesh");
    }
    r.mat(m.xUpdate);
    r.pod(m.updated);
    m.maxGroup = 0;
    m.forEachGroup([&](size_t i, size_t j) { m.maxGroup = std::max(m.maxGroup, j - i); });
}

}  // namespace bags
