// bagsim run, kind patient-on-array: the patient lowered onto an array of airbags, settling,
// then the gas of bags or groups changed over time (the coupling: cosim::PatientOnArray).
#include "ArrayRun.h"
#include "Format.h"

#include <bags/Units.h>
#include <bagsim/Version.h>
#include <cosim/ArrayPneumatics.h>
#include <cosim/ArrayReadings.h>
#include <cosim/ArrayShapes.h>
#include <io/ArrayResults.h>
#include <io/ArrayScenario.h>
#include <io/InputError.h>
#include <io/Units.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include "ArrayVerdict.h"
#include "Interrupt.h"
#include "ProgressEstimate.h"
#include "Report.h"

namespace bagsim::app {

namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;
constexpr double kPressedThreshold = 5.0 * bags::kPascalsPerMmHg;  // [Pa] 5 mmHg, as regions.csv

double calcBagVolume(const cosim::Bag& a) {
    double v = 0.0;
    for (int c = 0; c < a.getNumChambers(); ++c) v += a.getChamberState(c).volume;
    return v;
}

// The body's soft tissue in a few words: per site, one layer, or bare shapes.
std::string describeBodyTissue(const cosim::PatientOnArrayOptions& o) {
    if (!o.segmentTissue.empty()) {
        std::string s = "soft tissue per site (bag.body_tissue):";
        for (int i = 0; i < body::kTissueSiteCount; ++i) {
            const auto site = body::TissueSite(i);
            body::SoftTissue t;
            for (int g = 0; g < body::kSegmentCount; ++g)
                if (body::getTissueSite(body::Segment(g)) == site) t = o.segmentTissue[size_t(g)];
            s += std::string(i ? "," : "") + " " + body::getTissueSiteName(site) + " " +
                 (t.isRigid()
                      ? std::string("none")
                      : fmt("%.0f mm", 1e3 * t.thickness) + fmt(" %.0f kPa", 1e-3 * t.modulus));
        }
        return s;
    }
    if (o.contact.hasTissue())
        return "soft tissue " + fmt("%.0f mm", 1e3 * o.contact.tissueThickness) +
               fmt(" %.0f kPa", 1e-3 * o.contact.tissueModulus) + " on every segment";
    return "bare shapes (no soft tissue)";
}

struct Totals {
    int steps = 0, passes = 0, cuts = 0;
    long bodySteps = 0;  // the body integrator's internal steps in the committed passes
    // Macro steps kept with no fixed point (CouplingOptions::keepUnconverged): how many, and
    // the largest |H(x) - x| kept, its tolerance and when.
    long unconverged = 0;
    double worstResidual = 0.0, worstTolerance = 0.0, worstTime = 0.0;
    // Macro steps accepted where their passes stalled within coupling.accept_residual: how
    // many, the largest |H(x) - x| accepted and when.
    long accepted = 0;
    double worstAccepted = 0.0, worstAcceptedTime = 0.0;
};
// Totals as a checkpoint of the parts 'run-2' and 'run-3' holds them.
struct TotalsBefore4 {
    int steps = 0, passes = 0, cuts = 0;
    long bodySteps = 0;
};
// Totals as a checkpoint of the part 'run-4' holds them.
struct TotalsBefore5 {
    int steps = 0, passes = 0, cuts = 0;
    long bodySteps = 0;
    long unconverged = 0;
    double worstResidual = 0.0, worstTolerance = 0.0, worstTime = 0.0;
};

// Writes `data` to dir/checkpoint.bin through a temporary file, flushed to the disk and
// renamed over it: a kill while it is written leaves the previous checkpoint whole.
void writeFileAtomically(const std::filesystem::path& path, const std::string& data) {
    const std::filesystem::path tmp = path.string() + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) throw std::runtime_error("cannot write " + tmp.string());
    size_t done = 0;
    while (done < data.size()) {
        const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            ::close(fd);
            throw std::runtime_error("cannot write " + tmp.string());
        }
        done += size_t(n);
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0)
        throw std::runtime_error("cannot write " + tmp.string());
    std::filesystem::rename(tmp, path);
}

}  // namespace

namespace {

// A YAML value as one line of text (flow style), for comparison and messages.
std::string emitFlow(const YAML::Node& n) {
    YAML::Emitter e;
    e.SetMapFormat(YAML::Flow);
    e.SetSeqFormat(YAML::Flow);
    e << n;
    return e.c_str();
}

// The first difference between two scenario trees below `path`, skipping the keys in `free`
// (dotted paths); "" if none.
std::string findFirstDifference(const YAML::Node& a, const YAML::Node& b, const std::string& path,
                                const std::vector<std::string>& free) {
    auto shown = [](const YAML::Node& n) {
        return n && !n.IsNull() ? "'" + emitFlow(n) + "'" : std::string("absent");
    };
    if (a && b && a.IsMap() && b.IsMap()) {
        std::vector<std::string> keys;
        for (const YAML::Node* n : {&a, &b})
            for (auto it = n->begin(); it != n->end(); ++it) {
                const std::string k = it->first.as<std::string>();
                if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
            }
        for (const std::string& k : keys) {
            const std::string p = path.empty() ? k : path + "." + k;
            if (std::find(free.begin(), free.end(), p) != free.end()) continue;
            const std::string d = findFirstDifference(a[k], b[k], p, free);
            if (!d.empty()) return d;
        }
        return "";
    }
    const bool aHas = a && !a.IsNull(), bHas = b && !b.IsNull();
    if (aHas != bHas || (aHas && emitFlow(a) != emitFlow(b)))
        return path + ": " + shown(a) + " here, " + shown(b) + " in the rest state's scenario";
    return "";
}

}  // namespace

std::string describeRestDifference(const io::ScenarioFile& run, const io::ScenarioFile& rest) {
    // What acts only after the settle (the gas schedule, the controller and its network: the
    // network of a run from rest starts from the bags' gas as it finds it) or only on the
    // outputs.
    static const std::vector<std::string> kFree = {"description",  "gas", "control", "pneumatics",
                                                   "run.duration", "mat", "output"};
    return findFirstDifference(run.getRoot().getYaml(), rest.getRoot().getYaml(), "", kFree);
}

CheckpointHeader readCheckpointHeader(bags::StateReader& r) {
    CheckpointHeader h;
    r.tag("header");
    h.version = r.str();
    h.scenarioFile = r.str();
    h.scenarioText = r.str();
    h.overrides.resize(r.pod<std::uint64_t>());
    for (std::string& o : h.overrides) o = r.str();
    r.pod(h.time);
    if (r.readTagIf("model")) h.model = r.str();
    return h;
}

