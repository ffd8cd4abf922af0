// The bags and the body in results.h5 and results.xdmf (io::ArrayResultsWriter::setShapes): a
// tetrahedron for the bags and one for the body, frames every 0.1 s over 1 s with shapes every
// 0.25 s: the shapes are saved at 0, 0.3 (the first output at or after 0.25), 0.5, 0.8 and at
// the end (1.0 s), as float32 [N, 3]; results.xdmf names every dataset with its dimensions.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <io/ArrayResults.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

namespace fs = std::filesystem;

TEST(ArrayShapesOutput, ShapesAreSavedAtTheIntervalAndTheEndAndXdmfNamesThem) {
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "test-output" / "io" / "array-shapes";
    fs::remove_all(dir);
    fs::create_directories(dir.parent_path());
    io::OutputDir out(dir, false);
    cosim::PressureMatOptions mo;
    mo.rows = 4;
    mo.columns = 2;
    io::ArrayResultsWriter w(out, {"s.yaml", "kind: patient-on-array\n", {}, "bagsim run s.yaml"},
                             mo);
    cosim::SurfaceMesh tet;
    tet.triangles.resize(3, 4);
    tet.triangles << 0, 0, 0, 1, 2, 1, 3, 2, 1, 3, 2, 3;
    tet.triangleGroup = {7, 7, 7, 7};
    tet.groupNames = {"one"};
    w.setShapes(tet, tet, 0.25, 1.0);
    cosim::PressureMat mat(mo);
    std::vector<double> saved;
    for (int k = 0; k <= 10; ++k) {
        io::ArrayFrame f;
        f.time = 0.1 * k;
        f.mat = &mat;
        Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Random(3, 4), y = x * 2.0;
        if (w.wantsShapes(f.time)) {
            f.bagNodes = &x;
            f.bodyNodes = &y;
            saved.push_back(f.time);
        }
        w.addFrame(f);
    }
    w.finish("done");
    ASSERT_EQ(saved.size(), 5u);
    const double expected[] = {0.0, 0.3, 0.5, 0.8, 1.0};
    for (size_t i = 0; i < saved.size(); ++i) EXPECT_NEAR(saved[i], expected[i], 1e-9);

    const hid_t f = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    for (const char* set : {"bags", "body"})
        for (int k = 0; k < 5; ++k) {
            const std::string name =
                std::string("/shapes/") + set + "/positions/" + std::to_string(k);
            const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
            ASSERT_GE(d, 0) << name;
            const hid_t sp = H5Dget_space(d), ty = H5Dget_type(d);
            hsize_t dims[2] = {0, 0};
            EXPECT_EQ(H5Sget_simple_extent_dims(sp, dims, nullptr), 2);
            EXPECT_EQ(dims[0], 4u);
            EXPECT_EQ(dims[1], 3u);
            EXPECT_EQ(H5Tget_size(ty), 4u) << "float32";
            H5Tclose(ty), H5Sclose(sp), H5Dclose(d);
        }
    H5Fclose(f);

    std::stringstream x;
    x << std::ifstream(dir / "results.xdmf").rdbuf();
    const std::string xdmf = x.str();
    for (const char* coll : {"\"pressure mat\"", "\"bags\"", "\"body\""})
        EXPECT_NE(xdmf.find(std::string("<Grid Name=") + coll + " GridType=\"Collection\""),
                  std::string::npos)
            << coll;
    EXPECT_NE(xdmf.find("<Topology TopologyType=\"Triangle\" NumberOfElements=\"4\">"),
              std::string::npos);
    EXPECT_NE(xdmf.find("results.h5:/shapes/body/positions/4</DataItem>"), std::string::npos);
    EXPECT_EQ(xdmf.find("positions/5"), std::string::npos);
    EXPECT_NE(xdmf.find("<Time Value=\"0.8\"/>"), std::string::npos);
    EXPECT_NE(xdmf.find("results.h5:/shapes/bags/bag</DataItem>"), std::string::npos);
}
