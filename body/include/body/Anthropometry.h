#pragma once
/// @file Anthropometry of the lying patient: de Leva (1996) segment inertia parameters scaled to
/// a given sex, height and mass, and the body build (joint positions, segment breadths and
/// depths) that the contact shapes are made from.
///
/// Reference: P. de Leva, "Adjustments to Zatsiorsky-Seluyanov's segment inertia parameters",
/// J. Biomech. 29(9):1223-1230, 1996, Table 4 (mass fractions, centre-of-mass positions from the
/// proximal landmark, sagittal/transverse/longitudinal radii of gyration, segment lengths of the
/// 1.741 m / 73.0 kg male and 1.735 m / 61.9 kg female reference subjects).
///
/// Frames. Every segment has a body frame whose origin is the joint that connects it to its
/// parent (the mid-hip point for the root, the lower trunk) and whose axes, in the neutral
/// standing reference posture, are the whole-body anatomical axes: X anterior, Y superior,
/// Z to the patient's right (ISB convention). In that posture all body frames are parallel, so
/// a point's whole-body position is the body-frame origin plus its body-frame coordinates.

#include <SimTKcommon.h>

#include <array>
#include <string>

namespace body {

/// Sex of the patient: selects the de Leva male or female table.
enum class Sex { Female, Male };

/// The 16 rigid segments, in the order of the model's bodies.
enum class Segment {
    LowerTrunk,   ///< pelvis: omphalion to the hip joint centres (de Leva LPT); the root body
    MiddleTrunk,  ///< abdomen: xiphion to omphalion (de Leva MPT)
    UpperTrunk,   ///< thorax: suprasternale to xiphion (de Leva UPT)
    Head,         ///< head and neck: vertex to mid-gonion (de Leva)
    UpperArmR,    ///< right upper arm: shoulder to elbow joint centre
    ForearmR,     ///< right forearm: elbow to wrist joint centre
    HandR,        ///< right hand: wrist joint centre to 3rd metacarpale
    UpperArmL,    ///< left upper arm
    ForearmL,     ///< left forearm
    HandL,        ///< left hand
    ThighR,       ///< right thigh: hip to knee joint centre
    ShankR,       ///< right shank: knee joint centre to lateral malleolus
    FootR,        ///< right foot: heel to tip of the longest toe
    ThighL,       ///< left thigh
    ShankL,       ///< left shank
    FootL,        ///< left foot
};
constexpr int kSegmentCount = 16;  ///< number of segments

/// The kinds of segment that de Leva's Table 4 has a row for.
enum class SegmentType {
    Head,
    UpperTrunk,
    MiddleTrunk,
    LowerTrunk,
    UpperArm,
    Forearm,
    Hand,
    Thigh,
    Shank,
    Foot
};

/// Which side of the body a segment is on.
enum class Side { Centre, Right, Left };

/// One row of de Leva (1996) Table 4 for one sex.
struct DeLevaRow {
    double length = 0;        ///< segment length of the reference subject [m]
    double massFraction = 0;  ///< segment mass / body mass [-]
    double comFraction = 0;   ///< CoM distance from the proximal landmark / length [-]
    double rSagittal =
        0;  ///< radius of gyration about the sagittal (antero-posterior) axis / length
    double rTransverse =
        0;  ///< radius of gyration about the transverse (medio-lateral) axis / length
    double rLongitudinal = 0;   ///< radius of gyration about the longitudinal axis / length
    const char* proximal = "";  ///< proximal landmark (de Leva's abbreviation)
    const char* distal = "";    ///< distal landmark
};

/// Reference subject of a de Leva table.
struct DeLevaReference {
    double stature = 0;  ///< [m]
    double mass = 0;     ///< [kg]
};

/// Extra longitudinal distances of de Leva (1996) Table 4 (its alternative segment definitions)
/// that locate the cervicale, the shoulder joint centres and the fingertip.
struct DeLevaExtraLengths {
    double vertexToCervicale = 0;         ///< head length VERT-CERV [m]
    double cervicaleToMidHip = 0;         ///< trunk length CERV-MIDH [m]
    double midShoulderToMidHip = 0;       ///< trunk length MIDS-MIDH [m]
    double wristToFingertip = 0;          ///< hand length WJC-DA3 [m]
    double handFingertipComFraction = 0;  ///< hand CoM from WJC / WJC-DA3 length [-]
    std::array<double, 3>
        handFingertipGyration{};  ///< hand radii of gyration / WJC-DA3 (sag, trans, long)
};

/// The de Leva (1996) Table 4 row for a segment type and sex.
const DeLevaRow& getDeLevaRow(Sex sex, SegmentType type);
/// The reference subject (stature, mass) of the de Leva table for a sex.
DeLevaReference getDeLevaReference(Sex sex);
/// The extra lengths of de Leva's alternative segment definitions for a sex.
const DeLevaExtraLengths& getDeLevaExtraLengths(Sex sex);

/// The type of a segment (which de Leva row it uses).
SegmentType getSegmentType(Segment segment);
/// The side of a segment.
Side getSegmentSide(Segment segment);
/// The same segment on the other side (a midline segment is its own mirror).
Segment getMirrorSegment(Segment segment);
/// Short name of a segment, e.g. "thigh_r", as used in tables and reports.
const char* getSegmentName(Segment segment);
/// Short name of a sex, "female" or "male".
const char* getSexName(Sex sex);

/// Density of a segment's tissue used to size its contact shape [kg/m^3]:
/// Dempster (1955) via Winter (2009) Table 4.1.
double getSegmentDensity(SegmentType type);

/// Kind of a contact shape.
enum class ShapeKind { Ellipsoid, RoundCone };

/// Size and placement of a segment's contact shape, in the segment's body frame.
struct ShapeSize {
    ShapeKind kind = ShapeKind::Ellipsoid;
    SimTK::Vec3 centre{0};    ///< ellipsoid centre [m]
    SimTK::Vec3 semiAxes{0};  ///< ellipsoid semi-axes along body X, Y, Z [m]
    SimTK::Vec3 pointA{0};    ///< round cone: centre of the first sphere [m]
    SimTK::Vec3 pointB{0};    ///< round cone: centre of the second sphere [m]
    double radiusA = 0;       ///< round cone: radius at pointA [m]
    double radiusB = 0;       ///< round cone: radius at pointB [m]
};

/// Inertial parameters and shape of one segment, scaled to the patient.
struct SegmentParameters {
    Segment segment = Segment::LowerTrunk;  ///< which segment
    double mass = 0;                        ///< [kg]
    double length = 0;                      ///< de Leva segment length, scaled [m]
    SimTK::Vec3 p_BC{0};                    ///< centre of mass in the body frame [m]
    SimTK::Vec3 inertiaC{0};  ///< principal moments about the CoM along body X, Y, Z [kg m^2]
    SimTK::Vec3 p_WO{
        0};           ///< body-frame origin (joint centre) in the whole-body reference frame [m]
    ShapeSize shape;  ///< contact shape in the body frame
};

/// Frame-independent measures of the body build.
struct BodyBuild {
    double shoulderJointSeparation = 0;  ///< distance between the shoulder joint centres [m]
    double hipJointSeparation = 0;       ///< distance between the hip joint centres [m]
    double ankleHeight = 0;              ///< ankle joint centre above the sole [m]
    double shoulderBreadth = 0;          ///< outer breadth over the upper arms [m]
    double chestBreadth = 0;             ///< upper-trunk shape breadth [m]
    double chestDepth = 0;               ///< upper-trunk shape depth [m]
    double waistBreadth = 0;             ///< middle-trunk shape breadth [m]
    double waistDepth = 0;               ///< middle-trunk shape depth [m]
    double hipBreadth = 0;               ///< outer breadth over the thighs at the hip joints [m]
    double pelvisDepth = 0;              ///< lower-trunk shape depth [m]
    double buttockDepth = 0;             ///< thigh shape diameter at the hip joint [m]
    double headBreadth = 0;              ///< head shape breadth [m]
    double headLength = 0;               ///< head shape antero-posterior length [m]
    double modelStature = 0;             ///< vertex to sole in the standing reference posture [m]
};

/// The scaled anthropometry of one patient.
struct Anthropometry {
    Sex sex = Sex::Male;                                    ///< table used
    double height = 0;                                      ///< stature [m]
    double mass = 0;                                        ///< body mass [kg]
    double bmi = 0;                                         ///< body-mass index [kg/m^2]
    double lengthScale = 0;                                 ///< height / reference stature [-]
    std::array<SegmentParameters, kSegmentCount> segments;  ///< indexed by Segment
    BodyBuild build;  ///< breadths, depths and joint separations

    /// The parameters of a segment.
    const SegmentParameters& get(Segment s) const { return segments[static_cast<int>(s)]; }
};

/// Scales the de Leva table of a sex to a stature and mass and builds the body's shape.
/// Lengths scale with height / reference stature; masses with mass / (sum of the table's
/// fractions), so the total equals the input exactly; inertias are m (r L)^2. Shape breadths and
/// depths follow from segment mass, length and density (see docs/body.md), so they grow with BMI.
/// @throws std::invalid_argument if height or mass is not positive and finite.
Anthropometry calcAnthropometry(Sex sex, double height, double mass);

}  // namespace body
