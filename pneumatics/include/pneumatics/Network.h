#pragma once
/// @file A pneumatic network: gas volumes (bags, a manifold, rigid tanks) and reservoirs
/// (the ambient air, a constant-pressure supply) joined by valves, vents, pumps and orifices,
/// with pressure sensors on volumes and flowmeters on components.
///
/// Order of use:
///   1. Network(gas); addReservoir/addVolume/addBag for the nodes (node 0 is the ambient air);
///      addValve/addVent/addPump/addOrifice for the links; addPressureSensor/addFlowmeter.
///   2. In the time loop: setValveOpen/setPumpSpeed as a controller commands, then
///      step(dt, bagVolumes), which returns each bag's mean mass flow over the step [kg/s]
///      (what bags::Airbag::setMassFlow takes for the same step); read the sensors, the
///      flowmeters and the node states.
///
/// Integration: backward Euler over sub-steps of at most NetworkOptions::maxSubstep, each solved by
/// Newton with the analytic Jacobian (dense; networks have tens of nodes). Why implicit: a
/// manifold of a few mL behind a valve of 1 dm^3/(s bar) relaxes in about 1 ms, and as two
/// pressures equalise the valve's tangent grows without bound (ISO 6358's square root), so
/// an explicit scheme would need sub-steps far below the co-simulation's 1-10 ms; backward
/// Euler is L-stable and, with the orifice/laminar ends monotone, does not overshoot an
/// equalising pressure at any step. Mass is conserved by construction: each link moves
/// h q_l from one node to the other, q_l evaluated at the converged state, so the sum over
/// volumes plus what the reservoirs received changes only by roundoff.

#include <bags/Gas.h>

#include <Eigen/Core>
#include <random>
#include <string>
#include <vector>

#include "pneumatics/Components.h"

namespace pneumatics {

/// How a gas volume exchanges heat with its wall.
enum class Thermal {
    Isothermal,    ///< the gas stays at the wall temperature
    Adiabatic,     ///< no heat through the wall
    HeatExchange,  ///< heat hA (Tw - T) [W] through the wall
};

/// A gas volume: a bag (its volume comes with each step), a manifold or a rigid tank.
struct VolumeSpec {
    double volume = 1.0e-3;       ///< [m^3] (bags: the volume before the first step)
    double pressure = 1.0e5;      ///< [Pa] absolute, initial
    double temperature = 296.15;  ///< [K] initial gas temperature
    Thermal thermal = Thermal::Isothermal;
    double heatTransferCoefficient = 0.0;  ///< h [W/(m^2 K)] (HeatExchange)
    double wallArea = 0.0;                 ///< A [m^2] (HeatExchange)
    double wallTemperature = 296.15;       ///< Tw [K] (Isothermal: the gas temperature)
    /// @throws std::invalid_argument naming the parameter, its unit and the valid range.
    void validate(const std::string& name = "volume") const;
};

/// State of one node.
struct NodeState {
    double mass = 0.0;         ///< [kg] (reservoirs: 0)
    double pressure = 0.0;     ///< [Pa] absolute
    double temperature = 0.0;  ///< [K]
    double volume = 0.0;       ///< [m^3] (reservoirs: 0)
};

/// A bag's volume at the start of a step and its rate over the step.
struct BagVolume {
    double volume = 0.0;  ///< [m^3] at the step's start
    double rate = 0.0;    ///< dV/dt [m^3/s], held over the step
};

/// What the last step() did.
struct StepSummary {
    int substeps = 0;          ///< backward-Euler sub-steps taken (cuts included)
    int newtonIterations = 0;  ///< summed over the sub-steps
    int cuts = 0;              ///< sub-steps halved after a failed Newton solve
};

/// How the network integrates.
struct NetworkOptions {
    double maxSubstep = 1.0e-3;  ///< [s] longest backward-Euler sub-step
    double tolerance = 1.0e-12;  ///< relative Newton tolerance on mass and temperature
    int maxIterations = 30;      ///< Newton iterations before a sub-step is halved
    int maxCuts = 12;            ///< halvings before a step fails
    /// @throws std::invalid_argument naming the option, its unit and the valid range.
    void validate() const;
};

class Network {
  public:
    /// The ambient air (gas.ambientPressure, gas.temperature) is node 0.
    explicit Network(const bags::GasOptions& gas, const NetworkOptions& options = NetworkOptions());

