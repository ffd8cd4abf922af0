#include "ArrayVerdict.h"
#include "Format.h"

#include <bags/Units.h>
#include <cosim/ArrayReadings.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace bagsim::app {

namespace {

constexpr double kMmHg = bags::kPascalsPerMmHg;      // [Pa]
constexpr double kCapillary = cosim::kRiskPressure;  // the capillary closing pressure [Pa]
constexpr double kHandCheck = 0.025;                 // [m] the nurses' hand check: 1 inch of air
constexpr double kCarried = 1.0;                     // [N] a bag that carries him
constexpr double kNothing = 0.1;                     // [N] a bag that carries nothing
constexpr double kDeg = 180.0 / 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// [Pa] the highest cell pressure of the published clinical settings of active air mattresses
// found (a 4.0 kPa default, studied down to 1.6 kPa; docs/validation-interface-pressure.md),
// with 5 % for the setting's own tolerance.
constexpr double kClinicalHighest = 4.0e3 * 1.05;

}  // namespace

ArrayVerdict::ArrayVerdict(const cosim::ArrayLayout& layout, const bags::DoubleWedgeParams& bag,
                           double settleTime, double duration, double targetTilt)
    : m_bags(cosim::makeArrayBags(layout, bag)),
      m_columns(layout.columns),
      m_columnPitch(layout.columnPitch),
      m_settle(settleTime),
      m_duration(duration),
      m_targetTilt(targetTilt),
      m_reached(kNaN),
      m_turnedTilt(kNaN) {
    // The inner edges of the outer columns' footprints: a centre of mass beyond one lies over
    // the outermost bags.
    m_innerEdgeLow = -1e9;
    m_innerEdgeHigh = 1e9;
    for (const cosim::ArrayBag& b : m_bags) {
        if (b.column == 0) m_innerEdgeLow = std::max(m_innerEdgeLow, b.footprintMax.y());
        if (b.column == m_columns - 1)
            m_innerEdgeHigh = std::min(m_innerEdgeHigh, b.footprintMin.y());
    }
}

void ArrayVerdict::addFrame(const io::ArrayFrame& f, const std::vector<double>& heights) {
    if (m_duration > 0.0 && f.time < m_settle - 1e-9) return;
    if (!m_haveRef) {
        m_haveRef = true;
        m_refCom = f.centreOfMass;
        m_firstTime = m_lastTime = f.time;
    }
    const double dt = f.time - m_lastTime;
    m_lastTime = f.time;
    // Travel across the bed.
    const double dy = f.centreOfMass.y() - m_refCom.y();
    m_lastY = f.centreOfMass.y();
    if (std::abs(dy) > std::abs(m_maxTravel)) {
        m_maxTravel = dy;
        m_maxTravelTime = f.time;
    }
    if (f.centreOfMass.z() < m_lowestCom) {
        m_lowestCom = f.centreOfMass.z();
        m_lowestComTime = f.time;
    }
    // An outer bag that carried him and carries nothing after he moved on past it (10 mm or
    // more further toward its edge since it last carried him): he rolled or slid off it.
    if (m_columns > 1)
        for (const cosim::BagReading& b : f.bags) {
            const int column = m_bags[b.bag].column;
            if (column != 0 && column != m_columns - 1) continue;
            const double outward = column == 0 ? -1.0 : 1.0;
            if (b.force >= kCarried) {
                m_lastCarriedY[b.bag] = f.centreOfMass.y();
            } else if (b.force < kNothing && m_lastCarriedY.count(b.bag) &&
                       outward * (f.centreOfMass.y() - m_lastCarriedY[b.bag]) > 0.01 &&
                       !m_edgeLost.count(b.bag)) {
                m_edgeLost[b.bag] = f.time;
            }
        }
    // Bottoming out.
    for (size_t i = 0; i < f.bags.size() && i < heights.size(); ++i)
        if (heights[i] < m_minHeight) {
            m_minHeight = heights[i];
            m_minHeightTime = f.time;
            m_minHeightBag = f.bags[i].bag;
        }
    // Regions.
    for (const cosim::RegionLoad& r : f.regions) {
        if (!(r.peakPressure > 0.0)) continue;
        if (!m_regions.count(r.name)) m_regionOrder.push_back(r.name);
        Region& g = m_regions[r.name];
        if (r.peakPressure > g.peak) {
            g.peak = r.peakPressure;
            g.peakTime = f.time;
        }
        if (r.peakPressure > kCapillary) g.above += dt;
        g.patchPeak = std::max(g.patchPeak, r.patchPeakPressure);
        if (r.patchPeakPressure > kCapillary) g.patchAbove += dt;
    }
}

