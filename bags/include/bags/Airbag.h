#pragma once
/// @file One airbag as a module: the membrane, its gas bodies, the bed board, the rigid shapes
/// that may touch it and its own self contact, with the state, stepping, retry and rollback
/// that everything above the bag (the load-test rig, the co-simulation, studies, calibration)
/// drives.
///
/// Call protocol (an Airbag is not thread safe; different Airbags are independent and may run
/// on different threads, each with AirbagSpec::threads = 1):
///  1. Construct from an AirbagSpec (validated; the mesh is built and the stated imperfection
///     applied to it).
///  2. addShape() for every rigid shape that may touch the bag (their poses in Ground).
///  3. inflate(mass): from the flat panels to a sealed gas of that total mass, shapes where
///     they are (park them clear first). Committed.
///  4. Per step: setShapePose() to the poses at the end of the step; optionally
///     setMassFlow() / setTargetMass() (gas in or out over the step) or changeGasMass() (a
///     quasi-static let-down, solved at once); then advance(dt). advance() goes from the
///     committed state to the new poses and gas, cutting the step into sub-steps when a solve
///     fails (in a step in which no gas moves and no moving shape touches the bag before or
///     after, an equilibrium stands unsolved, and a state that cannot be relaxed stands as it
///     is: nothing acting on it changed); if even its smallest sub-step fails it
///     restores the committed state and returns
///     converged = false (the caller cuts its own step). After a converged advance the new
///     state is current but not yet committed: commit() makes it the state to go back to,
///     rollback() returns to the last commit (positions, gas, friction history, shape poses,
///     time). getSnapshot()/setSnapshot() do the same for any number of checkpoints (an
///     implicit coupling iterates a macro step from one).
///  5. Read back at the current state: calcShapeWrench() (force and torque on the shape, at its
///     origin, Ground), calcShapeWrenchTangent() (d wrench / d pose, with the bag
///     re-equilibrated), calcShapeContactPressure() (per node [Pa]), getChamberState() (gauge
///     pressure, volume, mass per chamber).
///
/// Units SI; frames: Ground (G); the mesh is built in the bag frame B and placed by X_GB.

#include <bags/Contact.h>
#include <bags/Dynamics.h>
#include <bags/Gas.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/Mesh.h>
#include <bags/EquilibriumSolver.h>
#include <bags/Viscoelastic.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace bags {

/// A stated geometric imperfection: every node of the reference (as-made) panels is moved
/// along its reference normal by amplitude * f(X), f a smooth random field of unit largest
/// magnitude (a sum of plane waves, wavelengths 60-240 mm, drawn from `seed`). Support
/// nodes stay. Real bags have seams and tolerances; the imperfection, not roundoff, then
/// chooses which way a symmetric fold goes.
struct Imperfection {
    double amplitude = 0.0;  ///< [m] largest normal offset (0: the perfect bag)
    std::uint64_t seed = 1;  ///< random field
    void validate() const;   ///< throws std::invalid_argument naming the option
};

/// Moves the free nodes of mesh.X by the imperfection (in place); a no-op at zero amplitude.
/// Deterministic: the same seed gives the same bits on every machine and thread count.
void applyImperfection(Mesh& mesh, const Imperfection& imperfection);

