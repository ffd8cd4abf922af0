// Newton solver for the quasi-static equilibrium of a MembraneModel.
#include <bags/EquilibriumSolver.h>

#include "SparseSolve.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace bags {

void SolverOptions::validate() const {
    auto fail = [](const char* name, double v, const char* valid) {
        std::ostringstream s;
        s << "solver option '" << name << "' = " << v << " is invalid; " << valid;
        throw std::invalid_argument(s.str());
    };
    if (!(relativeTolerance > 0.0 && relativeTolerance < 1.0))
        fail("relativeTolerance", relativeTolerance, "use 0 < tol < 1 (e.g. 1e-8)");
    if (!(absoluteTolerance > 0.0)) fail("absoluteTolerance", absoluteTolerance, "use > 0 N");
    if (maxIterations < 1) fail("maxIterations", maxIterations, "use at least 1");
    if (!(pseudoTransientShift > 0.0))
        fail("pseudoTransientShift", pseudoTransientShift, "use > 0");
    if (!(maxStep >= 0.0)) fail("maxStep", maxStep, "use >= 0 m (0: no limit)");
    if (maxKrylovIterations < 1) fail("maxKrylovIterations", maxKrylovIterations, "use >= 1");
    if (maxSparsifiedKrylovIterations < 1)
        fail("maxSparsifiedKrylovIterations", maxSparsifiedKrylovIterations, "use >= 1");
    if (!(krylovTolerance > 0.0 && krylovTolerance < 1.0))
        fail("krylovTolerance", krylovTolerance, "use 0 < tol < 1 (e.g. 1e-4)");
    if (!(forcingTerm > 0.0 && forcingTerm < 1.0))
        fail("forcingTerm", forcingTerm, "use 0 < eta < 1 (e.g. 0.1)");
    if (!(acceptableResidual >= 0.0))
        fail("acceptableResidual", acceptableResidual, "use >= 0 N (0: only the tolerance)");
}

