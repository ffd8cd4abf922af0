#include <bags/MembraneModel.h>

#include "SparseSolve.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace bags {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Gradient of the linear shape functions of a triangle in its local 2D reference frame.
struct ShapeGradients {
    Vec2 dN[3];
};

ShapeGradients calcShapeGradients(const Mat2& DmInv) {
    ShapeGradients s;
    s.dN[1] = DmInv.row(0).transpose();
    s.dN[2] = DmInv.row(1).transpose();
    s.dN[0] = -(s.dN[1] + s.dN[2]);
    return s;
}

using Mat32 = Eigen::Matrix<double, 3, 2>;

// Deformation gradient F = sum_a x_a dN_a^T (3 x 2) of triangle e at positions x.
Mat32 calcDeformationGradient(const Eigen::Matrix3Xi& tris, int e, const ShapeGradients& sg,
                              const Eigen::Matrix3Xd& x) {
    Mat32 F = Mat32::Zero();
    for (int a = 0; a < 3; ++a) F += x.col(tris(a, e)) * sg.dN[a].transpose();
    return F;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// MembraneModel

MembraneModel::MembraneModel(Mesh mesh, std::shared_ptr<const MembraneMaterial> material,
                             double thickness)
    : m_mesh(std::move(mesh)), m_material(std::move(material)), m_thickness(thickness) {
    if (!m_material) throw std::invalid_argument("MembraneModel needs a material");
    if (!(thickness > 0.0)) throw std::invalid_argument("membrane thickness must be positive");
    m_mesh.validate();
    precompute();
}

void MembraneModel::setWarpAxes(const Vec3& axis, const Vec3& fallback) {
    if (!(axis.norm() > 0.0) || !(fallback.norm() > 0.0) ||
        !(axis.normalized().cross(fallback.normalized()).norm() > 0.5))
        throw std::invalid_argument(
            "warp axes: give two directions more than 30 degrees apart (the bag's long side and "
            "its height)");
    m_warpAxis = axis.normalized();
    m_warpFallback = fallback.normalized();
    if (!m_material->isIsotropic()) precomputeFrames();
}

std::vector<Vec3> MembraneModel::calcWarpDirections() const {
    // Per panel: its mean normal if it is flat (every reference panel of the bags is; a
    // stated imperfection tilts its triangles a little), the warp axis projected onto that
    // plane, or the fallback's projection where the axis is within 30 degrees of the normal.
    // Then per triangle: that direction projected onto the triangle's own plane.
    const int nt = m_mesh.getNumTris();
    const int np = static_cast<int>(m_mesh.panelNames.size());
    std::vector<Vec3> normalSum(np, Vec3::Zero());
    std::vector<double> areaSum(np, 0.0);
    std::vector<Vec3> triNormal(nt);
    for (int e = 0; e < nt; ++e) {
        const Vec3 X0 = m_mesh.X.col(m_mesh.tris(0, e));
        const Vec3 n = (Vec3(m_mesh.X.col(m_mesh.tris(1, e))) - X0)
                           .cross(Vec3(m_mesh.X.col(m_mesh.tris(2, e))) - X0);
        triNormal[e] = n.normalized();
        const int p = m_mesh.triPanel.empty() ? -1 : m_mesh.triPanel[e];
        if (p >= 0 && p < np) {
            normalSum[p] += n;
            areaSum[p] += n.norm();
        }
    }
    auto inPlane = [&](const Vec3& nHat) {
        Vec3 w = m_warpAxis - m_warpAxis.dot(nHat) * nHat;
        if (w.norm() < 0.5) w = m_warpFallback - m_warpFallback.dot(nHat) * nHat;
        return w;
    };
    std::vector<Vec3> warp(nt);
    for (int e = 0; e < nt; ++e) {
        const int p = m_mesh.triPanel.empty() ? -1 : m_mesh.triPanel[e];
        const bool flat = p >= 0 && p < np && normalSum[p].norm() >= 0.99 * areaSum[p];
        const Vec3 w = inPlane(flat ? Vec3(normalSum[p].normalized()) : triNormal[e]);
        warp[e] = (w - w.dot(triNormal[e]) * triNormal[e]).normalized();
    }
    return warp;
}

void MembraneModel::precompute() {
    precomputeFrames();
    m_chamberGas.assign(m_mesh.chambers.size(), -1);
    m_chamberPressure.assign(m_mesh.chambers.size(), 0.0);

    std::vector<char> fixed(3 * m_mesh.getNumNodes(), 0);
    for (int n : m_mesh.supportNodes)
        for (int d = 0; d < 3; ++d) fixed[3 * n + d] = 1;
    for (int dof : m_mesh.fixedDofs) fixed[dof] = 1;
    m_fixedDofs.clear();
    for (int i = 0; i < static_cast<int>(fixed.size()); ++i)
        if (fixed[i]) m_fixedDofs.push_back(i);
    m_nodalMass = Eigen::VectorXd::Zero(m_mesh.getNumNodes());
    m_nodalArea = m_mesh.calcNodalAreas();
}

void MembraneModel::precomputeFrames() {
    const int nt = m_mesh.getNumTris();
    m_DmInv.resize(nt);
    m_area0.resize(nt);
    // An anisotropic film's element frame has the warp as its first axis; an isotropic one's
    // the first edge (as it always had: its results do not depend on the frame, its bits do).
    std::vector<Vec3> warp;
    if (!m_material->isIsotropic()) warp = calcWarpDirections();
    for (int e = 0; e < nt; ++e) {
        const Vec3 X0 = m_mesh.X.col(m_mesh.tris(0, e));
        const Vec3 X1 = m_mesh.X.col(m_mesh.tris(1, e));
        const Vec3 X2 = m_mesh.X.col(m_mesh.tris(2, e));
        const Vec3 a = X1 - X0, b = X2 - X0;
        const Vec3 n = a.cross(b);
        const double twiceArea = n.norm();
        if (!(twiceArea > 0.0)) {
            throw NumericalError("degenerate reference triangle " + std::to_string(e), -1, -1, e);
        }
        const Vec3 e1 = warp.empty() ? Vec3(a.normalized()) : warp[e];
        const Vec3 e2 = (n / twiceArea).cross(e1);
        Mat2 Dm;
        Dm << a.dot(e1), b.dot(e1), a.dot(e2), b.dot(e2);
        m_DmInv[e] = Dm.inverse();
        m_area0[e] = 0.5 * twiceArea;
    }
}

void MembraneModel::setBendingStiffness(double D) {
    BendingOptions o;
    o.stiffness = D;
    o.validate();
    m_bending = D > 0.0 ? std::make_shared<const DiscreteBending>(m_mesh, o) : nullptr;
}

void MembraneModel::setStabilization(double k, const Eigen::Matrix3Xd& anchor) {
    if (!(k >= 0.0)) throw std::invalid_argument("stabilisation stiffness must be >= 0");
    m_stabilization = k;
    m_anchor = anchor;
    m_stabilizationWeight.clear();
}

void MembraneModel::setStabilization(double k, const Eigen::Matrix3Xd& anchor,
                                     std::vector<double> weight) {
    setStabilization(k, anchor);
    if (!weight.empty() && static_cast<int>(weight.size()) != m_mesh.getNumNodes())
        throw std::invalid_argument("stabilisation weights: one per node");
    m_stabilizationWeight = std::move(weight);
}

double MembraneModel::calcStabilizationEnergy(const Eigen::Matrix3Xd& x) const {
    if (m_stabilization == 0.0) return 0.0;
    double e = 0.0;
    for (int i = 0; i < m_mesh.getNumNodes(); ++i)
        e += 0.5 * m_stabilization * m_nodalArea(i) *
             (m_stabilizationWeight.empty() ? 1.0 : m_stabilizationWeight[i]) *
             (x.col(i) - m_anchor.col(i)).squaredNorm();
    return e;
}

void MembraneModel::setGravity(double density, const Vec3& g) {
    m_density = density;
    m_gravity = g;
    m_nodalMass = m_mesh.calcNodalAreas() * (density * m_thickness);
}

int MembraneModel::addGas(const GasChamber& gas, const std::vector<int>& chambers) {
    if (chambers.empty()) throw std::invalid_argument("a gas must fill at least one chamber");
    for (int c : chambers) {
        if (c < 0 || c >= static_cast<int>(m_mesh.chambers.size()))
            throw std::invalid_argument("gas chamber index out of range");
        if (m_chamberGas[c] >= 0) throw std::invalid_argument("chamber already filled by a gas");
    }
    const int i = static_cast<int>(m_gases.size());
    m_gases.push_back({gas, chambers});
    for (int c : chambers) m_chamberGas[c] = i, m_chamberPressure[c] = 0.0;
    return i;
}

void MembraneModel::setChamberPressure(int chamber, double gaugePressure) {
    if (m_chamberGas.at(chamber) >= 0)
        throw std::invalid_argument("chamber pressure is set by its gas; cannot prescribe it");
    m_chamberPressure[chamber] = gaugePressure;
}

void MembraneModel::addRigidContact(std::shared_ptr<RigidContact> contact) {
    m_contacts.push_back(std::move(contact));
}

bool MembraneModel::isConservative() const {
    for (const auto& c : m_contacts)
        if (!c->isConservative()) return false;
    return true;
}

void MembraneModel::beginContactStep(const Eigen::Matrix3Xd& x, double dt) {
    for (auto& c : m_contacts) c->beginStep(x, dt);
}

void MembraneModel::commitStep(const Eigen::Matrix3Xd& x) {
    for (auto& c : m_contacts) c->commitStep(x);
}

std::vector<RigidContact::History> MembraneModel::getContactHistory() const {
    std::vector<RigidContact::History> h;
    for (const auto& c : m_contacts) h.push_back(c->getHistory());
    return h;
}

void MembraneModel::setContactHistory(const std::vector<RigidContact::History>& h) {
    if (h.size() != m_contacts.size())
        throw std::invalid_argument("MembraneModel::setContactHistory: wrong number of contacts");
    for (size_t i = 0; i < h.size(); ++i) m_contacts[i]->setHistory(h[i]);
}

double MembraneModel::calcGasVolume(int gas, const Eigen::Matrix3Xd& x,
                                    Eigen::VectorXd* grad) const {
    double V = 0.0;
    if (grad) grad->setZero(3 * m_mesh.getNumNodes());
    for (int c : m_gases[gas].chambers) {
        V += calcChamberVolume(m_mesh, c, x);
        if (grad) *grad += calcChamberVolumeGradient(m_mesh, c, x);
    }
    return V;
}

double MembraneModel::calcChamberGaugePressure(int c, const Eigen::Matrix3Xd& x) const {
    const int g = m_chamberGas.at(c);
    if (g < 0) return m_chamberPressure[c];
    return m_gases[g].gas.calcGaugePressure(calcGasVolume(g, x, nullptr));
}

void MembraneModel::addMembraneEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    const int nt = m_mesh.getNumTris();
    const MembraneMaterial& mat = *m_material;
    const bool wantG = acc.wantGradient, wantH = acc.wantHessian;
    bool invalid = false;
    int badElement = -1;

    // The elements are cut into a number of chunks that depends only on the mesh (one below
    // 4000 triangles); each chunk sums its energy and gradient on its own, and the chunks are
    // merged in chunk order, so the roundoff is the same for any number of threads. Every
    // element writes its 81 Hessian triplets at a fixed place: the triplet sequence is the
    // same on every call (the solver reuses its scatter map).
    const int nchunks =
        m_elementChunks > 0 ? std::min(m_elementChunks, std::max(1, nt)) : (nt > 4000 ? 16 : 1);
    std::vector<double> chunkEnergy(nchunks, 0.0);
    std::vector<Eigen::VectorXd> chunkGrad(nchunks > 1 && wantG ? nchunks : 0);
    const size_t hessBase = acc.hess.size();
    if (wantH) acc.hess.resize(hessBase + static_cast<size_t>(81) * nt);
#ifdef _OPENMP
    const int nthreads = std::min(nchunks, m_threads > 0 ? m_threads : omp_get_max_threads());
#else
    const int nthreads = 1;
#endif
#pragma omp parallel for schedule(dynamic, 1) num_threads(nthreads) if (nthreads > 1)
    for (int chunk = 0; chunk < nchunks; ++chunk) {
        Eigen::VectorXd* localG = &acc.grad;
        if (nchunks > 1 && wantG) {
            chunkGrad[chunk].setZero(acc.grad.size());
            localG = &chunkGrad[chunk];
        }
        double energy = 0.0;
        const int e0 = static_cast<int>(static_cast<long>(nt) * chunk / nchunks);
        const int e1 = static_cast<int>(static_cast<long>(nt) * (chunk + 1) / nchunks);
        for (int e = e0; e < e1; ++e) {
            const int n[3] = {m_mesh.tris(0, e), m_mesh.tris(1, e), m_mesh.tris(2, e)};
            const ShapeGradients sg = calcShapeGradients(m_DmInv[e]);
            const Mat32 F = calcDeformationGradient(m_mesh.tris, e, sg, x);
            const Mat2 C = F.transpose() * F;
            // A collapsed element (or a viscous branch that cannot be evaluated): recorded,
            // its Hessian slots zeroed, the element skipped.
            auto markInvalid = [&] {
#pragma omp critical
                {
                    if (!invalid || e < badElement) badElement = e;
                    invalid = true;
                }
                if (wantH)
                    std::fill(acc.hess.begin() + hessBase + 81 * static_cast<size_t>(e),
                              acc.hess.begin() + hessBase + 81 * static_cast<size_t>(e + 1),
                              Triplet(0, 0, 0.0));
            };
            if (!(C.determinant() > 1e-12)) {
                markInvalid();
                continue;
            }
            Eigen::Vector3d S;
            Eigen::Matrix3d D;
            const double vol = m_area0[e] * m_thickness;
            double w = mat.calcEnergy(C, wantG || wantH ? &S : nullptr, wantH ? &D : nullptr);
            if (m_viscous &&
                !addBranches(e, C, &w, wantG || wantH ? &S : nullptr, wantH ? &D : nullptr)) {
                markInvalid();
                continue;
            }
            energy += vol * w;
            if (!wantG && !wantH) continue;
            Mat2 Sm;
            Sm << S(0), S(2), S(2), S(1);
            const Vec3 f1 = F.col(0), f2 = F.col(1);
            if (wantG) {
                const Mat32 P = F * Sm;
                for (int a = 0; a < 3; ++a) localG->segment<3>(3 * n[a]) += vol * (P * sg.dN[a]);
            }
            if (wantH) {
                Triplet* out = acc.hess.data() + hessBase + 81 * static_cast<size_t>(e);
                Eigen::Matrix3d B[3];  // dE_v / dx_a
                for (int a = 0; a < 3; ++a) {
                    const Vec2& g = sg.dN[a];
                    B[a].row(0) = g(0) * f1.transpose();
                    B[a].row(1) = g(1) * f2.transpose();
                    B[a].row(2) = g(1) * f1.transpose() + g(0) * f2.transpose();
                }
                for (int a = 0; a < 3; ++a) {
                    const Eigen::Matrix3d DB = D * B[a];
                    for (int b = 0; b < 3; ++b) {
                        Mat3 K = B[b].transpose() * DB;  // (b,a) block
                        K.diagonal().array() += sg.dN[b].dot(Sm * sg.dN[a]);
                        K *= vol;
                        for (int i = 0; i < 3; ++i)
                            for (int j = 0; j < 3; ++j)
                                *out++ = Triplet(3 * n[b] + i, 3 * n[a] + j, K(i, j));
                    }
                }
            }
        }
        chunkEnergy[chunk] = energy;
    }
    double energy = 0.0;
    for (int c = 0; c < nchunks; ++c) {
        energy += chunkEnergy[c];
        if (nchunks > 1 && wantG) acc.grad += chunkGrad[c];
    }
    if (invalid) {
        acc.energy = kInf;
        if (wantG || wantH)
            throw NumericalError(
                "membrane element " + std::to_string(badElement) + " collapsed (det C <= 0)", -1,
                -1, badElement);
        return;
    }
    acc.energy += energy;
    if (m_bending) {
        acc.wideBegin = acc.hess.size();
        // The hinges share the elements' threads: none below the size at which the elements
        // are chunked (a small bag's parallel region costs more than it saves, and where other
        // processes hold the cores its threads wait on each other many times over: the taut
        // tiny rig's load test 0.5 -> 2.4 s on two loaded cores).
        m_bending->addEnergy(x, acc, nthreads);
        acc.wideEnd = acc.hess.size();
    }
}

