// The seed's test rig on a coarse mesh: inflation, loading to the peak force, unloading, the
// stiffness fit and the stage rule.
#include <bags/LoadTest.h>
#include <bags/MaterialFit.h>
#include <bags/Polynomial.h>

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>

using namespace bags;

namespace {

LoadTestOptions coarseOptions() {
    LoadTestOptions o;
    o.geometry.meshSize = 0.020;
    o.material = makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    // Taut bags: this geometry holds about 3.7 g of air at ambient pressure when inflated
    // (docs/seed-load-test.md), so 4.5 g and 4.0 g are above ambient.
    o.gasMasses = {4.5e-3, 4.0e-3};
    o.displacementStep = 2e-3;
    return o;
}

// A film that can be broken from outside: once `broken` is set, every evaluation is NaN, so
// every solve fails from then on (the bag's copies share the switch).
class BreakableMaterial : public MembraneMaterial {
  public:
    BreakableMaterial(std::shared_ptr<const MembraneMaterial> base,
                      std::shared_ptr<std::atomic<bool>> broken)
        : m_base(std::move(base)), m_broken(std::move(broken)) {}
    double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const override {
        const double w = m_base->calcEnergy(C, S, D);
        if (!*m_broken) return w;
        const double nan = std::numeric_limits<double>::quiet_NaN();
        if (S) S->setConstant(nan);
        if (D) D->setConstant(nan);
        return nan;
    }
    double getInitialShearModulus() const override { return m_base->getInitialShearModulus(); }
    std::string getName() const override { return m_base->getName(); }
    std::unique_ptr<MembraneMaterial> clone() const override {
        return std::make_unique<BreakableMaterial>(m_base, m_broken);
    }

  private:
    std::shared_ptr<const MembraneMaterial> m_base;
    std::shared_ptr<std::atomic<bool>> m_broken;
};

}  // namespace

TEST(LoadTest, CoarseBagIsLoadedToPeakAndUnloaded) {
    const LoadTestOptions o = coarseOptions();
    int observed = 0;
    const LoadTestResult r =
        runLoadTest(o, [&](const LoadStep&, const Mesh&, const Eigen::Matrix3Xd&) { ++observed; });
    ASSERT_EQ(r.curves.size(), 2u);
    int steps = 0;
    for (const LoadCurve& c : r.curves) {
        steps += static_cast<int>(c.steps.size());
        EXPECT_TRUE(c.reachedPeak) << c.gasMass;
        // The last loading step lands on the peak force within 2 %.
        double fmax = 0.0;
        for (const LoadStep& s : c.steps) fmax = std::max(fmax, s.force);
        EXPECT_NEAR(fmax, o.peakForce, 0.02 * o.peakForce);
        // Loading: force and gas pressure rise with the block travel.
        for (size_t i = 1; i < c.steps.size() && c.steps[i].loading; ++i) {
            EXPECT_GE(c.steps[i].force, c.steps[i - 1].force - 1e-6);
            EXPECT_GE(c.steps[i].gaugePressure[0], c.steps[i - 1].gaugePressure[0] - 1e-6);
        }
        // Unloading ends with the block back at the start and no force.
        EXPECT_FALSE(c.steps.back().loading);
        EXPECT_LT(c.steps.back().force, 0.5);
        EXPECT_GT(c.stiffness, 0.0);
        EXPECT_GT(c.inflatedGaugePressure, 0.0);
    }
    EXPECT_EQ(observed, steps);
    // Less gas, lower pressure.
    EXPECT_LT(r.curves[1].inflatedGaugePressure, r.curves[0].inflatedGaugePressure);
}

