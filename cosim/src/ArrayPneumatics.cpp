#include "cosim/ArrayPneumatics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cosim {

void ArrayPneumaticsSpec::validate(int numBags) const {
    pump.validate("pneumatics.pump");
    manifold.validate("pneumatics.manifold");
    line.validate("pneumatics.line");
    sensor.validate("pneumatics.sensor");
    network.validate();
    std::vector<int> owner(size_t(std::max(numBags, 0)), -1);
    for (size_t c = 0; c < channels.size(); ++c) {
        const PneumaticChannel& ch = channels[c];
        const std::string name = "pneumatics channel " + std::to_string(c) + " '" + ch.name + "'";
        if (ch.bags.empty()) throw std::invalid_argument(name + ": has no bag; valid: 1 or more");
        for (int b : ch.bags) {
            if (b < 0 || b >= numBags)
                throw std::invalid_argument(name + ": bag " + std::to_string(b) +
                                            " does not exist; valid: 0 to " +
                                            std::to_string(numBags - 1));
            if (owner[b] >= 0)
                throw std::invalid_argument(name + ": bag " + std::to_string(b) +
                                            " is already in channel " + std::to_string(owner[b]) +
                                            "; valid: a bag in one channel at most");
            owner[b] = int(c);
        }
        if (!(ch.lineVolume >= 0.0 && std::isfinite(ch.lineVolume)))
            throw std::invalid_argument(name + ": line volume must be >= 0 m^3");
        if (ch.bags.size() > 1 && !(ch.lineVolume > 0.0))
            throw std::invalid_argument(name + ": a channel of " + std::to_string(ch.bags.size()) +
                                        " bags needs a line (a hose volume > 0) joining them");
        ch.inflate.validate(name + " inflate valve");
        ch.vent.validate(name + " vent valve");
        if (ch.lineVolume > 0.0) ch.connector.validate();
    }
    for (size_t i = 0; i < orifices.size(); ++i) {
        const BagOrifice& o = orifices[i];
        if (o.a < 0 || o.a >= numBags || o.b < 0 || o.b >= numBags || o.a == o.b)
            throw std::invalid_argument("pneumatics orifice " + std::to_string(i) + ": bags " +
                                        std::to_string(o.a) + " and " + std::to_string(o.b) +
                                        "; valid: two different bags, 0 to " +
                                        std::to_string(numBags - 1));
        o.orifice.validate();
    }
}