void MembraneModel::addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    addMembraneEnergy(x, acc);
    if (!std::isfinite(acc.energy)) return;
    addLoadEnergy(x, acc);
}

void MembraneModel::addLoadEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    // Prescribed follower pressures: -p V_c.
    for (size_t c = 0; c < m_mesh.chambers.size(); ++c)
        if (m_chamberGas[c] < 0 && m_chamberPressure[c] != 0.0)
            calcChamberVolume(m_mesh, static_cast<int>(c), x, &acc, -m_chamberPressure[c]);
    // Gases: -G(V); gradient -(p - pa) dV; sparse Hessian -(p - pa) d2V. The dense rank-one
    // part -(dp/dV) g g^T is left to the solver (calcGasRankOne).
    for (const GasBody& gb : m_gases) {
        double V = 0.0;
        for (int c : gb.chambers) V += calcChamberVolume(m_mesh, c, x);
        if (!(V > 0.0)) {
            acc.energy = kInf;
            if (acc.wantGradient) throw NumericalError("gas volume became non-positive");
            return;
        }
        const double pg = gb.gas.calcGaugePressure(V);
        acc.energy -= gb.gas.calcWorkPotential(V);
        if (acc.wantGradient || acc.wantHessian) {
            // Add -pg * (dV, d2V); the energy part -pg*V is taken back out.
            const double e0 = acc.energy;
            for (int c : gb.chambers) calcChamberVolume(m_mesh, c, x, &acc, -pg);
            acc.energy = e0;
        }
    }
    // Gravity: -m g . x
    if (m_density > 0.0 && m_gravity.squaredNorm() > 0.0) {
        for (int i = 0; i < m_mesh.getNumNodes(); ++i) {
            acc.energy -= m_nodalMass(i) * m_gravity.dot(x.col(i));
            if (acc.wantGradient) acc.grad.segment<3>(3 * i) -= m_nodalMass(i) * m_gravity;
        }
    }
    for (const auto& c : m_contacts) c->addEnergy(x, acc);
    if (m_selfContact) m_selfContact->addEnergy(x, acc);
    if (m_stabilization > 0.0) {
        for (int i = 0; i < m_mesh.getNumNodes(); ++i) {
            const double k = m_stabilization * m_nodalArea(i) *
                             (m_stabilizationWeight.empty() ? 1.0 : m_stabilizationWeight[i]);
            if (k == 0.0) continue;
            const Vec3 d = x.col(i) - m_anchor.col(i);
            acc.energy += 0.5 * k * d.squaredNorm();
            if (acc.wantGradient) acc.grad.segment<3>(3 * i) += k * d;
            if (acc.wantHessian)
                for (int j = 0; j < 3; ++j) acc.hess.emplace_back(3 * i + j, 3 * i + j, k);
        }
    }
}

