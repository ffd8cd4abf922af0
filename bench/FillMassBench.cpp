// How the double wedge's taut volume, and the gas mass that fills it at ambient pressure,
// depend on the reading of the seed's dimensions. Not a test: run by hand, see
// docs/geometry.md ("How the results depend on the reading").
//
//   build/bin/bench_fill_mass [mesh_mm=10]
//
// For each reading the bag is inflated and sealed with 4.5 g and with 4.0 g of air (both
// taut); the volume is extrapolated linearly in the gauge pressure to zero gauge pressure, and
// the fill mass is that volume times the ambient density.
#include <bags/LoadTest.h>
#include <bags/MaterialFit.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

int main(int argc, char** argv) {
    const double meshMm = argc > 1 ? std::atof(argv[1]) : 10.0;
    struct Reading {
        const char* name;
        double longSide, shortSide, width, height;  // [m]
        bool diaphragm;
    };
    const Reading readings[] = {
        {"seed reading (350/200/100/150 mm, wall)", 0.350, 0.200, 0.100, 0.150, true},
        {"no internal wall", 0.350, 0.200, 0.100, 0.150, false},
        {"width 90 mm", 0.350, 0.200, 0.090, 0.150, true},
        {"width 80 mm", 0.350, 0.200, 0.080, 0.150, true},
        {"height 140 mm", 0.350, 0.200, 0.100, 0.140, true},
        {"long side 330 mm", 0.330, 0.200, 0.100, 0.150, true},
        {"profile scaled by 0.96", 0.336, 0.192, 0.100, 0.144, true},
        {"single wedge (short side = height)", 0.350, 0.150, 0.100, 0.150, false},
    };
    std::printf("mesh %.1f mm\n%-42s %8s %18s %18s %9s %7s\n", meshMm, "reading", "flat [L]",
                "4.5 g: V [L], p", "4.0 g: V [L], p", "V0 [L]", "fill [g]");
    for (const Reading& r : readings) {
        bags::LoadTestOptions o;
        o.geometry.longSide = r.longSide;
        o.geometry.shortSide = r.shortSide;
        o.geometry.width = r.width;
        o.geometry.height = r.height;
        o.geometry.diaphragm = r.diaphragm;
        o.geometry.meshSize = meshMm * 1e-3;
        o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
        o.gasMasses = {4.5e-3, 4.0e-3};
        o.peakForce = 0.5;  // the block barely touches: only the inflated states are used
        o.stiffnessFrom = 0.1;
        o.stiffnessTo = 0.4;
        o.unload = false;
        try {
            const bags::LoadTestResult res = bags::runLoadTest(o);
            const bags::LoadCurve& a = res.curves[0];
            const bags::LoadCurve& b = res.curves[1];
            const double dVdp = (a.inflatedVolume - b.inflatedVolume) /
                                (a.inflatedGaugePressure - b.inflatedGaugePressure);
            const double V0 = b.inflatedVolume - dVdp * b.inflatedGaugePressure;
            std::printf("%-42s %8.3f  %6.3f %6.2f kPa  %6.3f %6.2f kPa %9.3f %7.2f\n", r.name,
                        0.5 * r.longSide * r.height * r.width * 1e3, a.inflatedVolume * 1e3,
                        a.inflatedGaugePressure * 1e-3, b.inflatedVolume * 1e3,
                        b.inflatedGaugePressure * 1e-3, V0 * 1e3,
                        o.gas.getAmbientDensity() * V0 * 1e3);
        } catch (const std::exception& e) {
            std::printf("%-42s failed: %s\n", r.name, e.what());
        }
    }
    return 0;
}