void ArrayVerdict::setTurn(double reachedTime, double turnedTilt, bool backToSupine,
                           double setpoint) {
    m_setpoint = setpoint;
    m_reached = reachedTime;
    m_turnedTilt = turnedTilt;
    m_back = backToSupine;
    m_turnKnown = true;
}

void ArrayVerdict::setFilmSteps(bags::AirbagSpec::Stepping stepping, long unrelaxed, double largest,
                                int worstBag, double tolerance) {
    m_stepping = stepping;
    m_unrelaxed = unrelaxed;
    m_largestUnrelaxed = largest;
    m_unrelaxedBag = worstBag;
    m_forceTolerance = tolerance;
}

void ArrayVerdict::setRestPressures(double least, double highest) {
    m_restLeast = least;
    m_restHighest = highest;
}

void ArrayVerdict::setCouplingSteps(bool iterated, long unconverged, double worstResidual,
                                    double worstTolerance, double worstTime) {
    m_iterated = iterated;
    m_unconverged = unconverged;
    m_worstResidual = worstResidual;
    m_worstTolerance = worstTolerance;
    m_worstTime = worstTime;
}

void ArrayVerdict::setAcceptedSteps(long accepted, double worst, double worstTime,
                                    double acceptResidual) {
    m_accepted = accepted;
    m_worstAccepted = worst;
    m_worstAcceptedTime = worstTime;
    m_acceptResidual = acceptResidual;
}

