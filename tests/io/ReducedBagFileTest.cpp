// The reduced bag's calibration file (io/ReducedBagFile.h) and the scenario keys bag.model and
// bag.calibration: a calibration written and read back is the same; bad records, bad
// numbers and a calibration of another bag or mesh are located errors.
#include <gtest/gtest.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>
#include <io/ReducedBagFile.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "InputErrorTestUtil.h"

using io::test::expectInputError;

namespace {

cosim::ReducedBagCalibration small() {
    cosim::ReducedBagCalibration c;
    c.source = "made by hand\nfor a test";
    c.masses = {3e-3, 4e-3, 5e-3};
    c.gaugePressures = {0.0, 1e4, 2e4};
    c.volumes = {2.5e-3, 3.0e-3, 3.4e-3};
    c.nx = 3, c.ny = 2, c.x0 = 0.01, c.y0 = -0.02, c.pitch = 0.01;
    for (int i = 0; i < 3; ++i) {
        Eigen::MatrixXd t(3, 2);
        t << 0.1 + i * 0.01, 0.11, 0.12, std::nan(""), 0.09, 0.08;
        c.top.push_back(t);
    }
    c.depths = {0.0, 0.01, 0.03};
    c.pressureFactor = Eigen::MatrixXd::Constant(3, 3, 1.25);
    c.volumeFactor = Eigen::MatrixXd::Constant(3, 3, 0.75);
    c.pressureFactor(2, 1) = 1.5;
    c.skirt = 0.5;
    return c;
}

std::string tempFile(const std::string& name) { return testing::TempDir() + name; }

const std::string kScenario =
    "kind: patient-on-array\n"                                                   // 1
    "patient: {sex: male, height: 1.75 m, mass: 75 kg, position: [0 m, 0 m]}\n"  // 2
    "bag: {mesh_size: MESH, model: MODEL CAL}\n"                                 // 3
    "array: {rows: 6, columns: 7, row_pitch: 360 mm, column_pitch: 105 mm,\n"    // 4
    "        centre: [-30 mm, 0 mm], orientation: [along, along-flipped], gas_mass: 4.5 g}\n"
    "run: {settle_time: 1 s, duration: 1 s}\n";

io::PatientOnArrayScenario readWith(const std::string& mesh, const std::string& model,
                                    const std::string& cal) {
    std::string t = kScenario;
    t.replace(t.find("MESH"), 4, mesh);
    t.replace(t.find("MODEL"), 5, model);
    t.replace(t.find("CAL"), 3, cal.empty() ? "" : ", calibration: " + cal);
    // As if the file lay in scenarios/tests/, for the relative calibration path.
    return io::readPatientOnArrayScenario(
        io::ScenarioFile::parse(t, std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/r.yaml"));
}

}  // namespace

TEST(ReducedBagFile, AWrittenCalibrationReadsBackTheSame) {
    const cosim::ReducedBagCalibration c = small();
    const std::string path = tempFile("reduced-roundtrip.txt");
    io::writeReducedBagCalibration(path, c);
    const auto r = io::readReducedBagCalibration(path);
    EXPECT_EQ(r->source, c.source);
    EXPECT_EQ(r->masses, c.masses);
    EXPECT_EQ(r->depths, c.depths);
    EXPECT_EQ(r->nx, 3);
    EXPECT_DOUBLE_EQ(r->skirt, 0.5);
    EXPECT_DOUBLE_EQ(r->pressureFactor(2, 1), 1.5);
    EXPECT_TRUE(std::isnan(r->top[1](1, 1)));
    EXPECT_NEAR(r->top[2](0, 0), 0.12, 1e-6);
    EXPECT_EQ(r->panelSink, 0.0);  // no record: the panel coupling off
    // With the panel coupling, its record comes back to the digit written.
    cosim::ReducedBagCalibration coupled = small();
    coupled.panelSink = 1.057612147e-05, coupled.panelLift = 6.080769544e-06,
    coupled.panelBlend = 0.02;
    io::writeReducedBagCalibration(path, coupled);
    const auto rc = io::readReducedBagCalibration(path);
    EXPECT_DOUBLE_EQ(rc->panelSink, 1.057612147e-05);
    EXPECT_DOUBLE_EQ(rc->panelLift, 6.080769544e-06);
    EXPECT_DOUBLE_EQ(rc->panelBlend, 0.02);
    std::remove(path.c_str());
}

TEST(ReducedBagFile, BadRecordsAndNumbersAreLocated) {
    const std::string path = tempFile("reduced-bad.txt");
    io::writeReducedBagCalibration(path, small());
    std::string text;
    {
        std::ifstream f(path);
        text.assign(std::istreambuf_iterator<char>(f), {});
    }
    auto withLine = [&](const std::string& from, const std::string& to) {
        std::string t = text;
        t.replace(t.find(from), from.size(), to);
        std::ofstream(path) << t;
        return expectInputError([&] { io::readReducedBagCalibration(path); });
    };
    const io::InputError e1 = withLine("skirt 0.5", "skrit 0.5");
    EXPECT_EQ(e1.getWhere(), path);
    EXPECT_EQ(e1.getKey(), "skrit");
    EXPECT_EQ(e1.getLine(),
              9);  // after the magic, comment, 2 source lines, geometry, gas, board, rim
    EXPECT_NE(std::string(e1.what()).find("valid: source"), std::string::npos);
    const io::InputError e2 = withLine("skirt 0.5", "skirt 0.5x");
    EXPECT_EQ(e2.getKey(), "skirt");
    EXPECT_NE(std::string(e2.what()).find("\"0.5x\" is not a number"), std::string::npos);
    const io::InputError e6 = withLine("skirt 0.5", "skirt 0.5\npanel_coupling 1e-5 -6e-6 0.02");
    EXPECT_EQ(e6.getKey(), "panel_coupling");
    EXPECT_EQ(e6.getLine(), 10);
    EXPECT_NE(std::string(e6.what()).find("[0, 1e-3)"), std::string::npos);
    const io::InputError e3 = withLine("depths 0 0.01 0.03", "depths 0 0.03 0.01");
    EXPECT_NE(std::string(e3.what()).find("ascending"), std::string::npos);
    // A calibration of format 1 (its volume factors belong to the overlap volume before
    // version 2) is refused on its first line, naming the version and how to remake it.
    const io::InputError e5 = withLine("bagsim-reduced-bag 2", "bagsim-reduced-bag 1");
    EXPECT_EQ(e5.getLine(), 1);
    EXPECT_NE(std::string(e5.what()).find("format version 1"), std::string::npos);
    EXPECT_NE(std::string(e5.what()).find("bench_reduced_bag calibrate"), std::string::npos);
    const io::InputError e4 =
        expectInputError([] { io::readReducedBagCalibration("/nonexistent/c.txt"); });
    EXPECT_NE(std::string(e4.what()).find("cannot open"), std::string::npos);
    std::remove(path.c_str());
}

TEST(ReducedBagFile, TheScenarioKeysChooseTheModelAndCheckTheCalibration) {
    const std::string shipped = "../../data/reduced-bag/literal-30mm.txt";
    EXPECT_EQ(readWith("30 mm", "finite-element", "").options.model,
              cosim::PatientOnArrayOptions::BagModel::FiniteElement);
    const io::PatientOnArrayScenario r = readWith("30 mm", "reduced", shipped);
    EXPECT_EQ(r.options.model, cosim::PatientOnArrayOptions::BagModel::Reduced);
    // The coupling's defaults follow the model: the tangent scheme and the body at 1e-4 for
    // reduced bags, the implicit scheme and 1e-6 for finite-element ones; a scenario's own
    // coupling keys stand.
    EXPECT_EQ(r.options.coupling.scheme, cosim::Scheme::Tangent);
    EXPECT_DOUBLE_EQ(r.options.integrator.accuracy, 1e-4);
    const io::PatientOnArrayScenario fe = readWith("30 mm", "finite-element", "");
    EXPECT_EQ(fe.options.coupling.scheme, cosim::Scheme::Implicit);
    EXPECT_DOUBLE_EQ(fe.options.integrator.accuracy, 1e-6);
    {
        std::string t = kScenario;
        t.replace(t.find("MESH"), 4, "30 mm");
        t.replace(t.find("MODEL"), 5, "reduced");
        t.replace(t.find("CAL"), 3, ", calibration: " + shipped);
        t += "coupling: {scheme: implicit, body_accuracy: 1e-6}\n";
        const io::PatientOnArrayScenario own = io::readPatientOnArrayScenario(
            io::ScenarioFile::parse(t, std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/r.yaml"));
        EXPECT_EQ(own.options.coupling.scheme, cosim::Scheme::Implicit);
        EXPECT_DOUBLE_EQ(own.options.integrator.accuracy, 1e-6);
    }
    ASSERT_TRUE(r.options.reduced);
    EXPECT_DOUBLE_EQ(r.options.reduced->geometry.meshSize, 0.03);
    const io::InputError e1 = expectInputError([] { readWith("30 mm", "reduced", ""); });
    EXPECT_EQ(e1.getKey(), "bag.calibration");
    EXPECT_EQ(e1.getLine(), 3);
    const io::InputError e2 = expectInputError([] { readWith("30 mm", "fe", ""); });
    EXPECT_EQ(e2.getKey(), "bag.model");
    EXPECT_NE(std::string(e2.what()).find("finite-element"), std::string::npos);
    const io::InputError e3 = expectInputError([&] { readWith("20 mm", "reduced", shipped); });
    EXPECT_EQ(e3.getKey(), "bag.calibration");
    EXPECT_NE(std::string(e3.what()).find("bag.mesh_size"), std::string::npos);
    const io::InputError e4 = expectInputError([] { readWith("30 mm", "reduced", "none.txt"); });
    EXPECT_NE(std::string(e4.what()).find("no such file"), std::string::npos);
    const io::InputError e5 =
        expectInputError([&] { readWith("30 mm", "finite-element", shipped); });
    EXPECT_EQ(e5.getKey(), "bag.calibration");
    // Friction of the body on the reduced bag's film (docs/reduced-bag.md#friction): taken,
    // with the tangent scheme (the bag hands the body its friction's tangent) and its stick
    // distance (5 mm unless set); bag.stick_distance is the reduced bag's alone, in range,
    // and the reduced bag has the stick-slip law only.
    const io::PatientOnArrayScenario fr =
        readWith("30 mm", "reduced", shipped + ", body_friction: 0.4, stick_distance: 8 mm");
    EXPECT_DOUBLE_EQ(fr.options.contact.friction, 0.4);
    EXPECT_DOUBLE_EQ(fr.options.reducedFriction.stickDistance, 8e-3);
    EXPECT_EQ(fr.options.coupling.scheme, cosim::Scheme::Tangent);
    EXPECT_NO_THROW(fr.options.validate());
    EXPECT_DOUBLE_EQ(readWith("30 mm", "reduced", shipped + ", body_friction: 0.4")
                         .options.reducedFriction.stickDistance,
                     5e-3);
    const io::InputError e6 = expectInputError([] {
        std::string t = kScenario;
        t.replace(t.find("MESH"), 4, "30 mm");
        t.replace(t.find("MODEL"), 5, "finite-element");
        t.replace(t.find("CAL"), 3, ", stick_distance: 8 mm");
        io::readPatientOnArrayScenario(
            io::ScenarioFile::parse(t, std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/r.yaml"));
    });
    EXPECT_EQ(e6.getKey(), "bag.stick_distance");
    EXPECT_NE(std::string(e6.what()).find("model: reduced"), std::string::npos) << e6.what();
    const io::InputError e6b = expectInputError([&] {
        readWith("30 mm", "reduced", shipped + ", body_friction: 0.4, stick_distance: 90 mm");
    });
    EXPECT_EQ(e6b.getKey(), "bag.stick_distance");
    const io::InputError e6c = expectInputError([&] {
        readWith("30 mm", "reduced", shipped + ", body_friction: 0.4, friction_law: regularised");
    });
    EXPECT_EQ(e6c.getKey(), "bag.friction_law");
    EXPECT_NE(std::string(e6c.what()).find("stick-slip"), std::string::npos) << e6c.what();
    // Nor a soft-tissue layer: the reduced bag's contact law is its own.
    const io::InputError e7 = expectInputError([&] {
        readWith("30 mm", "reduced",
                 shipped + ", body_tissue: {thickness: 20 mm, modulus: 30 kPa}");
    });
    EXPECT_EQ(e7.getKey(), "bag.body_tissue");
    EXPECT_NE(std::string(e7.what()).find("model: reduced"), std::string::npos) << e7.what();
    EXPECT_TRUE(readWith("30 mm", "reduced", shipped).options.segmentTissue.empty());  // bare
    const io::InputError e7b = expectInputError(
        [&] { readWith("30 mm", "reduced", shipped + ", body_tissue: published"); });
    EXPECT_EQ(e7b.getKey(), "bag.body_tissue");
    EXPECT_NE(std::string(e7b.what()).find("model: reduced"), std::string::npos) << e7b.what();
    // Nor the film's damper: it has no film.
    const io::InputError e8 = expectInputError(
        [&] { readWith("30 mm", "reduced", shipped + ", film_damping: 1e5 Pa/m"); });
    EXPECT_EQ(e8.getKey(), "bag.film_damping");
    EXPECT_NE(std::string(e8.what()).find("finite-element"), std::string::npos) << e8.what();
}
