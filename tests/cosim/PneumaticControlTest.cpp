// The array's pneumatics and its controllers on a small network without the finite-element
// bags (rigid 3 L bags): a cut step restarts from its start, mass is conserved and the bags'
// in- and outflows add up to their mass change; a valve schedule repeated with its period (odd
// and even rows alternating); a target mass (and one chosen from a k(m) table) reached and
// held within its band; a target pressure held with hysteresis from a lagged, noisy sensor; the
// turn sequence on a stand-in tilt that follows the two sides' masses. Fast: about a second.
#include <cosim/ArrayPneumatics.h>
#include <cosim/PneumaticControl.h>
#include <bags/StateStream.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace {

constexpr double kDt = 0.01;      // [s] the co-simulation's macro step
constexpr double kVolume = 3e-3;  // [m^3] each rigid bag
constexpr double kMass = 4.5e-3;  // [kg] each bag at the start

// Two bags a channel ('a': bags 0, 1; 'b': bags 2, 3; 'c': bags 4, 5 ...), each channel with
// a line, the typical valves of the scenario defaults and a pump of 1 g/s shutting off at
// 100 kPa; two channels unless asked.
cosim::ArrayPneumaticsSpec makeSpec(int channels = 2) {
    cosim::ArrayPneumaticsSpec s;
    s.pump.pressureRise = {0.0, 100e3};
    s.pump.massFlow = {1e-3, 0.0};
    s.manifold.volume = 20e-6;
    s.line.volume = 20e-6;
    pneumatics::ValveSpec v;
    v.sonicConductance = 0.3e-8;
    v.criticalPressureRatio = 0.4;
    for (int c = 0; c < channels; ++c) {
        cosim::PneumaticChannel ch;
        ch.name = std::string(1, char('a' + c));
        ch.bags = {2 * c, 2 * c + 1};
        ch.inflate = ch.vent = v;
        ch.lineVolume = 20e-6;
        s.channels.push_back(ch);
    }
    return s;
}

// Every bag of the spec's channels at kMass in kVolume.
cosim::ArrayPneumatics makeNetwork(const cosim::ArrayPneumaticsSpec& s) {
    const size_t n = 2 * s.channels.size();
    return cosim::ArrayPneumatics(s, bags::GasOptions(), std::vector<double>(n, kMass),
                                  std::vector<double>(n, kVolume));
}

// The turn of these tests: from `start`, channel `inflate` filled and `vent` vented until the
// stand-in's tilt reaches 5 deg (half a gram of difference at 10 deg a gram), held 1 s, given up
// after 30 s of turning.
cosim::TurnSpec makeTurn(double start, int inflate, int vent) {
    cosim::TurnSpec t;
    t.start = start;
    t.inflate = {inflate};
    t.vent = {vent};
    t.tilt = 5.0 * M_PI / 180.0;
    t.hold = 1.0;
    t.maxTurnTime = 30.0;
    return t;
}

std::vector<pneumatics::BagVolume> rigid(const cosim::ArrayPneumatics& p) {
    return std::vector<pneumatics::BagVolume>(p.getBags().size(), {kVolume, 0.0});
}

// Runs the controller and the network from t0 to t1 in macro steps; `each` is called after
// every step with the time at its end.
double run(
    cosim::PneumaticController& c, cosim::ArrayPneumatics& p, double t0, double t1,
    std::vector<cosim::ControlEvent>& events,
    const std::function<double()>& tilt = [] { return 0.0; },
    const std::function<void(double)>& each = [](double) {}) {
    double t = t0;
    while (t < t1 - 1e-9) {
        cosim::ControlInputs in;
        in.time = t;
        in.pelvisTilt = tilt();
        c.update(in, p, events);
        const double dt = std::min(kDt, c.findNextChange(t) - t);
        p.step(t, dt, rigid(p));
        t += dt;
        each(t);
    }
    return t;
}

double channelMass(const cosim::ArrayPneumatics& p, int c) {
    return p.getChannelBagMass(c) / double(p.getChannelBags(c).size());
}

}  // namespace