/// Everything an Airbag is built from.
struct AirbagSpec {
    DoubleWedgeParams geometry;  ///< the double wedge, used when `mesh` has no nodes
    Mesh mesh;                   ///< a ready mesh in the bag frame (optional)
    Eigen::Isometry3d X_GB = Eigen::Isometry3d::Identity();  ///< bag frame in Ground
    std::shared_ptr<const MembraneMaterial> material;        ///< base material (wrinkling added)
    double thickness = 0.2e-3;                               ///< membrane thickness [m]
    double density = 1150.0;                                 ///< membrane density [kg/m^3]
    double wrinklingResidual = 1e-3;  ///< residual stiffness fraction of slack states
    /// Viscoelastic film: a Prony series on its stress (`material` is then the long-term law);
    /// its Maxwell branches relax over advance()'s time, a quasi-static change (inflate,
    /// changeGasMass) ends relaxed. Empty: elastic. docs/materials.md#viscoelasticity.
    PronySeries prony;
    /// Bending stiffness of the film [N m] (discrete hinges); 0: a pure membrane.
    double bendingStiffness = 0.0;
    Vec3 gravity = Vec3(0, 0, -9.81);  ///< [m/s^2] in Ground, on the sheet's own weight
    GasOptions gas;
    /// Open: one gas body fills all chambers; Orifice: one per chamber, neighbours (c, c+1)
    /// joined by `orifice`, the flow integrated over advance()'s time.
    enum class Connection { Open, Orifice };
    Connection connection = Connection::Open;
    /// Several bags in one module, side by side on its bed board: the bag (`mesh` or
    /// `geometry`) is placed at each of these poses in the module frame B (placeCopies), each
    /// copy with its own gas. Their walls meet through the module's self-contact, which must
    /// be on; the connection must be open (one gas body per bag). Empty: one bag at B.
    /// docs/airbag-module.md#several-bags-in-one-module.
    std::vector<Eigen::Isometry3d> cluster;
    /// The bags of a cluster share one body of air, as bags joined by open tubes (a manifold
    /// whose valves are open): one pressure in every bag, and air pressed out of one bag
    /// goes into the others. inflate() and changeGasMass() then take per-bag masses whose
    /// sum is the shared air's mass; getGasMass(b) is bag b's share (by volume); a flow into
    /// any bag goes into the shared air; per-bag targets (setTargetMass) are refused. Needs a
    /// cluster of two or more bags and the open connection. false: one body of air per bag.
    bool sharedAir = false;
    OrificeOptions orifice;
    Imperfection imperfection;
    bool bedBoard = true;              ///< a rigid plane z_B = 0 under the bag
    RigidContact::Options bedContact;  ///< its contact options
    bool selfContact = true;
    double selfContactPenalty = 1e7;  ///< [Pa/m]
    SolverOptions solver;             ///< Newton options (maxStep 0: one mesh size)
    /// [Pa/m] springs to the last converged state per unit area, used when Newton fails on a
    /// slack, wrinkling state (escalated 1x, 10x, 100x); 0 disables them.
    double stabilization = 1.0e4;
    /// [Pa/m] Damped stepping (pseudo-dynamics): each step is first solved with a spring of
    /// this stiffness per unit area from every node of film that is not taut (and not pressed
    /// by a shape or the bed) to its position at the step's start: a viscous damper
    /// c = damping * dt (backward Euler) where the film's own tangent is weak. An easy damped
    /// solve is followed by a damper-free one. The damper's work is reported
    /// (AdvanceSummary::stabilizationEnergy); docs/solver.md. 0: no damper.
    double damping = 0.0;
    /// [N] a step is converged when the out-of-balance nodal force norm is below this (or
    /// the solver's own tolerances). A property of the bag, never scaled by a load.
    double forceTolerance = 0.05;
    /// Start each step's Newton solve from the last committed step's increment, scaled by how
    /// far the shapes move now along the way they moved then, when that start has the smaller
    /// force residual (a secant predictor; smooth paths then take fewer iterations).
    bool predictor = true;
    /// A repeated advance() from the same commit (an implicit coupling's next pass) starts its
    /// Newton solve from where the last converged advance ended, when that start has the
    /// smaller force residual: the poses differ from the last pass's by the coupling's
    /// correction only. The equilibrium is the same to the force tolerance.
    bool warmStart = true;
    /// Threads for the bag's element loops: 0 the OpenMP default, 1 single-threaded (for many
    /// bags in parallel). The result is bit-identical for any value.
    int threads = 0;
    /// How advance() takes the bag over a step of time (docs/solver.md#the-film-in-time).
    /// QuasiStatic: an equilibrium at the step's end (Newton, cutting the step, the
    /// stabilisation springs and damper above). Dynamic: the film carries its velocity and is
    /// integrated through the step in stable explicit sub-steps (bags/Dynamics.h, `dynamics`),
    /// the shapes' poses interpolated across it; no equilibrium is asked for, so a fold that
    /// snaps through is a short dynamic event; what touches the bag feels the film's
    /// (scaled) inertia. Relaxed: the quasi-static step's equilibrium (what touches the bag
    /// feels no inertia of the film): Newton alone first (DynamicOptions::newtonFirst; the
    /// step cut as in the quasi-static stepping, no damper, no springs), and where it fails
    /// the film's damped explicit dynamics in
    /// pseudo-time (dynamic relaxation with kinetic damping, `dynamics`): the shapes are moved
    /// to their poses at DynamicOptions::relaxPace, then the film relaxes there until the force
    /// residual is within forceTolerance or DynamicOptions::relaxSubsteps run out (the state is
    /// then kept as it stands, AdvanceSummary::unrelaxed); a step never fails for want of an
    /// equilibrium. The gas, leakage, orifice transfer, friction and viscous branches see the
    /// step's time as in the quasi-static stepping. A step of no time (advance(0)), inflate()
    /// and changeGasMass() stay quasi-static in all three and end at rest.
    enum class Stepping { QuasiStatic, Dynamic, Relaxed };
    Stepping stepping = Stepping::QuasiStatic;
    DynamicOptions dynamics;  ///< mass scale, damping, sub-step (Dynamic, Relaxed)
    void validate() const;    ///< throws std::invalid_argument naming the option
};

