#pragma once
/// @file The seed study's test rig: one airbag on a rigid bed board, inflated to a gas mass,
/// then pressed by a rigid square block at a constant rate up to a peak force and released;
/// the gas is let out to the next mass and the test repeated.
///
/// Order: LoadTestOptions::validate(), then runLoadTest(options, observer). The observer is
/// called after every converged step (so a writer can stream frames and survive an interrupt);
/// the result holds the curves, the stiffness per gas mass and the k(m) fit.

#include <bags/Airbag.h>
#include <bags/Contact.h>
#include <bags/Gas.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/Polynomial.h>
#include <bags/EquilibriumSolver.h>

#include <functional>
#include <memory>
#include <string>
#include <array>
#include <vector>

namespace bags {

struct LoadTestOptions {
    DoubleWedgeParams geometry;
    /// The bag as a similar one (airbag.volume_change, the bag-volume candidate): the mesh built
    /// from `geometry`, every node times bagScale, so its volume is bagScale^3 times the
    /// geometry's and its mesh the same one (a new mesh of scaled sizes would not be: the side
    /// panels' diagonals are chosen on ties that round-off breaks). 1: the bag as built.
    /// getBagGeometry() gives the sizes as built.
    double bagScale = 1.0;
    /// `geometry` with its sizes and mesh size times bagScale: the bag's sizes as built.
    DoubleWedgeParams getBagGeometry() const;
    std::shared_ptr<const MembraneMaterial> material;  ///< base material (wrinkling added)
    double thickness = 0.2e-3;                         ///< membrane thickness [m]
    double density = 1150.0;          ///< membrane density [kg/m^3] (gravity on the sheet)
    double wrinklingResidual = 1e-3;  ///< residual stiffness fraction of slack states
    /// Viscoelastic film (AirbagSpec::prony): `material` is the long-term law; the
    /// Maxwell branches relax over the test's time (block travel / loadingRate). Empty: elastic.
    PronySeries prony;
    double bendingStiffness = 0.0;  ///< film bending stiffness [N m] (0: pure membrane)
    Imperfection imperfection;      ///< stated geometric imperfection of the bag
    int threads = 0;                ///< element-loop threads (0: default; results identical)
    bool predictor = true;          ///< secant predictor for block steps (AirbagSpec)
    /// Ensemble size: the test is also run for the imperfection seeds seed + 1 ... seed + N - 1
    /// (in parallel, one thread each) and each curve reports the spread of its stiffness over
    /// the N bags (LoadCurve::stiffnessMin/Max). 1: the one bag. Needs an imperfection.
    int ensemble = 1;
    bool gravity = true;  ///< self-weight of the sheet
    GasOptions gas;
    /// How the chambers share their air: Open, one gas body filling all chambers (pressures
    /// always equal); Orifice, one gas body per chamber, neighbouring chambers (c, c + 1)
    /// joined by `orifice`, the mass flow integrated over the test's time (needs two or more
    /// chambers, i.e. the diaphragm).
    enum class Connection { Open, Orifice };
    Connection connection = Connection::Open;
    OrificeOptions orifice;
    /// Orifice only: before each curve the chambers settle for settleTime [s], integrated by
    /// backward Euler in settleSteps steps of doubling length (10 steps agree with 40 to
    /// 1e-5 of the remaining pressure difference on the 20 mm rig). 0 s: no settling.
    double settleTime = 1000.0;
    int settleSteps = 10;
    std::vector<double> gasMasses;  ///< [kg], run in this order (seed: 3.5 g down to 1.0 g)
    /// The pressed bag among neighbours of the same bag, side by side in one module
    /// (AirbagSpec::cluster; their walls meet through self-contact, so selfContact must be
    /// on and the connection open). The pressed bag is bag 0 at the origin; across the width
    /// (y) the pitch is width + neighbourGap, along x (Block3x3 only) longSide + neighbourGap.
    /// None: the bag alone (the seed's rig); Pair: one neighbour at +y; Row3: one at -y and
    /// one at +y; Block3x3: a 3 x 3 block, the pressed bag at neighbourPressed within it.
    /// docs/array-coupling.md.
    enum class Neighbours { None, Pair, Row3, Block3x3 };
    Neighbours neighbours = Neighbours::None;
    /// Block3x3: where in the block the pressed bag stands, (along x, across y), each -1, 0
    /// or 1; (0, 0) the middle, (1, 1) the corner at +x +y. The block's other eight bags stand
    /// around it; pressing each position in turn maps the block's stiffness.
    std::array<int, 2> neighbourPressed{0, 0};
    double neighbourGap = 5.0e-3;  ///< [m] between facing flat panels (0 < gap < 100 mm)
    /// [kg] every neighbour's gas mass at every curve; 0: the pressed bag's mass of that curve
    double neighbourGasMass = 0.0;
    /// The pressed bag and its neighbours share one body of air (joined by open tubes:
    /// AirbagSpec::sharedAir), its mass the bags' masses summed; false: each its own.
    bool neighbourSharedAir = false;
    double blockSize = 0.050;             ///< square block edge [m]
    double loadingRate = 10.0e-3 / 60.0;  ///< [m/s] (10 mm/min)
    double peakForce = 50.0;              ///< [N]
    bool unload = true;                   ///< record the unloading branch too
    double displacementStep = 1.0e-3;     ///< target block increment [m] (adapted)
    /// While the block force is below a quarter of stiffnessFrom (a slack bag folding in
    /// under almost no force), block steps may grow to this many times displacementStep
    /// (the loading step also stays short of half stiffnessFrom by the stiffness so far).
    double lowForceStepFactor = 4.0;
    /// Where no equilibrium is found near the last one at any step down to the smallest, go on
    /// by 1, 2 or 4 displacement steps (stepOverSnap) instead of ending the curve as failed.
    bool stepOverSnaps = true;
    double stiffnessFrom = 10.0;  ///< [N] force range of the stiffness fit
    double stiffnessTo = 35.0;    ///< [N]
    int polynomialOrder = 5;      ///< k(m) fit order (seed: 5)
    RigidContact::Options blockContact;
    RigidContact::Options floorContact;
    bool selfContact = true;
    SolverOptions solver;
    /// Stabilisation [Pa/m] used when Newton fails on a step (slack, wrinkling bag): a spring
    /// of this stiffness per unit area to the last converged state; 0 disables it.
    double stabilization = 1.0e4;
    /// [Pa/m] damper on film that is not taut, per step (AirbagSpec::damping); 0: none
    double damping = 0.0;
    /// A step is converged when the norm of the out-of-balance nodal forces is below this
    /// fraction of the peak force, the peak force counted at most kToleranceForceCap (50 N), or
    /// below solver.absoluteTolerance, whichever is larger; 0 leaves only the solver's own
    /// tolerances. The cap keeps a large load from loosening the solve. The residual that lingers longest sits in the slack
    /// folds of the internal wall, away from the block (docs/solver.md).
    double residualTolerance = 1.0e-3;
    /// How the bag is taken through the test (AirbagSpec::Stepping). QuasiStatic: an
    /// equilibrium at every block step (Newton, the step cutting and snap-over above).
    /// Dynamic: the block moves on without stopping and the film is integrated in time, its
    /// inertia scaled (`dynamic`); quasi-static answers from slow loading, checked by the
    /// kinetic energy's share of the block's work (docs/solver.md#the-film-in-time).
    AirbagSpec::Stepping stepping = AirbagSpec::Stepping::QuasiStatic;
    /// The dynamic test. The film is integrated as if the block moved at `blockSpeed` with
    /// the film's masses times `massScale` and damping `damping`: in the test's own time
    /// (travel / loadingRate, which the gas and the film's viscous branches keep) that is
    /// the mass scale massScale r^2 and damping damping / r, r = blockSpeed / loadingRate.
    struct Dynamic {
        double blockSpeed = 0.02;      ///< [m/s] the pace the film is integrated at
        double massScale = 1000.0;     ///< film mass scale at that pace (>= 1)
        double damping = 20.0;         ///< [1/s] mass-proportional damping at that pace
        double stepFraction = 0.5;     ///< sub-step as a fraction of the stable step
        double recordEvery = 0.25e-3;  ///< [m] block travel between recorded states
        /// [m] at the start of the loading and of the unloading the block comes up to speed
        /// over this much travel (from a sixteenth of it, in proportion to the travel), so
        /// that the film at rest is not struck (0: at full speed at once).
        double rampTravel = 2.0e-3;
        /// Largest share of the film's kinetic energy in the block's work so far, over the
        /// loading branch from stiffnessFrom on: above it the curve is not quasi-static.
        double kineticShareLimit = 0.01;
        /// Along the loading the block's pace halves (up to this many times) while the film's
        /// kinetic energy is over half the limit of the block's work so far, and doubles back
        /// after 8 records below an eighth of it; a curve whose share still broke the limit is
        /// run again at half the block speed, up to this many times; still over: kept and
        /// marked (LoadCurve::kineticShare, quasiStatic, failure text).
        int maxHalvings = 3;
    };
    Dynamic dynamic;
    /// Throws std::invalid_argument naming the option and what would be valid.
    void validate() const;
};

/// One converged state of the test.
struct LoadStep {
    int curve = 0;        ///< index into LoadTestOptions::gasMasses
    int step = 0;         ///< step within the curve
    bool loading = true;  ///< false on the unloading branch
    double time = 0.0;    ///< test time of this curve [s]
    double displacement =
        0.0;             ///< block travel [m] from the top of the unloaded bag under the block
    double force = 0.0;  ///< block force [N]
    std::vector<double> gaugePressure;  ///< per chamber [Pa]
    std::vector<double> volume;         ///< per chamber [m^3]
    std::vector<double> gasMass;        ///< per chamber [kg] (its share of a shared gas)
    int newtonIterations = 0;
    int factorizations = 0;  ///< sparse factorisations of the step's solves
    /// [J] held by the stabilisation springs at the accepted state (0 if the step ended on a
    /// spring-free equilibrium)
    double stabilizationEnergy = 0.0;
    /// [N] force residual at the accepted state, without the springs (for a state accepted
    /// with springs this is the springs' force)
    double residual = 0.0;
    /// Dynamic test: [J] the film's kinetic energy at the state (scaled masses), and the
    /// explicit sub-steps integrated since the last state (newtonIterations stays 0).
    double kineticEnergy = 0.0;
    int substeps = 0;
};

struct LoadCurve {
    double gasMass = 0.0;                ///< [kg]
    double unloadedHeight = 0.0;         ///< top of the inflated bag before loading [m]
    double inflatedVolume = 0.0;         ///< [m^3] total
    double inflatedGaugePressure = 0.0;  ///< [Pa]
    std::vector<LoadStep> steps;
    double stiffness = 0.0;  ///< slope over the stiffness range [N/m]
    double r2 = 0.0;         ///< linearity of that range
    int stage = 0;           ///< 1, 2 or 3 (rule in docs/seed-load-test.md)
    bool reachedPeak = false;
    std::string failure;  ///< empty, or why the curve stopped early
    bool failed = false;  ///< a step could not be solved (not a bottoming out)
    /// The curve left the model's envelope and was stopped there (`failure` says how): the
    /// block force fell by more than kForceFallShare of the most it had reached (and by more
    /// than the stiffness range's start) while the block pressed deeper at a fixed gas mass,
    /// which a sealed bag cannot do: the film let the block through.
    bool outsideEnvelope = false;
    int stabilizedSteps = 0;  ///< steps accepted with the stabilisation springs
    /// Largest ratio, over the loading steps, of the energy the stabilisation springs held at
    /// the accepted states so far (LoadStep::stabilizationEnergy summed) to the work the block
    /// has done so far [-]:
    /// how far the curve is from a true equilibrium path
    /// (Abaqus' rule of thumb for its automatic stabilisation: keep it below about 0.05).
    double stabilizationShare = 0.0;
    /// Snaps the displacement control stepped over: where no equilibrium could be found near
    /// the last one at any step down to the smallest (a fold snapping through under the block),
    /// the block went on by 1, 2 or 4 displacement steps and the curve continued from the
    /// equilibrium found there, with no points in between. Their number and the block travel
    /// they span [m], loading and unloading together.
    int snaps = 0;
    double snapTravel = 0.0;
    /// Over the ensemble's bags (LoadTestOptions::ensemble; this curve's bag included): the
    /// least and largest stiffness [N/m] (NaN if any bag has none) and the number of bags.
    double stiffnessMin = 0.0;
    double stiffnessMax = 0.0;
    int ensembleSize = 1;
    /// Dynamic test: the slowest block speed [m/s] the curve's loading went at (its pace after
    /// any halvings, the start's ramp left out; 0: quasi-static), and the largest share of the film's kinetic energy in the block's
    /// work so far over the loading branch from stiffnessFrom on [-] (or at its end if it
    /// never gets there). Above LoadTestOptions::Dynamic::kineticShareLimit the curve is not
    /// quasi-static: `quasiStatic` false and `failure` says so.
    double blockSpeed = 0.0;
    double kineticShare = 0.0;
    bool quasiStatic = true;
};

struct LoadTestResult {
    std::vector<LoadCurve> curves;
    std::vector<double>
        kFit;              ///< polynomial coefficients, highest power first, k in N/mm of m in g
    double seconds = 0.0;  ///< wall time of the solve
};

/// Called after each converged step with the step and the nodal positions (3 x N).
using LoadTestObserver = std::function<void(const LoadStep&, const Mesh&, const Eigen::Matrix3Xd&)>;

/// The load test's way over a fold that snaps through under the block. When no equilibrium is
/// found near the last one (block travel `from`) at any step down to the smallest, the
/// equilibrium branch has turned back: the film snaps to another shape at about that travel.
/// The block then goes on from the last equilibrium by 1, 2 and 4 displacement steps in the
/// direction `dir` (+1 loading, -1 unloading), never past `limit`, skipping any not longer than
/// the step that failed (`tried`); `tryTravel(to)` solves the bag at travel `to` from the last
/// equilibrium and keeps it if it converges. Returns the travel of the first that converged, or
/// -1 if none did. The curve has no points in between (LoadCurve::snaps, snapTravel).
double stepOverSnap(const std::function<bool(double)>& tryTravel, double from, double tried,
                    double dir, double limit, double displacementStep);

LoadTestResult runLoadTest(const LoadTestOptions& options, const LoadTestObserver& observer = {});

/// The share of the most force a loading has reached by which the block force may fall while
/// the block presses deeper before the curve is outside the model's envelope
/// (LoadCurve::outsideEnvelope). A sealed bag's force rises as the block goes down; a fold
/// snapping through under the block loses a little of it for a step.
inline constexpr double kForceFallShare = 0.25;

/// [N] the most of the peak force that LoadTestOptions::residualTolerance scales.
inline constexpr double kToleranceForceCap = 50.0;
/// The bag's force tolerance [N] for these options (see residualTolerance).
double calcLoadTestForceTolerance(const LoadTestOptions& options);
/// The airbag the load test drives (geometry, material, gas, contact, solver of the options);
/// with neighbours, a cluster whose bag 0 is the pressed one.
AirbagSpec makeAirbagSpec(const LoadTestOptions& options);
/// The bag's dynamic options for the dynamic test at block speed `blockSpeed` [m/s]: the
/// options' massScale and damping carried into the test's time (LoadTestOptions::Dynamic).
DynamicOptions calcLoadTestDynamics(const LoadTestOptions& options, double blockSpeed);
/// Poses of the bags of the module (bag 0, the pressed one, at the identity) for the options'
/// neighbours layout; empty for Neighbours::None (one bag, no cluster).
std::vector<Eigen::Isometry3d> calcNeighbourPoses(const LoadTestOptions& options);

/// Stiffness of a curve's loading branch over the force range [from, to] [N]: least-squares
/// slope [N/m] and r^2 of force against displacement; NaN for both when the loading never
/// reached `to` or fewer than three loading steps lie in the range.
LinearFit calcRangeStiffness(const std::vector<LoadStep>& steps, double from, double to);

/// Sets LoadCurve::stage: stage 3 for masses below the one of least stiffness (stiffness rises
/// again as gas is let out); above it, stage 1 where the stiffness range is linear
/// (r2 >= linearR2) and stage 2 where it is not (kinked curves). Curves without a stiffness
/// get stage 0.
void classifyStages(std::vector<LoadCurve>& curves, double linearR2 = 0.995);

/// Seed's published fit k(m) [N/mm], m in g: highest power first.
std::vector<double> getSeedStiffnessPolynomial();

}  // namespace bags