TEST(LoadTest, OrificeBetweenTheWedgesConservesGasAndLimitsTheFlow) {
    // One taut curve three ways: open connection (one gas), a wide orifice (20 mm: the
    // pressures equalise within each step), a nearly closed one (0.01 mm: Cd A sqrt(2 rho dp)
    // t is about 8e-8 kg for dp ~ 100 Pa over the curve's ~100 s, 3e-5 of a chamber's gas).
    LoadTestOptions o = coarseOptions();
    o.gasMasses = {4.5e-3};
    o.unload = false;
    const LoadTestResult open = runLoadTest(o);
    o.connection = LoadTestOptions::Connection::Orifice;
    o.orifice.diameter = 20e-3;
    const LoadTestResult wide = runLoadTest(o);
    o.orifice.diameter = 0.01e-3;
    const LoadTestResult shut = runLoadTest(o);
    for (const LoadTestResult* r : {&open, &wide, &shut}) {
        ASSERT_EQ(r->curves.size(), 1u);
        EXPECT_TRUE(r->curves[0].reachedPeak);
        // The gas is only moved, never made or lost (1e-12 relative).
        for (const LoadStep& st : r->curves[0].steps) {
            ASSERT_EQ(st.gasMass.size(), 2u);
            EXPECT_NEAR(st.gasMass[0] + st.gasMass[1], 4.5e-3, 1e-12 * 4.5e-3);
        }
    }
    // Wide orifice: the chambers stay within 1 Pa of each other and the curve is the open
    // connection's (block travel at the peak within 1 %).
    for (const LoadStep& st : wide.curves[0].steps)
        EXPECT_NEAR(st.gaugePressure[0], st.gaugePressure[1], 1.0);
    const double dOpen = open.curves[0].steps.back().displacement;
    EXPECT_NEAR(wide.curves[0].steps.back().displacement, dOpen, 0.01 * dOpen);
    // Nearly shut: the chamber under more of the block (different share of the compression)
    // ends at a clearly different pressure (> 50 Pa apart; open: 0), and each chamber keeps
    // its gas to 1e-4.
    const LoadStep& first = shut.curves[0].steps.front();
    const LoadStep& last = shut.curves[0].steps.back();
    EXPECT_GT(std::abs(last.gaugePressure[0] - last.gaugePressure[1]), 50.0);
    for (int c = 0; c < 2; ++c)
        EXPECT_NEAR(last.gasMass[c], first.gasMass[c], 1e-4 * first.gasMass[c]);
}

TEST(LoadTest, ChambersSettleThroughTheOrificeBeforeEachCurve) {
    // The chambers are sealed at one pressure on the flat-panel shape; the inflation to 4.5 g
    // and the let-down to 3.75 g (gas shared by volume) leave them at different pressures
    // once the membrane has moved. Before the block comes down they settle through the
    // orifice for 1000 s (10 backward-Euler steps). Three orifices:
    //  - 2 mm equalises them (within 1 Pa);
    //  - 0.001 mm can pass at most Cd A sqrt(2 rho dp) x 1000 s, below 2e-8 kg for
    //    dp <= 500 Pa, so its chambers stay apart: the settle follows the flow law rather
    //    than simply setting one pressure;
    //  - 0.01 mm (100 times the area) settles part of the way.
    LoadTestOptions o = coarseOptions();
    o.gasMasses = {4.5e-3, 3.75e-3};
    o.unload = false;
    o.peakForce = 5.0;  // only the state before loading matters here
    o.stiffnessFrom = 1.0;
    o.stiffnessTo = 4.0;
    o.connection = LoadTestOptions::Connection::Orifice;
    std::vector<LoadTestResult> r;
    for (double d : {2e-3, 0.01e-3, 0.001e-3}) {
        o.orifice.diameter = d;
        r.push_back(runLoadTest(o));
        ASSERT_EQ(r.back().curves.size(), 2u) << d;
    }
    for (size_t c = 0; c < 2; ++c) {
        double dp[3];
        for (int k = 0; k < 3; ++k) {
            const LoadStep& s0 = r[k].curves[c].steps.front();
            dp[k] = s0.gaugePressure[0] - s0.gaugePressure[1];
            const double m = o.gasMasses[c];
            EXPECT_NEAR(s0.gasMass[0] + s0.gasMass[1], m, 1e-12 * m);  // moved, never lost
        }
        EXPECT_LT(std::abs(dp[0]), 1.0) << "curve " << c;
        EXPECT_GT(std::abs(dp[2]), 5.0) << "curve " << c;
        EXPECT_LT(std::abs(dp[2]), 500.0) << "curve " << c;  // the bound's premise
        if (c > 0) continue;
        // The first curve starts its settle from the same state for all three (same
        // inflation, mass shared by volume at the same shape): same sign, and the wider
        // orifice settles further (measured: 0.0, 52.8 and 67.5 Pa for 2, 0.01 and 0.001 mm). Later curves start from
        // states that carry each run's own history, so only the two bounds above apply there.
        EXPECT_GT(dp[1] * dp[2], 0.0);
        EXPECT_LT(std::abs(dp[1]), 0.9 * std::abs(dp[2]));
        EXPECT_GT(std::abs(dp[1]), 5.0);
    }
    // The settle's integration, 0.01 mm orifice: converged in its step count (40 steps instead
    // of 10 move the remaining difference by less than 1e-3 of it), while one step or no wait
    // give clearly different states (measured: 52.80, 52.80, 53.34 and 67.69 Pa). The orifice
    // solves ignore the load test's residual tolerance: at 1e-2 of the peak force (0.05 N) the
    // settle ends where it does at 1e-3 within 2e-3 (measured 52.83 Pa: the inflation before
    // it is solved to the looser tolerance; orifice solves at 0.05 N once left 48.54 Pa).
    o.orifice.diameter = 0.01e-3;
    o.gasMasses = {4.5e-3};
    const LoadStep& c0 = r[1].curves[0].steps.front();
    const double dp10 = c0.gaugePressure[0] - c0.gaugePressure[1];
    auto settled = [&](int steps, double time, double residualTolerance) {
        LoadTestOptions v = o;
        v.settleSteps = steps;
        v.settleTime = time;
        v.residualTolerance = residualTolerance;
        const LoadTestResult res = runLoadTest(v);
        const LoadStep& s0 = res.curves[0].steps.front();
        return s0.gaugePressure[0] - s0.gaugePressure[1];
    };
    EXPECT_NEAR(settled(40, 1000.0, o.residualTolerance), dp10, 1e-3 * std::abs(dp10));
    EXPECT_GT(std::abs(settled(1, 1000.0, o.residualTolerance) - dp10), 5e-3 * std::abs(dp10));
    EXPECT_GT(std::abs(settled(10, 0.0, o.residualTolerance)), std::abs(dp10) + 5.0);
    EXPECT_NEAR(settled(10, 1000.0, 1e-2), dp10, 2e-3 * std::abs(dp10));
}

