#pragma once
/// @file One patient-on-array run against a reference run of the same scenario (e.g. reduced
/// bags against finite-element bags, or a coarse mesh against a fine one): the tilt at every
/// output row both runs have, and each body region's patch peak pressure (20 cm^2, regions.csv)
/// at the output times, for the regions the reference loads. The measures of
/// docs/reduced-bag.md#checking-a-run-against-a-reference (the targets for a reduced
/// bag: tilt within 2 deg, region peaks within 15 % of the finite-element run).

#include <filesystem>
#include <string>
#include <vector>

namespace io {

struct RunComparisonOptions {
    double from = 0.0;          ///< [s] rows before this time are not compared
    std::vector<double> times;  ///< [s] the region moments; empty: every common row time
    double minForce = 10.0;     ///< [N] a region is judged where the reference carries this
    double tiltTolerance = 2.0 * 3.14159265358979323846 / 180.0;  ///< [rad]
    double peakTolerance = 0.15;  ///< relative, of the reference's patch peak
};

/// The tilt of one segment over the compared rows.
struct TiltDifference {
    double largest = 0.0;      ///< [rad] run - reference, the largest in magnitude
    double largestTime = 0.0;  ///< [s]
    double rms = 0.0;          ///< [rad]
};

/// One region at one moment.
struct RegionPeak {
    double time = 0.0;  ///< [s]
    std::string region;
    double referenceForce = 0.0;  ///< [N]
    double reference = 0.0;       ///< [Pa] the reference's patch peak
    double run = 0.0;             ///< [Pa] the run's (0 if the run does not load the region)
    double error() const { return run / reference - 1.0; }
};

/// The regions judged at one moment (or over all, time NaN).
struct RegionPeakSummary {
    double time = 0.0;  ///< [s]
    int regions = 0;
    int within = 0;     ///< within the peak tolerance
    double mean = 0.0;  ///< mean relative error
    double rms = 0.0;   ///< rms relative error
};

struct RunComparison {
    std::filesystem::path reference, run;
    RunComparisonOptions options;
    int tiltRows = 0;           ///< rows both runs have, from options.from
    int tiltRowsWithin = 0;     ///< both segments within the tilt tolerance
    int tiltRowsNotFinite = 0;  ///< compared rows with a NaN or infinite tilt (not within)
    int referenceTiltRows = 0;  ///< the reference's rows from options.from
    double firstTime = 0.0, lastTime = 0.0;  ///< [s] of the compared tilt rows
    TiltDifference pelvis, thorax;
    /// The turn alone: each run's tilt less its own at the first compared row, run - reference
    /// (a symmetric man settling on a symmetric array picks a side by a degree or two that the
    /// mesh moves; this leaves that pick out). Rows both segments are within the tolerance.
    TiltDifference pelvisSinceFirst, thoraxSinceFirst;
    int tiltRowsWithinSinceFirst = 0;
    std::vector<RegionPeak> peaks;           ///< every judged region-moment, by time
    std::vector<RegionPeakSummary> moments;  ///< per moment
    RegionPeakSummary overall;               ///< over every judged region-moment
    std::vector<double> missingTimes;        ///< asked-for moments one of the runs lacks [s]
    /// The status line of a folder's INCOMPLETE marker ("" when the run finished), for the
    /// reference and the run.
    std::string referenceIncomplete, runIncomplete;
    /// Why the comparison cannot judge the whole run ("" reasons: it can): an unfinished
    /// folder, tilt rows of the reference the run lacks, rows that are not finite, asked-for
    /// moments that are not output times of both, no region judged.
    std::vector<std::string> whyNotJudged() const;
    /// Whether the comparison is whole (whyNotJudged() empty) and the run meets both
    /// tolerances at every row and region-moment.
    bool meetsTargets() const;
};

/// Reads tilt.csv and regions.csv (with patch_peak_mmHg) of both result folders and compares.
/// The moments are output times of both runs (tilt.csv rows); at a moment the run loads none
/// of a region the reference loads (no regions.csv row) that region counts as -100 %. An
/// unfinished folder's last row is left out.
/// @throws InputError naming the file, line and column of a missing or malformed file or value,
/// or a comparison with no common row.
RunComparison compareRuns(const std::filesystem::path& reference, const std::filesystem::path& run,
                          const RunComparisonOptions& options);

/// The comparison as text: the tilt's summary, the peaks per moment and overall, and with
/// `detail` every region-moment.
std::string formatRunComparison(const RunComparison& c, bool detail);

/// Every judged region-moment as CSV (time_s, region, reference_force_N,
/// reference_patch_peak_mmHg, run_patch_peak_mmHg, error_percent, within).
std::string formatRegionPeaksCsv(const RunComparison& c);

}  // namespace io
