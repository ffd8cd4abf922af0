#pragma once
// Sparse symmetric positive-definite factorisation (CHOLMOD simplicial LL^T) that keeps its
// symbolic analysis while the sparsity pattern stays the same.

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

#include <cstdint>
#include <memory>

namespace bags::detail {

class SparseSpdSolver {
public:
    using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
    SparseSpdSolver();
    ~SparseSpdSolver();
    /// Factors A (only its lower triangle is read). Returns false if A is not positive definite.
    bool factorize(const Matrix& A);
    Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
    Eigen::MatrixXd solve(const Eigen::MatrixXd& B) const;
    int getNumFactorizations() const { return m_numFactorizations; }
    int getNumAnalyses() const { return m_numAnalyses; }
private:
    std::unique_ptr<Eigen::CholmodSimplicialLLT<Matrix, Eigen::Lower>> m_llt;
    std::uint64_t m_patternHash = 0;
    bool m_analyzed = false;
    int m_numFactorizations = 0;
    int m_numAnalyses = 0;
};

}  // namespace bags::detail
