// The patient-on-array scenario kind (io::readPatientOnArrayScenario): the shipped scenarios
// read into SI, and located errors (file, line, key, what is valid) for overlapping bags, a
// patient off the array, gas commands that name no bags or mix their kinds, and wrong units.
#include <cosim/BagParticipant.h>
#include <cosim/PatientOnArray.h>
#include <gtest/gtest.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>
#include <io/LoadTestScenario.h>

#include <cmath>
#include <string>

#include "ArrayScenarioTestUtil.h"

using io::test::expectInputError;
using io::test::read;
using io::test::readError;

namespace {

const std::string kBase =
    "kind: patient-on-array\n"                                                   // 1
    "patient: {sex: male, height: 1.75 m, mass: 75 kg, position: [0 m, 0 m]}\n"  // 2
    "bag: {mesh_size: 30 mm}\n"                                                  // 3
    "array:\n"                                                                   // 4
    "  rows: 20\n"                                                               // 5
    "  columns: 2\n"                                                             // 6
    "  row_pitch: 105 mm\n"                                                      // 7
    "  column_pitch: 360 mm\n"                                                   // 8
    "  centre: [-30 mm, 0 mm]\n"                                                 // 9
    "  orientation: [across, across-flipped]\n"                                  // 10
    "  gas_mass: 4.5 g\n"                                                        // 11
    "  groups:\n"                                                                // 12
    "    - {name: left, columns: [0]}\n"                                         // 13
    "    - {name: right, columns: [1], gas_mass: 5 g}\n"                         // 14
    "run: {settle_time: 1 s, duration: 10 s}\n";                                 // 15

}  // namespace

TEST(ArrayScenario, ReadsTheShippedScenariosInSI) {
    auto load = [](const std::string& name) {
        return io::readPatientOnArrayScenario(io::ScenarioFile::load(
            std::string(BAGSIM_SOURCE_DIR) + "/scenarios/" + name + ".yaml"));
    };
    for (const char* name : {"supine-on-array", "supine-on-array-firm", "turn-left"}) {
        const io::PatientOnArrayScenario sc = load(name);
        EXPECT_EQ(sc.name, name);
        EXPECT_DOUBLE_EQ(sc.patient.height, 1.75);
        EXPECT_DOUBLE_EQ(sc.patient.mass, 75.0);
        EXPECT_GE(sc.options.layout.rows * sc.options.layout.columns, 24);
        EXPECT_DOUBLE_EQ(sc.options.layout.rowPitch, 0.36);
        EXPECT_DOUBLE_EQ(sc.options.integrator.contactDamping, 2.0);
        EXPECT_EQ(sc.mat.rows, 64);
        EXPECT_EQ(sc.mat.columns, 32);
    }
    // The firm cases fill each bag with 4.5 g (about 20 kPa); the shipped supine one is set as a
    // clinical mattress is, by its pressure at rest (4 kPa: less gas than 4.5 g), in three
    // zones.
    EXPECT_DOUBLE_EQ(load("supine-on-array-firm").options.layout.gasMass, 4.5e-3);
    EXPECT_DOUBLE_EQ(load("turn-left").options.layout.gasMass, 4.5e-3);
    const io::PatientOnArrayScenario clinical = load("supine-on-array");
    EXPECT_LT(clinical.options.layout.gasMass, 4.5e-3);
    EXPECT_GT(clinical.options.layout.gasMass, 3.0e-3);
    EXPECT_EQ(clinical.options.layout.groups.size(), 3u);
    EXPECT_EQ(clinical.options.bag.stepping, bags::AirbagSpec::Stepping::Relaxed);
    const io::PatientOnArrayScenario turn = io::readPatientOnArrayScenario(
        io::ScenarioFile::load(std::string(BAGSIM_SOURCE_DIR) + "/scenarios/turn-left.yaml"));
    EXPECT_DOUBLE_EQ(turn.duration, 30.0);
    ASSERT_EQ(turn.gasText.size(), 2u);
    // The right group (columns 4-6) is filled to 6 g from the end of the settle, at 0.05 g/s.
    const cosim::GasCommand* c = turn.gas.findCommand(6, turn.settleTime);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(c->kind, cosim::GasCommand::Kind::Target);
    EXPECT_NEAR(c->targetMass, 6.0e-3, 1e-15);
    EXPECT_NEAR(c->rate, 0.05e-3, 1e-15);
    EXPECT_EQ(turn.gas.findCommand(6, turn.settleTime - 1e-3), nullptr);
    EXPECT_EQ(turn.gas.findCommand(3, turn.settleTime + 1.0), nullptr);  // the middle column
    const cosim::GasCommand* left = turn.gas.findCommand(0, turn.settleTime);
    ASSERT_NE(left, nullptr);
    EXPECT_NEAR(left->targetMass, 3.0e-3, 1e-15);
}

