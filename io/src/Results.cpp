#include <bagsim/Version.h>
#include <io/InputError.h>
#include <io/ResultFiles.h>
#include <io/Results.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "Hdf5.h"
#include "RunMeta.h"

namespace io {

namespace fs = std::filesystem;

std::string getUtcTimestamp() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

std::vector<std::pair<double, double>> findInvertibleKOfM(const bags::LoadTestResult& result) {
    std::vector<const bags::LoadCurve*> curves;
    for (const bags::LoadCurve& c : result.curves) curves.push_back(&c);
    std::sort(curves.begin(), curves.end(), [](const bags::LoadCurve* a, const bags::LoadCurve* b) {
        return a->gasMass > b->gasMass;
    });
    std::vector<std::pair<double, double>> km;
    for (const bags::LoadCurve* c : curves) {
        if (!c->reachedPeak || !std::isfinite(c->stiffness) || !(c->stiffness > 0.0)) break;
        if (!km.empty() && !(c->stiffness < km.back().second && c->gasMass < km.back().first))
            break;
        km.emplace_back(c->gasMass, c->stiffness);
    }
    if (km.size() < 2) return {};
    std::reverse(km.begin(), km.end());
    return km;
}

// ----------------------------------------------------------------------------------- OutputDir

namespace {

// Files a run writes; --force removes them first so no stale result survives a failed rerun.
const char* const kOwnedFiles[] = {
    kResultsH5,         kResultsXdmf,  kLoadDisplacementCsv, kStiffnessCsv,       kRigReadingsCsv,
    "results.xdmf.tmp", "regions.csv", "bags.csv",           "tilt.csv",          "report.html",
    "report.html.tmp",  "summary.txt", "verdict.csv",        "events.csv",        "body.csv",
    "pneumatics.csv",   kKOfMYaml,     kCheckpointFile,      "checkpoint.bin.tmp"};

}  // namespace

OutputDir::OutputDir(const fs::path& path, bool force) : m_path(path) {
    const std::string where = path.string();
    std::error_code ec;
    if (fs::exists(path, ec)) {
        if (!fs::is_directory(path, ec))
            throw InputError(where, 0, "",
                             "the output path exists and is not a folder; choose another --out");
        const bool empty = fs::is_empty(path, ec);
        if (!empty && !force)
            throw InputError(where, 0, "",
                             "the output folder exists and is not empty; pass --force to "
                             "overwrite the results in it, or choose another folder with --out");
        if (!empty)
            for (const char* name : kOwnedFiles) fs::remove(path / name, ec);
    }
    fs::create_directories(path, ec);
    if (ec || !fs::is_directory(path))
        throw InputError(where, 0, "", "cannot create the output folder (" + ec.message() + ")");
    setStatus("running", "started " + getUtcTimestamp());
}

OutputDir OutputDir::resume(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_directory(path, ec))
        throw InputError(path.string(), 0, "",
                         "is not a folder; --resume takes the output folder of an interrupted run");
    OutputDir d;
    d.m_path = path;
    return d;
}

void OutputDir::markResumed() const { setStatus("running", "resumed " + getUtcTimestamp()); }

