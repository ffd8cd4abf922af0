#include <io/ArrayResults.h>
#include <bags/Units.h>
#include <io/StudyTable.h>

#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "Hdf5.h"
#include "RunMeta.h"

namespace io {

namespace {

constexpr double kMmHg = bags::kPascalsPerMmHg;  // [Pa]
constexpr double kPi = 3.14159265358979323846;

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

}  // namespace

struct ArrayResultsWriter::Impl {
    explicit Impl(const OutputDir& d) : dir(d) {}
    const OutputDir& dir;
    cosim::PressureMatOptions mat;
    h5::Handle file, meta, matGroup;
    h5::GrowingDataset matTime, matPressure, matForce, matOffForce;
    std::ofstream regions, bags, tilt, body, events, pneumatics;
    std::vector<double> frameTimes;
    int frames = 0;
    // The shapes for ParaView (setShapes()).
    struct ShapeSet {
        std::string name;   ///< "bags", "body"
        std::string group;  ///< the cell attribute's name: "bag", "segment"
        Eigen::Index nodes = 0, triangles = 0;
    };
    std::vector<ShapeSet> shapeSets;
    h5::Handle shapesGroup;
    h5::GrowingDataset shapeTime;
    std::vector<double> shapeTimes;
    double shapeInterval = 0.0, shapeEnd = 0.0, nextShape = 0.0;
    bool closed = false;
    std::chrono::steady_clock::time_point lastFlush = std::chrono::steady_clock::now();