TEST(LoadTest, ResidualToleranceIsAFractionOfThePeakForce) {
    // The same taut curve solved to 1e-7 N (residualTolerance 0) and to 1e-3 of the peak force
    // (the default, 0.05 N): every step ends within its tolerance, and the block force, the
    // quantity the test reports, agrees within 0.02 N (0.04 % of the peak) at every step
    // (measured: 0.003 N at most, 58 Newton iterations instead of 83).
    LoadTestOptions o = coarseOptions();
    o.gasMasses = {4.5e-3};
    o.residualTolerance = 0.0;
    const LoadTestResult strict = runLoadTest(o);
    o.residualTolerance = 1e-3;
    const LoadTestResult loose = runLoadTest(o);
    const std::vector<LoadStep>& a = strict.curves[0].steps;
    const std::vector<LoadStep>& b = loose.curves[0].steps;
    ASSERT_EQ(a.size(), b.size());
    int iterationsStrict = 0, iterationsLoose = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        // Same steps; the unloaded height differs by the inflation's tolerance (< 10 um).
        EXPECT_NEAR(b[i].displacement, a[i].displacement, 1e-5) << "step " << i;
        EXPECT_NEAR(b[i].force, a[i].force, 0.02) << "step " << i;
        EXPECT_LE(b[i].residual, 1e-3 * o.peakForce) << "step " << i;
        EXPECT_LE(a[i].residual, 1e-3 * o.peakForce) << "step " << i;  // stall rule at worst
        iterationsStrict += a[i].newtonIterations;
        iterationsLoose += b[i].newtonIterations;
    }
    EXPECT_LT(iterationsLoose, iterationsStrict);
    EXPECT_NEAR(loose.curves[0].stiffness, strict.curves[0].stiffness,
                1e-3 * strict.curves[0].stiffness);
}

TEST(LoadTest, StageRuleFollowsTheDocumentedDefinition) {
    // Masses 3.5 ... 1.0 g with a stiffness minimum at 2.0 g: below it stage 3; above it
    // stage 1 where the 10-35 N range is linear (r2 >= 0.995), stage 2 where it is not.
    std::vector<LoadCurve> c(6);
    const double m[] = {3.5, 3.0, 2.5, 2.0, 1.5, 1.0};
    const double k[] = {8.0, 6.0, 3.0, 1.5, 2.0, 3.5};
    const double r2[] = {0.999, 0.998, 0.97, 0.96, 0.95, 0.999};
    for (int i = 0; i < 6; ++i)
        c[i].gasMass = m[i] * 1e-3, c[i].stiffness = k[i] * 1e3, c[i].r2 = r2[i];
    classifyStages(c);
    const int expected[] = {1, 1, 2, 2, 3, 3};
    for (int i = 0; i < 6; ++i) EXPECT_EQ(c[i].stage, expected[i]) << m[i] << " g";
}

