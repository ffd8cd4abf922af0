#include "cosim/ArrayShapes.h"

#include <bags/Airbag.h>

#include <cmath>
#include <stdexcept>

#include "cosim/BagParticipant.h"

namespace cosim {

namespace {

// The bag's film, or null for a bag without one (a ReducedBag: no surface is drawn).
const bags::Mesh* findFilm(const PatientOnArray& poa, int bag) {
    return poa.getBag(bag).getFilmMesh();
}

}  // namespace

SurfaceMesh makeBagSurfaces(const PatientOnArray& poa) {
    SurfaceMesh m;
    const std::vector<int>& indices = poa.getBagIndices();
    int nodes = 0, tris = 0;
    for (size_t b = 0; b < indices.size(); ++b)
        if (const bags::Mesh* f = findFilm(poa, int(b))) tris += f->getNumTris();
    m.triangles.resize(3, tris);
    m.triangleGroup.reserve(size_t(tris));
    int t = 0;
    for (size_t b = 0; b < indices.size(); ++b) {
        const bags::Mesh* film = findFilm(poa, int(b));
        if (!film) continue;
        const bags::Mesh& mesh = *film;
        for (int k = 0; k < mesh.getNumTris(); ++k, ++t) {
            m.triangles.col(t) = mesh.tris.col(k).array() + nodes;
            m.triangleGroup.push_back(indices[b]);
        }
        nodes += mesh.getNumNodes();
    }
    int maxIndex = -1;
    for (int i : indices) maxIndex = std::max(maxIndex, i);
    for (int i = 0; i <= maxIndex; ++i) m.groupNames.push_back("bag " + std::to_string(i));
    return m;
}

Eigen::Matrix3Xd calcBagSurfacePositions(const PatientOnArray& poa) {
    int nodes = 0;
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b)
        if (findFilm(poa, int(b))) nodes += int(poa.getBag(int(b)).getPressurePoints().cols());
    Eigen::Matrix3Xd x(3, nodes);
    int at = 0;
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        if (!findFilm(poa, int(b))) continue;
        const Eigen::Matrix3Xd& p = poa.getBag(int(b)).getPressurePoints();
        x.middleCols(at, p.cols()) = p;
        at += int(p.cols());
    }
    return x;
}

BodySurface makeBodySurface(const body::BodyModel& model, int rings, int sectors) {
    if (rings < 2 || rings % 2 != 0 || sectors < 3)
        throw std::invalid_argument(
            "makeBodySurface: rings must be even and at least 2, "
            "sectors at least 3");
    BodySurface s;
    const double pi = 3.14159265358979323846;
    std::vector<Eigen::Vector3i> tris;
    std::vector<Eigen::Vector3d> nodes;
    for (int seg = 0; seg < body::kSegmentCount; ++seg) {
        const body::ContactShape& shape = model.getContactShape(body::Segment(seg));
        // The axis: a round cone's from sphere A to B, an ellipsoid's third.
        SimTK::UnitVec3 a;
        if (shape.getKind() == body::ContactShape::Kind::RoundCone)
            a = SimTK::UnitVec3(shape.getPointB() - shape.getPointA());
        else
            a = shape.getEllipsoidPose().R().z();
        const SimTK::UnitVec3 u = a.perp();
        const SimTK::UnitVec3 v(SimTK::cross(a, u));
        const int first = int(nodes.size());
        // An ellipsoid: its own parametrization (semi-axes times the unit direction in its
        // frame) spreads the nodes evenly; a round cone: its support point in the direction.
        const bool ellipsoid = shape.getKind() == body::ContactShape::Kind::Ellipsoid;
        auto add = [&](const SimTK::Vec3& d) {
            SimTK::Vec3 p;
            if (ellipsoid) {
                const SimTK::Transform& X_BS = shape.getEllipsoidPose();
                const SimTK::Vec3 d_S = ~X_BS.R() * d;
                p = X_BS * SimTK::Vec3(shape.getSemiAxes()[0] * d_S[0],
                                       shape.getSemiAxes()[1] * d_S[1],
                                       shape.getSemiAxes()[2] * d_S[2]);
            } else {
                p = shape.calcSupportPoint(d);
            }
            nodes.emplace_back(p[0], p[1], p[2]);
            s.nodeSegment.push_back(seg);
        };
        add(-SimTK::Vec3(a));  // south pole (towards A)
        for (int i = 0; i < rings; ++i) {
            const double theta = pi * (i + 0.5) / rings;  // from the south pole
            for (int j = 0; j < sectors; ++j) {
                const double phi = 2.0 * pi * j / sectors;
                add(-std::cos(theta) * SimTK::Vec3(a) +
                    std::sin(theta) *
                        (std::cos(phi) * SimTK::Vec3(u) + std::sin(phi) * SimTK::Vec3(v)));
            }
        }
        add(SimTK::Vec3(a));  // north pole
        const int south = first, north = first + 1 + rings * sectors;
        auto node = [&](int i, int j) { return first + 1 + i * sectors + (j % sectors); };
        // (u, v, a) is right-handed: going round in +phi seen from +a is counter-clockwise.
        for (int j = 0; j < sectors; ++j) {
            tris.emplace_back(south, node(0, j + 1), node(0, j));
            for (int i = 0; i + 1 < rings; ++i) {
                tris.emplace_back(node(i, j), node(i, j + 1), node(i + 1, j + 1));
                tris.emplace_back(node(i, j), node(i + 1, j + 1), node(i + 1, j));
            }
            tris.emplace_back(north, node(rings - 1, j), node(rings - 1, j + 1));
        }
        s.mesh.triangleGroup.resize(tris.size(), seg);
        s.mesh.groupNames.push_back(body::getSegmentName(body::Segment(seg)));
    }
    s.p_B.resize(3, Eigen::Index(nodes.size()));
    for (size_t i = 0; i < nodes.size(); ++i) s.p_B.col(Eigen::Index(i)) = nodes[i];
    s.mesh.triangles.resize(3, Eigen::Index(tris.size()));
    for (size_t i = 0; i < tris.size(); ++i) s.mesh.triangles.col(Eigen::Index(i)) = tris[i];
    return s;
}

Eigen::Matrix3Xd calcBodySurfacePositions(const body::BodyModel& model, const SimTK::State& state,
                                          const BodySurface& surface) {
    Eigen::Matrix3Xd x(3, surface.p_B.cols());
    for (Eigen::Index i = 0; i < surface.p_B.cols(); ++i) {
        const SimTK::Transform& X_GB =
            model.getMobilizedBody(body::Segment(surface.nodeSegment[size_t(i)]))
                .getBodyTransform(state);
        const SimTK::Vec3 p =
            X_GB * SimTK::Vec3(surface.p_B(0, i), surface.p_B(1, i), surface.p_B(2, i));
        x.col(i) << p[0], p[1], p[2];
    }
    return x;
}

}  // namespace cosim
