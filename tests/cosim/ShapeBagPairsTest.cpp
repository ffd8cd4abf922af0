// Which bags each of the patient's contact shapes may touch, for a patient lying on an array
// and for one lying beside it.
#include <body/BodyModel.h>
#include <cosim/BodyParticipant.h>
#include <cosim/PatientOnArray.h>
#include <cosim/ShapeBagPairs.h>
#include <gtest/gtest.h>

#include <cstdio>

using namespace cosim;

namespace {

// The 16 segments' bounding spheres (Ground) of a 1.75 m, 75 kg man lying supine with his
// mid-hip point at (x, y), lowest point on z = 0.
void findSpheres(double x, double y, std::vector<Eigen::Vector3d>& centres,
                 std::vector<double>& radii) {
    body::PatientSpec spec;
    spec.position = {{x, y}};
    body::BodyModel model(spec);
    model.updSystem().realizeTopology();
    SimTK::State state = model.getSystem().getDefaultState();
    model.setPosture(state);
    model.getSystem().realize(state, SimTK::Stage::Position);
    calcSegmentBounds(model, state, centres, radii);
}

// 20 rows of 2 of the seed's wedges across the bed, 105 mm rows, 360 mm columns.
std::vector<ArrayBag> seedArray() {
    ArrayLayout a;
    a.rows = 20;
    a.columns = 2;
    a.rowPitch = 0.105;
    a.columnPitch = 0.36;
    a.rowOrientation = {BagOrientation::Across, BagOrientation::AcrossFlipped};
    a.gasMass = 2.8e-3;
    return makeArrayBags(a, bags::DoubleWedgeParams{});
}

}  // namespace

TEST(ShapeBagPairs, APatientOnTheArrayHasBagsUnderEverySegmentAndOnlyNearOnes) {
    // Reference: brute force on a 1 mm grid over each grown footprint: a (segment, bag) pair is
    // listed exactly when some grid point lies within the segment's bounding radius of its
    // centre (tolerance 1.5 mm, the grid's reach). A supine man centred on a 2.1 x 0.71 m array
    // has bags under every segment.
    std::vector<Eigen::Vector3d> c;
    std::vector<double> r;
    findSpheres(0.0, 0.0, c, r);
    const std::vector<ArrayBag> bags = seedArray();
    const double margin = 0.02;
    const std::vector<ShapeBagPair> pairs = findShapeBagPairs(c, r, bags, margin);
    EXPECT_TRUE(findUnsupportedShapes(body::kSegmentCount, pairs).empty());
    std::vector<std::vector<char>> listed(body::kSegmentCount, std::vector<char>(bags.size(), 0));
    for (const ShapeBagPair& p : pairs) listed[p.shape][p.bag] = 1;
    for (int s = 0; s < body::kSegmentCount; ++s) {
        int count = 0;
        for (const ArrayBag& b : bags) {
            const Eigen::Vector2d lo = b.footprintMin.array() - margin;
            const Eigen::Vector2d hi = b.footprintMax.array() + margin;
            double nearest = 1e9;
            for (double x = lo.x(); x <= hi.x() + 1e-12; x += 1e-3)
                for (double y = lo.y(); y <= hi.y() + 1e-12; y += 1e-3)
                    nearest = std::min(nearest, (Eigen::Vector2d(x, y) - c[s].head<2>()).norm());
            if (listed[s][b.index]) {
                EXPECT_LE(nearest, r[s] + 1.5e-3) << "segment " << s << " bag " << b.index;
                ++count;
            } else {
                EXPECT_GT(nearest, r[s] - 1.5e-3) << "segment " << s << " bag " << b.index;
            }
        }
        std::printf("segment %2d: bounding radius %.0f mm, %2d bags\n", s, 1e3 * r[s], count);
    }
}

TEST(ShapeBagPairs, APatientBesideTheArrayHasNoBagUnderAnySegment) {
    std::vector<Eigen::Vector3d> c;
    std::vector<double> r;
    findSpheres(0.0, 1.2, c, r);  // mid-hip 1.2 m to the side of the array's centre line
    const std::vector<ShapeBagPair> pairs = findShapeBagPairs(c, r, seedArray(), 0.02);
    EXPECT_TRUE(pairs.empty());
    EXPECT_EQ(int(findUnsupportedShapes(body::kSegmentCount, pairs).size()), body::kSegmentCount);
    EXPECT_THROW(findShapeBagPairs(c, {0.1}, seedArray(), 0.02), std::invalid_argument);
}
