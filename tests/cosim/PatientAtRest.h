#pragma once
// The light patient on the coarse array, shared by the default test (a short rest) and the long
// one (a 10 s rest).
#include <bags/MaterialFit.h>
#include <cosim/PatientOnArray.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace cosim::test {

// A 1.40 m, 28 kg patient (the lightest the body model takes, BMI 14.3) supine on 14 rows of 2
// of the seed's wedges (alternating, 105 mm rows, 360 mm columns) at 30 mm meshes, 4.5 g of
// gas each. The bags' self-contact is off: with it on, a macro step costs about 100 times as
// much (docs/cosim.md).
inline PatientOnArrayOptions coarseOptions() {
    PatientOnArrayOptions o;
    o.layout.rows = 14;
    o.layout.columns = 2;
    o.layout.rowPitch = 0.105;
    o.layout.columnPitch = 0.36;
    o.layout.centre = Eigen::Vector2d(-0.03, 0.0);
    o.layout.rowOrientation = {BagOrientation::Across, BagOrientation::AcrossFlipped};
    o.layout.gasMass = 4.5e-3;
    o.bag.geometry.meshSize = 0.030;
    o.bag.selfContact = false;
    o.bag.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.bag.forceTolerance = 1e-4;
    o.bag.threads = 1;
    o.contact.pressurePenalty = 1e8;
    o.integrator.accuracy = 1e-6;
    o.coupling.scheme = Scheme::Implicit;
    o.coupling.acceleration = AccelerationKind::IQNILS;
    o.coupling.macroStep = 1e-2;
    o.coupling.relativeTolerance = 1e-6;
    o.coupling.absoluteTolerance = 1e-3;
    o.coupling.threads = 2;
    return o;
}

inline body::PatientSpec lightPatient() {
    body::PatientSpec p;
    p.height = 1.40;
    p.mass = 28.0;
    return p;
}

/// Runs the light patient from release to `run` seconds and checks the last `rest` seconds
/// (see the comment inside).
inline void checkLightPatientSettlesAndRests(double kRun, double kRest) {
    // Released at rest where his first shape touches a bag, he falls into the valley between
    // the two columns' wedges and settles (joint damping, and the implicit scheme's hold
    // dissipates). Reference: his weight m g. At rest (the last kRest seconds of the run) the
    // vertical forces of all the bags on him, with the bed board's where a segment reaches it
    // between the bags, averaged over the rest, equal it within 0.5 %
    // (the check), and each step's sum within 2 %. The mechanical energy (body
    // kinetic + gravity + joint springs, bags' membrane + gas + own weight + contact) never
    // rises over the rest by more than 1e-3 J (the bags solve to 1e-4 N), nor over one step
    // anywhere in the run by more than that.
    const auto start = std::chrono::steady_clock::now();
    const PatientOnArrayOptions options = coarseOptions();
    PatientOnArray poa(lightPatient(), options);
    const double built =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double weight = poa.getWeight();
    std::printf(
        "patient on array: %d bags coupled, %d links, lowest point released at %.1f mm, "
        "built in %.1f s\n",
        int(poa.getBagIndices().size()), int(poa.getPairs().size()),
        1e3 * poa.getReleaseClearance(), built);
    EXPECT_EQ(int(poa.getBagIndices().size()), 28);
    // What carries him: the bags, and the bed board where a segment reaches it between them.
    auto carried = [&] { return poa.calcBagForce() + poa.calcBoardForce(); };
    std::vector<double> time{0.0}, energy{poa.calcEnergy()}, force{carried()};
    int passes = 0, steps = 0;
    while (poa.getTime() < kRun - 1e-9) {
        const StepSummary s = poa.step();
        passes += s.iterations;
        ++steps;
        time.push_back(poa.getTime());
        energy.push_back(poa.calcEnergy());
        force.push_back(carried());
        if (std::getenv("BAGSIM_COSIM_TRACE"))
            std::printf("  t %.3f bags %.3f N of %.3f N, E %+.5f J, vmax %.4f m/s, passes %d\n",
                        time.back(), force.back(), weight, energy.back() - energy.front(),
                        poa.calcMaxSpeed(), s.iterations);
    }
    double restForce = 0.0, worstForce = 0.0, restRise = -1e300, stepRise = -1e300;
    size_t rest = 0;
    while (time[rest] < kRun - kRest - 1e-9) ++rest;
    for (size_t i = rest + 1; i < time.size(); ++i) {
        restForce += force[i];
        worstForce = std::max(worstForce, std::abs(force[i] - weight));
        restRise = std::max(restRise, energy[i] - energy[rest]);
    }
    restForce /= double(time.size() - rest - 1);
    for (size_t i = 1; i < time.size(); ++i)
        stepRise = std::max(stepRise, energy[i] - energy[i - 1]);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "  at rest (%.2f-%.2f s): bags and board carry %.3f N of %.3f N on average (%+.3f %%), "
        "each step "
        "within %.2f %%; energy fell %.3f J since release, rose at most %+.2e J over the rest, "
        "%+.2e J in a step; vmax at the end %.2e m/s; %.2f passes a step, %d steps, %.1f s\n",
        kRun - kRest, kRun, restForce, weight, 100 * (restForce - weight) / weight,
        100 * worstForce / weight, energy.front() - energy.back(), restRise, stepRise,
        poa.calcMaxSpeed(), double(passes) / steps, steps, seconds);
    EXPECT_NEAR(restForce, weight, 0.005 * weight);
    EXPECT_LT(worstForce, 0.02 * weight);
    EXPECT_LT(restRise, 1e-3);
    EXPECT_LT(stepRise, 1e-3);
    EXPECT_LT(energy.back(), energy.front() - 1.0);  // it did fall and settle
    // The bed board (PatientOnArrayOptions::boardContact) carries what reaches it between the
    // bags: a small share here (measured 2.1 %), never more than the bags.
    const double board = poa.calcBoardForce();
    std::printf("  the bed board carries %.3f N of him directly (%.2f %%)\n", board,
                100 * board / weight);
    EXPECT_GE(board, 0.0);
    EXPECT_LT(board, 0.1 * weight);
}

}  // namespace cosim::test
