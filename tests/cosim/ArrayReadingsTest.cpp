// What is read off the patient on the array: the tilt's sign and size on the body model's own
// tilted postures, and the mat placed over the array's footprints.
#include <cosim/ArrayReadings.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace cosim;

namespace {

// Pelvis and thorax tilt [deg] in a posture (body::BodyModel::setPosture, realized).
std::pair<double, double> tiltOf(body::Posture posture) {
    body::PatientSpec p;
    p.height = 1.75;
    p.mass = 75.0;
    p.posture = posture;
    body::BodyModel m(p);
    m.updSystem().realizeTopology();
    SimTK::State s = m.getSystem().getDefaultState();
    m.setPosture(s, 0.0);
    m.getSystem().realize(s, SimTK::Stage::Position);
    const double deg = 180.0 / M_PI;
    return {deg * calcSegmentTilt(m, s, body::Segment::LowerTrunk),
            deg * calcSegmentTilt(m, s, body::Segment::UpperTrunk)};
}

// Two columns of wedges across the bed, alternating per row.
ArrayLayout twoColumns(int rows) {
    ArrayLayout a;
    a.rows = rows;
    a.columns = 2;
    a.rowPitch = 0.105;
    a.columnPitch = 0.36;
    a.rowOrientation = {BagOrientation::Across, BagOrientation::AcrossFlipped};
    a.gasMass = 4.5e-3;
    return a;
}

}  // namespace

TEST(ArrayReadings, TiltIsPositiveOntoTheLeftSideAndReadsThePosturesAngle) {
    // Reference: body/Posture.h's tilt-left-30 turns him 30 deg onto his left side (left side
    // down), tilt-right-30 onto his right; supine is 0.
    const auto supine = tiltOf(body::Posture::Supine);
    EXPECT_NEAR(supine.first, 0.0, 1e-9);
    EXPECT_NEAR(supine.second, 0.0, 1e-9);
    const auto left = tiltOf(body::Posture::TiltLeft30);
    EXPECT_NEAR(left.first, 30.0, 1e-6);
    EXPECT_NEAR(left.second, 30.0, 1e-6);
    const auto right = tiltOf(body::Posture::TiltRight30);
    EXPECT_NEAR(right.first, -30.0, 1e-6);
    EXPECT_NEAR(right.second, -30.0, 1e-6);
}

TEST(ArrayReadings, TheArraysMatCoversEveryFootprintExactly) {
    ArrayLayout a = twoColumns(20);
    a.centre = Eigen::Vector2d(-0.03, 0.0);
    const PressureMatOptions o = makeArrayMatOptions(a, bags::DoubleWedgeParams(), 64, 32);
    // 20 rows of 100 mm wide bags at 105 mm: 2.095 m; 2 columns of 350 mm at 360 mm: 0.71 m.
    EXPECT_NEAR(o.origin.x(), -0.03 - 1.0475, 1e-12);
    EXPECT_NEAR(o.size.x(), 2.095, 1e-12);
    EXPECT_NEAR(o.origin.y(), -0.355, 1e-12);
    EXPECT_NEAR(o.size.y(), 0.71, 1e-12);
    EXPECT_EQ(o.rows, 64);
    EXPECT_EQ(o.columns, 32);
    EXPECT_NO_THROW(o.validate());
}

TEST(ArrayReadings, MirroredColumnsFaceAwayFromEachOtherSymmetricAboutTheBedsAxis) {
    // Reference: the mirror image about y = 0 of column 0's bag frame origin (its steep end)
    // and x axis. Row 0 (across): column 0's steep end at the outer edge y = -355 mm, column
    // 1's at +355 mm; row 1 (across-flipped): both at the inner edges, -5 and +5 mm.
    ArrayLayout a = twoColumns(2);
    a.mirrorColumns = true;
    const std::vector<ArrayBag> b = makeArrayBags(a, bags::DoubleWedgeParams());
    EXPECT_EQ(b[1].orientation, BagOrientation::AcrossFlipped);
    EXPECT_EQ(b[3].orientation, BagOrientation::Across);
    const double edge[2] = {-0.355, -0.005};
    for (int r = 0; r < 2; ++r) {
        const Eigen::Isometry3d& left = b[2 * r].X_GB;
        const Eigen::Isometry3d& right = b[2 * r + 1].X_GB;
        EXPECT_NEAR(left.translation().y(), edge[r], 1e-12);
        EXPECT_NEAR(right.translation().y(), -left.translation().y(), 1e-12);
        EXPECT_NEAR(right.translation().x(), left.translation().x(), 1e-12);
        EXPECT_NEAR(right.linear().col(0).y(), -left.linear().col(0).y(), 1e-12);
    }
}