TEST(ArrayPneumatics, ACutStepStartsAgainFromItsStartAndMassIsConserved) {
    const cosim::ArrayPneumaticsSpec spec = makeSpec();
    cosim::ArrayPneumatics p = makeNetwork(spec), q = makeNetwork(spec);
    for (cosim::ArrayPneumatics* x : {&p, &q}) {
        x->setInflate(0, true);
        x->setVent(1, true);
    }
    // p: a 10 ms step, then the same step cut to 5 ms; q: 5 ms at once. Same bits.
    p.step(0.0, 0.01, rigid(p));
    const std::vector<double> fp = p.step(0.0, 0.005, rigid(p));
    const std::vector<double> fq = q.step(0.0, 0.005, rigid(q));
    ASSERT_EQ(fp.size(), 4u);
    for (size_t k = 0; k < fp.size(); ++k) EXPECT_EQ(fp[k], fq[k]) << k;
    EXPECT_DOUBLE_EQ(p.getTime(), 0.005);
    // A step from another time than the network's is refused.
    EXPECT_THROW(p.step(0.02, 0.01, rigid(p)), std::invalid_argument);
    // 2 s on: what the volumes gained is what the room lost (the pump's inlet and the vents
    // are the ambient node); each bag's in- and outflow add up to its mass change.
    const pneumatics::Network& n = p.getNetwork();
    const double total0 = n.calcVolumeMass() + n.getReservoirMassReceived(n.getAmbient());
    double t = 0.005;
    for (int i = 0; i < 200; ++i, t += kDt) {
        const double m0 = p.getBagMass(0), m2 = p.getBagMass(2);
        p.step(t, kDt, rigid(p));
        const cosim::BagFlow f0 = p.getBagFlow(0), f2 = p.getBagFlow(2);
        EXPECT_NEAR((f0.in - f0.out) * kDt, p.getBagMass(0) - m0, 1e-15);
        EXPECT_NEAR((f2.in - f2.out) * kDt, p.getBagMass(2) - m2, 1e-15);
        EXPECT_GE(f0.in, 0.0);
        EXPECT_GE(f2.out, 0.0);
    }
    const double total1 = n.calcVolumeMass() + n.getReservoirMassReceived(n.getAmbient());
    EXPECT_NEAR(total1, total0, 1e-12 * total0);
    EXPECT_GT(p.getBagMass(0), kMass + 0.1e-3);  // filled
    EXPECT_LT(p.getBagMass(2), kMass - 0.1e-3);  // vented
    // The pump stands while no inflate valve is open (it would only pressurise the manifold).
    p.setInflate(0, false);
    const double inlet = n.getReservoirMassReceived(n.getAmbient());
    p.step(t, kDt, rigid(p));
    EXPECT_EQ(p.getNetwork().getLinkMassFlow(0), 0.0);  // link 0: the first bag's connector
    EXPECT_GE(n.getReservoirMassReceived(n.getAmbient()), inlet);  // only vented air returns
}

TEST(ArrayPneumatics, BadChannelsAreRefusedNamingThem) {
    cosim::ArrayPneumaticsSpec s = makeSpec();
    s.channels[1].bags = {1, 2};
    EXPECT_THROW(
        {
            try {
                s.validate(4);
            } catch (const std::invalid_argument& e) {
                EXPECT_NE(std::string(e.what()).find("bag 1 is already in channel 0"),
                          std::string::npos)
                    << e.what();
                throw;
            }
        },
        std::invalid_argument);
    s = makeSpec();
    s.channels[0].bags = {0, 7};
    EXPECT_THROW(s.validate(4), std::invalid_argument);
    s = makeSpec();
    s.channels[0].lineVolume = 0.0;  // two bags need a line
    EXPECT_THROW(s.validate(4), std::invalid_argument);
}

