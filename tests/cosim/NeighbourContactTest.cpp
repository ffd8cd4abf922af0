// Neighbouring bags of an array that touch (cosim/NeighbourModules.h): the measure of how far
// two films pass through each other, the grouping of the bags that may meet into modules, and
// two inflated neighbours 5 mm apart pressed by a plank: solved alone their films overlap;
// grouped into one module they touch, and push each other with equal and opposite forces.
#include <bags/Airbag.h>
#include <bags/Geometry.h>
#include <bags/MaterialFit.h>
#include <cosim/ArrayLayout.h>
#include <cosim/NeighbourModules.h>
#include <gtest/gtest.h>

#include <cstdio>

using namespace cosim;

namespace {

bags::AirbagSpec makeSpec(double meshSize) {
    bags::AirbagSpec spec;
    spec.geometry.meshSize = meshSize;
    spec.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    spec.forceTolerance = 1e-4;
    spec.threads = 1;
    spec.selfContact = true;
    return spec;
}

// Two of the seed's wedges side by side along the bed, 5 mm between their flat side panels
// (the shipped scenarios' column pitch), column 0 at -y.
ArrayLayout makePair() {
    ArrayLayout layout;
    layout.rows = 1;
    layout.columns = 2;
    layout.columnPitch = 0.105;
    layout.rowOrientation = {BagOrientation::Along};
    layout.gasMass = 4.5e-3;
    return layout;
}

struct PairRun {
    std::vector<std::vector<int>> modules;
    double inflatedOverlap = 0.0, pressedOverlap = 0.0;     // [m]
    Vec3 neighbourForce[2] = {Vec3::Zero(), Vec3::Zero()};  // [N] on bag 0 and bag 1
    double plankForce = 0.0;                                // [N] up, both bags
    double gaugePressure = 0.0;                             // [Pa] bag 0, pressed
};

// The pair inflated to 4.5 g, then a 200 x 80 mm plank (its long side across both bags, over
// their apex ridges) pressed 20 mm below the inflated tops in 5 mm steps.
PairRun runPair(bool neighbourContact) {
    const bags::AirbagSpec spec = makeSpec(0.030);
    const std::vector<ArrayBag> cells = makeArrayBags(makePair(), spec.geometry);
    ArrayParticipants a =
        makeArrayParticipants(cells, {0, 1}, spec, neighbourContact, 0.005, 4.5e-3);
    PairRun r;
    r.modules = a.modules;
    const double ridgeX = cells[0].footprintMin.x() + spec.geometry.calcApexX();
    std::shared_ptr<bags::RigidShape> plank[2];
    int shape[2];
    for (int b = 0; b < 2; ++b) {
        plank[b] = bags::makeBox(Vec3(0.04, 0.10, 0.025), 1e-3);
        Eigen::Isometry3d parked = Eigen::Isometry3d::Identity();
        parked.translation() = Vec3(ridgeX, 0.0, 0.5);
        plank[b]->setPose(parked);
        bags::RigidContact::Options o;
        o.pressurePenalty = 1e8;
        shape[b] = a.addShape(b, plank[b], o, nullptr);
    }
    a.inflate({4.5e-3, 4.5e-3});
    auto overlap = [&] {
        return calcFilmOverlap(*a.bags[0]->getFilmMesh(), a.bags[0]->getPressurePoints(),
                               *a.bags[1]->getFilmMesh(), a.bags[1]->getPressurePoints());
    };
    r.inflatedOverlap = overlap();
    double top = 0.0;
    for (int b = 0; b < 2; ++b)
        top = std::max(top, a.bags[b]->getPressurePoints().row(2).maxCoeff());
    for (int k = 1; k <= 4; ++k) {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.translation() = Vec3(ridgeX, 0.0, top + 0.025 - 0.005 * k);
        ShapeState s;
        s.X_GS = pose;
        for (int b = 0; b < 2; ++b) a.bags[b]->setShapeState(shape[b], s);
        for (auto& p : a.participants) {
            EXPECT_TRUE(p->advance(0.0).converged) << "step " << k;
            p->commit();
        }
    }
    r.pressedOverlap = overlap();
    for (int b = 0; b < 2; ++b) r.plankForce += a.bags[b]->calcWrench(shape[b]).force.z();
    r.gaugePressure = a.bags[0]->getChamberState(0).gaugePressure;
    if (neighbourContact)
        for (int b = 0; b < 2; ++b)
            r.neighbourForce[b] = a.participants[0]->getAirbag().calcNeighbourForce(b);
    return r;
}

}  // namespace

TEST(NeighbourContact, FilmOverlapIsTheDepthOfOneBagsNodesInsideTheOther) {
    // Reference: two copies of the flat-paneled wedge, the second moved across by its width
    // less d: the facing side panel's nodes lie d inside the first bag (the panels are planes).
    bags::DoubleWedgeParams g;
    g.meshSize = 0.030;
    const bags::Mesh m = bags::makeDoubleWedgeBag(g);
    for (double d : {0.003, 0.012}) {
        Eigen::Matrix3Xd xB = m.X;
        xB.row(1).array() += g.width - d;
        EXPECT_NEAR(calcFilmOverlap(m, m.X, m, xB), d, 1e-9) << d;
        EXPECT_NEAR(calcFilmOverlap(m, xB, m, m.X), d, 1e-9) << d;
    }
    Eigen::Matrix3Xd apart = m.X;
    apart.row(1).array() += g.width + 0.005;
    EXPECT_EQ(calcFilmOverlap(m, m.X, m, apart), 0.0);
}

