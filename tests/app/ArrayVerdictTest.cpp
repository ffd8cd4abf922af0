// The support verdict (app/ArrayVerdict.cpp) on synthetic frames, each check against its stated
// criterion: time above 32 mmHg summed over the output intervals; a centre of mass that ends
// over the outer column fails, one that travels more than a column pitch warns; an outer bag
// that carried him and carries nothing once he moved on toward its edge warns; a pressed node less
// than 25 mm above the board fails; a centre of mass below the board fails; the turn's
// outcome. Frames before the end of the settle are not judged.
#include <gtest/gtest.h>

#include <cmath>

#include "ArrayVerdict.h"

namespace {

constexpr double kMmHg = 133.322387415;

cosim::ArrayLayout makeLayout() {  // the shipped 6 x 7 array, wedges along the bed
    cosim::ArrayLayout a;
    a.rows = 6;
    a.columns = 7;
    a.rowPitch = 0.36;
    a.columnPitch = 0.105;
    a.centre = Eigen::Vector2d(-0.03, 0.0);
    a.rowOrientation = {cosim::BagOrientation::Along, cosim::BagOrientation::AlongFlipped};
    a.gasMass = 4.5e-3;
    return a;
}

io::ArrayFrame frame(double t, double y, double z, double ppi, double edgeForce) {
    io::ArrayFrame f;
    f.time = t;
    f.centreOfMass = Eigen::Vector3d(0.08, y, z);
    cosim::RegionLoad r;
    r.name = "sacrum";
    r.peakPressure = ppi * kMmHg;
    r.patchPeakPressure = 0.75 * ppi * kMmHg;  // a patch peak below the nodal one
    f.regions = {r};
    for (int b : {0, 3, 6}) {  // row 0: columns 0 (his left edge), 3, 6 (his right edge)
        cosim::BagReading g;
        g.bag = b;
        g.force = b == 0 ? edgeForce : 100.0;
        f.bags.push_back(g);
    }
    return f;
}

const io::VerdictRow& row(const std::vector<io::VerdictRow>& rows, const std::string& check) {
    for (const io::VerdictRow& r : rows)
        if (r.check == check) return r;
    static io::VerdictRow none;
    ADD_FAILURE() << "no row " << check;
    return none;
}

}  // namespace

