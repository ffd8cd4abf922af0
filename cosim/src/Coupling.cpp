#include "cosim/Coupling.h"

#include <bags/Types.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace cosim {

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

[[noreturn]] void invalid(const std::string& key, double value, const std::string& valid) {
    std::ostringstream s;
    s << "CouplingOptions: " << key << " = " << value << "; valid: " << valid;
    throw std::invalid_argument(s.str());
}

}  // namespace

Scheme parseScheme(const std::string& name) {
    if (name == "explicit") return Scheme::Explicit;
    if (name == "implicit") return Scheme::Implicit;
    if (name == "tangent") return Scheme::Tangent;
    if (name == "tangent-implicit") return Scheme::TangentImplicit;
    throw std::invalid_argument("coupling scheme '" + name +
                                "'; valid: explicit, implicit, tangent, tangent-implicit");
}

std::string toString(Scheme scheme) {
    switch (scheme) {
        case Scheme::Explicit:
            return "explicit";
        case Scheme::Implicit:
            return "implicit";
        case Scheme::Tangent:
            return "tangent";
        case Scheme::TangentImplicit:
            return "tangent-implicit";
    }
    return "?";
}

AccelerationKind parseAcceleration(const std::string& name) {
    if (name == "constant") return AccelerationKind::Constant;
    if (name == "aitken") return AccelerationKind::Aitken;
    if (name == "iqn-ils") return AccelerationKind::IQNILS;
    throw std::invalid_argument("coupling acceleration '" + name +
                                "'; valid: constant, aitken, iqn-ils");
}

std::string toString(AccelerationKind kind) {
    switch (kind) {
        case AccelerationKind::Constant:
            return "constant";
        case AccelerationKind::Aitken:
            return "aitken";
        case AccelerationKind::IQNILS:
            return "iqn-ils";
    }
    return "?";
}

void CouplingOptions::validate() const {
    if (!(macroStep > 0.0) || !std::isfinite(macroStep))
        invalid("macroStep", macroStep, "a positive time step [s]");
    if (!(relativeTolerance >= 0.0 && relativeTolerance < 1.0))
        invalid("relativeTolerance", relativeTolerance, "0 <= tolerance < 1");
    if (!(absoluteTolerance >= 0.0) || !std::isfinite(absoluteTolerance))
        invalid("absoluteTolerance", absoluteTolerance, "0 or a positive force [N]");
    if (relativeTolerance == 0.0 && absoluteTolerance == 0.0)
        invalid("relativeTolerance", 0.0, "a positive value when absoluteTolerance is 0");
    if (!(torqueLength > 0.0) || !std::isfinite(torqueLength))
        invalid("torqueLength", torqueLength, "a positive length [m]");
    if (maxIterations < 1) invalid("maxIterations", maxIterations, "1 or more");
    if (!(initialRelaxation > 0.0 && initialRelaxation <= 1.0))
        invalid("initialRelaxation", initialRelaxation, "0 < relaxation <= 1");
    if (reuseSteps < 0) invalid("reuseSteps", reuseSteps, "0 or more");
    if (!(filter >= 0.0 && filter < 1.0)) invalid("filter", filter, "0 <= filter < 1");
    if (!(maxShapeTravel >= 0.0) || !std::isfinite(maxShapeTravel))
        invalid("maxShapeTravel", maxShapeTravel, "0 (no limit) or a positive length [m]");
    if (!(minMacroStep > 0.0 && minMacroStep <= macroStep))
        invalid("minMacroStep", minMacroStep, "a positive step no larger than macroStep");
    if (growAfter < 1) invalid("growAfter", growAfter, "1 or more");
    if (adaptive) {
        if (!(maxMacroStep >= macroStep) || !std::isfinite(maxMacroStep))
            invalid("maxMacroStep", maxMacroStep, "a step no smaller than macroStep [s]");
        if (!(stepAccuracy > 0.0) || !std::isfinite(stepAccuracy))
            invalid("stepAccuracy", stepAccuracy, "a positive multiple of the tolerance");
        if (targetPasses < 2) invalid("targetPasses", targetPasses, "2 or more");
        if (!(maxGrowth > 1.0 && maxGrowth <= 10.0))
            invalid("maxGrowth", maxGrowth, "1 < factor <= 10");
        if (!(minCutStep > 0.0)) invalid("minCutStep", minCutStep, "a positive step [s]");
    }
    if (threads < 0) invalid("threads", threads, "0 (one per core) or more");
    if (!(skipTravel >= 0.0) || !std::isfinite(skipTravel))
        invalid("skipTravel", skipTravel, "0 (never skip) or a positive length [m]");
    if (!(tangentTolerance >= 0.0) || !std::isfinite(tangentTolerance))
        invalid("tangentTolerance", tangentTolerance, "0 (every step) or a positive force [N]");
    if (!(acceptResidual >= 0.0) || !std::isfinite(acceptResidual))
        invalid("acceptResidual", acceptResidual, "0 (off) or a positive force [N]");
}

