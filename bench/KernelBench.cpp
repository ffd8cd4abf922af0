// Cost of the solver's kernels on the inflated double wedge: one energy + gradient, one
// energy + gradient + Hessian triplets, one assembly through the kept scatter map, one sparse
// factorisation and one solve. These bound what any Newton step can cost (docs/performance.md).
// Not a test: run by hand.
//
//   build/bin/bench_kernels [mesh_mm=5]
#include "SparseSolve.h"

#include <bags/Bending.h>
#include <bags/Dynamics.h>
#include <bags/LoadTest.h>
#include <bags/Material.h>
#include <bags/MaterialFit.h>
#include <bags/EquilibriumSolver.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cstdlib>

namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double millisecondsPerCall(int calls, const F& f) {
    const auto t0 = Clock::now();
    for (int k = 0; k < calls; ++k) f();
    return 1e3 * std::chrono::duration<double>(Clock::now() - t0).count() / calls;
}

}  // namespace

int main(int argc, char** argv) {
    const double meshMm = argc > 1 ? std::atof(argv[1]) : 5.0;
    if (!(meshMm >= 2.0 && meshMm <= 50.0)) {
        std::fprintf(stderr, "bench_kernels: mesh size %s is invalid; use 2 to 50 (mm)\n", argv[1]);
        return 2;
    }
    // The inflated shape: the load test's state before its first curve (4.5 g, taut).
    bags::LoadTestOptions o;
    o.geometry.meshSize = meshMm * 1e-3;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.gasMasses = {4.5e-3};
    o.peakForce = 1.0;
    o.stiffnessFrom = 0.2;
    o.stiffnessTo = 0.8;
    o.unload = false;
    Eigen::Matrix3Xd x;
    bags::Mesh mesh;
    double pressure = 0.0;
    bags::runLoadTest(o,
                      [&](const bags::LoadStep& s, const bags::Mesh& m, const Eigen::Matrix3Xd& y) {
                          if (s.step != 0) return;
                          x = y;
                          mesh = m;
                          pressure = s.gaugePressure[0];
                      });
    // The membrane with the gas as a follower pressure at that state: the load test's mesh,
    // dofs and element terms, without its contacts (block, bed board, self contact) and gas
    // bodies. The contacts add node-diagonal blocks and, for self contact, a few couplings, so
    // the pattern here is the load test's minus those couplings; the gas's rank-one term stays
    // outside the factorisation anyway. The assembly time is the best case (the whole
    // triplet sequence repeats).
    bags::MembraneModel model(
        mesh, std::make_shared<bags::WrinklingMaterial>(o.material->clone(), o.wrinklingResidual),
        o.thickness);
    for (int c = 0; c < static_cast<int>(mesh.chambers.size()); ++c)
        model.setChamberPressure(c, pressure);
    // `bending` as the second argument adds the film's plate bending stiffness.
    const bool bending = argc > 2 && std::strcmp(argv[2], "bending") == 0;
    if (bending)
        model.setBendingStiffness(bags::calcPlateBendingStiffness(*o.material, o.thickness));
    const int nn = mesh.getNumNodes();
    std::vector<int> map(3 * nn, 0);
    for (int d : model.getFixedDofs()) map[d] = -1;
    int nfree = 0;
    for (int& m : map)
        if (m >= 0) m = nfree++;

    bags::EnergyAccumulator acc(nn);
    acc.wantHessian = false;
    const double tGrad = millisecondsPerCall(50, [&] {
        acc.resize(nn);
        model.addEnergy(x, acc);
    });
    acc.wantHessian = true;
    const double tHess = millisecondsPerCall(20, [&] {
        acc.resize(nn);
        model.addEnergy(x, acc);
    });
    bags::detail::HessianAssembler assembler;
    assembler.assemble(acc.hess, map, nfree);  // builds the map
    const double tAssemble =
        millisecondsPerCall(20, [&] { assembler.assemble(acc.hess, map, nfree); });
    // A small shift (1e-3 of the mean diagonal) makes the wrinkled sheet's tangent definite,
    // as the solver's pseudo-transient shift does.
    bags::detail::SparseSpdSolver::Matrix K = assembler.assemble(acc.hess, map, nfree);
    const double shift = 1e-3 * K.diagonal().cwiseAbs().mean();
    for (int i = 0; i < nfree; ++i) K.coeffRef(i, i) += shift;
    bags::detail::SparseSpdSolver llt;
    bool ok = llt.factorize(K);  // with the symbolic analysis
    const double tFactor = millisecondsPerCall(10, [&] { ok = llt.factorize(K) && ok; });
    Eigen::VectorXd b = Eigen::VectorXd::Ones(nfree);
    const double tSolve = millisecondsPerCall(50, [&] { b = llt.solve(b).normalized(); });
    // The same matrix through CHOLMOD's supernodal factorisation (with the system's BLAS).
    Eigen::CholmodSupernodalLLT<bags::detail::SparseSpdSolver::Matrix, Eigen::Lower> sn;
    sn.cholmod().print = 0;
    sn.cholmod().nmethods = 1;
    sn.cholmod().method[0].ordering = CHOLMOD_NESDIS;
    sn.analyzePattern(K);
    const double tFactorSn = millisecondsPerCall(10, [&] { sn.factorize(K); });
    const double tSolveSn = millisecondsPerCall(50, [&] { b = sn.solve(b).normalized(); });
    if (!ok) {
        std::fprintf(stderr, "bench_kernels: the shifted tangent could not be factored\n");
        return 1;
    }
    std::printf("mesh %.2f mm: %d nodes, %d triangles, %d free dofs, %zu Hessian triplets\n",
                meshMm, nn, mesh.getNumTris(), nfree, acc.hess.size());
    std::printf("energy + gradient           %8.2f ms\n", tGrad);
    std::printf("  + Hessian triplets        %8.2f ms\n", tHess);
    std::printf("assembly (kept scatter map) %8.2f ms\n", tAssemble);
    std::printf("factorisation (CHOLMOD)     %8.2f ms\n", tFactor);
    std::printf("solve                       %8.2f ms\n", tSolve);
    std::printf("supernodal factorisation    %8.2f ms\n", tFactorSn);
    std::printf("supernodal solve            %8.2f ms\n", tSolveSn);
    std::printf("bending %s, nonzeros in K (lower) %ld\n", bending ? "on" : "off",
                static_cast<long>(K.nonZeros()));
    // The dynamic film's explicit step (bags/Dynamics.h: the forces above and the damped
    // central-difference update), on one core and on the machine's default threads with the
    // elements in 8 chunks (as a dynamically stepped bag has them): ns per triangle-step,
    // through the general path (MembraneModel::addEnergy without its Hessian, as the step was
    // before the force kernel) and through the force kernel (bags/FilmForce.h), in turns.
    bags::DynamicOptions dyn;
    dyn.massScale = 1000.0;
    dyn.damping = 20.0;
    for (const int threads : {1, 0}) {
        model.setNumThreads(threads);
        model.setElementChunks(threads == 1 ? 0 : 8);
        const bags::FilmDynamics film(model, o.density, dyn, 0.0);
        const Eigen::VectorXd& mass = film.getDofMass();
        Eigen::VectorXd invMass = Eigen::VectorXd::Zero(3 * nn);
        for (int d = 0; d < 3 * nn; ++d)
            if (mass(d) > 0.0) invMass(d) = 1.0 / mass(d);
        Eigen::Matrix3Xd xs = x, vs = Eigen::Matrix3Xd::Zero(3, nn);
        const double h = 1e-9;  // the state hardly moves: the cost of the state above
        bags::EnergyAccumulator sacc(nn);
        auto generalStep = [&] {
            sacc.wantHessian = false;
            sacc.resize(nn);
            model.addEnergy(xs, sacc);
            const double a = 0.5 * dyn.damping * h;
            const double keep = (1.0 - a) / (1.0 + a), push = h / (1.0 + a);
            for (int d = 0; d < 3 * nn; ++d) {
                vs.data()[d] =
                    invMass(d) > 0.0 ? keep * vs.data()[d] - push * invMass(d) * sacc.grad(d) : 0.0;
                xs.data()[d] += h * vs.data()[d];
            }
        };
        auto kernelStep = [&] { film.step(xs, vs, h, sacc); };
        kernelStep();  // builds the kernel
        // The best of 20 rounds each, in turns (other processes on the cores slow some).
        double tGeneral = 1e300, tKernel = 1e300;
        for (int round = 0; round < 20; ++round) {
            tGeneral = std::min(tGeneral, millisecondsPerCall(100, generalStep));
            tKernel = std::min(tKernel, millisecondsPerCall(100, kernelStep));
        }
        std::printf(
            "explicit step, %s general %8.3f ms %6.0f ns/tri-step; kernel %8.3f ms %6.0f "
            "ns/tri-step; ratio %.2f\n",
            threads == 1 ? "1 thread " : "threads 0", tGeneral, 1e6 * tGeneral / mesh.getNumTris(),
            tKernel, 1e6 * tKernel / mesh.getNumTris(), tGeneral / tKernel);
    }
    return 0;
}
