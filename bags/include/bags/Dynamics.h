#pragma once
/// @file The film in time: lumped (mass-scaled) inertia, mass-proportional damping and the
/// damped central-difference step that the Airbag's dynamic stepping sub-cycles with, and the
/// stable-step estimate it sub-cycles by. docs/solver.md#the-film-in-time.
///
/// The equations of motion of the free dofs are
///     M a + alpha M v + dE/dx (x) = 0,
/// M the lumped nodal masses (density x thickness x nodal reference area) times a mass scale S,
/// alpha [1/s] the damping, E the airbag's total potential (MembraneModel::addEnergy: membrane,
/// wrinkling, Prony branches, bending, gas, gravity on the real film mass, contacts). Central
/// differences with the velocity at the half steps,
///     v+ = ((1 - alpha h / 2) v- - h M^-1 dE/dx) / (1 + alpha h / 2),   x+ = x + h v+,
/// second order, explicit, and (undamped) symplectic: it keeps the energy of a free bag within
/// an oscillation of order h^2. Fixed dofs (support nodes) do not move.

#include <bags/FilmForce.h>
#include <bags/EquilibriumSolver.h>
#include <bags/Types.h>

#include <Eigen/Core>

#include <memory>

namespace bags {

/// How the film moves in time.
struct DynamicOptions {
    /// The lumped masses times this (>= 1): the stable step grows as its square root. The
    /// gravity on the sheet stays the real film's weight.
    double massScale = 1.0;
    /// [1/s] mass-proportional damping alpha (critical for a mode of angular frequency
    /// alpha / 2).
    double damping = 0.0;
    /// The sub-step as a fraction of the stable-step estimate, (0, 1].
    double stepFraction = 0.5;
    /// Relaxed stepping only (AirbagSpec::Stepping::Relaxed): the film is relaxed to the
    /// equilibrium of each step in pseudo-time, so these sub-steps are not the step's time.
    /// The most sub-steps one step may take; a step that has not reached the force tolerance
    /// by then is accepted as it stands, its residual reported (AdvanceSummary::relaxed false).
    int relaxSubsteps = 4000;
    /// [m/s of pseudo-time at mass scale 1000] how fast the shapes are moved to their step's
    /// poses before the film is relaxed there (at another mass scale the pace scales as one
    /// over its root, so that the film's response is the same): the pace at which the load test
    /// answers quasi-statically.
    double relaxPace = 0.02;
    /// Relaxed stepping: Newton alone (no damper, no stabilisation springs; cut as usual) is tried
    /// first, the relaxation only where it fails: where the film has an equilibrium near the
    /// last one (a taut bag) Newton's few iterations cost far less than a relaxation.
    bool newtonFirst = true;
    /// Relaxed stepping: where the sub-steps ran out short of the force tolerance, Newton
    /// alone (at most newtonPolish iterations, the self-contact candidates rechecked) is
    /// tried from the relaxed state; its equilibrium is kept if it finds one. 0: no polish.
    int newtonPolish = 30;
    /// Relaxed stepping: where neither the relaxation nor the polish reached the force
    /// tolerance, the step is taken once more by the quasi-static stepping (its retries:
    /// damped steps, stabilisation springs, cuts) from the committed state, and its answer kept
    /// if it finds one; else the relaxed state is kept, marked unrelaxed. false: no fallback.
    bool quasiStaticFallback = true;
    /// Throws std::invalid_argument naming the option and what would be valid.
    void validate() const;
};

/// The film's inertia and its explicit step, for one MembraneModel.
class FilmDynamics {
  public:
    /// Masses from the model's mesh (nodal reference areas), thickness and `density`
    /// [kg/m^3], times options.massScale. `contactPenalty` [Pa/m]: the stiffest penalty per
    /// area of any contact that may press a node (rigid shapes, bed, self contact), counted in
    /// the stable step as if every node were pressed.
    /// `tautMaterial` (optional): the film's law without its tension field (the base the
    /// model's wrinkling material relaxes). The stable step then counts film that is slack
    /// now as taut: slack film that is pulled taut within a step is as stiff as taut film,
    /// and a bound from the relaxed tangent alone (1e-3 of it) would be far too long a step.
    FilmDynamics(const MembraneModel& model, double density, const DynamicOptions& options,
                 double contactPenalty,
                 std::shared_ptr<const MembraneMaterial> tautMaterial = nullptr);

    const DynamicOptions& getOptions() const { return m_options; }
    /// Scaled lumped mass per dof [kg] (3 per node, equal), 0 on fixed dofs.
    const Eigen::VectorXd& getDofMass() const { return m_mass; }

    /// [s] The stable step at x: 2 / sqrt(lambda), lambda a bound on the largest eigenvalue
    /// of M^-1 K over the free dofs (Gershgorin's row sums of K: the film's tangent at x, or
    /// the taut film's where that is stiffer, plus the loads' tangent and the gas's dense
    /// terms) raised by every contact's penalty as if every node were pressed.
    /// Not yet times DynamicOptions::stepFraction. Costs one tangent assembly.
    double calcStableStep(const Eigen::Matrix3Xd& x) const;

    /// One damped central-difference step of h [s]: v (at the half steps) and x updated, from
    /// the forces of the model at x (FilmForce: the gradient alone, the model's kernel built
    /// at the first step). `acc` is scratch: on return its gradient is dE/dx at the old x and
    /// its energy NaN (MembraneModel::addEnergy gives the energy).
    /// @throws NumericalError if the model cannot evaluate x (collapsed element).
    /// Returns the squared norm [N^2] of the force on the free dofs at the old x (the
    /// quasi-static solver's residual there). calcForce() then update().
    double step(Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v, double h, EnergyAccumulator& acc) const;
    /// The model's energy gradient at x into acc (FilmForce; no tangent, energy NaN); returns
    /// the squared norm [N^2] of the force on the free dofs.
    double calcForce(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    /// The damped central-difference update over h from the gradient calcForce() left in acc.
    void update(Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v, double h,
                const EnergyAccumulator& acc) const;

    /// [J] 1/2 v^T M v with the scaled masses.
    double calcKineticEnergy(const Eigen::Matrix3Xd& v) const;

  private:
    const MembraneModel* m_model;
    std::unique_ptr<MembraneModel> m_taut;  // the film without its tension field (or null)
    DynamicOptions m_options;
    double m_contactPenalty;
    double m_areaDensity;                        // [kg/m^2] scaled: density x thickness x massScale
    Eigen::VectorXd m_mass;                      // per dof, 0 on fixed dofs
    Eigen::VectorXd m_invMass;                   // per dof, 0 on fixed dofs
    mutable std::unique_ptr<FilmForce> m_force;  // built at the first step
};

}  // namespace bags
