#include <fcntl.h>
#include <io/InputError.h>
#include <spawn.h>
#include <study/StudyRunner.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "Cluster.h"

extern char** environ;

namespace study {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr const char* kStamp = ".bagsim-study";
constexpr const char* kMarker = "INCOMPLETE";

std::string oneLine(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
}

std::string readText(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string describeCase(const io::StudyScenario& s, size_t i) {
    std::string d = "case " + std::to_string(i + 1) + " (";
    for (size_t p = 0; p < s.parameters.size(); ++p)
        d += (p ? ", " : "") + s.parameters[p].key + "=" + s.cases[i].values[p];
    return d + ")";
}

/// The files of a case in the study folder.
struct CasePaths {
    fs::path dir, log, record;
};

CasePaths getCasePaths(const fs::path& out, const std::string& key) {
    const fs::path cases = out / "cases";
    return {cases / key, cases / (key + ".log"), cases / (key + ".result")};
}

/// first, last, min, max or mean of a column's cells ("" if none is a number, for min, max
/// and mean; the cells as written for first and last).
std::string reduceValues(const std::vector<std::string>& values, const std::string& reduce) {
    if (values.empty()) return "";
    if (reduce == "first") return values.front();
    if (reduce == "last") return values.back();
    double acc = reduce == "min" ? INFINITY : reduce == "max" ? -INFINITY : 0.0;
    int n = 0;
    for (const std::string& t : values) {
        char* end = nullptr;
        const double x = std::strtod(t.c_str(), &end);
        if (end == t.c_str() || !std::isfinite(x)) continue;
        ++n;
        acc = reduce == "min" ? std::min(acc, x) : reduce == "max" ? std::max(acc, x) : acc + x;
    }
    if (n == 0) return "";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", reduce == "mean" ? acc / n : acc);
    return buf;
}

}  // namespace

std::string collectOutputs(const io::StudyScenario& s, const std::filesystem::path& dir,
                           CaseRecord* r) {
    for (size_t j = 0; j < s.outputs.size(); ++j) {
        const io::StudyOutput& o = s.outputs[j];
        const std::string where =
            "output " + o.file + " " + o.column +
            (o.line ? " (" + s.studyFile + ":" + std::to_string(o.line) + ")" : "");
        std::ifstream in(dir / o.file);
        if (!in) return where + ": the run wrote no " + o.file;
        std::string line;
        std::getline(in, line);
        const std::vector<std::string> head = io::splitCsvLine(line);
        auto find = [&](const std::string& name) {
            for (size_t c = 0; c < head.size(); ++c)
                if (head[c] == name) return int(c);
            return -1;
        };
        const int col = find(o.column), per = o.per.empty() ? -2 : find(o.per);
        std::string columns;
        for (const std::string& h : head) columns += (columns.empty() ? "" : ", ") + h;
        if (col < 0 || per == -1)
            return where + ": " + o.file + " has no column '" + (col < 0 ? o.column : o.per) +
                   "'; its columns: " + columns;
        std::vector<std::string> values, keys;
        while (std::getline(in, line)) {
            if (line.empty()) continue;
            const std::vector<std::string> cells = io::splitCsvLine(line);
            values.push_back(col < int(cells.size()) ? cells[col] : "");
            keys.push_back(per >= 0 && per < int(cells.size()) ? cells[per] : "");
        }
        if (per < 0) {
            r->outputs.push_back({int(j),
                                  o.reduce == "first" ? o.column : o.column + ":" + o.reduce,
                                  reduceValues(values, o.reduce)});
            continue;
        }
        // One column per value of `per`, in the order of its first row.
        std::vector<std::string> order;
        std::map<std::string, std::vector<std::string>> groups;
        for (size_t k = 0; k < values.size(); ++k) {
            auto [it, fresh] = groups.try_emplace(keys[k]);
            if (fresh) order.push_back(keys[k]);
            it->second.push_back(values[k]);
        }
        for (const std::string& key : order) {
            const std::vector<std::string>& g = groups[key];
            if (o.reduce.empty() && g.size() > 1)
                return where + ": " + o.file + " has " + std::to_string(g.size()) + " rows with " +
                       o.per + " = " + key +
                       "; give the output a reduce (last: the value at the end of a time "
                       "series; first, min, max, mean), or per a column whose values differ";
            r->outputs.push_back({int(j),
                                  o.column + (o.reduce.empty() ? "" : ":" + o.reduce) + "[" +
                                      o.per + "=" + key + "]",
                                  o.reduce.empty() ? g.front() : reduceValues(g, o.reduce)});
        }
    }
    return "";
}

namespace {

/// Why a run did not complete: its marker's detail, else the last line it printed.
std::string findReason(const CasePaths& p) {
    const std::string marker = readText(p.dir / kMarker);
    const auto at = marker.find("status: ");
    if (at != std::string::npos) {
        const auto nl = marker.find('\n', at);
        if (nl != std::string::npos && nl + 1 < marker.size())
            return oneLine(marker.substr(nl + 1));
    }
    std::istringstream log(readText(p.log));
    std::string line, last, lastError;
    while (std::getline(log, line)) {
        if (line.empty()) continue;
        last = line;
        if (line.find("error") != std::string::npos || line.find("failed") != std::string::npos)
            lastError = line;
    }
    return oneLine(lastError.empty() ? last : lastError);
}

/// A case's run in a child process.
class CaseProcess {
  public:
    CaseProcess(const io::StudyScenario& s, size_t index, const Options& o, bool singleThreaded)
        : m_index(index), m_paths(getCasePaths(o.outDir, io::getCaseKey(s, s.cases[index]))) {
        std::vector<std::string> args = {
            o.program, "run", s.baseScenario, "--out", m_paths.dir.string(), "--force", "--quiet"};
        for (const std::string& set : io::getCaseOverrides(s, s.cases[index])) {
            args.push_back("--set");
            args.push_back(set);
        }
        std::vector<char*> argv;
        for (std::string& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        // Several cases at once: each keeps to one thread (OpenMP inside a bag's solve).
        std::vector<std::string> env;
        for (char** e = environ; *e; ++e)
            if (!singleThreaded || std::strncmp(*e, "OMP_NUM_THREADS=", 16) != 0) env.push_back(*e);
        if (singleThreaded) env.push_back("OMP_NUM_THREADS=1");
        std::vector<char*> envp;
        for (std::string& e : env) envp.push_back(e.data());
        envp.push_back(nullptr);

        posix_spawn_file_actions_t fa;
        posix_spawn_file_actions_init(&fa);
        const std::string log = m_paths.log.string();
        posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log.c_str(),
                                         O_WRONLY | O_CREAT | O_TRUNC, 0644);
        posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
        posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
        posix_spawnattr_t attr;
        posix_spawnattr_init(&attr);
        // Its own process group: Ctrl-C reaches the study, which stops its cases itself.
        posix_spawnattr_setpgroup(&attr, 0);
        short flags = POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK;
        sigset_t def, mask;
        sigemptyset(&def);
        sigaddset(&def, SIGINT);
        sigaddset(&def, SIGTERM);
        sigemptyset(&mask);
        posix_spawnattr_setsigdefault(&attr, &def);
        posix_spawnattr_setsigmask(&attr, &mask);
        posix_spawnattr_setflags(&attr, flags);
        m_start = Clock::now();
        const int err =
            posix_spawn(&m_pid, o.program.c_str(), &fa, &attr, argv.data(), envp.data());
        posix_spawn_file_actions_destroy(&fa);
        posix_spawnattr_destroy(&attr);
        if (err != 0) {
            m_pid = -1;
            m_spawnError = std::string("cannot start ") + o.program + ": " + std::strerror(err);
        }
    }

