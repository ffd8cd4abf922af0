// The patient lying on an array of airbags through the co-simulation: a light patient on a
// coarse array is lowered onto it, settles, and at rest the bags carry his weight while the
// mechanical energy does not grow.
#include "PatientAtRest.h"

using namespace cosim;
using cosim::test::coarseOptions;
using cosim::test::lightPatient;

TEST(PatientOnArray, ALightPatientSettlesOnTheArrayTheBagsCarryHisWeightAndEnergyDoesNotGrow) {
    // Released, settled by 1.3 s, then 0.3 s at rest (the 10 s rest is a long test:
    // PatientOnArrayLongTest.cpp).
    cosim::test::checkLightPatientSettlesAndRests(1.6, 0.3);
}

TEST(PatientOnArray, APatientBesideTheArrayIsRefusedNamingTheSegments) {
    // Mid-hip 1.2 m to the side of the array's centre line: no bag under any segment. The
    // error is thrown before any bag is built.
    body::PatientSpec p = lightPatient();
    p.position = {{0.0, 1.2}};
    try {
        PatientOnArray poa(p, coarseOptions());
        FAIL() << "no error";
    } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("no bag of the array lies under segment(s) 0 1 2"), std::string::npos)
            << what;
    }
    PatientOnArrayOptions bad = coarseOptions();
    bad.pairMargin = -0.01;
    EXPECT_THROW(PatientOnArray(lightPatient(), bad), std::invalid_argument);
}
