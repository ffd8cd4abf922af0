#pragma once
/// @file Contact of membrane nodes with rigid analytic shapes (penalty, Coulomb friction) and
/// of the membrane with itself.
///
/// Order of calls in a load step: beginStep(x, dt) at the committed state (the regularised
/// friction law measures the slip from there), set the shapes' poses, then, inside the Newton loop,
/// addEnergy() for every trial x; once the step has converged, commitStep(x) (friction
/// anchors move with the slip). Results (forces on the rigid shape, nodal pressures) are read
/// with calc...() at the converged x.

#include <bags/Mesh.h>
#include <bags/Types.h>

#include <Eigen/Geometry>

#include <bags/StateStream.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace bags {

/// A rigid solid with an analytic surface, posed in Ground by X_GS (shape frame S).
class RigidShape {
  public:
    virtual ~RigidShape() = default;
    /// Signed distance [m] of Ground point p to the surface, negative inside the solid.
    /// Also the closest surface point and the outward unit normal there (Ground), if asked.
    virtual double calcSignedDistance(const Vec3& p_G, Vec3* closest_G, Vec3* normal_G) const = 0;
    /// Gradient-of-normal d n / d p (3x3, Ground) at p: the surface curvature seen from p;
    /// zero for flat faces. Used in the contact tangent.
    virtual Mat3 calcNormalDerivative(const Vec3& p_G) const = 0;
    /// Everything the contact law needs at p in one evaluation (any output may be null):
    /// signed distance [m], closest point and outward normal (Ground), d n / d p [1/m].
    virtual void calcContactGeometry(const Vec3& p_G, double* distance, Vec3* closest_G,
                                     Vec3* normal_G, Mat3* dndp_G) const;
    /// Radius [m] of a sphere about the frame origin that contains the solid (infinite for
    /// the plane); lets callers skip far nodes cheaply.
    virtual double getBoundingRadius() const;
    /// A cheap lower bound [m] of the signed distance at p (Ground), used to skip far nodes.
    virtual double calcDistanceLowerBound(const Vec3& p_G) const;
    /// Radius [m] of a sphere about the frame origin that holds every point whose
    /// calcDistanceLowerBound() is at most t: further out the bound is above t, so a caller
    /// may skip such points without asking (infinite when no sphere holds them). A shape
    /// that overrides calcDistanceLowerBound() overrides this with it.
    virtual double getLowerBoundReach(double t) const;
    virtual std::string getName() const = 0;
    void setPose(const Eigen::Isometry3d& X_GS) { m_X_GS = X_GS; }
    const Eigen::Isometry3d& getPose() const { return m_X_GS; }

  protected:
    Eigen::Isometry3d m_X_GS = Eigen::Isometry3d::Identity();
};

/// A shape that evaluates everything in its own frame S in one pass: derived classes give
/// evalLocal(); the distance queries and the transforms to and from Ground are done here.
class LocalRigidShape : public RigidShape {
  public:
    double calcSignedDistance(const Vec3& p_G, Vec3* closest_G, Vec3* normal_G) const override;
    Mat3 calcNormalDerivative(const Vec3& p_G) const override;
    void calcContactGeometry(const Vec3& p_G, double* distance, Vec3* closest_G, Vec3* normal_G,
                             Mat3* dndp_G) const override;

  protected:
    /// Signed distance d, closest point c, unit outward normal n and d n / d p, all in S.
    virtual void evalLocal(const Vec3& p, double& d, Vec3& c, Vec3& n, Mat3* dn) const = 0;
};

/// Half-space below the plane through the frame origin with normal +z of the frame.
std::unique_ptr<RigidShape> makePlane();
/// Box with half-extents h [m], edges rounded by radius r [m] (r < min(h)).
std::unique_ptr<RigidShape> makeBox(const Vec3& halfExtents, double edgeRadius = 0.0);
/// Ellipsoid with semi-axes a [m] along the frame axes.
std::unique_ptr<RigidShape> makeEllipsoid(const Vec3& semiAxes);
/// Capsule: segment from -halfLength to +halfLength along frame z, radius r [m].
std::unique_ptr<RigidShape> makeCapsule(double radius, double halfLength);