TEST(ArrayScenario, ReadsGroupsGasCommandsAndDefaults) {
    const io::PatientOnArrayScenario sc =
        read(kBase +
             "gas:\n"
             "  - {at: 2 s, group: right, target: 6 g, rate: 0.05 g/s}\n"
             "  - {at: 1 s, bags: [0, 2], flow: -3 g/min}\n");
    EXPECT_EQ(sc.bagReading, "literal");
    EXPECT_DOUBLE_EQ(sc.options.bag.geometry.meshSize, 0.030);
    EXPECT_FALSE(sc.options.bag.selfContact);
    ASSERT_EQ(sc.options.layout.groups.size(), 2u);
    EXPECT_DOUBLE_EQ(sc.options.layout.groups[0].gasMass, 4.5e-3);  // the array's by default
    EXPECT_DOUBLE_EQ(sc.options.layout.groups[1].gasMass, 5.0e-3);
    const cosim::GasCommand* flow = sc.gas.findCommand(2, 2.0);  // settle 1 s + at 1 s
    ASSERT_NE(flow, nullptr);
    EXPECT_NEAR(flow->massFlow, -0.05e-3, 1e-15);
    EXPECT_EQ(sc.gas.findCommand(2, 1.99), nullptr);
    EXPECT_EQ(sc.gas.findCommand(1, 2.99), nullptr);
    EXPECT_NE(sc.gas.findCommand(1, 3.0), nullptr);   // row 0, column 1: group right
    EXPECT_EQ(sc.gas.findCommand(4, 10.0), nullptr);  // row 2, column 0: no command
    EXPECT_DOUBLE_EQ(sc.getEndTime(), 11.0);
}

TEST(ArrayScenario, TheBedBoardCarriesTheBodyByDefaultAndCanBeLeftOut) {
    EXPECT_TRUE(read(kBase).options.boardContact);
    std::string off = kBase;
    off.insert(off.find("  groups:"), "  board_contact: false\n");
    EXPECT_FALSE(read(off).options.boardContact);
    std::string on = kBase;
    on.insert(on.find("  groups:"), "  board_contact: true\n");
    EXPECT_TRUE(read(on).options.boardContact);
    std::string bad = kBase;
    bad.insert(bad.find("  groups:"), "  board_contact: maybe\n");
    const io::InputError e = readError(bad);
    EXPECT_EQ(e.getLine(), 12);
    EXPECT_EQ(e.getKey(), "array.board_contact");
}

TEST(ArrayScenario, TheBedBoardsFrictionIsStickSlipByDefaultAndCanBeRegularised) {
    const io::PatientOnArrayScenario plain = read(kBase);
    EXPECT_EQ(plain.options.board.frictionLaw, body::SupportFrictionLaw::StickSlip);
    EXPECT_DOUBLE_EQ(plain.options.board.stickDistance, 1e-3);
    auto with = [](const std::string& lines) {
        std::string t = kBase;
        t.insert(t.find("  groups:"), lines);
        return t;
    };
    EXPECT_DOUBLE_EQ(read(with("  board_stick_distance: 0.5 mm\n")).options.board.stickDistance,
                     5e-4);
    const io::PatientOnArrayScenario reg =
        read(with("  board_friction_law: regularised\n  board_slip_velocity: 20 mm/s\n"));
    EXPECT_EQ(reg.options.board.frictionLaw, body::SupportFrictionLaw::Regularised);
    EXPECT_DOUBLE_EQ(reg.options.board.slipVelocity, 0.02);
    EXPECT_DOUBLE_EQ(read(with("  board_friction_law: regularised\n")).options.board.slipVelocity,
                     2e-3);
    struct Bad {
        std::string lines, key, says;
    };
    for (const Bad& b : std::vector<Bad>{
             {"  board_friction_law: regularised\n  board_slip_velocity: 0 mm/s\n",
              "array.board_slip_velocity", "mm/s"},
             {"  board_slip_velocity: 20 mm/s\n", "array.board_slip_velocity",
              "valid only with board_friction_law: regularised"},
             {"  board_stick_distance: 0 mm\n", "array.board_stick_distance", "mm"},
             {"  board_friction_law: regularised\n  board_stick_distance: 1 mm\n",
              "array.board_stick_distance", "valid only with board_friction_law: stick-slip"},
             {"  board_friction_law: sticky\n", "array.board_friction_law", "stick-slip"}}) {
        const io::InputError e = readError(with(b.lines));
        EXPECT_GE(e.getLine(), 12) << b.lines;
        EXPECT_EQ(e.getKey(), b.key) << b.lines;
        EXPECT_NE(std::string(e.what()).find(b.says), std::string::npos) << e.what();
    }
}

TEST(ArrayScenario, TheBodyOnTheFilmsIsFrictionlessByDefaultAndTakesACoulombCoefficient) {
    EXPECT_EQ(read(kBase).options.contact.friction, 0.0);
    auto with = [](const std::string& value) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23,
                  "bag: {mesh_size: 30 mm, body_friction: " + value + "}");
        return t;
    };
    EXPECT_EQ(read(with("0")).options.contact.friction, 0.0);
    EXPECT_DOUBLE_EQ(read(with("0.4")).options.contact.friction, 0.4);
    for (const char* bad : {"-0.1", "3"}) {
        const io::InputError e = readError(with(bad));
        EXPECT_EQ(e.getLine(), 3);
        EXPECT_EQ(e.getKey(), "bag.body_friction");
        EXPECT_NE(e.getMessage().find("valid: 0 (frictionless) to 2"), std::string::npos)
            << e.what();
    }
}

