#include "io/ReducedBagFile.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "io/InputError.h"
#include "io/Units.h"

namespace io {

namespace {

constexpr const char* kMagic = "bagsim-reduced-bag";

struct Reader {
    std::string path;
    std::vector<std::string> lines;
    int line = 0;  // 1-based of the record being read
    [[noreturn]] void fail(const std::string& record, const std::string& msg) const {
        throw InputError(path, line, record, msg);
    }
};

double toNumber(const Reader& r, const std::string& record, const std::string& s) {
    if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
    try {
        size_t used = 0;
        const double v = std::stod(s, &used);
        if (used == s.size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
    r.fail(record, "\"" + s + "\" is not a number (SI units, e.g. 0.035; nan only in top rows)");
}

std::vector<double> numbers(const Reader& r, const std::string& record, std::istringstream& in,
                            int count) {
    std::vector<double> v;
    std::string tok;
    while (in >> tok) v.push_back(toNumber(r, record, tok));
    if (count >= 0 && int(v.size()) != count)
        r.fail(record, std::to_string(v.size()) + " values; valid: " + std::to_string(count));
    return v;
}

}  // namespace

std::shared_ptr<const cosim::ReducedBagCalibration> readReducedBagCalibration(
    const std::string& path) {
    Reader r;
    r.path = path;
    std::ifstream f(path);
    if (!f) throw InputError(path, 0, "", "cannot open the reduced bag's calibration file");
    for (std::string s; std::getline(f, s);) r.lines.push_back(s);
    auto c = std::make_shared<cosim::ReducedBagCalibration>();
    bool magic = false, geometry = false, grid = false, depths = false, envelope = false;
    std::vector<std::pair<int, Eigen::VectorXd>> kappa, beta;
    for (size_t i = 0; i < r.lines.size(); ++i) {
        r.line = int(i) + 1;
        std::istringstream in(r.lines[i]);
        std::string rec;
        if (!(in >> rec) || rec[0] == '#') continue;
        if (!magic) {
            if (rec != kMagic)
                r.fail("", "not a reduced bag calibration (its first record must be '" +
                               std::string(kMagic) + " 2')");
            const std::vector<double> v = numbers(r, rec, in, 1);
            if (v[0] == 1.0)
                r.fail(rec,
                       "format version 1: its volume factors were measured with the overlap "
                       "volume of the reduced bag before version 2 (normal depths against the "
                       "sagged top of a slack bag); valid: 2, made by bench_reduced_bag "
                       "calibrate (docs/reduced-bag.md#calibration)");
            if (v[0] != 2.0) r.fail(rec, "format version " + std::to_string(v[0]) + "; valid: 2");
            magic = true;
        } else if (rec == "source") {
            std::string rest;
            std::getline(in, rest);
            const size_t from = rest.find_first_not_of(' ');
            c->source += (c->source.empty() ? "" : "\n") +
                         (from == std::string::npos ? std::string() : rest.substr(from));
        } else if (rec == "geometry") {
            const std::vector<double> v = numbers(r, rec, in, 6);
            c->geometry.longSide = v[0], c->geometry.shortSide = v[1], c->geometry.width = v[2];
            c->geometry.height = v[3], c->geometry.meshSize = v[4],
            c->geometry.diaphragm = v[5] != 0.0;
            geometry = true;
        } else if (rec == "gas") {
            const std::vector<double> v = numbers(r, rec, in, 3);
            c->gasConstant = v[0], c->temperature = v[1], c->ambientPressure = v[2];
        } else if (rec == "board_penalty") {
            c->boardPenalty = numbers(r, rec, in, 1)[0];
        } else if (rec == "rim_width") {
            c->rimWidth = numbers(r, rec, in, 1)[0];
        } else if (rec == "skirt") {
            c->skirt = numbers(r, rec, in, 1)[0];
        } else if (rec == "panel_coupling") {
            const std::vector<double> v = numbers(r, rec, in, 3);
            c->panelSink = v[0], c->panelLift = v[1], c->panelBlend = v[2];
            if (!(v[0] >= 0.0 && v[0] < 1e-3 && v[1] >= 0.0 && v[1] < 1e-3 && v[2] > 0.0))
                r.fail(rec, "sink and lift [m/N] must be in [0, 1e-3), the blend [m] > 0");
        } else if (rec == "grid") {
            const std::vector<double> v = numbers(r, rec, in, 5);
            c->nx = int(v[0]), c->ny = int(v[1]), c->x0 = v[2], c->y0 = v[3], c->pitch = v[4];
            if (c->nx < 2 || c->ny < 2 || c->nx > 1000 || c->ny > 1000)
                r.fail(rec, "nx, ny must be 2 to 1000");
            grid = true;
        } else if (rec == "depths") {
            c->depths = numbers(r, rec, in, -1);
            depths = true;
        } else if (rec == "mass") {
            const std::vector<double> v = numbers(r, rec, in, 3);
            c->masses.push_back(v[0]);
            c->gaugePressures.push_back(v[1]);
            c->volumes.push_back(v[2]);
        } else if (rec == "top") {
            if (!grid) r.fail(rec, "comes before the 'grid' record; valid: grid first");
            const int k = int(numbers(r, rec, in, 1)[0]);
            if (k != int(c->top.size()))
                r.fail(rec, "mass index " + std::to_string(k) +
                                "; valid: " + std::to_string(c->top.size()) + " (in order)");
            Eigen::MatrixXd t(c->nx, c->ny);
            for (int iy = 0; iy < c->ny; ++iy) {
                if (++i >= r.lines.size())
                    r.fail(rec, "ends before its " + std::to_string(c->ny) + " rows");
                r.line = int(i) + 1;
                std::istringstream row(r.lines[i]);
                const std::vector<double> v = numbers(r, "top row", row, c->nx);
                for (int ix = 0; ix < c->nx; ++ix) t(ix, iy) = v[ix];
            }
            c->top.push_back(t);
        } else if (rec == "pressure_factor" || rec == "volume_factor") {
            std::vector<double> v = numbers(r, rec, in, -1);
            if (v.size() < 2) r.fail(rec, "needs a mass index and one value per depth");
            Eigen::VectorXd row = Eigen::Map<Eigen::VectorXd>(v.data() + 1, int(v.size()) - 1);
            (rec == "pressure_factor" ? kappa : beta).emplace_back(int(v[0]), row);
        } else if (rec == "envelope") {
            const std::vector<double> v = numbers(r, rec, in, 4);
            c->depthMax = v[0], c->radiusMin = v[1], c->radiusMax = v[2], c->tiltMax = v[3];
            envelope = true;
        } else {
            r.fail(rec,
                   "unknown record; valid: source, geometry, gas, board_penalty, rim_width, skirt, "
                   "panel_coupling, grid, depths, mass, top, pressure_factor, volume_factor, "
                   "envelope");
        }
    }
    r.line = 0;
    if (!magic) r.fail("", "empty; not a reduced bag calibration");
    if (!geometry || !grid || !depths || !envelope)
        r.fail("", "incomplete: geometry, grid, depths and envelope are required");
    const int n = int(c->masses.size()), k = int(c->depths.size());
    c->pressureFactor.resize(n, k);
    c->volumeFactor.resize(n, k);
    for (auto* t : {&kappa, &beta}) {
        if (int(t->size()) != n)
            r.fail(t == &kappa ? "pressure_factor" : "volume_factor",
                   "one row per mass (" + std::to_string(n) + ") needed");
        for (const auto& [row, v] : *t) {
            if (row < 0 || row >= n || v.size() != k)
                r.fail(t == &kappa ? "pressure_factor" : "volume_factor",
                       "row " + std::to_string(row) + " does not fit the masses and depths");
            (t == &kappa ? c->pressureFactor : c->volumeFactor).row(row) = v.transpose();
        }
    }
    try {
        c->validate();
    } catch (const std::invalid_argument& e) {
        r.fail("", e.what());
    }
    return c;
}

// bag.model and bag.calibration (docs/reduced-bag.md): the calibration file is read relative
// to the scenario's folder and must describe this bag (its sizes and FE mesh).
void readReducedBagKeys(const ScenarioNode& s, cosim::PatientOnArrayOptions& options,
                        const std::string& fileName) {
    const std::string model = s.getChoice("model", {"finite-element", "reduced"}, "finite-element");
    if (model == "finite-element") {
        if (s.has("calibration"))
            s.fail("calibration", "is for model: reduced; the finite-element bag takes none");
        return;
    }
    if (!s.has("calibration"))
        s.fail("calibration",
               "missing: model: reduced needs its calibration file, e.g. "
               "calibration: ../data/reduced-bag/literal-30mm.txt (relative to "
               "this scenario's folder; made by bench_reduced_bag calibrate)");
    const std::string rel = s.getString("calibration");
    const std::string path =
        (std::filesystem::path(fileName).parent_path() / rel).lexically_normal().string();
    if (!std::filesystem::is_regular_file(path))
        s.fail("calibration",
               "\"" + rel + "\": no such file (" + path +
                   "); valid: a calibration file, relative to this scenario's folder");
    options.model = cosim::PatientOnArrayOptions::BagModel::Reduced;
    options.reduced = readReducedBagCalibration(path);
    const bags::DoubleWedgeParams& c = options.reduced->geometry;
    const bags::DoubleWedgeParams& g = options.bag.geometry;
    if (std::abs(c.meshSize - g.meshSize) > 1e-9 || std::abs(c.longSide - g.longSide) > 1e-9 ||
        std::abs(c.height - g.height) > 1e-9 || c.diaphragm != g.diaphragm)
        s.fail("calibration",
               "\"" + rel + "\" was made for a bag of " + formatSignificant(c.longSide, "mm") +
                   " and a " + formatSignificant(c.meshSize, "mm") +
                   " mesh, this scenario's bag is " + formatSignificant(g.longSide, "mm") +
                   " with a " + formatSignificant(g.meshSize, "mm") +
                   " mesh (bag.reading, bag.mesh_size); valid: a calibration of "
                   "this bag (bench_reduced_bag calibrate)");
}

void writeReducedBagCalibration(const std::string& path, const cosim::ReducedBagCalibration& c) {
    std::ofstream f(path);
    if (!f) throw std::runtime_error("cannot write " + path);
    f << std::setprecision(10);
    f << kMagic << " 2\n"
      << "# The reduced bag's calibration (docs/reduced-bag.md). SI units: m, kg, Pa, m^3, rad.\n";
    std::istringstream src(c.source);
    for (std::string s; std::getline(src, s);) f << "source " << s << "\n";
    const bags::DoubleWedgeParams& g = c.geometry;
    f << "geometry " << g.longSide << " " << g.shortSide << " " << g.width << " " << g.height << " "
      << g.meshSize << " " << (g.diaphragm ? 1 : 0) << "\n"
      << "gas " << c.gasConstant << " " << c.temperature << " " << c.ambientPressure << "\n"
      << "board_penalty " << c.boardPenalty << "\n"
      << "rim_width " << c.rimWidth << "\n"
      << "skirt " << c.skirt << "\n";
    if (c.panelSink > 0.0 || c.panelLift > 0.0)
        f << "panel_coupling " << c.panelSink << " " << c.panelLift << " " << c.panelBlend << "\n";
    f << "envelope " << c.depthMax << " " << c.radiusMin << " " << c.radiusMax << " " << c.tiltMax
      << "\n"
      << "grid " << c.nx << " " << c.ny << " " << c.x0 << " " << c.y0 << " " << c.pitch << "\n"
      << "depths";
    for (double d : c.depths) f << " " << d;
    f << "\n";
    for (size_t i = 0; i < c.masses.size(); ++i)
        f << "mass " << c.masses[i] << " " << c.gaugePressures[i] << " " << c.volumes[i] << "\n";
    for (size_t i = 0; i < c.masses.size(); ++i) {
        f << "pressure_factor " << i;
        for (int j = 0; j < c.pressureFactor.cols(); ++j) f << " " << c.pressureFactor(i, j);
        f << "\nvolume_factor " << i;
        for (int j = 0; j < c.volumeFactor.cols(); ++j) f << " " << c.volumeFactor(i, j);
        f << "\n";
    }
    f << std::setprecision(6);
    for (size_t i = 0; i < c.top.size(); ++i) {
        f << "top " << i << "\n";
        for (int iy = 0; iy < c.ny; ++iy) {
            for (int ix = 0; ix < c.nx; ++ix) {
                const double v = c.top[i](ix, iy);
                f << (ix ? " " : "") << (std::isfinite(v) ? std::to_string(v) : std::string("nan"));
            }
            f << "\n";
        }
    }
    if (!f) throw std::runtime_error("cannot write " + path);
}

}  // namespace io
