/// @file Parametric airbag meshes: the double wedge, a box, an icosphere, the square cushion
/// and the clamped disk. All conforming (shared nodes on shared edges), outer normals out.

#include <bags/Geometry.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace bags {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kSmoothSweeps = 20;  ///< Laplacian sweeps over the side panels' inner nodes

/// Collects nodes, triangles and panels; orients each triangle to a wanted normal.
class MeshBuilder {
  public:
    int addNode(const Vec3& p) {
        m_nodes.push_back(p);
        return static_cast<int>(m_nodes.size()) - 1;
    }
    const Vec3& getNode(int i) const { return m_nodes[i]; }
    int addPanel(const std::string& name) {
        m_panels.push_back(name);
        return static_cast<int>(m_panels.size()) - 1;
    }
    /// Adds triangle (a, b, c), flipped if needed so its normal has a positive component
    /// along `outward`. Returns its index.
    int addTri(int a, int b, int c, int panel, const Vec3& outward) {
        const Vec3 n = (m_nodes[b] - m_nodes[a]).cross(m_nodes[c] - m_nodes[a]);
        if (n.dot(outward) < 0.0) std::swap(b, c);
        m_tris.emplace_back(a, b, c);
        m_triPanel.push_back(panel);
        return static_cast<int>(m_tris.size()) - 1;
    }
    /// Splits quad a-b-c-d (cyclic order) along a-c (diagAC) or b-d.
    void addQuad(int a, int b, int c, int d, bool diagAC, int panel, const Vec3& outward) {
        if (diagAC) {
            addTri(a, b, c, panel, outward);
            addTri(a, c, d, panel, outward);
        } else {
            addTri(a, b, d, panel, outward);
            addTri(b, c, d, panel, outward);
        }
    }
    /// Splits quad a-b-c-d (cyclic order, planar) by `pattern`: along a-c or b-d as
    /// diagAC says (Legacy, Mirrored), or into four triangles around a new node at the
    /// corners' mean (Crossed), whose index is returned (-1 otherwise).
    int addCell(int a, int b, int c, int d, MeshPattern pattern, bool diagAC, int panel,
                const Vec3& outward) {
        if (pattern != MeshPattern::Crossed) {
            addQuad(a, b, c, d, diagAC, panel, outward);
            return -1;
        }
        const int m = addNode(0.25 * (m_nodes[a] + m_nodes[b] + m_nodes[c] + m_nodes[d]));
        addTri(a, b, m, panel, outward);
        addTri(b, c, m, panel, outward);
        addTri(c, d, m, panel, outward);
        addTri(d, a, m, panel, outward);
        return m;
    }
    /// Smallest interior angle of triangle (a, b, c) [rad].
    double calcMinAngle(int a, int b, int c) const {
        const Vec3* p[3] = {&m_nodes[a], &m_nodes[b], &m_nodes[c]};
        double m = kPi;
        for (int k = 0; k < 3; ++k) {
            const Vec3 u = *p[(k + 1) % 3] - *p[k], v = *p[(k + 2) % 3] - *p[k];
            m = std::min(m, std::atan2(u.cross(v).norm(), u.dot(v)));
        }
        return m;
    }
    /// Triangulates the strip between two node polylines that run the same way (lo[0] and
    /// up[0] at one end, lo.back() and up.back() at the other), choosing at each step the
    /// candidate triangle with the larger smallest angle.
    void zipRows(const std::vector<int>& lo, const std::vector<int>& up, int panel,
                 const Vec3& outward) {
        size_t i = 0, j = 0;
        while (i + 1 < lo.size() || j + 1 < up.size()) {
            bool advanceLo;
            if (j + 1 >= up.size())
                advanceLo = true;
            else if (i + 1 >= lo.size())
                advanceLo = false;
            else
                advanceLo =
                    calcMinAngle(lo[i], lo[i + 1], up[j]) >= calcMinAngle(lo[i], up[j + 1], up[j]);
            if (advanceLo) {
                addTri(lo[i], lo[i + 1], up[j], panel, outward);
                ++i;
            } else {
                addTri(lo[i], up[j + 1], up[j], panel, outward);
                ++j;
            }
        }
    }
    /// Laplacian smoothing of the `free` nodes over the triangles from index firstTri on
    /// (Gauss-Seidel sweeps; each free node moves to the mean of its neighbours). For a flat,
    /// convex panel this evens out the zipped rows while the panel's boundary stays put. The
    /// result is kept only if no triangle turned over (normal against `outward`) and the
    /// smallest angle lost less than 10 % (smoothing trades a little of the worst angle for
    /// much more even triangles); otherwise the nodes go back where they were.
    void smooth(const std::vector<int>& free, int firstTri, int sweeps, const Vec3& outward) {
        std::vector<Vec3> saved;
        for (int n : free) saved.push_back(m_nodes[n]);
        const double before = calcMinAngle(firstTri, outward);
        relax(free, firstTri, sweeps);
        if (!(calcMinAngle(firstTri, outward) >= 0.9 * before))
            for (size_t i = 0; i < free.size(); ++i) m_nodes[free[i]] = saved[i];
    }
    /// Smallest angle of the triangles from firstTri on [rad]; -1 if one faces against
    /// `outward`.
    double calcMinAngle(int firstTri, const Vec3& outward) const {
        double m = kPi;
        for (size_t t = firstTri; t < m_tris.size(); ++t) {
            const Eigen::Vector3i& v = m_tris[t];
            const Vec3 n = (m_nodes[v[1]] - m_nodes[v[0]]).cross(m_nodes[v[2]] - m_nodes[v[0]]);
            if (!(n.dot(outward) > 0.0)) return -1.0;
            m = std::min(m, calcMinAngle(v[0], v[1], v[2]));
        }
        return m;
    }