    void flush() {
        for (std::ofstream* f : {&regions, &bags, &tilt, &body, &events, &pneumatics}) f->flush();
        if (!regions || !bags || !tilt || !body || !events || !pneumatics)
            throw std::runtime_error("cannot write the CSV files in " + dir.getPath().string());
        if (file.isValid())
            h5::check(H5Fflush(file.get(), H5F_SCOPE_LOCAL), "cannot flush results");
        lastFlush = std::chrono::steady_clock::now();
    }
    void close() {
        if (closed) return;
        closed = true;
        matTime = {};
        matPressure = {};
        matForce = {};
        matOffForce = {};
        shapeTime = {};
        shapesGroup.reset();
        matGroup.reset();
        meta.reset();
        file.reset();
        for (std::ofstream* f : {&regions, &bags, &tilt, &body, &events, &pneumatics}) f->close();
    }
    void writeXdmf() const;
};

// The mat as one layer of cells per frame, drawn just under the bed board (a 2-D grid stands
// upright in ParaView's Xdmf3 readers, across the bags): XDMF's axes run slow to fast z, y, x,
// so its cells (1, columns, rows) are /mat/pressure's frame as stored (columns, rows).
constexpr double kMatZ = -0.011, kMatThickness = 0.001;  // [m]
void ArrayResultsWriter::Impl::writeXdmf() const {
    const std::string R = std::to_string(mat.rows), C = std::to_string(mat.columns);
    const std::string N = std::to_string(frameTimes.size());
    const double dx = mat.size.x() / mat.rows, dy = mat.size.y() / mat.columns;
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
      << "<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">\n"
      << "  <Domain>\n"
      << "    <Grid Name=\"pressure mat\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (size_t f = 0; f < frameTimes.size(); ++f) {
        x << "      <Grid Name=\"mat " << f << "\" GridType=\"Uniform\">\n"
          << "        <Time Value=\"" << fmt("%.9g", frameTimes[f]) << "\"/>\n"
          << "        <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"2 " << mat.columns + 1
          << " " << mat.rows + 1 << "\"/>\n"
          << "        <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
          << "          <DataItem Dimensions=\"3\" Format=\"XML\">" << fmt("%.9g", kMatZ) << " "
          << fmt("%.9g", mat.origin.y()) << " " << fmt("%.9g", mat.origin.x()) << "</DataItem>\n"
          << "          <DataItem Dimensions=\"3\" Format=\"XML\">" << fmt("%.9g", kMatThickness)
          << " " << fmt("%.9g", dy) << " " << fmt("%.9g", dx) << "</DataItem>\n"
          << "        </Geometry>\n"
          << "        <Attribute Name=\"pressure_Pa\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
          << "          <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 " << C << " " << R
          << "\" Type=\"HyperSlab\">\n"
          << "            <DataItem Dimensions=\"3 3\" Format=\"XML\">" << f << " 0 0 1 1 1 1 " << C
          << " " << R << "</DataItem>\n"
          << "            <DataItem Dimensions=\"" << N << " " << C << " " << R
          << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << kResultsH5
          << ":/mat/pressure</DataItem>\n"
          << "          </DataItem>\n"
          << "        </Attribute>\n"
          << "      </Grid>\n";
    }
    x << "    </Grid>\n";
    for (const ShapeSet& set : shapeSets) {
        if (shapeTimes.empty()) break;
        const std::string T = std::to_string(set.triangles), P = std::to_string(set.nodes);
        const std::string at = std::string(kResultsH5) + ":/shapes/" + set.name;
        x << "    <Grid Name=\"" << set.name
          << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
        for (size_t f = 0; f < shapeTimes.size(); ++f)
            x << "      <Grid Name=\"" << set.name << " " << f << "\" GridType=\"Uniform\">\n"
              << "        <Time Value=\"" << fmt("%.9g", shapeTimes[f]) << "\"/>\n"
              << "        <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << T << "\">\n"
              << "          <DataItem Dimensions=\"" << T
              << " 3\" NumberType=\"Int\" Format=\"HDF\">" << at << "/triangles</DataItem>\n"
              << "        </Topology>\n"
              << "        <Geometry GeometryType=\"XYZ\">\n"
              << "          <DataItem Dimensions=\"" << P
              << " 3\" NumberType=\"Float\" Precision=\"4\" "
              << "Format=\"HDF\">" << at << "/positions/" << f << "</DataItem>\n"
              << "        </Geometry>\n"
              << "        <Attribute Name=\"" << set.group
              << "\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
              << "          <DataItem Dimensions=\"" << T << "\" NumberType=\"Int\" Format=\"HDF\">"
              << at << "/" << set.group << "</DataItem>\n"
              << "        </Attribute>\n"
              << "      </Grid>\n";
        x << "    </Grid>\n";
    }
    x << "  </Domain>\n</Xdmf>\n";
    const std::filesystem::path tmp = dir.getFile(std::string(kResultsXdmf) + ".tmp");
    {
        std::ofstream out(tmp, std::ios::trunc);
        out << x.str();
        if (!out.flush()) throw std::runtime_error("cannot write " + tmp.string());
    }
    std::filesystem::rename(tmp, dir.getFile(kResultsXdmf));
}

ArrayResultsWriter::ArrayResultsWriter(const OutputDir& dir, const RunInfo& info,
                                       const cosim::PressureMatOptions& mat)
    : m_impl(std::make_unique<Impl>(dir)) {
    Impl& d = *m_impl;
    d.mat = mat;
    h5::silenceErrors();
    d.file = h5::createFile(dir.getFile(kResultsH5).string());
    d.meta = createRunMeta(d.file.get(), info, "patient-on-array");
    d.matGroup = h5::createGroup(d.file.get(), "mat");
    const hid_t g = d.matGroup.get();
    h5::setAttribute(g, "rows", mat.rows);
    h5::setAttribute(g, "columns", mat.columns);
    h5::setAttribute(g, "origin", std::vector<double>{mat.origin.x(), mat.origin.y()});
    h5::setAttribute(g, "size", std::vector<double>{mat.size.x(), mat.size.y()});
    h5::setAttribute(g, "layout",
                     std::string("pressure[frame][column (bed y)][row (bed x)]; "
                                 "sensel (r, c) centred at origin + ((r + 1/2) "
                                 "size_x / rows, (c + 1/2) size_y / columns)"));
    d.matTime = h5::GrowingDataset(g, "time", H5T_NATIVE_DOUBLE, {}, 256, "s");
    d.matPressure = h5::GrowingDataset(g, "pressure", H5T_NATIVE_DOUBLE,
                                       {hsize_t(mat.columns), hsize_t(mat.rows)}, 8, "Pa");
    d.matForce = h5::GrowingDataset(g, "force", H5T_NATIVE_DOUBLE, {}, 256, "N");
    d.matOffForce = h5::GrowingDataset(g, "off_mat_force", H5T_NATIVE_DOUBLE, {}, 256, "N");
    h5::check(H5Fflush(d.file.get(), H5F_SCOPE_LOCAL), "cannot flush results");

    auto open = [&](std::ofstream& f, const char* name, const char* header) {
        f.open(dir.getFile(name), std::ios::trunc);
        f << header << "\n";
        if (!f) throw std::runtime_error("cannot write " + dir.getFile(name).string());
    };
    open(d.regions, kRegionsCsv, kRegionsHeader);
    open(d.bags, kBagsCsv, kBagsHeader);
    open(d.tilt, kTiltCsv, kTiltHeader);
    open(d.body, kBodyCsv, kBodyHeader);
    open(d.events, kEventsCsv, kEventsHeader);
    open(d.pneumatics, kPneumaticsCsv, kPneumaticsHeader);
}