namespace {

using SpMat = detail::SparseSpdSolver::Matrix;

// Free-dof numbering: -1 for fixed dofs.
std::vector<int> makeFreeMap(int ndof, const std::vector<int>& fixed, int* nfree) {
    std::vector<int> map(ndof, 0);
    for (int d : fixed) map[d] = -1;
    int k = 0;
    for (int i = 0; i < ndof; ++i)
        if (map[i] >= 0) map[i] = k++;
    *nfree = k;
    return map;
}

Eigen::VectorXd reduce(const Eigen::VectorXd& full, const std::vector<int>& map, int nfree) {
    Eigen::VectorXd r(nfree);
    for (int i = 0; i < static_cast<int>(map.size()); ++i)
        if (map[i] >= 0) r(map[i]) = full(i);
    return r;
}

void expandAdd(const Eigen::VectorXd& red, const std::vector<int>& map, double alpha,
               Eigen::Matrix3Xd& x) {
    double* xp = x.data();
    for (int i = 0; i < static_cast<int>(map.size()); ++i)
        if (map[i] >= 0) xp[i] += alpha * red(map[i]);
}

// The gas bodies' dense rank-one tangent terms c g g^T over the free dofs: the columns of U
// are the bodies' dV/dx [m^2], c their -dp/dV [Pa/m^3] (> 0).
void calcGasTerms(const MembraneModel& model, const Eigen::Matrix3Xd& x,
                  const std::vector<int>& map, int nfree, Eigen::MatrixXd& U, Eigen::VectorXd& c) {
    const int ng = model.getNumGases();
    U.resize(nfree, ng);
    c.resize(ng);
    for (int g = 0; g < ng; ++g) {
        Eigen::VectorXd grad;
        const double V = model.calcGasVolume(g, x, &grad);
        U.col(g) = reduce(grad, map, nfree);
        c(g) = -model.getGas(g).calcPressureDerivative(V);
    }
}

double energyAt(const MembraneModel& model, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(0);
    acc.grad.resize(0);
    acc.wantGradient = false;
    acc.wantHessian = false;
    try {
        model.addEnergy(x, acc);
    } catch (const NumericalError&) {
        return std::numeric_limits<double>::infinity();
    }
    if (!x.allFinite()) return std::numeric_limits<double>::infinity();
    return acc.energy;
}

// Applies (P + U C U^T)^-1 by Sherman-Morrison-Woodbury, P^-1 from the factorisation.
struct WoodburySolve {
    const detail::SparseSpdSolver& P;
    Eigen::MatrixXd PU;                        // P^-1 U
    Eigen::LDLT<Eigen::MatrixXd> capacitance;  // C^-1 + U^T P^-1 U
    const Eigen::MatrixXd& U;
    WoodburySolve(const detail::SparseSpdSolver& p, const Eigen::MatrixXd& u,
                  const Eigen::VectorXd& c)
        : P(p), U(u) {
        if (U.cols() == 0) return;
        PU = P.solve(U);
        Eigen::MatrixXd cap = U.transpose() * PU;
        cap.diagonal() += c.cwiseInverse();
        capacitance.compute(cap);
    }
    Eigen::VectorXd apply(const Eigen::VectorXd& b) const {
        Eigen::VectorXd y = P.solve(b);
        if (U.cols() > 0) y -= PU * capacitance.solve(U.transpose() * y);
        return y;
    }
};

// Preconditioned CG on A = K + U C U^T + shift I (K stored as its lower triangle), from 0,
// until |b - A x| <= rtol |b|.
enum class PcgStatus { Converged, NegativeCurvature, MaxIterations };
PcgStatus solvePcg(const SpMat& K, const Eigen::MatrixXd& U, const Eigen::VectorXd& c,
                   const WoodburySolve& M, const Eigen::VectorXd& b, double rtol, int maxIt,
                   Eigen::VectorXd& x, int* iterations, double shift = 0.0) {
    x.setZero(b.size());
    Eigen::VectorXd res = b, z = M.apply(res), p = z, Ap(b.size());
    double rz = res.dot(z);
    const double stop = rtol * b.norm();
    for (int k = 1; k <= maxIt; ++k) {
        Ap.noalias() = K.selfadjointView<Eigen::Lower>() * p;
        if (shift != 0.0) Ap += shift * p;
        if (U.cols() > 0) Ap += U * c.cwiseProduct(U.transpose() * p);
        const double pAp = p.dot(Ap);
        *iterations = k;
        if (!(pAp > 0.0)) return PcgStatus::NegativeCurvature;
        const double a = rz / pAp;
        x += a * p;
        res -= a * Ap;
        if (res.norm() <= stop) return PcgStatus::Converged;
        z = M.apply(res);
        const double rzNew = res.dot(z);
        p = z + (rzNew / rz) * p;
        rz = rzNew;
    }
    return PcgStatus::MaxIterations;
}

// For each node, the sorted nodes it shares a triangle with, itself included.
std::vector<std::vector<int>> makeNodeAdjacency(const Mesh& mesh) {
    std::vector<std::vector<int>> adj = mesh.calcNodeNeighbours();
    for (int n = 0; n < static_cast<int>(adj.size()); ++n)
        adj[n].insert(std::lower_bound(adj[n].begin(), adj[n].end(), n), n);
    return adj;
}

// The tangent K without its couplings between nodes that share no triangle (the bending
// stencil's wide couplings, and self-contact pairs), each dropped entry's magnitude added to
// the two diagonal entries of its row and column: for the symmetric pair a_ij, a_ji that adds
// the positive semi-definite [|a| -a; -a |a|], so P is at least as definite as K. P's pattern
// and the map from K's value slots to P's are made once per pattern of K; each call then
// only gathers the values.
class Sparsifier {
  public:
    bool isFor(int patternId, int nfree) const {
        return m_pattern == patternId && m_nfree == nfree;
    }
    void build(const SpMat& K, const std::vector<int>& freeToNode,
               const std::vector<std::vector<int>>& adj, int patternId) {
        const int n = static_cast<int>(K.rows());
        std::vector<Eigen::Triplet<double>> keep;
        keep.reserve(K.nonZeros());
        for (int j = 0; j < n; ++j) keep.emplace_back(j, j, 0.0);
        m_target.assign(K.nonZeros(), -1);
        for (int j = 0; j < K.outerSize(); ++j)
            for (int k = K.outerIndexPtr()[j]; k < K.outerIndexPtr()[j + 1]; ++k) {
                const int i = K.innerIndexPtr()[k];
                const std::vector<int>& na = adj[freeToNode[i]];
                if (std::binary_search(na.begin(), na.end(), freeToNode[j]))
                    keep.emplace_back(i, j, 0.0);
            }
        m_P.resize(n, n);
        m_P.setFromTriplets(keep.begin(), keep.end());
        m_P.makeCompressed();
        m_diag.resize(n);
        for (int i = 0; i < n; ++i) m_diag[i] = find(i, i);
        m_rowDiag.assign(K.nonZeros(), -1);
        m_colDiag.assign(K.nonZeros(), -1);
        for (int j = 0; j < K.outerSize(); ++j)
            for (int k = K.outerIndexPtr()[j]; k < K.outerIndexPtr()[j + 1]; ++k) {
                const int i = K.innerIndexPtr()[k];
                m_target[k] = find(i, j);
                if (m_target[k] < 0) {
                    m_rowDiag[k] = m_diag[i];
                    m_colDiag[k] = m_diag[j];
                }
            }
        m_pattern = patternId;
        m_nfree = n;
    }
    const SpMat& update(const SpMat& K) {
        double* p = m_P.valuePtr();
        std::fill(p, p + m_P.nonZeros(), 0.0);
        const double* v = K.valuePtr();
        for (int k = 0; k < static_cast<int>(K.nonZeros()); ++k) {
            if (m_target[k] >= 0) {
                p[m_target[k]] += v[k];
            } else {
                p[m_rowDiag[k]] += std::abs(v[k]);
                p[m_colDiag[k]] += std::abs(v[k]);
            }
        }
        return m_P;
    }
    int diagonalSlot(int i) const { return m_diag[i]; }

