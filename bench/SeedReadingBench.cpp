// The seed's bag read from its words: the scale of the double wedge that a fill mass gives,
// how precisely the search finds it, and (optionally) load curves of the scaled bag. Not a
// test: run by hand, see docs/geometry.md ("The seed's bag read from its words").
//
//   build/bin/bench_seed_reading [--probes HIGH LOW] [mesh_mm=10] [profile|uniform|height]
//                                [fill_g ... = 2.7 2.8 2.9]
//   build/bin/bench_seed_reading --curves MESH_MM FILL_G GAS_MASS_G ...
//
// The first form finds the scale for each fill mass, prints the resolved sizes, every
// measurement of the search, and the unloaded gauge pressure of the scaled bag at the fill
// mass and 0.05 and 0.1 g either side (a check of the extrapolated fill mass). --probes sets
// the probe masses as multiples of the fill mass (FillMassOptions). The second form finds
// the profile scale for one fill mass and runs the seed's load test (0-50 N, scenario
// settings) at the gas masses given.
#include <bags/LoadTest.h>
#include <bags/MaterialFit.h>
#include <bags/SeedReading.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace {

bags::LoadTestOptions makeSeedRig(double meshMm) {
    bags::LoadTestOptions o;  // defaults are the seed scenario's settings
    o.geometry.meshSize = meshMm * 1e-3;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    return o;
}

void printScale(const bags::FillScaleResult& r, double target) {
    const bags::DoubleWedgeParams& g = r.geometry;
    std::printf(
        "fill %.3f g: s = %.4f -> long %.1f, short %.1f, width %.1f, height %.1f mm; "
        "measured %.4f g (from p(m): %.4f g); %zu measurements, %.1f s\n",
        target * 1e3, r.scale, g.longSide * 1e3, g.shortSide * 1e3, g.width * 1e3, g.height * 1e3,
        r.measurement.fillMass * 1e3, r.measurement.fillMassFromPressure * 1e3, r.scales.size(),
        r.seconds);
    for (size_t i = 0; i < r.scales.size(); ++i)
        std::printf("    s = %.5f: fill %.4f g\n", r.scales[i], r.fillMasses[i] * 1e3);
    const bags::FillMassMeasurement& m = r.measurement;
    for (int i = 0; i < 2; ++i)
        std::printf("    probe %.3f g: %.4f L, %.2f kPa, top %.1f mm\n", m.probeMass[i] * 1e3,
                    m.probeVolume[i] * 1e3, m.probePressure[i] * 1e-3, m.probeHeight[i] * 1e3);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc > 1 && std::strcmp(argv[1], "--curves") == 0) {
            if (argc < 5) {
                std::fprintf(stderr,
                             "usage: bench_seed_reading --curves MESH_MM FILL_G GAS_MASS_G ...\n");
                return 2;
            }
            bags::LoadTestOptions o = makeSeedRig(std::atof(argv[2]));
            const double target = std::atof(argv[3]) * 1e-3;
            const bags::FillScaleResult r =
                bags::findFillScale(o, target, bags::FillScaling::Profile);
            printScale(r, target);
            o.geometry = r.geometry;
            for (int i = 4; i < argc; ++i) o.gasMasses.push_back(std::atof(argv[i]) * 1e-3);
            const bags::LoadTestResult res = bags::runLoadTest(o);
            std::printf("%8s %10s %10s %12s %8s %9s %s\n", "mass g", "gauge kPa", "top mm",
                        "k N/mm", "r2", "F end N", "end");
            for (const bags::LoadCurve& c : res.curves) {
                double fEnd = 0.0, dEnd = 0.0;
                for (const bags::LoadStep& s : c.steps)
                    if (s.loading) fEnd = s.force, dEnd = s.displacement;
                std::printf("%8.3f %10.3f %10.1f %12.3f %8.4f %9.1f at %.1f mm%s%s\n",
                            c.gasMass * 1e3, c.inflatedGaugePressure * 1e-3, c.unloadedHeight * 1e3,
                            c.stiffness * 1e-3, c.r2, fEnd, dEnd * 1e3,
                            c.failure.empty() ? "" : "; ", c.failure.c_str());
            }
            std::printf("load test %.1f s\n", res.seconds);
            return 0;
        }
        bags::FillMassOptions fo;
        if (argc > 3 && std::strcmp(argv[1], "--probes") == 0) {
            fo.probeHigh = std::atof(argv[2]);
            fo.probeLow = std::atof(argv[3]);
            argv += 3;
            argc -= 3;
        }
        const double meshMm = argc > 1 ? std::atof(argv[1]) : 10.0;
        bags::FillScaling scaling = bags::FillScaling::Profile;
        int first = 2;
        if (argc > 2) {
            const std::string name = argv[2];
            if (name == "uniform") scaling = bags::FillScaling::Uniform;
            if (name == "height") scaling = bags::FillScaling::Height;
            if (name == "profile" || name == "uniform" || name == "height") first = 3;
        }
        std::vector<double> targets;
        for (int i = first; i < argc; ++i) targets.push_back(std::atof(argv[i]) * 1e-3);
        if (targets.empty()) targets = {2.7e-3, 2.8e-3, 2.9e-3};
        const bags::LoadTestOptions rig = makeSeedRig(meshMm);
        std::printf("mesh %.1f mm, scaling %s\n", meshMm, bags::getFillScalingName(scaling));
        for (double target : targets) {
            const bags::FillScaleResult r = bags::findFillScale(rig, target, scaling, fo);
            printScale(r, target);
            // The scaled bag at the fill mass and 0.1 g either side, unloaded.
            bags::LoadTestOptions o = rig;
            o.geometry = r.geometry;
            o.gasMasses = {target + 0.1e-3, target + 0.05e-3, target, target - 0.05e-3,
                           target - 0.1e-3};
            o.peakForce = 0.5;
            o.stiffnessFrom = 0.1;
            o.stiffnessTo = 0.4;
            o.unload = false;
            o.polynomialOrder = 1;
            const bags::LoadTestResult res = bags::runLoadTest(o);
            for (const bags::LoadCurve& c : res.curves)
                std::printf("    at %.3f g: %.4f L, gauge %.3f kPa, top %.1f mm\n", c.gasMass * 1e3,
                            c.inflatedVolume * 1e3, c.inflatedGaugePressure * 1e-3,
                            c.unloadedHeight * 1e3);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_seed_reading: %s\n", e.what());
        return 1;
    }
    return 0;
}