  private:
    void relax(const std::vector<int>& free, int firstTri, int sweeps) {
        std::vector<std::vector<int>> nbr(free.size());
        std::vector<int> slot(m_nodes.size(), -1);
        for (size_t i = 0; i < free.size(); ++i) slot[free[i]] = static_cast<int>(i);
        for (size_t t = firstTri; t < m_tris.size(); ++t)
            for (int k = 0; k < 3; ++k) {
                const int a = m_tris[t][k], c = m_tris[t][(k + 1) % 3];
                if (slot[a] >= 0) nbr[slot[a]].push_back(c);
                if (slot[c] >= 0) nbr[slot[c]].push_back(a);
            }
        for (auto& v : nbr) {
            std::sort(v.begin(), v.end());
            v.erase(std::unique(v.begin(), v.end()), v.end());
        }
        for (int s = 0; s < sweeps; ++s)
            for (size_t i = 0; i < free.size(); ++i) {
                Vec3 mean = Vec3::Zero();
                for (int c : nbr[i]) mean += m_nodes[c];
                m_nodes[free[i]] = mean / static_cast<double>(nbr[i].size());
            }
    }

  public:
    int getNumTris() const { return static_cast<int>(m_tris.size()); }
    Vec3 calcCentroid(int t) const {
        const Eigen::Vector3i& v = m_tris[t];
        return (m_nodes[v[0]] + m_nodes[v[1]] + m_nodes[v[2]]) / 3.0;
    }

    Mesh finish() const {
        Mesh m;
        m.X.resize(3, static_cast<int>(m_nodes.size()));
        for (size_t i = 0; i < m_nodes.size(); ++i) m.X.col(i) = m_nodes[i];
        m.tris.resize(3, static_cast<int>(m_tris.size()));
        for (size_t i = 0; i < m_tris.size(); ++i) m.tris.col(i) = m_tris[i];
        m.triPanel = m_triPanel;
        m.panelNames = m_panels;
        return m;
    }

  private:
    std::vector<Vec3> m_nodes;
    std::vector<Eigen::Vector3i> m_tris;
    std::vector<int> m_triPanel;
    std::vector<std::string> m_panels;
};

/// Number of segments of length about h on a line of length len (at least minSeg).
int numSegments(double len, double h, int minSeg = 1) {
    return std::max(minSeg, static_cast<int>(std::lround(len / h)));
}

