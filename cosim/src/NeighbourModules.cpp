#include "cosim/NeighbourModules.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace cosim {

namespace {

using V3 = Eigen::Vector3d;

// Solid angle [sr] of triangle (a, b, c) seen from the origin, signed by its orientation
// (Van Oosterom and Strackee 1983).
double solidAngle(const V3& a, const V3& b, const V3& c) {
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    return 2.0 * std::atan2(num, den);
}

// Distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection, 5.1.5).
double pointTriangleDistance(const V3& p, const V3& a, const V3& b, const V3& c) {
    const V3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) return ap.norm();
    const V3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) return bp.norm();
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
    const V3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) return cp.norm();
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
    const double denom = 1.0 / (va + vb + vc);
    return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

Eigen::AlignedBox3d boundingBox(const Eigen::Matrix3Xd& x) {
    Eigen::AlignedBox3d box;
    for (Eigen::Index i = 0; i < x.cols(); ++i) box.extend(V3(x.col(i)));
    return box;
}

// Largest depth of A's nodes inside B (see calcFilmOverlap), over the nodes in `region`.
double calcDepthInside(const Eigen::Matrix3Xd& xA, const bags::Mesh& filmB,
                       const Eigen::Matrix3Xd& xB, const Eigen::AlignedBox3d& region) {
    double depth = 0.0;
    for (Eigen::Index n = 0; n < xA.cols(); ++n) {
        const V3 p = xA.col(n);
        if (!region.contains(p)) continue;
        double omega = 0.0;
        for (const bags::ChamberBoundary& ch : filmB.chambers)
            for (size_t k = 0; k < ch.tris.size(); ++k) {
                const int t = ch.tris[k];
                const double w =
                    solidAngle(xB.col(filmB.tris(0, t)) - p, xB.col(filmB.tris(1, t)) - p,
                               xB.col(filmB.tris(2, t)) - p);
                omega += ch.signs[k] * w;
            }
        // Diaphragms between chambers appear once with each sign and cancel: the sum is the
        // winding number of the whole bag, 1 inside (either orientation) and 0 outside.
        if (!(std::abs(omega) > 2.0 * M_PI)) continue;
        double d = std::numeric_limits<double>::infinity();
        for (int t = 0; t < filmB.getNumTris(); ++t)
            d = std::min(
                d, pointTriangleDistance(p, xB.col(filmB.tris(0, t)), xB.col(filmB.tris(1, t)),
                                         xB.col(filmB.tris(2, t))));
        depth = std::max(depth, d);
    }
    return depth;
}

}  // namespace

double calcFilmOverlap(const bags::Mesh& filmA, const Eigen::Matrix3Xd& xA, const bags::Mesh& filmB,
                       const Eigen::Matrix3Xd& xB) {
    if (xA.cols() != filmA.getNumNodes() || xB.cols() != filmB.getNumNodes())
        throw std::invalid_argument("calcFilmOverlap: positions and film differ in node count");
    const Eigen::AlignedBox3d a = boundingBox(xA), b = boundingBox(xB);
    if (!a.intersects(b)) return 0.0;
    const Eigen::AlignedBox3d region = a.intersection(b);
    return std::max(calcDepthInside(xA, filmB, xB, region), calcDepthInside(xB, filmA, xA, region));
}

std::vector<std::vector<int>> findTouchingGroups(const std::vector<Eigen::AlignedBox2d>& boxes,
                                                 double margin) {
    if (!(margin >= 0.0) || !std::isfinite(margin))
        throw std::invalid_argument("findTouchingGroups: margin must be finite and >= 0 [m]");
    const int n = int(boxes.size());
    std::vector<int> parent(static_cast<size_t>(n), 0);
    std::iota(parent.begin(), parent.end(), 0);
    auto root = [&](int i) {
        while (parent[size_t(i)] != i) i = parent[size_t(i)] = parent[size_t(parent[size_t(i)])];
        return i;
    };
    const Eigen::Vector2d grow(2.0 * margin, 2.0 * margin);  // both boxes grown by margin
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            const Eigen::AlignedBox2d bi(boxes[size_t(i)].min() - grow,
                                         boxes[size_t(i)].max() + grow);
            if (!bi.intersects(boxes[size_t(j)])) continue;
            const int ri = root(i), rj = root(j);
            if (ri != rj) parent[size_t(std::max(ri, rj))] = std::min(ri, rj);
        }
    std::vector<std::vector<int>> groups;
    std::vector<int> groupOf(size_t(n), -1);
    for (int i = 0; i < n; ++i) {
        const int r = root(i);
        if (groupOf[size_t(r)] < 0) {
            groupOf[size_t(r)] = int(groups.size());
            groups.emplace_back();
        }
        groups[size_t(groupOf[size_t(r)])].push_back(i);
    }
    return groups;
}

