// A patient's measured data (docs/measured-data.md#a-patient-on-the-array): a valid folder
// reads into SI (mat frames, tilt, bag pressure sensors), and each kind of bad input (the mat
// file's layout, a cell, a short frame, unsorted frames; a tilt file without a tilt; a bag
// listed twice; the data against the scenario: its kind, the mat's size, a bag outside the
// array, samples after the run's end) is one InputError naming the file, the line and the
// frame, row and column or key.
#include <gtest/gtest.h>
#include "InputErrorTestUtil.h"

#include <io/MeasuredData.h>
#include <io/PatientMeasuredData.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using io::test::expectInputError;

namespace {

const std::string kManifest =
    "format: bagsim-measured-data 1\n"  // 1
    "scenario: " BAGSIM_SOURCE_DIR
    "/scenarios/tests/supine-on-array-coarse.yaml\n"  // 2
    "protocol:\n"                                     // 3
    "  kind: patient-on-array\n"                      // 4
    "  settle_time: 0.3 s\n"                          // 5
    "channels:\n"                                     // 6
    "  mat: mat.csv\n"                                // 7
    "  tilt: tilt.csv\n"                              // 8
    "  bag_pressures:\n"                              // 9
    "    - {bag: 17, file: b17.csv}\n"                // 10
    "    - {bag: 3, file: b3.csv}\n";                 // 11

const std::string kMat =
    "# mat export\n"  // 1
    "rows,2\n"        // 2
    "columns,3\n"     // 3
    "unit,mmHg\n"     // 4
    "time_s,0.1\n"    // 5
    "0,1,2\n"         // 6
    "3,4,5\n"         // 7
    "\n"              // 8
    "time_s,0.2\n"    // 9
    "0,10,20\n"       // 10
    "30,40,50\n";     // 11
const std::string kTilt = "time_s,pelvis_tilt_deg\n0,0\n0.1,1.5\n0.2,3\n";
const std::string kBag = "time [s],pressure [kPa]\n0,20\n0.2,21\n";

class PatientMeasuredDataTest : public ::testing::Test {
  protected:
    void SetUp() override {
        m_dir = fs::path(BAGSIM_BINARY_DIR) / "tests" / "io" / "patient-measured" /
                ::testing::UnitTest::GetInstance()->current_test_info()->name();
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
        write("measured.yaml", kManifest);
        write("mat.csv", kMat);
        write("tilt.csv", kTilt);
        write("b17.csv", kBag);
        write("b3.csv", kBag);
    }
    void write(const std::string& name, const std::string& text) {
        std::ofstream(m_dir / name) << text;
    }
    std::string file(const std::string& name) const { return (m_dir / name).string(); }
    io::InputError readError() {
        return expectInputError([&] { io::readPatientMeasuredData(m_dir.string()); });
    }
    io::InputError scenarioError() {
        return expectInputError(
            [&] { io::readPatientMeasuredScenario(io::readPatientMeasuredData(m_dir.string())); });
    }
    fs::path m_dir;
};

std::string replaceAll(std::string s, const std::string& a, const std::string& b) {
    s.replace(s.find(a), a.size(), b);
    return s;
}

// A mat of the scenario's 64 x 32 sensels, frames at these times, every sensel `p` mmHg.
std::string makeFullMat(const std::vector<double>& times, double p = 1.0) {
    std::string s = "rows,64\ncolumns,32\nunit,mmHg\n";
    for (double t : times) {
        s += "time_s," + std::to_string(t) + "\n";
        for (int r = 0; r < 64; ++r)
            for (int c = 0; c < 32; ++c) s += std::to_string(p) + (c == 31 ? "\n" : ",");
    }
    return s;
}

}  // namespace

