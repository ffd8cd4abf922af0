// bagsim fit-material: fits membrane materials to a uniaxial tensile test and prints the
// constants, the fit error, the stable stretch range and the scenario form.
#include <bags/MaterialFit.h>
#include <io/InputError.h>
#include <io/Scenario.h>
#include <io/Units.h>

#include <cmath>
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

namespace bagsim::app {

namespace {

const char* kHelp =
    "usage: bagsim fit-material TENSILE.csv --model MODEL [options]\n"
    "\n"
    "Fits a plane-stress incompressible membrane material to a uniaxial tensile test\n"
    "(engineering strain, engineering stress) by least squares, and prints the constants, the\n"
    "fit error, the stretch range where the fitted material stays stable, and the line to put\n"
    "in a scenario. See docs/materials.md.\n"
    "\n"
    "TENSILE.csv: '#' comment lines, a header 'strain,stress_MPa' (or strain_percent,\n"
    "stress_kPa, stress_Pa), then one 'strain,stress' row per point. Example:\n"
    "data/tensile/tpu-coated-nylon.csv.\n"
    "\n"
    "options:\n"
    "  --model M            neo-hookean, mooney-rivlin, yeoh, ogden, or all (compares them)\n"
    "  --strain-unit U      percent or fraction (default: from the header; 'strain' = fraction)\n"
    "  --stress-unit U      MPa, kPa or Pa (default: from the header, e.g. stress_MPa)\n"
    "  --ogden-terms N      number of Ogden terms, 1 to 3 (default 2)\n"
    "  --ogden-allow-negative  let Ogden mu_i be negative (default: mu_i >= 0, which keeps\n"
    "                       every term stable; negative terms may fit better but go unstable)\n"
    "  --max-stretch S      stability is scanned for stretches 1 to S (default 3)\n"
    "  --thickness T        film thickness the stresses were computed with (e.g. 0.2mm); it\n"
    "                       goes into the scenario form, which requires one\n"
    "  --out FILE.yaml      write the fitted material as a scenario 'membrane:' section (with\n"
    "                       --model all: the model of least RMS error, the others as comments)\n"
    "  --curves FILE.csv    write data and model stresses at the data strains\n"
    "  --force              overwrite existing --out / --curves files\n"
    "  -h, --help           this text\n"
    "\n"
    "exit status: 0 fitted, 2 bad input (file, option or data), 1 fit failed.\n";

struct Args {
    std::string file;
    std::string model;
    std::string strainUnit;
    std::string stressUnit;
    std::string out;
    std::string curves;
    bool force = false;
    std::string thickness;  ///< as given, e.g. "0.2 mm"; "" if not given
    bags::MaterialFitOptions fit;
};

std::string formatConstant(const std::string& name, double value) {
    if (bags::isStressConstant(name)) return name + " = " + fmt("%.7g", value * 1e-6) + " MPa";
    return name + " = " + fmt("%.7g", value);
}

double parseNumber(const std::string& option, const std::string& text) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
        throw UsageError(option + " '" + text + "' is not a number");
    return v;
}

Args parseArgs(int argc, char** argv) {
    Args a;
    for (int i = 0; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&] { return takeOptionValue(argc, argv, i); };
        if (arg == "--model") {
            a.model = value();
        } else if (arg == "--strain-unit") {
            a.strainUnit = value();
            if (a.strainUnit != "percent" && a.strainUnit != "fraction")
                throw UsageError("--strain-unit '" + a.strainUnit +
                                 "' is not valid; valid: percent, fraction");
        } else if (arg == "--stress-unit") {
            a.stressUnit = value();
            if (a.stressUnit != "MPa" && a.stressUnit != "kPa" && a.stressUnit != "Pa")
                throw UsageError("--stress-unit '" + a.stressUnit +
                                 "' is not valid; valid: MPa, kPa, Pa");
        } else if (arg == "--ogden-terms") {
            const std::string v = value();
            if (v != "1" && v != "2" && v != "3")
                throw UsageError("--ogden-terms '" + v + "' is not valid; valid: 1, 2, 3");
            a.fit.ogdenTerms = std::stoi(v);
        } else if (arg == "--ogden-allow-negative") {
            a.fit.ogdenStableTerms = false;
        } else if (arg == "--max-stretch") {
            const std::string v = value();
            a.fit.stabilityMaxStretch = parseNumber(arg, v);
            if (!(a.fit.stabilityMaxStretch > 1.0) || a.fit.stabilityMaxStretch > 20.0)
                throw UsageError("--max-stretch '" + v + "' is not valid; valid: 1 < S <= 20");
        } else if (arg == "--thickness") {
            a.thickness = value();
            try {
                const double t = io::parseQuantity(a.thickness, io::Dimension::Length);
                if (!(t > 0.0) || t > 0.01)
                    throw UsageError("--thickness '" + a.thickness +
                                     "' is not valid; valid: a length above 0 and up to 10 mm");
            } catch (const io::UnitError& e) {
                throw UsageError("--thickness '" + a.thickness + "': " + e.what());
            }
        } else if (arg == "--out") {
            a.out = value();
        } else if (arg == "--curves") {
            a.curves = value();
        } else if (arg == "--force") {
            a.force = true;
        } else if (!arg.empty() && arg[0] == '-') {
            throw UsageError("unknown option '" + arg +
                             "'; valid: --model, --strain-unit, --stress-unit, --ogden-terms, "
                             "--ogden-allow-negative, --max-stretch, --thickness, --out, --curves, "
                             "--force, --help");
        } else if (a.file.empty()) {
            a.file = arg;
        } else {
            throw UsageError("one tensile file expected, got '" + a.file + "' and '" + arg + "'");
        }
    }
    if (a.file.empty())
        throw UsageError(
            "no tensile file given (usage: bagsim fit-material "
            "TENSILE.csv --model M; see --help)");
    if (a.model.empty())
        throw UsageError(
            "--model is required; valid: neo-hookean, mooney-rivlin, yeoh, ogden, all");
    if (a.model != "all") {
        try {
            bags::parseMaterialModel(a.model);
        } catch (const std::invalid_argument&) {
            throw UsageError("--model '" + a.model +
                             "' is not valid; valid: neo-hookean, mooney-rivlin, yeoh, ogden, all");
        }
    }
    for (const std::string* f : {&a.out, &a.curves})
        if (!f->empty() && !a.force && std::filesystem::exists(*f))
            throw UsageError(*f + " exists; use --force to overwrite it or choose another name");
    if (!a.out.empty() && a.out == a.curves)
        throw UsageError("--out and --curves name the same file '" + a.out + "'");
    return a;
}

