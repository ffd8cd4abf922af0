// Lying postures (see Posture.h): root orientation and joint rotations, then placement on z = 0.
#include "body/Posture.h"

#include <map>
#include <string>

#include "body/BodyModel.h"

namespace body {
namespace {

const double kDeg = SimTK::Pi / 180.0;

// Supine: anatomical X (anterior) -> +z, Y (superior) -> +x, Z (right) -> +y.
SimTK::Rotation getSupineRotation() {
    return SimTK::Rotation(SimTK::Mat33(0, 1, 0,  //
                                        0, 0, 1,  //
                                        1, 0, 0));
}

SimTK::Rotation flexion(double deg) { return SimTK::Rotation(deg * kDeg, SimTK::ZAxis); }

}  // namespace

void BodyModel::setPosture(SimTK::State& state, double clearance) const {
    const PatientSpec& s = getSpec();
    setPosture(state, s.posture, s.position, s.headOfBedAngle, clearance);
}

void BodyModel::setPosture(SimTK::State& state, Posture posture,
                           const std::array<double, 2>& position, double headOfBedAngle,
                           double clearance) const {
    const SimTK::Rotation R_sup = getSupineRotation();
    SimTK::Rotation R_root = R_sup;
    std::map<std::string, SimTK::Rotation> jointRotation;  // joint name -> R_FM
    // Relaxed legs lying on the back roll outwards (the foot's mass is in front of the ankle):
    // start them in 15 deg external rotation so they settle the same way on both sides.
    const bool onBack = posture == Posture::Supine || posture == Posture::TiltLeft30 ||
                        posture == Posture::TiltRight30 || posture == Posture::HeadOfBedRaised;
    if (onBack) {
        jointRotation["hip_r"] = SimTK::Rotation(-15 * kDeg, SimTK::YAxis);
        jointRotation["hip_l"] = SimTK::Rotation(15 * kDeg, SimTK::YAxis);
    }
    switch (posture) {
        case Posture::Supine:
            break;
        case Posture::TiltLeft30:  // +angle about +x puts the left (-y) side down
            R_root = SimTK::Rotation(30 * kDeg, SimTK::XAxis) * R_sup;
            break;
        case Posture::TiltRight30:
            R_root = SimTK::Rotation(-30 * kDeg, SimTK::XAxis) * R_sup;
            break;
        case Posture::SideLeft90:
        case Posture::SideRight90: {
            const bool left = posture == Posture::SideLeft90;
            R_root = SimTK::Rotation((left ? 90 : -90) * kDeg, SimTK::XAxis) * R_sup;
            // Recovery-like position: the lower arm brought forward out from under the trunk.
            // Lower leg slightly flexed, upper leg brought forward (hip 45, knee 45 deg).
            const std::string lower = left ? "_l" : "_r";
            const std::string upper = left ? "_r" : "_l";
            jointRotation["hip" + lower] = flexion(20);
            jointRotation["knee" + lower] = flexion(-30);
            jointRotation["hip" + upper] = flexion(45);
            jointRotation["knee" + upper] = flexion(-45);
            jointRotation["shoulder" + lower] = flexion(70);
            jointRotation["elbow" + lower] = flexion(30);
            jointRotation["shoulder" + upper] = flexion(30);
            break;
        }
        case Posture::HeadOfBedRaised: {
            // Trunk pitched up about the hip line, thighs kept flat by equal hip flexion.
            const double deg = headOfBedAngle / kDeg;
            R_root = SimTK::Rotation(-headOfBedAngle, SimTK::YAxis) * R_sup;
            jointRotation["hip_r"] = flexion(deg) * jointRotation["hip_r"];
            jointRotation["hip_l"] = flexion(deg) * jointRotation["hip_l"];
            break;
        }
    }
    const SimTK::MobilizedBody& root = getMobilizedBody(Segment::LowerTrunk);
    root.setQToFitTransform(state,
                            SimTK::Transform(R_root, SimTK::Vec3(position[0], position[1], 0)));
    for (const JointSpec& j : getJoints()) {
        const auto it = jointRotation.find(j.name);
        getMobilizedBody(j.child).setQToFitRotation(
            state, it == jointRotation.end() ? SimTK::Rotation() : it->second);
    }
    state.updU() = 0;
    getSystem().realize(state, SimTK::Stage::Position);
    const double zLow = calcLowestPointHeight(state);
    root.setQToFitTransform(
        state, SimTK::Transform(R_root, SimTK::Vec3(position[0], position[1], clearance - zLow)));
    getSystem().realize(state, SimTK::Stage::Position);
}

}  // namespace body
