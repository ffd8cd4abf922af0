#pragma once
/// @file Writing the results of a patient-on-array run into its output folder, streamed as it
/// goes so an interrupted run keeps what it computed: regions.csv, bags.csv, tilt.csv and
/// results.h5 (the pressure mat's frames) with results.xdmf (the mat over time in ParaView).
/// Layout: docs/output-layout.md#patient-on-array. Units: SI in results.h5 (each dataset says
/// its unit); mmHg, cm^2, N, g, kPa, L, deg in the CSV files, as their column names say.
///
/// Order: OutputDir (claims the folder, writes the INCOMPLETE marker), ArrayResultsWriter on
/// it, addFrame() at every output time, then finish() (status "complete", marker removed) or
/// fail() (status "failed" or "interrupted", marker kept).

#include <cosim/ArrayReadings.h>
#include <io/Results.h>

#include <memory>
#include <string>
#include <vector>

namespace io {

inline constexpr const char* kRegionsCsv = "regions.csv";
inline constexpr const char* kBagsCsv = "bags.csv";
inline constexpr const char* kTiltCsv = "tilt.csv";

/// One output time of the run.
struct ArrayFrame {
    double time = 0.0;                        ///< [s] since the release
    std::vector<cosim::RegionLoad> regions;   ///< every region (rows with no load are skipped)
    std::vector<cosim::BagReading> bags;      ///< every coupled bag
    double pelvisTilt = 0.0, thoraxTilt = 0.0;  ///< [rad] cosim::calcSegmentTilt()
    const cosim::PressureMat* mat = nullptr;  ///< filled for this time (optional)
};

class ArrayResultsWriter {
  public:
    /// Creates results.h5 (status "running") and the CSV files with their headers.
    /// @throws std::runtime_error on I/O failure.
    ArrayResultsWriter(const OutputDir& dir, const RunInfo& info,
                       const cosim::PressureMatOptions& mat);
    ~ArrayResultsWriter();
    ArrayResultsWriter(const ArrayResultsWriter&) = delete;
    ArrayResultsWriter& operator=(const ArrayResultsWriter&) = delete;

    /// Appends one output time to every file (flushing them at most every few seconds).
    void addFrame(const ArrayFrame& frame);
    /// Status "complete": closes the files, writes results.xdmf and removes the marker.
    void finish(const std::string& message);
    /// Saves what was written, sets the status ("failed", "interrupted") and the message,
    /// closes the files and keeps the INCOMPLETE marker. Never throws.
    void fail(const std::string& status, const std::string& message) noexcept;
    int getNumFrames() const;  ///< output times written

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace io
