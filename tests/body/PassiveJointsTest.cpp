// Passive joint torques: work-conjugate to the potential (finite differences), damping, mirror.
#include <body/PassiveJoints.h>
#include <gtest/gtest.h>

#include <random>

namespace {

SimTK::Rotation exponential(const SimTK::Vec3& v) {
    const double a = v.norm();
    return a > 0 ? SimTK::Rotation(a, SimTK::UnitVec3(v)) : SimTK::Rotation();
}

const body::JointSpec& find(const std::vector<body::JointSpec>& joints, const std::string& name) {
    for (const auto& j : joints)
        if (j.name == name) return j;
    throw std::runtime_error("no joint " + name);
}

}  // namespace

TEST(PassiveJoints, FifteenJointsWithAnatomicalTypes) {
    const auto a = body::calcAnthropometry(body::Sex::Male, 1.741, 73.0);
    const auto joints = body::makeJointSpecs(a);
    EXPECT_EQ(joints.size(), 15u);
    for (const char* pin : {"elbow_r", "elbow_l", "knee_r", "knee_l"})
        EXPECT_EQ(find(joints, pin).type, body::JointType::Pin);
    for (const char* ball :
         {"neck", "thoracic", "lumbar", "shoulder_r", "hip_l", "ankle_r", "wrist_l"})
        EXPECT_EQ(find(joints, ball).type, body::JointType::Ball);
    EXPECT_EQ(find(joints, "knee_l").parent, body::Segment::ThighL);
    EXPECT_EQ(find(joints, "ankle_l").parent, body::Segment::ShankL);
}

TEST(PassiveJoints, LeftRangesMirrorTheRight) {
    const auto joints =
        body::makeJointSpecs(body::calcAnthropometry(body::Sex::Female, 1.62, 58.0));
    for (const char* base : {"shoulder", "wrist", "hip", "ankle"}) {
        const auto& r = find(joints, std::string(base) + "_r");
        const auto& l = find(joints, std::string(base) + "_l");
        for (int i = 0; i < 2; ++i) {  // theta_x, theta_y change sign
            EXPECT_DOUBLE_EQ(l.lower[i], -r.upper[i]);
            EXPECT_DOUBLE_EQ(l.upper[i], -r.lower[i]);
        }
        EXPECT_DOUBLE_EQ(l.lower[2], r.lower[2]);  // flexion is the same
        EXPECT_DOUBLE_EQ(l.upper[2], r.upper[2]);
    }
    // Hip flexion 120 deg (AAOS) is +theta_z.
    EXPECT_NEAR(find(joints, "hip_r").upper[2], 120 * SimTK::Pi / 180, 1e-12);
}

TEST(PassiveJoints, TorqueIsMinusPotentialGradientUnderRotation) {
    // tau . e_i = -dU/de for R(e) = exp(e e_i^) R_FM (a rotation of M about F's axis i).
    // Central differences with h = 1e-6: truncation ~h^2 * k, round-off ~1e-16 * U / h.
    const auto joints = body::makeJointSpecs(body::calcAnthropometry(body::Sex::Male, 1.8, 80.0));
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.6, 1.6);
    const double h = 1e-6;
    int n = 0;
    for (const auto& j : joints) {
        if (j.type != body::JointType::Ball) continue;
        for (int k = 0; k < 20; ++k) {
            const SimTK::Rotation R =
                exponential(SimTK::Vec3(u(rng), u(rng), u(rng)));    // often beyond limits
            if (body::calcRotationVector(R).norm() > 2.8) continue;  // away from the pi wrap
            const SimTK::Vec3 tau = body::calcJointTorque(j, R, SimTK::Vec3(0), 1.0);
            for (int i = 0; i < 3; ++i) {
                SimTK::Vec3 e(0);
                e[i] = h;
                const double dU = (body::calcJointPotential(j, exponential(e) * R) -
                                   body::calcJointPotential(j, exponential(-e) * R)) /
                                  (2 * h);
                EXPECT_NEAR(tau[i], -dU, 1e-5 * (1 + std::abs(dU))) << j.name;
            }
            ++n;
        }
    }
    EXPECT_GT(n, 50);
}

TEST(PassiveJoints, DampingOpposesRelativeAngularVelocity) {
    const auto joints = body::makeJointSpecs(body::calcAnthropometry(body::Sex::Male, 1.741, 73.0));
    const auto& hip = find(joints, "hip_r");
    const SimTK::Vec3 w(0.3, -0.2, 0.5);
    const SimTK::Vec3 tau = body::calcJointTorque(hip, SimTK::Rotation(), w, 1.0);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tau[i], -hip.damping[i] * w[i], 1e-15);
    // Reference male hip: 1 N m s/rad (scale factor 1 at 73 kg, 1.741 m).
    EXPECT_NEAR(hip.damping[0], 1.0, 1e-12);
    EXPECT_NEAR(body::calcJointTorque(hip, SimTK::Rotation(), w, 0.0).norm(), 0.0, 1e-15);
}

TEST(PassiveJoints, LimitStiffensBeyondRange) {
    const auto joints = body::makeJointSpecs(body::calcAnthropometry(body::Sex::Male, 1.741, 73.0));
    const auto& knee = find(joints, "knee_r");
    const double hyper = knee.upper[2] + 0.1;  // 0.1 rad past full extension
    const SimTK::Vec3 tau =
        body::calcJointTorque(knee, SimTK::Rotation(hyper, SimTK::ZAxis), SimTK::Vec3(0), 1.0);
    // Within the range only k theta; past it k theta + k_lim (theta - upper).
    EXPECT_NEAR(tau[2], -(knee.stiffness[2] * hyper + knee.limitStiffness * 0.1), 1e-9);
}