    size_t getIndex() const { return m_index; }
    pid_t getPid() const { return m_pid; }
    const std::string& getSpawnError() const { return m_spawnError; }
    void stop() const {
        if (m_pid > 0) kill(m_pid, SIGTERM);
    }

    /// The record of a finished run from its wait status.
    CaseRecord finish(const io::StudyScenario& s, int waitStatus) const {
        CaseRecord r;
        // Kept at the record's precision (formatRecord: 1 ms), so that the table written now
        // and the one a rerun writes from the records round the same number.
        r.seconds =
            std::round(std::chrono::duration<double>(Clock::now() - m_start).count() * 1e3) / 1e3;
        if (!m_spawnError.empty()) {
            r.status = "failed";
            r.reason = m_spawnError;
            return r;
        }
        if (WIFSIGNALED(waitStatus)) {
            const int sig = WTERMSIG(waitStatus);
            r.status = "failed";
            r.reason =
                "the run was killed by signal " + std::to_string(sig) + " (" + strsignal(sig) + ")";
            return r;
        }
        const int code = WEXITSTATUS(waitStatus);
        if (code == 0 || code == 3) {
            r.runStatus = code == 0 ? "ok" : "partial";
            if (code == 3) r.runReason = findReason(m_paths);
            recollectOutputs(s, m_paths.dir, &r);
            return r;
        }
        r.status = "failed";
        r.reason = (code == 2 ? "bad input: " : "") + findReason(m_paths) + " (exit status " +
                   std::to_string(code) + ")";
        return r;
    }

