#pragma once
/// @file Named body regions for reports: the places a pressure-mapping clinician reads
/// (occiput, scapulae, elbows, sacrum, ischia/buttocks, trochanters, heels; and when turned,
/// ears, shoulders, knees, malleoli).
///
/// A region is a sphere in the whole-body reference frame (standing, origin at the mid-hip
/// point, X anterior, Y superior, Z right) that collects the surface points of some segments
/// lying inside it. Regions are tested in order, the first match wins; a point in none has
/// region -1 and is reported under its segment.

#include <SimTKcommon.h>

#include <string>
#include <vector>

#include "body/Anthropometry.h"

namespace body {

/// One named region.
struct BodyRegion {
    std::string name;               ///< e.g. "heel_r"
    SimTK::Vec3 centre_W{0};        ///< sphere centre, whole-body reference frame [m]
    double radius = 0;              ///< sphere radius [m]
    std::vector<Segment> segments;  ///< segments whose surface the region may collect
};

/// The regions of a patient, placed from its anthropometry (see docs/body.md).
std::vector<BodyRegion> makeBodyRegions(const Anthropometry& anthropometry);

/// Index of the region containing the point p_B of a segment (body frame), or -1.
int findBodyRegion(const std::vector<BodyRegion>& regions, const Anthropometry& anthropometry,
                   Segment segment, const SimTK::Vec3& p_B);

}  // namespace body