std::vector<int> MembraneModel::calcWrinkleStates(const Eigen::Matrix3Xd& x) const {
    std::vector<int> states(m_mesh.getNumTris(), 0);
    const auto* w = dynamic_cast<const WrinklingMaterial*>(m_material.get());
    if (const auto* fabric = dynamic_cast<const FabricMaterial*>(m_material.get()))
        w = dynamic_cast<const WrinklingMaterial*>(&fabric->getMatrix());  // the matrix's state
    if (!w) return states;
    for (int e = 0; e < m_mesh.getNumTris(); ++e) {
        const ShapeGradients sg = calcShapeGradients(m_DmInv[e]);
        const Mat32 F = calcDeformationGradient(m_mesh.tris, e, sg, x);
        states[e] = w->calcState(F.transpose() * F);
    }
    return states;
}

Eigen::VectorXd MembraneModel::calcPrincipalStress(const Eigen::Matrix3Xd& x) const {
    Eigen::VectorXd s(m_mesh.getNumTris());
    for (int e = 0; e < m_mesh.getNumTris(); ++e) {
        const ShapeGradients sg = calcShapeGradients(m_DmInv[e]);
        const Mat32 F = calcDeformationGradient(m_mesh.tris, e, sg, x);
        const Mat2 C = F.transpose() * F;
        const Eigen::Vector3d S = calcElementStress(x, e);
        Mat2 Sm;
        Sm << S(0), S(2), S(2), S(1);
        // Cauchy stress in the deformed plane: sigma = J^-1 F S F^T with J = 1 (incompressible):
        // in-plane sigma has the eigenvalues of S C (similar matrix).
        const Mat2 SC = Sm * C;
        Eigen::EigenSolver<Mat2> es(SC);
        s(e) = es.eigenvalues().real().maxCoeff();
    }
    return s;
}