std::vector<io::VerdictRow> ArrayVerdict::makeRows() const {
    std::vector<io::VerdictRow> rows;
    const double span = m_lastTime - m_firstTime;
    const std::string window = m_duration > 0.0 ? "after the settle" : "over the run";
    // The turn.
    if (m_targetTilt == 0.0 || !m_turnKnown) {
        rows.push_back({"target tilt reached", "n/a", kNaN, "deg", "no turn in this run"});
        rows.push_back({"back to supine", "n/a", kNaN, "", "no turn in this run"});
    } else {
        const std::string target = fmt("target %+.1f deg", m_targetTilt * kDeg);
        if (std::isfinite(m_reached))
            rows.push_back({"target tilt reached", "ok", m_turnedTilt * kDeg, "deg",
                            "reached at " + fmt("%.2f s", m_reached) + " (" +
                                fmt("%.2f s", m_reached - m_settle) + " after the settle; " +
                                target + "; value: the pelvis tilt then)"});
        else if (std::isfinite(m_turnedTilt))
            rows.push_back({"target tilt reached", "fail", m_turnedTilt * kDeg, "deg",
                            "not reached in the longest turn time (" + target +
                                "; value: the pelvis tilt when the turn gave up)"});
        else
            rows.push_back({"target tilt reached", "warning", kNaN, "deg",
                            "not reached yet: the run ended during the turn (" + target + ")"});
        const std::string restored =
            m_setpoint > 0.0 ? "the turned zones were brought back to their setpoint (" +
                                   fmt("%.3f kPa", 1e-3 * m_setpoint) + ")"
                             : std::string("the initial gas masses were restored");
        const std::string pending = m_setpoint > 0.0
                                        ? "the turned zones were back at their setpoint"
                                        : "the initial masses were restored";
        rows.push_back({"back to supine", m_back ? "ok" : "warning", kNaN, "",
                        m_back ? restored : "the run ended before " + pending});
    }
    // Travel toward the edge.
    if (!m_haveRef) {
        rows.push_back({"slid or rolled toward the edge", "n/a", kNaN, "mm", "no frame judged"});
    } else {
        const bool over = m_lastY < m_innerEdgeLow || m_lastY > m_innerEdgeHigh;
        const bool far = std::abs(m_maxTravel) > m_columnPitch && m_columnPitch > 0.0;
        rows.push_back({"slid or rolled toward the edge",
                        over  ? "fail"
                        : far ? "warning"
                              : "ok",
                        1e3 * m_maxTravel, "mm",
                        "largest lateral travel of his centre of mass " + window +
                            fmt(" (at %.2f s", m_maxTravelTime) +
                            "); at the end at y = " + fmt("%.1f mm", 1e3 * m_lastY) +
                            "; fail when it ends over the outer column (beyond y = " +
                            fmt("%.0f mm", 1e3 * m_innerEdgeLow) + " or " +
                            fmt("%.0f mm", 1e3 * m_innerEdgeHigh) +
                            "); warning beyond one column pitch (" +
                            fmt("%.0f mm", 1e3 * m_columnPitch) + ")"});
        std::string lost;
        double first = kNaN;
        for (const auto& [bag, t] : m_edgeLost) {
            lost += (lost.empty() ? "" : " ") + std::to_string(bag);
            if (!(first <= t)) first = t;
        }
        rows.push_back({"contact lost at the array edge", lost.empty() ? "ok" : "warning",
                        double(m_edgeLost.size()), "bags",
                        lost.empty() ? "no outer bag lost him as he moved toward its edge"
                                     : "outer bags " + lost +
                                           " carried him (1 N or more) and "
                                           "nothing (< 0.1 N) once he had moved 10 mm or more "
                                           "further toward their edge; the first from " +
                                           fmt("%.2f s", first)});
    }
    // Fell through or off the bags: his centre of mass below the bed board (with
    // array.board_contact off only the bags carry him; with it the board stops him).
    if (m_haveRef)
        rows.push_back({"fell through or off the bags", m_lowestCom < 0.0 ? "fail" : "ok",
                        1e3 * m_lowestCom, "mm",
                        "lowest height of his centre of mass above the bed board " + window +
                            fmt(" (at %.2f s)", m_lowestComTime) +
                            "; fail below 0 mm: below the bed board"});
    // Bottoming out.
    if (m_minHeightBag < 0 || !std::isfinite(m_minHeight))
        rows.push_back({"bag bottomed out", "n/a", kNaN, "mm", "no pressed node judged"});
    else
        rows.push_back({"bag bottomed out", m_minHeight < kHandCheck ? "fail" : "ok",
                        1e3 * m_minHeight, "mm",
                        "least inner height under a pressed node (its height above the bed "
                        "board) " +
                            window + ": bag " + std::to_string(m_minHeightBag) +
                            fmt(" at %.2f s", m_minHeightTime) +
                            "; fail below 25 mm (the hand check: an inch of air)"});
    // The film within the range its material law was fitted and is stable in.
    if (m_filmBag < 0)
        rows.push_back({"film within its fitted range", "n/a", kNaN, "%",
                        "no finite-element film judged (reduced bags, or a law without a "
                        "fitted range)"});
    else
        rows.push_back(
            {"film within its fitted range", m_filmUse > 1.0 ? "fail" : "ok", 100.0 * m_filmUse,
             "%",
             std::string(
                 m_filmUse > 1.0
                     ? "a film was stretched beyond the range its material law was fitted and is "
                       "stable in (I1 - 3 above the law's limit): the results from there on are "
                       "outside the model's envelope; the run is partial. Largest: "
                     : "every film stayed within its material's fitted, stable range; the largest "
                       "use of it: ") +
                 "bag " + std::to_string(m_filmBag) + fmt(" at %.2f s", m_filmTime) +
                 fmt(", principal stretch %.3f", m_filmStretch)});
    // The films at their equilibrium (the relaxed stepping keeps a step whose sub-steps ran
    // out; the quasi-static one cuts it, the dynamic one has no equilibrium to reach).
    using Stepping = bags::AirbagSpec::Stepping;
    if (m_stepping != Stepping::Relaxed)
        rows.push_back({"bag films relaxed", "n/a", kNaN, "steps",
                        m_stepping == Stepping::Dynamic
                            ? "the films are stepped in time (bag.stepping: dynamic), not to an "
                              "equilibrium"
                            : "quasi-static bags (bag.stepping): every step is an equilibrium to "
                              "the force tolerance or is cut"});
    else if (m_unrelaxed == 0)
        rows.push_back({"bag films relaxed", "ok", 0.0, "steps",
                        "every committed bag step reached the film's force tolerance (" +
                            fmt("%.3g N", m_forceTolerance) + ")"});
    else
        rows.push_back({"bag films relaxed", "fail", double(m_unrelaxed), "steps",
                        "bag steps kept unrelaxed (the film's sub-steps, "
                        "bag.dynamic.relax_substeps, ran out before its force tolerance, " +
                            fmt("%.3g N", m_forceTolerance) + "); the largest residual kept " +
                            fmt("%.3g N", m_largestUnrelaxed) + " (bag " +
                            std::to_string(m_unrelaxedBag) + "); the run is partial"});
    // The coupling at its fixed point (the implicit schemes keep a step without one only at
    // the smallest step, coupling.keep_unconverged).
    if (!m_iterated)
        rows.push_back({"coupling converged", "n/a", kNaN, "steps",
                        "a one-pass scheme (coupling.scheme): no fixed point is sought"});
    else if (m_unconverged == 0 && m_accepted == 0)
        rows.push_back({"coupling converged", "ok", 0.0, "steps",
                        "every macro step reached the coupling's fixed point to its tolerance"});
    else if (m_unconverged == 0)
        rows.push_back(
            {"coupling converged", "ok", 0.0, "steps",
             "every macro step reached the coupling's fixed point to its tolerance "
             "but " +
                 std::to_string(m_accepted) +
                 ", accepted where their passes stalled within coupling.accept_residual (" +
                 fmt("%.3g N", m_acceptResidual) + "; the largest |H(x) - x| " +
                 fmt("%.3g N", m_worstAccepted) + fmt(" at %.4f s", m_worstAcceptedTime) + ")"});
    else
        rows.push_back({"coupling converged", "fail", double(m_unconverged), "steps",
                        "macro steps kept without a fixed point at the smallest step "
                        "(coupling.keep_unconverged); the largest |H(x) - x| kept " +
                            fmt("%.3g N", m_worstResidual) + " against " +
                            fmt("%.3g N", m_worstTolerance) + fmt(" at %.4f s", m_worstTime) +
                            "; the run is partial"});
    // The inflation against the published clinical settings: a firm setting is not a
    // dangerous one (that is what the bottoming out and the peaks say), but its peaks and
    // immersion are not those of a clinical mattress.
    if (m_restHighest >= 0.0) {
        const std::string range =
            fmt("the bags stand at %.1f", 1e-3 * m_restLeast) +
            fmt("-%.1f kPa before he lies on them; published active air mattresses run their "
                "cells at 1.6-4.0 kPa (docs/validation-interface-pressure.md)",
                1e-3 * m_restHighest);
        if (m_restHighest > kClinicalHighest)
            rows.push_back({"inflation", "warning", 1e-3 * m_restHighest, "kPa",
                            range + ": a firm setting, the peaks and immersion of this run are "
                                    "of it, not of a clinical setting"});
        else
            rows.push_back({"inflation", "ok", 1e-3 * m_restHighest, "kPa",
                            range + ": within the clinical settings"});
    }
    // Regions.
    for (const std::string& name : m_regionOrder) {
        const Region& g = m_regions.at(name);
        rows.push_back({"peak pressure " + name, g.peak > kCapillary ? "warning" : "ok",
                        g.peak / kMmHg, "mmHg",
                        fmt("at %.2f s; ", g.peakTime) + fmt("above 32 mmHg for %.2f s", g.above) +
                            fmt(" of %.2f s ", span) + window +
                            fmt("; patch peak (20 cm2) %.1f mmHg", g.patchPeak / kMmHg) +
                            fmt(", above 32 mmHg for %.2f s", g.patchAbove)});
    }
    return rows;
}

