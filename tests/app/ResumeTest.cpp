// bagsim run --resume (docs/output-layout.md#checkpoint): a coarse patient-on-array run stopped
// as by Ctrl-C (--stop-after) and resumed from its last checkpoint writes every CSV file byte
// for byte as the run that was never stopped; the supine settle (body, bags, coupling) and the
// pneumatic turn (network, valves, noisy lagged sensors, turn controller, and the body's
// friction on the films: every contact node's anchor is in the checkpoint), and the same turn
// with reduced bags and friction, on two threads against one stopped and resumed. A resumed run is
// refused, naming what differs, when given another scenario or other overrides, and when its
// checkpoint is cut short or of another bagsim.
#include <bagsim/Version.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "ArrayRun.h"
#include "ArrayRunTestUtil.h"

namespace fs = std::filesystem;

namespace {

const std::string kBagsim = std::string("\"") + BAGSIM_BINARY_DIR + "/bin/bagsim\"";
const std::string kScenarios = std::string(BAGSIM_SOURCE_DIR) + "/scenarios/tests/";

// Runs `bagsim run ARGS`, its output into log; returns the exit status.
int runBagsim(const std::string& args, const fs::path& log) {
    const std::string cmd = kBagsim + " run " + args + " > \"" + log.string() + "\" 2>&1";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string readFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

void writeFile(const fs::path& p, const std::string& data) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out << data;
}

// Every CSV file of the run that was never stopped, byte for byte in the resumed one.
void expectSameCsvFiles(const fs::path& whole, const fs::path& resumed) {
    int compared = 0;
    for (const auto& e : fs::directory_iterator(whole)) {
        if (e.path().extension() != ".csv") continue;
        const fs::path other = resumed / e.path().filename();
        ASSERT_TRUE(fs::exists(other)) << other;
        const std::string a = readFile(e.path()), b = readFile(other);
        EXPECT_EQ(a.size(), b.size()) << e.path().filename();
        if (a != b) {
            size_t i = 0;
            while (i < a.size() && i < b.size() && a[i] == b[i]) ++i;
            const size_t from = a.rfind('\n', i) == std::string::npos ? 0 : a.rfind('\n', i) + 1;
            ADD_FAILURE() << e.path().filename() << " differs from byte " << i
                          << ":\n  whole:   " << a.substr(from, a.find('\n', i) - from)
                          << "\n  resumed: " << b.substr(from, b.find('\n', i) - from);
        }
        ++compared;
    }
    EXPECT_GE(compared, 7);  // regions, bags, tilt, body, events, pneumatics, verdict
    // results.h5 holds the same frames: results.xdmf lists every mat and shape frame by time.
    EXPECT_EQ(readFile(whole / "results.xdmf"), readFile(resumed / "results.xdmf"));
}

// A checkpoint or rest state (magic, length and hash, data) as a build that printed `from`
// where this one prints `to` (same length) would have written it: the data changed and the
// length and hash made to match.
std::string withModelText(const std::string& file, const std::string& magic,
                          const std::string& from, const std::string& to) {
    std::string data = file.substr(magic.size() + 16);
    const size_t at = data.find(from);
    if (at == std::string::npos || from.size() != to.size()) return file;
    data.replace(at, from.size(), to);
    const std::uint64_t size = data.size(), hash = bagsim::app::calcCheckpointHash(data);
    std::string head(16, '\0');
    std::memcpy(head.data(), &size, 8);
    std::memcpy(head.data() + 8, &hash, 8);
    return magic + head + data;
}

std::string readLog(const fs::path& p) { return readFile(p); }

}  // namespace