ArrayPneumatics::ArrayPneumatics(const ArrayPneumaticsSpec& spec, const bags::GasOptions& gas,
                                 const std::vector<double>& masses,
                                 const std::vector<double>& volumes)
    : m_net(gas, spec.network), m_saved(gas, spec.network) {
    if (masses.size() != volumes.size())
        throw std::invalid_argument("ArrayPneumatics: one volume per mass");
    spec.validate(int(masses.size()));
    const double R = gas.getSpecificGasConstant(), T = gas.temperature;
    m_slot.assign(masses.size(), -1);
    unsigned long long seed = spec.sensor.seed;
    auto addSensor = [&](int node) {
        pneumatics::SensorSpec s = spec.sensor;
        s.seed = seed++;
        return m_net.addPressureSensor(node, s);
    };
    auto addBag = [&](int b) {
        if (m_slot[b] >= 0 || !(masses[b] >= 0.0)) return;
        if (!(volumes[b] > 0.0))
            throw std::invalid_argument("ArrayPneumatics: bag " + std::to_string(b) +
                                        " has no volume");
        pneumatics::VolumeSpec v;
        v.volume = volumes[b];
        v.pressure = masses[b] * R * T / volumes[b];
        v.temperature = v.wallTemperature = T;
        v.thermal = pneumatics::Thermal::Isothermal;
        const int node = m_net.addBag("bag " + std::to_string(b), v);
        m_slot[b] = int(m_bags.size());
        m_bags.push_back(b);
        m_bagSensor.push_back(addSensor(node));
        m_bagLinks.emplace_back();
    };
    // The bags first, in array order: each with its own node and sensor.
    for (const PneumaticChannel& ch : spec.channels)
        for (int b : ch.bags) addBag(b);
    for (const BagOrifice& o : spec.orifices) {
        addBag(o.a);
        addBag(o.b);
    }
    pneumatics::VolumeSpec mf = spec.manifold;
    mf.pressure = gas.ambientPressure;
    m_manifold = m_net.addVolume("manifold", mf);
    m_pump = m_net.addPump("pump", m_net.getAmbient(), m_manifold, spec.pump, 0.0);
    auto link = [&](int linkIndex, int bag, int sign) {
        if (bag >= 0 && m_slot[bag] >= 0) m_bagLinks[m_slot[bag]].push_back({linkIndex, sign});
    };
    for (const PneumaticChannel& pc : spec.channels) {
        Channel ch;
        ch.name = pc.name;
        for (int b : pc.bags)
            if (m_slot[b] >= 0) ch.bags.push_back(b);
        int single = -1;  // the bag the valves sit on (no line)
        if (pc.lineVolume > 0.0) {
            pneumatics::VolumeSpec lv = spec.line;
            lv.volume = pc.lineVolume;
            // The line starts at its bags' mean pressure (the group shares its air).
            double p = 0.0;
            for (int b : ch.bags) p += masses[b] * R * T / volumes[b];
            lv.pressure = ch.bags.empty() ? gas.ambientPressure : p / double(ch.bags.size());
            ch.node = m_net.addVolume("line " + pc.name, lv);
            for (int b : ch.bags)
                link(m_net.addOrifice("connector " + pc.name + " bag " + std::to_string(b), ch.node,
                                      m_net.getBagNode(m_slot[b]), pc.connector),
                     b, +1);
            ch.sensor = addSensor(ch.node);
        } else if (!ch.bags.empty()) {
            single = ch.bags[0];
            ch.node = m_net.getBagNode(m_slot[single]);
            ch.sensor = m_bagSensor[m_slot[single]];
        }
        if (ch.node >= 0) {
            ch.inflate =
                m_net.addValve("inflate " + pc.name, m_manifold, ch.node, pc.inflate, false);
            ch.vent = m_net.addVent("vent " + pc.name, ch.node, pc.vent, false);
            link(ch.inflate, single, +1);
            link(ch.vent, single, -1);
        }
        m_channels.push_back(ch);
    }
    for (const BagOrifice& o : spec.orifices) {
        if (m_slot[o.a] < 0 || m_slot[o.b] < 0) continue;
        const int l = m_net.addOrifice(
            "orifice bags " + std::to_string(o.a) + "-" + std::to_string(o.b),
            m_net.getBagNode(m_slot[o.a]), m_net.getBagNode(m_slot[o.b]), o.orifice);
        link(l, o.a, -1);
        link(l, o.b, +1);
    }
}

const std::string& ArrayPneumatics::getChannelName(int c) const { return m_channels.at(c).name; }
const std::vector<int>& ArrayPneumatics::getChannelBags(int c) const {
    return m_channels.at(c).bags;
}

void ArrayPneumatics::setPump() {
    bool any = false;
    for (const Channel& c : m_channels) any = any || (c.inflateOpen && c.inflate >= 0);
    m_net.setPumpSpeed(m_pump, any ? 1.0 : 0.0);
}

void ArrayPneumatics::setInflate(int channel, bool open) {
    Channel& c = m_channels.at(channel);
    c.inflateOpen = open;
    if (c.inflate >= 0) m_net.setValveOpen(c.inflate, open);
    setPump();
}

void ArrayPneumatics::setVent(int channel, bool open) {
    Channel& c = m_channels.at(channel);
    c.ventOpen = open;
    if (c.vent >= 0) m_net.setValveOpen(c.vent, open);
}

