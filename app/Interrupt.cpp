// Stopping a run on SIGINT or SIGTERM (see Interrupt.h).
#include "Interrupt.h"

#include <csignal>

namespace bagsim::app {

namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void onInterrupt(int sig) {
    g_signal = sig;
    // A second signal ends the program at once.
    std::signal(sig, SIG_DFL);
}

}  // namespace

Interrupted::Interrupted(int sig)
    : std::runtime_error("interrupted by " + describeInterruptSignal(sig)), signal(sig) {}

InterruptGuard::InterruptGuard() {
    g_signal = 0;
    m_previousInt = std::signal(SIGINT, onInterrupt);
    m_previousTerm = std::signal(SIGTERM, onInterrupt);
    m_previousHup = std::signal(SIGHUP, onInterrupt);  // the terminal closed: stop as for SIGTERM
}

InterruptGuard::~InterruptGuard() {
    std::signal(SIGINT, m_previousInt);
    std::signal(SIGTERM, m_previousTerm);
    std::signal(SIGHUP, m_previousHup);
}

int getInterruptSignal() { return g_signal; }

void throwIfInterrupted() {
    if (g_signal) throw Interrupted(g_signal);
}

std::string describeInterruptSignal(int sig) {
    return sig == SIGTERM  ? "SIGTERM"
           : sig == SIGHUP ? "SIGHUP (its terminal closed)"
                           : "the user (SIGINT)";
}

int getInterruptExitCode(int sig) { return 128 + sig; }

}  // namespace bagsim::app
