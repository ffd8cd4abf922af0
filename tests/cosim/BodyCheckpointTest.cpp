// The body participant's checkpoint carries its discrete states (the stick-slip support's
// friction anchors): a participant loaded from a checkpoint takes the same steps to the same
// bits as the one that wrote it went on; without the anchors the stick springs would restart
// at zero and the bits would differ (checked, so that the test can fail).
#include <bags/StateStream.h>
#include <body/BodyModel.h>
#include <body/SupportContact.h>
#include <cosim/BodyParticipant.h>
#include <gtest/gtest.h>

#include <memory>

namespace {

// The reference man on a stick-slip support under a horizontal body force of 0.3 g besides
// gravity (below Coulomb's limit: the anchors hold him), as a co-simulation body.
struct Body {
    body::PatientSpec spec;
    body::BodyModel model{spec};
    const body::PlaneSupport* support = nullptr;
    std::unique_ptr<cosim::BodyParticipant> participant;
    explicit Body(bool carryAnchors) {
        body::PlaneSupportOptions o;
        o.frictionLaw = body::SupportFrictionLaw::StickSlip;
        cosim::BodyIntegratorOptions io;
        io.accuracy = 1e-4;  // as the reduced bags' runs
        participant =
            std::make_unique<cosim::BodyParticipant>(model.updSystem(), model.updForces(), io);
        support = &body::addPlaneSupport(model, o);
        SimTK::Force::Gravity(model.updForces(), model.getSystem().getMatterSubsystem(),
                              SimTK::UnitVec3(1, 0, 0), 0.3 * 9.80665);
        if (carryAnchors) {
            const body::PlaneSupport* s = support;
            cosim::BodyParticipant::DiscreteState d;
            d.name = "the support's friction anchors";
            d.get = [s](const SimTK::State& st) { return s->getAnchors(st); };
            d.set = [s](SimTK::State& st, const std::vector<double>& v) { s->setAnchors(st, v); };
            participant->addDiscreteState(std::move(d));
        }
        SimTK::State state = model.updSystem().realizeTopology();
        model.setPosture(state);
        participant->initialize(state);
    }
    void advance(double t) {
        participant->advanceTo(t);
        participant->commit();
    }
};

bool sameBits(const SimTK::State& a, const SimTK::State& b) {
    if (a.getNQ() != b.getNQ() || a.getNU() != b.getNU()) return false;
    for (int i = 0; i < a.getNQ(); ++i)
        if (a.getQ()[i] != b.getQ()[i]) return false;
    for (int i = 0; i < a.getNU(); ++i)
        if (a.getU()[i] != b.getU()[i]) return false;
    return true;
}

}  // namespace

TEST(BodyCheckpoint, AResumedBodyOnAStickSlipSupportGoesOnToTheSameBits) {
    for (const bool carry : {true, false}) {
        Body whole(carry);
        for (int k = 1; k <= 20; ++k) whole.advance(0.01 * k);  // he lands and is held
        ASSERT_GT(whole.support->getAnchors(whole.participant->getCheckpoint()).size(), 300u);
        bags::StateWriter w;
        whole.participant->saveState(w);
        Body resumed(carry);
        bags::StateReader r(w.getData());
        resumed.participant->loadState(r);
        for (int k = 21; k <= 25; ++k) {
            whole.advance(0.01 * k);
            resumed.advance(0.01 * k);
        }
        const bool same = sameBits(whole.participant->getState(), resumed.participant->getState());
        if (carry) {
            EXPECT_TRUE(same) << "the anchors went through the checkpoint";
        } else {
            EXPECT_FALSE(same) << "without the anchors a resumed run would differ";
        }
    }
}

// A checkpoint's anchors that do not fit the body are refused by name.
TEST(BodyCheckpoint, ForeignAnchorsAreRefusedByName) {
    Body whole(true);
    whole.advance(0.05);
    bags::StateWriter w;
    whole.participant->saveState(w);
    Body plain(false);  // no discrete state to read
    bags::StateReader r(w.getData());
    try {
        plain.participant->loadState(r);
        FAIL() << "a checkpoint with anchors loaded into a body without them";
    } catch (const bags::StateError& e) {
        EXPECT_NE(std::string(e.what()).find("discrete states"), std::string::npos) << e.what();
    }
}