// ---------------------------------------------------------------------------------------------
// Viscoelasticity (bags/Viscoelastic.h): one Maxwell branch per Prony term and element

namespace {

// Green strain [E11, E22, E12] (tensor components) of an in-plane C.
Eigen::Vector3d calcGreenStrain(const Mat2& C) {
    return Eigen::Vector3d(0.5 * (C(0, 0) - 1.0), 0.5 * (C(1, 1) - 1.0), 0.5 * C(0, 1));
}

}  // namespace

Mat2 MembraneModel::calcElementC(const Eigen::Matrix3Xd& x, int e) const {
    const ShapeGradients sg = calcShapeGradients(m_DmInv[e]);
    const Mat32 F = calcDeformationGradient(m_mesh.tris, e, sg, x);
    return F.transpose() * F;
}

bool MembraneModel::addBranches(int e, const Mat2& C, double* W, Eigen::Vector3d* S,
                                Eigen::Matrix3d* D) const {
    const int nt = m_mesh.getNumTris();
    const Eigen::Vector3d E = calcGreenStrain(C);
    for (size_t i = 0; i < m_viscousPhi.size(); ++i) {
        const double phi = m_viscousPhi[i];
        if (!(phi > 0.0)) continue;  // no branch (g = 0) or a quasi-static step
        // The branch's elastic strain at the end of the step, linear in E: q = phi E + c. Its
        // energy (k / phi) W_L(I + 2 q) has the stress k S_L(I + 2 q) and the tangent
        // k phi D_L(I + 2 q) (dq/dE = phi).
        const Eigen::Vector3d q = phi * E + m_viscousOffset.col(int(i) * nt + e);
        Mat2 Cb;
        Cb << 1.0 + 2.0 * q(0), 2.0 * q(2), 2.0 * q(2), 1.0 + 2.0 * q(1);
        if (!(Cb.determinant() > 1e-12)) return false;
        Eigen::Vector3d Sb;
        Eigen::Matrix3d Db;
        const double wb = m_material->calcEnergy(Cb, S ? &Sb : nullptr, D ? &Db : nullptr);
        const double weight = m_viscousWeight[i];  // k / phi
        *W += weight * wb;
        if (S) *S += weight * phi * Sb;
        if (D) *D += weight * phi * phi * Db;
    }
    return true;
}

