#pragma once
/// @file Bending stiffness of the membrane: a rotation-free discrete Kirchhoff plate built on
/// the dihedral (hinge) angles of the triangle mesh.
///
/// Model. Each interior edge e is a hinge with dihedral angle theta_e (0 when its two triangles
/// are coplanar) and a rest angle from the reference X. Each triangle T gets a constant
/// curvature change from the hinge angles of its own three edges (the shape operator of
/// Grinspun, Gingold, Reisman & Zorin 2006, "Computing discrete shape operators on general
/// meshes"; the rotation-free Morley triangle with mid-edge slopes averaged over the two
/// triangles, as in the BST/S3 shells of Onate & Zarate 2000 and Sabourin & Brunet 2006):
///   dK_T = sum_i (theta_i - restTheta_i) |e_i| / (2 A_T) n_i n_i^T
/// (|e_i| the reference length of edge i, A_T the reference area, n_i the in-plane unit normal
/// of edge i, all in the reference configuration), and the Kirchhoff plate energy
///   E = sum_T A_T D/2 [ nu (tr dK)^2 + (1 - nu) dK : dK ],  D [N m] the bending stiffness,
/// which is (D/2)(kappa1^2 + kappa2^2 + 2 nu kappa1 kappa2) per area. The energy is a quadratic
/// form in the hinge angles, E = 1/2 d^T M d with d = theta - restTheta and M a constant
/// sparse matrix (hinges couple when they share a triangle).
///
/// Why not a pure hinge energy (Grinspun et al. 2003 "Discrete Shells", Bridson et al. 2003,
/// the quadratic model of Bergou et al. 2006, all sum_e k |e|^2/A_e theta_e^2 per edge): it is
/// not consistent. On the right-triangle grid bent into a cylinder about a grid line only the
/// grid-line hinges fold, and the per-edge energy is 3x the plate energy at every refinement
/// (its 1/3-per-edge area share assumes the curvature is spread over all three edge
/// directions). The per-triangle shape operator is exact there and converges for oblique bends
/// (docs/verification.md); it costs one extra coupling between the hinges of each triangle.
///
/// Free (boundary) edges contribute nothing to their triangle's curvature (the mid-edge slope
/// is the triangle's own): the energy of a bent strip misses a band of about half a triangle
/// along its free edges, an O(h) error in the total that vanishes under refinement.
///
/// Which edges are hinges: an edge of exactly two triangles is one (also across panel seams,
/// with the seam's reference angle as rest angle, unless seams are switched off: then a seam is
/// a free hinge). An edge of more than two triangles (where the diaphragm is welded to the
/// walls) gets one hinge per panel that has exactly two triangles there (the wall carries on
/// bending across the weld; the diaphragm and the three-sheet apex ridge hinge freely).
///
/// Valid range: a hinge's change from its rest angle, |theta - restTheta| < pi (the change is
/// taken on the branch nearest to rest, so a hinge may fold through theta = +-pi, the two
/// triangles flat on each other; at a change of +-pi the energy jumps). Energy, gradient and the full exact
/// Hessian (the Gauss-Newton part M's plus the angle curvature term); deterministic (one fixed
/// order, serial) and the Hessian has the same triplet sequence every call.

#include <bags/Mesh.h>
#include <bags/Types.h>

#include <array>
#include <vector>

namespace bags {

/// Plate bending stiffness D = E t^3 / (12 (1 - nu^2)) [N m] of a homogeneous sheet.
/// @pre youngsModulus > 0 [Pa], 0 <= poisson < 1, thickness > 0 [m]; else std::invalid_argument.
double calcPlateBendingStiffness(double youngsModulus, double poisson, double thickness);

class MembraneMaterial;
/// Plate bending stiffness [N m] of a homogeneous incompressible film of this material:
/// E = 3 mu (small-strain Young's modulus, mu = getInitialShearModulus()), nu = 0.5.
double calcPlateBendingStiffness(const MembraneMaterial& material, double thickness);

/// Signed dihedral angle [rad] of the hinge of triangles (x0, x1, x2) and (x1, x0, x3) on edge
/// x0-x1, in (-pi, pi]: 0 when coplanar, positive when the wings x2 and x3 move against their
/// triangles' normals ((x1-x0) x (x2-x0) and (x3-x0) x (x1-x0)). If grad (12: x0,x1,x2,x3)
/// or hess (12 x 12) are given, also its exact derivatives. @pre both triangles non-degenerate.
double calcHingeAngle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3,
                      Eigen::Matrix<double, 12, 1>* grad = nullptr,
                      Eigen::Matrix<double, 12, 12>* hess = nullptr);

struct BendingOptions {
    double stiffness = 0.0;  ///< plate bending stiffness D [N m]
    double poisson = 0.5;    ///< Poisson's ratio of the plate law [-] (0.5: incompressible)
    bool seamsBend = true;   ///< edges between two panels' triangles are hinges (rest: X)
    void validate() const;   ///< throws std::invalid_argument naming the option
};

/// The bending energy of a mesh; topology and reference data are built once, addEnergy() is
/// called every Newton iteration.
class DiscreteBending {
  public:
    /// @throws std::invalid_argument for bad options or a degenerate reference triangle.
    DiscreteBending(const Mesh& mesh, const BendingOptions& options);

    const BendingOptions& getOptions() const { return m_options; }
    int getNumHinges() const { return static_cast<int>(m_hinges.size()); }
    /// Nodes of hinge h: edge x0-x1, wings x2 and x3 (calcHingeAngle's order).
    const std::array<int, 4>& getHingeNodes(int h) const { return m_hinges[h].nodes; }
    /// Rest (reference) angle of hinge h [rad].
    double getRestAngle(int h) const { return m_hinges[h].restAngle; }

    /// Adds the bending energy [J], gradient [N] and Hessian [N/m] at x (as acc's want flags
    /// say). @throws NumericalError if a hinge triangle collapsed (when derivatives are wanted;
    /// energy only: acc.energy becomes +inf).
    void addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    /// As above, the hinges' angles and gradients on up to `threads` threads (0: the OpenMP
    /// default); bit-identical for any number.
    void addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc, int threads) const;
    /// Bending energy [J] at x alone.
    double calcEnergy(const Eigen::Matrix3Xd& x) const;
    /// The constant matrix K [N m] of the energy as a quadratic form in the hinges' changes
    /// from rest, E = 1/2 d^T K d: triplets (h, k, K_hk), one per pair of hinges of each
    /// plate, duplicates to be summed.
    std::vector<Triplet> calcHingeStiffness() const;

  private:
    struct Hinge {
        std::array<int, 4> nodes;
        double restAngle;
    };
    struct Plate {                  ///< a triangle with at least one hinge
        std::array<int, 3> hinges;  ///< hinge of edge i (opposite vertex i), -1: free edge
        Eigen::Matrix3d M;          ///< d2E/dtheta_i dtheta_j [N m], signs included
        int numNodes;               ///< distinct nodes of its hinges (<= 6)
        std::array<int, 6> nodes;
        std::array<std::array<int, 4>, 3> local;  ///< local node of hinge i's node k
        std::array<int, 36> slots;                ///< Hessian block slot of local pair (a,b), 6a+b
        std::array<bool, 3> ownsHinge;            ///< adds hinge i's angle-curvature Hessian term
    };
    BendingOptions m_options;
    int m_numNodes = 0;
    std::vector<Hinge> m_hinges;
    std::vector<Plate> m_plates;
    std::vector<std::pair<int, int>> m_blocks;  ///< node pairs of the Hessian, sorted
};

}  // namespace bags