TEST(ArrayScenario, BodyFrictionIsRefusedWithTheOnePassTangentScheme) {
    // The one-pass tangent scheme would hold the friction force from the step's start
    // (docs/cosim.md#friction-and-the-tangent-schemes): refused at coupling.scheme naming the
    // friction. Tangent-implicit takes it (its linearisation leaves the stick springs out and
    // its passes hold the friction force), as do the implicit and explicit schemes.
    std::string t = kBase;
    t.replace(t.find("bag: {mesh_size: 30 mm}"), 23, "bag: {mesh_size: 30 mm, body_friction: 0.4}");
    const io::InputError e = readError(t + "coupling: {scheme: tangent}\n");
    EXPECT_EQ(e.getKey(), "coupling.scheme");
    EXPECT_NE(e.getMessage().find("tangent is not valid with bag.body_friction 0.4"),
              std::string::npos)
        << e.what();
    EXPECT_NE(e.getMessage().find("valid: implicit, tangent-implicit or explicit, or "
                                  "bag.body_friction 0"),
              std::string::npos)
        << e.what();
    for (const char* scheme : {"implicit", "explicit", "tangent-implicit"})
        EXPECT_DOUBLE_EQ(read(t + "coupling: {scheme: " + scheme + "}\n").options.contact.friction,
                         0.4);
    cosim::PatientOnArrayOptions o = read(t).options;
    o.coupling.scheme = cosim::Scheme::Tangent;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.coupling.scheme = cosim::Scheme::TangentImplicit;
    EXPECT_NO_THROW(o.validate());
}

TEST(ArrayScenario, TheBodysShapesTakeASoftTissueLayer) {
    // By default each segment has its site's published layer (body/Tissue.h), the contact
    // options themselves none.
    const cosim::PatientOnArrayOptions d = read(kBase).options;
    EXPECT_FALSE(d.contact.hasTissue());
    ASSERT_EQ(d.segmentTissue.size(), size_t(body::kSegmentCount));
    const body::SoftTissue sacrum = body::getPublishedTissue(body::TissueSite::Sacrum);
    EXPECT_GT(sacrum.thickness, 0.0);
    EXPECT_EQ(d.getSegmentContact(body::Segment::LowerTrunk).tissueThickness, sacrum.thickness);
    EXPECT_EQ(d.getSegmentContact(body::Segment::LowerTrunk).tissueModulus, sacrum.modulus);
    EXPECT_EQ(d.getSegmentContact(body::Segment::FootL).tissueThickness,
              body::getPublishedTissue(body::TissueSite::Heels).thickness);
    EXPECT_FALSE(d.getSegmentContact(body::Segment::Head).hasTissue());  // none published
    auto with = [](const std::string& value) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23,
                  "bag: {mesh_size: 30 mm, body_tissue: " + value + "}");
        return t;
    };
    const io::PatientOnArrayScenario sc = read(with("{thickness: 20 mm, modulus: 30 kPa}"));
    EXPECT_DOUBLE_EQ(sc.options.contact.tissueThickness, 0.02);
    EXPECT_DOUBLE_EQ(sc.options.contact.tissueModulus, 3e4);
    const io::InputError e = readError(with("{thickness: 20 mm, modulus: 0 kPa}"));
    EXPECT_EQ(e.getLine(), 3);
    EXPECT_EQ(e.getKey(), "bag.body_tissue.modulus");
    EXPECT_NE(e.getMessage().find("10-200 kPa"), std::string::npos) << e.what();
    EXPECT_TRUE(sc.options.segmentTissue.empty());  // one layer: every segment's
    const io::InputError e2 = readError(with("{modulus: 30 kPa}"));
    EXPECT_EQ(e2.getKey(), "bag.body_tissue");
    EXPECT_NE(e2.getMessage().find("thickness"), std::string::npos) << e2.what();
    // none: bare shapes; published: as the default.
    const cosim::PatientOnArrayOptions none = read(with("none")).options;
    EXPECT_TRUE(none.segmentTissue.empty());
    EXPECT_FALSE(none.getSegmentContact(body::Segment::LowerTrunk).hasTissue());
    EXPECT_EQ(read(with("published")).options.segmentTissue.size(), size_t(body::kSegmentCount));
    // Sites changed on the published layers: the sacrum's own, the heels bare, the rest kept.
    const cosim::PatientOnArrayOptions s2 =
        read(with("{sacrum: {thickness: 20 mm, modulus: 30 kPa}, heels: none}")).options;
    EXPECT_DOUBLE_EQ(s2.getSegmentContact(body::Segment::LowerTrunk).tissueThickness, 0.02);
    EXPECT_DOUBLE_EQ(s2.getSegmentContact(body::Segment::LowerTrunk).tissueModulus, 3e4);
    EXPECT_FALSE(s2.getSegmentContact(body::Segment::FootR).hasTissue());
    EXPECT_EQ(s2.getSegmentContact(body::Segment::UpperTrunk).tissueThickness,
              body::getPublishedTissue(body::TissueSite::Scapulae).thickness);
    const io::InputError e3 = readError(with("{sacrun: none}"));
    EXPECT_EQ(e3.getKey(), "bag.body_tissue.sacrun");
    EXPECT_NE(e3.getMessage().find("sacrum"), std::string::npos) << e3.what();
    const io::InputError e4 = readError(with("{heels: {thickness: 18 mm}}"));
    EXPECT_EQ(e4.getKey(), "bag.body_tissue.heels");
    EXPECT_NE(e4.getMessage().find("modulus"), std::string::npos) << e4.what();
    const io::InputError e5 = readError(with("soft"));
    EXPECT_EQ(e5.getKey(), "bag.body_tissue");
    EXPECT_NE(e5.getMessage().find("published"), std::string::npos) << e5.what();
}

