#include "cosim/ArrayReadings.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <stdexcept>

#include "cosim/BodyShapes.h"

namespace cosim {

std::vector<std::string> getRegionLoadNames(const body::BodyModel& model) {
    std::vector<std::string> names;
    for (const body::BodyRegion& r : model.getRegions()) names.push_back(r.name);
    for (int k = 0; k < body::kSegmentCount; ++k)
        names.push_back(body::getSegmentName(static_cast<body::Segment>(k)));
    return names;
}

double calcPatchPeakPressure(const std::vector<Eigen::Vector2d>& points,
                             const std::vector<double>& forces, double patchArea) {
    if (!(patchArea > 0.0)) throw std::invalid_argument("calcPatchPeakPressure: patchArea <= 0");
    const double r2 = patchArea / 3.14159265358979323846;
    // Points sorted by x: a disc's neighbours lie within one radius in x.
    std::vector<int> order(points.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return points[a].x() < points[b].x(); });
    const double r = std::sqrt(r2);
    double best = 0.0;
    size_t lo = 0;
    for (size_t i = 0; i < order.size(); ++i) {
        const Eigen::Vector2d& c = points[order[i]];
        while (points[order[lo]].x() < c.x() - r) ++lo;
        double sum = 0.0;
        for (size_t j = lo; j < order.size() && points[order[j]].x() <= c.x() + r; ++j)
            if ((points[order[j]] - c).squaredNorm() <= r2) sum += forces[order[j]];
        best = std::max(best, sum);
    }
    return best / patchArea;
}

std::vector<RegionLoad> calcRegionLoads(const PatientOnArray& poa, double areaThreshold,
                                        double patchArea) {
    const body::BodyModel& model = poa.getModel();
    const std::vector<std::string> names = getRegionLoadNames(model);
    std::vector<RegionLoad> loads(names.size());
    std::vector<double> normalForce(names.size(), 0.0);
    // Per region: its loaded nodes in the bed's plane and their normal forces (patch peak).
    std::vector<std::vector<Eigen::Vector2d>> patchPoints(names.size());
    std::vector<std::vector<double>> patchForces(names.size());
    for (size_t i = 0; i < names.size(); ++i) loads[i].name = names[i];
    const int numRegions = int(model.getRegions().size());

    const SimTK::State& state = poa.getBody().getState();
    std::vector<Eigen::VectorXd> nodalAreas(poa.getBagIndices().size());
    // One probe per segment: the shape's outward normal at a node gives its force's direction.
    std::vector<std::shared_ptr<bags::RigidShape>> probes(body::kSegmentCount);
    const std::vector<ShapeBagPair>& pairs = poa.getPairs();
    const std::vector<Link>& links = poa.getLinks();
    for (size_t i = 0; i < pairs.size(); ++i) {
        const Link& link = links[i];
        const auto seg = static_cast<body::Segment>(pairs[i].shape);
        const Bag& bag = poa.getBag(link.participant);
        const Eigen::VectorXd p = bag.calcContactPressure(link.shape);
        if (p.size() == 0 || !(p.maxCoeff() > 0.0)) continue;
        Eigen::VectorXd& area = nodalAreas[link.participant];
        if (area.size() == 0) area = bag.getPressureAreas();
        std::shared_ptr<bags::RigidShape>& probe = probes[pairs[i].shape];
        if (!probe) probe = makeBagShape(model.getContactShape(seg)).shape;
        probe->setPose(poa.getBody().getShapeState(link.bodyShape).X_GS);
        const SimTK::Transform X_GB = model.getMobilizedBody(seg).getBodyTransform(state);
        const Eigen::Matrix3Xd& x = bag.getPressurePoints();
        for (int n = 0; n < int(p.size()); ++n) {
            if (!(p[n] > 0.0)) continue;
            const SimTK::Vec3 p_B = ~X_GB * SimTK::Vec3(x(0, n), x(1, n), x(2, n));
            const int region = model.findRegion(seg, p_B);
            RegionLoad& r = loads[region >= 0 ? region : numRegions + pairs[i].shape];
            Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
            probe->calcSignedDistance(x.col(n), nullptr, &normal);
            // The node pushes the shape along the shape's inward normal: the force on the body
            // points out of the membrane, against the shape's outward normal.
            r.force += p[n] * area[n] * -normal.z();
            r.peakPressure = std::max(r.peakPressure, p[n]);
            patchPoints[&r - loads.data()].emplace_back(x(0, n), x(1, n));
            patchForces[&r - loads.data()].push_back(p[n] * area[n]);
            if (p[n] > kRiskPressure) r.areaAtRisk += area[n];
            // A film's node has a rest height; a reduced bag's contact samples (no film) have
            // none: a region it touches has its immersion not measured (NaN).
            const Eigen::VectorXd& rest = poa.getRestHeights(link.participant);
            if (n >= rest.size()) r.immersion = std::numeric_limits<double>::quiet_NaN();
            if (p[n] > areaThreshold) {
                if (!std::isnan(r.immersion))
                    r.immersion = std::max(r.immersion, rest[n] - x(2, n));
                r.area += area[n];
                normalForce[&r - loads.data()] += p[n] * area[n];
            }
        }
    }
    for (size_t i = 0; i < loads.size(); ++i) {
        loads[i].meanPressure = loads[i].area > 0.0 ? normalForce[i] / loads[i].area : 0.0;
        loads[i].patchPeakPressure =
            calcPatchPeakPressure(patchPoints[i], patchForces[i], patchArea);
    }
    return loads;
}

