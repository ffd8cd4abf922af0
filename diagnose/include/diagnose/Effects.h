#pragma once
/// @file The library of candidate unmodelled effects of the seed's rig (docs/diagnosis.md):
/// each a real extension of the model that a scenario can also switch on (the key named per
/// parameter), with physical bounds. `bagsim synth-measurement` switches one on in its truth
/// run; `bagsim diagnose` calibrates each against measured data.

#include <diagnose/RigEffects.h>

#include <bags/LoadTest.h>

#include <string>
#include <vector>

namespace diagnose {

struct EffectParameter {
    std::string name;        ///< as given to --param ("lag")
    std::string unit;        ///< the unit it is shown and given in ("s")
    double siPerUnit = 1.0;  ///< SI value of one unit
    double lower = 0.0;      ///< physical bounds [SI]
    double upper = 0.0;
    double typical = 0.0;     ///< default magnitude for a synthetic check [SI]
    std::string scenarioKey;  ///< the scenario key that switches it on
};

struct Effect {
    std::string name;         ///< "pressure-sensor"
    std::string description;  ///< one line
    std::vector<EffectParameter> parameters;
    /// True when the effect changes the bag's response (a new simulation per trial value);
    /// false when it changes only what the instruments read.
    bool changesTheBag = false;
    /// False for effects kept out of the candidate library on purpose (an effect the
    /// diagnosis does not know, for the withheld-effect checks); --candidates may name them.
    bool inLibrary = true;
    /// The measurement that isolates this effect from the others (what a verdict that cannot
    /// tell it from a rival advises to measure): "a gauge under the bed board".
    std::string isolatedBy;
};

/// Upper bound of the heat exchange's time constant as a candidate [s]: beyond about three
/// times the rig's loading time the gas is adiabatic over the test (GasOptions accepts up to
/// an hour).
inline constexpr double kMaxHeatExchangeTimeConstant = 300.0;

/// Bounds of the film's viscoelasticity as a candidate (one Prony term): its relative modulus
/// g up to 0.5 (a coated fabric that loses half its stress when held), its relaxation time
/// from 1 s (about twice the instruments' sample interval: faster, the film is relaxed at every
/// sample) to 120 s (longer than a tiny-rig test's press and release, 38-106 s: slower, the term
/// acts more and more as a stiffer elastic film over the test).
inline constexpr double kMaxViscoelasticModulus = 0.5;
inline constexpr double kMinViscoelasticTime = 1.0;    ///< [s]
inline constexpr double kMaxViscoelasticTime = 120.0;  ///< [s]

/// Upper bound of the fabric's yarn stiffness as a candidate, as a multiple of the film law's
/// small-strain Young's modulus 3 mu (docs/diagnosis.md#fabric-anisotropy): 3, a strip cut
/// along a yarn 4 times as stiff as the isotropic law and about 3.4 times as stiff as one cut
/// on the bias. A judgement, not a measurement of this fabric: uncoated weaves reach larger
/// ratios (their bias is held only by the yarns' friction), a coating that locks the yarns
/// lowers them; beyond, the scenario's isotropic law would no longer be the film's matrix.
inline constexpr double kMaxYarnStiffnessRatio = 3.0;

/// Bounds of the soft-tissue candidate (docs/diagnosis.md#soft-tissue). Soft tissue over bone
/// is 5-40 mm thick (over the sacrum and heels a few mm to 15 mm, over the buttocks and the
/// back's muscles up to about 40 mm) with an effective compressive modulus of 10-200 kPa
/// (indentation of skin, fat and muscle in vivo: relaxed fat and muscle near 10-30 kPa, loaded
/// and tensed tissue up to 100-200 kPa); the same range covers a foam or rubber pad on an
/// indenter. The thickness's bound starts at 0, no layer (bone, a bare indenter: the model as
/// it is), so that the candidate contains the model: as the thickness falls to 0 at any modulus
/// the layer's compression falls to 0 with it. Without it the thinnest, stiffest layer (200 kPa
/// over 5 mm, 4e7 Pa/m in series with the penalty's 1e7 Pa/m) is still far from none on a taut
/// bag at 20 kPa, and the candidate could not return to the model on data without a layer.
inline constexpr double kMinTissueThickness = 0.0;    ///< [m]
inline constexpr double kMaxTissueThickness = 40e-3;  ///< [m]
inline constexpr double kMinTissueModulus = 10e3;     ///< [Pa]
inline constexpr double kMaxTissueModulus = 200e3;    ///< [Pa]

/// Bound of the film-stiffness candidate, the relative change of the film's membrane stiffness
/// (thickness times modulus, docs/diagnosis.md#film-stiffness): 40 % either way. A coated
/// fabric's thickness is held to a tolerance of the order of 10 %, and a law fitted to one
/// batch's tensile test may misstate another batch's modulus by tens of percent (a judgement,
/// not a measurement of this film); beyond 40 % the film is another film, not a misstatement.
inline constexpr double kMaxFilmStiffnessChange = 0.4;

/// The effects, in a fixed order: pressure-sensor, flowmeter-bias, gas-temperature,
/// machine-compliance, block-friction, leakage, heat-exchange, bed-compliance,
/// viscoelasticity, fabric-anisotropy, soft-tissue, bag-volume, film-stiffness (the library),
/// load-cell-gain (kept out of it).
const std::vector<Effect>& getEffects();
/// The effect of that name in a library (this one, or the patient's: PatientDiagnosis.h), or
/// nullptr; and the library's names joined by ", ".
const Effect* findEffectIn(const std::vector<Effect>& library, const std::string& name);
std::string listEffectNamesIn(const std::vector<Effect>& library);
/// The effect of that name, or nullptr.
const Effect* findEffect(const std::string& name);
/// "pressure-sensor, flowmeter-bias, ..." (for messages): all effects.
std::string listEffectNames();

/// Switches the effect on with these parameter values [SI] (one per parameter, in order):
/// rig effects go into `rig`; effects on the bag into `options` (for the flowmeter's bias,
/// options.gasMasses become `readings` less the offset; for the gas temperature,
/// options.gas.temperature is raised by its offset; leakage and heat exchange set
/// options.gas.leakConductance and .heatTimeConstant; bed-compliance rig.bedCompliance;
/// viscoelasticity options.prony, one term; fabric-anisotropy wraps options.material in a
/// bags::FabricMaterial whose warp and weft moduli are both the ratio times 3 mu, angle 0;
/// soft-tissue sets options.blockContact.tissueThickness and .tissueModulus, both 0 for a
/// thickness of 0; film-stiffness multiplies options.thickness by 1 + change and divides
/// options.density by it (the sheet's weight, and its bending stiffness, stay as stated); bag-volume scales the bag, options.bagScale, by bags::changeBagVolume: on
/// the bag as sized, a fill mass's sizing done first, as bagsim's commands do).
/// @throws std::invalid_argument for a value outside the bounds, naming it.
void applyEffect(const Effect& effect, const std::vector<double>& values,
                 const std::vector<double>& readings, RigEffects& rig,
                 bags::LoadTestOptions& options);

}  // namespace diagnose