TEST_F(PatientMeasuredDataTest, ValidFolderReadsInSi) {
    EXPECT_EQ(io::readMeasuredKind(m_dir.string()), "patient-on-array");
    const diagnose::PatientMeasurement d = io::readPatientMeasuredData(m_dir.string());
    EXPECT_DOUBLE_EQ(d.protocol.settleTime, 0.3);
    EXPECT_LT(d.protocol.duration, 0.0);  // the scenario's
    const diagnose::MatFrames& m = d.channels.mat;
    ASSERT_EQ(m.rows, 2);
    ASSERT_EQ(m.columns, 3);
    ASSERT_EQ(m.time.size(), 2u);
    ASSERT_EQ(m.pressure.size(), 2u);
    EXPECT_DOUBLE_EQ(m.time[1], 0.2);
    // Row 2, column 1 of frame 2: 30 mmHg.
    EXPECT_NEAR(m.pressure[1][1 * 3 + 0], 30 * 133.322387415, 1e-9);
    ASSERT_EQ(d.channels.tilt.time.size(), 3u);
    EXPECT_NEAR(d.channels.tilt.pelvis[2], 3.0 * M_PI / 180.0, 1e-15);
    EXPECT_TRUE(d.channels.tilt.thorax.empty());
    ASSERT_EQ(d.channels.bags.size(), 2u);
    EXPECT_EQ(d.channels.bags[0].bag, 3);  // sorted by bag
    EXPECT_DOUBLE_EQ(d.channels.bags[1].pressure.value[1], 21e3);
}

TEST_F(PatientMeasuredDataTest, TheRigsDataHaveNoKind) {
    write("measured.yaml", replaceAll(kManifest, "  kind: patient-on-array\n", ""));
    EXPECT_EQ(io::readMeasuredKind(m_dir.string()), "");
    EXPECT_EQ(io::readMeasuredKind((m_dir / "none").string()), "");
}

