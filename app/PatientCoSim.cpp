#include "PatientCoSim.h"

#include <body/Anthropometry.h>
#include <body/Regions.h>
#include <io/PatientMeasuredData.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "ArrayRun.h"
#include "DiagnoseShared.h"
#include "Interrupt.h"

namespace bagsim::app {

diagnose::PatientChannels runCoSimulation(const io::ScenarioFile& file, const std::string& dir) {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    ArrayRunControl control;
    control.force = true;
    control.quiet = true;
    control.silent = true;
    control.commandLine = "(co-simulation of the diagnosis)";
    const int rc = runPatientOnArray(file, dir, control);
    if (rc == 130 || rc == 143) throw Interrupted(rc == 130 ? 2 : 15);
    if (rc != 0)
        throw std::runtime_error("the co-simulation in " + dir + " failed (exit status " +
                                 std::to_string(rc) + "; its summary.txt says why)");
    return io::readArrayRunChannels(dir);
}

diagnose::MatRegions makeMatRegions(const io::PatientOnArrayScenario& sc) {
    diagnose::MatRegions m;
    const cosim::PressureMatOptions& mat = sc.mat;
    const size_t n = size_t(mat.rows) * size_t(mat.columns);
    if (sc.patient.posture != body::Posture::Supine) {
        m.names = {"whole mat"};
        m.sensel.assign(n, 0);
        return m;
    }
    const body::Anthropometry a =
        body::calcAnthropometry(sc.patient.sex, sc.patient.height, sc.patient.mass);
    struct Centre {
        int region;
        double x, y, r;
    };
    std::vector<Centre> centres;
    for (const body::BodyRegion& reg : body::makeBodyRegions(a)) {
        // On his back: the region's centre behind his frontal plane (standing X anterior).
        if (!(reg.centre_W[0] < 0.0)) continue;
        centres.push_back({int(m.names.size()), sc.patient.position[0] + reg.centre_W[1],
                           sc.patient.position[1] + reg.centre_W[2], reg.radius});
        m.names.push_back(reg.name);
    }
    const int elsewhere = int(m.names.size());
    m.names.push_back("elsewhere");
    const double px = mat.size.x() / mat.rows, py = mat.size.y() / mat.columns;
    m.sensel.assign(n, elsewhere);
    for (int r = 0; r < mat.rows; ++r)
        for (int c = 0; c < mat.columns; ++c) {
            const double x = mat.origin.x() + (r + 0.5) * px, y = mat.origin.y() + (c + 0.5) * py;
            double best = std::numeric_limits<double>::infinity();
            for (const Centre& k : centres) {
                const double d = std::hypot(x - k.x, y - k.y);
                if (d <= 1.5 * k.r && d / k.r < best) best = d / k.r, m.sensel[size_t(r) * mat.columns + c] = k.region;
            }
        }
    return m;
}

std::string formatHalfMacroStep(const io::PatientOnArrayScenario& sc) {
    return fmt("%.9g", 0.5 * sc.options.coupling.macroStep * 1e3) + " ms";
}

}  // namespace bagsim::app