namespace {

void saveMap(bags::StateWriter& w, const std::map<int, double>& m) {
    w.pod(std::uint64_t(m.size()));
    for (const auto& [k, v] : m) w.pod(k), w.pod(v);
}

void loadMap(bags::StateReader& r, std::map<int, double>& m) {
    m.clear();
    const auto n = r.pod<std::uint64_t>();
    for (std::uint64_t i = 0; i < n; ++i) {
        const int k = r.pod<int>();
        m[k] = r.pod<double>();
    }
}

}  // namespace

void ArrayVerdict::addFilmRange(double use, double stretch, int bag, double time) {
    if (bag < 0 || !(use > m_filmUse)) return;
    m_filmUse = use, m_filmStretch = stretch, m_filmBag = bag, m_filmTime = time;
}

void ArrayVerdict::saveState(bags::StateWriter& w) const {
    w.tag("verdict-2");  // 2: with the regions' patch peaks
    w.pod(m_reached), w.pod(m_turnedTilt), w.pod(m_back), w.pod(m_turnKnown);
    w.pod(m_haveRef), w.pod(m_lastTime), w.pod(m_firstTime);
    w.mat(m_refCom);
    w.pod(m_maxTravel), w.pod(m_maxTravelTime), w.pod(m_lastY);
    w.pod(m_lowestCom), w.pod(m_lowestComTime);
    saveMap(w, m_lastCarriedY);
    saveMap(w, m_edgeLost);
    w.pod(m_minHeight), w.pod(m_minHeightTime), w.pod(m_minHeightBag);
    w.pod(std::uint64_t(m_regions.size()));
    for (const auto& [name, reg] : m_regions) {
        w.str(name);
        w.pod(reg.peak), w.pod(reg.peakTime), w.pod(reg.above);
        w.pod(reg.patchPeak), w.pod(reg.patchAbove);
    }
    w.pod(std::uint64_t(m_regionOrder.size()));
    for (const std::string& name : m_regionOrder) w.str(name);
    w.tag("film-range");  // a later part: checkpoints before it have none
    w.pod(m_filmUse), w.pod(m_filmStretch), w.pod(m_filmTime), w.pod(m_filmBag);
}

