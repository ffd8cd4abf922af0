#pragma once
/// @file Writing a run's results into its output folder, streamed as the run goes so that an
/// interrupted run keeps what it computed: results.h5 (HDF5, layout in docs/output-layout.md),
/// results.xdmf (opens the deforming membrane in ParaView), load_displacement.csv and
/// stiffness.csv. Units: SI in results.h5 (each dataset says its unit); mm, N, kPa, g in the
/// CSV files, as their column names say.
///
/// Order: OutputDir (claims the folder, writes the INCOMPLETE marker), LoadTestWriter on it,
/// addStep() from the load test's observer after every converged step, then either finish()
/// with the result (status "complete", marker removed; or "partial", marker kept, when a curve
/// stopped on a numerical failure) or fail() (status "failed" or "interrupted", marker kept).
///
/// Statuses (results.h5 /meta status, and the INCOMPLETE marker's "status:" line):
///   running      the run is writing (or was killed without a word: the marker stays)
///   complete     every curve ended at its peak force or bottomed out; no marker
///   partial      every gas mass was run but at least one curve stopped on a numerical
///                failure (isCurveFailed()); everything is written, the marker says which
///   failed       the run stopped on an error before its end; what was computed is kept
///   interrupted  stopped by SIGINT (Ctrl-C) or SIGTERM; what was computed is kept

