// Several bags in one module (AirbagSpec::cluster): a cluster of one is the single bag, each
// bag keeps its own gas, and neighbours pressed together by their own inflation exert equal
// and opposite forces on each other through the module's self-contact.
#include <bags/Airbag.h>
#include <bags/MaterialFit.h>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

using namespace bags;

namespace {

AirbagSpec coarseSpec() {
    AirbagSpec s;
    s.geometry.meshSize = 0.025;
    s.material = makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    s.forceTolerance = 1e-6;
    return s;
}

Eigen::Isometry3d translation(const Vec3& p) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = p;
    return X;
}

// Two bags side by side across their width (y), `gap` [m] between their flat side panels.
AirbagSpec pairSpec(double gap) {
    AirbagSpec s = coarseSpec();
    const double pitch = s.geometry.width + gap;
    s.cluster = {translation(Vec3(0, -0.5 * pitch, 0)), translation(Vec3(0, 0.5 * pitch, 0))};
    return s;
}

}  // namespace

TEST(AirbagCluster, ACopyAtTheIdentityIsTheSingleBag) {
    // Reference: the single bag of the same spec. The copy's nodes are the bag's nodes times
    // an identity pose (exact), so the module must give the same state to the bit.
    AirbagSpec single = coarseSpec();
    AirbagSpec one = coarseSpec();
    one.cluster = {Eigen::Isometry3d::Identity()};
    Airbag a(single), b(one);
    ASSERT_EQ(b.getNumBags(), 1);
    auto press = [](Airbag& bag) {
        int apex = 0;
        bag.getMesh().X.row(2).maxCoeff(&apex);
        const Vec3 c(bag.getMesh().X(0, apex), 0.0, 0.0);
        std::shared_ptr<RigidShape> e(makeEllipsoid(Vec3(0.04, 0.03, 0.02)));
        e->setPose(translation(c + Vec3(0, 0, 0.5)));
        const int s = bag.addShape(e, RigidContact::Options());
        bag.inflate(4.5e-3);
        const double top = bag.getPositions().row(2).maxCoeff();
        bag.setShapePose(s, translation(c + Vec3(0, 0, top + 0.02 - 0.008)));
        EXPECT_TRUE(bag.advance(1.0).converged);
        bag.commit();
        return bag.calcShapeWrench(s).force;
    };
    const Vec3 fa = press(a), fb = press(b);
    EXPECT_GT(fa.z(), 1.0);  // the ellipsoid is pressed 8 mm in
    EXPECT_EQ(fa, fb);
    EXPECT_EQ((a.getPositions() - b.getPositions()).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(a.getTotalGasMass(), b.getGasMass(0));
}

TEST(AirbagCluster, NeighboursPressedByTheirOwnInflationBalanceTheirContactForces) {
    // Two bags 4 mm apart: their side panels bulge by more than that when inflated (4.5 g),
    // so they press on each other. Reference: Newton's third law, to roundoff of the contact
    // force (1e-9 relative); the force must be real (above 0.5 N) and push them apart (bag 0
    // lies at -y).
    Airbag pair(pairSpec(0.004));
    ASSERT_EQ(pair.getNumBags(), 2);
    EXPECT_EQ(pair.getBagNodes(1).first, pair.getBagNodes(0).second);
    pair.inflate(4.5e-3);
    const Vec3 f0 = pair.calcNeighbourForce(0), f1 = pair.calcNeighbourForce(1);
    EXPECT_GT(f1.y(), 0.5);
    EXPECT_LT(f0.y(), -0.5);
    EXPECT_LT((f0 + f1).norm(), 1e-9 * f1.norm());
    // Each bag holds its own gas.
    EXPECT_NEAR(pair.getGasMass(0), 4.5e-3, 1e-15);
    EXPECT_NEAR(pair.getGasMass(1), 4.5e-3, 1e-15);

    // Far apart (50 mm) they never meet: no force between them.
    Airbag apart(pairSpec(0.050));
    apart.inflate(4.5e-3);
    EXPECT_EQ(apart.calcNeighbourForce(0).norm(), 0.0);
}

TEST(AirbagCluster, EachBagKeepsItsOwnGasAndFlows) {
    // Reference: the masses given, to 1e-12 kg; a flow into one bag leaves the other's mass.
    Airbag pair(pairSpec(0.004));
    pair.inflate({4.5e-3, 3.5e-3});
    EXPECT_NEAR(pair.getGasMass(0), 4.5e-3, 1e-12);
    EXPECT_NEAR(pair.getGasMass(1), 3.5e-3, 1e-12);
    EXPECT_NEAR(pair.getTotalGasMass(), 8.0e-3, 1e-12);
    const double p0 = pair.getChamberState(pair.getBagChambers(0).front()).gaugePressure;
    const double p1 = pair.getChamberState(pair.getBagChambers(1).front()).gaugePressure;
    EXPECT_GT(p0, p1);                    // the fuller bag is at the higher pressure
    pair.setTargetMass(1, 4.0e-3, 1e-3);  // 1 g/s into bag 1 up to 4.0 g
    ASSERT_TRUE(pair.advance(1.0).converged);
    pair.commit();
    EXPECT_NEAR(pair.getGasMass(0), 4.5e-3, 1e-12);
    EXPECT_NEAR(pair.getGasMass(1), 4.0e-3, 1e-12);
    pair.changeGasMass({4.0e-3, 4.0e-3});
    EXPECT_NEAR(pair.getGasMass(0), 4.0e-3, 1e-12);
}

TEST(AirbagCluster, AGasMassChangeOfAFewUlpsEnds) {
    // A cluster ramps its gas in at least 16 increments. Asked for masses that differ from
    // the bags' own by roundoff only (a load test asks for the masses it inflated to, summed
    // back from the chambers), the increment is below the mass's roundoff: the ramp must end,
    // at exactly the masses asked (reference: the masses given, bit for bit), and not step in
    // place for ever.
    Airbag pair(pairSpec(0.004));
    pair.inflate(4.5e-3);
    const double m0 = pair.getGasMass(0), m1 = pair.getGasMass(1);
    const double up = std::nextafter(std::nextafter(m0, 1.0), 1.0);
    pair.changeGasMass({up, m1});
    EXPECT_EQ(pair.getGasMass(0), up);
    EXPECT_EQ(pair.getGasMass(1), m1);
}

TEST(AirbagCluster, BadClustersAndMassesAreRefusedNamingTheOption) {
    AirbagSpec noSelf = pairSpec(0.004);
    noSelf.selfContact = false;
    try {
        Airbag bag(noSelf);
        FAIL() << "a cluster without self-contact was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("selfContact"), std::string::npos) << e.what();
    }
    AirbagSpec orifice = pairSpec(0.004);
    orifice.connection = AirbagSpec::Connection::Orifice;
    EXPECT_THROW(Airbag bag(orifice), std::invalid_argument);
    Airbag pair(pairSpec(0.004));
    try {
        pair.inflate(std::vector<double>{4.5e-3});
        FAIL() << "one mass for two bags was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("one gas mass per bag"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(pair.getGasMass(2), std::out_of_range);
}

namespace {

// An ellipsoid pressed `depth` [m] into bag 0's apex, bag 0 at -y of a pair; returns the
// force on it. The ellipsoid starts clear of the bag while it inflates to `masses`.
Vec3 pressBagZero(Airbag& pair, const std::vector<double>& masses, double depth) {
    const auto [b0, e0] = pair.getBagNodes(0);
    int apex = b0;
    for (int i = b0; i < e0; ++i)
        if (pair.getMesh().X(2, i) > pair.getMesh().X(2, apex)) apex = i;
    const Vec3 c = pair.getMesh().X.col(apex);
    std::shared_ptr<RigidShape> e(makeEllipsoid(Vec3(0.04, 0.03, 0.02)));
    e->setPose(translation(c + Vec3(0, 0, 0.5)));
    const int s = pair.addShape(e, RigidContact::Options());
    pair.inflate(masses);
    double top = -1.0;
    for (int i = b0; i < e0; ++i) top = std::max(top, pair.getPositions()(2, i));
    pair.setShapePose(s, translation(Vec3(c.x(), c.y(), top + 0.02 - depth)));
    EXPECT_TRUE(pair.advance(1.0).converged);
    pair.commit();
    return pair.calcShapeWrench(s).force;
}

double gaugePressure(const Airbag& bag, int b) {
    return bag.getChamberState(bag.getBagChambers(b).front()).gaugePressure;
}

}  // namespace

TEST(AirbagCluster, SharedAirIsOneBodyOfAirThatAPressMovesIntoTheNeighbour) {
    // Two bags 50 mm apart (their walls never meet), each first with its own air, then
    // sharing it (AirbagSpec::sharedAir), 4.0 + 4.0 g, bag 0 pressed 10 mm by an ellipsoid.
    // References:
    //  - the shared air is one ideal gas: (p + p_ambient) V_total = m R T to 1e-9 relative,
    //    one pressure in every chamber of both bags (exact: one gas body), its mass the two
    //    masses summed (1e-15 kg);
    //  - pressed, it moves air into bag 1 (bag 1's share grows) and raises bag 1's pressure,
    //    which with separate air stays where inflation left it (1e-9 relative);
    //  - the press's pressure rise: isothermal, dp = p_abs dV / V, so twice the volume of air
    //    takes half the rise: shared / own = 0.5, to 2 % (the films' own give differs a
    //    little between the two states); the force on the ellipsoid is then lower.
    AirbagSpec own = pairSpec(0.050), shared = pairSpec(0.050);
    shared.sharedAir = true;
    const std::vector<double> masses{4.0e-3, 4.0e-3};
    // The unpressed pressures (the ellipsoid far away).
    auto unpressed = [&](const AirbagSpec& spec) {
        std::shared_ptr<RigidShape> far(makeEllipsoid(Vec3(0.01, 0.01, 0.01)));
        far->setPose(translation(Vec3(0, 0, 5.0)));
        Airbag probe(spec);
        probe.addShape(far, RigidContact::Options());
        probe.inflate(masses);
        return std::make_unique<Airbag>(std::move(probe));
    };
    const auto ownAt0 = unpressed(own), sharedAt0 = unpressed(shared);
    EXPECT_NEAR(sharedAt0->getTotalGasMass(), 8.0e-3, 1e-15);
    EXPECT_NEAR(sharedAt0->getGasMass(0), 4.0e-3, 1e-9);  // mirror images: equal shares
    EXPECT_EQ(gaugePressure(*sharedAt0, 0), gaugePressure(*sharedAt0, 1));

    Airbag a(own), b(shared);
    const Vec3 fOwn = pressBagZero(a, masses, 0.010);
    const Vec3 fShared = pressBagZero(b, masses, 0.010);
    const double p1 = gaugePressure(*ownAt0, 1);
    EXPECT_NEAR(gaugePressure(a, 1), p1, 1e-9 * p1);  // separate air: bag 1 feels nothing
    const double riseOwn = gaugePressure(a, 0) - gaugePressure(*ownAt0, 0);
    const double riseShared = gaugePressure(b, 0) - gaugePressure(*sharedAt0, 0);
    EXPECT_GT(riseOwn, 10.0);  // [Pa] a real press
    EXPECT_NEAR(riseShared / riseOwn, 0.5, 0.01);
    EXPECT_GT(fOwn.z(), 1.0);
    EXPECT_LT(fShared.z(), fOwn.z());  // softer with shared air

    EXPECT_NEAR(b.getTotalGasMass(), 8.0e-3, 1e-15);
    EXPECT_GT(b.getGasMass(1), 4.0e-3 + 1e-6);  // air pressed into bag 1
    EXPECT_NEAR(b.getGasMass(0) + b.getGasMass(1), 8.0e-3, 1e-12);
    for (int c = 0; c < b.getNumChambers(); ++c)
        EXPECT_EQ(b.getChamberState(c).gaugePressure, gaugePressure(b, 0));
    double V = 0.0;
    for (int c = 0; c < b.getNumChambers(); ++c) V += b.getChamberState(c).volume;
    const GasOptions& g = shared.gas;
    const double pAbs = gaugePressure(b, 0) + g.ambientPressure;
    EXPECT_NEAR(pAbs * V, 8.0e-3 * g.getSpecificGasConstant() * g.temperature, 1e-9 * pAbs * V);
    EXPECT_GT(gaugePressure(b, 1), gaugePressure(*sharedAt0, 1));  // the press reached bag 1
}

TEST(AirbagCluster, SharedAirTakesFlowsIntoAnyBagAndRefusesPerBagTargets) {
    // Reference: mass balance, 0.5 g/s into bag 1 over 1 s adds 0.5 g to the shared air
    // (1e-12 kg); a target for one bag has no meaning with one body of air.
    AirbagSpec shared = pairSpec(0.050);
    shared.sharedAir = true;
    Airbag pair(shared);
    pair.inflate({4.0e-3, 3.0e-3});
    EXPECT_NEAR(pair.getTotalGasMass(), 7.0e-3, 1e-15);
    EXPECT_EQ(gaugePressure(pair, 0), gaugePressure(pair, 1));
    pair.setMassFlow(1, 0.5e-3);
    ASSERT_TRUE(pair.advance(1.0).converged);
    pair.commit();
    EXPECT_NEAR(pair.getTotalGasMass(), 7.5e-3, 1e-12);
    EXPECT_THROW(pair.setTargetMass(0, 4.0e-3, 1e-3), std::logic_error);
    pair.changeGasMass({3.0e-3, 3.0e-3});
    EXPECT_NEAR(pair.getTotalGasMass(), 6.0e-3, 1e-12);

    AirbagSpec alone = coarseSpec();
    alone.sharedAir = true;
    try {
        Airbag bag(alone);
        FAIL() << "shared air without a cluster was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("sharedAir"), std::string::npos) << e.what();
    }
}
