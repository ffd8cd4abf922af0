// Reading the patient section and the patient-on-support scenario kind.
#include <io/PatientScenario.h>

#include <stdexcept>

namespace io {

namespace {

using D = Dimension;

std::vector<std::string> getPostureChoices() {
    std::vector<std::string> names;
    std::string all = body::getPostureNames();
    size_t start = 0;
    while (start < all.size()) {
        size_t end = all.find(", ", start);
        if (end == std::string::npos) end = all.size();
        names.push_back(all.substr(start, end - start));
        start = end + 2;
    }
    return names;
}

// body's messages start with "patient.<key>: "; the error goes to that key's line, with the
// rest of the message (which says the value and what is valid).
[[noreturn]] void failFromSpec(const ScenarioNode& s, const std::string& message) {
    const std::string prefix = "patient.";
    if (message.rfind(prefix, 0) == 0) {
        const size_t colon = message.find(':');
        if (colon != std::string::npos) {
            const std::string key = message.substr(prefix.size(), colon - prefix.size());
            std::string rest = message.substr(colon + 1);
            if (!rest.empty() && rest[0] == ' ') rest.erase(0, 1);
            s.fail(key, rest);
        }
    }
    s.fail("invalid patient: " + message);
}

// The SettleOptions / PlaneSupportOptions member named first in a message -> scenario key.
[[noreturn]] void failFromSettle(const ScenarioNode& root, const std::string& message) {
    struct Alias {
        const char* token;
        const char* section;  // "" for the top level
        const char* key;
    };
    static const Alias aliases[] = {
        {"stiffness", "support", "stiffness"},
        {"damping", "support", "damping"},
        {"friction", "support", "friction"},
        {"slipVelocity", "support", "slip_velocity"},
        {"stickDistance", "support", "stick_distance"},
        {"sampleSpacing", "support", "sample_spacing"},
        {"height", "support", "height"},
        {"settleTime", "", "settle_time"},
    };
    const Alias* best = nullptr;
    size_t bestPos = std::string::npos;
    for (const Alias& a : aliases) {
        const size_t pos = message.find(a.token);
        if (pos != std::string::npos && pos < bestPos) {
            best = &a;
            bestPos = pos;
        }
    }
    const std::string text = "invalid: " + message;
    if (best) {
        if (std::string(best->section).empty()) root.fail(best->key, text);
        if (root.has(best->section)) root.getSection(best->section).fail(best->key, text);
    }
    root.fail(text);
}

}  // namespace

void checkScenarioName(const ScenarioNode& root, const std::string& name) {
    if (name.empty() ||
        name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                               "._-") != std::string::npos)
        root.fail("name", "\"" + name +
                              "\" names the output folder: use letters, digits, "
                              "'.', '_' and '-' only");
    // out/. and out/.. are not a folder of the run's own (out/.. is where bagsim was started).
    if (name.find_first_not_of('.') == std::string::npos)
        root.fail("name", "\"" + name + "\" names the output folder out/" + name +
                              ", which is not a folder of its own; valid: a name with a letter "
                              "or digit, e.g. supine-75kg");
}

body::PatientSpec readPatientSection(const ScenarioNode& s) {
    if (!s.isMap())
        s.fail(
            "must be a section {sex, height, mass, posture, position}, e.g. "
            "patient: {sex: female, height: 1.62 m, mass: 58 kg}");
    s.checkKeys({"sex", "height", "mass"}, {"posture", "position", "head_of_bed_angle"});
    body::PatientSpec p;

    const std::string sex = s.getString("sex");
    try {
        p.sex = body::parseSex(sex);
    } catch (const std::invalid_argument&) {
        s.getChoice("sex", {"female", "male"});  // throws, listing both and the closest
        s.fail("sex", "\"" + sex + "\" is not valid; use female or male");
    }
    p.height = s.getQuantity("height", D::Length);
    p.mass = s.getQuantity("mass", D::Mass);

    if (s.has("posture")) {
        const std::string name = s.getString("posture");
        try {
            p.posture = body::parsePosture(name);
        } catch (const std::invalid_argument&) {
            s.getChoice("posture", getPostureChoices());  // throws with the list and suggestion
            s.fail("posture",
                   "\"" + name + "\" is not a posture; valid: " + body::getPostureNames());
        }
    }

    if (s.has("position")) {
        const ScenarioNode pos = s.get("position");
        if (!pos.isSequence() || pos.getElements().size() != 2)
            s.fail("position",
                   "must be two lengths [x, y] of the mid-hip point on the bed, "
                   "e.g. [0 m, 0 m] (head towards +x)");
        const std::vector<ScenarioNode> xy = pos.getElements();
        p.position = {xy[0].asQuantity(D::Length), xy[1].asQuantity(D::Length)};
    }

    if (s.has("head_of_bed_angle")) {
        if (p.posture != body::Posture::HeadOfBedRaised)
            s.fail("head_of_bed_angle",
                   "applies only to posture head-of-bed-raised (posture here: " +
                       std::string(body::getPostureName(p.posture)) +
                       "); remove it or set posture: head-of-bed-raised");
        p.headOfBedAngle = s.getQuantity("head_of_bed_angle", D::Angle);
    }

    try {
        p.validate();
    } catch (const std::invalid_argument& e) {
        failFromSpec(s, e.what());
    }
    return p;
}

