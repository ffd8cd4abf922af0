// de Leva (1996) tables, their scaling to a patient, and the body build (see docs/body.md).
#include "body/Anthropometry.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace body {
namespace {

constexpr int kTypeCount = 10;

// de Leva (1996) Table 4. Columns: length [m] of the reference subject, mass fraction,
// CoM from the proximal landmark / length, radii of gyration / length about the sagittal,
// transverse and longitudinal axes. Rows in SegmentType order.
const DeLevaRow kFemale[kTypeCount] = {
    {0.2002, 0.0668, 0.5894, 0.330, 0.359, 0.318, "VERT", "MIDG"},
    {0.1425, 0.1545, 0.2077, 0.746, 0.502, 0.718, "SUPR", "XYPH"},
    {0.2053, 0.1465, 0.4512, 0.433, 0.354, 0.415, "XYPH", "OMPH"},
    {0.1815, 0.1247, 0.4920, 0.433, 0.402, 0.444, "OMPH", "MIDH"},
    {0.2751, 0.0255, 0.5754, 0.278, 0.260, 0.148, "SJC", "EJC"},
    {0.2643, 0.0138, 0.4559, 0.261, 0.257, 0.094, "EJC", "WJC"},
    {0.0780, 0.0056, 0.7474, 0.531, 0.454, 0.335, "WJC", "MET3"},
    {0.3685, 0.1478, 0.3612, 0.369, 0.364, 0.162, "HJC", "KJC"},
    {0.4323, 0.0481, 0.4416, 0.271, 0.267, 0.093, "KJC", "LMAL"},
    {0.2283, 0.0129, 0.4014, 0.299, 0.279, 0.139, "HEEL", "TTIP"},
};
const DeLevaRow kMale[kTypeCount] = {
    {0.2033, 0.0694, 0.5976, 0.362, 0.376, 0.312, "VERT", "MIDG"},
    {0.1707, 0.1596, 0.2999, 0.716, 0.454, 0.659, "SUPR", "XYPH"},
    {0.2155, 0.1633, 0.4502, 0.482, 0.383, 0.468, "XYPH", "OMPH"},
    {0.1457, 0.1117, 0.6115, 0.615, 0.551, 0.587, "OMPH", "MIDH"},
    {0.2817, 0.0271, 0.5772, 0.285, 0.269, 0.158, "SJC", "EJC"},
    {0.2689, 0.0162, 0.4574, 0.276, 0.265, 0.121, "EJC", "WJC"},
    {0.0862, 0.0061, 0.7900, 0.628, 0.513, 0.401, "WJC", "MET3"},
    {0.4222, 0.1416, 0.4095, 0.329, 0.329, 0.149, "HJC", "KJC"},
    {0.4340, 0.0433, 0.4459, 0.255, 0.249, 0.103, "KJC", "LMAL"},
    {0.2581, 0.0137, 0.4415, 0.257, 0.245, 0.124, "HEEL", "TTIP"},
};
// de Leva (1996) Table 4, alternative definitions: head VERT-CERV, trunk CERV-MIDH and
// MIDS-MIDH, hand WJC-DA3 (with its CoM and radii of gyration).
const DeLevaExtraLengths kFemaleExtra = {0.2437, 0.6148, 0.4979,
                                         0.1701, 0.3427, {0.244, 0.208, 0.154}};
const DeLevaExtraLengths kMaleExtra = {0.2429, 0.6033, 0.5155,
                                       0.1879, 0.3624, {0.288, 0.235, 0.184}};

// Drillis & Contini (1966), as drawn in Winter (2009) Fig. 4.1: body dimensions / stature.
constexpr double kShoulderWidthPerHeight = 0.259;  // outer shoulder breadth
constexpr double kAnkleHeightPerHeight = 0.039;    // ankle joint above the sole
// Hip joint centres: Harrington et al. (2007) ML = 0.33 PW + 7.3 mm; with a pelvis (inter-ASIS)
// width PW of about 0.24 m for a 1.75 m adult this gives a separation of about 0.10 H.
constexpr double kHipSeparationPerHeight = 0.10;
// The lumbar lordosis keeps the waist off a flat support in supine lying; the middle-trunk shape
// is placed this far (per metre of stature) above the line touching the thorax and pelvis shapes.
constexpr double kLumbarClearancePerHeight = 0.010 / 1.75;

const char* kSegmentNames[kSegmentCount] = {
    "lower_trunk", "middle_trunk", "upper_trunk", "head",   "upper_arm_r", "forearm_r",
    "hand_r",      "upper_arm_l",  "forearm_l",   "hand_l", "thigh_r",     "shank_r",
    "foot_r",      "thigh_l",      "shank_l",     "foot_l"};

double sq(double x) { return x * x; }

// Semi-axes of the uniform ellipsoid with the given radii of gyration about X, Y, Z [m]:
// k_x^2 = (a_y^2 + a_z^2) / 5 etc., solved for a.
SimTK::Vec3 calcEquivalentEllipsoid(const SimTK::Vec3& k) {
    const double kx2 = sq(k[0]), ky2 = sq(k[1]), kz2 = sq(k[2]);
    const SimTK::Vec3 a2(2.5 * (ky2 + kz2 - kx2), 2.5 * (kx2 + kz2 - ky2), 2.5 * (kx2 + ky2 - kz2));
    for (int i = 0; i < 3; ++i)
        if (!(a2[i] > 0))
            throw std::logic_error("body: radii of gyration violate the triangle inequality");
    return SimTK::Vec3(std::sqrt(a2[0]), std::sqrt(a2[1]), std::sqrt(a2[2]));
}

// Scales the two transverse semi-axes (X and Z) so that density * volume = mass.
SimTK::Vec3 fitTransverseToMass(SimTK::Vec3 a, double mass, double density) {
    const double volume = 4.0 / 3.0 * SimTK::Pi * a[0] * a[1] * a[2];
    const double f = std::sqrt(mass / (density * volume));
    a[0] *= f;
    a[2] *= f;
    return a;
}

// Radius ratio q = r_distal / r_proximal of a truncated cone whose centroid lies at the fraction
// c of its length from the proximal end: (4c-3) q^2 + (4c-2) q + (4c-1) = 0. Limited to
// [0.4, 1]: a segment whose CoM is distal of its middle (the upper arm, whose proximal cut
// leaves the deltoid on the trunk) is given a uniform radius.
double calcTaperRatio(double c) {
    if (c >= 0.5) return 1.0;
    const double A = 4 * c - 3, B = 4 * c - 2, C = 4 * c - 1;
    const double disc = B * B - 4 * A * C;
    const double q = (-B - std::sqrt(disc)) / (2 * A);
    return std::min(1.0, std::max(0.4, q));
}

// Proximal radius of a truncated cone of length L, radius ratio q, with mass m and density rho.
double calcConeRadius(double m, double rho, double L, double q) {
    return std::sqrt(3 * m / (rho * SimTK::Pi * L * (1 + q + q * q)));
}

}  // namespace

