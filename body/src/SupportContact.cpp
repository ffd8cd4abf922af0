// Elastic-foundation contact of the body shapes with a flat rigid support (see SupportContact.h).
#include "body/SupportContact.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace body {

void PlaneSupportOptions::validate() const {
    auto check = [](bool ok, const char* what) {
        if (!ok) throw std::invalid_argument(std::string("PlaneSupportOptions.") + what);
    };
    check(std::isfinite(height), "height must be finite [m]");
    check(stiffness > 0 && std::isfinite(stiffness), "stiffness must be > 0 [Pa/m]");
    check(damping >= 0 && std::isfinite(damping), "damping must be >= 0 [Pa s/m]");
    check(friction >= 0 && std::isfinite(friction), "friction must be >= 0");
    check(slipVelocity > 0 && std::isfinite(slipVelocity), "slipVelocity must be > 0 [m/s]");
    check(sampleSpacing > 0.001 && sampleSpacing < 0.1, "sampleSpacing must be in (1, 100) mm");
    check(stickDistance > 0 && std::isfinite(stickDistance), "stickDistance must be > 0 [m]");
    check(frictionLaw != SupportFrictionLaw::StickSlip || friction == 0 || damping > 0,
          "the stick-slip law needs damping > 0 (its tangential time constant is "
          "damping / stiffness)");
}

PlaneSupport::PlaneSupport(const BodyModel& model, const PlaneSupportOptions& options)
    : m_model(model), m_options(options), m_forces(model.getForces()) {
    options.validate();
    // The patches are made mirror-symmetric about the sagittal plane (body Z = 0 for midline
    // segments, left = mirrored right), so that a symmetric posture stays symmetric.
    auto mirror = [](SurfaceSample s) {
        s.p_B[2] = -s.p_B[2];
        s.n_B[2] = -s.n_B[2];
        return s;
    };
    for (int i = 0; i < kSegmentCount; ++i) {
        const Segment seg = static_cast<Segment>(i);
        const Side side = getSegmentSide(seg);
        std::vector<SurfaceSample> samples;
        if (side == Side::Centre) {
            for (const SurfaceSample& s :
                 model.getContactShape(seg).calcSurfaceSamples(options.sampleSpacing)) {
                if (s.p_B[2] > 0) {
                    samples.push_back(s);
                    samples.push_back(mirror(s));
                } else if (s.p_B[2] == 0) {
                    samples.push_back(s);
                }
            }
        } else {
            // The right segment's samples, mirrored for the left one (segments are in
            // right-left pairs: the left counterpart has the same shape mirrored).
            const Segment right = side == Side::Right ? seg : getMirrorSegment(seg);
            samples = model.getContactShape(right).calcSurfaceSamples(options.sampleSpacing);
            if (side == Side::Left)
                for (SurfaceSample& s : samples) s = mirror(s);
        }
        m_firstPatch[i] = m_patchCount;
        for (const SurfaceSample& s : samples)
            m_patches[i].push_back({s.p_B, s.n_B, s.area, model.findRegion(seg, s.p_B)});
        m_patchCount += static_cast<int>(m_patches[i].size());
        SimTK::Vec3 lo(0), hi(0);
        if (!m_patches[i].empty()) lo = hi = m_patches[i].front().p_B;
        for (const Patch& p : m_patches[i])
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], p.p_B[k]);
                hi[k] = std::max(hi[k], p.p_B[k]);
            }
        m_boxCentre[i] = 0.5 * (lo + hi);
        m_boxHalf[i] = 0.5 * (hi - lo);
    }
}

bool PlaneSupport::isClearOfSupport(int i, const SimTK::Transform& X_GB) const {
    if (m_patches[i].empty()) return true;
    // Lowest point of the rotated box: its centre's height less the extents projected on Z.
    const SimTK::Mat33& R = X_GB.R().asMat33();
    double reach = 0;
    for (int k = 0; k < 3; ++k) reach += std::abs(R(2, k)) * m_boxHalf[i][k];
    return (X_GB * m_boxCentre[i])[2] - reach > m_options.height;
}

int PlaneSupport::getPatchCount() const { return m_patchCount; }

void PlaneSupport::realizeTopology(SimTK::State& state) const {
    if (m_options.frictionLaw != SupportFrictionLaw::StickSlip) return;
    // The anchors invalidate the forces (Dynamics); their update follows the positions and
    // velocities (Velocity). The integrator swaps the update in after every accepted step.
    m_anchorsIndex = m_forces.allocateAutoUpdateDiscreteVariable(
        state, SimTK::Stage::Dynamics, new SimTK::Value<Anchors>(), SimTK::Stage::Velocity);
}

