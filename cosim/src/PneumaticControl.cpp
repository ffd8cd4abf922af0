#include "cosim/PneumaticControl.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace cosim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-9;  // [s] a command due within this of t is due at t

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

void checkChannel(int c, int numChannels, const std::string& what) {
    if (c < 0 || c >= numChannels)
        throw std::invalid_argument(what + ": channel " + std::to_string(c) +
                                    " does not exist; valid: 0 to " +
                                    std::to_string(numChannels - 1));
}

const char* stateText(BandController::State s) {
    switch (s) {
        case BandController::State::Filling:
            return "filling";
        case BandController::State::Venting:
            return "venting";
        case BandController::State::Holding:
            break;
    }
    return "holding";
}

// The event of a band controller whose state changed: "WHAT: channel 'NAME' STATE at AT
// (GOAL VALUE)", and ": GOAL reached" when it had been filling or venting.
std::string describeBandChange(const std::string& what, const std::string& channel,
                               BandController::State before, BandController::State now,
                               const std::string& at, const std::string& goal,
                               const std::string& value) {
    return what + ": channel '" + channel + "' " + stateText(now) + " at " + at + " (" + goal +
           " " + value + ")" +
           (before != BandController::State::Holding ? ": " + goal + " reached" : "");
}

}  // namespace

// ------------------------------------------------------------------------------ ValveSchedule

ValveSchedule::ValveSchedule(std::vector<ValveCommand> commands, double start, double period,
                             int numChannels)
    : m_commands(std::move(commands)), m_start(start), m_period(period) {
    if (!(start >= 0.0 && std::isfinite(start)))
        throw std::invalid_argument("valve schedule: start " + fmt("%g s", start) +
                                    "; valid: >= 0 s");
    if (!(period >= 0.0 && std::isfinite(period)))
        throw std::invalid_argument("valve schedule: period " + fmt("%g s", period) +
                                    "; valid: 0 s (not repeated) or more");
    for (size_t i = 0; i < m_commands.size(); ++i) {
        const ValveCommand& c = m_commands[i];
        const std::string name = "valve schedule command " + std::to_string(i);
        checkChannel(c.channel, numChannels, name);
        if (!(c.time >= 0.0 && std::isfinite(c.time)) || (period > 0.0 && !(c.time < period)))
            throw std::invalid_argument(
                name + ": time " + fmt("%g s", c.time) + "; valid: >= 0 s" +
                (period > 0.0 ? " and less than the period " + fmt("%g s", period) : ""));
        if (c.inflate < -1 || c.inflate > 1 || c.vent < -1 || c.vent > 1)
            throw std::invalid_argument(name + ": a valve state is 1 (open), 0 (closed) or -1");
    }
    std::stable_sort(m_commands.begin(), m_commands.end(),
                     [](const ValveCommand& a, const ValveCommand& b) { return a.time < b.time; });
}

namespace {
// Time [s] of occurrence k of the commands (k counted over the repeats), infinity if none.
double occurrenceTime(const std::vector<ValveCommand>& c, double start, double period, long k) {
    const long n = long(c.size());
    if (n == 0) return kInf;
    if (period <= 0.0) return k < n ? start + c[k].time : kInf;
    return start + double(k / n) * period + c[k % n].time;
}
}  // namespace

void ValveSchedule::update(const ControlInputs& in, ArrayPneumatics& p,
                           std::vector<ControlEvent>& events) {
    const long n = long(m_commands.size());
    for (;;) {
        const double at = occurrenceTime(m_commands, m_start, m_period, m_applied);
        if (!(at <= in.time + kEps)) break;
        const ValveCommand& c = m_commands[m_applied % n];
        std::string what;
        if (c.inflate >= 0) {
            p.setInflate(c.channel, c.inflate == 1);
            what += std::string("inflate ") + (c.inflate ? "open" : "closed");
        }
        if (c.vent >= 0) {
            p.setVent(c.channel, c.vent == 1);
            what += std::string(what.empty() ? "" : "; ") + "vent " + (c.vent ? "open" : "closed");
        }
        events.push_back({in.time, "schedule: channel '" + p.getChannelName(c.channel) + "' " +
                                       (what.empty() ? "unchanged" : what)});
        ++m_applied;
    }
}