const DeLevaRow& getDeLevaRow(Sex sex, SegmentType type) {
    const int i = static_cast<int>(type);
    return sex == Sex::Female ? kFemale[i] : kMale[i];
}

DeLevaReference getDeLevaReference(Sex sex) {
    return sex == Sex::Female ? DeLevaReference{1.735, 61.9} : DeLevaReference{1.741, 73.0};
}

const DeLevaExtraLengths& getDeLevaExtraLengths(Sex sex) {
    return sex == Sex::Female ? kFemaleExtra : kMaleExtra;
}

SegmentType getSegmentType(Segment s) {
    switch (s) {
        case Segment::LowerTrunk:
            return SegmentType::LowerTrunk;
        case Segment::MiddleTrunk:
            return SegmentType::MiddleTrunk;
        case Segment::UpperTrunk:
            return SegmentType::UpperTrunk;
        case Segment::Head:
            return SegmentType::Head;
        case Segment::UpperArmR:
        case Segment::UpperArmL:
            return SegmentType::UpperArm;
        case Segment::ForearmR:
        case Segment::ForearmL:
            return SegmentType::Forearm;
        case Segment::HandR:
        case Segment::HandL:
            return SegmentType::Hand;
        case Segment::ThighR:
        case Segment::ThighL:
            return SegmentType::Thigh;
        case Segment::ShankR:
        case Segment::ShankL:
            return SegmentType::Shank;
        case Segment::FootR:
        case Segment::FootL:
            return SegmentType::Foot;
    }
    throw std::logic_error("body: unknown segment");
}

