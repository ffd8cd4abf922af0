#include <diagnose/Effects.h>

#include <bags/Material.h>
#include <bags/SeedReading.h>

#include <memory>
#include <sstream>
#include <stdexcept>

namespace diagnose {

const std::vector<Effect>& getEffects() {
    static const std::vector<Effect> effects = {
        {"pressure-sensor",
         "the pressure sensor lags (first order: tubing, filter) and reads with a zero offset",
         {{"lag", "s", 1.0, 0.0, RigEffects::kMaxPressureLag, 3.0, "rig.pressure_sensor.lag"},
          {"offset", "kPa", 1e3, -RigEffects::kMaxPressureOffset, RigEffects::kMaxPressureOffset,
           100.0, "rig.pressure_sensor.offset"}},
         false,
         true,
         "a reference gauge on the bag's own port read beside the sensor (its zero, and its lag "
         "at a step of pressure)"},
        {"flowmeter-bias",
         "the flowmeter reads the bag's gas mass plus an offset (the bag holds another mass)",
         {{"offset", "g", 1e-3, -RigEffects::kMaxFlowmeterOffset, RigEffects::kMaxFlowmeterOffset,
           0.1e-3, "rig.flowmeter.offset"}},
         true,
         true,
         "the bag weighed full and empty (the gas mass it holds), or the flowmeter checked "
         "against a reference"},
        {"gas-temperature",
         "the gas is warmer or colder than the room the protocol states (pump, lights, sun)",
         {{"offset", "K", 1.0, -15.0, 15.0, 5.0,
           "gas.temperature (the room temperature plus this)"}},
         true,
         true,
         "a thermometer in the bag's gas during the test"},
        {"machine-compliance",
         "the testing machine (frame, crosshead, load cell) yields in series with the block",
         {{"compliance", "mm/N", 1e-3, 0.0, RigEffects::kMaxMachineCompliance, 0.1e-3,
           "rig.machine_stiffness (its inverse)"}},
         false,
         true,
         "the block's travel read by a gauge on the block itself, beside the crosshead's"},
        {"block-friction",
         "Coulomb friction between the film and the block",
         {{"friction", "", 1.0, 0.0, 1.0, 0.5, "contact.block.friction"}},
         true,
         true,
         "a test with a lubricated (PTFE-faced) block"},
        {"leakage",
         "gas leaks through seams and valves during the test (laminar: mass flow out in "
         "proportion to the gauge pressure)",
         {{"conductance", "mg/(s kPa)", 1e-9, 0.0, bags::GasOptions::kMaxLeakConductance, 0.05e-9,
           "gas.leak_conductance"}},
         true,
         true,
         "a hold at a fixed displacement: the pressure falls with the leak and does not come back"},
        {"heat-exchange",
         "the gas compresses adiabatically and exchanges heat with the room through the film "
         "(Newton cooling with a time constant)",
         {{"time_constant", "s", 1.0, 0.0, kMaxHeatExchangeTimeConstant, 20.0,
           "gas.heat_time_constant"}},
         true,
         true,
         "a hold at a fixed displacement: the pressure relaxes to the isothermal one while the "
         "gas mass stays"},
        {"bed-compliance",
         "the bed board under the bag sinks on a spring (confusable with the machine's "
         "compliance on the rig's data, unless a gauge under the board reads its sink)",
         {{"compliance", "mm/N", 1e-3, 0.0, RigEffects::kMaxBedCompliance, 0.1e-3,
           "rig.bed_stiffness (its inverse)"}},
         false,
         true,
         "a gauge under the bed board (synth-measurement --bed-gauge)"},
        {"viscoelasticity",
         "the film relaxes (one Prony term on its stress): stiffer while pressed, softer while "
         "released, a loop that depends on the rate",
         {{"g", "", 1.0, 0.0, kMaxViscoelasticModulus, 0.2, "membrane.prony[0].g"},
          {"tau", "s", 1.0, kMinViscoelasticTime, kMaxViscoelasticTime, 20.0,
           "membrane.prony[0].tau"}},
         true,
         true,
         "tests at two rates, or a hold at a fixed displacement: the force relaxes while the "
         "gas does not"},
        {"fabric-anisotropy",
         "the film is a woven fabric: yarns along the warp and the weft (the bag's long side and "
         "across it) stiffen it along themselves and carry no compression",
         {{"yarn", "", 1.0, 0.0, kMaxYarnStiffnessRatio, 1.0,
           "membrane.anisotropy.warp and .weft (each this times the film's Young's modulus "
           "3 mu)"}},
         true,
         true,
         "tensile strips of the film cut along the yarns and on the bias"},
        {"soft-tissue",
         "a compliant layer between the block and the film (soft tissue over bone, a pad on the "
         "indenter): a Winkler layer that stiffens as it bottoms out, in series with the contact",
         // The default is a stiff layer (a rubber pad, tensed tissue: 2e7 Pa/m): softer ones
         // need a finer mesh than the tiny rig's 25 mm (docs/contact.md#contact-law).
         {{"thickness", "mm", 1e-3, kMinTissueThickness, kMaxTissueThickness, 10e-3,
           "contact.block.tissue.thickness"},
          {"modulus", "kPa", 1e3, kMinTissueModulus, kMaxTissueModulus, 200e3,
           "contact.block.tissue.modulus"}},
         true,
         true,
         "the block pressed bare, or a gauge on the block's face (the layer's compression)"},
        {"bag-volume",
         "the bag's volume (its fill mass) differs from the scenario's reading of it: a "
         "geometrically similar bag, every size times the cube root of 1 + volume",
         {{"volume", "", 1.0, -bags::kMaxVolumeChange, bags::kMaxVolumeChange, 0.05,
           "airbag.volume_change"}},
         true,
         true,
         "the bag's sizes or its volume measured (water displacement)"},
        {"film-stiffness",
         "the film is stiffer or softer than the scenario states (its thickness or its modulus "
         "misstated): every membrane stress times 1 + change; its weight and bending as stated",
         {{"change", "", 1.0, -kMaxFilmStiffnessChange, kMaxFilmStiffnessChange, 0.1,
           "membrane.thickness (the stated one times 1 + this)"}},
         true,
         true,
         "a tensile test of a strip of the bag's own film and its thickness measured (bagsim "
         "fit-material)"},
        {"load-cell-gain",
         "the load cell reads the force times 1 + gain (a calibration error)",
         {{"gain", "", 1.0, -RigEffects::kMaxLoadCellGain, RigEffects::kMaxLoadCellGain, 0.05,
           "rig.load_cell_gain"}},
         false,
         false,
         "the load cell checked with a dead weight"},
    };
    return effects;
}

const Effect* findEffectIn(const std::vector<Effect>& library, const std::string& name) {
    for (const Effect& e : library)
        if (e.name == name) return &e;
    return nullptr;
}

std::string listEffectNamesIn(const std::vector<Effect>& library) {
    std::string s;
    for (const Effect& e : library) s += (s.empty() ? "" : ", ") + e.name;
    return s;
}

const Effect* findEffect(const std::string& name) { return findEffectIn(getEffects(), name); }

std::string listEffectNames() { return listEffectNamesIn(getEffects()); }

void applyEffect(const Effect& effect, const std::vector<double>& values,
                 const std::vector<double>& readings, RigEffects& rig,
                 bags::LoadTestOptions& options) {
    if (values.size() != effect.parameters.size())
        throw std::invalid_argument("effect '" + effect.name + "' takes " +
                                    std::to_string(effect.parameters.size()) + " parameter(s)");
    for (size_t i = 0; i < values.size(); ++i) {
        const EffectParameter& p = effect.parameters[i];
        if (!(values[i] >= p.lower && values[i] <= p.upper)) {
            std::ostringstream s;
            s << "effect '" << effect.name << "' parameter '" << p.name
              << "' = " << values[i] / p.siPerUnit << (p.unit.empty() ? "" : " ") << p.unit
              << " is outside its physical bounds; valid: " << p.lower / p.siPerUnit << " to "
              << p.upper / p.siPerUnit << (p.unit.empty() ? "" : " ") << p.unit;
            throw std::invalid_argument(s.str());
        }
    }
    if (effect.name == "pressure-sensor") {
        rig.pressureLag = values[0];
        rig.pressureOffset = values[1];
    } else if (effect.name == "flowmeter-bias") {
        rig.flowmeterOffset = values[0];
        options.gasMasses = calcBagGasMasses(readings, rig);
    } else if (effect.name == "gas-temperature") {
        options.gas.temperature += values[0];
    } else if (effect.name == "load-cell-gain") {
        rig.loadCellGain = values[0];
    } else if (effect.name == "machine-compliance") {
        rig.machineCompliance = values[0];
    } else if (effect.name == "leakage") {
        options.gas.leakConductance = values[0];
    } else if (effect.name == "heat-exchange") {
        options.gas.heatTimeConstant = values[0];
    } else if (effect.name == "bed-compliance") {
        rig.bedCompliance = values[0];
    } else if (effect.name == "viscoelasticity") {
        options.prony.terms = {{values[0], values[1]}};
    } else if (effect.name == "fabric-anisotropy") {
        // A balanced weave (840D nylon both ways): the same yarn stiffness along warp and weft.
        if (!options.material)
            throw std::invalid_argument(
                "effect 'fabric-anisotropy' needs the film's material "
                "(load test option 'material' is not set)");
        const auto* fabric = dynamic_cast<const bags::FabricMaterial*>(options.material.get());
        const bags::MembraneMaterial& matrix = fabric ? fabric->getMatrix() : *options.material;
        bags::FabricAnisotropy yarns;
        yarns.warpModulus = yarns.weftModulus = values[0] * 3.0 * matrix.getInitialShearModulus();
        if (yarns.isOn())
            options.material = std::make_shared<bags::FabricMaterial>(matrix.clone(), yarns);
        else
            options.material = matrix.clone();
    } else if (effect.name == "soft-tissue") {
        const bool layer = values[0] > 0.0;  // 0: no layer, the model as it is
        options.blockContact.tissueThickness = layer ? values[0] : 0.0;
        options.blockContact.tissueModulus = layer ? values[1] : 0.0;
    } else if (effect.name == "bag-volume") {
        // On the bag as the scenario sizes it (its sizes, or its fill mass's scale, and its
        // own airbag.volume_change): the base options' geometry is already fixed.
        bags::changeBagVolume(options, values[0]);
    } else if (effect.name == "film-stiffness") {
        // Membrane forces go as thickness times stress: a thickness times 1 + change is every
        // stress times it. The sheet's weight (density times thickness) stays as stated, and
        // so does its bending (a stiffness of its own, options.bendingStiffness).
        options.thickness *= 1.0 + values[0];
        options.density /= 1.0 + values[0];
    } else if (effect.name == "block-friction") {
        options.blockContact.friction = values[0];
    } else {
        throw std::invalid_argument("effect '" + effect.name + "' has no model");
    }
}

}  // namespace diagnose
