// Gas over time for the bags of an array: which command holds when, and a bag driven by it.
#include <bags/Airbag.h>
#include <bags/MaterialFit.h>
#include <cosim/BagParticipant.h>
#include <cosim/GasSchedule.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace cosim;

namespace {

GasCommand flow(double t, double mdot) {
    GasCommand c;
    c.time = t;
    c.kind = GasCommand::Kind::Flow;
    c.massFlow = mdot;
    return c;
}

GasCommand target(double t, double m, double rate) {
    GasCommand c;
    c.time = t;
    c.kind = GasCommand::Kind::Target;
    c.targetMass = m;
    c.rate = rate;
    return c;
}

}  // namespace

TEST(GasSchedule, TheLatestCommandThatHasStartedHoldsAndStepsEndAtTheNextStart) {
    // Four bags: the left pair (0, 1) deflates from 10 s to 2.0 g, the right pair (2, 3)
    // inflates at 0.01 g/s from 10 s and stops at 40 s; bag 3 is held from 0 s.
    GasSchedule s;
    s.add({0, 1}, target(10.0, 2.0e-3, 2e-5), "groups[0] 'left'");
    s.add({2, 3}, flow(10.0, 1e-5), "groups[1] 'right'");
    s.add({2, 3}, flow(40.0, 0.0), "groups[1] 'right'");
    s.add({3}, flow(0.0, 0.0), "bags[3]");
    s.validate(4);
    EXPECT_EQ(s.findCommand(0, 5.0), nullptr);
    EXPECT_EQ(s.findCommand(0, 10.0)->kind, GasCommand::Kind::Target);
    EXPECT_EQ(s.findCommand(2, 39.9)->massFlow, 1e-5);
    EXPECT_EQ(s.findCommand(2, 40.0)->massFlow, 0.0);
    EXPECT_EQ(s.findCommand(3, 5.0)->massFlow, 0.0);
    EXPECT_EQ(s.findCommand(3, 20.0)->massFlow, 1e-5);
    EXPECT_EQ(s.findNextChange(0.0), 10.0);
    EXPECT_EQ(s.findNextChange(10.0), 40.0);
    EXPECT_TRUE(std::isinf(s.findNextChange(40.0)));
}

TEST(GasSchedule, CommandsThatCannotHoldAreRefusedNamingThem) {
    GasSchedule a;
    a.add({0, 5}, flow(0.0, 1e-5), "groups[1] 'right'");
    try {
        a.validate(4);
        FAIL() << "accepted bag 5 of 4";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("gas command groups[1] 'right': bag 5; valid: 0 to 3"),
                  std::string::npos)
            << e.what();
    }
    GasSchedule b;
    b.add({0}, flow(2.0, 1e-5), "groups[0] 'left'");
    b.add({0}, target(2.0, 2e-3, 1e-5), "bags[0]");
    EXPECT_THROW(b.validate(1), std::invalid_argument);  // two commands for bag 0 at 2 s
    GasSchedule c;
    c.add({0}, target(0.0, 2e-3, 0.0), "bags[0]");
    EXPECT_THROW(c.validate(1), std::invalid_argument);  // no rate
    GasSchedule d;
    d.add({0}, flow(-1.0, 0.0), "bags[0]");
    EXPECT_THROW(d.validate(1), std::invalid_argument);  // before 0 s
}

TEST(GasSchedule, ABagLetDownToItsTargetAtTheStatedRateAndThenHeld) {
    // Reference: the gas mass m(t) = 4.5 g - 0.02 g/s (t - 1 s) from 1 s until 4.4 g (6 s),
    // then held; the schedule applied before each 1 s step that ends at the next change.
    // Tolerance 1e-12 kg (the bag integrates its flow exactly).
    bags::AirbagSpec spec;
    spec.geometry.meshSize = 0.025;
    spec.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    spec.threads = 1;
    auto bag = std::make_unique<bags::Airbag>(spec);
    bag->inflate(4.5e-3);
    BagParticipant part(std::move(bag));
    GasSchedule s;
    s.add({0}, target(1.0, 4.4e-3, 2e-5), "bags[0]");
    s.validate(1);
    double t = 0.0;
    while (t < 8.0 - 1e-12) {
        s.apply(t, {&part});
        const double t1 = std::min(std::floor(t + 1.0 + 1e-9), s.findNextChange(t));
        ASSERT_TRUE(part.advance(t1 - t).converged) << "at t = " << t;
        part.commit();
        t = t1;
        const double expected = t <= 1.0 ? 4.5e-3 : std::max(4.4e-3, 4.5e-3 - 2e-5 * (t - 1.0));
        EXPECT_NEAR(part.getAirbag().getTotalGasMass(), expected, 1e-12) << "at t = " << t;
    }
}