std::vector<BagReading> calcBagReadings(const PatientOnArray& poa) {
    const std::vector<double> forces = poa.calcBagForces();
    const std::vector<double> overlaps = poa.calcNeighbourOverlaps();
    std::vector<BagReading> out;
    for (size_t i = 0; i < poa.getBagIndices().size(); ++i) {
        const Bag& a = poa.getBag(int(i));
        BagReading r;
        r.bag = poa.getBagIndices()[i];
        r.gasMass = a.getGasMass();
        double pv = 0.0;
        for (int c = 0; c < a.getNumChambers(); ++c) {
            const bags::ChamberState s = a.getChamberState(c);
            r.volume += s.volume;
            pv += s.gaugePressure * s.volume;
        }
        r.gaugePressure = r.volume > 0.0 ? pv / r.volume : 0.0;
        r.force = forces[i];
        r.overlap = overlaps[i];
        out.push_back(r);
    }
    return out;
}

double calcSegmentTilt(const body::BodyModel& model, const SimTK::State& state,
                       body::Segment segment) {
    const SimTK::Rotation& R_GB = model.getMobilizedBody(segment).getBodyRotation(state);
    const SimTK::Vec3 anterior = R_GB * SimTK::Vec3(1, 0, 0);
    return std::atan2(-anterior[1], anterior[2]);
}

double calcSegmentTilt(const PatientOnArray& poa, body::Segment segment) {
    return calcSegmentTilt(poa.getModel(), poa.getBody().getState(), segment);
}

Eigen::Vector3d calcCentreOfMass(const PatientOnArray& poa) {
    const SimTK::Vec3 c =
        poa.getModel().getMatter().calcSystemMassCenterLocationInGround(poa.getBody().getState());
    return Eigen::Vector3d(c[0], c[1], c[2]);
}

std::vector<double> calcPressedNodeHeights(const PatientOnArray& poa, double threshold) {
    std::vector<double> out;
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const Bag& bag = poa.getBag(int(b));
        double lowest = std::numeric_limits<double>::infinity();
        const Eigen::Matrix3Xd& x = bag.getPressurePoints();
        for (int s = 0; s < bag.getNumShapes(); ++s) {
            const Eigen::VectorXd p = bag.calcContactPressure(s);
            for (Eigen::Index i = 0; i < p.size(); ++i)
                if (p[i] > threshold) lowest = std::min(lowest, x(2, i));
        }
        out.push_back(lowest);
    }
    return out;
}