TEST(ArrayScenario, EverySegmentLiesOnOneTissueSiteAndTheSitesNamesAreTheScenarioKeys) {
    const std::vector<body::SoftTissue> t = body::makeSegmentTissue(body::getPublishedTissues());
    ASSERT_EQ(t.size(), size_t(body::kSegmentCount));
    for (int g = 0; g < body::kSegmentCount; ++g) {
        const body::SoftTissue p = body::getPublishedTissue(body::getTissueSite(body::Segment(g)));
        EXPECT_EQ(t[size_t(g)].thickness, p.thickness) << g;
        EXPECT_EQ(t[size_t(g)].modulus, p.modulus) << g;
        // Within the range the scenario accepts for a layer (or none).
        if (!p.isRigid()) {
            EXPECT_GE(p.thickness, io::kMinTissueThickness) << g;
            EXPECT_LE(p.thickness, io::kMaxTissueThickness) << g;
            EXPECT_GE(p.modulus, io::kMinTissueModulus) << g;
            EXPECT_LE(p.modulus, io::kMaxTissueModulus) << g;
        }
    }
    EXPECT_EQ(body::getTissueSite(body::Segment::LowerTrunk), body::TissueSite::Sacrum);
    EXPECT_EQ(body::getTissueSite(body::Segment::ThighL), body::TissueSite::Buttocks);
    EXPECT_EQ(body::getTissueSite(body::Segment::FootR), body::TissueSite::Heels);
    EXPECT_EQ(body::getTissueSite(body::Segment::UpperTrunk), body::TissueSite::Scapulae);
    EXPECT_EQ(body::getTissueSite(body::Segment::ShankL), body::TissueSite::Calves);
    EXPECT_EQ(body::getTissueSite(body::Segment::Head), body::TissueSite::Occiput);
    EXPECT_STREQ(body::getTissueSiteName(body::TissueSite::Heels), "heels");
}

TEST(ArrayScenario, FrictionLawIsStickSlipByDefaultAndSlipVelocityBelongsToTheRegularisedLaw) {
    auto with = [](const std::string& keys) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23,
                  "bag: {mesh_size: 30 mm, body_friction: 0.4" + keys + "}");
        return t;
    };
    using Law = bags::RigidContact::FrictionLaw;
    EXPECT_EQ(read(with("")).options.contact.frictionLaw, Law::StickSlip);
    const io::PatientOnArrayScenario reg = read(with(", friction_law: regularised"));
    EXPECT_EQ(reg.options.contact.frictionLaw, Law::Regularised);
    EXPECT_DOUBLE_EQ(reg.options.contact.slipVelocity, 2e-3);
    EXPECT_DOUBLE_EQ(read(with(", friction_law: regularised, slip_velocity: 5 mm/s"))
                         .options.contact.slipVelocity,
                     5e-3);
    {
        const io::InputError e = readError(with(", friction_law: viscous"));
        EXPECT_EQ(e.getLine(), 3);
        EXPECT_EQ(e.getKey(), "bag.friction_law");
        EXPECT_NE(e.getMessage().find("regularised"), std::string::npos) << e.what();
    }
    {
        const io::InputError e = readError(with(", slip_velocity: 2 mm/s"));
        EXPECT_EQ(e.getKey(), "bag.slip_velocity");
        EXPECT_NE(e.getMessage().find("valid only with friction_law: regularised"),
                  std::string::npos)
            << e.what();
    }
    for (const char* bad : {"0 mm/s", "-1 mm/s", "2 m/s"}) {
        const io::InputError e =
            readError(with(std::string(", friction_law: regularised, slip_velocity: ") + bad));
        EXPECT_EQ(e.getLine(), 3);
        EXPECT_EQ(e.getKey(), "bag.slip_velocity");
        EXPECT_NE(e.getMessage().find("valid: in [0.01 mm/s, 1000 mm/s]"), std::string::npos)
            << e.what();
    }
}

TEST(ArrayScenario, NeighbourContactIsOffByDefaultAndNeedsTheBagsSelfContact) {
    const io::PatientOnArrayScenario plain = read(kBase);
    EXPECT_FALSE(plain.options.neighbourContact);
    EXPECT_DOUBLE_EQ(plain.options.neighbourMargin, 0.003);
    std::string on = kBase;
    on.replace(on.find("bag: {mesh_size: 30 mm}"), 23,
               "bag: {mesh_size: 30 mm, self_contact: true}");
    on.insert(on.find("  groups:"), "  neighbour_contact: true\n  neighbour_margin: 8 mm\n");
    const io::PatientOnArrayScenario sc = read(on);
    EXPECT_TRUE(sc.options.neighbourContact);
    EXPECT_DOUBLE_EQ(sc.options.neighbourMargin, 0.008);
    // Without the bags' self-contact (off by default) the films cannot meet: refused there.
    std::string noSelf = kBase;
    noSelf.insert(noSelf.find("  groups:"), "  neighbour_contact: true\n");
    const io::InputError e = readError(noSelf);
    EXPECT_EQ(e.getLine(), 12);
    EXPECT_EQ(e.getKey(), "array.neighbour_contact");
    EXPECT_NE(e.getMessage().find("needs bag.self_contact: true"), std::string::npos) << e.what();
    std::string badMargin = on;
    badMargin.replace(badMargin.find("8 mm"), 4, "-1 mm");
    const io::InputError m = readError(badMargin);
    EXPECT_EQ(m.getKey(), "array.neighbour_margin");
    // The layout's own located errors are unchanged with the key on.
    std::string overlap = on;
    overlap.replace(overlap.find("105 mm"), 6, "90 mm");
    const io::InputError o = readError(overlap);
    EXPECT_EQ(o.getLine(), 7);
    EXPECT_EQ(o.getKey(), "array.row_pitch");
    EXPECT_NE(o.getMessage().find("would overlap; valid: 100 mm or more"), std::string::npos)
        << o.what();
}

TEST(ArrayScenario, OverlappingRowsAreRefusedAtTheRowPitch) {
    std::string text = kBase;
    text.replace(text.find("105 mm"), 6, "90 mm");
    const io::InputError e = readError(text);
    EXPECT_EQ(e.getLine(), 7);
    EXPECT_EQ(e.getKey(), "array.row_pitch");
    EXPECT_NE(e.getMessage().find("would overlap; valid: 100 mm or more"), std::string::npos)
        << e.what();
}