    // --- nodes
    int getAmbient() const { return 0; }
    /// A reservoir held at pressure [Pa] absolute and temperature [K] (a supply line).
    int addReservoir(const std::string& name, double pressure, double temperature);
    /// A rigid volume (manifold, tank).
    int addVolume(const std::string& name, const VolumeSpec& spec);
    /// A bag: its volume is given with each step. Bags are numbered in the order added.
    int addBag(const std::string& name, const VolumeSpec& spec);

    // --- links (mass flow positive from a to b); each returns the link's index
    int addValve(const std::string& name, int a, int b, const ValveSpec& spec, bool open);
    /// A valve from `node` to the ambient air.
    int addVent(const std::string& name, int node, const ValveSpec& spec, bool open);
    /// A pump from inlet to outlet, running at `speed` in [0, 1].
    int addPump(const std::string& name, int inlet, int outlet, const PumpSpec& spec, double speed);
    int addOrifice(const std::string& name, int a, int b, const bags::OrificeOptions& spec);

    /// Commands a valve (or vent) open or closed; it moves there over its opening time.
    void setValveOpen(int link, bool open);
    void setPumpSpeed(int link, double speed);

    // --- instruments
    /// A pressure sensor on a volume; its lag starts settled at the current gauge pressure.
    int addPressureSensor(int node, const SensorSpec& spec);
    /// A flowmeter on a link: the mass through it a to b [kg] from now on.
    int addFlowmeter(int link);

    // --- time loop
    /// Advances the network by dt [s] with each bag's volume and rate (one per bag, in the
    /// order added) and returns each bag's mean mass flow in [kg/s] over the step: exactly
    /// the mass it gained divided by dt.
    /// @throws std::invalid_argument for dt <= 0, a wrong count or a non-positive volume;
    /// bags::NumericalError (the network left at its state before the step) if a sub-step
    /// fails after maxCuts halvings or a volume would lose all its gas.
    std::vector<double> step(double dt, const std::vector<BagVolume>& bags);

    // --- read back
    int getNumNodes() const { return int(m_nodes.size()); }
    int getNumLinks() const { return int(m_links.size()); }
    int getNumBags() const { return int(m_bags.size()); }
    int getBagNode(int bag) const;  ///< the node of the bag'th bag
    NodeState getNodeState(int node) const;
    const std::string& getNodeName(int node) const;
    const std::string& getLinkName(int link) const;
    /// Sets a volume's gas mass [kg] and temperature [K] (e.g. to the bag's own gas).
    void setNodeGas(int node, double mass, double temperature);
    double getTime() const { return m_time + m_timeCompensation; }  ///< [s]
    /// Mass [kg] in all volumes.
    double calcVolumeMass() const;
    /// Net mass [kg] a reservoir has received since the start (negative: delivered).
    double getReservoirMassReceived(int node) const;
    /// Mean mass flow [kg/s] through a link, a to b, over the last step.
    double getLinkMassFlow(int link) const;
    /// The valve's opening in [0, 1].
    double getValveOpening(int link) const;
    /// Sensor reading [Pa] gauge: lagged pressure + offset + the noise drawn at the last step.
    double getSensorReading(int sensor) const;
    /// The sensor's lag state [Pa] gauge, without offset and noise.
    double getSensorLagState(int sensor) const;
    /// Sets the sensor's lag state [Pa] gauge (e.g. a sensor not yet settled).
    void setSensorLagState(int sensor, double value);
    /// Mass [kg] through the flowmeter's link, a to b, since it was added.
    double getFlowmeterMass(int meter) const;
    /// Mean mass flow [kg/s] through the flowmeter's link over the last step.
    double getFlowmeterFlow(int meter) const;
    const StepSummary& getLastStepSummary() const { return m_summary; }
    const bags::GasOptions& getGas() const { return m_gas; }

