// The array layout: where every bag stands and faces, the gas each holds, and the errors a
// layout that cannot be built gets.
#include <bags/Geometry.h>
#include <cosim/ArrayLayout.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace cosim;

namespace {

// 12 rows of 2 of the seed's wedges across the bed, alternating, a left and a right group.
ArrayLayout seedArray() {
    ArrayLayout a;
    a.rows = 12;
    a.columns = 2;
    a.rowPitch = 0.105;
    a.columnPitch = 0.36;
    a.centre = Eigen::Vector2d(0.1, -0.02);
    a.rowOrientation = {BagOrientation::Across, BagOrientation::AcrossFlipped};
    a.gasMass = 2.8e-3;
    a.groups.push_back(BagGroup{"left", {}, {1}, 3.0e-3});
    a.groups.push_back(BagGroup{"foot-right", {0, 1}, {0}, 2.5e-3});
    return a;
}

std::string errorOf(const ArrayLayout& a, const bags::DoubleWedgeParams& g) {
    try {
        a.validate(g);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(ArrayLayout, PlacesEveryBagInItsCellFacingItsRowsWayWithoutOverlap) {
    // Reference: the wedge's mesh (25 mm) placed by each bag's pose. Every node lies in the
    // bag's stated footprint (1e-12 m), no node lies strictly inside another bag's footprint
    // (so the flat footprints do not overlap), the footprints tile the cells at the pitches,
    // and the apex (the steep chamber's side) alternates from row to row.
    bags::DoubleWedgeParams g;
    g.meshSize = 0.025;
    const bags::Mesh mesh = bags::makeDoubleWedgeBag(g);
    const ArrayLayout a = seedArray();
    const std::vector<ArrayBag> bags = makeArrayBags(a, g);
    ASSERT_EQ(int(bags.size()), 24);
    int apexNode = 0;
    mesh.X.row(2).maxCoeff(&apexNode);
    for (const ArrayBag& b : bags) {
        EXPECT_EQ(b.index, b.row * a.columns + b.column);
        const Eigen::Matrix3Xd x = b.X_GB * mesh.X;
        EXPECT_NEAR(x.row(2).minCoeff(), 0.0, 1e-12);  // on the bed board
        for (int n = 0; n < x.cols(); ++n) {
            const Eigen::Vector2d p = x.col(n).head<2>();
            EXPECT_TRUE((p.array() >= b.footprintMin.array() - 1e-12).all() &&
                        (p.array() <= b.footprintMax.array() + 1e-12).all())
                << "bag " << b.index << " node " << n;
            for (const ArrayBag& o : bags)
                if (o.index != b.index) {
                    ASSERT_FALSE((p.array() > o.footprintMin.array() + 1e-9).all() &&
                                 (p.array() < o.footprintMax.array() - 1e-9).all())
                        << "bag " << b.index << " node " << n << " inside bag " << o.index;
                }
        }
        const Eigen::Vector2d cell = 0.5 * (b.footprintMin + b.footprintMax);
        EXPECT_NEAR(cell.x(), a.centre.x() + (b.row - 5.5) * a.rowPitch, 1e-12);
        EXPECT_NEAR(cell.y(), a.centre.y() + (b.column - 0.5) * a.columnPitch, 1e-12);
        EXPECT_NEAR(b.footprintMax.y() - b.footprintMin.y(), g.longSide, 1e-12);  // across
        // The apex ridge lies g.calcApexX() from the footprint's -y end in even rows (across)
        // and from its +y end in odd rows (across-flipped).
        const double apexY = x(1, apexNode);
        if (b.row % 2 == 0)
            EXPECT_NEAR(apexY, b.footprintMin.y() + g.calcApexX(), 1e-12);
        else
            EXPECT_NEAR(apexY, b.footprintMax.y() - g.calcApexX(), 1e-12);
    }
    // findArrayBag: every cell centre finds its bag; a point beyond the array finds none.
    for (const ArrayBag& b : bags)
        EXPECT_EQ(findArrayBag(bags, 0.5 * (b.footprintMin + b.footprintMax)), b.index);
    EXPECT_EQ(findArrayBag(bags, Eigen::Vector2d(2.0, 0.0)), -1);
}

TEST(ArrayLayout, GivesEachBagItsGroupsGasOrTheArraysDefault) {
    bags::DoubleWedgeParams g;
    const std::vector<ArrayBag> bags = makeArrayBags(seedArray(), g);
    for (const ArrayBag& b : bags) {
        if (b.column == 1) {
            EXPECT_EQ(b.group, 0);
            EXPECT_EQ(b.gasMass, 3.0e-3);
        } else if (b.row <= 1) {
            EXPECT_EQ(b.group, 1);
            EXPECT_EQ(b.gasMass, 2.5e-3);
        } else {
            EXPECT_EQ(b.group, -1);
            EXPECT_EQ(b.gasMass, 2.8e-3);
        }
    }
}

TEST(ArrayLayout, LayoutsThatCannotBeBuiltAreRefusedNamingTheKeyAndWhatIsValid) {
    bags::DoubleWedgeParams g;  // 350 x 100 mm footprint
    ArrayLayout a = seedArray();
    a.rowPitch = 0.09;
    EXPECT_NE(errorOf(a, g).find("key 'array.row_pitch': 90 mm is less than the 100 mm"),
              std::string::npos)
        << errorOf(a, g);
    EXPECT_NE(errorOf(a, g).find("valid: 100 mm or more"), std::string::npos);

    a = seedArray();
    a.rowOrientation = {BagOrientation::Across, BagOrientation::Along};  // 100 + 350 mm
    EXPECT_NE(errorOf(a, g).find("valid: 225 mm or more"), std::string::npos) << errorOf(a, g);

    a = seedArray();
    a.columnPitch = 0.30;
    EXPECT_NE(errorOf(a, g).find("key 'array.column_pitch': 300 mm"), std::string::npos)
        << errorOf(a, g);

    a = seedArray();
    a.groups.push_back(BagGroup{"head", {11}, {}, 2.0e-3});  // row 11, column 1 is also left
    EXPECT_NE(errorOf(a, g).find("key 'array.groups[2]': the bag at row 11, column 1 is in group "
                                 "'left' and in group 'head'"),
              std::string::npos)
        << errorOf(a, g);

    a = seedArray();
    a.groups[1].rows = {12};
    EXPECT_NE(errorOf(a, g).find("key 'array.groups[1].rows': row 12 of group 'foot-right'; "
                                 "valid: 0 to 11"),
              std::string::npos)
        << errorOf(a, g);

    a = seedArray();
    a.groups[1].name = "left";
    EXPECT_NE(errorOf(a, g).find("'left' names two groups"), std::string::npos) << errorOf(a, g);

    a = seedArray();
    a.gasMass = 0.0;  // the bags in no group have none
    EXPECT_NE(errorOf(a, g).find("key 'array.gas_mass': 0 g, and the bag at row 2, column 0 is in "
                                 "no group"),
              std::string::npos)
        << errorOf(a, g);
    a.groups.push_back(BagGroup{"rest", {}, {0}, 2.8e-3});  // now every bag has a group...
    a.groups[1].rows.clear();                               // ...once foot-right is dropped
    a.groups.erase(a.groups.begin() + 1);
    EXPECT_EQ(errorOf(a, g), "");

    EXPECT_THROW(parseBagOrientation("sideways"), std::invalid_argument);
    EXPECT_EQ(parseBagOrientation("across-flipped"), BagOrientation::AcrossFlipped);
}
