#pragma once
/// @file Stopping a run on SIGINT (Ctrl-C), SIGTERM or SIGHUP with its results kept. While an
/// InterruptGuard lives, either signal only sets a flag (a second one ends the program at once,
/// as without the guard); the run calls throwIfInterrupted() where it can stop cleanly (after a
/// load step, within a Newton iteration, between integration chunks), catches Interrupted,
/// marks its output "interrupted" and exits with getInterruptExitCode().

#include <stdexcept>
#include <string>

namespace bagsim::app {

/// Thrown by throwIfInterrupted(); unwinds out of the solver.
struct Interrupted : std::runtime_error {
    explicit Interrupted(int signal);
    int signal;  ///< SIGINT or SIGTERM
};

/// Installs the SIGINT, SIGTERM and SIGHUP handlers and clears the flag; restores the previous
/// handlers when destroyed.
class InterruptGuard {
  public:
    InterruptGuard();
    ~InterruptGuard();
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

  private:
    void (*m_previousInt)(int);
    void (*m_previousTerm)(int);
    void (*m_previousHup)(int);
};

/// The signal received since the guard was made (SIGINT or SIGTERM), 0 if none.
int getInterruptSignal();
/// @throws Interrupted if a signal was received.
void throwIfInterrupted();
/// "the user (SIGINT)" or "SIGTERM", for messages.
std::string describeInterruptSignal(int signal);
/// The shell's convention for a run ended by a signal: 128 + signal (129 SIGHUP, 130 SIGINT,
/// 143 SIGTERM).
int getInterruptExitCode(int signal);

}  // namespace bagsim::app