using GasDerivative = Eigen::Matrix<double, 6, Eigen::Dynamic>;

struct Coupling::Impl {
    BodyParticipant& body;
    std::vector<Participant*> participants;
    std::vector<Link> links;
    CouplingOptions options;
    std::unique_ptr<Accelerator> accelerator;
    std::vector<std::vector<int>> linksOf;  // per participant
    std::vector<ShapeWrench> W;             // per link, at the checkpoint
    std::vector<Mat6> T;
    std::vector<GasDerivative> G;  // per link: d wrench / d gas inputs of its participant
    std::vector<Eigen::Isometry3d> X0;
    double baseTime = 0.0;  // time when the macro step was last set
    int stepsSinceBase = 0;
    double largestStep = 0.0;  // the macroStep the coupling was built with
    std::function<void(double, double)> beforeStep;
    int goodInARow = 0;  // stepAdaptive(): successes at the current step
    int steps = 0;
    bool initialized = false;
    CouplingProfile profile;
    // [N] per participant, the force its last advance was kept short of its equilibrium by
    // (ParticipantStep::unresolvedForce; a skipped participant keeps its last).
    std::vector<double> unresolved;

    Impl(BodyParticipant& b, std::vector<Participant*> p, std::vector<Link> l,
         const CouplingOptions& o)
        : body(b), participants(std::move(p)), links(std::move(l)), options(o) {}

    Eigen::VectorXd pack(const std::vector<ShapeWrench>& w) const {
        Eigen::VectorXd x(6 * links.size());
        for (size_t i = 0; i < links.size(); ++i) {
            x.segment<3>(6 * i) = w[i].torque / options.torqueLength;
            x.segment<3>(6 * i + 3) = w[i].force;
        }
        return x;
    }
    // |a - b| in the implicit residual's measure (torques divided by torqueLength).
    double scaledNorm(const ShapeWrench& a, const ShapeWrench& b) const {
        Vec6 d;
        d << (a.torque - b.torque) / options.torqueLength, a.force - b.force;
        return d.norm();
    }
    ShapeWrench unpack(const Eigen::VectorXd& x, int i) const {
        ShapeWrench w;
        w.torque = x.segment<3>(6 * i) * options.torqueLength;
        w.force = x.segment<3>(6 * i + 3);
        return w;
    }