/// Force [N] and torque [N m] about the shape frame's origin, both in Ground.
struct Wrench {
    Vec3 torque = Vec3::Zero();
    Vec3 force = Vec3::Zero();
};

/// State of one chamber.
struct ChamberState {
    double gaugePressure = 0.0;  ///< [Pa]
    double volume = 0.0;         ///< [m^3]
    double mass = 0.0;           ///< [kg] (its share of a shared gas, by volume)
};

/// What one advance() did.
struct AdvanceSummary {
    bool converged = false;
    int substeps = 0;          ///< sub-steps solved (1 without cutting)
    int newtonIterations = 0;  ///< over every solve of the call
    int factorizations = 0;
    double residual = 0.0;  ///< [N] spring-free force residual at the accepted state
    /// [J] held by the stabilisation springs at the accepted state, or the damper's work over
    /// the step
    double stabilizationEnergy = 0.0;
    /// Dynamic stepping: [J] the film's kinetic energy at the step's end (scaled masses), and
    /// the sub-step [s] it was integrated with (0: none, the bag slept or the step had no time).
    double kineticEnergy = 0.0;
    double substep = 0.0;
    /// Relaxed stepping: the sub-steps ran out before the residual was within the force
    /// tolerance (the state was kept as it stood; `residual` says how far it was).
    bool unrelaxed = false;
};

class Airbag {
  public:
    explicit Airbag(const AirbagSpec& spec);
    ~Airbag();
    Airbag(Airbag&&) noexcept;
    Airbag& operator=(Airbag&&) noexcept;

    // --- set-up
    /// Adds a rigid shape that may touch the bag's free nodes (shared: the caller may keep
    /// it, but moves it only through setShapePose). Returns its index.
    int addShape(std::shared_ptr<RigidShape> shape, const RigidContact::Options& options);
    /// As addShape(), the shape touching only bag b's free nodes (a module of several bags,
    /// AirbagSpec::cluster): its wrench and contact pressures are then that bag's alone.
    int addShape(std::shared_ptr<RigidShape> shape, const RigidContact::Options& options, int bag);
    int getNumShapes() const;

    // --- gas
    /// Inflates the flat bag (a pressure ramp shapes the panels), seals its gas and takes it
    /// to `mass` [kg] in all (every bag of a cluster to `mass`); commits.
    /// @throws NumericalError if it cannot be solved.
    void inflate(double mass);
    /// As inflate(mass), bag b of the module to masses[b] [kg].
    void inflate(const std::vector<double>& masses);
    /// Inflates the flat bag to a gauge pressure [Pa], as a regulated supply fills a cell to
    /// its setpoint, and seals the gas that is then in it (every bag of a cluster alike):
    /// getGasMass() then says how much that is; commits.
    /// @throws NumericalError if it cannot be solved.
    void inflateToPressure(double gaugePressure);
    /// Takes the gas mass of the bag (of every bag of a cluster) to `mass` [kg] now,
    /// quasi-statically (shapes held), in steps it cuts as needed; commits.
    /// @throws NumericalError if it cannot be solved.
    void changeGasMass(double mass);
    /// As changeGasMass(mass), bag b to masses[b] [kg], the bags' masses moving together.
    void changeGasMass(const std::vector<double>& masses);
    /// Gas mass flow [kg/s] into the bag (into every bag of a cluster; negative: out) during
    /// the following advance() calls, shared among a bag's gas bodies by volume.
    void setMassFlow(double massFlow);
    void setMassFlow(int bag, double massFlow);  ///< one bag of a cluster
    /// Flow at |rate| [kg/s] during the following advance() calls until the bag's (every
    /// bag's) mass is `mass` [kg], then none. Refused with AirbagSpec::sharedAir.
    void setTargetMass(double mass, double rate);
    void setTargetMass(int bag, double mass, double rate);  ///< one bag of a cluster
    double getTotalGasMass() const;                         ///< [kg] summed over the module's bags
    /// [kg] of one bag (AirbagSpec::sharedAir: its share of the shared air, by volume)
    double getGasMass(int bag) const;
    /// No gas enters or leaves any bag, nor passes an orifice between chambers, nor leaks
    /// (GasOptions::leakConductance), nor exchanges heat with the room
    /// (GasOptions::heatTimeConstant), over the following advance() calls (no flow set, or
    /// every target reached), and the film has no strained viscous branch that would relax
    /// (AirbagSpec::prony): only the shapes' poses can change what advance() finds.
    bool isGasStill() const;