/// Penalty contact of a set of membrane nodes with one rigid shape, with regularised Coulomb
/// friction. Penalty stiffness per node = pressurePenalty * nodal reference area, so the
/// contact pressure at a node is pressurePenalty * penetration [Pa]. With a tissue layer
/// (Options::tissueThickness) the penetration is shared between the layer's compression c and
/// the penalty: p = pressurePenalty * (penetration - c) = sigma(c), sigma the layer's law
/// (calcTissueStress).
class RigidContact {
  public:
    /// How the tangential force follows the slip (docs/contact.md).
    enum class FrictionLaw {
        /// An elastic stick spring (stickStiffnessRatio) to an anchor, capped at mu f_n; the
        /// anchor keeps the spring's offset from step to step.
        StickSlip,
        /// Coulomb regularised by the slip rate over the step: f_t = -mu f_n s / sqrt(|s|^2 +
        /// (v_s dt)^2), s the film's slip on the shape since the step began and dt its time
        /// (beginStep), v_s = slipVelocity. Viscous below v_s, mu f_n above.
        Regularised
    };
    struct Options {
        double pressurePenalty = 1e7;  ///< [Pa/m]: 1 mm penetration carries 10 kPa
        double friction = 0.0;         ///< Coulomb coefficient (0 = frictionless)
        FrictionLaw frictionLaw = FrictionLaw::StickSlip;  ///< the tangential law
        double slipVelocity = 2e-3;                        ///< [m/s] v_s of the regularised law
        double stickStiffnessRatio = 1.0;  ///< tangential / normal penalty (stick-slip law)
        double onsetGap = 0.0;  ///< [m] smoothing width of the contact onset (0: C1 quadratic)
        int minNodesForThreads = 50000;  ///< evaluate nodes with OpenMP from this many nodes on
        /// A compliant layer on the shape (soft tissue over bone, a pad on an indenter), inside
        /// its surface: the surface is the layer's unloaded outside, the rigid core lies
        /// tissueThickness below it. 0 (with tissueModulus 0): no layer, the shape is rigid.
        /// The layer is a Winkler bed in series with the penalty (docs/contact.md#contact-law).
        double tissueThickness = 0.0;  ///< [m] layer thickness h
        double tissueModulus = 0.0;    ///< [Pa] its effective compressive (Young's) modulus E
        bool hasTissue() const { return tissueThickness > 0.0; }
        void validate() const;  ///< throws std::invalid_argument naming the option
    };
    RigidContact(const Mesh& mesh, std::vector<int> nodes, const RigidShape& shape,
                 const Options& options);
    /// Adds penalty energy, gradient and (symmetrised) Hessian at x.
    void addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    /// True when friction is on: the term is then not a potential (solver uses residual norms).
    bool isConservative() const;
    /// While on, every evaluation is the frictionless contact's (the friction history kept):
    /// for the frictionless linearisation of a state with friction
    /// (Airbag::calcShapeWrenchLinearisation()). Not to be set while another thread
    /// evaluates this contact.
    void setFrictionSuppressed(bool on) const;
    /// Starts a step of dt [s] from x (the committed state, the shape at its pose at the
    /// step's start). Regularised law: each anchored node's anchor goes to its contact point
    /// at x, so the slip is measured over the step, and the slip length becomes v_s dt
    /// (kMinSlipLength at least; dt = 0, a change with no time such as a quasi-static ramp,
    /// is Coulomb's rate-independent limit). Stick-slip law: nothing. Until the next call the
    /// committed state keeps the force of the step that reached it.
    void beginStep(const Eigen::Matrix3Xd& x, double dt);
    /// [m] floor of the regularised law's slip length v_s dt.
    static constexpr double kMinSlipLength = 1e-8;
    /// d(dE/dp)/dp of each node of the contact set at x (3 x 3 per node, zero out of contact):
    /// the exact derivative of the force law, not symmetric with friction (the coupling of
    /// the friction force to the normal force, mu t (d f_n/dp)^T, and the curvature terms).
    /// addEnergy() adds its symmetric part without the f_n coupling (docs/contact.md).
    std::vector<Mat3> calcNodeTangents(const Eigen::Matrix3Xd& x) const;
    /// Accepts x as converged: friction anchors follow the slip.
    void commitStep(const Eigen::Matrix3Xd& x);
    /// The friction history (anchors) committed so far, to be restored when a step that has
    /// committed trial states is abandoned.
    struct History {
        std::vector<Vec3> anchor_S;
        std::vector<char> hasAnchor;
        double slipLength = kMinSlipLength;  ///< [m] v_s dt of the step (regularised law)
    };
    History getHistory() const;
    /// Restores a history taken from this contact by getHistory().
    void setHistory(const History& h);
    /// Total force [N] the membrane exerts on the shape, and torque [N m] about the shape's
    /// frame origin, both in Ground.
    void calcWrenchOnShape(const Eigen::Matrix3Xd& x, Vec3* force, Vec3* torque) const;
    /// d(torque, force)/d(node positions) of calcWrenchOnShape() at x [6 x 3 n], n the mesh's
    /// nodes: rows torque then force (Ground), columns node coordinates (node v at 3v..3v+2),
    /// the shape held. Central differences of each contact node's own term (1e-7 m), zero
    /// columns for nodes out of contact. Without friction this is -B^T, B the derivative of
    /// the contact's gradient with respect to the shape's pose; with friction the tangential
    /// force is a law, not the gradient of a potential, and the two differ.
    Eigen::MatrixXd calcWrenchNodeDerivative(const Eigen::Matrix3Xd& x) const;
    /// Contact pressure [Pa] per mesh node (0 for nodes not in contact / not in the set).
    Eigen::VectorXd calcNodalPressure(const Eigen::Matrix3Xd& x) const;
    int getNumActive(const Eigen::Matrix3Xd& x) const;
    /// The contact node set (mesh node indices) and the shape it touches.
    const std::vector<int>& getNodes() const;
    const RigidShape& getShape() const;
    const Options& getOptions() const;