#include <bags/LoadTest.h>

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace io {

/// An output folder claimed by one run. While the run writes, the folder holds a marker file
/// INCOMPLETE saying so (and, after a failure, why); only a finished run removes it.
class OutputDir {
  public:
    static constexpr const char* kMarkerName = "INCOMPLETE";  ///< marker file name

    /// Creates the folder (and its parents) and the marker.
    /// @throws InputError if the folder exists and is not empty, unless `force` (then files in
    ///   it are overwritten where the run writes them, others are left alone), or if it cannot
    ///   be created.
    OutputDir(const std::filesystem::path& path, bool force);
    /// The folder of an interrupted run, to resume it: nothing in it is removed or written
    /// (the marker keeps the stopped run's status until markResumed(), so that a resume
    /// refused on its checks leaves the folder as it was). @throws InputError if it is not a
    /// folder.
    static OutputDir resume(const std::filesystem::path& path);
    /// The marker says the run is running again (once the resume is accepted).
    void markResumed() const;
    /// The marker's text as it stands ("" without one).
    std::string readMarker() const;
    /// Writes `text` as the marker, verbatim (a refused resume puts the stopped run's back).
    void writeMarker(const std::string& text) const;

    const std::filesystem::path& getPath() const { return m_path; }  ///< the folder
    /// Path of a file in the folder.
    std::filesystem::path getFile(const std::string& name) const { return m_path / name; }
    /// Rewrites the marker with a status ("running", "partial", "failed", "interrupted") and a
    /// detail line.
    void setStatus(const std::string& status, const std::string& detail) const;
    /// Removes the marker: the folder's contents are complete.
    void markComplete() const;
    /// True while the marker exists.
    bool isIncomplete() const;

  private:
    OutputDir() = default;
    std::filesystem::path m_path;
};

/// The checkpoint a patient-on-array run keeps in its output folder (docs/output-layout.md).
inline constexpr const char* kCheckpointFile = "checkpoint.bin";
/// The state at the end of a patient-on-array run's settle (docs/output-layout.md#rest-state),
/// from which `bagsim run --from-rest DIR` starts another run of the same patient and array.
inline constexpr const char* kRestStateFile = "rest-state.bin";

/// True if a curve stopped on a numerical failure (LoadCurve::failure says "no convergence
/// ..."), a dynamic test's curve was not quasi-static (its film's kinetic energy over the
/// limit of the block's work), or the curve left the model's envelope (the block force fell
/// while the block pressed deeper: LoadCurve::outsideEnvelope): the run's status is then
/// "partial". A curve that bottomed out
/// (the block reached its stop 2 mm above the bed board before the peak force) ended on a
/// physical outcome and is not a failure.
bool isCurveFailed(const bags::LoadCurve& curve);

/// How a curve ended, as written in stiffness.csv's column "end": "outside-envelope" (the
/// block force fell while the block pressed deeper), "not-quasi-static" (a dynamic test's
/// curve over its kinetic-energy limit), "failed" (isCurveFailed()), "peak"
/// (reached the peak force), "bottomed-out" or "stopped" (any other early end).
std::string getCurveEnd(const bags::LoadCurve& curve);

/// Where a run came from, stored in results.h5 /meta.
struct RunInfo {
    std::string scenarioFile;            ///< path as given
    std::string scenarioText;            ///< file text verbatim
    std::vector<std::string> overrides;  ///< --set key=value, in order
    std::string commandLine;             ///< the program's arguments, for the record
};

/// The record of where a run came from in the results.h5 of folder `dir` (/meta scenario,
/// scenario_file, overrides, command_line): a run's identity, against which a checkpoint found
/// in the folder is checked. @throws std::runtime_error if there is none or it cannot be read.
RunInfo readRunInfo(const std::string& dir);

/// Streams a load test (bags::runLoadTest) into results.h5, results.xdmf and the CSV files.
class LoadTestWriter {
  public:
    struct Options {
        /// Save node positions every this many steps, plus the first and last step of each
        /// loading and unloading branch; 0: no frames.
        int frameEvery = 5;
        /// Flush results.h5 and refresh results.xdmf at least this often [s] (and after each
        /// curve).
        double flushInterval = 10.0;
    };

    /// Creates results.h5 (status "running") and load_displacement.csv in `dir`.
    /// `test` gives the gas masses of the curves. @throws std::runtime_error on I/O failure.
    LoadTestWriter(const OutputDir& dir, const RunInfo& info, const bags::LoadTestOptions& test,
                   const Options& options);
    ~LoadTestWriter();
    LoadTestWriter(const LoadTestWriter&) = delete;
    LoadTestWriter& operator=(const LoadTestWriter&) = delete;

    /// Records one converged step (the load test's observer). The first call writes the mesh.
    void addStep(const bags::LoadStep& step, const bags::Mesh& mesh, const Eigen::Matrix3Xd& x);
    /// Writes the per-curve results, the stiffness table and the k(m) fits and closes the
    /// files. Status "complete" (the INCOMPLETE marker removed) if no curve failed, else
    /// "partial" (the marker kept, naming the failed curves). Returns the status.
    std::string finish(const bags::LoadTestResult& result);
    /// Saves what was computed, sets the status (e.g. "failed", "interrupted") and the
    /// message, closes the files and keeps the INCOMPLETE marker. Never throws.
    void fail(const std::string& status, const std::string& message) noexcept;

    int getNumFrames() const;  ///< frames saved so far
    int getNumSteps() const;   ///< steps recorded so far

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// Names of the files a load test writes (for messages and tests).
inline constexpr const char* kResultsH5 = "results.h5";
inline constexpr const char* kResultsXdmf = "results.xdmf";
inline constexpr const char* kLoadDisplacementCsv = "load_displacement.csv";
inline constexpr const char* kStiffnessCsv = "stiffness.csv";
/// The instruments' readings of the curves, written when the scenario has a `rig` section.
inline constexpr const char* kRigReadingsCsv = "rig_readings.csv";
/// The bag's k(m) for the controllers (`control.k_of_m` of a patient-on-array scenario) and its
/// inverse, the gas mass for a wanted stiffness: written when at least two curves form a branch.
inline constexpr const char* kKOfMYaml = "k_of_m.yaml";

/// The rows of the load test's k(m) that a controller can invert: the taut branch, from the
/// highest gas mass down while the stiffness strictly falls, over curves that reached their
/// peak with a finite stiffness, in increasing mass ([kg], [N/m]). Empty if fewer than two.
std::vector<std::pair<double, double>> findInvertibleKOfM(const bags::LoadTestResult& result);

/// Current UTC time as ISO 8601 ("2026-11-22T05:43:49Z").
std::string getUtcTimestamp();

}  // namespace io