/// Writes text to path through a temporary file, so an interrupted write leaves no partial
/// file under the final name.
void writeFile(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp);
        if (!f) throw UsageError(path + ": cannot open for writing");
        f << text;
        if (!f.flush()) throw UsageError(path + ": write failed");
    }
    std::filesystem::rename(tmp, path);
}

std::string describeStability(const bags::StabilityRange& s) {
    std::ostringstream os;
    auto cell = [&](double v) {
        std::string c = fmt("%.3f", v);
        if (v >= s.maxChecked) c = ">=" + c;
        return c;
    };
    os << "  stable range of the taut membrane (stretch scanned 1 to " << fmt("%.3g", s.maxChecked)
       << "):\n"
       << "    path          Drucker   rising nominal stress\n";
    const std::pair<const char*, const bags::PathStability*> rows[] = {
        {"uniaxial   ", &s.uniaxial}, {"planar     ", &s.planar}, {"equibiaxial", &s.equibiaxial}};
    for (const auto& r : rows) {
        char line[160];
        std::snprintf(line, sizeof line, "    %s   %-9s %s\n", r.first,
                      cell(r.second->drucker).c_str(), cell(r.second->monotone).c_str());
        os << line;
    }
    const double st = s.getStable();
    os << "  => stable for stretches 1 to " << (st >= s.maxChecked ? ">= " : "") << fmt("%.3f", st)
       << " on all paths (engineering strain " << fmt("%.1f", 100 * (st - 1)) << " %)\n";
    return os.str();
}

