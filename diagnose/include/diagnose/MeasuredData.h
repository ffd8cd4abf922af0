#pragma once
/// @file Measured data of the seed's rig (one airbag, a block pressed into it, several gas
/// masses) as the lab records it, in SI: per test (one gas mass) the testing machine's
/// time/displacement/force, the pressure sensor's time/gauge pressure, the flowmeter's
/// time/gas mass and, when the rig has one, a bed gauge's time/sink. The folder format and its reader are io::readMeasuredData
/// (docs/measured-data.md); this is the plain data the diagnosis works on.

#include <string>
#include <vector>

namespace diagnose {

/// One instrument's samples: time [s] strictly increasing, value in SI.
struct Channel {
    std::vector<double> time;   ///< [s] from the start of the test
    std::vector<double> value;  ///< SI ([m], [N], [Pa], [kg])
    bool empty() const { return time.empty(); }
};

/// One loading-unloading test at one gas mass.
struct MeasuredTest {
    double gasMass = 0.0;  ///< [kg] as the flowmeter read it (the protocol's value)
    /// The stated standard uncertainty of that reading [kg] (the manifest's
    /// `gas_mass_uncertainty`, the test's or the protocol's); 0 when not stated.
    double gasMassUncertainty = 0.0;
    bool gasMassUncertaintyStated = false;
    /// Testing machine: displacement [m] (crosshead travel from first contact) and force [N]
    /// on one time base.
    std::vector<double> time, displacement, force;
    Channel pressure;   ///< gauge pressure of the bag [Pa]
    Channel flowmeter;  ///< gas mass in the bag as the flowmeter reads it [kg]
    /// The bed board's sink under the bag [m] as a gauge against the floor reads it (a dial
    /// gauge or displacement transducer under the board), from first contact; empty when the
    /// rig has no such gauge. It tells the bed's compliance from the machine's, which the
    /// other channels cannot (docs/diagnosis.md#the-bed-gauge).
    Channel bed;
};

/// The protocol the tests followed (what the simulation must repeat).
struct Protocol {
    double blockSize = 0.0;        ///< square block edge [m]
    double rate = 0.0;             ///< crosshead speed [m/s]
    double peakForce = 0.0;        ///< loading stops at this force [N]
    double roomTemperature = 0.0;  ///< [K] (the gas temperature of the test)
    /// The stated standard uncertainty of the room temperature [K] (the manifest's
    /// `room_temperature_uncertainty`); 0 when not stated.
    double roomTemperatureUncertainty = 0.0;
    bool roomTemperatureUncertaintyStated = false;
};

/// A measured stiffness curve k(m): the stiffness over the scenario's load range
/// (test.stiffness_range) at each gas mass, as a study reports it (a table, or a fitted
/// polynomial evaluated at the masses it names), with the stage it states for each mass.
struct StiffnessChannel {
    std::vector<double> gasMass;    ///< [kg] strictly increasing
    std::vector<double> stiffness;  ///< [N/m]
    std::vector<int> stage;         ///< 1, 2, 3, or 0 (not stated); empty if the file has none
    bool empty() const { return gasMass.empty(); }
};

/// A measured data set: the tests and what they correspond to.
struct MeasuredData {
    std::string folder;        ///< where it was read from
    std::string scenarioFile;  ///< path of the scenario it corresponds to
    std::string description;
    Protocol protocol;
    std::vector<MeasuredTest> tests;  ///< may be empty when a stiffness curve is given
    StiffnessChannel stiffness;       ///< empty unless the manifest names one
    std::string stiffnessFile;        ///< the stiffness curve's file as named in messages
};

}  // namespace diagnose