double ValveSchedule::findNextChange(double t) const {
    for (long k = m_applied;; ++k) {
        const double at = occurrenceTime(m_commands, m_start, m_period, k);
        if (!(at < kInf) || at > t + kEps) return at;
    }
}

// ----------------------------------------------------------------------------- BandController

bool BandController::update(double measured, double target, double band, int channel,
                            ArrayPneumatics& p) {
    const State before = m_state;
    switch (m_state) {
        case State::Holding:
            if (measured < target - band)
                m_state = State::Filling;
            else if (measured > target + band)
                m_state = State::Venting;
            break;
        case State::Filling:
            if (measured >= target) m_state = State::Holding;
            break;
        case State::Venting:
            if (measured <= target) m_state = State::Holding;
            break;
    }
    p.setInflate(channel, m_state == State::Filling);
    p.setVent(channel, m_state == State::Venting);
    return m_state != before;
}

// --------------------------------------------------------------------------- TargetController

TargetController::TargetController(Quantity quantity, std::vector<Target> targets, double start)
    : m_quantity(quantity),
      m_targets(std::move(targets)),
      m_band(m_targets.size()),
      m_start(start) {
    for (const Target& t : m_targets) {
        const bool mass = quantity == Quantity::MassPerBag;
        if ((mass ? !(t.value > 0.0) : !std::isfinite(t.value)) || !(t.band >= 0.0))
            throw std::invalid_argument(
                std::string(mass ? "target mass" : "target pressure") + ": channel " +
                std::to_string(t.channel) +
                (mass ? " needs a mass > 0 g" : " needs a finite pressure") + " and a band >= 0");
    }
}

double TargetController::measure(const ArrayPneumatics& p, int channel) const {
    if (m_quantity == Quantity::Pressure) return p.readChannelSensor(channel);
    const size_t n = p.getChannelBags(channel).size();
    return n ? p.getChannelBagMass(channel) / double(n) : 0.0;
}

void TargetController::update(const ControlInputs& in, ArrayPneumatics& p,
                              std::vector<ControlEvent>& events) {
    if (in.time < m_start - kEps) return;
    const bool mass = m_quantity == Quantity::MassPerBag;
    auto text = [&](double v) {
        return mass ? fmt("%.4f g a bag", 1e3 * v) : fmt("%.3f kPa", 1e-3 * v);
    };
    for (size_t i = 0; i < m_targets.size(); ++i) {
        const Target& t = m_targets[i];
        if (p.getChannelBags(t.channel).empty()) continue;
        const double v = measure(p, t.channel);
        const BandController::State before = m_band[i].getState();
        if (m_band[i].update(v, t.value, t.band, t.channel, p))
            events.push_back(
                {in.time,
                 describeBandChange(mass ? "target mass" : "target pressure",
                                    p.getChannelName(t.channel), before, m_band[i].getState(),
                                    (mass ? "" : "sensor ") + text(v), "target", text(t.value))});
    }
}

double TargetController::findNextChange(double t) const {
    return t < m_start - kEps ? m_start : kInf;
}

double calcCellPressureForBody(const body::PatientSpec& patient) {
    patient.validate();
    body::PatientSpec reference;  // 75 kg, 1.75 m
    reference.mass = 75.0;
    reference.height = 1.75;
    const double loadPerArea = patient.mass / patient.getBodySurfaceArea();
    const double referenceLoad = reference.mass / reference.getBodySurfaceArea();
    return 4000.0 * loadPerArea / referenceLoad;
}