TEST(Resume, SupineSettleStoppedTwiceEndsByteIdentical) {
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "tests/app/resume/supine";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string scenario = "\"" + kScenarios + "supine-on-array-coarse.yaml\"";
    const std::string sets =
        " --set run.settle_time='0.3 s' --set output.checkpoint_every='0.1 s' --quiet";
    ASSERT_EQ(runBagsim(scenario + " --out \"" + (dir / "whole").string() + "\"" + sets,
                        dir / "whole.log"),
              0)
        << readLog(dir / "whole.log");
    EXPECT_FALSE(fs::exists(dir / "whole" / "checkpoint.bin"));  // a finished run keeps none

    // Stopped after 0.15 s (checkpoint at 0.1 s), resumed and stopped after 0.25 s (its own
    // checkpoint at 0.2 s), resumed to the end.
    const fs::path out = dir / "stopped";
    ASSERT_EQ(
        runBagsim(scenario + " --out \"" + out.string() + "\"" + sets + " --stop-after '0.15 s'",
                  dir / "stopped.log"),
        130)
        << readLog(dir / "stopped.log");
    ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
    ASSERT_TRUE(fs::exists(out / "INCOMPLETE"));

    // Bad input, refused with exit 2 and the folder left as it was.
    const std::string checkpoint = readFile(out / "checkpoint.bin");
    const std::string tilt = readFile(out / "tilt.csv");
    EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" \"" + kScenarios +
                            "turn-left-coarse.yaml\" --quiet",
                        dir / "other.log"),
              2);
    EXPECT_NE(
        readLog(dir / "other.log")
            .find("turn-left-coarse.yaml is not the scenario the run was started with (line 1"),
        std::string::npos)
        << readLog(dir / "other.log");
    EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" --set run.settle_time='0.4 s' --quiet",
                        dir / "set.log"),
              2);
    EXPECT_NE(readLog(dir / "set.log")
                  .find("the overrides differ from the run's (--set "
                        "run.settle_time=0.4 s given, --set "
                        "run.settle_time=0.3 s, --set "
                        "output.checkpoint_every=0.1 s in the checkpoint)"),
              std::string::npos)
        << readLog(dir / "set.log");
    writeFile(out / "checkpoint.bin", checkpoint.substr(0, checkpoint.size() / 2));
    EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "cut.log"), 2);
    EXPECT_NE(readLog(dir / "cut.log").find("checkpoint.bin is cut short ("), std::string::npos)
        << readLog(dir / "cut.log");
    std::string otherVersion = checkpoint;
    const size_t at = otherVersion.find(bagsim::kVersion);
    ASSERT_NE(at, std::string::npos);
    otherVersion[at] = otherVersion[at] == '9' ? '8' : '9';
    writeFile(out / "checkpoint.bin", otherVersion);
    EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "version.log"), 2);
    EXPECT_NE(readLog(dir / "version.log").find("its checkpoint was written by bagsim "),
              std::string::npos)
        << readLog(dir / "version.log");
    EXPECT_NE(
        readLog(dir / "version.log").find(std::string(", this is bagsim ") + bagsim::kVersion),
        std::string::npos);
    // Written by a build that made another model of the same scenario (a default changed):
    // the model the checkpoint keeps, as the run header prints it, differs from this build's;
    // refused, naming the line, before anything in the folder is touched.
    {
        const std::string other =
            withModelText(checkpoint, bagsim::app::kCheckpointMagic,
                          "body on the films: frictionless", "body on the films: frictionlesS");
        ASSERT_NE(other, checkpoint);
        writeFile(out / "checkpoint.bin", other);
        const std::string bags = readFile(out / "bags.csv"), marker = readFile(out / "INCOMPLETE");
        EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "model.log"), 2);
        EXPECT_NE(readLog(dir / "model.log")
                      .find("the checkpoint was written by a build that made another model of "
                            "this scenario (it had \"array "),
                  std::string::npos)
            << readLog(dir / "model.log");
        EXPECT_NE(readLog(dir / "model.log").find("frictionlesS"), std::string::npos);
        EXPECT_NE(readLog(dir / "model.log").find("(the folder is left as it was)"),
                  std::string::npos);
        EXPECT_EQ(readFile(out / "bags.csv"), bags);
        EXPECT_EQ(readFile(out / "INCOMPLETE"), marker);
    }
    writeFile(out / "checkpoint.bin", checkpoint);
    EXPECT_EQ(readFile(out / "tilt.csv"), tilt);
    {  // A run part this build does not know (a sound file): found only once the writer has
        // cut the files back to the checkpoint (their rows past it, which any resume writes
        // again bit for bit, are gone); the marker keeps the stopped run's text and says so.
        const std::string other = withModelText(checkpoint, bagsim::app::kCheckpointMagic,
                                                std::string("\x05\0\0\0\0\0\0\0run-5", 13),
                                                std::string("\x05\0\0\0\0\0\0\0run-9", 13));
        ASSERT_NE(other, checkpoint);
        writeFile(out / "checkpoint.bin", other);
        const std::string marker = readFile(out / "INCOMPLETE");
        EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "part.log"), 2);
        EXPECT_NE(readLog(dir / "part.log").find("expected the part 'run-5', found 'run-9'"),
                  std::string::npos)
            << readLog(dir / "part.log");
        const std::string after = readFile(out / "INCOMPLETE");
        EXPECT_EQ(after.substr(0, marker.size()), marker);
        EXPECT_NE(after.find("bagsim run --resume was refused: checkpoint: expected the part"),
                  std::string::npos)
            << after;
        const std::string cut = readFile(out / "tilt.csv");
        EXPECT_LT(cut.size(), tilt.size());
        EXPECT_EQ(tilt.substr(0, cut.size()), cut);
        writeFile(out / "INCOMPLETE", marker);
        writeFile(out / "checkpoint.bin", checkpoint);
    }

    ASSERT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet --stop-after '0.25 s'",
                        dir / "resumed1.log"),
              130)
        << readLog(dir / "resumed1.log");
    ASSERT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "resumed2.log"), 0)
        << readLog(dir / "resumed2.log");
    EXPECT_FALSE(fs::exists(out / "INCOMPLETE"));
    EXPECT_FALSE(fs::exists(out / "checkpoint.bin"));
    expectSameCsvFiles(dir / "whole", out);
    // Finished: nothing to resume.
    EXPECT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "again.log"), 2);
    EXPECT_NE(readLog(dir / "again.log").find("the run there finished"), std::string::npos)
        << readLog(dir / "again.log");
}

