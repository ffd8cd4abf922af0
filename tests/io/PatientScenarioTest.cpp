// The patient section of a scenario (io::readPatientSection) and the patient-on-support kind:
// SI values, and located errors for out-of-range, misspelt, missing and mis-unit values.
#include <gtest/gtest.h>
#include <io/InputError.h>
#include <io/PatientScenario.h>

#include <cmath>
#include <string>

namespace {

const char* kGood =
    "kind: patient-on-support\n"        // 1
    "settle_time: 1.5 s\n"              // 2
    "support:\n"                        // 3
    "  stiffness: 3 MPa/m\n"            // 4
    "  friction: 0.4\n"                 // 5
    "patient:\n"                        // 6
    "  sex: female\n"                   // 7
    "  height: 162 cm\n"                // 8
    "  mass: 58 kg\n"                   // 9
    "  posture: head-of-bed-raised\n"   // 10
    "  head_of_bed_angle: 45 deg\n"     // 11
    "  position: [100 mm, -0.05 m]\n";  // 12

// A scenario whose patient section has the given height and mass (lines 4 and 5) and extra lines.
std::string patientWith(const std::string& height, const std::string& mass,
                        const std::string& extra = "") {
    return "kind: patient-on-support\n"  // 1
           "patient:\n"                  // 2
           "  sex: male\n"               // 3
           "  height: " +
           height +
           "\n"  // 4
           "  mass: " +
           mass + "\n" + extra;  // 5, 6...
}

io::InputError readError(const std::string& text, const std::string& name) {
    try {
        io::readScenarioPatient(io::ScenarioFile::parse(text, name));
    } catch (const io::InputError& e) {
        return e;
    }
    ADD_FAILURE() << "no InputError for:\n" << text;
    return io::InputError("", 0, "", "");
}

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

}  // namespace

TEST(PatientScenario, ReadsGoodSectionInSiUnits) {
    const io::PatientOnSupportScenario sc =
        io::readPatientOnSupportScenario(io::ScenarioFile::parse(kGood, "good.yaml"));
    const body::PatientSpec& p = sc.patient;
    EXPECT_EQ(p.sex, body::Sex::Female);
    // Unit conversions are exact up to rounding (1e-12 relative).
    EXPECT_NEAR(p.height, 1.62, 1e-12);
    EXPECT_NEAR(p.mass, 58.0, 1e-12);
    EXPECT_EQ(p.posture, body::Posture::HeadOfBedRaised);
    EXPECT_NEAR(p.headOfBedAngle, 45.0 * M_PI / 180.0, 1e-12);
    EXPECT_NEAR(p.position[0], 0.1, 1e-12);
    EXPECT_NEAR(p.position[1], -0.05, 1e-12);
    EXPECT_NEAR(sc.settle.settleTime, 1.5, 1e-12);
    EXPECT_NEAR(sc.settle.support.stiffness, 3e6, 1e-3);
    EXPECT_NEAR(sc.settle.support.friction, 0.4, 1e-12);
    EXPECT_EQ(sc.name, "good");
}

TEST(PatientScenario, DefaultsPostureSupineAtOrigin) {
    const body::PatientSpec p =
        io::readScenarioPatient(io::ScenarioFile::parse(patientWith("1.75 m", "70 kg"), "d.yaml"));
    EXPECT_EQ(p.sex, body::Sex::Male);
    EXPECT_EQ(p.posture, body::Posture::Supine);
    EXPECT_EQ(p.position[0], 0.0);
    EXPECT_EQ(p.position[1], 0.0);
}

TEST(PatientScenario, RefusesHeightOutsideRangeAtItsLine) {
    const io::InputError e = readError(patientWith("2.3 m", "90 kg"), "tall.yaml");
    const std::string msg = e.what();
    EXPECT_EQ(e.getWhere(), "tall.yaml");
    EXPECT_EQ(e.getLine(), 4);  // the height line of patientWith()
    EXPECT_EQ(e.getKey(), "patient.height");
    EXPECT_TRUE(contains(msg, "tall.yaml:4")) << msg;
    EXPECT_TRUE(contains(msg, "patient.height")) << msg;
    EXPECT_TRUE(contains(msg, "1.4-2.1 m")) << msg;
    EXPECT_TRUE(contains(msg, "2.3")) << msg;
}

TEST(PatientScenario, RefusesBmiOutsideRangeNamingTheBmi) {
    // 1.75 m and 183.75 kg: BMI = 183.75 / 1.75^2 = 60.0 exactly.
    const io::InputError e = readError(patientWith("1.75 m", "183.75 kg"), "heavy.yaml");
    const std::string msg = e.what();
    EXPECT_EQ(e.getLine(), 5);  // the mass line
    EXPECT_EQ(e.getKey(), "patient.mass");
    EXPECT_TRUE(contains(msg, "BMI of 60")) << msg;
    EXPECT_TRUE(contains(msg, "14-50")) << msg;
}

