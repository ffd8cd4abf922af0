// The solver's Hessian assembly: the scatter map kept between calls gives the matrix that a
// fresh setFromTriplets gives, whatever changes in the triplet sequence; and the membrane's
// triplets come in the same sequence on every call, also when the element loop runs on a
// team of threads (the map relies on it).
#include "SparseSolve.h"

#include <bags/Geometry.h>
#include <bags/Material.h>
#include <bags/EquilibriumSolver.h>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace bags;
using detail::HessianAssembler;

namespace {

// The reference: lower triangle of K(map[r], map[c]), fixed dofs dropped, as a dense matrix.
Eigen::MatrixXd reference(const std::vector<Triplet>& trips, const std::vector<int>& map,
                          int nfree) {
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nfree, nfree);
    for (const Triplet& t : trips) {
        const int i = map[t.row()], j = map[t.col()];
        if (i >= 0 && j >= 0 && i >= j) K(i, j) += t.value();
    }
    return K;
}

// A symmetric "element" part on a fixed pattern (the same sequence every call, new values)
// and a tail of `tail` random symmetric pairs (contact-like terms that come and go).
std::vector<Triplet> makeTriplets(int n, int tail, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_int_distribution<int> node(0, n - 1);
    std::vector<Triplet> t;
    for (int e = 0; e + 2 < n; ++e)  // "elements" coupling e, e+1, e+2
        for (int a = e; a < e + 3; ++a)
            for (int b = e; b < e + 3; ++b) t.emplace_back(a, b, u(rng));
    for (int k = 0; k < tail; ++k) {
        const int a = node(rng), b = node(rng);
        const double v = u(rng);
        t.emplace_back(a, b, v);
        if (a != b) t.emplace_back(b, a, v);
    }
    return t;
}

}  // namespace

TEST(HessianAssembler, ReusedMapGivesTheFreshlyAssembledMatrix) {
    const int n = 40;
    std::vector<int> map(n);
    int nfree = 0;
    for (int i = 0; i < n; ++i) map[i] = (i % 7 == 3) ? -1 : nfree++;  // some fixed dofs
    HessianAssembler as;
    std::mt19937 rng(11);
    // Calls with new values on the same prefix and tails of 0-4 random entries: most tails
    // fall outside the pattern at first (new pattern), later ones reuse it.
    for (int call = 0; call < 60; ++call) {
        const std::vector<Triplet> trips = makeTriplets(n, call % 5, rng);
        const HessianAssembler::Matrix& K = as.assemble(trips, map, nfree);
        ASSERT_EQ(K.rows(), nfree);
        const Eigen::MatrixXd Kd = Eigen::MatrixXd(K);
        // Exact up to the order of summing duplicates: 1e-14 relative.
        EXPECT_LT((Kd - reference(trips, map, nfree)).norm(), 1e-14 * (1.0 + Kd.norm()))
            << "call " << call;
        for (int i = 0; i < nfree; ++i) EXPECT_EQ(K.valuePtr()[as.diagonalSlot(i)], Kd(i, i));
    }
    // The pattern was reused at least once (fewer patterns than calls) and rebuilt when a
    // tail entry was new (more than one).
    EXPECT_GT(as.getNumPatterns(), 1);
    EXPECT_LT(as.getNumPatterns(), 60);
    // The same sequence again: no new pattern.
    const int patterns = as.getNumPatterns();
    std::mt19937 same(5);
    const std::vector<Triplet> a = makeTriplets(n, 3, same);
    as.assemble(a, map, nfree);
    const int afterFirst = as.getNumPatterns();
    EXPECT_LE(afterFirst, patterns + 1);
    std::vector<Triplet> b = a;
    for (Triplet& t : b) t = Triplet(t.row(), t.col(), 2.0 * t.value());
    const Eigen::MatrixXd Kb = Eigen::MatrixXd(as.assemble(b, map, nfree));
    EXPECT_EQ(as.getNumPatterns(), afterFirst);
    EXPECT_LT((Kb - 2.0 * reference(a, map, nfree)).norm(), 1e-14 * (1.0 + Kb.norm()));
    // Other fixed dofs, the same number of them: a new pattern, and the right matrix.
    std::vector<int> other(n);
    int k = 0;
    for (int i = 0; i < n; ++i) other[i] = (i % 7 == 4) ? -1 : k++;
    ASSERT_EQ(k, nfree);
    const Eigen::MatrixXd Ko = Eigen::MatrixXd(as.assemble(b, other, nfree));
    EXPECT_EQ(as.getNumPatterns(), afterFirst + 1);
    EXPECT_LT((Ko - reference(b, other, nfree)).norm(), 1e-14 * (1.0 + Ko.norm()));
    // No fixed dofs: a larger matrix.
    for (int i = 0; i < n; ++i) map[i] = i;
    as.assemble(b, map, n);
    EXPECT_EQ(as.getNumPatterns(), afterFirst + 2);
}

