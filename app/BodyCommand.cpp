// bagsim body: prints the patient's segment table (de Leva 1996 scaled to sex, height, mass).
#include <body/Anthropometry.h>
#include <body/BodyModel.h>
#include <body/PatientSpec.h>
#include <io/InputError.h>
#include <io/PatientScenario.h>
#include <io/Scenario.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <string>

#include "Commands.h"

namespace bagsim::app {
namespace {

const char* kBodyUsage =
    "usage: bagsim body --sex female|male --height H --mass M [--format table|csv]\n"
    "       bagsim body --scenario FILE.yaml [--format table|csv]\n"
    "\n"
    "Prints the patient model's segment table: de Leva (1996) segment masses, centres of mass\n"
    "and principal moments of inertia scaled to the given sex, height and mass, and the size of\n"
    "each segment's contact shape (which grows with BMI). See docs/body.md.\n"
    "\n"
    "options:\n"
    "  --sex S        female or male (selects the de Leva table)\n"
    "  --height H     stature in metres, 1.4 to 2.1\n"
    "  --mass M       body mass in kilograms; BMI = M / H^2 must be 14 to 50\n"
    "  --scenario F   take the patient from the scenario's patient section (units as\n"
    "                 written there, e.g. height: 1.62 m; docs/scenario-reference.md)\n"
    "  --format F     table (default) or csv\n"
    "  --help         this text\n"
    "\n"
    "Body frames: origin at the joint with the parent segment (mid-hip point for the lower\n"
    "trunk), X anterior, Y superior, Z to the patient's right in the standing reference.\n";

int fail(const std::string& msg) {
    std::cerr << "bagsim body: " << msg << "\n";
    return 2;
}

// Parses a whole string as a number; false if anything is left over.
bool parseNumber(const std::string& text, double& value) {
    try {
        std::size_t used = 0;
        value = std::stod(text, &used);
        return used == text.size();
    } catch (const std::exception&) {
        return false;
    }
}

std::string replaceKey(std::string msg) {
    for (const char* key : {"sex", "height", "mass"}) {
        const std::string from = std::string("patient.") + key;
        const auto pos = msg.find(from);
        if (pos != std::string::npos) msg.replace(pos, from.size(), std::string("--") + key);
    }
    return msg;
}

void printTable(const body::BodyModel& model) {
    const body::Anthropometry& a = model.getAnthropometry();
    const body::DeLevaReference ref = body::getDeLevaReference(a.sex);
    std::printf("patient: %s, height %.3f m, mass %.1f kg, BMI %.1f kg/m^2\n",
                body::getSexName(a.sex), a.height, a.mass, a.bmi);
    std::printf("table: de Leva (1996) %s (reference %.3f m, %.1f kg); lengths x %.4f\n",
                body::getSexName(a.sex), ref.stature, ref.mass, a.lengthScale);
    std::printf("frames: origin at the proximal joint, X anterior, Y superior, Z right\n\n");
    std::printf("%-13s %8s %7s %23s %29s  %s\n", "segment", "mass", "length", "CoM x y z",
                "inertia Ixx Iyy Izz (CoM)", "contact shape");
    std::printf("%-13s %8s %7s %23s %29s  %s\n", "", "[kg]", "[m]", "[m]", "[kg m^2]", "[m]");
    double total = 0;
    for (int i = 0; i < body::kSegmentCount; ++i) {
        const body::SegmentParameters& p = a.segments[i];
        total += p.mass;
        const body::ShapeSize& s = p.shape;
        char shape[160];
        if (s.kind == body::ShapeKind::Ellipsoid)
            std::snprintf(shape, sizeof shape, "ellipsoid semi-axes %.3f %.3f %.3f", s.semiAxes[0],
                          s.semiAxes[1], s.semiAxes[2]);
        else
            std::snprintf(shape, sizeof shape, "round cone radii %.3f %.3f, axis %.3f", s.radiusA,
                          s.radiusB, (s.pointB - s.pointA).norm());
        std::printf("%-13s %8.3f %7.4f %7.4f %7.4f %7.4f %9.5f %9.5f %9.5f  %s\n",
                    body::getSegmentName(p.segment), p.mass, p.length, p.p_BC[0], p.p_BC[1],
                    p.p_BC[2], p.inertiaC[0], p.inertiaC[1], p.inertiaC[2], shape);
    }
    std::printf("%-13s %8.3f\n\n", "total", total);
    const body::BodyBuild& b = a.build;
    std::printf(
        "build [m]: shoulder breadth %.3f, chest breadth %.3f depth %.3f, waist breadth "
        "%.3f depth %.3f,\n",
        b.shoulderBreadth, b.chestBreadth, b.chestDepth, b.waistBreadth, b.waistDepth);
    std::printf(
        "           hip breadth %.3f, pelvis depth %.3f, buttock depth %.3f, head %.3f x "
        "%.3f,\n",
        b.hipBreadth, b.pelvisDepth, b.buttockDepth, b.headLength, b.headBreadth);
    std::printf(
        "           joint separation shoulders %.3f hips %.3f, ankle height %.3f, model "
        "stature %.3f\n",
        b.shoulderJointSeparation, b.hipJointSeparation, b.ankleHeight, b.modelStature);
}

void printCsv(const body::BodyModel& model) {
    const body::Anthropometry& a = model.getAnthropometry();
    std::printf(
        "segment,mass_kg,length_m,com_x_m,com_y_m,com_z_m,Ixx_kgm2,Iyy_kgm2,Izz_kgm2,"
        "shape,semi_x_m,semi_y_m,semi_z_m,radius_a_m,radius_b_m,axis_length_m\n");
    for (int i = 0; i < body::kSegmentCount; ++i) {
        const body::SegmentParameters& p = a.segments[i];
        const body::ShapeSize& s = p.shape;
        const bool ell = s.kind == body::ShapeKind::Ellipsoid;
        std::printf("%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%s,",
                    body::getSegmentName(p.segment), p.mass, p.length, p.p_BC[0], p.p_BC[1],
                    p.p_BC[2], p.inertiaC[0], p.inertiaC[1], p.inertiaC[2],
                    ell ? "ellipsoid" : "round_cone");
        if (ell)
            std::printf("%.6g,%.6g,%.6g,,,\n", s.semiAxes[0], s.semiAxes[1], s.semiAxes[2]);
        else
            std::printf(",,,%.6g,%.6g,%.6g\n", s.radiusA, s.radiusB, (s.pointB - s.pointA).norm());
    }
}

}  // namespace

int runBodyCommand(int argc, char** argv) {
    std::string sex, height, mass, scenario, format = "table";
    for (int i = 0; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "--help" || arg == "-h") {
            std::cout << kBodyUsage;
            return 0;
        }
        std::string value;
        const auto eq = arg.find('=');
        if (arg.rfind("--", 0) == 0 && eq != std::string::npos) {
            value = arg.substr(eq + 1);
            arg = arg.substr(0, eq);
        } else if (arg == "--sex" || arg == "--height" || arg == "--mass" || arg == "--format" ||
                   arg == "--scenario") {
            if (i + 1 >= argc) return fail(arg + " needs a value (see bagsim body --help)");
            value = argv[++i];
        } else {
            return fail("unknown argument '" + arg +
                        "'; valid: --sex, --height, --mass, --scenario, --format, --help");
        }
        if (arg == "--sex")
            sex = value;
        else if (arg == "--height")
            height = value;
        else if (arg == "--mass")
            mass = value;
        else if (arg == "--format")
            format = value;
        else if (arg == "--scenario")
            scenario = value;
        else
            return fail("unknown option '" + arg +
                        "'; valid: --sex, --height, --mass, --scenario, --format, --help");
    }
    if (format != "table" && format != "csv")
        return fail("--format: '" + format + "' is not valid; use table or csv");
    if (!scenario.empty()) {
        if (!sex.empty() || !height.empty() || !mass.empty())
            return fail("--scenario gives the patient; leave out --sex, --height and --mass");
        try {
            const io::ScenarioFile file = io::ScenarioFile::load(scenario);
            const body::BodyModel model(io::readScenarioPatient(file));
            if (format == "csv")
                printCsv(model);
            else
                printTable(model);
        } catch (const io::InputError& e) {
            std::cerr << "bagsim: error: " << e.what() << "\n";
            return 2;
        }
        return 0;
    }
    if (sex.empty()) return fail("--sex is required: female or male (or give --scenario FILE)");
    if (height.empty()) return fail("--height is required: stature in metres, 1.4 to 2.1");
    if (mass.empty()) return fail("--mass is required: body mass in kilograms (BMI 14 to 50)");
    if (format != "table" && format != "csv")
        return fail("--format: '" + format + "' is not valid; use table or csv");
    body::PatientSpec spec;
    try {
        spec.sex = body::parseSex(sex);
    } catch (const std::invalid_argument&) {
        return fail("--sex: '" + sex + "' is not valid; use female or male");
    }
    if (!parseNumber(height, spec.height))
        return fail("--height: '" + height +
                    "' is not a number; give the stature in metres, 1.4 to 2.1");
    if (!parseNumber(mass, spec.mass))
        return fail("--mass: '" + mass + "' is not a number; give the body mass in kilograms");
    try {
        spec.validate();
        const body::BodyModel model(spec);
        if (format == "csv")
            printCsv(model);
        else
            printTable(model);
    } catch (const std::invalid_argument& e) {
        return fail(replaceKey(e.what()));
    }
    return 0;
}

}  // namespace bagsim::app
