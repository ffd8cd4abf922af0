#include "cosim/BodyParticipant.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cosim {

void BodyIntegratorOptions::validate() const {
    if (!(accuracy > 0.0 && accuracy < 1.0)) {
        std::ostringstream s;
        s << "BodyIntegratorOptions: accuracy = " << accuracy << "; valid: 0 < accuracy < 1";
        throw std::invalid_argument(s.str());
    }
    if (!(contactDamping >= 0.0) || !std::isfinite(contactDamping)) {
        std::ostringstream s;
        s << "BodyIntegratorOptions: contactDamping = " << contactDamping
          << " s/m; valid: 0 (none) or a positive value";
        throw std::invalid_argument(s.str());
    }
    if (!(maxStepSize >= 0.0) || !std::isfinite(maxStepSize)) {
        std::ostringstream s;
        s << "BodyIntegratorOptions: maxStepSize = " << maxStepSize
          << " s; valid: 0 (no limit) or a positive step";
        throw std::invalid_argument(s.str());
    }
}

Eigen::Isometry3d toEigen(const SimTK::Transform& X) {
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    for (int i = 0; i < 3; ++i) {
        out.translation()(i) = X.p()[i];
        for (int j = 0; j < 3; ++j) out.linear()(i, j) = X.R().asMat33()(i, j);
    }
    return out;
}

SimTK::Transform toSimTK(const Eigen::Isometry3d& X) {
    SimTK::Mat33 R;
    SimTK::Vec3 p;
    for (int i = 0; i < 3; ++i) {
        p[i] = X.translation()(i);
        for (int j = 0; j < 3; ++j) R(i, j) = X.linear()(i, j);
    }
    return SimTK::Transform(SimTK::Rotation(R, true), p);
}

namespace {

Vec3 vecToEigen(const SimTK::Vec3& v) { return Vec3(v[0], v[1], v[2]); }
SimTK::Vec3 vecToSimTK(const Vec3& v) { return SimTK::Vec3(v.x(), v.y(), v.z()); }

}  // namespace

struct BodyParticipant::Shape {
    SimTK::MobilizedBodyIndex body;
    SimTK::Transform X_BS;
    ShapeWrench W0;
    Mat6 T = Mat6::Zero();
    Eigen::Isometry3d X0 = Eigen::Isometry3d::Identity();
    Vec6 rate = Vec6::Zero();  ///< the load's rate over the step [(N m, N)/s]
    double t0 = 0.0;           ///< [s] when the rate starts (the checkpoint's time)
    bool loaded = false;       ///< W0, T or rate not zero; an unloaded shape adds nothing
};