double calcFilmPassThrough(const bags::Mesh& film, const Eigen::Matrix3Xd& x,
                           const bags::RigidShape& shape) {
    if (x.cols() != film.getNumNodes())
        throw std::invalid_argument("calcFilmPassThrough: positions and film differ in node count");
    double depth = 0.0;
    for (int t = 0; t < film.getNumTris(); ++t) {
        const Eigen::Vector3d a = x.col(film.tris(0, t)), b = x.col(film.tris(1, t)),
                              c = x.col(film.tris(2, t));
        const Eigen::Vector3d centroid = (a + b + c) / 3.0;
        // Far triangles cannot hold a point inside (the bound is at most the distance).
        const double reach =
            std::max({(a - centroid).norm(), (b - centroid).norm(), (c - centroid).norm()});
        if (shape.calcDistanceLowerBound(centroid) > reach) continue;
        for (const Eigen::Vector3d& p :
             {centroid, Eigen::Vector3d(0.5 * (a + b)), Eigen::Vector3d(0.5 * (b + c)),
              Eigen::Vector3d(0.5 * (c + a))})
            depth = std::max(depth, -shape.calcSignedDistance(p, nullptr, nullptr));
    }
    return depth;
}

std::vector<PassThrough> calcPassThroughs(const PatientOnArray& poa) {
    std::vector<PassThrough> out;
    for (int b : poa.getBagIndices()) out.push_back(PassThrough{b, -1, 0.0});
    const std::vector<Link>& links = poa.getLinks();
    for (size_t i = 0; i < links.size(); ++i) {
        const Bag& bag = poa.getBag(links[i].participant);
        const bags::Mesh* film = bag.getFilmMesh();
        if (!film) continue;
        const std::shared_ptr<bags::RigidShape> shape = poa.makePairShape(int(i));
        const Eigen::Matrix3Xd& x = bag.getPressurePoints();
        const double d = calcFilmPassThrough(*film, x, *shape);
        PassThrough& o = out[size_t(links[i].participant)];
        if (!(d > o.depth)) continue;
        o.depth = d, o.segment = poa.getPairs()[i].shape, o.nodeDepth = 0.0;
        for (Eigen::Index n = 0; n < x.cols(); ++n)
            o.nodeDepth =
                std::max(o.nodeDepth, -shape->calcSignedDistance(x.col(n), nullptr, nullptr));
    }
    return out;
}

void fillPressureMat(const PatientOnArray& poa, PressureMat& mat) {
    mat.clear();
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const Bag& bag = poa.getBag(int(b));
        const int shapes = bag.getNumShapes();
        if (shapes == 0) continue;
        Eigen::VectorXd p = bag.calcContactPressure(0);
        for (int s = 1; s < shapes; ++s) p += bag.calcContactPressure(s);
        if (p.size() == 0 || !(p.maxCoeff() > 0.0)) continue;
        mat.addNodalPressures(bag.getPressurePoints(), p, bag.getPressureAreas());
    }
}

PressureMatOptions makeArrayMatOptions(const ArrayLayout& layout,
                                       const bags::DoubleWedgeParams& bag, int rows, int columns) {
    const std::vector<ArrayBag> bags = makeArrayBags(layout, bag);
    Eigen::Vector2d lo = bags.front().footprintMin, hi = bags.front().footprintMax;
    for (const ArrayBag& b : bags) {
        lo = lo.cwiseMin(b.footprintMin);
        hi = hi.cwiseMax(b.footprintMax);
    }
    PressureMatOptions o;
    o.rows = rows;
    o.columns = columns;
    o.origin = lo;
    o.size = hi - lo;
    return o;
}

}  // namespace cosim