/// Diagonal choice of cell (i, j) of an ni x nj grid mirrored about the grid's centre lines
/// (a "union jack" pattern): keeps the mesh symmetric under both reflections.
bool unionJack(int i, int j, int ni, int nj) { return (2 * i + 1 < ni) == (2 * j + 1 < nj); }

/// Alternating diagonals along i, the index j mirrored about the centre line of j. The
/// mirrored cell gets the same diagonal, not the mirrored one: MeshPattern::Legacy.
bool diamond(int i, int j, int nj) {
    const int jm = (2 * j + 1 < nj) ? j : nj - 1 - j;
    return ((i + jm) % 2) == 0;
}

/// Alternating diagonals on the lower half of j (as diamond()), each mirrored onto the upper
/// half: cell (i, nj-1-j) takes the mirror image of cell (i, j)'s diagonal, which is the other
/// diagonal of the quad. With nj even no cell is its own mirror image.
bool mirroredDiagonal(int i, int j, int nj) {
    if (2 * j + 1 < nj) return ((i + j) % 2) == 0;
    return ((i + nj - 1 - j) % 2) != 0;
}

ChamberBoundary allTrisChamber(const std::string& name, int numTris) {
    ChamberBoundary ch;
    ch.name = name;
    ch.tris.resize(numTris);
    for (int t = 0; t < numTris; ++t) ch.tris[t] = t;
    ch.signs.assign(numTris, 1);
    return ch;
}

std::string fmt(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

void requirePositive(const std::string& what, double v) {
    if (!(std::isfinite(v) && v > 0.0))
        throw std::invalid_argument(what + " = " + fmt(v) + " is invalid: it must be positive");
}

}  // namespace

// ------------------------------------------------------------------------------------------
// Double wedge

const char* getMeshPatternName(MeshPattern pattern) {
    switch (pattern) {
        case MeshPattern::Legacy:
            return "legacy";
        case MeshPattern::Mirrored:
            return "mirrored";
        case MeshPattern::Crossed:
            return "crossed";
    }
    return "unknown";
}

double DoubleWedgeParams::calcApexX() const {
    return std::sqrt(std::max(0.0, shortSide * shortSide - height * height));
}

double DoubleWedgeParams::calcFlatVolume() const { return 0.5 * longSide * height * width; }

void DoubleWedgeParams::validate() const {
    const std::string p = "DoubleWedgeParams.";
    requirePositive(p + "longSide [m]", longSide);
    requirePositive(p + "shortSide [m]", shortSide);
    requirePositive(p + "width [m]", width);
    requirePositive(p + "height [m]", height);
    requirePositive(p + "meshSize [m]", meshSize);
    if (diaphragm ? !(shortSide > height) : !(shortSide >= height))
        throw std::invalid_argument(
            p + "shortSide = " + fmt(shortSide) + " m is invalid: the steep side must be " +
            (diaphragm ? "longer than the height (" + fmt(height) + " m)"
                       : "at least the height (" + fmt(height) +
                             " m; equal gives a single right-angled wedge)"));
    const double ax = calcApexX();
    if (!(longSide > ax))
        throw std::invalid_argument(p + "longSide = " + fmt(longSide) +
                                    " m is invalid: it must exceed the apex's x, "
                                    "sqrt(shortSide^2 - height^2) = " +
                                    fmt(ax) + " m, so the apex lies above the base");
    const double minDim = std::min({longSide, shortSide, width, height});
    const double hi = std::min(0.05, 0.5 * minDim);
    if (meshSize < 0.001 || meshSize > hi)
        throw std::invalid_argument(p + "meshSize = " + fmt(meshSize) +
                                    " m is invalid: valid is 0.001 m to " + fmt(hi) +
                                    " m (at most 0.05 m and half the smallest dimension)");
}

