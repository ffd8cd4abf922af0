// bagsim run, kind patient-on-support: the patient settled on a rigid flat support.
#include "PatientRun.h"
#include "Format.h"

#include <bagsim/Version.h>
#include <body/SettleOnSupport.h>
#include <io/InputError.h>
#include <io/PatientScenario.h>
#include <io/ResultFiles.h>
#include <io/Results.h>
#include <io/Units.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "Interrupt.h"

namespace bagsim::app {

namespace {

std::string describePatient(const body::PatientSpec& p) {
    std::ostringstream os;
    os << body::getSexName(p.sex) << ", " << fmt("%.3f", p.height) << " m, " << fmt("%.1f", p.mass)
       << " kg (BMI " << fmt("%.1f", p.getBmi()) << "), " << body::getPostureName(p.posture);
    if (p.posture == body::Posture::HeadOfBedRaised)
        os << " " << fmt("%.0f", p.headOfBedAngle * 180.0 / 3.14159265358979323846) << " deg";
    os << ", mid-hip at (" << fmt("%.3f", p.position[0]) << ", " << fmt("%.3f", p.position[1])
       << ") m";
    return os.str();
}

}  // namespace

int runPatientOnSupport(const io::ScenarioFile& file, const std::string& out, bool force,
                        bool quiet) {
    io::PatientOnSupportScenario sc;
    std::filesystem::path outPath;
    std::unique_ptr<io::OutputDir> outDir;
    try {
        sc = io::readPatientOnSupportScenario(file);
        outPath = out.empty() ? std::filesystem::path("out") / sc.name : std::filesystem::path(out);
        outDir = std::make_unique<io::OutputDir>(outPath, force);
    } catch (const io::InputError& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    }
    body::SettleOptions& o = sc.settle;
    // SIGINT or SIGTERM (InterruptGuard in RunCommand.cpp) stops the settle within 0.1 s of
    // simulated time.
    double settled = 0.0;
    o.monitor = [&settled](double t) {
        settled = t;
        throwIfInterrupted();
    };
    const std::string patient = describePatient(sc.patient);
    if (!quiet)
        std::cerr << "bagsim " << bagsim::kVersion << ": " << file.getFileName() << " (" << sc.name
                  << ")\n  patient " << patient << "\n  rigid flat support: "
                  << io::formatSignificant(o.support.stiffness, "Pa/m") << ", friction "
                  << fmt("%g", o.support.friction) << "; settling for " << fmt("%g", o.settleTime)
                  << " s\n  writing to " << outPath.string()
                  << "/ (Ctrl-C stops and marks it INCOMPLETE)\n";

    body::SettleReport r;
    try {
        outDir->setStatus("running", "settling the patient on the flat support");
        r = body::settleOnSupport(sc.patient, o);
    } catch (const Interrupted& e) {
        // The loads are known only once the patient has settled: nothing to keep but the mark.
        const std::string msg = std::string(e.what()) + " at " + fmt("%.1f", settled) + " s of " +
                                fmt("%g", o.settleTime) + " s settling; no loads written";
        outDir->setStatus("interrupted", msg);
        std::cerr << "bagsim: " << msg << " (" << outPath.string() << "/ marked INCOMPLETE)\n";
        return getInterruptExitCode(e.signal);
    } catch (const std::exception& e) {
        outDir->setStatus("failed", e.what());
        std::cerr << "bagsim: run failed: " << e.what() << "\n";
        return 1;
    }

    const double support = r.load.force[2];
    std::ostringstream table;
    table << "support force " << fmt("%.1f", support) << " N vs body weight "
          << fmt("%.1f", r.weight) << " N (" << fmt("%.2f", r.mass) << " kg): ratio "
          << fmt("%.5f", support / r.weight) << " (" << fmt("%+.3f", 100 * (support / r.weight - 1))
          << " %)\n";
    table << "after " << fmt("%g", r.simulatedTime) << " s: pelvis drift over the last 0.5 s "
          << fmt("%.2e", r.drift) << " m, largest segment speed " << fmt("%.2e", r.maxSpeed)
          << " m/s; contact area " << fmt("%.4f", r.load.contactArea) << " m^2, peak pressure "
          << fmt("%.1f", r.load.peakPressure * 1e-3) << " kPa\n";
    table << "share of the body weight per region:\n";
    table << "  region           force [N]  share [%]  peak [kPa]\n";
    std::ostringstream csv;
    csv << io::kRegionLoadsHeader << "\n";
    for (std::size_t i = 0; i < r.regionNames.size(); ++i) {
        const double f = r.load.regionForce[i];
        csv << r.regionNames[i] << "," << fmt("%.4f", f) << "," << fmt("%.4f", 100 * f / r.weight)
            << "\n";
        if (f <= 0) continue;
        char line[128];
        std::snprintf(line, sizeof line, "  %-15s %10.1f %10.1f %11.1f\n", r.regionNames[i].c_str(),
                      f, 100 * f / r.weight, r.load.regionPeakPressure[i] * 1e-3);
        table << line;
    }
    csv << "other," << fmt("%.4f", r.load.otherForce) << ","
        << fmt("%.4f", 100 * r.load.otherForce / r.weight) << "\n";
    char line[128];
    std::snprintf(line, sizeof line, "  %-15s %10.1f %10.1f\n", "(no region)", r.load.otherForce,
                  100 * r.load.otherForce / r.weight);
    table << line;

    try {
        std::ofstream c(outDir->getFile(io::kRegionLoadsCsv));
        c << csv.str();
        std::ofstream s(outDir->getFile("summary.txt"));
        s << "bagsim " << bagsim::kVersion << " patient-on-support: " << file.getFileName() << " ("
          << sc.name << ")\n";
        if (!sc.description.empty()) s << sc.description << "\n";
        s << "patient " << patient << "\n"
          << "support: flat, rigid, stiffness " << fmt("%g", o.support.stiffness)
          << " Pa/m, damping " << fmt("%g", o.support.damping) << " Pa s/m, friction "
          << fmt("%g", o.support.friction)
          << (o.support.frictionLaw == body::SupportFrictionLaw::StickSlip
                  ? fmt(" (stick-slip, %g mm)", 1e3 * o.support.stickDistance)
                  : fmt(" (regularised, %g mm/s)", 1e3 * o.support.slipVelocity))
          << "; settle time " << fmt("%g", o.settleTime) << " s, " << r.steps
          << " integrator steps, " << fmt("%.2f", r.wallSeconds) << " s wall-clock\n"
          << table.str();
        c.close();
        s.close();
        if (!c || !s) throw std::runtime_error("cannot write into " + outPath.string());
    } catch (const std::exception& e) {
        outDir->setStatus("failed", e.what());
        std::cerr << "bagsim: run failed: " << e.what() << "\n";
        return 1;
    }
    outDir->markComplete();
    std::cout << table.str() << "\nsettled in " << fmt("%.1f", r.wallSeconds) << " s; results in "
              << outPath.string() << "/:\n  region_loads.csv  region,force_N,share_percent\n"
              << "  summary.txt       patient, support, force balance, shares\n";
    return 0;
}

}  // namespace bagsim::app
