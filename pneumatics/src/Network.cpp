#include "pneumatics/Network.h"

#include <bags/Types.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "Check.h"

namespace pneumatics {

void VolumeSpec::validate(const std::string& name) const {
    checkParameter(std::isfinite(volume) && volume > 0.0, name, "volume", volume, "m^3",
                   "volume > 0 m^3");
    checkParameter(std::isfinite(pressure) && pressure > 0.0, name, "pressure", pressure,
                   "Pa (absolute)", "pressure > 0 Pa absolute");
    checkParameter(std::isfinite(temperature) && temperature > 0.0, name, "temperature",
                   temperature, "K", "temperature > 0 K");
    checkParameter(heatTransferCoefficient >= 0.0 && std::isfinite(heatTransferCoefficient), name,
                   "heatTransferCoefficient", heatTransferCoefficient, "W/(m^2 K)",
                   "h >= 0 W/(m^2 K) (still air on a film: about 5-25)");
    checkParameter(wallArea >= 0.0 && std::isfinite(wallArea), name, "wallArea", wallArea, "m^2",
                   "A >= 0 m^2");
    checkParameter(std::isfinite(wallTemperature) && wallTemperature > 0.0, name, "wallTemperature",
                   wallTemperature, "K", "Tw > 0 K");
}

void NetworkOptions::validate() const {
    const std::string name = "network options";
    checkParameter(std::isfinite(maxSubstep) && maxSubstep > 0.0, name, "maxSubstep", maxSubstep,
                   "s", "maxSubstep > 0 s (e.g. 1e-3 s)");
    checkParameter(tolerance > 0.0 && tolerance < 1e-3, name, "tolerance", tolerance, "(-)",
                   "0 < tolerance < 1e-3 (relative; default 1e-12)");
    checkParameter(maxIterations >= 1, name, "maxIterations", maxIterations, "(count)",
                   "maxIterations >= 1");
    checkParameter(maxCuts >= 0 && maxCuts <= 40, name, "maxCuts", maxCuts, "(count)",
                   "0 <= maxCuts <= 40");
}

/// What one backward-Euler sub-step holds fixed: its length, each node's volume at its start
/// and end, each valve's opening at its end.
struct Network::Substep {
    double h = 0.0;
    std::vector<double> volumeStart, volumeEnd;  // per node [m^3]
    std::vector<double> opening;                 // per link
};

Network::Network(const bags::GasOptions& gas, const NetworkOptions& options)
    : m_gas(gas), m_options(options) {
    gas.validate();
    options.validate();
    m_R = gas.getSpecificGasConstant();
    m_cv = m_R / (gas.gamma - 1.0);
    m_cp = gas.gamma * m_cv;
    addReservoir("ambient", gas.ambientPressure, gas.temperature);
}

int Network::addNode(Node node) {
    m_nodes.push_back(std::move(node));
    numberUnknowns();
    return int(m_nodes.size()) - 1;
}

int Network::addReservoir(const std::string& name, double pressure, double temperature) {
    checkParameter(std::isfinite(pressure) && pressure > 0.0, name, "pressure", pressure,
                   "Pa (absolute)", "pressure > 0 Pa absolute");
    checkParameter(std::isfinite(temperature) && temperature > 0.0, name, "temperature",
                   temperature, "K", "temperature > 0 K");
    Node n;
    n.name = name;
    n.reservoir = true;
    n.pressure = pressure;
    n.temperature = temperature;
    return addNode(n);
}

int Network::addVolume(const std::string& name, const VolumeSpec& spec) {
    spec.validate(name);
    Node n;
    n.name = name;
    n.spec = spec;
    n.volume = spec.volume;
    n.temperature = spec.thermal == Thermal::Isothermal ? spec.wallTemperature : spec.temperature;
    n.mass = spec.pressure * spec.volume / (m_R * n.temperature);
    return addNode(n);
}

int Network::addBag(const std::string& name, const VolumeSpec& spec) {
    const int node = addVolume(name, spec);
    m_nodes[node].bag = true;
    m_bags.push_back(node);
    return node;
}

void Network::numberUnknowns() {
    int k = 0;
    for (Node& n : m_nodes) n.massIndex = n.reservoir ? -1 : k++;
    for (Node& n : m_nodes)
        n.temperatureIndex = n.reservoir || n.spec.thermal == Thermal::Isothermal ? -1 : k++;
    m_numUnknowns = k;
}

void Network::checkNode(int node, const char* what) const {
    if (node < 0 || node >= getNumNodes()) {
        std::ostringstream s;
        s << what << ": node " << node << " is out of range; valid: 0 to " << getNumNodes() - 1;
        throw std::invalid_argument(s.str());
    }
}

void Network::checkLink(int link, const char* what) const {
    if (link < 0 || link >= getNumLinks()) {
        std::ostringstream s;
        s << what << ": link " << link << " is out of range; valid: 0 to " << getNumLinks() - 1;
        throw std::invalid_argument(s.str());
    }
}

Network::Link Network::makeLink(const std::string& name, LinkKind kind, int a, int b) {
    Link l;
    l.name = name;
    l.kind = kind;
    l.a = a;
    l.b = b;
    return l;
}

int Network::addLink(Link link) {
    checkNode(link.a, link.name.c_str());
    checkNode(link.b, link.name.c_str());
    if (link.a == link.b || (m_nodes[link.a].reservoir && m_nodes[link.b].reservoir))
        throw std::invalid_argument(link.name +
                                    ": a link joins two different nodes, one of them a volume");
    m_links.push_back(std::move(link));
    return int(m_links.size()) - 1;
}

int Network::addValve(const std::string& name, int a, int b, const ValveSpec& spec, bool open) {
    spec.validate(name);
    Link l = makeLink(name, LinkKind::Valve, a, b);
    l.valve = spec;
    l.opening = l.command = open ? 1.0 : 0.0;
    return addLink(l);
}

int Network::addVent(const std::string& name, int node, const ValveSpec& spec, bool open) {
    return addValve(name, node, getAmbient(), spec, open);
}

int Network::addPump(const std::string& name, int inlet, int outlet, const PumpSpec& spec,
                     double speed) {
    spec.validate(name);
    Link l = makeLink(name, LinkKind::Pump, inlet, outlet);
    l.pump = spec;
    const int link = addLink(l);
    setPumpSpeed(link, speed);
    return link;
}

int Network::addOrifice(const std::string& name, int a, int b, const bags::OrificeOptions& spec) {
    spec.validate();
    Link l = makeLink(name, LinkKind::Orifice, a, b);
    l.orifice = spec;
    return addLink(l);
}

void Network::setValveOpen(int link, bool open) {
    checkLink(link, "setValveOpen");
    if (m_links[link].kind != LinkKind::Valve)
        throw std::invalid_argument("setValveOpen: '" + m_links[link].name + "' is no valve");
    m_links[link].command = open ? 1.0 : 0.0;
}

void Network::setPumpSpeed(int link, double speed) {
    checkLink(link, "setPumpSpeed");
    if (m_links[link].kind != LinkKind::Pump)
        throw std::invalid_argument("setPumpSpeed: '" + m_links[link].name + "' is no pump");
    checkParameter(speed >= 0.0 && speed <= 1.0, m_links[link].name, "speed", speed, "(-)",
                   "0 <= speed <= 1 (0: off)");
    m_links[link].speed = speed;
}

int Network::addPressureSensor(int node, const SensorSpec& spec) {
    checkNode(node, "addPressureSensor");
    spec.validate("sensor on '" + m_nodes[node].name + "'");
    Sensor s;
    s.node = node;
    s.spec = spec;
    s.lag = getNodeState(node).pressure - m_gas.ambientPressure;
    s.rng.seed(spec.seed);
    s.reading = s.lag + spec.offset;
    m_sensors.push_back(s);
    return int(m_sensors.size()) - 1;
}

int Network::addFlowmeter(int link) {
    checkLink(link, "addFlowmeter");
    Meter m;
    m.link = link;
    m_meters.push_back(m);
    return int(m_meters.size()) - 1;
}

// --- the implicit step

double Network::calcTemperature(const Node& n, const Eigen::VectorXd& x) const {
    return n.temperatureIndex >= 0 ? x[n.temperatureIndex] : n.temperature;
}

double Network::calcMass(const Node& n, const Eigen::VectorXd& x) const {
    return n.massIndex >= 0 ? x[n.massIndex] : 0.0;
}

Flow Network::calcLinkFlow(const Link& l, double opening, const Eigen::VectorXd& x,
                           const std::vector<double>& V) const {
    const Node &na = m_nodes[l.a], &nb = m_nodes[l.b];
    const double Ta = calcTemperature(na, x), Tb = calcTemperature(nb, x);
    const double pa = na.reservoir ? na.pressure : calcMass(na, x) * m_R * Ta / V[l.a];
    const double pb = nb.reservoir ? nb.pressure : calcMass(nb, x) * m_R * Tb / V[l.b];
    switch (l.kind) {
        case LinkKind::Valve:
            return calcValveFlow(l.valve, opening, pa, Ta, pb, Tb);
        case LinkKind::Pump:
            return calcPumpFlow(l.pump, l.speed, pa, pb);
        case LinkKind::Orifice:
            return calcOrificeFlow(l.orifice, m_R, pa, Ta, pb, Tb);
    }
    return Flow();
}

Eigen::VectorXd Network::getUnknowns() const {
    Eigen::VectorXd x(m_numUnknowns);
    for (const Node& n : m_nodes) {
        if (n.massIndex >= 0) x[n.massIndex] = n.mass;
        if (n.temperatureIndex >= 0) x[n.temperatureIndex] = n.temperature;
    }
    return x;
}

Eigen::VectorXd Network::calcResidual(const Substep& s, const Eigen::VectorXd& x,
                                      Eigen::MatrixXd* J) const {
    const int N = m_numUnknowns;
    Eigen::VectorXd R = Eigen::VectorXd::Zero(N);
    if (J) J->setZero(N, N);
    for (int i = 0; i < getNumNodes(); ++i) {
        const Node& n = m_nodes[i];
        if (n.reservoir) continue;
        const int im = n.massIndex, iT = n.temperatureIndex;
        R[im] = x[im] - n.mass;
        if (J) (*J)(im, im) += 1.0;
        if (iT < 0) continue;
        // Energy: cv (m T - m0 T0) + p dV - h hA (Tw - T) - h sum(enthalpy in - out) = 0.
        const double m = x[im], T = x[iT], dV = s.volumeEnd[i] - s.volumeStart[i];
        const double hA = n.spec.thermal == Thermal::HeatExchange
                              ? n.spec.heatTransferCoefficient * n.spec.wallArea
                              : 0.0;
        const double work = m_R * dV / s.volumeEnd[i];  // p dV = m T work
        R[iT] = m_cv * (m * T - n.mass * n.temperature) + m * T * work -
                s.h * hA * (n.spec.wallTemperature - T);
        if (J) {
            (*J)(iT, im) += (m_cv + work) * T;
            (*J)(iT, iT) += (m_cv + work) * m + s.h * hA;
        }
    }
    for (int k = 0; k < getNumLinks(); ++k) {
        const Link& l = m_links[k];
        const Flow f = calcLinkFlow(l, s.opening[k], x, s.volumeEnd);
        const double q = f.massFlow;
        const Node& up = m_nodes[q >= 0.0 ? l.a : l.b];
        const double TUp = calcTemperature(up, x);
        const double H = m_cp * q * TUp;  // enthalpy flow a to b [W]
        // d(q)/d(unknowns) through one port: p = m R T / V.
        struct Entry {
            int index;
            double dq;
        };
        Entry d[4];
        int nd = 0;
        auto addPort = [&](int node, double dp, double dT) {
            const Node& n = m_nodes[node];
            if (n.reservoir) return;
            const double T = calcTemperature(n, x), V = s.volumeEnd[node];
            d[nd++] = {n.massIndex, dp * m_R * T / V};
            if (n.temperatureIndex >= 0)
                d[nd++] = {n.temperatureIndex, dp * calcMass(n, x) * m_R / V + dT};
        };
        addPort(l.a, f.dpa, f.dTa);
        addPort(l.b, f.dpb, f.dTb);
        // Node a loses h q and h H, node b gains them.
        for (int side = 0; side < 2; ++side) {
            const Node& n = m_nodes[side == 0 ? l.a : l.b];
            if (n.reservoir) continue;
            const double sign = side == 0 ? 1.0 : -1.0;
            R[n.massIndex] += sign * s.h * q;
            if (n.temperatureIndex >= 0) R[n.temperatureIndex] += sign * s.h * H;
            if (!J) continue;
            for (int e = 0; e < nd; ++e) {
                (*J)(n.massIndex, d[e].index) += sign * s.h * d[e].dq;
                if (n.temperatureIndex >= 0)
                    (*J)(n.temperatureIndex, d[e].index) += sign * s.h * m_cp * d[e].dq * TUp;
            }
            if (n.temperatureIndex >= 0 && up.temperatureIndex >= 0)
                (*J)(n.temperatureIndex, up.temperatureIndex) += sign * s.h * m_cp * q;
        }
    }
    return R;
}

Eigen::VectorXd Network::calcSubstepResidual(double h, const std::vector<double>& bagVolumesEnd,
                                             const Eigen::VectorXd& x, Eigen::MatrixXd* J) const {
    if (int(bagVolumesEnd.size()) != getNumBags() || x.size() != m_numUnknowns)
        throw std::invalid_argument("calcSubstepResidual: one volume per bag, one x per unknown");
    Substep s;
    s.h = h;
    for (const Node& n : m_nodes) s.volumeStart.push_back(n.volume);
    s.volumeEnd = s.volumeStart;
    for (int b = 0; b < getNumBags(); ++b) s.volumeEnd[m_bags[b]] = bagVolumesEnd[b];
    for (const Link& l : m_links) s.opening.push_back(l.opening);
    return calcResidual(s, x, J);
}

bool Network::solveSubstep(const Substep& s, Eigen::VectorXd* x, int* iterations) const {
    Eigen::MatrixXd J;
    for (int it = 1; it <= m_options.maxIterations; ++it) {
        *iterations = it;
        const Eigen::VectorXd R = calcResidual(s, *x, &J);
        const Eigen::VectorXd dx = J.partialPivLu().solve(-R);
        if (!dx.allFinite()) return false;
        // Keep every mass and temperature above a tenth of its value (Newton from far off
        // may overshoot through zero where the flows are steep).
        double alpha = 1.0, change = 0.0;
        for (int i = 0; i < dx.size(); ++i) {
            const double xi = (*x)[i];
            if (xi + dx[i] < 0.1 * xi) alpha = std::min(alpha, 0.9 * xi / -dx[i]);
        }
        for (const Node& n : m_nodes) {
            if (n.massIndex >= 0) change = std::max(change, std::abs(dx[n.massIndex]) / n.mass);
            if (n.temperatureIndex >= 0)
                change = std::max(change, std::abs(dx[n.temperatureIndex]) / n.temperature);
        }
        *x += alpha * dx;
        if (alpha == 1.0 && change <= m_options.tolerance) return true;
    }
    return false;
}

void Network::takeSubstep(double h, const std::vector<BagVolume>& bags, double t0) {
    Substep s;
    s.h = h;
    for (const Node& n : m_nodes) s.volumeStart.push_back(n.volume);
    s.volumeEnd = s.volumeStart;
    for (int b = 0; b < getNumBags(); ++b) {
        const double V = bags[b].volume + bags[b].rate * (t0 + h);
        if (!(V > 0.0))
            throw bags::NumericalError(
                "pneumatics: bag '" + m_nodes[m_bags[b]].name + "' volume would not be positive",
                m_time + t0 + h);
        s.volumeEnd[m_bags[b]] = V;
    }
    for (const Link& l : m_links) {
        const double rate = l.valve.openingTime > 0.0 ? h / l.valve.openingTime : 1.0;
        s.opening.push_back(l.command > l.opening ? std::min(l.command, l.opening + rate)
                                                  : std::max(l.command, l.opening - rate));
    }
    Eigen::VectorXd x = getUnknowns();
    int iterations = 0;
    const bool ok = solveSubstep(s, &x, &iterations);
    m_summary.newtonIterations += iterations;
    if (!ok) {
        if (m_summary.cuts >= m_options.maxCuts)
            throw bags::NumericalError("pneumatics: a sub-step did not converge after " +
                                           std::to_string(m_options.maxCuts) + " halvings",
                                       m_time + t0);
        ++m_summary.cuts;
        takeSubstep(0.5 * h, bags, t0);
        takeSubstep(0.5 * h, bags, t0 + 0.5 * h);
        return;
    }
    ++m_summary.substeps;
    std::vector<double> gaugeStart;
    for (const Sensor& sn : m_sensors)
        gaugeStart.push_back(getNodeState(sn.node).pressure - m_gas.ambientPressure);
    // Move the mass as signed transfers at the converged state: conserved to roundoff.
    std::vector<double> mass(getNumNodes());
    for (int i = 0; i < getNumNodes(); ++i) mass[i] = m_nodes[i].mass;
    for (int k = 0; k < getNumLinks(); ++k) {
        Link& l = m_links[k];
        const double dm = h * calcLinkFlow(l, s.opening[k], x, s.volumeEnd).massFlow;
        mass[l.a] -= dm;
        mass[l.b] += dm;
        m_stepTransfer[k] += dm;
        l.opening = s.opening[k];
    }
    for (int i = 0; i < getNumNodes(); ++i) {
        Node& n = m_nodes[i];
        if (n.reservoir) {
            n.received += mass[i];
            continue;
        }
        if (!(mass[i] > 0.0))
            throw bags::NumericalError("pneumatics: volume '" + n.name + "' lost all its gas",
                                       m_time + t0 + h);
        n.mass = mass[i];
        n.temperature = calcTemperature(n, x);
        n.volume = s.volumeEnd[i];
    }
    for (size_t k = 0; k < m_sensors.size(); ++k) {
        Sensor& sn = m_sensors[k];
        const double gauge = getNodeState(sn.node).pressure - m_gas.ambientPressure;
        sn.lag = calcFirstOrderLag(sn.lag, gaugeStart[k], gauge, h, sn.spec.timeConstant);
    }
}

std::vector<double> Network::step(double dt, const std::vector<BagVolume>& bags) {
    if (!(dt > 0.0 && std::isfinite(dt)))
        throw std::invalid_argument("pneumatics step: dt = " + std::to_string(dt) +
                                    " s is invalid; valid: dt > 0 s");
    if (int(bags.size()) != getNumBags())
        throw std::invalid_argument("pneumatics step: " + std::to_string(bags.size()) +
                                    " bag volumes for " + std::to_string(getNumBags()) +
                                    " bags; give one per bag, in the order added");
    for (int b = 0; b < getNumBags(); ++b) {
        checkParameter(std::isfinite(bags[b].volume) && bags[b].volume > 0.0,
                       m_nodes[m_bags[b]].name, "volume", bags[b].volume, "m^3", "volume > 0 m^3");
        checkParameter(std::isfinite(bags[b].rate), m_nodes[m_bags[b]].name, "rate", bags[b].rate,
                       "m^3/s", "a finite rate in m^3/s");
        m_nodes[m_bags[b]].volume = bags[b].volume;
    }
    const std::vector<Node> nodes = m_nodes;
    const std::vector<Link> links = m_links;
    const std::vector<Sensor> sensors = m_sensors;
    m_summary = StepSummary();
    m_stepTransfer.assign(getNumLinks(), 0.0);
    const int n = std::max(1, int(std::ceil(dt / m_options.maxSubstep * (1.0 - 1e-12))));
    const double h = dt / n;
    try {
        for (int k = 0; k < n; ++k) takeSubstep(h, bags, k * h);
    } catch (...) {
        m_nodes = nodes;
        m_links = links;
        m_sensors = sensors;
        throw;
    }
    std::vector<double> flows(getNumBags());
    for (int b = 0; b < getNumBags(); ++b)
        flows[b] = (m_nodes[m_bags[b]].mass - nodes[m_bags[b]].mass) / dt;
    for (int k = 0; k < getNumLinks(); ++k) m_links[k].lastFlow = m_stepTransfer[k] / dt;
    for (Meter& m : m_meters) {
        m.mass += m_stepTransfer[m.link];
        m.flow = m_links[m.link].lastFlow;
    }
    for (Sensor& sn : m_sensors) {
        double noise = 0.0;
        if (sn.spec.noiseStdDev > 0.0)
            noise = std::normal_distribution<double>(0.0, sn.spec.noiseStdDev)(sn.rng);
        sn.reading = sn.lag + sn.spec.offset + noise;
    }
    // Neumaier-compensated sum, so that many small steps add up to their total time.
    const double t = m_time + dt;
    m_timeCompensation += std::abs(m_time) >= dt ? (m_time - t) + dt : (dt - t) + m_time;
    m_time = t;
    return flows;
}

// --- read back

int Network::getBagNode(int bag) const {
    if (bag < 0 || bag >= getNumBags())
        throw std::invalid_argument("getBagNode: bag " + std::to_string(bag) + " out of range");
    return m_bags[bag];
}

NodeState Network::getNodeState(int node) const {
    checkNode(node, "getNodeState");
    const Node& n = m_nodes[node];
    NodeState s;
    s.temperature = n.temperature;
    if (n.reservoir) {
        s.pressure = n.pressure;
        return s;
    }
    s.mass = n.mass;
    s.volume = n.volume;
    s.pressure = n.mass * m_R * n.temperature / n.volume;
    return s;
}

const std::string& Network::getNodeName(int node) const {
    checkNode(node, "getNodeName");
    return m_nodes[node].name;
}

const std::string& Network::getLinkName(int link) const {
    checkLink(link, "getLinkName");
    return m_links[link].name;
}

void Network::setNodeGas(int node, double mass, double temperature) {
    checkNode(node, "setNodeGas");
    Node& n = m_nodes[node];
    if (n.reservoir) throw std::invalid_argument("setNodeGas: '" + n.name + "' is a reservoir");
    checkParameter(std::isfinite(mass) && mass > 0.0, n.name, "mass", mass, "kg", "mass > 0 kg");
    checkParameter(std::isfinite(temperature) && temperature > 0.0, n.name, "temperature",
                   temperature, "K", "temperature > 0 K");
    n.mass = mass;
    if (n.temperatureIndex >= 0) n.temperature = temperature;
}

double Network::calcVolumeMass() const {
    double m = 0.0;
    for (const Node& n : m_nodes) m += n.mass;
    return m;
}

double Network::getReservoirMassReceived(int node) const {
    checkNode(node, "getReservoirMassReceived");
    return m_nodes[node].received;
}

double Network::getLinkMassFlow(int link) const {
    checkLink(link, "getLinkMassFlow");
    return m_links[link].lastFlow;
}

double Network::getValveOpening(int link) const {
    checkLink(link, "getValveOpening");
    return m_links[link].opening;
}

double Network::getSensorReading(int sensor) const { return m_sensors.at(sensor).reading; }
double Network::getSensorLagState(int sensor) const { return m_sensors.at(sensor).lag; }
void Network::setSensorLagState(int sensor, double value) {
    Sensor& s = m_sensors.at(sensor);
    s.lag = value;
    s.reading = value + s.spec.offset;
}
double Network::getFlowmeterMass(int meter) const { return m_meters.at(meter).mass; }
double Network::getFlowmeterFlow(int meter) const { return m_meters.at(meter).flow; }

void Network::saveState(bags::StateWriter& w) const {
    w.tag("pneumatic network");
    w.pod(std::uint64_t(m_nodes.size()));
    for (const Node& n : m_nodes) {
        w.str(n.name);
        w.pod(n.mass), w.pod(n.temperature), w.pod(n.volume), w.pod(n.pressure), w.pod(n.received);
    }
    w.pod(std::uint64_t(m_links.size()));
    for (const Link& l : m_links) {
        w.str(l.name);
        w.pod(l.opening), w.pod(l.command), w.pod(l.speed), w.pod(l.lastFlow);
    }
    w.pod(std::uint64_t(m_sensors.size()));
    for (const Sensor& s : m_sensors) {
        w.pod(s.lag), w.pod(s.reading);
        w.rng(s.rng);
    }
    w.pod(std::uint64_t(m_meters.size()));
    for (const Meter& m : m_meters) w.pod(m.mass), w.pod(m.flow);
    w.pod(m_time), w.pod(m_timeCompensation);
    w.pod(m_summary);
    w.vec(m_stepTransfer);
}

void Network::loadState(bags::StateReader& r) {
    r.tag("pneumatic network");
    auto count = [&](size_t expected, const char* what) {
        const auto n = r.pod<std::uint64_t>();
        if (n != expected) bags::StateReader::mismatch(what, n, expected);
    };
    count(m_nodes.size(), "nodes of the pneumatic network");
    for (Node& n : m_nodes) {
        const std::string name = r.str();
        if (name != n.name)
            throw bags::StateError("checkpoint: pneumatic node '" + name +
                                   "' where the model has '" + n.name + "'");
        r.pod(n.mass), r.pod(n.temperature), r.pod(n.volume), r.pod(n.pressure), r.pod(n.received);
    }
    count(m_links.size(), "links of the pneumatic network");
    for (Link& l : m_links) {
        const std::string name = r.str();
        if (name != l.name)
            throw bags::StateError("checkpoint: pneumatic link '" + name +
                                   "' where the model has '" + l.name + "'");
        r.pod(l.opening), r.pod(l.command), r.pod(l.speed), r.pod(l.lastFlow);
    }
    count(m_sensors.size(), "pressure sensors");
    for (Sensor& s : m_sensors) {
        r.pod(s.lag), r.pod(s.reading);
        r.rng(s.rng);
    }
    count(m_meters.size(), "flowmeters");
    for (Meter& m : m_meters) r.pod(m.mass), r.pod(m.flow);
    r.pod(m_time), r.pod(m_timeCompensation);
    r.pod(m_summary);
    r.vec(m_stepTransfer);
}

}  // namespace pneumatics
