// Settling the patient on the rigid flat support (see SettleOnSupport.h).
#include "body/SettleOnSupport.h"

#include <Simbody.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "body/BodyModel.h"

namespace body {
namespace {

std::string fmt(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

}  // namespace

void SettleOptions::validate() const {
    support.validate();
    if (!std::isfinite(settleTime) || !(settleTime > 0) || settleTime > 60)
        throw std::invalid_argument("settleTime: " + fmt(settleTime) +
                                    " s is not valid; use more than 0 and at most 60 s");
    if (!std::isfinite(accuracy) || !(accuracy > 0) || accuracy > 0.1)
        throw std::invalid_argument("accuracy: " + fmt(accuracy) +
                                    " is not valid; use more than 0 and at most 0.1");
}

SettleReport settleOnSupport(const PatientSpec& spec, const SettleOptions& options) {
    spec.validate();
    options.validate();
    BodyModel model(spec);
    const PlaneSupport& support = addPlaneSupport(model, options.support);
    SimTK::State state = model.updSystem().realizeTopology();
    model.setPosture(state, options.support.height);  // lowest point on the plane
    SimTK::RungeKuttaMersonIntegrator integ(model.getSystem());
    integ.setAccuracy(options.accuracy);
    SimTK::TimeStepper ts(model.getSystem(), integ);
    ts.initialize(state);

    // With a monitor, the integration reports every 0.1 s; the integrator interpolates the
    // reports, so its own steps (and the result) are those of one stepTo.
    auto stepTo = [&](double t) {
        if (!options.monitor) {
            ts.stepTo(t);
            return;
        }
        while (integ.getState().getTime() < t) {
            ts.stepTo(std::min(t, integ.getState().getTime() + 0.1));
            options.monitor(integ.getState().getTime());
        }
    };
    const auto t0 = std::chrono::steady_clock::now();
    const double tMid = std::max(0.0, options.settleTime - 0.5);
    if (tMid > 0) stepTo(tMid);
    const SimTK::MobilizedBody& pelvis = model.getMobilizedBody(Segment::LowerTrunk);
    const SimTK::Vec3 p1 = pelvis.getBodyOriginLocation(integ.getState());
    stepTo(options.settleTime);

    SettleReport r;
    r.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const SimTK::State& end = integ.getState();
    model.getSystem().realize(end, SimTK::Stage::Velocity);
    const SimTK::Vec3 p2 = pelvis.getBodyOriginLocation(end);
    r.drift = std::hypot(p2[0] - p1[0], p2[1] - p1[1]);
    for (int i = 0; i < kSegmentCount; ++i)
        r.maxSpeed = std::max(
            r.maxSpeed,
            model.getMobilizedBody(static_cast<Segment>(i)).getBodyOriginVelocity(end).norm());
    r.mass = model.calcTotalMass();
    r.weight = r.mass * BodyModelOptions{}.gravity;
    r.load = support.calcSupportLoad(end);
    for (const BodyRegion& reg : model.getRegions()) r.regionNames.push_back(reg.name);
    r.simulatedTime = end.getTime();
    r.steps = integ.getNumStepsTaken();
    return r;
}

}  // namespace body
