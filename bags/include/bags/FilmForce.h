#pragma once
/// @file The film's forces for the explicit step (bags/Dynamics.h): the gradient of a
/// MembraneModel's total potential, what MembraneModel::addEnergy gives without its Hessian,
/// in a few fused passes over the mesh with the per-element and per-hinge constants kept and
/// no heap allocation in its own passes (the contacts' terms are the model's own).
/// docs/solver.md#the-film-in-time, docs/performance.md#the-film-in-time-2026-12-06.
///
/// Order of calls: construct from the model once its mesh, material, element frames, bending
/// stiffness and Prony series are set; then addGradient(x, acc) every sub-step. What changes
/// from step to step (gases, prescribed pressures, the viscous step and state, contacts,
/// gravity, stabilisation) is read from the model on every call.
///
/// The passes, each over elements, hinges or nodes:
///  1. elements: deformation, stress and nodal forces into the element's own slots, the
///     triangle's volume term and its normal N / |N|^2;
///  2. hinges: the angle's change from rest from the wing triangles' normals (one atan2 of
///     the angle rotated by the rest angle), the hinge's length and its wings' alphas;
///  3. the chambers' volumes, summed in their fixed order, and their pressures; the hinges'
///     moments from the constant hinge stiffness (DiscreteBending::calcHingeStiffness);
///  4. elements: the pressures' forces and the bending forces of the hinges on their edges
///     (each along the triangle's normal) added into their slots;
///  5. nodes: each gathers its elements' slots in element order (on one thread each element
///     is added as it is finished, which is the same order).
/// Every slot is computed on its own and every sum runs in one fixed order, so the result is
/// the same bits for any number of threads. Then gravity, stabilisation and rigid and self
/// contact add theirs through the model's own terms.
///
/// The film's law runs inline where it is an InvariantPolynomial (neo-Hooke, Mooney-Rivlin,
/// Yeoh), alone or under its tension field (WrinklingMaterial, with or without its own residual
/// law), with or without fabric yarns (FabricMaterial) and Prony branches; any other law
/// (Ogden, St. Venant-Kirchhoff) goes through its virtual calcEnergy, stress only.
///
/// A collapsed hinge wing is a collapsed element (det C <= 1e-12), reported as one.
/// Not thread-safe: one call at a time per object (its scratch is its own).

#include <bags/MembraneModel.h>
#include <bags/Types.h>

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace bags {

/// atan2(y, x) [rad] in [-pi, pi] within 2 ulp of std::atan2 for finite arguments (0 for
/// y = x = 0), at a third of its cost: the kernel's hinge angles.
double calcAtan2(double y, double x);

class FilmForce {
  public:
    /// Keeps a reference to `model` (which must outlive this object) and its constants.
    /// @throws std::invalid_argument if the model's element frames are not set.
    explicit FilmForce(const MembraneModel& model);

    /// Adds dE/dx [N] at x (3 x N, [m]) into acc.grad (resized to 3N if it is empty); acc.hess
    /// is left alone. With `withEnergy` adds E [J] into acc.energy; without, acc.energy becomes
    /// NaN (the contacts' energy alone would mislead).
    /// @throws NumericalError for a collapsed element (det C <= 1e-12, or a viscous branch
    /// likewise; the lowest one named) or a non-positive gas volume.
    void addGradient(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc,
                     bool withEnergy = false) const;

    /// True if the film's law runs inline (see the file comment); false: virtual calls.
    bool isLawInline() const;
    /// Threads the passes run on: the model's (0: the OpenMP default) where its elements are
    /// chunked (MembraneModel::setElementChunks, or more than 4000 triangles), else one.
    int getNumThreads() const;

    /// The film's law as the kernel evaluates it (public for the source's helpers only).
    struct Law;

  private:
    template <bool withEnergy>
    void addGradientImpl(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;

    struct Element {
        int n[3];
        double d1x, d1y, d2x, d2y;  ///< shape-function gradients of nodes 1 and 2 [1/m]
        double vol;                 ///< reference volume [m^3]
    };
    struct HingeData {
        int n[4];                 ///< x0, x1 (the edge), x2, x3 (the wings' far nodes)
        int tri[2];               ///< the wing triangles (of x2, of x3)
        double sign[2];           ///< NA (NB) = sign x the wing triangle's normal
        double cosRest, sinRest;  ///< of the rest angle
    };
    struct TriHinges {                       ///< a triangle's view of the hinges on its edges
        int hinge[3] = {-1, -1, -1};         ///< of the edge opposite vertex i, -1: none
        double sign[3] = {0.0, 0.0, 0.0};    ///< HingeData::sign of this wing
        unsigned char wing[3] = {0, 0, 0};   ///< 0: the hinge's wing A (x2), 1: B (x3)
        unsigned char edge0[3] = {0, 0, 0};  ///< local vertex that is the hinge's x0
        unsigned char edge1[3] = {0, 0, 0};  ///< local vertex that is the hinge's x1
    };
    const MembraneModel* m_model;
    std::shared_ptr<const Law> m_law;
    std::vector<Element> m_elements;
    /// Per element, CSR: its chambers and signs (+1: its normal points out of the chamber).
    std::vector<int> m_triChamberStart, m_triChamber;
    std::vector<double> m_triChamberSign;
    std::vector<char> m_inChamber;  ///< per element: bounds some chamber
    std::vector<HingeData> m_hinges;
    std::vector<TriHinges> m_triHinges;
    std::vector<int> m_couplingStart, m_couplingHinge;  ///< CSR rows of the hinge stiffness
    std::vector<double> m_coupling;                     ///< [N m]
    /// Per node, CSR: its element slots (9 e + 3 a), in element order.
    std::vector<int> m_nodeElemStart, m_nodeElemSlot;

    // Scratch, sized once.
    mutable std::vector<double> m_elemForce;    ///< 9 per element [N]
    mutable std::vector<double> m_elemEnergy;   ///< per element [J] (energy wanted)
    mutable std::vector<double> m_volume6;      ///< per element: x0 . (x1 x x2) [m^3]
    mutable std::vector<double> m_triNormal;    ///< 3 per element: N / |N|^2 [1/m^2]
    mutable std::vector<double> m_hingeShape;   ///< 3 per hinge: L [m], alpha_A, alpha_B [-]
    mutable std::vector<double> m_dtheta;       ///< per hinge [rad]
    mutable std::vector<double> m_moment;       ///< per hinge [N m]
    mutable std::vector<double> m_wingScale;    ///< per hinge: -moment L [N m^2]
    mutable std::vector<double> m_chamberCoef;  ///< per chamber: -p / 6 [Pa]
};

}  // namespace bags