Mesh makeDoubleWedgeBag(const DoubleWedgeParams& p) {
    p.validate();
    const double L = p.longSide, H = p.height, W = p.width, ms = p.meshSize;
    const double ax = p.calcApexX();
    const double sLen = p.shortSide, gLen = std::hypot(L - ax, H);

    // Rows of the side panels at heights z_k = H k / n; both sloped sides get n segments.
    // Rows sqrt(3)/2 h apart give the side panels near-equilateral triangles of edge h; more
    // rows if a sloped side's segments would exceed 1.5 h (shallow slopes).
    const int n = std::max(numSegments(H, std::sqrt(3.0) / 2.0 * ms, 2),
                           numSegments(std::max(sLen, gLen), 1.5 * ms, 2));
    // In-row node spacing: h, or less when rows are closer than sqrt(3)/2 h (equilateral).
    const double rowSpacing = std::min(ms, 2.0 / std::sqrt(3.0) * H / n);
    // Mirrored needs an even number of cells across the width (an odd count has a middle cell
    // that is its own mirror image, which no diagonal can be): the even count nearest W / h.
    const int ny = p.pattern == MeshPattern::Mirrored
                       ? std::max(2, 2 * static_cast<int>(std::lround(0.5 * W / ms)))
                       : numSegments(W, ms, 1);
    auto diagonal = [&](int i, int j) {
        return p.pattern == MeshPattern::Mirrored ? mirroredDiagonal(i, j, ny) : diamond(i, j, ny);
    };
    std::vector<int> baseCentres;  // Crossed: the base cells' centre nodes (bonded with the base)

    // Base x stations (with a station at the apex's x when there is a diaphragm).
    std::vector<double> xs;
    int nbLeft = 0;  // base segments left of the diaphragm
    if (p.diaphragm) {
        nbLeft = numSegments(ax, ms);
        const int nbRight = numSegments(L - ax, ms);
        for (int i = 0; i < nbLeft; ++i) xs.push_back(ax * i / nbLeft);
        for (int i = 0; i <= nbRight; ++i) xs.push_back(ax + (L - ax) * i / nbRight);
        xs.back() = L;
    } else {
        const int nb = numSegments(L, ms, 2);
        for (int i = 0; i <= nb; ++i) xs.push_back(L * i / nb);
    }
    const int nb = static_cast<int>(xs.size()) - 1;

    // Closed perimeter loop of the profile: base A -> B, gentle B -> C, steep C -> A.
    std::vector<Vec2> perim;  // (x, z)
    for (int i = 0; i <= nb; ++i) perim.emplace_back(xs[i], 0.0);
    for (int k = 1; k <= n; ++k) perim.emplace_back(L + (ax - L) * k / n, H * k / n);
    perim.back() = Vec2(ax, H);
    for (int k = n - 1; k >= 1; --k) perim.emplace_back(ax * k / n, H * k / n);
    const int np = static_cast<int>(perim.size());
    auto gentleIdx = [&](int k) { return nb + k; };                      // k = 0 (B) .. n (C)
    auto steepIdx = [&](int k) { return k == 0 ? 0 : nb + 2 * n - k; };  // k = 0 (A) .. n (C)

    MeshBuilder b;
    const int pBase = b.addPanel("base");
    const int pSteep = b.addPanel("steep");
    const int pGentle = b.addPanel("gentle");
    const int pFront = b.addPanel("side-front");
    const int pBack = b.addPanel("side-back");
    const int pDia = p.diaphragm ? b.addPanel("diaphragm") : -1;

    std::vector<double> ys(ny + 1);
    for (int j = 0; j <= ny; ++j) ys[j] = -0.5 * W + W * j / ny;
    ys[ny] = 0.5 * W;

    // Extruded perimeter nodes id(p, j).
    std::vector<int> grid(static_cast<size_t>(np) * (ny + 1));
    auto gid = [&](int pi, int j) -> int& { return grid[static_cast<size_t>(pi) * (ny + 1) + j]; };
    for (int pi = 0; pi < np; ++pi)
        for (int j = 0; j <= ny; ++j)
            gid(pi, j) = b.addNode(Vec3(perim[pi][0], ys[j], perim[pi][1]));

    const Vec3 nBase(0, 0, -1);
    const Vec3 nSteep = Vec3(-H, 0, ax).normalized();
    const Vec3 nGentle = Vec3(H, 0, L - ax).normalized();
    for (int pi = 0; pi < np; ++pi) {
        const int q = (pi + 1) % np;
        int panel;
        Vec3 nrm;
        if (pi < nb) {
            panel = pBase;
            nrm = nBase;
        } else if (pi < nb + n) {
            panel = pGentle;
            nrm = nGentle;
        } else {
            panel = pSteep;
            nrm = nSteep;
        }
        for (int j = 0; j < ny; ++j) {
            const int centre = b.addCell(gid(pi, j), gid(q, j), gid(q, j + 1), gid(pi, j + 1),
                                         p.pattern, diagonal(pi, j), panel, nrm);
            if (centre >= 0 && panel == pBase) baseCentres.push_back(centre);
        }
    }

    // Side panels: rows of nodes at the sloped panels' grid heights, zipped row to row; with
    // a diaphragm each row has a node at x = ax and the two halves are zipped separately.
    std::vector<int> column[2];  // diaphragm column nodes on each side, k = 0..n
    for (int side = 0; side < 2; ++side) {
        const int j = side == 0 ? 0 : ny;
        const int panel = side == 0 ? pFront : pBack;
        const Vec3 nrm(0, side == 0 ? -1.0 : 1.0, 0);
        std::vector<std::vector<int>> left(n + 1), right(n + 1);  // right unused w/o diaphragm
        column[side].assign(n + 1, -1);
        std::vector<int> interior;  // nodes inside the side panel, free to be smoothed
        const int firstTri = b.getNumTris();
        auto addRowNodes = [&](std::vector<int>& row, double x0, double x1, double z) {
            const int m = numSegments(x1 - x0, rowSpacing);
            for (int i = 1; i < m; ++i) {
                row.push_back(b.addNode(Vec3(x0 + (x1 - x0) * i / m, ys[j], z)));
                interior.push_back(row.back());
            }
        };
        for (int k = 0; k <= n; ++k) {
            if (k == 0) {
                const int split = p.diaphragm ? nbLeft : nb;
                for (int i = 0; i <= split; ++i) left[0].push_back(gid(i, j));
                for (int i = split; i <= nb && p.diaphragm; ++i) right[0].push_back(gid(i, j));
                column[side][0] = gid(split, j);
                continue;
            }
            if (k == n) {
                const int c = gid(gentleIdx(n), j);
                left[n] = {c};
                right[n] = {c};
                column[side][n] = c;
                continue;
            }
            const double z = H * k / n;
            const double xl = ax * k / n, xr = L + (ax - L) * k / n;
            const int nl = gid(steepIdx(k), j), nr = gid(gentleIdx(k), j);
            if (p.diaphragm) {
                const int c = b.addNode(Vec3(ax, ys[j], z));
                column[side][k] = c;
                left[k].push_back(nl);
                addRowNodes(left[k], xl, ax, z);
                left[k].push_back(c);
                right[k].push_back(c);
                addRowNodes(right[k], ax, xr, z);
                right[k].push_back(nr);
            } else {
                left[k].push_back(nl);
                addRowNodes(left[k], xl, xr, z);
                left[k].push_back(nr);
            }
        }
        for (int k = 0; k < n; ++k) {
            b.zipRows(left[k], left[k + 1], panel, nrm);
            if (p.diaphragm) b.zipRows(right[k], right[k + 1], panel, nrm);
        }
        b.smooth(interior, firstTri, kSmoothSweeps, nrm);
    }

    // Diaphragm: plane x = ax, rows k (z) x columns j (y), normal +x (out of wedge-steep).
    const Vec3 nDia(1, 0, 0);
    if (p.diaphragm) {
        std::vector<int> d(static_cast<size_t>(n + 1) * (ny + 1));
        auto did = [&](int k, int j) -> int& { return d[static_cast<size_t>(k) * (ny + 1) + j]; };
        for (int k = 0; k <= n; ++k)
            for (int j = 0; j <= ny; ++j) {
                if (k == 0)
                    did(k, j) = gid(nbLeft, j);
                else if (k == n)
                    did(k, j) = gid(gentleIdx(n), j);
                else if (j == 0)
                    did(k, j) = column[0][k];
                else if (j == ny)
                    did(k, j) = column[1][k];
                else
                    did(k, j) = b.addNode(Vec3(ax, ys[j], H * k / n));
            }
        for (int k = 0; k < n; ++k)
            for (int j = 0; j < ny; ++j)
                b.addCell(did(k, j), did(k + 1, j), did(k + 1, j + 1), did(k, j + 1), p.pattern,
                          diagonal(k, j), pDia, nDia);
    }

    Mesh mesh = b.finish();
    const int nt = mesh.getNumTris();
    if (p.diaphragm) {
        ChamberBoundary steep, gentle;
        steep.name = "wedge-steep";
        gentle.name = "wedge-gentle";
        for (int t = 0; t < nt; ++t) {
            if (mesh.triPanel[t] == pDia) {
                steep.tris.push_back(t);
                steep.signs.push_back(1);
                gentle.tris.push_back(t);
                gentle.signs.push_back(-1);
            } else if (b.calcCentroid(t)[0] < ax) {
                steep.tris.push_back(t);
                steep.signs.push_back(1);
            } else {
                gentle.tris.push_back(t);
                gentle.signs.push_back(1);
            }
        }
        mesh.chambers = {steep, gentle};
    } else {
        mesh.chambers = {allTrisChamber("bag", nt)};
    }
    if (p.bondBase)
        for (int i = 0; i <= nb; ++i)
            for (int j = 0; j <= ny; ++j) mesh.supportNodes.push_back(gid(i, j));
    if (p.bondBase)
        mesh.supportNodes.insert(mesh.supportNodes.end(), baseCentres.begin(), baseCentres.end());
    std::sort(mesh.supportNodes.begin(), mesh.supportNodes.end());
    return mesh;
}