body::PatientSpec readScenarioPatient(const ScenarioFile& file) {
    const ScenarioNode root = file.getRoot();
    if (!root.has("patient"))
        root.fail(
            "the scenario has no 'patient' section; add one, e.g. patient: {sex: female, "
            "height: 1.62 m, mass: 58 kg, posture: supine, position: [0 m, 0 m]}");
    return readPatientSection(root.getSection("patient"));
}

void readSupportFriction(const ScenarioNode& s, const std::string& prefix,
                         const std::string& defaultLaw, body::PlaneSupportOptions& o) {
    const std::string lawKey = prefix + "friction_law", slipKey = prefix + "slip_velocity",
                      stickKey = prefix + "stick_distance";
    const std::string law = s.getChoice(lawKey, {"stick-slip", "regularised"}, defaultLaw);
    o.frictionLaw = law == "regularised" ? body::SupportFrictionLaw::Regularised
                                         : body::SupportFrictionLaw::StickSlip;
    if (s.has(slipKey) && law != "regularised")
        s.fail(slipKey, "is the regularised law's; valid only with " + lawKey +
                            ": regularised (this file's law: " + law + ")");
    if (s.has(stickKey) && law != "stick-slip")
        s.fail(stickKey, "is the stick-slip law's; valid only with " + lawKey +
                             ": stick-slip (this file's law: " + law + ")");
    o.slipVelocity = s.getQuantity(slipKey, D::Velocity, o.slipVelocity);
    o.stickDistance = s.getQuantity(stickKey, D::Length, o.stickDistance);
}

PatientOnSupportScenario readPatientOnSupportScenario(const ScenarioFile& file) {
    const ScenarioNode root = file.getRoot();
    root.checkKeys({"kind", "patient"}, {"name", "description", "support", "settle_time"});
    root.getChoice("kind", {kPatientOnSupportKind});

    PatientOnSupportScenario sc;
    sc.name = root.getString("name", file.getStem());
    checkScenarioName(root, sc.name);
    sc.description = root.getString("description", "");
    sc.patient = readPatientSection(root.getSection("patient"));

    body::SettleOptions& o = sc.settle;
    const ScenarioNode sup = root.getSection("support", false);
    if (!sup.isNull()) {
        sup.checkKeys({}, {"height", "stiffness", "damping", "friction", "friction_law",
                           "slip_velocity", "stick_distance", "sample_spacing"});
        body::PlaneSupportOptions& so = o.support;
        so.height = sup.getQuantity("height", D::Length, so.height);
        so.stiffness = sup.getQuantity("stiffness", D::StiffnessPerArea, so.stiffness);
        // Pa s/m has no unit of its own in io::Units: a plain number in Pa s/m.
        so.damping = sup.getNumber("damping", so.damping);
        so.friction = sup.getNumber("friction", so.friction);
        // The friction law (body/SupportContact.h): regularised (the default here) or
        // stick-slip (as the bed board under the bags).
        readSupportFriction(sup, "", "regularised", so);
        so.sampleSpacing = sup.getQuantity("sample_spacing", D::Length, so.sampleSpacing);
    }
    o.settleTime = root.getQuantity("settle_time", D::Time, o.settleTime);
    try {
        o.validate();
    } catch (const std::invalid_argument& e) {
        failFromSettle(root, e.what());
    }
    return sc;
}

}  // namespace io
