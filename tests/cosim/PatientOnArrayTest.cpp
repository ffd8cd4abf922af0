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

TEST(PatientOnArray, CoSimulationsRunOneAfterAnotherInOneProcessAreIndependent) {
    // Studies and diagnoses run many co-simulations; each must be its own. Reference: the
    // same run repeated gives the same bits, whatever ran before it in the process (here a
    // run at half the macro step) and on one thread as on two. The half-step run itself must
    // differ (else the check could not see a leak from it).
    auto run = [](double macroStep, int threads) {
        PatientOnArrayOptions o = coarseOptions();
        o.coupling.macroStep = macroStep;
        o.coupling.threads = threads;
        PatientOnArray poa(lightPatient(), o);
        while (poa.getTime() < 0.03 - 1e-9) poa.step();
        return poa.calcBagForces();
    };
    const std::vector<double> first = run(0.010, 2);
    const std::vector<double> half = run(0.005, 2);
    const std::vector<double> again = run(0.010, 2);
    const std::vector<double> oneThread = run(0.010, 1);
    ASSERT_EQ(first.size(), again.size());
    double total = 0.0;
    for (double f : first) total += f;
    EXPECT_GT(total, 1.0);  // he has landed on some bags by 30 ms
    EXPECT_EQ(first, again);
    EXPECT_EQ(first, oneThread);
    EXPECT_NE(first, half);
}

TEST(PatientOnArray, WithBodyFrictionTheBagsHandTheBodyTheirLinearisationWithoutFriction) {
    // With body friction the bags' stick springs stay out of the body's linearised load (they
    // spun the landing patient under tangent-implicit, docs/cosim.md#friction-and-the-tangent-
    // schemes): every finite-element bag is set to its linearisation without friction, and
    // none is without friction. Tangent-implicit is taken with friction, tangent is not.
    for (const double mu : {0.0, 0.4}) {
        PatientOnArrayOptions o = coarseOptions();
        o.contact.friction = mu;
        o.coupling.scheme = Scheme::TangentImplicit;
        PatientOnArray poa(lightPatient(), o);
        int n = 0;
        for (size_t i = 0; i < poa.getBagIndices().size(); ++i) {
            const auto* b = dynamic_cast<const BagParticipant*>(&poa.getBag(int(i)));
            ASSERT_NE(b, nullptr);
            EXPECT_EQ(b->getLinearisationWithoutFriction(), mu > 0.0) << "bag " << i;
            ++n;
        }
        EXPECT_EQ(n, 28);
    }
    PatientOnArrayOptions o = coarseOptions();
    o.contact.friction = 0.4;
    o.coupling.scheme = Scheme::Tangent;
    EXPECT_THROW(o.validate(), std::invalid_argument);
}