Eigen::AlignedBox2d calcInflatedExtent(const bags::AirbagSpec& spec, double mass) {
    bags::AirbagSpec s = spec;
    s.X_GB = Eigen::Isometry3d::Identity();
    s.cluster.clear();
    bags::Airbag bag(s);
    bag.inflate(mass);
    const Eigen::Matrix3Xd& x = bag.getPositions();
    Eigen::AlignedBox2d box;
    for (Eigen::Index i = 0; i < x.cols(); ++i) box.extend(Eigen::Vector2d(x(0, i), x(1, i)));
    return box;
}

// ------------------------------------------------------------------------------- ModuleBag

ModuleBag::ModuleBag(BagParticipant& module, int bag) : m_module(module), m_bag(bag) {
    const bags::Airbag& a = module.getAirbag();
    const std::pair<int, int> nodes = a.getBagNodes(bag);
    m_first = nodes.first;
    m_count = nodes.second - nodes.first;
    const bags::Mesh& mesh = a.getMesh();
    const int trisPerBag = mesh.getNumTris() / a.getNumBags();
    const int firstTri = bag * trisPerBag;
    m_film.X = mesh.X.middleCols(m_first, m_count);
    m_film.tris = mesh.tris.middleCols(firstTri, trisPerBag).array() - m_first;
    m_film.triPanel.assign(mesh.triPanel.begin() + firstTri,
                           mesh.triPanel.begin() + firstTri + trisPerBag);
    m_film.panelNames = mesh.panelNames;
    for (int c : a.getBagChambers(bag)) {
        bags::ChamberBoundary ch = mesh.chambers[size_t(c)];
        for (int& t : ch.tris) t -= firstTri;
        m_film.chambers.push_back(std::move(ch));
    }
    for (int s : mesh.supportNodes)
        if (s >= m_first && s < m_first + m_count) m_film.supportNodes.push_back(s - m_first);
}

int ModuleBag::addModuleShape(int moduleShape) {
    m_shapes.push_back(moduleShape);
    return int(m_shapes.size()) - 1;
}

void ModuleBag::setShapeState(int shape, const ShapeState& state) {
    m_module.updAirbag().setShapePose(getModuleShape(shape), state.X_GS);
}

namespace {
[[noreturn]] void moduleOnly(const char* what) {
    throw std::logic_error(std::string("ModuleBag::") + what +
                           ": a bag of a module is stepped, saved and counted by its module");
}
}  // namespace

ParticipantStep ModuleBag::advance(double) { moduleOnly("advance"); }
void ModuleBag::commit() { moduleOnly("commit"); }
void ModuleBag::rollback() { moduleOnly("rollback"); }
double ModuleBag::calcPotentialEnergy() const { moduleOnly("calcPotentialEnergy"); }
void ModuleBag::saveState(bags::StateWriter&) const { moduleOnly("saveState"); }
void ModuleBag::loadState(bags::StateReader&) { moduleOnly("loadState"); }

ShapeWrench ModuleBag::calcWrench(int shape) const {
    return m_module.calcWrench(getModuleShape(shape));
}
Mat6 ModuleBag::calcWrenchTangent(int shape) const {
    return m_module.calcWrenchTangent(getModuleShape(shape));
}
Eigen::VectorXd ModuleBag::calcContactPressure(int shape) const {
    return m_module.calcContactPressure(getModuleShape(shape)).segment(m_first, m_count);
}
bool ModuleBag::isSteady() const { return m_module.isSteady(); }
void ModuleBag::setMassFlow(double massFlow) { m_module.updAirbag().setMassFlow(m_bag, massFlow); }
void ModuleBag::setTargetMass(double mass, double rate) {
    m_module.updAirbag().setTargetMass(m_bag, mass, rate);
}
double ModuleBag::getGasMass() const { return m_module.getAirbag().getGasMass(m_bag); }
int ModuleBag::getNumChambers() const {
    return int(m_module.getAirbag().getBagChambers(m_bag).size());
}
bags::ChamberState ModuleBag::getChamberState(int chamber) const {
    const std::vector<int>& c = m_module.getAirbag().getBagChambers(m_bag);
    return m_module.getAirbag().getChamberState(c.at(size_t(chamber)));
}
const Eigen::Matrix3Xd& ModuleBag::getPressurePoints() const {
    m_points = m_module.getAirbag().getPositions().middleCols(m_first, m_count);
    return m_points;
}
Eigen::VectorXd ModuleBag::getPressureAreas() const {
    return m_module.getPressureAreas().segment(m_first, m_count);
}