TEST(PneumaticControl, AValveScheduleRepeatsWithItsPeriodOddAndEvenAlternating) {
    const cosim::ArrayPneumaticsSpec spec = makeSpec();
    cosim::ArrayPneumatics p = makeNetwork(spec);
    // From 1 s, every 0.4 s: 'a' fills and 'b' vents for 0.2 s, then the other way round.
    std::vector<cosim::ValveCommand> cmds = {
        {0.0, 0, 1, 0}, {0.0, 1, 0, 1}, {0.2, 0, 0, 1}, {0.2, 1, 1, 0}};
    cosim::ValveSchedule s(cmds, 1.0, 0.4, 2);
    EXPECT_DOUBLE_EQ(s.findNextChange(0.0), 1.0);
    std::vector<cosim::ControlEvent> events;
    struct State {
        double t;
        bool aFills, bVents;
    };
    std::vector<State> states;
    run(
        s, p, 0.0, 2.0, events, [] { return 0.0; },
        [&](double t) {
            states.push_back({t, p.isInflateOpen(0), p.isVentOpen(1)});
        });
    // Closed before 1 s; then 'a' fills and 'b' vents in [1.0, 1.2), [1.4, 1.6), [1.8, 2.0).
    for (const State& st : states) {
        const double start = st.t - kDt;  // the step's start decides
        const bool want = start >= 1.0 - 1e-9 && std::fmod(start - 1.0 + 1e-9, 0.4) < 0.2;
        EXPECT_EQ(st.aFills, want) << "step from " << start << " s";
        if (start >= 1.0 - 1e-9) {
            EXPECT_EQ(st.bVents, want) << "step from " << start << " s";
        }
    }
    // 5 switch times (1.0, 1.2, 1.4, 1.6, 1.8), two channels each.
    EXPECT_EQ(events.size(), 10u);
    EXPECT_NEAR(events.front().time, 1.0, 1e-12);
    EXPECT_NE(events.front().text.find("channel 'a' inflate open; vent closed"), std::string::npos)
        << events.front().text;
    EXPECT_NEAR(s.findNextChange(2.0), 2.2, 1e-12);
    // A command beyond the period is refused.
    EXPECT_THROW(cosim::ValveSchedule({{0.5, 0, 1, 0}}, 0.0, 0.4, 2), std::invalid_argument);
    EXPECT_THROW(cosim::ValveSchedule({{0.1, 2, 1, 0}}, 0.0, 0.4, 2), std::invalid_argument);
}

TEST(PneumaticControl, ATargetMassIsReachedAndHeldWithinItsBand) {
    const cosim::ArrayPneumaticsSpec spec = makeSpec();
    cosim::ArrayPneumatics p = makeNetwork(spec);
    // 'a' up to 5.0 g a bag, 'b' down to 4.0 g, bands 0.02 g.
    cosim::TargetController c(cosim::TargetController::Quantity::MassPerBag,
                              {{0, 5.0e-3, 0.02e-3}, {1, 4.0e-3, 0.02e-3}}, 0.5);
    std::vector<cosim::ControlEvent> events;
    double reachedA = -1.0;
    run(
        c, p, 0.0, 6.0, events, [] { return 0.0; },
        [&](double t) {
            if (reachedA < 0.0 && channelMass(p, 0) >= 5.0e-3) reachedA = t;
        });
    // Reached (a bag of a channel gains what one valve step delivers: less than the band) and
    // held: valves closed, masses within the band.
    EXPECT_GT(reachedA, 0.5);
    EXPECT_NEAR(channelMass(p, 0), 5.0e-3, 0.02e-3);
    EXPECT_NEAR(channelMass(p, 1), 4.0e-3, 0.02e-3);
    EXPECT_FALSE(p.isInflateOpen(0) || p.isVentOpen(0) || p.isInflateOpen(1) || p.isVentOpen(1));
    ASSERT_EQ(events.size(), 4u);  // both start, both reach
    EXPECT_NE(events[2].text.find("target reached"), std::string::npos) << events[2].text;
}

TEST(PneumaticControl, TheMassForAWantedStiffnessComesFromTheKmTable) {
    // The seed's idea: the mass that gives a wanted stiffness, here from a rising table.
    const std::vector<double> m = {3.0e-3, 3.5e-3, 4.5e-3}, k = {900.0, 1600.0, 3200.0};
    EXPECT_NEAR(cosim::calcMassForStiffness(m, k, 1600.0), 3.5e-3, 1e-15);
    EXPECT_NEAR(cosim::calcMassForStiffness(m, k, 2400.0), 4.0e-3, 1e-15);  // halfway
    EXPECT_NEAR(cosim::calcMassForStiffness(m, k, 1250.0), 3.25e-3, 1e-15);
    EXPECT_THROW(cosim::calcMassForStiffness(m, k, 5000.0), std::invalid_argument);
    EXPECT_THROW(cosim::calcMassForStiffness(m, {900.0, 800.0, 3200.0}, 1000.0),
                 std::invalid_argument);  // not monotone
}