namespace {

// The scenario run with the options `whole` into dir/whole, never stopped, and with the
// options `stopped` into dir/stopped, stopped as by Ctrl-C at `stopAfter` and resumed from its
// last checkpoint: every CSV file of the two alike. The turn has started in the whole run
// (its events hold the release, the settle's end and the turn's start).
void expectResumedRunAsWhole(const fs::path& dir, const std::string& scenario,
                             const std::string& whole, const std::string& stopped,
                             const std::string& stopAfter) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    ASSERT_EQ(runBagsim(scenario + " --out \"" + (dir / "whole").string() + "\"" + whole,
                        dir / "whole.log"),
              0)
        << readLog(dir / "whole.log");
    const app::test::Csv events = app::test::readCsv(dir / "whole" / "events.csv");
    ASSERT_GE(events.rows.size(), 3u);
    const fs::path out = dir / "stopped";
    ASSERT_EQ(runBagsim(scenario + " --out \"" + out.string() + "\"" + stopped + " --stop-after '" +
                            stopAfter + "'",
                        dir / "stopped.log"),
              130)
        << readLog(dir / "stopped.log");
    ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
    ASSERT_EQ(runBagsim("--resume \"" + out.string() + "\" --quiet", dir / "resumed.log"), 0)
        << readLog(dir / "resumed.log");
    expectSameCsvFiles(dir / "whole", out);
    EXPECT_FALSE(fs::exists(out / "INCOMPLETE"));
}

}  // namespace

TEST(Resume, PneumaticTurnWithNoisySensorsEndsByteIdentical) {
    // The turn starts (valves open, noisy sensors read) before the checkpoint at 0.2 s, and
    // the body has lain on the films with friction since his release.
    const std::string sets =
        " --set run.settle_time='0.15 s' --set run.duration='0.15 s' --set output.every='50 ms'"
        " --set output.checkpoint_every='0.1 s' --set bag.body_friction=0.4 --quiet";
    expectResumedRunAsWhole(fs::path(BAGSIM_BINARY_DIR) / "tests/app/resume/pneumatic",
                            "\"" + kScenarios + "turn-left-pneumatic-coarse.yaml\"", sets, sets,
                            "0.23 s");
}

TEST(Resume, ReducedBagsWithFrictionOnOneAndTwoThreadsEndByteIdentical) {
    // The coarse pneumatic turn with reduced bags and friction between body and films
    // (docs/reduced-bag.md#friction): each bag's stick anchors are in its checkpoint part. The
    // run on two threads, never stopped, and the run on one thread stopped 0.7 s into the turn
    // (checkpoint at 2.0 s) and resumed, write every CSV file byte for byte alike. A few
    // seconds of wall-clock.
    const std::string sets =
        " --set bag.model=reduced --set bag.calibration=../../data/reduced-bag/literal-30mm.txt"
        " --set bag.body_friction=0.4 --set run.duration='1 s'"
        " --set output.checkpoint_every='0.5 s' --quiet";
    expectResumedRunAsWhole(fs::path(BAGSIM_BINARY_DIR) / "tests/app/resume/reduced",
                            "\"" + kScenarios + "turn-left-pneumatic-coarse.yaml\"",
                            sets + " --set coupling.threads=2", sets + " --set coupling.threads=1",
                            "2.2 s");
}

