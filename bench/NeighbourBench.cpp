// Measurement, not a test: how much do neighbours change a bag's stiffness? The seed's 50 mm
// block presses the middle bag of a row of 1, 2 or 3 bags side by side across their width
// (one module, AirbagSpec::cluster; their walls meet through its self-contact), displacement
// controlled in 1 mm steps up to 35 N; the 10-35 N stiffness of each (least squares) and the
// force the neighbours take. docs/airbag-module.md.
//
//   build/bin/bench_neighbours [--gap MM] [--scale F] MESH_MM OWN_MASS_G [NEIGHBOUR_MASS_G]
#include <bags/Airbag.h>
#include <bags/Bending.h>
#include <bags/LoadTest.h>
#include <bags/MaterialFit.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace {

Eigen::Isometry3d translation(const bags::Vec3& p) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = p;
    return X;
}

}  // namespace

int main(int argc, char** argv) {
    double gap = 5e-3, scale = 1.0;
    int first = 1;
    while (first + 1 < argc && std::strncmp(argv[first], "--", 2) == 0) {
        if (!std::strcmp(argv[first], "--gap"))
            gap = std::atof(argv[first + 1]) * 1e-3;
        else if (!std::strcmp(argv[first], "--scale"))
            scale = std::atof(argv[first + 1]);
        else {
            std::fprintf(stderr, "bench_neighbours: unknown option %s\n", argv[first]);
            return 2;
        }
        first += 2;
    }
    if (argc < first + 2) {
        std::fprintf(
            stderr, "usage: bench_neighbours [--gap MM] [--scale F] MESH_MM OWN_G [NEIGHBOUR_G]\n");
        return 2;
    }
    bags::LoadTestOptions o;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.geometry.meshSize = std::atof(argv[first]) * 1e-3;
    o.geometry.longSide *= scale;
    o.geometry.shortSide *= scale;
    o.geometry.height *= scale;
    o.bendingStiffness = bags::calcPlateBendingStiffness(*o.material, o.thickness);
    o.blockContact.pressurePenalty = o.floorContact.pressurePenalty = 1e8;
    const double own = std::atof(argv[first + 1]) * 1e-3;
    const double other = argc > first + 2 ? std::atof(argv[first + 2]) * 1e-3 : own;
    const double pitch = o.geometry.width + gap;
    std::printf("mesh %.1f mm, gap %.1f mm, own %.2f g, neighbours %.2f g\n",
                o.geometry.meshSize * 1e3, gap * 1e3, own * 1e3, other * 1e3);
    for (int n : {1, 2, 3}) {
        const auto t0 = std::chrono::steady_clock::now();
        bags::AirbagSpec spec = bags::makeAirbagSpec(o);
        spec.forceTolerance = 0.01;
        // Bag 0 is pressed; with 2 its neighbour is at +y, with 3 one on each side.
        const std::vector<double> ys = n == 1   ? std::vector<double>{0.0}
                                       : n == 2 ? std::vector<double>{0.0, pitch}
                                                : std::vector<double>{0.0, -pitch, pitch};
        for (double y : ys) spec.cluster.push_back(translation(bags::Vec3(0, y, 0)));
        bags::Airbag bag(spec);
        const auto [b0, e0] = bag.getBagNodes(0);
        int apex = b0;
        for (int i = b0; i < e0; ++i)
            if (bag.getMesh().X(2, i) > bag.getMesh().X(2, apex)) apex = i;
        const double half = 0.5 * o.blockSize, hh = 0.01;
        std::shared_ptr<bags::RigidShape> block(bags::makeBox(bags::Vec3(half, half, hh), 1e-3));
        const bags::Vec3 c(bag.getMesh().X(0, apex), 0.0, 0.0);
        block->setPose(translation(c + bags::Vec3(0, 0, 0.5)));
        const int s = bag.addShape(block, o.blockContact);
        std::vector<double> masses(n, other);
        masses[0] = own;
        bag.inflate(masses);
        double top = -1.0;
        for (int i = b0; i < e0; ++i)
            if (std::abs(bag.getPositions()(0, i) - c.x()) <= half &&
                std::abs(bag.getPositions()(1, i)) <= half)
                top = std::max(top, bag.getPositions()(2, i));
        std::vector<double> d, f;
        double force = 0.0, travel = 0.0;
        int iterations = 0;
        bool ok = true;
        while (force < 35.0 && travel < 0.08) {
            travel += 1e-3;
            bag.setShapePose(s, translation(c + bags::Vec3(0, 0, top - travel + hh)));
            const bags::AdvanceSummary sum = bag.advance(travel / o.loadingRate, 8);
            if (!sum.converged) {
                ok = false;
                break;
            }
            bag.commit();
            iterations += sum.newtonIterations;
            force = bag.calcShapeWrench(s).force.z();
            d.push_back(travel);
            f.push_back(force);
        }
        // Least-squares slope over 10-35 N.
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        int m = 0;
        for (size_t i = 0; i < d.size(); ++i)
            if (f[i] >= 10.0 && f[i] <= 35.0) {
                sx += d[i], sy += f[i], sxx += d[i] * d[i], sxy += d[i] * f[i];
                ++m;
            }
        const double k = m >= 2 ? (m * sxy - sx * sy) / (m * sxx - sx * sx) : 0.0;
        const double wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf(
            "  %d bag%s: k 10-35 N = %.3f N/mm over %d points, F = %.2f N at %.0f mm, "
            "pressed bag %.2f kPa, neighbour force on it %.2f N (y), %d Newton "
            "iterations, %.1f s%s\n",
            n, n > 1 ? "s" : " ", k * 1e-3, m, force, travel * 1e3,
            bag.getChamberState(bag.getBagChambers(0).front()).gaugePressure * 1e-3,
            bag.calcNeighbourForce(0).y(), iterations, wall,
            ok ? "" : " (stopped: no convergence)");
        std::fflush(stdout);
    }
    return 0;
}
