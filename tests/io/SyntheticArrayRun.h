#pragma once
// A synthetic patient-on-array results folder for the report's tests, written through the
// run's own writer (io::ArrayResultsWriter), so it has the layout a run writes: a 6 s run on
// 2 x 3 bags, settle 1.5 s, a turn onto his left side to 25 deg at 3.5 s and back to 0 deg at
// 6 s; pressure blobs under the head, shoulders, sacrum and heels that move across the bed with
// the tilt, with the sacrum's pressure known at each frame. Optionally the files another part
// of the run adds (verdict.csv, events.csv, body.csv, pneumatics.csv).
#include <cosim/ArrayReadings.h>
#include <cosim/PressureMat.h>
#include <io/ArrayResults.h>
#include <io/Results.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace io::test {

inline constexpr double kSyntheticMmHg = 133.322387415;

struct SyntheticRun {
    std::vector<double> times;    ///< output times [s]
    std::vector<double> tilt;     ///< [deg] pelvis and thorax alike
    std::vector<double> matPeak;  ///< highest sensel of each frame [mmHg]
};

/// Tilt of the synthetic turn [deg] at time t [s].
inline double getSyntheticTilt(double t) {
    if (t <= 1.5) return 0.0;
    if (t <= 3.5) return 25.0 * (t - 1.5) / 2.0;
    if (t <= 4.5) return 25.0;
    return std::max(0.0, 25.0 * (6.0 - t) / 1.5);
}