TEST(PneumaticControl, ATargetPressureIsHeldWithHysteresisFromALaggedNoisySensor) {
    cosim::ArrayPneumaticsSpec spec = makeSpec();
    spec.sensor.timeConstant = 0.05;
    spec.sensor.noiseStdDev = 50.0;  // 0.05 kPa
    // A leak: bag 1 (channel 'a') is joined by a 0.5 mm orifice to bag 2, whose channel 'b'
    // vents all the time, so 'a' keeps losing air and must be topped up.
    spec.orifices.push_back({1, 2, bags::OrificeOptions()});
    spec.orifices.back().orifice.diameter = 0.5e-3;
    cosim::ArrayPneumatics p = makeNetwork(spec);
    p.setVent(1, true);
    const double target = 30e3, band = 1e3;
    cosim::TargetController c(cosim::TargetController::Quantity::Pressure, {{0, target, band}},
                              0.0);
    std::vector<cosim::ControlEvent> events;
    std::vector<double> readings;
    int opened = 0;
    bool wasOpen = false;
    run(
        c, p, 0.0, 8.0, events, [] { return 0.0; },
        [&](double t) {
            const double r = p.readChannelSensor(0);
            if (t > 3.0) readings.push_back(r);
            if (p.isInflateOpen(0) && !wasOpen) ++opened;
            wasOpen = p.isInflateOpen(0);
        });
    // After the first fill (20.5 to 30 kPa) the reading stays in the hysteresis band (plus the
    // overshoot of the lag and one step's fill); the leak makes it cycle, a few times, not
    // at every step (noise 0.05 kPa << band 1 kPa).
    double lo = 1e9, hi = -1e9;
    for (double r : readings) {
        lo = std::min(lo, r);
        hi = std::max(hi, r);
    }
    EXPECT_GT(lo, target - band - 0.5e3);
    EXPECT_LT(hi, target + band);
    EXPECT_GE(opened, 2);
    EXPECT_LE(opened, 40);
    EXPECT_GE(events.size(), 2u);
}

TEST(PneumaticControl, TheTurnReachesItsTiltHoldsAndRestoresTheInitialMasses) {
    const cosim::ArrayPneumaticsSpec spec = makeSpec();
    cosim::ArrayPneumatics p = makeNetwork(spec);
    // A stand-in patient: his tilt follows the two sides' mass difference, 10 deg a gram.
    const double degPerGram = 10.0 * M_PI / 180.0 / 1e-3;
    auto tilt = [&] { return degPerGram * (channelMass(p, 0) - channelMass(p, 1)); };
    cosim::TurnSpec t = makeTurn(1.0, 0, 1);
    t.band = 0.02e-3;
    cosim::TurnController c(t, 2);
    std::vector<cosim::ControlEvent> events;
    run(c, p, 0.0, 12.0, events, tilt);
    ASSERT_EQ(events.size(), 4u);
    EXPECT_EQ(events[0].text.rfind("turn started", 0), 0u);
    EXPECT_NEAR(events[0].time, 1.0, 1e-12);
    EXPECT_EQ(events[1].text.rfind("target tilt reached", 0), 0u);
    const double reached = events[1].time;
    EXPECT_EQ(c.getTiltReachedTime(), reached);
    EXPECT_EQ(events[2].text, "hold ended");
    EXPECT_NEAR(events[2].time, reached + 1.0, 1e-9);
    EXPECT_EQ(events[3].text.rfind("back to supine", 0), 0u);
    EXPECT_EQ(c.getPhase(), cosim::TurnController::Phase::Done);
    EXPECT_NEAR(channelMass(p, 0), kMass, 0.02e-3);
    EXPECT_NEAR(channelMass(p, 1), kMass, 0.02e-3);
    EXPECT_NEAR(tilt(), 0.0, degPerGram * 0.04e-3);
    // A target it cannot reach (the vent side stops at its least mass) gives up after the
    // longest turn time, says so, and still comes back.
    cosim::ArrayPneumatics q = makeNetwork(spec);
    auto tiltQ = [&] { return degPerGram * (channelMass(q, 0) - channelMass(q, 1)); };
    t.tilt = 60.0 * M_PI / 180.0;
    t.maxTurnTime = 2.0;
    t.minMass = 4.3e-3;
    cosim::TurnController g(t, 2);
    events.clear();
    run(g, q, 0.0, 12.0, events, tiltQ);
    ASSERT_GE(events.size(), 4u);
    EXPECT_NE(events[1].text.find("at its least mass, vent closed"), std::string::npos)
        << events[1].text;
    bool gaveUp = false;
    for (const auto& e : events) gaveUp = gaveUp || e.text.rfind("target tilt not reached", 0) == 0;
    EXPECT_TRUE(gaveUp);
    EXPECT_TRUE(std::isnan(g.getTiltReachedTime()));
    EXPECT_EQ(g.getPhase(), cosim::TurnController::Phase::Done);
}

