// The pneumatics and control sections of the patient-on-array kind: the coarse pneumatic turn
// read into SI with the documented defaults, and located errors (file, line, key, what is
// valid) for a gas list beside the pneumatics, unknown channels, wrong units, bad valves and
// pump curves, and controllers without their keys.
#include <gtest/gtest.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>

#include <cmath>
#include <string>

#include "ArrayScenarioTestUtil.h"

using io::test::expectInputError;
using io::test::read;
using io::test::readError;

namespace {

const std::string kBase =
    "kind: patient-on-array\n"                                                   // 1
    "patient: {sex: male, height: 1.75 m, mass: 75 kg, position: [0 m, 0 m]}\n"  // 2
    "bag: {mesh_size: 30 mm}\n"                                                  // 3
    "array:\n"                                                                   // 4
    "  rows: 6\n"                                                                // 5
    "  columns: 7\n"                                                             // 6
    "  row_pitch: 360 mm\n"                                                      // 7
    "  column_pitch: 105 mm\n"                                                   // 8
    "  centre: [-30 mm, 0 mm]\n"                                                 // 9
    "  orientation: [along, along-flipped]\n"                                    // 10
    "  gas_mass: 4.5 g\n"                                                        // 11
    "  groups:\n"                                                                // 12
    "    - {name: left, columns: [0, 1, 2]}\n"                                   // 13
    "    - {name: right, columns: [4, 5, 6]}\n"                                  // 14
    "run: {settle_time: 1 s, duration: 10 s}\n";                                 // 15

}  // namespace

