#pragma once
// Small hand-made meshes for element and solver tests (independent of the generators).
#include <bags/Mesh.h>

namespace bags::test {

/// Flat nx x ny-cell grid of lx x ly in the x-y plane, normals +z, no chambers; each cell
/// split along alternating diagonals (`alternate`, the union-jack-like pattern) or all along
/// the same one.
inline Mesh makeGrid(int nx, int ny, double lx, double ly, bool alternate) {
    Mesh m;
    m.X.resize(3, (nx + 1) * (ny + 1));
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i)
            m.X.col(j * (nx + 1) + i) = Vec3(lx * i / nx, ly * j / ny, 0.0);
    m.tris.resize(3, 2 * nx * ny);
    int t = 0;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
            if (!alternate || (i + j) % 2 == 0) {
                m.tris.col(t++) = Eigen::Vector3i(a, b, d);
                m.tris.col(t++) = Eigen::Vector3i(a, d, c);
            } else {
                m.tris.col(t++) = Eigen::Vector3i(a, b, c);
                m.tris.col(t++) = Eigen::Vector3i(b, d, c);
            }
        }
    m.triPanel.assign(m.getNumTris(), 0);
    m.panelNames = {"patch"};
    return m;
}

/// Flat n x n-cell square patch of edge `edge`, alternating diagonals.
inline Mesh makePatch(int n, double edge) { return makeGrid(n, n, edge, edge, true); }

/// Removes the rigid-body modes of a sphere centred at the origin with nodes on the axes
/// (icosphere, refinement >= 1): the poles move along z only, the +x equator node stays in
/// the x-z plane at z = 0. Six constraints, radial growth stays free. Returns false if the
/// mesh has no such nodes.
inline bool fixSphereRigidModes(Mesh& m) {
    int top = 0, bottom = 0, eq = -1;
    const double R = m.X.col(0).norm();
    m.X.row(2).maxCoeff(&top);
    m.X.row(2).minCoeff(&bottom);
    for (int i = 0; i < m.getNumNodes(); ++i)
        if ((m.X.col(i) - Vec3(R, 0, 0)).norm() < 1e-9 * R) eq = i;
    if (eq < 0 || m.X.col(top).head<2>().norm() > 1e-9 * R) return false;
    m.fixedDofs = {3 * top, 3 * top + 1, 3 * bottom, 3 * bottom + 1, 3 * eq + 1, 3 * eq + 2};
    return true;
}

}  // namespace bags::test