double calcMassForStiffness(const std::vector<double>& m, const std::vector<double>& k,
                            double want) {
    if (m.size() != k.size() || m.size() < 2)
        throw std::invalid_argument("k(m) table: give two or more (mass, stiffness) pairs");
    const double dir = k.back() > k.front() ? 1.0 : -1.0;
    for (size_t i = 1; i < m.size(); ++i)
        if (!(m[i] > m[i - 1]) || !(dir * (k[i] - k[i - 1]) > 0.0))
            throw std::invalid_argument(
                "k(m) table: masses must increase and the stiffness must rise (or fall) strictly "
                "with them; row " +
                std::to_string(i) + " does not");
    const double lo = std::min(k.front(), k.back()), hi = std::max(k.front(), k.back());
    if (!(want >= lo && want <= hi))
        throw std::invalid_argument("k(m) table: stiffness " + fmt("%g N/mm", want * 1e-3) +
                                    " is outside the table's " + fmt("%g", lo * 1e-3) + " to " +
                                    fmt("%g N/mm", hi * 1e-3));
    for (size_t i = 1; i < m.size(); ++i) {
        const double a = k[i - 1], b = k[i];
        if ((want - a) * (want - b) <= 0.0)
            return a == b ? m[i - 1] : m[i - 1] + (want - a) / (b - a) * (m[i] - m[i - 1]);
    }
    return m.back();
}

// ----------------------------------------------------------------------------- TurnController

void TurnSpec::validate(int numChannels) const {
    for (int c : inflate) checkChannel(c, numChannels, "turn inflate");
    for (int c : vent) checkChannel(c, numChannels, "turn vent");
    for (int c : inflate)
        if (std::find(vent.begin(), vent.end(), c) != vent.end())
            throw std::invalid_argument("turn: channel " + std::to_string(c) +
                                        " is both inflated and vented; valid: one side each");
    if (inflate.empty() && vent.empty())
        throw std::invalid_argument("turn: name the channels to inflate or to vent");
    if (!(tilt != 0.0 && std::abs(tilt) < 1.5))
        throw std::invalid_argument("turn: target tilt " + fmt("%g deg", tilt * 57.29578) +
                                    "; valid: not 0, within +-85 deg");
    if (!(hold >= 0.0) || !(maxTurnTime > 0.0) || !(start >= 0.0) || !(minMass >= 0.0) ||
        !(maxPressure >= 0.0) || !(band > 0.0))
        throw std::invalid_argument(
            "turn: start, hold, min mass and max pressure must be >= 0, the longest turn time "
            "and the band > 0");
    if (!(holdPressure >= 0.0 && holdPressure < 1e6) || !(pressureBand > 0.0))
        throw std::invalid_argument(
            "turn: the held pressure " + fmt("%g kPa", 1e-3 * holdPressure) + " and its band " +
            fmt("%g kPa", 1e-3 * pressureBand) + "; valid: 0 (sealed) to 1000 kPa, a band > 0");
}

TurnController::TurnController(const TurnSpec& spec, int numChannels) : m_spec(spec) {
    spec.validate(numChannels);
    m_channels = spec.inflate;
    m_channels.insert(m_channels.end(), spec.vent.begin(), spec.vent.end());
    m_band.resize(m_channels.size());
    m_isTurnChannel.assign(numChannels, 0);
    for (int c : m_channels) m_isTurnChannel[c] = 1;
    if (isHeld()) m_hold.resize(numChannels);
}

void TurnController::holdChannel(int c, double t, ArrayPneumatics& p,
                                 std::vector<ControlEvent>& events) {
    if (p.getChannelBags(c).empty()) return;
    const double v = p.readChannelSensor(c);
    const BandController::State before = m_hold[c].getState();
    if (m_hold[c].update(v, m_spec.holdPressure, m_spec.pressureBand, c, p))
        events.push_back(
            {t, describeBandChange("zone held", p.getChannelName(c), before, m_hold[c].getState(),
                                   "sensor " + fmt("%.3f kPa", 1e-3 * v), "setpoint",
                                   fmt("%.3f kPa", 1e-3 * m_spec.holdPressure))});
}