TEST(LoadTest, SeedPolynomialIsTheSeedsFit) {
    // Seed eq. (18)-(24): k(3.5 g) = 7.90 N/mm, k(1.0 g) = 3.471 N/mm (hand-evaluated).
    const std::vector<double> c = getSeedStiffnessPolynomial();
    EXPECT_NEAR(evalPolynomial(c, 1.0), 3.471, 1e-9);
    EXPECT_NEAR(evalPolynomial(c, 3.5),
                -0.945 * std::pow(3.5, 5) + 8.394 * std::pow(3.5, 4) - 25.707 * std::pow(3.5, 3) +
                    32.714 * 3.5 * 3.5 - 17.181 * 3.5 + 6.196,
                1e-9);
}

TEST(LoadTest, RejectsImpossibleOptions) {
    LoadTestOptions o = coarseOptions();
    o.gasMasses = {-1.0};
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = coarseOptions();
    o.blockSize = 1.0;  // larger than the airbag
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = coarseOptions();
    o.connection = LoadTestOptions::Connection::Orifice;
    o.settleSteps = 0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.settleSteps = 61;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.settleSteps = 10;
    o.settleTime = -1.0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.settleTime = std::numeric_limits<double>::infinity();
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = coarseOptions();
    o.residualTolerance = 0.06;  // above 5 % of the peak force
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.residualTolerance = -1e-3;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = coarseOptions();
    o.material.reset();
    EXPECT_THROW(o.validate(), std::invalid_argument);
}

TEST(LoadTest, RangeStiffnessNeedsTheWholeRange) {
    // F = 2 N/mm x d on loading: slope 2000 N/m, r2 = 1 over 10-35 N when the curve reaches
    // 35 N; a curve stopping at 20 N has no stiffness over that range (NaN), and unloading
    // steps are ignored.
    std::vector<LoadStep> steps;
    for (int i = 0; i <= 20; ++i) {
        LoadStep s;
        s.displacement = 1e-3 * i;
        s.force = 2.0 * i;
        steps.push_back(s);
    }
    LoadStep back = steps.back();
    back.loading = false;
    back.force = 12.0;  // hysteresis on unloading must not enter the fit
    steps.push_back(back);
    const LinearFit full = calcRangeStiffness(steps, 10.0, 35.0);
    EXPECT_NEAR(full.slope, 2000.0, 1e-9);
    EXPECT_NEAR(full.r2, 1.0, 1e-12);
    steps.resize(11);  // loading up to 20 N only
    EXPECT_TRUE(std::isnan(calcRangeStiffness(steps, 10.0, 35.0).slope));
}

TEST(LoadTest, EnsembleReportsTheStiffnessSpreadOverImperfectionSeeds) {
    LoadTestOptions o = coarseOptions();
    o.gasMasses = {4.5e-3};
    o.imperfection.amplitude = 1.0e-3;
    o.imperfection.seed = 3;
    const LoadTestResult one = runLoadTest(o);
    o.ensemble = 3;
    const LoadTestResult r = runLoadTest(o);
    ASSERT_EQ(r.curves.size(), 1u);
    const LoadCurve& c = r.curves[0];
    EXPECT_EQ(c.ensembleSize, 3);
    // The first bag is the one-bag run, bit for bit; the others are other bags.
    EXPECT_EQ(c.stiffness, one.curves[0].stiffness);
    EXPECT_LE(c.stiffnessMin, c.stiffness);
    EXPECT_GE(c.stiffnessMax, c.stiffness);
    EXPECT_LT(c.stiffnessMin, c.stiffnessMax);
    EXPECT_LT(c.stiffnessMax - c.stiffnessMin, 0.2 * c.stiffness);  // a taut bag: a small spread
    // Without an imperfection an ensemble is refused.
    o.imperfection.amplitude = 0.0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
}

