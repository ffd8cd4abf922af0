#pragma once
// The ranks of an MPI job as the study runner sees them (Cluster.cpp). Rank 0 hands out case
// indices on request and receives each case's record; the other ranks ask for a case, run it
// and send its record back, until told to stop. Without MPI (or outside mpirun) there is no
// cluster and the runner works alone.

#include <functional>
#include <memory>
#include <string>

namespace study {

class Cluster {
  public:
    virtual ~Cluster() = default;
    virtual int getRank() const = 0;
    virtual int getSize() const = 0;

    // Rank 0. Answers what has arrived without blocking: a rank asking for work gets next()
    // (-1: no more, that rank stops), a record is handed to done(case, record text).
    virtual void poll(const std::function<int()>& next,
                      const std::function<void(int, const std::string&)>& done) = 0;
    /// Ranks that hold a case (rank 0 excluded).
    virtual int getNumBusy() const = 0;
    /// True once every other rank has been told to stop.
    virtual bool isAllStopped() const = 0;

    // Other ranks. Sends the previous case's record (case -1: none) and waits for the next
    // case; -1 means stop. Returns -1 too if `interrupted` becomes true while waiting.
    virtual int exchange(int previousCase, const std::string& record,
                         const std::function<bool()>& interrupted) = 0;
};

/// The MPI job this process is a rank of, or nullptr (not built with MPI, not started by
/// mpirun, or a job of one rank). Initialises MPI; the object finalises it.
std::unique_ptr<Cluster> joinCluster();

}  // namespace study
