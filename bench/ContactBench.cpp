// Cost of the contact terms on meshes of the size the airbag solver uses (run by hand; see
// docs/contact.md). Prints the time per call of RigidContact::addEnergy (the hot path, called
// every Newton iteration) and of SelfContact::updateCandidates / addEnergy.
//
//   build/bin/bagsim_contact_bench [nodesPerSide=91]

#include <bags/Contact.h>

#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace {

bags::Mesh makeGrid(int n, double s, double z) {
    bags::Mesh m;
    m.X.resize(3, n * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) m.X.col(j * n + i) = bags::Vec3(i * s, j * s, z);
    m.tris.resize(3, 2 * (n - 1) * (n - 1));
    int t = 0;
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
            m.tris.col(t++) << a, b, d;
            m.tris.col(t++) << a, d, c;
        }
    return m;
}

template <class F>
double secondsPerCall(F&& f) {
    using Clock = std::chrono::steady_clock;
    int reps = 1;
    for (;;) {
        const auto t0 = Clock::now();
        for (int r = 0; r < reps; ++r) f();
        const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
        if (dt > 0.3) return dt / reps;
        reps *= 2;
    }
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 91;  // 91 x 91 = 8281 nodes, 5 mm spacing
    const double s = 0.005;
    const bags::Mesh grid = makeGrid(n, s, 0.0);
    const double L = (n - 1) * s;
    std::vector<int> nodes(grid.getNumNodes());
    for (int i = 0; i < grid.getNumNodes(); ++i) nodes[i] = i;
    std::printf("contact bench: %d nodes, %d triangles, %d OpenMP threads\n", grid.getNumNodes(),
                grid.getNumTris(), omp_get_max_threads());

    // A block (rounded box) and an ellipsoid pressed 5 mm into the middle of the sheet.
    auto box = bags::makeBox(bags::Vec3(0.025, 0.025, 0.025), 0.002);
    auto ell = bags::makeEllipsoid(bags::Vec3(0.2, 0.15, 0.1));
    auto plane = bags::makePlane();
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = bags::Vec3(0.5 * L, 0.5 * L, 0.025 - 0.005);
    box->setPose(X);
    X.translation() = bags::Vec3(0.5 * L, 0.5 * L, 0.1 - 0.005);
    ell->setPose(X);
    X.translation() = bags::Vec3(0, 0, 1e-3);
    plane->setPose(X);
    for (const bags::RigidShape* shape : {plane.get(), box.get(), ell.get()}) {
        for (double mu : {0.0, 0.4}) {
            for (int threshold : {1 << 30, 1}) {
                bags::RigidContact::Options o;
                o.friction = mu;
                o.minNodesForThreads = threshold;
                bags::RigidContact c(grid, nodes, *shape, o);
                c.commitStep(grid.X);
                Eigen::Matrix3Xd x = grid.X;
                x.row(0).array() += 1e-4;
                bags::EnergyAccumulator acc(grid.getNumNodes());
                const double t = secondsPerCall([&] {
                    acc.resize(grid.getNumNodes());
                    c.addEnergy(x, acc);
                });
                std::printf("  RigidContact %-9s mu=%.1f %-8s active %5d  addEnergy %8.3f ms\n",
                            shape->getName().c_str(), mu, threshold == 1 ? "threads" : "serial",
                            c.getNumActive(x), 1e3 * t);
            }
        }
    }

    // Two sheets 0.5 mm apart (thickness 1 mm): every node of each touches the other.
    const bags::Mesh top = makeGrid(n, s, 0.5e-3);
    bags::Mesh two;
    two.X.resize(3, 2 * grid.getNumNodes());
    two.X << grid.X, top.X;
    two.tris.resize(3, 2 * grid.getNumTris());
    two.tris << grid.tris, (top.tris.array() + grid.getNumNodes()).matrix();
    bags::SelfContact sc(two, bags::SelfContact::Options());
    const double tu = secondsPerCall([&] { sc.updateCandidates(two.X); });
    bags::EnergyAccumulator acc(two.getNumNodes());
    const double te = secondsPerCall([&] {
        acc.resize(two.getNumNodes());
        sc.addEnergy(two.X, acc);
    });
    std::printf("  SelfContact  %d nodes: %zu candidate pairs, %d active nodes\n",
                two.getNumNodes(), sc.getCandidatePairs().size(), sc.getNumActive(two.X));
    std::printf("  SelfContact  updateCandidates %8.3f ms, addEnergy %8.3f ms\n", 1e3 * tu,
                1e3 * te);
    return 0;
}
