#pragma once
/// @file The body side of the co-simulation: a Simbody multibody system (the patient, or a
/// rigid block for tests) whose contact shapes are fixed on its mobilized bodies, integrated
/// over a macro step under the bags' contact wrenches.
///
/// Order of calls:
///  1. Construct on the system and its force subsystem before the topology is realized (a
///     Force::Custom that applies the bags' wrenches is added to the forces).
///  2. addShape() for every contact shape (a frame fixed on a mobilized body).
///  3. Realize the topology, make the initial state and initialize() with it (the checkpoint).
///  4. Per macro step: setShapeLoad() for every shape, advanceTo(t_end) from the checkpoint,
///     read getShapeState() at the end of the step; commit() makes the state reached the
///     checkpoint, rollback() returns to it (an implicit scheme repeats 4 from the checkpoint).
///
/// The load on a shape inside the step is W(X, t) = W0 + T * d(X0, X) + R (t - t0): a
/// zero-order hold when T = 0 and R = 0, the bag's tangent linearisation about X0 otherwise;
/// d is the small rotation (rotation vector of R_GS R_GS0^T, Ground) and translation of the
/// shape's origin from X0; R is the load's rate from the bag's gas over the step (t0 the
/// checkpoint's time).
/// W's torque is about the shape's origin, as the bags give it; it is moved to the body origin
/// when applied. The force adds no potential energy to the system's.

#include <Simbody.h>

#include <bags/StateStream.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cosim/Participant.h"

namespace cosim {

/// How the body is integrated over a macro step.
struct BodyIntegratorOptions {
    /// Simbody's error-controlled Runge-Kutta-Merson accuracy (relative) [-].
    double accuracy = 1e-7;
    /// Largest internal step [s] (0: Simbody's default, no limit).
    double maxStepSize = 0.0;
    /// [s/m] Contact damping d: each linked shape whose held load has a force F0 is also
    /// pushed by -d |F0| v_S (v_S the velocity of the shape's origin, Ground), inside the
    /// body's step. It stands for the losses in the bags' film and air that the quasi-static
    /// bags leave out, and lets a patient come to rest on them (a vertical bounce of angular
    /// frequency w gets a damping ratio of about d g / (2 w)). It vanishes at rest and off
    /// contact, is not part of the bags' wrench, and only takes energy out. 0: none.
    double contactDamping = 0.0;
    void validate() const;  ///< throws std::invalid_argument naming the option
};

/// Converts Simbody's transform to Eigen's isometry and back.
Eigen::Isometry3d toEigen(const SimTK::Transform& X);
SimTK::Transform toSimTK(const Eigen::Isometry3d& X);

class BodyParticipant {
  public:
    /// Adds the coupling force to `forces`. @pre the system's topology is not yet realized.
    BodyParticipant(SimTK::MultibodySystem& system, SimTK::GeneralForceSubsystem& forces,
                    const BodyIntegratorOptions& options = {});
    ~BodyParticipant();
    BodyParticipant(const BodyParticipant&) = delete;
    BodyParticipant& operator=(const BodyParticipant&) = delete;

    /// A contact shape: frame S fixed on `body` at X_BS. Returns its index.
    /// @pre before initialize().
    int addShape(SimTK::MobilizedBodyIndex body, const SimTK::Transform& X_BS);
    int getNumShapes() const;

    /// A part of the body's state outside time, q, u and z that checkpoints carry (a force
    /// element's discrete variables, e.g. the bed board's stick-slip anchors): how to read
    /// its values from a state and write them back. @pre before initialize().
    struct DiscreteState {
        std::string name;  ///< for messages ("the bed board's friction anchors")
        std::function<std::vector<double>(const SimTK::State&)> get;
        std::function<void(SimTK::State&, const std::vector<double>&)> set;
    };
    void addDiscreteState(DiscreteState d);

    /// The initial state (topology realized); it becomes the checkpoint.
    void initialize(const SimTK::State& state);

    /// The load on `shape` during the coming advance: W0 + T * d(X0, X) + rate (t - t0),
    /// rate [(N m, N)/s] as ShapeWrench, t0 the checkpoint's time. T and rate zero: a hold.
    void setShapeLoad(int shape, const ShapeWrench& W0, const Mat6& T = Mat6::Zero(),
                      const Eigen::Isometry3d& X0 = Eigen::Isometry3d::Identity(),
                      const Vec6& rate = Vec6::Zero());
    /// Integrates from the checkpoint to `time` [s] under the set loads.
    /// @throws std::runtime_error naming the time if Simbody's integrator fails.
    void advanceTo(double time);
    void commit();    ///< the state reached becomes the checkpoint
    void rollback();  ///< back to the checkpoint

    /// Pose and velocity of a shape at the current state (Ground).
    ShapeState getShapeState(int shape) const;
    /// The load the coupling force applies to a shape at the current state.
    ShapeWrench calcShapeLoad(int shape) const;
    const SimTK::State& getState() const;       ///< current state, realized to Velocity
    const SimTK::State& getCheckpoint() const;  ///< the checkpoint
    double getTime() const;                     ///< [s] of the current state
    int getLastIntegratorSteps() const;         ///< internal steps of the last advanceTo()

    // --- checkpoints (bags/StateStream.h), between steps
    /// Writes the checkpoint's and the current state (time, q, u, z, the discrete states
    /// added) and every shape's load.
    void saveState(bags::StateWriter& w) const;
    /// Reads what saveState() wrote into a participant on the same system, initialized.
    /// @throws bags::StateError if the system's sizes or the shapes differ.
    void loadState(bags::StateReader& r);

    struct Shape;  ///< a shape and its load (implementation detail)
  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cosim
