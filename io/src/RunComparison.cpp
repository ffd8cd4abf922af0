#include "io/RunComparison.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>

#include "ChannelCsv.h"
#include "ReportPage.h"
#include "io/InputError.h"
#include "io/Results.h"
#include "io/Units.h"

namespace io {

namespace fs = std::filesystem;

namespace {

// Output rows are written every output.every (at least 1 ms); times are matched to 0.1 ms.
long timeKey(double t) { return std::lround(t * 1e4); }

using csv::fmt;

const char* kHelp =
    "a patient-on-array results folder (bagsim run --out DIR) holds tilt.csv and "
    "regions.csv";

// Tilt rows by time key: (pelvis, thorax) [rad].
std::map<long, std::pair<double, double>> readTilt(const fs::path& dir) {
    const report::CsvTable t = report::readCsvTable(
        dir / "tilt.csv", {"time_s", "pelvis_tilt_deg", "thorax_tilt_deg"}, false, kHelp);
    const int ct = t.find("time_s"), cp = t.find("pelvis_tilt_deg"), cq = t.find("thorax_tilt_deg");
    std::map<long, std::pair<double, double>> out;
    for (size_t r = 0; r < t.rows.size(); ++r)
        out[timeKey(t.number(r, ct))] = {fromUnit(t.number(r, cp), "deg"),
                                         fromUnit(t.number(r, cq), "deg")};
    return out;
}

struct RegionRow {
    double force = 0.0, peak = 0.0;  // [N], [Pa]
};

// Region rows by time key and region name.
std::map<long, std::map<std::string, RegionRow>> readRegions(const fs::path& dir) {
    const report::CsvTable t = report::readCsvTable(
        dir / "regions.csv", {"time_s", "region", "force_N", "patch_peak_mmHg"}, false, kHelp);
    const int ct = t.find("time_s"), cr = t.find("region"), cf = t.find("force_N"),
              cp = t.find("patch_peak_mmHg");
    std::map<long, std::map<std::string, RegionRow>> out;
    for (size_t r = 0; r < t.rows.size(); ++r)
        out[timeKey(t.number(r, ct))][t.text(r, cr)] = {t.number(r, cf),
                                                        fromUnit(t.number(r, cp), "mmHg")};
    return out;
}

RegionPeakSummary summarise(const std::vector<const RegionPeak*>& ps, double time, double tol) {
    RegionPeakSummary s;
    s.time = time;
    s.regions = int(ps.size());
    double sum = 0.0, sum2 = 0.0;
    for (const RegionPeak* p : ps) {
        const double e = p->error();
        sum += e, sum2 += e * e;
        if (std::abs(e) <= tol) ++s.within;
    }
    if (s.regions > 0) s.mean = sum / s.regions, s.rms = std::sqrt(sum2 / s.regions);
    return s;
}

}  // namespace

std::vector<std::string> RunComparison::whyNotJudged() const {
    std::vector<std::string> why;
    if (!referenceIncomplete.empty()) why.push_back("the reference is an unfinished run");
    if (!runIncomplete.empty()) why.push_back("the run is an unfinished run");
    if (tiltRows < referenceTiltRows)
        why.push_back("the run lacks " + std::to_string(referenceTiltRows - tiltRows) +
                      " of the reference's " + std::to_string(referenceTiltRows) + " tilt rows");
    if (tiltRowsNotFinite > 0)
        why.push_back(std::to_string(tiltRowsNotFinite) + " tilt rows are not finite numbers");
    if (!missingTimes.empty())
        why.push_back(std::to_string(missingTimes.size()) +
                      " asked-for moments are not output times of both runs");
    if (overall.regions == 0) why.push_back("no region was judged");
    return why;
}

bool RunComparison::meetsTargets() const {
    return whyNotJudged().empty() && tiltRowsWithin == tiltRows &&
           overall.within == overall.regions;
}

RunComparison compareRuns(const fs::path& reference, const fs::path& run,
                          const RunComparisonOptions& options) {
    RunComparison c;
    c.reference = reference, c.run = run, c.options = options;
    for (const fs::path& d : {reference, run}) {
        std::error_code ec;
        if (!fs::is_directory(d, ec))
            throw InputError(d.string(), 0, "", std::string("is not a folder; ") + kHelp);
    }
    // An unfinished run's folder says so (io::OutputDir's marker): its status line.
    auto incomplete = [](const fs::path& d) -> std::string {
        const std::string text = report::readTextIfPresent(d / OutputDir::kMarkerName);
        if (text.empty()) return "";
        const size_t at = text.find("status: ");
        if (at == std::string::npos) return "incomplete";
        return text.substr(at + 8, text.find('\n', at) - (at + 8));
    };
    c.referenceIncomplete = incomplete(reference), c.runIncomplete = incomplete(run);
    auto tiltRef = readTilt(reference), tiltRun = readTilt(run);
    // An unfinished run's last output row may be half-written (its regions before its tilt):
    // it is left out.
    if (!c.referenceIncomplete.empty() && !tiltRef.empty()) tiltRef.erase(std::prev(tiltRef.end()));
    if (!c.runIncomplete.empty() && !tiltRun.empty()) tiltRun.erase(std::prev(tiltRun.end()));
    auto range = [](const std::map<long, std::pair<double, double>>& t) {
        return t.empty() ? std::string("no rows")
                         : fmt("rows from %g s", t.begin()->first * 1e-4) +
                               fmt(" to %g s", t.rbegin()->first * 1e-4);
    };
    const long from = timeKey(options.from);
    double sp = 0.0, sq = 0.0, sp0 = 0.0, sq0 = 0.0;
    std::pair<double, double> firstRef{0.0, 0.0}, firstRun{0.0, 0.0};
    int sinceFirst = 0;  // finite rows compared since the first
    for (const auto& [k, ref] : tiltRef) {
        if (k < from) continue;
        ++c.referenceTiltRows;
        const auto it = tiltRun.find(k);
        if (it == tiltRun.end()) continue;
        const double t = k * 1e-4;
        if (c.tiltRows == 0) c.firstTime = t;
        c.lastTime = t;
        ++c.tiltRows;
        const double dp = it->second.first - ref.first, dq = it->second.second - ref.second;
        if (!std::isfinite(dp) || !std::isfinite(dq)) {
            ++c.tiltRowsNotFinite;
            continue;
        }
        sp += dp * dp, sq += dq * dq;
        if (c.tiltRows - c.tiltRowsNotFinite == 1 || std::abs(dp) > std::abs(c.pelvis.largest))
            c.pelvis.largest = dp, c.pelvis.largestTime = t;
        if (c.tiltRows - c.tiltRowsNotFinite == 1 || std::abs(dq) > std::abs(c.thorax.largest))
            c.thorax.largest = dq, c.thorax.largestTime = t;
        if (std::abs(dp) <= options.tiltTolerance && std::abs(dq) <= options.tiltTolerance)
            ++c.tiltRowsWithin;
        // The turn alone, from the first finite row on.
        if (sinceFirst == 0) firstRef = ref, firstRun = it->second;
        const double ep = dp - (firstRun.first - firstRef.first),
                     eq = dq - (firstRun.second - firstRef.second);
        ++sinceFirst;
        sp0 += ep * ep, sq0 += eq * eq;
        if (sinceFirst == 1 || std::abs(ep) > std::abs(c.pelvisSinceFirst.largest))
            c.pelvisSinceFirst.largest = ep, c.pelvisSinceFirst.largestTime = t;
        if (sinceFirst == 1 || std::abs(eq) > std::abs(c.thoraxSinceFirst.largest))
            c.thoraxSinceFirst.largest = eq, c.thoraxSinceFirst.largestTime = t;
        if (std::abs(ep) <= options.tiltTolerance && std::abs(eq) <= options.tiltTolerance)
            ++c.tiltRowsWithinSinceFirst;
    }
    if (sinceFirst > 0)
        c.pelvisSinceFirst.rms = std::sqrt(sp0 / sinceFirst),
        c.thoraxSinceFirst.rms = std::sqrt(sq0 / sinceFirst);
    if (c.tiltRows == 0)
        throw InputError((run / "tilt.csv").string(), 0, "time_s",
                         "no row at a time of " + (reference / "tilt.csv").string() +
                             (options.from > 0 ? " from " + fmt("%g s", options.from) : "") +
                             " (the reference has " + range(tiltRef) + ", the run " +
                             range(tiltRun) +
                             "); compare runs of the same scenario and output.every, and a "
                             "--from within them");
    const int finite = c.tiltRows - c.tiltRowsNotFinite;
    if (finite > 0) c.pelvis.rms = std::sqrt(sp / finite), c.thorax.rms = std::sqrt(sq / finite);

    // The moments: output times of both runs (their tilt.csv rows: a row is written every
    // frame, a region only while it is loaded, so a time without region rows is a frame where
    // the run loads none of them).
    const auto regRef = readRegions(reference), regRun = readRegions(run);
    std::vector<long> keys;
    if (options.times.empty()) {
        for (const auto& [k, row] : tiltRef)
            if (k >= from && tiltRun.count(k)) keys.push_back(k);
    } else {
        std::vector<double> times = options.times;
        std::sort(times.begin(), times.end());
        times.erase(std::unique(times.begin(), times.end(),
                                [](double a, double b) { return timeKey(a) == timeKey(b); }),
                    times.end());
        for (double t : times) {
            const long k = timeKey(t);
            if (tiltRef.count(k) && tiltRun.count(k))
                keys.push_back(k);
            else
                c.missingTimes.push_back(t);
        }
    }
    static const std::map<std::string, RegionRow> kNone;
    for (long k : keys) {
        const auto r = regRef.find(k), u = regRun.find(k);
        if (r == regRef.end()) continue;  // the reference loads no region then
        const auto& run_ = u == regRun.end() ? kNone : u->second;
        for (const auto& [name, ref] : r->second) {
            if (!(ref.force >= options.minForce) || !(ref.peak > 0.0)) continue;
            RegionPeak p;
            p.time = k * 1e-4, p.region = name, p.referenceForce = ref.force,
            p.reference = ref.peak;
            const auto it = run_.find(name);
            p.run = it == run_.end() ? 0.0 : it->second.peak;
            c.peaks.push_back(p);
        }
    }
    std::vector<const RegionPeak*> all;
    for (size_t i = 0; i < c.peaks.size();) {
        std::vector<const RegionPeak*> at;
        const double t = c.peaks[i].time;
        for (; i < c.peaks.size() && c.peaks[i].time == t; ++i) at.push_back(&c.peaks[i]);
        all.insert(all.end(), at.begin(), at.end());
        c.moments.push_back(summarise(at, t, options.peakTolerance));
    }
    c.overall = summarise(all, std::numeric_limits<double>::quiet_NaN(), options.peakTolerance);
    return c;
}

std::string formatRunComparison(const RunComparison& c, bool detail) {
    std::ostringstream o;
    const double tolDeg = toUnit(c.options.tiltTolerance, "deg");
    const double tolPc = 100.0 * c.options.peakTolerance;
    o << c.run.string() << " against " << c.reference.string() << "\n";
    for (const auto& [what, status] :
         {std::pair<const char*, const std::string&>{"the reference", c.referenceIncomplete},
          {"the run", c.runIncomplete}})
        if (!status.empty())
            o << "NOTE: " << what << " is an incomplete run (its INCOMPLETE marker: status "
              << status
              << "); its rows so far are compared, but its last one (it may be half-written)\n";
    o << "\n";
    o << "tilt (run - reference), " << c.tiltRows << " rows from " << fmt("%g s", c.firstTime)
      << " to " << fmt("%g s", c.lastTime);
    if (c.tiltRows < c.referenceTiltRows)
        o << " (the reference has " << c.referenceTiltRows << "; the run lacks the others)";
    o << ":\n";
    for (const auto& [name, d] :
         {std::pair<const char*, const TiltDifference&>{"pelvis", c.pelvis}, {"thorax", c.thorax}})
        o << "  " << name << ": largest " << fmt("%+.2f deg", toUnit(d.largest, "deg")) << " at "
          << fmt("%g s", d.largestTime) << ", rms " << fmt("%.2f deg", toUnit(d.rms, "deg"))
          << "\n";
    o << "  within " << fmt("%g deg", tolDeg) << ": " << c.tiltRowsWithin << " of " << c.tiltRows
      << " rows (both segments)";
    if (c.tiltRowsNotFinite > 0) o << "; " << c.tiltRowsNotFinite << " rows not finite numbers";
    o << "\n";
    o << "the turn alone (each run's tilt less its own at the first row; the side a settle picks "
         "left out):\n";
    for (const auto& [name, d] :
         {std::pair<const char*, const TiltDifference&>{"pelvis", c.pelvisSinceFirst},
          {"thorax", c.thoraxSinceFirst}})
        o << "  " << name << ": largest " << fmt("%+.2f deg", toUnit(d.largest, "deg")) << " at "
          << fmt("%g s", d.largestTime) << ", rms " << fmt("%.2f deg", toUnit(d.rms, "deg"))
          << "\n";
    o << "  within " << fmt("%g deg", tolDeg) << ": " << c.tiltRowsWithinSinceFirst << " of "
      << c.tiltRows - c.tiltRowsNotFinite << " rows (both segments)\n\n";
    o << "region patch peaks (20 cm^2, regions.csv), the regions carrying at least "
      << fmt("%g N", c.options.minForce) << " in the reference; error = run / reference - 1:\n";
    o << "  time       regions   mean      rms       within " << fmt("%g %%", tolPc) << "\n";
    auto line = [&](const std::string& when, const RegionPeakSummary& s) {
        char buf[160];
        if (s.regions == 0)
            std::snprintf(buf, sizeof buf, "  %-10s %7d   -         -         -\n", when.c_str(),
                          0);
        else
            std::snprintf(buf, sizeof buf, "  %-10s %7d   %+6.1f %%  %6.1f %%  %d\n", when.c_str(),
                          s.regions, 100 * s.mean, 100 * s.rms, s.within);
        o << buf;
    };
    for (const RegionPeakSummary& s : c.moments) line(fmt("%g s", s.time), s);
    line("all", c.overall);
    for (double t : c.missingTimes)
        o << "  " << fmt("%g s", t) << ": not an output time of both runs (their tilt.csv)\n";
    if (detail && !c.peaks.empty()) {
        o << "\n  time       region            reference  run        error\n";
        for (const RegionPeak& p : c.peaks) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "  %-10s %-16s %6.1f mmHg %6.1f mmHg %+6.1f %%%s\n",
                          fmt("%g s", p.time).c_str(), p.region.c_str(),
                          toUnit(p.reference, "mmHg"), toUnit(p.run, "mmHg"), 100 * p.error(),
                          std::abs(p.error()) <= c.options.peakTolerance ? "" : "  *");
            o << buf;
        }
    }
    const std::vector<std::string> why = c.whyNotJudged();
    const bool within = c.tiltRowsWithin == c.tiltRows && c.overall.within == c.overall.regions;
    o << "\n";
    if (!why.empty() && within) {
        o << "not judged: within the targets where compared, but";
        for (size_t i = 0; i < why.size(); ++i) o << (i ? "; " : " ") << why[i];
        o << "\n";
    } else {
        o << (c.meetsTargets() ? "meets" : "misses") << " the targets (tilt within "
          << fmt("%g deg", tolDeg) << " at every row, every region's peak within "
          << fmt("%g %%", tolPc) << ")";
        if (!why.empty()) {
            o << "; also";
            for (size_t i = 0; i < why.size(); ++i) o << (i ? "; " : " ") << why[i];
        }
        o << "\n";
    }
    return o.str();
}

std::string formatRegionPeaksCsv(const RunComparison& c) {
    std::ostringstream o;
    o << "time_s,region,reference_force_N,reference_patch_peak_mmHg,run_patch_peak_mmHg,"
         "error_percent,within\n";
    for (const RegionPeak& p : c.peaks) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "%.4f,%s,%.3f,%.3f,%.3f,%.2f,%d\n", p.time, p.region.c_str(),
                      p.referenceForce, toUnit(p.reference, "mmHg"), toUnit(p.run, "mmHg"),
                      100 * p.error(), std::abs(p.error()) <= c.options.peakTolerance ? 1 : 0);
        o << buf;
    }
    return o.str();
}

}  // namespace io