TEST(ArrayScenario, APatientOffTheArrayIsRefusedAtHisPositionNamingTheSegments) {
    std::string text = kBase;
    text.replace(text.find("position: [0 m, 0 m]"), 20, "position: [0 m, 0.6 m]");
    const io::InputError e = readError(text);
    EXPECT_EQ(e.getLine(), 2);
    EXPECT_EQ(e.getKey(), "patient.position");
    EXPECT_NE(
        e.getMessage().find("no bag of the array lies under his lower_trunk, middle_trunk, head"),
        std::string::npos)
        << e.what();
    EXPECT_NE(
        e.getMessage().find("the bags cover x from -1077.5 mm to 1017.5 mm and y from -355 mm "
                            "to 355 mm"),
        std::string::npos)
        << e.what();
}

TEST(ArrayScenario, GasCommandsNameOneGroupOrBagsAndOneKind) {
    const io::InputError unknown =
        readError(kBase + "gas:\n  - {group: rigth, target: 6 g, rate: 0.05 g/s}\n");
    EXPECT_EQ(unknown.getLine(), 17);
    EXPECT_EQ(unknown.getKey(), "gas[0].group");
    EXPECT_NE(unknown.getMessage().find("right"), std::string::npos) << unknown.what();

    const io::InputError both =
        readError(kBase + "gas:\n  - {group: right, target: 6 g, flow: 0.01 g/s}\n");
    EXPECT_EQ(both.getKey(), "gas[0]");
    EXPECT_NE(both.getMessage().find("either 'target'"), std::string::npos) << both.what();

    const io::InputError noRate = readError(kBase + "gas:\n  - {group: right, target: 6 g}\n");
    EXPECT_EQ(noRate.getKey(), "gas[0].rate");
    EXPECT_NE(noRate.getMessage().find("0.05 g/s"), std::string::npos) << noRate.what();

    const io::InputError unit = readError(kBase + "gas:\n  - {bags: [1], flow: 0.05 g}\n");
    EXPECT_EQ(unit.getKey(), "gas[0].flow");
    EXPECT_NE(unit.getMessage().find("g/s"), std::string::npos) << unit.what();

    const io::InputError bag = readError(kBase + "gas:\n  - {bags: [40], flow: 0.05 g/s}\n");
    EXPECT_NE(bag.getMessage().find("bag 40 does not exist; valid: 0 to 39"), std::string::npos)
        << bag.what();

    const io::InputError late =
        readError(kBase + "gas:\n  - {at: 12 s, group: left, flow: -0.05 g/s}\n");
    EXPECT_EQ(late.getKey(), "gas[0].at");
    EXPECT_NE(late.getMessage().find("after the run's end"), std::string::npos) << late.what();

    const io::InputError twice = readError(kBase +
                                           "gas:\n  - {group: left, flow: -0.05 g/s}\n"
                                           "  - {bags: [0], flow: 0.05 g/s}\n");
    EXPECT_EQ(twice.getLine(), 18);
    EXPECT_NE(twice.getMessage().find("one command per bag and start time"), std::string::npos)
        << twice.what();
}

TEST(ArrayScenario, GroupErrorsAreLocatedInTheirGroup) {
    std::string text = kBase;
    text.replace(text.find("columns: [1], gas_mass: 5 g"), 27, "columns: [0], gas_mass: 5 g");
    const io::InputError e = readError(text);
    EXPECT_EQ(e.getLine(), 14);
    EXPECT_NE(e.getMessage().find("in group 'left' and in group 'right'"), std::string::npos)
        << e.what();

    std::string column = kBase;
    column.replace(column.find("columns: [1]"), 12, "columns: [2]");
    const io::InputError c = readError(column);
    EXPECT_EQ(c.getKey(), "array.groups[1].columns[0]");
    EXPECT_NE(c.getMessage().find("column 2 does not exist; valid: 0 to 1"), std::string::npos)
        << c.what();
}

TEST(ArrayScenario, TheFilmsBendingStiffnessIsAMomentThePlateValueOrOff) {
    auto with = [](const std::string& keys) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23, "bag: {mesh_size: 30 mm" + keys + "}");
        return t;
    };
    // The seed's film, 0.2 mm: E t^3 / (12 (1 - nu^2)) = 1.685e-4 N m (docs/materials.md).
    const double plate = 1.685e-4;
    EXPECT_NEAR(read(kBase).options.bag.bendingStiffness, plate, 1e-3 * plate);  // the default
    EXPECT_EQ(read(with(", bending_stiffness: plate")).options.bag.bendingStiffness,
              read(kBase).options.bag.bendingStiffness);
    EXPECT_EQ(read(with(", bending_stiffness: 0")).options.bag.bendingStiffness, 0.0);
    EXPECT_DOUBLE_EQ(read(with(", bending_stiffness: 0.05 N mm")).options.bag.bendingStiffness,
                     5e-5);
    for (const char* bad : {"stiff", "-1 N mm", "2 N m", "5 mm"}) {
        const io::InputError e = readError(with(std::string(", bending_stiffness: ") + bad));
        EXPECT_EQ(e.getLine(), 3) << bad;
        EXPECT_EQ(e.getKey(), "bag.bending_stiffness") << bad;
    }
    // The value reaches every coupled bag the run builds.
    const io::PatientOnArrayScenario sc = read(kBase);
    const cosim::PatientOnArray poa(sc.patient, sc.options);
    ASSERT_GT(poa.getBagIndices().size(), 0u);
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const auto* fe = dynamic_cast<const cosim::BagParticipant*>(&poa.getBag(int(b)));
        ASSERT_NE(fe, nullptr);
        EXPECT_EQ(fe->getAirbag().getSpec().bendingStiffness, sc.options.bag.bendingStiffness) << b;
    }
}