// ----------------------------------------------------------------------- ArrayParticipants

ArrayParticipants makeArrayParticipants(const std::vector<ArrayBag>& cells,
                                        const std::vector<int>& coupled,
                                        const bags::AirbagSpec& spec, bool neighbourContact,
                                        double margin, double mass) {
    if (neighbourContact && !spec.selfContact)
        throw std::invalid_argument(
            "array.neighbour_contact: the films of neighbouring bags meet through the bags' "
            "self-contact; valid: with bag.self_contact: true");
    ArrayParticipants a;
    const int n = int(coupled.size());
    if (neighbourContact) {
        const Eigen::AlignedBox2d ext = calcInflatedExtent(spec, mass);
        std::vector<Eigen::AlignedBox2d> boxes;
        for (int b : coupled) {
            Eigen::AlignedBox2d box;
            for (int c = 0; c < 4; ++c) {
                const Eigen::Vector2d corner = ext.corner(Eigen::AlignedBox2d::CornerType(c));
                const Eigen::Vector3d g =
                    cells.at(size_t(b)).X_GB * Eigen::Vector3d(corner.x(), corner.y(), 0.0);
                box.extend(Eigen::Vector2d(g.x(), g.y()));
            }
            boxes.push_back(box);
        }
        a.modules = findTouchingGroups(boxes, margin);
    } else {
        for (int i = 0; i < n; ++i) a.modules.push_back({i});
    }
    a.bags.assign(size_t(n), nullptr);
    a.participantOf.assign(size_t(n), -1);
    for (size_t q = 0; q < a.modules.size(); ++q) {
        const std::vector<int>& mod = a.modules[q];
        bags::AirbagSpec bs = spec;
        bs.cluster.clear();
        if (mod.size() == 1) {
            bs.X_GB = cells.at(size_t(coupled[size_t(mod[0])])).X_GB;
        } else {  // the bags placed in one module, its frame Ground
            bs.X_GB = Eigen::Isometry3d::Identity();
            for (int i : mod) bs.cluster.push_back(cells.at(size_t(coupled[size_t(i)])).X_GB);
        }
        a.participants.push_back(
            std::make_unique<BagParticipant>(std::make_unique<bags::Airbag>(bs)));
        for (size_t k = 0; k < mod.size(); ++k) {
            a.participantOf[size_t(mod[k])] = int(q);
            if (mod.size() == 1) {
                a.bags[size_t(mod[k])] = a.participants.back().get();
            } else {
                a.moduleBags.push_back(std::make_unique<ModuleBag>(*a.participants.back(), int(k)));
                a.bags[size_t(mod[k])] = a.moduleBags.back().get();
            }
        }
    }
    return a;
}

int ArrayParticipants::addShape(int bag, std::shared_ptr<bags::RigidShape> shape,
                                const bags::RigidContact::Options& options, int* participantShape) {
    BagParticipant& p = *participants.at(size_t(participantOf.at(size_t(bag))));
    if (auto* mb = dynamic_cast<ModuleBag*>(bags[size_t(bag)])) {
        const int s = p.updAirbag().addShape(std::move(shape), options, mb->getBagInModule());
        if (participantShape) *participantShape = s;
        return mb->addModuleShape(s);
    }
    const int s = p.updAirbag().addShape(std::move(shape), options);
    if (participantShape) *participantShape = s;
    return s;
}

void ArrayParticipants::inflate(const std::vector<double>& masses) {
    if (masses.size() != bags.size())
        throw std::invalid_argument("ArrayParticipants::inflate: give one mass per bag");
    for (size_t q = 0; q < participants.size(); ++q) {
        std::vector<double> m;
        for (int i : modules[q]) m.push_back(masses[size_t(i)]);
        if (m.size() == 1)
            participants[q]->updAirbag().inflate(m[0]);
        else
            participants[q]->updAirbag().inflate(m);
    }
}

}  // namespace cosim
