#pragma once
/// @file The patient's contact shapes (body::ContactShape: ellipsoids and round cones) as
/// rigid shapes a bag's membrane can touch (bags::RigidShape), and the frame on the segment
/// that the coupling tracks for each.
///
/// Use: for a segment's shape s, `BagShapeOfBody b = makeBagShape(s)`; add b.shape to every
/// bag it may touch (bags::Airbag::addShape) and b.X_BS on the segment's mobilized body to the
/// body side (BodyParticipant::addShape), then link the two. The coupling sets the bag
/// shape's pose to X_GB X_BS every step.

#include <Simbody.h>
#include <bags/Contact.h>
#include <body/ContactShape.h>

#include <memory>

namespace cosim {

/// Round cone: spheres (centre pA, radius rA) and (pB, rB) joined by their common tangent
/// cone (a capsule when rA == rB), in its own frame; signed distance, closest point, normal
/// and the normal's derivative in closed form. @throws std::invalid_argument unless radii are
/// positive and |pB - pA| > |rA - rB|.
std::unique_ptr<bags::RigidShape> makeRoundCone(const Eigen::Vector3d& pA, double rA,
                                                const Eigen::Vector3d& pB, double rB);

/// A body shape as a bag shape, and where its frame sits on the segment.
struct BagShapeOfBody {
    std::shared_ptr<bags::RigidShape> shape;  ///< ellipsoid (bags::makeEllipsoid) or round cone
    SimTK::Transform X_BS;                    ///< the shape frame on the segment's body
};
/// An ellipsoid becomes bags' own ellipsoid in its frame (X_BS its pose on the segment); a
/// round cone becomes makeRoundCone() in the body frame (X_BS identity).
BagShapeOfBody makeBagShape(const body::ContactShape& shape);

}  // namespace cosim