namespace {

// The rows of a CSV file (header dropped) whose first column, the time, is at least t0.
std::string rowsFrom(const fs::path& csv, double t0) {
    std::istringstream in(readFile(csv));
    std::string line, out;
    std::getline(in, line);
    while (std::getline(in, line))
        if (std::stod(line.substr(0, line.find(','))) >= t0 - 1e-9) out += line + "\n";
    return out;
}

}  // namespace

TEST(FromRest, ATurnFromTheRestStateOfASettleGivesTheWholeRunsBits) {
    // bagsim run --from-rest (docs/output-layout.md#rest-state). Reference: the run that
    // settled and turned in one go. A run of the same scenario started from its rest state,
    // and one started from the rest state of a settle-only run (run.duration 0 s, a free
    // key), write the same rows of tilt.csv, bags.csv and regions.csv from the settle's end
    // on, bit for bit. A scenario that differs in the model is refused naming the key, and
    // leaves no folder.
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "tests/app/from-rest";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string scenario = "\"" + kScenarios + "turn-left-coarse.yaml\"";
    const std::string settle = " --set run.settle_time='0.06 s' --set output.every='10 ms' --quiet";
    const std::string sets = settle + " --set run.duration='0.04 s'";
    auto out = [&](const std::string& name) { return " --out \"" + (dir / name).string() + "\""; };
    auto from = [&](const std::string& name) {
        return " --from-rest \"" + (dir / name).string() + "\"";
    };
    ASSERT_EQ(runBagsim(scenario + out("whole") + sets, dir / "whole.log"), 0)
        << readLog(dir / "whole.log");
    ASSERT_TRUE(fs::exists(dir / "whole" / "rest-state.bin"));
    ASSERT_EQ(runBagsim(scenario + out("settle") + settle + " --set run.duration='0 s'",
                        dir / "settle.log"),
              0)
        << readLog(dir / "settle.log");
    ASSERT_EQ(runBagsim(scenario + out("turned") + sets + from("whole"), dir / "turned.log"), 0)
        << readLog(dir / "turned.log");
    ASSERT_EQ(runBagsim(scenario + out("turned2") + sets + from("settle"), dir / "turned2.log"), 0)
        << readLog(dir / "turned2.log");
    for (const char* csv : {"tilt.csv", "bags.csv", "regions.csv"}) {
        const std::string whole = rowsFrom(dir / "whole" / csv, 0.06);
        EXPECT_GT(std::count(whole.begin(), whole.end(), '\n'), 4) << csv;
        EXPECT_EQ(rowsFrom(dir / "turned" / csv, 0.0), whole) << csv;
        EXPECT_EQ(rowsFrom(dir / "turned2" / csv, 0.0), whole) << csv;
    }
    EXPECT_NE(readFile(dir / "turned" / "events.csv").find("started from the rest state in"),
              std::string::npos);

    EXPECT_EQ(
        runBagsim(scenario + out("other") + sets + " --set bag.body_friction=0.4" + from("settle"),
                  dir / "other.log"),
        2);
    EXPECT_NE(readLog(dir / "other.log")
                  .find("(bag.body_friction: '0.4' here, absent in the rest state's scenario)"),
              std::string::npos)
        << readLog(dir / "other.log");
    EXPECT_FALSE(fs::exists(dir / "other"));
    const std::string rest = readFile(dir / "settle" / "rest-state.bin");
    {  // written by a build that made another patient or array of the same scenario
        const std::string other =
            withModelText(rest, bagsim::app::kRestStateMagic, "body on the films: frictionless",
                          "body on the films: frictionlesS");
        ASSERT_NE(other, rest);
        writeFile(dir / "settle" / "rest-state.bin", other);
        EXPECT_EQ(runBagsim(scenario + out("model") + sets + from("settle"), dir / "model.log"), 2);
        EXPECT_NE(readLog(dir / "model.log")
                      .find("the rest state was written by a build that made another model of "
                            "this scenario (it had \"array "),
                  std::string::npos)
            << readLog(dir / "model.log");
        EXPECT_FALSE(fs::exists(dir / "model"));
    }
    std::string damaged = rest;
    damaged[damaged.size() - 20] ^= 1;
    writeFile(dir / "settle" / "rest-state.bin", damaged);
    EXPECT_EQ(runBagsim(scenario + out("damaged") + sets + from("settle"), dir / "damaged.log"), 2);
    EXPECT_NE(readLog(dir / "damaged.log").find("rest-state.bin is damaged"), std::string::npos)
        << readLog(dir / "damaged.log");
}

