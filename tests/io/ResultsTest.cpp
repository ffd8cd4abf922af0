// Result writers: a fake mesh and two curves are streamed into an output folder and read back
// with the HDF5 C API (values, attributes, layout), the XDMF file is checked to be well-formed
// XML whose every HDF5 reference exists with the stated dimensions, the CSV headers are exact,
// and the output folder is claimed safely (refused when not empty, marker until finished).
#include <bagsim/Version.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <io/InputError.h>
#include <io/Results.h>
#include <io/Scenario.h>
#include <io/Units.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path makeTestDir(const std::string& name) {
    const fs::path p = fs::path(BAGSIM_BINARY_DIR) / "test-output" / "io" / name;
    fs::remove_all(p);
    fs::create_directories(p.parent_path());
    return p;
}

std::string readText(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::vector<std::string> readLines(const fs::path& p) {
    std::ifstream in(p);
    std::vector<std::string> lines;
    std::string l;
    while (std::getline(in, l)) lines.push_back(l);
    return lines;
}

// A closed tetrahedron: 4 nodes, 4 triangles, 2 panels, 1 chamber.
bags::Mesh makeTetMesh() {
    bags::Mesh m;
    m.X.resize(3, 4);
    m.X << 0, 1, 0, 0,  //
        0, 0, 1, 0,     //
        0, 0, 0, 1;
    m.tris.resize(3, 4);
    m.tris << 0, 0, 0, 1,  //
        2, 1, 3, 2,        //
        1, 3, 2, 3;
    m.triPanel = {0, 1, 1, 1};
    m.panelNames = {"bottom", "walls"};
    m.chambers.push_back({"inside", {0, 1, 2, 3}, {1, 1, 1, 1}});
    m.supportNodes = {0, 1, 2};
    return m;
}

bags::LoadStep makeStep(int curve, int step, bool loading, double disp, double force) {
    bags::LoadStep s;
    s.curve = curve;
    s.step = step;
    s.loading = loading;
    s.time = 6.0 * step;
    s.displacement = disp;
    s.force = force;
    s.gaugePressure = {5000.0 + 100.0 * step};
    s.volume = {1e-3};
    s.newtonIterations = 3 + step;
    s.stabilizationEnergy = 1e-6 * step;
    s.residual = 1e-8 * step;
    return s;
}

// Positions of step s: the reference mesh with node 3 lowered by the step's displacement.
Eigen::Matrix3Xd makePositions(const bags::Mesh& m, const bags::LoadStep& s) {
    Eigen::Matrix3Xd x = m.X;
    x(2, 3) -= s.displacement;
    x(0, 3) += 0.001 * s.curve;
    return x;
}

struct FakeRun {
    std::vector<bags::LoadStep> steps;
    bags::LoadTestOptions options;
    bags::LoadTestResult result;
};

// Curve 0 (3.5 g): steps 0-2 loading, 3-4 unloading. Curve 1 (2.0 g): steps 0-3 loading.
FakeRun makeRun() {
    FakeRun r;
    r.options.gasMasses = {3.5e-3, 2.0e-3};
    r.steps = {makeStep(0, 0, true, 0.0, 0.0),    makeStep(0, 1, true, 0.002, 10.0),
               makeStep(0, 2, true, 0.004, 25.0), makeStep(0, 3, false, 0.002, 12.0),
               makeStep(0, 4, false, 0.0, 0.0),   makeStep(1, 0, true, 0.0, 0.0),
               makeStep(1, 1, true, 0.003, 8.0),  makeStep(1, 2, true, 0.006, 20.0),
               makeStep(1, 3, true, 0.009, 50.0)};
    for (int c = 0; c < 2; ++c) {
        bags::LoadCurve curve;
        curve.gasMass = r.options.gasMasses[c];
        curve.unloadedHeight = 0.15 - 0.01 * c;
        curve.inflatedVolume = 1e-3;
        curve.inflatedGaugePressure = 5000.0 - 1000.0 * c;
        curve.stiffness = 6000.0 - 1500.0 * c;
        // An ensemble's spread on the first curve; one bag on the second.
        curve.stiffnessMin = curve.stiffness - (c == 0 ? 200.0 : 0.0);
        curve.stiffnessMax = curve.stiffness + (c == 0 ? 100.0 : 0.0);
        curve.r2 = 0.99 - 0.1 * c;
        curve.stage = 1 + c;
        curve.reachedPeak = c == 0;
        // A physical early end: the run is still complete.
        if (c == 1) curve.failure = "bottomed out: the block is within 2 mm of the bed board";
        for (const bags::LoadStep& s : r.steps)
            if (s.curve == c) curve.steps.push_back(s);
        r.result.curves.push_back(curve);
    }
    r.result.kFit = {1.5, 2.0};
    r.result.seconds = 0.25;
    return r;
}

// --- reading HDF5 back

std::string readStringAttr(hid_t obj, const char* name) {
    const hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    if (a < 0) return "<missing>";
    const hid_t t = H5Aget_type(a);
    std::string s(H5Tget_size(t), '\0');
    H5Aread(a, t, s.data());
    H5Tclose(t);
    H5Aclose(a);
    return s.substr(0, s.find('\0'));
}

double readDoubleAttr(hid_t obj, const char* name) {
    double v = -1.0;
    const hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    if (a < 0) return -1.0;
    H5Aread(a, H5T_NATIVE_DOUBLE, &v);
    H5Aclose(a);
    return v;
}

std::vector<hsize_t> readDims(hid_t file, const std::string& path) {
    const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
    if (d < 0) return {};
    const hid_t s = H5Dget_space(d);
    std::vector<hsize_t> dims(H5Sget_simple_extent_ndims(s));
    H5Sget_simple_extent_dims(s, dims.data(), nullptr);
    H5Sclose(s);
    H5Dclose(d);
    return dims;
}

template <class T>
std::vector<T> readAll(hid_t file, const std::string& path, hid_t memType) {
    const hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
    if (d < 0) return {};
    const hid_t s = H5Dget_space(d);
    std::vector<T> v(H5Sget_simple_extent_npoints(s));
    if (!v.empty()) H5Dread(d, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(s);
    H5Dclose(d);
    return v;
}

// --- a minimal XML well-formedness check (tags nest and close, attributes are quoted)

bool isWellFormedXml(const std::string& x, std::string* why) {
    std::vector<std::string> stack;
    size_t i = 0;
    bool sawRoot = false;
    while (i < x.size()) {
        if (x[i] != '<') {
            if (x[i] == '>' || (x[i] == '&' && x.find(';', i) == std::string::npos)) {
                *why = "stray character at " + std::to_string(i);
                return false;
            }
            if (stack.empty() && !std::isspace(static_cast<unsigned char>(x[i]))) {
                *why = "text outside the root at " + std::to_string(i);
                return false;
            }
            ++i;
            continue;
        }
        const size_t end = x.find('>', i);
        if (end == std::string::npos) {
            *why = "unclosed tag";
            return false;
        }
        std::string tag = x.substr(i + 1, end - i - 1);
        i = end + 1;
        if (tag.rfind("?", 0) == 0 || tag.rfind("!--", 0) == 0) continue;
        if (tag.rfind("/", 0) == 0) {
            if (stack.empty() || stack.back() != tag.substr(1)) {
                *why = "mismatched </" + tag.substr(1) + ">";
                return false;
            }
            stack.pop_back();
            continue;
        }
        const bool selfClosing = !tag.empty() && tag.back() == '/';
        if (selfClosing) tag.pop_back();
        const std::string name = tag.substr(0, tag.find_first_of(" \t\n"));
        const std::string attrs = tag.substr(name.size());
        static const std::regex attrRe(R"(^(\s+[A-Za-z_:][\w:.-]*="[^"<]*")*\s*$)");
        if (!std::regex_match(attrs, attrRe)) {
            *why = "bad attributes in <" + name + ">: " + attrs;
            return false;
        }
        if (stack.empty()) {
            if (sawRoot) {
                *why = "two root elements";
                return false;
            }
            sawRoot = true;
        }
        if (!selfClosing) stack.push_back(name);
    }
    if (!stack.empty()) {
        *why = "unclosed <" + stack.back() + ">";
        return false;
    }
    return sawRoot;
}

}  // namespace

TEST(ResultsWriter, WritesHdf5LayoutThatReadsBack) {
    const fs::path dir = makeTestDir("writer");
    const FakeRun run = makeRun();
    const bags::Mesh mesh = makeTetMesh();
    io::OutputDir out(dir, false);
    io::RunInfo info{"scenarios/x.yaml",
                     "kind: seed-load-test\n# text verbatim\n",
                     {"airbag.mesh_size=5 mm"},
                     "bagsim run scenarios/x.yaml"};
    io::LoadTestWriter::Options wo;
    wo.frameEvery = 2;
    {
        io::LoadTestWriter w(out, info, run.options, wo);
        for (const bags::LoadStep& s : run.steps) {
            w.addStep(s, mesh, makePositions(mesh, s));
            EXPECT_TRUE(fs::exists(dir / "INCOMPLETE"));  // marker while running
        }
        // Frames: every 2nd step and the first and last of each branch (c0: 0,2,3,4; c1: 0,2,
        // and 3 once the run finishes).
        EXPECT_EQ(w.getNumFrames(), 6);
        w.finish(run.result);
        EXPECT_EQ(w.getNumFrames(), 7);
        EXPECT_EQ(w.getNumSteps(), 9);
    }
    EXPECT_FALSE(fs::exists(dir / "INCOMPLETE"));
    EXPECT_FALSE(out.isIncomplete());

    const hid_t f = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t meta = H5Gopen2(f, "/meta", H5P_DEFAULT);
    ASSERT_GE(meta, 0);
    EXPECT_EQ(readStringAttr(meta, "status"), "complete");
    EXPECT_EQ(readStringAttr(meta, "version"), bagsim::kVersion);
    EXPECT_EQ(readStringAttr(meta, "program"), "bagsim");
    EXPECT_EQ(readStringAttr(meta, "scenario"), info.scenarioText);
    EXPECT_EQ(readStringAttr(meta, "scenario_file"), "scenarios/x.yaml");
    EXPECT_EQ(readStringAttr(meta, "overrides"), "airbag.mesh_size=5 mm");
    EXPECT_EQ(readStringAttr(meta, "started").size(), 20u);  // 2026-11-22T05:43:49Z
    H5Gclose(meta);

    // Mesh: N x 3 nodes [m] in node order, T x 3 triangles, panel ids.
    EXPECT_EQ(readDims(f, "/mesh/nodes"), (std::vector<hsize_t>{4, 3}));
    const auto nodes = readAll<double>(f, "/mesh/nodes", H5T_NATIVE_DOUBLE);
    ASSERT_EQ(nodes.size(), 12u);
    EXPECT_EQ(nodes[3 * 1 + 0], 1.0);  // node 1 at x = 1
    EXPECT_EQ(nodes[3 * 3 + 2], 1.0);  // node 3 at z = 1
    const auto tris = readAll<int>(f, "/mesh/triangles", H5T_NATIVE_INT);
    ASSERT_EQ(tris.size(), 12u);
    EXPECT_EQ((std::vector<int>(tris.begin() + 3, tris.begin() + 6)), (std::vector<int>{0, 1, 3}));
    EXPECT_EQ(readAll<int>(f, "/mesh/panel", H5T_NATIVE_INT), (std::vector<int>{0, 1, 1, 1}));
    EXPECT_EQ(readAll<int>(f, "/mesh/support_nodes", H5T_NATIVE_INT), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(readAll<int>(f, "/mesh/chambers/0/signs", H5T_NATIVE_INT).size(), 4u);

    // Curves: per-step series, exactly as streamed.
    const auto force0 = readAll<double>(f, "/curves/0/force", H5T_NATIVE_DOUBLE);
    EXPECT_EQ(force0, (std::vector<double>{0.0, 10.0, 25.0, 12.0, 0.0}));
    EXPECT_EQ(readAll<signed char>(f, "/curves/0/loading", H5T_NATIVE_SCHAR),
              (std::vector<signed char>{1, 1, 1, 0, 0}));
    EXPECT_EQ(readAll<double>(f, "/curves/1/displacement", H5T_NATIVE_DOUBLE),
              (std::vector<double>{0.0, 0.003, 0.006, 0.009}));
    EXPECT_EQ(readDims(f, "/curves/1/gauge_pressure"), (std::vector<hsize_t>{4, 1}));
    EXPECT_EQ(readAll<double>(f, "/curves/1/gauge_pressure", H5T_NATIVE_DOUBLE)[3], 5300.0);
    EXPECT_EQ(readAll<int>(f, "/curves/0/newton_iterations", H5T_NATIVE_INT)[4], 7);
    EXPECT_EQ(readAll<double>(f, "/curves/0/stabilization_energy", H5T_NATIVE_DOUBLE)[4], 4e-6);
    EXPECT_EQ(readAll<double>(f, "/curves/0/residual", H5T_NATIVE_DOUBLE)[2], 2e-8);
    const hid_t c1 = H5Gopen2(f, "/curves/1", H5P_DEFAULT);
    EXPECT_EQ(readDoubleAttr(c1, "gas_mass"), 2.0e-3);
    EXPECT_EQ(readDoubleAttr(c1, "stiffness"), 4500.0);
    EXPECT_EQ(readDoubleAttr(c1, "inflated_gauge_pressure"), 4000.0);
    EXPECT_EQ(readStringAttr(c1, "failure"),
              "bottomed out: the block is within 2 mm of the bed board");
    EXPECT_EQ(readStringAttr(c1, "end"), "bottomed-out");
    H5Gclose(c1);
    const hid_t forceDs = H5Dopen2(f, "/curves/0/force", H5P_DEFAULT);
    EXPECT_EQ(readStringAttr(forceDs, "unit"), "N");
    H5Dclose(forceDs);

    // Frames: one N x 3 dataset of positions per frame, with its curve and step.
    H5G_info_t positions;
    ASSERT_GE(H5Gget_info_by_name(f, "/frames/positions", &positions, H5P_DEFAULT), 0);
    EXPECT_EQ(positions.nlinks, 7u);
    EXPECT_EQ(readDims(f, "/frames/positions/6"), (std::vector<hsize_t>{4, 3}));
    EXPECT_EQ(readAll<int>(f, "/frames/curve", H5T_NATIVE_INT),
              (std::vector<int>{0, 0, 0, 0, 1, 1, 1}));
    EXPECT_EQ(readAll<int>(f, "/frames/step", H5T_NATIVE_INT),
              (std::vector<int>{0, 2, 3, 4, 0, 2, 3}));
    const auto pos1 = readAll<double>(f, "/frames/positions/1", H5T_NATIVE_DOUBLE);
    const auto pos6 = readAll<double>(f, "/frames/positions/6", H5T_NATIVE_DOUBLE);
    ASSERT_EQ(pos1.size(), 12u);
    ASSERT_EQ(pos6.size(), 12u);
    EXPECT_DOUBLE_EQ(pos1[3 * 3 + 2], 1.0 - 0.004);  // frame 1 = c0 step 2, node 3 z
    EXPECT_DOUBLE_EQ(pos6[3 * 3 + 0], 0.001);        // frame 6 = c1 step 3, node 3 x
    EXPECT_DOUBLE_EQ(pos6[3 * 3 + 2], 1.0 - 0.009);

    // Summary.
    EXPECT_EQ(readAll<double>(f, "/summary/stiffness", H5T_NATIVE_DOUBLE),
              (std::vector<double>{6000.0, 4500.0}));
    EXPECT_EQ(readAll<int>(f, "/summary/stage", H5T_NATIVE_INT), (std::vector<int>{1, 2}));
    EXPECT_EQ(readAll<int>(f, "/summary/reached_peak", H5T_NATIVE_INT), (std::vector<int>{1, 0}));
    EXPECT_EQ(readAll<double>(f, "/summary/k_fit", H5T_NATIVE_DOUBLE),
              (std::vector<double>{1.5, 2.0}));
    EXPECT_EQ(readAll<double>(f, "/summary/k_seed", H5T_NATIVE_DOUBLE).size(), 6u);
    H5Fclose(f);
}

TEST(ResultsWriter, WritesExactCsvHeadersAndRowsInBoundaryUnits) {
    const fs::path dir = makeTestDir("csv");
    const FakeRun run = makeRun();
    const bags::Mesh mesh = makeTetMesh();
    io::OutputDir out(dir, false);
    io::LoadTestWriter w(out, {}, run.options, {});
    for (const bags::LoadStep& s : run.steps) w.addStep(s, mesh, makePositions(mesh, s));
    w.finish(run.result);

    const auto ld = readLines(dir / "load_displacement.csv");
    ASSERT_EQ(ld.size(), 10u);  // header + 9 steps
    EXPECT_EQ(ld[0], "gas_mass_g,displacement_mm,force_N,pressure_kPa,branch");
    EXPECT_EQ(ld[3], "3.5,4,25,5.2,loading");  // c0 step 2: 4 mm, 25 N, 5200 Pa
    EXPECT_EQ(ld[4], "3.5,2,12,5.3,unloading");
    EXPECT_EQ(ld[9], "2,9,50,5.3,loading");
    const auto st = readLines(dir / "stiffness.csv");
    ASSERT_EQ(st.size(), 3u);
    EXPECT_EQ(st[0], "gas_mass_g,stiffness_N_per_mm,k_min_N_per_mm,k_max_N_per_mm,r2,stage,end");
    EXPECT_EQ(st[1], "3.5,6,5.8,6.1,0.99,1,peak");  // 6000 N/m = 6 N/mm
    EXPECT_EQ(st[2], "2,4.5,4.5,4.5,0.89,2,bottomed-out");
}

TEST(ResultsWriter, KOfMForTheControllersIsTheTautBranchAndReadsBackAsTheirTable) {
    // Reference: the seed sweep's shape, k falling from 3.5 g to 2.75 g and rising again below
    // (docs/seed-load-test.md): the invertible branch is 2.75-3.5 g, increasing in mass; a
    // curve that did not reach its peak ends the branch.
    bags::LoadTestResult r;
    const double m[] = {3.5e-3, 3.25e-3, 3.0e-3, 2.75e-3, 2.5e-3};
    const double k[] = {5000, 3900, 1700, 1600, 2600};
    for (int i = 0; i < 5; ++i) {
        bags::LoadCurve c;
        c.gasMass = m[i];
        c.stiffness = k[i];
        c.reachedPeak = true;
        r.curves.push_back(c);
    }
    const auto km = io::findInvertibleKOfM(r);
    ASSERT_EQ(km.size(), 4u);
    EXPECT_EQ(km.front(), std::make_pair(2.75e-3, 1600.0));
    EXPECT_EQ(km.back(), std::make_pair(3.5e-3, 5000.0));
    bags::LoadTestResult cut = r;
    cut.curves[2].reachedPeak = false;  // 3.0 g stopped before its peak
    EXPECT_EQ(io::findInvertibleKOfM(cut).size(), 2u);
    cut.curves[1].stiffness = std::nan("");
    EXPECT_TRUE(io::findInvertibleKOfM(cut).empty());  // one row cannot be inverted

    // The file reads back as a k_of_m list in boundary units.
    const fs::path dir = makeTestDir("k-of-m");
    const FakeRun run = makeRun();
    const bags::Mesh mesh = makeTetMesh();
    io::OutputDir out(dir, false);
    io::LoadTestWriter w(out, {}, run.options, {});
    for (const bags::LoadStep& s : run.steps) w.addStep(s, mesh, makePositions(mesh, s));
    bags::LoadTestResult both = run.result;
    both.curves[1].reachedPeak = true;  // 2 g at 4.5 N/mm, 3.5 g at 6 N/mm
    w.finish(both);
    const io::ScenarioFile f = io::ScenarioFile::load((dir / io::kKOfMYaml).string());
    const std::vector<io::ScenarioNode> rows = f.getRoot().get("k_of_m").getElements();
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_NEAR(rows[0].getElements()[0].asQuantity(io::Dimension::Mass), 2e-3, 1e-12);
    EXPECT_NEAR(rows[0].getElements()[1].asQuantity(io::Dimension::Stiffness), 4500, 1e-9);
    EXPECT_NEAR(rows[1].getElements()[1].asQuantity(io::Dimension::Stiffness), 6000, 1e-9);

    // The fake run as it is (2 g bottomed out): one row, no file.
    const fs::path none = makeTestDir("k-of-m-none");
    io::OutputDir out2(none, false);
    io::LoadTestWriter w2(out2, {}, run.options, {});
    w2.finish(run.result);
    EXPECT_FALSE(fs::exists(none / io::kKOfMYaml));
}

TEST(ResultsWriter, CurveStoppedByNoConvergenceMarksTheRunPartial) {
    const fs::path dir = makeTestDir("partial");
    FakeRun run = makeRun();
    run.result.curves[1].failure = "no convergence loading at block travel 9 mm";
    const bags::Mesh mesh = makeTetMesh();
    io::OutputDir out(dir, false);
    io::LoadTestWriter w(out, {}, run.options, {});
    for (const bags::LoadStep& s : run.steps) w.addStep(s, mesh, makePositions(mesh, s));
    EXPECT_EQ(w.finish(run.result), "partial");

    // Everything is written, and marked: the marker stays and names the failed curve.
    EXPECT_TRUE(out.isIncomplete());
    const std::string marker = readText(dir / "INCOMPLETE");
    EXPECT_NE(marker.find("status: partial"), std::string::npos) << marker;
    EXPECT_NE(
        marker.find("1 of 2 curves stopped on a numerical failure or outside the model's envelope "
                    "(2 g: no convergence "
                    "loading at block travel 9 mm)"),
        std::string::npos)
        << marker;
    const auto st = readLines(dir / "stiffness.csv");
    ASSERT_EQ(st.size(), 3u);
    EXPECT_EQ(st[1], "3.5,6,5.8,6.1,0.99,1,peak");
    EXPECT_EQ(st[2], "2,4.5,4.5,4.5,0.89,2,failed");
    const hid_t f = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t meta = H5Gopen2(f, "/meta", H5P_DEFAULT);
    EXPECT_EQ(readStringAttr(meta, "status"), "partial");
    EXPECT_NE(readStringAttr(meta, "message").find("2 g: no convergence"), std::string::npos);
    H5Gclose(meta);
    EXPECT_EQ(readAll<int>(f, "/summary/failed", H5T_NATIVE_INT), (std::vector<int>{0, 1}));
    EXPECT_EQ(readAll<double>(f, "/curves/1/force", H5T_NATIVE_DOUBLE).size(), 4u);
    H5Fclose(f);
}

TEST(ResultsWriter, OnlyNoConvergenceCountsAsACurveFailure) {
    bags::LoadCurve c;
    c.reachedPeak = true;
    EXPECT_FALSE(io::isCurveFailed(c));
    EXPECT_EQ(io::getCurveEnd(c), "peak");
    c.reachedPeak = false;
    c.failure = "bottomed out: the block is within 2 mm of the bed board at block travel 140 mm";
    EXPECT_FALSE(io::isCurveFailed(c));
    EXPECT_EQ(io::getCurveEnd(c), "bottomed-out");
    c.failure = "no convergence loading at block travel 12 mm";
    EXPECT_TRUE(io::isCurveFailed(c));
    EXPECT_EQ(io::getCurveEnd(c), "failed");
    c.reachedPeak = true;  // the peak was reached, then unloading failed: still a failure
    c.failure = "no convergence unloading at block travel 3 mm";
    EXPECT_TRUE(io::isCurveFailed(c));
    EXPECT_EQ(io::getCurveEnd(c), "failed");
}

TEST(ResultsWriter, XdmfIsWellFormedAndReferencesExistingDatasets) {
    const fs::path dir = makeTestDir("xdmf");
    const FakeRun run = makeRun();
    const bags::Mesh mesh = makeTetMesh();
    io::OutputDir out(dir, false);
    io::LoadTestWriter::Options wo;
    wo.frameEvery = 2;
    io::LoadTestWriter w(out, {}, run.options, wo);
    for (const bags::LoadStep& s : run.steps) {
        w.addStep(s, mesh, makePositions(mesh, s));
        // Refreshed when curve 1 starts: already there with curve 0's four frames.
        if (s.curve == 1 && s.step == 0) {
            EXPECT_TRUE(fs::exists(dir / "results.xdmf"));
        }
    }
    w.finish(run.result);

    const std::string x = readText(dir / "results.xdmf");
    std::string why;
    EXPECT_TRUE(isWellFormedXml(x, &why)) << why;
    EXPECT_NE(x.find("CollectionType=\"Temporal\""), std::string::npos);
    // One uniform grid and one time per frame.
    size_t grids = 0, times = 0;
    for (size_t p = x.find("GridType=\"Uniform\""); p != std::string::npos;
         p = x.find("GridType=\"Uniform\"", p + 1))
        ++grids;
    for (size_t p = x.find("<Time "); p != std::string::npos; p = x.find("<Time ", p + 1)) ++times;
    EXPECT_EQ(grids, 7u);
    EXPECT_EQ(times, 7u);

    // Every HDF5 reference names an existing dataset whose dimensions match the DataItem's.
    const hid_t f = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    static const std::regex item(
        R"re(<DataItem Dimensions="([0-9 ]+)"[^>]*Format="HDF">results\.h5:([^<]+)</DataItem>)re");
    int refs = 0;
    for (auto it = std::sregex_iterator(x.begin(), x.end(), item); it != std::sregex_iterator();
         ++it) {
        const std::string path = (*it)[2];
        std::istringstream dimsText((*it)[1]);
        std::vector<hsize_t> dims;
        for (hsize_t d; dimsText >> d;) dims.push_back(d);
        EXPECT_GT(H5Lexists(f, path.c_str(), H5P_DEFAULT), 0) << path;
        EXPECT_EQ(readDims(f, path), dims) << path;
        ++refs;
    }
    EXPECT_EQ(refs, 7 * 3);  // triangles, positions, panel per frame
    H5Fclose(f);
}

TEST(OutputDir, RefusesNonEmptyFolderWithoutForce) {
    const fs::path dir = makeTestDir("existing");
    fs::create_directories(dir);
    std::ofstream(dir / "notes.txt") << "keep me\n";
    std::ofstream(dir / "stiffness.csv") << "stale\n";
    try {
        io::OutputDir out(dir, false);
        FAIL() << "a non-empty folder was accepted";
    } catch (const io::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "INCOMPLETE"));  // nothing touched
    io::OutputDir forced(dir, true);
    EXPECT_TRUE(fs::exists(dir / "INCOMPLETE"));
    EXPECT_TRUE(fs::exists(dir / "notes.txt"));       // not ours: left alone
    EXPECT_FALSE(fs::exists(dir / "stiffness.csv"));  // ours: a stale result is removed
    // An empty existing folder is fine without --force; a file in the way is not.
    const fs::path empty = makeTestDir("empty");
    fs::create_directories(empty);
    EXPECT_NO_THROW(io::OutputDir(empty, false));
    EXPECT_THROW(io::OutputDir(dir / "notes.txt", true), io::InputError);
}

TEST(OutputDir, FailedRunKeepsMarkerAndStatus) {
    const fs::path dir = makeTestDir("failed");
    const FakeRun run = makeRun();
    const bags::Mesh mesh = makeTetMesh();
    io::OutputDir out(dir, false);
    {
        io::LoadTestWriter w(out, {}, run.options, {});
        for (int i = 0; i < 4; ++i)
            w.addStep(run.steps[i], mesh, makePositions(mesh, run.steps[i]));
        w.fail("interrupted", "interrupted by the user (SIGINT) in curve 1");
    }
    EXPECT_TRUE(out.isIncomplete());
    const std::string marker = readText(dir / "INCOMPLETE");
    EXPECT_NE(marker.find("status: interrupted"), std::string::npos) << marker;
    EXPECT_FALSE(fs::exists(dir / "stiffness.csv"));  // only a finished run has one
    const hid_t f = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t meta = H5Gopen2(f, "/meta", H5P_DEFAULT);
    EXPECT_EQ(readStringAttr(meta, "status"), "interrupted");
    EXPECT_NE(readStringAttr(meta, "message").find("SIGINT"), std::string::npos);
    H5Gclose(meta);
    // What was computed is kept: 4 steps of curve 0.
    EXPECT_EQ(readAll<double>(f, "/curves/0/force", H5T_NATIVE_DOUBLE).size(), 4u);
    H5Fclose(f);
    EXPECT_EQ(readLines(dir / "load_displacement.csv").size(), 5u);

    // A writer destroyed without finish() (an exception unwinding) also marks the run failed.
    const fs::path dir2 = makeTestDir("unwound");
    io::OutputDir out2(dir2, false);
    {
        io::LoadTestWriter w(out2, {}, run.options, {});
        w.addStep(run.steps[0], mesh, makePositions(mesh, run.steps[0]));
    }
    EXPECT_NE(readText(dir2 / "INCOMPLETE").find("status: failed"), std::string::npos);
}
