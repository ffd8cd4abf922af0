// Benchmark of the seed load test: one 0-50 N curve and the whole gas-mass sweep at a given
// mesh size. Prints wall time, Newton iterations and peak memory. Not a test: run by hand,
// see docs/performance.md.
//
//   build/bin/bench_load_test [--step MM] [--bending N_M|plate] [--imperfection MM]
//                             [--seed N] [--threads N] [--scale F] [--verbose 1] [--sparsify 0|1]
//                             [--predictor 0|1] [--low-force-steps F]
//                             [--dynamic 0|1] [--block-speed MM_PER_S] [--mass-scale S]
//                             [--film-damping PER_S] [--record-every MM] [--halvings N]
//                             [mesh_mm=5] [gas masses in g ... | seed]
// --dynamic 1: the film integrated in time (LoadTestOptions::stepping Dynamic) with the other
// --block-speed ... options of LoadTestOptions::Dynamic.
// "seed" (the default) runs the seed's sweep 3.5 g down to 1.0 g in 0.25 g steps; --step sets
// the target block increment (default 1 mm, as the scenario).
#include <bags/LoadTest.h>
#include <bags/SeedReading.h>
#include <bags/Bending.h>
#include <bags/MaterialFit.h>

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <stdexcept>

// Force [N] at block travel d [m] on a curve's loading branch (linear between steps), NaN if
// the branch does not reach d.
double forceAt(const bags::LoadCurve& c, double d) {
    for (size_t i = 1; i < c.steps.size(); ++i) {
        const bags::LoadStep &a = c.steps[i - 1], &b = c.steps[i];
        if (!a.loading || !b.loading || b.displacement < d) continue;
        return a.force +
               (b.force - a.force) * (d - a.displacement) / (b.displacement - a.displacement);
    }
    return std::nan("");
}