std::string describeFit(const bags::MaterialFitResult& r, const bags::TensileData& d,
                        const Args& a) {
    std::ostringstream os;
    double peak = 0.0;
    for (double v : d.stress) peak = std::max(peak, std::abs(v));
    os << "model " << bags::getMaterialModelName(r.model)
       << (r.model == bags::MaterialModel::Ogden
               ? " (bounded nonlinear least squares, " + std::to_string(r.ogdenStarts) +
                     " starts, " + (a.fit.ogdenStableTerms ? "mu_i >= 0, " : "") +
                     "|alpha_i| <= " + fmt("%g", a.fit.ogdenAlphaBound) + ")"
               : std::string(" (linear least squares)"))
       << "\n";
    for (std::size_t i = 0; i < r.constants.size(); ++i)
        os << "  " << formatConstant(r.names[i], r.constants[i]) << "\n";
    os << "  initial shear modulus mu = "
       << fmt("%.5g", r.makeMaterial()->getInitialShearModulus() * 1e-6)
       << " MPa, Young's modulus 3 mu = "
       << fmt("%.5g", 3e-6 * r.makeMaterial()->getInitialShearModulus()) << " MPa\n";
    os << "  fit: RMS error " << fmt("%.4g", r.rmsError * 1e-6) << " MPa ("
       << fmt("%.2f", 100.0 * r.rmsError / peak) << " % of the peak stress), max error "
       << fmt("%.4g", r.maxError * 1e-6) << " MPa, R^2 = " << fmt("%.6f", r.r2) << "\n";
    os << describeStability(r.stability);
    const double lmax = 1.0 + r.maxStrain;
    if (r.stability.uniaxial.getStable() < lmax)
        os << "  warning: the data reach stretch " << fmt("%.3f", lmax)
           << ", beyond the fitted model's stable uniaxial range\n";
    return os.str();
}

/// The scenario's membrane section for a fit; every line prefixed by `prefix` ("# " to comment
/// it out).
std::string makeMembraneSection(const bags::MaterialFitResult& r, const Args& a,
                                const std::string& prefix) {
    std::ostringstream os;
    os << prefix << "membrane:\n" << r.formatScenarioYaml(prefix + "  ");
    if (a.thickness.empty())
        os << prefix
           << "  # thickness: required; the film thickness the stresses were computed "
              "with (--thickness)\n";
    else
        os << prefix << "  thickness: " << a.thickness << "\n";
    return os.str();
}

std::string makeYamlComment(const bags::MaterialFitResult& r, const Args& a) {
    std::ostringstream os;
    os << "# " << bags::getMaterialModelName(r.model) << " fitted by bagsim fit-material to "
       << a.file << " (" << r.numPoints << " points, strain " << fmt("%.3g", 100 * r.minStrain)
       << " to " << fmt("%.3g", 100 * r.maxStrain) << " %): RMS error "
       << fmt("%.4g", r.rmsError * 1e-6) << " MPa, R^2 " << fmt("%.6f", r.r2)
       << "; stable to stretch " << fmt("%.3f", r.stability.getStable()) << "\n";
    return os.str();
}

/// Largest tensile file read [bytes], 10 MiB: a test logged at 100 points a second for an hour
/// is about 7 MiB; a larger file is the wrong file (or a pipe that never ends).
constexpr std::uintmax_t kMaxTensileBytes = 10 * 1024 * 1024;

