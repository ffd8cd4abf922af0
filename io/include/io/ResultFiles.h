#pragma once
/// @file The CSV files each kind of run writes in its folder, with their headers: one list
/// that the writers take their headers from and a study checks its outputs against before
/// any case runs (docs/output-layout.md, docs/studies.md#outputs).

#include <string>
#include <vector>

namespace io {

/// A results CSV file: its name in the run's folder and its header line (no newline).
struct ResultCsv {
    const char* file;
    const char* header;
    /// When the run writes it ("" always), for messages: "with a rig section".
    const char* when;
};

// The load test (seed-load-test).
inline constexpr const char* kLoadDisplacementHeader =
    "gas_mass_g,displacement_mm,force_N,pressure_kPa,branch";
inline constexpr const char* kStiffnessHeader =
    "gas_mass_g,stiffness_N_per_mm,k_min_N_per_mm,k_max_N_per_mm,r2,stage,end";
inline constexpr const char* kRigReadingsHeader =
    "gas_mass_g,time_s,displacement_mm,force_N,pressure_kPa,branch";
// The patient on a rigid support (patient-on-support).
inline constexpr const char* kRegionLoadsCsv = "region_loads.csv";
inline constexpr const char* kRegionLoadsHeader = "region,force_N,share_percent";
// The patient on the array (patient-on-array).
inline constexpr const char* kRegionsHeader =
    "time_s,region,ppi_mmHg,mean_mmHg,area_cm2,force_N,patch_peak_mmHg,immersion_mm,"
    "area_above_32_cm2";
inline constexpr const char* kBagsHeader =
    "time_s,bag,mass_g,pressure_kPa,volume_l,force_N,overlap_mm,inner_height_mm";
inline constexpr const char* kTiltHeader = "time_s,pelvis_tilt_deg,thorax_tilt_deg";
inline constexpr const char* kBodyHeader = "time_s,com_x_mm,com_y_mm,com_z_mm";
inline constexpr const char* kEventsHeader = "time_s,event";
inline constexpr const char* kPneumaticsHeader =
    "time_s,bag,sensor_kPa,inflow_g_per_s,outflow_g_per_s";
inline constexpr const char* kVerdictHeader = "check,status,value,unit,detail";

/// The CSV files a run of `kind` (seed-load-test, patient-on-support, patient-on-array)
/// writes; empty for another kind.
std::vector<ResultCsv> getResultCsvs(const std::string& kind);

/// The columns of a header line.
std::vector<std::string> splitResultHeader(const std::string& header);

}  // namespace io