// ------------------------------------------------------------------------------------------
// Box

Mesh makeBoxBag(double lx, double ly, double lz, double meshSize, bool bondBase) {
    requirePositive("makeBoxBag: lx [m]", lx);
    requirePositive("makeBoxBag: ly [m]", ly);
    requirePositive("makeBoxBag: lz [m]", lz);
    requirePositive("makeBoxBag: meshSize [m]", meshSize);
    const int nx = numSegments(lx, meshSize), ny = numSegments(ly, meshSize),
              nz = numSegments(lz, meshSize);
    const int n[3] = {nx, ny, nz};
    const double lo[3] = {-0.5 * lx, -0.5 * ly, 0.0};
    const double len[3] = {lx, ly, lz};
    MeshBuilder b;
    // Surface lattice nodes, created on first use so edges and corners are shared.
    std::vector<int> lattice(static_cast<size_t>(nx + 1) * (ny + 1) * (nz + 1), -1);
    auto node = [&](int i, int j, int k) {
        int& id = lattice[(static_cast<size_t>(k) * (ny + 1) + j) * (nx + 1) + i];
        if (id < 0) {
            const int ijk[3] = {i, j, k};
            Vec3 pos;
            for (int d = 0; d < 3; ++d)
                pos[d] = ijk[d] == n[d] ? lo[d] + len[d] : lo[d] + len[d] * ijk[d] / n[d];
            id = b.addNode(pos);
        }
        return id;
    };
    const char* names[3][2] = {
        {"side-x-minus", "side-x-plus"}, {"side-y-minus", "side-y-plus"}, {"bottom", "top"}};
    std::vector<int> bottom;
    for (int d = 0; d < 3; ++d) {
        const int u = (d + 1) % 3, v = (d + 2) % 3;  // in-face directions
        for (int s = 0; s < 2; ++s) {
            const int panel = b.addPanel(names[d][s]);
            Vec3 nrm = Vec3::Zero();
            nrm[d] = s == 0 ? -1.0 : 1.0;
            auto at = [&](int a, int c) {
                int ijk[3];
                ijk[d] = s == 0 ? 0 : n[d];
                ijk[u] = a;
                ijk[v] = c;
                return node(ijk[0], ijk[1], ijk[2]);
            };
            for (int a = 0; a < n[u]; ++a)
                for (int c = 0; c < n[v]; ++c)
                    b.addQuad(at(a, c), at(a + 1, c), at(a + 1, c + 1), at(a, c + 1),
                              unionJack(a, c, n[u], n[v]), panel, nrm);
            if (d == 2 && s == 0)
                for (int a = 0; a <= n[u]; ++a)
                    for (int c = 0; c <= n[v]; ++c) bottom.push_back(at(a, c));
        }
    }
    Mesh mesh = b.finish();
    mesh.chambers = {allTrisChamber("box", mesh.getNumTris())};
    if (bondBase) {
        std::sort(bottom.begin(), bottom.end());
        mesh.supportNodes = bottom;
    }
    return mesh;
}

