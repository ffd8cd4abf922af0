#pragma once
/// @file The shapes of a patient-on-array run as triangle meshes for viewing (results.xdmf in
/// ParaView): the coupled bags' membranes, and the patient's contact shapes (one closed mesh
/// per segment's ellipsoid or round cone).
///
/// Order of use: makeBagSurfaces() and makeBodySurface() once after the PatientOnArray is
/// built (their topology never changes), then calcBagSurfacePositions() and
/// calcBodySurfacePositions() at any output time; they read the committed state.

#include <body/BodyModel.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "cosim/PatientOnArray.h"

namespace cosim {

/// A triangle mesh whose triangles belong to groups (a bag, a segment).
struct SurfaceMesh {
    Eigen::Matrix3Xi triangles;           ///< node indices of each triangle (outward normal)
    std::vector<int> triangleGroup;       ///< per triangle: its group's id
    std::vector<std::string> groupNames;  ///< per id, for the reader
};

/// Every coupled bag's membrane, nodes stacked in PatientOnArray::getBagIndices() order; the
/// group of a triangle is its bag's array index (ArrayBag::index). Reduced bags have no
/// membrane and add nothing.
SurfaceMesh makeBagSurfaces(const PatientOnArray& poa);
/// The coupled bags' node positions [m], Ground, in makeBagSurfaces()' order.
Eigen::Matrix3Xd calcBagSurfacePositions(const PatientOnArray& poa);

/// The patient's contact shapes, meshed in their segments' frames.
struct BodySurface {
    SurfaceMesh mesh;              ///< group: the segment (body::Segment as int)
    Eigen::Matrix3Xd p_B;          ///< nodes in their segment's frame [m]
    std::vector<int> nodeSegment;  ///< per node: its segment (body::Segment as int)
};

/// Meshes each segment's contact shape over a latitude-longitude grid of directions about its
/// axis (the round cone's, the ellipsoid's third): a round cone's support point in each
/// direction, an ellipsoid's semi-axes times the direction in its frame; `rings`
/// latitudes (even, so no ring lies on the equator where a round cone's support point jumps
/// from one sphere to the other: the strip between the two middle rings is the cone) and
/// `sectors` longitudes, plus the two poles. Every node lies on the shape's surface; the mesh
/// is closed and its triangles face outwards.
BodySurface makeBodySurface(const body::BodyModel& model, int rings = 10, int sectors = 20);
/// The body surface's node positions [m], Ground, at the state given.
Eigen::Matrix3Xd calcBodySurfacePositions(const body::BodyModel& model, const SimTK::State& state,
                                          const BodySurface& surface);

}  // namespace cosim