void MembraneModel::setProny(const PronySeries& prony) {
    prony.validate();
    m_prony = prony;
    m_viscous = prony.isOn();
    m_viscousState = ViscousState();
    m_viscousOffset.resize(3, 0);
    m_viscousPhi.clear();
    m_viscousWeight.clear();
    m_viscousStepTime = std::numeric_limits<double>::infinity();
    if (m_viscous) resetViscousState(m_mesh.X);
}

void MembraneModel::setViscousStep(double dt) {
    const double ginf = m_prony.getLongTermFraction();
    m_viscousStepTime = dt;
    m_viscousPhi.assign(m_prony.terms.size(), 0.0);
    m_viscousWeight.assign(m_prony.terms.size(), 0.0);
    for (size_t i = 0; i < m_prony.terms.size(); ++i) {
        const PronyTerm& t = m_prony.terms[i];
        if (!(t.g > 0.0)) continue;
        m_viscousPhi[i] = calcPronyPhi(dt / t.tau);
        if (m_viscousPhi[i] > 0.0) m_viscousWeight[i] = t.g / ginf / m_viscousPhi[i];
    }
}

void MembraneModel::resetViscousState(const Eigen::Matrix3Xd& x) {
    if (!m_viscous) return;
    const int nt = m_mesh.getNumTris();
    ViscousState s;
    s.branchStrain = Eigen::Matrix3Xd::Zero(3, nt * static_cast<int>(m_prony.terms.size()));
    s.strain.resize(3, nt);
    for (int e = 0; e < nt; ++e) s.strain.col(e) = calcGreenStrain(calcElementC(x, e));
    setViscousState(s);
}

