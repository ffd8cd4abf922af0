// The measured-data folder (docs/measured-data.md): a valid folder reads into SI, and each kind
// of bad input (missing channel, unsorted time, missing or wrong unit, NaN, inconsistent
// flowmeter or peak force, a protocol the scenario cannot run) is one InputError naming the
// file, the line and the column or key.
#include <gtest/gtest.h>
#include "InputErrorTestUtil.h"

#include <io/MeasuredData.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using io::test::expectInputError;

namespace {

const std::string kManifest =
    "format: bagsim-measured-data 1\n"  // 1
    "scenario: " BAGSIM_SOURCE_DIR
    "/scenarios/tests/tiny-load-test.yaml\n"  // 2
    "protocol:\n"                             // 3
    "  block: 50 mm\n"                        // 4
    "  rate: 10 mm/min\n"                     // 5
    "  peak_force: 4 N\n"                     // 6
    "  room_temperature: 23 degC\n"           // 7
    "tests:\n"                                // 8
    "  - gas_mass: 3.5 g\n"                   // 9
    "    machine: m.csv\n"                    // 10
    "    pressure: p.csv\n"                   // 11
    "    flowmeter: f.csv\n";                 // 12

const std::string kMachine =
    "# testing machine export\n"        // 1
    "time_s,displacement_mm,force_N\n"  // 2
    "0,0,0\n"                           // 3
    "6,1,1.5\n"                         // 4
    "12,2,4.0\n"                        // 5
    "18,1,1.4\n";                       // 6
const std::string kPressure = "time [s],pressure [kPa]\n0,0.5\n9,0.9\n18,0.6\n";
const std::string kFlow = "time (s),mass (g)\n0,3.501\n18,3.499\n";

std::string replaceAll(std::string s, const std::string& a, const std::string& b) {
    s.replace(s.find(a), a.size(), b);
    return s;
}

class MeasuredDataTest : public ::testing::Test {
  protected:
    void SetUp() override {
        m_dir = fs::path(BAGSIM_BINARY_DIR) / "tests" / "io" / "measured" /
                ::testing::UnitTest::GetInstance()->current_test_info()->name();
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
        write("measured.yaml", kManifest);
        write("m.csv", kMachine);
        write("p.csv", kPressure);
        write("f.csv", kFlow);
    }
    void write(const std::string& name, const std::string& text) {
        std::ofstream(m_dir / name) << text;
    }
    std::string file(const std::string& name) const { return (m_dir / name).string(); }
    io::InputError readError() {
        return expectInputError([&] { io::readMeasuredData(m_dir.string()); });
    }
    // Writes d into the folder copy/ and reads it back (the copy's manifest pointed at the real
    // scenario, as the writer writes the scenario's text given).
    diagnose::MeasuredData writeAndReadBack(const diagnose::MeasuredData& d) {
        const fs::path out = m_dir / "copy";
        fs::create_directories(out);
        io::writeMeasuredData(out.string(), d, "kind: seed-load-test\n", "# copy\n");
        std::ifstream in(out / "measured.yaml");
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        text = replaceAll(text, "scenario: scenario.yaml",
                          "scenario: " BAGSIM_SOURCE_DIR "/scenarios/tests/tiny-load-test.yaml");
        std::ofstream(out / "measured.yaml") << text;
        return io::readMeasuredData(out.string());
    }
    fs::path m_dir;
};

}  // namespace

TEST_F(MeasuredDataTest, ValidFolderReadsInSi) {
    const diagnose::MeasuredData d = io::readMeasuredData(m_dir.string());
    ASSERT_EQ(d.tests.size(), 1u);
    const diagnose::MeasuredTest& t = d.tests[0];
    EXPECT_DOUBLE_EQ(t.gasMass, 3.5e-3);
    ASSERT_EQ(t.time.size(), 4u);
    EXPECT_DOUBLE_EQ(t.displacement[2], 2e-3);
    EXPECT_DOUBLE_EQ(t.force[2], 4.0);
    EXPECT_DOUBLE_EQ(t.pressure.value[1], 900.0);
    EXPECT_DOUBLE_EQ(t.flowmeter.value[0], 3.501e-3);
    EXPECT_NEAR(d.protocol.rate, 10e-3 / 60, 1e-15);
    EXPECT_NEAR(d.protocol.roomTemperature, 296.15, 1e-12);
}