/// Writes the folder. `stopAt` < 6 s: the run is interrupted there (status interrupted,
/// INCOMPLETE kept, the last line of regions.csv cut short as a kill would leave it).
inline SyntheticRun writeSyntheticRun(const std::filesystem::path& dir, bool optionalFiles,
                                      double stopAt = 6.0) {
    namespace fs = std::filesystem;
    fs::remove_all(dir);
    const std::string scenario =
        "kind: patient-on-array\n"
        "name: synthetic-turn\n"
        "description: a synthetic turn to 25 deg and back, for the report's tests\n"
        "patient: {sex: male, height: 1.75 m, mass: 75 kg, posture: supine}\n"
        "array: {rows: 2, columns: 3, row_pitch: 360 mm, column_pitch: 105 mm, gas_mass: 4.5 g}\n"
        "run: {duration: 4.5 s}\n";
    SyntheticRun out;
    io::OutputDir outDir(dir, false);
    cosim::PressureMatOptions mo;
    mo.rows = 64;
    mo.columns = 32;
    io::ArrayResultsWriter writer(outDir,
                                  {"synthetic-turn.yaml",
                                   scenario,
                                   {"run.settle_time=1.5 s"},
                                   "bagsim run synthetic-turn.yaml"},
                                  mo);
    cosim::PressureMat mat(mo);
    const double dx = mo.size.x() / mo.rows, dy = mo.size.y() / mo.columns;
    struct Blob {
        std::string region;
        double x, y, rx, ry, mmHg;
    };
    const std::vector<Blob> blobs = {
        {"occiput", 0.80, 0.0, 0.05, 0.05, 30},    {"scapula_l", 0.45, -0.12, 0.08, 0.06, 25},
        {"scapula_r", 0.45, 0.12, 0.08, 0.06, 25}, {"sacrum", 0.0, 0.0, 0.07, 0.07, 45},
        {"heel_l", -0.85, -0.09, 0.04, 0.04, 38},  {"heel_r", -0.85, 0.09, 0.04, 0.04, 38}};
    for (int k = 0; k <= 60; ++k) {
        const double t = 0.1 * k;
        if (t > stopAt + 1e-9) break;
        const double tilt = getSyntheticTilt(t);
        const double shift = -0.004 * tilt;          // turned onto his left: towards y < 0
        const double load = std::min(1.0, t / 0.5);  // lowered onto the bags
        Eigen::Matrix3Xd x(3, mo.rows * mo.columns);
        Eigen::VectorXd p(mo.rows * mo.columns), a = Eigen::VectorXd::Constant(p.size(), dx * dy);
        io::ArrayFrame f;
        f.time = t;
        f.pelvisTilt = f.thoraxTilt = tilt * M_PI / 180.0;
        std::vector<double> regionPeak(blobs.size(), 0.0);
        double peak = 0.0;
        for (int r = 0; r < mo.rows; ++r)
            for (int c = 0; c < mo.columns; ++c) {
                const int i = r * mo.columns + c;
                x.col(i) << mo.origin.x() + (r + 0.5) * dx, mo.origin.y() + (c + 0.5) * dy, 0.0;
                double v = 0.0;
                for (size_t b = 0; b < blobs.size(); ++b) {
                    const Blob& B = blobs[b];
                    // The side he turns onto takes more; the other side less.
                    const double side = 1.0 + 0.02 * tilt * (B.y < 0 ? 1 : B.y > 0 ? -1 : 0.3);
                    const double u = (x(0, i) - B.x) / B.rx, w = (x(1, i) - B.y - shift) / B.ry;
                    const double e = load * std::max(0.0, side) * B.mmHg * std::exp(-u * u - w * w);
                    regionPeak[b] = std::max(regionPeak[b], e);
                    v += e;
                }
                p(i) = v * kSyntheticMmHg;
                peak = std::max(peak, v);
            }
        mat.clear();
        mat.addNodalPressures(x, p, a);
        double matPeak = 0.0;
        for (int r = 0; r < mo.rows; ++r)
            for (int c = 0; c < mo.columns; ++c)
                matPeak = std::max(matPeak, mat.getPressure()(r, c) / kSyntheticMmHg);
        for (size_t b = 0; b < blobs.size(); ++b)
            if (regionPeak[b] > 0.1)
                f.regions.push_back({blobs[b].region, regionPeak[b] * kSyntheticMmHg,
                                     0.5 * regionPeak[b] * kSyntheticMmHg,
                                     0.01 * regionPeak[b] / 40, 10.0 * regionPeak[b] / 40});
        for (int b = 0; b < 6; ++b) {
            const int column = b % 3;
            const double dm = (column == 2 ? 0.5 : column == 0 ? -0.5 : 0.0) * tilt / 25.0;
            f.bags.push_back({b, (4.5 + dm) * 1e-3,
                              (2.0 + 0.04 * tilt * (column == 0 ? 1 : -1)) * 1e3, 3.0e-3,
                              120.0 * load});
        }
        f.mat = &mat;
        if (optionalFiles) {  // what a run with pneumatics writes besides
            f.centreOfMass << 0.01, -1.5e-3 * tilt, 0.18 - 0.2e-3 * tilt;
            for (int b = 0; b < 6; ++b)
                f.pneumatics.push_back({b, (2.0 + 0.03 * tilt * (b % 3 == 0 ? 1 : -1)) * 1e3,
                                        b % 3 == 2 && tilt > 0 ? 0.25e-3 : 0.0,
                                        b % 3 == 0 && tilt > 0 ? 0.25e-3 : 0.0});
            for (const auto& [at, text] : std::vector<std::pair<double, std::string>>{
                     {1.5, "settle ended; turn to the left starts"},
                     {3.5, "target tilt reached"},
                     {4.5, "back to supine starts"}})
                if (std::fabs(t - at) < 1e-9) writer.addEvent(t, text);
        }
        writer.addFrame(f);
        out.times.push_back(t);
        out.tilt.push_back(tilt);
        out.matPeak.push_back(matPeak);
    }
    if (optionalFiles) {  // the verdict, as a run writes it at its end
        const double nan = std::numeric_limits<double>::quiet_NaN();
        writer.writeVerdict(
            {{"target tilt reached", "ok", 25.0, "deg", "at 3.50 s (target 25 deg)"},
             {"centre of mass travel", "warning", 42, "mm", "towards the left edge"},
             {"bag bottomed out", "fail", 1, "bags", "bag 0 under the sacrum, 2.1 s to 3.4 s"},
             {"sacrum time above 32 mmHg", "n/a", nan, "s", "not measured"}});
    }
    if (stopAt < 6.0) {
        writer.fail("interrupted",
                    "interrupted by SIGINT (Ctrl-C) at " + std::to_string(stopAt) + " s");
        std::ofstream(dir / "regions.csv", std::ios::app) << "9.9,sacr";  // cut short by the kill
    } else {
        std::ofstream(dir / "summary.txt") << "synthetic summary: the bags carry his weight\n";
        writer.finish("6 s simulated");
    }
    return out;
}

}  // namespace io::test
