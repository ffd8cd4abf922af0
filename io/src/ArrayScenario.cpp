// Reading the patient-on-array scenario kind.
#include <bags/Airbag.h>
#include <bags/MaterialFit.h>
#include <body/Tissue.h>
#include <cosim/ArrayReadings.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>
#include <io/LoadTestScenario.h>
#include <io/PatientScenario.h>
#include <io/ReducedBagFile.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace io {

namespace {

// The bed board's friction law unless a scenario names one (array.board_friction_law).
constexpr const char* kDefaultBoardFrictionLaw = "stick-slip";

using D = Dimension;

std::string fmtUnit(double si, const std::string& unit) {
    char buf[48];
    if (unit.empty())  // a plain number
        std::snprintf(buf, sizeof buf, "%g", si);
    else
        std::snprintf(buf, sizeof buf, "%g %s", toUnit(si, unit), unit.c_str());
    return buf;
}

std::string fmtNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

// A value of `key` must lie in [lo, hi] (SI), shown in `unit`.
void checkBetween(const ScenarioNode& s, const std::string& key, double v, double lo, double hi,
                  const std::string& unit, const std::string& why = "") {
    if (v >= lo && v <= hi && std::isfinite(v)) return;
    const std::string range = std::isinf(hi)
                                  ? ">= " + fmtUnit(lo, unit)
                                  : "in [" + fmtUnit(lo, unit) + ", " + fmtUnit(hi, unit) + "]";
    s.fail(key, fmtUnit(v, unit) + " is not valid; valid: " + range +
                    (why.empty() ? "" : " (" + why + ")"));
}

void checkPositive(const ScenarioNode& s, const std::string& key, double v,
                   const std::string& unit) {
    if (v > 0.0 && std::isfinite(v)) return;
    s.fail(key, fmtUnit(v, unit) + " is not valid; valid: greater than 0 " + unit);
}

// The node at a dotted key path such as "array.groups[1].gas_mass" from the root, as far as it
// exists; the error goes to the deepest key found.
[[noreturn]] void failAtPath(const ScenarioNode& root, const std::string& path,
                             const std::string& message) {
    ScenarioNode node = root;
    std::string rest = path;
    while (!rest.empty()) {
        const size_t dot = rest.find('.');
        std::string part = rest.substr(0, dot);
        rest = dot == std::string::npos ? "" : rest.substr(dot + 1);
        int index = -1;
        const size_t bracket = part.find('[');
        if (bracket != std::string::npos) {
            index = std::atoi(part.c_str() + bracket + 1);
            part = part.substr(0, bracket);
        }
        if (!node.isMap() || !node.has(part)) node.fail(message);
        if (rest.empty() && index < 0) node.fail(part, message);
        ScenarioNode child = node.get(part);
        if (index >= 0) {
            if (!child.isSequence() || index >= int(child.getElements().size()))
                node.fail(part, message);
            child = child.getElements()[index];
            if (rest.empty()) child.fail(message);
        }
        node = child;
    }
    node.fail(message);
}

// cosim's layout errors read "key 'array.row_pitch': <what>": the error goes to that key.
[[noreturn]] void failFromCosim(const ScenarioNode& root, const std::string& message) {
    const std::string prefix = "key '";
    if (message.rfind(prefix, 0) == 0) {
        const size_t end = message.find("': ", prefix.size());
        if (end != std::string::npos)
            failAtPath(root, message.substr(prefix.size(), end - prefix.size()),
                       message.substr(end + 3));
    }
    root.fail("invalid: " + message);
}

std::vector<int> readIndices(const ScenarioNode& s, const std::string& key, int count,
                             const std::string& what) {
    std::vector<int> out;
    if (!s.has(key)) return out;
    const ScenarioNode list = s.get(key);
    if (!list.isSequence())
        s.fail(key, "must be a list of " + what + " indices from 0, e.g. [0, 1]");
    for (const ScenarioNode& e : list.getElements()) {
        const int i = e.asInteger();
        if (i < 0 || i >= count)
            e.fail(what + " " + std::to_string(i) + " does not exist; valid: 0 to " +
                   std::to_string(count - 1));
        out.push_back(i);
    }
    return out;
}

Eigen::Vector2d readXY(const ScenarioNode& s, const std::string& key, const std::string& example) {
    const ScenarioNode v = s.get(key);
    if (!v.isSequence() || v.getElements().size() != 2)
        s.fail(key, "must be two lengths [x, y], e.g. " + example);
    const std::vector<ScenarioNode> xy = v.getElements();
    return Eigen::Vector2d(xy[0].asQuantity(D::Length), xy[1].asQuantity(D::Length));
}

// ---------------------------------------------------------------------------------------- bag

// Soft tissue between the segments' bones and the films: the segments' shapes are the skin,
// the layer lies inside them (docs/contact.md#contact-law, its soft tissue).
// bag.body_tissue: absent or `published`, each site's published layer (docs/body.md#soft-tissue;
// finite-element bags; reduced bags: none); `none`, bare shapes; {thickness, modulus}, one layer
// on every segment; {site: {thickness, modulus} or none, ...}, the published layers with those
// sites changed.
void readBodyTissue(const ScenarioNode& bag, PatientOnArrayScenario& sc) {
    const bool reduced = sc.options.model == cosim::PatientOnArrayOptions::BagModel::Reduced;
    const char* const reducedWhy =
        " is not valid with model: reduced (the reduced bag's contact law is its own, fitted "
        "with bare shapes); valid: none, or model: finite-element";
    std::vector<std::string> sites;
    for (int i = 0; i < body::kTissueSiteCount; ++i)
        sites.push_back(body::getTissueSiteName(body::TissueSite(i)));
    std::array<body::SoftTissue, body::kTissueSiteCount> perSite = body::getPublishedTissues();
    if (!bag.has("body_tissue")) {
        if (!reduced) sc.options.segmentTissue = body::makeSegmentTissue(perSite);
        return;
    }
    const ScenarioNode t = bag.get("body_tissue");
    if (t.isScalar()) {
        const std::string v = t.asChoice({"published", "none"});
        if (v == "published" && reduced)
            bag.fail("body_tissue", "published" + std::string(reducedWhy));
        if (v == "published") sc.options.segmentTissue = body::makeSegmentTissue(perSite);
        return;  // none: bare shapes (contact has no layer)
    }
    if (!t.isMap())
        bag.fail("body_tissue",
                 "must be published, none, {thickness, modulus} (one layer on every segment) or "
                 "{site: {thickness, modulus} or none, ...} with sites occiput, scapulae, back, "
                 "sacrum, buttocks, calves, heels, arms");
    if (reduced) bag.fail("body_tissue", "a tissue layer" + std::string(reducedWhy));
    if (t.has("thickness") || t.has("modulus")) {  // one layer on every segment
        readTissueLayer(t, sc.options.contact);
        return;
    }
    t.checkKeys({}, sites);
    for (int i = 0; i < body::kTissueSiteCount; ++i) {
        if (!t.has(sites[size_t(i)])) continue;
        const ScenarioNode e = t.get(sites[size_t(i)]);
        if (e.isScalar()) {
            e.asChoice({"none"});
            perSite[size_t(i)] = body::SoftTissue();
            continue;
        }
        bags::RigidContact::Options c = sc.options.contact;
        readTissueLayer(t.getSection(sites[size_t(i)]), c);
        perSite[size_t(i)] = {c.tissueThickness, c.tissueModulus};
    }
    sc.options.segmentTissue = body::makeSegmentTissue(perSite);
}

void readBag(const ScenarioNode& s, PatientOnArrayScenario& sc, const std::string& fileName) {
    s.checkKeys({}, {"reading", "mesh_size", "self_contact", "diaphragm", "force_tolerance",
                     "contact_penalty", "body_friction", "friction_law", "slip_velocity",
                     "body_tissue", "model", "calibration", "bending_stiffness", "stick_distance",
                     "film_damping", "stepping", "dynamic"});
    bags::AirbagSpec& b = sc.options.bag;
    bags::DoubleWedgeParams& g = b.geometry;
    sc.bagReading = s.getChoice("reading", {"literal", "fill-2.8g"}, "literal");
    if (sc.bagReading == "fill-2.8g") {
        // The seed's sizes scaled (side profile, width kept) until 2.8 g of air just fills the
        // inflated bag: s = 0.8796 at the 10 mm mesh (docs/geometry.md).
        g.longSide = 0.3079;
        g.shortSide = 0.1759;
        g.height = 0.1319;
    }  // literal: the sizes as written, DoubleWedgeParams' defaults (350, 200, 100, 150 mm)
    g.meshSize = s.getQuantity("mesh_size", D::Length, 0.030);
    checkBetween(s, "mesh_size", g.meshSize, 0.005, 0.05, "mm",
                 "finer than 5 mm makes every bag thousands of nodes");
    g.diaphragm = s.getBool("diaphragm", g.diaphragm);
    b.selfContact = s.getBool("self_contact", false);
    b.forceTolerance = s.getQuantity("force_tolerance", D::Force, 1e-4);
    checkBetween(s, "force_tolerance", b.forceTolerance, 1e-6, 1.0, "N");
    sc.options.contact.pressurePenalty = s.getQuantity("contact_penalty", D::StiffnessPerArea, 1e8);
    checkBetween(s, "contact_penalty", sc.options.contact.pressurePenalty, 1e5, 1e10, "Pa/m");
    // Coulomb friction of the body's shapes on the films (skin or sheet on the bags' nylon or
    // TPU film). 0, frictionless, is the default: every figure measured before the key came
    // was frictionless (docs/cosim.md#friction-between-the-body-and-the-films).
    sc.options.contact.friction = s.getNumber("body_friction", 0.0);
    if (!(sc.options.contact.friction >= 0.0 && sc.options.contact.friction <= 2.0))
        s.fail("body_friction", fmtNumber(sc.options.contact.friction) +
                                    " is not valid; valid: 0 (frictionless) to 2, e.g. 0.4 "
                                    "(skin or cotton on a fabric or film: 0.3-0.5)");
    // How the friction force follows the slip (docs/contact.md#contact-law): the elastic stick
    // spring capped at mu f_n, or Coulomb regularised by the slip rate over the step.
    const std::string law =
        s.getChoice("friction_law", {"stick-slip", "regularised"}, "stick-slip");
    sc.options.contact.frictionLaw = law == "regularised"
                                         ? bags::RigidContact::FrictionLaw::Regularised
                                         : bags::RigidContact::FrictionLaw::StickSlip;
    if (s.has("slip_velocity") && law != "regularised")
        s.fail("slip_velocity",
               "is the regularised law's; valid only with friction_law: "
               "regularised (this file's law: " +
                   law + ")");
    sc.options.contact.slipVelocity =
        s.getQuantity("slip_velocity", D::Velocity, sc.options.contact.slipVelocity);
    checkBetween(s, "slip_velocity", sc.options.contact.slipVelocity, 1e-5, 1.0, "mm/s",
                 "below the body's sliding speeds, e.g. 2 mm/s as the bed board's");
    // The seed's Yeoh fit of its tensile test, 0.2 mm film (scenarios/seed-load-test.yaml).
    b.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    // The film's bending stiffness (docs/materials.md#bending-stiffness-of-the-film), the plate
    // value unless set, as in the load test: it gives slack film a stiffness of its own
    // (docs/cosim.md#slack-film-and-the-films-bending).
    b.bendingStiffness = readBendingStiffness(s, "bending_stiffness", *b.material, b.thickness);
    // Damped steps (docs/solver.md#damped-steps-damping-measured-not-a-speed-up): each step first solved with a damper
    // on the film that is not taut, then the damper-free equilibrium. Off by default.
    b.damping = s.getQuantity("film_damping", D::StiffnessPerArea, 0.0);
    checkBetween(s, "film_damping", b.damping, 0.0, 1e8, "Pa/m",
                 "0: none; 1e5 Pa/m was measured on the seed's bag");
    b.threads = 1;  // bags run in parallel, one per thread
    // The film in time (docs/solver.md#the-film-in-time): its mass scale, damping and
    // sub-step. Quasi-static by default: the relaxed stepping goes on where the quasi-static
    // one stops on a crumpled film, but it failed the clinical 20 mm settle the quasi-static
    // one completes (docs/solver.md, "The defaults, chosen by those figures").
    b.stepping = readStepping(s, bags::AirbagSpec::Stepping::QuasiStatic);
    if (s.has("dynamic")) {
        const ScenarioNode d = s.getSection("dynamic");
        d.checkKeys({}, {"mass_scale", "damping", "step_fraction", "relax_substeps", "relax_pace",
                         "newton_first", "newton_polish", "quasi_static_fallback"});
        b.dynamics.massScale = d.getNumber("mass_scale", 1000.0);
        checkBetween(d, "mass_scale", b.dynamics.massScale, 1.0, 1e6, "",
                     "the film's masses times this, e.g. 1000");
        b.dynamics.damping = d.getQuantity("damping", D::Rate, 20.0);
        checkBetween(d, "damping", b.dynamics.damping, 0.0, 1e4, "1/s", "e.g. 20 1/s");
        b.dynamics.stepFraction = d.getNumber("step_fraction", 0.5);
        checkBetween(d, "step_fraction", b.dynamics.stepFraction, 1e-3, 1.0, "",
                     "a fraction of the stable step, e.g. 0.5");
        if (b.stepping != bags::AirbagSpec::Stepping::Relaxed)
            for (const char* key : {"relax_substeps", "relax_pace", "newton_first", "newton_polish",
                                    "quasi_static_fallback"})
                if (d.has(key))
                    d.fail(key, "is the relaxed stepping's: leave it out, or 'stepping: relaxed'");
        b.dynamics.relaxSubsteps = d.getInteger("relax_substeps", b.dynamics.relaxSubsteps);
        checkBetween(d, "relax_substeps", b.dynamics.relaxSubsteps, 1, 1e7, "",
                     "the most sub-steps a step may relax with, e.g. 4000");
        b.dynamics.relaxPace = d.getQuantity("relax_pace", D::Velocity, b.dynamics.relaxPace);
        checkBetween(d, "relax_pace", b.dynamics.relaxPace, 1e-5, 10.0, "mm/s",
                     "e.g. 20 mm/s (at mass scale 1000)");
        b.dynamics.newtonFirst = d.getBool("newton_first", b.dynamics.newtonFirst);
        b.dynamics.quasiStaticFallback =
            d.getBool("quasi_static_fallback", b.dynamics.quasiStaticFallback);
        b.dynamics.newtonPolish = d.getInteger("newton_polish", b.dynamics.newtonPolish);
        checkBetween(d, "newton_polish", b.dynamics.newtonPolish, 0, 1000, "",
                     "0 (no Newton after the relaxation) to 1000 iterations, e.g. 30");
    } else if (b.stepping != bags::AirbagSpec::Stepping::QuasiStatic) {
        b.dynamics.massScale = 1000.0;
        b.dynamics.damping = 20.0;
    }
    readReducedBagKeys(s, sc.options, fileName);
    // The reduced bag's friction (docs/reduced-bag.md#friction): one stick spring per shape,
    // capped at mu times its contact force; the travel over which it takes hold.
    const bool reduced = sc.options.model == cosim::PatientOnArrayOptions::BagModel::Reduced;
    if (s.has("stick_distance")) {
        if (!reduced)
            s.fail("stick_distance",
                   "is the reduced bag's (model: reduced); the finite-element "
                   "bag's film takes hold node by node");
        sc.options.reducedFriction.stickDistance = s.getQuantity("stick_distance", D::Length);
        checkBetween(s, "stick_distance", sc.options.reducedFriction.stickDistance, 1e-4, 0.05,
                     "mm");
    }
    if (reduced && (s.has("stepping") || s.has("dynamic")))
        s.fail(s.has("stepping") ? "stepping" : "dynamic",
               "is the finite-element bag's (how its film is stepped); the reduced bag has no "
               "film: leave it out, or model: finite-element");
    if (reduced && s.has("film_damping"))
        s.fail("film_damping",
               "is the finite-element bag's (its slack film's damper); the "
               "reduced bag has no film to damp: leave it out, or model: "
               "finite-element");
    if (!reduced && b.stepping != bags::AirbagSpec::Stepping::QuasiStatic && b.damping > 0.0)
        s.fail("film_damping",
               "is the quasi-static stepping's damped steps; the " +
                   std::string(b.stepping == bags::AirbagSpec::Stepping::Relaxed ? "relaxed"
                                                                                 : "dynamic") +
                   " stepping takes no damper: leave it out, or "
                   "'stepping: quasi-static' beside it");
    if (reduced && s.has("friction_law") && law != "stick-slip")
        s.fail("friction_law", law +
                                   " is not valid with model: reduced; valid: stick-slip "
                                   "(the reduced bag's one law)");
    readBodyTissue(s, sc);
}

// -------------------------------------------------------------------------------------- array

// The gas mass that fills the scenario's bag to a gauge pressure p [Pa], unloaded and at rest:
// a regulated supply filling the cell to its setpoint, then sealed (Airbag::inflateToPressure()
// on one bag of the array's geometry and mesh; the same for every bag, whatever its place).
// One inflation per distinct pressure of the file.
// A cell pressure [Pa gauge]: a pressure, or `from-body` (cosim::calcCellPressureForBody, from
// the patient's mass and height; *fromBody then true).
double readCellPressure(const ScenarioNode& s, const std::string& key,
                        const body::PatientSpec& patient, bool* fromBody) {
    *fromBody = false;
    const ScenarioNode v = s.get(key);
    if (v.isScalar() && v.asString() == "from-body") {
        *fromBody = true;
        return cosim::calcCellPressureForBody(patient);
    }
    if (!v.isScalar()) return v.asQuantity(D::Pressure);  // fails, naming what it is
    try {
        return parseQuantity(v.asString(), D::Pressure);
    } catch (const UnitError& e) {
        s.fail(key, std::string(e.what()) +
                        "; or from-body (the pressure set from the patient's mass and height, "
                        "docs/pneumatics.md#a-setpoint-from-his-body)");
    }
}

double readMassAtPressure(const ScenarioNode& s, const std::string& key,
                          const bags::AirbagSpec& bag,
                          std::vector<std::pair<double, double>>& known,
                          const body::PatientSpec& patient, bool* fromBody) {
    const double p = readCellPressure(s, key, patient, fromBody);
    checkBetween(s, key, p, 200.0, 1e5, "kPa",
                 "clinical cells run at about 1.5-8 kPa; the seed's wedge is at about 20 kPa with "
                 "4.5 g");
    for (const auto& [pk, mass] : known)
        if (pk == p) return mass;
    bags::AirbagSpec spec = bag;
    spec.selfContact = false;  // the unloaded cell's walls stand apart
    spec.stepping = bags::AirbagSpec::Stepping::QuasiStatic;
    spec.damping = 0.0;
    double mass = 0.0;
    try {
        bags::Airbag probe(spec);
        probe.inflateToPressure(p);
        mass = probe.getGasMass(0);
    } catch (const std::exception& e) {
        s.fail(key, fmtUnit(p, "kPa") + ": the bag could not be inflated to it (" + e.what() +
                        "); valid: a pressure the bag holds, e.g. 4 kPa");
    }
    known.emplace_back(p, mass);
    return mass;
}

// A gas mass no film bag can hold (io::calcMostPlausibleGasMass) is refused at its key.
void checkPlausibleGas(const ScenarioNode& s, const std::string& key, double mass,
                       const bags::AirbagSpec& bag) {
    const double most = calcMostPlausibleGasMass(bag.geometry, bag.gas);
    if (mass > most) s.fail(key, describeTooMuchGas(mass, most));
}

void readArray(const ScenarioNode& s, PatientOnArrayScenario& sc) {
    s.checkKeys(
        {"rows", "columns"},
        {"gas_mass", "pressure", "row_pitch", "column_pitch", "centre", "orientation",
         "mirror_columns", "groups", "board_contact", "board_friction_law", "board_stick_distance",
         "board_slip_velocity", "neighbour_contact", "neighbour_margin"});
    cosim::ArrayLayout& a = sc.options.layout;
    a.rows = s.get("rows").asInteger();
    a.columns = s.get("columns").asInteger();
    if (a.rows < 1) s.fail("rows", std::to_string(a.rows) + "; valid: 1 or more");
    if (a.columns < 1) s.fail("columns", std::to_string(a.columns) + "; valid: 1 or more");
    if (a.rows * a.columns > kMaxArrayBags)
        s.fail("rows", std::to_string(a.rows) + " x " + std::to_string(a.columns) +
                           " bags; valid: at most " + std::to_string(kMaxArrayBags) +
                           " bags in all (docs/scenario-reference.md#limits)");
    if (a.rows > 1 && !s.has("row_pitch"))
        s.fail("row_pitch", "missing: " + std::to_string(a.rows) +
                                " rows need the distance between row centres, e.g. 105 mm");
    if (a.columns > 1 && !s.has("column_pitch"))
        s.fail("column_pitch", "missing: " + std::to_string(a.columns) +
                                   " columns need the distance between column centres, e.g. "
                                   "360 mm");
    a.rowPitch = s.getQuantity("row_pitch", D::Length, 0.0);
    a.columnPitch = s.getQuantity("column_pitch", D::Length, 0.0);
    if (s.has("centre")) a.centre = readXY(s, "centre", "[0 m, 0 m]");
    if (s.has("orientation")) {
        const ScenarioNode o = s.get("orientation");
        const std::vector<std::string> choices = {"across", "across-flipped", "along",
                                                  "along-flipped"};
        if (o.isScalar()) {
            a.rowOrientation = {cosim::parseBagOrientation(o.asChoice(choices))};
        } else if (o.isSequence() && !o.getElements().empty()) {
            for (const ScenarioNode& e : o.getElements())
                a.rowOrientation.push_back(cosim::parseBagOrientation(e.asChoice(choices)));
        } else {
            s.fail("orientation",
                   "must be one orientation or a list repeated over the rows, e.g. [across, "
                   "across-flipped]; valid: across, across-flipped, along, along-flipped");
        }
    }
    a.mirrorColumns = s.getBool("mirror_columns", false);
    // The bed board under the bags, as the body feels it where it reaches it (between bags,
    // through a slack or bottomed bag, beside the array): PatientOnArrayOptions::boardContact.
    sc.options.boardContact = s.getBool("board_contact", true);
    // Its friction (body::PlaneSupportOptions::frictionLaw, docs/scenario-reference.md):
    // stick-slip, an elastic stick spring per patch capped at mu f_n (no creep; a spring of
    // mu f_n / d_s), or Coulomb regularised at a slip velocity (a body resting on the board
    // creeps at v_s f_t / (mu f_n), and small v_s make the friction stiff in the body's
    // velocity: it then sets the body's steps where hands and forearms rest on the board,
    // docs/performance.md#the-reduced-bag).
    readSupportFriction(s, "board_", kDefaultBoardFrictionLaw, sc.options.board);
    checkBetween(s, "board_slip_velocity", sc.options.board.slipVelocity, 1e-5, 1.0, "mm/s",
                 "a creep speed: 2 mm/s by default, 20 mm/s halves a reduced-bag run's time");
    checkBetween(s, "board_stick_distance", sc.options.board.stickDistance, 1e-5, 0.02, "mm",
                 "the elastic slip of skin or cloth on the board before it slides: 1 mm by "
                 "default");
    // Neighbouring bags touch: the bags that may meet once inflated are solved as one module
    // (PatientOnArrayOptions::neighbourContact, docs/cosim.md#contact-between-neighbouring-bags).
    sc.options.neighbourContact = s.getBool("neighbour_contact", false);
    sc.options.neighbourMargin =
        s.getQuantity("neighbour_margin", D::Length, sc.options.neighbourMargin);
    checkBetween(s, "neighbour_margin", sc.options.neighbourMargin, 0.0, 0.1, "mm",
                 "added on every side of an inflated bag's extent when grouping neighbours");
    if (sc.options.neighbourContact && !sc.options.bag.selfContact)
        s.fail("neighbour_contact",
               "true needs bag.self_contact: true (the films of neighbouring bags meet through "
               "the bags' self-contact); valid: false, or turn bag.self_contact on");
    if (sc.options.neighbourContact &&
        sc.options.model != cosim::PatientOnArrayOptions::BagModel::FiniteElement)
        s.fail("neighbour_contact",
               "true needs the finite-element bags (the reduced model has no film to touch); "
               "valid: false with bag.model reduced");
    // The bags' fill: a gas mass, or a gauge pressure the bag is filled to at rest (then
    // sealed, or held by the pneumatics' controller), as a clinical mattress is set.
    if (s.has("gas_mass") == s.has("pressure"))
        s.fail(s.has("gas_mass") ? "pressure" : "gas_mass",
               s.has("gas_mass") ? "and gas_mass both set the bags' fill; valid: one of them"
                                 : "missing: the bags' fill, a gas mass (gas_mass: 4.5 g) or the "
                                   "gauge pressure they are filled to at rest (pressure: 4 kPa)");
    std::vector<std::pair<double, double>> known;  // pressure, mass: inflated once each
    bool fromBody = false;
    if (s.has("pressure")) {
        a.gasMass = readMassAtPressure(s, "pressure", sc.options.bag, known, sc.patient, &fromBody);
        if (fromBody) sc.fillFromBody = cosim::calcCellPressureForBody(sc.patient);
    } else {
        a.gasMass = s.getQuantity("gas_mass", D::Mass);
        checkPositive(s, "gas_mass", a.gasMass, "g");
        checkPlausibleGas(s, "gas_mass", a.gasMass, sc.options.bag);
    }
    if (s.has("groups")) {
        const ScenarioNode gs = s.get("groups");
        if (!gs.isSequence())
            s.fail("groups",
                   "must be a list of groups, e.g. - {name: left, columns: [0], "
                   "gas_mass: 4.5 g}");
        for (const ScenarioNode& e : gs.getElements()) {
            e.checkKeys({"name"}, {"rows", "columns", "gas_mass", "pressure"});
            cosim::BagGroup g;
            g.name = e.getString("name");
            g.rows = readIndices(e, "rows", a.rows, "row");
            g.columns = readIndices(e, "columns", a.columns, "column");
            if (e.has("gas_mass") && e.has("pressure"))
                e.fail("pressure", "and gas_mass both set the group's fill; valid: one of them");
            if (e.has("pressure")) {
                g.gasMass =
                    readMassAtPressure(e, "pressure", sc.options.bag, known, sc.patient, &fromBody);
                if (fromBody) sc.fillFromBody = cosim::calcCellPressureForBody(sc.patient);
            } else {
                g.gasMass = e.getQuantity("gas_mass", D::Mass, a.gasMass);
                checkPositive(e, "gas_mass", g.gasMass, "g");
                if (e.has("gas_mass")) checkPlausibleGas(e, "gas_mass", g.gasMass, sc.options.bag);
            }
            a.groups.push_back(g);
        }
    }
}

// ---------------------------------------------------------------------------------------- gas

void readGas(const ScenarioNode& root, PatientOnArrayScenario& sc) {
    if (!root.has("gas")) return;
    const ScenarioNode gs = root.get("gas");
    if (!gs.isSequence())
        root.fail("gas",
                  "must be a list of commands, e.g. - {at: 0 s, group: right, target: "
                  "5.5 g, rate: 0.05 g/s}");
    const cosim::ArrayLayout& a = sc.options.layout;
    const int numBags = a.rows * a.columns;
    std::vector<std::string> groupNames;
    for (const cosim::BagGroup& g : a.groups) groupNames.push_back(g.name);
    int index = 0;
    for (const ScenarioNode& e : gs.getElements()) {
        e.checkKeys({}, {"at", "group", "bags", "target", "rate", "flow"});
        GasCommandText text;
        std::vector<int> bags;
        if (e.has("group") == e.has("bags"))
            e.fail(
                "name the bags with either 'group' (one of array.groups) or 'bags' (a list of "
                "bag indices, row x columns + column), not both or neither");
        if (e.has("group")) {
            if (groupNames.empty())
                e.fail("group",
                       "the array has no groups; define them in array.groups, or use "
                       "'bags: [...]'");
            const std::string name = e.getChoice("group", groupNames);
            const int gi =
                int(std::find(groupNames.begin(), groupNames.end(), name) - groupNames.begin());
            for (const cosim::ArrayBag& b : cosim::makeArrayBags(a, sc.options.bag.geometry))
                if (b.group == gi) bags.push_back(b.index);
            text.who = "group '" + name + "'";
        } else {
            bags = readIndices(e, "bags", numBags, "bag");
            if (bags.empty())
                e.fail("bags", "is empty; valid: bag indices 0 to " + std::to_string(numBags - 1));
            text.who = "bags";
            for (size_t i = 0; i < bags.size(); ++i)
                text.who += (i ? ", " : " ") + std::to_string(bags[i]);
        }
        cosim::GasCommand c;
        text.at = e.getQuantity("at", D::Time, 0.0);
        checkBetween(e, "at", text.at, 0.0, INFINITY, "s",
                     "from the end of the settle, run.settle_time");
        if (text.at > sc.duration)
            e.fail("at", fmtUnit(text.at, "s") + " is after the run's end (run.duration " +
                             fmtUnit(sc.duration, "s") + "); valid: 0 s to " +
                             fmtUnit(sc.duration, "s"));
        c.time = sc.settleTime + text.at;
        if (e.has("target") == e.has("flow"))
            e.fail(
                "give either 'target' (a gas mass per bag, with 'rate') or 'flow' (a mass "
                "flow into each bag, negative out), not both or neither");
        if (e.has("target")) {
            c.kind = cosim::GasCommand::Kind::Target;
            c.targetMass = e.getQuantity("target", D::Mass);
            // The grouping of neighbours measures a bag inflated to the largest mass it is
            // taken to.
            sc.options.neighbourMass = std::max(sc.options.neighbourMass, c.targetMass);
            checkPositive(e, "target", c.targetMass, "g");
            if (!e.has("rate"))
                e.fail("rate",
                       "missing: a target is reached at a stated mass flow, e.g. rate: "
                       "0.05 g/s");
            c.rate = e.getQuantity("rate", D::MassFlow);
            checkPositive(e, "rate", c.rate, "g/s");
            text.what = "target " + fmtUnit(c.targetMass, "g") + " at " + fmtUnit(c.rate, "g/s");
        } else {
            if (e.has("rate")) e.fail("rate", "only applies with 'target'; a flow is its own rate");
            c.kind = cosim::GasCommand::Kind::Flow;
            c.massFlow = e.getQuantity("flow", D::MassFlow);
            if (!std::isfinite(c.massFlow)) e.fail("flow", "must be finite");
            text.what = "flow " + fmtUnit(c.massFlow, "g/s");
        }
        const std::string name = "gas[" + std::to_string(index) + "]";
        sc.gas.add(bags, c, name);
        try {
            sc.gas.validate(numBags);
        } catch (const std::invalid_argument& err) {
            e.fail(std::string(err.what()) +
                   "; valid: one command per bag and start time (give a later 'at')");
        }
        sc.gasText.push_back(text);
        ++index;
    }
}

// ----------------------------------------------------------------------------------- coupling

// coupling.macro_step: a time (the fixed step, halved only where a step fails) or `adaptive`
// (the step follows each step's accuracy between min_macro_step and max_macro_step,
// docs/cosim.md#the-schemes).
void readMacroStep(const ScenarioNode& s, cosim::CouplingOptions& c) {
    c.adaptive = s.has("macro_step") && s.get("macro_step").isScalar() &&
                 s.get("macro_step").asString() == "adaptive";
    if (!c.adaptive) {
        for (const char* key : {"max_macro_step", "step_accuracy"})
            if (s.has(key))
                s.fail(key,
                       "only applies with macro_step: adaptive; valid: leave it out or "
                       "set macro_step: adaptive");
        try {
            c.macroStep = s.getQuantity("macro_step", D::Time, 0.01);
        } catch (const InputError&) {
            if (!s.get("macro_step").isScalar()) throw;
            s.fail("macro_step", "'" + s.get("macro_step").asString() +
                                     "' is not valid; valid: a time such as 10 ms, or adaptive");
        }
        checkBetween(s, "macro_step", c.macroStep, 1e-5, 0.1, "ms");
        c.minMacroStep = s.getQuantity("min_macro_step", D::Time, 1e-5);
        checkBetween(s, "min_macro_step", c.minMacroStep, 1e-7, c.macroStep, "ms",
                     "at most the macro step");
        return;
    }
    c.maxMacroStep = s.getQuantity("max_macro_step", D::Time, 0.04);
    checkBetween(s, "max_macro_step", c.maxMacroStep, 1e-5, 0.1, "ms");
    c.minMacroStep = s.getQuantity("min_macro_step", D::Time, 1e-3);
    checkBetween(s, "min_macro_step", c.minMacroStep, 1e-7, c.maxMacroStep, "ms",
                 "at most max_macro_step");
    c.macroStep = c.minMacroStep;  // the first step: grown while the steps are accurate
    c.minCutStep = 1e-5;           // a failing step is halved as far as a fixed one may be
    c.stepAccuracy = s.getNumber("step_accuracy", 1000.0);
    if (!(c.stepAccuracy >= 0.1 && c.stepAccuracy <= 1e4))
        s.fail("step_accuracy", fmtNumber(c.stepAccuracy) +
                                    " is not valid; valid: 0.1 to 10000 (multiples of the "
                                    "coupling tolerance), e.g. 1000");
}

void readCoupling(const ScenarioNode& s, cosim::PatientOnArrayOptions& o) {
    s.checkKeys({}, {"scheme", "acceleration", "macro_step", "min_macro_step", "max_macro_step",
                     "step_accuracy", "relative_tolerance", "absolute_tolerance", "max_iterations",
                     "threads", "body_accuracy", "tangent_tolerance", "skip_travel", "gas_tangent",
                     "keep_unconverged", "accept_residual"});
    cosim::CouplingOptions& c = o.coupling;
    // The defaults follow the bag model. Reduced bags: the tangent scheme (the implicit one
    // stops where a shape's overlap jumps, docs/reduced-bag.md#in-the-turn) and the body's
    // integrator at 1e-4 (2.2 times fewer steps than 1e-6, the tilts within 0.04 deg: far
    // inside the reduced bag's own errors, docs/performance.md#the-reduced-bag).
    const bool reduced = o.model == cosim::PatientOnArrayOptions::BagModel::Reduced;
    c.scheme = cosim::parseScheme(
        s.getChoice("scheme", {"explicit", "implicit", "tangent", "tangent-implicit"},
                    reduced ? "tangent" : "implicit"));
    c.acceleration = cosim::parseAcceleration(
        s.getChoice("acceleration", {"constant", "aitken", "iqn-ils"}, "iqn-ils"));
    readMacroStep(s, c);
    c.relativeTolerance = s.getNumber("relative_tolerance", 1e-6);
    if (!(c.relativeTolerance > 0.0 && c.relativeTolerance < 1.0))
        s.fail("relative_tolerance", "must lie between 0 and 1, e.g. 1e-6");
    c.absoluteTolerance = s.getQuantity("absolute_tolerance", D::Force, 1e-3);
    checkBetween(s, "absolute_tolerance", c.absoluteTolerance, 1e-6, 10.0, "N");
    if (!(c.absoluteTolerance > o.bag.forceTolerance))
        s.fail("absolute_tolerance",
               fmtUnit(c.absoluteTolerance, "N") +
                   " is not above the bags' own solve "
                   "tolerance bag.force_tolerance (" +
                   fmtUnit(o.bag.forceTolerance, "N") +
                   "): a bag's wrench is no more exact than that; valid: above it");
    c.maxIterations = s.getInteger("max_iterations", 50);
    if (c.maxIterations < 1 || c.maxIterations > 1000)
        s.fail("max_iterations", std::to_string(c.maxIterations) + "; valid: 1 to 1000");
    c.threads = s.getInteger("threads", 0);
    if (c.threads < 0 || c.threads > 256)
        s.fail("threads", std::to_string(c.threads) + "; valid: 0 (one per core) to 256");
    c.tangentTolerance = s.getQuantity("tangent_tolerance", D::Force, 0.0);
    checkBetween(s, "tangent_tolerance", c.tangentTolerance, 0.0, 10.0, "N",
                 "0: recomputed every step");
    c.skipTravel = s.getQuantity("skip_travel", D::Length, 0.0);
    checkBetween(s, "skip_travel", c.skipTravel, 0.0, 0.01, "mm", "0: every bag every step");
    c.gasTangent = s.getBool("gas_tangent", true);
    // A step with no fixed point at the smallest step is kept (the run ends partial) rather
    // than ending the run there (docs/cosim.md#the-schemes).
    c.keepUnconverged = s.getBool("keep_unconverged", true);
    // A step whose passes stall within this is accepted at its size: 0.1 N is 1 mmHg over one
    // sensel of the clinical mat (7.7 cm2), a change no reading shows (docs/cosim.md).
    c.acceptResidual = s.getQuantity("accept_residual", D::Force, 0.1);
    checkBetween(s, "accept_residual", c.acceptResidual, 0.0, 10.0, "N",
                 "0: only the tolerance is accepted");
    o.integrator.accuracy = s.getNumber("body_accuracy", reduced ? 1e-4 : 1e-6);
    if (!(o.integrator.accuracy > 0.0 && o.integrator.accuracy < 1e-2))
        s.fail("body_accuracy", "must lie between 0 and 0.01, e.g. 1e-6");
}

// --------------------------------------------------------------------------------- pneumatics

// Typical values of the clinical alternating-pressure and turning mattress hardware this
// class of device uses (docs/pneumatics.md#the-scenarios-hardware-typical-values): stated as typical values
// of the class, not as one product's data.
pneumatics::ValveSpec makeTypicalValve() {
    pneumatics::ValveSpec v;
    v.sonicConductance = 0.3e-8;  // 0.3 dm^3/(s bar): a miniature 2/2 solenoid valve
    v.criticalPressureRatio = 0.4;
    v.openingTime = 0.02;  // 20 ms
    return v;
}

pneumatics::ValveSpec readValve(const ScenarioNode& s, pneumatics::ValveSpec v) {
    s.checkKeys({}, {"conductance", "critical_ratio", "subsonic_index", "opening_time"});
    v.sonicConductance = s.getQuantity("conductance", D::SonicConductance, v.sonicConductance);
    checkBetween(s, "conductance", v.sonicConductance, 0.0, 1e-6, "dm^3/(s bar)");
    v.criticalPressureRatio = s.getNumber("critical_ratio", v.criticalPressureRatio);
    if (!(v.criticalPressureRatio >= 0.0 && v.criticalPressureRatio < 1.0))
        s.fail("critical_ratio", "must lie in [0, 1), e.g. 0.4 (ISO 6358's b)");
    v.subsonicIndex = s.getNumber("subsonic_index", v.subsonicIndex);
    if (!(v.subsonicIndex > 0.0 && v.subsonicIndex <= 1.0))
        s.fail("subsonic_index", "must lie in (0, 1], e.g. 0.5 (ISO 6358's m)");
    v.openingTime = s.getQuantity("opening_time", D::Time, v.openingTime);
    checkBetween(s, "opening_time", v.openingTime, 0.0, 10.0, "ms");
    return v;
}

// A gas volume's thermal model (and its heat exchange) from keys thermal, heat_transfer,
// wall_area.
void readThermal(const ScenarioNode& s, pneumatics::VolumeSpec& v) {
    const std::string t =
        s.getChoice("thermal", {"isothermal", "adiabatic", "heat-exchange"}, "isothermal");
    v.thermal = t == "adiabatic"       ? pneumatics::Thermal::Adiabatic
                : t == "heat-exchange" ? pneumatics::Thermal::HeatExchange
                                       : pneumatics::Thermal::Isothermal;
    if (v.thermal != pneumatics::Thermal::HeatExchange) {
        for (const char* k : {"heat_transfer", "wall_area"})
            if (s.has(k)) s.fail(k, "only applies with thermal: heat-exchange");
        return;
    }
    for (const char* k : {"heat_transfer", "wall_area"})
        if (!s.has(k))
            s.fail(k,
                   "missing: thermal: heat-exchange needs heat_transfer (W/(m^2 K), e.g. 10) "
                   "and wall_area (e.g. 100 cm^2)");
    // [W/(m^2 K)]: io::Units has no unit for it, so a plain number in W/(m^2 K).
    v.heatTransferCoefficient = s.getNumber("heat_transfer");
    if (!(v.heatTransferCoefficient >= 0.0 && v.heatTransferCoefficient <= 1e4))
        s.fail("heat_transfer", "must be a number of W/(m^2 K) from 0 to 10000, e.g. 10");
    v.wallArea = s.getQuantity("wall_area", D::Area);
    checkBetween(s, "wall_area", v.wallArea, 0.0, 100.0, "cm^2");
}

// The channel names: a group's name, or the one given.
int findChannel(const ScenarioNode& s, const std::string& key,
                const cosim::ArrayPneumaticsSpec& p) {
    std::vector<std::string> names;
    for (const cosim::PneumaticChannel& c : p.channels) names.push_back(c.name);
    const std::string name = s.getChoice(key, names);
    return int(std::find(names.begin(), names.end(), name) - names.begin());
}

void readPneumatics(const ScenarioNode& root, PatientOnArrayScenario& sc) {
    if (!root.has("pneumatics")) return;
    if (root.has("gas"))
        root.fail("gas",
                  "a scenario with a pneumatics section moves its gas through the valves "
                  "(control:); remove the gas list, or the pneumatics section");
    const ScenarioNode s = root.getSection("pneumatics");
    s.checkKeys({}, {"pump", "manifold", "valves", "line", "sensor", "channels", "orifices",
                     "max_substep"});
    sc.hasPneumatics = true;
    cosim::ArrayPneumaticsSpec& p = sc.pneumatics;
    const cosim::ArrayLayout& a = sc.options.layout;
    const int numBags = a.rows * a.columns;
    // The pump: a small diaphragm pump, about 8 L/min of free air (0.16 g/s) into no
    // back-pressure, shut off near 100 kPa.
    p.pump.pressureRise = {0.0, 50e3, 100e3};
    p.pump.massFlow = {0.16e-3, 0.10e-3, 0.0};
    const ScenarioNode pump = s.getSection("pump", false);
    pump.checkKeys({}, {"curve"});
    if (pump.has("curve")) {
        const ScenarioNode c = pump.get("curve");
        const char* example =
            "must be a list of [pressure rise, mass flow] points, e.g. [[0 kPa, 0.16 g/s], "
            "[50 kPa, 0.1 g/s], [100 kPa, 0 g/s]]";
        if (!c.isSequence() || c.getElements().size() < 2) pump.fail("curve", example);
        p.pump.pressureRise.clear();
        p.pump.massFlow.clear();
        // Each point checked here, in the user's words and units (the library's own check
        // below speaks of its fields in SI).
        for (const ScenarioNode& e : c.getElements()) {
            if (!e.isSequence() || e.getElements().size() != 2) e.fail(example);
            const ScenarioNode rise = e.getElements()[0], flow = e.getElements()[1];
            const double dp = rise.asQuantity(D::Pressure), q = flow.asQuantity(D::MassFlow);
            if (!(dp >= 0.0))
                rise.fail("the pressure rise " + rise.asString() +
                          " is below 0 kPa; valid: 0 kPa "
                          "(the free-flow point) or more");
            if (!(q >= 0.0))
                flow.fail("the mass flow " + flow.asString() +
                          " is below 0 g/s; valid: 0 g/s or more");
            if (!p.pump.pressureRise.empty() && !(dp > p.pump.pressureRise.back()))
                rise.fail("the pressure rise " + rise.asString() +
                          " is not above the point "
                          "before's; valid: points in increasing pressure rise, e.g. [[0 kPa, "
                          "8 g/s], [60 kPa, 5 g/s], [120 kPa, 0 g/s]]");
            if (!p.pump.massFlow.empty() && q > p.pump.massFlow.back())
                flow.fail("the mass flow " + flow.asString() +
                          " is above the point before's; "
                          "valid: a pump delivers less as the pressure it works against rises");
            p.pump.pressureRise.push_back(dp);
            p.pump.massFlow.push_back(q);
        }
        if (p.pump.massFlow.back() != 0.0)
            c.getElements().back().getElements()[1].fail(
                "the last point's mass flow is " +
                c.getElements().back().getElements()[1].asString() +
                "; valid: 0 g/s, the last point is the pump's shut-off pressure");
        try {
            p.pump.validate("pump curve");
        } catch (const std::invalid_argument& err) {
            pump.fail("curve", std::string(err.what()));
        }
    }
    const ScenarioNode mf = s.getSection("manifold", false);
    mf.checkKeys({}, {"volume", "thermal", "heat_transfer", "wall_area"});
    p.manifold.volume = mf.getQuantity("volume", D::Volume, 20e-6);
    checkBetween(mf, "volume", p.manifold.volume, 1e-7, 0.1, "mL");
    readThermal(mf, p.manifold);
    p.manifold.temperature = p.manifold.wallTemperature = sc.options.bag.gas.temperature;
    const ScenarioNode line = s.getSection("line", false);
    line.checkKeys({}, {"volume", "connector", "thermal", "heat_transfer", "wall_area"});
    const double lineVolume = line.getQuantity("volume", D::Volume, 20e-6);
    checkBetween(line, "volume", lineVolume, 1e-7, 0.01, "mL");
    bags::OrificeOptions connector;  // bags' orifice law, Cd 0.62
    connector.diameter = line.getQuantity("connector", D::Length, 4e-3);
    checkBetween(line, "connector", connector.diameter, 0.2e-3, 20e-3, "mm");
    readThermal(line, p.line);
    p.line.temperature = p.line.wallTemperature = sc.options.bag.gas.temperature;
    const ScenarioNode valves = s.getSection("valves", false);
    valves.checkKeys({}, {"inflate", "vent"});
    pneumatics::ValveSpec inflate = makeTypicalValve(), vent = makeTypicalValve();
    if (valves.has("inflate")) inflate = readValve(valves.getSection("inflate"), inflate);
    if (valves.has("vent")) vent = readValve(valves.getSection("vent"), vent);
    const ScenarioNode sensor = s.getSection("sensor", false);
    sensor.checkKeys({}, {"lag", "offset", "noise", "seed"});
    p.sensor.timeConstant = sensor.getQuantity("lag", D::Time, 0.05);
    checkBetween(sensor, "lag", p.sensor.timeConstant, 0.0, 60.0, "ms");
    p.sensor.offset = sensor.getQuantity("offset", D::Pressure, 0.0);
    checkBetween(sensor, "offset", p.sensor.offset, -10e3, 10e3, "kPa");
    p.sensor.noiseStdDev = sensor.getQuantity("noise", D::Pressure, 50.0);
    checkBetween(sensor, "noise", p.sensor.noiseStdDev, 0.0, 10e3, "kPa");
    const int seed = sensor.getInteger("seed", 1);
    if (seed < 0) sensor.fail("seed", std::to_string(seed) + "; valid: 0 or more");
    p.sensor.seed = static_cast<unsigned long long>(seed);
    p.network.maxSubstep = s.getQuantity("max_substep", D::Time, 1e-3);
    checkBetween(s, "max_substep", p.network.maxSubstep, 1e-6, 0.1, "ms");

    const std::vector<cosim::ArrayBag> arrayBags = cosim::makeArrayBags(a, sc.options.bag.geometry);
    auto groupBags = [&](int gi) {
        std::vector<int> out;
        for (const cosim::ArrayBag& b : arrayBags)
            if (b.group == gi) out.push_back(b.index);
        return out;
    };
    std::vector<std::string> groupNames;
    for (const cosim::BagGroup& g : a.groups) groupNames.push_back(g.name);
    if (!s.has("channels")) {
        // One channel per group of the array.
        if (a.groups.empty())
            s.fail("channels",
                   "missing: the array has no groups to give a channel each; list "
                   "the channels, e.g. - {group: left} or - {bags: [3]}");
        for (size_t g = 0; g < a.groups.size(); ++g) {
            cosim::PneumaticChannel c;
            c.name = a.groups[g].name;
            c.bags = groupBags(int(g));
            c.inflate = inflate;
            c.vent = vent;
            c.lineVolume = lineVolume;
            c.connector = connector;
            p.channels.push_back(c);
        }
    } else {
        const ScenarioNode cs = s.get("channels");
        if (!cs.isSequence())
            s.fail("channels", "must be a list of channels, e.g. - {group: left}");
        for (const ScenarioNode& e : cs.getElements()) {
            e.checkKeys({}, {"name", "group", "bags", "inflate", "vent", "line_volume"});
            cosim::PneumaticChannel c;
            if (e.has("group") == e.has("bags"))
                e.fail(
                    "name the channel's bags with either 'group' (one of array.groups) or "
                    "'bags' (bag indices), not both or neither");
            if (e.has("group")) {
                if (groupNames.empty())
                    e.fail("group", "the array has no groups; define them in array.groups");
                c.name = e.getChoice("group", groupNames);
                c.bags = groupBags(int(std::find(groupNames.begin(), groupNames.end(), c.name) -
                                       groupNames.begin()));
            } else {
                c.bags = readIndices(e, "bags", numBags, "bag");
                if (c.bags.empty())
                    e.fail("bags",
                           "is empty; valid: bag indices 0 to " + std::to_string(numBags - 1));
                c.name = "bags";
                for (int b : c.bags) c.name += " " + std::to_string(b);
            }
            c.name = e.getString("name", c.name);
            c.inflate = e.has("inflate") ? readValve(e.getSection("inflate"), inflate) : inflate;
            c.vent = e.has("vent") ? readValve(e.getSection("vent"), vent) : vent;
            // One bag: the valves on the bag unless a line is asked for.
            c.lineVolume =
                e.getQuantity("line_volume", D::Volume, c.bags.size() == 1 ? 0.0 : lineVolume);
            checkBetween(e, "line_volume", c.lineVolume, c.bags.size() == 1 ? 0.0 : 1e-7, 0.01,
                         "mL", "a channel of several bags needs a line");
            c.connector = connector;
            for (const cosim::PneumaticChannel& o : p.channels)
                if (o.name == c.name)
                    e.fail("name", "'" + c.name + "' is used twice; valid: a name of its own");
            for (int b : c.bags)
                for (const cosim::PneumaticChannel& o : p.channels)
                    if (std::find(o.bags.begin(), o.bags.end(), b) != o.bags.end())
                        e.fail("bag " + std::to_string(b) + " is already in channel '" + o.name +
                               "'; valid: a bag in one channel at most");
            p.channels.push_back(c);
        }
    }
    if (s.has("orifices")) {
        const ScenarioNode os = s.get("orifices");
        if (!os.isSequence())
            s.fail("orifices", "must be a list, e.g. - {bags: [3, 10], diameter: 4 mm}");
        for (const ScenarioNode& e : os.getElements()) {
            e.checkKeys({"bags"}, {"diameter", "discharge_coefficient"});
            const std::vector<int> pair = readIndices(e, "bags", numBags, "bag");
            if (pair.size() != 2 || pair[0] == pair[1])
                e.fail("bags", "must name two different bags, e.g. [3, 10]");
            cosim::BagOrifice o;
            o.a = pair[0];
            o.b = pair[1];
            o.orifice.diameter = e.getQuantity("diameter", D::Length, 4e-3);
            checkBetween(e, "diameter", o.orifice.diameter, 0.2e-3, 20e-3, "mm");
            o.orifice.dischargeCoefficient =
                e.getNumber("discharge_coefficient", o.orifice.dischargeCoefficient);
            if (!(o.orifice.dischargeCoefficient > 0.0 && o.orifice.dischargeCoefficient <= 1.0))
                e.fail("discharge_coefficient", "must lie in (0, 1], e.g. 0.62");
            p.orifices.push_back(o);
        }
    }
    try {
        p.validate(numBags);
    } catch (const std::invalid_argument& err) {
        s.fail(err.what());
    }
}

// ------------------------------------------------------------------------------------ control

std::vector<int> readChannelList(const ScenarioNode& s, const std::string& key,
                                 const cosim::ArrayPneumaticsSpec& p) {
    std::vector<int> out;
    if (!s.has(key)) return out;
    const ScenarioNode list = s.get(key);
    if (!list.isSequence()) s.fail(key, "must be a list of channel names, e.g. [right]");
    std::vector<std::string> names;
    for (const cosim::PneumaticChannel& c : p.channels) names.push_back(c.name);
    for (const ScenarioNode& e : list.getElements()) {
        const std::string n = e.asChoice(names);
        out.push_back(int(std::find(names.begin(), names.end(), n) - names.begin()));
    }
    return out;
}

int readOpenClosed(const ScenarioNode& e, const std::string& key) {
    if (!e.has(key)) return -1;
    return e.getChoice(key, {"open", "closed"}) == "open" ? 1 : 0;
}

void readControl(const ScenarioNode& root, PatientOnArrayScenario& sc) {
    if (!root.has("control")) return;
    if (!sc.hasPneumatics)
        root.fail("control",
                  "a controller commands the valves of the pneumatics section; add "
                  "one (docs/scenario-reference.md#pneumatics)");
    const ScenarioNode s = root.getSection("control");
    const cosim::ArrayPneumaticsSpec& p = sc.pneumatics;
    const int nc = int(p.channels.size());
    sc.controlKind = s.getChoice("kind", {"schedule", "target-mass", "target-pressure", "turn"});
    const double t0 = sc.settleTime;
    auto readAt = [&](const ScenarioNode& e) {
        const double at = e.getQuantity("at", D::Time, 0.0);
        checkBetween(e, "at", at, 0.0, sc.duration, "s",
                     "from the end of the settle, within run.duration");
        return at;
    };
    try {
        if (sc.controlKind == "schedule") {
            s.checkKeys({"kind", "commands"}, {"period"});
            const double period = s.getQuantity("period", D::Time, 0.0);
            checkBetween(s, "period", period, 0.0, 3600.0, "s", "0 s: not repeated");
            const ScenarioNode cs = s.get("commands");
            if (!cs.isSequence() || cs.getElements().empty())
                s.fail("commands",
                       "must be a list of valve states, e.g. - {at: 0 s, channel: "
                       "right, inflate: open, vent: closed}");
            std::vector<cosim::ValveCommand> cmds;
            for (const ScenarioNode& e : cs.getElements()) {
                e.checkKeys({"channel"}, {"at", "inflate", "vent"});
                cosim::ValveCommand c;
                if (period > 0.0) {  // times within the period, repeated over the run
                    c.time = e.getQuantity("at", D::Time, 0.0);
                    if (!(c.time >= 0.0 && c.time < period))
                        e.fail("at", fmtUnit(c.time, "s") + " is not within the period " +
                                         fmtUnit(period, "s") +
                                         "; valid: 0 s up to (not including) the period");
                } else {
                    c.time = readAt(e);
                }
                c.channel = findChannel(e, "channel", p);
                c.inflate = readOpenClosed(e, "inflate");
                c.vent = readOpenClosed(e, "vent");
                if (c.inflate < 0 && c.vent < 0) e.fail("give inflate and/or vent: open or closed");
                cmds.push_back(c);
                sc.controlText.push_back(
                    "from " + fmtUnit(c.time, "s") + ": '" + p.channels[c.channel].name + "'" +
                    (c.inflate >= 0 ? std::string(" inflate ") + (c.inflate ? "open" : "closed")
                                    : "") +
                    (c.vent >= 0 ? std::string(" vent ") + (c.vent ? "open" : "closed") : ""));
            }
            if (period > 0.0) sc.controlText.push_back("repeated every " + fmtUnit(period, "s"));
            sc.controller = std::make_shared<cosim::ValveSchedule>(cmds, t0, period, nc);
        } else if (sc.controlKind == "target-mass") {
            s.checkKeys({"kind", "targets"}, {"at", "k_of_m"});
            const double at = readAt(s);
            std::vector<double> km, kk;
            if (s.has("k_of_m")) {
                const ScenarioNode t = s.get("k_of_m");
                const char* example =
                    "must be a list of [gas mass, stiffness] rows, e.g. "
                    "[[3.0 g, 0.9 N/mm], [3.5 g, 1.6 N/mm], [4.5 g, 3.2 N/mm]]";
                if (!t.isSequence() || t.getElements().size() < 2) s.fail("k_of_m", example);
                for (const ScenarioNode& e : t.getElements()) {
                    if (!e.isSequence() || e.getElements().size() != 2) e.fail(example);
                    km.push_back(e.getElements()[0].asQuantity(D::Mass));
                    kk.push_back(e.getElements()[1].asQuantity(D::Stiffness));
                }
                try {
                    cosim::calcMassForStiffness(km, kk, kk.front());
                } catch (const std::invalid_argument& err) {
                    s.fail("k_of_m", err.what());
                }
            }
            const ScenarioNode ts = s.get("targets");
            if (!ts.isSequence())
                s.fail("targets", "must be a list, e.g. - {channel: right, mass: 5 g}");
            std::vector<cosim::TargetController::Target> targets;
            for (const ScenarioNode& e : ts.getElements()) {
                e.checkKeys({"channel"}, {"mass", "stiffness", "band"});
                cosim::TargetController::Target t;
                t.channel = findChannel(e, "channel", p);
                if (e.has("mass") == e.has("stiffness"))
                    e.fail("give either 'mass' (per bag) or 'stiffness' (through k_of_m)");
                if (e.has("mass")) {
                    t.value = e.getQuantity("mass", D::Mass);
                    checkPositive(e, "mass", t.value, "g");
                } else {
                    if (km.empty())
                        e.fail("stiffness", "needs the bag's k(m) table: control.k_of_m");
                    const double k = e.getQuantity("stiffness", D::Stiffness);
                    try {
                        t.value = cosim::calcMassForStiffness(km, kk, k);
                    } catch (const std::invalid_argument& err) {
                        e.fail("stiffness", err.what());
                    }
                }
                t.band = e.getQuantity("band", D::Mass, 0.02e-3);
                checkBetween(e, "band", t.band, 0.0, 1e-3, "g");
                targets.push_back(t);
                sc.controlText.push_back("'" + p.channels[t.channel].name + "' to " +
                                         fmtUnit(t.value, "g") + " a bag (band " +
                                         fmtUnit(t.band, "g") + ")");
            }
            sc.controller = std::make_shared<cosim::TargetController>(
                cosim::TargetController::Quantity::MassPerBag, targets, t0 + at);
        } else if (sc.controlKind == "target-pressure") {
            // Either a target per channel (targets:) or one for every channel (pressure:,
            // band:); a pressure may be from-body.
            s.checkKeys({"kind"}, {"at", "targets", "pressure", "band"});
            const double at = readAt(s);
            if (s.has("targets") == s.has("pressure"))
                s.fail(s.has("targets") ? "pressure" : "targets",
                       s.has("targets")
                           ? "and targets both set the channels' pressures; valid: one of them"
                           : "missing: targets (a list, e.g. - {channel: right, pressure: 4 kPa}) "
                             "or pressure (one for every channel: 4 kPa, or from-body)");
            if (s.has("band") && !s.has("pressure"))
                s.fail("band", "goes with control.pressure; give each target its own band");
            std::vector<cosim::TargetController::Target> targets;
            auto add = [&](const ScenarioNode& e, int channel) {
                cosim::TargetController::Target t;
                t.channel = channel;
                bool fromBody = false;
                t.value = readCellPressure(e, "pressure", sc.patient, &fromBody);
                checkBetween(e, "pressure", t.value, 0.0, 200e3, "kPa", "gauge");
                t.band = e.getQuantity("band", D::Pressure, 1e3);
                checkBetween(e, "band", t.band, 0.0, 50e3, "kPa");
                targets.push_back(t);
                sc.controlText.push_back(
                    "'" + p.channels[t.channel].name + "' to " + fmtUnit(t.value, "kPa") +
                    " gauge (band " + fmtUnit(t.band, "kPa") + ")" +
                    (fromBody ? " from his body (" + fmtUnit(sc.patient.mass, "kg") + ", " +
                                    fmtUnit(sc.patient.height, "m") + ")"
                              : std::string()));
            };
            if (s.has("pressure")) {
                for (int c = 0; c < nc; ++c) add(s, c);
            } else {
                const ScenarioNode ts = s.get("targets");
                if (!ts.isSequence())
                    s.fail("targets", "must be a list, e.g. - {channel: right, pressure: 30 kPa}");
                for (const ScenarioNode& e : ts.getElements()) {
                    e.checkKeys({"channel", "pressure"}, {"band"});
                    add(e, findChannel(e, "channel", p));
                }
            }
            sc.controller = std::make_shared<cosim::TargetController>(
                cosim::TargetController::Quantity::Pressure, targets, t0 + at);
        } else {
            s.checkKeys({"kind", "tilt"},
                        {"at", "inflate", "vent", "hold", "max_turn_time", "min_mass",
                         "max_pressure", "band", "pressure", "pressure_band"});
            cosim::TurnSpec t;
            t.start = t0 + readAt(s);
            t.inflate = readChannelList(s, "inflate", p);
            t.vent = readChannelList(s, "vent", p);
            t.tilt = s.getQuantity("tilt", D::Angle);
            checkBetween(s, "tilt", std::abs(t.tilt), 1e-3, 1.4, "deg",
                         "signed: positive onto his left side");
            t.hold = s.getQuantity("hold", D::Time, 0.0);
            checkBetween(s, "hold", t.hold, 0.0, 3600.0, "s");
            t.maxTurnTime = s.getQuantity("max_turn_time", D::Time, 120.0);
            checkBetween(s, "max_turn_time", t.maxTurnTime, 1e-3, 3600.0, "s");
            t.minMass = s.getQuantity("min_mass", D::Mass, 0.0);
            checkBetween(s, "min_mass", t.minMass, 0.0, 1.0, "g");
            t.maxPressure = s.getQuantity("max_pressure", D::Pressure, 0.0);
            checkBetween(s, "max_pressure", t.maxPressure, 0.0, 500e3, "kPa");
            t.band = s.getQuantity("band", D::Mass, 0.02e-3);
            checkBetween(s, "band", t.band, 1e-7, 1e-3, "g");
            // The zones held at a setpoint (a clinical mattress) or sealed (the default).
            bool fromBody = false;
            if (s.has("pressure")) {
                if (s.has("band"))
                    s.fail("band",
                           "is the mass band of a return to the start's masses; with "
                           "control.pressure the turn returns to the pressure within "
                           "pressure_band (valid: pressure_band, or no pressure)");
                t.holdPressure = readCellPressure(s, "pressure", sc.patient, &fromBody);
                checkBetween(s, "pressure", t.holdPressure, 200.0, 100e3, "kPa", "gauge");
                t.pressureBand = s.getQuantity("pressure_band", D::Pressure, 0.3e3);
                checkBetween(s, "pressure_band", t.pressureBand, 10.0, 50e3, "kPa");
            } else if (s.has("pressure_band")) {
                s.fail("pressure_band", "goes with control.pressure (the zones' setpoint)");
            }
            sc.targetTilt = t.tilt;
            sc.controller = std::make_shared<cosim::TurnController>(t, nc);
            std::string in, out;
            for (int c : t.inflate) in += (in.empty() ? "'" : ", '") + p.channels[c].name + "'";
            for (int c : t.vent) out += (out.empty() ? "'" : ", '") + p.channels[c].name + "'";
            sc.controlText.push_back("turn from " + fmtUnit(t.start - t0, "s") + ": inflate " +
                                     (in.empty() ? "none" : in) + ", vent " +
                                     (out.empty() ? "none" : out) + " to a pelvis tilt of " +
                                     fmtUnit(t.tilt, "deg") + ", hold " + fmtUnit(t.hold, "s") +
                                     (t.holdPressure > 0.0 ? ", then back to the zones' setpoint"
                                                           : ", then back to the initial masses"));
            if (t.holdPressure > 0.0)
                sc.controlText.push_back(
                    "every zone held at " + fmtUnit(t.holdPressure, "kPa") + " gauge (band " +
                    fmtUnit(t.pressureBand, "kPa") + ")" +
                    (fromBody ? " from his body (" + fmtUnit(sc.patient.mass, "kg") + ", " +
                                    fmtUnit(sc.patient.height, "m") + ")"
                              : std::string()) +
                    " from the release, the turned zones sealed while he is turned and held");
        }
    } catch (const std::invalid_argument& err) {
        s.fail(err.what());
    }
}

}  // namespace

