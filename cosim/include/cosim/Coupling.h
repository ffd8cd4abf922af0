#pragma once
/// @file The staggered co-simulation of one body and N participants (bags): the coupling
/// schemes, their convergence measure, and the macro-step loop.
///
/// Order of calls: construct with the body (initialized), the participants (their shapes
/// added, bags inflated) and the links (which body shape meets which participant shape);
/// initialize() evaluates the participants at the body's initial poses (dt = 0, committed);
/// then step() per macro step. step() either commits the body and every participant at
/// t + dt, or throws bags::NumericalError (a participant could not reach the poses, or the
/// implicit iterations did not converge) with every side rolled back to t, so the caller may
/// cut the step (setMacroStep()) and call step() again.
///
/// Schemes (docs/cosim.md), every one body first, then the bags (Gauss-Seidel):
///  - Explicit: the body integrates over [t, t + dt] under the wrenches the bags returned at
///    t, held constant (zero-order hold); the bags then advance to the body's poses at
///    t + dt. One pass.
///  - Implicit: the same pass repeated from the checkpoint, the wrench the body is held at
///    being the unknown x (torques divided by torqueLength, so all entries are forces): H(x)
///    is what the bags return at the body's end poses. Iterations stop when
///    |H(x) - x| <= relativeTolerance |H(x)| + absoluteTolerance (2-norms over every link),
///    the next x from an Accelerator (constant relaxation, Aitken or IQN-ILS).
///  - Tangent: the body integrates under W(t) + T(t) d(X(t), X) + G(t) dm (s - t) / dt (the
///    bags' wrench linearised in the shape's pose by its tangent and in the gas dm the bag
///    takes in over the step, inside the body's own step through a Force::Custom); the bags
///    then advance to the end poses and return W, T and G there. One pass.
///  - Tangent-implicit: the tangent scheme's pass repeated from the checkpoint while the bags'
///    wrench at the end poses misses the linearised load: the unknown x is a correction c
///    added to it (W(t) + c + T(t) d), iterated by the accelerator to the implicit scheme's
///    tolerance. One pass where the tangent predicts well, more at contact changes.
///    With tangentTolerance a bag's tangents are kept while they predict well; with
///    skipTravel a bag with no gas flowing whose shapes hardly moved is not solved.
/// For the one-pass schemes the step's mismatch |H(x) - x| (x the load the body saw at the
/// end pose) is reported in the same measure.

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "cosim/Acceleration.h"
#include "cosim/BodyParticipant.h"
#include "cosim/Participant.h"

