// Located errors: every mistake in a scenario names the file, the line, the key and what is
// valid; misspelt keys suggest the closest valid one; --set overrides point at themselves.
#include <gtest/gtest.h>
#include "InputErrorTestUtil.h"

#include <io/Scenario.h>

#include <functional>
#include <string>

using io::Dimension;
using io::InputError;
using io::ScenarioFile;
using io::ScenarioNode;

namespace {

using io::test::expectInputError;

// Line numbers below count from 1 at "kind:".
const char* kText =
    "kind: test\n"            // 1
    "airbag:\n"               // 2
    "  long_side: 350 mm\n"   // 3
    "  widht: 100 mm\n"       // 4
    "gas:\n"                  // 5
    "  mass: 3.5 kg/m\n"      // 6
    "  temperature: 23\n"     // 7
    "  process: isotermal\n"  // 8
    "list: [1 mm, 2 g]\n"     // 9
    "flag: maybe\n";          // 10

}  // namespace

TEST(EditDistance, CountsInsertionsDeletionsSubstitutions) {
    // Reference: Levenshtein distances worked by hand.
    EXPECT_EQ(io::calcEditDistance("kitten", "sitting"), 3);
    EXPECT_EQ(io::calcEditDistance("", "abc"), 3);
    EXPECT_EQ(io::calcEditDistance("width", "widht"), 2);
    EXPECT_EQ(io::calcEditDistance("mesh_size", "mesh_size"), 0);
    EXPECT_EQ(io::findClosest("widht", {"long_side", "width", "height"}), "width");
    EXPECT_EQ(io::findClosest("c10", {"C10", "C20", "C30"}), "C10");
    EXPECT_EQ(io::findClosest("banana", {"long_side", "width", "height"}), "");
}

TEST(Scenario, UnknownKeySuggestsClosestWithLine) {
    const ScenarioFile f = ScenarioFile::parse(kText, "scenarios/x.yaml");
    const ScenarioNode airbag = f.getRoot().getSection("airbag");
    const InputError e = expectInputError([&] {
        airbag.checkKeys({"long_side", "width"}, {"height"});
    });
    EXPECT_EQ(e.getWhere(), "scenarios/x.yaml");
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_EQ(e.getKey(), "airbag.widht");
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scenarios/x.yaml:4: key 'airbag.widht': unknown key", 0), 0u) << what;
    EXPECT_NE(what.find("did you mean 'width'?"), std::string::npos) << what;
    EXPECT_NE(what.find("valid keys: long_side, width, height"), std::string::npos) << what;
}

TEST(Scenario, MissingKeyNamesSectionAndListsRequired) {
    const ScenarioFile f = ScenarioFile::parse(kText, "x.yaml");
    const ScenarioNode airbag = f.getRoot().getSection("airbag");
    const InputError e = expectInputError([&] {
        airbag.checkKeys({"long_side", "widht", "height"}, {"mesh_size"});
    });
    EXPECT_EQ(e.getLine(), 2);  // the section's key
    EXPECT_EQ(e.getKey(), "airbag");
    const std::string what = e.what();
    EXPECT_NE(what.find("missing required key 'height' in section 'airbag'"), std::string::npos)
        << what;
    EXPECT_NE(what.find("it requires long_side, widht, height"), std::string::npos) << what;
    EXPECT_NE(what.find("optional: mesh_size"), std::string::npos) << what;
}

TEST(Scenario, WrongUnitIsLocatedAtItsKey) {
    const ScenarioFile f = ScenarioFile::parse(kText, "scenarios/x.yaml");
    const ScenarioNode gas = f.getRoot().getSection("gas");
    const InputError e = expectInputError([&] { gas.getQuantity("mass", Dimension::Mass); });
    EXPECT_EQ(std::string(e.what()),
              "scenarios/x.yaml:6: key 'gas.mass': \"3.5 kg/m\" is not a mass (unknown unit "
              "'kg/m'); use g, kg, mg (e.g. \"3.5 g\")");
    const InputError e2 =
        expectInputError([&] { gas.getQuantity("temperature", Dimension::Temperature); });
    EXPECT_EQ(e2.getLine(), 7);
    EXPECT_NE(std::string(e2.what()).find("has no unit"), std::string::npos);
}

