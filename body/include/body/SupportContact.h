#pragma once
/// @file A rigid flat support under the patient: an elastic foundation (Winkler bed) of stiff
/// springs against the plane z = height, acting on patches of every contact shape's surface,
/// with damping and regularized Coulomb friction. Good enough to lay the patient down and read
/// how its weight is shared between body regions; the airbags replace it later.
///
/// Pressure on a patch that is below the plane by delta, moving down at -v_z:
///   p = max(0, k delta - c v_z), normal force p * A * max(0, -n_z) (the patch's area projected
///   on the plane), and friction by one of two laws (PlaneSupportOptions::frictionLaw):
/// - regularised: -mu F_n v_t / sqrt(|v_t|^2 + v_s^2). A patch under a tangential load below
///   mu F_n creeps at about v_s f_t / (mu F_n), and the law is a damper of mu F_n / v_s at
///   rest: stiff in the body's velocity for small v_s.
/// - stick-slip: each patch in contact is tied to an anchor on the plane by an elastic stick
///   spring with Kelvin-Voigt damping, capped at Coulomb's limit:
///     s = u + tau v_t,   f_t = -mu F_n s / max(|s|, d_s),
///   u the patch's tangential displacement from its anchor, tau = damping / stiffness (the
///   normal direction's time constant), d_s the stick distance (the spring reaches mu F_n at
///   |s| = d_s). After every accepted integrator step the anchors of sliding patches follow
///   (return mapping: |s| = d_s, which leaves the force unchanged); a patch that comes into
///   contact is anchored where it touches; one that leaves loses its anchor. No creep under a
///   load below mu F_n, and a spring of mu F_n / d_s in place of the regularised law's damper.

#include <Simbody.h>

#include <array>
#include <vector>

#include "body/BodyModel.h"

namespace body {

/// How the support's friction follows the slip (SupportContact.h's file comment).
enum class SupportFrictionLaw { Regularised, StickSlip };

/// Settings of the flat support.
struct PlaneSupportOptions {
    double height = 0.0;           ///< plane z [m]
    double stiffness = 2.0e6;      ///< pressure per penetration [Pa/m] (20 kPa at 10 mm)
    double damping = 4.0e4;        ///< pressure per penetration rate [Pa s/m]
    double friction = 0.6;         ///< Coulomb coefficient [-]
    double slipVelocity = 2.0e-3;  ///< friction regularization velocity [m/s] (regularised)
    SupportFrictionLaw frictionLaw = SupportFrictionLaw::Regularised;
    double stickDistance = 1.0e-3;  ///< [m] elastic slip at which the stick spring is at mu F_n
    double sampleSpacing = 0.012;   ///< patch size on the shapes' surfaces [m]
    /// @throws std::invalid_argument naming the option if a value is out of range.
    void validate() const;
};

/// How the support carries the body at one state.
struct SupportLoad {
    SimTK::Vec3 force{0};             ///< total force of the support on the body, Ground [N]
    double contactArea = 0;           ///< projected area of the patches in contact [m^2]
    double peakPressure = 0;          ///< highest patch pressure [Pa]
    std::vector<double> regionForce;  ///< normal force per region (BodyModel::getRegions()) [N]
    std::vector<double> regionPeakPressure;            ///< highest pressure per region [Pa]
    double otherForce = 0;                             ///< normal force on patches in no region [N]
    std::array<double, kSegmentCount> segmentForce{};  ///< normal force per segment [N]
};

/// The flat support as a Simbody force element.
class PlaneSupport : public SimTK::Force::Custom::Implementation {
  public:
    /// Samples the model's shapes. @throws std::invalid_argument if options are invalid.
    PlaneSupport(const BodyModel& model, const PlaneSupportOptions& options);

    /// Adds the contact forces to bodyForces.
    void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>& bodyForces,
                   SimTK::Vector_<SimTK::Vec3>& particleForces,
                   SimTK::Vector& mobilityForces) const override;
    /// Elastic energy of the foundation springs, sum k delta^2 A_proj / 2 [J].
    SimTK::Real calcPotentialEnergy(const SimTK::State& state) const override;
    /// Forces per region and segment. @pre state realized to Velocity.
    SupportLoad calcSupportLoad(const SimTK::State& state) const;
    /// Number of surface patches.
    int getPatchCount() const;
    /// Stick-slip law: allocates the patches' anchors in the state (an auto-update discrete
    /// variable of the force subsystem).
    void realizeTopology(SimTK::State& state) const override;
    /// The stick-slip anchors as stored in the state: (patch index, x [m], y [m]) per anchored
    /// patch, patches ascending; empty under the regularised law. For checkpoints:
    /// setAnchors() restores them. @throws std::invalid_argument if the values are not such
    /// triples of this support's patches.
    std::vector<double> getAnchors(const SimTK::State& state) const;
    void setAnchors(SimTK::State& state, const std::vector<double>& anchors) const;
    /// Patches of the stick-slip law sliding (|s| > d_s) and in contact, at a realized state
    /// (Dynamics); 0 under the regularised law.
    std::array<int, 2> countSlidingPatches(const SimTK::State& state) const;

  private:
    struct Patch {
        SimTK::Vec3 p_B, n_B;
        double area;
        int region;
    };
    struct Anchors {  // the stick-slip law's anchors: the anchored patches (ascending), x, y
        std::vector<int> patch;
        std::vector<SimTK::Vec2> a;
    };
    // Calls visit(segment, patch index, patch, r_G, F_G, pressure, projected area, new
    // anchor) for every patch in contact, in ascending patch index (the new anchor: NaN under
    // the regularised law).
    template <class Visit>
    void forEachContact(const SimTK::State& state, Visit&& visit) const;
    // True when no patch of segment i can reach the support at body pose X_GB (the patches'
    // box in the body frame lies wholly above the plane).
    bool isClearOfSupport(int i, const SimTK::Transform& X_GB) const;

    const BodyModel& m_model;
    PlaneSupportOptions m_options;
    std::array<std::vector<Patch>, kSegmentCount> m_patches;
    std::array<int, kSegmentCount> m_firstPatch{};  // global index of each segment's first
    int m_patchCount = 0;
    const SimTK::Subsystem& m_forces;  // holds the anchors (stick-slip)
    mutable SimTK::DiscreteVariableIndex m_anchorsIndex;
    // Per segment, the axis-aligned box of its patches in the body frame: centre and half
    // extents [m] (the broad phase; tighter than the shape's bounding sphere).
    std::array<SimTK::Vec3, kSegmentCount> m_boxCentre, m_boxHalf;
};

/// Adds a PlaneSupport to the model's forces; the returned reference stays valid as long as
/// the model. @pre topology not yet realized.
const PlaneSupport& addPlaneSupport(BodyModel& model, const PlaneSupportOptions& options = {});

}  // namespace body
