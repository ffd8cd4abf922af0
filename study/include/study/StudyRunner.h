#pragma once
/// @file Running a study (docs/studies.md): every case of an io::StudyScenario is a `bagsim run`
/// of the base scenario with the case's --set overrides, in a child process of its own, in
/// DIR/cases/<key>/. Several run at once (Options::jobs), each single-threaded; under mpirun the
/// ranks share the cases. A case that fails is a row with its reason; the others go on. Each
/// finished case leaves a record (DIR/cases/<key>.result) that a later run of the same study
/// into the same folder reads instead of running the case again. The table (study.csv after
/// every case, study.h5 at the end) is rebuilt from the records in the study's case order, so
/// it does not depend on how many ran at once or where.
///
/// Order of use: io::readStudyScenario(), then runStudy(); the library prints nothing (progress
/// goes to Options::onProgress).

#include <io/StudyScenario.h>
#include <io/StudyTable.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace study {

/// What became of one case, as kept in its record.
struct CaseRecord {
    std::string status;  ///< ok, partial, failed (or, never recorded: interrupted, not-run)
    std::string reason;  ///< why it failed or is partial; "" if ok
    double seconds = 0;  ///< wall-clock time of its run [s]
    /// The run's own status and reason, before its outputs were collected (ok, partial or
    /// failed): the outputs of a run that ended ok or partial are collected again when the
    /// study is run again, so that a changed `outputs` list never leaves a stale table.
    /// Records of older versions have none: their status stands for it.
    std::string runStatus;
    std::string runReason;
    /// Collected outputs: (index of the StudyOutput, column name, value as written by the run).
    struct Output {
        int output = 0;
        std::string name;
        std::string value;
    };
    std::vector<Output> outputs;
};

/// Text of a record and back (one "field=value" a line); readRecord() returns false for a
/// malformed record, which is then run again.
std::string formatRecord(const CaseRecord& r);
bool parseRecord(const std::string& text, CaseRecord* r);

/// Progress after each finished case.
struct Progress {
    int total = 0;           ///< cases in the study
    int finished = 0;        ///< finished so far, skipped ones included
    int skipped = 0;         ///< done by an earlier run, not run again
    int failed = 0;          ///< failed so far (this run and earlier)
    int running = 0;         ///< running now
    double elapsed = 0;      ///< since this run started [s]
    double remaining = -1;   ///< estimate [s], -1 before the first case of this run finishes
    std::string lastCase;    ///< "case 3 (contact.penalty=1e8 Pa/m)"
    std::string lastStatus;  ///< its status
};

struct Options {
    std::filesystem::path outDir;  ///< the study's folder
    std::string program;           ///< the bagsim executable that runs a case
    int jobs = 1;                  ///< cases at once on this machine (per MPI rank)
    bool retryFailed = false;      ///< run failed cases of an earlier run again
    std::string commandLine;       ///< for the record in study.h5
    /// Called often while cases run; true stops the study (Ctrl-C, SIGTERM): running cases get
    /// SIGTERM and keep their partial results, the table is written and marked.
    std::function<bool()> isInterrupted = [] { return false; };
    std::function<void(const Progress&)> onProgress;  ///< on rank 0 only
    /// Before the first case, on rank 0 only: cases to run, cases skipped, MPI ranks (1 alone).
    std::function<void(int, int, int)> onStart;
    /// @return what is wrong, "" if valid
    std::string validate() const;
};

struct Summary {
    int total = 0, ok = 0, partial = 0, failed = 0, skipped = 0, notRun = 0;
    bool interrupted = false;
    bool isRoot = true;  ///< false on MPI ranks other than 0 (they write nothing)
    double seconds = 0;  ///< wall-clock time of this run [s]
    io::StudyTable table;
};

/// Creates the study folder, or accepts it for a resumed run if it holds a study already.
/// @throws io::InputError if the folder exists, is not empty and is not a study's folder (its
///   files are left alone), or cannot be created.
void prepareStudyDir(const std::filesystem::path& dir, const io::StudyScenario& s);

/// Prepares the folder (prepareStudyDir(), on rank 0), runs the cases not yet done and writes
/// study.csv, study.h5 and, while the table is not complete, the marker INCOMPLETE. Under mpirun
/// (built with BAGSIM_MPI) rank 0 hands out the cases and writes the table; a rank that dies loses
/// only the case it was running.
Summary runStudy(const io::StudyScenario& s, const Options& o);

/// The study's outputs of one finished run (its folder `dir`) into r->outputs: per output,
/// one value (`reduce` over the column), or with `per` one per value of that column (its
/// rows reduced, or, without `reduce`, its one row; docs/studies.md#outputs). Returns "" or
/// what is missing (no such file or column, a `per` value on two rows without `reduce`).
std::string collectOutputs(const io::StudyScenario& s, const std::filesystem::path& dir,
                           CaseRecord* r);

/// The outputs of a run that ended ok or partial (r->runStatus) collected again from its
/// folder into *r, its status and reason with them (failed where an output is missing).
/// Returns true if the record changed. A run that failed is left as it is (false).
bool recollectOutputs(const io::StudyScenario& s, const std::filesystem::path& dir, CaseRecord* r);

/// The table from the records (in the study's case order); missing records are `not-run` (or
/// `interrupted` if listed in `interrupted`).
io::StudyTable buildStudyTable(const io::StudyScenario& s,
                               const std::vector<const CaseRecord*>& records,
                               const std::vector<bool>& interrupted);

}  // namespace study
