/// @file Mesh areas, validation, quality statistics and chamber volumes with their derivatives.

#include <bags/Mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace bags {

namespace {

Vec3 nodeOf(const Eigen::Matrix3Xd& x, int n) { return x.col(n); }

double triArea(const Eigen::Matrix3Xd& x, int a, int b, int c) {
    return 0.5 * (nodeOf(x, b) - nodeOf(x, a)).cross(nodeOf(x, c) - nodeOf(x, a)).norm();
}

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument("Mesh: " + msg); }

/// Key of the undirected edge {a, b}.
std::uint64_t edgeKey(int a, int b) {
    const auto lo = static_cast<std::uint64_t>(std::min(a, b));
    const auto hi = static_cast<std::uint64_t>(std::max(a, b));
    return (lo << 32) | hi;
}

/// Appends the nine entries of scale * s * [v]_x at block (a, b), where [v]_x y = v x y.
/// Only the six off-diagonal entries are nonzero.
inline void pushSkew(std::vector<Triplet>& h, int a, int b, const Vec3& v, double f) {
    const int r = 3 * a, c = 3 * b;
    // [v]_x = [[0, -v2, v1], [v2, 0, -v0], [-v1, v0, 0]]
    h.emplace_back(r + 0, c + 1, -f * v[2]);
    h.emplace_back(r + 0, c + 2, f * v[1]);
    h.emplace_back(r + 1, c + 0, f * v[2]);
    h.emplace_back(r + 1, c + 2, -f * v[0]);
    h.emplace_back(r + 2, c + 0, -f * v[1]);
    h.emplace_back(r + 2, c + 1, f * v[0]);
}

void checkChamberIndex(const Mesh& mesh, int c) {
    if (c < 0 || c >= static_cast<int>(mesh.chambers.size()))
        throw std::out_of_range("calcChamberVolume: chamber index " + std::to_string(c) +
                                " is not in [0, " + std::to_string(mesh.chambers.size()) + ")");
}

}  // namespace

std::vector<std::vector<int>> Mesh::calcNodeNeighbours() const {
    std::vector<std::vector<int>> nb(getNumNodes());
    for (int t = 0; t < getNumTris(); ++t)
        for (int a = 0; a < 3; ++a) {
            nb[tris(a, t)].push_back(tris((a + 1) % 3, t));
            nb[tris(a, t)].push_back(tris((a + 2) % 3, t));
        }
    for (std::vector<int>& n : nb) {
        std::sort(n.begin(), n.end());
        n.erase(std::unique(n.begin(), n.end()), n.end());
    }
    return nb;
}

Eigen::VectorXd Mesh::calcTriangleAreas() const {
    Eigen::VectorXd a(getNumTris());
    for (int t = 0; t < getNumTris(); ++t) a[t] = triArea(X, tris(0, t), tris(1, t), tris(2, t));
    return a;
}

Eigen::VectorXd Mesh::calcNodalAreas() const {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(getNumNodes());
    for (int t = 0; t < getNumTris(); ++t) {
        const double at = triArea(X, tris(0, t), tris(1, t), tris(2, t)) / 3.0;
        for (int k = 0; k < 3; ++k) a[tris(k, t)] += at;
    }
    return a;
}

int Mesh::findPanel(const std::string& name) const {
    for (size_t i = 0; i < panelNames.size(); ++i)
        if (panelNames[i] == name) return static_cast<int>(i);
    return -1;
}

int Mesh::findChamber(const std::string& name) const {
    for (size_t i = 0; i < chambers.size(); ++i)
        if (chambers[i].name == name) return static_cast<int>(i);
    return -1;
}