namespace {

// Pose of a shape in Ground at a state realized to Position.
Eigen::Isometry3d calcShapePose(const SimTK::SimbodyMatterSubsystem& matter,
                                const SimTK::State& state, const BodyParticipant::Shape& s) {
    const SimTK::MobilizedBody& mobod = matter.getMobilizedBody(s.body);
    return toEigen(mobod.getBodyTransform(state) * s.X_BS);
}

// W0 + T d(X0, X) + rate (t - t0), torque about the shape's origin (Ground).
Vec6 calcLoad(const BodyParticipant::Shape& s, const Eigen::Isometry3d& X_GS, double t) {
    Vec6 w = s.W0.asVector();
    if (!s.rate.isZero(0.0)) w += s.rate * (t - s.t0);
    if (!s.T.isZero(0.0)) {
        Vec6 d;
        const Eigen::AngleAxisd aa(Eigen::Matrix3d(X_GS.linear() * s.X0.linear().transpose()));
        d << aa.angle() * aa.axis(), X_GS.translation() - s.X0.translation();
        w += s.T * d;
    }
    return w;
}

// The bags' wrenches on the body's shapes, applied as body spatial forces.
class CouplingForce : public SimTK::Force::Custom::Implementation {
  public:
    CouplingForce(const SimTK::SimbodyMatterSubsystem& matter,
                  std::shared_ptr<std::vector<BodyParticipant::Shape>> shapes, double damping)
        : m_matter(matter), m_shapes(std::move(shapes)), m_damping(damping) {}
    void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>& bodyForces,
                   SimTK::Vector_<SimTK::Vec3>& particleForces,
                   SimTK::Vector& mobilityForces) const override {
        for (const BodyParticipant::Shape& s : *m_shapes) {
            if (!s.loaded) continue;  // no wrench, no tangent: no force, no damping
            const SimTK::MobilizedBody& mobod = m_matter.getMobilizedBody(s.body);
            const SimTK::Transform& X_GB = mobod.getBodyTransform(state);
            const SimTK::Transform X_GS = X_GB * s.X_BS;
            const Vec6 w = calcLoad(s, toEigen(X_GS), state.getTime());
            SimTK::Vec3 force = vecToSimTK(Vec3(w.tail<3>()));
            if (m_damping > 0.0)
                force -= m_damping * s.W0.force.norm() *
                         mobod.findStationVelocityInGround(state, s.X_BS.p());
            // torque about the body origin = torque about S's origin + r_BS x force
            const SimTK::Vec3 torque =
                vecToSimTK(Vec3(w.head<3>())) + SimTK::cross(X_GS.p() - X_GB.p(), force);
            bodyForces[s.body] += SimTK::SpatialVec(torque, force);
        }
    }
    SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0.0; }

  private:
    const SimTK::SimbodyMatterSubsystem& m_matter;
    std::shared_ptr<std::vector<BodyParticipant::Shape>> m_shapes;
    double m_damping;  // [s/m] BodyIntegratorOptions::contactDamping
};

}  // namespace

struct BodyParticipant::Impl {
    SimTK::MultibodySystem& system;
    BodyIntegratorOptions options;
    std::shared_ptr<std::vector<Shape>> shapes = std::make_shared<std::vector<Shape>>();
    bool initialized = false;
    std::vector<DiscreteState> discrete;
    SimTK::State checkpoint, current;
    int lastSteps = 0;
    Impl(SimTK::MultibodySystem& sys, const BodyIntegratorOptions& o) : system(sys), options(o) {}
    const SimTK::SimbodyMatterSubsystem& matter() const { return system.getMatterSubsystem(); }
    const Shape& shape(int i) const {
        if (i < 0 || i >= int(shapes->size()))
            throw std::out_of_range("BodyParticipant: shape " + std::to_string(i) +
                                    " out of range [0, " + std::to_string(shapes->size()) + ")");
        return (*shapes)[i];
    }
};

BodyParticipant::BodyParticipant(SimTK::MultibodySystem& system,
                                 SimTK::GeneralForceSubsystem& forces,
                                 const BodyIntegratorOptions& options)
    : m_impl(std::make_unique<Impl>(system, options)) {
    options.validate();
    // Force::Custom takes ownership of the implementation.
    SimTK::Force::Custom(forces, new CouplingForce(system.getMatterSubsystem(), m_impl->shapes,
                                                   options.contactDamping));
}

BodyParticipant::~BodyParticipant() = default;

int BodyParticipant::addShape(SimTK::MobilizedBodyIndex body, const SimTK::Transform& X_BS) {
    if (m_impl->initialized)
        throw std::logic_error("BodyParticipant::addShape: called after initialize()");
    Shape s;
    s.body = body;
    s.X_BS = X_BS;
    m_impl->shapes->push_back(s);
    return int(m_impl->shapes->size()) - 1;
}

void BodyParticipant::addDiscreteState(DiscreteState d) {
    if (m_impl->initialized)
        throw std::logic_error("BodyParticipant::addDiscreteState: called after initialize()");
    m_impl->discrete.push_back(std::move(d));
}

int BodyParticipant::getNumShapes() const { return int(m_impl->shapes->size()); }

void BodyParticipant::initialize(const SimTK::State& state) {
    m_impl->checkpoint = state;
    m_impl->system.realize(m_impl->checkpoint, SimTK::Stage::Velocity);
    m_impl->current = m_impl->checkpoint;
    // A copied state's cache is not up to date with its prerequisites until realized again.
    m_impl->system.realize(m_impl->current, SimTK::Stage::Velocity);
    m_impl->initialized = true;
}

