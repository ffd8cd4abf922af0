#include "cosim/Coupling.h"

#include <bags/Types.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace cosim {

namespace {

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
    throw std::invalid_argument("coupling scheme '" + name +
                                "'; valid: explicit, implicit, tangent");
}

std::string toString(Scheme scheme) {
    switch (scheme) {
        case Scheme::Explicit:
            return "explicit";
        case Scheme::Implicit:
            return "implicit";
        case Scheme::Tangent:
            return "tangent";
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
    if (threads < 0) invalid("threads", threads, "0 (one per core) or more");
}

struct Coupling::Impl {
    BodyParticipant& body;
    std::vector<Participant*> participants;
    std::vector<Link> links;
    CouplingOptions options;
    std::unique_ptr<Accelerator> accelerator;
    std::vector<std::vector<int>> linksOf;  // per participant
    std::vector<ShapeWrench> W;             // per link, at the checkpoint
    std::vector<Mat6> T;
    std::vector<Eigen::Isometry3d> X0;
    double baseTime = 0.0;  // time when the macro step was last set
    int stepsSinceBase = 0;
    double largestStep = 0.0;  // the macroStep the coupling was built with
    std::function<void(double, double)> beforeStep;
    int goodInARow = 0;        // stepAdaptive(): successes at the current step
    int steps = 0;
    bool initialized = false;

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
    ShapeWrench unpack(const Eigen::VectorXd& x, int i) const {
        ShapeWrench w;
        w.torque = x.segment<3>(6 * i) * options.torqueLength;
        w.force = x.segment<3>(6 * i + 3);
        return w;
    }

    // Every participant to the body's current end poses over dt; wrenches (and tangents) per
    // link into w (and t). Returns the Newton iterations; throws with everything rolled back
    // if a participant fails.
    int advanceParticipants(double dt, bool wantTangent, std::vector<ShapeWrench>& w,
                            std::vector<Mat6>& t) {
        std::vector<ShapeState> states(links.size());
        for (size_t i = 0; i < links.size(); ++i)
            states[i] = body.getShapeState(links[i].bodyShape);
        const int np = int(participants.size());
        std::vector<std::exception_ptr> errors(np);
        std::vector<int> failed(np, 0), iterations(np, 0);
        w.assign(links.size(), ShapeWrench());
        t.assign(links.size(), Mat6::Zero());
        auto work = [&](int p) {
            try {
                Participant& part = *participants[p];
                for (int i : linksOf[p]) part.setShapeState(links[i].shape, states[i]);
                const ParticipantStep s = part.advance(dt);
                iterations[p] = s.solverIterations;
                if (!s.converged) {
                    failed[p] = 1;
                    return;
                }
                for (int i : linksOf[p]) {
                    w[i] = part.calcWrench(links[i].shape);
                    if (wantTangent) t[i] = part.calcWrenchTangent(links[i].shape);
                }
            } catch (...) {
                errors[p] = std::current_exception();
            }
        };
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
        int total = 0;
        for (int p = 0; p < np; ++p) total += iterations[p];
        for (int p = 0; p < np; ++p)
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
        return total;
    }

    int calcThreads() const {
        if (options.threads > 0) return options.threads;
        return std::max(1, int(std::thread::hardware_concurrency()));
    }

    void rollbackAll() {
        body.rollback();
        for (Participant* p : participants) p->rollback();
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
    m.advanceParticipants(0.0, m.options.scheme == Scheme::Tangent, m.W, m.T);
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
    const CouplingOptions& o = m.options;
    const double dt = o.macroStep;
    const double tEnd = m.baseTime + (m.stepsSinceBase + 1) * dt;
    if (m.beforeStep) m.beforeStep(getTime(), dt);
    const bool tangent = o.scheme == Scheme::Tangent;
    StepSummary sum;
    sum.step = m.steps;
    sum.time = tEnd;
    Eigen::VectorXd x = m.pack(m.W);
    std::vector<ShapeWrench> w;
    std::vector<Mat6> t;
    m.accelerator->beginStep();
    for (int k = 0;; ++k) {
        m.body.rollback();
        for (size_t i = 0; i < m.links.size(); ++i) {
            if (tangent)
                m.body.setShapeLoad(m.links[i].bodyShape, m.W[i], m.T[i], m.X0[i]);
            else
                m.body.setShapeLoad(m.links[i].bodyShape, m.unpack(x, int(i)));
        }
        m.body.advanceTo(tEnd);
        sum.shapeTravel = 0.0;
        for (size_t i = 0; i < m.links.size(); ++i)
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
        std::vector<ShapeWrench> seen(m.links.size());
        for (size_t i = 0; i < m.links.size(); ++i)
            seen[i] = m.body.calcShapeLoad(m.links[i].bodyShape);
        sum.bagIterations += m.advanceParticipants(dt, tangent, w, t);
        sum.iterations = k + 1;
        const Eigen::VectorXd Hx = m.pack(w);
        const Eigen::VectorXd xSeen = m.pack(seen);
        sum.residual = (Hx - xSeen).norm();
        sum.wrenchNorm = Hx.norm();
        if (o.scheme != Scheme::Implicit) break;
        if (sum.residual <= o.relativeTolerance * sum.wrenchNorm + o.absoluteTolerance) break;
        if (k + 1 >= o.maxIterations) {
            m.rollbackAll();
            std::ostringstream s;
            s << "Coupling: the implicit iterations did not converge in " << o.maxIterations
              << " iterations at t = " << tEnd << " s (macro step " << m.steps
              << "): |H(x) - x| = " << sum.residual << " N against a tolerance of "
              << o.relativeTolerance * sum.wrenchNorm + o.absoluteTolerance
              << " N; cut the macro step or raise maxIterations";
            throw bags::NumericalError(s.str(), tEnd - dt, m.steps);
        }
        x = m.accelerator->next(x, Hx);
    }
    m.accelerator->endStep();
    m.body.commit();
    for (Participant* p : m.participants) p->commit();
    m.W = w;
    m.T = t;
    for (size_t i = 0; i < m.links.size(); ++i)
        m.X0[i] = m.body.getShapeState(m.links[i].bodyShape).X_GS;
    ++m.steps;
    ++m.stepsSinceBase;
    sum.macroStep = dt;
    return sum;
}

StepSummary Coupling::stepAdaptive() {
    Impl& m = *m_impl;
    int cuts = 0;
    for (;;) {
        try {
            StepSummary s = step();
            s.cuts = cuts;
            if (++m.goodInARow >= m.options.growAfter && m.options.macroStep < m.largestStep) {
                setMacroStep(std::min(2.0 * m.options.macroStep, m.largestStep));
                m.goodInARow = 0;
            }
            return s;
        } catch (const bags::NumericalError&) {
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
const CouplingOptions& Coupling::getOptions() const { return m_impl->options; }

}  // namespace cosim
