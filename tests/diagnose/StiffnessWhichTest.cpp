// The which part on a measured stiffness curve (diagnose/StiffnessWhich.h) on a curve whose
// answer is known: a stand-in model's k(m), V-shaped with its least stiffness at 2.9 g like
// the seed's bag model, "measured" with one effect on. The effect must come back and be named,
// the unshifted curve must be called none and a curve no candidate makes unexplained.
#include <gtest/gtest.h>

#include <diagnose/StiffnessWhich.h>

#include <cmath>
#include <functional>
#include <stdexcept>

namespace {

using namespace diagnose;

constexpr double kGram = 1e-3;
constexpr double kRoom = 296.15;  // [K]

// The stand-in model's stiffness [N/m] at a gas mass [kg]: least (1 N/mm) at 2.9 g, rising to
// 5.5 N/mm at 3.5 g and 4.4 N/mm at 2.0 g.
double modelStiffness(double m) {
    const double x = (m - 2.9e-3) / kGram;
    return 1000.0 * (1.0 + (x > 0 ? 12.5 : 4.3) * x * x);
}

// The stand-in's "bag-volume": a bag of 1 + v the volume fills as the model at m / (1 + v).
double volumeStiffness(double m, double v) { return modelStiffness(m / (1.0 + v)); }

const std::vector<double> kMasses = {2.0e-3, 2.3e-3, 2.5e-3, 2.9e-3, 3.2e-3, 3.5e-3};

StiffnessComparison makeComparison(const std::function<double(double)>& measured) {
    StiffnessComparison c;
    for (double m : kMasses) {
        StiffnessPoint p;
        p.gasMass = m;
        p.measured = measured(m);
        p.simulated = modelStiffness(m);
        c.points.push_back(p);
    }
    return c;
}

StiffnessTable makeTable(const std::vector<double>& masses,
                         const std::function<double(double)>& k) {
    StiffnessTable t;
    t.gasMass = masses;
    for (double m : masses) t.stiffness.push_back(k(m));
    return t;
}

// The candidates as the app builds them, the grids from the stand-in: the dense curve at the
// masses makeShiftMasses gives (every 0.125 g), bag-volume every 0.0625 over its bounds.
std::vector<CurveCandidate> makeCandidates() {
    const StiffnessTable dense =
        makeTable(makeShiftMasses(kMasses, 0.125 * kGram, kRoom), modelStiffness);
    const StiffnessTable base = makeTable(kMasses, modelStiffness);
    std::vector<CurveCandidate> out;
    for (const char* name : {"flowmeter-bias", "gas-temperature", "bag-volume",
                             "machine-compliance", "bed-compliance"}) {
        CurveCandidate c;
        c.effect = findEffect(name);
        std::string why;
        EXPECT_TRUE(actsOnStiffnessCurve(*c.effect, c.action, why)) << name;
        c.roomTemperature = kRoom;
        if (c.action == CurveAction::MassOffset || c.action == CurveAction::MassScale) {
            c.tables = {dense};
        } else if (c.action == CurveAction::Grid) {
            for (int j = 0; j <= 8; ++j) {
                const double v = -0.25 + 0.0625 * j;
                c.values.push_back(v);
                c.tables.push_back(
                    makeTable(kMasses, [v](double m) { return volumeStiffness(m, v); }));
            }
        } else {
            c.tables = {base};
        }
        out.push_back(c);
    }
    return out;
}

const CandidateResult& find(const StiffnessWhich& w, const std::string& name) {
    for (const CandidateResult& c : w.which.candidates)
        if (c.effect == name) return c;
    throw std::runtime_error("no candidate " + name);
}

const double kValidation = 20.0;  // [N/m]: 0.02 N/mm

TEST(StiffnessWhich, InterpolationAndItsLeaveOneOutError) {
    // A quadratic a m^2 on a grid of spacing h: the midpoint of two neighbours is off by a h^2.
    StiffnessTable t = makeTable({1.0, 2.0, 3.0, 4.0}, [](double m) { return 5.0 * m * m; });
    EXPECT_DOUBLE_EQ(calcLeaveOneOutInterpolationError(t), 5.0);
    EXPECT_DOUBLE_EQ(interpolateStiffness(t, 2.5), 0.5 * (20.0 + 45.0));
    EXPECT_DOUBLE_EQ(interpolateStiffness(t, 3.0), 45.0);
    EXPECT_TRUE(std::isnan(interpolateStiffness(t, 4.5)));
    t.stiffness[2] = NAN;  // no stiffness at 3: nothing beside it is read
    EXPECT_TRUE(std::isnan(interpolateStiffness(t, 2.5)));
    EXPECT_DOUBLE_EQ(interpolateStiffness(t, 2.0), 20.0);
    // The dense masses: on multiples of the step, from 0.25 g below the least mass (the
    // flowmeter's bound) to 0.25 g above the largest, the used masses added.
    const std::vector<double> m = makeShiftMasses({2.3e-3, 3.0e-3}, 0.25e-3, kRoom);
    ASSERT_EQ(m.size(), 7u);
    EXPECT_NEAR(m.front(), 2.0e-3, 1e-12);
    EXPECT_NEAR(m[2], 2.3e-3, 1e-12);
    EXPECT_NEAR(m.back(), 3.25e-3, 1e-12);
}

TEST(StiffnessWhich, NamesTheFlowmeterOffsetOfAShiftedCurve) {
    // The bag holds 0.2 g more than the flowmeter reads (offset -0.2 g): the measured curve is
    // the model's re-read 0.2 g further on. Beyond the gas temperature's reach (5 % at 15 K).
    const double offset = -0.2 * kGram;
    const StiffnessWhich w = calibrateStiffnessCandidates(
        makeComparison([&](double m) { return modelStiffness(m - offset); }), makeCandidates(),
        kValidation, "stand-in", CalibrationOptions());
    EXPECT_FALSE(w.withinValidation);
    EXPECT_EQ(w.which.verdict, "flowmeter-bias") << w.which.reason;
    const CandidateResult& c = w.which.candidates.front();
    ASSERT_EQ(c.effect, "flowmeter-bias");
    EXPECT_NEAR(c.parameters[0], offset, 0.01 * kGram);  // the dense grid's interpolation
    EXPECT_GT(c.excessShrink, 0.9);
    EXPECT_EQ(c.folds.size(), kMasses.size());
    for (const FoldResult& f : c.folds) EXPECT_NEAR(f.parameters[0], offset, 0.02 * kGram);
    ASSERT_EQ(c.heldoutMetricsAfter.size(), 1u);
    EXPECT_LT(c.heldoutMetricsAfter[0].rmse, 0.1 * c.heldoutMetricsBefore[0].rmse);
    // The temperature reaches a 5 % scale only: at its bound, it explains less.
    EXPECT_LT(find(w, "gas-temperature").score, c.score);
    EXPECT_EQ(w.which.reason.find("at its bound"), std::string::npos);
}

TEST(StiffnessWhich, SaysWhenTheVerdictIsFittedAtItsBound) {
    // The bag holds 0.4 g more than the flowmeter reads: beyond the offset's bound (0.25 g);
    // the flowmeter and a compliance the candidates.
    const std::vector<CurveCandidate> all = makeCandidates();
    const StiffnessWhich w = calibrateStiffnessCandidates(
        makeComparison([](double m) { return modelStiffness(m + 0.4 * kGram); }), {all[0], all[3]},
        kValidation, "stand-in", CalibrationOptions());
    ASSERT_EQ(w.which.verdict, "flowmeter-bias") << w.which.reason;
    EXPECT_DOUBLE_EQ(w.which.candidates.front().parameters[0], -0.25 * kGram);
    EXPECT_NE(w.which.reason.find("fitted at its bound (offset -0.25 g)"), std::string::npos)
        << w.which.reason;
}

TEST(StiffnessWhich, NamesTheBagVolumeAndTheTemperatureAsAFlowmeterGain) {
    // A bag 18.75 % smaller (between the grid's values): only bag-volume reaches it.
    const StiffnessWhich w = calibrateStiffnessCandidates(
        makeComparison([](double m) { return volumeStiffness(m, -0.1875 - 0.01); }),
        makeCandidates(), kValidation, "stand-in", CalibrationOptions());
    EXPECT_EQ(w.which.verdict, "bag-volume") << w.which.reason;
    EXPECT_NEAR(w.which.candidates.front().parameters[0], -0.1975, 0.01);
    // The temperature is named the same as a flowmeter gain, and the two compliances alike.
    int named = 0;
    for (const auto& [pair, why] : w.identical) {
        if (pair.first == "gas-temperature" && pair.second == "a flowmeter gain") ++named;
        if (pair.first == "machine-compliance" && pair.second == "bed-compliance") ++named;
    }
    EXPECT_EQ(named, 2);
}

TEST(StiffnessWhich, AWarmerGasIsConfusableWithTheBagVolume) {
    // 12 K warmer: the gas acts as 4 % more, as a bag 3.9 % smaller does in the stand-in.
    const double dT = 12.0;
    const StiffnessWhich w = calibrateStiffnessCandidates(
        makeComparison([&](double m) { return modelStiffness(m * (kRoom + dT) / kRoom); }),
        makeCandidates(), kValidation, "stand-in", CalibrationOptions());
    // The verdict names both (each is held to its own grid's interpolation error beside the
    // curve's validation uncertainty), and what would tell them apart.
    ASSERT_TRUE(w.which.verdict == "gas-temperature or bag-volume" ||
                w.which.verdict == "bag-volume or gas-temperature")
        << w.which.reason;
    EXPECT_EQ(w.which.explained, "fully") << w.which.reason;
    EXPECT_EQ(w.which.rivals.size(), 1u);
    EXPECT_NE(w.which.tellApart.find("a thermometer in the bag's gas"), std::string::npos)
        << w.which.tellApart;
    EXPECT_NE(w.which.tellApart.find("the bag's sizes or its volume measured"), std::string::npos)
        << w.which.tellApart;
    EXPECT_NEAR(find(w, "gas-temperature").parameters[0], dT, 0.5);
    bool confusable = false;
    for (const auto& [a, b] : w.which.confusable)
        confusable = confusable || ((a == "gas-temperature" && b == "bag-volume") ||
                                    (a == "bag-volume" && b == "gas-temperature"));
    EXPECT_TRUE(confusable) << w.which.reason;
}

TEST(StiffnessWhich, TheModelsOwnCurveIsNone) {
    const StiffnessWhich w =
        calibrateStiffnessCandidates(makeComparison(modelStiffness), makeCandidates(), kValidation,
                                     "stand-in", CalibrationOptions());
    EXPECT_TRUE(w.withinValidation);
    EXPECT_EQ(w.which.verdict, "none");
    EXPECT_TRUE(w.which.verdictEffects.empty());
    // Each candidate fits to nothing (the model as it is wins the ties).
    EXPECT_NEAR(find(w, "flowmeter-bias").parameters[0], 0.0, 1e-9);
    EXPECT_NEAR(find(w, "machine-compliance").parameters[0], 0.0, 1e-9);
    // The model's curve as a file keeps it (rounded to 1e-9): the fit stays at 0, not a
    // roundoff's step beside it (where bag-volume's grid may give no stiffness).
    const StiffnessWhich r = calibrateStiffnessCandidates(
        makeComparison([](double m) { return modelStiffness(m) * (1.0 + 1e-9); }), makeCandidates(),
        kValidation, "stand-in", CalibrationOptions());
    EXPECT_EQ(r.which.verdict, "none");
    for (const CandidateResult& c : r.which.candidates) {
        EXPECT_EQ(c.parameters[0], 0.0) << c.effect;
        for (const FoldResult& f : c.folds) EXPECT_EQ(f.parameters[0], 0.0) << c.effect;
    }
}

TEST(StiffnessWhich, ACurveNoCandidateMakesIsUnexplained) {
    // Every other mass 40 % stiffer: no shift, scale or compliance zig-zags.
    int i = 0;
    const StiffnessWhich w = calibrateStiffnessCandidates(
        makeComparison([&](double m) { return modelStiffness(m) * (i++ % 2 ? 1.4 : 1.0); }),
        makeCandidates(), kValidation, "stand-in", CalibrationOptions());
    EXPECT_FALSE(w.withinValidation);
    EXPECT_EQ(w.which.verdict, "unexplained") << w.which.reason;
}

TEST(StiffnessWhich, TheOthersAreNotApplicableWithAReason) {
    int applicable = 0;
    for (const Effect& e : getEffects()) {
        CurveAction a;
        std::string why;
        if (actsOnStiffnessCurve(e, a, why))
            ++applicable;
        else
            EXPECT_FALSE(why.empty()) << e.name;
    }
    EXPECT_EQ(applicable, 6);  // five of the library and the load cell's gain
    CalibrationOptions o;
    const std::vector<CurveCandidate> all = makeCandidates();
    const std::vector<CurveCandidate> two = {all[0], all[1]};
    StiffnessComparison c = makeComparison(modelStiffness);
    c.points.resize(2);
    EXPECT_THROW(calibrateStiffnessCandidates(c, two, kValidation, "", o), std::invalid_argument);
}

}  // namespace