Side getSegmentSide(Segment s) {
    switch (s) {
        case Segment::UpperArmR:
        case Segment::ForearmR:
        case Segment::HandR:
        case Segment::ThighR:
        case Segment::ShankR:
        case Segment::FootR:
            return Side::Right;
        case Segment::UpperArmL:
        case Segment::ForearmL:
        case Segment::HandL:
        case Segment::ThighL:
        case Segment::ShankL:
        case Segment::FootL:
            return Side::Left;
        default:
            return Side::Centre;
    }
}

Segment getMirrorSegment(Segment s) {
    // Enum order: each left segment follows its right counterpart by three.
    switch (getSegmentSide(s)) {
        case Side::Right:
            return static_cast<Segment>(static_cast<int>(s) + 3);
        case Side::Left:
            return static_cast<Segment>(static_cast<int>(s) - 3);
        default:
            return s;
    }
}

const char* getSegmentName(Segment s) { return kSegmentNames[static_cast<int>(s)]; }

const char* getSexName(Sex sex) { return sex == Sex::Female ? "female" : "male"; }

double getSegmentDensity(SegmentType type) {
    switch (type) {
        case SegmentType::Head:
            return 1110;  // head and neck
        case SegmentType::UpperTrunk:
            return 920;  // thorax
        case SegmentType::MiddleTrunk:
            return 1010;  // abdomen and pelvis
        case SegmentType::LowerTrunk:
            return 1010;  // abdomen and pelvis
        case SegmentType::UpperArm:
            return 1070;
        case SegmentType::Forearm:
            return 1130;
        case SegmentType::Hand:
            return 1160;
        case SegmentType::Thigh:
            return 1050;
        case SegmentType::Shank:
            return 1090;
        case SegmentType::Foot:
            return 1100;
    }
    throw std::logic_error("body: unknown segment type");
}