TEST(PneumaticControl, AClinicalTurnHoldsTheZonesAtTheirSetpointAndReturnsToIt) {
    // Three channels of two rigid 3 L bags each: 'a' filled by the turn, 'b' held throughout
    // (a centre column), 'c' vented by the turn. The bags start at 4.5 g (25.3 kPa gauge); the
    // zones' setpoint is 20 kPa within 0.5 kPa, so before the turn each channel vents down to
    // it and holds. The stand-in tilt follows 'a' against 'c', 10 deg a gram.
    cosim::ArrayPneumaticsSpec spec = makeSpec(3);
    // A leak keeps the held zone busy: bag 3 ('b') is joined by a 1 mm orifice to bag 4
    // ('c'), so while the turn vents 'c', 'b' loses air and must be topped up.
    spec.orifices.push_back({3, 4, bags::OrificeOptions()});
    spec.orifices.back().orifice.diameter = 1e-3;
    cosim::ArrayPneumatics p = makeNetwork(spec);
    const double degPerGram = 10.0 * M_PI / 180.0 / 1e-3;
    auto tilt = [&] { return degPerGram * (channelMass(p, 0) - channelMass(p, 2)); };
    cosim::TurnSpec t = makeTurn(4.0, 0, 2);
    t.holdPressure = 20e3;
    t.pressureBand = 0.5e3;
    cosim::TurnController c(t, 3);
    std::vector<cosim::ControlEvent> events;
    double lowB = 1e9, highB = -1e9;  // the held channel's sensor after its first approach
    run(c, p, 0.0, t.start, events, tilt, [&](double u) {
        if (u > 3.0) {
            lowB = std::min(lowB, p.readChannelSensor(1));
            highB = std::max(highB, p.readChannelSensor(1));
        }
    });
    // Before the turn every zone is at its setpoint: it vented from 25 kPa and holds within
    // the band (plus one step's overshoot, 0.5 kPa allowed).
    const double margin = 0.5e3;
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(p.readChannelSensor(ch), t.holdPressure, t.pressureBand + margin) << ch;
    // The turn, its hold and the return; stopped once in the hold and resumed from the
    // controller's checkpoint beside the one that goes on.
    double now = t.start;
    while (c.getPhase() != cosim::TurnController::Phase::Holding && now < 30.0)
        now = run(c, p, now, now + kDt, events, tilt);
    ASSERT_EQ(c.getPhase(), cosim::TurnController::Phase::Holding);
    EXPECT_GT(channelMass(p, 0) - channelMass(p, 2), 0.45e-3);  // 5 deg: half a gram apart
    bags::StateWriter w;
    c.saveState(w);
    cosim::TurnController resumed(t, 3);
    bags::StateReader r(w.getData());
    resumed.loadState(r);
    cosim::ArrayPneumatics q = p;
    std::vector<cosim::ControlEvent> eventsQ;
    auto tiltQ = [&] { return degPerGram * (channelMass(q, 0) - channelMass(q, 2)); };
    auto watchB = [&](double) {
        lowB = std::min(lowB, p.readChannelSensor(1));
        highB = std::max(highB, p.readChannelSensor(1));
    };
    run(c, p, now, 20.0, events, tilt, watchB);
    run(resumed, q, now, 20.0, eventsQ, tiltQ);
    ASSERT_EQ(c.getPhase(), cosim::TurnController::Phase::Done);
    // The channel the turn does not move was held all along.
    EXPECT_GT(lowB, t.holdPressure - t.pressureBand - margin);
    EXPECT_LT(highB, t.holdPressure + t.pressureBand + margin);
    // The turned zones are back at the setpoint, not sealed where the turn left them.
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(p.readChannelSensor(ch), t.holdPressure, t.pressureBand + margin) << ch;
    bool started = false, reached = false, back = false, held = false, topped = false;
    for (const auto& e : events) {
        started = started || e.text.rfind("turn started", 0) == 0;
        reached = reached || e.text.rfind("target tilt reached", 0) == 0;
        back = back || e.text == "back to supine (the turned zones at 20.000 kPa)";
        held = held || e.text.rfind("zone held: channel 'b' venting", 0) == 0;
        topped = topped || (started && e.text.rfind("zone held: channel 'b' filling", 0) == 0);
    }
    EXPECT_TRUE(started && reached && back && held);
    EXPECT_TRUE(topped);  // the leak was made good during the turn
    // The resumed controller made the same commands: the same events from the hold on, and
    // the same gas in every bag.
    ASSERT_FALSE(eventsQ.empty());
    for (size_t k = 0; k < eventsQ.size(); ++k) {
        const auto& e = events[events.size() - eventsQ.size() + k];
        EXPECT_EQ(eventsQ[k].text, e.text);
        EXPECT_EQ(eventsQ[k].time, e.time);
    }
    for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(channelMass(q, ch), channelMass(p, ch)) << ch;
    // After the turn the zones are still held: a zone vented by hand for half a second (the
    // controller not asked) is filled back to the setpoint.
    p.setVent(0, true);
    for (double u = 20.0; u < 20.5 - 1e-9; u += kDt) p.step(u, kDt, rigid(p));
    ASSERT_LT(p.readChannelSensor(0), t.holdPressure - t.pressureBand - margin);
    run(c, p, 20.5, 25.0, events, tilt);
    EXPECT_NEAR(p.readChannelSensor(0), t.holdPressure, t.pressureBand + margin);
    EXPECT_EQ(events.back().text.rfind("zone held: channel 'a' holding", 0), 0u)
        << events.back().text;
}

