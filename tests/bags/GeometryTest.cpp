// Tests of the parametric airbag meshes: volumes, conformity, orientation, quality, counts.

#include <bags/Geometry.h>
#include <bags/Mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>

using namespace bags;

namespace {

constexpr double kDeg = M_PI / 180.0;

/// Number of node pairs closer than tol (sort-and-sweep along x).
int countDuplicateNodes(const Mesh& m, double tol) {
    std::vector<int> order(m.getNumNodes());
    for (int i = 0; i < m.getNumNodes(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return m.X(0, a) < m.X(0, b); });
    int dup = 0;
    for (size_t i = 0; i < order.size(); ++i)
        for (size_t j = i + 1; j < order.size() && m.X(0, order[j]) - m.X(0, order[i]) < tol; ++j)
            if ((m.X.col(order[i]) - m.X.col(order[j])).norm() < tol) ++dup;
    return dup;
}

/// Directed-edge use counts of the triangles accepted by `keep`.
std::map<std::pair<int, int>, int> directedEdges(const Mesh& m, const std::vector<char>& keep) {
    std::map<std::pair<int, int>, int> e;
    for (int t = 0; t < m.getNumTris(); ++t)
        if (keep[t])
            for (int k = 0; k < 3; ++k) ++e[{m.tris(k, t), m.tris((k + 1) % 3, t)}];
    return e;
}

/// Every edge of the kept triangles is used exactly twice, once in each direction (a closed,
/// consistently oriented 2-manifold). Returns the number of offending edges.
int countNonManifoldEdges(const Mesh& m, const std::vector<char>& keep) {
    const auto e = directedEdges(m, keep);
    int bad = 0;
    for (const auto& [ab, count] : e) {
        const auto it = e.find({ab.second, ab.first});
        if (count != 1 || it == e.end() || it->second != 1) ++bad;
    }
    return bad;
}

double panelArea(const Mesh& m, const std::string& panel) {
    const Eigen::VectorXd a = m.calcTriangleAreas();
    const int p = m.findPanel(panel);
    double s = 0.0;
    for (int t = 0; t < m.getNumTris(); ++t)
        if (m.triPanel[t] == p) s += a[t];
    return s;
}

Vec3 triNormal(const Mesh& m, int t) {
    const Vec3 a = m.X.col(m.tris(0, t)), b = m.X.col(m.tris(1, t)), c = m.X.col(m.tris(2, t));
    return (b - a).cross(c - a).normalized();
}

Vec3 triCentroid(const Mesh& m, int t) {
    return (m.X.col(m.tris(0, t)) + m.X.col(m.tris(1, t)) + m.X.col(m.tris(2, t))) / 3.0;
}

double totalVolume(const Mesh& m) {
    double v = 0.0;
    for (int c = 0; c < static_cast<int>(m.chambers.size()); ++c) v += calcChamberVolume(m, c, m.X);
    return v;
}

/// For each node, the node at its mirror image across the plane y = 0, -1 if there is none
/// within tol [m] (sort-and-sweep along x).
std::vector<int> findMirrorNodes(const Mesh& m, double tol) {
    const int nn = m.getNumNodes();
    std::vector<int> order(nn), mirror(nn, -1);
    for (int i = 0; i < nn; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return m.X(0, a) < m.X(0, b); });
    for (int i = 0; i < nn; ++i) {
        const Vec3 want(m.X(0, i), -m.X(1, i), m.X(2, i));
        auto it = std::lower_bound(order.begin(), order.end(), want.x() - tol,
                                   [&](int a, double x) { return m.X(0, a) < x; });
        for (; it != order.end() && m.X(0, *it) <= want.x() + tol; ++it)
            if ((m.X.col(*it) - want).norm() < tol) mirror[i] = *it;
    }
    return mirror;
}

