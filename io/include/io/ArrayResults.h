#pragma once
/// @file Writing the results of a patient-on-array run into its output folder, streamed as it
/// goes so an interrupted run keeps what it computed: regions.csv, bags.csv, tilt.csv,
/// body.csv, events.csv, pneumatics.csv, verdict.csv (at the end) and
/// results.h5 (the pressure mat's frames) with results.xdmf (the mat over time in ParaView).
/// Layout: docs/output-layout.md#patient-on-array. Units: SI in results.h5 (each dataset says
/// its unit); mmHg, cm^2, N, g, kPa, L, deg in the CSV files, as their column names say.
///
/// Order: OutputDir (claims the folder, writes the INCOMPLETE marker), ArrayResultsWriter on
/// it, addFrame() at every output time, then finish() (status "complete", marker removed; or
/// "partial", marker kept) or fail() (status "failed" or "interrupted", marker kept).

#include <bags/StateStream.h>
#include <cosim/ArrayReadings.h>
#include <cosim/ArrayShapes.h>
#include <io/ResultFiles.h>
#include <io/Results.h>

#include <memory>
#include <string>
#include <vector>

namespace io {

inline constexpr const char* kRegionsCsv = "regions.csv";
inline constexpr const char* kBagsCsv = "bags.csv";
inline constexpr const char* kTiltCsv = "tilt.csv";
inline constexpr const char* kBodyCsv = "body.csv";
inline constexpr const char* kEventsCsv = "events.csv";
inline constexpr const char* kPneumaticsCsv = "pneumatics.csv";
inline constexpr const char* kVerdictCsv = "verdict.csv";
// The headers: io/ResultFiles.h (docs/output-layout.md#patient-on-array).

/// One bag's pneumatics at an output time (pneumatics.csv).
struct PneumaticsReading {
    int bag = 0;           ///< ArrayBag index
    double sensor = 0.0;   ///< [Pa] gauge, the bag's sensor reading
    double inflow = 0.0;   ///< [kg/s] into the bag over the last step
    double outflow = 0.0;  ///< [kg/s] out of the bag over the last step
};

/// One check of the support verdict (verdict.csv).
struct VerdictRow {
    std::string check;   ///< e.g. "target tilt reached"
    std::string status;  ///< ok, warning, fail or n/a
    double value = 0.0;  ///< in `unit` (NaN: none)
    std::string unit;
    std::string detail;
};

/// One output time of the run.
struct ArrayFrame {
    double time = 0.0;                          ///< [s] since the release
    std::vector<cosim::RegionLoad> regions;     ///< every region (rows with no load are skipped)
    std::vector<cosim::BagReading> bags;        ///< every coupled bag
    double pelvisTilt = 0.0, thoraxTilt = 0.0;  ///< [rad] cosim::calcSegmentTilt()
    const cosim::PressureMat* mat = nullptr;    ///< filled for this time (optional)
    Eigen::Vector3d centreOfMass = Eigen::Vector3d::Zero();  ///< [m] the patient's, Ground
    std::vector<PneumaticsReading> pneumatics;  ///< every bag in the network (none: no rows)
    /// With setShapes(), at the times wantsShapes() says: the node positions [m], Ground, of
    /// the bags' and the body's meshes (cosim::calcBagSurfacePositions(),
    /// cosim::calcBodySurfacePositions()).
    const Eigen::Matrix3Xd* bagNodes = nullptr;
    const Eigen::Matrix3Xd* bodyNodes = nullptr;
};

class ArrayResultsWriter {
  public:
    /// Creates results.h5 (status "running") and the CSV files with their headers.
    /// @throws std::runtime_error on I/O failure.
    ArrayResultsWriter(const OutputDir& dir, const RunInfo& info,
                       const cosim::PressureMatOptions& mat);
    /// A resumed run: opens the files a run wrote into `dir` and cuts each back to where
    /// saveState() found it (CSV files to their byte length then, results.h5's datasets to
    /// their rows then, the shapes saved after it removed); further frames are appended.
    /// @throws bags::StateError if the checkpoint does not fit, std::runtime_error on I/O.
    ArrayResultsWriter(const OutputDir& dir, const cosim::PressureMatOptions& mat,
                       bags::StateReader& r);
    ~ArrayResultsWriter();
    ArrayResultsWriter(const ArrayResultsWriter&) = delete;
    ArrayResultsWriter& operator=(const ArrayResultsWriter&) = delete;

    /// Saves the bags' and the body's meshes in results.h5 (/shapes) and shows them beside the
    /// mat in results.xdmf: node positions at the first output, every `interval` [s] and at
    /// `end` [s], stored as float32 (0.1 um at 2 m). Call before the first addFrame().
    void setShapes(const cosim::SurfaceMesh& bags, const cosim::SurfaceMesh& body, double interval,
                   double end);
    /// True if the frame at `time` [s] should carry the shapes' node positions.
    bool wantsShapes(double time) const;
    /// Appends one output time to every file (flushing them at most every few seconds).
    void addFrame(const ArrayFrame& frame);
    /// Appends a row to events.csv: what happened at `time` [s] (a controller's change).
    void addEvent(double time, const std::string& event);
    /// Writes verdict.csv (replacing one written before) and returns its text as a table.
    std::string writeVerdict(const std::vector<VerdictRow>& rows);
    /// Status "complete": closes the files, writes results.xdmf and removes the marker. With
    /// a `partial` reason (the run reached its end, but something in it did not hold, e.g.
    /// bag steps kept unrelaxed), status "partial": the marker is kept and says why.
    void finish(const std::string& message, const std::string& partial = {});
    /// Saves what was written, sets the status ("failed", "interrupted") and the message,
    /// closes the files and keeps the INCOMPLETE marker. Never throws.
    void fail(const std::string& status, const std::string& message) noexcept;
    int getNumFrames() const;  ///< output times written
    /// Flushes every file and writes where each stands into a checkpoint (for the resuming
    /// constructor).
    void saveState(bags::StateWriter& w);

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace io