ArrayResultsWriter::~ArrayResultsWriter() {
    if (!m_impl->closed) fail("failed", "the writer was closed before the run finished");
}

void ArrayResultsWriter::setShapes(const cosim::SurfaceMesh& bags, const cosim::SurfaceMesh& body,
                                   double interval, double end) {
    Impl& d = *m_impl;
    if (d.closed || d.frames > 0 || !d.shapeSets.empty())
        throw std::logic_error("ArrayResultsWriter::setShapes: once, before the first frame");
    d.shapesGroup = h5::createGroup(d.file.get(), "shapes");
    h5::setAttribute(d.shapesGroup.get(), "interval", interval);
    h5::setAttribute(d.shapesGroup.get(), "layout",
                     std::string("per set (bags, body): triangles [T, 3] node indices; a cell "
                                 "group per triangle (bags: bag, the array index; body: segment, "
                                 "names in its attribute names); positions/<f> [N, 3] float32 "
                                 "node positions at time[f], Ground"));
    d.shapeTime = h5::GrowingDataset(d.shapesGroup.get(), "time", H5T_NATIVE_DOUBLE, {}, 64, "s");
    auto add = [&](const char* name, const char* group, const cosim::SurfaceMesh& m) {
        h5::Handle g = h5::createGroup(d.shapesGroup.get(), name);
        const hsize_t T = hsize_t(m.triangles.cols());
        // Matrix3Xi is column-major 3 x T: in memory the rows of a [T, 3] array.
        h5::writeDataset(g.get(), "triangles", {T, 3}, m.triangles.data(), "");
        h5::writeDataset(g.get(), group, {T}, m.triangleGroup.data(), "");
        h5::setAttribute(g.get(), "names", m.groupNames);
        h5::createGroup(g.get(), "positions");
        Eigen::Index nodes = 0;
        for (Eigen::Index t = 0; t < m.triangles.cols(); ++t)
            nodes = std::max<Eigen::Index>(nodes, m.triangles.col(t).maxCoeff() + 1);
        d.shapeSets.push_back({name, group, nodes, m.triangles.cols()});
    };
    add("bags", "bag", bags);
    add("body", "segment", body);
    d.shapeInterval = interval;
    d.shapeEnd = end;
    d.nextShape = 0.0;
}

bool ArrayResultsWriter::wantsShapes(double time) const {
    const Impl& d = *m_impl;
    return !d.shapeSets.empty() && (time >= d.nextShape - 1e-9 || time >= d.shapeEnd - 1e-9);
}