  private:
    int find(int i, int j) const { return detail::findSlot(m_P, i, j); }
    SpMat m_P;
    std::vector<int> m_target, m_rowDiag, m_colDiag, m_diag;
    int m_pattern = -1;
    int m_nfree = -1;
};

}  // namespace

struct SolverWorkspace::Impl {
    detail::SparseSpdSolver llt;
    detail::HessianAssembler assembler;
    Sparsifier sparsifier;                    // the tangent without its wide couplings
    std::vector<std::vector<int>> adjacency;  // node neighbours of the model's mesh
    const Mesh* adjacencyMesh = nullptr;
    int nfree = -1;
    bool valid = false;
    int factorizations = 0;
    double precondShift = 0.0;  // [N/m] on the last factorisation's diagonal (truncated Newton)
    SpMat shifted;              // the factored matrix plus its shift
};

SolverWorkspace::SolverWorkspace() : m_impl(std::make_unique<Impl>()) {}
SolverWorkspace::~SolverWorkspace() = default;
SolverWorkspace::SolverWorkspace(SolverWorkspace&&) noexcept = default;
SolverWorkspace& SolverWorkspace::operator=(SolverWorkspace&&) noexcept = default;
void SolverWorkspace::reset() { m_impl->valid = false; }
int SolverWorkspace::getNumFactorizations() const { return m_impl->factorizations; }

namespace {
// The direction d of an inexact Newton step: CG on the whole tangent K + shift I (gas terms
// included) to the forcing tolerance, preconditioned by a factorisation of P (K, or K without
// its wide couplings) whose diagonal is raised only until the factorisation succeeds, so
// that a preconditioner that fails to factor does not shift the Newton system itself. False
// at negative curvature of K + shift I (the caller then shifts the tangent: truncating CG
// there, Nocedal & Wright's Algorithm 7.1, missed the square cushion's verification by
// 4.3 %). The factorisation is reused while CG converges within maxKrylovIterations on it.
// With P = K and no raise needed it is an exact (shifted) Newton solve.
bool calcInexactNewtonDirection(const SpMat& K, const SpMat& P, bool wide, const Eigen::MatrixXd& U,
                                const Eigen::VectorXd& cgas, const Eigen::VectorXd& r, double shift,
                                double diagMean, double tolerance, const SolverOptions& options,
                                SolverWorkspace::Impl& ws, SolveSummary& sum, Eigen::VectorXd& d) {
    auto run = [&](int maxIt) {
        int kit = 0;
        const WoodburySolve M(ws.llt, U, cgas);
        const PcgStatus status = solvePcg(K, U, cgas, M, -r, tolerance, maxIt, d, &kit, shift);
        sum.krylovIterations += kit;
        return status;
    };
    if (options.reuseFactorization && ws.valid) {
        const PcgStatus status = run(options.maxKrylovIterations);
        if (status != PcgStatus::MaxIterations) return status == PcgStatus::Converged;
    }
    // A raise that sufficed last time, tried a tenth as large first.
    double raise = 0.1 * ws.precondShift;
    if (raise < 1e-8 * diagMean) raise = 0.0;
    bool factored = false;
    for (int attempt = 0; attempt < 30 && !factored; ++attempt) {
        ++sum.factorizations;
        ++ws.factorizations;
        if (shift + raise > 0.0) {
            ws.shifted = P;  // same pattern: the diagonal slots hold
            for (int i = 0; i < P.cols(); ++i)
                ws.shifted.valuePtr()[wide ? ws.sparsifier.diagonalSlot(i)
                                           : ws.assembler.diagonalSlot(i)] += shift + raise;
            factored = ws.llt.factorize(ws.shifted);
        } else {
            factored = ws.llt.factorize(P);
        }
        if (!factored) raise = raise > 0.0 ? raise * 10.0 : options.pseudoTransientShift * diagMean;
    }
    ws.valid = factored;
    if (!factored) throw NumericalError("tangent could not be factored", -1, 0);
    ws.precondShift = raise;
    if (!wide && raise == 0.0) {
        d = WoodburySolve(ws.llt, U, cgas).apply(-r);
        return true;
    }
    // Converged, or CG's last iterate after its iteration limit.
    return run(options.maxSparsifiedKrylovIterations) != PcgStatus::NegativeCurvature;
}
}  // namespace