void MembraneModel::setViscousState(const ViscousState& state) {
    if (!m_viscous) return;
    const int nt = m_mesh.getNumTris();
    const int nk = static_cast<int>(m_prony.terms.size());
    if (state.branchStrain.cols() != nt * nk || state.strain.cols() != nt)
        throw std::invalid_argument(
            "MembraneModel::setViscousState: the state is of another "
            "mesh or Prony series");
    m_viscousState = state;
    // The potential of the step that ended here: q_i(C) = phi_i E(C) + c gives q_i at the
    // state's own strain, c = q_i - phi_i E.
    setViscousStep(state.stepTime);
    m_viscousOffset.resize(3, nt * nk);
    for (int i = 0; i < nk; ++i)
        m_viscousOffset.middleCols(i * nt, nt) =
            state.branchStrain.middleCols(i * nt, nt) - m_viscousPhi[i] * state.strain;
}

void MembraneModel::beginViscousStep(double dt) {
    if (!m_viscous) return;
    if (!(dt >= 0.0)) throw std::invalid_argument("MembraneModel::beginViscousStep: dt < 0");
    const int nt = m_mesh.getNumTris();
    const int nk = static_cast<int>(m_prony.terms.size());
    setViscousStep(dt);
    // Over the step the branch's strain q obeys dq/dt = dE/dt - q / tau; with E linear in
    // time, q(end) = exp(-dt / tau) q(n) + phi (E(end) - E(n)) exactly.
    m_viscousOffset.resize(3, nt * nk);
    for (int i = 0; i < nk; ++i) {
        const double decay = m_viscousPhi[i] > 0.0 ? std::exp(-dt / m_prony.terms[i].tau) : 0.0;
        m_viscousOffset.middleCols(i * nt, nt) =
            decay * m_viscousState.branchStrain.middleCols(i * nt, nt) -
            m_viscousPhi[i] * m_viscousState.strain;
    }
}

