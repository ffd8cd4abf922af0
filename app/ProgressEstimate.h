#pragma once
/// @file The remaining wall time of a run that advances a simulated time to an end: from the
/// wall time per simulated second over the last stretch (about the last minute of wall time),
/// since the cost per simulated second changes along a run (a settling patient, bags pressed
/// taut, a turn). Used by the progress line of the patient-on-array run.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <string>
#include <utility>

namespace bagsim::app {

class ProgressEstimate {
  public:
    /// @param window [s] of wall time the rate is measured over
    explicit ProgressEstimate(double window = 60.0) : m_window(window) {}

    /// A sample: wall time since the start [s] and the simulated time reached [s].
    void add(double wall, double simulated) {
        m_samples.emplace_back(wall, simulated);
        // Keep one sample at or before the window's start, so the stretch spans the window.
        while (m_samples.size() > 2 && m_samples[1].first <= wall - m_window) m_samples.pop_front();
    }
    /// Wall seconds per simulated second over the stretch; NaN before two samples.
    double getRate() const {
        if (m_samples.size() < 2) return NAN;
        const double dw = m_samples.back().first - m_samples.front().first;
        const double ds = m_samples.back().second - m_samples.front().second;
        return ds > 0.0 ? dw / ds : NAN;
    }
    /// Wall seconds to reach `end` at that rate; NaN if unknown.
    double getRemaining(double end) const {
        return m_samples.empty() ? NAN : getRate() * std::max(0.0, end - m_samples.back().second);
    }
    /// The stretch the rate is measured over [s of wall time].
    double getStretch() const {
        return m_samples.size() < 2 ? 0.0 : m_samples.back().first - m_samples.front().first;
    }

    /// "42 s", "3 min 05 s", "2 h 10 min"; "?" for NaN.
    static std::string formatDuration(double s) {
        if (!std::isfinite(s)) return "?";
        char b[48];
        const long n = std::lround(std::max(0.0, s));
        if (n < 60)
            std::snprintf(b, sizeof b, "%ld s", n);
        else if (n < 3600)
            std::snprintf(b, sizeof b, "%ld min %02ld s", n / 60, n % 60);
        else
            std::snprintf(b, sizeof b, "%ld h %02ld min", n / 3600, (n % 3600) / 60);
        return b;
    }

  private:
    double m_window;
    std::deque<std::pair<double, double>> m_samples;
};

}  // namespace bagsim::app