TEST(ArrayScenario, TheFilmsDamperIsOffByDefaultAStiffnessPerAreaAndTheFiniteElementBagsOwn) {
    auto with = [](const std::string& keys) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23, "bag: {mesh_size: 30 mm" + keys + "}");
        return t;
    };
    EXPECT_EQ(read(kBase).options.bag.damping, 0.0);
    const std::string qs = ", stepping: quasi-static";
    EXPECT_DOUBLE_EQ(read(with(qs + ", film_damping: 1e5 Pa/m")).options.bag.damping, 1e5);
    EXPECT_DOUBLE_EQ(read(with(qs + ", film_damping: 0.1 N/mm^3")).options.bag.damping, 1e8);
    for (const char* bad : {"soft", "-1 Pa/m", "1e9 Pa/m", "5 mm"}) {
        const io::InputError e = readError(with(qs + ", film_damping: " + bad));
        EXPECT_EQ(e.getLine(), 3) << bad;
        EXPECT_EQ(e.getKey(), "bag.film_damping") << bad;
    }
    // The damped steps are the quasi-static stepping's: with the relaxed or the dynamic one
    // the damper would do nothing, so it is refused, saying why.
    EXPECT_DOUBLE_EQ(read(with(", film_damping: 1e5 Pa/m")).options.bag.damping, 1e5);
    for (const char* stepping : {", stepping: relaxed", ", stepping: dynamic"}) {
        const io::InputError e =
            readError(with(std::string(stepping) + ", film_damping: 1e5 Pa/m"));
        EXPECT_EQ(e.getKey(), "bag.film_damping") << stepping;
        EXPECT_NE(std::string(e.what()).find("stepping: quasi-static"), std::string::npos)
            << e.what();
    }
    // (refused with the reduced bag: ReducedBagFile.*)
    // It reaches every coupled bag the run builds.
    const io::PatientOnArrayScenario sc = read(with(qs + ", film_damping: 1e5 Pa/m"));
    const cosim::PatientOnArray poa(sc.patient, sc.options);
    ASSERT_GT(poa.getBagIndices().size(), 0u);
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const auto* fe = dynamic_cast<const cosim::BagParticipant*>(&poa.getBag(int(b)));
        ASSERT_NE(fe, nullptr);
        EXPECT_EQ(fe->getAirbag().getSpec().damping, 1e5) << b;
    }
}

TEST(ArrayScenario, TheGasInTheLinearisationIsOnByDefaultAndCanBeSwitchedOff) {
    auto with = [](const std::string& coupling) {
        return kBase + "coupling: {" + coupling + "}\n";
    };
    EXPECT_TRUE(read(kBase).options.coupling.gasTangent);
    EXPECT_FALSE(
        read(with("scheme: tangent-implicit, gas_tangent: false")).options.coupling.gasTangent);
    const io::InputError e = readError(with("gas_tangent: maybe"));
    EXPECT_EQ(e.getLine(), 16);
    EXPECT_EQ(e.getKey(), "coupling.gas_tangent");
    EXPECT_NE(e.getMessage().find("true or false"), std::string::npos) << e.what();
}

TEST(ArrayScenario, AnAdaptiveMacroStepTakesItsBoundsAndAccuracyAndBadValuesAreLocated) {
    const io::PatientOnArrayScenario plain = read(kBase);
    EXPECT_FALSE(plain.options.coupling.adaptive);
    EXPECT_DOUBLE_EQ(plain.options.coupling.macroStep, 0.01);
    auto with = [](const std::string& coupling) {
        return kBase + "coupling: {" + coupling + "}\n";
    };
    const io::PatientOnArrayScenario a = read(with("macro_step: adaptive"));
    EXPECT_TRUE(a.options.coupling.adaptive);
    EXPECT_DOUBLE_EQ(a.options.coupling.minMacroStep, 1e-3);
    EXPECT_DOUBLE_EQ(a.options.coupling.macroStep, 1e-3);  // the first step
    EXPECT_DOUBLE_EQ(a.options.coupling.maxMacroStep, 0.04);
    EXPECT_DOUBLE_EQ(a.options.coupling.stepAccuracy, 1000.0);
    const io::PatientOnArrayScenario b = read(with(
        "macro_step: adaptive, min_macro_step: 2 ms, max_macro_step: 20 ms, step_accuracy: 50"));
    EXPECT_DOUBLE_EQ(b.options.coupling.minMacroStep, 2e-3);
    EXPECT_DOUBLE_EQ(b.options.coupling.maxMacroStep, 0.02);
    EXPECT_DOUBLE_EQ(b.options.coupling.stepAccuracy, 50.0);
    struct Bad {
        const char* coupling;
        const char* key;
        const char* valid;
    };
    for (const Bad& bad :
         {Bad{"macro_step: fast", "coupling.macro_step",
              "valid: a time such as 10 ms, or adaptive"},
          Bad{"macro_step: 10 ms, max_macro_step: 40 ms", "coupling.max_macro_step",
              "only applies with macro_step: adaptive"},
          Bad{"step_accuracy: 10", "coupling.step_accuracy",
              "only applies with macro_step: adaptive"},
          Bad{"macro_step: adaptive, max_macro_step: 1 s", "coupling.max_macro_step", "valid:"},
          Bad{"macro_step: adaptive, min_macro_step: 50 ms, max_macro_step: 20 ms",
              "coupling.min_macro_step", "at most max_macro_step"},
          Bad{"macro_step: adaptive, step_accuracy: 0", "coupling.step_accuracy",
              "valid: 0.1 to 10000"}}) {
        const io::InputError e = readError(with(bad.coupling));
        EXPECT_EQ(e.getLine(), 16) << bad.coupling;
        EXPECT_EQ(e.getKey(), bad.key) << e.what();
        EXPECT_NE(e.getMessage().find(bad.valid), std::string::npos) << e.what();
    }
}

