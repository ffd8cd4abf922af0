#pragma once
// Sparse symmetric positive-definite factorisation (CHOLMOD simplicial LL^T) that keeps its
// symbolic analysis while the sparsity pattern stays the same.

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

#include <cstdint>
#include <memory>
#include <vector>

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

// Index in K's value array of entry (i, j) of a compressed column-major matrix with sorted
// rows; -1 if the pattern lacks it.
int findSlot(const SparseSpdSolver::Matrix& K, int i, int j);

// Lower triangle of the reduced Hessian K(map[r], map[c]) (fixed dofs map to -1 and are
// dropped; duplicates summed), assembled through a scatter map (triplet -> slot in the value
// array) kept between calls. The membrane's triplets come first and in element order on every
// call, so the sequence repeats but for a short tail (contact terms that come and go): the
// common prefix keeps its slots, each tail triplet is looked up in the pattern, and only an
// entry the pattern lacks (e.g. a new self-contact pair) makes a new pattern (one
// setFromTriplets, i.e. a sort, and a search per triplet), the union of the old pattern and
// the new entries: while the dofs stay the same the pattern only grows, so pairs that come
// and go stop making new patterns. The diagonal is always stored.
class HessianAssembler {
  public:
    using Matrix = SparseSpdSolver::Matrix;
    const Matrix& assemble(const std::vector<Eigen::Triplet<double>>& trips,
                           const std::vector<int>& map, int nfree);
    /// Index in the value array of diagonal entry i of the last assembled matrix.
    int diagonalSlot(int i) const { return m_diag[i]; }
    /// Sparsity patterns built so far (1 + the number of times the map was rebuilt).
    int getNumPatterns() const { return m_patterns; }

  private:
    int find(int i, int j) const;
    bool mapSlots(const std::vector<Eigen::Triplet<double>>& trips, const std::vector<int>& map,
                  size_t from);
    bool remap(const std::vector<Eigen::Triplet<double>>& trips, const std::vector<int>& map,
               int nfree);
    void rebuild(const std::vector<Eigen::Triplet<double>>& trips, const std::vector<int>& map,
                 int nfree);

    Matrix m_K;
    std::vector<Eigen::Triplet<double>> m_red;
    std::vector<int> m_rows, m_cols, m_slot, m_diag, m_map;
    int m_patterns = 0;
};

}  // namespace bags::detail