void ArrayResultsWriter::addFrame(const ArrayFrame& f) {
    Impl& d = *m_impl;
    if (d.closed) throw std::logic_error("ArrayResultsWriter::addFrame after finish/fail");
    if (f.bagNodes && f.bodyNodes && wantsShapes(f.time)) {
        const int n = int(d.shapeTimes.size());
        const Eigen::Matrix3Xd* x[2] = {f.bagNodes, f.bodyNodes};
        for (size_t k = 0; k < d.shapeSets.size(); ++k) {
            if (x[k]->cols() != d.shapeSets[k].nodes)
                throw std::invalid_argument("ArrayResultsWriter::addFrame: " + d.shapeSets[k].name +
                                            " has " + std::to_string(x[k]->cols()) +
                                            " nodes, its mesh " +
                                            std::to_string(d.shapeSets[k].nodes));
            const Eigen::Matrix3Xf xf = x[k]->cast<float>();
            h5::Handle g = h5::openGroup(d.shapesGroup.get(), d.shapeSets[k].name + "/positions");
            h5::writeDataset(g.get(), std::to_string(n), {hsize_t(xf.cols()), 3}, xf.data(), "m");
        }
        d.shapeTime.append(&f.time);
        d.shapeTimes.push_back(f.time);
        while (d.nextShape <= f.time + 1e-9)
            d.nextShape += d.shapeInterval > 0 ? d.shapeInterval : 1e300;
    }
    const std::string t = fmt("%.4f", f.time);
    for (const cosim::RegionLoad& r : f.regions) {
        if (!(r.peakPressure > 0.0)) continue;
        d.regions << t << "," << r.name << "," << fmt("%.3f", r.peakPressure / kMmHg) << ","
                  << fmt("%.3f", r.meanPressure / kMmHg) << "," << fmt("%.4f", r.area * 1e4) << ","
                  << fmt("%.5f", r.force) << "," << fmt("%.3f", r.patchPeakPressure / kMmHg) << ","
                  << (std::isnan(r.immersion) ? "" : fmt("%.2f", r.immersion * 1e3)) << ","
                  << fmt("%.4f", r.areaAtRisk * 1e4) << "\n";
    }
    for (const cosim::BagReading& b : f.bags)
        d.bags << t << "," << b.bag << "," << fmt("%.6f", b.gasMass * 1e3) << ","
               << fmt("%.5f", b.gaugePressure * 1e-3) << "," << fmt("%.6f", b.volume * 1e3) << ","
               << fmt("%.5f", b.force) << "," << fmt("%.3f", b.overlap * 1e3) << ","
               << (std::isfinite(b.innerHeight) ? fmt("%.2f", b.innerHeight * 1e3) : "") << "\n";
    d.tilt << t << "," << fmt("%.4f", f.pelvisTilt * 180.0 / kPi) << ","
           << fmt("%.4f", f.thoraxTilt * 180.0 / kPi) << "\n";
    d.body << t << "," << fmt("%.3f", 1e3 * f.centreOfMass.x()) << ","
           << fmt("%.3f", 1e3 * f.centreOfMass.y()) << "," << fmt("%.3f", 1e3 * f.centreOfMass.z())
           << "\n";
    for (const PneumaticsReading& r : f.pneumatics)
        d.pneumatics << t << "," << r.bag << "," << fmt("%.4f", 1e-3 * r.sensor) << ","
                     << fmt("%.6f", 1e3 * r.inflow) << "," << fmt("%.6f", 1e3 * r.outflow) << "\n";
    if (f.mat) {
        d.matTime.append(&f.time);
        d.matPressure.append(f.mat->getPressure().data());  // column-major: [column][row]
        const double force = f.mat->calcTotalForce(), off = f.mat->getOffMatForce();
        d.matForce.append(&force);
        d.matOffForce.append(&off);
        d.frameTimes.push_back(f.time);
    }
    ++d.frames;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - d.lastFlush).count() > 5.0)
        d.flush();
}

void ArrayResultsWriter::finish(const std::string& message, const std::string& partial) {
    Impl& d = *m_impl;
    setRunStatus(d.meta.get(), partial.empty() ? "complete" : "partial",
                 partial.empty() ? message : message + "; " + partial);
    d.flush();
    d.close();
    d.writeXdmf();
    if (partial.empty())
        d.dir.markComplete();
    else
        d.dir.setStatus("partial", message + "; " + partial);
}