/// Number of triangles whose mirror image across y = 0 (the double wedge's mid-width plane)
/// is not a triangle of the same panel.
int countUnmirroredTris(const Mesh& m) {
    const std::vector<int> mirror = findMirrorNodes(m, 1e-9);
    std::set<std::array<int, 4>> tris;  // sorted nodes and panel
    auto key = [&](int a, int b, int c, int panel) {
        std::array<int, 4> k = {a, b, c, panel};
        std::sort(k.begin(), k.begin() + 3);
        return k;
    };
    for (int t = 0; t < m.getNumTris(); ++t)
        tris.insert(key(m.tris(0, t), m.tris(1, t), m.tris(2, t), m.triPanel[t]));
    int missing = 0;
    for (int t = 0; t < m.getNumTris(); ++t) {
        const int a = mirror[m.tris(0, t)], b = mirror[m.tris(1, t)], c = mirror[m.tris(2, t)];
        const std::string& panel = m.panelNames[m.triPanel[t]];
        // The side panels swap under the mirror; the others map onto themselves.
        const std::string other = panel == "side-front"  ? "side-back"
                                  : panel == "side-back" ? "side-front"
                                                         : panel;
        if (a < 0 || b < 0 || c < 0 || !tris.count(key(a, b, c, m.findPanel(other)))) ++missing;
    }
    return missing;
}

/// FNV-1a digest of bytes.
std::uint64_t fnv1a(std::uint64_t h, const void* p, size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) {
        h ^= c[i];
        h *= 1099511628211ull;
    }
    return h;
}

/// Digest of a mesh's connectivity: triangles, panels, supports, chambers and signs.
std::uint64_t calcTopologyDigest(const Mesh& m) {
    std::uint64_t h = 1469598103934665603ull;
    auto add = [&](int v) { h = fnv1a(h, &v, sizeof v); };
    for (int t = 0; t < m.getNumTris(); ++t)
        for (int k = 0; k < 3; ++k) add(m.tris(k, t));
    for (int v : m.triPanel) add(v);
    for (int v : m.supportNodes) add(v);
    for (const ChamberBoundary& c : m.chambers) {
        for (int v : c.tris) add(v);
        for (int v : c.signs) add(v);
    }
    return h;
}

const MeshPattern kAllPatterns[] = {MeshPattern::Legacy, MeshPattern::Mirrored,
                                    MeshPattern::Crossed};

}  // namespace

// ------------------------------------------------------------------------------------------
// Double wedge

TEST(DoubleWedge, FlatPanelVolumeIsHalfBaseTimesHeightTimesWidth) {
    for (double h : {0.010, 0.005}) {
        for (bool dia : {true, false}) {
            DoubleWedgeParams p;
            p.meshSize = h;
            p.diaphragm = dia;
            const Mesh m = makeDoubleWedgeBag(p);
            // Reference: 0.5 * 0.350 * 0.150 * 0.100 = 2.625e-3 m^3 (flat panels: exact);
            // tolerance 1e-12 relative (rounding).
            EXPECT_NEAR(totalVolume(m), 2.625e-3, 1e-12 * 2.625e-3) << "h " << h << " dia " << dia;
            EXPECT_DOUBLE_EQ(p.calcFlatVolume(), 2.625e-3);
        }
    }
}

TEST(DoubleWedge, ChamberVolumesAreTheTwoSubTrianglesAndSumToTotal) {
    DoubleWedgeParams p;
    const Mesh m = makeDoubleWedgeBag(p);
    ASSERT_EQ(m.chambers.size(), 2u);
    const double ax = p.calcApexX();
    // Reference: apex x = sqrt(0.2^2 - 0.15^2) = 0.13229 m; steep wedge 0.5 ax H W, gentle
    // 0.5 (L - ax) H W; tolerance 1e-12 relative.
    EXPECT_NEAR(ax, std::sqrt(0.0175), 1e-15);
    const double vs = calcChamberVolume(m, m.findChamber("wedge-steep"), m.X);
    const double vg = calcChamberVolume(m, m.findChamber("wedge-gentle"), m.X);
    EXPECT_NEAR(vs, 0.5 * ax * 0.15 * 0.1, 1e-12 * vs);
    EXPECT_NEAR(vg, 0.5 * (0.35 - ax) * 0.15 * 0.1, 1e-12 * vg);
    DoubleWedgeParams q = p;
    q.diaphragm = false;
    const Mesh single = makeDoubleWedgeBag(q);
    EXPECT_NEAR(vs + vg, calcChamberVolume(single, 0, single.X), 1e-12 * (vs + vg));
    // Also in a deformed state: the diaphragm terms cancel in the sum, so the sum equals the
    // outer surface's volume.
    Eigen::Matrix3Xd x = m.X;
    for (int n = 0; n < x.cols(); ++n)
        x.col(n) +=
            0.01 * Vec3(std::sin(40 * x(1, n)), std::cos(30 * x(0, n)), std::sin(20 * x(2, n)));
    ChamberBoundary outer;
    const int dia = m.findPanel("diaphragm");
    for (int t = 0; t < m.getNumTris(); ++t)
        if (m.triPanel[t] != dia) {
            outer.tris.push_back(t);
            outer.signs.push_back(1);
        }
    Mesh mo = m;
    mo.chambers = {outer};
    const double sum = calcChamberVolume(m, 0, x) + calcChamberVolume(m, 1, x);
    EXPECT_NEAR(sum, calcChamberVolume(mo, 0, x), 1e-12 * sum);
}

