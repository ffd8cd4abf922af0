// Assembly of the Simbody patient model (see BodyModel.h).
#include "body/BodyModel.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace body {

void BodyModelOptions::validate() const {
    if (!(jointDampingScale >= 0) || !std::isfinite(jointDampingScale))
        throw std::invalid_argument("BodyModelOptions.jointDampingScale must be >= 0");
    if (!(gravity >= 0) || !std::isfinite(gravity))
        throw std::invalid_argument("BodyModelOptions.gravity must be >= 0 [m/s^2]");
}

struct BodyModel::Impl {
    PatientSpec spec;
    BodyModelOptions options;
    Anthropometry anthropometry;
    SimTK::MultibodySystem system;
    SimTK::SimbodyMatterSubsystem matter{system};
    SimTK::GeneralForceSubsystem forces{system};
    std::array<SimTK::MobilizedBodyIndex, kSegmentCount> mobod;
    std::vector<ContactShape> shapes;
    std::vector<BodyRegion> regions;
    std::vector<JointSpec> joints;
};

BodyModel::BodyModel(const PatientSpec& spec, const BodyModelOptions& options)
    : m_impl(std::make_unique<Impl>()) {
    spec.validate();
    options.validate();
    Impl& m = *m_impl;
    m.spec = spec;
    m.options = options;
    m.anthropometry = calcAnthropometry(spec.sex, spec.height, spec.mass);
    m.joints = makeJointSpecs(m.anthropometry);
    const Anthropometry& a = m.anthropometry;

    std::vector<PassiveJointForce::Entry> entries;
    for (int i = 0; i < kSegmentCount; ++i) {
        const Segment seg = static_cast<Segment>(i);
        const SegmentParameters& p = a.get(seg);
        const SimTK::Inertia I_C(p.inertiaC[0], p.inertiaC[1], p.inertiaC[2]);
        const SimTK::Body::Rigid bodyInfo(
            SimTK::MassProperties(p.mass, p.p_BC, I_C.shiftFromMassCenter(p.p_BC, p.mass)));
        if (seg == Segment::LowerTrunk) {
            SimTK::MobilizedBody::Free root(m.matter.Ground(), SimTK::Transform(), bodyInfo,
                                            SimTK::Transform());
            m.mobod[i] = root.getMobilizedBodyIndex();
        } else {
            const JointSpec* joint = nullptr;
            for (const JointSpec& j : m.joints)
                if (j.child == seg) joint = &j;
            if (!joint) throw std::logic_error("body: segment without a joint");
            SimTK::MobilizedBody& parent =
                m.matter.updMobilizedBody(m.mobod[static_cast<int>(joint->parent)]);
            const SimTK::Transform X_PF(SimTK::Rotation(), p.p_WO - a.get(joint->parent).p_WO);
            if (joint->type == JointType::Ball) {
                SimTK::MobilizedBody::Ball b(parent, X_PF, bodyInfo, SimTK::Transform());
                m.mobod[i] = b.getMobilizedBodyIndex();
            } else {
                SimTK::MobilizedBody::Pin b(parent, X_PF, bodyInfo, SimTK::Transform());
                m.mobod[i] = b.getMobilizedBodyIndex();
            }
            entries.push_back({*joint, m.mobod[static_cast<int>(joint->parent)], m.mobod[i]});
        }
        const ShapeSize& sh = p.shape;
        m.shapes.push_back(
            sh.kind == ShapeKind::Ellipsoid
                ? ContactShape::makeEllipsoid(sh.semiAxes, sh.centre)
                : ContactShape::makeRoundCone(sh.pointA, sh.radiusA, sh.pointB, sh.radiusB));
    }
    m.regions = makeBodyRegions(a);
    SimTK::Force::Gravity(m.forces, m.matter, SimTK::UnitVec3(0, 0, -1), options.gravity);
    if (options.passiveJoints)
        SimTK::Force::Custom(m.forces, new PassiveJointForce(m.matter, std::move(entries),
                                                             options.jointDampingScale));
}

BodyModel::~BodyModel() = default;

const PatientSpec& BodyModel::getSpec() const { return m_impl->spec; }
const Anthropometry& BodyModel::getAnthropometry() const { return m_impl->anthropometry; }
SimTK::MultibodySystem& BodyModel::updSystem() { return m_impl->system; }
const SimTK::MultibodySystem& BodyModel::getSystem() const { return m_impl->system; }
SimTK::SimbodyMatterSubsystem& BodyModel::updMatter() { return m_impl->matter; }
const SimTK::SimbodyMatterSubsystem& BodyModel::getMatter() const { return m_impl->matter; }
SimTK::GeneralForceSubsystem& BodyModel::updForces() { return m_impl->forces; }
const SimTK::GeneralForceSubsystem& BodyModel::getForces() const { return m_impl->forces; }

SimTK::MobilizedBodyIndex BodyModel::getMobilizedBodyIndex(Segment s) const {
    return m_impl->mobod[static_cast<int>(s)];
}
const SimTK::MobilizedBody& BodyModel::getMobilizedBody(Segment s) const {
    return m_impl->matter.getMobilizedBody(getMobilizedBodyIndex(s));
}
int BodyModel::findSegment(SimTK::MobilizedBodyIndex index) const {
    for (int i = 0; i < kSegmentCount; ++i)
        if (m_impl->mobod[i] == index) return i;
    return -1;
}
const ContactShape& BodyModel::getContactShape(Segment s) const {
    return m_impl->shapes[static_cast<int>(s)];
}
const std::vector<BodyRegion>& BodyModel::getRegions() const { return m_impl->regions; }
int BodyModel::findRegion(Segment segment, const SimTK::Vec3& p_B) const {
    return findBodyRegion(m_impl->regions, m_impl->anthropometry, segment, p_B);
}
const std::vector<JointSpec>& BodyModel::getJoints() const { return m_impl->joints; }

double BodyModel::calcTotalMass() const {
    double sum = 0;
    for (int i = 0; i < kSegmentCount; ++i)
        sum += getMobilizedBody(static_cast<Segment>(i)).getDefaultMassProperties().getMass();
    return sum;
}

double BodyModel::calcLowestPointHeight(const SimTK::State& state) const {
    double zMin = SimTK::Infinity;
    for (int i = 0; i < kSegmentCount; ++i) {
        const Segment seg = static_cast<Segment>(i);
        const SimTK::Transform& X_GB = getMobilizedBody(seg).getBodyTransform(state);
        const SimTK::Vec3 d_B = ~X_GB.R() * SimTK::Vec3(0, 0, -1);
        const SimTK::Vec3 p_G = X_GB * getContactShape(seg).calcSupportPoint(d_B);
        zMin = std::min(zMin, p_G[2]);
    }
    return zMin;
}

}  // namespace body
