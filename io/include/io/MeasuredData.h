#pragma once
/// @file Measured data of the seed's rig as a folder (docs/measured-data.md): a manifest
/// measured.yaml (the scenario it corresponds to, the protocol, one entry per test naming its
/// channel files) and CSV channels as lab equipment writes them (testing machine
/// time/displacement/force, pressure sensor time/pressure, flowmeter time/mass), each column's
/// unit in its header.
///
/// Order: readMeasuredData(folder), then readMeasuredScenario(data) for the scenario with the
/// protocol applied, ready to simulate. writeMeasuredData() writes the format (synthetic data).
/// Every problem is one io::InputError naming the file, the line (for a CSV: the row's line),
/// the key or column, and what would be valid.

#include <diagnose/MeasuredData.h>
#include <io/LoadTestScenario.h>

#include <string>
#include <vector>

namespace io {

/// The manifest's file name in a measured-data folder.
inline constexpr const char* kMeasuredManifest = "measured.yaml";
/// The manifest's `format` value this reader knows.
inline constexpr const char* kMeasuredFormat = "bagsim-measured-data 1";
/// Largest channel file read [bytes], 16 MiB: a machine file logged at 100 Hz for an hour
/// (time, displacement, force) is about 10 MiB; the rig's tests take minutes.
inline constexpr std::uintmax_t kMaxChannelBytes = 16ull * 1024 * 1024;
/// How far the flowmeter's mean reading of a test may be from the manifest's gas mass:
/// the larger of 0.05 g and 2 % (a flowmeter's stated accuracy is about 1 %).
inline constexpr double kFlowmeterAbsTolerance = 0.05e-3;  ///< [kg]
inline constexpr double kFlowmeterRelTolerance = 0.02;
/// How far a test's largest force may be from the protocol's peak force (fraction).
inline constexpr double kPeakForceTolerance = 0.10;
/// Largest stated standard uncertainty of a test's gas mass, as a share of the mass: the
/// diagnosis simulates the test at the mass plus and minus it and takes the response as linear
/// in between (a flowmeter's stated accuracy is about 1 %; ten times that is no longer a
/// reading the test was run at).
inline constexpr double kMaxGasMassUncertaintyShare = 0.10;
/// Largest stated standard uncertainty of the room temperature [K]: 10 K is 3.4 % of the gas's
/// m T at 23 degC, the share above for the gas mass (the gas-temperature candidate reaches 15 K).
inline constexpr double kMaxRoomTemperatureUncertainty = 10.0;

/// One column a channel file must have: its name and its kind of unit.
struct ChannelColumn {
    std::string name;       ///< "time", "displacement", "force", "pressure", "mass"
    Dimension dimension;    ///< Dimensionless: a plain number, written without a unit
    bool optional = false;  ///< a missing column is returned empty instead of refused
};

/// Reads one CSV channel file: '#' comment lines and blank lines are skipped; the first other
/// line is the header, each column named `name_unit`, `name [unit]` or `name (unit)`
/// (e.g. time_s, "force [N]"); columns not asked for are ignored; then one row per sample.
/// Returns the wanted columns in SI, in the order asked. Checks: each wanted column present
/// once with a unit of its kind; every cell of a wanted column a finite number; the first
/// column (time) strictly increasing; at least two rows.
/// @param shownName the file as named in messages
/// @throws InputError naming the file, the line, the column and what would be valid.
std::vector<std::vector<double>> readChannelCsv(const std::string& path,
                                                const std::string& shownName,
                                                const std::vector<ChannelColumn>& columns);

/// Reads a measured-data folder: its tests, and the stiffness curve k(m) when the manifest
/// names one (`stiffness`: columns gas_mass, stiffness and an optional stage; either may be
/// given alone); a test's optional `bed` channel (time, sink: the bed gauge) must be given for
/// every test or none. @throws InputError (missing manifest, key, channel file or
/// column; bad units; NaN; unsorted time; a flowmeter reading or a peak force that disagrees
/// with the manifest).
diagnose::MeasuredData readMeasuredData(const std::string& folder);

/// The scenario the data correspond to, with the protocol applied to it (its gas masses: the
/// tests', or without tests the stiffness curve's from the largest down; its block,
/// rate, peak force and room temperature replace the scenario's), read and checked as
/// `bagsim run` would. @throws InputError at the manifest's key when the scenario cannot run
/// the protocol (saying why), or for the scenario's own errors.
LoadTestScenario readMeasuredScenario(const diagnose::MeasuredData& data);
/// The same scenario as a file (its text and the protocol as overrides), e.g. to run variants.
ScenarioFile loadMeasuredScenarioFile(const diagnose::MeasuredData& data);

/// Writes a measured-data folder (which must exist): measured.yaml, scenario.yaml (the
/// scenario text given) and per test test<N>-machine.csv, test<N>-pressure.csv,
/// test<N>-flowmeter.csv and, when the test has the bed gauge's channel, test<N>-bed.csv. `comment` goes at the top of the manifest. Returns the file names.
std::vector<std::string> writeMeasuredData(const std::string& folder,
                                           const diagnose::MeasuredData& data,
                                           const std::string& scenarioText,
                                           const std::string& comment);

/// The instruments' readings of a load test's curves with the rig's effects
/// (docs/output-layout.md#rig_readingscsv): a header
/// gas_mass_g,time_s,displacement_mm,force_N,pressure_kPa,branch and one row per step, the
/// displacement as the crosshead travels, the pressure as the sensor reads it.
std::string formatRigReadingsCsv(const bags::LoadTestResult& result,
                                 const diagnose::RigEffects& rig, double rate);

}  // namespace io