TEST(DoubleWedge, PanelAreasMatchTheProfile) {
    DoubleWedgeParams p;
    const Mesh m = makeDoubleWedgeBag(p);
    const double ax = p.calcApexX(), L = 0.35, H = 0.15, W = 0.1;
    // References: exact panel areas of the flat layout; tolerance 1e-12 relative.
    EXPECT_NEAR(panelArea(m, "base"), L * W, 1e-12);
    EXPECT_NEAR(panelArea(m, "steep"), 0.2 * W, 1e-12);
    EXPECT_NEAR(panelArea(m, "gentle"), std::hypot(L - ax, H) * W, 1e-12);
    EXPECT_NEAR(panelArea(m, "side-front"), 0.5 * L * H, 1e-12);
    EXPECT_NEAR(panelArea(m, "side-back"), 0.5 * L * H, 1e-12);
    EXPECT_NEAR(panelArea(m, "diaphragm"), H * W, 1e-12);
}

TEST(DoubleWedge, MeshConformsAndOuterNormalsPointOut) {
    for (MeshPattern pattern : kAllPatterns)
        for (double h : {0.010, 0.005}) {
            SCOPED_TRACE(getMeshPatternName(pattern));
            DoubleWedgeParams p;
            p.meshSize = h;
            p.pattern = pattern;
            const Mesh m = makeDoubleWedgeBag(p);
            ASSERT_NO_THROW(m.validate());
            EXPECT_EQ(countDuplicateNodes(m, 1e-9), 0);
            const int dia = m.findPanel("diaphragm");
            std::vector<char> outer(m.getNumTris()), inner(m.getNumTris());
            for (int t = 0; t < m.getNumTris(); ++t) {
                outer[t] = m.triPanel[t] != dia;
                inner[t] = !outer[t];
            }
            // The outer surface alone is a closed, consistently oriented 2-manifold.
            EXPECT_EQ(countNonManifoldEdges(m, outer), 0) << "h " << h;
            // Every diaphragm edge is either interior to it (two diaphragm triangles) or an edge
            // of the outer surface (a shared, conforming seam).
            const auto eo = directedEdges(m, outer);
            const auto ed = directedEdges(m, inner);
            int loose = 0;
            for (const auto& [ab, count] : ed) {
                const bool interior = ed.count({ab.second, ab.first}) > 0;
                const bool seam = eo.count(ab) > 0 || eo.count({ab.second, ab.first}) > 0;
                if (!interior && !seam) ++loose;
            }
            EXPECT_EQ(loose, 0);
            // The prism is convex: outer normals point away from an interior point.
            const Vec3 inside(0.35 / 3, 0.0, 0.05);
            int inward = 0;
            for (int t = 0; t < m.getNumTris(); ++t)
                if (outer[t] && triNormal(m, t).dot(triCentroid(m, t) - inside) <= 0) ++inward;
            EXPECT_EQ(inward, 0);
            // Panel normals: base -z, sides -y / +y, diaphragm +x.
            for (int t = 0; t < m.getNumTris(); ++t) {
                const std::string& name = m.panelNames[m.triPanel[t]];
                const Vec3 nrm = triNormal(m, t);
                Vec3 want = Vec3::Zero();
                if (name == "base") want = Vec3(0, 0, -1);
                if (name == "side-front") want = Vec3(0, -1, 0);
                if (name == "side-back") want = Vec3(0, 1, 0);
                if (name == "diaphragm") want = Vec3(1, 0, 0);
                if (want.norm() > 0) {
                    EXPECT_NEAR(nrm.dot(want), 1.0, 1e-12) << name << " triangle " << t;
                }
            }
        }
}

