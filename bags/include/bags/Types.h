#pragma once
/// @file Common types of the bags library: vectors, the energy accumulator every physics term
/// adds into, and the numerical-failure error.
///
/// The airbag is solved as a minimisation of total potential energy over the 3N nodal
/// coordinates x (Ground frame, [m]). Every term (membrane elements, gas, contact) adds its
/// energy, gradient and Hessian into an EnergyAccumulator owned by the caller.

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <stdexcept>
#include <string>
#include <vector>

namespace bags {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;
using Triplet = Eigen::Triplet<double>;

/// Sums energy [J], gradient [N] and Hessian [N/m] contributions over the 3N dofs of a mesh.
/// Dof of node n, direction d (0=x,1=y,2=z) is 3*n+d. Terms add, never overwrite.
struct EnergyAccumulator {
    double energy = 0.0;        ///< [J]
    Eigen::VectorXd grad;       ///< dE/dx [N], size 3N
    std::vector<Triplet> hess;  ///< d2E/dx2 [N/m] as triplets (duplicates are summed)
    bool wantGradient = true;   ///< false: only energy is needed (line search)
    bool wantHessian = true;    ///< false: skip triplets
    /// Triplets [wideBegin, wideEnd) of `hess` couple nodes beyond the element's own (the
    /// bending stencil reaches the neighbouring triangles' far vertices); the solver may leave
    /// those couplings out of the matrix it factors (docs/solver.md).
    size_t wideBegin = 0, wideEnd = 0;

    explicit EnergyAccumulator(int numNodes = 0) : grad(Eigen::VectorXd::Zero(3 * numNodes)) {}

    void resize(int numNodes) {
        energy = 0.0;
        grad.setZero(3 * numNodes);
        hess.clear();
        wideBegin = wideEnd = 0;
    }
    void addGrad(int node, const Vec3& g) { grad.segment<3>(3 * node) += g; }
    /// Adds the 3x3 block d2E/dx_a dx_b (and nothing for (b,a): callers add both blocks).
    void addHessBlock(int a, int b, const Mat3& h) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (h(i, j) != 0.0) hess.emplace_back(3 * a + i, 3 * b + j, h(i, j));
    }
};

/// Numerical failure (inverted element, negative volume, no convergence). Carries where it
/// happened so the caller can cut the step and retry, or report it.
class NumericalError : public std::runtime_error {
  public:
    NumericalError(const std::string& what, double time = -1.0, int step = -1, int element = -1)
        : std::runtime_error(what), m_time(time), m_step(step), m_element(element) {}
    double getTime() const { return m_time; }     ///< simulated time [s], -1 if unknown
    int getStep() const { return m_step; }        ///< load step, -1 if unknown
    int getElement() const { return m_element; }  ///< element index, -1 if none
  private:
    double m_time;
    int m_step;
    int m_element;
};

}  // namespace bags
