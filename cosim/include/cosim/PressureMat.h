#pragma once
/// @file A virtual pressure mat: the membranes' nodal contact pressures gathered onto a grid of
/// sensels over the bed, as the mats clinicians lay under a patient read them.
///
/// Order of use per frame: clear(); addNodalPressures() for every bag (and every shape whose
/// pressure is wanted); read getPressure(). Each node's contact force p_i A_i (pressure times
/// its lumped reference area, exactly the force the contact law put on it) is shared among the
/// four sensels whose centres surround the node's (x, y), bilinearly; nodes between the outer
/// sensel centres and the mat's edge go to the edge sensels. The weights sum to one, so the
/// mat conserves force: the sum of sensel pressure times sensel area equals the sum of p_i A_i
/// over the nodes on the mat, to roundoff. Nodes off the mat are counted in getOffMatForce().
/// The sensel reads the nodal normal force, not its vertical part (a mat lies along the
/// surface it measures).

#include <Eigen/Core>

namespace cosim {

struct PressureMatOptions {
    int rows = 64;                                           ///< sensels along the bed (x)
    int columns = 32;                                        ///< sensels across the bed (y)
    Eigen::Vector2d origin = Eigen::Vector2d(-0.96, -0.40);  ///< [m] (x, y) of the mat's corner
    Eigen::Vector2d size = Eigen::Vector2d(1.92, 0.80);      ///< [m] extent along x and y
    void validate() const;  ///< throws std::invalid_argument naming the option
};

class PressureMat {
  public:
    /// @throws std::invalid_argument if the options are invalid.
    explicit PressureMat(const PressureMatOptions& options);
    /// Empties every sensel and the off-mat force.
    void clear();
    /// Adds nodal contact pressures [Pa] at nodal positions x (Ground, only x and y used) with
    /// lumped areas [m^2]. @throws std::invalid_argument if the sizes differ.
    void addNodalPressures(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& pressure,
                           const Eigen::VectorXd& nodalArea);
    /// Sensel pressures [Pa], rows (x) by columns (y); sensel (r, c) centred at
    /// origin + ((r + 1/2) pitch_x, (c + 1/2) pitch_y).
    const Eigen::MatrixXd& getPressure() const { return m_pressure; }
    double getSenselArea() const;  ///< [m^2]
    /// Sum of sensel pressure times sensel area [N].
    double calcTotalForce() const;
    /// Force [N] of the nodes that lay off the mat.
    double getOffMatForce() const { return m_offMat; }
    const PressureMatOptions& getOptions() const { return m_options; }

  private:
    PressureMatOptions m_options;
    Eigen::MatrixXd m_pressure;
    double m_offMat = 0.0;
};

}  // namespace cosim
