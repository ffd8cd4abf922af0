#pragma once
/// @file The seed study's load test as a scenario file (kind: seed-load-test): reads the
/// sections airbag, membrane, gas, test, contact, solver and output into
/// bags::LoadTestOptions, converting units to SI and checking every value, so that an error
/// names the file, line and key. Every key, unit, default and valid range is listed in
/// docs/scenario-reference.md.

#include <bags/LoadTest.h>
#include <bags/SeedReading.h>
#include <diagnose/RigEffects.h>
#include <io/Scenario.h>

#include <string>
#include <vector>

namespace io {

/// What is written besides the curves.
struct OutputOptions {
    /// Save the membrane's nodal positions every this many steps (and at the first and last
    /// step of each loading and unloading branch); 0 saves no frames.
    int frameEvery = 5;
};

/// A scenario of kind seed-load-test, ready to run.
struct LoadTestScenario {
    std::string name;         ///< 'name' key, else the file name without extension
    std::string description;  ///< 'description' key (free text), may be empty
    bags::LoadTestOptions options;
    OutputOptions output;
    /// airbag.fill_mass: the gas mass that just fills the inflated bag at ambient pressure
    /// [kg]; 0 when absent (the sizes as given). When set, options.geometry holds the sizes as
    /// written, which bags::findFillScale scales before the run (docs/geometry.md).
    double fillMass = 0.0;
    /// airbag.fill_scaling: which sizes the fill mass scales.
    bags::FillScaling fillScaling = bags::FillScaling::Profile;
    /// airbag.volume_change: the bag's volume (and fill mass) relative to its sizes' reading
    /// [-], 0 when absent. Applied after the fill mass's sizing by bags::changeBagVolume (a
    /// similar bag: options.bagScale times cbrt(1 + change)); options do not hold it until
    /// then (applyBagSizing).
    double volumeChange = 0.0;
    /// Section `rig`: the test rig's effects the airbag model leaves out (instruments, rig
    /// compliance). The flowmeter's offset is already applied: options.gasMasses are the
    /// masses the bag holds, test.gas_masses minus rig.flowmeter.offset.
    diagnose::RigEffects rig;
};

/// Fixes the bag's geometry before a run: with airbag.fill_mass, sizes it (a few inflations,
/// bags::findFillScale), then applies airbag.volume_change (bags::changeBagVolume); both are
/// then cleared (fillMass and volumeChange 0), so a second call changes nothing. Returns the
/// fill mass's search (scale 1 and no measurements without a fill mass).
bags::FillScaleResult applyBagSizing(LoadTestScenario& sc);

/// Limits that keep a run within memory and time (docs/scenario-reference.md#limits); a
/// scenario beyond one is refused before anything runs, naming the key and the limit.
///
/// Largest mesh [nodes]. Measured on the seed bag (docs/performance.md): 1520 nodes (10 mm)
/// take 36 MB and 2 s per curve, 5924 nodes (5 mm) 123 MB and 34 s per curve, time growing as
/// about the square of the node count. 60 000 nodes would need about 1.5-2 GB and one to two
/// hours per curve; beyond that a run exhausts a workstation's memory or a day.
inline constexpr int kMaxMeshNodes = 60000;
/// Most gas masses (curves) in one test: a curve takes 1-12 minutes at the 10 mm mesh, so 200
/// curves are already one to two days. The seed's sweep has 11.
inline constexpr int kMaxGasMasses = 200;
/// Most block steps one branch (loading or unloading) may need at test.displacement_step over
/// the bag's height: each step is one or more equilibrium solves.
inline constexpr int kMaxStepsPerBranch = 5000;
/// peak_force may be at most this factor above the force the bag can carry
/// (estimateForceCapacity()).
inline constexpr double kPeakForceFactor = 10.0;

/// Estimated node count of makeDoubleWedgeBag(g), from the bag's surface area and the mesh
/// size (about sqrt(3)/2 h^2 of membrane per node), without meshing; within about 10 % of
/// the mesh for the seed bag from 25 mm to 2.5 mm.
double estimateNumNodes(const bags::DoubleWedgeParams& g);

/// Rough upper estimate of the block force the bag can carry [N]: the gauge pressure of the
/// largest gas mass squeezed (by the test's gas process) from the flat volume into the flat
/// volume less the block's footprint times the height, acting on the base. Infinite when the
/// block is large enough to squeeze the bag flat.
double estimateForceCapacity(const bags::LoadTestOptions& o);

/// The most gas [kg] a bag of geometry g can plausibly hold: the mass that fills its
/// unstretched (flat-panel) volume at 1 MPa gauge, ten atmospheres, far beyond what a film bag
/// survives (the seed's bag is at about 20 kPa with 4.5 g). More cannot be physical and is
/// refused where it is read (test.gas_masses, array.gas_mass).
double calcMostPlausibleGasMass(const bags::DoubleWedgeParams& g, const bags::GasOptions& gas);
/// The message for a gas mass [kg] above that, `most` [kg]: why, and what is valid.
std::string describeTooMuchGas(double mass, double most);

/// The scenario kinds `bagsim run` knows.
std::vector<std::string> getScenarioKinds();

/// The scenario's 'kind' (checked against getScenarioKinds()). @throws InputError.
std::string readScenarioKind(const ScenarioFile& file);

/// Reads a seed-load-test scenario and validates the options (LoadTestOptions::validate()
/// and the material's own checks; their std::invalid_argument becomes an InputError at the
/// key concerned) and the limits above. @throws InputError on any missing, misspelt or invalid
/// key or value, or a value beyond a limit.
LoadTestScenario readLoadTestScenario(const ScenarioFile& file);

/// Reads a compliant layer on a rigid shape, `{thickness: 15 mm, modulus: 50 kPa}` (soft tissue,
/// a pad; bags::RigidContact::Options::tissueThickness and tissueModulus), both keys required:
/// thickness in [kMinTissueThickness, kMaxTissueThickness], modulus in [kMinTissueModulus,
/// kMaxTissueModulus]. Used by the load test's `contact.block.tissue` and the patient's
/// `bag.body_tissue`. @throws InputError naming the key and what is valid.
void readTissueLayer(const ScenarioNode& s, bags::RigidContact::Options& c);
inline constexpr double kMinTissueThickness = 0.5e-3;  ///< [m]
inline constexpr double kMaxTissueThickness = 0.2;     ///< [m]
inline constexpr double kMinTissueModulus = 1e3;       ///< [Pa]
inline constexpr double kMaxTissueModulus = 100e6;     ///< [Pa]

/// Reads the film's bending stiffness D [N m] under `key` of s: a moment, `plate` or absent
/// (the homogeneous film's plate value from `material` and `thickness`,
/// bags::calcPlateBendingStiffness) or 0 (off). Used by the load test's
/// `membrane.bending_stiffness` and the patient's `bag.bending_stiffness`.
/// @throws InputError naming the key and what is valid.
double readBendingStiffness(const ScenarioNode& s, const std::string& key,
                            const bags::MembraneMaterial& material, double thickness);

/// Reads how a bag is stepped, `stepping: quasi-static | dynamic` (default `current`), and
/// refuses a `dynamic` section of settings beside a stepping that is not dynamic. Used by the
/// load test's `solver` and the patient's `bag` section. @throws InputError naming the key.
bags::AirbagSpec::Stepping readStepping(const ScenarioNode& s, bags::AirbagSpec::Stepping current);

}  // namespace io