    // Runs work(p) for every participant on the threads the options give (one participant
    // per thread at a time); returns the number of threads.
    template <class Work>
    int runParticipants(const Work& work) const {
        const int np = int(participants.size());
        const int nt = std::min(np, options.parallel ? calcThreads() : 1);
        if (nt <= 1) {
            for (int p = 0; p < np; ++p) work(p);
        } else if (options.threading == Threading::OpenMP) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
            for (int p = 0; p < np; ++p) work(p);
        } else {
            // Threads made for this call: nothing spins between calls, while the body steps.
            std::atomic<int> next{0};
            auto loop = [&] {
                for (int p = next++; p < np; p = next++) work(p);
            };
            std::vector<std::thread> team;
            for (int k = 1; k < nt; ++k) team.emplace_back(loop);
            loop();
            for (std::thread& th : team) th.join();
        }
        return std::max(1, nt);
    }

    // Rolls every side back and throws for the first participant that failed.
    void throwIfFailed(const std::vector<std::exception_ptr>& errors,
                       const std::vector<int>& failed, double dt) {
        for (size_t p = 0; p < errors.size(); ++p)
            if (errors[p] || failed[p]) {
                rollbackAll();
                if (errors[p]) std::rethrow_exception(errors[p]);
                std::ostringstream m;
                m << "Coupling: participant " << p << " could not reach the body's poses at t = "
                  << baseTime + (stepsSinceBase + 1) * options.macroStep << " s (macro step "
                  << steps << ", dt = " << dt << " s); cut the macro step";
                throw bags::NumericalError(m.str(), baseTime + stepsSinceBase * options.macroStep,
                                           steps);
            }
    }

    // Every participant not skipped to the body's current end poses over dt; the wrench per
    // link into w (a skipped participant's links keep W). Returns the Newton iterations;
    // throws with everything rolled back if a participant fails.
    int advanceParticipants(double dt, std::vector<ShapeWrench>& w,
                            const std::vector<char>* skip = nullptr) {
        std::vector<ShapeState> states(links.size());
        for (size_t i = 0; i < links.size(); ++i)
            states[i] = body.getShapeState(links[i].bodyShape);
        const int np = int(participants.size());
        std::vector<std::exception_ptr> errors(np);
        std::vector<int> failed(np, 0), iterations(np, 0);
        unresolved.resize(np, 0.0);
        std::vector<double> busy(np, 0.0);
        w.assign(links.size(), ShapeWrench());
        const auto start = std::chrono::steady_clock::now();
        auto skipped = [&](int p) { return skip && (*skip)[p]; };
        const int nt = runParticipants([&](int p) {
            if (skipped(p)) {
                for (int i : linksOf[p]) w[i] = W[i];
                return;
            }
            const auto t0 = std::chrono::steady_clock::now();
            try {
                Participant& part = *participants[p];
                for (int i : linksOf[p]) part.setShapeState(links[i].shape, states[i]);
                const ParticipantStep s = part.advance(dt);
                iterations[p] = s.solverIterations;
                unresolved[p] = s.unresolvedForce;
                if (s.converged)
                    for (int i : linksOf[p]) w[i] = part.calcWrench(links[i].shape);
                else
                    failed[p] = 1;
            } catch (...) {
                errors[p] = std::current_exception();
            }
            busy[p] = secondsSince(t0);
        });
        int total = 0;
        CouplingProfile& pr = profile;
        pr.bagsSeconds += secondsSince(start);
        pr.threads = nt;
        pr.participantSeconds.resize(np, 0.0);
        pr.participantIterations.resize(np, 0);
        for (int p = 0; p < np; ++p) {
            if (skipped(p)) {
                ++pr.skipped;
                continue;
            }
            total += iterations[p];
            pr.bagBusySeconds += busy[p];
            pr.participantSeconds[p] += busy[p];
            pr.participantIterations[p] += iterations[p];
            pr.solverIterations += iterations[p];
            ++pr.advances;
            if (iterations[p] == 0) ++pr.idleAdvances;
        }
        throwIfFailed(errors, failed, dt);
        return total;
    }

    // The tangents (and with gasTangent the gas derivatives) of the participants marked in
    // `which`, at their current states, into t and g (per link); the others' entries are left
    // as they are. Throws with everything rolled back if one fails.
    void refreshTangents(const std::vector<char>& which, std::vector<Mat6>& t,
                         std::vector<GasDerivative>& g) {
        const int np = int(participants.size());
        std::vector<std::exception_ptr> errors(np);
        std::vector<double> busy(np, 0.0);
        const auto start = std::chrono::steady_clock::now();
        runParticipants([&](int p) {
            if (!which[p] || linksOf[p].empty()) return;
            const auto t0 = std::chrono::steady_clock::now();
            try {
                std::vector<int> shapes;
                for (int i : linksOf[p]) shapes.push_back(links[i].shape);
                const Participant::WrenchLinearisation lp =
                    options.gasTangent ? participants[p]->calcWrenchLinearisation(shapes)
                                       : Participant::WrenchLinearisation{
                                             participants[p]->calcWrenchTangents(shapes), {}};
                for (size_t k = 0; k < shapes.size(); ++k) {
                    t[linksOf[p][k]] = lp.pose.at(k);
                    g[linksOf[p][k]] = lp.gas.empty() ? GasDerivative(6, 0) : lp.gas.at(k);
                }
            } catch (...) {
                errors[p] = std::current_exception();
            }
            busy[p] = secondsSince(t0);
        });
        CouplingProfile& pr = profile;
        pr.bagsSeconds += secondsSince(start);
        pr.participantSeconds.resize(np, 0.0);
        pr.participantIterations.resize(np, 0);
        for (int p = 0; p < np; ++p) {
            if (!which[p]) continue;
            pr.bagBusySeconds += busy[p];
            pr.tangentSeconds += busy[p];
            pr.participantSeconds[p] += busy[p];
            ++pr.tangentRefreshes;
        }
        throwIfFailed(errors, std::vector<int>(np, 0), 0.0);
    }

    // The participants left standing this step (CouplingOptions::skipTravel), the body at
    // its end poses.
    std::vector<char> findSkipped() const {
        std::vector<char> skip(participants.size(), 0);
        if (!isLinearised() || !(options.skipTravel > 0.0)) return skip;
        for (size_t p = 0; p < participants.size(); ++p) {
            if (!participants[p]->isSteady()) continue;
            bool near = true;
            for (int i : linksOf[p]) {
                const Eigen::Isometry3d X = body.getShapeState(links[i].bodyShape).X_GS;
                const Eigen::AngleAxisd turn(
                    Eigen::Matrix3d(X.linear() * X0[i].linear().transpose()));
                const double travel = (X.translation() - X0[i].translation()).norm() +
                                      std::abs(turn.angle()) * links[i].reach;
                near = near && travel <= options.skipTravel;
            }
            skip[p] = near;
        }
        return skip;
    }

    bool isLinearised() const {
        return options.scheme == Scheme::Tangent || options.scheme == Scheme::TangentImplicit;
    }

    int calcThreads() const {
        if (options.threads > 0) return options.threads;
        return std::max(1, int(std::thread::hardware_concurrency()));
    }

    void rollbackAll() {
        body.rollback();
        for (Participant* p : participants) p->rollback();
    }

    StepSummary runStep(double t, double dt, double tEnd, bool judge, bool& rejected);
    /// Set by the steppers while they try a step at the smallest size with
    /// CouplingOptions::keepUnconverged: runStep() then keeps a step that did not converge.
    bool lastResort = false;

    // The order in dt of a step's accuracy measure, taken as 1 for every scheme: a held
    // load's change over the step (explicit; the first implicit pass) is first order; the
    // linearisation's miss would be second order for a smooth bag, but every node that enters
    // or leaves contact within the step adds a force the tangent did not know, in proportion
    // to its travel (measured at the patient's landing: a miss of 1-5 N at 1 ms steps, 46-150 N
    // at 30-32 ms). Taking the lower order shrinks enough at once and grows cautiously.
    static constexpr double kMeasureOrder = 1.0;

    // The adaptive step's measure over its target (1: on target): the first pass's
    // |H(x) - x| over stepAccuracy times the coupling tolerance.
    double calcAccuracyRatio(const StepSummary& s) const {
        return s.firstResidual / (options.stepAccuracy * s.tolerance);
    }

    // The factor from a step of summary s to the next: the measure brought to half its
    // target at its order (it scatters by a factor of a few from step to step at the
    // patient's landing, so aiming at the target itself had a step in four redone), the
    // passes of the iterated schemes to targetPasses (first order), bounded by 0.2 and
    // maxGrowth.
    double calcStepFactor(const StepSummary& s) const {
        constexpr double safety = 0.5, smallest = 0.2;
        const double ratio = calcAccuracyRatio(s);
        double f = ratio > 0.0 ? safety * std::pow(ratio, -1.0 / kMeasureOrder) : options.maxGrowth;
        const bool iterated =
            options.scheme == Scheme::Implicit || options.scheme == Scheme::TangentImplicit;
        if (iterated && s.iterations > options.targetPasses)
            f = std::min(f, double(options.targetPasses - 1) / double(s.iterations - 1));
        return std::clamp(f, smallest, options.maxGrowth);
    }

    // Time restarts at t with steps of dt (Coupling::getTime() == t).
    void restartAt(double t, double dt) {
        baseTime = t;
        stepsSinceBase = 0;
        options.macroStep = dt;
    }
};