TEST(Scenario, ChoicesListTheValidValues) {
    const ScenarioFile f = ScenarioFile::parse(kText, "x.yaml");
    const ScenarioNode gas = f.getRoot().getSection("gas");
    const InputError e = expectInputError([&] {
        gas.getChoice("process", {"isothermal", "adiabatic", "polytropic"});
    });
    EXPECT_EQ(e.getLine(), 8);
    const std::string what = e.what();
    EXPECT_NE(what.find("did you mean 'isothermal'?"), std::string::npos) << what;
    EXPECT_NE(what.find("valid values: isothermal, adiabatic, polytropic"), std::string::npos);
    const InputError b = expectInputError([&] { f.getRoot().getBool("flag", false); });
    EXPECT_EQ(b.getLine(), 10);
    EXPECT_NE(std::string(b.what()).find("true or false"), std::string::npos);
}

TEST(Scenario, ListElementsCarryTheirLineAndIndex) {
    const ScenarioFile f = ScenarioFile::parse(kText, "x.yaml");
    const std::vector<ScenarioNode> list = f.getRoot().get("list").getElements();
    ASSERT_EQ(list.size(), 2u);
    EXPECT_DOUBLE_EQ(list[0].asQuantity(Dimension::Length), 1e-3);
    const InputError e = expectInputError([&] { list[1].asQuantity(Dimension::Length); });
    EXPECT_EQ(e.getLine(), 9);
    EXPECT_EQ(e.getKey(), "list[1]");
}

TEST(Scenario, DefaultsApplyOnlyWhenKeyAbsent) {
    const ScenarioFile f = ScenarioFile::parse(kText, "x.yaml");
    const ScenarioNode airbag = f.getRoot().getSection("airbag");
    EXPECT_DOUBLE_EQ(airbag.getQuantity("long_side", Dimension::Length, 1.0), 0.35);
    EXPECT_DOUBLE_EQ(airbag.getQuantity("mesh_size", Dimension::Length, 0.01), 0.01);
    EXPECT_TRUE(f.getRoot().getSection("absent", false).isNull() ||
                f.getRoot().getSection("absent", false).isMap());
    EXPECT_THROW(f.getRoot().getSection("absent"), InputError);
}

