#pragma once
/// @file One section of a bag's film across the bag, as a plane film of fixed rest length:
/// the first part of the film-section model the reduced bag needs
/// (docs/reduced-bag.md#a-film-section). Not yet used by cosim::ReducedBag.
///
/// In the (y, z) plane a film runs from anchor a to anchor b, stretched by its tension
/// T = EA (l / l0 - 1) per unit depth (EA the membrane stiffness [N/m]), pushed outwards by the
/// gas's gauge pressure P on the enclosed side (the region between the film and the chord
/// b -> a, to the film's right walking from a to b), kept out of rigid obstacles and above the
/// bed board z = 0 by penalty contact. Discretised as a chain of straight segments of equal
/// rest length; its equilibrium minimises the potential energy
///   Pi = sum_i EA (l_i - l0_i)^2 / (2 l0_i) - P A + sum_nodes k w e(pen),  e ~ pen^2 / 2,
/// A the enclosed area, pen a node's depth inside an obstacle or below the board, w its rest
/// tributary length, k the contact penalty [Pa/m] (its force k (pen - 5 um) beyond 10 um, rounded
/// below so that Newton's model is continuous). Free spans are then arcs of radius T / P;
/// where the film wraps a shape of radius rho its contact pressure is P + T / rho, and P on a
/// flat face (tests/cosim/FilmSectionTest.cpp).

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace cosim {

struct FilmSectionSpec {
    Eigen::Vector2d a = Eigen::Vector2d(-0.05, 0.0);  ///< first anchor (y, z) [m]
    Eigen::Vector2d b = Eigen::Vector2d(0.05, 0.0);   ///< second anchor [m]
    double restLength = 0.15;                         ///< [m]
    double stiffness = 1e4;                           ///< EA [N/m]
    int segments = 100;
    double contactPenalty = 1e8;  ///< [Pa/m]
    bool board = true;            ///< the bed board z >= 0
    /// @throws std::invalid_argument naming the member if a value is out of range.
    void validate() const;
};

class FilmSection {
  public:
    /// A rigid obstacle as its signed distance phi(p) (> 0 outside) with its gradient (the
    /// outward normal) and Hessian (dn/dp); n and dndp may be null (not wanted).
    using Obstacle =
        std::function<double(const Eigen::Vector2d& p, Eigen::Vector2d* n, Eigen::Matrix2d* dndp)>;

    /// The film starts as an arc of its rest length through the anchors, bulging to the
    /// enclosed side's outside (up for a left-to-right film).
    explicit FilmSection(const FilmSectionSpec& spec);
    void addObstacle(Obstacle obstacle);

    /// The equilibrium at gauge pressure P [Pa] > 0, from the current shape (Newton with a
    /// line search on Pi). Returns the Newton iterations.
    /// @throws std::runtime_error if it does not converge.
    int solve(double pressure);

    const Eigen::Matrix2Xd& getNodes() const { return m_x; }  ///< (y, z) per node [m]
    double calcArea() const;                                  ///< enclosed [m^2]
    double calcLength() const;                                ///< [m]
    Eigen::VectorXd calcTensions() const;                     ///< per segment [N/m]
    /// Per node: the contact pressure [Pa] of the obstacles and the board on the film (the
    /// penalty's force over the stretched film's tributary length).
    Eigen::VectorXd calcContactPressures() const;

    /// Pi at the free nodes' coordinates q (y1, z1, y2, z2, ...; the anchors fixed), its
    /// gradient and Hessian (for the solver and its tests).
    double calcEnergy(const Eigen::VectorXd& q, double pressure, Eigen::VectorXd* gradient,
                      Eigen::MatrixXd* hessian) const;
    Eigen::VectorXd getFreeCoordinates() const;

    /// The contact's energy per unit penalty and rest length at a depth pen > 0, and its
    /// first and second derivatives: pen^2 / 2 (a force k pen) rounded over the first
    /// kContactRounding so that its second derivative is continuous.
    static double calcContactLaw(double pen, double* d1, double* d2);
    static constexpr double kContactRounding = 1e-5;  ///< [m]

  private:
    Eigen::Matrix2Xd nodesOf(const Eigen::VectorXd& q) const;

    FilmSectionSpec m_spec;
    double m_l0 = 0.0;  // rest length of a segment
    Eigen::Matrix2Xd m_x;
    std::vector<Obstacle> m_obstacles;
};

}  // namespace cosim