Coupling::Coupling(BodyParticipant& body, std::vector<Participant*> participants,
                   std::vector<Link> links, const CouplingOptions& options)
    : m_impl(std::make_unique<Impl>(body, std::move(participants), std::move(links), options)) {
    options.validate();
    Impl& m = *m_impl;
    m.largestStep = options.macroStep;
    m.linksOf.resize(m.participants.size());
    for (size_t i = 0; i < m.links.size(); ++i) {
        const Link& l = m.links[i];
        std::ostringstream s;
        s << "Coupling: link " << i << ": ";
        if (l.bodyShape < 0 || l.bodyShape >= body.getNumShapes()) {
            s << "body shape " << l.bodyShape << "; valid: 0.." << body.getNumShapes() - 1;
            throw std::invalid_argument(s.str());
        }
        if (l.participant < 0 || l.participant >= int(m.participants.size()) ||
            !m.participants[l.participant]) {
            s << "participant " << l.participant << "; valid: 0.." << m.participants.size() - 1;
            throw std::invalid_argument(s.str());
        }
        const int ns = m.participants[l.participant]->getNumShapes();
        if (l.shape < 0 || l.shape >= ns) {
            s << "shape " << l.shape << " of participant " << l.participant << "; valid: 0.."
              << ns - 1;
            throw std::invalid_argument(s.str());
        }
        for (int j : m.linksOf[l.participant])
            if (m.links[j].shape == l.shape) {
                s << "shape " << l.shape << " of participant " << l.participant
                  << " is already linked (link " << j << ")";
                throw std::invalid_argument(s.str());
            }
        m.linksOf[l.participant].push_back(int(i));
    }
    switch (options.acceleration) {
        case AccelerationKind::Constant:
            m.accelerator = std::make_unique<ConstantRelaxation>(options.initialRelaxation);
            break;
        case AccelerationKind::Aitken:
            m.accelerator = std::make_unique<AitkenRelaxation>(options.initialRelaxation);
            break;
        case AccelerationKind::IQNILS:
            m.accelerator = std::make_unique<IQNILS>(options.initialRelaxation, options.reuseSteps,
                                                     options.filter);
            break;
    }
}