TEST(DoubleWedge, ChambersSplitAtTheDiaphragm) {
    DoubleWedgeParams p;
    const Mesh m = makeDoubleWedgeBag(p);
    const double ax = p.calcApexX();
    const int dia = m.findPanel("diaphragm");
    for (int c = 0; c < 2; ++c) {
        const ChamberBoundary& ch = m.chambers[c];
        const bool steep = ch.name == "wedge-steep";
        for (size_t i = 0; i < ch.tris.size(); ++i) {
            const int t = ch.tris[i];
            if (m.triPanel[t] == dia) {
                EXPECT_EQ(ch.signs[i], steep ? 1 : -1);
            } else {
                EXPECT_EQ(ch.signs[i], 1);
                EXPECT_EQ(triCentroid(m, t).x() < ax, steep);
            }
        }
    }
}

TEST(DoubleWedge, BaseNodesAreSupportsWhenBonded) {
    for (MeshPattern pattern : kAllPatterns) {
        SCOPED_TRACE(getMeshPatternName(pattern));
        DoubleWedgeParams p;
        p.pattern = pattern;
        Mesh m = makeDoubleWedgeBag(p);
        std::set<int> sup(m.supportNodes.begin(), m.supportNodes.end());
        EXPECT_EQ(sup.size(), m.supportNodes.size());
        int onBase = 0;
        for (int n = 0; n < m.getNumNodes(); ++n) {
            const bool base = std::abs(m.X(2, n)) < 1e-12;
            onBase += base;
            EXPECT_EQ(base, sup.count(n) == 1) << "node " << n;
        }
        EXPECT_EQ(onBase, static_cast<int>(sup.size()));
        p.bondBase = false;
        EXPECT_TRUE(makeDoubleWedgeBag(p).supportNodes.empty());
    }
}

TEST(DoubleWedge, QualityAndCountsAtFiveAndTenMillimetres) {
    for (MeshPattern pattern : kAllPatterns)
        for (double h : {0.010, 0.005}) {
            DoubleWedgeParams p;
            p.meshSize = h;
            p.pattern = pattern;
            const MeshQuality q = calcMeshQuality(makeDoubleWedgeBag(p));
            std::cout << "[ wedge   ] " << getMeshPatternName(pattern) << ", h = " << h * 1e3
                      << " mm: " << q.numNodes << " nodes, " << q.numTris
                      << " triangles, min angle " << q.minAngle / kDeg << " deg, max angle "
                      << q.maxAngle / kDeg << " deg, aspect mean " << q.meanAspect << " max "
                      << q.maxAspect << ", edge min/mean/max " << q.minEdge * 1e3 << "/"
                      << q.meanEdge * 1e3 << "/" << q.maxEdge * 1e3 << " mm\n";
            // Targets of the generator: min angle > 25 deg, aspect R/2r < 2 (1 = equilateral),
            // mean edge within 25 % of the mesh size, no edge beyond 2 h.
            EXPECT_GT(q.minAngle, 25 * kDeg);
            EXPECT_LT(q.maxAngle, 120 * kDeg);
            EXPECT_LT(q.maxAspect, 2.0);
            EXPECT_NEAR(q.meanEdge, h, 0.25 * h);
            EXPECT_LT(q.maxEdge, 2.0 * h);
        }
}

TEST(DoubleWedge, MirroredAndCrossedPatternsMapOntoThemselvesAcrossTheMidWidthPlane) {
    // The bag is mirror-symmetric across y = 0; so must its mesh be, or mirror-image load
    // cases (a neighbour at +y or at -y) disagree. 20 mm gives an odd number of cells across
    // the 100 mm width, 25 mm an even one; 0.88 is about the seed reading's profile scale.
    for (double h : {0.025, 0.020, 0.010, 0.0075})
        for (double scale : {1.0, 0.88}) {
            DoubleWedgeParams p;
            p.meshSize = h;
            p.longSide *= scale;
            p.shortSide *= scale;
            p.height *= scale;
            for (MeshPattern pattern : kAllPatterns) {
                p.pattern = pattern;
                const Mesh m = makeDoubleWedgeBag(p);
                ASSERT_NO_THROW(m.validate());
                const int missing = countUnmirroredTris(m);
                if (pattern == MeshPattern::Legacy) {
                    std::cout << "[ mirror  ] legacy, h = " << h * 1e3 << " mm, scale " << scale
                              << ": " << missing << " of " << m.getNumTris()
                              << " triangles have no mirror image\n";
                    // The defect the other patterns remove: most triangles have no mirror image.
                    EXPECT_GT(missing, m.getNumTris() / 2) << "h " << h;
                } else {
                    EXPECT_EQ(missing, 0)
                        << getMeshPatternName(pattern) << ", h " << h << ", scale " << scale;
                }
            }
        }
}