void BodyParticipant::setShapeLoad(int shape, const ShapeWrench& W0, const Mat6& T,
                                   const Eigen::Isometry3d& X0, const Vec6& rate) {
    m_impl->shape(shape);
    Shape& s = (*m_impl->shapes)[shape];
    s.W0 = W0;
    s.T = T;
    s.X0 = X0;
    s.rate = rate;
    s.t0 = m_impl->checkpoint.getTime();
    s.loaded = !(W0.asVector().isZero(0.0) && T.isZero(0.0) && rate.isZero(0.0));
}

void BodyParticipant::advanceTo(double time) {
    if (!m_impl->initialized) throw std::logic_error("BodyParticipant::advanceTo: not initialized");
    SimTK::State s = m_impl->checkpoint;
    // The loads changed outside the state: nothing cached at Dynamics or above may stand.
    // Velocity too: a discrete state's update (the board's anchors after a step) is then
    // computed afresh from the checkpoint, as after loadState(), so that a resumed run takes
    // the same steps as one that went on.
    s.invalidateAll(SimTK::Stage::Velocity);
    if (time < s.getTime()) {
        std::ostringstream m;
        m << "BodyParticipant::advanceTo: time " << time << " s lies before the checkpoint's "
          << s.getTime() << " s";
        throw std::invalid_argument(m.str());
    }
    if (time == s.getTime()) {
        m_impl->current = s;
        m_impl->system.realize(m_impl->current, SimTK::Stage::Velocity);
        m_impl->lastSteps = 0;
        return;
    }
    SimTK::RungeKuttaMersonIntegrator integ(m_impl->system);
    integ.setAccuracy(m_impl->options.accuracy);
    if (m_impl->options.maxStepSize > 0.0) integ.setMaximumStepSize(m_impl->options.maxStepSize);
    SimTK::TimeStepper ts(m_impl->system, integ);
    ts.initialize(s);
    const SimTK::Integrator::SuccessfulStepStatus status = ts.stepTo(time);
    if (integ.isSimulationOver() &&
        integ.getTerminationReason() != SimTK::Integrator::ReachedFinalTime) {
        std::ostringstream m;
        m << "BodyParticipant::advanceTo: Simbody's integrator stopped at t = " << integ.getTime()
          << " s on the way to " << time << " s";
        throw std::runtime_error(m.str());
    }
    (void)status;
    m_impl->current = integ.getState();
    m_impl->lastSteps = integ.getNumStepsTaken();
    m_impl->system.realize(m_impl->current, SimTK::Stage::Velocity);
}

void BodyParticipant::commit() { m_impl->checkpoint = m_impl->current; }
void BodyParticipant::rollback() {
    m_impl->current = m_impl->checkpoint;
    m_impl->system.realize(m_impl->current, SimTK::Stage::Velocity);
}

ShapeState BodyParticipant::getShapeState(int shape) const {
    const Shape& s = m_impl->shape(shape);
    const SimTK::MobilizedBody& mobod = m_impl->matter().getMobilizedBody(s.body);
    const SimTK::State& st = m_impl->current;
    ShapeState out;
    out.X_GS = calcShapePose(m_impl->matter(), st, s);
    out.w_GS = vecToEigen(mobod.getBodyAngularVelocity(st));
    out.v_GS = vecToEigen(mobod.findStationVelocityInGround(st, s.X_BS.p()));
    return out;
}

ShapeWrench BodyParticipant::calcShapeLoad(int shape) const {
    const Shape& s = m_impl->shape(shape);
    return ShapeWrench::fromVector(calcLoad(s, calcShapePose(m_impl->matter(), m_impl->current, s),
                                            m_impl->current.getTime()));
}

const SimTK::State& BodyParticipant::getState() const { return m_impl->current; }
const SimTK::State& BodyParticipant::getCheckpoint() const { return m_impl->checkpoint; }
double BodyParticipant::getTime() const { return m_impl->current.getTime(); }
int BodyParticipant::getLastIntegratorSteps() const { return m_impl->lastSteps; }

