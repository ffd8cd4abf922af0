#pragma once
/// @file The patient as a Simbody multibody system: 16 rigid segments (de Leva 1996) in a tree
/// rooted at the pelvis (free joint to Ground), passive ball and pin joints, gravity, a contact
/// shape per segment and named regions. It knows nothing of airbags.
///
/// Order of use: construct from a PatientSpec; optionally add forces to updForces() (a support,
/// the airbags' contact forces through Force::DiscreteForces or Force::Custom); call
/// updSystem().realizeTopology(); take the default state, setPosture() it, and integrate.
///
/// Ground: z up, the bed surface z = 0, head towards +x (see Posture.h).

#include <Simbody.h>

#include <array>
#include <memory>
#include <vector>

#include "body/Anthropometry.h"
#include "body/ContactShape.h"
#include "body/PassiveJoints.h"
#include "body/PatientSpec.h"
#include "body/Regions.h"

namespace body {

/// How the model is built.
struct BodyModelOptions {
    bool passiveJoints = true;       ///< add joint stiffness, damping and range limits
    double jointDampingScale = 1.0;  ///< multiplies the joint damping (0: undamped joints) [-]
    double gravity = 9.80665;        ///< gravitational acceleration along -z [m/s^2]
    /// @throws std::invalid_argument naming the option if a value is negative or not finite.
    void validate() const;
};

/// The patient model.
class BodyModel {
  public:
    /// Builds the model. @throws std::invalid_argument if spec or options are invalid.
    explicit BodyModel(const PatientSpec& spec, const BodyModelOptions& options = {});
    ~BodyModel();
    BodyModel(const BodyModel&) = delete;
    BodyModel& operator=(const BodyModel&) = delete;

    /// The patient this model was built for.
    const PatientSpec& getSpec() const;
    /// Segment masses, inertias, joint centres and shape sizes.
    const Anthropometry& getAnthropometry() const;

    /// The multibody system (add subsystems or realize it).
    SimTK::MultibodySystem& updSystem();
    const SimTK::MultibodySystem& getSystem() const;  ///< the multibody system
    /// The matter subsystem holding the 16 bodies.
    SimTK::SimbodyMatterSubsystem& updMatter();
    const SimTK::SimbodyMatterSubsystem& getMatter() const;  ///< the matter subsystem
    /// The force subsystem (gravity and the passive joints are in it).
    SimTK::GeneralForceSubsystem& updForces();
    const SimTK::GeneralForceSubsystem& getForces() const;  ///< the force subsystem

    /// Mobilized body of a segment.
    SimTK::MobilizedBodyIndex getMobilizedBodyIndex(Segment segment) const;
    /// Mobilized body of a segment.
    const SimTK::MobilizedBody& getMobilizedBody(Segment segment) const;
    /// The segment of a mobilized body, or -1 for Ground.
    int findSegment(SimTK::MobilizedBodyIndex index) const;
    /// Contact shape of a segment, in its body frame.
    const ContactShape& getContactShape(Segment segment) const;
    /// The named regions (indices are the region ids used in reports).
    const std::vector<BodyRegion>& getRegions() const;
    /// Region id of a surface point p_B of a segment, or -1.
    int findRegion(Segment segment, const SimTK::Vec3& p_B) const;
    /// The passive joints.
    const std::vector<JointSpec>& getJoints() const;
    /// Total mass of the bodies [kg].
    double calcTotalMass() const;

    /// Sets q for the spec's posture and position, u = 0, and lifts the body so its lowest
    /// point is at z = clearance. @pre the system's topology is realized.
    void setPosture(SimTK::State& state, double clearance = 0) const;
    /// Same for a given posture, mid-hip (x, y) position [m] and head-of-bed angle [rad].
    void setPosture(SimTK::State& state, Posture posture, const std::array<double, 2>& position,
                    double headOfBedAngle, double clearance = 0) const;
    /// Lowest z of all contact shapes [m]. @pre state realized to Position.
    double calcLowestPointHeight(const SimTK::State& state) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace body