SolveSummary solveEquilibrium(const MembraneModel& model, Eigen::Matrix3Xd& x,
                              const SolverOptions& options, SolverWorkspace* workspace) {
    options.validate();
    const int nn = model.getMesh().getNumNodes();
    const int ndof = 3 * nn;
    int nfree = 0;
    const std::vector<int> map = makeFreeMap(ndof, model.getFixedDofs(), &nfree);
    const bool conservative = model.isConservative();

    SolveSummary sum;
    SolverWorkspace localWorkspace;
    SolverWorkspace::Impl& ws = *(workspace ? workspace : &localWorkspace)->m_impl;
    if (ws.nfree != nfree) ws.valid = false;
    ws.nfree = nfree;
    double shift = 0.0;  // pseudo-transient diagonal shift [N/m]
    double prevResidual = -1.0;
    double bestResidual = std::numeric_limits<double>::infinity();
    int sinceBest = 0;  // iterations since the residual last fell below its best by 1 %

    EnergyAccumulator acc(nn);  // reused: its buffers keep their capacity
    for (int it = 0; it <= options.maxIterations; ++it) {
        if (!x.allFinite()) throw NumericalError("non-finite nodal positions", -1, it);
        acc.resize(nn);
        model.addMembraneEnergy(x, acc);
        const double membraneForce = reduce(acc.grad, map, nfree).norm();
        model.addLoadEnergy(x, acc);
        const Eigen::VectorXd r = reduce(acc.grad, map, nfree);
        const double rnorm = r.norm();
        sum.residualNorm = rnorm;
        sum.energy = acc.energy;
        sum.iterations = it;
        if (!std::isfinite(rnorm)) throw NumericalError("non-finite residual", -1, it);
        const double tol = std::max(options.absoluteTolerance,
                                    options.relativeTolerance * std::max(membraneForce, 1e-300));
        if (rnorm <= tol) {
            sum.converged = true;
            return sum;
        }
        if (rnorm < 0.99 * bestResidual) {
            bestResidual = rnorm;
            sinceBest = 0;
        } else if (++sinceBest >= 8 && rnorm <= options.acceptableResidual) {
            sum.converged = true;
            sum.stalled = true;
            return sum;
        }
        if (it == options.maxIterations) break;

        const SpMat& K = ws.assembler.assemble(acc.hess, map, nfree);
        // The matrix to factor: K, or K without its wide couplings (then CG on K).
        const bool wide = options.sparsifyWideCouplings && acc.wideEnd > acc.wideBegin;
        const SpMat* P = &K;
        if (wide) {
            if (ws.adjacencyMesh != &model.getMesh() ||
                static_cast<int>(ws.adjacency.size()) != nn) {
                ws.adjacency = makeNodeAdjacency(model.getMesh());
                ws.adjacencyMesh = &model.getMesh();
            }
            if (!ws.sparsifier.isFor(ws.assembler.getNumPatterns(), nfree)) {
                std::vector<int> freeToNode(nfree);
                for (int d = 0; d < ndof; ++d)
                    if (map[d] >= 0) freeToNode[map[d]] = d / 3;
                ws.sparsifier.build(K, freeToNode, ws.adjacency, ws.assembler.getNumPatterns());
            }
            P = &ws.sparsifier.update(K);
        }
        double diagMean = 0.0;
        for (int i = 0; i < nfree; ++i)
            diagMean += std::abs(K.valuePtr()[ws.assembler.diagonalSlot(i)]);
        diagMean = std::max(diagMean / std::max(nfree, 1), 1e-12);

        // Dense rank-one gas terms: c g g^T, c = -dp/dV > 0.
        Eigen::MatrixXd U;
        Eigen::VectorXd cgas;
        calcGasTerms(model, x, map, nfree, U, cgas);

        // Newton direction, inexact: the linear solve need only be as accurate as the forcing
        // term, or as brings the residual to half the tolerance, whichever is tighter. Where
        // CG meets negative curvature the tangent itself is shifted (pseudo-transient).
        const double krylovTolerance =
            std::clamp(0.5 * tol / rnorm, options.krylovTolerance, options.forcingTerm);
        Eigen::VectorXd d;
        int attempts = 0;
        while (!calcInexactNewtonDirection(K, *P, wide, U, cgas, r, shift, diagMean,
                                           krylovTolerance, options, ws, sum, d)) {
            shift = shift > 0.0 ? shift * 10.0 : options.pseudoTransientShift * diagMean;
            if (++attempts > 30) throw NumericalError("tangent could not be shifted", -1, it);
        }
        if (shift > 0.0) ++sum.shiftedIterations;

        // Trust limit on the largest nodal move (slack membranes can propose huge steps).
        if (options.maxStep > 0.0) {
            const double dmax = d.size() ? d.cwiseAbs().maxCoeff() : 0.0;  // per component
            if (dmax > options.maxStep) d *= options.maxStep / dmax;
        }

        // Line search: Armijo on the energy (conservative), on the residual norm otherwise.
        const double slope = r.dot(d);
        double alpha = 1.0;
        bool accepted = false;
        const Eigen::Matrix3Xd x0 = x;
        for (int ls = 0; ls < 25; ++ls) {
            x = x0;
            expandAdd(d, map, alpha, x);
            if (conservative && slope < 0.0) {
                const double E = energyAt(model, x);
                const double roundoff = 1e-13 * (std::abs(acc.energy) + 1.0);
                if (std::isfinite(E) && E <= acc.energy + 1e-4 * alpha * slope + roundoff) {
                    accepted = true;
                    break;
                }
            } else {
                EnergyAccumulator trial(nn);
                trial.wantHessian = false;
                bool ok = true;
                try {
                    model.addEnergy(x, trial);
                } catch (const NumericalError&) {
                    ok = false;
                }
                if (ok && reduce(trial.grad, map, nfree).norm() < (1.0 - 1e-4 * alpha) * rnorm) {
                    accepted = true;
                    break;
                }
            }
            alpha *= 0.5;
        }
        if (options.monitor) options.monitor(it, rnorm, accepted ? alpha : 0.0, shift);
        if (!accepted) {
            // Not a usable direction: go back and damp harder (pseudo-transient).
            x = x0;
            shift = std::max(shift * 10.0, options.pseudoTransientShift * diagMean);
            continue;
        }
        // Relax the shift as the step is accepted whole; stop shifting once small.
        if (shift > 0.0) {
            const double ratio = prevResidual > 0.0 ? rnorm / prevResidual : 1.0;
            shift *= (alpha == 1.0) ? std::min(0.1, ratio) : (alpha < 0.1 ? 2.0 : 1.0);
            if (shift < 1e-10 * diagMean) shift = 0.0;
        }
        prevResidual = rnorm;
    }
    sum.converged = false;
    return sum;
}