PatientOnArrayScenario readPatientOnArrayScenario(const ScenarioFile& file) {
    const ScenarioNode root = file.getRoot();
    root.checkKeys({"kind", "patient", "array"}, {"name", "description", "bag", "gas", "coupling",
                                                  "run", "mat", "output", "pneumatics", "control"});
    root.getChoice("kind", {kPatientOnArrayKind});
    PatientOnArrayScenario sc;
    sc.name = root.getString("name", file.getStem());
    checkScenarioName(root, sc.name);
    sc.description = root.getString("description", "");
    sc.patient = readPatientSection(root.getSection("patient"));

    readBag(root.getSection("bag", false), sc, file.getFileName());
    readArray(root.getSection("array"), sc);
    readCoupling(root.getSection("coupling", false), sc.options);
    // (Reduced bags hand the body their friction's tangent: the tangent scheme holds only its
    // damping over a step; docs/reduced-bag.md#friction.)
    if (sc.options.contact.friction > 0.0 && sc.options.coupling.scheme == cosim::Scheme::Tangent &&
        sc.options.model == cosim::PatientOnArrayOptions::BagModel::FiniteElement)
        root.getSection("coupling", false)
            .fail("scheme", "tangent is not valid with bag.body_friction " +
                                fmtNumber(sc.options.contact.friction) +
                                ": its one pass would hold the friction force from the step's "
                                "start (docs/cosim.md#friction-and-the-tangent-schemes); valid: "
                                "implicit, tangent-implicit or explicit, or bag.body_friction 0");

    const ScenarioNode run = root.getSection("run", false);
    run.checkKeys({}, {"settle_time", "duration", "drop_height", "contact_damping"});
    sc.settleTime = run.getQuantity("settle_time", D::Time, sc.settleTime);
    checkBetween(run, "settle_time", sc.settleTime, 0.0, 600.0, "s");
    sc.duration = run.getQuantity("duration", D::Time, 0.0);
    checkBetween(run, "duration", sc.duration, 0.0, 3600.0, "s");
    if (!(sc.getEndTime() > 0.0))
        run.fail("settle_time", "the run has no time: give run.settle_time or run.duration > 0 s");
    sc.options.dropHeight = run.getQuantity("drop_height", D::Length, 0.0);
    checkBetween(run, "drop_height", sc.options.dropHeight, 0.0, 0.5, "mm");
    // [s/m]: io::Units has no unit for it, so a plain number in s/m.
    sc.options.integrator.contactDamping = run.getNumber("contact_damping", 0.0);
    if (!(sc.options.integrator.contactDamping >= 0.0 &&
          sc.options.integrator.contactDamping <= 100.0))
        run.fail("contact_damping", "must be a number of s/m from 0 (none) to 100, e.g. 2");

    try {
        sc.options.layout.validate(sc.options.bag.geometry);
    } catch (const std::invalid_argument& e) {
        failFromCosim(root, e.what());
    }
    readGas(root, sc);
    readPneumatics(root, sc);
    readControl(root, sc);

    const ScenarioNode mat = root.getSection("mat", false);
    mat.checkKeys({}, {"rows", "columns", "origin", "size"});
    sc.mat = cosim::makeArrayMatOptions(sc.options.layout, sc.options.bag.geometry,
                                        mat.getInteger("rows", 64), mat.getInteger("columns", 32));
    if (sc.mat.rows < 1 || sc.mat.rows > 1024)
        mat.fail("rows", std::to_string(sc.mat.rows) + " sensels; valid: 1 to 1024");
    if (sc.mat.columns < 1 || sc.mat.columns > 1024)
        mat.fail("columns", std::to_string(sc.mat.columns) + " sensels; valid: 1 to 1024");
    if (mat.has("origin")) sc.mat.origin = readXY(mat, "origin", "[-0.96 m, -0.40 m]");
    if (mat.has("size")) {
        sc.mat.size = readXY(mat, "size", "[1.92 m, 0.80 m]");
        if (!(sc.mat.size.minCoeff() > 0.0))
            mat.fail("size", "both extents must be greater than 0 m, e.g. [1.92 m, 0.80 m]");
    }

    const ScenarioNode out = root.getSection("output", false);
    out.checkKeys({}, {"every", "checkpoint_every"});
    sc.outputInterval = out.getQuantity("every", D::Time, sc.outputInterval);
    checkBetween(out, "every", sc.outputInterval, 1e-3, 60.0, "ms");
    {  // the mat's frames: frames x sensels x 8 bytes, refused before anything runs
        const double frames = std::floor(sc.getEndTime() / sc.outputInterval) + 2.0;
        const double bytes = frames * double(sc.mat.rows) * double(sc.mat.columns) * 8.0;
        if (bytes > kMaxMatFrameBytes) {
            const double every =
                sc.getEndTime() / (kMaxMatFrameBytes / (8.0 * sc.mat.rows * sc.mat.columns) - 2.0);
            const ScenarioNode& at = out.has("every") ? out : mat;
            at.fail(out.has("every") ? "every" : "rows",
                    fmtUnit(sc.outputInterval, "ms") + " over " + fmtUnit(sc.getEndTime(), "s") +
                        " with a mat of " + std::to_string(sc.mat.rows) + " x " +
                        std::to_string(sc.mat.columns) + " sensels writes about " +
                        fmtNumber(std::round(bytes / 1e9)) +
                        " GB of frames; at most 4 GiB are allowed; valid: output.every at least " +
                        fmtNumber(std::ceil(every * 1e3)) +
                        " ms, or fewer sensels "
                        "(docs/scenario-reference.md#limits)");
        }
    }
    sc.checkpointInterval = out.getQuantity("checkpoint_every", D::Time, sc.checkpointInterval);
    if (sc.checkpointInterval != 0.0)
        checkBetween(out, "checkpoint_every", sc.checkpointInterval, 1e-3, 3600.0, "s",
                     "or 0 s for no checkpoints");

    try {
        sc.options.validate();
    } catch (const std::invalid_argument& e) {
        failFromCosim(root, e.what());
    }
    // A patient (partly) off the array: named at patient.position.
    const std::vector<int> off = cosim::findSegmentsOffArray(sc.patient, sc.options);
    if (!off.empty()) {
        const cosim::PressureMatOptions extent =
            cosim::makeArrayMatOptions(sc.options.layout, sc.options.bag.geometry, 1, 1);
        std::ostringstream s;
        s << "no bag of the array lies under his ";
        for (size_t i = 0; i < off.size(); ++i)
            s << (i ? ", " : "") << body::getSegmentName(static_cast<body::Segment>(off[i]));
        s << " (mid-hip at [" << fmtUnit(sc.patient.position[0], "mm") << ", "
          << fmtUnit(sc.patient.position[1], "mm") << "]; the bags cover x from "
          << fmtUnit(extent.origin.x(), "mm") << " to "
          << fmtUnit(extent.origin.x() + extent.size.x(), "mm") << " and y from "
          << fmtUnit(extent.origin.y(), "mm") << " to "
          << fmtUnit(extent.origin.y() + extent.size.y(), "mm")
          << "); valid: a position that puts him on the array, or more rows or columns";
        const ScenarioNode p = root.getSection("patient");
        if (p.has("position")) p.fail("position", s.str());
        p.fail(s.str());
    }
    return sc;
}

}  // namespace io