  private:
    size_t m_index;
    CasePaths m_paths;
    pid_t m_pid = -1;
    Clock::time_point m_start;
    std::string m_spawnError;
};

bool isInterruptExit(int waitStatus) {
    return WIFEXITED(waitStatus) &&
           (WEXITSTATUS(waitStatus) == 129 || WEXITSTATUS(waitStatus) == 130 ||
            WEXITSTATUS(waitStatus) == 143);
}

void writeRecord(const fs::path& path, const CaseRecord& r) {
    const fs::path tmp = path.string() + ".tmp";
    {
        std::ofstream out(tmp, std::ios::trunc);
        out << formatRecord(r);
        if (!out.flush()) throw std::runtime_error("cannot write " + tmp.string());
    }
    fs::rename(tmp, path);
}

void pause() { std::this_thread::sleep_for(std::chrono::milliseconds(20)); }

/// Runs one case in this process's child and waits for it (MPI ranks other than 0).
/// Returns false if interrupted.
bool runOneCase(const io::StudyScenario& s, size_t i, const Options& o, CaseRecord* r) {
    CaseProcess p(s, i, o, true);
    int status = 0;
    for (;;) {
        if (p.getPid() < 0) break;
        const pid_t w = waitpid(p.getPid(), &status, WNOHANG);
        if (w == p.getPid()) break;
        if (o.isInterrupted()) {
            p.stop();
            waitpid(p.getPid(), &status, 0);
            return false;
        }
        pause();
    }
    if (p.getPid() > 0 && isInterruptExit(status) && o.isInterrupted()) return false;
    *r = p.finish(s, status);
    writeRecord(getCasePaths(o.outDir, io::getCaseKey(s, s.cases[i])).record, *r);
    return true;
}

void writeMarker(const fs::path& dir, const Summary& sum) {
    if (sum.table.status == "complete") {
        std::error_code ec;
        fs::remove(dir / kMarker, ec);
        return;
    }
    std::ofstream out(dir / kMarker, std::ios::trunc);
    out << "This study's table is incomplete: " << sum.notRun << " of " << sum.total
        << " cases have not run" << (sum.interrupted ? " (the study was interrupted)" : "")
        << ". Run the same study into this folder again to run them; the cases done are kept.\n"
        << "status: " << sum.table.status << "\n";
}

}  // namespace

std::string formatRecord(const CaseRecord& r) {
    std::ostringstream out;
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.3f", r.seconds);
    out << "status=" << r.status << "\nreason=" << oneLine(r.reason) << "\nseconds=" << secs
        << "\n";
    if (!r.runStatus.empty())
        out << "run_status=" << r.runStatus << "\nrun_reason=" << oneLine(r.runReason) << "\n";
    for (const CaseRecord::Output& o : r.outputs)
        out << "output=" << o.output << "\t" << oneLine(o.name) << "\t" << oneLine(o.value) << "\n";
    out << "end\n";
    return out.str();
}

bool parseRecord(const std::string& text, CaseRecord* r) {
    std::istringstream in(text);
    std::string line;
    bool end = false;
    *r = CaseRecord{};
    while (std::getline(in, line)) {
        if (line == "end") {
            end = true;
            break;
        }
        const auto eq = line.find('=');
        if (eq == std::string::npos) return false;
        const std::string field = line.substr(0, eq), value = line.substr(eq + 1);
        if (field == "status") {
            r->status = value;
        } else if (field == "reason") {
            r->reason = value;
        } else if (field == "seconds") {
            r->seconds = std::atof(value.c_str());
        } else if (field == "run_status") {
            r->runStatus = value;
        } else if (field == "run_reason") {
            r->runReason = value;
        } else if (field == "output") {
            const auto t1 = value.find('\t'), t2 = value.find('\t', t1 + 1);
            if (t1 == std::string::npos || t2 == std::string::npos) return false;
            r->outputs.push_back({std::atoi(value.substr(0, t1).c_str()),
                                  value.substr(t1 + 1, t2 - t1 - 1), value.substr(t2 + 1)});
        }
    }
    if (r->runStatus.empty() && (r->status == "ok" || r->status == "partial")) {
        r->runStatus = r->status;
        r->runReason = r->reason;
    }
    return end && (r->status == "ok" || r->status == "partial" || r->status == "failed");
}

bool recollectOutputs(const io::StudyScenario& s, const std::filesystem::path& dir, CaseRecord* r) {
    if (r->runStatus != "ok" && r->runStatus != "partial") return false;
    const CaseRecord before = *r;
    r->status = r->runStatus;
    r->reason = r->runReason;
    r->outputs.clear();
    const std::string missing = collectOutputs(s, dir, r);
    if (!missing.empty()) {
        r->status = "failed";
        r->reason = missing;
    }
    auto same = [](const CaseRecord& a, const CaseRecord& b) {
        if (a.status != b.status || a.reason != b.reason || a.outputs.size() != b.outputs.size())
            return false;
        for (size_t k = 0; k < a.outputs.size(); ++k)
            if (a.outputs[k].output != b.outputs[k].output ||
                a.outputs[k].name != b.outputs[k].name || a.outputs[k].value != b.outputs[k].value)
                return false;
        return true;
    };
    return !same(before, *r);
}

std::string Options::validate() const {
    if (jobs < 1) return "--jobs must be at least 1";
    if (program.empty()) return "no program to run the cases with";
    if (outDir.empty()) return "no output folder";
    return "";
}

void prepareStudyDir(const fs::path& dir, const io::StudyScenario& s) {
    const std::string where = dir.string();
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        if (!fs::is_directory(dir, ec))
            throw io::InputError(where, 0, "",
                                 "the output path exists and is not a folder; "
                                 "choose another --out");
        if (!fs::is_empty(dir, ec) && !fs::exists(dir / kStamp, ec))
            throw io::InputError(where, 0, "",
                                 "the output folder exists, is not empty and is not a study's "
                                 "folder (no " +
                                     std::string(kStamp) +
                                     "); its files are left alone: choose another --out");
    }
    fs::create_directories(dir / "cases", ec);
    if (ec) throw io::InputError(where, 0, "", "cannot create the folder: " + ec.message());
    std::ofstream stamp(dir / kStamp, std::ios::trunc);
    stamp << "A bagsim study folder (docs/studies.md): bagsim study may run cases and rewrite "
             "study.csv, study.h5, INCOMPLETE and cases/ here.\nlast study: "
          << s.studyFile << "\n";
    if (!stamp) throw io::InputError(where, 0, "", "cannot write into the folder");
}