TEST(NeighbourContact, BagsWhoseGrownExtentsMeetAreGroupedIntoConnectedModules) {
    using Box = Eigen::AlignedBox2d;
    const std::vector<Box> boxes = {
        Box(Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 1)),
        Box(Eigen::Vector2d(1.004, 0), Eigen::Vector2d(2, 1)),  // 4 mm from 0
        Box(Eigen::Vector2d(2.1, 0), Eigen::Vector2d(3, 1)),    // 100 mm from 1
        Box(Eigen::Vector2d(0, 1.02), Eigen::Vector2d(1, 2))};  // 20 mm from 0
    EXPECT_EQ(findTouchingGroups(boxes, 0.005), (std::vector<std::vector<int>>{{0, 1}, {2}, {3}}));
    EXPECT_EQ(findTouchingGroups(boxes, 0.0), (std::vector<std::vector<int>>{{0}, {1}, {2}, {3}}));
    EXPECT_EQ(findTouchingGroups(boxes, 0.011), (std::vector<std::vector<int>>{{0, 1, 3}, {2}}));
    EXPECT_THROW(findTouchingGroups(boxes, -1.0), std::invalid_argument);
}

TEST(NeighbourContact, TwoNeighboursPressedByAPlankTouchAndPushEachOtherEqually) {
    // Two wedges 5 mm apart at 4.5 g (taut, above the literal bag's 3.6 g fill), a plank
    // pressed 20 mm into both. Solved alone (neighbour contact off) their side panels bulge
    // through each other (measured 21.1 mm inflated, 21.8 mm pressed); in one module they
    // touch: no node of one film lies deeper inside the other than the contact's penalty give,
    // and the films' forces on each other balance (Newton's third law, to 1e-9 of their size:
    // measured 160.8 N each, equal to the printed digits), pushing the bags apart.
    const PairRun off = runPair(false), on = runPair(true);
    const Eigen::AlignedBox2d ext = calcInflatedExtent(makeSpec(0.030), 4.5e-3);
    std::printf(
        "one bag inflated to 4.5 g alone: x %.2f to %.2f mm, y %.2f to %.2f mm "
        "(flat footprint 350 x 100 mm); pressed pair's gauge pressure %.3f kPa\n",
        1e3 * ext.min().x(), 1e3 * ext.max().x(), 1e3 * ext.min().y(), 1e3 * ext.max().y(),
        1e-3 * on.gaugePressure);
    std::printf(
        "alone: films overlap %.3f mm inflated, %.3f mm pressed (plank %.2f N)\n"
        "module: films overlap %.3f mm inflated, %.3f mm pressed (plank %.2f N); "
        "neighbour forces on bag 0 (%.4f, %.4f, %.4f) N, on bag 1 (%.4f, %.4f, %.4f) N\n",
        1e3 * off.inflatedOverlap, 1e3 * off.pressedOverlap, off.plankForce,
        1e3 * on.inflatedOverlap, 1e3 * on.pressedOverlap, on.plankForce, on.neighbourForce[0].x(),
        on.neighbourForce[0].y(), on.neighbourForce[0].z(), on.neighbourForce[1].x(),
        on.neighbourForce[1].y(), on.neighbourForce[1].z());
    EXPECT_EQ(off.modules, (std::vector<std::vector<int>>{{0}, {1}}));
    EXPECT_EQ(on.modules, (std::vector<std::vector<int>>{{0, 1}}));
    // Alone: the films pass through each other (the overlap the grouping removes).
    EXPECT_GT(off.inflatedOverlap, 1e-3);
    EXPECT_GT(off.pressedOverlap, off.inflatedOverlap);
    // Grouped: touching. What is left is the self-contact penalty's give: the films press on
    // each other with about the gas's gauge pressure p, and 1e7 Pa/m gives p / 1e7 Pa/m of
    // penetration (less the 0.5 mm contact thickness): measured 1.6 and 1.8 mm at 23.4 kPa.
    const double give = on.gaugePressure / 1e7;
    EXPECT_LT(on.inflatedOverlap, give);
    EXPECT_LT(on.pressedOverlap, give);
    EXPECT_LT(on.pressedOverlap, 0.1 * off.pressedOverlap);
    const Vec3 f0 = on.neighbourForce[0], f1 = on.neighbourForce[1];
    EXPECT_GT(f0.norm(), 0.5);
    EXPECT_LT((f0 + f1).norm(), 1e-9 * f0.norm());
    EXPECT_LT(f0.y(), -0.5);  // bag 0 (at -y) pushed towards -y
    EXPECT_GT(f1.y(), 0.5);
    EXPECT_GT(on.plankForce, 1.0);
}