TEST(ArrayScenario, StepsWithNoFixedPointAreKeptAndStalledPassesAcceptedWithinAResidual) {
    // Patient runs keep a step with no fixed point at the smallest step (the run then ends
    // partial) and accept a step whose passes stall within 0.1 N, 1 mmHg over one sensel of
    // the clinical mat; both can be switched off; a bad residual is located.
    const io::PatientOnArrayScenario plain = read(kBase);
    EXPECT_TRUE(plain.options.coupling.keepUnconverged);
    EXPECT_DOUBLE_EQ(plain.options.coupling.acceptResidual, 0.1);
    auto with = [](const std::string& coupling) {
        return kBase + "coupling: {" + coupling + "}\n";
    };
    const io::PatientOnArrayScenario off =
        read(with("keep_unconverged: false, accept_residual: 0 N"));
    EXPECT_FALSE(off.options.coupling.keepUnconverged);
    EXPECT_EQ(off.options.coupling.acceptResidual, 0.0);
    EXPECT_DOUBLE_EQ(read(with("accept_residual: 50 mN")).options.coupling.acceptResidual, 0.05);
    for (const char* bad :
         {"accept_residual: -1 N", "accept_residual: 20 N", "accept_residual: 5"}) {
        const io::InputError e = readError(with(bad));
        EXPECT_EQ(e.getLine(), 16) << bad;
        EXPECT_EQ(e.getKey(), "coupling.accept_residual") << e.what();
    }
}

TEST(ArrayScenario, TheFilmsSteppingIsQuasiStaticByDefaultAndDynamicWithItsSettings) {
    auto with = [](const std::string& keys) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23, "bag: {mesh_size: 30 mm" + keys + "}");
        return t;
    };
    EXPECT_EQ(read(kBase).options.bag.stepping, bags::AirbagSpec::Stepping::QuasiStatic);
    EXPECT_EQ(read(with(", stepping: relaxed")).options.bag.stepping,
              bags::AirbagSpec::Stepping::Relaxed);
    const bags::AirbagSpec dflt = read(with(", stepping: dynamic")).options.bag;
    EXPECT_EQ(dflt.stepping, bags::AirbagSpec::Stepping::Dynamic);
    EXPECT_EQ(dflt.dynamics.massScale, 1000.0);
    EXPECT_EQ(dflt.dynamics.damping, 20.0);
    const bags::AirbagSpec set =
        read(with(", stepping: dynamic, dynamic: {mass_scale: 100, damping: 5 1/s, "
                  "step_fraction: 0.25}"))
            .options.bag;
    EXPECT_EQ(set.dynamics.massScale, 100.0);
    EXPECT_EQ(set.dynamics.damping, 5.0);
    EXPECT_EQ(set.dynamics.stepFraction, 0.25);
    // The settings without the stepping, a damping without its rate unit, a stepping unknown.
    for (const char* bad :
         {", stepping: quasi-static, dynamic: {mass_scale: 100}",
          ", stepping: dynamic, dynamic: {damping: 5 s}", ", stepping: implicit"}) {
        const io::InputError e = readError(with(bad));
        EXPECT_EQ(e.getLine(), 3) << bad;
    }
    // It reaches every coupled bag the run builds.
    const io::PatientOnArrayScenario sc = read(with(", stepping: dynamic"));
    const cosim::PatientOnArray poa(sc.patient, sc.options);
    for (size_t b = 0; b < poa.getBagIndices().size(); ++b) {
        const auto* fe = dynamic_cast<const cosim::BagParticipant*>(&poa.getBag(int(b)));
        ASSERT_NE(fe, nullptr);
        EXPECT_EQ(fe->getAirbag().getSpec().stepping, bags::AirbagSpec::Stepping::Dynamic) << b;
    }
}

