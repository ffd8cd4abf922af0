// Body regions placed on the contact shapes (see Regions.h).
#include "body/Regions.h"

#include <cmath>

namespace body {

std::vector<BodyRegion> makeBodyRegions(const Anthropometry& a) {
    const double s = a.height / 1.75;  // region sizes scale with stature
    std::vector<BodyRegion> r;
    auto origin = [&](Segment seg) { return a.get(seg).p_WO; };
    auto shape = [&](Segment seg) -> const ShapeSize& { return a.get(seg).shape; };

    // Occiput: back of the head ellipsoid, a little above its centre.
    {
        const ShapeSize& h = shape(Segment::Head);
        const SimTK::Vec3 c =
            origin(Segment::Head) + h.centre + SimTK::Vec3(-h.semiAxes[0], 0.25 * h.semiAxes[1], 0);
        r.push_back({"occiput", c, 0.06 * s, {Segment::Head}});
        for (int side : {1, -1}) {  // ears, for side-lying
            const SimTK::Vec3 e =
                origin(Segment::Head) + h.centre + SimTK::Vec3(0, 0, side * h.semiAxes[2]);
            r.push_back({side > 0 ? "ear_r" : "ear_l", e, 0.05 * s, {Segment::Head}});
        }
    }
    // Heels first (they touch the ankle region), then malleoli.
    for (int side : {1, -1}) {
        const Segment foot = side > 0 ? Segment::FootR : Segment::FootL;
        const ShapeSize& f = shape(foot);
        const SimTK::Vec3 c =
            origin(foot) + f.pointA + SimTK::Vec3(-f.radiusA, -0.3 * f.radiusA, 0);
        const Segment shank = side > 0 ? Segment::ShankR : Segment::ShankL;
        r.push_back({side > 0 ? "heel_r" : "heel_l", c, 0.05 * s, {foot}});
        r.push_back(
            {side > 0 ? "malleolus_r" : "malleolus_l", origin(foot), 0.045 * s, {foot, shank}});
    }
    // Elbows: olecranon, the back of the elbow joint.
    for (int side : {1, -1}) {
        const Segment fa = side > 0 ? Segment::ForearmR : Segment::ForearmL;
        const Segment ua = side > 0 ? Segment::UpperArmR : Segment::UpperArmL;
        const SimTK::Vec3 c = origin(fa) + SimTK::Vec3(-shape(ua).radiusB, 0, 0);
        r.push_back({side > 0 ? "elbow_r" : "elbow_l", c, 0.055 * s, {ua, fa}});
    }
    // Shoulders (lateral, over the acromion and deltoid): for side-lying.
    for (int side : {1, -1}) {
        const Segment ua = side > 0 ? Segment::UpperArmR : Segment::UpperArmL;
        const SimTK::Vec3 c = origin(ua) + SimTK::Vec3(0, 0, side * shape(ua).radiusA);
        r.push_back(
            {side > 0 ? "shoulder_r" : "shoulder_l", c, 0.07 * s, {ua, Segment::UpperTrunk}});
    }
    // Scapulae: the back of the thorax either side of the spine.
    {
        const ShapeSize& t = shape(Segment::UpperTrunk);
        for (int side : {1, -1}) {
            const double z = 0.45 * t.semiAxes[2];
            const double x = -t.semiAxes[0] * std::sqrt(1 - 0.45 * 0.45);
            const SimTK::Vec3 c = origin(Segment::UpperTrunk) + t.centre +
                                  SimTK::Vec3(x, 0.1 * t.semiAxes[1], side * z);
            r.push_back({side > 0 ? "scapula_r" : "scapula_l", c, 0.09 * s, {Segment::UpperTrunk}});
        }
    }
    // Thoracic spine between the scapulae (spinous processes).
    {
        const ShapeSize& t = shape(Segment::UpperTrunk);
        const SimTK::Vec3 c =
            origin(Segment::UpperTrunk) + t.centre + SimTK::Vec3(-t.semiAxes[0], 0, 0);
        r.push_back({"thoracic_spine", c, 0.07 * s, {Segment::UpperTrunk, Segment::MiddleTrunk}});
    }
    // Sacrum: back of the pelvis at the level of the hip joints.
    {
        const ShapeSize& p = shape(Segment::LowerTrunk);
        const SimTK::Vec3 c =
            origin(Segment::LowerTrunk) + SimTK::Vec3(p.centre[0] - p.semiAxes[0], 0.02 * s, 0);
        r.push_back({"sacrum", c, 0.07 * s, {Segment::LowerTrunk}});
    }
    // Trochanters (lateral hip), then ischial tuberosities/buttocks (back of the thigh root).
    for (int side : {1, -1}) {
        const Segment th = side > 0 ? Segment::ThighR : Segment::ThighL;
        const SimTK::Vec3 c = origin(th) + SimTK::Vec3(0, -0.03 * s, side * shape(th).radiusA);
        r.push_back(
            {side > 0 ? "trochanter_r" : "trochanter_l", c, 0.07 * s, {th, Segment::LowerTrunk}});
    }
    for (int side : {1, -1}) {
        const Segment th = side > 0 ? Segment::ThighR : Segment::ThighL;
        const SimTK::Vec3 c = origin(th) + SimTK::Vec3(-shape(th).radiusA, -0.04 * s, 0);
        r.push_back({side > 0 ? "ischium_r" : "ischium_l", c, 0.10 * s, {th}});
    }
    // Calves: back of the shank's upper half.
    for (int side : {1, -1}) {
        const Segment sh = side > 0 ? Segment::ShankR : Segment::ShankL;
        const SimTK::Vec3 c =
            origin(sh) + SimTK::Vec3(-shape(sh).radiusA, -0.35 * a.get(sh).length, 0);
        r.push_back({side > 0 ? "calf_r" : "calf_l", c, 0.1 * s, {sh}});
    }
    // Knees (condyles and patella) for side-lying and prone.
    for (int side : {1, -1}) {
        const Segment sh = side > 0 ? Segment::ShankR : Segment::ShankL;
        const Segment th = side > 0 ? Segment::ThighR : Segment::ThighL;
        r.push_back({side > 0 ? "knee_r" : "knee_l", origin(sh), 0.07 * s, {th, sh}});
    }
    return r;
}

int findBodyRegion(const std::vector<BodyRegion>& regions, const Anthropometry& a, Segment segment,
                   const SimTK::Vec3& p_B) {
    const SimTK::Vec3 p_W = a.get(segment).p_WO + p_B;
    for (int i = 0; i < static_cast<int>(regions.size()); ++i) {
        const BodyRegion& reg = regions[i];
        bool allowed = false;
        for (Segment s : reg.segments) allowed = allowed || s == segment;
        if (allowed && (p_W - reg.centre_W).normSqr() <= reg.radius * reg.radius) return i;
    }
    return -1;
}

}  // namespace body