void Mesh::validate() const {
    const int nn = getNumNodes();
    const int nt = getNumTris();
    if (nn == 0 || nt == 0) fail("it has no nodes or no triangles");
    if (!X.allFinite()) fail("a reference node position is not finite");
    for (int t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k)
            if (tris(k, t) < 0 || tris(k, t) >= nn)
                fail("triangle " + std::to_string(t) + " refers to node " +
                     std::to_string(tris(k, t)) + ", valid are 0.." + std::to_string(nn - 1));
        const int a = tris(0, t), b = tris(1, t), c = tris(2, t);
        if (a == b || b == c || a == c) fail("triangle " + std::to_string(t) + " repeats a node");
        const double len2 =
            std::max({(X.col(b) - X.col(a)).squaredNorm(), (X.col(c) - X.col(b)).squaredNorm(),
                      (X.col(a) - X.col(c)).squaredNorm()});
        if (!(triArea(X, a, b, c) > 1e-10 * len2))
            fail("triangle " + std::to_string(t) + " is degenerate (zero reference area)");
    }
    if (static_cast<int>(triPanel.size()) != nt)
        fail("triPanel has " + std::to_string(triPanel.size()) +
             " entries, expected one per "
             "triangle (" +
             std::to_string(nt) + ")");
    for (int t = 0; t < nt; ++t)
        if (triPanel[t] < 0 || triPanel[t] >= static_cast<int>(panelNames.size()))
            fail("triangle " + std::to_string(t) + " has panel index " +
                 std::to_string(triPanel[t]) + ", valid are 0.." +
                 std::to_string(static_cast<int>(panelNames.size()) - 1));

    std::vector<char> isSupport(nn, 0);
    for (int s : supportNodes) {
        if (s < 0 || s >= nn)
            fail("support node " + std::to_string(s) + " is not in 0.." + std::to_string(nn - 1));
        isSupport[s] = 1;
    }
    for (int d : fixedDofs)
        if (d < 0 || d >= 3 * nn)
            fail("fixed dof " + std::to_string(d) + " is not in 0.." + std::to_string(3 * nn - 1));

    std::vector<char> seen(nt, 0);
    for (const ChamberBoundary& ch : chambers) {
        const std::string who = "chamber '" + ch.name + "'";
        if (ch.tris.empty()) fail(who + " has no triangles");
        if (ch.tris.size() != ch.signs.size())
            fail(who + " has " + std::to_string(ch.tris.size()) + " triangles but " +
                 std::to_string(ch.signs.size()) + " signs");
        std::fill(seen.begin(), seen.end(), 0);
        // Net orientation count of each undirected edge: +1 per use as (lo -> hi), -1 per
        // (hi -> lo), after flipping triangles whose sign is -1. Closed and consistently
        // oriented <=> every net count is zero.
        std::unordered_map<std::uint64_t, int> net;
        net.reserve(3 * ch.tris.size());
        for (size_t i = 0; i < ch.tris.size(); ++i) {
            const int t = ch.tris[i];
            if (t < 0 || t >= nt)
                fail(who + " refers to triangle " + std::to_string(t) + ", valid are 0.." +
                     std::to_string(nt - 1));
            if (ch.signs[i] != 1 && ch.signs[i] != -1)
                fail(who + " has sign " + std::to_string(ch.signs[i]) + " for triangle " +
                     std::to_string(t) + ", valid are +1 and -1");
            if (seen[t]) fail(who + " lists triangle " + std::to_string(t) + " twice");
            seen[t] = 1;
            for (int k = 0; k < 3; ++k) {
                int a = tris(k, t), b = tris((k + 1) % 3, t);
                if (ch.signs[i] < 0) std::swap(a, b);
                net[edgeKey(a, b)] += (a < b) ? 1 : -1;
            }
        }
        for (const auto& [key, count] : net) {
            if (count == 0) continue;
            const int lo = static_cast<int>(key >> 32);
            const int hi = static_cast<int>(key & 0xffffffffu);
            if (std::abs(count) > 1 || !isSupport[lo] || !isSupport[hi]) {
                std::ostringstream os;
                os << who << " is not closed: edge (" << lo << ", " << hi
                   << ") has net orientation count " << count
                   << " (a closed, consistently oriented chamber has 0 on every edge; an open "
                      "edge is allowed only if both its nodes are support nodes). A triangle "
                      "is missing or misoriented there";
                fail(os.str());
            }
        }
    }
}

MeshQuality calcMeshQuality(const Mesh& mesh) {
    MeshQuality q;
    q.numNodes = mesh.getNumNodes();
    q.numTris = mesh.getNumTris();
    if (q.numTris == 0) return q;
    q.minAngle = 3.14159265358979323846;
    q.minEdge = std::numeric_limits<double>::infinity();
    double sumAspect = 0.0, sumEdge = 0.0;
    for (int t = 0; t < q.numTris; ++t) {
        Vec3 p[3];
        for (int k = 0; k < 3; ++k) p[k] = mesh.X.col(mesh.tris(k, t));
        double len[3];
        for (int k = 0; k < 3; ++k) len[k] = (p[(k + 1) % 3] - p[k]).norm();
        for (int k = 0; k < 3; ++k) {
            const Vec3 u = p[(k + 1) % 3] - p[k], v = p[(k + 2) % 3] - p[k];
            const double ang = std::atan2(u.cross(v).norm(), u.dot(v));
            q.minAngle = std::min(q.minAngle, ang);
            q.maxAngle = std::max(q.maxAngle, ang);
            q.minEdge = std::min(q.minEdge, len[k]);
            q.maxEdge = std::max(q.maxEdge, len[k]);
            sumEdge += len[k];
        }
        const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
        const double s = 0.5 * (len[0] + len[1] + len[2]);
        const double rIn = area / s;
        const double rCirc = len[0] * len[1] * len[2] / (4.0 * area);
        const double aspect = rCirc / (2.0 * rIn);
        sumAspect += aspect;
        q.maxAspect = std::max(q.maxAspect, aspect);
    }
    q.meanAspect = sumAspect / q.numTris;
    q.meanEdge = sumEdge / (3.0 * q.numTris);
    return q;
}