TEST(MembraneAssembly, TripletSequenceAndGradientDoNotDependOnThreadTiming) {
    // The double wedge at 5 mm has about 12 000 triangles: above the 4000 at which the element
    // loop runs on a team. With a team of two (set here, whatever the machine), calls give the
    // same triplet sequence (bit for bit) and the same gradient; with one thread the sequence
    // is the same too.
#ifdef _OPENMP
    struct TeamOfTwo {  // restores the OpenMP settings however the test ends
        int threads = omp_get_max_threads();
        int dynamic = omp_get_dynamic();
        TeamOfTwo() {
            omp_set_dynamic(0);
            omp_set_num_threads(2);
        }
        ~TeamOfTwo() {
            omp_set_num_threads(threads);
            omp_set_dynamic(dynamic);
        }
    } team;
#endif
    DoubleWedgeParams p;
    p.meshSize = 0.005;
    const Mesh mesh = makeDoubleWedgeBag(p);
    ASSERT_GT(mesh.getNumTris(), 4000);
    MembraneModel model(mesh, std::make_shared<WrinklingMaterial>(makeNeoHookean(1e6), 1e-3),
                        0.2e-3);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3Xd x = 1.02 * mesh.X;  // stretched: taut and wrinkled elements
    for (int i = 0; i < x.size(); ++i) x.data()[i] += 0.5e-3 * u(rng);
    auto evaluate = [&](EnergyAccumulator& acc) {
        acc.resize(mesh.getNumNodes());
        model.addMembraneEnergy(x, acc);
    };
    EnergyAccumulator first(mesh.getNumNodes());
    evaluate(first);
    ASSERT_EQ(first.hess.size(), 81u * mesh.getNumTris());
    for (int call = 0; call < 5; ++call) {
        EnergyAccumulator again(mesh.getNumNodes());
        evaluate(again);
        ASSERT_EQ(again.hess.size(), first.hess.size());
        size_t differ = 0;
        for (size_t t = 0; t < first.hess.size(); ++t)
            differ += again.hess[t].row() != first.hess[t].row() ||
                      again.hess[t].col() != first.hess[t].col() ||
                      again.hess[t].value() != first.hess[t].value();
        EXPECT_EQ(differ, 0u) << "call " << call;
        EXPECT_EQ((again.grad - first.grad).cwiseAbs().maxCoeff(), 0.0) << "call " << call;
    }
#ifdef _OPENMP
    omp_set_num_threads(1);
    EnergyAccumulator serial(mesh.getNumNodes());
    evaluate(serial);
    omp_set_num_threads(2);
    ASSERT_EQ(serial.hess.size(), first.hess.size());
    size_t differ = 0;
    for (size_t t = 0; t < first.hess.size(); ++t)
        differ += serial.hess[t].row() != first.hess[t].row() ||
                  serial.hess[t].col() != first.hess[t].col();
    EXPECT_EQ(differ, 0u);
    // Same sums in another order: equal to roundoff (1e-12 of the largest component).
    EXPECT_LT((serial.grad - first.grad).cwiseAbs().maxCoeff(),
              1e-12 * first.grad.cwiseAbs().maxCoeff());
#endif
}
