#pragma once
/// @file The airbag's quasi-static Newton solver. solveEquilibrium() minimises a
/// MembraneModel's energy over the free dofs with Newton's method: a sparse factorisation of
/// the membrane + contact + pressure tangent, the dense rank-one gas terms added through
/// Sherman-Morrison-Woodbury (so the solve stays sparse), a backtracking line search, and a
/// pseudo-transient shift when the tangent is not positive definite or Newton stalls.

#include <bags/MembraneModel.h>

#include <functional>
#include <memory>

namespace bags {

struct SolverOptions {
    double relativeTolerance = 1e-8;     ///< |r| / |f_ref| to converge
    double absoluteTolerance = 1e-7;     ///< [N] |r| to converge regardless
    int maxIterations = 60;              ///< Newton iterations per solve
    double pseudoTransientShift = 1e-3;  ///< initial shift, as a fraction of mean tangent diagonal
    double maxStep = 0.0;                ///< [m] largest nodal move per iteration (0: no limit)
    /// Solve Newton systems by conjugate gradients preconditioned with the last factorisation
    /// (kept in a SolverWorkspace across iterations and solves); refactor only when that
    /// takes more than maxKrylovIterations.
    bool reuseFactorization = true;
    int maxKrylovIterations = 40;
    double krylovTolerance = 1e-4;  ///< tightest relative residual of the inner linear solve
    /// With a bending term: factor the tangent without the bending couplings between nodes
    /// that share no element (each dropped entry's magnitude added to its two diagonal
    /// entries, so the factored matrix stays positive definite) and solve the exact tangent
    /// by CG preconditioned with it. The bending stencil otherwise makes each factorisation
    /// about 6 times dearer (docs/performance.md).
    bool sparsifyWideCouplings = true;
    int maxSparsifiedKrylovIterations = 150;  ///< CG iterations on a fresh sparsified factor
    /// Inexact Newton: the Newton system is solved by CG on the exact tangent only to this
    /// relative residual (tighter near convergence, never below krylovTolerance),
    /// preconditioned by a factorisation whose diagonal is raised just enough to factor; the
    /// tangent itself is shifted (pseudo-transient) only where CG meets negative curvature.
    double forcingTerm = 0.1;
    /// [N] If Newton stalls (non-smooth contact: the residual stops falling for 8 iterations)
    /// below this residual, the state is accepted and SolveSummary::stalled is set. 0: never.
    double acceptableResidual = 0.0;
    /// Observer of each Newton iteration (iteration, residual [N], step length, shift [N/m]);
    /// for diagnostics, the library itself prints nothing.
    std::function<void(int, double, double, double)> monitor;
    void validate() const;  ///< throws std::invalid_argument naming the option
};

struct SolveSummary {
    bool converged = false;
    int iterations = 0;
    int factorizations = 0;
    double residualNorm = 0.0;  ///< [N] free-dof residual at exit
    double energy = 0.0;        ///< [J] at exit
    int shiftedIterations = 0;  ///< iterations that needed the pseudo-transient shift
    bool stalled = false;       ///< accepted under acceptableResidual, not tolerance
    int krylovIterations = 0;   ///< preconditioned CG iterations (reused factorisation)
};

class MembraneModel;

class SolverWorkspace {
  public:
    SolverWorkspace();
    ~SolverWorkspace();
    SolverWorkspace(SolverWorkspace&&) noexcept;
    SolverWorkspace& operator=(SolverWorkspace&&) noexcept;
    /// Forgets the stored factorisation (e.g. after the model's structure changed).
    void reset();
    int getNumFactorizations() const;  ///< factorisations made through this workspace
    struct Impl;                       ///< defined in the solver's source only
  private:
    friend SolveSummary solveEquilibrium(const MembraneModel&, Eigen::Matrix3Xd&,
                                         const SolverOptions&, SolverWorkspace*);
    std::unique_ptr<Impl> m_impl;
};

/// Minimises the model's energy over the free dofs, starting from x (updated in place).
/// @throws NumericalError if x becomes non-finite or an element inverts beyond recovery.
/// `workspace` (optional) carries a factorisation between calls; without it each call factors
/// afresh.
SolveSummary solveEquilibrium(const MembraneModel& model, Eigen::Matrix3Xd& x,
                              const SolverOptions& options, SolverWorkspace* workspace = nullptr);

/// Solves K Y = B with K the model's whole tangent at x (membrane, loads, contacts and the
/// dense gas terms) over the free dofs; B is 3N x m, Y has zero rows at fixed dofs. Used for
/// the sensitivity of an equilibrium to a load parameter (dx/dq = -K^-1 dr/dq).
/// @throws NumericalError if K is not positive definite (an unstable state).
Eigen::MatrixXd solveTangent(const MembraneModel& model, const Eigen::Matrix3Xd& x,
                             const Eigen::MatrixXd& B);

}  // namespace bags