TEST(DoubleWedge, CrossedPatternAddsACentreNodePerCellAndMirroredAnEvenWidthCount) {
    DoubleWedgeParams p;
    p.meshSize = 0.020;  // 100 mm / 20 mm: 5 cells across the width
    const Mesh legacy = makeDoubleWedgeBag(p);
    p.pattern = MeshPattern::Crossed;
    const Mesh crossed = makeDoubleWedgeBag(p);
    p.pattern = MeshPattern::Mirrored;
    const Mesh mirrored = makeDoubleWedgeBag(p);
    // Every cell of the structured panels: two triangles in Legacy, four around one new node
    // in Crossed; the side panels are the same.
    const int cells = crossed.getNumNodes() - legacy.getNumNodes();
    EXPECT_GT(cells, 0);
    EXPECT_EQ(crossed.getNumTris() - legacy.getNumTris(), 2 * cells);
    // Nodes of a base row: one per cell boundary across the width (ny + 1).
    auto countAcross = [](const Mesh& m) {
        int n = 0;
        for (int i = 0; i < m.getNumNodes(); ++i)
            if (m.X(0, i) == 0.0 && m.X(2, i) == 0.0) ++n;
        return n - 1;
    };
    EXPECT_EQ(countAcross(legacy), 5);
    EXPECT_EQ(countAcross(crossed), 5);
    EXPECT_EQ(countAcross(mirrored), 6);
    // Same volume (the panels are flat; only their triangulation differs).
    EXPECT_NEAR(totalVolume(crossed), totalVolume(legacy), 1e-12);
    EXPECT_NEAR(totalVolume(mirrored), totalVolume(legacy), 1e-12);
}

TEST(DoubleWedge, LegacyPatternIsTheMeshOfBefore) {
    // Digests of the double wedge as built before the patterns were added (the default is
    // Legacy): connectivity bit for bit, and node positions to 1e-12 m.
    struct Ref {
        double h;
        int nodes, tris;
        std::uint64_t topology;
        double sumAbsX;
    };
    const Ref refs[] = {
        {0.025, 234, 484, 0x39aca71e7752cc10ull, 56.561391929792634},
        {0.02, 380, 782, 0x61561f051e2e2bd4ull, 91.495409692901077},
        {0.01, 1520, 3090, 0x1a6fa73d88ec28c2ull, 367.68964923703743},
        {0.0075, 2680, 5428, 0x0bf3202983a92f87ull, 648.28136080509262},
        {0.005, 5924, 11952, 0x6491b049f3a300d3ull, 1431.8603595236702},
    };
    for (const Ref& r : refs) {
        DoubleWedgeParams p;
        p.meshSize = r.h;
        const Mesh m = makeDoubleWedgeBag(p);
        EXPECT_EQ(m.getNumNodes(), r.nodes) << "h " << r.h;
        EXPECT_EQ(m.getNumTris(), r.tris) << "h " << r.h;
        EXPECT_EQ(calcTopologyDigest(m), r.topology) << "h " << r.h;
        EXPECT_NEAR(m.X.cwiseAbs().sum(), r.sumAbsX, 1e-12) << "h " << r.h;
    }
}

TEST(DoubleWedge, ElementCountScalesWithInverseSquareOfMeshSize) {
    DoubleWedgeParams p;
    p.meshSize = 0.010;
    const int n10 = makeDoubleWedgeBag(p).getNumTris();
    p.meshSize = 0.005;
    const int n5 = makeDoubleWedgeBag(p).getNumTris();
    // Reference: halving h quadruples the count; tolerance 10 % (rounding of divisions).
    EXPECT_NEAR(static_cast<double>(n5) / n10, 4.0, 0.4);
}