Coupling::~Coupling() = default;

void Coupling::initialize() {
    Impl& m = *m_impl;
    m.body.rollback();
    m.advanceParticipants(0.0, m.W);
    m.T.assign(m.links.size(), Mat6::Zero());
    m.G.assign(m.links.size(), GasDerivative(6, 0));
    if (m.isLinearised()) m.refreshTangents(std::vector<char>(m.participants.size(), 1), m.T, m.G);
    for (Participant* p : m.participants) p->commit();
    m.X0.resize(m.links.size());
    for (size_t i = 0; i < m.links.size(); ++i)
        m.X0[i] = m.body.getShapeState(m.links[i].bodyShape).X_GS;
    m.baseTime = m.body.getTime();
    m.stepsSinceBase = 0;
    m.initialized = true;
}

StepSummary Coupling::step() {
    Impl& m = *m_impl;
    if (!m.initialized) throw std::logic_error("Coupling::step: initialize() first");
    const double dt = m.options.macroStep;
    bool rejected = false;
    const StepSummary s =
        m.runStep(getTime(), dt, m.baseTime + (m.stepsSinceBase + 1) * dt, false, rejected);
    ++m.stepsSinceBase;
    return s;
}

// One attempt of a macro step from t to tEnd = t + dt (see Coupling::step()); commits it
// unless `judge` and its accuracy measure is above its target (calcAccuracyRatio()) while dt
// is above the smallest step: then every side is rolled back and `rejected` set.
StepSummary Coupling::Impl::runStep(double t, double dt, double tEnd, bool judge, bool& rejected) {
    Impl& m = *this;
    const CouplingOptions& o = m.options;
    rejected = false;
    if (m.beforeStep) m.beforeStep(t, dt);
    const bool linearised = m.isLinearised();
    const size_t nl = m.links.size(), np = m.participants.size();
    StepSummary sum;
    sum.step = m.steps;
    sum.time = tEnd;
    ++m.profile.steps;
    // Implicit: x is the held load; tangent-implicit: x is the correction added to the
    // linearised load (zero: the tangent scheme's prediction).
    Eigen::VectorXd x = linearised ? Eigen::VectorXd::Zero(6 * nl) : m.pack(m.W);
    // The gas's share of the linearised load: its rate over the step per link (the
    // derivative times the gas the participant lets in over the step).
    std::vector<Vec6> gasRate(nl, Vec6::Zero());
    if (linearised && o.gasTangent && dt > 0.0)
        for (size_t p = 0; p < np; ++p) {
            if (m.linksOf[p].empty()) continue;
            const Eigen::VectorXd dm = m.participants[p]->calcGasInflow(dt);
            for (int i : m.linksOf[p])
                if (m.G[i].cols() > 0 && m.G[i].cols() == dm.size()) gasRate[i] = m.G[i] * dm / dt;
        }
    std::vector<ShapeWrench> w, seen(nl);
    std::vector<char> skip;         // participants left standing (skipTravel)
    std::vector<double> firstMiss;  // per participant: the linearisation's miss, first pass
    // The pass of least residual so far (the one kept if the step is kept unconverged), and
    // whether the pass under way is that pass again, taken after the last iteration.
    Eigen::VectorXd bestX;
    double bestResidual = std::numeric_limits<double>::infinity();
    bool finalPass = false;
    // The last pass that lowered the least residual by 1 % (CouplingOptions::acceptResidual:
    // passes stall after kStallPasses more).
    int lastGain = 0;
    double gainBase = std::numeric_limits<double>::infinity();
    m.accelerator->beginStep();
    for (int k = 0;; ++k) {
        m.body.rollback();
        for (size_t i = 0; i < nl; ++i) {
            const ShapeWrench xi = m.unpack(x, int(i));
            if (linearised) {
                ShapeWrench w0 = m.W[i];
                w0.torque += xi.torque;
                w0.force += xi.force;
                m.body.setShapeLoad(m.links[i].bodyShape, w0, m.T[i], m.X0[i], gasRate[i]);
            } else {
                m.body.setShapeLoad(m.links[i].bodyShape, xi);
            }
        }
        const auto bodyStart = std::chrono::steady_clock::now();
        m.body.advanceTo(tEnd);
        m.profile.bodySeconds += secondsSince(bodyStart);
        ++m.profile.passes;
        sum.shapeTravel = 0.0;
        for (size_t i = 0; i < nl; ++i)
            sum.shapeTravel = std::max(
                sum.shapeTravel, (m.body.getShapeState(m.links[i].bodyShape).X_GS.translation() -
                                  m.X0[i].translation())
                                     .norm());
        if (o.maxShapeTravel > 0.0 && sum.shapeTravel > o.maxShapeTravel) {
            m.rollbackAll();
            std::ostringstream s;
            s << "Coupling: a shape would travel " << sum.shapeTravel
              << " m in the macro step to t = " << tEnd << " s (step " << m.steps
              << "), more than maxShapeTravel = " << o.maxShapeTravel << " m; cut the macro step";
            throw bags::NumericalError(s.str(), tEnd - dt, m.steps);
        }
        // What the body saw at its end poses (x itself unless linearised).
        for (size_t i = 0; i < nl; ++i) seen[i] = m.body.calcShapeLoad(m.links[i].bodyShape);
        skip = m.findSkipped();
        sum.bagIterations += m.advanceParticipants(dt, w, &skip);
        sum.iterations = k + 1;
        // A skipped participant's links: the body felt their linearised load, which stands.
        std::vector<ShapeWrench> returned = w;
        for (size_t i = 0; i < nl; ++i)
            if (skip[m.links[i].participant]) returned[i] = seen[i];
        if (k == 0 && linearised) {
            firstMiss.assign(np, 0.0);
            for (size_t i = 0; i < nl; ++i) {
                double& f = firstMiss[m.links[i].participant];
                f = std::max(f, m.scaledNorm(returned[i], seen[i]));
            }
        }
        const Eigen::VectorXd Hx = m.pack(returned);
        const Eigen::VectorXd r = Hx - m.pack(seen);
        sum.residual = r.norm();
        sum.wrenchNorm = Hx.norm();
        sum.lastWorstLink = -1;
        sum.lastWorstMiss = 0.0;
        for (size_t i = 0; i < nl; ++i) {
            const double ri = r.segment<6>(6 * i).norm();
            if (ri > sum.lastWorstMiss || sum.lastWorstLink < 0) {
                sum.lastWorstLink = int(i);
                sum.lastWorstMiss = ri;
            }
        }
        if (k == 0) {
            sum.firstWorstLink = sum.lastWorstLink;
            sum.firstWorstMiss = sum.lastWorstMiss;
        }
        // The wrenches of a participant kept short of its equilibrium are resolved only to
        // the force it was kept with: the fixed point is sought to that too.
        const double unresolved = std::accumulate(m.unresolved.begin(), m.unresolved.end(), 0.0);
        sum.unresolvedForce = std::max(sum.unresolvedForce, unresolved);
        const double tolerance =
            o.relativeTolerance * sum.wrenchNorm + o.absoluteTolerance + unresolved;
        if (k == 0) {
            sum.firstResidual = sum.residual;
            sum.tolerance = tolerance;
        }
        if (o.scheme == Scheme::Explicit || o.scheme == Scheme::Tangent) break;
        if (sum.residual <= tolerance) break;
        if (finalPass) {  // the best pass again: kept as it came out
            sum.converged = false;
            break;
        }
        if (sum.residual < bestResidual) {
            bestResidual = sum.residual;
            bestX = x;
        }
        if (bestResidual < 0.99 * gainBase) {
            gainBase = bestResidual;
            lastGain = k;
        }
        // Stalled: a pass within acceptResidual is accepted at this step's size (this pass
        // itself, not the best one taken again: a bag's answer to the same poses may differ
        // by as much as the stall).
        const bool stalled =
            k - lastGain >= CouplingOptions::kStallPasses || k + 1 >= o.maxIterations;
        if (o.acceptResidual > 0.0 && stalled && sum.residual <= o.acceptResidual) {
            sum.accepted = true;
            break;
        }
        if (k + 1 >= o.maxIterations && m.lastResort) {
            sum.converged = false;
            if (sum.residual <= bestResidual) break;  // this pass is the best one
            x = bestX;
            finalPass = true;
            continue;
        }
        if (k + 1 >= o.maxIterations) {
            m.rollbackAll();
            std::ostringstream s;
            s << "Coupling: the implicit iterations did not converge in " << o.maxIterations
              << " iterations at t = " << tEnd << " s (macro step " << m.steps
              << "): |H(x) - x| = " << sum.residual << " N against a tolerance of " << tolerance
              << " N; cut the macro step or raise maxIterations";
            throw bags::NumericalError(s.str(), tEnd - dt, m.steps);
        }
        x = m.accelerator->next(x, linearised ? Eigen::VectorXd(x + r) : Hx);
    }
    sum.macroStep = dt;
    if (judge) {
        sum.accuracyRatio = m.calcAccuracyRatio(sum);
        if (sum.accuracyRatio > 1.0 && dt > o.minMacroStep * (1.0 + 1e-9)) {
            m.rollbackAll();
            rejected = true;
            return sum;
        }
    }
    m.accelerator->endStep();
    // The tangents at the new state, of the participants whose linearisation missed (all of
    // those advanced when tangentTolerance is 0).
    std::vector<Mat6> tangents = m.T;
    std::vector<GasDerivative> gasDerivatives = m.G;
    if (linearised) {
        std::vector<char> which(np, 0);
        for (size_t p = 0; p < np; ++p)
            which[p] =
                !skip[p] && (!(o.tangentTolerance > 0.0) || firstMiss[p] > o.tangentTolerance);
        m.refreshTangents(which, tangents, gasDerivatives);
    }
    m.body.commit();
    for (size_t p = 0; p < np; ++p)
        if (!skip[p]) m.participants[p]->commit();
    m.W = w;
    m.T = tangents;
    m.G = std::move(gasDerivatives);
    // A skipped participant's links keep their linearisation about its last poses.
    for (size_t i = 0; i < nl; ++i)
        if (!skip[m.links[i].participant])
            m.X0[i] = m.body.getShapeState(m.links[i].bodyShape).X_GS;
    ++m.steps;
    return sum;
}

