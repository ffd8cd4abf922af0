// Cost of the membrane's bending term (DiscreteBending) against its element loop: one call of
// MembraneModel::addMembraneEnergy with and without bending (energy + gradient, and energy +
// gradient + Hessian triplets) and of the bending term alone, on the double wedge at a few
// mesh sizes (docs/performance.md). Not a test: run by hand.
//
//   build/bin/bench_bending [mesh_mm ...]     (default: 10 5)
#include <bags/Bending.h>
#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/MaterialFit.h>
#include <bags/EquilibriumSolver.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

// Best of five batches (milliseconds per call): the machine is shared.
template <class F>
double millisecondsPerCall(int calls, const F& f) {
    double best = 1e300;
    for (int batch = 0; batch < 5; ++batch) {
        const auto t0 = Clock::now();
        for (int k = 0; k < calls; ++k) f();
        best =
            std::min(best, 1e3 * std::chrono::duration<double>(Clock::now() - t0).count() / calls);
    }
    return best;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<double> sizesMm;
    for (int i = 1; i < argc; ++i) sizesMm.push_back(std::atof(argv[i]));
    if (sizesMm.empty()) sizesMm = {10.0, 5.0};
    std::printf(
        "mesh_mm tris hinges | membrane g / g+H [ms] | with bending g / g+H [ms] | "
        "bending alone g / g+H [ms] | triplets membrane / bending\n");
    for (double mm : sizesMm) {
        if (!(mm >= 2.0 && mm <= 50.0)) {
            std::fprintf(stderr, "bench_bending: mesh size %g is invalid; use 2 to 50 (mm)\n", mm);
            return 2;
        }
        bags::DoubleWedgeParams p;
        p.meshSize = mm * 1e-3;
        const bags::Mesh mesh = bags::makeDoubleWedgeBag(p);
        auto material = std::make_shared<bags::WrinklingMaterial>(
            bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6), 1e-3);
        bags::MembraneModel model(mesh, material, 0.2e-3);
        // A stretched, wrinkled-looking state: 1 % growth and 0.3 mm noise.
        std::mt19937 rng(1);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        Eigen::Matrix3Xd x = 1.01 * mesh.X;
        for (int i = 0; i < x.cols(); ++i)
            for (int d = 0; d < 3; ++d) x(d, i) += 3e-4 * u(rng);
        const int calls = mm >= 8.0 ? 40 : 10;
        auto run = [&](bool hessian, size_t* triplets) {
            return millisecondsPerCall(calls, [&] {
                bags::EnergyAccumulator acc(mesh.getNumNodes());
                acc.wantHessian = hessian;
                model.addMembraneEnergy(x, acc);
                if (triplets) *triplets = acc.hess.size();
            });
        };
        size_t tripletsPlain = 0, tripletsBent = 0;
        const double plainG = run(false, nullptr), plainH = run(true, &tripletsPlain);
        const double D = bags::calcPlateBendingStiffness(*material, 0.2e-3);
        model.setBendingStiffness(D);
        const double bentG = run(false, nullptr), bentH = run(true, &tripletsBent);
        bags::BendingOptions o;
        o.stiffness = D;
        const bags::DiscreteBending bending(mesh, o);
        auto alone = [&](bool hessian) {
            return millisecondsPerCall(calls, [&] {
                bags::EnergyAccumulator acc(mesh.getNumNodes());
                acc.wantHessian = hessian;
                bending.addEnergy(x, acc);
            });
        };
        const double aloneG = alone(false), aloneH = alone(true);
        std::printf("%7.1f %5d %6d | %7.2f / %7.2f | %7.2f / %7.2f | %7.2f / %7.2f | %zu / %zu\n",
                    mm, mesh.getNumTris(), bending.getNumHinges(), plainG, plainH, bentG, bentH,
                    aloneG, aloneH, tripletsPlain, tripletsBent - tripletsPlain);
    }
    return 0;
}