TEST(ArrayScenario, TheRelaxedSteppingTakesItsSubstepsAndPaceAndOnlyIt) {
    auto with = [](const std::string& keys) {
        std::string t = kBase;
        t.replace(t.find("bag: {mesh_size: 30 mm}"), 23, "bag: {mesh_size: 30 mm" + keys + "}");
        return t;
    };
    const bags::AirbagSpec dflt = read(with(", stepping: relaxed")).options.bag;
    EXPECT_EQ(dflt.stepping, bags::AirbagSpec::Stepping::Relaxed);
    EXPECT_EQ(dflt.dynamics.massScale, 1000.0);
    EXPECT_EQ(dflt.dynamics.relaxSubsteps, 4000);
    EXPECT_TRUE(dflt.dynamics.newtonFirst);
    const bags::AirbagSpec set =
        read(with(", stepping: relaxed, dynamic: {relax_substeps: 500, relax_pace: 5 mm/s, "
                  "newton_first: false, newton_polish: 0}"))
            .options.bag;
    EXPECT_FALSE(set.dynamics.newtonFirst);
    EXPECT_EQ(dflt.dynamics.newtonPolish, 30);
    EXPECT_EQ(set.dynamics.newtonPolish, 0);
    EXPECT_EQ(set.dynamics.relaxSubsteps, 500);
    EXPECT_DOUBLE_EQ(set.dynamics.relaxPace, 0.005);
    // The relaxation's keys with the dynamic stepping; a pace without its unit; no sub-step.
    const io::InputError e = readError(with(", stepping: dynamic, dynamic: {relax_substeps: 500}"));
    EXPECT_EQ(e.getLine(), 3);
    EXPECT_NE(std::string(e.what()).find("relax_substeps"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("stepping: relaxed"), std::string::npos) << e.what();
    for (const auto& [bad, key] : std::vector<std::pair<std::string, std::string>>{
             {", stepping: relaxed, dynamic: {relax_pace: 5}", "relax_pace': \"5\" has no unit"},
             {", stepping: relaxed, dynamic: {relax_substeps: 0}",
              "relax_substeps': 0 is not valid; valid: in [1, 1e+07]"},
             {", stepping: relaxed, dynamic: {mass_scale: 0.5}",
              "mass_scale': 0.5 is not valid; valid: in [1, 1e+06]"},
             {", stepping: relaxed, dynamic: {newton_polish: -1}",
              "newton_polish': -1 is not valid; valid: in [0, 1000]"},
             {", stepping: dynamic, dynamic: {newton_polish: 5}",
              "newton_polish': is the relaxed stepping's"}}) {
        const io::InputError b = readError(with(bad));
        EXPECT_EQ(b.getLine(), 3) << bad;
        EXPECT_NE(std::string(b.what()).find(key), std::string::npos) << b.what();
    }
}

TEST(ArrayScenario, ThePressureAtRestSetsTheFillAsAClinicalMattressIsSet) {
    // `pressure` in place of `gas_mass`: the gas mass that fills the bag to that gauge pressure
    // unloaded, at rest. Reference: a bag of the same spec inflated with that mass by the other
    // path (Airbag::inflate(mass): the flat panels' ramp, then the gas mass ramp) reads the
    // pressure back within 0.5 %; a group's own pressure likewise; a higher pressure, more gas.
    auto with = [](const std::string& array, const std::string& right) {
        std::string t = kBase;
        const std::string fill = "  gas_mass: 4.5 g\n";
        const std::string right5 = "{name: right, columns: [1], gas_mass: 5 g}";
        t.replace(t.find(fill), fill.size(), array);
        t.replace(t.find(right5), right5.size(), "{name: right, columns: [1]" + right + "}");
        return t;
    };
    const io::PatientOnArrayScenario sc = read(with("  pressure: 4 kPa\n", ", pressure: 8 kPa"));
    const double m4 = sc.options.layout.gasMass, m8 = sc.options.layout.groups.at(1).gasMass;
    EXPECT_EQ(sc.options.layout.groups.at(0).gasMass, m4);
    EXPECT_GT(m8, m4);
    for (const auto& [mass, pressure] : {std::pair{m4, 4e3}, std::pair{m8, 8e3}}) {
        bags::AirbagSpec spec = sc.options.bag;
        spec.selfContact = false;
        bags::Airbag bag(spec);
        bag.inflate(mass);
        EXPECT_NEAR(bag.getChamberState(0).gaugePressure, pressure, 5e-3 * pressure) << mass;
    }
    // The seed's bag at 4.5 g is at about 20 kPa: 4 kPa needs less gas.
    EXPECT_LT(m4, 4.5e-3);
    EXPECT_GT(m4, 3.0e-3);
    // Refused: both or neither, a pressure out of range or without its unit, both in a group.
    auto refused = [](const std::string& text, int line, const std::string& key,
                      const std::string& what) {
        const io::InputError e = readError(text);
        EXPECT_EQ(e.getLine(), line) << e.what();
        EXPECT_EQ(e.getKey(), key) << e.what();
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    };
    refused((with("  gas_mass: 4 g\n  pressure: 4 kPa\n", "")), 12, "array.pressure",
            "and gas_mass both set the bags' fill; valid: one of them");
    refused((with("", "")), 4, "array.gas_mass",
            "missing: the bags' fill, a gas mass (gas_mass: 4.5 g) or the gauge pressure");
    refused((with("  pressure: 50 Pa\n", "")), 11, "array.pressure",
            "0.05 kPa is not valid; valid: in [0.2 kPa, 100 kPa]");
    refused((with("  pressure: 4\n", "")), 11, "array.pressure", "has no unit");
    refused((with("  pressure: 4 kPa\n", ", gas_mass: 4 g, pressure: 4 kPa")), 14,
            "array.groups[1].pressure", "and gas_mass both set the group's fill");
}

TEST(ArrayScenario, AMatWhoseFramesWouldFillTheDiskIsRefused) {
    // frames x sensels x 8 bytes above 4 GiB (1 ms over an hour on a 1024 x 1024 mat: 30 TB)
    // is refused at output.every with the size and the least interval that fits; the shipped
    // 64 x 32 mat at 50 ms over 30 s is 10 MB.
    const io::InputError e =
        readError(kBase + "mat: {rows: 1024, columns: 1024}\noutput: {every: 1 ms}\n");
    EXPECT_EQ(e.getKey(), "output.every") << e.what();
    EXPECT_NE(std::string(e.what()).find("sensels writes about"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at most 4 GiB are allowed; valid: output.every at least"),
              std::string::npos)
        << e.what();
    EXPECT_NO_THROW(read(kBase + "mat: {rows: 64, columns: 32}\noutput: {every: 50 ms}\n"));
}