    /// How far the film is into its material's fitted range: the largest (I1 - 3) / limit over
    /// the film's elements now, limit = calcFittedRangeLimit(material) (0 where the law has no
    /// such limit). Above 1 an element is beyond the range the law was fitted for and stable in
    /// (the continued Yeoh there is an extrapolation, not the film): the results are outside
    /// the model's envelope. *stretch (optional): that element's largest principal stretch.
    double calcFittedRangeUse(double* stretch = nullptr) const;

    // --- the bags of a module (one unless AirbagSpec::cluster)
    int getNumBags() const;
    /// Bag b's nodes are [first, second) of the module's mesh.
    std::pair<int, int> getBagNodes(int bag) const;
    const std::vector<int>& getBagChambers(int bag) const;  ///< its chambers' indices
    /// Force [N] (Ground) the other bags' films exert on bag b's film through contact.
    Vec3 calcNeighbourForce(int bag) const;

    // --- shapes
    void setShapePose(int shape, const Eigen::Isometry3d& X_GS);
    const Eigen::Isometry3d& getShapePose(int shape) const;

    // --- stepping
    /// Goes from the committed state to the set shape poses and gas over dt [s] (the time
    /// drives the gas flows), with up to maxCuts halvings of a failing (sub-)step.
    AdvanceSummary advance(double dt, int maxCuts = 6);
    void commit();
    void rollback();
    struct Snapshot;
    /// A copy of the whole current state (positions, gas, friction history, the film's
    /// viscous internal variables, poses, time).
    std::shared_ptr<const Snapshot> getSnapshot() const;
    /// Makes a snapshot current (and the commit point).
    void setSnapshot(const std::shared_ptr<const Snapshot>& snapshot);
    double getTime() const;  ///< [s] accumulated by advance()
    /// Dynamic stepping: the film's mass scale, damping and sub-step from the next advance()
    /// on (the velocity kept). @throws std::logic_error for a quasi-statically stepped bag.
    void setDynamicOptions(const DynamicOptions& options);
    /// [J] the film's kinetic energy now (scaled masses; 0 for a quasi-static bag).
    double calcKineticEnergy() const;

    // --- checkpoints (bags/StateStream.h)
    /// Writes everything that decides what the bag does next into a checkpoint: the current
    /// and the committed state (positions, gas, friction history, the film's viscous internal
    /// variables when it has Prony terms, shape poses and targets, time), the gas flows set, the predictor's and warm start's increments, and the
    /// self-contact's candidate pairs with their sides. The solver's caches are not written:
    /// call resetCaches() where the checkpoint is taken.
    void saveState(StateWriter& w) const;
    /// Reads what saveState() wrote, into an Airbag built from the same spec with the same
    /// shapes and inflated (its own state is replaced); then resetCaches().
    /// @throws StateError if the checkpoint is of another bag (sizes, chambers, shapes).
    void loadState(StateReader& r);
    /// Forgets the caches that only speed the solves up but shape their roundoff: the stored
    /// factorisation that preconditions the Newton solves and the sparsity pattern it grew.
    /// A run that checkpoints calls it at every checkpoint, and a resumed run after loading,
    /// so that both continue from the same bits.
    void resetCaches();

