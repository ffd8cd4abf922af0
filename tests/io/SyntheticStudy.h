#pragma once
// Synthetic study folders for the study report's tests, written through the study's own table
// writers (io::writeStudyCsv, io::writeStudyH5), with the layout bagsim study leaves: the stamp,
// study.csv, study.h5, cases/<key>/load_displacement.csv and, when cases are missing,
// INCOMPLETE. Two studies of the array-coupling page (docs/array-coupling.md):
// - the map: airbag.neighbours.pressed over six positions of a 3 x 3 block x two gas masses
//   (12 cases; the middle column 1.8 % stiffer than the edge column); the last case failed;
//   `incomplete` leaves the one before it not run;
// - the coupling: layout none / pair / row3 x own gas mass x neighbours' gas mass (12 cases);
//   a neighbour changes the stiffness by 4 % per 0.5 g it holds above the pressed bag, two
//   neighbours by twice that.
#include <io/StudyTable.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace io::test {

inline std::string formatSyntheticNumber(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.10g", v);
    return b;
}

/// The bag's stiffness [N/mm] in the synthetic map at a position and gas mass [g].
inline double getSyntheticMapStiffness(int across, double gasMass) {
    const double base = gasMass > 3.25 ? 3.553 : 1.825;
    return across == 0 ? base * 1.018 : base;
}

/// The bag's stiffness [N/mm] in the synthetic coupling study.
inline double getSyntheticCouplingStiffness(const std::string& layout, double own, double nb) {
    const double alone = own > 3.25 ? 3.545 : 1.608;
    const double perNeighbour = 0.04 * (nb - own) / 0.5;
    const double n = layout == "pair" ? 1.0 : layout == "row3" ? 2.0 : 0.0;
    return alone * (1.0 + n * perNeighbour);
}

/// One case's load_displacement.csv: loading to 36 N along a line of the case's stiffness.
inline void writeSyntheticCurve(const std::filesystem::path& dir, double gasMass, double k) {
    std::filesystem::create_directories(dir);
    std::ofstream f(dir / "load_displacement.csv");
    f << "gas_mass_g,displacement_mm,force_N,pressure_kPa,branch\n";
    for (int i = 0; i <= 20; ++i) {
        const double d = 36.0 / k * i / 20.0;
        f << formatSyntheticNumber(gasMass) << "," << formatSyntheticNumber(d) << ","
          << formatSyntheticNumber(k * d) << ",18.3,loading\n";
    }
}

inline void writeSyntheticStudyFiles(const std::filesystem::path& dir, StudyTable& t,
                                     const std::string& studyFile) {
    namespace fs = std::filesystem;
    fs::create_directories(dir / "cases");
    std::ofstream(dir / ".bagsim-study")
        << "A bagsim study folder\nlast study: " << studyFile << "\n";
    t.studyFile = studyFile;
    t.baseText = "kind: seed-load-test\n";
    t.commandLine = "bagsim study " + studyFile + " --out " + dir.string();
    writeStudyCsv(t, (dir / "study.csv").string());
    writeStudyH5(t, (dir / "study.h5").string());
    if (t.status != "complete")
        std::ofstream(dir / "INCOMPLETE")
            << "This study's table is incomplete: 1 of " << t.rows.size()
            << " cases have not run.\nstatus: " << t.status << "\n";
}

/// The map study (12 cases). Returns the folder's table as written.
inline StudyTable writeSyntheticMapStudy(const std::filesystem::path& dir, bool incomplete) {
    StudyTable t;
    t.header = {"case",
                "key",
                "airbag.neighbours.pressed",
                "test.gas_masses [g]",
                "status",
                "reason",
                "seconds",
                "stiffness_N_per_mm",
                "r2",
                "pressure_kPa"};
    t.studyText =
        "kind: study\ndescription: stiffness map of a synthetic 3 x 3 block\n"
        "scenario: seed-load-test.yaml\nset:\n  airbag.neighbours.layout: block3x3\n"
        "parameters:\n  grid:\n    airbag.neighbours.pressed: [[-1, 0], [0, 0], [1, 0], "
        "[-1, 1], [0, 1], [1, 1]]\n    test.gas_masses: [[3.5 g], [3.0 g]]\noutputs:\n"
        "  - {file: stiffness.csv, column: stiffness_N_per_mm}\n"
        "  - {file: stiffness.csv, column: r2}\n"
        "  - {file: load_displacement.csv, column: pressure_kPa, reduce: first}\n";
    const int positions[6][2] = {{-1, 0}, {0, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};
    std::filesystem::remove_all(dir);
    int n = 0;
    for (const auto& p : positions)
        for (double m : {3.5, 3.0}) {
            ++n;
            char key[17];
            std::snprintf(key, sizeof key, "%016x", 0xa000 + n);
            const std::string pos = "[" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + "]";
            const double k = getSyntheticMapStiffness(p[1], m);
            std::vector<std::string> row = {std::to_string(n), key, pos, formatSyntheticNumber(m)};
            if (n == 12) {
                row.insert(row.end(), {"failed",
                                       "numerical failure: no convergence while inflating the "
                                       "airbag (before the first step) (exit status 1)",
                                       "3.1", "", "", ""});
            } else if (n == 11 && incomplete) {
                row.insert(row.end(), {"not-run", "", "", "", "", ""});
            } else {
                row.insert(row.end(), {"ok", "", "12.5", formatSyntheticNumber(k), "0.9991",
                                       formatSyntheticNumber(m > 3.25 ? (p[1] ? 19.09 : 19.72)
                                                                      : (p[1] ? 5.35 : 5.67))});
                writeSyntheticCurve(dir / "cases" / key, m, k);
            }
            t.rows.push_back(row);
        }
    t.status = incomplete ? "incomplete" : "complete";
    writeSyntheticStudyFiles(dir, t, "scenarios/array-stiffness-map.yaml");
    return t;
}

/// The coupling study (12 cases, all ok).
inline StudyTable writeSyntheticCouplingStudy(const std::filesystem::path& dir) {
    StudyTable t;
    t.header = {"case",
                "key",
                "airbag.neighbours.layout",
                "test.gas_masses [g]",
                "airbag.neighbours.gas_mass [g]",
                "status",
                "reason",
                "seconds",
                "stiffness_N_per_mm",
                "r2"};
    t.studyText =
        "kind: study\ndescription: synthetic array coupling\nscenario: "
        "seed-load-test.yaml\nparameters:\n  grid:\n    airbag.neighbours.layout: "
        "[none, pair, row3]\n    test.gas_masses: [[3.5 g], [3.0 g]]\n"
        "    airbag.neighbours.gas_mass: [3.5 g, 3.0 g]\n";
    std::filesystem::remove_all(dir);
    int n = 0;
    for (const char* layout : {"none", "pair", "row3"})
        for (double own : {3.5, 3.0})
            for (double nb : {3.5, 3.0}) {
                ++n;
                char key[17];
                std::snprintf(key, sizeof key, "%016x", 0xc000 + n);
                t.rows.push_back(
                    {std::to_string(n), key, layout, formatSyntheticNumber(own),
                     formatSyntheticNumber(nb), "ok", "", "20.0",
                     formatSyntheticNumber(getSyntheticCouplingStiffness(layout, own, nb)),
                     "0.999"});
            }
    t.status = "complete";
    writeSyntheticStudyFiles(dir, t, "scenarios/array-coupling-study.yaml");
    return t;
}

}  // namespace io::test