int run(const Args& a) {
    std::istringstream text(io::readInputFile(a.file, kMaxTensileBytes, "tensile data file"));
    const bags::TensileData data = bags::parseTensileCsv(text, a.file, a.strainUnit, a.stressUnit);
    std::vector<bags::MaterialModel> models;
    if (a.model == "all")
        models = bags::getMaterialModels();
    else
        models = {bags::parseMaterialModel(a.model)};
    double smin = data.stress[0], smax = data.stress[0];
    for (double v : data.stress) {
        smin = std::min(smin, v);
        smax = std::max(smax, v);
    }
    std::vector<bags::MaterialFitResult> fits;
    for (bags::MaterialModel m : models) fits.push_back(bags::fitMaterial(data, m, a.fit));
    const bags::MaterialFitResult& first = fits[0];

    std::cout << "tensile data " << a.file << ": " << first.numPoints << " points, strain "
              << fmt("%.3g", 100 * first.minStrain) << " to " << fmt("%.3g", 100 * first.maxStrain)
              << " %, stress " << fmt("%.4g", smin * 1e-6) << " to " << fmt("%.4g", smax * 1e-6)
              << " MPa\n\n";
    for (const auto& r : fits) std::cout << describeFit(r, data, a) << "\n";

    std::size_t best = 0;
    for (std::size_t i = 1; i < fits.size(); ++i)
        if (fits[i].rmsError < fits[best].rmsError) best = i;
    if (fits.size() > 1) {
        std::cout << "comparison (uniaxial fit; stable = Drucker and rising nominal stress on the "
                     "uniaxial, planar and equibiaxial paths):\n";
        std::printf("  %-14s %12s %10s %12s %14s\n", "model", "RMS [MPa]", "R^2", "max [MPa]",
                    "stable to");
        for (const auto& r : fits)
            std::printf("  %-14s %12.4g %10.6f %12.4g %14.3f\n",
                        bags::getMaterialModelName(r.model).c_str(), r.rmsError * 1e-6, r.r2,
                        r.maxError * 1e-6, r.stability.getStable());
        std::cout << "  least RMS error: " << bags::getMaterialModelName(fits[best].model)
                  << "\n\n";
    }
    std::cout << "scenario form (keys of the scenario's membrane section):\n";
    for (std::size_t i = 0; i < fits.size(); ++i)
        std::cout << (i ? "\n" : "") << makeMembraneSection(fits[i], a, "");
    std::cout.flush();

    if (!a.out.empty()) {
        std::ostringstream os;
        os << makeYamlComment(fits[best], a) << makeMembraneSection(fits[best], a, "");
        for (std::size_t i = 0; i < fits.size(); ++i)
            if (i != best)
                os << "\n# alternative:\n"
                   << makeYamlComment(fits[i], a) << makeMembraneSection(fits[i], a, "# ");
        writeFile(a.out, os.str());
        std::cout << "wrote " << a.out << "\n";
    }
    if (!a.curves.empty()) {
        std::ostringstream os;
        os << "# data " << a.file
           << " and fitted models (engineering stress at the data strains)\n";
        os << "strain,stress_data_MPa";
        for (const auto& r : fits) os << "," << bags::getMaterialModelName(r.model) << "_MPa";
        os << "\n";
        std::vector<std::unique_ptr<bags::MembraneMaterial>> mats;
        for (const auto& r : fits) mats.push_back(r.makeMaterial());
        for (std::size_t i = 0; i < data.strain.size(); ++i) {
            os << fmt("%.6g", data.strain[i]) << "," << fmt("%.7g", data.stress[i] * 1e-6);
            for (const auto& m : mats)
                os << "," << fmt("%.7g", m->calcUniaxialNominalStress(1.0 + data.strain[i]) * 1e-6);
            os << "\n";
        }
        writeFile(a.curves, os.str());
        std::cout << "wrote " << a.curves << "\n";
    }
    return 0;
}

}  // namespace

int runFitMaterialCommand(int argc, char** argv) {
    if (printHelpIfAsked(argc, argv, kHelp)) return 0;
    try {
        const Args a = parseArgs(argc, argv);
        a.fit.validate();
        return run(a);
    } catch (const UsageError& e) {
        std::cerr << "bagsim fit-material: " << e.what() << "\n";
        return 2;
    } catch (const io::InputError& e) {
        std::cerr << "bagsim fit-material: " << e.what() << "\n";
        return 2;
    } catch (const std::invalid_argument& e) {
        std::cerr << "bagsim fit-material: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "bagsim fit-material: fit failed: " << e.what() << "\n";
        return 1;
    }
}

}  // namespace bagsim::app
