// Validation of the patient section: refused with a reason, never clamped.
#include <body/PatientSpec.h>
#include <gtest/gtest.h>

namespace {

std::string errorOf(const body::PatientSpec& s) {
    try {
        s.validate();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(PatientSpec, AcceptsTheDocumentedRange) {
    body::PatientSpec s;
    for (double h : {1.4, 1.62, 2.1})
        for (double bmi : {14.0, 25.0, 50.0}) {
            s.height = h;
            s.mass = bmi * h * h;
            EXPECT_EQ(errorOf(s), "") << h << " " << bmi;
        }
}

TEST(PatientSpec, RefusesHeightOutsideRangeWithReason) {
    body::PatientSpec s;
    s.height = 2.3;
    s.mass = 90;
    const std::string e = errorOf(s);
    EXPECT_NE(e.find("patient.height"), std::string::npos) << e;
    EXPECT_NE(e.find("1.4-2.1"), std::string::npos) << e;
    EXPECT_DOUBLE_EQ(s.height, 2.3);  // not clamped
    s.height = 1.39;
    s.mass = 40;
    EXPECT_NE(errorOf(s).find("patient.height"), std::string::npos);
    s.height = 175;  // centimetres by mistake
    EXPECT_NE(errorOf(s).find("metres"), std::string::npos);
}

TEST(PatientSpec, RefusesBmiOutsideRangeWithReason) {
    body::PatientSpec s;
    s.height = 1.8;
    s.mass = 200;  // BMI 61.7
    std::string e = errorOf(s);
    EXPECT_NE(e.find("BMI of 61.7"), std::string::npos) << e;
    EXPECT_NE(e.find("14-50"), std::string::npos) << e;
    s.mass = 13.9 * 1.8 * 1.8;
    EXPECT_NE(errorOf(s).find("BMI"), std::string::npos);
    s.mass = -3;
    EXPECT_NE(errorOf(s).find("patient.mass"), std::string::npos);
}

TEST(PatientSpec, ParsesSexAndPostureNames) {
    EXPECT_EQ(body::parseSex("Female"), body::Sex::Female);
    EXPECT_EQ(body::parseSex("m"), body::Sex::Male);
    EXPECT_THROW(body::parseSex("x"), std::invalid_argument);
    EXPECT_EQ(body::parsePosture("tilt-left-30"), body::Posture::TiltLeft30);
    EXPECT_EQ(body::parsePosture("Head-Of-Bed-Raised"), body::Posture::HeadOfBedRaised);
    try {
        body::parsePosture("prone");
        FAIL() << "prone is not a posture";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("side-left-90"), std::string::npos);
    }
}