TEST(Scenario, DuplicateKeyIsAnError) {
    const ScenarioFile f =
        ScenarioFile::parse("kind: a\nairbag:\n  width: 1 mm\n  width: 2 mm\n", "d.yaml");
    const InputError e =
        expectInputError([&] { f.getRoot().getSection("airbag").checkKeys({"width"}, {}); });
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(std::string(e.what()).find("appears twice"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("first at line 3"), std::string::npos) << e.what();
}

TEST(Scenario, YamlSyntaxErrorBecomesInputErrorWithLine) {
    const InputError e = expectInputError([] {
        ScenarioFile::parse("kind: a\nairbag:\n  width: [1 mm, 2 mm\n  height: 3 mm\n", "s.yaml");
    });
    EXPECT_EQ(e.getWhere(), "s.yaml");
    EXPECT_GE(e.getLine(), 3);  // yaml-cpp reports where it noticed: at or after the bracket
    EXPECT_NE(std::string(e.what()).find("not valid YAML"), std::string::npos) << e.what();
    const InputError e2 = expectInputError([] { ScenarioFile::parse("- a\n- b\n", "l.yaml"); });
    EXPECT_NE(std::string(e2.what()).find("YAML mapping"), std::string::npos) << e2.what();
}

TEST(Scenario, ASecondYamlDocumentIsAnErrorAtItsLine) {
    // It used to be ignored: the run took the first document and said nothing of the rest.
    const InputError e = expectInputError(
        [] { ScenarioFile::parse("kind: a\nairbag: {width: 1 mm}\n---\nkind: b\n", "t.yaml"); });
    EXPECT_EQ(e.getWhere(), "t.yaml");
    EXPECT_EQ(e.getLine(), 4);
    EXPECT_NE(std::string(e.what()).find("a second YAML document"), std::string::npos) << e.what();
    // A document marker before the only document, and an empty file, are one document.
    EXPECT_NO_THROW(ScenarioFile::parse("---\nkind: a\n", "one.yaml"));
    EXPECT_NO_THROW(ScenarioFile::parse("", "empty.yaml"));
}

TEST(Scenario, MissingFileIsAnInputError) {
    const InputError e = expectInputError([] { ScenarioFile::load("/nonexistent/x.yaml"); });
    EXPECT_EQ(e.getWhere(), "/nonexistent/x.yaml");
    EXPECT_NE(std::string(e.what()).find("cannot read"), std::string::npos);
    const InputError e2 = expectInputError([] { ScenarioFile::load(BAGSIM_SOURCE_DIR); });
    EXPECT_NE(std::string(e2.what()).find("is a folder"), std::string::npos) << e2.what();
}

TEST(Scenario, OverrideReplacesValueAndLocatesErrorsAtTheOption) {
    ScenarioFile f = ScenarioFile::parse(kText, "x.yaml");
    f.applyOverride("airbag.long_side=400 mm");
    f.applyOverride("output.frame_every", "3");  // a new section
    f.applyOverride("gas.temperature=[1, 2]");   // parsed as YAML: a list
    const ScenarioNode root = f.getRoot();
    EXPECT_DOUBLE_EQ(root.getSection("airbag").getQuantity("long_side", Dimension::Length), 0.4);
    EXPECT_EQ(root.getSection("output").getInteger("frame_every", 0), 3);
    EXPECT_TRUE(root.getSection("gas").get("temperature").isSequence());
    ASSERT_EQ(f.getOverrides().size(), 3u);
    EXPECT_EQ(f.getOverrides()[0], "airbag.long_side=400 mm");
    EXPECT_EQ(f.getText(), kText);  // the text stays verbatim

    f.applyOverride("airbag.long_side", "400");
    const InputError e = expectInputError(
        [&] { f.getRoot().getSection("airbag").getQuantity("long_side", Dimension::Length); });
    EXPECT_EQ(e.getWhere(), "--set airbag.long_side");
    EXPECT_EQ(e.getLine(), 0);
    EXPECT_EQ(std::string(e.what()).rfind("--set airbag.long_side: key 'airbag.long_side'", 0), 0u)
        << e.what();
    // Other keys keep their file lines.
    const InputError e2 = expectInputError(
        [&] { f.getRoot().getSection("gas").getQuantity("mass", Dimension::Mass); });
    EXPECT_EQ(e2.getWhere(), "x.yaml");
    EXPECT_EQ(e2.getLine(), 6);

    EXPECT_THROW(f.applyOverride("airbag.long_side.x=1"), InputError);  // through a value
    EXPECT_THROW(f.applyOverride("no-equals-sign"), InputError);
    EXPECT_THROW(f.applyOverride(".x=1"), InputError);
}

TEST(Scenario, StemIsFileNameWithoutExtension) {
    EXPECT_EQ(ScenarioFile::parse("kind: a\n", "scenarios/seed-load-test.yaml").getStem(),
              "seed-load-test");
}

// A copy is its own scenario: the diagnosis copies the data's scenario for each co-simulation
// and sets its keys (half the macro step, a trial gas mass); the original must not take them.
TEST(Scenario, OverridesOfACopyLeaveTheOriginal) {
    const ScenarioFile original =
        ScenarioFile::parse("kind: x\ncoupling:\n  macro_step: 10 ms\n", "s.yaml");
    ScenarioFile copy = original;
    copy.applyOverride("coupling.macro_step", "5 ms");
    ScenarioFile assigned;
    assigned = original;
    assigned.applyOverride("array.gas_mass", "4 g");
    EXPECT_TRUE(original.getOverrides().empty());
    EXPECT_EQ(original.getRoot().getSection("coupling").getString("macro_step"), "10 ms");
    EXPECT_FALSE(original.getRoot().has("array"));
    EXPECT_EQ(copy.getRoot().getSection("coupling").getString("macro_step"), "5 ms");
    ASSERT_EQ(copy.getOverrides().size(), 1u);
    EXPECT_FALSE(copy.getRoot().has("array"));
    EXPECT_EQ(assigned.getOverrides().size(), 1u);
    EXPECT_EQ(assigned.getRoot().getSection("coupling").getString("macro_step"), "10 ms");
}