namespace {

void saveVector(bags::StateWriter& w, const SimTK::Vector& v) {
    w.pod(std::uint64_t(v.size()));
    for (int i = 0; i < v.size(); ++i) w.pod(v[i]);
}

void loadVector(bags::StateReader& r, SimTK::Vector& v, const char* what) {
    const auto n = r.pod<std::uint64_t>();
    if (n != std::uint64_t(v.size())) bags::StateReader::mismatch(what, n, size_t(v.size()));
    for (int i = 0; i < v.size(); ++i) v[i] = r.pod<double>();
}

using DiscreteStates = std::vector<BodyParticipant::DiscreteState>;

void saveBodyState(bags::StateWriter& w, const SimTK::State& s, const DiscreteStates& d) {
    w.pod(s.getTime());
    saveVector(w, s.getQ());
    saveVector(w, s.getU());
    saveVector(w, s.getZ());
    w.pod(std::uint64_t(d.size()));
    for (const BodyParticipant::DiscreteState& x : d) {
        const std::vector<double> v = x.get(s);
        w.pod(std::uint64_t(v.size()));
        for (double e : v) w.pod(e);
    }
}

void loadBodyState(bags::StateReader& r, SimTK::State& s, const DiscreteStates& d) {
    s.setTime(r.pod<double>());
    loadVector(r, s.updQ(), "the body's generalized coordinates q");
    loadVector(r, s.updU(), "the body's generalized speeds u");
    loadVector(r, s.updZ(), "the body's auxiliary states z");
    const auto n = r.pod<std::uint64_t>();
    if (n != d.size()) bags::StateReader::mismatch("the body's discrete states", n, d.size());
    for (const BodyParticipant::DiscreteState& x : d) {
        std::vector<double> v(r.pod<std::uint64_t>());
        for (double& e : v) e = r.pod<double>();
        try {
            x.set(s, v);
        } catch (const std::invalid_argument& e) {
            throw bags::StateError(x.name + " do not fit this body: " + e.what());
        }
    }
}

}  // namespace

void BodyParticipant::saveState(bags::StateWriter& w) const {
    w.tag("body-2");
    saveBodyState(w, m_impl->checkpoint, m_impl->discrete);
    saveBodyState(w, m_impl->current, m_impl->discrete);
    w.pod(std::uint64_t(m_impl->shapes->size()));
    for (const Shape& s : *m_impl->shapes) {
        w.mat(s.W0.torque), w.mat(s.W0.force);
        w.mat(s.T);
        w.pose(s.X0);
        w.mat(s.rate);
        w.pod(s.t0);
    }
}

void BodyParticipant::loadState(bags::StateReader& r) {
    if (!m_impl->initialized) throw std::logic_error("BodyParticipant::loadState: not initialized");
    r.tag("body-2");
    loadBodyState(r, m_impl->checkpoint, m_impl->discrete);
    loadBodyState(r, m_impl->current, m_impl->discrete);
    const auto n = r.pod<std::uint64_t>();
    if (n != m_impl->shapes->size())
        bags::StateReader::mismatch("the body's contact shapes", n, m_impl->shapes->size());
    for (Shape& s : *m_impl->shapes) {
        Vec3 torque, force;
        r.mat(torque), r.mat(force);
        s.W0.torque = torque;
        s.W0.force = force;
        Mat6 T;
        r.mat(T);
        s.T = T;
        s.X0 = r.pose();
        Vec6 rate;
        r.mat(rate);
        s.rate = rate;
        r.pod(s.t0);
        s.loaded = !(s.W0.asVector().isZero(0.0) && s.T.isZero(0.0) && s.rate.isZero(0.0));
    }
    m_impl->system.realize(m_impl->checkpoint, SimTK::Stage::Velocity);
    m_impl->system.realize(m_impl->current, SimTK::Stage::Velocity);
}

}  // namespace cosim