TEST(PatientScenario, SuggestsHeightForMisspeltKey) {
    const std::string text =
        "patient:\n"
        "  sex: male\n"
        "  hieght: 1.8 m\n"
        "  mass: 80 kg\n";
    const io::InputError e = readError(text, "typo.yaml");
    const std::string msg = e.what();
    EXPECT_EQ(e.getLine(), 3);
    EXPECT_EQ(e.getKey(), "patient.hieght");
    EXPECT_TRUE(contains(msg, "did you mean 'height'?")) << msg;
}

TEST(PatientScenario, ListsRequiredKeysWhenSexIsMissing) {
    const std::string text =
        "patient:\n"
        "  height: 1.8 m\n"
        "  mass: 80 kg\n";
    const io::InputError e = readError(text, "nosex.yaml");
    const std::string msg = e.what();
    EXPECT_TRUE(contains(msg, "missing required key 'sex'")) << msg;
    EXPECT_TRUE(contains(msg, "it requires sex, height, mass")) << msg;
    EXPECT_EQ(e.getLine(), 1);  // the 'patient:' line
    EXPECT_EQ(e.getWhere(), "nosex.yaml");
}

TEST(PatientScenario, ListsMassUnitsForWrongUnit) {
    const io::InputError e = readError(patientWith("1.8 m", "58 g/mol"), "unit.yaml");
    const std::string msg = e.what();
    EXPECT_EQ(e.getLine(), 5);
    EXPECT_EQ(e.getKey(), "patient.mass");
    EXPECT_TRUE(contains(msg, "use g, kg, mg")) << msg;  // the valid mass units
    EXPECT_TRUE(contains(msg, "not a mass")) << msg;
}

TEST(PatientScenario, SuggestsPostureAndRefusesAngleForOtherPostures) {
    const io::InputError e1 =
        readError(patientWith("1.8 m", "80 kg", "  posture: supin\n"), "p.yaml");
    EXPECT_EQ(e1.getLine(), 6);
    EXPECT_TRUE(contains(e1.what(), "supine")) << e1.what();
    const io::InputError e2 =
        readError(patientWith("1.8 m", "80 kg", "  head_of_bed_angle: 30 deg\n"), "a.yaml");
    EXPECT_EQ(e2.getKey(), "patient.head_of_bed_angle");
    EXPECT_TRUE(contains(e2.what(), "head-of-bed-raised")) << e2.what();
    const io::InputError e3 =
        readError(patientWith("1.8 m", "80 kg", "  position: [0 m]\n"), "pos.yaml");
    EXPECT_EQ(e3.getKey(), "patient.position");
}

TEST(PatientScenario, ReportsInvalidSupportOptionAtItsKey) {
    std::string text = kGood;
    text.replace(text.find("0.4"), 3, "-1");
    try {
        io::readPatientOnSupportScenario(io::ScenarioFile::parse(text, "sup.yaml"));
        FAIL() << "negative friction accepted";
    } catch (const io::InputError& e) {
        EXPECT_EQ(e.getLine(), 5);
        EXPECT_EQ(e.getKey(), "support.friction");
    }
}

TEST(PatientScenario, TheSupportsFrictionLawIsRegularisedByDefaultAndCanBeStickSlip) {
    auto read = [](const std::string& lines) {
        std::string text = kGood;
        text.insert(text.find("patient:"), lines);
        return io::readPatientOnSupportScenario(io::ScenarioFile::parse(text, "sup.yaml"));
    };
    EXPECT_EQ(read("").settle.support.frictionLaw, body::SupportFrictionLaw::Regularised);
    const io::PatientOnSupportScenario s =
        read("  friction_law: stick-slip\n  stick_distance: 0.5 mm\n");
    EXPECT_EQ(s.settle.support.frictionLaw, body::SupportFrictionLaw::StickSlip);
    EXPECT_DOUBLE_EQ(s.settle.support.stickDistance, 5e-4);
    struct Bad {
        std::string lines, key;
        int line;
    };
    for (const Bad& b : std::vector<Bad>{
             {"  friction_law: sticky\n", "support.friction_law", 6},
             {"  slip_velocity: 5 mm/s\n  friction_law: stick-slip\n", "support.slip_velocity", 6},
             {"  stick_distance: 1 mm\n", "support.stick_distance", 6},
             {"  friction_law: stick-slip\n  stick_distance: 0 mm\n", "support.stick_distance",
              7}}) {
        try {
            read(b.lines);
            ADD_FAILURE() << "accepted:\n" << b.lines;
        } catch (const io::InputError& e) {
            EXPECT_EQ(e.getKey(), b.key) << b.lines;
            EXPECT_EQ(e.getLine(), b.line) << b.lines;
        }
    }
}