int main(int argc, char** argv) {
    bags::LoadTestOptions o;
    int first = 1;
    bool verbose = false;
    double fillMass = 0.0;  // [kg] --fill-mass G: profile scaled until G just fills the bag
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    // Leading options: --step MM, --bending N_M|plate, --imperfection MM, --seed N,
    // --threads N, --scale F (the x-z profile scaled by F), --pattern legacy|mirrored|crossed.
    while (first + 1 < argc && std::strncmp(argv[first], "--", 2) == 0) {
        const char* key = argv[first];
        const char* val = argv[first + 1];
        if (std::strcmp(key, "--step") == 0) {
            o.displacementStep = std::atof(val) * 1e-3;
        } else if (std::strcmp(key, "--bending") == 0) {
            o.bendingStiffness = std::strcmp(val, "plate") == 0
                                     ? bags::calcPlateBendingStiffness(*o.material, o.thickness)
                                     : std::atof(val);
        } else if (std::strcmp(key, "--imperfection") == 0) {
            o.imperfection.amplitude = std::atof(val) * 1e-3;
        } else if (std::strcmp(key, "--seed") == 0) {
            o.imperfection.seed = static_cast<std::uint64_t>(std::atoll(val));
        } else if (std::strcmp(key, "--low-force-steps") == 0) {
            o.lowForceStepFactor = std::atof(val);
        } else if (std::strcmp(key, "--predictor") == 0) {
            o.predictor = std::atoi(val) != 0;
        } else if (std::strcmp(key, "--sparsify") == 0) {
            o.solver.sparsifyWideCouplings = std::atoi(val) != 0;
        } else if (std::strcmp(key, "--damping") == 0) {
            o.damping = std::atof(val);
        } else if (std::strcmp(key, "--dynamic") == 0) {
            o.stepping = std::atoi(val) != 0 ? bags::AirbagSpec::Stepping::Dynamic
                                             : bags::AirbagSpec::Stepping::QuasiStatic;
        } else if (std::strcmp(key, "--block-speed") == 0) {
            o.dynamic.blockSpeed = std::atof(val) * 1e-3;
        } else if (std::strcmp(key, "--mass-scale") == 0) {
            o.dynamic.massScale = std::atof(val);
        } else if (std::strcmp(key, "--film-damping") == 0) {
            o.dynamic.damping = std::atof(val);
        } else if (std::strcmp(key, "--record-every") == 0) {
            o.dynamic.recordEvery = std::atof(val) * 1e-3;
        } else if (std::strcmp(key, "--halvings") == 0) {
            o.dynamic.maxHalvings = std::atoi(val);
        } else if (std::strcmp(key, "--step-fraction") == 0) {
            o.dynamic.stepFraction = std::atof(val);
        } else if (std::strcmp(key, "--onset") == 0) {
            o.blockContact.onsetGap = o.floorContact.onsetGap = std::atof(val) * 1e-3;
        } else if (std::strcmp(key, "--krylov-tolerance") == 0) {
            o.solver.krylovTolerance = std::atof(val);
        } else if (std::strcmp(key, "--forcing") == 0) {
            o.solver.forcingTerm = std::atof(val);
        } else if (std::strcmp(key, "--residual-tolerance") == 0) {
            o.residualTolerance = std::atof(val);
        } else if (std::strcmp(key, "--self") == 0) {
            o.selfContact = std::atoi(val) != 0;
        } else if (std::strcmp(key, "--wrinkling") == 0) {
            o.wrinklingResidual = std::atof(val);
        } else if (std::strcmp(key, "--penalty") == 0) {
            o.blockContact.pressurePenalty = o.floorContact.pressurePenalty = std::atof(val);
        } else if (std::strcmp(key, "--monitor") == 0) {
            if (std::atoi(val) != 0)
                o.solver.monitor = [](int it, double r, double alpha, double shift) {
                    std::printf("        it %2d residual %.3e N alpha %.3g shift %.3g\n", it, r,
                                alpha, shift);
                };
        } else if (std::strcmp(key, "--verbose") == 0) {
            verbose = std::atoi(val) != 0;
        } else if (std::strcmp(key, "--threads") == 0) {
            o.threads = std::atoi(val);
        } else if (std::strcmp(key, "--pattern") == 0) {
            if (std::strcmp(val, "crossed") == 0) {
                o.geometry.pattern = bags::MeshPattern::Crossed;
            } else if (std::strcmp(val, "mirrored") == 0) {
                o.geometry.pattern = bags::MeshPattern::Mirrored;
            } else if (std::strcmp(val, "legacy") == 0) {
                o.geometry.pattern = bags::MeshPattern::Legacy;
            } else {
                std::fprintf(stderr,
                             "bench_load_test: --pattern %s: valid are legacy, mirrored, crossed\n",
                             val);
                return 2;
            }
        } else if (std::strcmp(key, "--fill-mass") == 0) {
            fillMass = std::atof(val) * 1e-3;
        } else if (std::strcmp(key, "--scale") == 0) {
            const double f = std::atof(val);
            o.geometry.longSide *= f;
            o.geometry.shortSide *= f;
            o.geometry.height *= f;
        } else {
            std::fprintf(stderr, "bench_load_test: unknown option %s\n", key);
            return 2;
        }
        first += 2;
    }
    const double meshMm = argc > first ? std::atof(argv[first]) : 5.0;
    o.geometry.meshSize = meshMm * 1e-3;
    for (int i = first + 1; i < argc; ++i)
        if (std::strcmp(argv[i], "seed") != 0) o.gasMasses.push_back(std::atof(argv[i]) * 1e-3);
    if (o.gasMasses.empty())
        for (int i = 0; i <= 10; ++i) o.gasMasses.push_back((3.5 - 0.25 * i) * 1e-3);
    if (fillMass > 0.0) {
        // As `airbag.fill_mass` with `fill_scaling: profile` in a scenario (after --scale).
        const bags::FillScaleResult fs =
            bags::findFillScale(o, fillMass, bags::FillScaling::Profile);
        o.geometry = fs.geometry;
        std::printf("fill mass %.4f g: profile scale %.6f\n", fillMass * 1e3, fs.scale);
    }
    int nodes = 0, tris = 0, steps = 0, iterations = 0, loadingSteps = 0;
    long substeps = 0;
    const auto t0 = std::chrono::steady_clock::now();
    double tFirst = -1.0, tInflated = -1.0;
    bags::LoadTestResult r;
    try {
        o.validate();
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr,
                     "bench_load_test: %s\nusage: bench_load_test [--step MM] MESH_MM "
                     "[GAS_MASS_G ... | seed]\n",
                     e.what());
        return 2;
    }
    r = bags::runLoadTest(o, [&](const bags::LoadStep& s, const bags::Mesh& m,
                                 const Eigen::Matrix3Xd&) {
        nodes = m.getNumNodes();
        tris = m.getNumTris();
        ++steps;
        if (s.loading) ++loadingSteps;
        iterations += s.newtonIterations;
        substeps += s.substeps;
        if (verbose && o.stepping == bags::AirbagSpec::Stepping::Dynamic)
            std::printf(
                "    curve %d step %3d %s d = %7.3f mm F = %8.3f N substeps %6d "
                "KE %.3e J residual %.2e N t = %.1f s\n",
                s.curve, s.step, s.loading ? "load  " : "unload", s.displacement * 1e3, s.force,
                s.substeps, s.kineticEnergy, s.residual,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        else if (verbose)
            std::printf(
                "    curve %d step %3d %s d = %7.3f mm F = %8.3f N iterations %4d "
                "factorisations %3d residual %.2e N springs %.2e J t = %.1f s\n",
                s.curve, s.step, s.loading ? "load  " : "unload", s.displacement * 1e3, s.force,
                s.newtonIterations, s.factorizations, s.residual, s.stabilizationEnergy,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (tInflated < 0.0)
            tInflated =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (s.curve == 1 && tFirst < 0.0)
            tFirst = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    });
    const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    std::printf("mesh %.2f mm: %d nodes, %d triangles\n", meshMm, nodes, tris);
    for (const auto& c : r.curves) {
        double work = 0.0, held = 0.0;
        for (size_t i = 1; i < c.steps.size(); ++i)
            if (c.steps[i].loading) {
                work += 0.5 * (c.steps[i].force + c.steps[i - 1].force) *
                        (c.steps[i].displacement - c.steps[i - 1].displacement);
                held += c.steps[i].stabilizationEnergy;
            }
        std::printf("  %.2f g: loading work %.4f J, springs/damping %.3g J (%.2g)\n",
                    c.gasMass * 1e3, work, held, work > 0 ? held / work : 0.0);
        std::printf(
            "  %.2f g: p0 %.2f kPa, %zu steps, k = %.3f N/mm, r2 = %.4f, F(5 mm) = %.2f N, "
            "stage %d, peak %s, springs' share %.2g%s%s\n",
            c.gasMass * 1e3, c.inflatedGaugePressure * 1e-3, c.steps.size(), c.stiffness * 1e-3,
            c.r2, forceAt(c, 5e-3), c.stage, c.reachedPeak ? "yes" : "no", c.stabilizationShare,
            c.failure.empty() ? "" : ", stopped: ", c.failure.c_str());
        if (c.blockSpeed > 0.0)
            std::printf("  %.2f g: dynamic, block %.2f mm/s, kinetic share %.2g%s\n",
                        c.gasMass * 1e3, c.blockSpeed * 1e3, c.kineticShare,
                        c.quasiStatic ? "" : " (not quasi-static)");
    }
    std::printf("steps %d (loading %d), Newton iterations %d, explicit sub-steps %ld\n", steps,
                loadingSteps, iterations, substeps);
    if (tFirst > 0)
        std::printf("inflation + first curve (loading and unloading): %.2f s\n", tFirst);
    std::printf("inflation (flat panels to the first gas mass): %.2f s\n", tInflated);
    std::printf("total wall time: %.2f s\n", total);
    std::printf("peak resident memory: %.1f MB\n", ru.ru_maxrss / 1024.0);
    return 0;
}