Anthropometry calcAnthropometry(Sex sex, double height, double mass) {
    if (!(height > 0) || !std::isfinite(height))
        throw std::invalid_argument("body: height must be a positive number of metres, got " +
                                    std::to_string(height));
    if (!(mass > 0) || !std::isfinite(mass))
        throw std::invalid_argument("body: mass must be a positive number of kilograms, got " +
                                    std::to_string(mass));
    const DeLevaReference ref = getDeLevaReference(sex);
    const DeLevaExtraLengths& extra = getDeLevaExtraLengths(sex);
    Anthropometry a;
    a.sex = sex;
    a.height = height;
    a.mass = mass;
    a.bmi = mass / (height * height);
    const double s = height / ref.stature;
    a.lengthScale = s;
    const double bmiRef = ref.mass / (ref.stature * ref.stature);
    // Body mass of a patient of this height at the reference subject's BMI [kg].
    const double massAtRefBmi = bmiRef * height * height;

    double fractionSum = 0;
    for (int t = 0; t < kTypeCount; ++t) {
        const DeLevaRow& row = getDeLevaRow(sex, static_cast<SegmentType>(t));
        const bool paired = t >= static_cast<int>(SegmentType::UpperArm);
        fractionSum += (paired ? 2 : 1) * row.massFraction;
    }
    auto rowOf = [&](SegmentType t) -> const DeLevaRow& { return getDeLevaRow(sex, t); };
    auto massOf = [&](SegmentType t) { return rowOf(t).massFraction / fractionSum * mass; };
    auto massRefOf = [&](SegmentType t) {
        return rowOf(t).massFraction / fractionSum * massAtRefBmi;
    };
    auto lenOf = [&](SegmentType t) { return rowOf(t).length * s; };

    const double Llt = lenOf(SegmentType::LowerTrunk);
    const double Lmt = lenOf(SegmentType::MiddleTrunk);
    const double LheadC = extra.vertexToCervicale * s;
    const double LtrunkC = extra.cervicaleToMidHip * s;
    const double LtrunkS = extra.midShoulderToMidHip * s;
    const double Lua = lenOf(SegmentType::UpperArm);
    const double Lfa = lenOf(SegmentType::Forearm);
    const double LhandTip = extra.wristToFingertip * s;
    const double Lth = lenOf(SegmentType::Thigh);
    const double Lsh = lenOf(SegmentType::Shank);
    const double ankleHeight = kAnkleHeightPerHeight * height;

    // Joint separations: skeletal, so set from the stature and the reference-BMI upper arm.
    const double rUpperArmRef = calcConeRadius(massRefOf(SegmentType::UpperArm),
                                               getSegmentDensity(SegmentType::UpperArm), Lua, 1.0);
    const double shoulderSep = kShoulderWidthPerHeight * height - 2 * rUpperArmRef;
    const double hipSep = kHipSeparationPerHeight * height;

    for (int i = 0; i < kSegmentCount; ++i) {
        const Segment seg = static_cast<Segment>(i);
        const SegmentType type = getSegmentType(seg);
        const DeLevaRow& row = rowOf(type);
        const Side side = getSegmentSide(seg);
        const double zSide = side == Side::Right ? 1.0 : (side == Side::Left ? -1.0 : 0.0);
        SegmentParameters& p = a.segments[i];
        p.segment = seg;
        p.mass = massOf(type);
        p.length = row.length * s;
        const double L = p.length;
        const double c = row.comFraction;
        const double rho = getSegmentDensity(type);
        // Radii of gyration about body X (antero-posterior), Y (longitudinal), Z (medio-lateral).
        SimTK::Vec3 k(row.rSagittal * L, row.rLongitudinal * L, row.rTransverse * L);
        if (type == SegmentType::Foot)  // the foot's long axis is body X
            k = SimTK::Vec3(row.rLongitudinal * L, row.rTransverse * L, row.rSagittal * L);
        p.inertiaC = p.mass * SimTK::Vec3(sq(k[0]), sq(k[1]), sq(k[2]));

        switch (type) {
            case SegmentType::LowerTrunk:
                p.p_WO = SimTK::Vec3(0);
                p.p_BC = SimTK::Vec3(0, (1 - c) * L, 0);
                break;
            case SegmentType::MiddleTrunk:
                p.p_WO = SimTK::Vec3(0, Llt, 0);
                p.p_BC = SimTK::Vec3(0, (1 - c) * L, 0);
                break;
            case SegmentType::UpperTrunk:
                p.p_WO = SimTK::Vec3(0, Llt + Lmt, 0);
                p.p_BC = SimTK::Vec3(0, (1 - c) * L, 0);
                break;
            case SegmentType::Head:
                // Neck joint on the body axis at the level of the cervicale; the vertex lies
                // VERT-CERV above it.
                p.p_WO = SimTK::Vec3(0, LtrunkC, 0);
                p.p_BC = SimTK::Vec3(0, LheadC - c * L, 0);
                break;
            case SegmentType::UpperArm:
                p.p_WO = SimTK::Vec3(0, LtrunkS, zSide * shoulderSep / 2);
                p.p_BC = SimTK::Vec3(0, -c * L, 0);
                break;
            case SegmentType::Forearm:
                p.p_WO = SimTK::Vec3(0, LtrunkS - Lua, zSide * shoulderSep / 2);
                p.p_BC = SimTK::Vec3(0, -c * L, 0);
                break;
            case SegmentType::Hand:
                p.p_WO = SimTK::Vec3(0, LtrunkS - Lua - Lfa, zSide * shoulderSep / 2);
                p.p_BC = SimTK::Vec3(0, -c * L, 0);
                break;
            case SegmentType::Thigh:
                p.p_WO = SimTK::Vec3(0, 0, zSide * hipSep / 2);
                p.p_BC = SimTK::Vec3(0, -c * L, 0);
                break;
            case SegmentType::Shank:
                p.p_WO = SimTK::Vec3(0, -Lth, zSide * hipSep / 2);
                p.p_BC = SimTK::Vec3(0, -c * L, 0);
                break;
            case SegmentType::Foot:
                p.p_WO = SimTK::Vec3(0, -Lth - Lsh, zSide * hipSep / 2);
                break;
        }

        ShapeSize& shape = p.shape;
        switch (type) {
            case SegmentType::Head: {
                // Uniform ellipsoid with the segment's radii of gyration; its breadth and depth
                // fitted to the mass the head would have at the reference BMI (skull size does
                // not follow body fat).
                shape.kind = ShapeKind::Ellipsoid;
                shape.semiAxes =
                    fitTransverseToMass(calcEquivalentEllipsoid(k), massRefOf(type), rho);
                shape.centre = p.p_BC;
                break;
            }
            case SegmentType::UpperTrunk:
            case SegmentType::MiddleTrunk:
            case SegmentType::LowerTrunk:
                shape.kind = ShapeKind::Ellipsoid;
                shape.semiAxes = fitTransverseToMass(calcEquivalentEllipsoid(k), p.mass, rho);
                shape.centre = p.p_BC;
                break;
            case SegmentType::Hand: {
                // Shape from the wrist-to-fingertip definition (the hand with its fingers).
                const SimTK::Vec3 kTip(extra.handFingertipGyration[0] * LhandTip,
                                       extra.handFingertipGyration[2] * LhandTip,
                                       extra.handFingertipGyration[1] * LhandTip);
                shape.kind = ShapeKind::Ellipsoid;
                shape.semiAxes = fitTransverseToMass(calcEquivalentEllipsoid(kTip), p.mass, rho);
                shape.centre = SimTK::Vec3(0, -extra.handFingertipComFraction * LhandTip, 0);
                break;
            }
            case SegmentType::UpperArm:
            case SegmentType::Forearm:
            case SegmentType::Thigh:
            case SegmentType::Shank: {
                // Truncated cone between the joint centres holding the segment's mass, with its
                // centroid at the table's CoM; drawn as a round cone (spheres at the joints).
                const double q = calcTaperRatio(c);
                shape.kind = ShapeKind::RoundCone;
                shape.radiusA = calcConeRadius(p.mass, rho, L, q);
                shape.radiusB = q * shape.radiusA;
                shape.pointA = SimTK::Vec3(0);
                shape.pointB = SimTK::Vec3(0, -L, 0);
                break;
            }
            case SegmentType::Foot: {
                // Round cone from a heel sphere below the ankle to a toe sphere, both resting on
                // the sole plane; heel-to-toe-tip length and CoM from the table.
                const double q = calcTaperRatio(c);
                const double r1 = calcConeRadius(p.mass, rho, L, q);
                const double r2 = q * r1;
                shape.kind = ShapeKind::RoundCone;
                shape.radiusA = r1;
                shape.radiusB = r2;
                shape.pointA = SimTK::Vec3(0, -(ankleHeight - r1), 0);
                shape.pointB = SimTK::Vec3(-r1 + L - r2, -(ankleHeight - r2), 0);
                const double xC = -r1 + c * L;
                const double t = (xC - shape.pointA[0]) / (shape.pointB[0] - shape.pointA[0]);
                p.p_BC = shape.pointA + t * (shape.pointB - shape.pointA);
                break;
            }
        }
    }

    // Lumbar clearance: place the middle-trunk shape so its back lies kLumbarClearance above the
    // mean of the thorax and pelvis backs.
    {
        SegmentParameters& mt = a.segments[static_cast<int>(Segment::MiddleTrunk)];
        const double backUpper = a.get(Segment::UpperTrunk).shape.semiAxes[0];
        const double backLower = a.get(Segment::LowerTrunk).shape.semiAxes[0];
        const double backMiddle =
            0.5 * (backUpper + backLower) - kLumbarClearancePerHeight * height;
        mt.shape.centre[0] = mt.shape.semiAxes[0] - backMiddle;
    }

    BodyBuild& b = a.build;
    const ShapeSize& ut = a.get(Segment::UpperTrunk).shape;
    const ShapeSize& mt = a.get(Segment::MiddleTrunk).shape;
    const ShapeSize& lt = a.get(Segment::LowerTrunk).shape;
    const ShapeSize& hd = a.get(Segment::Head).shape;
    const ShapeSize& th = a.get(Segment::ThighR).shape;
    const ShapeSize& ua = a.get(Segment::UpperArmR).shape;
    b.shoulderJointSeparation = shoulderSep;
    b.hipJointSeparation = hipSep;
    b.ankleHeight = ankleHeight;
    b.shoulderBreadth = shoulderSep + 2 * ua.radiusA;
    b.chestBreadth = 2 * ut.semiAxes[2];
    b.chestDepth = 2 * ut.semiAxes[0];
    b.waistBreadth = 2 * mt.semiAxes[2];
    b.waistDepth = 2 * mt.semiAxes[0];
    b.hipBreadth = hipSep + 2 * th.radiusA;
    b.pelvisDepth = 2 * lt.semiAxes[0];
    b.buttockDepth = 2 * th.radiusA;
    b.headBreadth = 2 * hd.semiAxes[2];
    b.headLength = 2 * hd.semiAxes[0];
    b.modelStature = (LtrunkC + LheadC) + (Lth + Lsh + ankleHeight);
    return a;
}

}  // namespace body
