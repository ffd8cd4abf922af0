#pragma once
// A test double for a bag: each shape is held by a linear spring-like law,
// W(X) = W_ref + K d(X_ref, X) (d: rotation vector and translation from X_ref, Ground), with
// the exact tangent K (or K scaled by tangentScale, a stand-in for a bag whose tangent is off).
// It counts its advances and tangents, can be told to fail one, and to say it is steady; a
// one-sided spring pushes only while its shape lies below X_ref (contact: no pull, no tangent
// above it). With `unresolved` > 0 it stands in for a bag kept short of its equilibrium: its
// force along z is off by that much, with a sign that alternates advance by advance (not a
// function of the pose), and, if `reportUnresolved`, it says so (ParticipantStep).
#include <cosim/Participant.h>

#include <vector>

namespace cosim::test {

class SpringParticipant : public Participant {
  public:
    struct Spring {
        Eigen::Isometry3d X_ref = Eigen::Isometry3d::Identity();
        Vec6 W_ref = Vec6::Zero();
        Mat6 K = Mat6::Zero();  // d(torque, force)/d(rotation, translation)
    };
    explicit SpringParticipant(std::vector<Spring> springs)
        : m_springs(std::move(springs)), m_pose(m_springs.size()), m_committed(m_springs.size()) {
        for (size_t i = 0; i < m_springs.size(); ++i)
            m_pose[i] = m_committed[i] = m_springs[i].X_ref;
        m_next = m_pose;
    }
    int getNumShapes() const override { return int(m_springs.size()); }
    void setShapeState(int shape, const ShapeState& s) override { m_next.at(shape) = s.X_GS; }
    ParticipantStep advance(double) override {
        ++advances;
        ParticipantStep s;
        s.converged = advances != failAt;
        m_pose = s.converged ? m_next : m_committed;
        m_error = advances % 2 == 0 ? unresolved : -unresolved;
        if (reportUnresolved) s.unresolvedForce = unresolved;
        return s;
    }
    void commit() override { m_committed = m_pose; }
    void rollback() override { m_pose = m_committed; }
    ShapeWrench calcWrench(int shape) const override {
        const Spring& s = m_springs.at(shape);
        const Eigen::Isometry3d& X = m_pose.at(shape);
        const Eigen::AngleAxisd aa(Eigen::Matrix3d(X.linear() * s.X_ref.linear().transpose()));
        Vec6 d;
        d << aa.angle() * aa.axis(), X.translation() - s.X_ref.translation();
        if (oneSided && d(5) >= 0.0) return ShapeWrench();
        Vec6 W = s.W_ref + s.K * d;
        W(5) += m_error;
        return ShapeWrench::fromVector(W);
    }
    Mat6 calcWrenchTangent(int shape) const override {
        ++tangents;
        if (oneSided &&
            m_pose.at(shape).translation().z() >= m_springs.at(shape).X_ref.translation().z())
            return Mat6::Zero();
        return tangentScale * m_springs.at(shape).K;
    }
    bool isSteady() const override { return steady; }
    Eigen::VectorXd calcContactPressure(int) const override { return Eigen::VectorXd(); }

    int advances = 0;
    int failAt = -1;            // the advance (1-based count) that fails
    mutable int tangents = 0;   // calcWrenchTangent() calls
    double tangentScale = 1.0;  // the tangent reported, as a multiple of the true one
    bool steady = false;        // isSteady()
    bool oneSided = false;      // pushes only below X_ref (z)
    double unresolved = 0.0;    // [N] the force error of a step kept short of equilibrium
    bool reportUnresolved = false;

  private:
    std::vector<Spring> m_springs;
    std::vector<Eigen::Isometry3d> m_pose, m_committed, m_next;
    double m_error = 0.0;
};

}  // namespace cosim::test