Eigen::MatrixXd solveTangent(const MembraneModel& model, const Eigen::Matrix3Xd& x,
                             const Eigen::MatrixXd& B) {
    const int nn = model.getMesh().getNumNodes();
    const int ndof = 3 * nn;
    if (B.rows() != ndof) throw std::invalid_argument("solveTangent: B must have 3N rows");
    int nfree = 0;
    const std::vector<int> map = makeFreeMap(ndof, model.getFixedDofs(), &nfree);
    EnergyAccumulator acc(nn);
    model.addEnergy(x, acc);
    detail::HessianAssembler assembler;
    const SpMat& K = assembler.assemble(acc.hess, map, nfree);
    detail::SparseSpdSolver llt;
    if (!llt.factorize(K))
        throw NumericalError("solveTangent: the tangent is not positive definite");
    Eigen::MatrixXd U;
    Eigen::VectorXd cgas;
    calcGasTerms(model, x, map, nfree, U, cgas);
    const WoodburySolve solve(llt, U, cgas);
    Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(ndof, B.cols());
    for (int j = 0; j < B.cols(); ++j) {
        const Eigen::VectorXd y = solve.apply(reduce(B.col(j), map, nfree));
        for (int i = 0; i < ndof; ++i)
            if (map[i] >= 0) Y(i, j) = y(map[i]);
    }
    return Y;
}

}  // namespace bags