io::StudyTable buildStudyTable(const io::StudyScenario& s,
                               const std::vector<const CaseRecord*>& records,
                               const std::vector<bool>& interrupted) {
    io::StudyTable t;
    t.studyFile = s.studyFile;
    t.studyText = s.studyText;
    t.baseText = s.baseText;
    t.header = {"case", "key"};
    for (const io::StudyParameter& p : s.parameters)
        t.header.push_back(p.unit.empty() ? p.key : p.key + " [" + p.unit + "]");
    t.header.insert(t.header.end(), {"status", "reason", "seconds"});
    // Output columns: per output, the names in the order the cases first give them.
    std::vector<std::string> outNames;
    std::map<std::string, size_t> outColumn;
    for (size_t j = 0; j < s.outputs.size(); ++j)
        for (const CaseRecord* r : records)
            if (r)
                for (const CaseRecord::Output& o : r->outputs)
                    if (o.output == int(j) && !outColumn.count(o.name)) {
                        outColumn[o.name] = outNames.size();
                        outNames.push_back(o.name);
                    }
    t.header.insert(t.header.end(), outNames.begin(), outNames.end());
    bool complete = true;
    for (size_t i = 0; i < s.cases.size(); ++i) {
        const io::StudyCase& c = s.cases[i];
        std::vector<std::string> row = {std::to_string(i + 1), io::getCaseKey(s, c)};
        for (size_t p = 0; p < s.parameters.size(); ++p) {
            if (std::isfinite(c.numbers[p])) {
                char buf[32];
                std::snprintf(buf, sizeof buf, "%.10g", c.numbers[p]);
                row.push_back(buf);
            } else {
                row.push_back(c.values[p]);
            }
        }
        const CaseRecord* r = records[i];
        std::vector<std::string> outs(outNames.size());
        if (r) {
            char secs[32];
            std::snprintf(secs, sizeof secs, "%.1f", r->seconds);
            row.insert(row.end(), {r->status, r->reason, secs});
            for (const CaseRecord::Output& o : r->outputs) outs[outColumn[o.name]] = o.value;
        } else {
            complete = false;
            row.insert(row.end(), {interrupted[i] ? "interrupted" : "not-run", "", ""});
        }
        row.insert(row.end(), outs.begin(), outs.end());
        t.rows.push_back(std::move(row));
    }
    t.status = complete ? "complete" : "incomplete";
    return t;
}