StepSummary Coupling::stepAdaptive(double until) {
    return m_impl->options.adaptive ? stepAccurate(until) : stepFixed(until);
}

StepSummary Coupling::stepFixed(double until) {
    Impl& m = *m_impl;
    const double t = getTime(), dt = m.options.macroStep;
    if (t + dt <= until + 1e-12 * std::max(1.0, std::abs(until))) return stepFixed();
    setMacroStep(until - t);
    const StepSummary s = stepFixed();
    if (s.cuts == 0) setMacroStep(dt);
    return s;
}

StepSummary Coupling::stepAccurate(double until) {
    Impl& m = *m_impl;
    if (!m.initialized) throw std::logic_error("Coupling::stepAdaptive: initialize() first");
    const CouplingOptions& o = m.options;
    const double t = getTime();
    const double left = until - t;
    if (!(left > 0.0)) throw std::invalid_argument("Coupling::stepAdaptive: until is not ahead");
    double h = o.macroStep;  // the step proposed
    int cuts = 0, redone = 0;
    for (;;) {
        // Land on `until`, never leaving a sliver before it.
        double dt = h;
        const bool lands = dt >= left - 1e-12 * std::max(1.0, std::abs(until));
        if (lands)
            dt = left;
        else if (dt > 0.5 * left)
            dt = 0.5 * left;
        const double tEnd = lands ? until : t + dt;
        m.restartAt(t, dt);
        bool rejected = false;
        StepSummary s;
        m.lastResort = o.keepUnconverged && 0.5 * dt < std::min(o.minCutStep, o.minMacroStep);
        try {
            s = m.runStep(t, dt, tEnd, true, rejected);
            m.lastResort = false;
        } catch (const bags::NumericalError&) {
            m.lastResort = false;
            m.restartAt(t, h);
            if (0.5 * dt < std::min(o.minCutStep, o.minMacroStep)) throw;
            h = 0.5 * dt;
            ++cuts;
            continue;
        }
        const double f = m.calcStepFactor(s);
        if (rejected) {
            h = std::max(o.minMacroStep, dt * std::min(f, 0.9));
            ++redone;
            continue;
        }
        // The next step: grown or shrunk from this one; a step shortened to land (or split)
        // does not shrink the proposal unless its measure asks for it; no growth right after
        // a step was redone or cut.
        double next = f >= 1.0 ? std::max(h, dt * f) : dt * f;
        if (cuts + redone > 0) next = std::min(next, dt);
        next = std::clamp(next, o.minMacroStep, o.maxMacroStep);
        m.restartAt(tEnd, next);
        s.time = tEnd;
        s.cuts = cuts;
        s.redone = redone;
        return s;
    }
}