TEST(PneumaticsScenario, ReadsTheCoarsePneumaticTurnAndTheDefaults) {
    const io::PatientOnArrayScenario sc = io::readPatientOnArrayScenario(io::ScenarioFile::load(
        std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/turn-left-pneumatic-coarse.yaml"));
    ASSERT_TRUE(sc.hasPneumatics);
    const cosim::ArrayPneumaticsSpec& p = sc.pneumatics;
    ASSERT_EQ(p.channels.size(), 2u);
    EXPECT_EQ(p.channels[0].name, "left");
    EXPECT_EQ(p.channels[0].bags.size(), 18u);
    EXPECT_DOUBLE_EQ(p.channels[1].inflate.sonicConductance, 8e-8);
    EXPECT_DOUBLE_EQ(p.channels[1].vent.criticalPressureRatio, 0.4);
    EXPECT_DOUBLE_EQ(p.channels[1].inflate.openingTime, 0.02);
    EXPECT_DOUBLE_EQ(p.channels[0].lineVolume, 50e-6);
    EXPECT_DOUBLE_EQ(p.channels[0].connector.diameter, 6e-3);
    EXPECT_DOUBLE_EQ(p.pump.massFlow[0], 8e-3);
    EXPECT_DOUBLE_EQ(p.pump.pressureRise[2], 120e3);
    EXPECT_DOUBLE_EQ(p.manifold.volume, 50e-6);
    EXPECT_DOUBLE_EQ(p.sensor.timeConstant, 0.05);
    EXPECT_DOUBLE_EQ(p.sensor.noiseStdDev, 50.0);
    EXPECT_EQ(sc.controlKind, "turn");
    EXPECT_NEAR(sc.targetTilt, 12.0 * M_PI / 180.0, 1e-12);  // what these wedges reach
    ASSERT_TRUE(sc.controller);

    // The defaults: one channel per group, the typical hardware.
    const io::PatientOnArrayScenario d = read(kBase + "pneumatics: {}\n");
    ASSERT_EQ(d.pneumatics.channels.size(), 2u);
    EXPECT_DOUBLE_EQ(d.pneumatics.channels[1].inflate.sonicConductance, 0.3e-8);
    EXPECT_DOUBLE_EQ(d.pneumatics.channels[1].vent.criticalPressureRatio, 0.4);
    EXPECT_DOUBLE_EQ(d.pneumatics.channels[1].lineVolume, 20e-6);
    EXPECT_DOUBLE_EQ(d.pneumatics.pump.massFlow[0], 0.16e-3);
    EXPECT_DOUBLE_EQ(d.pneumatics.pump.pressureRise.back(), 100e3);
    EXPECT_TRUE(d.pneumatics.manifold.thermal == pneumatics::Thermal::Isothermal);
    EXPECT_FALSE(d.controller);

    // A channel of its own bags; one bag alone has its valves on the bag.
    const io::PatientOnArrayScenario c =
        read(kBase +
             "pneumatics:\n  channels:\n    - {bags: [3]}\n    - {bags: [10, 17], "
             "name: middle}\n  manifold: {volume: 0.1 L, thermal: heat-exchange, "
             "heat_transfer: 10, wall_area: 100 cm^2}\n");
    EXPECT_EQ(c.pneumatics.channels[0].name, "bags 3");
    EXPECT_DOUBLE_EQ(c.pneumatics.channels[0].lineVolume, 0.0);
    EXPECT_EQ(c.pneumatics.channels[1].name, "middle");
    EXPECT_DOUBLE_EQ(c.pneumatics.manifold.volume, 1e-4);
    EXPECT_DOUBLE_EQ(c.pneumatics.manifold.wallArea, 0.01);
}

TEST(PneumaticsScenario, ErrorsAreLocatedAtTheirKeys) {
    const io::InputError gas =
        readError(kBase + "gas:\n  - {group: right, flow: 0.01 g/s}\npneumatics: {}\n");
    EXPECT_EQ(gas.getKey(), "gas");
    EXPECT_NE(gas.getMessage().find("remove the gas list"), std::string::npos) << gas.what();

    const io::InputError unit =
        readError(kBase + "pneumatics:\n  valves:\n    vent: {conductance: 0.3 L/s}\n");
    EXPECT_EQ(unit.getLine(), 18);
    EXPECT_EQ(unit.getKey(), "pneumatics.valves.vent.conductance");
    EXPECT_NE(unit.getMessage().find("dm^3/(s bar)"), std::string::npos) << unit.what();

    const io::InputError ratio =
        readError(kBase + "pneumatics:\n  valves:\n    inflate: {critical_ratio: 1.2}\n");
    EXPECT_EQ(ratio.getKey(), "pneumatics.valves.inflate.critical_ratio");

    const io::InputError curve =
        readError(kBase + "pneumatics:\n  pump: {curve: [[0 kPa, 0.1 g/s], [50 kPa, 0.2 g/s]]}\n");
    EXPECT_EQ(curve.getKey(), "pneumatics.pump.curve[1][1]");  // at the point that rises

    const io::InputError misspelt = readError(kBase + "pneumatics:\n  manifodl: {}\n");
    EXPECT_NE(misspelt.getMessage().find("did you mean 'manifold'"), std::string::npos)
        << misspelt.what();

    const io::InputError twice =
        readError(kBase + "pneumatics:\n  channels:\n    - {group: left}\n    - {bags: [1]}\n");
    EXPECT_EQ(twice.getLine(), 19);
    EXPECT_NE(twice.getMessage().find("bag 1 is already in channel 'left'"), std::string::npos)
        << twice.what();

    const io::InputError noPneumatics = readError(kBase + "control: {kind: turn, tilt: 30 deg}\n");
    EXPECT_EQ(noPneumatics.getKey(), "control");

    const io::InputError channel = readError(
        kBase + "pneumatics: {}\ncontrol: {kind: turn, tilt: 30 deg, inflate: [rihgt]}\n");
    EXPECT_EQ(channel.getKey(), "control.inflate[0]");
    EXPECT_NE(channel.getMessage().find("right"), std::string::npos) << channel.what();

    const io::InputError stiffness =
        readError(kBase +
                  "pneumatics: {}\ncontrol:\n  kind: target-mass\n  targets:\n"
                  "    - {channel: left, stiffness: 2 N/mm}\n");
    EXPECT_EQ(stiffness.getKey(), "control.targets[0].stiffness");
    EXPECT_NE(stiffness.getMessage().find("k_of_m"), std::string::npos) << stiffness.what();

    const io::InputError outside =
        readError(kBase +
                  "pneumatics: {}\ncontrol:\n  kind: target-mass\n"
                  "  k_of_m: [[3 g, 0.9 N/mm], [4.5 g, 3.2 N/mm]]\n  targets:\n"
                  "    - {channel: left, stiffness: 5 N/mm}\n");
    EXPECT_EQ(outside.getKey(), "control.targets[0].stiffness");
    EXPECT_NE(outside.getMessage().find("outside the table"), std::string::npos) << outside.what();

    const io::InputError period =
        readError(kBase +
                  "pneumatics: {}\ncontrol:\n  kind: schedule\n  period: 10 s\n  commands:\n"
                  "    - {at: 12 s, channel: left, inflate: open}\n");
    EXPECT_EQ(period.getKey(), "control.commands[0].at");
}

TEST(PneumaticsScenario, ATargetMassFromAStiffnessIsInterpolatedInTheTable) {
    const io::PatientOnArrayScenario sc =
        read(kBase +
             "pneumatics: {}\ncontrol:\n  kind: target-mass\n"
             "  k_of_m: [[3 g, 1 N/mm], [4 g, 3 N/mm]]\n  targets:\n"
             "    - {channel: left, stiffness: 2 N/mm}\n    - {channel: right, mass: 5 g}\n");
    EXPECT_EQ(sc.controlKind, "target-mass");
    ASSERT_EQ(sc.controlText.size(), 2u);
    EXPECT_NE(sc.controlText[0].find("'left' to 3.5 g a bag"), std::string::npos)
        << sc.controlText[0];
}

TEST(PneumaticsScenario, TheShippedPneumaticScenariosRead) {
    for (const char* name : {"turn-left-pneumatic", "turn-right-pneumatic", "alternating-pressure",
                             "turn-left-pneumatic-small-woman", "turn-left-pneumatic-tall-man",
                             "turn-left-pneumatic-high-bmi"}) {
        SCOPED_TRACE(name);
        const io::PatientOnArrayScenario sc = io::readPatientOnArrayScenario(io::ScenarioFile::load(
            std::string(BAGSIM_SOURCE_DIR) + "/scenarios/" + name + ".yaml"));
        EXPECT_TRUE(sc.hasPneumatics);
        EXPECT_TRUE(sc.controller);
        // Clinical inflation: filled at rest to the setpoint from the patient's body; the turns
        // hold three zones (left, centre, right columns), the cycle its two sets of rows.
        const bool turn = std::string(name).rfind("turn", 0) == 0;
        EXPECT_EQ(sc.pneumatics.channels.size(), turn ? 3u : 2u);
        EXPECT_GT(sc.fillFromBody, 2.7e3);
        EXPECT_LT(sc.fillFromBody, 6.3e3);
        EXPECT_EQ(sc.options.bag.stepping, bags::AirbagSpec::Stepping::Relaxed);
        EXPECT_TRUE(sc.options.bag.selfContact);
        if (turn) {
            const auto* t = dynamic_cast<const cosim::TurnController*>(sc.controller.get());
            ASSERT_NE(t, nullptr);
            EXPECT_EQ(t->getHoldPressure(), sc.fillFromBody);  // held where they were filled
        }
        EXPECT_DOUBLE_EQ(sc.options.bag.geometry.meshSize, 0.02);
    }
    const io::PatientOnArrayScenario right = io::readPatientOnArrayScenario(io::ScenarioFile::load(
        std::string(BAGSIM_SOURCE_DIR) + "/scenarios/turn-right-pneumatic.yaml"));
    EXPECT_NEAR(right.targetTilt, -30.0 * M_PI / 180.0, 1e-12);
}

TEST(PneumaticsScenario, TheZonesPressureIsStatedOnceOrSetFromHisBody) {
    // control.pressure (with band) gives every channel one target; `from-body` sets it, and
    // array.pressure likewise, from his mass and height (cosim::calcCellPressureForBody:
    // 4 kPa at 75 kg and 1.75 m, and 3.5823 kPa at 55 kg and 1.60 m by hand computation).
    const std::string control =
        "pneumatics: {}\ncontrol: {kind: target-pressure, pressure: from-body, band: 0.3 kPa}\n";
    const io::PatientOnArrayScenario sc = read(kBase + control);
    EXPECT_EQ(sc.controlKind, "target-pressure");
    ASSERT_EQ(sc.controlText.size(), 2u);
    EXPECT_EQ(sc.controlText[0],
              "'left' to 4 kPa gauge (band 0.3 kPa) from his body (75 kg, 1.75 m)");
    EXPECT_EQ(sc.controlText[1].substr(0, 20), "'right' to 4 kPa gau");
    EXPECT_EQ(sc.fillFromBody, 0.0);  // the array is filled by gas mass here

    std::string small = kBase + control;
    small.replace(small.find("height: 1.75 m, mass: 75 kg"), 27, "height: 1.60 m, mass: 55 kg");
    small.replace(small.find("  gas_mass: 4.5 g\n"), 18, "  pressure: from-body\n");
    const io::PatientOnArrayScenario s2 = read(small);
    EXPECT_NEAR(s2.fillFromBody, 3582.4, 0.1);
    EXPECT_NE(
        s2.controlText[0].find("to 3.58236 kPa gauge (band 0.3 kPa) from his body (55 kg, 1.6 m)"),
        std::string::npos)
        << s2.controlText[0];
    // The stated pressure fills the bags as a stated 3.58236 kPa does.
    std::string stated = small;
    stated.replace(stated.find("  pressure: from-body\n"), 22, "  pressure: 3582.36 Pa\n");
    EXPECT_NEAR(read(stated).options.layout.gasMass, s2.options.layout.gasMass,
                1e-6 * s2.options.layout.gasMass);

    // Refused: both or neither of targets and pressure; a band without pressure; a word that
    // is not from-body (its message names both valid forms).
    auto refused = [](const std::string& text, const std::string& key, const std::string& what) {
        const io::InputError e = readError(text);
        EXPECT_EQ(e.getLine(), 17) << e.what();
        EXPECT_EQ(e.getKey(), key) << e.what();
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    };
    refused(kBase +
                "pneumatics: {}\ncontrol: {kind: target-pressure, pressure: 4 kPa, "
                "targets: [{channel: left, pressure: 4 kPa}]}\n",
            "control.pressure", "and targets both set the channels' pressures");
    refused(kBase + "pneumatics: {}\ncontrol: {kind: target-pressure}\n", "control.targets",
            "missing: targets");
    refused(kBase +
                "pneumatics: {}\ncontrol: {kind: target-pressure, band: 1 kPa, "
                "targets: [{channel: left, pressure: 4 kPa}]}\n",
            "control.band", "goes with control.pressure");
    refused(kBase + "pneumatics: {}\ncontrol: {kind: target-pressure, pressure: from-bdy}\n",
            "control.pressure", "; or from-body (the pressure set from the patient's mass");
}

TEST(PneumaticsScenario, ATurnHoldsTheZonesAtAPressureWhenOneIsGiven) {
    // control.pressure on a turn: the zones held at it (from-body: 4 kPa for this man) within
    // pressure_band (0.3 kPa by default); the run header says so. Refused: the mass band of a
    // sealed turn beside it, a pressure_band alone, a pressure outside 0.2-100 kPa.
    const std::string turn =
        "pneumatics: {}\ncontrol: {kind: turn, tilt: 12 deg, inflate: [right], "
        "vent: [left]";
    const io::PatientOnArrayScenario sc = read(kBase + turn + ", pressure: from-body}\n");
    ASSERT_EQ(sc.controlText.size(), 2u);
    EXPECT_NE(sc.controlText[0].find("then back to the zones' setpoint"), std::string::npos)
        << sc.controlText[0];
    EXPECT_EQ(sc.controlText[1],
              "every zone held at 4 kPa gauge (band 0.3 kPa) from his body (75 kg, 1.75 m) from "
              "the release, the turned zones sealed while he is turned and held");
    const io::PatientOnArrayScenario stated =
        read(kBase + turn + ", pressure: 5 kPa, pressure_band: 0.5 kPa}\n");
    EXPECT_NE(stated.controlText[1].find("held at 5 kPa gauge (band 0.5 kPa) from the release"),
              std::string::npos)
        << stated.controlText[1];
    const io::PatientOnArrayScenario sealed = read(kBase + turn + ", band: 0.05 g}\n");
    ASSERT_EQ(sealed.controlText.size(), 1u);
    EXPECT_NE(sealed.controlText[0].find("then back to the initial masses"), std::string::npos);

    auto refused = [](const std::string& text, const std::string& key, const std::string& what) {
        const io::InputError e = readError(text);
        EXPECT_EQ(e.getLine(), 17) << e.what();
        EXPECT_EQ(e.getKey(), key) << e.what();
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    };
    refused(kBase + turn + ", pressure: 4 kPa, band: 0.05 g}\n", "control.band",
            "with control.pressure the turn returns to the pressure within pressure_band");
    refused(kBase + turn + ", pressure_band: 0.3 kPa}\n", "control.pressure_band",
            "goes with control.pressure");
    refused(kBase + turn + ", pressure: 150 kPa}\n", "control.pressure", "150 kPa");
}

TEST(PneumaticsScenario, APumpCurvesFaultIsNamedAtItsPointInTheUsersUnits) {
    // It was "pump curve: 'pressureRise[1]' = 0 Pa is invalid": a C++ field, in SI.
    auto error = [](const std::string& curve) {
        return readError(kBase + "pneumatics:\n  pump: {curve: " + curve + "}\n");
    };
    const io::InputError flat = error("[[0 kPa, 8 g/s], [0 kPa, 5 g/s]]");
    EXPECT_EQ(flat.getKey(), "pneumatics.pump.curve[1][0]") << flat.what();
    EXPECT_NE(flat.getMessage().find("the pressure rise 0 kPa is not above the point before's"),
              std::string::npos)
        << flat.what();
    EXPECT_EQ(std::string(flat.what()).find("pressureRise"), std::string::npos) << flat.what();
    const io::InputError rising = error("[[0 kPa, 5 g/s], [60 kPa, 8 g/s], [120 kPa, 0 g/s]]");
    EXPECT_EQ(rising.getKey(), "pneumatics.pump.curve[1][1]") << rising.what();
    EXPECT_NE(rising.getMessage().find("the mass flow 8 g/s is above the point before's"),
              std::string::npos)
        << rising.what();
    const io::InputError open = error("[[0 kPa, 8 g/s], [60 kPa, 5 g/s]]");
    EXPECT_EQ(open.getKey(), "pneumatics.pump.curve[1][1]") << open.what();
    EXPECT_NE(open.getMessage().find("the last point is the pump's shut-off pressure"),
              std::string::npos)
        << open.what();
    EXPECT_NO_THROW(read(kBase + "pneumatics:\n  pump: {curve: [[0 kPa, 8 g/s], [60 kPa, 5 g/s], "
                                 "[120 kPa, 0 g/s]]}\n"));
}