TEST(ArrayVerdict, EachCheckFollowsItsCriterion) {
    const cosim::ArrayLayout layout = makeLayout();
    bagsim::app::ArrayVerdict v(layout, bags::DoubleWedgeParams(), 1.0, 3.0, 30.0 * M_PI / 180);
    // Before the settle's end: not judged (a landing's 500 mmHg and a pressed node at 5 mm).
    v.addFrame(frame(0.5, 0.0, 0.2, 500.0, 10.0), {0.005, 0.1, 0.1});
    // From 1 s every 0.5 s: 40 mmHg for two intervals, then 20 mmHg; he drifts to his left
    // (-y) by 300 mm, the left edge bag (column 0) loses him, the least inner height 30 mm.
    v.addFrame(frame(1.0, 0.0, 0.20, 40.0, 10.0), {0.10, 0.10, 0.10});
    v.addFrame(frame(1.5, -0.05, 0.19, 40.0, 10.0), {0.08, 0.03, 0.10});
    v.addFrame(frame(2.0, -0.15, 0.18, 20.0, 0.05), {0.08, 0.08, 0.10});
    v.addFrame(frame(2.5, -0.30, 0.17, 20.0, 0.0), {0.08, 0.08, 0.10});
    v.setTurn(2.0, 0.5, true);
    std::vector<io::VerdictRow> rows = v.makeRows();
    EXPECT_EQ(row(rows, "target tilt reached").status, "ok");
    EXPECT_NEAR(row(rows, "target tilt reached").value, 0.5 * 180 / M_PI, 1e-9);
    EXPECT_EQ(row(rows, "back to supine").status, "ok");
    EXPECT_EQ(row(rows, "back to supine").detail, "the initial gas masses were restored");
    // A turn with the zones held returns to their setpoint, and says so.
    v.setTurn(2.0, 0.5, true, 4000.0);
    EXPECT_EQ(row(v.makeRows(), "back to supine").detail,
              "the turned zones were brought back to their setpoint (4.000 kPa)");
    v.setTurn(2.0, 0.5, false, 4000.0);
    EXPECT_EQ(row(v.makeRows(), "back to supine").detail,
              "the run ended before the turned zones were back at their setpoint");
    v.setTurn(2.0, 0.5, true);
    // Ends at y = -300 mm: column 0's bags stand at y = -315 mm, 100 mm wide, so their inner
    // edge is at -265 mm and he lies over the outer column.
    EXPECT_EQ(row(rows, "slid or rolled toward the edge").status, "fail");
    EXPECT_NEAR(row(rows, "slid or rolled toward the edge").value, -300.0, 1e-9);
    EXPECT_EQ(row(rows, "contact lost at the array edge").status, "warning");
    EXPECT_NE(row(rows, "contact lost at the array edge").detail.find("from 2.00 s"),
              std::string::npos)
        << row(rows, "contact lost at the array edge").detail;
    EXPECT_EQ(row(rows, "bag bottomed out").status, "ok");  // 30 mm >= 25 mm
    EXPECT_NEAR(row(rows, "bag bottomed out").value, 30.0, 1e-9);
    EXPECT_EQ(row(rows, "fell through or off the bags").status, "ok");
    const io::VerdictRow& sacrum = row(rows, "peak pressure sacrum");
    EXPECT_EQ(sacrum.status, "warning");
    EXPECT_NEAR(sacrum.value, 40.0, 1e-9);
    EXPECT_NE(sacrum.detail.find("above 32 mmHg for 0.50 s of 1.50 s"), std::string::npos)
        << sacrum.detail;  // the 1.0 s frame opens the window; 1.5 s adds its interval
    // The patch peak beside it (0.75 of the nodal one: 30 mmHg, never above 32 mmHg).
    EXPECT_NE(sacrum.detail.find("patch peak (20 cm2) 30.0 mmHg, above 32 mmHg for 0.00 s"),
              std::string::npos)
        << sacrum.detail;

    // A warning for travel beyond one column pitch that ends over the middle; a pressed node
    // 20 mm up fails; his centre of mass under the board fails; a turn that gave up fails.
    bagsim::app::ArrayVerdict w(layout, bags::DoubleWedgeParams(), 1.0, 3.0, 30.0 * M_PI / 180);
    w.addFrame(frame(1.0, 0.0, 0.2, 10.0, 10.0), {0.1});
    w.addFrame(frame(1.5, 0.12, 0.1, 10.0, 10.0), {0.02});
    w.addFrame(frame(2.0, 0.0, -0.01, 10.0, 10.0), {0.1});
    w.setTurn(std::nan(""), 0.2, false);
    rows = w.makeRows();
    EXPECT_EQ(row(rows, "slid or rolled toward the edge").status, "warning");
    EXPECT_EQ(row(rows, "bag bottomed out").status, "fail");
    EXPECT_EQ(row(rows, "fell through or off the bags").status, "fail");
    EXPECT_EQ(row(rows, "target tilt reached").status, "fail");
    EXPECT_EQ(row(rows, "back to supine").status, "warning");
    EXPECT_EQ(row(rows, "peak pressure sacrum").status, "ok");

    // No turn: its checks are n/a.
    bagsim::app::ArrayVerdict n(layout, bags::DoubleWedgeParams(), 1.0, 3.0, 0.0);
    n.addFrame(frame(1.0, 0.0, 0.2, 10.0, 10.0), {0.1});
    rows = n.makeRows();
    EXPECT_EQ(row(rows, "target tilt reached").status, "n/a");
    EXPECT_EQ(row(rows, "back to supine").status, "n/a");
}

// The films at their equilibrium: n/a for quasi-static and dynamic bags (their steps are
// equilibria or are cut; or have none to reach), ok for relaxed bags that kept no step
// unrelaxed, fail with the count, the largest residual and its bag when they did.
TEST(ArrayVerdict, RelaxedBagsWithUnrelaxedStepsFail) {
    using Stepping = bags::AirbagSpec::Stepping;
    const cosim::ArrayLayout layout = makeLayout();
    bagsim::app::ArrayVerdict v(layout, bags::DoubleWedgeParams(), 1.0, 3.0, 0.0);
    v.addFrame(frame(1.0, 0.0, 0.2, 10.0, 10.0), {0.1});
    EXPECT_EQ(row(v.makeRows(), "bag films relaxed").status, "n/a");  // quasi-static by default
    v.setFilmSteps(Stepping::Dynamic, 0, 0.0, -1, 0.05);
    EXPECT_EQ(row(v.makeRows(), "bag films relaxed").status, "n/a");
    EXPECT_FALSE(v.hasUnrelaxedSteps());
    v.setFilmSteps(Stepping::Relaxed, 0, 0.0, -1, 0.05);
    EXPECT_EQ(row(v.makeRows(), "bag films relaxed").status, "ok");
    EXPECT_FALSE(v.hasUnrelaxedSteps());
    v.setFilmSteps(Stepping::Relaxed, 12, 0.31, 17, 0.05);
    const io::VerdictRow r = row(v.makeRows(), "bag films relaxed");
    EXPECT_EQ(r.status, "fail");
    EXPECT_EQ(r.value, 12.0);
    EXPECT_NE(r.detail.find("the largest residual kept 0.31 N (bag 17)"), std::string::npos)
        << r.detail;
    EXPECT_TRUE(v.hasUnrelaxedSteps());
}