void ArrayResultsWriter::fail(const std::string& status, const std::string& message) noexcept {
    Impl& d = *m_impl;
    if (d.closed) return;
    try {
        setRunStatus(d.meta.get(), status, message);
        d.flush();
    } catch (...) {
        // Keep going: the marker below still says the folder is incomplete.
    }
    d.close();
    try {
        d.writeXdmf();
    } catch (...) {
    }
    try {
        d.dir.setStatus(status, message);
    } catch (...) {
    }
}

void ArrayResultsWriter::addEvent(double time, const std::string& event) {
    Impl& d = *m_impl;
    if (d.closed) throw std::logic_error("ArrayResultsWriter::addEvent after finish/fail");
    d.events << fmt("%.4f", time) << "," << quoteCsvCell(event) << "\n";
    d.events.flush();
}

std::string ArrayResultsWriter::writeVerdict(const std::vector<VerdictRow>& rows) {
    std::ostringstream csv, table;
    csv << kVerdictHeader << "\n";
    for (const VerdictRow& r : rows) {
        const std::string value = std::isfinite(r.value) ? fmt("%.6g", r.value) : "";
        csv << quoteCsvCell(r.check) << "," << r.status << "," << value << ","
            << quoteCsvCell(r.unit) << "," << quoteCsvCell(r.detail) << "\n";
        char line[512];
        std::snprintf(line, sizeof line, "  %-7s  %-34s %10s %-5s  %s\n", r.status.c_str(),
                      r.check.c_str(), value.c_str(), r.unit.c_str(), r.detail.c_str());
        table << line;
    }
    const std::filesystem::path path = m_impl->dir.getFile(kVerdictCsv);
    std::ofstream out(path, std::ios::trunc);
    out << csv.str();
    if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
    return table.str();
}

int ArrayResultsWriter::getNumFrames() const { return m_impl->frames; }

namespace {
constexpr const char* kCsvNames[] = {kRegionsCsv, kBagsCsv,   kTiltCsv,
                                     kBodyCsv,    kEventsCsv, kPneumaticsCsv};
}

void ArrayResultsWriter::saveState(bags::StateWriter& w) {
    Impl& d = *m_impl;
    if (d.closed) throw std::logic_error("ArrayResultsWriter::saveState after finish/fail");
    d.flush();
    w.tag("array results");
    // Each file's length on the disk, everything written flushed into it.
    for (const char* name : kCsvNames)
        w.pod(std::int64_t(std::filesystem::file_size(d.dir.getFile(name))));
    w.pod(d.frames);
    w.vec(d.frameTimes);
    w.pod(std::uint64_t(d.matTime.getRows()));
    w.pod(std::uint64_t(d.shapeSets.size()));
    for (const Impl::ShapeSet& set : d.shapeSets) {
        w.str(set.name), w.str(set.group);
        w.pod(std::int64_t(set.nodes)), w.pod(std::int64_t(set.triangles));
    }
    w.vec(d.shapeTimes);
    w.pod(d.shapeInterval), w.pod(d.shapeEnd), w.pod(d.nextShape);
}