    // --- verification of the implicit step
    /// The unknowns of a sub-step: per volume its mass [kg], then per non-isothermal volume
    /// its temperature [K], at the current state.
    Eigen::VectorXd getUnknowns() const;
    /// The backward-Euler residual of a sub-step of length h [s] from the current state to
    /// the unknowns x, the bags at volumes bagVolumesEnd [m^3] at its end, and (if J) its
    /// Jacobian dR/dx, the tangent the Newton solve uses. Rows: mass [kg], energy [J].
    Eigen::VectorXd calcSubstepResidual(double h, const std::vector<double>& bagVolumesEnd,
                                        const Eigen::VectorXd& x, Eigen::MatrixXd* J) const;

    // --- checkpoints (bags/StateStream.h)
    /// Writes the network's state (every node's gas, every link's opening, command, speed and
    /// last flow, the sensors' lag, reading and random generator, the flowmeters, the time).
    void saveState(bags::StateWriter& w) const;
    /// Reads what saveState() wrote into a network built the same way.
    /// @throws bags::StateError if its nodes, links, sensors or meters differ.
    void loadState(bags::StateReader& r);

  private:
    struct Node {
        std::string name;
        bool reservoir = false;
        bool bag = false;
        VolumeSpec spec;
        double mass = 0.0;                          // [kg]
        double temperature = 0.0;                   // [K]
        double volume = 0.0;                        // [m^3]
        double pressure = 0.0;                      // reservoirs: fixed [Pa]
        double received = 0.0;                      // reservoirs: net mass received [kg]
        int massIndex = -1, temperatureIndex = -1;  // in the unknowns, -1: none
    };
    enum class LinkKind { Valve, Pump, Orifice };
    struct Link {
        std::string name;
        LinkKind kind = LinkKind::Valve;
        int a = 0, b = 0;
        ValveSpec valve;
        PumpSpec pump;
        bags::OrificeOptions orifice;
        double opening = 0.0, command = 0.0;  // valve [0, 1]
        double speed = 0.0;                   // pump [0, 1]
        double lastFlow = 0.0;                // [kg/s] mean over the last step
    };
    struct Sensor {
        int node = 0;
        SensorSpec spec;
        double lag = 0.0;      // [Pa] gauge
        double reading = 0.0;  // [Pa]
        std::mt19937_64 rng;
    };
    struct Meter {
        int link = 0;
        double mass = 0.0;  // [kg]
        double flow = 0.0;  // [kg/s]
    };
    struct Substep;  // volumes and openings of one sub-step

    int addNode(Node node);
    static Link makeLink(const std::string& name, LinkKind kind, int a, int b);
    int addLink(Link link);
    void checkNode(int node, const char* what) const;
    void checkLink(int link, const char* what) const;
    void numberUnknowns();
    double calcTemperature(const Node& n, const Eigen::VectorXd& x) const;
    double calcMass(const Node& n, const Eigen::VectorXd& x) const;
    Flow calcLinkFlow(const Link& l, double opening, const Eigen::VectorXd& x,
                      const std::vector<double>& V) const;
    Eigen::VectorXd calcResidual(const Substep& s, const Eigen::VectorXd& x,
                                 Eigen::MatrixXd* J) const;
    bool solveSubstep(const Substep& s, Eigen::VectorXd* x, int* iterations) const;
    void takeSubstep(double h, const std::vector<BagVolume>& bags, double t0);

    bags::GasOptions m_gas;
    NetworkOptions m_options;
    double m_R = 0.0, m_cv = 0.0, m_cp = 0.0;  // [J/(kg K)]
    std::vector<Node> m_nodes;
    std::vector<Link> m_links;
    std::vector<int> m_bags;  // node of each bag
    std::vector<Sensor> m_sensors;
    std::vector<Meter> m_meters;
    int m_numUnknowns = 0;
    double m_time = 0.0, m_timeCompensation = 0.0;
    StepSummary m_summary;
    std::vector<double> m_stepTransfer;  // per link, mass a to b in the current step [kg]
};

}  // namespace pneumatics