TEST_F(PatientMeasuredDataTest, AnUnknownKindListsTheValidOne) {
    write("measured.yaml", replaceAll(kManifest, "kind: patient-on-array", "kind: patient"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(std::string(e.what()).find("patient-on-array"), std::string::npos) << e.what();
}

TEST_F(PatientMeasuredDataTest, NeitherMatNorTiltIsRefused) {
    std::string m = replaceAll(kManifest, "  mat: mat.csv\n", "");
    write("measured.yaml", replaceAll(m, "  tilt: tilt.csv\n", ""));
    const io::InputError e = readError();
    EXPECT_NE(e.getMessage().find("names no 'mat' and no 'tilt'"), std::string::npos) << e.what();
}

TEST_F(PatientMeasuredDataTest, MissingMatFileNamesTheManifestKey) {
    fs::remove(m_dir / "mat.csv");
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "channels.mat");
    EXPECT_NE(e.getMessage().find("channel file \"mat.csv\" is missing"), std::string::npos);
}

TEST_F(PatientMeasuredDataTest, MatWithoutItsLayoutLinesSaysWhatIsValid) {
    write("mat.csv", replaceAll(kMat, "columns,3\n", ""));
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("mat.csv"));
    EXPECT_EQ(e.getLine(), 3);
    EXPECT_NE(e.getMessage().find("where the line columns,N was expected"), std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, MatUnitMustBeAPressure) {
    write("mat.csv", replaceAll(kMat, "unit,mmHg", "unit,N"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(e.getMessage().find("'N' is not a unit of a pressure; valid: "), std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("mmHg"), std::string::npos);
}

TEST_F(PatientMeasuredDataTest, MatCellNamesFrameRowAndColumn) {
    write("mat.csv", replaceAll(kMat, "30,40,50", "30,nan,50"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("mat.csv"));
    EXPECT_EQ(e.getLine(), 11);
    EXPECT_NE(
        e.getMessage().find("frame 2 (time 0.2 s), row 2, column 2: 'nan' is not a finite number"),
        std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("valid: a finite pressure in mmHg"), std::string::npos);
    write("mat.csv", replaceAll(kMat, "0,1,2", "0,1,x"));
    const io::InputError t = readError();
    EXPECT_EQ(t.getLine(), 6);
    EXPECT_NE(t.getMessage().find("frame 1 (time 0.1 s), row 1, column 3: 'x' is not a number"),
              std::string::npos)
        << t.what();
}

TEST_F(PatientMeasuredDataTest, MatRowOfTheWrongWidthIsNamed) {
    write("mat.csv", replaceAll(kMat, "3,4,5", "3,4"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_NE(e.getMessage().find("frame 1 (time 0.1 s), row 2: has 2 cells; valid: 3 pressures"),
              std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, MatFrameShortOfRowsIsNamed) {
    write("mat.csv", replaceAll(kMat, "3,4,5\n", ""));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 8);  // the next frame's time line
    EXPECT_NE(e.getMessage().find("frame 1 (time 0.1 s) (line 5) has 1 rows; valid: 2 rows of 3"),
              std::string::npos)
        << e.what();
    write("mat.csv", replaceAll(kMat, "30,40,50\n", "30,40,50\n1,1,1\n"));
    const io::InputError extra = readError();
    EXPECT_EQ(extra.getLine(), 12);
    EXPECT_NE(extra.getMessage().find("a row 3 beyond the mat's 2 rows"), std::string::npos)
        << extra.what();
}

TEST_F(PatientMeasuredDataTest, MatFramesMustBeInTimeOrder) {
    write("mat.csv", replaceAll(kMat, "time_s,0.2", "time_s,0.1"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 9);
    EXPECT_NE(
        e.getMessage().find("the frame's time 0.1 is not after the previous frame's (line 5) 0.1"),
        std::string::npos)
        << e.what();
    write("mat.csv", replaceAll(kMat, "time_s,0.2", "time_h,0.2"));
    EXPECT_NO_THROW(io::readPatientMeasuredData(m_dir.string()));  // 0.2 h: later
    write("mat.csv", replaceAll(kMat, "time_s,0.2", "time_kPa,0.2"));
    const io::InputError u = readError();
    EXPECT_EQ(u.getLine(), 9);
    EXPECT_NE(u.getMessage().find("'kPa' is not a unit of a time"), std::string::npos) << u.what();
}

TEST_F(PatientMeasuredDataTest, MatWithOneFrameIsRefused) {
    write("mat.csv", kMat.substr(0, kMat.find("\ntime_s,0.2")) + "\n");
    const io::InputError e = readError();
    EXPECT_NE(e.getMessage().find("has 1 frame(s); valid: at least two frames"), std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, TiltFileNeedsATiltColumn) {
    write("tilt.csv", "time_s,roll_deg\n0,0\n0.2,1\n");
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("tilt.csv"));
    EXPECT_NE(e.getMessage().find("no 'pelvis_tilt' and no 'thorax_tilt' column"),
              std::string::npos)
        << e.what();
    write("tilt.csv", "time_s,pelvis_tilt_mm\n0,0\n0.2,1\n");
    const io::InputError u = readError();
    EXPECT_EQ(u.getLine(), 1);
    EXPECT_NE(u.getMessage().find("'mm' is not a unit of an angle"), std::string::npos) << u.what();
}

TEST_F(PatientMeasuredDataTest, BagListedTwiceIsNamed) {
    write("measured.yaml",
          replaceAll(kManifest, "{bag: 3, file: b3.csv}", "{bag: 17, file: b3.csv}"));
    const io::InputError e = readError();
    EXPECT_EQ(e.getLine(), 11);
    EXPECT_NE(e.getMessage().find("bag 17 is listed twice"), std::string::npos) << e.what();
}

TEST_F(PatientMeasuredDataTest, BagSensorCellIsLocated) {
    write("b3.csv", "time [s],pressure [kPa]\n0,20\n0.2,abc\n");
    const io::InputError e = readError();
    EXPECT_EQ(e.getWhere(), file("b3.csv"));
    EXPECT_EQ(e.getLine(), 3);
    EXPECT_NE(e.getMessage().find("column 2 'pressure [kPa]': 'abc' is not a number"),
              std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, TheScenarioMustBeAPatientOnArray) {
    write("measured.yaml",
          replaceAll(kManifest, "supine-on-array-coarse.yaml", "tiny-load-test.yaml"));
    const io::InputError e = scenarioError();
    EXPECT_EQ(e.getLine(), 2);
    EXPECT_NE(
        e.getMessage().find("is of kind 'seed-load-test'; valid: a patient-on-array scenario"),
        std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, TheMatMustBeTheScenarios) {
    const io::InputError e = scenarioError();  // 2 x 3 against the scenario's 64 x 32
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "channels.mat");
    EXPECT_NE(e.getMessage().find("has 2 x 3 sensels, the scenario's mat 64 x 32"),
              std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, SamplesAfterTheRunsEndAndBagsOutsideTheArray) {
    write("mat.csv", makeFullMat({0.1, 0.2}));
    EXPECT_NO_THROW(io::readPatientMeasuredScenario(io::readPatientMeasuredData(m_dir.string())));
    write("tilt.csv", "time_s,pelvis_tilt_deg\n0,0\n0.5,1\n");
    const io::InputError e = scenarioError();
    EXPECT_EQ(e.getLine(), 8);
    EXPECT_NE(e.getMessage().find("runs from 0 s to 0.5 s; valid: samples from the release (0 s) "
                                  "to the run's end, 0.3 s"),
              std::string::npos)
        << e.what();
    write("tilt.csv", kTilt);
    write("measured.yaml", replaceAll(kManifest, "bag: 17", "bag: 42"));
    const io::InputError b = scenarioError();
    EXPECT_EQ(b.getLine(), 9);
    EXPECT_NE(
        b.getMessage().find("bag 42 (" + file("b17.csv") + ") is not in the array of 42 bags"),
        std::string::npos)
        << b.what();
    write("measured.yaml", replaceAll(kManifest, "settle_time: 0.3 s", "settle_time: -1 s"));
    const io::InputError s = readError();
    EXPECT_EQ(s.getLine(), 5);
}

TEST_F(PatientMeasuredDataTest, WrittenDataReadBackTheSame) {
    const diagnose::PatientMeasurement d = io::readPatientMeasuredData(m_dir.string());
    const fs::path out = m_dir / "written";
    fs::create_directories(out);
    io::writePatientMeasuredData(out.string(), d, "kind: patient-on-array\n", "# synthetic\n");
    const diagnose::PatientMeasurement r = io::readPatientMeasuredData(out.string());
    EXPECT_DOUBLE_EQ(r.protocol.settleTime, 0.3);
    ASSERT_EQ(r.channels.mat.pressure.size(), 2u);
    for (size_t k = 0; k < 6; ++k)
        EXPECT_NEAR(r.channels.mat.pressure[1][k], d.channels.mat.pressure[1][k], 1e-2 * 133.3);
    EXPECT_NEAR(r.channels.tilt.pelvis[2], d.channels.tilt.pelvis[2], 1e-6);
    ASSERT_EQ(r.channels.bags.size(), 2u);
    EXPECT_EQ(r.channels.bags[1].bag, 17);
    EXPECT_NEAR(r.channels.bags[1].pressure.value[1], 21e3, 1e-2);
}

// ------------------------------------------------------------------ several tests

namespace {

const std::string kTestsManifest =
    "format: bagsim-measured-data 1\n"  // 1
    "scenario: " BAGSIM_SOURCE_DIR
    "/scenarios/tests/supine-on-array-coarse.yaml\n"                // 2
    "protocol:\n"                                                   // 3
    "  kind: patient-on-array\n"                                    // 4
    "  settle_time: 0.3 s\n"                                        // 5
    "tests:\n"                                                      // 6
    "  - name: gas-4.0g\n"                                          // 7
    "    overrides: {array.gas_mass: 4.0 g}\n"                      // 8
    "    channels:\n"                                               // 9
    "      mat: full.csv\n"                                         // 10
    "      bag_pressures: [{bag: 17, file: b17.csv}]\n"             // 11
    "  - name: gas-5.0g\n"                                          // 12
    "    overrides:\n"                                              // 13
    "      array.gas_mass: 5.0 g\n"                                 // 14
    "      bag.body_tissue: {thickness: 10 mm, modulus: 50 kPa}\n"  // 15
    "    channels:\n"                                               // 16
    "      tilt: tilt.csv\n";                                       // 17

}  // namespace

TEST_F(PatientMeasuredDataTest, TestsReadWithTheirOverridesAndChannels) {
    write("full.csv", makeFullMat({0.1, 0.2}));
    write("measured.yaml", kTestsManifest);
    const diagnose::PatientMeasurement d = io::readPatientMeasuredData(m_dir.string());
    EXPECT_TRUE(d.channels.mat.empty());
    ASSERT_EQ(d.tests.size(), 2u);
    EXPECT_EQ(d.tests[0].name, "gas-4.0g");
    ASSERT_EQ(d.tests[0].overrides.size(), 1u);
    EXPECT_EQ(d.tests[0].overrides[0].first, "array.gas_mass");
    EXPECT_EQ(d.tests[0].overrides[0].second, "4.0 g");
    EXPECT_EQ(d.tests[0].channels.mat.rows, 64);
    ASSERT_EQ(d.tests[0].channels.bags.size(), 1u);
    EXPECT_TRUE(d.tests[1].channels.mat.empty());
    EXPECT_EQ(d.tests[1].channels.tilt.time.size(), 3u);
    ASSERT_EQ(d.tests[1].overrides.size(), 2u);
    // Each test's scenario: the protocol's settle time, then its own keys.
    const io::PatientMeasuredScenario s = io::readPatientMeasuredScenario(d);
    ASSERT_EQ(s.tests.size(), 2u);
    EXPECT_NEAR(s.tests[0].scenario.options.layout.gasMass, 4.0e-3, 1e-12);
    EXPECT_NEAR(s.tests[1].scenario.options.layout.gasMass, 5.0e-3, 1e-12);
    EXPECT_NEAR(s.tests[1].scenario.settleTime, 0.3, 1e-12);
    EXPECT_NEAR(s.scenario.options.layout.gasMass, 4.5e-3, 1e-12);  // the scenario's, untouched
}

TEST_F(PatientMeasuredDataTest, TestsWrittenReadBackTheSame) {
    write("full.csv", makeFullMat({0.1, 0.2}, 2.5));
    write("measured.yaml", kTestsManifest);
    const diagnose::PatientMeasurement d = io::readPatientMeasuredData(m_dir.string());
    const fs::path out = m_dir / "written";
    fs::create_directories(out);
    io::writePatientMeasuredData(out.string(), d, "kind: patient-on-array\n", "# synthetic\n");
    EXPECT_TRUE(fs::exists(out / "gas-4.0g-mat.csv"));
    EXPECT_TRUE(fs::exists(out / "gas-5.0g-tilt.csv"));
    const diagnose::PatientMeasurement r = io::readPatientMeasuredData(out.string());
    ASSERT_EQ(r.tests.size(), 2u);
    EXPECT_EQ(r.tests[1].name, "gas-5.0g");
    EXPECT_EQ(r.tests[1].overrides, d.tests[1].overrides);
    EXPECT_NEAR(r.tests[0].channels.mat.pressure[1][5], 2.5 * 133.322387415, 1e-2 * 133.3);
    EXPECT_NEAR(r.tests[1].channels.tilt.pelvis[2], d.tests[1].channels.tilt.pelvis[2], 1e-6);
}

TEST_F(PatientMeasuredDataTest, ChannelsAndTestsTogetherAreRefused) {
    write("measured.yaml", kManifest + "tests: []\n");
    const io::InputError e = readError();
    EXPECT_EQ(e.getKey(), "tests");
    EXPECT_EQ(e.getLine(), 12);
    EXPECT_NE(
        e.getMessage().find("both 'channels' and 'tests'; valid: 'channels' for one record, or "
                            "'tests'"),
        std::string::npos)
        << e.what();
    write("measured.yaml", kManifest.substr(0, kManifest.find("channels:")));
    const io::InputError n = readError();
    EXPECT_NE(n.getMessage().find("neither 'channels' nor 'tests'"), std::string::npos) << n.what();
    write("measured.yaml", kManifest.substr(0, kManifest.find("channels:")) + "tests: []\n");
    const io::InputError z = readError();
    EXPECT_EQ(z.getLine(), 6);
    EXPECT_NE(z.getMessage().find("is an empty list"), std::string::npos) << z.what();
}

TEST_F(PatientMeasuredDataTest, ATestNeedsANameOnceAndChannels) {
    write("full.csv", makeFullMat({0.1, 0.2}));
    write("measured.yaml", replaceAll(kTestsManifest, "name: gas-5.0g", "name: gas-4.0g"));
    const io::InputError twice = readError();
    EXPECT_EQ(twice.getLine(), 12);
    EXPECT_EQ(twice.getKey(), "tests[1].name");
    EXPECT_NE(twice.getMessage().find("the test \"gas-4.0g\" is named twice (first on line 7)"),
              std::string::npos)
        << twice.what();
    write("measured.yaml", replaceAll(kTestsManifest, "name: gas-5.0g", "name: gas 5/g"));
    const io::InputError bad = readError();
    EXPECT_EQ(bad.getLine(), 12);
    EXPECT_NE(bad.getMessage().find("is not a test's name; valid: 1-64 letters"), std::string::npos)
        << bad.what();
    write("measured.yaml",
          replaceAll(kTestsManifest, "  - name: gas-5.0g\n", "  - nam: gas-5.0g\n"));
    const io::InputError missing = readError();
    EXPECT_NE(std::string(missing.what()).find("tests[1]"), std::string::npos) << missing.what();
    write("measured.yaml",
          replaceAll(kTestsManifest, "      tilt: tilt.csv\n", "      tilt: none.csv\n"));
    const io::InputError file = readError();
    EXPECT_EQ(file.getLine(), 17);
    EXPECT_EQ(file.getKey(), "tests[1].channels.tilt");
    EXPECT_NE(file.getMessage().find("channel file \"none.csv\" is missing"), std::string::npos);
}

TEST_F(PatientMeasuredDataTest, ATestsOverridesAreCheckedAgainstTheScenario) {
    write("full.csv", makeFullMat({0.1, 0.2}));
    // A key the scenario does not have: at the test's key, with the scenario's own message.
    write("measured.yaml",
          replaceAll(kTestsManifest, "array.gas_mass: 5.0 g", "array.gas_mas: 5.0 g"));
    const io::InputError typo = scenarioError();
    EXPECT_EQ(typo.getLine(), 14);
    EXPECT_EQ(typo.getKey(), "tests[1].overrides.array.gas_mas");
    EXPECT_NE(typo.getMessage().find("the test \"gas-5.0g\": "), std::string::npos) << typo.what();
    EXPECT_NE(typo.getMessage().find("did you mean 'gas_mass'"), std::string::npos) << typo.what();
    // A value out of its bounds.
    write("measured.yaml",
          replaceAll(kTestsManifest, "{array.gas_mass: 4.0 g}", "{array.gas_mass: 4.0 m}"));
    const io::InputError unit = scenarioError();
    EXPECT_EQ(unit.getLine(), 8);
    EXPECT_EQ(unit.getKey(), "tests[0].overrides.array.gas_mass");
    // The protocol's keys are every test's.
    write("measured.yaml",
          replaceAll(kTestsManifest, "array.gas_mass: 5.0 g", "run.settle_time: 1 s"));
    const io::InputError proto = readError();
    EXPECT_EQ(proto.getLine(), 14);
    EXPECT_NE(proto.getMessage().find("a test cannot change 'run.settle_time'"), std::string::npos)
        << proto.what();
    // A test's channels against its scenario: at the test's key.
    write("measured.yaml", replaceAll(kTestsManifest, "mat: full.csv", "mat: mat.csv"));
    const io::InputError mat = scenarioError();
    EXPECT_EQ(mat.getLine(), 10);
    EXPECT_EQ(mat.getKey(), "tests[0].channels.mat");
    EXPECT_NE(mat.getMessage().find("has 2 x 3 sensels, the scenario's mat 64 x 32"),
              std::string::npos);
    write("measured.yaml", kTestsManifest);
    write("tilt.csv", "time_s,pelvis_tilt_deg\n0,0\n0.5,1\n");
    const io::InputError span = scenarioError();
    EXPECT_EQ(span.getLine(), 17);
    EXPECT_EQ(span.getKey(), "tests[1].channels.tilt");
}

namespace {

// Three tests of two subjects (docs/measured-data.md#several-subjects).
const std::string kSubjectsManifest =
    "format: bagsim-measured-data 1\n"  // 1
    "scenario: " BAGSIM_SOURCE_DIR
    "/scenarios/tests/supine-on-array-coarse.yaml\n"                                       // 2
    "protocol: {kind: patient-on-array, settle_time: 0.3 s}\n"                             // 3
    "tests:\n"                                                                             // 4
    "  - name: woman-4.5g\n"                                                               // 5
    "    subject: small-woman\n"                                                           // 6
    "    overrides: {patient.sex: female, patient.height: 1.55 m, patient.mass: 50 kg}\n"  // 7
    "    channels: {tilt: tilt.csv}\n"                                                     // 8
    "  - name: man-4.5g\n"                                                                 // 9
    "    subject: tall-man\n"                                                              // 10
    "    overrides: {patient.height: 1.90 m, patient.mass: 110 kg}\n"                      // 11
    "    channels: {tilt: tilt.csv}\n"                                                     // 12
    "  - name: woman-5.0g\n"                                                               // 13
    "    subject: small-woman\n"                                                           // 14
    "    overrides: {patient.sex: female, patient.height: 1.55 m, patient.mass: 50 kg, "
    "array.gas_mass: 5.0 g}\n"           // 15
    "    channels: {tilt: tilt.csv}\n";  // 16

}  // namespace

TEST_F(PatientMeasuredDataTest, SubjectsReadInTheManifestsOrder) {
    write("measured.yaml", kSubjectsManifest);
    const diagnose::PatientMeasurement d = io::readPatientMeasuredData(m_dir.string());
    ASSERT_EQ(d.tests.size(), 3u);
    EXPECT_EQ(d.tests[0].subject, "small-woman");
    EXPECT_EQ(d.tests[1].subject, "tall-man");
    EXPECT_EQ(d.tests[2].subject, "small-woman");
    EXPECT_EQ(d.getSubjects(), (std::vector<std::string>{"small-woman", "tall-man"}));
    // Each test's scenario holds its subject's build.
    const io::PatientMeasuredScenario s = io::readPatientMeasuredScenario(d);
    ASSERT_EQ(s.tests.size(), 3u);
    EXPECT_NEAR(s.tests[0].scenario.patient.height, 1.55, 1e-12);
    EXPECT_NEAR(s.tests[1].scenario.patient.mass, 110.0, 1e-12);
    EXPECT_NEAR(s.tests[2].scenario.options.layout.gasMass, 5.0e-3, 1e-12);
    // Without subjects the tests have none.
    write("full.csv", makeFullMat({0.1, 0.2}));
    write("measured.yaml", kTestsManifest);
    const diagnose::PatientMeasurement n = io::readPatientMeasuredData(m_dir.string());
    EXPECT_TRUE(n.getSubjects().empty());
    EXPECT_TRUE(n.tests[0].subject.empty());
}

TEST_F(PatientMeasuredDataTest, SubjectsWrittenReadBackTheSame) {
    write("measured.yaml", kSubjectsManifest);
    const diagnose::PatientMeasurement d = io::readPatientMeasuredData(m_dir.string());
    const fs::path out = m_dir / "written";
    fs::create_directories(out);
    io::writePatientMeasuredData(out.string(), d, "kind: patient-on-array\n", "# synthetic\n");
    const diagnose::PatientMeasurement r = io::readPatientMeasuredData(out.string());
    ASSERT_EQ(r.tests.size(), 3u);
    for (size_t i = 0; i < 3; ++i) EXPECT_EQ(r.tests[i].subject, d.tests[i].subject) << i;
}

TEST_F(PatientMeasuredDataTest, ATestWithoutASubjectWhereAnotherNamesOneIsLocated) {
    write("measured.yaml", replaceAll(kSubjectsManifest, "    subject: tall-man\n", ""));
    const io::InputError e = readError();
    EXPECT_NE(e.getWhere().find("measured.yaml"), std::string::npos) << e.what();
    EXPECT_EQ(e.getLine(), 9);  // the test's entry: its key is absent
    EXPECT_EQ(e.getKey(), "tests[1].subject");
    EXPECT_NE(
        e.getMessage().find("the test \"man-4.5g\" names no subject, the test \"woman-4.5g\" "
                            "(line 6) names \"small-woman\"; valid: a subject for every test"),
        std::string::npos)
        << e.what();
}

TEST_F(PatientMeasuredDataTest, SubjectsNeedTwoAndPlainNames) {
    write("measured.yaml",
          replaceAll(kSubjectsManifest, "subject: tall-man", "subject: small-woman"));
    const io::InputError one = readError();
    EXPECT_EQ(one.getLine(), 6);
    EXPECT_EQ(one.getKey(), "tests[0].subject");
    EXPECT_NE(
        one.getMessage().find("every test names the subject \"small-woman\"; valid: at least two "
                              "subjects"),
        std::string::npos)
        << one.what();
    write("measured.yaml",
          replaceAll(kSubjectsManifest, "subject: tall-man", "subject: tall man/2"));
    const io::InputError bad = readError();
    EXPECT_EQ(bad.getLine(), 10);
    EXPECT_EQ(bad.getKey(), "tests[1].subject");
    EXPECT_NE(bad.getMessage().find("\"tall man/2\" is not a subject's name; valid: 1-64 letters"),
              std::string::npos)
        << bad.what();
    // A subject's key where the manifest has no tests list is an unknown key of the manifest.
    write("measured.yaml", kManifest + "subject: a\n");
    const io::InputError top = readError();
    EXPECT_EQ(top.getLine(), 12);
}