TEST(LoadTest, ALargePeakForceDoesNotLoosenTheSolve) {
    // The force tolerance is a fraction of the peak force counted at most 50 N: a 1e6 N peak
    // once made it 1000 N, and an uninflated bag passed as converged.
    LoadTestOptions o = coarseOptions();
    const double usual = calcLoadTestForceTolerance(o);
    o.peakForce = 1e6;
    o.stiffnessTo = 35.0;
    EXPECT_DOUBLE_EQ(calcLoadTestForceTolerance(o), usual);
    o.peakForce = 5.0;
    o.stiffnessTo = 4.0;
    EXPECT_LT(calcLoadTestForceTolerance(o), usual);
}

// --- the pressed bag among neighbours (LoadTestOptions::neighbours; docs/array-coupling.md)

namespace {

// One taut curve on a 30 mm mesh, loading only, to just past the stiffness range.
LoadTestOptions coarseNeighbourOptions() {
    LoadTestOptions o = coarseOptions();
    o.geometry.meshSize = 0.030;
    o.gasMasses = {4.5e-3};
    o.peakForce = 36.0;
    o.unload = false;
    o.displacementStep = 1e-3;  // enough steps in the 10-35 N range for a stiffness
    return o;
}

}  // namespace

TEST(LoadTest, NoNeighboursIsTheBagAloneBitForBit) {
    // Layout none takes no cluster, and ignores the neighbours' gap and gas mass.
    LoadTestOptions o = coarseNeighbourOptions();
    EXPECT_TRUE(makeAirbagSpec(o).cluster.empty());
    LoadTestOptions v = o;
    v.neighbours = LoadTestOptions::Neighbours::None;
    v.neighbourGap = 0.02;
    v.neighbourGasMass = 1.0e-3;
    const LoadTestResult a = runLoadTest(o), b = runLoadTest(v);
    ASSERT_EQ(a.curves.size(), 1u);
    ASSERT_EQ(a.curves[0].steps.size(), b.curves[0].steps.size());
    EXPECT_EQ(a.curves[0].stiffness, b.curves[0].stiffness);
    EXPECT_EQ(a.curves[0].inflatedGaugePressure, b.curves[0].inflatedGaugePressure);
    for (size_t i = 0; i < a.curves[0].steps.size(); ++i) {
        EXPECT_EQ(a.curves[0].steps[i].force, b.curves[0].steps[i].force);
        EXPECT_EQ(a.curves[0].steps[i].gaugePressure, b.curves[0].steps[i].gaugePressure);
    }
}

TEST(LoadTest, ANeighbourSqueezesThePressedBagAndStiffensIt) {
    // Two taut bags 5 mm apart flatten their facing side panels against each other: the
    // pressed bag's pressure rises before the block touches, and its stiffness with it.
    const LoadTestOptions alone = coarseNeighbourOptions();
    LoadTestOptions pair = alone;
    pair.neighbours = LoadTestOptions::Neighbours::Pair;
    ASSERT_EQ(makeAirbagSpec(pair).cluster.size(), 2u);
    const LoadTestResult a = runLoadTest(alone), p = runLoadTest(pair);
    const LoadCurve &ca = a.curves.at(0), &cp = p.curves.at(0);
    ASSERT_TRUE(std::isfinite(ca.stiffness));
    ASSERT_TRUE(std::isfinite(cp.stiffness));
    // The steps record the pressed bag's chambers only: the same columns as alone.
    EXPECT_EQ(cp.steps.front().gaugePressure.size(), ca.steps.front().gaugePressure.size());
    EXPECT_GT(cp.inflatedGaugePressure, ca.inflatedGaugePressure * 1.01);
    EXPECT_LT(cp.inflatedVolume, ca.inflatedVolume);
    EXPECT_GT(cp.stiffness, ca.stiffness);
    // The pressed bag holds its own gas: its mass is the curve's, not the pair's.
    double mass = 0.0;
    for (double m : cp.steps.front().gasMass) mass += m;
    EXPECT_NEAR(mass, 4.5e-3, 1e-9);
}

