#pragma once
/// @file The bag side of the co-simulation: what one participant (one airbag, or a test
/// double standing in for one) is handed and what it hands back in each macro step.
///
/// A participant carries a number of contact shapes: rigid shapes fixed on the body's
/// segments that may touch it (shape k of a participant is whatever the coupling linked to it).
/// Call protocol, per macro step [t, t + dt] (the coupling loop, cosim/Coupling.h, makes it):
///  1. setShapeState() for every shape: the shape's pose and velocity at the end of the step
///     (Ground, SI).
///  2. advance(dt): from the last checkpoint to those poses over dt (dt drives the gas flows).
///     It always starts from the checkpoint, so an implicit scheme iterates a macro step by
///     calling 1 and 2 again with other poses. A participant that cannot reach the poses
///     returns converged = false and stands at its checkpoint.
///  3. Read back at the state advance() reached, per shape: calcWrench() (the contact force
///     on the shape and the torque about the shape frame's origin, Ground),
///     calcWrenchTangent() (its derivative with respect to the shape's pose, on demand: it
///     costs about one factorisation of the bag) and calcContactPressure() (per node [Pa]).
///  4. commit() makes the state reached the new checkpoint; rollback() returns to the
///     checkpoint (after a macro step that is abandoned or cut).
/// Before the first step the loop does 1-4 once with dt = 0 at the initial poses.
///
/// Participants are independent of each other given the shapes' states: the loop may run
/// different participants on different threads (never one participant on two).

#include <bags/Types.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace cosim {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Pose and velocity of one contact shape, all in Ground.
struct ShapeState {
    Eigen::Isometry3d X_GS = Eigen::Isometry3d::Identity();  ///< shape frame S in Ground [m]
    Vec3 w_GS = Vec3::Zero();                                ///< angular velocity of S [rad/s]
    Vec3 v_GS = Vec3::Zero();                                ///< velocity of S's origin [m/s]
};

/// Contact load on one shape: rows torque [N m] about the shape frame's origin, then force
/// [N], both in Ground.
struct ShapeWrench {
    Vec3 torque = Vec3::Zero();  ///< [N m] about the shape's origin, Ground
    Vec3 force = Vec3::Zero();   ///< [N], Ground
    Vec6 asVector() const {      ///< (torque, force)
        Vec6 v;
        v << torque, force;
        return v;
    }
    static ShapeWrench fromVector(const Vec6& v) {  ///< from (torque, force)
        ShapeWrench w;
        w.torque = v.head<3>();
        w.force = v.tail<3>();
        return w;
    }
};

/// What one advance() did.
struct ParticipantStep {
    bool converged = false;    ///< false: the participant stands at its checkpoint
    int solverIterations = 0;  ///< Newton iterations (0 for a state that stood)
    /// [N] a step kept short of its equilibrium (a relaxed bag's unrelaxed step): the force
    /// residual it was kept with, to which its wrenches are resolved; 0 for an equilibrium.
    double unresolvedForce = 0.0;
};

/// One bag (or a stand-in) as the coupling loop sees it. Not thread safe.
class Participant {
  public:
    virtual ~Participant() = default;
    /// Number of contact shapes this participant carries.
    virtual int getNumShapes() const = 0;
    /// Pose and velocity of a shape at the end of the coming step (Ground).
    virtual void setShapeState(int shape, const ShapeState& state) = 0;
    /// From the checkpoint to the set shape states over dt [s] (dt >= 0).
    virtual ParticipantStep advance(double dt) = 0;
    /// Makes the current state the checkpoint.
    virtual void commit() = 0;
    /// Returns to the checkpoint.
    virtual void rollback() = 0;
    /// Contact wrench on the shape at the current state.
    virtual ShapeWrench calcWrench(int shape) const = 0;
    /// d(torque, force)/d(rotation, translation) of the shape's pose [6x6]: columns a small
    /// rotation of the shape about Ground axes through its origin [rad], then a translation
    /// [m]; rows as ShapeWrench. The participant re-equilibrates (its own stiffness counted).
    virtual Mat6 calcWrenchTangent(int shape) const = 0;
    /// calcWrenchTangent() of several shapes, in their order. The default calls it per shape;
    /// a participant that shares work between its shapes (one factorisation) overrides it.
    virtual std::vector<Mat6> calcWrenchTangents(const std::vector<int>& shapes) const {
        std::vector<Mat6> t;
        for (int s : shapes) t.push_back(calcWrenchTangent(s));
        return t;
    }
    /// The wrenches linearised in the shapes' poses and in the gas the participant takes in.
    struct WrenchLinearisation {
        std::vector<Mat6> pose;  ///< per shape, as calcWrenchTangents()
        /// Per shape, 6 x (the participant's gas inputs, calcGasInflow()): d wrench / d m_k
        /// [N m/kg, N/kg], the shapes held. Empty: linearised in the poses only.
        std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> gas;
    };
    /// At the current state, the shapes' wrench tangents and their derivatives by the gas
    /// (one factorisation for both). The default: calcWrenchTangents(), no gas.
    virtual WrenchLinearisation calcWrenchLinearisation(const std::vector<int>& shapes) const {
        return {calcWrenchTangents(shapes), {}};
    }
    /// Gas [kg] per gas input (the columns of WrenchLinearisation::gas) that an advance(dt)
    /// from the current state lets in (negative: out) with the flows now set. Default: none
    /// (empty).
    virtual Eigen::VectorXd calcGasInflow(double dt) const {
        (void)dt;
        return Eigen::VectorXd();
    }
    /// True when nothing but the shapes' poses changes what advance() finds (no gas flows
    /// in the coming steps): the coupling may then leave the participant standing while its
    /// shapes stay near where it last solved (CouplingOptions::skipTravel). Default: false.
    virtual bool isSteady() const { return false; }
    /// Contact pressure [Pa] per node of the participant's mesh from this shape (empty for
    /// a participant without a mesh).
    virtual Eigen::VectorXd calcContactPressure(int shape) const = 0;
};

}  // namespace cosim
