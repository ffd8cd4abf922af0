#pragma once
/// @file Parametric airbag geometries and meshes for the bags solver and its verification
/// cases. All dimensions [m]; the mesh size is the target triangle edge length [m].

#include <bags/Mesh.h>

#include <Eigen/Geometry>

#include <vector>

namespace bags {

/// How the double wedge's structured panels (base, sloped sides, internal wall: rectangular
/// cells of about meshSize) are split into triangles. The side profiles are triangulated
/// row by row in every pattern. See docs/geometry.md#mesh-patterns.
enum class MeshPattern {
    /// Two triangles per cell, diagonals alternating from cell to cell; a cell and its mirror
    /// image across the bag's mid-width plane (y = 0) take the same diagonal, so most
    /// triangles have no mirror image (the pattern of every result before the option).
    Legacy,
    /// Two triangles per cell, alternating as Legacy on the y < 0 half and mirrored onto the
    /// y > 0 half; an even number of cells across the width. Maps onto itself under y -> -y.
    Mirrored,
    /// Four triangles per cell around a node at the cell's centre: symmetric under both
    /// reflections of every cell, with no preferred diagonal (one node more per cell).
    Crossed,
};

/// The scenario's name of a pattern ("legacy", "mirrored", "crossed").
const char* getMeshPatternName(MeshPattern pattern);

/// The seed study's double-wedge airbag (see docs/geometry.md for the shape and why).
/// Side profile in the x-z plane: a triangle with the long side on the bed board (z = 0),
/// apex at height `height`, one sloped side of length `shortSide`; extruded along y by
/// `width`. An internal vertical diaphragm under the apex splits it into two wedge chambers
/// ("wedge-steep", "wedge-gentle") joined by the intermediate connection. Without the
/// diaphragm and with shortSide == height it is a single right-angled wedge.
struct DoubleWedgeParams {
    double longSide = 0.350;                    ///< base length [m]
    double shortSide = 0.200;                   ///< steep sloped side [m]
    double width = 0.100;                       ///< extrusion width [m]
    double height = 0.150;                      ///< apex height of the panel layout [m]
    double meshSize = 0.010;                    ///< target element edge [m]
    MeshPattern pattern = MeshPattern::Legacy;  ///< how the structured panels' cells are split
    bool diaphragm = true;  ///< build the internal wall (two chambers); false: one chamber
    bool bondBase = true;   ///< base panel nodes are support nodes
    /// Throws std::invalid_argument naming the parameter if the geometry is impossible.
    void validate() const;
    /// x of the apex (and of the diaphragm), sqrt(shortSide^2 - height^2) [m].
    double calcApexX() const;
    /// Volume of the flat-panel (unstretched) shape, longSide * height * width / 2 [m^3].
    double calcFlatVolume() const;
};
Mesh makeDoubleWedgeBag(const DoubleWedgeParams& p);

/// Copies of one bag's mesh, copy k placed by poses[k] (rigid: rotation and translation of its
/// reference nodes), as one mesh: nodes, triangles, panels and chambers of copy k follow those
/// of copy k-1 (each copy has bag.getNumNodes() nodes, so copy k's nodes start at
/// k * bag.getNumNodes()); panel and chamber names get the prefix "bag<k>/". Support nodes and
/// fixed dofs are copied (a fixed dof names a Ground direction, so rotated copies keep only
/// those of copies whose rotation is the identity). @throws std::invalid_argument for no
/// poses or a pose that is not a rigid motion.
Mesh placeCopies(const Mesh& bag, const std::vector<Eigen::Isometry3d>& poses);

/// Rectangular box bag lx x ly x lz with the base on z = 0, centred on x = y = 0 (one chamber
/// "box"; panels "bottom", "top", "side-x-minus", "side-x-plus", "side-y-minus", "side-y-plus").
Mesh makeBoxBag(double lx, double ly, double lz, double meshSize, bool bondBase = true);

/// Sphere of radius r centred at the origin (icosphere, `refinements` subdivisions), one
/// chamber, no supports (caller fixes rigid modes, e.g. through Mesh::fixedDofs).
Mesh makeSphere(double r, int refinements);

/// Square cushion of two flat square sheets of edge `edge` welded at their rim, reference
/// configuration flat (top at z = +gap/2, bottom at z = -gap/2), `n` divisions per edge.
/// Rim nodes shared (they lie at z = 0, so with gap > 0 the outermost ring of triangles is
/// slightly tilted). One chamber. For the inflated-square-airbag benchmark.
Mesh makeSquareCushion(double edge, int n, double gap = 0.0);

/// Flat circular disk of radius r in the x-y plane, normals +z, rim nodes in supportNodes.
/// It has one open chamber made of all its triangles: with the rim fixed, the volume formula
/// measures the volume swept from the flat state, so a pressure on it is a follower load
/// (Hencky's clamped membrane). `rings` radial divisions.
Mesh makeDisk(double r, int rings);

}  // namespace bags