std::string OutputDir::readMarker() const {
    std::ifstream in(getFile(kMarkerName), std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return in ? text.str() : std::string();
}

void OutputDir::writeMarker(const std::string& text) const {
    std::ofstream out(getFile(kMarkerName), std::ios::binary | std::ios::trunc);
    out << text;
    if (!out)
        throw std::runtime_error("cannot write " + getFile(kMarkerName).string() + ": " +
                                 std::strerror(errno));
}

void OutputDir::setStatus(const std::string& status, const std::string& detail) const {
    std::ofstream out(getFile(kMarkerName), std::ios::trunc);
    if (status == "partial")
        out << "This folder's results are incomplete: the run finished, but part of it did not "
               "hold (a curve stopped on a numerical failure or outside the model's envelope, "
               "or bag steps were kept unrelaxed; the line below says which).\n";
    else if (status == "running")
        out << "This folder's results are incomplete: the run that writes them has not finished "
               "(or was killed).\n";
    else
        out << "This folder's results are incomplete: the run that wrote them stopped early.\n";
    out << "status: " << status << "\n" << detail << "\n";
    if (!out)
        throw std::runtime_error("cannot write " + getFile(kMarkerName).string() + ": " +
                                 std::strerror(errno));
}

void OutputDir::markComplete() const {
    std::error_code ec;
    fs::remove(getFile(kMarkerName), ec);
    if (ec)
        throw std::runtime_error("cannot remove " + getFile(kMarkerName).string() + ": " +
                                 ec.message());
}

bool OutputDir::isIncomplete() const {
    std::error_code ec;
    return fs::exists(getFile(kMarkerName), ec);
}

// ------------------------------------------------------------------------------ LoadTestWriter

bool isCurveFailed(const bags::LoadCurve& c) {
    // The load test's one physical early end is "bottomed out: ..."; every other reason is a
    // step that could not be solved (a bottomed-out curve whose unloading then fails is
    // flagged by `failed`).
    return c.failed || !c.quasiStatic || c.outsideEnvelope ||
           (!c.failure.empty() && c.failure.rfind("bottomed out", 0) != 0);
}

std::string getCurveEnd(const bags::LoadCurve& c) {
    if (c.outsideEnvelope) return "outside-envelope";
    if (!c.quasiStatic && !c.failed) return "not-quasi-static";
    if (isCurveFailed(c)) return "failed";
    if (c.reachedPeak) return "peak";
    if (c.failure.rfind("bottomed out", 0) == 0) return "bottomed-out";
    return "stopped";
}

namespace {

struct CurveData {
    h5::Handle group;
    h5::GrowingDataset step, loading, time, displacement, force, iterations, pressure, volume,
        gasMass, stabilization, residual, kineticEnergy;
    size_t chambers = 0;  ///< columns of pressure and volume
};

struct FrameInfo {
    int curve;
    int step;
    bool loading;
    double time;
};

std::string fmtG(double v, int digits = 9) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

// Volume-weighted mean gauge pressure of the chambers [Pa] (chambers sharing a gas agree).
double calcMeanPressure(const bags::LoadStep& s) {
    double pv = 0.0, v = 0.0, p = 0.0;
    for (size_t i = 0; i < s.gaugePressure.size(); ++i) {
        const double vi = i < s.volume.size() ? s.volume[i] : 0.0;
        pv += s.gaugePressure[i] * vi;
        v += vi;
        p += s.gaugePressure[i];
    }
    if (v > 0.0) return pv / v;
    return s.gaugePressure.empty() ? 0.0 : p / double(s.gaugePressure.size());
}

std::string escapeXml(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

}  // namespace

struct LoadTestWriter::Impl {
    OutputDir dir;
    Options options;
    std::vector<double> gasMasses;
    h5::Handle file, meta, mesh, curvesGroup, framesGroup;
    std::vector<CurveData> curves;
    h5::Handle framePositions;  // group of one N x 3 dataset per frame
    h5::GrowingDataset frameCurve, frameStep, frameLoading, frameTime, frameDisplacement,
        frameForce;
    std::vector<FrameInfo> frames;
    bool meshWritten = false;
    int numNodes = 0;
    int numTris = 0;
    int numSteps = 0;
    bool hasPending = false;
    bool pendingSaved = false;
    bags::LoadStep pending;
    Eigen::Matrix3Xd pendingX;
    std::ofstream csv;
    std::chrono::steady_clock::time_point lastFlush = std::chrono::steady_clock::now();
    std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
    bool closed = false;

    explicit Impl(const OutputDir& d) : dir(d) {}

    void writeMesh(const bags::Mesh& m);
    CurveData& getCurve(const bags::LoadStep& s);
    void saveFrame(const bags::LoadStep& s, const Eigen::Matrix3Xd& x);
    void flush();
    void writeXdmf() const;
    void close();
};

void LoadTestWriter::Impl::writeMesh(const bags::Mesh& m) {
    numNodes = m.getNumNodes();
    numTris = m.getNumTris();
    const hsize_t n = static_cast<hsize_t>(numNodes), t = static_cast<hsize_t>(numTris);
    // Eigen's 3 x N column-major storage is the N x 3 row-major layout HDF5 and XDMF expect.
    h5::writeDataset(mesh.get(), "nodes", {n, 3}, m.X.data(), "m");
    Eigen::Matrix3Xi tris = m.tris;
    h5::writeDataset(mesh.get(), "triangles", {t, 3}, tris.data(), "");
    std::vector<int> panel = m.triPanel;
    panel.resize(t, -1);
    h5::writeDataset(mesh.get(), "panel", {t}, panel.data(), "");
    h5::Handle panelDs(h5::check(H5Dopen2(mesh.get(), "panel", H5P_DEFAULT), "open /mesh/panel"));
    h5::setAttribute(panelDs.get(), "names", m.panelNames);
    h5::writeDataset(mesh.get(), "support_nodes", {hsize_t(m.supportNodes.size())},
                     m.supportNodes.data(), "");
    h5::Handle chambers = h5::createGroup(mesh.get(), "chambers");
    std::vector<std::string> names;
    for (size_t c = 0; c < m.chambers.size(); ++c) {
        const bags::ChamberBoundary& ch = m.chambers[c];
        names.push_back(ch.name);
        h5::Handle g = h5::createGroup(chambers.get(), std::to_string(c));
        h5::setAttribute(g.get(), "name", ch.name);
        h5::writeDataset(g.get(), "triangles", {hsize_t(ch.tris.size())}, ch.tris.data(), "");
        h5::writeDataset(g.get(), "signs", {hsize_t(ch.signs.size())}, ch.signs.data(), "");
    }
    h5::setAttribute(mesh.get(), "chamber_names", names);
    h5::setAttribute(mesh.get(), "num_nodes", numNodes);
    h5::setAttribute(mesh.get(), "num_triangles", numTris);

    if (options.frameEvery > 0) {
        // One dataset per frame rather than one F x N x 3 array: ParaView's XDMF 3 reader does
        // not read HyperSlab geometry, and plain datasets open in every reader.
        framePositions = h5::createGroup(framesGroup.get(), "positions");
        frameCurve = h5::GrowingDataset(framesGroup.get(), "curve", H5T_NATIVE_INT, {}, 256, "");
        frameStep = h5::GrowingDataset(framesGroup.get(), "step", H5T_NATIVE_INT, {}, 256, "");
        frameLoading =
            h5::GrowingDataset(framesGroup.get(), "loading", H5T_NATIVE_INT8, {}, 256, "");
        frameTime = h5::GrowingDataset(framesGroup.get(), "time", H5T_NATIVE_DOUBLE, {}, 256, "s");
        frameDisplacement =
            h5::GrowingDataset(framesGroup.get(), "displacement", H5T_NATIVE_DOUBLE, {}, 256, "m");
        frameForce =
            h5::GrowingDataset(framesGroup.get(), "force", H5T_NATIVE_DOUBLE, {}, 256, "N");
    }
    meshWritten = true;
}

CurveData& LoadTestWriter::Impl::getCurve(const bags::LoadStep& s) {
    if (s.curve < 0 || s.curve >= static_cast<int>(gasMasses.size()))
        throw std::runtime_error("load step of curve " + std::to_string(s.curve) +
                                 " but the test has " + std::to_string(gasMasses.size()) +
                                 " gas masses");
    if (static_cast<int>(curves.size()) <= s.curve) curves.resize(s.curve + 1);
    CurveData& c = curves[s.curve];
    if (!c.group.isValid()) {
        c.group = h5::createGroup(curvesGroup.get(), std::to_string(s.curve));
        h5::setAttribute(c.group.get(), "gas_mass", gasMasses[s.curve]);
        const hid_t g = c.group.get();
        const hsize_t chambers = s.gaugePressure.size();
        c.chambers = chambers;
        c.step = h5::GrowingDataset(g, "step", H5T_NATIVE_INT, {}, 256, "");
        c.loading = h5::GrowingDataset(g, "loading", H5T_NATIVE_INT8, {}, 256, "");
        c.time = h5::GrowingDataset(g, "time", H5T_NATIVE_DOUBLE, {}, 256, "s");
        c.displacement = h5::GrowingDataset(g, "displacement", H5T_NATIVE_DOUBLE, {}, 256, "m");
        c.force = h5::GrowingDataset(g, "force", H5T_NATIVE_DOUBLE, {}, 256, "N");
        c.iterations = h5::GrowingDataset(g, "newton_iterations", H5T_NATIVE_INT, {}, 256, "");
        c.stabilization =
            h5::GrowingDataset(g, "stabilization_energy", H5T_NATIVE_DOUBLE, {}, 256, "J");
        c.residual = h5::GrowingDataset(g, "residual", H5T_NATIVE_DOUBLE, {}, 256, "N");
        c.kineticEnergy = h5::GrowingDataset(g, "kinetic_energy", H5T_NATIVE_DOUBLE, {}, 256, "J");
        c.pressure =
            h5::GrowingDataset(g, "gauge_pressure", H5T_NATIVE_DOUBLE, {chambers}, 256, "Pa");
        c.volume = h5::GrowingDataset(g, "volume", H5T_NATIVE_DOUBLE, {chambers}, 256, "m^3");
        c.gasMass = h5::GrowingDataset(g, "gas_mass", H5T_NATIVE_DOUBLE, {chambers}, 256, "kg");
    }
    return c;
}

void LoadTestWriter::Impl::saveFrame(const bags::LoadStep& s, const Eigen::Matrix3Xd& x) {
    if (options.frameEvery <= 0) return;
    const hsize_t n = static_cast<hsize_t>(numNodes);
    h5::writeDataset(framePositions.get(), std::to_string(frames.size()), {n, 3}, x.data(), "m");
    const int curve = s.curve, step = s.step;
    const signed char loading = s.loading ? 1 : 0;
    frameCurve.append(&curve);
    frameStep.append(&step);
    frameLoading.append(&loading);
    frameTime.append(&s.time);
    frameDisplacement.append(&s.displacement);
    frameForce.append(&s.force);
    frames.push_back({s.curve, s.step, s.loading, s.time});
}

void LoadTestWriter::Impl::flush() {
    if (csv.is_open()) csv.flush();
    if (file.isValid()) h5::check(H5Fflush(file.get(), H5F_SCOPE_LOCAL), "cannot flush results");
    if (meshWritten) writeXdmf();
    lastFlush = std::chrono::steady_clock::now();
}

void LoadTestWriter::Impl::writeXdmf() const {
    const std::string h5 = kResultsH5;
    const std::string N = std::to_string(numNodes), T = std::to_string(numTris);
    std::ostringstream x;
    auto topology = [&](const std::string& indent) {
        x << indent << "<Topology TopologyType=\"Triangle\" NumberOfElements=\"" << T << "\">\n"
          << indent << "  <DataItem Dimensions=\"" << T << " 3\" NumberType=\"Int\" Precision=\"4\""
          << " Format=\"HDF\">" << h5 << ":/mesh/triangles</DataItem>\n"
          << indent << "</Topology>\n";
    };
    auto panel = [&](const std::string& indent) {
        x << indent << "<Attribute Name=\"panel\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
          << indent << "  <DataItem Dimensions=\"" << T << "\" NumberType=\"Int\" Precision=\"4\""
          << " Format=\"HDF\">" << h5 << ":/mesh/panel</DataItem>\n"
          << indent << "</Attribute>\n";
    };
    x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
      << "<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">\n"
      << "  <Domain>\n";
    if (frames.empty()) {
        // No frames saved: the reference (stress-free) membrane alone.
        x << "    <Grid Name=\"reference\" GridType=\"Uniform\">\n";
        topology("      ");
        x << "      <Geometry GeometryType=\"XYZ\">\n"
          << "        <DataItem Dimensions=\"" << N << " 3\" NumberType=\"Float\" Precision=\"8\""
          << " Format=\"HDF\">" << h5 << ":/mesh/nodes</DataItem>\n"
          << "      </Geometry>\n";
        panel("      ");
        x << "    </Grid>\n";
    } else {
        x << "    <Grid Name=\"membrane\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
        for (size_t f = 0; f < frames.size(); ++f) {
            const FrameInfo& fi = frames[f];
            const double mass = gasMasses[fi.curve] * 1e3;
            char name[160];
            std::snprintf(name, sizeof name, "frame %zu: curve %d (%.4g g) step %d %s", f, fi.curve,
                          mass, fi.step, fi.loading ? "loading" : "unloading");
            x << "      <Grid Name=\"" << escapeXml(name) << "\" GridType=\"Uniform\">\n"
              << "        <Time Value=\"" << f << "\"/>\n";
            topology("        ");
            x << "        <Geometry GeometryType=\"XYZ\">\n"
              << "          <DataItem Dimensions=\"" << N << " 3\" NumberType=\"Float\""
              << " Precision=\"8\" Format=\"HDF\">" << h5 << ":/frames/positions/" << f
              << "</DataItem>\n"
              << "        </Geometry>\n";
            panel("        ");
            x << "      </Grid>\n";
        }
        x << "    </Grid>\n";
    }
    x << "  </Domain>\n</Xdmf>\n";

    // Write beside and rename, so a reader never sees a half-written file.
    const fs::path tmp = dir.getFile("results.xdmf.tmp");
    {
        std::ofstream out(tmp, std::ios::trunc);
        out << x.str();
        if (!out) throw std::runtime_error("cannot write " + tmp.string());
    }
    fs::rename(tmp, dir.getFile(kResultsXdmf));
}

void LoadTestWriter::Impl::close() {
    if (closed) return;
    closed = true;
    if (csv.is_open()) csv.close();
    curves.clear();
    framePositions.reset();
    frameCurve = {};
    frameStep = {};
    frameLoading = {};
    frameTime = {};
    frameDisplacement = {};
    frameForce = {};
    framesGroup.reset();
    curvesGroup.reset();
    mesh.reset();
    meta.reset();
    file.reset();
}

RunInfo readRunInfo(const std::string& dir) {
    const std::string path = (std::filesystem::path(dir) / kResultsH5).string();
    h5::Handle file = h5::openFileReadOnly(path);
    if (!h5::hasLink(file.get(), "meta"))
        throw std::runtime_error(path + " has no /meta group: not written by bagsim");
    h5::Handle meta = h5::openGroup(file.get(), "meta");
    auto str = [&](const char* key) {
        return h5::hasAttribute(meta.get(), key) ? h5::readStringAttribute(meta.get(), key)
                                                 : std::string();
    };
    RunInfo info;
    info.scenarioText = str("scenario");
    info.scenarioFile = str("scenario_file");
    info.commandLine = str("command_line");
    std::istringstream os(str("overrides"));
    for (std::string line; std::getline(os, line);)
        if (!line.empty()) info.overrides.push_back(line);
    return info;
}

h5::Handle createRunMeta(hid_t file, const RunInfo& info, const std::string& kind) {
    h5::Handle meta = h5::createGroup(file, "meta");
    h5::setAttribute(meta.get(), "program", std::string("bagsim"));
    h5::setAttribute(meta.get(), "version", std::string(bagsim::kVersion));
    h5::setAttribute(meta.get(), "kind", kind);
    h5::setAttribute(meta.get(), "scenario", info.scenarioText);
    h5::setAttribute(meta.get(), "scenario_file", info.scenarioFile);
    h5::setAttribute(meta.get(), "overrides", info.overrides);
    h5::setAttribute(meta.get(), "command_line", info.commandLine);
    h5::setAttribute(meta.get(), "started", getUtcTimestamp());
    h5::setAttribute(meta.get(), "status", std::string("running"));
    h5::setAttribute(meta.get(), "message", std::string(""));
    return meta;
}

void setRunStatus(hid_t meta, const std::string& status, const std::string& message) {
    h5::setAttribute(meta, "status", status);
    h5::setAttribute(meta, "message", message);
    h5::setAttribute(meta, "finished", getUtcTimestamp());
}

LoadTestWriter::LoadTestWriter(const OutputDir& dir, const RunInfo& info,
                               const bags::LoadTestOptions& test, const Options& options)
    : m_impl(std::make_unique<Impl>(dir)) {
    Impl& d = *m_impl;
    d.options = options;
    d.gasMasses = test.gasMasses;
    d.file = h5::createFile(dir.getFile(kResultsH5).string());
    d.meta = createRunMeta(d.file.get(), info, "seed-load-test");
    h5::setAttribute(d.meta.get(), "frame_every", options.frameEvery);
    d.mesh = h5::createGroup(d.file.get(), "mesh");
    d.curvesGroup = h5::createGroup(d.file.get(), "curves");
    h5::setAttribute(d.curvesGroup.get(), "gas_masses", test.gasMasses);
    d.framesGroup = h5::createGroup(d.file.get(), "frames");
    h5::check(H5Fflush(d.file.get(), H5F_SCOPE_LOCAL), "cannot flush results");

    d.csv.open(dir.getFile(kLoadDisplacementCsv), std::ios::trunc);
    if (!d.csv)
        throw std::runtime_error("cannot write " + dir.getFile(kLoadDisplacementCsv).string());
    d.csv << kLoadDisplacementHeader << "\n";
}

LoadTestWriter::~LoadTestWriter() {
    if (m_impl && !m_impl->closed)
        fail("failed", "the run stopped before its results were complete");
}

void LoadTestWriter::addStep(const bags::LoadStep& s, const bags::Mesh& mesh,
                             const Eigen::Matrix3Xd& x) {
    Impl& d = *m_impl;
    if (d.closed) throw std::logic_error("LoadTestWriter::addStep after finish() or fail()");
    if (!d.meshWritten) d.writeMesh(mesh);
    if (x.cols() != d.numNodes)
        throw std::runtime_error("load step with " + std::to_string(x.cols()) +
                                 " nodes; the mesh has " + std::to_string(d.numNodes));
    const bool newCurve = d.hasPending && d.pending.curve != s.curve;
    const bool newBranch = !d.hasPending || newCurve || d.pending.loading != s.loading;
    // The last step of a branch is always a frame (the peak, the end of unloading).
    if (d.hasPending && newBranch && !d.pendingSaved) d.saveFrame(d.pending, d.pendingX);
    if (newCurve) d.flush();  // the previous curve is complete on disk

    CurveData& c = d.getCurve(s);
    const signed char loading = s.loading ? 1 : 0;
    c.step.append(&s.step);
    c.loading.append(&loading);
    c.time.append(&s.time);
    c.displacement.append(&s.displacement);
    c.force.append(&s.force);
    c.iterations.append(&s.newtonIterations);
    c.stabilization.append(&s.stabilizationEnergy);
    c.residual.append(&s.residual);
    c.kineticEnergy.append(&s.kineticEnergy);
    std::vector<double> p = s.gaugePressure, v = s.volume, m = s.gasMass;
    p.resize(c.chambers, 0.0);
    v.resize(c.chambers, 0.0);
    m.resize(c.chambers, 0.0);
    c.pressure.append(p.data());
    c.volume.append(v.data());
    c.gasMass.append(m.data());

    d.csv << fmtG(d.gasMasses[s.curve] * 1e3, 6) << ',' << fmtG(s.displacement * 1e3) << ','
          << fmtG(s.force) << ',' << fmtG(calcMeanPressure(s) * 1e-3) << ','
          << (s.loading ? "loading" : "unloading") << '\n';

    const bool save = d.options.frameEvery > 0 && (newBranch || s.step % d.options.frameEvery == 0);
    if (save) d.saveFrame(s, x);
    d.pending = s;
    d.pendingX = x;
    d.pendingSaved = save;
    d.hasPending = true;
    ++d.numSteps;

    const double sinceFlush =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - d.lastFlush).count();
    if (sinceFlush > d.options.flushInterval) d.flush();
}

std::string LoadTestWriter::finish(const bags::LoadTestResult& r) {
    Impl& d = *m_impl;
    if (d.closed) throw std::logic_error("LoadTestWriter::finish after finish() or fail()");
    if (d.hasPending && !d.pendingSaved) d.saveFrame(d.pending, d.pendingX);
    d.pendingSaved = true;

    const size_t n = r.curves.size();
    std::vector<double> mass(n), stiffness(n), r2(n), height(n), pressure(n), volume(n);
    std::vector<int> stage(n), peak(n), steps(n), failed(n);
    std::string failures;  // "3.5 g: no convergence ...; 3 g: ..."
    int numFailed = 0;
    for (size_t i = 0; i < n; ++i) {
        const bags::LoadCurve& c = r.curves[i];
        mass[i] = c.gasMass;
        stiffness[i] = c.stiffness;
        r2[i] = c.r2;
        height[i] = c.unloadedHeight;
        pressure[i] = c.inflatedGaugePressure;
        volume[i] = c.inflatedVolume;
        stage[i] = c.stage;
        peak[i] = c.reachedPeak ? 1 : 0;
        steps[i] = static_cast<int>(c.steps.size());
        failed[i] = isCurveFailed(c) ? 1 : 0;
        if (failed[i]) {
            ++numFailed;
            failures +=
                (failures.empty() ? "" : "; ") + fmtG(c.gasMass * 1e3, 6) + " g: " + c.failure;
        }
        h5::Handle g;
        const std::string name = std::to_string(i);
        if (H5Lexists(d.curvesGroup.get(), name.c_str(), H5P_DEFAULT) > 0)
            g = h5::Handle(h5::check(H5Gopen2(d.curvesGroup.get(), name.c_str(), H5P_DEFAULT),
                                     "open /curves/" + name));
        else
            g = h5::createGroup(d.curvesGroup.get(), name);
        h5::setAttribute(g.get(), "gas_mass", c.gasMass);
        h5::setAttribute(g.get(), "unloaded_height", c.unloadedHeight);
        h5::setAttribute(g.get(), "inflated_volume", c.inflatedVolume);
        h5::setAttribute(g.get(), "inflated_gauge_pressure", c.inflatedGaugePressure);
        h5::setAttribute(g.get(), "stiffness", c.stiffness);
        h5::setAttribute(g.get(), "stiffness_min", c.stiffnessMin);
        h5::setAttribute(g.get(), "stiffness_max", c.stiffnessMax);
        h5::setAttribute(g.get(), "ensemble_size", c.ensembleSize);
        h5::setAttribute(g.get(), "r2", c.r2);
        h5::setAttribute(g.get(), "stage", c.stage);
        h5::setAttribute(g.get(), "reached_peak", c.reachedPeak ? 1 : 0);
        h5::setAttribute(g.get(), "failure", c.failure);
        h5::setAttribute(g.get(), "end", getCurveEnd(c));
        h5::setAttribute(g.get(), "stabilized_steps", c.stabilizedSteps);
        h5::setAttribute(g.get(), "stabilization_share", c.stabilizationShare);
        h5::setAttribute(g.get(), "snaps", c.snaps);
        h5::setAttribute(g.get(), "snap_travel", c.snapTravel);
        h5::setAttribute(g.get(), "block_speed", c.blockSpeed);
        h5::setAttribute(g.get(), "kinetic_share", c.kineticShare);
        h5::setAttribute(g.get(), "quasi_static", c.quasiStatic ? 1 : 0);
    }
    h5::Handle sum = h5::createGroup(d.file.get(), "summary");
    const hsize_t hn = n;
    h5::writeDataset(sum.get(), "gas_mass", {hn}, mass.data(), "kg");
    h5::writeDataset(sum.get(), "stiffness", {hn}, stiffness.data(), "N/m");
    h5::writeDataset(sum.get(), "r2", {hn}, r2.data(), "");
    h5::writeDataset(sum.get(), "stage", {hn}, stage.data(), "");
    h5::writeDataset(sum.get(), "reached_peak", {hn}, peak.data(), "");
    h5::writeDataset(sum.get(), "failed", {hn}, failed.data(), "");
    h5::writeDataset(sum.get(), "num_steps", {hn}, steps.data(), "");
    h5::writeDataset(sum.get(), "unloaded_height", {hn}, height.data(), "m");
    h5::writeDataset(sum.get(), "inflated_gauge_pressure", {hn}, pressure.data(), "Pa");
    h5::writeDataset(sum.get(), "inflated_volume", {hn}, volume.data(), "m^3");
    const std::string polyUnit = "k [N/mm] = sum c[i] m^(n-1-i), m [g], highest power first";
    h5::writeDataset(sum.get(), "k_fit", {hsize_t(r.kFit.size())}, r.kFit.data(), polyUnit);
    const std::vector<double> seed = bags::getSeedStiffnessPolynomial();
    h5::writeDataset(sum.get(), "k_seed", {hsize_t(seed.size())}, seed.data(), polyUnit);
    h5::setAttribute(sum.get(), "solve_seconds", r.seconds);

    {
        std::ofstream out(d.dir.getFile(kStiffnessCsv), std::ios::trunc);
        out << kStiffnessHeader << "\n";
        for (size_t i = 0; i < n; ++i)
            out << fmtG(mass[i] * 1e3, 6) << ',' << fmtG(stiffness[i] * 1e-3) << ','
                << fmtG(r.curves[i].stiffnessMin * 1e-3) << ','
                << fmtG(r.curves[i].stiffnessMax * 1e-3) << ',' << fmtG(r2[i], 6) << ',' << stage[i]
                << ',' << getCurveEnd(r.curves[i]) << '\n';
        if (!out) throw std::runtime_error("cannot write " + d.dir.getFile(kStiffnessCsv).string());
    }

    // The controllers' table: k(m) on its invertible branch, and the inverse.
    const std::vector<std::pair<double, double>> km = findInvertibleKOfM(r);
    if (km.size() >= 2) {
        std::ofstream out(d.dir.getFile(kKOfMYaml), std::ios::trunc);
        out << "# k(m) of this run's bag, the stiffness of stiffness.csv on its taut branch: from "
               "the\n"
               "# highest gas mass down while the stiffness falls, curves that reached their peak. "
               "Paste\n"
               "# under 'control:' of a patient-on-array scenario with kind target-mass, whose "
               "targets\n"
               "# may then give a stiffness (docs/scenario-reference.md).\n"
               "k_of_m: [";
        for (size_t i = 0; i < km.size(); ++i)
            out << (i ? ", " : "") << '[' << fmtG(km[i].first * 1e3, 6) << " g, "
                << fmtG(km[i].second * 1e-3, 6) << " N/mm]";
        out << "]\n# The inverse, the gas mass for a wanted stiffness (linear between the rows;\n"
               "# outside them the controller refuses the target):\n"
               "#   stiffness [N/mm]   gas mass [g]\n";
        for (const auto& [m, k] : km) {
            char line[80];
            std::snprintf(line, sizeof line, "#   %17.4f   %12.4f\n", k * 1e-3, m * 1e3);
            out << line;
        }
        if (!out) throw std::runtime_error("cannot write " + d.dir.getFile(kKOfMYaml).string());
    }

    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - d.started).count();
    h5::setAttribute(d.meta.get(), "wall_seconds", wall);
    h5::setAttribute(d.meta.get(), "finished", getUtcTimestamp());
    const std::string status = numFailed > 0 ? "partial" : "complete";
    const std::string message =
        numFailed > 0 ? std::to_string(numFailed) + " of " + std::to_string(n) +
                            " curves stopped on a numerical failure or outside the model's "
                            "envelope (" +
                            failures + ")"
                      : std::string("");
    h5::setAttribute(d.meta.get(), "status", status);
    h5::setAttribute(d.meta.get(), "message", message);
    d.flush();
    d.close();
    if (numFailed > 0)
        d.dir.setStatus(status, message);
    else
        d.dir.markComplete();
    return status;
}

void LoadTestWriter::fail(const std::string& status, const std::string& message) noexcept {
    Impl& d = *m_impl;
    if (d.closed) return;
    try {
        if (d.hasPending && !d.pendingSaved) d.saveFrame(d.pending, d.pendingX);
        d.pendingSaved = true;
        setRunStatus(d.meta.get(), status, message);
        d.flush();
    } catch (...) {
        // Keep going: the marker below still says the folder is incomplete.
    }
    d.close();
    try {
        d.dir.setStatus(status, message);
    } catch (...) {
    }
}

int LoadTestWriter::getNumFrames() const { return static_cast<int>(m_impl->frames.size()); }
int LoadTestWriter::getNumSteps() const { return m_impl->numSteps; }

}  // namespace io
