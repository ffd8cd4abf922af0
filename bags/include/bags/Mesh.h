#pragma once
/// @file A closed (or open) triangulated membrane surface: reference geometry, panels,
/// gas chambers and supported nodes.
///
/// The reference configuration X is stress-free: the flat panels the bag is sewn or welded
/// from, placed in 3D. Triangles are oriented so their normal (x1-x0) x (x2-x0) points out of
/// the bag for outer walls. A chamber is bounded by a closed set of triangles; each carries a
/// sign, +1 if its normal points out of that chamber, -1 if into it (an internal diaphragm
/// between two chambers appears in both, once with each sign).

#include <bags/Types.h>

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace bags {

/// The triangles that close one gas chamber, with orientation signs.
struct ChamberBoundary {
    std::string name;
    std::vector<int> tris;   ///< triangle indices into Mesh::tris
    std::vector<int> signs;  ///< +1: triangle normal points out of the chamber; -1: into it
};

struct Mesh {
    Eigen::Matrix3Xd X;                   ///< reference node positions, Ground [m]
    Eigen::Matrix3Xi tris;                ///< node indices of each triangle (columns)
    std::vector<int> triPanel;            ///< panel index of each triangle
    std::vector<std::string> panelNames;  ///< name of each panel ("bottom", "side-left", ...)
    std::vector<ChamberBoundary> chambers;
    std::vector<int> supportNodes;  ///< nodes bonded to the bed board (fixed), if any
    std::vector<int> fixedDofs;     ///< extra fixed dofs (3*node+dir), e.g. symmetry planes

    int getNumNodes() const { return static_cast<int>(X.cols()); }
    int getNumTris() const { return static_cast<int>(tris.cols()); }

    /// Lumped reference area per node [m^2] (one third of each adjacent triangle).
    Eigen::VectorXd calcNodalAreas() const;
    /// For each node, the nodes it shares a triangle with, sorted (itself excluded).
    std::vector<std::vector<int>> calcNodeNeighbours() const;
    /// Reference area of each triangle [m^2].
    Eigen::VectorXd calcTriangleAreas() const;
    /// Checks indices, panels, non-degenerate triangles, orientation signs and that each
    /// chamber is closed and consistently oriented (after flipping its sign -1 triangles,
    /// every edge is used as often in one direction as in the other) or, if open, that all
    /// nodes on its open edges are support nodes (then its volume is measured from the fixed
    /// rim); throws std::invalid_argument with the reason.
    void validate() const;

    /// Index of the panel called `name`, -1 if there is none.
    int findPanel(const std::string& name) const;
    /// Index of the chamber called `name`, -1 if there is none.
    int findChamber(const std::string& name) const;
};

/// Shape statistics of a mesh's reference triangles (for choosing and reporting mesh sizes).
struct MeshQuality {
    int numNodes = 0;         ///< number of nodes
    int numTris = 0;          ///< number of triangles
    double minAngle = 0.0;    ///< smallest interior angle of any triangle [rad]
    double maxAngle = 0.0;    ///< largest interior angle of any triangle [rad]
    double meanAspect = 0.0;  ///< mean R/(2 r), circumradius over twice inradius (1: equilateral)
    double maxAspect = 0.0;   ///< largest R/(2 r)
    double minEdge = 0.0;     ///< shortest edge [m]
    double meanEdge = 0.0;    ///< mean edge length over triangles' edges [m]
    double maxEdge = 0.0;     ///< longest edge [m]
};

/// Triangle shape statistics of the reference configuration mesh.X.
MeshQuality calcMeshQuality(const Mesh& mesh);

/// Enclosed volume [m^3] of chamber `c` at deformed positions x (3 x N) by the divergence
/// theorem, V = 1/6 sum sign * x0 . (x1 x x2). If acc is given, adds scale*V to acc.energy,
/// scale*dV/dx to acc.grad and scale*d2V/dx2 to acc.hess (as acc's want* flags say).
double calcChamberVolume(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x,
                         EnergyAccumulator* acc = nullptr, double scale = 1.0);

/// dV/dx of chamber c as a dense 3N vector [m^2].
Eigen::VectorXd calcChamberVolumeGradient(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x);

/// Adds scale*dV/dx of chamber c into `grad` (size 3N) without allocating; returns V [m^3].
double addChamberVolumeGradient(const Mesh& mesh, int c, const Eigen::Matrix3Xd& x,
                                Eigen::VectorXd& grad, double scale = 1.0);

}  // namespace bags