// The coupling at its fixed point: ok with the implicit schemes when every step reached it,
// fail with the count, the largest residual, its tolerance and time when steps were kept
// without one (coupling.keep_unconverged), n/a for the one-pass schemes.
TEST(ArrayVerdict, StepsKeptWithoutTheCouplingsFixedPointFail) {
    const cosim::ArrayLayout layout = makeLayout();
    bagsim::app::ArrayVerdict v(layout, bags::DoubleWedgeParams(), 1.0, 3.0, 0.0);
    v.addFrame(frame(1.0, 0.0, 0.2, 10.0, 10.0), {0.1});
    EXPECT_EQ(row(v.makeRows(), "coupling converged").status, "ok");  // implicit by default
    v.setCouplingSteps(false, 0, 0.0, 0.0, 0.0);
    EXPECT_EQ(row(v.makeRows(), "coupling converged").status, "n/a");
    v.setCouplingSteps(true, 3, 0.0347, 0.0014, 22.625);
    const io::VerdictRow r = row(v.makeRows(), "coupling converged");
    EXPECT_EQ(r.status, "fail");
    EXPECT_EQ(r.value, 3.0);
    EXPECT_NE(r.detail.find("0.0347 N against 0.0014 N at 22.6250 s"), std::string::npos)
        << r.detail;
    EXPECT_NE(r.detail.find("the run is partial"), std::string::npos) << r.detail;
    // Steps accepted where their passes stalled within coupling.accept_residual do not fail
    // the row; it says how many and the largest residual accepted. Beside a step kept without
    // a fixed point the row still fails.
    v.setCouplingSteps(true, 0, 0.0, 0.0, 0.0);
    v.setAcceptedSteps(12, 0.0412, 26.0123, 0.1);
    const io::VerdictRow a = row(v.makeRows(), "coupling converged");
    EXPECT_EQ(a.status, "ok");
    EXPECT_NE(a.detail.find("to its tolerance but 12, accepted where their passes stalled within "
                            "coupling.accept_residual (0.1 N; the largest |H(x) - x| 0.0412 N "
                            "at 26.0123 s)"),
              std::string::npos)
        << a.detail;
    v.setCouplingSteps(true, 3, 0.0347, 0.0014, 22.625);
    EXPECT_EQ(row(v.makeRows(), "coupling converged").status, "fail");
}

// The inflation: ok within the published clinical settings (up to 4 kPa), a warning above
// them (a firm setting), no row when the pressures were not given.
TEST(ArrayVerdict, AFirmInflationIsToldFromAClinicalOne) {
    const cosim::ArrayLayout layout = makeLayout();
    bagsim::app::ArrayVerdict v(layout, bags::DoubleWedgeParams(), 1.0, 3.0, 0.0);
    v.addFrame(frame(1.0, 0.0, 0.2, 10.0, 10.0), {0.1});
    for (const io::VerdictRow& r : v.makeRows()) EXPECT_NE(r.check, "inflation");
    v.setRestPressures(3.9e3, 4.1e3);
    io::VerdictRow r = row(v.makeRows(), "inflation");
    EXPECT_EQ(r.status, "ok");
    EXPECT_DOUBLE_EQ(r.value, 4.1);
    v.setRestPressures(18.5e3, 20.5e3);
    r = row(v.makeRows(), "inflation");
    EXPECT_EQ(r.status, "warning");
    EXPECT_NE(r.detail.find("18.5-20.5 kPa"), std::string::npos) << r.detail;
    EXPECT_NE(r.detail.find("a firm setting"), std::string::npos) << r.detail;
    // The whole text, its source included (it once lost its end to a fixed buffer).
    EXPECT_NE(r.detail.find("1.6-4.0 kPa (docs/validation-interface-pressure.md)"),
              std::string::npos)
        << r.detail;
}

// The film within its material's fitted range: n/a with no film judged; ok at a use below 1
// (the largest kept, with its bag, time and stretch); fail above, which makes the run partial.
TEST(ArrayVerdict, AFilmBeyondItsFittedRangeFailsTheRunsEnvelope) {
    bagsim::app::ArrayVerdict v(makeLayout(), bags::DoubleWedgeParams(), 1.0, 3.0, 0.0);
    EXPECT_EQ(row(v.makeRows(), "film within its fitted range").status, "n/a");
    v.addFilmRange(0.05, 1.02, 7, 0.5);
    v.addFilmRange(0.30, 1.08, 12, 1.5);
    v.addFilmRange(0.10, 1.04, 3, 2.0);
    io::VerdictRow r = row(v.makeRows(), "film within its fitted range");
    EXPECT_EQ(r.status, "ok");
    EXPECT_DOUBLE_EQ(r.value, 30.0);
    EXPECT_NE(r.detail.find("bag 12 at 1.50 s, principal stretch 1.080"), std::string::npos)
        << r.detail;
    EXPECT_FALSE(v.isFilmOutsideItsRange());
    v.addFilmRange(2.5, 1.9, 24, 2.5);
    r = row(v.makeRows(), "film within its fitted range");
    EXPECT_EQ(r.status, "fail");
    EXPECT_NE(r.detail.find("outside the model's envelope; the run is partial"), std::string::npos)
        << r.detail;
    EXPECT_TRUE(v.isFilmOutsideItsRange());
}
