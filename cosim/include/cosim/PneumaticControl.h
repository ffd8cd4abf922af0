#pragma once
/// @file Controllers that command the valves of ArrayPneumatics between macro steps: a timed
/// schedule of valve states, a target gas mass per channel (or the mass that gives a wanted
/// stiffness through a k(m) table), a target pressure with hysteresis read from the channel's
/// (lagged, offset, noisy) sensor, and the turn sequence (inflate one side and vent the other
/// until the pelvis tilt reaches a target, hold, then restore the initial masses).
///
/// Order of use: before each macro step starting at t, update(inputs at t, pneumatics, events)
/// sets the valves for that step; the time loop ends its step at findNextChange(t) at the
/// latest, so a timed command starts at its own time. Every change of what a controller does
/// is appended to `events` (time, text), the events.csv of the run.
///
/// The controllers read the gas mass from the network (a device knows it from a flowmeter on
/// its valves integrated from a known fill) and the pressure from the sensor.

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "body/PatientSpec.h"
#include "cosim/ArrayPneumatics.h"

namespace cosim {

struct ControlEvent {
    double time = 0.0;  ///< [s]
    std::string text;   ///< e.g. "turn started", "target tilt reached"
};

/// What a controller sees at the start of a step.
struct ControlInputs {
    double time = 0.0;        ///< [s]
    double pelvisTilt = 0.0;  ///< [rad] the pelvis' roll, positive onto his left side
};

class PneumaticController {
  public:
    virtual ~PneumaticController() = default;
    /// Commands the valves for the step that starts at in.time; appends what changed.
    virtual void update(const ControlInputs& in, ArrayPneumatics& p,
                        std::vector<ControlEvent>& events) = 0;
    /// The first time [s] strictly after t at which a timed command is due (infinity: none).
    virtual double findNextChange(double /*t*/) const {
        return std::numeric_limits<double>::infinity();
    }
    /// Writes what the controller remembers between steps (its modes, phases, commands
    /// applied) into a checkpoint; loadState() reads it into a controller built the same way.
    /// @throws bags::StateError (loadState) if the checkpoint is of another controller.
    virtual void saveState(bags::StateWriter& w) const = 0;
    virtual void loadState(bags::StateReader& r) = 0;
};

/// A timed valve state of one channel.
struct ValveCommand {
    double time = 0.0;  ///< [s] from which it holds (within the period if repeated)
    int channel = 0;
    int inflate = -1;  ///< 1 open, 0 closed, -1 as it was
    int vent = -1;     ///< 1 open, 0 closed, -1 as it was
};

/// A timed schedule of valve states, optionally repeated every `period` from `start`.
class ValveSchedule : public PneumaticController {
  public:
    /// Times are from `start` [s]; period 0: not repeated, else every command's time < period.
    /// @throws std::invalid_argument naming the command (time, channel, period).
    ValveSchedule(std::vector<ValveCommand> commands, double start, double period, int numChannels);
    void update(const ControlInputs& in, ArrayPneumatics& p,
                std::vector<ControlEvent>& events) override;
    double findNextChange(double t) const override;
    void saveState(bags::StateWriter& w) const override;
    void loadState(bags::StateReader& r) override;

  private:
    std::vector<ValveCommand> m_commands;  // sorted by time
    double m_start = 0.0, m_period = 0.0;
    long m_applied = 0;  // commands applied so far, counted over the repeats
};

/// Bang-bang with a dead band, per channel: below target - band it fills until the target is
/// reached, above target + band it vents until the target is reached, else holds (both closed).
class BandController {
  public:
    enum class State { Holding, Filling, Venting };
    /// Sets the channel's valves for a measured value; returns true if the state changed.
    bool update(double measured, double target, double band, int channel, ArrayPneumatics& p);
    State getState() const { return m_state; }
    void setState(State s) { m_state = s; }  ///< as read from a checkpoint

  private:
    State m_state = State::Holding;
};

/// A target per channel for what it measures, held by a BandController from `start`: the gas
/// mass per bag (the mean over the channel's bags) or the gauge pressure its sensor reads.
class TargetController : public PneumaticController {
  public:
    enum class Quantity {
        MassPerBag,  ///< [kg] the network's mass (a flowmeter integrated from a known fill)
        Pressure,    ///< [Pa] gauge, the channel's (lagged, offset, noisy) sensor reading
    };
    struct Target {
        int channel = 0;
        double value = 0.0;  ///< [kg] per bag or [Pa] gauge
        double band = 0.0;   ///< the dead band, same unit
    };
    /// @throws std::invalid_argument naming the channel: a mass not > 0, a pressure not finite,
    /// a band < 0.
    TargetController(Quantity quantity, std::vector<Target> targets, double start);
    void update(const ControlInputs& in, ArrayPneumatics& p,
                std::vector<ControlEvent>& events) override;
    double findNextChange(double t) const override;
    void saveState(bags::StateWriter& w) const override;
    void loadState(bags::StateReader& r) override;

