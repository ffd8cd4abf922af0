#pragma once
/// @file Passive joints of a relaxed patient: which segments they join, their type (ball or
/// pin), and the rotational stiffness, damping and range limits acting in them.
///
/// Joint angles are the rotation vector theta = angle * axis of R_FM, the rotation of the child
/// body frame M relative to the joint frame F on the parent, expressed in F. F and M are
/// parallel to the segment frames (X anterior, Y superior, Z right in the standing reference),
/// so theta_z is flexion/extension, theta_x ab/adduction (lateral bending for the spine,
/// inversion/eversion at the ankle, ulnar/radial deviation at the wrist) and theta_y axial
/// rotation. The elastic moment derives from the potential
///   U = sum_i [ k_i theta_i^2 / 2 + k_lim (theta_i - upper_i)_+^2 / 2 + k_lim (lower_i -
///   theta_i)_+^2 / 2 ],
/// and is applied as the exact work-conjugate torque tau_F = -J_l(theta)^-T dU/dtheta, so an
/// undamped patient conserves energy. Damping adds -c_i w_i with w the relative angular velocity
/// in F.

#include <Simbody.h>

#include <string>
#include <vector>

#include "body/Anthropometry.h"

namespace body {

/// Ball (3 rotations) or pin (flexion about Z only).
enum class JointType { Ball, Pin };

/// One passive joint.
struct JointSpec {
    std::string name;                      ///< e.g. "hip_r"
    Segment parent = Segment::LowerTrunk;  ///< segment carrying F
    Segment child = Segment::LowerTrunk;   ///< segment carrying M, whose origin is the joint centre
    JointType type = JointType::Ball;      ///< mobilizer
    SimTK::Vec3 stiffness{0};   ///< linear stiffness within the range, about F's X, Y, Z [N m/rad]
    SimTK::Vec3 damping{0};     ///< viscous damping about X, Y, Z [N m s/rad]
    SimTK::Vec3 lower{0};       ///< lower range limit of theta [rad]
    SimTK::Vec3 upper{0};       ///< upper range limit of theta [rad]
    double limitStiffness = 0;  ///< added stiffness beyond a limit [N m/rad]
};

/// The 15 joints of the patient, scaled to its size (stiffness and damping with body mass times
/// height relative to the 73 kg, 1.741 m reference male). Values and sources in docs/body.md.
std::vector<JointSpec> makeJointSpecs(const Anthropometry& anthropometry);

/// Rotation vector theta = angle * axis of R_FM [rad].
SimTK::Vec3 calcRotationVector(const SimTK::Rotation& R_FM);
/// Elastic potential energy U(theta) of a joint [J].
double calcJointPotential(const JointSpec& joint, const SimTK::Rotation& R_FM);
/// Torque on the child (reaction on the parent) expressed in F [N m], for the relative rotation
/// R_FM and relative angular velocity w_FM (in F); damping scaled by dampingScale.
SimTK::Vec3 calcJointTorque(const JointSpec& joint, const SimTK::Rotation& R_FM,
                            const SimTK::Vec3& w_FM, double dampingScale);

/// The torques of all passive joints as a Simbody force element.
class PassiveJointForce : public SimTK::Force::Custom::Implementation {
  public:
    /// A joint and the mobilized bodies it acts between.
    struct Entry {
        JointSpec spec;                    ///< the joint
        SimTK::MobilizedBodyIndex parent;  ///< parent body
        SimTK::MobilizedBodyIndex child;   ///< child body
    };
    /// @param dampingScale multiplies every damping coefficient (0 for an energy check).
    PassiveJointForce(const SimTK::SimbodyMatterSubsystem& matter, std::vector<Entry> entries,
                      double dampingScale);

    /// Adds the joint torques to bodyForces.
    void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>& bodyForces,
                   SimTK::Vector_<SimTK::Vec3>& particleForces,
                   SimTK::Vector& mobilityForces) const override;
    /// Sum of the joints' elastic energies [J].
    SimTK::Real calcPotentialEnergy(const SimTK::State& state) const override;
    /// The joints acted on.
    const std::vector<Entry>& getEntries() const { return m_entries; }

  private:
    const SimTK::SimbodyMatterSubsystem& m_matter;
    std::vector<Entry> m_entries;
    double m_dampingScale;
};

}  // namespace body