// ------------------------------------------------------------------------------------------
// Icosphere

Mesh makeSphere(double r, int refinements) {
    requirePositive("makeSphere: r [m]", r);
    if (refinements < 0 || refinements > 8)
        throw std::invalid_argument("makeSphere: refinements = " + std::to_string(refinements) +
                                    " is invalid: valid is 0..8");
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (Vec3& p : v) p = r * p.normalized();
    std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                      {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                      {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int level = 0; level < refinements; ++level) {
        std::map<std::pair<int, int>, int> mid;
        auto midpoint = [&](int a, int c) {
            const auto key = std::minmax(a, c);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back(r * (v[a] + v[c]).normalized());
            const int id = static_cast<int>(v.size()) - 1;
            mid.emplace(key, id);
            return id;
        };
        std::vector<Eigen::Vector3i> g;
        g.reserve(4 * f.size());
        for (const Eigen::Vector3i& tri : f) {
            const int a = midpoint(tri[0], tri[1]), c = midpoint(tri[1], tri[2]),
                      d = midpoint(tri[2], tri[0]);
            g.emplace_back(tri[0], a, d);
            g.emplace_back(tri[1], c, a);
            g.emplace_back(tri[2], d, c);
            g.emplace_back(a, c, d);
        }
        f.swap(g);
    }
    MeshBuilder b;
    for (const Vec3& p : v) b.addNode(p);
    const int panel = b.addPanel("sphere");
    for (const Eigen::Vector3i& tri : f) {
        const Vec3 c = (v[tri[0]] + v[tri[1]] + v[tri[2]]) / 3.0;
        b.addTri(tri[0], tri[1], tri[2], panel, c);
    }
    Mesh mesh = b.finish();
    mesh.chambers = {allTrisChamber("sphere", mesh.getNumTris())};
    return mesh;
}

// ------------------------------------------------------------------------------------------
// Square cushion

Mesh makeSquareCushion(double edge, int n, double gap) {
    requirePositive("makeSquareCushion: edge [m]", edge);
    if (n < 2)
        throw std::invalid_argument("makeSquareCushion: n = " + std::to_string(n) +
                                    " is invalid: at least 2 divisions per edge");
    if (!(std::isfinite(gap) && gap >= 0.0))
        throw std::invalid_argument("makeSquareCushion: gap = " + fmt(gap) +
                                    " m is invalid: it must be zero or positive");
    MeshBuilder b;
    std::vector<int> top((n + 1) * (n + 1)), bot((n + 1) * (n + 1));
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double x = -0.5 * edge + edge * i / n, y = -0.5 * edge + edge * j / n;
            const int k = j * (n + 1) + i;
            if (i == 0 || j == 0 || i == n || j == n) {
                top[k] = bot[k] = b.addNode(Vec3(x, y, 0.0));
            } else {
                top[k] = b.addNode(Vec3(x, y, 0.5 * gap));
                bot[k] = b.addNode(Vec3(x, y, -0.5 * gap));
            }
        }
    const int pTop = b.addPanel("top"), pBot = b.addPanel("bottom");
    for (int s = 0; s < 2; ++s) {
        const std::vector<int>& g = s == 0 ? top : bot;
        const Vec3 nrm(0, 0, s == 0 ? 1.0 : -1.0);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const int k = j * (n + 1) + i;
                b.addQuad(g[k], g[k + 1], g[k + n + 2], g[k + n + 1], unionJack(i, j, n, n),
                          s == 0 ? pTop : pBot, nrm);
            }
    }
    Mesh mesh = b.finish();
    mesh.chambers = {allTrisChamber("cushion", mesh.getNumTris())};
    return mesh;
}

