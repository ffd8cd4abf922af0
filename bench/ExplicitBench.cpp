// Measurement, not a test: can explicit dynamics (central differences, lumped mass, mass
// scaling, mass-proportional damping) press the seed's block into a slack bag faster than the
// implicit quasi-static solver, and to the same force? The bag is inflated by the implicit
// module (Airbag::inflate), then the block is driven down at a constant speed and the film
// integrated explicitly; the block force is sampled along the way. docs/solver.md.
//
//   build/bin/bench_explicit [--scale F] [--mass-scale S] [--damping ALPHA_PER_S]
//                            [--speed MM_PER_S] [--travel MM] [--cfl C] [--threads N]
//                            [--every MM] MESH_MM GAS_MASS_G
#include <bags/Airbag.h>
#include <bags/Bending.h>
#include <bags/Contact.h>
#include <bags/LoadTest.h>
#include <bags/MaterialFit.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

int main(int argc, char** argv) {
    bags::LoadTestOptions o;
    o.material = bags::makeStableYeoh(31.587917e6, -0.76582566e6, -3.06587618e6);
    o.imperfection.amplitude = 0.5e-3;
    o.imperfection.seed = 1;
    o.blockContact.pressurePenalty = 1e8;
    o.floorContact.pressurePenalty = 1e8;
    double massScale = 100.0, alpha = 20.0, speed = 0.02, travel = 0.08, cfl = 0.5, every = 1e-3;
    double scale = 0.8799;
    int first = 1;
    while (first + 1 < argc && std::strncmp(argv[first], "--", 2) == 0) {
        const char* k = argv[first];
        const double v = std::atof(argv[first + 1]);
        if (!std::strcmp(k, "--scale"))
            scale = v;
        else if (!std::strcmp(k, "--mass-scale"))
            massScale = v;
        else if (!std::strcmp(k, "--damping"))
            alpha = v;
        else if (!std::strcmp(k, "--speed"))
            speed = v * 1e-3;
        else if (!std::strcmp(k, "--travel"))
            travel = v * 1e-3;
        else if (!std::strcmp(k, "--cfl"))
            cfl = v;
        else if (!std::strcmp(k, "--every"))
            every = v * 1e-3;
        else if (!std::strcmp(k, "--threads"))
            o.threads = static_cast<int>(v);
        else {
            std::fprintf(stderr, "bench_explicit: unknown option %s\n", k);
            return 2;
        }
        first += 2;
    }
    if (argc < first + 2) {
        std::fprintf(stderr, "usage: bench_explicit [options] MESH_MM GAS_MASS_G\n");
        return 2;
    }
    o.geometry.meshSize = std::atof(argv[first]) * 1e-3;
    const double gasMass = std::atof(argv[first + 1]) * 1e-3;
    o.gasMasses = {gasMass};
    o.geometry.longSide *= scale;
    o.geometry.shortSide *= scale;
    o.geometry.height *= scale;
    // The seed scenario's plate bending stiffness.
    o.bendingStiffness = bags::calcPlateBendingStiffness(*o.material, o.thickness);
    o.validate();
    bags::Airbag bag(bags::makeAirbagSpec(o));
    const bags::Mesh& mesh = bag.getMesh();
    int topNode = 0;
    mesh.X.row(2).maxCoeff(&topNode);
    const bags::Vec3 centre(mesh.X(0, topNode), 0.0, 0.0);
    const double halfH = 0.010;
    std::shared_ptr<bags::RigidShape> block(
        bags::makeBox(bags::Vec3(0.5 * o.blockSize, 0.5 * o.blockSize, halfH), 1e-3));
    auto pose = [&](double zBottom) {
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = bags::Vec3(centre.x(), centre.y(), zBottom + halfH);
        return X;
    };
    block->setPose(pose(mesh.X.row(2).maxCoeff() + 0.2));
    bag.addShape(block, o.blockContact);
    const auto t0 = std::chrono::steady_clock::now();
    bag.inflate(gasMass);
    const double tInflate =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    const bags::MembraneModel& model = bag.getModel();
    Eigen::Matrix3Xd x = bag.getPositions();
    const int nn = static_cast<int>(x.cols());
    // Where the block first touches: the highest node under its footprint.
    double top = -1.0;
    for (int i = 0; i < nn; ++i)
        if (std::abs(x(0, i) - centre.x()) <= 0.5 * o.blockSize &&
            std::abs(x(1, i)) <= 0.5 * o.blockSize)
            top = std::max(top, x(2, i));
    std::vector<int> allNodes(nn);
    for (int i = 0; i < nn; ++i) allNodes[i] = i;
    const bags::RigidContact gauge(mesh, allNodes, *block, o.blockContact);

    // Lumped mass, scaled; the fixed dofs stay.
    const Eigen::VectorXd area = mesh.calcNodalAreas();
    Eigen::VectorXd invMass(3 * nn);
    for (int i = 0; i < nn; ++i)
        for (int c = 0; c < 3; ++c)
            invMass(3 * i + c) = 1.0 / (1150.0 * o.thickness * area(i) * massScale);
    for (int d : model.getFixedDofs()) invMass(d) = 0.0;
    // Stable step: the membrane's dilatational wave (4 mu / rho) across the shortest edge, and
    // the contact penalty's nodal frequency.
    double minEdge = 1e9;
    for (int e = 0; e < mesh.getNumTris(); ++e)
        for (int k = 0; k < 3; ++k)
            minEdge = std::min(
                minEdge,
                (mesh.X.col(mesh.tris(k, e)) - mesh.X.col(mesh.tris((k + 1) % 3, e))).norm());
    const double rhoS = 1150.0 * o.thickness * massScale;  // kg/m^2
    const double mu = o.material->getInitialShearModulus();
    const double c = std::sqrt(4.0 * mu * o.thickness / rhoS);
    const double dtWave = minEdge / c;
    const double dtContact = 2.0 / std::sqrt(o.blockContact.pressurePenalty / rhoS);
    const double dt = cfl * std::min(dtWave, dtContact);
    std::printf(
        "mesh %.1f mm: %d nodes, shortest edge %.2f mm; mass scale %.0f; dt %.3g s "
        "(wave %.3g, contact %.3g); damping %.3g /s; block %.1f mm/s; inflation %.2f s\n",
        o.geometry.meshSize * 1e3, nn, minEdge * 1e3, massScale, dt, dtWave, dtContact, alpha,
        speed * 1e3, tInflate);

    Eigen::VectorXd v = Eigen::VectorXd::Zero(3 * nn);
    bags::EnergyAccumulator acc(nn);
    acc.wantHessian = false;
    auto selfContact = model.getSelfContact();
    const double z0 = top + 0.5e-3;  // block bottom 0.5 mm above the film
    const long steps = static_cast<long>((travel + 0.5e-3) / speed / dt) + 1;
    double nextSample = 0.0;
    const std::clock_t c0 = std::clock();
    const auto w0 = std::chrono::steady_clock::now();
    double ke = 0.0;
    int rebuilds = 0;
    for (long s = 0; s <= steps; ++s) {
        const double t = s * dt;
        const double d = speed * t - 0.5e-3;  // block travel past first touch
        block->setPose(pose(z0 - speed * t));
        if (selfContact && !selfContact->isCandidateListValid(x)) {
            selfContact->updateCandidates(x);
            ++rebuilds;
        }
        acc.resize(nn);
        model.addEnergy(x, acc);
        // Semi-implicit damping: v' = ((1 - a dt/2) v - dt M^-1 g) / (1 + a dt/2).
        const double a = 0.5 * alpha * dt;
        v = ((1.0 - a) * v - dt * invMass.cwiseProduct(acc.grad)) / (1.0 + a);
        for (int i = 0; i < nn; ++i) x.col(i) += dt * v.segment<3>(3 * i);
        if (d >= nextSample) {
            bags::Vec3 f, m;
            gauge.calcWrenchOnShape(x, &f, &m);
            ke = 0.0;
            for (int i = 0; i < 3 * nn; ++i)
                if (invMass(i) > 0.0) ke += 0.5 * v(i) * v(i) / invMass(i) / massScale;
            std::printf(
                "  d = %6.2f mm  F = %8.3f N  p = %7.3f kPa  KE(unscaled) %.3g J  "
                "cpu %.1f s\n",
                d * 1e3, f.z(), model.calcChamberGaugePressure(0, x) * 1e-3, ke,
                double(std::clock() - c0) / CLOCKS_PER_SEC);
            std::fflush(stdout);
            nextSample += every;
        }
        if (!x.allFinite()) {
            std::printf("blew up at step %ld\n", s);
            return 1;
        }
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    std::printf("steps %ld, self-contact rebuilds %d, wall %.1f s, cpu %.1f s, %.3f ms/step\n",
                steps, rebuilds, wall, double(std::clock() - c0) / CLOCKS_PER_SEC,
                1e3 * wall / steps);
    return 0;
}
