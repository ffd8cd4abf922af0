#include "cosim/PatientOnArray.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "cosim/BodyShapes.h"
#include "cosim/NeighbourModules.h"

namespace cosim {

bags::RigidContact::Options PatientOnArrayOptions::getSegmentContact(body::Segment segment) const {
    bags::RigidContact::Options c = contact;
    if (!segmentTissue.empty()) {
        const body::SoftTissue& t = segmentTissue.at(size_t(segment));
        c.tissueThickness = t.thickness;
        c.tissueModulus = t.isRigid() ? 0.0 : t.modulus;
    }
    return c;
}

void PatientOnArrayOptions::validate() const {
    layout.validate(bag.geometry);
    if (!(pairMargin >= 0.0) || !std::isfinite(pairMargin))
        throw std::invalid_argument("pairMargin must be finite and >= 0 [m]");
    if (!(dropHeight >= 0.0) || !std::isfinite(dropHeight))
        throw std::invalid_argument("dropHeight must be finite and >= 0 [m]");
    if (model == BagModel::Reduced) {
        if (!reduced) throw std::invalid_argument("bag.calibration: the reduced model needs one");
        reduced->validate();
        const bags::DoubleWedgeParams& c = reduced->geometry;
        const bags::DoubleWedgeParams& g = bag.geometry;
        if (std::abs(c.longSide - g.longSide) > 1e-6 ||
            std::abs(c.shortSide - g.shortSide) > 1e-6 || std::abs(c.width - g.width) > 1e-6 ||
            std::abs(c.height - g.height) > 1e-6 || c.diaphragm != g.diaphragm)
            throw std::invalid_argument(
                "bag.calibration: made for another bag (sizes or diaphragm differ from the "
                "scenario's bag reading); valid: a calibration of this bag");
        ReducedBagFriction f = reducedFriction;
        f.coefficient = contact.friction;
        f.validate();
    }
    contact.validate();
    if (!segmentTissue.empty()) {
        if (segmentTissue.size() != size_t(body::kSegmentCount))
            throw std::invalid_argument("segmentTissue: one layer per segment (" +
                                        std::to_string(body::kSegmentCount) + "), or none");
        for (int s = 0; s < body::kSegmentCount; ++s) {
            const body::SoftTissue& t = segmentTissue[size_t(s)];
            if (!t.isRigid() && model == BagModel::Reduced)
                throw std::invalid_argument(
                    "segmentTissue: a tissue layer is not valid with reduced bags (their contact "
                    "law is their own, fitted with bare shapes); valid: rigid segments");
            getSegmentContact(body::Segment(s)).validate();
        }
    }
    if (contact.friction > 0.0 && coupling.scheme == Scheme::Tangent &&
        model == BagModel::FiniteElement)
        throw std::invalid_argument(
            "coupling.scheme: tangent is not valid with body friction (bag.body_friction > 0): "
            "its one pass would hold the friction force from the step's start "
            "(docs/cosim.md#friction-and-the-tangent-schemes); valid: implicit, "
            "tangent-implicit or explicit with friction, or bag.body_friction 0");
    if (neighbourContact) {
        if (model != BagModel::FiniteElement)
            throw std::invalid_argument(
                "array.neighbour_contact: needs the finite-element bags (the reduced model has "
                "no film to touch); valid: false with bag.model reduced");
        if (!bag.selfContact)
            throw std::invalid_argument(
                "array.neighbour_contact: the films of neighbouring bags meet through the bags' "
                "self-contact; valid: with bag.self_contact: true");
    }
    if (!(neighbourMargin >= 0.0) || !std::isfinite(neighbourMargin))
        throw std::invalid_argument("array.neighbour_margin must be finite and >= 0 [m]");
    if (!(neighbourMass >= 0.0) || !std::isfinite(neighbourMass))
        throw std::invalid_argument("neighbourMass must be finite and >= 0 [kg]");
    body.validate();
    if (boardContact) board.validate();
    integrator.validate();
    coupling.validate();
}

struct PatientOnArray::Impl {
    std::unique_ptr<body::BodyModel> model;
    std::unique_ptr<BodyParticipant> body;
    ArrayParticipants fe;  // finite-element bags and modules
    std::vector<std::unique_ptr<ReducedBag>> reducedBags;
    std::vector<Bag*> participants;         // what the coupling advances
    std::vector<Bag*> bags;                 // per coupled bag: a participant or a ModuleBag
    std::vector<std::vector<int>> modules;  // per participant: its bags (positions in bags)
    bool grouped = false;                   // neighbourContact
    std::vector<int> bagIndices;            // ArrayBag index per coupled bag
    std::vector<ShapeBagPair> pairs;        // shape = segment
    std::vector<int> pairBag;               // per pair: the bag's position in bags
    std::vector<Link> links;                // per pair, in bag terms
    std::unique_ptr<Coupling> coupling;
    const body::PlaneSupport* board = nullptr;  // the body's bed board (owned by the model)
    double clearance = 0.0;
    double gravity = 0.0;
    std::vector<Eigen::VectorXd> restHeights;  // per coupled bag [m]: getRestHeights()
};

namespace {

Eigen::Isometry3d shapePose(const body::BodyModel& model, const SimTK::State& s, int segment,
                            const SimTK::Transform& X_BS) {
    const SimTK::Transform X_GB =
        model.getMobilizedBody(static_cast<body::Segment>(segment)).getBodyTransform(s);
    return toEigen(X_GB * X_BS);
}

// The pairs of segment and bag with the patient in the spec's posture, his lowest point on the
// bed board. @pre the system's topology is realized; `state` is set to that posture.
std::vector<ShapeBagPair> findPairsAtPosture(const body::BodyModel& model, SimTK::State& state,
                                             const std::vector<ArrayBag>& cells, double margin) {
    model.setPosture(state, 0.0);
    model.getSystem().realize(state, SimTK::Stage::Position);
    std::vector<Eigen::Vector3d> centres;
    std::vector<double> radii;
    calcSegmentBounds(model, state, centres, radii);
    return findShapeBagPairs(centres, radii, cells, margin);
}

}  // namespace

void calcSegmentBounds(const body::BodyModel& model, const SimTK::State& state,
                       std::vector<Eigen::Vector3d>& centres, std::vector<double>& radii) {
    centres.clear();
    radii.clear();
    for (int k = 0; k < body::kSegmentCount; ++k) {
        const auto seg = static_cast<body::Segment>(k);
        const body::ContactShape& s = model.getContactShape(seg);
        const SimTK::Vec3 c =
            model.getMobilizedBody(seg).getBodyTransform(state) * s.getBoundingCentre();
        centres.emplace_back(c[0], c[1], c[2]);
        radii.push_back(s.getBoundingRadius());
    }
}

std::vector<int> findSegmentsOffArray(const body::PatientSpec& spec,
                                      const PatientOnArrayOptions& options) {
    options.validate();
    body::BodyModel model(spec, options.body);
    model.updSystem().realizeTopology();
    SimTK::State state = model.getSystem().getDefaultState();
    const std::vector<ArrayBag> cells = makeArrayBags(options.layout, options.bag.geometry);
    return findUnsupportedShapes(body::kSegmentCount,
                                 findPairsAtPosture(model, state, cells, options.pairMargin));
}

PatientOnArray::PatientOnArray(const body::PatientSpec& spec, const PatientOnArrayOptions& options)
    : m_impl(std::make_unique<Impl>()) {
    options.validate();
    Impl& m = *m_impl;
    m.model = std::make_unique<body::BodyModel>(spec, options.body);
    m.gravity = options.body.gravity;
    body::BodyModel& model = *m.model;
    m.body =
        std::make_unique<BodyParticipant>(model.updSystem(), model.updForces(), options.integrator);

    if (options.boardContact) {
        m.board = &body::addPlaneSupport(model, options.board);
        if (options.board.frictionLaw == body::SupportFrictionLaw::StickSlip) {
            const body::PlaneSupport* board = m.board;
            m.body->addDiscreteState(
                {"the bed board's friction anchors",
                 [board](const SimTK::State& s) { return board->getAnchors(s); },
                 [board](SimTK::State& s, const std::vector<double>& v) {
                     board->setAnchors(s, v);
                 }});
        }
    }

    // Where the shapes lie in the posture (lowest point on the bed board) picks the pairs.
    model.updSystem().realizeTopology();
    SimTK::State state = model.getSystem().getDefaultState();
    const std::vector<ArrayBag> cells = makeArrayBags(options.layout, options.bag.geometry);
    m.pairs = findPairsAtPosture(model, state, cells, options.pairMargin);
    const std::vector<int> off = findUnsupportedShapes(body::kSegmentCount, m.pairs);
    if (!off.empty()) {
        std::ostringstream s;
        s << "patient: no bag of the array lies under segment(s)";
        for (int k : off) s << ' ' << k;
        s << " (patient.position or the array's rows, columns, pitches and centre)";
        throw std::invalid_argument(s.str());
    }

    // The bags that some shape may touch; each pair gets its own bag shape (bags advance on
    // different threads and set their shapes' poses) and its own body shape (one link each).
    std::vector<int> positionOf(cells.size(), -1);
    for (const ShapeBagPair& p : m.pairs)
        if (positionOf[p.bag] < 0) {
            positionOf[p.bag] = int(m.bagIndices.size());
            m.bagIndices.push_back(p.bag);
        }
    const int numBags = int(m.bagIndices.size());
    // Parked well clear above the flat panels while the bags inflate.
    const double parked = options.bag.geometry.height + 0.5;
    model.setPosture(state, parked);
    model.getSystem().realize(state, SimTK::Stage::Position);
    const bool reduced = options.model == PatientOnArrayOptions::BagModel::Reduced;
    // The participants: one per bag, or with neighbourContact one per group of bags whose
    // inflated extents may meet (cosim/NeighbourModules.h).
    m.grouped = options.neighbourContact;
    std::vector<int> participantOf;
    if (reduced) {
        for (int i = 0; i < numBags; ++i) {
            m.reducedBags.push_back(
                std::make_unique<ReducedBag>(options.reduced, cells[m.bagIndices[i]].X_GB));
            ReducedBagFriction f = options.reducedFriction;
            f.coefficient = options.contact.friction;
            m.reducedBags.back()->setFriction(f);
            m.participants.push_back(m.reducedBags.back().get());
            m.bags.push_back(m.reducedBags.back().get());
            m.modules.push_back({i});
            participantOf.push_back(i);
        }
    } else {
        double mass = options.neighbourMass;
        for (int b : m.bagIndices) mass = std::max(mass, cells[b].gasMass);
        m.fe = makeArrayParticipants(cells, m.bagIndices, options.bag, options.neighbourContact,
                                     options.neighbourMargin, mass);
        for (auto& p : m.fe.participants) {
            // With friction the body's linearised load leaves the films' stick springs out;
            // the tangent-implicit passes hold the friction force
            // (docs/cosim.md#friction-and-the-tangent-schemes).
            p->setLinearisationWithoutFriction(options.contact.friction > 0.0);
            m.participants.push_back(p.get());
        }
        m.bags = m.fe.bags;
        m.modules = m.fe.modules;
        participantOf = m.fe.participantOf;
    }
    std::vector<Link> links;
    std::vector<std::shared_ptr<bags::RigidShape>> probes;  // per pair, for the touch search
    std::vector<SimTK::Transform> X_BS;                     // per pair
    for (const ShapeBagPair& p : m.pairs) {
        const auto seg = static_cast<body::Segment>(p.shape);
        BagShapeOfBody b = makeBagShape(model.getContactShape(seg));
        b.shape->setPose(shapePose(model, state, p.shape, b.X_BS));
        const int pos = positionOf[p.bag];
        const int part = participantOf[size_t(pos)];
        int local = 0, bagLocal = 0;
        if (reduced)
            local = bagLocal = m.reducedBags[size_t(pos)]->addShape(b.shape);
        else
            bagLocal = m.fe.addShape(pos, b.shape, options.getSegmentContact(seg), &local);
        const int bodyShape = m.body->addShape(model.getMobilizedBodyIndex(seg), b.X_BS);
        const body::ContactShape& cs = model.getContactShape(seg);
        const double reach = (cs.getBoundingCentre() - b.X_BS.p()).norm() + cs.getBoundingRadius();
        links.push_back(Link{bodyShape, part, local, reach});
        m.links.push_back(Link{bodyShape, pos, bagLocal, reach});
        m.pairBag.push_back(pos);
        probes.push_back(makeBagShape(model.getContactShape(seg)).shape);
        X_BS.push_back(b.X_BS);
    }
    std::vector<double> masses;
    for (int b : m.bagIndices) masses.push_back(cells[b].gasMass);
    if (reduced)
        for (size_t i = 0; i < masses.size(); ++i) m.reducedBags[i]->setGasMass(masses[i]);
    else
        m.fe.inflate(masses);
    for (const Bag* bag : m.bags)
        m.restHeights.push_back(bag->getPressurePoints().row(2).transpose());

    // The lowest clearance at which no node of a paired bag lies inside a shape (bisection to
    // 1e-6 m over [0, parked]).
    auto touches = [&](double clearance) {
        model.setPosture(state, clearance);
        model.getSystem().realize(state, SimTK::Stage::Position);
        for (size_t i = 0; i < m.pairs.size(); ++i) {
            bags::RigidShape& s = *probes[i];
            s.setPose(shapePose(model, state, m.pairs[i].shape, X_BS[i]));
            const Eigen::Matrix3Xd& x = m.bags[m.pairBag[i]]->getPressurePoints();
            for (int n = 0; n < x.cols(); ++n)
                if (s.calcSignedDistance(x.col(n), nullptr, nullptr) < 0.0) return true;
        }
        return false;
    };
    double lo = 0.0, hi = parked;
    if (touches(hi)) throw std::runtime_error("patient: touches the bags even when parked");
    while (hi - lo > 1e-6) (touches(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
    m.clearance = hi + options.dropHeight;
    model.setPosture(state, m.clearance);
    m.body->initialize(state);

    std::vector<Participant*> ps;
    for (Bag* b : m.participants) ps.push_back(b);
    m.coupling = std::make_unique<Coupling>(*m.body, ps, links, options.coupling);
    m.coupling->initialize();
}

PatientOnArray::~PatientOnArray() = default;

StepSummary PatientOnArray::step() { return m_impl->coupling->stepAdaptive(); }

StepSummary PatientOnArray::stepUntil(double limit) {
    return m_impl->coupling->stepAdaptive(limit);
}
double PatientOnArray::getTime() const { return m_impl->coupling->getTime(); }

std::vector<double> PatientOnArray::calcBagForces() const {
    std::vector<double> f(m_impl->bags.size(), 0.0);
    for (size_t i = 0; i < m_impl->pairBag.size(); ++i)
        f[m_impl->pairBag[i]] += m_impl->coupling->getLinkWrench(int(i)).force.z();
    return f;
}

double PatientOnArray::calcBoardForce() const {
    const Impl& m = *m_impl;
    if (!m.board) return 0.0;
    const SimTK::State& s = m.body->getState();
    m.model->getSystem().realize(s, SimTK::Stage::Velocity);
    return m.board->calcSupportLoad(s).force[2];
}

double PatientOnArray::calcBagForce() const {
    double sum = 0.0;
    for (double f : calcBagForces()) sum += f;
    return sum;
}

double PatientOnArray::getWeight() const {
    return m_impl->model->calcTotalMass() * m_impl->gravity;
}

double PatientOnArray::calcEnergy() const {
    const Impl& m = *m_impl;
    SimTK::State s = m.body->getState();
    m.model->getSystem().realize(s, SimTK::Stage::Dynamics);
    double e = m.model->getSystem().calcEnergy(s);
    for (const Bag* b : m.participants) e += b->calcPotentialEnergy();
    return e;
}

double PatientOnArray::calcMaxSpeed() const {
    const SimTK::State& s = m_impl->body->getState();
    double v = 0.0;
    for (int k = 0; k < body::kSegmentCount; ++k)
        v = std::max(v, m_impl->model->getMobilizedBody(static_cast<body::Segment>(k))
                            .getBodyOriginVelocity(s)
                            .norm());
    return v;
}

double PatientOnArray::getReleaseClearance() const { return m_impl->clearance; }
EnvelopeCounts PatientOnArray::getEnvelopeCounts() const {
    EnvelopeCounts sum;
    for (const auto& b : m_impl->reducedBags)
        if (const ReducedBag* r = b.get()) {
            const EnvelopeCounts& e = r->getEnvelopeCounts();
            sum.mass += e.mass, sum.depth += e.depth, sum.radius += e.radius, sum.tilt += e.tilt;
            sum.steps += e.steps;
            if (e.mass) sum.worstMass = e.worstMass;
            sum.worstDepth = std::max(sum.worstDepth, e.worstDepth);
            if (e.radius) sum.worstRadius = e.worstRadius;
            sum.worstTilt = std::max(sum.worstTilt, e.worstTilt);
        }
    return sum;
}

const std::vector<ShapeBagPair>& PatientOnArray::getPairs() const { return m_impl->pairs; }
const std::vector<int>& PatientOnArray::getBagIndices() const { return m_impl->bagIndices; }
const Eigen::VectorXd& PatientOnArray::getRestHeights(int bag) const {
    return m_impl->restHeights.at(size_t(bag));
}
const body::BodyModel& PatientOnArray::getModel() const { return *m_impl->model; }
const BodyParticipant& PatientOnArray::getBody() const { return *m_impl->body; }
const Bag& PatientOnArray::getBag(int bag) const { return *m_impl->bags.at(size_t(bag)); }
const std::vector<Link>& PatientOnArray::getLinks() const { return m_impl->links; }
Bag& PatientOnArray::updBag(int bag) { return *m_impl->bags.at(size_t(bag)); }
const std::vector<std::vector<int>>& PatientOnArray::getModules() const { return m_impl->modules; }

std::vector<double> PatientOnArray::calcNeighbourOverlaps() const {
    const Impl& m = *m_impl;
    const size_t n = m.bags.size();
    std::vector<double> out(n, 0.0);
    std::vector<Eigen::Matrix3Xd> x(n);
    for (size_t i = 0; i < n; ++i)
        if (m.bags[i]->getFilmMesh()) x[i] = m.bags[i]->getPressurePoints();
    for (size_t i = 0; i < n; ++i) {
        const bags::Mesh* fi = m.bags[i]->getFilmMesh();
        if (!fi) continue;
        for (size_t j = i + 1; j < n; ++j) {
            const bags::Mesh* fj = m.bags[j]->getFilmMesh();
            if (!fj) continue;
            const double d = calcFilmOverlap(*fi, x[i], *fj, x[j]);
            out[i] = std::max(out[i], d);
            out[j] = std::max(out[j], d);
        }
    }
    return out;
}
std::shared_ptr<bags::RigidShape> PatientOnArray::makePairShape(int pair) const {
    const Impl& m = *m_impl;
    const int seg = m.pairs.at(size_t(pair)).shape;
    BagShapeOfBody b = makeBagShape(m.model->getContactShape(static_cast<body::Segment>(seg)));
    const SimTK::State& s = m.body->getState();
    m.model->getSystem().realize(s, SimTK::Stage::Position);
    b.shape->setPose(shapePose(*m.model, s, seg, b.X_BS));
    return b.shape;
}
Coupling& PatientOnArray::updCoupling() { return *m_impl->coupling; }

void PatientOnArray::saveState(bags::StateWriter& w) const {
    const Impl& m = *m_impl;
    w.tag("patient on array");
    w.vec(m.bagIndices);
    if (m.grouped) {  // the modules (a checkpoint without them is of bags solved alone)
        w.tag("neighbour modules");
        w.pod(std::uint64_t(m.modules.size()));
        for (const std::vector<int>& mod : m.modules) w.vec(mod);
    }
    m.body->saveState(w);
    for (const Bag* b : m.participants) b->saveState(w);
    m.coupling->saveState(w);
}

void PatientOnArray::loadState(bags::StateReader& r) {
    Impl& m = *m_impl;
    r.tag("patient on array");
    std::vector<int> indices;
    r.vec(indices);
    if (indices != m.bagIndices)
        throw bags::StateError(
            "checkpoint: other bags take part (the patient or the array differs)");
    if (m.grouped) {
        r.tag("neighbour modules");
        std::vector<std::vector<int>> modules(size_t(r.pod<std::uint64_t>()));
        for (std::vector<int>& mod : modules) r.vec(mod);
        if (modules != m.modules)
            throw bags::StateError(
                "checkpoint: the neighbouring bags were grouped into other modules (the "
                "array or array.neighbour_margin differs)");
    }
    m.body->loadState(r);
    for (Bag* b : m.participants) b->loadState(r);
    m.coupling->loadState(r);
    resetCaches();
}

void PatientOnArray::resetCaches() {
    for (Bag* b : m_impl->participants) b->resetCaches();
}

}  // namespace cosim