TEST(PneumaticControl, TheCellPressureFromHisBodyFollowsHisLoadPerAreaOfBodySurface) {
    // Reference: Mosteller's body surface area sqrt(h [cm] m [kg] / 3600), 1.9094 m^2 at 75 kg,
    // 1.75 m (hand computation, 1e-4); 4 kPa for that body by definition (exactly: the same
    // arithmetic). The rule's scaling: m / BSA = 60 sqrt(m / h), so 2.25 times the mass at one
    // height is 1.5 times the pressure, and the bounds of the modelled bodies are 2.71-6.26 kPa.
    body::PatientSpec p;
    p.mass = 75.0;
    p.height = 1.75;
    EXPECT_NEAR(p.getBodySurfaceArea(), 1.9094, 1e-4);
    EXPECT_EQ(cosim::calcCellPressureForBody(p), 4000.0);
    body::PatientSpec light = p, heavy = p;
    light.mass = 50.0;  // BMI 19.5
    light.height = 1.60;
    heavy.mass = 112.5;  // BMI 43.9
    heavy.height = 1.60;
    EXPECT_NEAR(cosim::calcCellPressureForBody(heavy) / cosim::calcCellPressureForBody(light), 1.5,
                1e-12);
    EXPECT_NEAR(cosim::calcCellPressureForBody(light),
                4000.0 * std::sqrt((50.0 / 160.0) / (75.0 / 175.0)), 1e-9);
    body::PatientSpec smallest = p, largest = p;
    smallest.height = 1.4;
    smallest.mass = 14.0 * 1.4 * 1.4;
    largest.height = 2.1;
    largest.mass = 50.0 * 2.1 * 2.1;
    EXPECT_NEAR(cosim::calcCellPressureForBody(smallest), 2705.1, 0.1);
    EXPECT_NEAR(cosim::calcCellPressureForBody(largest), 6261.0, 0.1);
    // A body the model does not cover is refused, not extrapolated.
    body::PatientSpec child = p;
    child.height = 1.2;
    EXPECT_THROW(cosim::calcCellPressureForBody(child), std::invalid_argument);
}
