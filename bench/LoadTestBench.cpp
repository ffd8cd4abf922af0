// Benchmark of the seed load test: one 0-50 N curve and the whole gas-mass sweep at a given
// mesh size. Prints wall time, Newton iterations and peak memory. Not a test: run by hand,
// see docs/performance.md.
//
//   build/bin/bench_load_test [mesh_mm=5] [masses: all|one] [threads]
#include <bags/LoadTest.h>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#ifdef _OPENMP
#include <omp.h>
#endif

int main(int argc, char** argv) {
    const double meshMm = argc > 1 ? std::atof(argv[1]) : 5.0;
    const bool all = !(argc > 2 && std::strcmp(argv[2], "one") == 0);
#ifdef _OPENMP
    if (argc > 3) omp_set_num_threads(std::atoi(argv[3]));
#endif
    bags::LoadTestOptions o;
    o.geometry.meshSize = meshMm * 1e-3;
    o.material = bags::makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    if (all)
        for (int i = 0; i <= 10; ++i) o.gasMasses.push_back((3.5 - 0.25 * i) * 1e-3);
    else
        o.gasMasses = {3.5e-3};
    int nodes = 0, tris = 0, steps = 0, iterations = 0;
    const auto t0 = std::chrono::steady_clock::now();
    double tFirst = -1.0;
    const bags::LoadTestResult r = bags::runLoadTest(
        o, [&](const bags::LoadStep& s, const bags::Mesh& m, const Eigen::Matrix3Xd&) {
            nodes = m.getNumNodes();
            tris = m.getNumTris();
            ++steps;
            iterations += s.newtonIterations;
            if (s.curve == 1 && tFirst < 0.0)
                tFirst = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        });
    const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    std::printf("mesh %.2f mm: %d nodes, %d triangles\n", meshMm, nodes, tris);
    for (const auto& c : r.curves)
        std::printf("  %.2f g: %zu steps, k = %.3f N/mm, r2 = %.4f, stage %d, peak %s\n",
                    c.gasMass * 1e3, c.steps.size(), c.stiffness * 1e-3, c.r2, c.stage,
                    c.reachedPeak ? "yes" : "no");
    std::printf("steps %d, Newton iterations %d\n", steps, iterations);
    if (tFirst > 0) std::printf("inflation + first curve: %.2f s\n", tFirst);
    std::printf("total wall time: %.2f s\n", total);
    std::printf("peak resident memory: %.1f MB\n", ru.ru_maxrss / 1024.0);
    return 0;
}