namespace {

// 6 V of chamber c at x by the divergence theorem over its signed boundary triangles; adds
// scale * dV/dx into grad and scale * d2V/dx2 into hess when they are given.
double sumChamberVolume(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x, Eigen::VectorXd* grad,
                        std::vector<Triplet>* hess, double scale) {
    const ChamberBoundary& ch = mesh.chambers[c];
    const int nt = static_cast<int>(ch.tris.size());
    if (hess) {
        // Grow geometrically: an exact reserve per call would copy the caller's (large)
        // triplet list on every chamber evaluation.
        const size_t need = hess->size() + 36 * static_cast<size_t>(nt);
        if (hess->capacity() < need) hess->reserve(std::max(need, 2 * hess->capacity()));
    }
    const double sixth = 1.0 / 6.0;
    double v6 = 0.0;
    for (int i = 0; i < nt; ++i) {
        const int t = ch.tris[i];
        const int a = mesh.tris(0, t), b = mesh.tris(1, t), d = mesh.tris(2, t);
        const Vec3 x0 = x.col(a), x1 = x.col(b), x2 = x.col(d);
        const double s = ch.signs[i];
        const Vec3 c12 = x1.cross(x2);
        v6 += s * x0.dot(c12);
        const double f = scale * s * sixth;
        if (grad) {
            grad->segment<3>(3 * a) += f * c12;
            grad->segment<3>(3 * b) += f * x2.cross(x0);
            grad->segment<3>(3 * d) += f * x0.cross(x1);
        }
        if (hess) {
            // dV/dx0 = s/6 x1 x x2 = -s/6 [x2]_x x1  =>  d2V/dx0 dx1 = -s/6 [x2]_x, and
            // cyclically; the transposed blocks are +s/6 [.]_x since [v]_x^T = -[v]_x.
            pushSkew(*hess, a, b, x2, -f);
            pushSkew(*hess, b, a, x2, f);
            pushSkew(*hess, b, d, x0, -f);
            pushSkew(*hess, d, b, x0, f);
            pushSkew(*hess, d, a, x1, -f);
            pushSkew(*hess, a, d, x1, f);
        }
    }
    return v6;
}

void checkGradientSize(const char* what, const Eigen::VectorXd& g, const Eigen::Matrix3Xd& x) {
    if (g.size() != 3 * x.cols())
        throw std::invalid_argument(std::string(what) + ": gradient has size " +
                                    std::to_string(g.size()) + ", expected " +
                                    std::to_string(3 * x.cols()));
}

}  // namespace

double calcChamberVolume(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x, EnergyAccumulator* acc,
                         double scale) {
    checkChamberIndex(mesh, c);
    const bool wantG = acc && acc->wantGradient;
    const bool wantH = acc && acc->wantHessian;
    if (wantG) checkGradientSize("calcChamberVolume: accumulator", acc->grad, x);
    const double V = sumChamberVolume(mesh, c, x, wantG ? &acc->grad : nullptr,
                                      wantH ? &acc->hess : nullptr, scale) *
                     (1.0 / 6.0);
    if (acc) acc->energy += scale * V;
    return V;
}

double addChamberVolumeGradient(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x,
                                Eigen::VectorXd& grad, double scale) {
    checkChamberIndex(mesh, c);
    checkGradientSize("addChamberVolumeGradient", grad, x);
    return sumChamberVolume(mesh, c, x, &grad, nullptr, scale) * (1.0 / 6.0);
}

Eigen::VectorXd calcChamberVolumeGradient(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * x.cols());
    addChamberVolumeGradient(mesh, c, x, g);
    return g;
}

}  // namespace bags