StepSummary Coupling::stepFixed() {
    Impl& m = *m_impl;
    int cuts = 0;
    for (;;) {
        m.lastResort =
            m.options.keepUnconverged && 0.5 * m.options.macroStep < m.options.minMacroStep;
        try {
            StepSummary s = step();
            m.lastResort = false;
            s.cuts = cuts;
            if (++m.goodInARow >= m.options.growAfter && m.options.macroStep < m.largestStep) {
                setMacroStep(std::min(2.0 * m.options.macroStep, m.largestStep));
                m.goodInARow = 0;
            }
            return s;
        } catch (const bags::NumericalError&) {
            m.lastResort = false;
            m.goodInARow = 0;
            const double half = 0.5 * m.options.macroStep;
            if (half < m.options.minMacroStep) throw;
            setMacroStep(half);
            ++cuts;
        }
    }
}

void Coupling::setBeforeStep(std::function<void(double t, double dt)> beforeStep) {
    m_impl->beforeStep = std::move(beforeStep);
}

void Coupling::setMacroStep(double dt) {
    CouplingOptions o = m_impl->options;
    o.macroStep = dt;
    o.minMacroStep = std::min(o.minMacroStep, dt);
    o.validate();
    m_impl->baseTime = getTime();
    m_impl->stepsSinceBase = 0;
    m_impl->options = o;
}