// ------------------------------------------------------------------------------------------
// Clamped disk

Mesh makeDisk(double r, int rings) {
    requirePositive("makeDisk: r [m]", r);
    if (rings < 1)
        throw std::invalid_argument("makeDisk: rings = " + std::to_string(rings) +
                                    " is invalid: at least 1");
    MeshBuilder b;
    const int panel = b.addPanel("disk");
    const Vec3 nrm(0, 0, 1);
    std::vector<int> prev = {b.addNode(Vec3::Zero())};
    for (int k = 1; k <= rings; ++k) {
        // Ring k holds 6k nodes; the first at angle 0 in every ring so rings zip in order.
        const double rk = k == rings ? r : r * k / rings;
        std::vector<int> ring;
        for (int i = 0; i < 6 * k; ++i) {
            const double a = 2.0 * kPi * i / (6 * k);
            ring.push_back(b.addNode(Vec3(rk * std::cos(a), rk * std::sin(a), 0.0)));
        }
        std::vector<int> lo = prev, up = ring;
        up.push_back(ring.front());  // close the loops
        if (k > 1) lo.push_back(prev.front());
        b.zipRows(lo, up, panel, nrm);  // for k = 1 the centre fans out
        prev = ring;
    }
    Mesh mesh = b.finish();
    mesh.chambers = {allTrisChamber("disk", mesh.getNumTris())};
    mesh.supportNodes = prev;
    std::sort(mesh.supportNodes.begin(), mesh.supportNodes.end());
    return mesh;
}

