#pragma once
// A rigid block for the coupling tests: one Simbody body on a vertical slider (or a free
// joint), gravity, an optional viscous damper on the slider, and its contact shape frame at the
// body origin, coupled through a cosim::BodyParticipant.
#include <Simbody.h>
#include <cosim/BodyParticipant.h>

#include <memory>

namespace cosim::test {

struct BlockSystem {
    SimTK::MultibodySystem system;
    SimTK::SimbodyMatterSubsystem matter{system};
    SimTK::GeneralForceSubsystem forces{system};
    SimTK::MobilizedBody mobod;
    std::unique_ptr<BodyParticipant> body;
    int shape = -1;
    int extraShape = -1;  // a second shape at the same frame (a second bag under the block)
    double mass = 0.0;

    // Slider along Ground z through (x, y) = (x0, y0); body frame aligned with Ground, its origin
    // at z = q; the shapes' frame at X_BS on it. free: a free joint instead (no damper).
    BlockSystem(double m, double damping, double gravity, double x0 = 0.0, double y0 = 0.0,
                bool free = false, const BodyIntegratorOptions& integ = {},
                const SimTK::Transform& X_BS = SimTK::Transform())
        : mass(m) {
        if (gravity != 0.0)
            SimTK::Force::Gravity(forces, matter, SimTK::UnitVec3(0, 0, -1), gravity);
        const SimTK::Body::Rigid info(SimTK::MassProperties(
            m, SimTK::Vec3(0), SimTK::UnitInertia::brick(0.025, 0.025, 0.01) * m));
        if (free) {
            mobod = SimTK::MobilizedBody::Free(matter.updGround(),
                                               SimTK::Transform(SimTK::Vec3(x0, y0, 0)), info,
                                               SimTK::Transform());
        } else {
            // A slider moves along its frames' x: turn x onto Ground z.
            const SimTK::Rotation R(-SimTK::Pi / 2, SimTK::YAxis);
            mobod = SimTK::MobilizedBody::Slider(matter.updGround(),
                                                 SimTK::Transform(R, SimTK::Vec3(x0, y0, 0)), info,
                                                 SimTK::Transform(R));
            if (damping > 0.0)
                SimTK::Force::MobilityLinearDamper(forces, mobod, SimTK::MobilizerUIndex(0),
                                                   damping);
        }
        body = std::make_unique<BodyParticipant>(system, forces, integ);
        shape = body->addShape(mobod.getMobilizedBodyIndex(), X_BS);
        extraShape = body->addShape(mobod.getMobilizedBodyIndex(), X_BS);
        system.realizeTopology();
    }
    // Starts the slider at height z [m] with velocity v [m/s].
    void start(double z, double v = 0.0) {
        SimTK::State s = system.getDefaultState();
        mobod.setOneQ(s, 0, z);
        mobod.setOneU(s, 0, v);
        body->initialize(s);
    }
    double getZ() const { return mobod.getOneQ(body->getState(), 0); }
    double getV() const { return mobod.getOneU(body->getState(), 0); }
};

}  // namespace cosim::test