Summary runStudy(const io::StudyScenario& s, const Options& o) {
    if (const std::string e = o.validate(); !e.empty()) throw std::invalid_argument(e);
    const Clock::time_point start = Clock::now();
    Summary sum;
    sum.total = int(s.cases.size());
    std::unique_ptr<Cluster> cluster = joinCluster();

    if (cluster && cluster->getRank() != 0) {
        // A worker: asks rank 0 for cases until told to stop.
        sum.isRoot = false;
        int previous = -1;
        std::string record;
        for (;;) {
            const int next = cluster->exchange(previous, record, o.isInterrupted);
            if (next < 0 || next >= int(s.cases.size())) break;
            CaseRecord r;
            if (!runOneCase(s, size_t(next), o, &r)) {
                sum.interrupted = true;
                break;
            }
            previous = next;
            record = formatRecord(r);
        }
        sum.seconds = std::chrono::duration<double>(Clock::now() - start).count();
        return sum;
    }

    try {
        prepareStudyDir(o.outDir, s);
    } catch (...) {
        // The other ranks wait for cases: tell them there are none.
        while (cluster && !cluster->isAllStopped()) {
            cluster->poll([] { return -1; }, [](int, const std::string&) {});
            pause();
        }
        throw;
    }
    // What earlier runs left: their records.
    const size_t n = s.cases.size();
    std::vector<CaseRecord> records(n);
    std::vector<bool> have(n, false), interrupted(n, false);
    std::vector<size_t> todo;
    for (size_t i = 0; i < n; ++i) {
        const CasePaths p = getCasePaths(o.outDir, io::getCaseKey(s, s.cases[i]));
        CaseRecord r;
        if (parseRecord(readText(p.record), &r) && !(o.retryFailed && r.status == "failed")) {
            // The outputs again from the run's folder: the study's outputs may have changed.
            if (recollectOutputs(s, p.dir, &r)) writeRecord(p.record, r);
            records[i] = r;
            have[i] = true;
            ++sum.skipped;
        } else {
            todo.push_back(i);
        }
    }
    // Cases run in the study's order; the table does not depend on it.
    size_t nextTodo = 0;
    int finishedThisRun = 0;
    Progress pr;
    pr.total = int(n);
    pr.skipped = sum.skipped;
    for (size_t i = 0; i < n; ++i)
        if (have[i] && records[i].status == "failed") ++pr.failed;
    pr.finished = sum.skipped;

    auto tablePointers = [&] {
        std::vector<const CaseRecord*> ptr(n, nullptr);
        for (size_t i = 0; i < n; ++i)
            if (have[i]) ptr[i] = &records[i];
        return ptr;
    };
    auto writeCsv = [&] {
        io::StudyTable t = buildStudyTable(s, tablePointers(), interrupted);
        io::writeStudyCsv(t, (o.outDir / "study.csv").string());
    };
    auto onDone = [&](size_t i, const CaseRecord& r) {
        records[i] = r;
        have[i] = true;
        ++finishedThisRun;
        ++pr.finished;
        if (r.status == "failed") ++pr.failed;
        pr.elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        const int left = int(n) - pr.finished;
        pr.remaining = pr.elapsed / finishedThisRun * left;
        pr.lastCase = describeCase(s, i);
        pr.lastStatus = r.status + (r.reason.empty() ? "" : ": " + r.reason);
        writeCsv();
        if (o.onProgress) o.onProgress(pr);
    };
    auto nextCase = [&]() -> int {
        if (o.isInterrupted() || nextTodo >= todo.size()) return -1;
        return int(todo[nextTodo++]);
    };

    writeCsv();
    if (o.onStart) o.onStart(int(todo.size()), sum.skipped, cluster ? cluster->getSize() : 1);
    std::vector<std::unique_ptr<CaseProcess>> running;
    const bool single = o.jobs > 1 || cluster != nullptr;
    for (;;) {
        if (o.isInterrupted()) {
            sum.interrupted = true;
            for (auto& p : running) p->stop();
            for (auto& p : running) {
                int st = 0;
                if (p->getPid() > 0) waitpid(p->getPid(), &st, 0);
                // A case that ended on its own just before the signal is kept.
                if (p->getPid() > 0 && !isInterruptExit(st) && !WIFSIGNALED(st)) {
                    const CaseRecord r = p->finish(s, st);
                    writeRecord(
                        getCasePaths(o.outDir, io::getCaseKey(s, s.cases[p->getIndex()])).record,
                        r);
                    onDone(p->getIndex(), r);
                } else {
                    interrupted[p->getIndex()] = true;
                }
            }
            running.clear();
            if (cluster)
                cluster->poll([] { return -1; },
                              [&](int c, const std::string& text) {
                                  CaseRecord r;
                                  if (parseRecord(text, &r)) onDone(size_t(c), r);
                              });
            break;
        }
        while (int(running.size()) < o.jobs) {
            const int c = nextCase();
            if (c < 0) break;
            running.push_back(std::make_unique<CaseProcess>(s, size_t(c), o, single));
        }
        for (size_t k = 0; k < running.size();) {
            int st = 0;
            const pid_t pid = running[k]->getPid();
            const bool ended = pid < 0 || waitpid(pid, &st, WNOHANG) == pid;
            if (!ended) {
                ++k;
                continue;
            }
            const size_t i = running[k]->getIndex();
            if (pid > 0 && isInterruptExit(st) && o.isInterrupted()) {
                interrupted[i] = true;
            } else {
                const CaseRecord r = running[k]->finish(s, st);
                writeRecord(getCasePaths(o.outDir, io::getCaseKey(s, s.cases[i])).record, r);
                pr.running = int(running.size()) - 1 + (cluster ? cluster->getNumBusy() : 0);
                onDone(i, r);
            }
            running.erase(running.begin() + long(k));
        }
        if (cluster)
            cluster->poll(nextCase, [&](int c, const std::string& text) {
                CaseRecord r;
                if (c >= 0 && c < int(n) && parseRecord(text, &r)) {
                    pr.running = int(running.size()) + cluster->getNumBusy();
                    onDone(size_t(c), r);
                }
            });
        pr.running = int(running.size()) + (cluster ? cluster->getNumBusy() : 0);
        const bool workLeft = nextTodo < todo.size();
        if (running.empty() && !workLeft &&
            (!cluster || (cluster->getNumBusy() == 0 && cluster->isAllStopped())))
            break;
        pause();
    }

    for (size_t i = 0; i < n; ++i) {
        if (!have[i]) {
            ++sum.notRun;
            continue;
        }
        const std::string& st = records[i].status;
        sum.ok += st == "ok";
        sum.partial += st == "partial";
        sum.failed += st == "failed";
    }
    sum.table = buildStudyTable(s, tablePointers(), interrupted);
    if (sum.interrupted && sum.table.status != "complete") sum.table.status = "interrupted";
    sum.table.commandLine = o.commandLine;
    io::writeStudyCsv(sum.table, (o.outDir / "study.csv").string());
    io::writeStudyH5(sum.table, (o.outDir / "study.h5").string());
    writeMarker(o.outDir, sum);
    sum.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return sum;
}

}  // namespace study