TEST_F(MeasuredDataTest, MissingChannelFileNamesManifestLineAndKey) {
    fs::remove(m_dir / "p.csv");
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 11);
    EXPECT_EQ(e.getKey(), "tests[0].pressure");
    EXPECT_NE(e.getMessage().find("channel file \"p.csv\" is missing"), std::string::npos);
}

TEST_F(MeasuredDataTest, MissingChannelKeyIsNamed) {
    write("measured.yaml", replaceAll(kManifest, "    flowmeter: f.csv\n", ""));
    const io::InputError e = readError();
    EXPECT_NE(std::string(e.what()).find("flowmeter"), std::string::npos) << e.what();
}

TEST_F(MeasuredDataTest, MissingColumnListsTheValidHeader) {
    write("m.csv", replaceAll(kMachine, "force_N", "load_N"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("m.csv"));
    EXPECT_EQ(e.getLine(), 2);
    EXPECT_NE(e.getMessage().find("no 'force' column"), std::string::npos) << e.what();
    EXPECT_NE(e.getMessage().find("time_s,displacement_mm,force_N"), std::string::npos);
}

TEST_F(MeasuredDataTest, UnsortedTimeNamesRowAndColumn) {
    write("m.csv", replaceAll(kMachine, "12,2,4.0", "5,2,4.0"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("m.csv"));
    EXPECT_EQ(e.getLine(), 5);
    EXPECT_NE(
        e.getMessage().find("column 1 'time_s': 5 is not after the previous row's (line 4) 6"),
        std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("strictly increasing"), std::string::npos);
}

TEST_F(MeasuredDataTest, MissingUnitSaysHowToWriteIt) {
    write("p.csv", replaceAll(kPressure, "pressure [kPa]", "pressure"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("p.csv"));
    EXPECT_EQ(e.getLine(), 1);
    EXPECT_NE(e.getMessage().find("column 2 'pressure': no unit"), std::string::npos) << e.what();
    EXPECT_NE(e.getMessage().find("kPa, Pa, MPa"), std::string::npos);
}

TEST_F(MeasuredDataTest, WrongUnitListsTheValidOnes) {
    write("f.csv", replaceAll(kFlow, "mass (g)", "mass (kPa)"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("f.csv"));
    EXPECT_NE(e.getMessage().find(
                  "column 2 'mass (kPa)': 'kPa' is not a unit of a mass; valid: g, kg, mg"),
              std::string::npos)
        << e.what();
}

TEST_F(MeasuredDataTest, NanCellNamesRowAndColumn) {
    write("m.csv", replaceAll(kMachine, "6,1,1.5", "6,1,nan"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(e.getMessage().find("column 3 'force_N': 'nan' is not a finite number (NaN)"),
              std::string::npos)
        << e.what();
}

TEST_F(MeasuredDataTest, RaggedRowIsNamed) {
    write("m.csv", replaceAll(kMachine, "6,1,1.5", "6,1"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(e.getMessage().find("has 2 cells; the header (line 2) has 3"), std::string::npos);
}

TEST_F(MeasuredDataTest, FlowmeterDisagreeingWithTheManifestIsNamed) {
    write("measured.yaml", replaceAll(kManifest, "gas_mass: 3.5 g", "gas_mass: 3.0 g"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 9);
    EXPECT_EQ(e.getKey(), "tests[0].gas_mass");
    EXPECT_NE(e.getMessage().find("reads 3.5 g on average"), std::string::npos) << e.what();
}

TEST_F(MeasuredDataTest, PeakForceDisagreeingWithTheMachineIsNamed) {
    write("measured.yaml", replaceAll(kManifest, "peak_force: 4 N", "peak_force: 8 N"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 6);
    EXPECT_NE(e.getMessage().find("force peaks at 4 N"), std::string::npos) << e.what();
}

TEST_F(MeasuredDataTest, UnknownFormatIsRefused) {
    write("measured.yaml", replaceAll(kManifest, "bagsim-measured-data 1", "instron 2"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 1);
    EXPECT_NE(e.getMessage().find("valid: \"bagsim-measured-data 1\""), std::string::npos);
}

TEST_F(MeasuredDataTest, ProtocolTheScenarioCannotRunIsNamedAtTheManifest) {
    // A 400 mm block is longer than the tiny scenario's 350 mm airbag.
    write("measured.yaml", replaceAll(kManifest, "block: 50 mm", "block: 400 mm"));
    const diagnose::MeasuredData d = io::readMeasuredData(m_dir.string());
    const io::InputError e = expectInputError([&] { io::readMeasuredScenario(d); });
    EXPECT_EQ(e.getWhere(), file("measured.yaml"));
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_EQ(e.getKey(), "protocol.block");
    EXPECT_NE(e.getMessage().find("cannot run this protocol: \"400 mm\" must be in (0 mm, 350 mm] "
                                  "(at most the airbag's long side)"),
              std::string::npos)
        << e.what();
}

TEST_F(MeasuredDataTest, ProtocolIsAppliedToTheScenario) {
    const io::LoadTestScenario sc = io::readMeasuredScenario(io::readMeasuredData(m_dir.string()));
    ASSERT_EQ(sc.options.gasMasses.size(), 1u);
    EXPECT_NEAR(sc.options.gasMasses[0], 3.5e-3, 1e-15);
    EXPECT_NEAR(sc.options.peakForce, 4.0, 1e-12);
    EXPECT_NEAR(sc.options.gas.temperature, 296.15, 1e-9);
}

// A stiffness curve k(m) alone (the seed study's kind of data): read in SI with its stages; the
// scenario runs its masses from the largest down.
TEST_F(MeasuredDataTest, StiffnessCurveAloneReadsInSi) {
    write("measured.yaml", kManifest.substr(0, kManifest.find("tests:")) + "stiffness: k.csv\n");
    write("k.csv",
          "# k(m)\ngas_mass_g,stiffness [N/mm],stage\n1.0,3.47,3\n2.5,1.64,2\n3.5,7.91,1\n");
    const diagnose::MeasuredData d = io::readMeasuredData(m_dir.string());
    EXPECT_TRUE(d.tests.empty());
    ASSERT_EQ(d.stiffness.gasMass.size(), 3u);
    EXPECT_DOUBLE_EQ(d.stiffness.gasMass[1], 2.5e-3);
    EXPECT_DOUBLE_EQ(d.stiffness.stiffness[1], 1640.0);
    EXPECT_EQ(d.stiffness.stage, (std::vector<int>{3, 2, 1}));
    const io::LoadTestScenario sc = io::readMeasuredScenario(d);
    ASSERT_EQ(sc.options.gasMasses.size(), 3u);
    EXPECT_NEAR(sc.options.gasMasses[0], 3.5e-3, 1e-15);
    EXPECT_NEAR(sc.options.gasMasses[2], 1.0e-3, 1e-15);
}

TEST_F(MeasuredDataTest, StiffnessCurveBadStageNamesItsLine) {
    write("measured.yaml", kManifest + "stiffness: k.csv\n");
    write("k.csv", "# k(m)\ngas_mass_g,stiffness_N/mm,stage\n1.0,3.47,3\n2.5,1.64,4\n");
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("k.csv"));
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(e.getMessage().find("column 'stage': 4 is not a stage; valid: 1, 2, 3, or 0"),
              std::string::npos)
        << e.what();
}

TEST_F(MeasuredDataTest, StiffnessCurveWrongUnitListsTheValidOnes) {
    write("measured.yaml", kManifest + "stiffness: k.csv\n");
    write("k.csv", "gas_mass_g,stiffness_kPa\n1.0,3.47\n2.5,1.64\n");
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 1);
    EXPECT_NE(e.getMessage().find("'kPa' is not a unit of"), std::string::npos) << e.what();
    EXPECT_NE(e.getMessage().find("N/mm"), std::string::npos) << e.what();
}

TEST_F(MeasuredDataTest, NoTestsAndNoStiffnessIsRefused) {
    write("measured.yaml", kManifest.substr(0, kManifest.find("tests:")));
    const io::InputError e = readError();
    EXPECT_NE(e.getMessage().find("lists no 'tests' and no 'stiffness'"), std::string::npos)
        << e.what();
}

TEST_F(MeasuredDataTest, WrittenFolderReadsBack) {
    const diagnose::MeasuredData d = io::readMeasuredData(m_dir.string());
    const diagnose::MeasuredData r = writeAndReadBack(d);
    ASSERT_EQ(r.tests.size(), 1u);
    EXPECT_NEAR(r.tests[0].force[2], 4.0, 1e-9);
    EXPECT_NEAR(r.tests[0].pressure.value[1], 900.0, 1e-6);
    EXPECT_NEAR(r.protocol.roomTemperature, d.protocol.roomTemperature, 1e-9);
}

TEST_F(MeasuredDataTest, TheBedGaugeIsOptionalReadsInSiAndWritesBack) {
    EXPECT_TRUE(io::readMeasuredData(m_dir.string()).tests[0].bed.empty());
    write("b.csv", "time_s,sink_mm\n0,0\n12,0.25\n18,0.1\n");
    write("measured.yaml", kManifest + "    bed: b.csv\n");
    const diagnose::MeasuredData d = io::readMeasuredData(m_dir.string());
    ASSERT_EQ(d.tests[0].bed.time.size(), 3u);
    EXPECT_DOUBLE_EQ(d.tests[0].bed.value[1], 0.25e-3);
    const diagnose::MeasuredData r = writeAndReadBack(d);
    ASSERT_EQ(r.tests[0].bed.value.size(), 3u);
    EXPECT_NEAR(r.tests[0].bed.value[1], 0.25e-3, 1e-12);
    EXPECT_TRUE(fs::exists(m_dir / "copy" / "test1-bed.csv"));
    // A wrong unit is named at the gauge's file.
    write("b.csv", "time_s,sink_N\n0,0\n12,0.25\n");
    const io::InputError unit = readError();
    EXPECT_EQ(unit.getWhere(), file("b.csv"));
    EXPECT_NE(unit.getMessage().find("sink"), std::string::npos) << unit.what();
}

TEST_F(MeasuredDataTest, ABedGaugeForSomeTestsOnlyIsNamed) {
    write("b.csv", "time_s,sink_mm\n0,0\n12,0.25\n18,0.1\n");
    write("f2.csv", "time (s),mass (g)\n0,3.001\n18,2.999\n");
    write("measured.yaml", kManifest +
                               "    bed: b.csv\n"
                               "  - gas_mass: 3.0 g\n"  // 14
                               "    machine: m.csv\n"
                               "    pressure: p.csv\n"
                               "    flowmeter: f2.csv\n");
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("measured.yaml"));
    EXPECT_EQ(e.getLine(), 14);
    EXPECT_NE(e.getMessage().find("no 'bed' channel while 1 other test(s) have one"),
              std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("every test or for none"), std::string::npos) << e.what();
}

TEST_F(MeasuredDataTest, StatedInputUncertaintiesReadInSiAndAreOptional) {
    const diagnose::MeasuredData none = io::readMeasuredData(m_dir.string());
    EXPECT_FALSE(none.tests[0].gasMassUncertaintyStated);
    EXPECT_EQ(none.tests[0].gasMassUncertainty, 0.0);
    EXPECT_FALSE(none.protocol.roomTemperatureUncertaintyStated);
    // For all tests in the protocol, and the room temperature's in K.
    write("measured.yaml", replaceAll(kManifest, "  room_temperature: 23 degC\n",
                                      "  room_temperature: 23 degC\n  gas_mass_uncertainty: 20 mg\n"
                                      "  room_temperature_uncertainty: 0.5 K\n"));
    diagnose::MeasuredData d = io::readMeasuredData(m_dir.string());
    EXPECT_TRUE(d.tests[0].gasMassUncertaintyStated);
    EXPECT_DOUBLE_EQ(d.tests[0].gasMassUncertainty, 0.02e-3);
    EXPECT_TRUE(d.protocol.roomTemperatureUncertaintyStated);
    EXPECT_DOUBLE_EQ(d.protocol.roomTemperatureUncertainty, 0.5);
    // A test's own statement wins over the protocol's; a stated 0 is stated.
    write("measured.yaml", replaceAll(kManifest, "    machine: m.csv\n",
                                      "    gas_mass_uncertainty: 0 g\n    machine: m.csv\n"));
    d = io::readMeasuredData(m_dir.string());
    EXPECT_TRUE(d.tests[0].gasMassUncertaintyStated);
    EXPECT_EQ(d.tests[0].gasMassUncertainty, 0.0);
    // Written and read back.
    d.tests[0].gasMassUncertainty = 0.03e-3;
    d.protocol.roomTemperatureUncertainty = 0.25,
    d.protocol.roomTemperatureUncertaintyStated = true;
    const diagnose::MeasuredData r = writeAndReadBack(d);
    EXPECT_NEAR(r.tests[0].gasMassUncertainty, 0.03e-3, 1e-12);
    EXPECT_NEAR(r.protocol.roomTemperatureUncertainty, 0.25, 1e-12);
}

TEST_F(MeasuredDataTest, StatedInputUncertaintiesOutOfRangeNameFileLineKeyAndTheRange) {
    // A test's: beyond 10 % of its gas mass (3.5 g: 0.35 g).
    write("measured.yaml", replaceAll(kManifest, "    machine: m.csv\n",
                                      "    gas_mass_uncertainty: 0.4 g\n    machine: m.csv\n"));
    io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("measured.yaml"));
    EXPECT_EQ(e.getLine(), 10);
    EXPECT_EQ(e.getKey(), "tests[0].gas_mass_uncertainty");
    EXPECT_NE(e.getMessage().find("0.4 g is out of range; valid: 0 g to 10 % of the test's gas "
                                  "mass (0.35 g)"),
              std::string::npos)
        << e.what();
    // The protocol's, negative: named at the protocol's key, with the test it fails for.
    write("measured.yaml",
          replaceAll(kManifest, "  room_temperature: 23 degC\n",
                     "  room_temperature: 23 degC\n  gas_mass_uncertainty: -1 mg\n"));
    e = readError();
    EXPECT_EQ(e.getLine(), 8);
    EXPECT_EQ(e.getKey(), "protocol.gas_mass_uncertainty");
    EXPECT_NE(e.getMessage().find("-0.001 g is out of range for the test of 3.5 g; valid: 0 g to"),
              std::string::npos)
        << e.what();
    // Not a mass.
    write("measured.yaml",
          replaceAll(kManifest, "  room_temperature: 23 degC\n",
                     "  room_temperature: 23 degC\n  gas_mass_uncertainty: 2 %\n"));
    e = readError();
    EXPECT_EQ(e.getLine(), 8);
    EXPECT_EQ(e.getKey(), "protocol.gas_mass_uncertainty");
    // The room temperature's: beyond 10 K, and in degC (a temperature, not a difference).
    for (const std::string v : {"12 K", "0.5 degC", "0.5"}) {
        write(
            "measured.yaml",
            replaceAll(kManifest, "  room_temperature: 23 degC\n",
                       "  room_temperature: 23 degC\n  room_temperature_uncertainty: " + v + "\n"));
        e = readError();
        EXPECT_EQ(e.getLine(), 8) << v;
        EXPECT_EQ(e.getKey(), "protocol.room_temperature_uncertainty") << v;
        EXPECT_NE(
            e.getMessage().find("valid: 0 K to 10 K, a standard uncertainty in K (e.g. 0.5 K)"),
            std::string::npos)
            << e.what();
    }
}

// The scenario's rig section (docs/scenario-reference.md#rig): the effects the diagnosis can
// blame, as keys a scenario can switch on.
TEST(RigSection, KeysReadInSiAndTheFlowmeterOffsetShiftsTheBagsMasses) {
    const io::ScenarioFile f = io::ScenarioFile::parse(
        "kind: seed-load-test\n"
        "airbag: {long_side: 350 mm, short_side: 200 mm, width: 100 mm, height: 150 mm}\n"
        "membrane: {model: neo-hookean, C10: 1 MPa, thickness: 0.2 mm}\n"
        "test: {gas_masses: [3.5 g, 3.0 g], polynomial_order: 1}\n"
        "rig:\n"
        "  pressure_sensor: {lag: 2 s, offset: 0.3 kPa}\n"
        "  flowmeter: {offset: 0.1 g}\n"
        "  machine_stiffness: 20 N/mm\n"
        "  bed_stiffness: 5 N/mm\n"
        "  load_cell_gain: -0.02\n",
        "rig.yaml");
    const io::LoadTestScenario sc = io::readLoadTestScenario(f);
    EXPECT_DOUBLE_EQ(sc.rig.pressureLag, 2.0);
    EXPECT_DOUBLE_EQ(sc.rig.pressureOffset, 300.0);
    EXPECT_DOUBLE_EQ(sc.rig.flowmeterOffset, 0.1e-3);
    EXPECT_NEAR(sc.rig.machineCompliance, 1.0 / 20e3, 1e-15);
    EXPECT_DOUBLE_EQ(sc.rig.loadCellGain, -0.02);
    EXPECT_NEAR(sc.rig.bedCompliance, 1.0 / 5e3, 1e-15);
    // The flowmeter reads 3.5 g and 3.0 g; the bag holds 0.1 g less.
    EXPECT_NEAR(sc.options.gasMasses[0], 3.4e-3, 1e-15);
    EXPECT_NEAR(sc.options.gasMasses[1], 2.9e-3, 1e-15);
}

TEST(RigSection, BadValuesAreLocated) {
    const std::string head =
        "kind: seed-load-test\n"
        "airbag: {long_side: 350 mm, short_side: 200 mm, width: 100 mm, height: 150 mm}\n"
        "membrane: {model: neo-hookean, C10: 1 MPa, thickness: 0.2 mm}\n"
        "test: {gas_masses: [3.5 g, 3.0 g], polynomial_order: 1}\n"
        "rig:\n";
    auto error = [&](const std::string& rig) {
        return expectInputError(
            [&] { io::readLoadTestScenario(io::ScenarioFile::parse(head + rig, "rig.yaml")); });
    };
    io::InputError e = error("  pressure_sensor: {lag: 2}\n");
    EXPECT_EQ(e.getLine(), 6);
    EXPECT_EQ(e.getKey(), "rig.pressure_sensor.lag");
    EXPECT_NE(e.getMessage().find("has no unit"), std::string::npos) << e.what();
    e = error("  pressure_sensor: {lag: 60 s}\n");
    EXPECT_NE(e.getMessage().find("must be in [0 s, 30 s]"), std::string::npos) << e.what();
    e = error("  flowmeter: {offset: 0.3 g}\n  machine_stiffness: 20 N/mm\n");
    EXPECT_EQ(e.getKey(), "rig.flowmeter.offset");
    EXPECT_EQ(e.getLine(), 6);
    e = error("  flowmeter: {offest: 0.1 g}\n");
    EXPECT_NE(e.getMessage().find("did you mean 'offset'"), std::string::npos) << e.what();
    e = error("  machine_stiffness: 0.1 N/mm\n");
    EXPECT_EQ(e.getKey(), "rig.machine_stiffness");
    e = error("  bed_stiffness: 0.2 N/mm\n");
    EXPECT_EQ(e.getKey(), "rig.bed_stiffness");
    EXPECT_NE(e.getMessage().find("must be >= 0.5 N/mm"), std::string::npos) << e.what();
}

// The gas's leakage and heat exchange (docs/scenario-reference.md#gas): keys read in SI,
// bounds located.
TEST(GasSection, LeakageAndHeatExchangeKeysReadInSiAndBadValuesAreLocated) {
    const std::string head =
        "kind: seed-load-test\n"
        "airbag: {long_side: 350 mm, short_side: 200 mm, width: 100 mm, height: 150 mm}\n"
        "membrane: {model: neo-hookean, C10: 1 MPa, thickness: 0.2 mm}\n"
        "test: {gas_masses: [3.5 g, 3.0 g], polynomial_order: 1}\n"
        "gas:\n";
    const io::LoadTestScenario sc = io::readLoadTestScenario(io::ScenarioFile::parse(
        head + "  leak_conductance: 0.05 mg/(s kPa)\n  heat_time_constant: 20 s\n", "gas.yaml"));
    EXPECT_NEAR(sc.options.gas.leakConductance, 0.05e-9, 1e-24);
    EXPECT_DOUBLE_EQ(sc.options.gas.heatTimeConstant, 20.0);
    EXPECT_NEAR(
        io::readLoadTestScenario(
            io::ScenarioFile::parse(head + "  leak_conductance: 0.05 mg/s/kPa\n", "gas.yaml"))
            .options.gas.leakConductance,
        0.05e-9, 1e-24);
    auto error = [&](const std::string& gas) {
        return expectInputError(
            [&] { io::readLoadTestScenario(io::ScenarioFile::parse(head + gas, "gas.yaml")); });
    };
    io::InputError e = error("  leak_conductance: 2 mg/(s kPa)\n");
    EXPECT_EQ(e.getKey(), "gas.leak_conductance");
    EXPECT_EQ(e.getLine(), 6);
    EXPECT_NE(e.getMessage().find("must be in [0 mg/(s kPa), 1 mg/(s kPa)]"), std::string::npos)
        << e.what();
    e = error("  leak_conductance: 0.05 g/s\n");
    EXPECT_EQ(e.getKey(), "gas.leak_conductance");
    e = error("  heat_time_constant: -1 s\n");
    EXPECT_EQ(e.getKey(), "gas.heat_time_constant");
    e = error("  process: polytropic\n  polytropic_index: 1.2\n  heat_time_constant: 20 s\n");
    EXPECT_EQ(e.getKey(), "gas.heat_time_constant");
    EXPECT_NE(e.getMessage().find("polytropic"), std::string::npos) << e.what();
}

// A load-test scenario up to its membrane section's last required key (line 7), for the film's
// optional keys to follow.
const char* const kFilmScenarioHead =
    "kind: seed-load-test\n"
    "airbag: {long_side: 350 mm, short_side: 200 mm, width: 100 mm, height: 150 mm}\n"
    "test: {gas_masses: [3.5 g, 3.0 g], polynomial_order: 1}\n"
    "membrane:\n"
    "  model: neo-hookean\n"
    "  C10: 1 MPa\n"
    "  thickness: 0.2 mm\n";

// The film's viscoelasticity (docs/scenario-reference.md#membrane): membrane.prony read in SI
// (times with units), every bad term located at its own key and line.
TEST(MembraneSection, PronyTermsReadInSiAndBadTermsAreLocated) {
    const std::string head = kFilmScenarioHead;
    const io::LoadTestScenario sc = io::readLoadTestScenario(io::ScenarioFile::parse(
        head + "  prony: [{g: 0.1, tau: 20 s}, {g: 0.25, tau: 2 min}]\n", "film.yaml"));
    ASSERT_EQ(sc.options.prony.terms.size(), 2u);
    EXPECT_DOUBLE_EQ(sc.options.prony.terms[0].g, 0.1);
    EXPECT_DOUBLE_EQ(sc.options.prony.terms[0].tau, 20.0);
    EXPECT_DOUBLE_EQ(sc.options.prony.terms[1].tau, 120.0);
    EXPECT_TRUE(io::readLoadTestScenario(io::ScenarioFile::parse(head, "film.yaml"))
                    .options.prony.terms.empty());
    auto error = [&](const std::string& prony) {
        return expectInputError(
            [&] { io::readLoadTestScenario(io::ScenarioFile::parse(head + prony, "film.yaml")); });
    };
    io::InputError e = error("  prony:\n    - {g: 0.1, tau: 20 s}\n    - {g: 1.2, tau: 5 s}\n");
    EXPECT_EQ(e.getKey(), "membrane.prony[1].g");
    EXPECT_EQ(e.getLine(), 10);
    EXPECT_NE(e.getMessage().find("must be in [0, 1)"), std::string::npos) << e.what();
    e = error("  prony: [{g: 0.6, tau: 20 s}, {g: 0.5, tau: 5 s}]\n");
    EXPECT_EQ(e.getKey(), "membrane.prony[1].g");
    EXPECT_NE(e.getMessage().find("sum"), std::string::npos) << e.what();
    e = error("  prony: [{g: 0.1, tau: 20}]\n");
    EXPECT_EQ(e.getKey(), "membrane.prony[0].tau");
    EXPECT_NE(e.getMessage().find("has no unit"), std::string::npos) << e.what();
    e = error("  prony: [{g: 0.1, tau: 0 s}]\n");
    EXPECT_EQ(e.getKey(), "membrane.prony[0].tau");
    e = error("  prony: [{g: 0.1}]\n");
    EXPECT_NE(e.getMessage().find("tau"), std::string::npos) << e.what();
    e = error("  prony: [{g: 0.1, tau: 20 s, beta: 1}]\n");
    EXPECT_EQ(e.getKey(), "membrane.prony[0].beta") << e.what();
}

// The woven film's yarns (docs/scenario-reference.md#membrane): membrane.anisotropy read in
// SI, moduli 0 (or no key) the isotropic film, every bad value located at its key and line.
TEST(MembraneSection, AnisotropyReadInSiAndBadValuesAreLocated) {
    const std::string head = kFilmScenarioHead;
    auto read = [&](const std::string& extra) {
        return io::readLoadTestScenario(io::ScenarioFile::parse(head + extra, "film.yaml"));
    };
    const io::LoadTestScenario sc =
        read("  anisotropy: {warp: 12 MPa, weft: 6 MPa, angle: 30 deg}\n");
    const auto* fabric = dynamic_cast<const bags::FabricMaterial*>(sc.options.material.get());
    ASSERT_NE(fabric, nullptr);
    EXPECT_DOUBLE_EQ(fabric->getYarns().warpModulus, 12e6);
    EXPECT_DOUBLE_EQ(fabric->getYarns().weftModulus, 6e6);
    EXPECT_NEAR(fabric->getYarns().angle, M_PI / 6, 1e-15);
    EXPECT_EQ(fabric->getMatrix().getName(), "neo-hookean");
    // The plate bending default stays the matrix's (the coating bends, not the yarns).
    EXPECT_DOUBLE_EQ(sc.options.bendingStiffness, read("").options.bendingStiffness);
    EXPECT_TRUE(read("").options.material->isIsotropic());
    EXPECT_TRUE(read("  anisotropy: {warp: 0 MPa, weft: 0 MPa}\n").options.material->isIsotropic());
    auto error = [&](const std::string& extra) { return expectInputError([&] { read(extra); }); };
    io::InputError e = error("  anisotropy: {warp: -1 MPa, weft: 6 MPa}\n");
    EXPECT_EQ(e.getKey(), "membrane.anisotropy.warp");
    EXPECT_EQ(e.getLine(), 8);
    EXPECT_NE(e.getMessage().find("must be in [0 MPa, 20000 MPa]"), std::string::npos) << e.what();
    e = error("  anisotropy:\n    warp: 10 MPa\n    weft: 1e5 MPa\n");
    EXPECT_EQ(e.getKey(), "membrane.anisotropy.weft");
    EXPECT_EQ(e.getLine(), 10);
    e = error("  anisotropy: {warp: 10 MPa, weft: 6 MPa, angle: 100 deg}\n");
    EXPECT_EQ(e.getKey(), "membrane.anisotropy.angle");
    EXPECT_NE(e.getMessage().find("must be in [-90 deg, 90 deg]"), std::string::npos) << e.what();
    e = error("  anisotropy: {warp: 10, weft: 6 MPa}\n");
    EXPECT_EQ(e.getKey(), "membrane.anisotropy.warp");
    EXPECT_NE(e.getMessage().find("has no unit"), std::string::npos) << e.what();
    e = error("  anisotropy: {warp: 10 MPa}\n");
    EXPECT_NE(e.getMessage().find("weft"), std::string::npos) << e.what();
    e = error("  anisotropy: {warp: 10 MPa, weft: 6 MPa, ratio: 2}\n");
    EXPECT_EQ(e.getKey(), "membrane.anisotropy.ratio") << e.what();
}
