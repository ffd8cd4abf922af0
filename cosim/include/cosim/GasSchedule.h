#pragma once
/// @file Gas over time for the bags of an array: per bag (or per group of bags) a list of
/// commands, each holding from its start time until the next one: a mass flow [kg/s] into each
/// bag (negative: out), or a target mass [kg] reached at a stated rate [kg/s].
///
/// Order of use: add() the commands; validate(numBags); in the time loop, before the step that
/// starts at t, apply(t, bags) sets each bag's flow (Bag::setMassFlow/setTargetMass),
/// and the loop ends its step at findNextChange(t) at the latest, so a command takes effect at
/// its own time, not at the next step's start.

#include <string>
#include <vector>

#include "cosim/Bag.h"

namespace cosim {

struct GasCommand {
    enum class Kind { Flow, Target };
    double time = 0.0;  ///< [s] from which the command holds
    Kind kind = Kind::Flow;
    double massFlow = 0.0;    ///< Flow: [kg/s] into each bag (negative: out)
    double targetMass = 0.0;  ///< Target: [kg] per bag
    double rate = 0.0;        ///< Target: [kg/s] of flow until the target is reached (> 0)
};

class GasSchedule {
  public:
    /// Adds a command for the listed bags (indices into the array), named for errors
    /// (e.g. "groups[2] 'left'").
    void add(const std::vector<int>& bags, const GasCommand& command, const std::string& name);
    /// @throws std::invalid_argument naming the command if a bag index is out of range, a
    /// time is negative or not finite, two commands for one bag share a start time, or a
    /// target has no positive mass or rate.
    void validate(int numBags) const;
    /// The command that holds for `bag` at time t (the latest that started at or before t),
    /// or null if none has started.
    const GasCommand* findCommand(int bag, double t) const;
    /// The first start time of any command strictly after t [s] (infinity if none).
    double findNextChange(double t) const;
    /// Sets each bag's flow for a step starting at t (bags without a command are left alone).
    /// `bags` is indexed by the array's bag index; null entries (bags not simulated, e.g. no
    /// shape over them) are skipped.
    void apply(double t, const std::vector<Bag*>& bags) const;

  private:
    struct Entry {
        std::vector<int> bags;
        GasCommand command;
        std::string name;
    };
    std::vector<Entry> m_entries;
};

}  // namespace cosim