void TurnController::holdOthers(double t, ArrayPneumatics& p, std::vector<ControlEvent>& events,
                                bool all) {
    for (int c = 0; c < int(m_isTurnChannel.size()); ++c)
        if (all || !m_isTurnChannel[c]) holdChannel(c, t, p, events);
}

void TurnController::closeAll(ArrayPneumatics& p) const {
    for (int c : m_channels) {
        p.setInflate(c, false);
        p.setVent(c, false);
    }
}

void TurnController::update(const ControlInputs& in, ArrayPneumatics& p,
                            std::vector<ControlEvent>& events) {
    const double t = in.time;
    auto perBag = [&](int c) {
        const size_t n = p.getChannelBags(c).size();
        return n ? p.getChannelBagMass(c) / double(n) : 0.0;
    };
    const double sign = m_spec.tilt > 0.0 ? 1.0 : -1.0;
    if (m_phase == Phase::Done) {
        if (isHeld()) holdOthers(t, p, events, true);
        return;
    }
    if (m_phase == Phase::Waiting) {
        if (t < m_spec.start - kEps) {
            if (isHeld()) holdOthers(t, p, events, true);
            return;
        }
        m_initialMass.clear();
        for (int c : m_channels) m_initialMass.push_back(perBag(c));
        // From here the turn commands its own channels; the zone hold starts them again
        // from rest once they are back.
        if (isHeld())
            for (int c : m_channels) m_hold[c].setState(BandController::State::Holding);
        m_phase = Phase::Turning;
        m_phaseStart = t;
        events.push_back({t, "turn started (target pelvis tilt " +
                                 fmt("%+.1f deg", m_spec.tilt * 180.0 / M_PI) + ")"});
    }
    if (isHeld()) holdOthers(t, p, events, false);
    if (m_phase == Phase::Turning) {
        if (sign * in.pelvisTilt >= std::abs(m_spec.tilt)) {
            m_reached = t;
            events.push_back({t, "target tilt reached (pelvis " +
                                     fmt("%+.2f deg", in.pelvisTilt * 180.0 / M_PI) + ")"});
        } else if (t - m_phaseStart >= m_spec.maxTurnTime - kEps) {
            events.push_back({t, "target tilt not reached in " + fmt("%g s", m_spec.maxTurnTime) +
                                     " (pelvis " + fmt("%+.2f deg", in.pelvisTilt * 180.0 / M_PI) +
                                     ")"});
        } else {
            for (int c : m_spec.inflate) {
                const bool full =
                    m_spec.maxPressure > 0.0 && p.readChannelSensor(c) >= m_spec.maxPressure;
                if (full && p.isInflateOpen(c))
                    events.push_back({t, "turn: channel '" + p.getChannelName(c) +
                                             "' at its largest pressure, inflate closed"});
                p.setInflate(c, !full);
                p.setVent(c, false);
            }
            for (int c : m_spec.vent) {
                const bool empty = m_spec.minMass > 0.0 && perBag(c) <= m_spec.minMass;
                if (empty && p.isVentOpen(c))
                    events.push_back({t, "turn: channel '" + p.getChannelName(c) +
                                             "' at its least mass, vent closed"});
                p.setVent(c, !empty);
                p.setInflate(c, false);
            }
            return;
        }
        closeAll(p);
        m_turnedMass.clear();
        m_turnedTilt = in.pelvisTilt;
        for (int c : m_channels) m_turnedMass.push_back(perBag(c));
        m_phase = Phase::Holding;
        m_phaseStart = t;
        return;
    }
    if (m_phase == Phase::Holding) {
        if (t - m_phaseStart < m_spec.hold - kEps) return;
        events.push_back({t, "hold ended"});
        m_phase = Phase::Returning;
        m_phaseStart = t;
    }
    if (m_phase == Phase::Returning) {
        bool done = true;
        for (size_t i = 0; i < m_channels.size(); ++i) {
            const int c = m_channels[i];
            // Back to the start's mass, or to the zones' pressure: fill or vent until it is
            // crossed (no dead band to start from: every channel moves back, then holds
            // within the band).
            const double now = isHeld() ? p.readChannelSensor(c) : perBag(c);
            const double target = isHeld() ? m_spec.holdPressure : m_initialMass[i];
            const double band = isHeld() ? m_spec.pressureBand : m_spec.band;
            if (m_band[i].getState() == BandController::State::Holding &&
                std::abs(now - target) > 0.0 && t == m_phaseStart)
                m_band[i].update(now, target, 0.0, c, p);
            else
                m_band[i].update(now, target, band, c, p);
            done = done && m_band[i].getState() == BandController::State::Holding;
        }
        if (done) {
            closeAll(p);
            m_phase = Phase::Done;
            events.push_back({t, isHeld() ? "back to supine (the turned zones at " +
                                                fmt("%.3f kPa", 1e-3 * m_spec.holdPressure) + ")"
                                          : std::string("back to supine (initial masses "
                                                        "restored)")});
        }
    }
}