void ArrayVerdict::loadState(bags::StateReader& r) {
    r.tag("verdict-2");
    r.pod(m_reached), r.pod(m_turnedTilt), r.pod(m_back), r.pod(m_turnKnown);
    r.pod(m_haveRef), r.pod(m_lastTime), r.pod(m_firstTime);
    Eigen::Vector3d com;
    r.mat(com);
    m_refCom = com;
    r.pod(m_maxTravel), r.pod(m_maxTravelTime), r.pod(m_lastY);
    r.pod(m_lowestCom), r.pod(m_lowestComTime);
    loadMap(r, m_lastCarriedY);
    loadMap(r, m_edgeLost);
    r.pod(m_minHeight), r.pod(m_minHeightTime), r.pod(m_minHeightBag);
    m_regions.clear();
    const auto n = r.pod<std::uint64_t>();
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::string name = r.str();
        Region& reg = m_regions[name];
        r.pod(reg.peak), r.pod(reg.peakTime), r.pod(reg.above);
        r.pod(reg.patchPeak), r.pod(reg.patchAbove);
    }
    m_regionOrder.resize(r.pod<std::uint64_t>());
    for (std::string& name : m_regionOrder) name = r.str();
    if (r.readTagIf("film-range")) {
        r.pod(m_filmUse), r.pod(m_filmStretch), r.pod(m_filmTime), r.pod(m_filmBag);
    }
}

}  // namespace bagsim::app