Mesh placeCopies(const Mesh& bag, const std::vector<Eigen::Isometry3d>& poses) {
    if (poses.empty()) throw std::invalid_argument("placeCopies: no poses");
    const int nn = bag.getNumNodes(), nt = bag.getNumTris();
    const int np = static_cast<int>(bag.panelNames.size());
    Mesh m;
    const int n = static_cast<int>(poses.size());
    m.X.resize(3, static_cast<Eigen::Index>(nn) * n);
    m.tris.resize(3, static_cast<Eigen::Index>(nt) * n);
    for (int k = 0; k < n; ++k) {
        const Eigen::Isometry3d& P = poses[k];
        const Mat3 R = P.linear();
        if (!P.matrix().allFinite() || (R.transpose() * R - Mat3::Identity()).norm() > 1e-9 ||
            R.determinant() < 0.0)
            throw std::invalid_argument("placeCopies: pose " + std::to_string(k) +
                                        " is not a rigid motion (rotation and translation)");
        if (!bag.fixedDofs.empty() && (R - Mat3::Identity()).norm() > 0.0)
            throw std::invalid_argument("placeCopies: a bag with fixed dofs cannot be rotated");
        const std::string prefix = "bag" + std::to_string(k) + "/";
        for (int i = 0; i < nn; ++i) m.X.col(k * nn + i) = P * Vec3(bag.X.col(i));
        m.tris.middleCols(k * nt, nt) = bag.tris.array() + k * nn;
        for (int t = 0; t < nt; ++t) m.triPanel.push_back(bag.triPanel[t] + k * np);
        for (const std::string& name : bag.panelNames) m.panelNames.push_back(prefix + name);
        for (const ChamberBoundary& c : bag.chambers) {
            ChamberBoundary cc = c;
            cc.name = prefix + c.name;
            for (int& t : cc.tris) t += k * nt;
            m.chambers.push_back(std::move(cc));
        }
        for (int s : bag.supportNodes) m.supportNodes.push_back(s + k * nn);
        for (int d : bag.fixedDofs) m.fixedDofs.push_back(d + 3 * k * nn);
    }
    return m;
}

}  // namespace bags
