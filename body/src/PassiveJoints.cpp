// Passive joint torques (see PassiveJoints.h and docs/body.md for the values and sources).
#include "body/PassiveJoints.h"

#include <cmath>

namespace body {
namespace {

const double kDeg = SimTK::Pi / 180.0;

// Values for the reference male (73 kg, 1.741 m). Range of motion: AAOS (Greene & Heckman 1994),
// as anatomical angles; see docs/body.md. Ranges are given for the right side in the
// joint-angle convention of PassiveJoints.h; the left side mirrors theta_x and theta_y.
struct JointTemplate {
    const char* name;
    Segment parent, childR, childL;  // childL == childR for midline joints
    JointType type;
    double k, c, kLim;    // [N m/rad], [N m s/rad], [N m/rad]
    double lo[3], hi[3];  // [deg] theta_x, theta_y, theta_z
};

const JointTemplate kJoints[] = {
    // Spine: thoracolumbar flexion 80, extension 25, lateral bending 35, rotation 45 shared by
    // two joints; flexion of a joint whose child lies above it is -theta_z.
    {"lumbar",
     Segment::LowerTrunk,
     Segment::MiddleTrunk,
     Segment::MiddleTrunk,
     JointType::Ball,
     60,
     5,
     600,
     {-17.5, -22.5, -40},
     {17.5, 22.5, 12.5}},
    {"thoracic",
     Segment::MiddleTrunk,
     Segment::UpperTrunk,
     Segment::UpperTrunk,
     JointType::Ball,
     60,
     5,
     600,
     {-17.5, -22.5, -40},
     {17.5, 22.5, 12.5}},
    // Cervical: flexion 45, extension 45, lateral bending 45, rotation 60.
    {"neck",
     Segment::UpperTrunk,
     Segment::Head,
     Segment::Head,
     JointType::Ball,
     5,
     0.5,
     50,
     {-45, -60, -45},
     {45, 60, 45}},
    // Shoulder: flexion 180 (170 kept clear of the rotation-vector wrap), extension 60,
    // abduction 170 (-theta_x on the right), adduction 30, internal rotation 70, external 90.
    {"shoulder",
     Segment::UpperTrunk,
     Segment::UpperArmR,
     Segment::UpperArmL,
     JointType::Ball,
     2,
     0.3,
     50,
     {-170, -90, -60},
     {30, 70, 170}},
    // Elbow: flexion 145, 5 hyperextension.
    {"elbow",
     Segment::UpperArmR,
     Segment::ForearmR,
     Segment::ForearmL,
     JointType::Pin,
     1,
     0.2,
     30,
     {0, 0, -5},
     {0, 0, 145}},
    // Wrist: flexion 80, extension 70, ulnar deviation 30 (+theta_x right), radial 20.
    {"wrist",
     Segment::ForearmR,
     Segment::HandR,
     Segment::HandL,
     JointType::Ball,
     0.5,
     0.05,
     10,
     {-20, -10, -70},
     {30, 10, 80}},
    // Hip: flexion 120, extension 30, abduction 45 (-theta_x right), adduction 30, internal
    // rotation 45 (+theta_y right), external 45.
    {"hip",
     Segment::LowerTrunk,
     Segment::ThighR,
     Segment::ThighL,
     JointType::Ball,
     10,
     1,
     200,
     {-45, -45, -30},
     {30, 45, 120}},
    // Knee: flexion 135 (-theta_z), 5 hyperextension.
    {"knee",
     Segment::ThighR,
     Segment::ShankR,
     Segment::ShankL,
     JointType::Pin,
     5,
     0.5,
     200,
     {0, 0, -135},
     {0, 0, 5}},
    // Ankle: dorsiflexion 20, plantarflexion 50, inversion 35 (+theta_x right), eversion 15,
    // forefoot adduction/abduction 15.
    {"ankle",
     Segment::ShankR,
     Segment::FootR,
     Segment::FootL,
     JointType::Ball,
     5,
     0.3,
     50,
     {-15, -15, -50},
     {35, 15, 20}},
};

double sq(double x) { return x * x; }

// Skew-symmetric cross-product matrix of v.
SimTK::Mat33 skew(const SimTK::Vec3& v) {
    return SimTK::Mat33(0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0);
}

}  // namespace

std::vector<JointSpec> makeJointSpecs(const Anthropometry& a) {
    const double scale = (a.mass * a.height) / (73.0 * 1.741);
    std::vector<JointSpec> out;
    for (const JointTemplate& t : kJoints) {
        const bool paired = t.childR != t.childL;
        for (int side = 0; side < (paired ? 2 : 1); ++side) {
            JointSpec j;
            j.name = std::string(t.name) + (paired ? (side == 0 ? "_r" : "_l") : "");
            j.parent = side == 0 ? t.parent : getMirrorSegment(t.parent);
            j.child = side == 0 ? t.childR : t.childL;
            j.type = t.type;
            j.stiffness = SimTK::Vec3(t.k * scale);
            j.damping = SimTK::Vec3(t.c * scale);
            j.limitStiffness = t.kLim * scale;
            for (int i = 0; i < 3; ++i) {
                double lo = t.lo[i] * kDeg, hi = t.hi[i] * kDeg;
                if (side == 1 && i < 2) {  // mirror ab/adduction and axial rotation
                    const double l = -hi;
                    hi = -lo;
                    lo = l;
                }
                j.lower[i] = lo;
                j.upper[i] = hi;
            }
            if (t.type == JointType::Pin) {  // only theta_z moves
                j.stiffness[0] = j.stiffness[1] = 0;
                j.damping[0] = j.damping[1] = 0;
                j.lower[0] = j.lower[1] = -SimTK::Pi;
                j.upper[0] = j.upper[1] = SimTK::Pi;
            }
            out.push_back(j);
        }
    }
    return out;
}

SimTK::Vec3 calcRotationVector(const SimTK::Rotation& R_FM) {
    const SimTK::Vec4 aa = R_FM.convertRotationToAngleAxis();
    return aa[0] * SimTK::Vec3(aa[1], aa[2], aa[3]);
}

namespace {
// dU/dtheta.
SimTK::Vec3 calcPotentialGradient(const JointSpec& j, const SimTK::Vec3& th) {
    SimTK::Vec3 g;
    for (int i = 0; i < 3; ++i) {
        g[i] = j.stiffness[i] * th[i];
        if (th[i] > j.upper[i]) g[i] += j.limitStiffness * (th[i] - j.upper[i]);
        if (th[i] < j.lower[i]) g[i] += j.limitStiffness * (th[i] - j.lower[i]);
    }
    return g;
}
}  // namespace

double calcJointPotential(const JointSpec& j, const SimTK::Rotation& R_FM) {
    const SimTK::Vec3 th = calcRotationVector(R_FM);
    double u = 0;
    for (int i = 0; i < 3; ++i) {
        u += 0.5 * j.stiffness[i] * sq(th[i]);
        if (th[i] > j.upper[i]) u += 0.5 * j.limitStiffness * sq(th[i] - j.upper[i]);
        if (th[i] < j.lower[i]) u += 0.5 * j.limitStiffness * sq(th[i] - j.lower[i]);
    }
    return u;
}

SimTK::Vec3 calcJointTorque(const JointSpec& j, const SimTK::Rotation& R_FM,
                            const SimTK::Vec3& w_FM, double dampingScale) {
    const SimTK::Vec3 th = calcRotationVector(R_FM);
    const double a = th.norm();
    // Inverse of the left Jacobian of SO(3): thetadot = Jinv * w_FM.
    double beta;
    if (a < 1e-4)
        beta = 1.0 / 12.0 + a * a / 720.0;
    else
        beta = 1.0 / (a * a) - (1.0 + std::cos(a)) / (2.0 * a * std::sin(a));
    const SimTK::Mat33 S = skew(th);
    const SimTK::Mat33 Jinv = SimTK::Mat33(1) - 0.5 * S + beta * S * S;
    SimTK::Vec3 tau = -(~Jinv * calcPotentialGradient(j, th));
    for (int i = 0; i < 3; ++i) tau[i] -= dampingScale * j.damping[i] * w_FM[i];
    return tau;
}

PassiveJointForce::PassiveJointForce(const SimTK::SimbodyMatterSubsystem& matter,
                                     std::vector<Entry> entries, double dampingScale)
    : m_matter(matter), m_entries(std::move(entries)), m_dampingScale(dampingScale) {}

void PassiveJointForce::calcForce(const SimTK::State& state,
                                  SimTK::Vector_<SimTK::SpatialVec>& bodyForces,
                                  SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector&) const {
    for (const Entry& e : m_entries) {
        const SimTK::MobilizedBody& P = m_matter.getMobilizedBody(e.parent);
        const SimTK::MobilizedBody& C = m_matter.getMobilizedBody(e.child);
        const SimTK::Rotation& R_GP = P.getBodyRotation(state);
        const SimTK::Rotation R_FM = ~R_GP * C.getBodyRotation(state);
        const SimTK::Vec3 w_FM =
            ~R_GP * (C.getBodyAngularVelocity(state) - P.getBodyAngularVelocity(state));
        const SimTK::Vec3 tau_G = R_GP * calcJointTorque(e.spec, R_FM, w_FM, m_dampingScale);
        bodyForces[e.child][0] += tau_G;
        bodyForces[e.parent][0] -= tau_G;
    }
}

SimTK::Real PassiveJointForce::calcPotentialEnergy(const SimTK::State& state) const {
    double u = 0;
    for (const Entry& e : m_entries) {
        const SimTK::Rotation R_FM = ~m_matter.getMobilizedBody(e.parent).getBodyRotation(state) *
                                     m_matter.getMobilizedBody(e.child).getBodyRotation(state);
        u += calcJointPotential(e.spec, R_FM);
    }
    return u;
}

}  // namespace body