void MembraneModel::endViscousStep(const Eigen::Matrix3Xd& x) {
    if (!m_viscous) return;
    const int nt = m_mesh.getNumTris();
    const int nk = static_cast<int>(m_prony.terms.size());
    ViscousState& s = m_viscousState;
    for (int e = 0; e < nt; ++e) {
        const Eigen::Vector3d E = calcGreenStrain(calcElementC(x, e));
        for (int i = 0; i < nk; ++i)
            s.branchStrain.col(i * nt + e) = m_viscousPhi[i] * E + m_viscousOffset.col(i * nt + e);
        s.strain.col(e) = E;
    }
    s.stepTime = m_viscousStepTime;
}

bool MembraneModel::isViscouslyRelaxed() const {
    return !m_viscous || (m_viscousState.branchStrain.array() == 0.0).all();
}

Eigen::Vector3d MembraneModel::calcElementStress(const Eigen::Matrix3Xd& x, int e) const {
    const Mat2 C = calcElementC(x, e);
    Eigen::Vector3d S;
    double w = m_material->calcEnergy(C, &S, nullptr);
    if (m_viscous && !addBranches(e, C, &w, &S, nullptr))
        throw NumericalError(
            "membrane element " + std::to_string(e) + ": a viscous branch collapsed (det <= 0)", -1,
            -1, e);
    return S;
}

}  // namespace bags