  private:
    struct Impl;
    std::shared_ptr<Impl> m_impl;
};

/// The tissue layer's law per unit reference area, a compressed neo-Hookean (incompressible)
/// block in uniaxial stress, lambda = 1 - c / h: sigma = (E / 3)(lambda^-2 - lambda) [Pa],
/// E c / h at small c, stiffening as the layer bottoms out; below lambda = kTissueMinStretch
/// continued linearly (C1), so that Newton's trial states past the core stay finite.
struct TissueStress {
    double sigma = 0.0;   ///< compressive stress [Pa]
    double dsigma = 0.0;  ///< d sigma / d c [Pa/m]
    double energy = 0.0;  ///< stored energy per unit area, the integral of sigma dc [J/m^2]
};
inline constexpr double kTissueMinStretch = 0.2;
/// The layer's stress, stiffness and energy at compression c [m] (c >= 0).
TissueStress calcTissueStress(double compression, double thickness, double modulus);

/// Membrane-membrane contact of a mesh with itself (top wall meeting bottom wall, folds):
/// node-to-triangle penalty with a thickness offset, broad phase by spatial hashing.
class SelfContact {
  public:
    struct Options {
        double pressurePenalty = 1e7;   ///< [Pa/m]
        double thickness = 1e-3;        ///< [m] contact offset between two sheets
        double candidateMargin = 2e-3;  ///< [m] extra search distance kept in the candidate list
        /// beta * thickness [-] of the soft minimum over the facets a node sees on one side:
        /// the energy is C2 where the nearest facet changes, smoothed over distance
        /// differences of ~ thickness / softMinSharpness (docs/contact.md).
        double softMinSharpness = 20.0;
        void validate() const;  ///< throws std::invalid_argument naming the option
    };
    SelfContact(const Mesh& mesh, const Options& options);
    /// Rebuilds the candidate pairs at x (call once per load step or when x moved far).
    void updateCandidates(const Eigen::Matrix3Xd& x);
    void addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    int getNumActive(const Eigen::Matrix3Xd& x) const;
    /// False once some node moved more than candidateMargin/2 since updateCandidates(): the
    /// candidate list may then miss pairs and should be rebuilt.
    bool isCandidateListValid(const Eigen::Matrix3Xd& x) const;
    /// Current candidate pairs as (node, triangle), sorted.
    std::vector<std::pair<int, int>> getCandidatePairs() const;
    /// The candidate list with each pair's side (history: a pair that persists keeps the
    /// side its node was found on), and the positions it was built at, into a checkpoint
    /// (bags/StateStream.h), and back into a SelfContact of the same mesh.
    void saveState(StateWriter& w) const;
    /// @throws StateError if the checkpoint is of another mesh.
    void loadState(StateReader& r);

  private:
    struct Impl;
    std::shared_ptr<Impl> m_impl;
};

}  // namespace bags