double Coupling::getTime() const {
    return m_impl->baseTime + m_impl->stepsSinceBase * m_impl->options.macroStep;
}
int Coupling::getNumSteps() const { return m_impl->steps; }
ShapeWrench Coupling::getLinkWrench(int link) const { return m_impl->W.at(link); }
const Mat6& Coupling::getLinkTangent(int link) const { return m_impl->T.at(link); }
const GasDerivative& Coupling::getLinkGasDerivative(int link) const { return m_impl->G.at(link); }
const CouplingOptions& Coupling::getOptions() const { return m_impl->options; }
const CouplingProfile& Coupling::getProfile() const { return m_impl->profile; }
void Coupling::resetProfile() { m_impl->profile = CouplingProfile(); }

void Coupling::saveState(bags::StateWriter& w) const {
    const Impl& m = *m_impl;
    if (!m.initialized) throw std::logic_error("Coupling::saveState: initialize() first");
    w.tag("coupling");
    w.pod(m.options.macroStep), w.pod(m.options.minMacroStep);
    w.pod(m.baseTime), w.pod(m.stepsSinceBase), w.pod(m.largestStep);
    w.pod(m.goodInARow), w.pod(m.steps);
    w.pod(std::uint64_t(m.links.size()));
    for (size_t i = 0; i < m.links.size(); ++i) {
        w.mat(m.W[i].torque), w.mat(m.W[i].force);
        w.mat(m.T[i]);
        w.pose(m.X0[i]);
        w.mat(m.G[i]);
    }
    m.accelerator->saveState(w);
}

void Coupling::loadState(bags::StateReader& r) {
    Impl& m = *m_impl;
    if (!m.initialized) throw std::logic_error("Coupling::loadState: initialize() first");
    r.tag("coupling");
    r.pod(m.options.macroStep), r.pod(m.options.minMacroStep);
    r.pod(m.baseTime), r.pod(m.stepsSinceBase), r.pod(m.largestStep);
    r.pod(m.goodInARow), r.pod(m.steps);
    const auto n = r.pod<std::uint64_t>();
    if (n != m.links.size()) bags::StateReader::mismatch("coupling links", n, m.links.size());
    for (size_t i = 0; i < m.links.size(); ++i) {
        Vec3 torque, force;
        r.mat(torque), r.mat(force);
        m.W[i].torque = torque;
        m.W[i].force = force;
        Mat6 T;
        r.mat(T);
        m.T[i] = T;
        m.X0[i] = r.pose();
        GasDerivative G;
        r.mat(G);
        if (G.rows() != 6)
            bags::StateReader::mismatch("rows of a link's gas derivative", size_t(G.rows()), 6);
        m.G[i] = G;
    }
    m.accelerator->loadState(r);
}

}  // namespace cosim
