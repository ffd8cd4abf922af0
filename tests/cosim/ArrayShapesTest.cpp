// The patient's contact shapes as closed triangle meshes for viewing (cosim/ArrayShapes.h):
// every node on its shape's surface, every mesh closed with its triangles facing out, its
// volume that of the shape less the inscribed polyhedron's shortfall, and placed in Ground by
// the segments' poses.
#include <cosim/ArrayShapes.h>
#include <gtest/gtest.h>

#include <map>

using namespace cosim;

TEST(ArrayShapes, TheBodySurfaceIsClosedOutwardAndOnEveryShape) {
    body::PatientSpec p;
    p.height = 1.75;
    p.mass = 75.0;
    body::BodyModel model(p);
    const BodySurface s = makeBodySurface(model, 10, 20);
    ASSERT_EQ(s.p_B.cols(), Eigen::Index(body::kSegmentCount * (10 * 20 + 2)));
    for (Eigen::Index i = 0; i < s.p_B.cols(); ++i) {
        const body::ContactShape& shape =
            model.getContactShape(body::Segment(s.nodeSegment[size_t(i)]));
        const SimTK::Vec3 x(s.p_B(0, i), s.p_B(1, i), s.p_B(2, i));
        ASSERT_NEAR(shape.calcSignedDistance(x), 0.0, 1e-9) << "node " << i;
    }
    // Closed and consistently oriented: every directed edge once, and its reverse once.
    std::map<std::pair<int, int>, int> edges;
    std::vector<double> volume(body::kSegmentCount, 0.0);
    for (Eigen::Index t = 0; t < s.mesh.triangles.cols(); ++t) {
        const Eigen::Vector3i n = s.mesh.triangles.col(t);
        for (int k = 0; k < 3; ++k) ++edges[{n[k], n[(k + 1) % 3]}];
        const int seg = s.mesh.triangleGroup[size_t(t)];
        for (int k = 0; k < 3; ++k) ASSERT_EQ(s.nodeSegment[size_t(n[k])], seg);
        volume[size_t(seg)] += s.p_B.col(n[0]).dot(s.p_B.col(n[1]).cross(s.p_B.col(n[2]))) / 6.0;
    }
    for (const auto& [e, count] : edges) {
        ASSERT_EQ(count, 1) << e.first << "-" << e.second;
        ASSERT_EQ(edges.count({e.second, e.first}), 1u) << e.first << "-" << e.second;
    }
    // Outward (positive volume), and an inscribed polyhedron: a little below the shape's volume.
    for (int seg = 0; seg < body::kSegmentCount; ++seg) {
        const double v = model.getContactShape(body::Segment(seg)).calcVolume();
        EXPECT_GT(volume[size_t(seg)], 0.9 * v) << body::getSegmentName(body::Segment(seg));
        EXPECT_LT(volume[size_t(seg)], 1.0 * v) << body::getSegmentName(body::Segment(seg));
    }
    // In Ground: supine with his lowest point on the bed (z = 0), so the lowest node is just
    // above it (nodes lie on the shapes, which the bed touches).
    model.updSystem().realizeTopology();
    SimTK::State state = model.getSystem().getDefaultState();
    model.setPosture(state);
    model.getSystem().realize(state, SimTK::Stage::Position);
    const Eigen::Matrix3Xd x = calcBodySurfacePositions(model, state, s);
    EXPECT_GT(x.row(2).minCoeff(), -1e-9);
    EXPECT_LT(x.row(2).minCoeff(), 0.005);
    EXPECT_GT(x.row(0).maxCoeff() - x.row(0).minCoeff(), 1.6);  // head to heels of 1.75 m
}
