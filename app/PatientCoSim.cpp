#include "PatientCoSim.h"

#include <body/Anthropometry.h>
#include <body/Regions.h>
#include <io/PatientMeasuredData.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

extern char** environ;

#include "DiagnoseShared.h"
#include "Interrupt.h"

namespace bagsim::app {

diagnose::PatientChannels runCoSimulation(const io::ScenarioFile& file, const std::string& dir) {
    // A child process (`bagsim run`), not a call in this one: co-simulations run one after
    // another in one process are not independent (after a run at 5 ms macro steps, the same
    // 10 ms run differs by 2 % in a bag's force at its first output), and a child is the run a
    // user would make of the same scenario.
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    std::filesystem::create_directories(std::filesystem::path(dir).parent_path(), ec);
    const std::string log = dir + ".log";
    std::vector<std::string> args = {"bagsim", "run", file.getFileName(), "--out", dir, "--quiet"};
    for (const std::string& o : file.getOverrides()) args.insert(args.end(), {"--set", o});
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = 0;
    const int err = posix_spawn(&pid, "/proc/self/exe", &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (err != 0)
        throw std::runtime_error(std::string("cannot start the co-simulation (") +
                                 std::strerror(err) + ")");
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) throw std::runtime_error("lost the co-simulation's process");
    const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (rc == 129 || rc == 130 || rc == 143) throw Interrupted(rc - 128);
    throwIfInterrupted();
    if (rc != 0)
        throw std::runtime_error("the co-simulation in " + dir + " failed (exit status " +
                                 std::to_string(rc) + "; " + log + " says why)");
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
    // Elsewhere under him: the segment whose centre of mass is nearest (as regions.csv counts
    // nodes in no region under their segment's name), within kSegmentReach.
    constexpr double kSegmentReach = 0.3;  // [m]
    std::vector<Centre> segments;
    for (int k = 0; k < body::kSegmentCount; ++k) {
        const body::SegmentParameters& sp = a.get(static_cast<body::Segment>(k));
        const SimTK::Vec3 c = sp.p_WO + sp.p_BC;
        segments.push_back({int(m.names.size()), sc.patient.position[0] + c[1],
                            sc.patient.position[1] + c[2], kSegmentReach});
        m.names.push_back(body::getSegmentName(static_cast<body::Segment>(k)));
    }
    const int offBody = int(m.names.size());
    m.names.push_back("off the body");
    const double px = mat.size.x() / mat.rows, py = mat.size.y() / mat.columns;
    m.sensel.assign(n, offBody);
    for (int r = 0; r < mat.rows; ++r)
        for (int c = 0; c < mat.columns; ++c) {
            const double x = mat.origin.x() + (r + 0.5) * px, y = mat.origin.y() + (c + 0.5) * py;
            int& region = m.sensel[size_t(r) * mat.columns + c];
            double best = std::numeric_limits<double>::infinity();
            for (const Centre& k : centres) {
                const double d = std::hypot(x - k.x, y - k.y);
                if (d <= 1.5 * k.r && d / k.r < best) best = d / k.r, region = k.region;
            }
            if (region != offBody) continue;
            for (const Centre& k : segments) {
                const double d = std::hypot(x - k.x, y - k.y);
                if (d <= k.r && d < best) best = d, region = k.region;
            }
        }
    return m;
}

std::string formatHalfMacroStep(const io::PatientOnArrayScenario& sc) {
    return fmt("%.9g", 0.5 * sc.options.coupling.macroStep * 1e3) + " ms";
}

}  // namespace bagsim::app