bool ArrayPneumatics::isInflateOpen(int c) const { return m_channels.at(c).inflateOpen; }
bool ArrayPneumatics::isVentOpen(int c) const { return m_channels.at(c).ventOpen; }

void ArrayPneumatics::setStartTime(double t) {
    if (m_savedTime != -1.0)  // a step was taken
        throw std::logic_error("the pneumatic network's clock is set before its first step");
    m_time = t;
}

std::vector<double> ArrayPneumatics::step(double t, double dt,
                                          const std::vector<pneumatics::BagVolume>& v) {
    if (t == m_savedTime) {
        m_net = m_saved;  // the same step again (cut): from its start
    } else {
        if (!(std::abs(t - m_time) <= 1e-9 * std::max(1.0, std::abs(t))))
            throw std::invalid_argument("the pneumatic network was asked to step from " +
                                        std::to_string(t) + " s, but it stands at " +
                                        std::to_string(m_time) + " s");
        m_saved = m_net;
        m_savedTime = t;
    }
    std::vector<double> q = m_net.step(dt, v);
    m_time = t + dt;
    return q;
}

int ArrayPneumatics::bagSlot(int bag, const char* what) const {
    if (bag < 0 || bag >= int(m_slot.size()) || m_slot[bag] < 0)
        throw std::invalid_argument(std::string("ArrayPneumatics::") + what + ": bag " +
                                    std::to_string(bag) + " is not in the network");
    return m_slot[bag];
}

bool ArrayPneumatics::hasBag(int bag) const {
    return bag >= 0 && bag < int(m_slot.size()) && m_slot[bag] >= 0;
}

double ArrayPneumatics::readChannelSensor(int channel) const {
    const Channel& c = m_channels.at(channel);
    return c.sensor >= 0 ? m_net.getSensorReading(c.sensor) : 0.0;
}

double ArrayPneumatics::readBagSensor(int bag) const {
    return m_net.getSensorReading(m_bagSensor[bagSlot(bag, "readBagSensor")]);
}

double ArrayPneumatics::getBagMass(int bag) const {
    return m_net.getNodeState(m_net.getBagNode(bagSlot(bag, "getBagMass"))).mass;
}

double ArrayPneumatics::getChannelBagMass(int channel) const {
    double m = 0.0;
    for (int b : m_channels.at(channel).bags) m += getBagMass(b);
    return m;
}

BagFlow ArrayPneumatics::getBagFlow(int bag) const {
    BagFlow f;
    for (const auto& [l, sign] : m_bagLinks[bagSlot(bag, "getBagFlow")]) {
        const double q = sign * m_net.getLinkMassFlow(l);
        (q > 0.0 ? f.in : f.out) += std::abs(q);
    }
    return f;
}

double ArrayPneumatics::getManifoldPressure() const {
    return m_net.getNodeState(m_manifold).pressure - m_net.getGas().ambientPressure;
}

void ArrayPneumatics::saveState(bags::StateWriter& w) const {
    w.tag("array pneumatics");
    m_net.saveState(w);
    w.pod(m_time);
    w.pod(std::uint64_t(m_channels.size()));
    for (const Channel& c : m_channels) {
        w.str(c.name);
        w.pod(c.inflateOpen), w.pod(c.ventOpen);
    }
}

void ArrayPneumatics::loadState(bags::StateReader& r) {
    r.tag("array pneumatics");
    m_net.loadState(r);
    r.pod(m_time);
    const auto n = r.pod<std::uint64_t>();
    if (n != m_channels.size())
        bags::StateReader::mismatch("pneumatic channels", n, m_channels.size());
    for (Channel& c : m_channels) {
        const std::string name = r.str();
        if (name != c.name)
            throw bags::StateError("checkpoint: channel '" + name + "' where the scenario has '" +
                                   c.name + "'");
        r.pod(c.inflateOpen), r.pod(c.ventOpen);
    }
    m_savedTime = -1.0;  // the next step is a new one
}

}  // namespace cosim