double TurnController::findNextChange(double t) const {
    if (m_phase == Phase::Waiting && t < m_spec.start - kEps) return m_spec.start;
    if (m_phase == Phase::Holding) return m_phaseStart + m_spec.hold;
    return kInf;
}

namespace {

void saveBands(bags::StateWriter& w, const std::vector<BandController>& bands) {
    w.pod(std::uint64_t(bands.size()));
    for (const BandController& b : bands) w.pod(int(b.getState()));
}

void loadBands(bags::StateReader& r, std::vector<BandController>& bands, bool fixedSize) {
    const auto n = r.pod<std::uint64_t>();
    if (fixedSize && n != bands.size())
        bags::StateReader::mismatch("controller channels", n, bands.size());
    bands.resize(n);
    for (BandController& b : bands) {
        const int s = r.pod<int>();
        if (s < 0 || s > 2) throw bags::StateError("checkpoint: a controller state out of range");
        b.setState(static_cast<BandController::State>(s));
    }
}

}  // namespace

void ValveSchedule::saveState(bags::StateWriter& w) const {
    w.tag("valve schedule");
    w.pod(std::uint64_t(m_commands.size()));
    w.pod(m_applied);
}

void ValveSchedule::loadState(bags::StateReader& r) {
    r.tag("valve schedule");
    const auto n = r.pod<std::uint64_t>();
    if (n != m_commands.size()) bags::StateReader::mismatch("valve commands", n, m_commands.size());
    r.pod(m_applied);
}

void TargetController::saveState(bags::StateWriter& w) const {
    w.tag("target controller");
    saveBands(w, m_band);
}

void TargetController::loadState(bags::StateReader& r) {
    r.tag("target controller");
    loadBands(r, m_band, true);
}

void TurnController::saveState(bags::StateWriter& w) const {
    w.tag("turn controller");
    w.pod(int(m_phase));
    w.pod(m_phaseStart);
    w.pod(m_reached);
    w.vec(m_channels);
    w.vec(m_initialMass);
    w.vec(m_turnedMass);
    w.pod(m_turnedTilt);
    saveBands(w, m_band);
    if (isHeld()) saveBands(w, m_hold);
}

void TurnController::loadState(bags::StateReader& r) {
    r.tag("turn controller");
    const int phase = r.pod<int>();
    if (phase < 0 || phase > int(Phase::Done))
        throw bags::StateError("checkpoint: the turn's phase out of range");
    m_phase = static_cast<Phase>(phase);
    r.pod(m_phaseStart);
    r.pod(m_reached);
    std::vector<int> channels;
    r.vec(channels);
    if (channels != m_channels)
        throw bags::StateError("checkpoint: the turn's channels differ from the scenario's");
    r.vec(m_initialMass);
    r.vec(m_turnedMass);
    r.pod(m_turnedTilt);
    loadBands(r, m_band, false);
    if (isHeld()) loadBands(r, m_hold, true);
}

}  // namespace cosim