TEST(LoadTest, ABlockPressedAtEachPositionHasItsEightNeighboursAroundIt) {
    // Reference: the 3 x 3 block's positions on the pitches (long side + gap along x, width +
    // gap across y), exact to roundoff of the sums; the pressed bag (bag 0) at the origin.
    LoadTestOptions o = coarseNeighbourOptions();
    o.neighbours = LoadTestOptions::Neighbours::Block3x3;
    const double px = o.geometry.longSide + o.neighbourGap, py = o.geometry.width + o.neighbourGap;
    for (int pi = -1; pi <= 1; ++pi)
        for (int pj = -1; pj <= 1; ++pj) {
            o.neighbourPressed = {pi, pj};
            const std::vector<Eigen::Isometry3d> poses = calcNeighbourPoses(o);
            ASSERT_EQ(poses.size(), 9u);
            EXPECT_EQ(poses[0].translation().norm(), 0.0);
            // Every block position once, the pressed one being the origin.
            int found = 0;
            for (int i = -1; i <= 1; ++i)
                for (int j = -1; j <= 1; ++j) {
                    const Vec3 want((i - pi) * px, (j - pj) * py, 0.0);
                    for (const Eigen::Isometry3d& X : poses)
                        if ((X.translation() - want).norm() < 1e-12) ++found;
                }
            EXPECT_EQ(found, 9) << "pressed at (" << pi << ", " << pj << ")";
        }
    // A corner has 3 adjacent bags (one pitch away along, across or both), an edge 5, the
    // middle 8.
    auto near = [&](std::array<int, 2> at) {
        o.neighbourPressed = at;
        int n = 0;
        for (const Eigen::Isometry3d& X : calcNeighbourPoses(o)) {
            const double di = std::abs(X.translation().x()) / px,
                         dj = std::abs(X.translation().y()) / py;
            if (di + dj > 0.5 && di < 1.5 && dj < 1.5) ++n;
        }
        return n;
    };
    EXPECT_EQ(near({0, 0}), 8);
    EXPECT_EQ(near({1, 1}), 3);
    EXPECT_EQ(near({0, 1}), 5);
    o.neighbourPressed = {2, 0};
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.neighbourPressed = {0, 1};
    o.neighbours = LoadTestOptions::Neighbours::Row3;
    EXPECT_THROW(o.validate(), std::invalid_argument);
}

