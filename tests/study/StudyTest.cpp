// The study file's reader and the table (docs/studies.md): grids multiply, zips pair, random
// samples are seeded and within their bounds, every bad input is located in the study file, a
// case's key depends on its parameters only, records survive a round trip.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <io/InputError.h>
#include <io/StudyScenario.h>
#include <io/StudyTable.h>
#include <study/StudyRunner.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <unistd.h>

namespace {

const std::string kTests = std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/";

/// A study file next to the tests' scenarios, so `scenario: tiny-load-test.yaml` resolves.
io::StudyScenario readText(const std::string& text) {
    return io::readStudyScenario(io::ScenarioFile::parse(text, kTests + "inline-study.yaml"));
}

/// The InputError of reading `text`, or fails the test.
io::InputError readError(const std::string& text) {
    try {
        readText(text);
    } catch (const io::InputError& e) {
        return e;
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return io::InputError("", 0, "", "");
}

const char* kHead = "kind: study\nscenario: tiny-load-test.yaml\n";

TEST(StudyScenario, GridMultipliesAndZipPairsInOrder) {
    const io::StudyScenario s = readText(std::string(kHead) +
                                         "parameters:\n"
                                         "  grid:\n"
                                         "    contact.penalty: [1e7 Pa/m, 1e8 Pa/m]\n"
                                         "    airbag.mesh_size: [25 mm, 3 cm]\n"
                                         "  zip:\n"
                                         "    test.peak_force: [4 N, 3 N, 5 N]\n"
                                         "    test.gas_masses: [[3.5 g], [3.4 g], [3.3 g]]\n");
    ASSERT_EQ(s.parameters.size(), 4u);
    EXPECT_EQ(s.cases.size(), 2u * 2u * 3u);
    EXPECT_EQ(s.parameters[0].key, "contact.penalty");
    EXPECT_EQ(s.parameters[0].unit, "Pa/m");
    EXPECT_EQ(s.parameters[1].unit, "mm");
    EXPECT_EQ(s.parameters[3].unit, "g");  // a list of one quantity is a number in the table
    // The first grid key varies slowest; "3 cm" is converted to the column's unit.
    EXPECT_EQ(s.cases[0].values[0], "1e7 Pa/m");
    EXPECT_EQ(s.cases[3].values[1], "3 cm");
    EXPECT_DOUBLE_EQ(s.cases[3].numbers[1], 30.0);
    EXPECT_EQ(s.cases[6].values[0], "1e8 Pa/m");
    EXPECT_EQ(s.cases[1].values[2], "3 N");
    EXPECT_EQ(s.cases[1].values[3], "[3.4 g]");
    EXPECT_DOUBLE_EQ(s.cases[1].numbers[3], 3.4);
    // The default output of a load test: the stiffness per gas mass.
    ASSERT_EQ(s.outputs.size(), 1u);
    EXPECT_EQ(s.outputs[0].per, "gas_mass_g");
    EXPECT_EQ(s.baseKind, "seed-load-test");
}

TEST(StudyScenario, RandomSamplesAreSeededAndWithinBounds) {
    const std::string text =
        std::string(kHead) +
        "parameters:\n"
        "  random:\n"
        "    samples: 50\n"
        "    seed: 7\n"
        "    values:\n"
        "      airbag.height: {uniform: [140 mm, 160 mm]}\n"
        "      test.peak_force: {normal: [4 N, 0.5 N], within: [3.5 N, 4.2 N]}\n";
    const io::StudyScenario a = readText(text), b = readText(text);
    ASSERT_EQ(a.cases.size(), 50u);
    for (size_t i = 0; i < a.cases.size(); ++i) {
        EXPECT_EQ(a.cases[i].values, b.cases[i].values);
        EXPECT_GE(a.cases[i].numbers[0], 140.0);
        EXPECT_LE(a.cases[i].numbers[0], 160.0);
        EXPECT_GE(a.cases[i].numbers[1], 3.5);
        EXPECT_LE(a.cases[i].numbers[1], 4.2);
    }
    EXPECT_NE(a.cases[0].values[0], a.cases[1].values[0]);
    const io::StudyScenario c = readText(text.substr(0, text.find("seed: 7")) + "seed: 8" +
                                         text.substr(text.find("seed: 7") + 7));
    EXPECT_NE(a.cases[0].values[0], c.cases[0].values[0]);
}

TEST(StudyScenario, RefusedValueIsLocatedAtItsLineInTheStudyFile) {
    const io::InputError e = readError(std::string(kHead) +
                                       "parameters:\n"
                                       "  grid:\n"
                                       "    test.gas_masses: [[3.5 g], [-1 g]]\n");
    EXPECT_EQ(e.getLine(), 5);
    EXPECT_EQ(e.getKey(), "parameters.grid.test.gas_masses");
    const std::string what = e.what();
    EXPECT_NE(what.find("inline-study.yaml:5: key 'parameters.grid.test.gas_masses': case 2 sets "
                        "test.gas_masses = [-1 g]"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("greater than zero"), std::string::npos) << what;
}

TEST(StudyScenario, MistakesNameFileLineKeyAndWhatIsValid) {
    struct Case {
        std::string body, expect;
    };
    const std::vector<Case> cases = {
        {"parameters:\n  gird: {contact.penalty: [1e7 Pa/m]}\n", "did you mean 'grid'"},
        {"parameters:\n  grid: {contact.penalty: 1e7 Pa/m}\n", "a non-empty list"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\n  zip: {test.peak_force: [1 N, 2 N], "
         "test.block: [50 mm]}\n",
         "has 1 values and 'test.peak_force' has 2"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\n  zip: {contact.penalty: [1e8 "
         "Pa/m]}\n",
         "is swept twice"},
        {"parameters:\n  grid: {airbag.colour: [red]}\n", "airbag.colour"},
        {"parameters:\n  random: {samples: 3, values: {airbag.height: {uniform: [160 mm, 15 "
         "cm]}}}\n",
         "same unit"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\noutputs:\n  - {file: ../x.csv, "
         "column: a}\n",
         "a CSV file the run writes in its folder"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\noutputs:\n  - {file: s.csv, column: "
         "a, "
         "reduce: median}\n",
         "first, last, min, max, mean"},
        // Outputs are checked against the files and columns the base scenario's kind writes
        // (io/ResultFiles.h), before any case runs.
        // A study's name is its output folder's (out/NAME): checked as a run's.
        {"name: ../..\nparameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\n",
         "names the output folder: use letters, digits"},
        {"name: ..\nparameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\n",
         "which is not a folder of its own"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\noutputs:\n  - {file: regions.csv, "
         "column: patch_peak_mmHg}\n",
         "\"regions.csv\" is not a file a seed-load-test run writes; valid: load_displacement.csv, "
         "stiffness.csv, rig_readings.csv"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\noutputs:\n  - {file: stiffness.csv, "
         "column: stifness_N_per_mm}\n",
         "\"stifness_N_per_mm\": stiffness.csv has no such column; its columns: gas_mass_g, "
         "stiffness_N_per_mm, k_min_N_per_mm"},
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\noutputs:\n  - {file: stiffness.csv, "
         "column: r2, per: gas_mass}\n",
         "key 'outputs[0].per': \"gas_mass\": stiffness.csv has no such column"},
        // A file only some runs of the kind write: the tiny load test has no rig section.
        {"parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\noutputs:\n  - {file: "
         "rig_readings.csv, column: force_N}\n",
         "rig_readings.csv is written only by a run with a rig section, and case 1 of"},
    };
    for (const Case& c : cases) {
        const io::InputError e = readError(std::string(kHead) + c.body);
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(kTests + "inline-study.yaml:", 0), 0u) << what;
        EXPECT_GT(e.getLine(), 0) << what;
        EXPECT_NE(what.find(c.expect), std::string::npos) << what;
    }
    const io::InputError base =
        readError("kind: study\nscenario: nowhere.yaml\nparameters: {grid: {a.b: [1]}}\n");
    EXPECT_NE(std::string(base.what()).find("inline-study.yaml:2: key 'scenario'"),
              std::string::npos)
        << base.what();
}

TEST(StudyScenario, CaseKeyDependsOnParametersAndBaseOnly) {
    const io::StudyScenario a = readText(
        std::string(kHead) + "parameters: {grid: {contact.penalty: [1e7 Pa/m, 1e8 Pa/m]}}\n");
    const io::StudyScenario b = readText(std::string(kHead) + "description: another text\n" +
                                         "parameters: {grid: {contact.penalty: [1e8 Pa/m]}}\n");
    EXPECT_EQ(io::getCaseKey(a, a.cases[1]), io::getCaseKey(b, b.cases[0]));
    EXPECT_NE(io::getCaseKey(a, a.cases[0]), io::getCaseKey(a, a.cases[1]));
    EXPECT_EQ(io::getCaseKey(a, a.cases[0]).size(), 16u);
}

TEST(StudyRecord, RoundTripsAndRefusesATruncatedOne) {
    study::CaseRecord r;
    r.status = "failed";
    r.reason = "numerical failure:\nno convergence";
    r.seconds = 1.25;
    r.outputs.push_back({0, "stiffness_N_per_mm[gas_mass_g=3.5]", "0.123"});
    const std::string text = study::formatRecord(r);
    study::CaseRecord back;
    ASSERT_TRUE(study::parseRecord(text, &back));
    EXPECT_EQ(back.status, "failed");
    EXPECT_EQ(back.reason, "numerical failure: no convergence");
    EXPECT_DOUBLE_EQ(back.seconds, 1.25);
    ASSERT_EQ(back.outputs.size(), 1u);
    EXPECT_EQ(back.outputs[0].name, "stiffness_N_per_mm[gas_mass_g=3.5]");
    EXPECT_EQ(back.outputs[0].value, "0.123");
    EXPECT_FALSE(study::parseRecord(text.substr(0, text.size() - 4), &back));
}

TEST(StudyTable, RowPerCaseWithUnitsStatusAndOutputs) {
    const io::StudyScenario s =
        readText(std::string(kHead) +
                 "parameters: {grid: {contact.penalty: [1e7 Pa/m, 1e8 Pa/m, 1e9 Pa/m]}}\n");
    study::CaseRecord ok, bad;
    ok.status = "ok";
    ok.outputs.push_back({0, "k[m=3.5]", "0.5"});
    bad.status = "failed";
    bad.reason = "no convergence, twice";
    const io::StudyTable t = study::buildStudyTable(s, {&ok, &bad, nullptr}, {false, false, true});
    ASSERT_EQ(t.header.size(), 7u);
    EXPECT_EQ(t.header[2], "contact.penalty [Pa/m]");
    EXPECT_EQ(t.header[6], "k[m=3.5]");
    EXPECT_EQ(t.rows[0][2], "10000000");
    EXPECT_EQ(t.rows[0][3], "ok");
    EXPECT_EQ(t.rows[0][6], "0.5");
    EXPECT_EQ(t.rows[1][3], "failed");
    EXPECT_EQ(t.rows[1][6], "");
    EXPECT_EQ(t.rows[2][3], "interrupted");
    EXPECT_EQ(t.status, "incomplete");
    EXPECT_EQ(io::quoteCsvCell(t.rows[1][4]), "\"no convergence, twice\"");
    EXPECT_EQ(io::splitCsvLine("a,\"b, \"\"c\"\"\",d"),
              (std::vector<std::string>{"a", "b, \"c\"", "d"}));
}

TEST(StudyTable, Hdf5HoldsTheSameTable) {
    io::StudyTable t;
    t.header = {"case", "contact.penalty [Pa/m]", "status", "k"};
    t.rows = {{"1", "1e7", "ok", "0.5"}, {"2", "1e8", "failed", ""}};
    t.status = "complete";
    const std::string path =
        (std::filesystem::temp_directory_path() / "bagsim-study-table-test.h5").string();
    io::writeStudyH5(t, path);
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    // Column 1 is numeric (doubles), column 2 strings, column 3 numeric with NaN for "".
    double v[2] = {0, 0};
    hid_t d = H5Dopen2(f, "/table/001", H5P_DEFAULT);
    ASSERT_GE(d, 0);
    ASSERT_GE(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v), 0);
    EXPECT_DOUBLE_EQ(v[0], 1e7);
    EXPECT_DOUBLE_EQ(v[1], 1e8);
    H5Dclose(d);
    d = H5Dopen2(f, "/table/003", H5P_DEFAULT);
    ASSERT_GE(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v), 0);
    EXPECT_DOUBLE_EQ(v[0], 0.5);
    EXPECT_TRUE(std::isnan(v[1]));
    H5Dclose(d);
    d = H5Dopen2(f, "/table/002", H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    char* cells[2] = {nullptr, nullptr};
    ASSERT_GE(H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, cells), 0);
    EXPECT_STREQ(cells[0], "ok");
    EXPECT_STREQ(cells[1], "failed");
    const hid_t name = H5Aopen(d, "name", H5P_DEFAULT);
    EXPECT_GE(name, 0);
    H5Aclose(name);
    const hid_t space = H5Dget_space(d);
    H5Dvlen_reclaim(type, space, H5P_DEFAULT, cells);
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(d);
    H5Fclose(f);
    std::filesystem::remove(path);
}

}  // namespace

TEST(StudyOutputs, ATimeSeriesIsReducedPerValueAndARepeatedValueWithoutReduceIsNamed) {
    // A regions.csv-like time series: two regions at three times. `per: region` with `reduce:
    // last` gives each region's value at the end; `max` its largest; without `reduce` the
    // repeated region is refused by name (it would otherwise give one column three times).
    const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                      ("bagsim-study-outputs-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    {
        std::ofstream f(dir / "regions.csv");
        f << "time_s,region,patch_peak_mmHg\n"
             "0.5,sacrum,30\n0.5,heel_l,50\n1.0,sacrum,41\n1.0,heel_l,45\n1.5,sacrum,38\n"
             "1.5,heel_l,47\n";
    }
    auto collect = [&](const std::string& output, std::string* missing) {
        const bool array = output.find("regions.csv") != std::string::npos;
        const io::StudyScenario s = readText(
            array ? "kind: study\nscenario: supine-on-array-coarse.yaml\nparameters:\n  grid: "
                    "{run.duration: [1 s]}\noutputs:\n  - " +
                        output + "\n"
                  : std::string(kHead) +
                        "parameters:\n  grid: {contact.penalty: [1e7 Pa/m]}\n"
                        "outputs:\n  - " +
                        output + "\n");
        study::CaseRecord r;
        *missing = study::collectOutputs(s, dir, &r);
        std::map<std::string, std::string> out;
        for (const auto& o : r.outputs) out[o.name] = o.value;
        return out;
    };
    std::string missing;
    auto last = collect("{file: regions.csv, column: patch_peak_mmHg, per: region, reduce: last}",
                        &missing);
    EXPECT_EQ(missing, "");
    ASSERT_EQ(last.size(), 2u);
    EXPECT_EQ(last["patch_peak_mmHg:last[region=sacrum]"], "38");
    EXPECT_EQ(last["patch_peak_mmHg:last[region=heel_l]"], "47");
    auto max =
        collect("{file: regions.csv, column: patch_peak_mmHg, per: region, reduce: max}", &missing);
    EXPECT_EQ(max["patch_peak_mmHg:max[region=sacrum]"], "41");
    EXPECT_EQ(max["patch_peak_mmHg:max[region=heel_l]"], "50");
    collect("{file: regions.csv, column: patch_peak_mmHg, per: region}", &missing);
    EXPECT_NE(missing.find("regions.csv has 3 rows with region = sacrum; give the output a "
                           "reduce (last: the value at the end of a time series"),
              std::string::npos)
        << missing;
    // One row per value (as the load test's stiffness.csv has) needs no reduce.
    {
        std::ofstream f(dir / "stiffness.csv");
        f << "gas_mass_g,stiffness_N_per_mm\n3.5,5.8\n3,1.7\n";
    }
    auto k =
        collect("{file: stiffness.csv, column: stiffness_N_per_mm, per: gas_mass_g}", &missing);
    EXPECT_EQ(missing, "");
    EXPECT_EQ(k["stiffness_N_per_mm[gas_mass_g=3.5]"], "5.8");
    EXPECT_EQ(k["stiffness_N_per_mm[gas_mass_g=3]"], "1.7");
    std::filesystem::remove_all(dir);
}