std::vector<double> PlaneSupport::getAnchors(const SimTK::State& state) const {
    std::vector<double> out;
    if (!m_anchorsIndex.isValid()) return out;
    const Anchors& an =
        SimTK::Value<Anchors>::downcast(m_forces.getDiscreteVariable(state, m_anchorsIndex));
    out.reserve(3 * an.a.size());
    for (std::size_t i = 0; i < an.a.size(); ++i)
        out.insert(out.end(), {double(an.patch[i]), an.a[i][0], an.a[i][1]});
    return out;
}

void PlaneSupport::setAnchors(SimTK::State& state, const std::vector<double>& anchors) const {
    auto fail = [&](const std::string& why) {
        throw std::invalid_argument("PlaneSupport::setAnchors: " + why +
                                    "; valid: (patch index, x, y) triples, patches ascending "
                                    "in [0, " +
                                    std::to_string(m_patchCount) + ")");
    };
    if (!m_anchorsIndex.isValid()) {
        if (!anchors.empty()) fail("anchors given to a support without the stick-slip law");
        return;
    }
    if (anchors.size() % 3 != 0) fail(std::to_string(anchors.size()) + " values");
    Anchors an;
    for (std::size_t i = 0; i < anchors.size(); i += 3) {
        const double k = anchors[i];
        if (!(k >= 0 && k < m_patchCount && k == std::floor(k)) ||
            (!an.patch.empty() && int(k) <= an.patch.back()) || !std::isfinite(anchors[i + 1]) ||
            !std::isfinite(anchors[i + 2]))
            fail("triple " + std::to_string(i / 3) + " does not fit");
        an.patch.push_back(int(k));
        an.a.emplace_back(anchors[i + 1], anchors[i + 2]);
    }
    SimTK::Value<Anchors>::updDowncast(m_forces.updDiscreteVariable(state, m_anchorsIndex)).upd() =
        std::move(an);
}

std::array<int, 2> PlaneSupport::countSlidingPatches(const SimTK::State& state) const {
    std::array<int, 2> n{0, 0};  // sliding, in contact
    if (!m_anchorsIndex.isValid()) return n;
    const PlaneSupportOptions& o = m_options;
    forEachContact(state, [&](int, int, const Patch&, const SimTK::Vec3&, const SimTK::Vec3& F,
                              double, double, const SimTK::Vec2&) {
        ++n[1];
        if (std::hypot(F[0], F[1]) >= o.friction * F[2] * (1 - 1e-12) && F[2] > 0) ++n[0];
    });
    return n;
}

template <class Visit>
void PlaneSupport::forEachContact(const SimTK::State& state, Visit&& visit) const {
    const PlaneSupportOptions& o = m_options;
    const bool stick = m_anchorsIndex.isValid();
    const Anchors* anchors =
        stick
            ? &SimTK::Value<Anchors>::downcast(m_forces.getDiscreteVariable(state, m_anchorsIndex))
                   .get()
            : nullptr;
    std::size_t cursor = 0;  // into anchors: the patches come in ascending index
    const double tau = o.damping / o.stiffness;
    const SimTK::Vec2 none(SimTK::NaN);
    for (int i = 0; i < kSegmentCount; ++i) {
        const Segment seg = static_cast<Segment>(i);
        const SimTK::MobilizedBody& mb = m_model.getMobilizedBody(seg);
        const SimTK::Transform& X_GB = mb.getBodyTransform(state);
        if (isClearOfSupport(i, X_GB)) continue;  // broad phase
        const SimTK::SpatialVec& V_GB = mb.getBodyVelocity(state);
        for (int j = 0; j < int(m_patches[i].size()); ++j) {
            const Patch& p = m_patches[i][j];
            const SimTK::Vec3 r_G = X_GB.R() * p.p_B;
            const SimTK::Vec3 p_G = X_GB.p() + r_G;
            const double delta = o.height - p_G[2];
            if (delta <= 0) continue;
            const double nz = (X_GB.R() * p.n_B)[2];
            if (nz >= 0) continue;  // patch faces away from the support
            const double aProj = -nz * p.area;
            const SimTK::Vec3 v = V_GB[1] + V_GB[0] % r_G;
            const double pressure = o.stiffness * delta - o.damping * v[2];
            if (pressure <= 0) continue;
            const double fn = pressure * aProj;
            const int k = m_firstPatch[i] + j;
            if (!stick) {
                const double vt =
                    std::sqrt(v[0] * v[0] + v[1] * v[1] + o.slipVelocity * o.slipVelocity);
                const SimTK::Vec3 F(-o.friction * fn * v[0] / vt, -o.friction * fn * v[1] / vt, fn);
                visit(i, k, p, r_G, F, pressure, aProj, none);
                continue;
            }
            // The stick spring: s = u + tau v_t, f_t = -mu f_n s / max(|s|, d_s); the anchor
            // after the step keeps the same force (|s| = d_s when sliding).
            const SimTK::Vec2 x(p_G[0], p_G[1]), vt(v[0], v[1]);
            const std::vector<int>& anchored = anchors->patch;
            while (cursor < anchored.size() && anchored[cursor] < k) ++cursor;
            const SimTK::Vec2& a =
                cursor < anchored.size() && anchored[cursor] == k ? anchors->a[cursor] : none;
            const SimTK::Vec2 u = std::isnan(a[0]) ? SimTK::Vec2(0) : x - a;
            const SimTK::Vec2 sv = u + tau * vt;
            const double ns = sv.norm();
            const double scale = o.friction * fn / std::max(ns, o.stickDistance);
            const SimTK::Vec3 F(-scale * sv[0], -scale * sv[1], fn);
            const SimTK::Vec2 next = ns > o.stickDistance
                                         ? SimTK::Vec2(x - (o.stickDistance / ns) * sv + tau * vt)
                                     : std::isnan(a[0]) ? x
                                                        : a;
            visit(i, k, p, r_G, F, pressure, aProj, next);
        }
    }
}

