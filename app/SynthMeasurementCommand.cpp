// bagsim synth-measurement: measured data made from a truth simulation of the seed's rig with
// one unmodelled effect switched on, sensor noise and a model-form difference from what the
// diagnosis simulates (docs/diagnosis.md#synthetic-measured-data). The effect's name and
// parameters go only to the label file.
#include <bags/LoadTest.h>
#include <bags/Units.h>
#include <diagnose/Effects.h>
#include <diagnose/PatientDiagnosis.h>
#include <diagnose/Synthesis.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>
#include <io/LoadTestScenario.h>
#include <io/MeasuredData.h>
#include <io/PatientMeasuredData.h>
#include <io/Scenario.h>
#include <io/Units.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <functional>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "Commands.h"
#include "DiagnoseShared.h"
#include "Interrupt.h"
#include "PatientCoSim.h"

namespace bagsim::app {

namespace {

namespace fs = std::filesystem;

const char* kHelp =
    "usage: bagsim synth-measurement --scenario S.yaml --effect E [--param NAME=VALUE]...\n"
    "           [--noise CHANNEL=VALUE]... [--seed N] [--sample-interval T]\n"
    "           [--gas-mass-uncertainty U] [--room-temperature-uncertainty U]\n"
    "           [--truth-mesh SIZE] [--bed-gauge] --out DIR --label-out FILE [--force]\n"
    "           [--quiet]\n"
    "\n"
    "Makes measured data (docs/measured-data.md) of the seed's rig from a truth simulation of\n"
    "the scenario with one unmodelled effect switched on, sensor noise, and a model-form\n"
    "difference from what bagsim diagnose simulates: the truth run takes half the scenario's\n"
    "displacement step and, if the scenario has an imperfection, another imperfection seed\n"
    "(the scenario's + 100); with --truth-mesh, a finer mesh too.\n"
    "The folder names neither the effect nor its parameters; they go to the label file only.\n"
    "\n"
    "  --gas-mass-uncertainty U          the manifest states U as the standard uncertainty of\n"
    "                                    the flowmeter's gas mass (e.g. 0.05g; at most 10 % of\n"
    "                                    the smallest gas mass)\n"
    "  --room-temperature-uncertainty U  the manifest states U as the standard uncertainty of\n"
    "                                    the room temperature (e.g. 0.5K; at most 10 K)\n"
    "  (statements only: the data are made as without them; bagsim diagnose adds their\n"
    "  sensitivities to the validation uncertainty)\n"
    "  --truth-mesh SIZE                 the truth run's mesh size in place of the scenario's\n"
    "                                    airbag.mesh_size (e.g. 20mm; finer than the\n"
    "                                    scenario's, at least 5 mm; scaled with the bag as the\n"
    "                                    scenario's is): a model-form difference the diagnosis\n"
    "                                    does not simulate\n"
    "  --bed-gauge                       the rig has a gauge under the bed board: each test\n"
    "                                    gets the board's sink (test<N>-bed.csv), which tells\n"
    "                                    bed-compliance from machine-compliance\n"
    "\n"
    "effects (--effect E, or several: --effect E1,E2) and their parameters (--param NAME=VALUE\n"
    "with units, or EFFECT.NAME=VALUE where two effects share a name; default in brackets):\n"
    "  none                 no effect: noise and the model-form difference only\n"
    "  pressure-sensor      lag [3 s], offset [0.1 kPa]\n"
    "  flowmeter-bias       offset [0.1 g] (the flowmeter reads the bag's mass plus this)\n"
    "  gas-temperature      offset [5 K] (the gas is warmer than the room the manifest states)\n"
    "  machine-compliance   compliance [0.1 mm/N] (the testing machine in series)\n"
    "  block-friction       friction [0.5] (Coulomb, film on block)\n"
    "  leakage              conductance [0.05 mg/(s kPa)] (gas out through seams and valves\n"
    "                       in proportion to the gauge pressure; also mg/s/kPa)\n"
    "  heat-exchange        time_constant [20 s] (adiabatic gas relaxing to the room)\n"
    "  bed-compliance       compliance [0.1 mm/N] (the bed board under the bag on a spring)\n"
    "  viscoelasticity      g [0.2], tau [20 s] (one Prony term on the film's stress;\n"
    "                       the scenario's film constants are its long-term law)\n"
    "  fabric-anisotropy    yarn [1] (warp and weft yarns, each of this times the film's\n"
    "                       Young's modulus, carrying tension only; the scenario's film\n"
    "                       law is the matrix)\n"
    "  soft-tissue          thickness [10 mm], modulus [200 kPa] (a compliant layer on the\n"
    "                       block, soft tissue or a pad: its compression adds to the\n"
    "                       block's travel; softer layers need a finer mesh than 25 mm)\n"
    "  bag-volume           volume [0.05] (the bag's volume and fill mass times 1 + volume:\n"
    "                       a similar bag, every size times the cube root; -0.25 to 0.25)\n"
    "  film-stiffness       change [0.1] (the film's membrane stiffness, thickness times\n"
    "                       modulus, times 1 + change; its weight and bending as stated;\n"
    "                       -0.4 to 0.4)\n"
    "  load-cell-gain       gain [0.05] (reads the force times 1 + gain; not among the\n"
    "                       diagnosis's candidates: an effect outside its library)\n"
    "\n"
    "options:\n"
    "  --noise CH=VALUE     sensor noise (standard deviation) per channel: displacement\n"
    "                       [0.002 mm], force [0.01 N], pressure [0.005 kPa], mass [0.002 g],\n"
    "                       bed [0.002 mm] (with --bed-gauge); --noise none for none\n"
    "  --seed N             seed of the noise (default 1)\n"
    "  --sample-interval T  instruments' sampling interval (default 0.5 s)\n"
    "  --out DIR            the measured-data folder to write (refused if not empty, unless\n"
    "                       --force: then this command's files in it are replaced)\n"
    "  --label-out FILE     the label: effect, parameters, noise, seed, model-form difference\n"
    "  --force              replace earlier output of this command\n"
    "  --quiet              print only the summary\n"
    "\n"
    "\n"
    "A patient-on-array scenario (docs/diagnosis.md#a-patient-on-the-array) gives a patient's\n"
    "data instead: a pressure mat, a tilt sensor (pelvis, thorax) and every simulated bag's\n"
    "pressure sensor, from a truth co-simulation at half the scenario's macro step (kept in\n"
    "LABEL.truth-run/, beside the label). Its effects:\n"
    "  bag-pressure-sensor  lag [0.1 s], offset [0.5 kPa] (the bags' sensors)\n"
    "  mat-gain             gain [0.1] (the mat reads the pressure times 1 + gain)\n"
    "  film-friction        friction [0.4] (bag.body_friction)\n"
    "  gas-mass-bias        offset [0.2 g] (the bags hold array.gas_mass plus this)\n"
    "  soft-tissue          thickness [20 mm], modulus [30 kPa] (bag.body_tissue)\n"
    "  --noise mat=0.5mmHg, tilt=0.1deg, pressure=0.05kPa (the defaults), or none;\n"
    "  --sample-interval T (tilt and bag sensors, default 0.02 s), --mat-interval T (the\n"
    "  mat's frames, default 0.1 s).\n"
    "  --test NAME:KEY=VALUE[,KEY=VALUE]...  (repeatable) data of several tests instead of one\n"
    "  record: each test is the scenario with its keys set (e.g. --test "
    "gas-4.0g:array.gas_mass=4.0g),\n"
    "  the effect in every test, a truth co-simulation each (LABEL.truth-run/NAME/), noise\n"
    "  seed N + the test's index; the manifest lists the tests (docs/measured-data.md).\n"
    "  --test NAME@SUBJECT:KEY=VALUE,...  the test of a subject (a patient; his build in the "
    "keys,\n"
    "  e.g. --test woman@small-woman:patient.sex=female,patient.height=1.55m,patient.mass=50kg);\n"
    "  every test names one, at least two subjects; the diagnosis leaves one subject out.\n"
    "\n"
    "exit status: 0 written, 1 the truth run failed, 2 bad input, 129/130/143 interrupted\n"
    "(SIGHUP, SIGINT, SIGTERM).\n";

/// The truth's imperfection seed is the scenario's plus this.
constexpr std::uint64_t kTruthSeedOffset = 100;

struct Args {
    std::string scenario, effect, out, labelOut;
    std::vector<std::string> params, noise;
    std::vector<std::string> tests;  ///< --test NAME:KEY=VALUE[,KEY=VALUE] as given
    std::uint64_t seed = 1;
    std::string sampleInterval;  ///< "" the kind's default (0.5 s rig, 0.02 s patient)
    std::string matInterval = "0.1 s";
    std::string gasMassUncertainty, roomTemperatureUncertainty;  ///< "" not stated
    std::string truthMesh;  ///< --truth-mesh as given; "" the scenario's mesh
    bool force = false, quiet = false;
    bool bedGauge = false;  ///< --bed-gauge: the rig's data get the bed board's sink
};

Args parseArgs(int argc, char** argv) {
    Args a;
    for (int i = 0; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&] { return takeOptionValue(argc, argv, i); };
        if (arg == "--scenario")
            a.scenario = value();
        else if (arg == "--effect")
            a.effect = value();
        else if (arg == "--param")
            a.params.push_back(value());
        else if (arg == "--noise")
            a.noise.push_back(value());
        else if (arg == "--test")
            a.tests.push_back(value());
        else if (arg == "--seed") {
            const std::string v = value();
            char* end = nullptr;
            const unsigned long long s = std::strtoull(v.c_str(), &end, 10);
            if (v.empty() || *end || v[0] == '-')
                throw UsageError("--seed '" + v + "' is not valid; valid: a whole number >= 0");
            a.seed = s;
        } else if (arg == "--sample-interval")
            a.sampleInterval = value();
        else if (arg == "--mat-interval")
            a.matInterval = value();
        else if (arg == "--gas-mass-uncertainty")
            a.gasMassUncertainty = value();
        else if (arg == "--room-temperature-uncertainty")
            a.roomTemperatureUncertainty = value();
        else if (arg == "--truth-mesh")
            a.truthMesh = value();
        else if (arg == "--out")
            a.out = value();
        else if (arg == "--label-out")
            a.labelOut = value();
        else if (arg == "--force")
            a.force = true;
        else if (arg == "--bed-gauge")
            a.bedGauge = true;
        else if (arg == "--quiet" || arg == "-q")
            a.quiet = true;
        else
            throw UsageError(
                "unknown option '" + arg +
                "'; valid: --scenario, --effect, --param, --noise, --test, --seed, "
                "--sample-interval, --mat-interval, --gas-mass-uncertainty, "
                "--room-temperature-uncertainty, --truth-mesh, --bed-gauge, --out, --label-out, "
                "--force, --quiet, --help");
    }
    if (a.scenario.empty())
        throw UsageError("--scenario is required (e.g. scenarios/tests/tiny-load-test.yaml)");
    if (a.effect.empty())
        throw UsageError("--effect is required; valid: none, " + diagnose::listEffectNames() +
                         " (a patient-on-array scenario: " + diagnose::listPatientEffectNames() +
                         ")");
    if (a.out.empty()) throw UsageError("--out DIR is required");
    if (a.labelOut.empty()) throw UsageError("--label-out FILE is required");
    if (fs::exists(a.labelOut) && !a.force)
        throw UsageError(a.labelOut + " exists; pass --force to replace it or choose another name");
    const fs::path lab = fs::absolute(a.labelOut).lexically_normal();
    if (lab.parent_path() == fs::absolute(a.out).lexically_normal())
        throw UsageError(
            "--label-out must not be inside --out: the measured data must not name "
            "the effect");
    return a;
}

io::Dimension getDimension(const std::string& unit) {
    if (unit.empty()) return io::Dimension::Dimensionless;
    return io::findUnit(unit == "mm/N" ? "mm" : unit)->dimension;
}

// Parses one parameter's text into SI.
double parseParamValue(const diagnose::EffectParameter& p, const std::string& g,
                       const std::string& text) {
    try {
        if (p.unit == "mm/N") {
            // A compliance: "0.5 mm/N".
            const size_t u = text.find("mm/N");
            if (u == std::string::npos)
                throw io::UnitError("a compliance needs the unit mm/N (e.g. \"0.1 mm/N\")");
            return io::parseQuantity(text.substr(0, u), io::Dimension::Dimensionless) * 1e-3;
        }
        if (p.unit == "K") {
            // A temperature difference: K only (degC would shift it by 273.15).
            const size_t u = text.find('K');
            if (u == std::string::npos || u + 1 != text.size())
                throw io::UnitError("a temperature difference needs the unit K (e.g. \"5 K\")");
            return io::parseQuantity(text.substr(0, u), io::Dimension::Dimensionless);
        }
        return io::parseQuantity(text, getDimension(p.unit));
    } catch (const io::UnitError& ex) {
        throw UsageError("--param '" + g + "': " + ex.what());
    }
}

// Parses "NAME=VALUE" or "EFFECT.NAME=VALUE" into each effect's parameter values [SI]
// (defaults where not given); `shown` gets one label line per parameter.
std::vector<std::vector<double>> parseParams(const std::vector<const diagnose::Effect*>& effects,
                                             const std::vector<std::string>& given,
                                             std::vector<std::string>& shown) {
    std::vector<std::vector<double>> v;
    std::vector<std::vector<bool>> seen;
    for (const diagnose::Effect* e : effects) {
        v.emplace_back();
        for (const auto& p : e->parameters) v.back().push_back(p.typical);
        seen.emplace_back(v.back().size(), false);
    }
    for (const std::string& g : given) {
        const size_t eq = g.find('=');
        if (eq == std::string::npos) throw UsageError("--param '" + g + "' needs NAME=VALUE");
        std::string name = g.substr(0, eq), only;
        if (name.find('.') != std::string::npos) {
            only = name.substr(0, name.find('.'));
            name = name.substr(name.find('.') + 1);
        }
        std::vector<std::pair<size_t, size_t>> hits;
        std::string list;
        for (size_t i = 0; i < effects.size(); ++i)
            for (size_t k = 0; k < effects[i]->parameters.size(); ++k) {
                list += (list.empty() ? "" : ", ") + effects[i]->name + "." +
                        effects[i]->parameters[k].name;
                if (effects[i]->parameters[k].name == name &&
                    (only.empty() || only == effects[i]->name))
                    hits.push_back({i, k});
            }
        if (hits.empty())
            throw UsageError("--param '" + g + "': no effect given has a parameter '" +
                             (only.empty() ? "" : only + ".") + name +
                             "'; valid: " + (list.empty() ? "none" : list));
        if (hits.size() > 1)
            throw UsageError("--param '" + g + "': '" + name +
                             "' is a parameter of several effects; write EFFECT." + name +
                             "=VALUE (valid: " + list + ")");
        const auto [i, k] = hits[0];
        v[i][k] = parseParamValue(effects[i]->parameters[k], g, g.substr(eq + 1));
        seen[i][k] = true;
    }
    for (size_t i = 0; i < effects.size(); ++i)
        for (size_t k = 0; k < v[i].size(); ++k) {
            const auto& p = effects[i]->parameters[k];
            shown.push_back((effects.size() > 1 ? effects[i]->name + "." : std::string()) + p.name +
                            ": " + fmt("%.6g", v[i][k] / p.siPerUnit) +
                            (p.unit.empty() ? "" : " " + p.unit) +
                            (seen[i][k] ? "" : "  # default"));
        }
    return v;
}

// One channel's noise option: its name, dimension and where its value goes [SI].
struct NoiseChannel {
    const char* name;
    io::Dimension d;
    double* value;
};

void parseNoise(const std::vector<std::string>& given, const std::vector<NoiseChannel>& chans) {
    std::string names, example;
    for (const NoiseChannel& c : chans) names += (names.empty() ? "" : ", ") + std::string(c.name);
    for (const std::string& g : given) {
        if (g == "none") {
            for (const NoiseChannel& c : chans) *c.value = 0.0;
            continue;
        }
        const size_t eq = g.find('=');
        const std::string ch = g.substr(0, eq);
        const std::string text = eq == std::string::npos ? "" : g.substr(eq + 1);
        bool found = false;
        for (const NoiseChannel& c : chans)
            if (ch == c.name) {
                found = true;
                try {
                    *c.value = io::parseQuantity(text, c.d);
                } catch (const io::UnitError& ex) {
                    throw UsageError("--noise '" + g + "': " + ex.what());
                }
                if (*c.value < 0.0) throw UsageError("--noise '" + g + "': must be >= 0");
            }
        if (!found || eq == std::string::npos)
            throw UsageError("--noise '" + g +
                             "' is not valid; valid: none, or CHANNEL=VALUE with CHANNEL one of " +
                             names + " (e.g. " + chans[0].name + "=...)");
    }
}

void parseNoise(const std::vector<std::string>& given, diagnose::SynthesisOptions& o) {
    parseNoise(given, {{"displacement", io::Dimension::Length, &o.displacementNoise},
                       {"force", io::Dimension::Force, &o.forceNoise},
                       {"pressure", io::Dimension::Pressure, &o.pressureNoise},
                       {"mass", io::Dimension::Mass, &o.massNoise},
                       {"bed", io::Dimension::Length, &o.bedNoise}});
}

// The effects named by --effect (none: empty), from `find`'s library.
std::vector<const diagnose::Effect*> parseEffects(
    const Args& a, const std::function<const diagnose::Effect*(const std::string&)>& find,
    const std::string& valid) {
    std::vector<const diagnose::Effect*> effects;
    if (a.effect != "none") {
        std::istringstream is(a.effect);
        std::string name;
        while (std::getline(is, name, ',')) {
            const diagnose::Effect* e = find(name);
            if (!e) throw UsageError("--effect '" + name + "' is not known; valid: none, " + valid);
            for (const diagnose::Effect* f : effects)
                if (f == e) throw UsageError("--effect names '" + name + "' twice");
            effects.push_back(e);
        }
    }
    if (effects.empty() && !a.params.empty()) throw UsageError("--effect none takes no --param");
    return effects;
}

double parseInterval(const std::string& option, const std::string& text) {
    try {
        const double v = io::parseQuantity(text, io::Dimension::Time);
        if (!(v > 0.0)) throw std::invalid_argument("must be greater than 0 s");
        // A test's samples go as its length over the interval: 1e-9 s filled the memory.
        if (v < 1e-3)
            throw std::invalid_argument(
                "is finer than 1 ms, a 1 kHz logger (a 100 s test would "
                "give over 100 000 rows a channel); valid: 1 ms to 60 s");
        return v;
    } catch (const std::exception& e) {
        throw UsageError(option + " '" + text + "': " + e.what());
    }
}

// Writes the label file (through a temporary file): the effect, its parameters and scenario
// keys, then `lines` (noise, seed, sampling, model form, scenario).
void writeLabel(const Args& a, const std::vector<const diagnose::Effect*>& effects,
                const std::vector<std::string>& shownParams, const std::string& lines) {
    std::ostringstream label;
    label << "# Label of the synthetic measured data in " << a.out
          << " (bagsim synth-measurement): what the truth run had that the data do not say.\n"
          << "effect: " << a.effect << "\n";
    if (!effects.empty()) {
        label << "parameters:\n";
        for (const std::string& s : shownParams) label << "  " << s << "\n";
        label << "scenario_keys: [";
        bool first = true;
        for (const diagnose::Effect* e : effects)
            for (const auto& p : e->parameters) {
                label << (first ? "" : ", ") << p.scenarioKey;
                first = false;
            }
        label << "]\n";
    }
    label << lines;
    const std::string tmp = a.labelOut + ".tmp";
    std::ofstream f(tmp);
    f << label.str();
    if (!f.flush()) throw std::runtime_error(a.labelOut + ": cannot write");
    f.close();
    fs::rename(tmp, a.labelOut);
}

// A test's or subject's name: letters, digits, '.', '-', '_' (it names folders).
bool isPlainName(const std::string& n) {
    const bool plain = std::all_of(n.begin(), n.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '_';
    });
    return plain && !n.empty() && n[0] != '.' && n[0] != '-' && n.size() <= 64;
}