TEST(LoadTest, RejectsImpossibleNeighbourOptions) {
    LoadTestOptions o = coarseNeighbourOptions();
    o.neighbours = LoadTestOptions::Neighbours::Row3;
    EXPECT_NO_THROW(o.validate());
    auto message = [](const LoadTestOptions& v) {
        try {
            v.validate();
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    LoadTestOptions v = o;
    v.neighbourGap = 0.0;
    EXPECT_NE(message(v).find("neighbourGap"), std::string::npos);
    v.neighbourGap = 0.1;
    EXPECT_NE(message(v).find("100 mm"), std::string::npos);
    v = o;
    v.neighbourGasMass = -1e-3;
    EXPECT_NE(message(v).find("neighbourGasMass"), std::string::npos);
    v = o;
    v.selfContact = false;
    EXPECT_NE(message(v).find("selfContact"), std::string::npos);
    v = o;
    v.geometry.diaphragm = true;
    v.connection = LoadTestOptions::Connection::Orifice;
    EXPECT_NE(message(v).find("open connection"), std::string::npos);
    // Block3x3: the pressed bag in the middle, pitch long side + gap along x.
    v = o;
    v.neighbours = LoadTestOptions::Neighbours::Block3x3;
    const auto poses = calcNeighbourPoses(v);
    ASSERT_EQ(poses.size(), 9u);
    EXPECT_TRUE(poses[0].translation().isZero());
    EXPECT_NEAR(poses[1].translation().x(), -(v.geometry.longSide + v.neighbourGap), 1e-15);
}

// A curve whose set-up cannot be solved (parking the block, letting the gas out) ends as
// failed with its reason and no steps; the curves done before keep their results, bit for bit,
// and the sweep goes on to the next mass instead of losing everything to one exception.
TEST(LoadTest, ASetUpThatCannotBeSolvedFailsThatCurveAndKeepsTheOthers) {
    LoadTestOptions o = coarseOptions();
    o.gasMasses = {4.5e-3, 4.0e-3, 3.9e-3};
    const LoadTestResult clean = runLoadTest(o);
    ASSERT_EQ(clean.curves.size(), 3u);
    ASSERT_TRUE(clean.curves[0].reachedPeak);

    auto broken = std::make_shared<std::atomic<bool>>(false);
    o.material = std::make_shared<BreakableMaterial>(o.material, broken);
    // The film breaks at the last step of the first curve's unloading (the block has left).
    const LoadTestResult r =
        runLoadTest(o, [&](const LoadStep& s, const Mesh&, const Eigen::Matrix3Xd&) {
            if (s.curve == 0 && !s.loading && s.force <= 0.0) *broken = true;
        });
    ASSERT_TRUE(*broken);
    ASSERT_EQ(r.curves.size(), 3u);
    const LoadCurve& first = r.curves[0];
    EXPECT_TRUE(first.reachedPeak);
    EXPECT_FALSE(first.failed);
    ASSERT_EQ(first.steps.size(), clean.curves[0].steps.size());
    EXPECT_EQ(first.stiffness, clean.curves[0].stiffness);  // bit for bit
    for (size_t k = 1; k < 3; ++k) {
        const LoadCurve& c = r.curves[k];
        EXPECT_EQ(c.gasMass, o.gasMasses[k]);
        EXPECT_TRUE(c.failed) << k;
        EXPECT_FALSE(c.reachedPeak) << k;
        EXPECT_TRUE(c.steps.empty()) << k;
        EXPECT_EQ(c.failure.rfind("before loading: no convergence", 0), 0u) << c.failure;
        EXPECT_TRUE(std::isnan(c.stiffness)) << k;
        EXPECT_TRUE(std::isnan(c.unloadedHeight)) << k;  // never reached: unknown, not zero
        EXPECT_TRUE(std::isnan(c.inflatedGaugePressure)) << k;
        EXPECT_EQ(c.stage, 0) << k;
    }
}

// Stepping over a snapping fold (docs/solver.md#snaps-stepped-over): from the last equilibrium
// the block goes on by 1, 2, 4 displacement steps, the first that converges is taken, never
// past the limit, never a step no longer than the one that failed; -1 when none converges.
TEST(LoadTest, ASnappingFoldIsSteppedOverByOneTwoOrFourSteps) {
    std::vector<double> tried;
    // The film finds an equilibrium again from 65.2 mm of travel on (loading from 63.5 mm).
    auto beyond = [&](double at) {
        return [&tried, at](double to) {
            tried.push_back(to);
            return to >= at;
        };
    };
    const double h = 1e-3, from = 63.5e-3;
    EXPECT_NEAR(stepOverSnap(beyond(64.0e-3), from, 2.5e-5, +1.0, 0.2, h), 64.5e-3, 1e-15);
    EXPECT_EQ(tried.size(), 1u);
    tried.clear();
    EXPECT_NEAR(stepOverSnap(beyond(65.2e-3), from, 2.5e-5, +1.0, 0.2, h), 65.5e-3, 1e-15);
    EXPECT_EQ(tried.size(), 2u);
    tried.clear();
    EXPECT_NEAR(stepOverSnap(beyond(66.0e-3), from, 2.5e-5, +1.0, 0.2, h), 67.5e-3, 1e-15);
    ASSERT_EQ(tried.size(), 3u);
    tried.clear();
    EXPECT_EQ(stepOverSnap(beyond(70.0e-3), from, 2.5e-5, +1.0, 0.2, h), -1.0);  // no way over
    EXPECT_EQ(tried.size(), 3u);
    tried.clear();
    // The limit (the block 2 mm above the board) caps the jumps; a capped jump no longer than
    // the failed step is not tried again.
    EXPECT_NEAR(stepOverSnap(beyond(0.0), from, 2.5e-5, +1.0, 64.2e-3, h), 64.2e-3, 1e-15);
    tried.clear();
    EXPECT_EQ(stepOverSnap(beyond(0.0), from, 2.5e-5, +1.0, from + 1e-5, h), -1.0);
    EXPECT_TRUE(tried.empty());
    // Unloading goes back, down to the block's first touch at 0.
    auto below = [&](double at) { return [at](double to) { return to <= at; }; };
    EXPECT_NEAR(stepOverSnap(below(1.5e-3), 3.0e-3, 2.5e-5, -1.0, 0.0, h), 1.0e-3, 1e-15);
    EXPECT_NEAR(stepOverSnap(below(0.0), 3.0e-3, 2.5e-5, -1.0, 0.0, h), 0.0, 0.0);
}
