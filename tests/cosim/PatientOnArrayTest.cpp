// The patient lying on an array of airbags through the co-simulation: a light patient on a
// coarse array is lowered onto it, settles, and at rest the bags carry his weight while the
// mechanical energy does not grow.
#include <cosim/ArrayReadings.h>

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

TEST(PatientOnArray, ImmersionIsMeasuredFromTheBagsTopAsInflatedBeforeHeLayOnThem) {
    // The rest tops: one per coupled bag, the highest of its pressure points once inflated
    // (before any step), a wedge's inflated height (the seed's bag rises to 150 mm; at 4.5 g
    // on 30 mm meshes 100-160 mm). After he has landed (0.1 s), reference: the bags' own
    // nodes. Every region's immersion lies between 0 and its bag's top, and the deepest
    // region's is the deepest pressed node's depth below its top over the bags
    // (calcPressedNodeHeights(): the same 5 mmHg threshold on each shape's pressure, read per
    // bag, not per region), to 1e-12 m.
    PatientOnArray poa(lightPatient(), coarseOptions());
    const std::vector<double>& top = poa.getRestTopHeights();
    ASSERT_EQ(top.size(), poa.getBagIndices().size());
    for (size_t b = 0; b < top.size(); ++b) {
        EXPECT_EQ(top[b], poa.getBag(int(b)).getPressurePoints().row(2).maxCoeff()) << b;
        EXPECT_GT(top[b], 0.100) << b;
        EXPECT_LT(top[b], 0.160) << b;
    }
    while (poa.getTime() < 0.1 - 1e-9) poa.step();
    const double threshold = 5.0 * 133.322387415;
    const std::vector<RegionLoad> regions = calcRegionLoads(poa, threshold);
    const std::vector<double> inner = calcPressedNodeHeights(poa, threshold);
    double deepestRegion = 0.0, deepestBag = 0.0;
    int immersed = 0;
    for (const RegionLoad& r : regions) {
        EXPECT_GE(r.immersion, 0.0) << r.name;
        EXPECT_LT(r.immersion, 0.160) << r.name;
        if (r.area == 0.0) EXPECT_EQ(r.immersion, 0.0) << r.name;
        immersed += r.immersion > 1e-3;
        deepestRegion = std::max(deepestRegion, r.immersion);
    }
    for (size_t b = 0; b < inner.size(); ++b)
        if (std::isfinite(inner[b])) deepestBag = std::max(deepestBag, top[b] - inner[b]);
    EXPECT_GT(immersed, 3);
    EXPECT_GT(deepestRegion, 0.005);  // he has sunk into the bags by more than 5 mm somewhere
    EXPECT_NEAR(deepestRegion, deepestBag, 1e-12);
}