ArrayResultsWriter::ArrayResultsWriter(const OutputDir& dir, const cosim::PressureMatOptions& mat,
                                       bags::StateReader& r)
    : m_impl(std::make_unique<Impl>(dir)) {
    Impl& d = *m_impl;
    d.mat = mat;
    r.tag("array results");
    std::int64_t sizes[6];
    for (std::int64_t& n : sizes) r.pod(n);
    r.pod(d.frames);
    r.vec(d.frameTimes);
    const auto matRows = r.pod<std::uint64_t>();
    d.shapeSets.resize(r.pod<std::uint64_t>());
    for (Impl::ShapeSet& set : d.shapeSets) {
        set.name = r.str(), set.group = r.str();
        set.nodes = Eigen::Index(r.pod<std::int64_t>());
        set.triangles = Eigen::Index(r.pod<std::int64_t>());
    }
    r.vec(d.shapeTimes);
    r.pod(d.shapeInterval), r.pod(d.shapeEnd), r.pod(d.nextShape);

    h5::silenceErrors();
    try {
        d.file = h5::openFileReadWrite(dir.getFile(kResultsH5).string());
    } catch (const std::exception& e) {
        throw std::runtime_error(dir.getFile(kResultsH5).string() + ": " + e.what() +
                                 "; the run cannot be resumed from this folder");
    }
    // The CSV files as they were at the checkpoint (what the run wrote after it goes).
    // Every file checked before any is cut.
    for (int k = 0; k < 6; ++k) {
        const std::filesystem::path path = dir.getFile(kCsvNames[k]);
        std::error_code ec;
        const auto size = std::filesystem::file_size(path, ec);
        if (ec || size < std::uintmax_t(sizes[k]))
            throw std::runtime_error(
                path.string() + " is " +
                (ec ? std::string("missing") : "shorter than at the checkpoint") +
                "; the run cannot be resumed from this folder");
    }
    // A folder written by a bagsim whose files had other columns cannot take this one's rows.
    for (const auto& [name, header] :
         {std::pair{kRegionsCsv, kRegionsHeader}, std::pair{kBagsCsv, kBagsHeader}}) {
        std::ifstream in(dir.getFile(name));
        std::string line;
        std::getline(in, line);
        if (line != header)
            throw std::runtime_error(dir.getFile(name).string() + " has the columns '" + line +
                                     "', this bagsim writes '" + header +
                                     "' (the folder was written by an earlier version); the run "
                                     "cannot be resumed from this folder: run it again");
    }
    std::ofstream* files[] = {&d.regions, &d.bags, &d.tilt, &d.body, &d.events, &d.pneumatics};
    for (int k = 0; k < 6; ++k) {
        const std::filesystem::path path = dir.getFile(kCsvNames[k]);
        std::filesystem::resize_file(path, std::uintmax_t(sizes[k]));
        files[k]->open(path, std::ios::in | std::ios::out);
        files[k]->seekp(0, std::ios::end);
        if (!*files[k]) throw std::runtime_error("cannot write " + path.string());
    }
    d.meta = h5::openGroup(d.file.get(), "meta");
    d.matGroup = h5::openGroup(d.file.get(), "mat");
    const hid_t g = d.matGroup.get();
    d.matTime = h5::GrowingDataset::open(g, "time", H5T_NATIVE_DOUBLE, {}, matRows);
    d.matPressure = h5::GrowingDataset::open(g, "pressure", H5T_NATIVE_DOUBLE,
                                             {hsize_t(mat.columns), hsize_t(mat.rows)}, matRows);
    d.matForce = h5::GrowingDataset::open(g, "force", H5T_NATIVE_DOUBLE, {}, matRows);
    d.matOffForce = h5::GrowingDataset::open(g, "off_mat_force", H5T_NATIVE_DOUBLE, {}, matRows);
    if (!d.shapeSets.empty()) {
        d.shapesGroup = h5::openGroup(d.file.get(), "shapes");
        d.shapeTime = h5::GrowingDataset::open(d.shapesGroup.get(), "time", H5T_NATIVE_DOUBLE, {},
                                               d.shapeTimes.size());
        for (const Impl::ShapeSet& set : d.shapeSets) {
            h5::Handle pos = h5::openGroup(d.shapesGroup.get(), set.name + "/positions");
            for (size_t n = d.shapeTimes.size();; ++n) {
                if (!h5::hasLink(pos.get(), std::to_string(n))) break;
                h5::deleteLink(pos.get(), std::to_string(n));
            }
        }
    }
    setRunStatus(d.meta.get(), "running", "resumed from its checkpoint");
    h5::check(H5Fflush(d.file.get(), H5F_SCOPE_LOCAL), "cannot flush results");
}

}  // namespace io
