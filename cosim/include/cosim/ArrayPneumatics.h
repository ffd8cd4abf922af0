#pragma once
/// @file The air hardware of an airbag array, on pneumatics::Network: a pump feeding a
/// manifold; per channel (one bag, or a group of bags) an inflate valve from the manifold and a
/// vent valve to the room; a group's channel ends in a line (a hose volume) joined to each of
/// its bags by a connector orifice, so the group's bags share their air; orifices between
/// bags; a pressure sensor on every bag and line. The bags' gas mass has one owner per step:
/// the network computes each bag's mean mass flow over the step, and the bag is given exactly
/// that flow (bags::Airbag::setMassFlow), so bag and network masses agree to roundoff without
/// being re-synchronised.
///
/// Order of use: construct from the spec, the gas and every array bag's initial mass and
/// volume (bags not simulated are left out: a negative mass); a controller commands valves
/// between steps (setInflate/setVent); per macro step attempt, step(t, dt, volumes) with each
/// network bag's volume at t and its rate, which returns each network bag's mass flow [kg/s];
/// a step attempted again from the same t (a cut macro step) restarts from the state saved at
/// its first attempt. After the step is committed, read masses, sensors and flows.
///
/// The pump runs (speed 1) while any inflate valve is commanded open, and stands otherwise (a
/// pump started on demand; it never runs backwards). The bags' gas is isothermal at the gas
/// temperature, as the finite-element bag's own gas (bags::GasOptions), so the two agree on
/// pressure as well as mass; manifold and lines may be isothermal, adiabatic or exchange heat.

#include <bags/Gas.h>
#include <pneumatics/Network.h>

#include <string>
#include <vector>

namespace cosim {

/// One channel: an inflate valve (manifold to it) and a vent valve (it to the room).
struct PneumaticChannel {
    std::string name;       ///< e.g. the group's name or "bag 12"
    std::vector<int> bags;  ///< array bag indices
    pneumatics::ValveSpec inflate;
    pneumatics::ValveSpec vent;
    /// [m^3] the group's hose volume; > 0 gives the channel a line node joined to each bag by
    /// `connector`. 0 with one bag: the valves sit on the bag itself.
    double lineVolume = 20e-6;
    bags::OrificeOptions connector;  ///< line to each bag (a cell's tube fitting)
};

/// An orifice between two bags that share air.
struct BagOrifice {
    int a = 0, b = 0;  ///< array bag indices
    bags::OrificeOptions orifice;
};

struct ArrayPneumaticsSpec {
    pneumatics::PumpSpec pump;        ///< flow against pressure rise
    pneumatics::VolumeSpec manifold;  ///< volume, thermal model (pressure: set to ambient)
    pneumatics::VolumeSpec line;      ///< thermal model of the lines (volume per channel)
    std::vector<PneumaticChannel> channels;
    std::vector<BagOrifice> orifices;
    pneumatics::SensorSpec sensor;  ///< every bag's and line's (seeds: sensor.seed + node)
    pneumatics::NetworkOptions network;
    /// @throws std::invalid_argument naming the channel or orifice: a bag out of range or in
    /// two channels, a channel with no bag, a group channel without a line, bad components.
    void validate(int numBags) const;
};

/// Mass flow into a bag over the last step, split by sign per link [kg/s].
struct BagFlow {
    double in = 0.0;   ///< >= 0
    double out = 0.0;  ///< >= 0
};

class ArrayPneumatics {
  public:
    /// @param masses per array bag its gas mass [kg]; negative: the bag is not simulated and
    /// not connected (a channel or orifice naming it leaves it out)
    /// @param volumes per array bag its volume [m^3] (ignored where the mass is negative)
    ArrayPneumatics(const ArrayPneumaticsSpec& spec, const bags::GasOptions& gas,
                    const std::vector<double>& masses, const std::vector<double>& volumes);

    // --- commands (a controller, between steps)
    int getNumChannels() const { return int(m_channels.size()); }
    const std::string& getChannelName(int channel) const;
    /// The channel's simulated bags (array indices).
    const std::vector<int>& getChannelBags(int channel) const;
    void setInflate(int channel, bool open);
    void setVent(int channel, bool open);
    bool isInflateOpen(int channel) const;
    bool isVentOpen(int channel) const;

    // --- the time loop
    /// Network bags (array indices) in the order step() takes their volumes and returns flows.
    const std::vector<int>& getBags() const { return m_bags; }
    /// Advances the network over [t, t + dt] with each network bag's volume at t and its rate;
    /// returns each network bag's mean mass flow [kg/s]. Called again with the same t, it
    /// starts again from the state it had at that t's first call (a cut macro step).
    std::vector<double> step(double t, double dt, const std::vector<pneumatics::BagVolume>& v);
    /// Time [s] of the network's state (the end of the last step).
    double getTime() const { return m_time; }
    /// Starts the network's clock at t [s] (before its first step): a run from a rest state,
    /// whose bags stand at the settle's end, builds its network there.
    /// @throws std::logic_error once the network has stepped.
    void setStartTime(double t);

    // --- read back (the last step)
    /// The channel's sensor reading [Pa] gauge: its line's, or its single bag's.
    double readChannelSensor(int channel) const;
    /// The sensor reading [Pa] gauge of an array bag in the network.
    double readBagSensor(int bag) const;
    /// Gas mass [kg] of an array bag in the network.
    double getBagMass(int bag) const;
    /// Gas mass [kg] of the channel's bags (its line excluded).
    double getChannelBagMass(int channel) const;
    BagFlow getBagFlow(int bag) const;
    /// Whether the array bag is in the network.
    bool hasBag(int bag) const;
    const pneumatics::Network& getNetwork() const { return m_net; }
    double getManifoldPressure() const;  ///< [Pa] gauge

    // --- checkpoints (bags/StateStream.h), between steps
    /// The network's state and every channel's commanded valves.
    void saveState(bags::StateWriter& w) const;
    /// @throws bags::StateError if the checkpoint's network or channels differ.
    void loadState(bags::StateReader& r);

  private:
    struct Channel {
        std::string name;
        std::vector<int> bags;
        int node = -1;  ///< line node, or the single bag's node
        int inflate = -1, vent = -1, sensor = -1;
        bool inflateOpen = false, ventOpen = false;
    };
    int bagSlot(int bag, const char* what) const;
    void setPump();

    pneumatics::Network m_net;
    pneumatics::Network m_saved;  // at m_savedTime, before its first attempt
    double m_savedTime = -1.0, m_time = 0.0;
    int m_pump = -1, m_manifold = -1;
    std::vector<Channel> m_channels;
    std::vector<int> m_bags;       // array index per network bag
    std::vector<int> m_slot;       // network bag per array index, -1: none
    std::vector<int> m_bagSensor;  // per network bag
    std::vector<std::vector<std::pair<int, int>>> m_bagLinks;  // per network bag: (link, sign)
};

}  // namespace cosim