namespace cosim {

enum class Scheme { Explicit, Implicit, Tangent, TangentImplicit };
enum class AccelerationKind { Constant, Aitken, IQNILS };
enum class Threading { PerCall, OpenMP };

/// Parses "explicit", "implicit", "tangent", "tangent-implicit" (throws
/// std::invalid_argument listing them).
Scheme parseScheme(const std::string& name);
std::string toString(Scheme scheme);
/// Parses "constant", "aitken", "iqn-ils".
AccelerationKind parseAcceleration(const std::string& name);
std::string toString(AccelerationKind kind);

struct CouplingOptions {
    Scheme scheme = Scheme::Implicit;
    AccelerationKind acceleration = AccelerationKind::IQNILS;
    double macroStep = 1e-3;          ///< [s]
    double relativeTolerance = 1e-5;  ///< [-] of |H(x)|
    /// [N] must lie above the bags' own solve tolerance (bags::AirbagSpec::forceTolerance,
    /// 0.05 N by default): the wrench a bag returns is no more exact than that. A pass in
    /// which participants were kept short of their equilibrium (ParticipantStep::
    /// unresolvedForce) adds the sum of their forces to the tolerance: their wrenches are no
    /// more exact than that either (StepSummary::unresolvedForce).
    double absoluteTolerance = 0.1;
    double torqueLength = 0.1;       ///< [m] torques count as torque / torqueLength [N]
    int maxIterations = 50;          ///< implicit iterations per macro step
    double initialRelaxation = 0.5;  ///< [-] first iteration of a step (and Constant)
    int reuseSteps = 0;              ///< IQN-ILS: earlier steps whose secants are kept
    double filter = 1e-10;           ///< IQN-ILS QR filter
    bool parallel = true;            ///< participants on threads (one at a time each)
    /// Threads for the participants: 0 one per core (std::thread::hardware_concurrency).
    int threads = 0;
    /// Threads made per call (nothing waits between calls), or an OpenMP team (its idle
    /// threads may spin while the body steps, which costs on a loaded machine; docs/cosim.md).
    Threading threading = Threading::PerCall;
    /// [m] largest travel of a linked shape's origin in one step (0: no limit). A bag moves a
    /// shape along a straight line in sub-steps of up to a mesh size; a shape that travels
    /// more than its half-thickness in one step can come out on the wrong side of the
    /// membrane (docs/cosim.md), so a step that moves a shape further is refused.
    double maxShapeTravel = 0.0;
    /// [N] Tangent scheme: a participant's tangents are recomputed only after a step in which
    /// one of its links' wrench missed the linearised load the body felt by more than this
    /// (measured as the implicit residual, torques divided by torqueLength); otherwise the
    /// last ones are kept (they only shape the load inside the step: the wrench at each
    /// step's end is the participant's own). 0: recomputed every step.
    double tangentTolerance = 0.0;
    /// Tangent schemes: the linearised load also follows the gas each participant lets in or
    /// out over the step (Participant::calcWrenchLinearisation()'s gas derivatives times its
    /// calcGasInflow(), ramped over the step), so that a bag being filled or let down is
    /// predicted as well as one being pressed. false: the poses only (the gas's effect is
    /// left to the next step, or to tangent-implicit's passes).
    bool gasTangent = true;
    /// [m] Tangent scheme: a participant that is steady (Participant::isSteady(), no gas
    /// flowing) and whose linked shapes have all moved less than this since it was last
    /// advanced (translation of the origin plus rotation angle times Link::reach) is not
    /// advanced: its links keep their linearised load W0 + T d about the poses of its last
    /// advance, and it is advanced again once a shape moves further or its gas flows. An
    /// untouched bag of a patient at rest then costs nothing. 0: every participant is
    /// advanced every step.
    double skipTravel = 0.0;
    /// stepAdaptive(): the smallest step a failing step is halved to [s] (adaptive: also the
    /// smallest step the accuracy control chooses).
    double minMacroStep = 1e-6;
    /// stepAdaptive(): steps in a row that must succeed before the step is doubled again
    /// (never beyond the largest step, the macroStep the coupling was built with).
    int growAfter = 4;
    /// stepAdaptive(): the step follows the accuracy of each step (docs/cosim.md, "Adaptive
    /// macro step") between minMacroStep and maxMacroStep, macroStep being the first step;
    /// false: the step is the user's, halved only when it fails (growAfter).
    bool adaptive = false;
    double maxMacroStep = 0.04;  ///< [s] adaptive: the largest step
    /// [-] adaptive: the step's accuracy measure aimed at, as a multiple of the coupling
    /// tolerance relativeTolerance |H| + absoluteTolerance of its first pass: the linearised
    /// schemes' miss, the hold schemes' change of the interface wrench over the step. A step
    /// whose measure exceeds it is redone smaller; one well inside it lets the next one grow.
    double stepAccuracy = 1000.0;
    /// adaptive, implicit and tangent-implicit: passes a step aimed at; a step that needed
    /// more makes the next one smaller (never redone for it: it converged).
    int targetPasses = 4;
    double maxGrowth = 2.0;  ///< adaptive: the largest factor from one step to the next
    /// [s] adaptive: the smallest step a failing step is halved to (below minMacroStep, which
    /// bounds only the steps chosen for accuracy: a bag that cannot follow may need less).
    double minCutStep = 1e-5;
    /// stepAdaptive(): a step of the implicit schemes whose passes did not converge at the
    /// smallest step (minCutStep, minMacroStep) is kept, with the pass of the least residual,
    /// instead of failing: StepSummary::converged is then false and the caller says so (a
    /// patient run is partial). A film whose equilibrium jumps as the body moves (a fold
    /// giving way) leaves the coupling no fixed point at any step (docs/cosim.md#the-schemes).
    /// false: such a step throws bags::NumericalError.
    bool keepUnconverged = false;
    /// [N] implicit schemes: once a step's passes stall short of the tolerance (no pass has
    /// lowered the least |H(x) - x| by 1 % in kStallPasses passes, or the last pass,
    /// maxIterations, is reached), the first pass within
    /// this is accepted at the step's size: StepSummary::accepted. A film near a fold has many
    /// equilibria a few mN apart, so its wrench is not a function of the poses to better than
    /// that, and the passes cannot reach a tolerance below it at any step
    /// (docs/cosim.md#the-schemes); halving the step to the smallest then costs hundreds of
    /// passes for nothing the outputs can show. Passes that do not come within it run on to
    /// maxIterations, and the step is cut as before. |H(x) - x| is the norm over every link,
    /// so each link's share lies within it too. 0 (the default): only the tolerance is
    /// accepted.
    double acceptResidual = 0.0;
    /// Passes without a 1 % lower least residual after which a step counts as stalled
    /// (acceptResidual).
    static constexpr int kStallPasses = 8;
    void validate() const;  ///< throws std::invalid_argument naming the option
};

/// Body shape `bodyShape` meets shape `shape` of participant `participant`.
struct Link {
    int bodyShape = 0;
    int participant = 0;
    int shape = 0;
    /// [m] how far the shape reaches from its frame's origin: CouplingOptions::skipTravel
    /// counts a rotation by the angle times this (0: rotations not counted).
    double reach = 0.0;
};

/// What one macro step did.
struct StepSummary {
    int step = 0;        ///< index of the macro step (0 the first)
    double time = 0.0;   ///< [s] at its end
    int iterations = 0;  ///< passes (1 for the one-pass schemes)
    /// implicit: within tolerance; one-pass schemes: true; false only for a step kept
    /// unconverged at the smallest step (CouplingOptions::keepUnconverged)
    bool converged = true;
    /// converged to CouplingOptions::acceptResidual, not to the tolerance: the passes stalled
    /// (residual then says where)
    bool accepted = false;
    double residual = 0.0;       ///< [N] |H(x) - x| of the last pass (scaled as above)
    double wrenchNorm = 0.0;     ///< [N] |H(x)| of the last pass
    int bagIterations = 0;       ///< Newton iterations over every participant and pass
    double macroStep = 0.0;      ///< [s] the step taken
    int cuts = 0;                ///< stepAdaptive(): halvings before this step succeeded
    double shapeTravel = 0.0;    ///< [m] the largest travel of a linked shape's origin
    double firstResidual = 0.0;  ///< [N] |H(x) - x| of the first pass (scaled as above)
    /// [N] the coupling tolerance at the first pass, relativeTolerance |H| + absoluteTolerance
    double tolerance = 0.0;
    /// adaptive: the step's measure over its target (CouplingOptions::stepAccuracy); above 1
    /// only where the step could not be made smaller
    double accuracyRatio = 0.0;
    int redone = 0;  ///< adaptive: attempts redone smaller because their measure was above 1
    /// The link whose |H(x) - x| was largest at the first and at the last pass (-1: no
    /// links), and that link's share [N] (scaled as above): where a step's passes go.
    int firstWorstLink = -1, lastWorstLink = -1;
    double firstWorstMiss = 0.0, lastWorstMiss = 0.0;
    /// [N] the largest sum over a pass of the participants' ParticipantStep::unresolvedForce:
    /// the implicit tolerance was widened by it (0 when every participant reached its
    /// equilibrium).
    double unresolvedForce = 0.0;
};

/// Where a coupling's wall time went, summed over the steps since the last resetProfile()
/// (failed and cut steps included). Read by bench/CosimBench.cpp (docs/performance.md).
struct CouplingProfile {
    int steps = 0;             ///< step() calls (cut ones included)
    int passes = 0;            ///< body-then-bags passes
    double bodySeconds = 0.0;  ///< [s] wall in the body's advanceTo()
    double bagsSeconds = 0.0;  ///< [s] wall of the participants' sections (all threads at once)
    /// [s] the participants' own wall time summed over participants (advance and read-back):
    /// threads x bagsSeconds - bagBusySeconds is the time threads waited for one another.
    double bagBusySeconds = 0.0;
    double tangentSeconds = 0.0;             ///< [s] of bagBusySeconds in calcWrenchTangents()
    int threads = 1;                         ///< threads the participants ran on
    long tangentRefreshes = 0;               ///< participants' tangents computed (tangent scheme)
    long skipped = 0;                        ///< participant steps skipped (skipTravel)
    long advances = 0;                       ///< participant advance() calls
    long idleAdvances = 0;                   ///< of which returned with no solver iteration (stood)
    long solverIterations = 0;               ///< over every advance
    std::vector<double> participantSeconds;  ///< per participant [s]
    std::vector<long> participantIterations;  ///< per participant
};

class Coupling {
  public:
    /// The participants are not owned and must outlive the coupling.
    /// @throws std::invalid_argument if options or links are invalid.
    Coupling(BodyParticipant& body, std::vector<Participant*> participants, std::vector<Link> links,
             const CouplingOptions& options);
    ~Coupling();
    /// Evaluates the participants at the body's current poses (advance(0), commit); the
    /// wrenches (and tangents) found start the first step.
    void initialize();
    /// One macro step (see the file comment). @throws bags::NumericalError, sides rolled back.
    StepSummary step();
    /// One macro step that is halved, down to minMacroStep, while it fails (a participant
    /// that cannot follow, implicit iterations that do not converge, a shape that would
    /// travel more than maxShapeTravel), and ends at `until` [s] at the latest.
    /// Fixed (CouplingOptions::adaptive false): the step is doubled again after growAfter
    /// steps in a row succeed, up to the macroStep the coupling was built with; a step
    /// shortened to end at `until` leaves the step size as it was unless it had to be cut.
    /// Adaptive: the step follows each step's accuracy measure (a step above its target is
    /// redone smaller from the checkpoint; the next step grows by up to maxGrowth while the
    /// measure is well inside it), and a step that reaches `until` ends exactly there
    /// (getTime() == until); one that would leave less than its own size before `until` is
    /// split into two equal ones.
    /// @throws bags::NumericalError once even minMacroStep fails (sides rolled back).
    StepSummary stepAdaptive(double until = std::numeric_limits<double>::infinity());
    /// Changes the macro step from the next step on (time keeps counting from the last one).
    void setMacroStep(double dt);
    /// A function called at the start of every attempt of a macro step (a step cut and tried
    /// again calls it again) with the step's start time t [s] and size dt [s], before any side
    /// moves: what the participants are given for exactly that step (e.g. the gas flows a
    /// pneumatic network computed over [t, t + dt]). It may throw bags::NumericalError, which
    /// fails the attempt like a participant that cannot follow.
    void setBeforeStep(std::function<void(double t, double dt)> beforeStep);
    double getTime() const;   ///< [s] at the last committed step
    int getNumSteps() const;  ///< macro steps committed
    /// Wrench the participant returned on a link at the last committed step.
    ShapeWrench getLinkWrench(int link) const;
    /// Its tangent (Tangent scheme only; zero otherwise).
    const Mat6& getLinkTangent(int link) const;
    /// Its derivative by the participant's gas inputs [(N m, N)/kg] (tangent schemes with
    /// gasTangent; 6 x 0 otherwise).
    const Eigen::Matrix<double, 6, Eigen::Dynamic>& getLinkGasDerivative(int link) const;
    const CouplingOptions& getOptions() const;
    /// Where the time went since construction or the last resetProfile().
    const CouplingProfile& getProfile() const;
    void resetProfile();

    // --- checkpoints (bags/StateStream.h), between steps
    /// Writes the coupling's own state: time and step count, the current and largest macro
    /// step and the successes in a row (stepAdaptive()), every link's wrench, tangent and
    /// linearisation pose and gas derivative, the accelerator's memory. The body and the participants are
    /// written by their owner.
    void saveState(bags::StateWriter& w) const;
    /// Reads what saveState() wrote into a coupling built the same way and initialized.
    /// @throws bags::StateError if the links differ.
    void loadState(bags::StateReader& r);

  private:
    StepSummary stepFixed();  // the fixed step, halved on failure
    StepSummary stepFixed(double until);
    StepSummary stepAccurate(double until);
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cosim