TEST(DoubleWedge, OtherProportionsStillMeshWell) {
    // A steeper, shorter, wider bag and a coarse mesh: still valid and conforming.
    for (const auto& [L, s, W, H, h] :
         std::vector<std::tuple<double, double, double, double, double>>{
             {0.35, 0.16, 0.10, 0.15, 0.01},
             {0.40, 0.3, 0.2, 0.12, 0.02},
             {0.35, 0.2, 0.1, 0.15, 0.05}}) {
        DoubleWedgeParams p;
        p.longSide = L;
        p.shortSide = s;
        p.width = W;
        p.height = H;
        p.meshSize = h;
        const Mesh m = makeDoubleWedgeBag(p);
        EXPECT_NO_THROW(m.validate());
        EXPECT_NEAR(totalVolume(m), p.calcFlatVolume(), 1e-12 * p.calcFlatVolume());
        // The profile's own corners bound the smallest angle: alpha = atan(H / ax) at the
        // steep foot, beta at the gentle foot, and 90 deg - alpha, 90 deg - beta where the
        // diaphragm splits the apex. Require 85 % of the smallest of these, or 25 deg.
        const double ax = p.calcApexX();
        const double alpha = std::atan2(H, ax), beta = std::atan2(H, L - ax);
        const double corner = std::min({alpha, beta, M_PI / 2 - alpha, M_PI / 2 - beta});
        EXPECT_GT(calcMeshQuality(m).minAngle, std::min(25 * kDeg, 0.85 * corner))
            << L << " " << s << " " << W << " " << H;
    }
}

TEST(DoubleWedge, SingleRightAngledWedgeWhenShortSideEqualsHeight) {
    DoubleWedgeParams p;
    p.shortSide = p.height;                             // vertical back wall at x = 0
    EXPECT_THROW(p.validate(), std::invalid_argument);  // a diaphragm would lie on that wall
    p.diaphragm = false;
    const Mesh m = makeDoubleWedgeBag(p);
    EXPECT_NO_THROW(m.validate());
    EXPECT_EQ(countDuplicateNodes(m, 1e-9), 0);
    EXPECT_EQ(countNonManifoldEdges(m, std::vector<char>(m.getNumTris(), 1)), 0);
    // Reference: the same triangular prism, 2.625e-3 m^3; tolerance 1e-12 relative.
    EXPECT_NEAR(totalVolume(m), 2.625e-3, 1e-12 * 2.625e-3);
    EXPECT_NEAR(panelArea(m, "steep"), 0.15 * 0.1, 1e-12);  // the vertical wall
    // Smallest profile corner: atan(0.15 / 0.35) = 23.2 deg at the foot; require 85 % of it.
    EXPECT_GT(calcMeshQuality(m).minAngle, 0.85 * std::atan2(0.15, 0.35));
}