// "NAME[@SUBJECT]:KEY=VALUE[,KEY=VALUE]..." of --test: the test's name, its subject and its
// scenario keys ("NAME@SUBJECT" alone: the scenario's own keys). A piece without '=' continues
// the previous value (a value with a comma: {thickness: 20 mm, ...}).
diagnose::PatientTest parseTestOption(const std::string& g) {
    const std::string valid =
        "valid: NAME[@SUBJECT]:KEY=VALUE[,KEY=VALUE]..., e.g. --test "
        "gas-4.0g:array.gas_mass=4.0g or --test woman-4.5g@small-woman:"
        "patient.sex=female,patient.height=1.55m,patient.mass=50kg";
    size_t colon = g.find(':');
    const size_t at = g.substr(0, colon).find('@');
    if (colon == std::string::npos && at != std::string::npos) colon = g.size();  // NAME@SUBJECT
    if (colon == std::string::npos || colon == 0 || at == 0)
        throw UsageError("--test '" + g + "' has no name; " + valid);
    diagnose::PatientTest t;
    t.name = g.substr(0, std::min(colon, at));
    if (!isPlainName(t.name))
        throw UsageError("--test '" + g + "': '" + t.name +
                         "' is not a test's name; valid: 1-64 letters, "
                         "digits, '.', '-' and '_', not starting with '.' or '-'");
    if (at != std::string::npos) {
        t.subject = g.substr(at + 1, colon - at - 1);
        if (!isPlainName(t.subject))
            throw UsageError(
                "--test '" + g + "': '" + t.subject +
                "' is not a subject's name; valid: "
                "1-64 letters, digits, '.', '-' and '_', not starting with '.' or '-'");
    }
    if (colon == g.size()) return t;
    std::string rest = g.substr(colon + 1);
    size_t start = 0;
    while (start <= rest.size()) {
        size_t comma = rest.find(',', start);
        if (comma == std::string::npos) comma = rest.size();
        const std::string piece = rest.substr(start, comma - start);
        const size_t eq = piece.find('=');
        if (eq != std::string::npos && eq > 0) {
            std::string key = piece.substr(0, eq);
            key.erase(0, key.find_first_not_of(' '));
            t.overrides.emplace_back(key, piece.substr(eq + 1));
        } else if (!t.overrides.empty() && !piece.empty()) {
            t.overrides.back().second += "," + piece;
        } else {
            throw UsageError("--test '" + g + "': '" + piece + "' is not KEY=VALUE; " + valid);
        }
        start = comma + 1;
    }
    for (const auto& [k, v] : t.overrides)
        if (k == "kind" || k == "run" || k == "run.settle_time" || k == "run.duration")
            throw UsageError("--test '" + g + "': a test cannot change '" + k +
                             "'; valid: any other scenario key (the settle time and duration are "
                             "every test's)");
    return t;
}

