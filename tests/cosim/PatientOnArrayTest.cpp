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

TEST(PatientOnArray, ImmersionIsMeasuredFromWhereEachPointOfTheFilmStoodBeforeHeLayOnIt) {
    // The rest heights: per coupled bag, its pressure points' heights once inflated (before
    // any step), the films' shape at rest (a wedge's crest at 100-160 mm on 30 mm meshes at
    // 4.5 g). After he has landed (0.1 s), reference: the films' own nodes. Every region's
    // immersion lies between 0 and the highest rest height; a region with no area has none;
    // and the deepest region's is the most any node pressed above the 5 mmHg threshold
    // (calcPressedNodeHeights()' criterion, per shape) lies below its rest height, found here
    // over the bags' nodes and shapes directly, to 1e-12 m.
    PatientOnArray poa(lightPatient(), coarseOptions());
    double highest = 0.0;
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const Eigen::VectorXd& z0 = poa.getRestHeights(int(b));
        EXPECT_EQ(z0, poa.getBag(int(b)).getPressurePoints().row(2).transpose()) << b;
        EXPECT_GT(z0.maxCoeff(), 0.100) << b;
        EXPECT_LT(z0.maxCoeff(), 0.160) << b;
        highest = std::max(highest, z0.maxCoeff());
    }
    while (poa.getTime() < 0.1 - 1e-9) poa.step();
    const double threshold = 5.0 * 133.322387415;
    double deepestRegion = 0.0, deepestNode = 0.0;
    int immersed = 0;
    for (const RegionLoad& r : calcRegionLoads(poa, threshold)) {
        EXPECT_GE(r.immersion, 0.0) << r.name;
        EXPECT_LT(r.immersion, highest) << r.name;
        if (r.area == 0.0) EXPECT_EQ(r.immersion, 0.0) << r.name;
        immersed += r.immersion > 1e-3;
        deepestRegion = std::max(deepestRegion, r.immersion);
    }
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const Bag& bag = poa.getBag(int(b));
        const Eigen::Matrix3Xd& x = bag.getPressurePoints();
        for (int s = 0; s < bag.getNumShapes(); ++s) {
            const Eigen::VectorXd p = bag.calcContactPressure(s);
            for (Eigen::Index n = 0; n < p.size(); ++n)
                if (p[n] > threshold)
                    deepestNode = std::max(deepestNode, poa.getRestHeights(int(b))[n] - x(2, n));
        }
    }
    EXPECT_GT(immersed, 3);
    EXPECT_GT(deepestRegion, 0.005);  // he has pushed the films down by more than 5 mm somewhere
    EXPECT_NEAR(deepestRegion, deepestNode, 1e-12);
}