// The model a scenario makes, as the run's header prints it: patient, array, films, contact,
// coupling, gas, pneumatics, reduced bags (one line each, indented).
std::string describeModel(const io::PatientOnArrayScenario& sc) {
    const cosim::ArrayLayout& layout = sc.options.layout;
    const body::PatientSpec& p = sc.patient;
    const cosim::CouplingOptions& c = sc.options.coupling;
    const bool reduced = sc.options.model == cosim::PatientOnArrayOptions::BagModel::Reduced;
    const bags::AirbagSpec::Stepping stepping = sc.options.bag.stepping;
    std::ostringstream out;
    out << "  patient " << body::getSexName(p.sex) << ", " << fmt("%.2f m", p.height) << ", "
        << fmt("%.1f kg", p.mass) << ", " << body::getPostureName(p.posture) << "\n";
    out << "  array " << layout.rows << " x " << layout.columns << " seed wedges (" << sc.bagReading
        << ", mesh " << io::formatSignificant(sc.options.bag.geometry.meshSize, "mm")
        << ", self-contact " << (sc.options.bag.selfContact ? "on" : "off");
    if (!reduced)
        out << ", films "
            << (stepping == bags::AirbagSpec::Stepping::Relaxed   ? "relaxed"
                : stepping == bags::AirbagSpec::Stepping::Dynamic ? "dynamic"
                                                                  : "quasi-static");
    out << "), " << io::formatQuantity(layout.gasMass, "g", 2) << " each";
    if (sc.fillFromBody > 0.0)
        out << " (filled to " << io::formatQuantity(sc.fillFromBody, "kPa", 2)
            << " at rest, set from his body)";
    for (const cosim::BagGroup& g : layout.groups)
        out << ", group '" << g.name << "' " << io::formatQuantity(g.gasMass, "g", 2);
    out << (sc.options.boardContact ? "; the bed board carries him where he reaches it"
                                    : "; no bed board under him (array.board_contact)");
    out << "; body on the films: "
        << (sc.options.contact.friction > 0.0 ? "friction " + fmt("%g", sc.options.contact.friction)
                                              : std::string("frictionless"))
        << ", " << describeBodyTissue(sc.options) << "\n";
    out << "  " << cosim::toString(c.scheme) << " coupling (" << cosim::toString(c.acceleration)
        << "), macro step "
        << (c.adaptive ? "adaptive " + io::formatSignificant(c.minMacroStep, "ms") + " to " +
                             io::formatSignificant(c.maxMacroStep, "ms") +
                             fmt(", accuracy %g x the tolerance", c.stepAccuracy)
                       : io::formatSignificant(c.macroStep, "ms"))
        << fmt(", tolerance %g |H|", c.relativeTolerance) << " + "
        << io::formatSignificant(c.absoluteTolerance, "mN")
        << fmt(", %g passes", double(c.maxIterations))
        << (c.keepUnconverged ? ", keeps" : ", stops at") << " a step with no fixed point"
        << (c.acceptResidual > 0.0
                ? ", accepts stalled passes within " + io::formatSignificant(c.acceptResidual, "mN")
                : std::string())
        << "; settle " << fmt("%g s", sc.settleTime) << ", then " << fmt("%g s", sc.duration)
        << "\n";
    for (const io::GasCommandText& g : sc.gasText)
        out << "  gas from " << fmt("%g s", g.at) << " after the settle: " << g.who << " " << g.what
            << "\n";
    if (sc.hasPneumatics) {
        out << "  pneumatics: " << sc.pneumatics.channels.size() << " channels";
        for (const cosim::PneumaticChannel& ch : sc.pneumatics.channels)
            out << " '" << ch.name << "' (" << ch.bags.size() << ")";
        out << "; control " << (sc.controlKind.empty() ? "none" : sc.controlKind) << "\n";
        for (const std::string& t : sc.controlText) out << "    " << t << "\n";
    }
    if (reduced)
        out << "  bags: the reduced model (docs/reduced-bag.md), calibrated by "
            << sc.options.reduced->source.substr(0, sc.options.reduced->source.find('\n')) << "\n";
    return out.str();
}

// Why a checkpoint (or rest state: `what`) whose writer made the model `written` cannot be
// taken up by this build, which makes `now`: the first line in which they differ.
std::string describeModelDifference(const std::string& written, const std::string& now,
                                    const std::string& what = "checkpoint") {
    auto lines = [](const std::string& t) {
        std::vector<std::string> v;
        std::istringstream in(t);
        for (std::string l; std::getline(in, l);)
            v.push_back(l.substr(std::min(l.find_first_not_of(' '), l.size())));
        return v;
    };
    const std::vector<std::string> a = lines(written), b = lines(now);
    size_t k = 0;
    while (k < a.size() && k < b.size() && a[k] == b[k]) ++k;
    return "the " + what +
           " was written by a build that made another model of this scenario (it "
           "had \"" +
           (k < a.size() ? a[k] : std::string("nothing more")) + "\", this build makes \"" +
           (k < b.size() ? b[k] : std::string("nothing more")) + "\"); " +
           (what == "checkpoint" ? "resume it" : "start from it") +
           " with the build that wrote it, or run the scenario again";
}