std::string joinNames(const std::vector<std::string>& names) {
    std::string s;
    for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
    return s;
}

// A patient-on-array scenario: the truth co-simulation and the patient's channels.
int runPatient(const Args& a, const io::ScenarioFile& file) {
    const std::vector<const diagnose::Effect*> effects =
        parseEffects(a, diagnose::findPatientEffect, diagnose::listPatientEffectNames());
    std::vector<std::string> shownParams;
    const std::vector<std::vector<double>> values = parseParams(effects, a.params, shownParams);
    diagnose::PatientSynthesisOptions so;
    parseNoise(a.noise, {{"mat", io::Dimension::Pressure, &so.matNoise},
                         {"tilt", io::Dimension::Angle, &so.tiltNoise},
                         {"pressure", io::Dimension::Pressure, &so.pressureNoise}});
    so.seed = a.seed;
    so.sampleInterval =
        parseInterval("--sample-interval", a.sampleInterval.empty() ? "0.02 s" : a.sampleInterval);
    so.matInterval = parseInterval("--mat-interval", a.matInterval);

    const io::PatientOnArrayScenario sc = io::readPatientOnArrayScenario(file);
    std::vector<diagnose::PatientTest> tests;
    for (const std::string& g : a.tests) {
        tests.push_back(parseTestOption(g));
        for (size_t k = 0; k + 1 < tests.size(); ++k)
            if (tests[k].name == tests.back().name)
                throw UsageError("--test '" + g + "': the test '" + tests.back().name +
                                 "' is given twice; valid: one --test per name");
    }
    const bool several = !tests.empty();
    if (!several) tests.push_back({"", "", {}, {}});
    // Subjects: one per test or none, and at least two (the diagnosis holds one out at a time).
    std::vector<std::string> subjects;
    for (const diagnose::PatientTest& t : tests)
        if (!t.subject.empty() &&
            std::find(subjects.begin(), subjects.end(), t.subject) == subjects.end())
            subjects.push_back(t.subject);
    for (const diagnose::PatientTest& t : tests)
        if (!subjects.empty() && t.subject.empty())
            throw UsageError(
                "--test '" + t.name + "' names no subject, another names '" + subjects.front() +
                "'; valid: NAME@SUBJECT:KEY=VALUE,... for every test, or no subject at all");
    if (subjects.size() == 1)
        throw UsageError("every --test names the subject '" + subjects.front() +
                         "'; valid: at least two subjects (NAME@SUBJECT), or none");
    // Each test's truth: the test's scenario, the effect (a response effect at the test's stated
    // gas mass), half the macro step.
    diagnose::PatientInstruments inst;
    std::vector<io::ScenarioFile> truths;
    for (const diagnose::PatientTest& t : tests) {
        io::ScenarioFile truth = file;
        io::PatientOnArrayScenario tsc;
        try {
            for (const auto& [k, v] : t.overrides) truth.applyOverride(k, v);
            tsc = io::readPatientOnArrayScenario(truth);
        } catch (const io::InputError& e) {
            throw UsageError("--test '" + t.name + "': " + e.what());
        }
        inst = {};
        for (size_t i = 0; i < effects.size(); ++i) {
            try {
                if (effects[i]->changesTheBag) {
                    for (const auto& [key, value] : diagnose::getPatientEffectOverrides(
                             *effects[i], values[i], tsc.options.layout.gasMass))
                        truth.applyOverride(key, value);
                } else {
                    diagnose::applyPatientInstrumentEffect(*effects[i], values[i], inst);
                }
            } catch (const std::invalid_argument& e) {
                throw UsageError(std::string("--param: ") + e.what());
            }
        }
        truth.applyOverride("coupling.macro_step", formatHalfMacroStep(tsc));
        truths.push_back(truth);
    }
    const std::string half = formatHalfMacroStep(sc);
    const std::string modelForm = "macro step " + half + " (the scenario's " +
                                  io::formatSignificant(sc.options.coupling.macroStep, "ms") + ")";
    const fs::path out(a.out);
    claimOutputFolder(out, a.force,
                      {io::kMeasuredManifest, "scenario.yaml", "mat.csv", "tilt.csv",
                       "bag*-pressure.csv", "*-mat.csv", "*-tilt.csv"});
    const std::string truthDir = a.labelOut + ".truth-run";
    if (several) {
        std::error_code ec;
        fs::remove_all(truthDir, ec);
    }
    if (!a.quiet)
        std::cerr << "bagsim synth-measurement: truth co-simulation of " << a.scenario << " ("
                  << fmt("%g s", sc.getEndTime()) << ", " << modelForm << ") in " << truthDir
                  << (several ? "/<test>/ for " + std::to_string(tests.size()) + " tests"
                              : std::string())
                  << "\n";
    const auto start = std::chrono::steady_clock::now();
    diagnose::PatientMeasurement data;
    std::string testLines;
    for (size_t t = 0; t < tests.size(); ++t) {
        if (several && !a.quiet) std::cerr << "  test " << tests[t].name << "\n";
        const diagnose::PatientChannels run =
            runCoSimulation(truths[t], several ? truthDir + "/" + tests[t].name : truthDir);
        diagnose::PatientSynthesisOptions st = so;
        st.seed = a.seed + t;  // each test its own noise
        tests[t].channels = diagnose::synthesizePatientChannels(run, inst, st);
        if (several) {
            testLines +=
                "  - {name: " + tests[t].name +
                (tests[t].subject.empty() ? std::string() : ", subject: " + tests[t].subject) +
                ", noise_seed: " + std::to_string(st.seed) + ", overrides: {";
            for (size_t k = 0; k < tests[t].overrides.size(); ++k)
                testLines += (k ? ", " : "") + tests[t].overrides[k].first + ": \"" +
                             tests[t].overrides[k].second + "\"";
            testLines += "}}\n";
        }
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (several)
        data.tests = tests;
    else
        data.channels = tests.front().channels;
    data.protocol.settleTime = sc.settleTime;
    data.protocol.duration = sc.duration;
    data.description =
        "synthetic (bagsim synth-measurement, noise seed " + std::to_string(a.seed) + ")";
    io::writePatientMeasuredData(
        out.string(), data, file.getText(),
        "# Measured data of a patient on the array (docs/measured-data.md), "
        "synthesised by\n# bagsim synth-measurement from a truth "
        "co-simulation of scenario.yaml.\n");
    writeLabel(
        a, effects, shownParams,
        "noise: {mat: " + fmt("%g", so.matNoise / bags::kPascalsPerMmHg) +
            " mmHg, tilt: " + fmt("%g", so.tiltNoise * 180.0 / 3.14159265358979323846) +
            " deg, pressure: " + fmt("%g", so.pressureNoise * 1e-3) + " kPa}\nseed: " +
            std::to_string(a.seed) + "\nsample_interval: " + fmt("%g", so.sampleInterval) +
            " s\nmat_interval: " + fmt("%g", so.matInterval) + " s\nmodel_form: \"" + modelForm +
            "\"\ntruth_run: " + truthDir + "\nscenario: " + a.scenario + "\n" +
            (subjects.empty() ? std::string() : "subjects: [" + joinNames(subjects) + "]\n") +
            (several ? "tests:\n" + testLines : std::string()));
    size_t frames = 0, tilts = 0, bags = 0;
    for (const diagnose::PatientTest& t : tests)
        frames += t.channels.mat.time.size(), tilts += t.channels.tilt.time.size(),
            bags += t.channels.bags.size();
    std::cout << "measured data in " << a.out << "/: "
              << (subjects.empty() ? std::string()
                                   : std::to_string(subjects.size()) + " subjects, ")
              << (several ? std::to_string(tests.size()) + " tests, " : std::string()) << frames
              << " mat frames, " << tilts << " tilt samples, " << bags
              << " bag sensors (truth co-simulation" << (several ? "s " : " ")
              << fmt("%.1f", seconds) << " s); label in " << a.labelOut << "\n";
    return 0;
}

// The standard uncertainties the manifest is to state (--gas-mass-uncertainty,
// --room-temperature-uncertainty), in the ranges the reader accepts.
struct StatedUncertainties {
    bool mass = false, temperature = false;
    double massValue = 0.0, temperatureValue = 0.0;  ///< [kg], [K]
    void applyTo(diagnose::MeasuredData& data) const {
        for (diagnose::MeasuredTest& t : data.tests)
            t.gasMassUncertainty = massValue, t.gasMassUncertaintyStated = mass;
        data.protocol.roomTemperatureUncertainty = temperatureValue;
        data.protocol.roomTemperatureUncertaintyStated = temperature;
    }
};

StatedUncertainties parseStatedUncertainties(const Args& a, const std::vector<double>& masses) {
    StatedUncertainties s;
    if (!a.gasMassUncertainty.empty()) {
        const double least = *std::min_element(masses.begin(), masses.end());
        const double most = io::kMaxGasMassUncertaintyShare * least;
        const std::string valid = "valid: 0 g to " +
                                  fmt("%g", 100 * io::kMaxGasMassUncertaintyShare) +
                                  " % of the smallest gas mass (" + fmt("%.4g", most * 1e3) + " g)";
        try {
            s.massValue = io::parseQuantity(a.gasMassUncertainty, io::Dimension::Mass);
        } catch (const io::UnitError& ex) {
            throw UsageError("--gas-mass-uncertainty '" + a.gasMassUncertainty + "': " + ex.what() +
                             "; " + valid);
        }
        if (!(s.massValue >= 0.0) || s.massValue > most)
            throw UsageError("--gas-mass-uncertainty '" + a.gasMassUncertainty +
                             "' is out of range; " + valid);
        s.mass = true;
    }
    if (!a.roomTemperatureUncertainty.empty()) {
        const std::string& t = a.roomTemperatureUncertainty;
        const std::string valid = "valid: 0 K to " + fmt("%g", io::kMaxRoomTemperatureUncertainty) +
                                  " K, a temperature difference in K (e.g. 0.5K)";
        const size_t k = t.find('K');
        if (k == std::string::npos || k + 1 != t.size())
            throw UsageError("--room-temperature-uncertainty '" + t + "': " + valid);
        try {
            s.temperatureValue = io::parseQuantity(t.substr(0, k), io::Dimension::Dimensionless);
        } catch (const io::UnitError& ex) {
            throw UsageError("--room-temperature-uncertainty '" + t + "': " + ex.what() + "; " +
                             valid);
        }
        if (!(s.temperatureValue >= 0.0) || s.temperatureValue > io::kMaxRoomTemperatureUncertainty)
            throw UsageError("--room-temperature-uncertainty '" + t + "' is out of range; " +
                             valid);
        s.temperature = true;
    }
    return s;
}

int run(const Args& a) {
    const io::ScenarioFile file = io::ScenarioFile::load(a.scenario);
    if (file.getRoot().getString("kind", "") == io::kPatientOnArrayKind) {
        if (!a.gasMassUncertainty.empty() || !a.roomTemperatureUncertainty.empty())
            throw UsageError(
                "--gas-mass-uncertainty and --room-temperature-uncertainty are for the "
                "rig's data (a patient-on-array scenario's manifest does not state them)");
        if (!a.truthMesh.empty())
            throw UsageError(
                "--truth-mesh is for the rig's data (a patient-on-array scenario's "
                "truth differs by its macro step)");
        if (a.bedGauge)
            throw UsageError(
                "--bed-gauge is for the rig's data (a patient lies on the array, "
                "which has no bed gauge)");
        return runPatient(a, file);
    }
    if (!a.tests.empty())
        throw UsageError(
            "--test is for a patient-on-array scenario; the rig's scenario lists its gas "
            "masses (test.gas_masses)");
    // The effects and their parameters.
    const std::vector<const diagnose::Effect*> effects =
        parseEffects(a, diagnose::findEffect, diagnose::listEffectNames());
    std::vector<std::string> shownParams;
    const std::vector<std::vector<double>> values = parseParams(effects, a.params, shownParams);
    diagnose::SynthesisOptions so;
    parseNoise(a.noise, so);
    so.seed = a.seed;
    so.bedGauge = a.bedGauge;
    for (const std::string& n : a.noise)
        if (n.rfind("bed=", 0) == 0 && !a.bedGauge)
            throw UsageError("--noise '" + n + "': the bed gauge's noise needs --bed-gauge");
    so.sampleInterval =
        parseInterval("--sample-interval", a.sampleInterval.empty() ? "0.5 s" : a.sampleInterval);
    try {
        so.validate();
    } catch (const std::exception& e) {
        throw UsageError("--sample-interval '" + a.sampleInterval + "': " + e.what());
    }

    // The scenario as the diagnosis will read it, then the truth's model-form difference.
    io::LoadTestScenario sc = io::readLoadTestScenario(file);
    if (!sc.rig.isNone())
        throw io::InputError(a.scenario, file.getRoot().getLine("rig"), "rig",
                             "the scenario switches rig effects on; give synth-measurement a "
                             "scenario without a rig section (the effect is chosen by --effect)");
    const std::vector<double> readings = sc.options.gasMasses;  // what the flowmeter reads
    const StatedUncertainties statedUncertainties = parseStatedUncertainties(a, readings);
    const double roomTemperature = sc.options.gas.temperature;  // what the lab's thermometer reads
    // The bag as the scenario sizes it (a fill mass's sizing, its volume change), as the
    // diagnosis will; the effects act on that bag (bag-volume scales it; a warmer gas does not
    // resize it).
    sc.options.solver.monitor = [](int, double, double, double) { throwIfInterrupted(); };
    const double writtenMesh = sc.options.geometry.meshSize;  // airbag.mesh_size as read
    const double truthMesh = parseFinerMesh("--truth-mesh", a.truthMesh, writtenMesh);
    prepareGeometry(sc);
    bags::LoadTestOptions truth = sc.options;
    std::string meshForm;
    if (truthMesh > 0.0) {
        // The sizing (fill mass, volume change) scales the truth's mesh as it scales the
        // scenario's; the effects act on the truth's bag after it (bag-volume scales it again).
        applyFinerMesh("--truth-mesh", a.truthMesh, truthMesh, writtenMesh, truth);
        meshForm = "mesh size " + io::formatSignificant(truthMesh, "mm") + " (the scenario's " +
                   io::formatSignificant(writtenMesh, "mm") + "), ";
    }
    diagnose::RigEffects rig;
    for (size_t i = 0; i < effects.size(); ++i) {
        try {
            diagnose::applyEffect(*effects[i], values[i], readings, rig, truth);
        } catch (const std::invalid_argument& e) {
            throw UsageError(std::string("--param: ") + e.what());
        }
    }
    // A testing machine stops at its load cell's reading of the peak force: the truth is
    // loaded to the force the load cell reads as the protocol's peak.
    const double peakReading = sc.options.peakForce;  // the protocol's, as the load cell reads it
    truth.peakForce = peakReading / (1.0 + rig.loadCellGain);
    std::string modelForm = meshForm + "displacement step " +
                            io::formatSignificant(0.5 * truth.displacementStep, "mm") +
                            " (the scenario's " +
                            io::formatSignificant(truth.displacementStep, "mm") + ")";
    truth.displacementStep *= 0.5;
    if (truth.imperfection.amplitude > 0.0) {
        // Another bag of the scenario's population; not one of the next few seeds, which the
        // diagnosis takes for the imperfection's spread.
        truth.imperfection.seed += kTruthSeedOffset;
        modelForm += ", imperfection seed " + std::to_string(truth.imperfection.seed) +
                     " (the scenario's " +
                     std::to_string(truth.imperfection.seed - kTruthSeedOffset) + ")";
    }

    const fs::path out(a.out);
    claimOutputFolder(out, a.force,
                      {io::kMeasuredManifest, "scenario.yaml", "test*-machine.csv",
                       "test*-pressure.csv", "test*-flowmeter.csv", "test*-bed.csv"});
    if (!a.quiet)
        std::cerr << "bagsim synth-measurement: truth run of " << a.scenario << " ("
                  << truth.gasMasses.size() << " gas masses, " << modelForm << ")\n";
    const bags::LoadTestResult result = bags::runLoadTest(truth);
    for (const bags::LoadCurve& c : result.curves)
        if (c.failed)
            throw std::runtime_error("the truth run's curve at " +
                                     io::formatQuantity(c.gasMass, "g", 3) +
                                     " stopped: " + c.failure);

    diagnose::Protocol protocol;
    // The protocol as the lab states it: the scenario's, not the truth's (whose gas may be
    // warmer than the room).
    protocol.blockSize = truth.blockSize;
    protocol.rate = truth.loadingRate;
    protocol.peakForce = peakReading;
    protocol.roomTemperature = roomTemperature;
    diagnose::MeasuredData data =
        diagnose::synthesizeMeasurement(result.curves, readings, rig, protocol, so);
    statedUncertainties.applyTo(data);
    data.description =
        "synthetic (bagsim synth-measurement, noise seed " + std::to_string(a.seed) + ")";
    io::writeMeasuredData(
        out.string(), data, file.getText(),
        "# Measured data of the seed's rig (docs/measured-data.md), synthesised by\n"
        "# bagsim synth-measurement from a truth simulation of scenario.yaml.\n");

    std::ostringstream lines;
    lines << "noise: {displacement: " << fmt("%g", so.displacementNoise * 1e3)
          << " mm, force: " << fmt("%g", so.forceNoise)
          << " N, pressure: " << fmt("%g", so.pressureNoise * 1e-3)
          << " kPa, mass: " << fmt("%g", so.massNoise * 1e3) << " g"
          << (so.bedGauge ? ", bed: " + fmt("%g", so.bedNoise * 1e3) + " mm" : std::string())
          << "}\n"
          << "bed_gauge: " << (so.bedGauge ? "true" : "false") << "\n"
          << "seed: " << a.seed << "\n"
          << "sample_interval: " << fmt("%g", so.sampleInterval) << " s\n"
          << "model_form: \"" << modelForm << "\"\n"
          << "scenario: " << a.scenario << "\n";
    writeLabel(a, effects, shownParams, lines.str());
    size_t samples = 0;
    for (const auto& t : data.tests) samples += t.time.size();
    std::cout << "measured data in " << a.out << "/: " << data.tests.size() << " tests, " << samples
              << " machine samples (truth run " << fmt("%.1f", result.seconds) << " s); label in "
              << a.labelOut << "\n";
    return 0;
}

}  // namespace

int runSynthMeasurementCommand(int argc, char** argv) {
    return runCommandMain("bagsim synth-measurement", kHelp, argc, argv,
                          [](int n, char** v) { return run(parseArgs(n, v)); });
}

}  // namespace bagsim::app
