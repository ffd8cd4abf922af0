#include "SparseSolve.h"

#include <algorithm>
#include <mutex>

namespace bags::detail {

namespace {
std::uint64_t hashPattern(const SparseSpdSolver::Matrix& A) {
    std::uint64_t h = 1469598103934665603ull ^ static_cast<std::uint64_t>(A.rows());
    auto mix = [&h](std::uint64_t v) { h = (h ^ v) * 1099511628211ull; };
    for (int j = 0; j <= A.outerSize(); ++j) mix(static_cast<std::uint64_t>(A.outerIndexPtr()[j]));
    for (int k = 0; k < A.nonZeros(); ++k) mix(static_cast<std::uint64_t>(A.innerIndexPtr()[k]));
    return h;
}

// METIS, under CHOLMOD's nested dissection, draws from one random generator for the whole
// process, seeded at the start of each ordering. Two bags analysed at once on two threads (the
// co-simulation advances bags in parallel) interleave its draws: the ordering, and so the
// roundoff of every later solve, then depends on the threads' timing (two runs of one
// scenario differed in the 8th significant digit of a bag's force). One analysis at a time
// keeps every ordering a function of its pattern alone.
std::mutex g_analysisMutex;
}  // namespace

SparseSpdSolver::SparseSpdSolver() = default;
SparseSpdSolver::~SparseSpdSolver() = default;

bool SparseSpdSolver::factorize(const Matrix& A) {
    const std::uint64_t h = hashPattern(A);
    if (!m_llt || !m_analyzed || h != m_patternHash) {
        m_llt = std::make_unique<Eigen::CholmodSimplicialLLT<Matrix, Eigen::Lower>>();
        m_llt->cholmod().print = 0;  // the library prints nothing
        // CHOLMOD's nested dissection: on the 5 mm bag (17.7k dofs) 823k nonzeros in L and
        // 113 MFlop per factorisation, against 933k and 158 MFlop with its default (AMD);
        // docs/performance.md.
        m_llt->cholmod().nmethods = 1;
        m_llt->cholmod().method[0].ordering = CHOLMOD_NESDIS;
        m_llt->cholmod().postorder = 1;
        {
            const std::lock_guard<std::mutex> lock(g_analysisMutex);
            m_llt->analyzePattern(A);
        }
        m_patternHash = h;
        m_analyzed = true;
        ++m_numAnalyses;
    }
    m_llt->factorize(A);
    ++m_numFactorizations;
    return m_llt->info() == Eigen::Success;
}

Eigen::VectorXd SparseSpdSolver::solve(const Eigen::VectorXd& b) const { return m_llt->solve(b); }

Eigen::MatrixXd SparseSpdSolver::solve(const Eigen::MatrixXd& B) const { return m_llt->solve(B); }

namespace {
bool dropped(int i, int j) { return i < 0 || j < 0 || i < j; }
}  // namespace

const HessianAssembler::Matrix& HessianAssembler::assemble(
    const std::vector<Eigen::Triplet<double>>& trips, const std::vector<int>& map, int nfree) {
    if (!remap(trips, map, nfree)) {
        rebuild(trips, map, nfree);
        return m_K;
    }
    double* v = m_K.valuePtr();
    std::fill(v, v + m_K.nonZeros(), 0.0);
    const size_t n = trips.size();
    for (size_t t = 0; t < n; ++t)
        if (m_slot[t] >= 0) v[m_slot[t]] += trips[t].value();
    return m_K;
}

// Slot of (i, j), i >= j, in the compressed pattern; -1 if the pattern lacks it.
int findSlot(const SparseSpdSolver::Matrix& K, int i, int j) {
    const int* inner = K.innerIndexPtr();
    const int* begin = inner + K.outerIndexPtr()[j];
    const int* end = inner + K.outerIndexPtr()[j + 1];
    const int* it = std::lower_bound(begin, end, i);
    return (it != end && *it == i) ? static_cast<int>(it - inner) : -1;
}

int HessianAssembler::find(int i, int j) const { return findSlot(m_K, i, j); }

// Records the rows and columns of trips[from, end) and their slots in the current pattern;
// false (and the rest left unset) at the first entry the pattern lacks.
bool HessianAssembler::mapSlots(const std::vector<Eigen::Triplet<double>>& trips,
                                const std::vector<int>& map, size_t from) {
    const size_t n = trips.size();
    m_rows.resize(n);
    m_cols.resize(n);
    m_slot.resize(n);
    for (size_t t = from; t < n; ++t) {
        m_rows[t] = trips[t].row();
        m_cols[t] = trips[t].col();
        const int i = map[m_rows[t]], j = map[m_cols[t]];
        if (dropped(i, j)) {
            m_slot[t] = -1;
        } else if ((m_slot[t] = find(i, j)) < 0) {
            return false;
        }
    }
    return true;
}

// Keeps the slots of the prefix shared with the last call and maps the rest; false if an entry
// is not in the pattern (rebuild() then rewrites every slot).
bool HessianAssembler::remap(const std::vector<Eigen::Triplet<double>>& trips,
                             const std::vector<int>& map, int nfree) {
    if (m_patterns == 0 || m_K.rows() != nfree || map != m_map) return false;
    const size_t m = std::min(trips.size(), m_rows.size());
    size_t t = 0;
    while (t < m && trips[t].row() == m_rows[t] && trips[t].col() == m_cols[t]) ++t;
    return mapSlots(trips, map, t);
}

void HessianAssembler::rebuild(const std::vector<Eigen::Triplet<double>>& trips,
                               const std::vector<int>& map, int nfree) {
    m_red.clear();
    // The pattern only grows while the dofs stay the same: entries of the last pattern are
    // kept (as zeros), so contact pairs that come and go (self contact under a moving block)
    // stop forcing new patterns, new symbolic analyses and a full remap once seen.
    const bool grow = m_patterns > 0 && m_K.rows() == nfree && map == m_map;
    m_red.reserve(trips.size() / 2 + nfree + (grow ? m_K.nonZeros() : 0));
    if (grow)
        for (int j = 0; j < m_K.outerSize(); ++j)
            for (Matrix::InnerIterator it(m_K, j); it; ++it)
                m_red.emplace_back(it.row(), it.col(), 0.0);
    for (const Eigen::Triplet<double>& t : trips) {
        const int i = map[t.row()], j = map[t.col()];
        if (!dropped(i, j)) m_red.emplace_back(i, j, t.value());
    }
    for (int i = 0; i < nfree; ++i) m_red.emplace_back(i, i, 0.0);  // diagonal in the pattern
    m_K.resize(nfree, nfree);
    m_K.setFromTriplets(m_red.begin(), m_red.end());
    m_K.makeCompressed();
    mapSlots(trips, map, 0);  // every entry is in the pattern just built
    m_diag.resize(nfree);
    for (int i = 0; i < nfree; ++i) m_diag[i] = find(i, i);
    m_map = map;
    ++m_patterns;
}

}  // namespace bags::detail