int runPatientOnArray(const io::ScenarioFile& file, const std::string& out,
                      const ArrayRunControl& control) {
    const bool quiet = control.quiet;
    const std::string& commandLine = control.commandLine;
    bags::StateReader* const resume = control.resume;
    bags::StateReader* const fromRest = control.fromRest;
    io::PatientOnArrayScenario sc;
    std::filesystem::path outPath;
    std::unique_ptr<io::OutputDir> outDir;
    try {
        sc = io::readPatientOnArrayScenario(file);
        outPath = out.empty() ? std::filesystem::path("out") / sc.name : std::filesystem::path(out);
        // A rest state's patient and array (the settle's model; gas, control and pneumatics
        // may differ) must be what this build makes of them: the model's first two lines.
        // Refused before the folder is made.
        if (fromRest && !control.fromRestModel.empty()) {
            auto settled = [](const std::string& m) {
                const size_t first = m.find('\n');
                return m.substr(0, first == std::string::npos ? first : m.find('\n', first + 1));
            };
            const std::string was = settled(control.fromRestModel),
                              now = settled(describeModel(sc));
            if (was != now) {
                std::cerr << "bagsim: error: cannot start from the rest state in "
                          << control.fromRestDir << ": "
                          << describeModelDifference(was, now, "rest state") << "\n";
                return 2;
            }
        }
        outDir = resume ? std::make_unique<io::OutputDir>(io::OutputDir::resume(outPath))
                        : std::make_unique<io::OutputDir>(outPath, control.force);
    } catch (const io::InputError& e) {
        std::cerr << "bagsim: error: " << e.what() << "\n";
        return 2;
    }
    const auto start = std::chrono::steady_clock::now();
    auto wall = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    // Ctrl-C is noticed within one Newton iteration of a bag (inflating the bags takes many).
    sc.options.bag.solver.monitor = [](int, double, double, double) { throwIfInterrupted(); };
    const cosim::ArrayLayout& layout = sc.options.layout;
    // What this build makes of the scenario (printed, and kept in checkpoints: a resume by a
    // build that makes another model of it is refused).
    const std::string model = describeModel(sc);
    if (!quiet) {
        std::cerr << "bagsim " << bagsim::kVersion << ": " << file.getFileName() << " (" << sc.name
                  << ")\n"
                  << model;
        std::cerr << "  writing to " << outPath.string()
                  << "/ (Ctrl-C stops and keeps what was computed, marked INCOMPLETE";
        if (sc.checkpointInterval > 0.0)
            std::cerr << "; a checkpoint every " << fmt("%g s", sc.checkpointInterval)
                      << " for bagsim run --resume";
        std::cerr << ")\n";
    }

    // A build whose defaults changed makes another model of the same scenario text: the
    // checkpoint's state would be loaded into the wrong model. Refused before anything in the
    // folder is touched (checkpoints written before the model was kept cannot say).
    if (resume && !control.resumeModel.empty() && control.resumeModel != model) {
        std::cerr << "bagsim: error: cannot resume from " << outPath.string() << ": "
                  << describeModelDifference(control.resumeModel, model)
                  << " (the folder is left as it was)\n";
        return 2;
    }
    io::RunInfo info{file.getFileName(), file.getText(), file.getOverrides(), commandLine};
    std::unique_ptr<io::ArrayResultsWriter> writer;
    try {
        writer = resume ? std::make_unique<io::ArrayResultsWriter>(*outDir, sc.mat, *resume)
                        : std::make_unique<io::ArrayResultsWriter>(*outDir, info, sc.mat);
    } catch (const std::exception& e) {
        if (resume) {
            // Refused before any file was touched (the writer checks every file before it
            // cuts one): the folder, its marker included, stays as the stopped run left it.
            std::cerr << "bagsim: error: cannot resume from " << outPath.string() << ": "
                      << e.what() << " (the folder is left as it was)\n";
            return 2;
        }
        std::cerr << "bagsim: error: cannot write the results: " << e.what() << "\n";
        outDir->setStatus("failed", e.what());
        return 1;
    }
    // The stopped run's marker, put back if the resume is refused past this point (the
    // writer has then cut the files back to the checkpoint, which a later resume redoes).
    const std::string stoppedMarker = resume ? outDir->readMarker() : std::string();
    if (resume) outDir->markResumed();
    auto refuseResume = [&](const std::string& why) {
        std::cerr << "bagsim: error: cannot resume from " << outPath.string() << ": " << why
                  << " (the files are cut back to the checkpoint; the marker keeps the "
                     "stopped run's status)\n";
        writer->fail("interrupted", "resume refused: " + why);
        try {
            outDir->writeMarker(stoppedMarker + "bagsim run --resume was refused: " + why + "\n");
        } catch (const std::exception&) {
        }
        return 2;
    };

    std::unique_ptr<cosim::PatientOnArray> poa;
    cosim::PressureMat mat(sc.mat);
    Totals totals;
    cosim::EnvelopeCounts envelope;
    const double end = sc.getEndTime();
    double nextOutput = 0.0;
    bool settled = !(sc.settleTime > 0.0 && sc.duration > 0.0);
    const bool checkpoints = sc.checkpointInterval > 0.0;
    double nextCheckpoint = checkpoints ? sc.checkpointInterval : 0.0;
    ArrayVerdict verdict(layout, sc.options.bag.geometry, sc.settleTime, sc.duration,
                         sc.targetTilt);
    // The pneumatics: the network's bags (participants), their volumes at the last committed
    // step and its rate; the largest relative difference of bag and network gas masses.
    std::unique_ptr<cosim::ArrayPneumatics> air;
    std::vector<int> airParticipant;
    std::vector<double> airVolume, airRate;
    double massMismatch = 0.0;
    std::vector<cosim::ControlEvent> events;
    size_t eventsWritten = 0;
    auto writeEvents = [&] {
        for (; eventsWritten < events.size(); ++eventsWritten)
            writer->addEvent(events[eventsWritten].time, events[eventsWritten].text);
    };
    cosim::BodySurface bodySurface;  // bags and body for ParaView (results.xdmf)
    Eigen::Matrix3Xd bagNodes, bodyNodes;
    // The finite-element bags, with their index in the array (the reduced ones are left out).
    auto feBags = [&] {
        std::vector<std::pair<cosim::BagParticipant*, int>> fe;
        for (size_t b = 0; b < poa->getBagIndices().size(); ++b)
            if (auto* p = dynamic_cast<cosim::BagParticipant*>(&poa->updBag(int(b))))
                fe.emplace_back(p, poa->getBagIndices()[b]);
        return fe;
    };
    auto record = [&] {
        io::ArrayFrame f;
        f.time = poa->getTime();
        f.regions = cosim::calcRegionLoads(*poa);
        f.bags = cosim::calcBagReadings(*poa);
        const std::vector<double> pressedHeights =
            cosim::calcPressedNodeHeights(*poa, kPressedThreshold);
        for (size_t i = 0; i < f.bags.size(); ++i) f.bags[i].innerHeight = pressedHeights[i];
        f.pelvisTilt = cosim::calcSegmentTilt(*poa, body::Segment::LowerTrunk);
        f.thoraxTilt = cosim::calcSegmentTilt(*poa, body::Segment::UpperTrunk);
        f.centreOfMass = cosim::calcCentreOfMass(*poa);
        if (air)
            for (int b : air->getBags()) {
                const cosim::BagFlow q = air->getBagFlow(b);
                f.pneumatics.push_back({b, air->readBagSensor(b), q.in, q.out});
            }
        cosim::fillPressureMat(*poa, mat);
        f.mat = &mat;
        if (writer->wantsShapes(f.time)) {
            bagNodes = cosim::calcBagSurfacePositions(*poa);
            bodyNodes = cosim::calcBodySurfacePositions(poa->getModel(), poa->getBody().getState(),
                                                        bodySurface);
            f.bagNodes = &bagNodes;
            f.bodyNodes = &bodyNodes;
        }
        writer->addFrame(f);
        verdict.addFrame(f, pressedHeights);
        for (const auto& [fe, bag] : feBags()) {
            double stretch = 1.0;
            const double use = fe->getAirbag().calcFittedRangeUse(&stretch);
            verdict.addFilmRange(use, stretch, bag, f.time);
        }
        return f;
    };
    auto where = [&] {
        return poa ? fmt("at %.4f s", poa->getTime()) + fmt(" of %g s", end)
                   : std::string("while building the model (inflating the bags)");
    };
    auto setTurn = [&] {
        if (const auto* turn = dynamic_cast<const cosim::TurnController*>(sc.controller.get()))
            verdict.setTurn(
                turn->getTiltReachedTime(),
                turn->getTurnedMasses().empty() ? std::numeric_limits<double>::quiet_NaN()
                                                : turn->getTurnedTilt(),
                turn->getPhase() == cosim::TurnController::Phase::Done, turn->getHoldPressure());
    };
    // The relaxed bags' steps kept unrelaxed, summed over the bags, the largest residual and
    // its bag; into the verdict.
    struct UnrelaxedTally {
        long steps = 0;
        double largest = 0.0;
        int bag = -1;
    };
    auto tallyUnrelaxed = [&] {
        UnrelaxedTally t;
        for (const auto& [fe, bag] : feBags()) {
            t.steps += fe->getNumUnrelaxedSteps();
            if (fe->getNumUnrelaxedSteps() > 0 && fe->getLargestUnrelaxedResidual() >= t.largest) {
                t.largest = fe->getLargestUnrelaxedResidual();
                t.bag = bag;
            }
        }
        verdict.setFilmSteps(
            sc.options.reduced ? bags::AirbagSpec::Stepping::QuasiStatic : sc.options.bag.stepping,
            t.steps, t.largest, t.bag, sc.options.bag.forceTolerance);
        const cosim::Scheme scheme = sc.options.coupling.scheme;
        verdict.setCouplingSteps(
            scheme == cosim::Scheme::Implicit || scheme == cosim::Scheme::TangentImplicit,
            totals.unconverged, totals.worstResidual, totals.worstTolerance, totals.worstTime);
        verdict.setAcceptedSteps(totals.accepted, totals.worstAccepted, totals.worstAcceptedTime,
                                 sc.options.coupling.acceptResidual);
        return t;
    };
    // The checkpoint (docs/output-layout.md#checkpoint): header, the writers' positions, the
    // loop's own state, the verdict so far, then the model: body, bags, coupling, pneumatics,
    // controller. A resumed run reads it in that order.
    auto saveRunState = [&](bags::StateWriter& w) {
        w.tag("run-5");
        w.pod(nextOutput), w.pod(settled), w.pod(nextCheckpoint);
        w.pod(std::uint64_t(events.size()));
        for (const cosim::ControlEvent& e : events) w.pod(e.time), w.str(e.text);
        w.pod(std::uint64_t(eventsWritten));
        w.pod(totals), w.pod(massMismatch), w.pod(envelope);
        w.vec(airVolume), w.vec(airRate);
        verdict.saveState(w);
        // The relaxed bags' tally of steps kept unrelaxed, bag by bag (not in the bags' state).
        std::vector<double> tally;
        for (const auto& [fe, bag] : feBags())
            tally.push_back(double(fe->getNumUnrelaxedSteps())),
                tally.push_back(fe->getLargestUnrelaxedResidual());
        w.vec(tally);
    };
    std::vector<double> resumedTally;                      // until the bags are built
    std::vector<double> resumedAirVolume, resumedAirRate;  // until the network is built
    bool resumedTallyKnown = true;  // a checkpoint written before the tally (run-2) has none
    auto loadRunState = [&](bags::StateReader& r) {
        const std::string part = r.str();
        if (part != "run-5" && part != "run-4" && part != "run-3" && part != "run-2")
            throw bags::StateError("checkpoint: expected the part 'run-5', found '" +
                                   part.substr(0, 60) + "' (the checkpoint is of another model)");
        resumedTallyKnown = part != "run-2";
        r.pod(nextOutput), r.pod(settled), r.pod(nextCheckpoint);
        events.resize(r.pod<std::uint64_t>());
        for (cosim::ControlEvent& e : events) r.pod(e.time), e.text = r.str();
        eventsWritten = size_t(r.pod<std::uint64_t>());
        if (part == "run-5") {
            r.pod(totals);
        } else if (part == "run-4") {  // before the tally of accepted steps
            TotalsBefore5 t;
            r.pod(t);
            totals = Totals();
            totals.steps = t.steps, totals.passes = t.passes, totals.cuts = t.cuts;
            totals.bodySteps = t.bodySteps;
            totals.unconverged = t.unconverged, totals.worstResidual = t.worstResidual;
            totals.worstTolerance = t.worstTolerance, totals.worstTime = t.worstTime;
        } else {  // before the tally of unconverged steps
            TotalsBefore4 t;
            r.pod(t);
            totals = Totals();
            totals.steps = t.steps, totals.passes = t.passes, totals.cuts = t.cuts;
            totals.bodySteps = t.bodySteps;
        }
        r.pod(massMismatch), r.pod(envelope);
        r.vec(resumedAirVolume), r.vec(resumedAirRate);
        verdict.loadState(r);
        if (resumedTallyKnown) r.vec(resumedTally);
    };
    // A checkpoint's or rest state's header (readCheckpointHeader() reads it), and the file:
    // magic, length and hash of the data, the data.
    auto writeHeader = [&](bags::StateWriter& w) {
        w.tag("header");
        w.str(bagsim::kVersion);
        w.str(file.getFileName());
        w.str(file.getText());
        w.pod(std::uint64_t(file.getOverrides().size()));
        for (const std::string& o : file.getOverrides()) w.str(o);
        w.pod(poa->getTime());
        w.tag("model");
        w.str(model);
    };
    auto writeStateFile = [&](const char* name, const char* magic, const bags::StateWriter& w) {
        bags::StateWriter head;
        head.pod(std::uint64_t(w.getData().size()));
        head.pod(calcCheckpointHash(w.getData()));
        writeFileAtomically(outDir->getFile(name),
                            std::string(magic) + head.getData() + w.getData());
    };
    auto saveCheckpoint = [&] {
        bags::StateWriter w;
        writeHeader(w);
        writer->saveState(w);
        saveRunState(w);
        poa->saveState(w);
        if (air) air->saveState(w);
        if (sc.controller) sc.controller->saveState(w);
        w.tag("end");
        writeStateFile(io::kCheckpointFile, kCheckpointMagic, w);
        // The caches that shape later roundoff start afresh here, as in a run resumed here.
        poa->resetCaches();
    };
    // The rest state (docs/output-layout.md#rest-state): written once, when the simulated time
    // reaches the settle's end; the caches that shape later roundoff start afresh there, as
    // in a run started from it, so that such a run gives this run's bits.
    bool restWritten = !(sc.settleTime > 0.0) || fromRest != nullptr;
    auto saveRestState = [&] {
        bags::StateWriter w;
        writeHeader(w);
        poa->saveState(w);
        w.tag("end");
        writeStateFile(io::kRestStateFile, kRestStateMagic, w);
        poa->resetCaches();
        restWritten = true;
    };
    auto stop = [&](const std::string& status, const std::string& msg) {
        try {  // the verdict on what was run (the folder stays marked INCOMPLETE)
            writeEvents();
            setTurn();
            if (poa) tallyUnrelaxed();
            writer->writeVerdict(verdict.makeRows());
        } catch (...) {
        }
        writer->fail(status, msg);
        writeReportAfterRun(outPath, quiet);
        std::cerr << "bagsim: " << msg << "; results so far kept in " << outPath.string()
                  << "/ (marked INCOMPLETE)\n";
    };
    if (resume) {
        try {
            loadRunState(*resume);
        } catch (const bags::StateError& e) {
            return refuseResume(e.what());
        }
    }
    try {
        outDir->setStatus("running", "building the patient and inflating the bags");
        poa = std::make_unique<cosim::PatientOnArray>(sc.patient, sc.options);
        std::vector<cosim::Bag*> bags(size_t(layout.rows) * layout.columns, nullptr);
        for (size_t i = 0; i < poa->getBagIndices().size(); ++i)
            bags[poa->getBagIndices()[i]] = &poa->updBag(int(i));
        bodySurface = cosim::makeBodySurface(poa->getModel());
        {  // the bags as inflated, before he lies on them (and before any state is loaded)
            double least = 1e30, highest = 0.0;
            for (const cosim::BagReading& r : cosim::calcBagReadings(*poa))
                least = std::min(least, r.gaugePressure),
                highest = std::max(highest, r.gaugePressure);
            if (highest > 0.0) verdict.setRestPressures(least, highest);
        }
        if (fromRest) {
            // The body, the bags and the coupling as the settle left them (before the network
            // is built: it starts from the bags' gas as it finds it).
            try {
                poa->loadState(*fromRest);
                fromRest->tag("end");
                if (!fromRest->atEnd()) throw bags::StateError("rest state: data after its end");
            } catch (const bags::StateError& e) {
                std::cerr << "bagsim: error: cannot start from the rest state in "
                          << control.fromRestDir << ": " << e.what() << "\n";
                writer->fail("failed", std::string("rest state refused: ") + e.what());
                return 2;
            }
        }
        if (!resume)
            writer->setShapes(cosim::makeBagSurfaces(*poa), bodySurface.mesh,
                              std::max(sc.outputInterval, end / 60.0), end);
        if (!quiet)
            std::cerr << "  built in " << fmt("%.1f s", wall()) << ": "
                      << poa->getBagIndices().size() << " bags under him, "
                      << poa->getPairs().size() << " segment-bag pairs; released "
                      << fmt("%.1f mm", 1e3 * poa->getReleaseClearance()) << " above the board\n";
        if (!quiet && sc.options.neighbourContact) {
            // The modules of neighbours that may touch (one participant each).
            std::cerr << "  neighbouring bags touch: " << poa->getModules().size()
                      << " modules (one participant each) of";
            for (const std::vector<int>& mod : poa->getModules()) std::cerr << ' ' << mod.size();
            std::cerr << " bags\n";
        }
        if (sc.hasPneumatics) {
            const int n = layout.rows * layout.columns;
            std::vector<double> masses(n, -1.0), volumes(n, 0.0);
            for (size_t i = 0; i < poa->getBagIndices().size(); ++i) {
                const cosim::Bag& a = poa->getBag(int(i));
                masses[poa->getBagIndices()[i]] = a.getGasMass();
                volumes[poa->getBagIndices()[i]] = calcBagVolume(a);
            }
            air = std::make_unique<cosim::ArrayPneumatics>(sc.pneumatics, sc.options.bag.gas,
                                                           masses, volumes);
            // From a rest state the bags stand at the settle's end: the network starts there.
            if (fromRest) air->setStartTime(poa->getTime());
            for (int b : air->getBags()) {
                const auto it =
                    std::find(poa->getBagIndices().begin(), poa->getBagIndices().end(), b);
                airParticipant.push_back(int(it - poa->getBagIndices().begin()));
                airVolume.push_back(volumes[b]);
                airRate.push_back(0.0);
            }
            // Every attempt of a macro step (a cut step again) steps the network over exactly
            // that step and gives each bag the mass the network moved into it.
            poa->updCoupling().setBeforeStep([&](double t, double dt) {
                std::vector<pneumatics::BagVolume> v(airVolume.size());
                for (size_t k = 0; k < v.size(); ++k) v[k] = {airVolume[k], airRate[k]};
                const std::vector<double> q = air->step(t, dt, v);
                for (size_t k = 0; k < q.size(); ++k)
                    poa->updBag(airParticipant[k]).setMassFlow(q[k]);
            });
            if (!quiet)
                std::cerr << "  pneumatics: " << air->getBags().size() << " bags in the network\n";
        }
        if (resume) {
            // The model as it was at the checkpoint (the bags just inflated are replaced).
            try {
                if (resumedAirVolume.size() != airVolume.size() ||
                    resumedAirRate.size() != airRate.size())
                    bags::StateReader::mismatch("bags in the pneumatic network",
                                                resumedAirVolume.size(), airVolume.size());
                airVolume = resumedAirVolume;
                airRate = resumedAirRate;
                const auto fe = feBags();
                if (!resumedTallyKnown) resumedTally.assign(2 * fe.size(), 0.0);
                if (resumedTally.size() != 2 * fe.size())
                    bags::StateReader::mismatch("finite-element bags' tallies",
                                                resumedTally.size() / 2, fe.size());
                for (size_t k = 0; k < fe.size(); ++k)
                    fe[k].first->setUnrelaxedTally(long(resumedTally[2 * k]),
                                                   resumedTally[2 * k + 1]);
                poa->loadState(*resume);
                if (air) air->loadState(*resume);
                if (sc.controller) sc.controller->loadState(*resume);
                resume->tag("end");
                if (!resume->atEnd()) throw bags::StateError("checkpoint: data after its end");
            } catch (const bags::StateError& e) {
                return refuseResume(e.what());
            }
            outDir->setStatus(
                "running", "the patient on the bags (resumed" + fmt(" at %.4f s)", poa->getTime()));
            if (!quiet)
                std::cerr << "  resumed at " << fmt("%.4f s", poa->getTime())
                          << " from the checkpoint\n";
        } else if (fromRest) {
            const double t0 = poa->getTime();
            settled = true;
            events.push_back({t0, "started from the rest state in " + control.fromRestDir +
                                      " (the end of its settle)"});
            writeEvents();
            outDir->setStatus("running", "the patient on the bags (from the rest state in " +
                                             control.fromRestDir + fmt(" at %.4f s)", t0));
            if (!quiet)
                std::cerr << "  started at " << fmt("%.4f s", t0) << " from the rest state in "
                          << control.fromRestDir << "\n";
            record();
            // The output and checkpoint times of a run from the release, past the start.
            nextOutput = sc.outputInterval;
            while (nextOutput <= t0 + 1e-9) nextOutput += sc.outputInterval;
            if (checkpoints)
                while (nextCheckpoint <= t0 + 1e-9) nextCheckpoint += sc.checkpointInterval;
        } else {
            events.push_back({0.0, "released onto the bags"});
            writeEvents();
            outDir->setStatus("running", "the patient on the bags");
            record();
            nextOutput = sc.outputInterval;
        }
        // A resumed run wrote its rest state before its checkpoint if the settle had ended.
        if (resume && poa->getTime() >= sc.settleTime - 1e-9) restWritten = true;
        double lastPrint = wall();
        ProgressEstimate estimate;  // remaining wall time from the last minute's pace
        estimate.add(wall(), poa->getTime());
        while (poa->getTime() < end - 1e-9) {
            const double t = poa->getTime() + 1e-9;
            if (!settled && t >= sc.settleTime) {
                settled = true;
                events.push_back({poa->getTime(), "settle ended"});
            }
            sc.gas.apply(t, bags);
            double limit = std::min(end, sc.gas.findNextChange(t));
            if (!settled) limit = std::min(limit, sc.settleTime);
            // Adaptive steps land on the output times too (fixed ones do as multiples of them).
            if (sc.options.coupling.adaptive) limit = std::min(limit, nextOutput);
            if (sc.controller) {
                cosim::ControlInputs in;
                in.time = poa->getTime();
                in.pelvisTilt = cosim::calcSegmentTilt(*poa, body::Segment::LowerTrunk);
                sc.controller->update(in, *air, events);
                limit = std::min(limit, sc.controller->findNextChange(t));
            }
            writeEvents();
            const cosim::StepSummary s = poa->stepUntil(limit);
            ++totals.steps;
            totals.passes += s.iterations;
            totals.cuts += s.cuts;
            totals.bodySteps += poa->getBody().getLastIntegratorSteps();
            if (s.accepted && s.converged) {
                ++totals.accepted;
                if (s.residual >= totals.worstAccepted) {
                    totals.worstAccepted = s.residual;
                    totals.worstAcceptedTime = s.time;
                }
            }
            if (!s.converged) {
                ++totals.unconverged;
                if (s.residual >= totals.worstResidual) {
                    totals.worstResidual = s.residual;
                    totals.worstTolerance = s.tolerance;
                    totals.worstTime = s.time;
                }
                if (!quiet)
                    std::cerr << "bagsim: warning: the coupling found no fixed point at "
                              << fmt("%.6f s", s.time)
                              << " (|H(x) - x| = " << fmt("%.3g N", s.residual) << " against "
                              << fmt("%.3g N", s.tolerance) << " at the smallest step, "
                              << fmt("%.3g ms", 1e3 * s.macroStep)
                              << "); the step is kept and the run will be partial\n";
            }
            if (air) {
                // The committed step: each bag's volume now and its rate over the step; the
                // bag's and the network's masses (one owner: they must agree to roundoff).
                for (size_t k = 0; k < airVolume.size(); ++k) {
                    const cosim::Bag& a = poa->getBag(airParticipant[k]);
                    const double v = calcBagVolume(a);
                    airRate[k] = (v - airVolume[k]) / s.macroStep;
                    airVolume[k] = v;
                    const double mb = a.getGasMass(), mn = air->getBagMass(air->getBags()[k]);
                    massMismatch = std::max(massMismatch, std::abs(mb - mn) / mn);
                }
            }
            throwIfInterrupted();
            if (control.stopAfter >= 0.0 && poa->getTime() >= control.stopAfter - 1e-9)
                throw Interrupted(SIGINT);  // as Ctrl-C noticed here (--stop-after)
            if (sc.options.reduced) {       // the reduced bags' first exit of each kind
                const cosim::EnvelopeCounts e = poa->getEnvelopeCounts();
                const std::string w =
                    cosim::describeNewEnvelopeExits(e, envelope, *sc.options.reduced);
                if (!w.empty())
                    std::cerr << "bagsim: warning: " << w << fmt(" at %.3f s", poa->getTime())
                              << "\n";
                envelope = e;
            }
            if (poa->getTime() >= nextOutput - 1e-9 || poa->getTime() >= end - 1e-9) {
                const io::ArrayFrame f = record();
                while (nextOutput <= poa->getTime() + 1e-9) nextOutput += sc.outputInterval;
                estimate.add(wall(), f.time);
                if (!quiet && wall() - lastPrint > 5.0) {
                    lastPrint = wall();
                    std::cerr << "  t " << fmt("%7.3f", f.time) << fmt(" of %g s", end)
                              << "  bags carry " << fmt("%7.1f N", poa->calcBagForce()) << " of "
                              << fmt("%.1f N", poa->getWeight()) << "  tilt pelvis "
                              << fmt("%+5.1f", f.pelvisTilt * kDeg) << " thorax "
                              << fmt("%+5.1f deg", f.thoraxTilt * kDeg) << "  "
                              << fmt("%.1f passes/step", double(totals.passes) / totals.steps)
                              << "  elapsed " << ProgressEstimate::formatDuration(wall())
                              << ", left ~"
                              << ProgressEstimate::formatDuration(estimate.getRemaining(end))
                              << fmt(" (%.3g s per simulated s", estimate.getRate())
                              << fmt(" over the last %.0f s)", estimate.getStretch()) << "\n";
                }
            }
            if (!restWritten && poa->getTime() >= sc.settleTime - 1e-9) saveRestState();
            if (checkpoints && poa->getTime() >= nextCheckpoint - 1e-9 &&
                poa->getTime() < end - 1e-9) {
                while (nextCheckpoint <= poa->getTime() + 1e-9)
                    nextCheckpoint += sc.checkpointInterval;
                saveCheckpoint();
            }
        }
    } catch (const Interrupted& e) {
        stop("interrupted", std::string(e.what()) + " " + where());
        return getInterruptExitCode(e.signal);
    } catch (const std::exception& e) {
        if (getInterruptSignal()) {
            stop("interrupted",
                 Interrupted(getInterruptSignal()).what() + std::string(" ") + where());
            return getInterruptExitCode(getInterruptSignal());
        }
        stop("failed", std::string("run failed ") + where() + ": " + e.what());
        return 1;
    }

    // The summary: the force balance, the tilt, the heaviest-loaded regions at the end.
    const double weight = poa->getWeight(), carried = poa->calcBagForce();
    std::vector<cosim::RegionLoad> regions = cosim::calcRegionLoads(*poa);
    std::sort(regions.begin(), regions.end(),
              [](const cosim::RegionLoad& a, const cosim::RegionLoad& b) {
                  return a.peakPressure > b.peakPressure;
              });
    std::ostringstream table;
    table << "at " << fmt("%.3f s", poa->getTime()) << ": the bags carry " << fmt("%.2f N", carried)
          << " of his " << fmt("%.2f N", weight) << " ("
          << fmt("%+.3f %%", 100.0 * (carried - weight) / weight) << "); the mat reads "
          << fmt("%.2f N", mat.calcTotalForce()) << " (normal force, "
          << fmt("%.2f N", mat.getOffMatForce()) << " off the mat)\n";
    {  // how far neighbouring films pass through each other (bags.csv overlap_mm over time)
        const std::vector<double> overlaps = poa->calcNeighbourOverlaps();
        const auto worst = std::max_element(overlaps.begin(), overlaps.end());
        if (worst != overlaps.end())
            table << "films of neighbouring bags overlap by at most "
                  << fmt("%.2f mm", 1e3 * *worst) << " (bag "
                  << poa->getBagIndices()[size_t(worst - overlaps.begin())] << "; "
                  << (sc.options.neighbourContact ? "neighbours touch: array.neighbour_contact"
                                                  : "each bag solved alone")
                  << ")\n";
    }
    const UnrelaxedTally unrelaxed = tallyUnrelaxed();
    if (unrelaxed.steps > 0)  // relaxed bags: steps kept before their film reached its tolerance
        table << "relaxed bags: " << unrelaxed.steps
              << " bag steps were kept unrelaxed (the film's sub-steps ran out before its "
                 "force tolerance), the largest residual "
              << fmt("%.3g N", unrelaxed.largest) << " (bag " << unrelaxed.bag
              << "; "
                 "docs/"
                 "solver.md#relaxed-stepping-the-equilibrium-found-by-the-film-in-time-for-the-"
                 "patients-bags)"
                 ": the run is partial\n";
    if (totals.accepted > 0)  // steps whose passes stalled within coupling.accept_residual
        table << "coupling: " << totals.accepted << " of " << totals.steps
              << " macro steps were accepted where their passes stalled within "
                 "coupling.accept_residual ("
              << fmt("%.3g N", sc.options.coupling.acceptResidual) << "), the largest |H(x) - x| "
              << fmt("%.3g N", totals.worstAccepted) << fmt(" at %.4f s", totals.worstAcceptedTime)
              << " (docs/cosim.md#the-schemes)\n";
    if (totals.unconverged > 0)  // the coupling kept steps without a fixed point
        table << "coupling: " << totals.unconverged
              << " macro steps were kept without a fixed point at the smallest step, the "
                 "largest |H(x) - x| "
              << fmt("%.3g N", totals.worstResidual) << " against "
              << fmt("%.3g N", totals.worstTolerance) << fmt(" at %.4f s", totals.worstTime)
              << " (docs/cosim.md#the-schemes): the run is partial\n";
    {  // how deep a segment lies inside a film between its nodes, beyond its nodes' own
        // depth (the penalty's, and a soft-tissue layer's compression), which the contact does
        // not see
        const std::vector<cosim::PassThrough> pass = cosim::calcPassThroughs(*poa);
        const auto worst = std::max_element(
            pass.begin(), pass.end(), [](const cosim::PassThrough& a, const cosim::PassThrough& b) {
                return a.depth - a.nodeDepth < b.depth - b.nodeDepth;
            });
        if (worst != pass.end() && worst->segment >= 0)
            table << "segments lie inside a film between its nodes by at most "
                  << fmt("%.2f mm", 1e3 * worst->depth) << " ("
                  << body::getSegmentName(static_cast<body::Segment>(worst->segment)) << ", bag "
                  << worst->bag << "; its nodes by " << fmt("%.2f mm", 1e3 * worst->nodeDepth)
                  << ")"
                  << (worst->depth - worst->nodeDepth > 5e-3
                          ? ": the contact acts at the nodes and lets it through; a finer "
                            "bag.mesh_size holds it (docs/cosim.md#shapes-between-the-films-nodes)"
                          : "")
                  << "\n";
    }
    if (const double board = poa->calcBoardForce(); board > 0.0)
        table << "the bed board carries " << fmt("%.2f N", board)
              << " of him directly (pressed through slack bags or beside the array)\n";
    table << "tilt: pelvis "
          << fmt("%+.2f deg", cosim::calcSegmentTilt(*poa, body::Segment::LowerTrunk) * kDeg)
          << ", thorax "
          << fmt("%+.2f deg", cosim::calcSegmentTilt(*poa, body::Segment::UpperTrunk) * kDeg)
          << " (positive: turned onto his left side)\n"
          << "  region           PPI [mmHg]  mean [mmHg]  area [cm^2]  force [N]  immersion [mm]\n";
    for (const cosim::RegionLoad& r : regions) {
        if (!(r.peakPressure > 0.0)) continue;
        char line[160];
        const std::string depth = std::isnan(r.immersion) ? "-" : fmt("%.1f", 1e3 * r.immersion);
        std::snprintf(line, sizeof line, "  %-15s %11.1f %12.1f %12.1f %10.2f %15s\n",
                      r.name.c_str(), r.peakPressure / bags::kPascalsPerMmHg,
                      r.meanPressure / bags::kPascalsPerMmHg, r.area * 1e4, r.force, depth.c_str());
        table << line;
    }
    if (air) {
        table << "pneumatics: gas masses of bag and network agree to " << fmt("%.1e", massMismatch)
              << " (largest relative difference over the run)\n";
        for (int c = 0; c < air->getNumChannels(); ++c) {
            const size_t n = air->getChannelBags(c).size();
            table << "  channel '" << air->getChannelName(c) << "': " << n << " bags, "
                  << fmt("%.4f g", n ? 1e3 * air->getChannelBagMass(c) / double(n) : 0.0)
                  << " a bag at the end, sensor "
                  << fmt("%.2f kPa\n", 1e-3 * air->readChannelSensor(c));
        }
    }
    if (const auto* turn = dynamic_cast<const cosim::TurnController*>(sc.controller.get())) {
        // How much gas the turn took: each turn channel's mass per bag when it ended.
        const std::vector<double>& m0 = turn->getStartMasses();
        const std::vector<double>& m1 = turn->getTurnedMasses();
        if (!m1.empty()) {
            table << "the turn ended at pelvis tilt "
                  << fmt("%+.2f deg", turn->getTurnedTilt() * kDeg) << ":";
            for (size_t i = 0; i < m1.size(); ++i)
                table << (i ? "," : "") << " '" << air->getChannelName(turn->getChannels()[i])
                      << "' " << fmt("%.3f g", 1e3 * m1[i]) << " a bag ("
                      << fmt("%+.3f g", 1e3 * (m1[i] - m0[i])) << " from "
                      << fmt("%.3f g", 1e3 * m0[i]) << ")";
            table << "\n";
        }
    }
    table << totals.steps << " macro steps (" << totals.cuts << " cuts), "
          << fmt("%.2f", totals.steps ? double(totals.passes) / totals.steps : 0.0)
          << " coupling passes a step, " << totals.bodySteps << " steps of the body's integrator; "
          << fmt("%.1f s", wall()) << " wall-clock\n";
    std::string verdictText;
    try {
        events.push_back({poa->getTime(), "run ended"});
        writeEvents();
        setTurn();
        verdictText = writer->writeVerdict(verdict.makeRows());
    } catch (const std::exception& e) {
        stop("failed", e.what());
        return 1;
    }
    if (sc.options.reduced)
        table << cosim::describeEnvelopeCounts(poa->getEnvelopeCounts(), *sc.options.reduced)
              << "\n";
    try {
        std::ofstream s(outDir->getFile("summary.txt"));
        s << "bagsim " << bagsim::kVersion << " patient-on-array: " << file.getFileName() << " ("
          << sc.name << ")\n";
        if (!sc.description.empty()) s << sc.description << "\n";
        s << table.str();
        s << "support verdict (verdict.csv):\n" << verdictText;
        s.close();
        if (!s) throw std::runtime_error("cannot write summary.txt in " + outPath.string());
        std::string partial;
        if (unrelaxed.steps > 0)
            partial = std::to_string(unrelaxed.steps) +
                      " bag steps were kept unrelaxed (verdict.csv, 'bag films relaxed')";
        if (verdict.isFilmOutsideItsRange())
            partial += std::string(partial.empty() ? "" : "; ") +
                       "a film left its material's fitted range, outside the model's envelope "
                       "(verdict.csv, 'film within its fitted range')";
        if (totals.unconverged > 0)
            partial += (partial.empty() ? "" : "; ") + std::to_string(totals.unconverged) +
                       " macro steps were kept without a fixed point (verdict.csv, 'coupling "
                       "converged')";
        if (!partial.empty())
            writer->finish(fmt("%.4f s simulated", poa->getTime()), partial);
        else
            writer->finish(fmt("%.4f s simulated", poa->getTime()));
        // Finished: nothing left to resume.
        std::filesystem::remove(outDir->getFile(io::kCheckpointFile));
    } catch (const std::exception& e) {
        stop("failed", e.what());
        return 1;
    }
    writeReportAfterRun(outPath, quiet);
    std::cout << table.str() << "support verdict:\n"
              << verdictText << "results in " << outPath.string() << "/:\n"
              << "  " << io::kRegionsCsv << "   " << io::kRegionsHeader << "\n"
              << "  " << io::kBagsCsv << "      " << io::kBagsHeader << "\n"
              << "  " << io::kTiltCsv << "      time_s,pelvis_tilt_deg,thorax_tilt_deg\n"
              << "  " << io::kBodyCsv << "      time_s,com_x_mm,com_y_mm,com_z_mm\n"
              << "  " << io::kEventsCsv << "    time_s,event\n"
              << "  " << io::kPneumaticsCsv
              << "  time_s,bag,sensor_kPa,inflow_g_per_s,outflow_g_per_s\n"
              << "  " << io::kVerdictCsv << "   check,status,value,unit,detail\n"
              << "  " << io::kResultsH5 << "    pressure-mat frames (/mat), " << io::kResultsXdmf
              << " to open them in ParaView\n"
              << "  summary.txt, report.html (open it in a browser)\n";
    if (unrelaxed.steps > 0)
        std::cerr << "bagsim: run partial: " << unrelaxed.steps
                  << " bag steps were kept unrelaxed (largest residual "
                  << fmt("%.3g N", unrelaxed.largest) << ", bag " << unrelaxed.bag
                  << "); raise bag.dynamic.relax_substeps; results in " << outPath.string()
                  << "/ (marked INCOMPLETE, status partial)\n";
    if (totals.unconverged > 0)
        std::cerr << "bagsim: run partial: " << totals.unconverged
                  << " macro steps were kept without the coupling's fixed point (largest "
                  << "|H(x) - x| " << fmt("%.3g N", totals.worstResidual) << " against "
                  << fmt("%.3g N", totals.worstTolerance) << fmt(" at %.4f s", totals.worstTime)
                  << "); results in " << outPath.string()
                  << "/ (marked INCOMPLETE, status partial)\n";
    if (verdict.isFilmOutsideItsRange())
        std::cerr << "bagsim: run partial: a film was stretched beyond its material's fitted "
                     "range (verdict.csv, 'film within its fitted range'): outside the model's "
                     "envelope; results in "
                  << outPath.string() << "/ (marked INCOMPLETE, status partial)\n";
    return unrelaxed.steps > 0 || totals.unconverged > 0 || verdict.isFilmOutsideItsRange() ? 3 : 0;
}

}  // namespace bagsim::app