// The patch peak against closed forms. A paraboloid pressure p0 (1 - r^2/R^2) sampled on a
// fine grid (point forces p a): the best disc of radius b sits at its centre and holds the
// mean p0 (1 - b^2 / (2 R^2)). Tolerance 1 %: the count of 1 mm grid points in a disc of
// 18-36 mm radius against its area.
TEST(ArrayReadings, ThePatchPeakIsTheMeanPressureOverTheBestDisc) {
    const double p0 = 8000.0, R = 0.06, pitch = 0.001, a = pitch * pitch;
    std::vector<Eigen::Vector2d> pts;
    std::vector<double> f;
    for (double x = -R; x <= R + 1e-12; x += pitch)
        for (double y = -R; y <= R + 1e-12; y += pitch) {
            const double r2 = x * x + y * y;
            if (r2 >= R * R) continue;
            pts.emplace_back(x + 0.3, y - 0.1);  // anywhere in the plane
            f.push_back(p0 * (1.0 - r2 / (R * R)) * a);
        }
    for (double area : {10e-4, 20e-4, 40e-4}) {
        const double b2 = area / M_PI;
        EXPECT_NEAR(calcPatchPeakPressure(pts, f, area), p0 * (1.0 - b2 / (2 * R * R)), 0.01 * p0)
            << area * 1e4 << " cm2";
    }
    // Uniform pressure on a region larger than the disc: the pressure itself.
    std::vector<double> uniform(pts.size(), p0 * a);
    EXPECT_NEAR(calcPatchPeakPressure(pts, uniform, 20e-4), p0, 0.01 * p0);
}

// A point load alone, loads farther apart than a disc's diameter, loads within its radius.
TEST(ArrayReadings, ThePatchPeakAddsTheLoadsOneDiscHolds) {
    const double area = 20e-4, r = std::sqrt(area / M_PI);  // 25.2 mm
    EXPECT_EQ(calcPatchPeakPressure({}, {}, area), 0.0);
    EXPECT_DOUBLE_EQ(calcPatchPeakPressure({{0.1, 0.2}}, {3.0}, area), 3.0 / area);
    EXPECT_DOUBLE_EQ(calcPatchPeakPressure({{0, 0}, {2.2 * r, 0}}, {3.0, 5.0}, area), 5.0 / area);
    EXPECT_DOUBLE_EQ(
        calcPatchPeakPressure({{0, 0}, {0.7 * r, 0.7 * r}, {5 * r, 0}}, {3.0, 5.0, 6.0}, area),
        8.0 / area);
    // Sorted by x inside: the order given does not matter.
    EXPECT_DOUBLE_EQ(
        calcPatchPeakPressure({{5 * r, 0}, {0.7 * r, 0.7 * r}, {0, 0}}, {6.0, 5.0, 3.0}, area),
        8.0 / area);
    EXPECT_THROW(calcPatchPeakPressure({{0, 0}}, {1.0}, 0.0), std::invalid_argument);
}

// A sphere poking up through one triangle of a flat film between its nodes: the film's
// nodes all lie outside it (the node contact sees nothing), and the pass-through is the
// sphere's depth at the triangle's centroid, exactly: r - |centroid - centre| (reference:
// the sphere's signed distance, 1e-12 m). A sphere clear of the film reads 0.
TEST(ArrayReadings, AShapeBetweenAFilmsNodesIsMeasuredAtTheTrianglesCentroid) {
    bags::Mesh film;
    film.X.resize(3, 4);
    film.X << 0.0, 0.04, 0.04, 0.0,  //
        0.0, 0.0, 0.04, 0.04,        //
        0.0, 0.0, 0.0, 0.0;
    film.tris.resize(3, 2);
    film.tris << 0, 0, 1, 2, 2, 3;
    film.triPanel = {0, 0};
    film.panelNames = {"top"};
    const Eigen::Vector3d centroid = (film.X.col(0) + film.X.col(1) + film.X.col(2)) / 3.0;
    const double r = 0.012, depth = 0.004;
    auto sphere = bags::makeEllipsoid(Eigen::Vector3d::Constant(r));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = centroid - Eigen::Vector3d(0.0, 0.0, r - depth);  // its top 4 mm above
    sphere->setPose(X);
    for (int n = 0; n < 4; ++n)
        EXPECT_GT(sphere->calcSignedDistance(film.X.col(n), nullptr, nullptr), 0.0) << n;
    EXPECT_NEAR(calcFilmPassThrough(film, film.X, *sphere), depth, 1e-12);
    X.translation().z() -= 0.01;
    sphere->setPose(X);
    EXPECT_EQ(calcFilmPassThrough(film, film.X, *sphere), 0.0);
    EXPECT_THROW(calcFilmPassThrough(film, film.X.leftCols(3), *sphere), std::invalid_argument);
}