    // --- results at the current state
    Wrench calcShapeWrench(int shape) const;
    /// d(torque, force)/d(rotation, translation) of the shape's pose [6x6]: rows torque then
    /// force (Ground), columns a small rotation of the shape about Ground axes through its
    /// origin [rad] then a translation of it [m]; the bag re-equilibrates (its tangent
    /// stiffness, gas included, solved once). Units N m/rad, N m/m, N/rad, N/m.
    /// @throws NumericalError if the bag's tangent is not positive definite.
    Eigen::Matrix<double, 6, 6> calcShapeWrenchTangent(int shape) const;
    /// calcShapeWrenchTangent() of several shapes at once, in their order: the bag's tangent
    /// is assembled and factored once for all of them. A shape that presses no node gets
    /// zero without a solve (if none does, nothing is factored).
    std::vector<Eigen::Matrix<double, 6, 6>> calcShapeWrenchTangents(
        const std::vector<int>& shapes) const;
    /// As calcShapeWrenchTangents(), but where the bag's tangent is not positive definite (a
    /// state at or past a limit point, e.g. one held by the stabilisation springs) each
    /// pressing shape gets the film-held tangent dW/dq at fixed nodes (the contact's own
    /// stiffness: the bag's stiffest answer, no re-equilibration) and *filmHeld is set,
    /// instead of a throw. withoutFriction: the tangents of the same state with the shapes'
    /// contacts taken frictionless (their normal law, the film and the gas; no stick or slip
    /// force, the friction history kept), for a coupling whose passes hold the friction force
    /// (docs/cosim.md#friction-and-the-tangent-schemes). Without friction on the shapes it is
    /// the tangent itself, except where the bag's tangent is not positive definite: zero
    /// there instead of the film-held tangent (the load held over the coupling's step).
    std::vector<Eigen::Matrix<double, 6, 6>> calcShapeWrenchTangents(
        const std::vector<int>& shapes, bool* filmHeld, bool withoutFriction = false) const;
    /// The shapes' wrenches linearised at the current state in their poses and in the bags'
    /// gas: what calcShapeWrenchTangents(shapes, filmHeld) gives, and per shape the
    /// derivative of its wrench by each bag's gas mass, with one factorisation for all.
    struct WrenchLinearisation {
        /// Per shape, d wrench / d pose (calcShapeWrenchTangents()).
        std::vector<Eigen::Matrix<double, 6, 6>> pose;
        /// Per shape, 6 x getNumBags(): column b is d wrench / d m_b [N m/kg, N/kg], the
        /// shapes held and the bag re-equilibrated, the gas added to bag b as advance()'s
        /// flows add it (shared among its gas bodies by volume, each keeping its temperature).
        std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> gas;
        /// The bag's tangent was not positive definite: film-held pose tangents, and zero
        /// gas columns (at fixed nodes the wrench does not see the gas).
        bool filmHeld = false;
    };
    /// withoutFriction as in calcShapeWrenchTangents().
    WrenchLinearisation calcShapeWrenchLinearisation(const std::vector<int>& shapes,
                                                     bool withoutFriction = false) const;
    /// Gas mass [kg] the flows set (setMassFlow(), setTargetMass()) let into bag b (negative:
    /// out) over an advance(dt) from the current state: the flow times dt, at most what is
    /// left to a target. Leakage, orifices and heat are not counted.
    double calcGasInflow(int bag, double dt) const;
    /// Contact pressure [Pa] per mesh node from this shape.
    Eigen::VectorXd calcShapeContactPressure(int shape) const;
    /// Force [N] on the bed board (Ground).
    Vec3 calcBedForce() const;
    int getNumChambers() const;
    ChamberState getChamberState(int chamber) const;
    const Mesh& getMesh() const;  ///< in Ground (X_GB applied), imperfection included
    const Eigen::Matrix3Xd& getPositions() const;  ///< nodes [m], Ground
    const MembraneModel& getModel() const;
    const AirbagSpec& getSpec() const;  ///< as built (validated)
    /// Force [N] residual of the current state without stabilisation springs.
    double calcResidual() const;

  private:
    int checkBag(int bag) const;  ///< bag, or std::out_of_range
    /// The inflation's pressure ramp to pTarget[b] [Pa] per bag (bags ramp together, the
    /// highest's pressure the parameter), then each bag's gas sealed at that state.
    void rampAndSeal(std::vector<double> pTarget);
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace bags