TEST(DoubleWedge, ValidateNamesTheBadParameter) {
    auto message = [](DoubleWedgeParams p) {
        try {
            p.validate();
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    DoubleWedgeParams p;
    EXPECT_EQ(message(p), "");
    p.shortSide = 0.15;  // not longer than the height: no apex
    EXPECT_NE(message(p).find("shortSide"), std::string::npos);
    p = DoubleWedgeParams{};
    p.longSide = 0.1;  // apex x is 0.132 m
    EXPECT_NE(message(p).find("longSide"), std::string::npos);
    p = DoubleWedgeParams{};
    p.width = -0.1;
    EXPECT_NE(message(p).find("width"), std::string::npos);
    p = DoubleWedgeParams{};
    p.meshSize = 0.0005;
    EXPECT_NE(message(p).find("meshSize"), std::string::npos);
    p.meshSize = 0.06;  // above half the width (0.05 m)
    EXPECT_NE(message(p).find("meshSize"), std::string::npos);
    p = DoubleWedgeParams{};
    p.height = std::nan("");
    EXPECT_NE(message(p).find("height"), std::string::npos);
    p = DoubleWedgeParams{};
    p.shortSide = 0.15;
    EXPECT_THROW(makeDoubleWedgeBag(p), std::invalid_argument);
}

// ------------------------------------------------------------------------------------------
// Box, sphere, cushion, disk

TEST(BoxBag, ClosedConformingWithBondedBottom) {
    const Mesh m = makeBoxBag(0.35, 0.1, 0.15, 0.01);
    EXPECT_NO_THROW(m.validate());
    EXPECT_EQ(countDuplicateNodes(m, 1e-9), 0);
    EXPECT_EQ(countNonManifoldEdges(m, std::vector<char>(m.getNumTris(), 1)), 0);
    // Bottom of 36 x 11 nodes (35 x 10 divisions) bonded.
    EXPECT_EQ(m.supportNodes.size(), 36u * 11u);
    for (int n : m.supportNodes) EXPECT_EQ(m.X(2, n), 0.0);
    const MeshQuality q = calcMeshQuality(m);
    // Square cells split in two: right isosceles triangles, angles 45 and 90 deg.
    EXPECT_NEAR(q.minAngle, 45 * kDeg, 1e-9);
    EXPECT_NEAR(q.maxAngle, 90 * kDeg, 1e-9);
}

TEST(Sphere, VolumeConvergesToBallFromBelow) {
    const double r = 0.2, ball = 4.0 / 3.0 * M_PI * r * r * r;
    double prevErr = 0.0;
    for (int k = 1; k <= 5; ++k) {
        const Mesh m = makeSphere(r, k);
        ASSERT_NO_THROW(m.validate());
        EXPECT_EQ(m.getNumTris(), 20 << (2 * k));
        for (int n = 0; n < m.getNumNodes(); ++n) EXPECT_NEAR(m.X.col(n).norm(), r, 1e-15);
        const double V = calcChamberVolume(m, 0, m.X);
        // The inscribed convex polyhedron holds the ball through its nearest face and lies in
        // the circumscribed ball: (d_min / r)^3 V_ball <= V < V_ball.
        double dmin = r;
        for (int t = 0; t < m.getNumTris(); ++t)
            dmin = std::min(dmin, triNormal(m, t).dot(m.X.col(m.tris(0, t))));
        EXPECT_LT(V, ball);
        EXPECT_GE(V, std::pow(dmin / r, 3) * ball);
        const double err = (ball - V) / ball;
        std::cout << "[ sphere  ] refinements " << k << ": " << m.getNumTris()
                  << " triangles, relative volume deficit " << err << "\n";
        // Piecewise-flat error is O(h^2): each refinement cuts it by about 4 (3.6..4.4).
        if (k > 1) {
            EXPECT_GT(prevErr / err, 3.6);
            EXPECT_LT(prevErr / err, 4.4);
        }
        prevErr = err;
    }
}

TEST(SquareCushion, FrustumVolumeAndSheetNormals) {
    const double e = 0.8485, gap = 0.02;
    const int n = 10;
    const Mesh m = makeSquareCushion(e, n, gap);
    EXPECT_NO_THROW(m.validate());
    EXPECT_EQ(countDuplicateNodes(m, 1e-9), 0);
    EXPECT_EQ(countNonManifoldEdges(m, std::vector<char>(m.getNumTris(), 1)), 0);
    EXPECT_EQ(m.getNumNodes(), 2 * 121 - 40);  // rim nodes (4 n) shared
    for (int t = 0; t < m.getNumTris(); ++t) {
        const std::string& name = m.panelNames[m.triPanel[t]];
        EXPECT_GT(triNormal(m, t).z() * (name == "top" ? 1 : -1), 0.0);
    }
    // The union-jack split makes each half an exact frustum of a square pyramid: bases e and
    // a = e (n - 2) / n, height gap / 2: V = 2 (gap/2) / 3 (e^2 + e a + a^2); tolerance 1e-12.
    const double a = e * (n - 2) / n;
    const double ref = 2.0 * (0.5 * gap) / 3.0 * (e * e + e * a + a * a);
    EXPECT_NEAR(calcChamberVolume(m, 0, m.X), ref, 1e-12 * ref);
    // Flat (gap 0): zero volume, still a valid closed chamber.
    const Mesh flat = makeSquareCushion(e, n, 0.0);
    EXPECT_NO_THROW(flat.validate());
    EXPECT_NEAR(calcChamberVolume(flat, 0, flat.X), 0.0, 1e-15);
}

TEST(SquareCushion, MeshIsSymmetricUnderMirrorAndDiagonalReflection) {
    const Mesh m = makeSquareCushion(1.0, 8, 0.0);
    // The set of top-sheet edge midpoints must map onto itself under x -> -x, y -> -y, x <-> y.
    std::set<std::pair<long, long>> mids;
    const int top = m.findPanel("top");
    for (int t = 0; t < m.getNumTris(); ++t)
        if (m.triPanel[t] == top)
            for (int k = 0; k < 3; ++k) {
                const Vec3 mid = 0.5 * (m.X.col(m.tris(k, t)) + m.X.col(m.tris((k + 1) % 3, t)));
                mids.insert({std::lround(mid.x() * 1e6), std::lround(mid.y() * 1e6)});
            }
    for (const auto& [x, y] : mids) {
        EXPECT_TRUE(mids.count({-x, y}));
        EXPECT_TRUE(mids.count({x, -y}));
        EXPECT_TRUE(mids.count({y, x}));
    }
}

TEST(Disk, RimIsSupportedAndTrianglesAreNearlyEquilateral) {
    const double R = 0.1;
    const int rings = 12;
    const Mesh m = makeDisk(R, rings);
    EXPECT_NO_THROW(m.validate());
    EXPECT_EQ(m.getNumNodes(), 1 + 3 * rings * (rings + 1));  // 1 + sum 6k
    EXPECT_EQ(m.getNumTris(), 6 * rings * rings);
    EXPECT_EQ(m.supportNodes.size(), 6u * rings);
    for (int n : m.supportNodes) EXPECT_NEAR(m.X.col(n).norm(), R, 1e-15);
    for (int t = 0; t < m.getNumTris(); ++t) EXPECT_GT(triNormal(m, t).z(), 0.0);
    // Reference: the inscribed 72-gon's area, 0.5 N R^2 sin(2 pi / N); tolerance 1e-12.
    const int N = 6 * rings;
    EXPECT_NEAR(m.calcTriangleAreas().sum(), 0.5 * N * R * R * std::sin(2 * M_PI / N), 1e-12);
    const MeshQuality q = calcMeshQuality(m);
    std::cout << "[ disk    ] rings " << rings << ": min angle " << q.minAngle / kDeg
              << " deg, max aspect " << q.maxAspect << "\n";
    EXPECT_GT(q.minAngle, 30 * kDeg);
    EXPECT_LT(q.maxAspect, 1.6);
}

TEST(PlaceCopies, CopiesKeepTheirVolumesAndNamesAndRefuseNonRigidPoses) {
    // Reference: each copy is the bag moved rigidly, so each copy's chamber volumes equal the
    // bag's (to 1e-12 relative) and the copy's nodes follow those of the one before.
    bags::DoubleWedgeParams p;
    p.meshSize = 0.03;
    const bags::Mesh bag = bags::makeDoubleWedgeBag(p);
    Eigen::Isometry3d a = Eigen::Isometry3d::Identity(), b = Eigen::Isometry3d::Identity();
    b.translation() = Eigen::Vector3d(0.0, 0.11, 0.0);
    b.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const bags::Mesh two = bags::placeCopies(bag, {a, b});
    two.validate();
    ASSERT_EQ(two.getNumNodes(), 2 * bag.getNumNodes());
    ASSERT_EQ(two.chambers.size(), 2 * bag.chambers.size());
    EXPECT_EQ(two.chambers[bag.chambers.size()].name, "bag1/" + bag.chambers[0].name);
    EXPECT_EQ(two.supportNodes.size(), 2 * bag.supportNodes.size());
    for (size_t c = 0; c < bag.chambers.size(); ++c) {
        const double v = bags::calcChamberVolume(bag, static_cast<int>(c), bag.X);
        for (size_t k = 0; k < 2; ++k)
            EXPECT_NEAR(
                bags::calcChamberVolume(two, static_cast<int>(c + k * bag.chambers.size()), two.X),
                v, 1e-12 * std::abs(v));
    }
    Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
    scaled.linear() *= 1.1;
    EXPECT_THROW(bags::placeCopies(bag, {a, scaled}), std::invalid_argument);
    EXPECT_THROW(bags::placeCopies(bag, {}), std::invalid_argument);
}
