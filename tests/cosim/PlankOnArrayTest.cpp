// A rigid plank lying across two bags of an array: the bags, advanced in parallel, carry its
// weight at rest, and give the same bits as when advanced in turn.
#include <bags/Airbag.h>
#include <bags/MaterialFit.h>
#include <cosim/ArrayLayout.h>
#include <cosim/BagParticipant.h>
#include <cosim/Coupling.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "BlockSystem.h"

using namespace cosim;
using cosim::test::BlockSystem;

namespace {

constexpr double kGravity = 9.81;
constexpr double kWeight = 40.0;           // [N]
const Vec3 kPlankHalf(0.10, 0.04, 0.025);  // [m] spans both bags' widths along x

struct PlankRun {
    double depth = 0.0;            // [m] below the touching pose, at the end
    std::vector<double> bagForce;  // [N] vertical, per bag, at the end
    Eigen::Matrix3Xd x0, x1;       // the bags' positions at the end
    double seconds = 0.0;
    int passes = 0;
    std::vector<double> steps;  // [s] adaptive: every step taken
};

// The plank released just touching, coupled for 0.3 s: 60 fixed steps of 5 ms, or with
// `adaptive` accuracy-driven steps (1 to 40 ms) ending at every 0.1 s.
PlankRun run(bool parallel, Threading threading = Threading::PerCall, bool adaptive = false) {
    bags::DoubleWedgeParams g;
    g.meshSize = 0.020;
    ArrayLayout layout;
    layout.rows = 2;
    layout.rowPitch = 0.11;  // 10 mm between the bags' bases
    layout.gasMass = 4.5e-3;
    const std::vector<ArrayBag> cells = makeArrayBags(layout, g);
    // The apex ridge of an across bag lies apexX from its footprint's -y end.
    const double ridgeY = cells[0].footprintMin.y() + g.calcApexX();
    std::vector<std::unique_ptr<BagParticipant>> parts;
    double top = -1.0;
    for (const ArrayBag& c : cells) {
        bags::AirbagSpec spec;
        spec.geometry = g;
        spec.X_GB = c.X_GB;
        spec.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
        spec.forceTolerance = 1e-4;
        spec.threads = 1;
        auto bag = std::make_unique<bags::Airbag>(spec);
        std::shared_ptr<bags::RigidShape> box(bags::makeBox(kPlankHalf, 1e-3));
        Eigen::Isometry3d parked = Eigen::Isometry3d::Identity();
        parked.translation() = Vec3(0, ridgeY, 0.5);
        box->setPose(parked);
        bags::RigidContact::Options o;
        o.pressurePenalty = 1e8;
        bag->addShape(box, o);
        bag->inflate(c.gasMass);
        const Eigen::Matrix3Xd& x = bag->getPositions();
        for (int i = 0; i < x.cols(); ++i)
            if (std::abs(x(1, i) - ridgeY) <= kPlankHalf.y()) top = std::max(top, x(2, i));
        parts.push_back(std::make_unique<BagParticipant>(std::move(bag)));
    }
    const double m = kWeight / kGravity, k = 2 * 3.2e3;  // two bags of about 3.2 N/mm
    const double zTouch = top + kPlankHalf.z();
    BlockSystem plank(m, 2 * 0.7 * std::sqrt(k * m), kGravity, 0.0, ridgeY);
    plank.start(zTouch);
    CouplingOptions o;
    o.scheme = Scheme::Implicit;
    o.acceleration = AccelerationKind::IQNILS;
    o.macroStep = 5e-3;
    o.relativeTolerance = 1e-6;
    o.absoluteTolerance = 1e-3;
    o.parallel = parallel;
    o.threads = 2;
    o.threading = threading;
    if (adaptive) {
        o.adaptive = true;
        o.minMacroStep = o.macroStep = 1e-3;
        o.maxMacroStep = 0.04;
        o.stepAccuracy = 1000.0;  // of a tolerance of about 1 mN
    }
    std::vector<Participant*> ps{parts[0].get(), parts[1].get()};
    Coupling c(*plank.body, ps, {Link{plank.shape, 0, 0}, Link{plank.extraShape, 1, 0}}, o);
    c.initialize();
    PlankRun r;
    const auto start = std::chrono::steady_clock::now();  // the coupled steps only
    if (adaptive) {
        for (int k = 1; k <= 3; ++k)
            while (c.getTime() < k * 0.1) {
                const StepSummary st = c.stepAdaptive(k * 0.1);
                r.passes += st.iterations;
                r.steps.push_back(st.macroStep);
            }
    } else {
        for (int i = 0; i < 60; ++i) r.passes += c.step().iterations;
    }
    r.depth = zTouch - plank.getZ();
    for (int b = 0; b < 2; ++b) r.bagForce.push_back(c.getLinkWrench(b).force.z());
    r.x0 = parts[0]->getAirbag().getPositions();
    r.x1 = parts[1]->getAirbag().getPositions();
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

}  // namespace

TEST(PlankOnArray, TwoBagsInParallelCarryThePlanksWeightAndMatchTheSerialRunBitForBit) {
    // Reference: the plank's weight, 40 N. At rest (0.3 s at damping ratio 0.7) the two bags'
    // vertical forces sum to it within 0.5 % (the check for the patient). Each bag
    // carries half within 15 %: the bags are translated copies, not mirror images, and the
    // level plank presses opposite sides of their 20 mm meshes (measured 18.24 / 21.76 N; with a
    // 140 mm plank 22.33 / 17.68 N). The bags advanced on two threads give the same positions
    // and forces, bit for bit, as in turn.
    const PlankRun ser = run(false), par = run(true), omp = run(true, Threading::OpenMP);
    const double sum = par.bagForce[0] + par.bagForce[1];
    std::printf(
        "plank: depth %.4f mm, bags carry %.3f + %.3f = %.3f N of %.1f N; %.2f passes a "
        "step; 60 steps in %.2f s in turn, %.2f s on two threads made per call, %.2f s "
        "on an OpenMP team of two\n",
        1e3 * par.depth, par.bagForce[0], par.bagForce[1], sum, kWeight, double(par.passes) / 60,
        ser.seconds, par.seconds, omp.seconds);
    EXPECT_NEAR(sum, kWeight, 0.005 * kWeight);
    EXPECT_NEAR(par.bagForce[0], 0.5 * kWeight, 0.15 * 0.5 * kWeight);
    EXPECT_NEAR(par.bagForce[1], 0.5 * kWeight, 0.15 * 0.5 * kWeight);
    EXPECT_EQ(par.depth, ser.depth);
    EXPECT_EQ(par.bagForce, ser.bagForce);
    EXPECT_EQ((par.x0 - ser.x0).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((par.x1 - ser.x1).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(omp.bagForce, ser.bagForce);
    EXPECT_EQ((omp.x0 - ser.x0).cwiseAbs().maxCoeff(), 0.0);
}

TEST(PlankOnArray, AccuracyDrivenStepsAgreeWithTheFixedStepAndGiveTheSameBitsOnTwoThreads) {
    // The same plank, implicit IQN-ILS, with the step chosen by each step's accuracy (first
    // pass's residual, passes; 1 to 40 ms, stepAccuracy 1000, about 1 N). Reference: the fixed 5 ms run
    // above. At rest (0.3 s) the depth within 0.5 % of the fixed run's and each bag's force
    // within 0.5 % of the weight of it; the step grown to 40 ms by then (measured: 64 steps
    // in all against 60, the landing taken in steps of 1-5 ms); and the run on two threads
    // the serial run's bits, steps included (the controller reads only what the bags return).
    const PlankRun fixed = run(false);
    const PlankRun ser = run(false, Threading::PerCall, true);
    const PlankRun par = run(true, Threading::PerCall, true);
    std::printf(
        "plank, adaptive: %zu steps (%.2f passes a step, %.3g to %.3g ms) against 60 fixed; "
        "depth %.4f mm against %.4f mm; bags %.3f + %.3f N against %.3f + %.3f N\n",
        ser.steps.size(), double(ser.passes) / ser.steps.size(),
        1e3 * *std::min_element(ser.steps.begin(), ser.steps.end()),
        1e3 * *std::max_element(ser.steps.begin(), ser.steps.end()), 1e3 * ser.depth,
        1e3 * fixed.depth, ser.bagForce[0], ser.bagForce[1], fixed.bagForce[0], fixed.bagForce[1]);
    EXPECT_NEAR(ser.depth, fixed.depth, 0.005 * fixed.depth);
    for (int b = 0; b < 2; ++b) EXPECT_NEAR(ser.bagForce[b], fixed.bagForce[b], 0.005 * kWeight);
    EXPECT_EQ(*std::max_element(ser.steps.begin(), ser.steps.end()), 0.04);
    EXPECT_EQ(par.steps, ser.steps);
    EXPECT_EQ(par.depth, ser.depth);
    EXPECT_EQ(par.bagForce, ser.bagForce);
    EXPECT_EQ((par.x0 - ser.x0).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((par.x1 - ser.x1).cwiseAbs().maxCoeff(), 0.0);
}