  private:
    double measure(const ArrayPneumatics& p, int channel) const;
    Quantity m_quantity;
    std::vector<Target> m_targets;
    std::vector<BandController> m_band;
    double m_start = 0.0;
};

/// The cell pressure set from the patient's body [Pa gauge]: 4 kPa for a 75 kg, 1.75 m adult
/// (the default of the active mattress in the Fitting Mode study, J Jpn WOCM 15(3)), scaled by
/// his mass per area of body surface (Mosteller's), m / BSA = 60 sqrt(m / h) kg/m^2 with h in
/// cm: a cell carries its share of him at about its own pressure (a slack film transmits the
/// gas pressure), so the same immersion asks for a pressure in proportion to his load per
/// area of his back, and the back's area in proportion to his body surface. No published
/// rule of a device was found (they set 'a basic setting according to the user's weight'
/// without saying how); docs/pneumatics.md#a-setpoint-from-his-body.
/// Over the modelled bodies (BMI 14-50, 1.4-2.1 m) it lies between 2.71 and 6.26 kPa.
double calcCellPressureForBody(const body::PatientSpec& patient);

/// The gas mass [kg] that gives stiffness k [N/m] by linear interpolation in a k(m) table
/// (masses increasing, stiffness strictly monotone over them).
/// @throws std::invalid_argument if k lies outside the table or the table is not monotone.
double calcMassForStiffness(const std::vector<double>& masses, const std::vector<double>& stiffness,
                            double k);

/// The turn: from `start`, the `inflate` channels fill and the `vent` channels vent until the
/// pelvis tilt reaches `tilt` (signed: positive onto his left side), or `maxTurnTime` passes;
/// all valves close for `hold`; then every turn channel is brought back to the mass per bag
/// it had at the start (dead band `band`): back to supine.
/// With a `holdPressure` (a clinical mattress's zones, held at their setpoint) every channel's
/// sensor is held at it within `pressureBand` from the release: all of them before the turn
/// and after it, the channels the turn does not move throughout; the turn channels are
/// sealed for `hold` and then brought back to the pressure, not to their masses.
struct TurnSpec {
    double start = 0.0;              ///< [s]
    std::vector<int> inflate, vent;  ///< channels
    double tilt = 0.0;               ///< [rad] signed target pelvis tilt
    double hold = 0.0;               ///< [s]
    double maxTurnTime = 60.0;       ///< [s] the turn gives up after this
    double minMass = 0.0;            ///< [kg] per bag: venting stops below it (0: none)
    double maxPressure = 0.0;        ///< [Pa] gauge: filling stops above it (0: none)
    double band = 0.05e-3;           ///< [kg] per bag, for the return
    double holdPressure = 0.0;       ///< [Pa] gauge, the zones' setpoint (0: sealed bags)
    double pressureBand = 0.3e3;     ///< [Pa] its dead band (with a holdPressure)
    /// @throws std::invalid_argument naming the parameter.
    void validate(int numChannels) const;
};

class TurnController : public PneumaticController {
  public:
    enum class Phase { Waiting, Turning, Holding, Returning, Done };
    TurnController(const TurnSpec& spec, int numChannels);
    void update(const ControlInputs& in, ArrayPneumatics& p,
                std::vector<ControlEvent>& events) override;
    double findNextChange(double t) const override;
    void saveState(bags::StateWriter& w) const override;
    void loadState(bags::StateReader& r) override;
    Phase getPhase() const { return m_phase; }
    /// [s] when the target tilt was reached (NaN: not yet, or never).
    double getTiltReachedTime() const { return m_reached; }
    /// The turn's channels: inflate then vent, with their mass per bag [kg] at the turn's start
    /// and when the turn ended (target reached or given up; empty before).
    const std::vector<int>& getChannels() const { return m_channels; }
    const std::vector<double>& getStartMasses() const { return m_initialMass; }
    const std::vector<double>& getTurnedMasses() const { return m_turnedMass; }
    double getTurnedTilt() const { return m_turnedTilt; }  ///< [rad] pelvis, at the turn's end
    /// [Pa] the zones' setpoint the turn holds and returns to (0: sealed zones, masses).
    double getHoldPressure() const { return m_spec.holdPressure; }

  private:
    void closeAll(ArrayPneumatics& p) const;
    /// Holds channel c at the spec's pressure (its own dead band m_hold[c]); says what changed.
    void holdChannel(int c, double t, ArrayPneumatics& p, std::vector<ControlEvent>& events);
    /// Holds every channel that is not a turn channel (all of them with `all`).
    void holdOthers(double t, ArrayPneumatics& p, std::vector<ControlEvent>& events, bool all);
    bool isHeld() const { return m_spec.holdPressure > 0.0; }
    TurnSpec m_spec;
    Phase m_phase = Phase::Waiting;
    double m_phaseStart = 0.0;
    double m_reached = std::numeric_limits<double>::quiet_NaN();
    std::vector<int> m_channels;        // inflate then vent
    std::vector<double> m_initialMass;  // per bag, per m_channels entry
    std::vector<double> m_turnedMass;   // per bag, per m_channels entry, at the turn's end
    double m_turnedTilt = 0.0;
    std::vector<BandController> m_band;  // the return
    std::vector<char> m_isTurnChannel;   // per channel of the network
    std::vector<BandController> m_hold;  // per channel of the network: the zones' setpoint
};

}  // namespace cosim