TEST(FromRest, PneumaticRunsStartFromARestStateWithEveryShippedController) {
    // A scenario with pneumatics: (the network is built at the rest state's time, its clock
    // set there; before, every such run failed at its first step, "from 0.05 s, but the
    // network stands at 0 s"). The settle of the coarse pneumatic turn (0.05 s), then a run from
    // its rest state with each kind of controller the shipped scenarios use: each ends (exit
    // 0) and its controller acts from the settle's end, as events.csv says.
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "tests/app/from-rest-pneumatic";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string scenario = "\"" + kScenarios + "turn-left-pneumatic-coarse.yaml\"";
    const std::string settle = " --set run.settle_time='0.05 s' --quiet";
    ASSERT_EQ(runBagsim(scenario + settle + " --set run.duration='0 s' --out \"" +
                            (dir / "rest").string() + "\"",
                        dir / "rest.log"),
              0)
        << readLog(dir / "rest.log");
    struct Case {
        std::string name, control, event;
    };
    const std::vector<Case> cases = {
        {"turn", "", "0.0500,turn started (target pelvis tilt +12.0 deg)"},
        {"schedule", "{kind: schedule, commands: [{at: 0.01 s, channel: right, inflate: open}]}",
         "0.0600,schedule: channel 'right' inflate open"},
        {"target-mass", "{kind: target-mass, targets: [{channel: right, mass: 5 g}]}",
         "0.0500,target mass: channel 'right' filling at 4.5000 g a bag (target 5.0000 g a bag)"},
        {"target-pressure", "{kind: target-pressure, pressure: from-body, band: 0.3 kPa}",
         "0.0500,target pressure: channel 'left' venting at sensor"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string control = c.control.empty() ? "" : " --set \"control=" + c.control + "\"";
        EXPECT_EQ(runBagsim(scenario + settle + " --set run.duration='0.05 s'" + control +
                                " --from-rest \"" + (dir / "rest").string() + "\" --out \"" +
                                (dir / c.name).string() + "\"",
                            dir / (c.name + ".log")),
                  0)
            << readLog(dir / (c.name + ".log"));
        const std::string events = readFile(dir / c.name / "events.csv");
        EXPECT_NE(events.find("0.0500,started from the rest state in"), std::string::npos)
            << events;
        EXPECT_NE(events.find(c.event), std::string::npos) << events;
        EXPECT_NE(events.find("0.1000,run ended"), std::string::npos) << events;
    }
}

TEST(Resume, ACheckpointOfAnotherRunIsRefusedAndTheFolderKept) {
    // Two runs of one scenario, one with another override (run.duration), both stopped; the
    // first's checkpoint copied into the second's folder. It used to be resumed: the first
    // run continued into the second's files. Now refused (exit 2) naming the overrides of
    // both, every file of the folder as it was; the first run still resumes from its own.
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "tests/app/resume-other";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string scenario = "\"" + kScenarios + "supine-on-array-coarse.yaml\"";
    const std::string sets =
        " --quiet --set run.settle_time='0.06 s' --set "
        "output.checkpoint_every='0.02 s' --stop-after '0.045 s'";
    ASSERT_EQ(runBagsim(scenario + sets + " --out \"" + (dir / "a").string() + "\"", dir / "a.log"),
              130);
    ASSERT_EQ(runBagsim(scenario + sets + " --set run.duration='0 s' --out \"" +
                            (dir / "b").string() + "\"",
                        dir / "b.log"),
              130);
    fs::copy_file(dir / "a" / "checkpoint.bin", dir / "b" / "checkpoint.bin",
                  fs::copy_options::overwrite_existing);
    std::map<std::string, std::string> before;
    for (const auto& e : fs::directory_iterator(dir / "b"))
        before[e.path().filename().string()] = readFile(e.path());
    EXPECT_EQ(runBagsim("--resume \"" + (dir / "b").string() + "\"", dir / "b-resume.log"), 2);
    const std::string log = readLog(dir / "b-resume.log");
    EXPECT_NE(log.find("its checkpoint was written by another run than the one whose results are "
                       "there (overrides"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("--set run.duration=0 s in results.h5"), std::string::npos) << log;
    std::map<std::string, std::string> after;
    for (const auto& e : fs::directory_iterator(dir / "b"))
        after[e.path().filename().string()] = readFile(e.path());
    EXPECT_TRUE(before == after) << "the folder changed";
    EXPECT_EQ(runBagsim("--resume \"" + (dir / "a").string() + "\" --quiet", dir / "a-resume.log"),
              0)
        << readLog(dir / "a-resume.log");
}