void PlaneSupport::calcForce(const SimTK::State& state,
                             SimTK::Vector_<SimTK::SpatialVec>& bodyForces,
                             SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector&) const {
    Anchors* next = nullptr;
    if (m_anchorsIndex.isValid()) {
        next = &SimTK::Value<Anchors>::updDowncast(
                    m_forces.updDiscreteVarUpdateValue(state, m_anchorsIndex))
                    .upd();
        next->patch.clear();
        next->a.clear();
    }
    forEachContact(state, [&](int i, int k, const Patch&, const SimTK::Vec3& r_G,
                              const SimTK::Vec3& F, double, double, const SimTK::Vec2& a) {
        const SimTK::MobilizedBodyIndex mbx =
            m_model.getMobilizedBodyIndex(static_cast<Segment>(i));
        bodyForces[mbx][0] += r_G % F;
        bodyForces[mbx][1] += F;
        if (next) {
            next->patch.push_back(k);
            next->a.push_back(a);
        }
    });
    if (next) m_forces.markDiscreteVarUpdateValueRealized(state, m_anchorsIndex);
}

SimTK::Real PlaneSupport::calcPotentialEnergy(const SimTK::State& state) const {
    double e = 0;
    const PlaneSupportOptions& o = m_options;
    for (int i = 0; i < kSegmentCount; ++i) {
        const SimTK::Transform& X_GB =
            m_model.getMobilizedBody(static_cast<Segment>(i)).getBodyTransform(state);
        if (isClearOfSupport(i, X_GB)) continue;
        for (const Patch& p : m_patches[i]) {
            const double delta = o.height - (X_GB * p.p_B)[2];
            const double nz = (X_GB.R() * p.n_B)[2];
            if (delta > 0 && nz < 0) e += 0.5 * o.stiffness * delta * delta * (-nz * p.area);
        }
    }
    return e;
}

SupportLoad PlaneSupport::calcSupportLoad(const SimTK::State& state) const {
    SupportLoad load;
    const int nRegions = static_cast<int>(m_model.getRegions().size());
    load.regionForce.assign(nRegions, 0.0);
    load.regionPeakPressure.assign(nRegions, 0.0);
    forEachContact(state, [&](int i, int, const Patch& p, const SimTK::Vec3&, const SimTK::Vec3& F,
                              double pressure, double aProj, const SimTK::Vec2&) {
        load.force += F;
        load.contactArea += aProj;
        load.peakPressure = std::max(load.peakPressure, pressure);
        load.segmentForce[i] += F[2];
        if (p.region >= 0) {
            load.regionForce[p.region] += F[2];
            load.regionPeakPressure[p.region] =
                std::max(load.regionPeakPressure[p.region], pressure);
        } else {
            load.otherForce += F[2];
        }
    });
    return load;
}

const PlaneSupport& addPlaneSupport(BodyModel& model, const PlaneSupportOptions& options) {
    auto* impl = new PlaneSupport(model, options);
    SimTK::Force::Custom(model.updForces(), impl);
    return *impl;
}

}  // namespace body
