#include <bags/LoadTest.h>
#include <bags/Polynomial.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace bags {

namespace {

void require(bool ok, const std::string& option, double value, const std::string& valid) {
    if (ok) return;
    std::ostringstream s;
    s << "load test option '" << option << "' = " << value << " is invalid; " << valid;
    throw std::invalid_argument(s.str());
}

constexpr double kBlockHalfHeight = 0.010;  // [m] thickness of the rigid block is irrelevant

// Everything one curve of the test needs, kept across curves (the bag is deflated in place).
struct Rig {
    std::shared_ptr<MembraneModel> model;
    std::shared_ptr<RigidShape> block;
    std::shared_ptr<RigidShape> floor;
    std::shared_ptr<RigidContact> blockContact;
    std::shared_ptr<SelfContact> self;  // null without self contact
    Eigen::Matrix3Xd x;
    Vec3 blockCentreXY = Vec3::Zero();
    SolverWorkspace workspace;  // factorisation reused across steps
};

// The gas bodies: one (open connection) or one per chamber (orifices).
double getTotalGasMass(const MembraneModel& model) {
    double m = 0.0;
    for (int g = 0; g < model.getNumGases(); ++g) m += model.getGas(g).getMass();
    return m;
}

// Copies of the model's gas bodies (a state to go back to or to integrate the flow from).
std::vector<GasChamber> copyGases(const MembraneModel& model) {
    std::vector<GasChamber> gases;
    for (int g = 0; g < model.getNumGases(); ++g) gases.push_back(model.getGas(g));
    return gases;
}

// Sets the total gas mass, shared among the gas bodies at equal pressure (at a fixed
// temperature a body's share is its volume's share), each resealed at its current volume.
void setTotalGasMass(MembraneModel& model, const Eigen::Matrix3Xd& x, double m) {
    const int ng = model.getNumGases();
    std::vector<double> V(ng);
    double Vsum = 0.0;
    for (int g = 0; g < ng; ++g) Vsum += V[g] = model.calcGasVolume(g, x, nullptr);
    for (int g = 0; g < ng; ++g) model.updGas(g).setMass(m * V[g] / Vsum, V[g]);
}

// Puts back gas bodies copied by copyGases.
void setGases(MembraneModel& model, const std::vector<GasChamber>& gases) {
    for (size_t g = 0; g < gases.size(); ++g) model.updGas(static_cast<int>(g)) = gases[g];
}

// Sets the two gas bodies to `start` with dm [kg] moved from body 0 to body 1 at x.
void moveGas(MembraneModel& model, const std::vector<GasChamber>& start,
             const Eigen::Matrix3Xd& x, double dm) {
    setGases(model, start);
    model.updGas(0).transferMass(-dm, model.calcGasVolume(0, x, nullptr));
    model.updGas(1).transferMass(dm, model.calcGasVolume(1, x, nullptr));
}

// Mass [kg] the orifice passes from body 0 to body 1 during dt [s] from the `start` masses,
// by backward Euler with the volumes held at x.
double calcTransfer(const MembraneModel& model, const std::vector<GasChamber>& start,
                    const Eigen::Matrix3Xd& x, const LoadTestOptions& o, double dt) {
    return calcOrificeTransfer(o.orifice, start[0], model.calcGasVolume(0, x, nullptr), start[1],
                               model.calcGasVolume(1, x, nullptr), dt);
}

double calcTop(const Eigen::Matrix3Xd& x) { return x.row(2).maxCoeff(); }

void placeBlock(Rig& rig, double zBottom) {
    Eigen::Isometry3d X_GS = Eigen::Isometry3d::Identity();
    X_GS.translation() = Vec3(rig.blockCentreXY.x(), rig.blockCentreXY.y(),
                              zBottom + kBlockHalfHeight);
    rig.block->setPose(X_GS);
}


// Solves with step cutting on a scalar control parameter: apply(s) sets the loads for s in
// [s0, s1]; on failure the increment is halved. Returns the number of Newton iterations.
// Newton from x under the model's current stabilisation; false if it does not converge.
bool runNewton(Rig& rig, const LoadTestOptions& o, Eigen::Matrix3Xd& x, SolveSummary* sum) {
    SolverOptions so = o.solver;
    if (so.maxStep == 0.0) so.maxStep = o.geometry.meshSize;  // trust limit: one element
    so.absoluteTolerance = std::max(so.absoluteTolerance, o.residualTolerance * o.peakForce);
    // Non-smooth self contact can stall Newton a little above the tolerance: accept a
    // residual below 0.1 % of the peak force then (recorded per step).
    if (so.acceptableResidual == 0.0) so.acceptableResidual = 1e-3 * o.peakForce;
    try {
        const int before = sum->iterations;
        *sum = solveEquilibrium(*rig.model, x, so, &rig.workspace);
        sum->iterations += before;  // summed over the solves of one step
        return sum->converged;
    } catch (const NumericalError&) {
        return false;
    }
}

// Norm [N] of the force residual over the free dofs at x, without the stabilisation springs
// (for a stabilised state: the springs' force).
double calcFreeResidual(const MembraneModel& model, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(static_cast<int>(x.cols()));
    acc.wantHessian = false;
    model.addEnergy(x, acc);
    for (int d : model.getFixedDofs()) acc.grad(d) = 0.0;
    return acc.grad.norm();
}

// Solves the current loads starting from rig.x. If Newton fails, retries with the
// stabilisation springs anchored at rig.x (slack, wrinkling states), at up to `levels`
// stiffnesses (1x, 10x, 100x the option). A stabilised state is then relaxed: the springs are
// re-anchored at it and the step solved again (a pseudo-time step that moves towards the true
// equilibrium), up to kRelaxations times, each time first trying without springs.
// *stabEnergy is the energy the springs hold at the accepted state: zero when the step ends
// on a spring-free equilibrium (the springs then only chose which of the nearly equal folded
// states the sheet reached; the energy a snapping fold releases on the way is real
// dissipation, not an error of the state). A state accepted with springs records its
// spring-free residual (the springs' force) in sum->residualNorm.
// On success rig.x is updated and contact history committed.
bool trySolve(Rig& rig, const LoadTestOptions& o, SolveSummary* sum, double* stabEnergy,
              int levels = 1) {
    constexpr int kRelaxations = 4;
    *sum = SolveSummary();
    *stabEnergy = 0.0;
    auto accept = [&](const Eigen::Matrix3Xd& x, double energy) {
        rig.x = x;
        rig.model->commitStep(x);
        *stabEnergy = energy;
        return true;
    };
    Eigen::Matrix3Xd x = rig.x;
    if (runNewton(rig, o, x, sum)) return accept(x, 0.0);
    if (o.stabilization <= 0.0) return false;
    for (int level = 0; level < levels; ++level) {
        const double k = o.stabilization * std::pow(10.0, level);
        x = rig.x;
        rig.model->setStabilization(k, x);
        const bool ok = runNewton(rig, o, x, sum);
        double energy = ok ? rig.model->calcStabilizationEnergy(x) : 0.0;
        rig.model->setStabilization(0.0, rig.x);
        if (!ok) continue;
        SolveSummary acceptedSum = *sum;  // the summary of the state that is kept
        for (int r = 0; r < kRelaxations; ++r) {
            Eigen::Matrix3Xd free = x;
            if (runNewton(rig, o, free, sum)) return accept(free, 0.0);
            Eigen::Matrix3Xd next = x;
            rig.model->setStabilization(k, x);
            const bool relaxed = runNewton(rig, o, next, sum);
            const double e = relaxed ? rig.model->calcStabilizationEnergy(next) : 0.0;
            rig.model->setStabilization(0.0, rig.x);
            if (!relaxed) break;
            x = next;
            energy = e;
            acceptedSum = *sum;
        }
        const int iterations = sum->iterations;  // all solves of the step
        *sum = acceptedSum;
        sum->iterations = iterations;
        sum->residualNorm = calcFreeResidual(*rig.model, x);
        return accept(x, energy);
    }
    return false;
}

// Solves the current loads with the gas flowing through the orifice over dt [s] from the
// `start` gas states: the transferred mass dm and the membrane's equilibrium are found together
// by a secant iteration on R(dm) = dm - T(dm), T the backward-Euler transfer at the volumes of
// the equilibrium reached with dm (the diaphragm moves with the pressure difference, so plain
// fixed-point iteration can diverge). Open connection: a plain solve.
bool solveWithFlow(Rig& rig, const LoadTestOptions& o, const std::vector<GasChamber>& start,
                   double dt, SolveSummary* sum, double* stab) {
    if (o.connection != LoadTestOptions::Connection::Orifice) return trySolve(rig, o, sum, stab, 3);
    // Every iterate is solved to the solver's own tolerances: under residualTolerance a state
    // close to the last one would be accepted unmoved, T(dm) evaluated at unchanged volumes and
    // the chamber pressures left wrong (measured: 48.5 Pa instead of 52.8 Pa after the settle of
    // a 0.01 mm orifice). Every iterate starts from the step's friction history (a rejected
    // iterate committed its own), and dm stays inside what either body holds (a secant step
    // can overshoot).
    LoadTestOptions strict = o;
    strict.residualTolerance = 0.0;
    const std::vector<RigidContact::History> history = rig.model->getContactHistory();
    const double dmMax = 0.99 * start[0].getMass(), dmMin = -0.99 * start[1].getMass();
    double dm = calcTransfer(*rig.model, start, rig.x, o, dt);  // predictor: last volumes
    double dmPrev = 0.0, rPrev = 0.0;
    for (int k = 0; k < 30; ++k) {
        dm = std::clamp(dm, dmMin, dmMax);
        rig.model->setContactHistory(history);
        moveGas(*rig.model, start, rig.x, dm);
        if (!trySolve(rig, strict, sum, stab, 3)) return false;
        const double t = calcTransfer(*rig.model, start, rig.x, o, dt);
        const double r = dm - t;
        if (std::abs(r) <= 1e-4 * std::abs(t) + 1e-12 * (start[0].getMass() + start[1].getMass())) {
            moveGas(*rig.model, start, rig.x, t);  // gas at the final volumes
            return true;
        }
        const double next = (k == 0 || r == rPrev) ? t : dm - r * (dm - dmPrev) / (r - rPrev);
        dmPrev = dm;
        rPrev = r;
        dm = next;
    }
    return false;
}

// Ramps a scalar load parameter from s0 to s1 (apply(s) sets the loads), halving the increment
// on failure. Always solves at least once. Each solve starts with the self-contact candidates
// rebuilt at the current state (a ramp can move the sheet far: letting gas out of a slack bag,
// lifting the block, or a return to an earlier state) and may use the stabilisation springs at
// up to 100 times their stiffness, as block steps do.
template <class Apply>
void solveRamp(Rig& rig, const LoadTestOptions& o, double s0, double s1, const Apply& apply,
               const char* what) {
    double s = s0, ds = s1 - s0;
    int cuts = 0;
    bool solved = false;
    while (!solved || s != s1) {
        const double next = std::abs(s1 - s) <= std::abs(ds) * (1.0 + 1e-9) ? s1 : s + ds;
        apply(next);
        SolveSummary sum;
        double stab = 0.0;
        if (rig.self) rig.self->updateCandidates(rig.x);
        if (trySolve(rig, o, &sum, &stab, 3)) {
            s = next;
            solved = true;
            if (sum.iterations < 8) ds *= 2.0;
        } else {
            apply(s);
            ds *= 0.5;
            if (++cuts > 30) throw NumericalError(std::string("no convergence while ") + what);
        }
    }
}

// Top of the bag under the block's footprint [m] (where the block first touches).
double calcTopUnderBlock(const Eigen::Matrix3Xd& x, const Vec3& centre, double half) {
    double top = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < x.cols(); ++i)
        if (std::abs(x(0, i) - centre.x()) <= half && std::abs(x(1, i) - centre.y()) <= half)
            top = std::max(top, x(2, i));
    return std::isfinite(top) ? top : calcTop(x);
}

}  // namespace

void LoadTestOptions::validate() const {
    geometry.validate();
    if (!material) throw std::invalid_argument("load test option 'material' is not set");
    require(thickness > 0.0 && thickness < 0.01, "thickness", thickness, "use 0 < t < 10 mm");
    require(density >= 0.0, "density", density, "use a density >= 0 kg/m^3");
    require(wrinklingResidual > 0.0 && wrinklingResidual < 0.1, "wrinklingResidual",
            wrinklingResidual, "use 0 < residual < 0.1 (e.g. 1e-3)");
    gas.validate();
    if (gasMasses.empty()) throw std::invalid_argument("load test option 'gasMasses' is empty");
    for (double m : gasMasses)
        require(m > 0.0 && m < 1.0, "gasMasses", m, "use masses > 0 (in kg inside; e.g. 3.5 g)");
    require(blockSize > 0.0 && blockSize <= geometry.longSide, "blockSize", blockSize,
            "use 0 < block <= the airbag's long side");
    require(loadingRate > 0.0, "loadingRate", loadingRate, "use a positive rate (e.g. 10 mm/min)");
    require(peakForce > 0.0, "peakForce", peakForce, "use a positive force (e.g. 50 N)");
    require(displacementStep > 0.0 && displacementStep <= 0.02, "displacementStep",
            displacementStep, "use 0 < step <= 20 mm");
    require(stiffnessFrom >= 0.0 && stiffnessTo > stiffnessFrom && stiffnessTo <= peakForce,
            "stiffnessTo", stiffnessTo, "use 0 <= from < to <= peak force");
    require(polynomialOrder >= 1 && polynomialOrder <= 8, "polynomialOrder", polynomialOrder,
            "use an order from 1 to 8");
    if (connection == Connection::Orifice) {
        orifice.validate();
        require(settleTime >= 0.0 && std::isfinite(settleTime), "settleTime", settleTime,
                "use a time >= 0 s (the chambers' rest before each curve, e.g. 1000 s)");
        require(settleSteps >= 1 && settleSteps <= 60, "settleSteps", settleSteps,
                "use 1 to 60 backward-Euler steps (e.g. 10)");
        if (!geometry.diaphragm)
            throw std::invalid_argument(
                "load test option 'connection' = orifice needs the two chambers; set the "
                "geometry's diaphragm (or use the open connection)");
    }
    require(residualTolerance >= 0.0 && residualTolerance <= 0.05, "residualTolerance",
            residualTolerance, "use a fraction of the peak force from 0 to 0.05 (e.g. 1e-3)");
    require(stabilization >= 0.0, "stabilization", stabilization,
            "use a stiffness per area >= 0 Pa/m (0 disables it; e.g. 1e4)");
    blockContact.validate();
    floorContact.validate();
    solver.validate();
}

std::vector<double> getSeedStiffnessPolynomial() {
    return {-0.945, 8.394, -25.707, 32.714, -17.181, 6.196};
}

LoadTestResult runLoadTest(const LoadTestOptions& o, const LoadTestObserver& observer) {
    o.validate();
    const auto wallStart = std::chrono::steady_clock::now();
    const Mesh mesh = makeDoubleWedgeBag(o.geometry);

    Rig rig;
    auto material = std::make_shared<WrinklingMaterial>(o.material->clone(), o.wrinklingResidual);
    rig.model = std::make_shared<MembraneModel>(mesh, material, o.thickness);
    if (o.gravity && o.density > 0.0) rig.model->setGravity(o.density, Vec3(0, 0, -9.81));

    // Contact candidates: every node not bonded to the bed board.
    std::vector<char> isSupport(mesh.getNumNodes(), 0);
    for (int n : mesh.supportNodes) isSupport[n] = 1;
    std::vector<int> freeNodes;
    for (int n = 0; n < mesh.getNumNodes(); ++n)
        if (!isSupport[n]) freeNodes.push_back(n);

    rig.floor = makePlane();
    rig.model->addRigidContact(
        std::make_shared<RigidContact>(mesh, freeNodes, *rig.floor, o.floorContact));
    rig.block = makeBox(Vec3(0.5 * o.blockSize, 0.5 * o.blockSize, kBlockHalfHeight),
                        std::min(1e-3, 0.1 * o.blockSize));
    rig.blockContact = std::make_shared<RigidContact>(mesh, freeNodes, *rig.block, o.blockContact);
    rig.model->addRigidContact(rig.blockContact);
    if (o.selfContact) {
        SelfContact::Options so;
        so.pressurePenalty = o.blockContact.pressurePenalty;
        so.thickness = std::max(2.0 * o.thickness, 0.5e-3);
        rig.self = std::make_shared<SelfContact>(mesh, so);
        rig.model->setSelfContact(rig.self);
    }
    SelfContact* const self = rig.self.get();
    rig.x = mesh.X;
    // Block above the apex ridge, parked well clear while inflating.
    {
        int top = 0;
        mesh.X.row(2).maxCoeff(&top);
        rig.blockCentreXY = Vec3(mesh.X(0, top), 0.0, 0.0);
    }
    placeBlock(rig, calcTop(rig.x) + 0.2);

    // Inflate: a prescribed pressure ramp shapes the flat panels, then the gas takes over.
    const int nc = static_cast<int>(mesh.chambers.size());
    std::vector<int> allChambers(nc);
    for (int c = 0; c < nc; ++c) allChambers[c] = c;
    {
        double Vflat = 0.0;
        for (int c = 0; c < nc; ++c) Vflat += calcChamberVolume(mesh, c, rig.x);
        GasChamber probe(o.gas, o.gasMasses.front());
        probe.seal(Vflat);
        const double pTarget = std::clamp(probe.calcGaugePressure(Vflat), 200.0, 5000.0);
        solveRamp(rig, o, 0.0, pTarget,
                  [&](double p) {
                      for (int c = 0; c < nc; ++c) rig.model->setChamberPressure(c, p);
                  },
                  "inflating the airbag");
        for (int c = 0; c < nc; ++c) rig.model->setChamberPressure(c, 0.0);
        // Seal the gas that is in the bag at this pressure (one body, or one per chamber
        // behind orifices); the first curve's ramp then takes the mass to its value in steps
        // it can cut.
        auto sealGas = [&](const std::vector<int>& chambers) {
            double V = 0.0;
            for (int c : chambers) V += calcChamberVolume(mesh, c, rig.x);
            const double mSeal = (o.gas.ambientPressure + pTarget) * V /
                                 (o.gas.getSpecificGasConstant() * o.gas.temperature);
            GasChamber gas(o.gas, mSeal);
            gas.seal(V);
            rig.model->addGas(gas, chambers);
        };
        if (o.connection == LoadTestOptions::Connection::Orifice) {
            for (int c = 0; c < nc; ++c) sealGas({c});
        } else {
            sealGas(allChambers);
        }
    }

    LoadTestResult result;
    for (size_t k = 0; k < o.gasMasses.size(); ++k) {
        LoadCurve curve;
        curve.gasMass = o.gasMasses[k];
        // Let the gas out (or in) to this curve's mass in small mass steps, block clear.
        placeBlock(rig, calcTop(rig.x) + 0.05);
        const double m0 = getTotalGasMass(*rig.model);
        solveRamp(rig, o, m0, curve.gasMass,
                  [&](double m) { setTotalGasMass(*rig.model, rig.x, m); },
                  "changing the gas mass");
        if (o.connection == LoadTestOptions::Connection::Orifice && o.settleTime > 0.0) {
            // Before loading, the chambers settle towards one pressure (a long wait, 1000 s
            // by default). Backward Euler in steps doubling in length (0.98 s first of 10):
            // the pressure difference falls fastest at the start. On the 20 mm rig with a
            // 0.01 mm orifice one step leaves 53.34 Pa, 10 steps 52.7988 Pa, 40 steps
            // 52.7982 Pa (tests/bags/LoadTestTest.cpp).
            const int n = o.settleSteps;
            const double first = o.settleTime / (std::pow(2.0, n) - 1.0);
            for (int i = 0; i < n; ++i) {
                SolveSummary sum;
                double stab = 0.0;
                if (!solveWithFlow(rig, o, copyGases(*rig.model), first * std::pow(2.0, i), &sum,
                                   &stab))
                    throw NumericalError(
                        "no convergence while the chambers settle through the orifice");
            }
        }
        // setMass reseals at the current volume: isothermal p V = m R T holds whatever the
        // sealing volume, so the state is exact; for adiabatic gases the reference is the
        // state at this mass, as in a slow let-down at room temperature.
        const double top = calcTopUnderBlock(rig.x, rig.blockCentreXY, 0.5 * o.blockSize);
        curve.unloadedHeight = top;
        curve.inflatedVolume = 0.0;
        for (int g = 0; g < rig.model->getNumGases(); ++g)
            curve.inflatedVolume += rig.model->calcGasVolume(g, rig.x, nullptr);
        curve.inflatedGaugePressure = rig.model->calcChamberGaugePressure(0, rig.x);
        if (self) self->updateCandidates(rig.x);
        const Eigen::Matrix3Xd xUnloaded = rig.x;

        auto record = [&](double disp, bool loading, const SolveSummary& sum, double stabEnergy) {
            LoadStep st;
            st.curve = static_cast<int>(k);
            st.step = static_cast<int>(curve.steps.size());
            st.loading = loading;
            st.displacement = disp;
            const double prevDisp = curve.steps.empty() ? 0.0 : curve.steps.back().displacement;
            const double prevTime = curve.steps.empty() ? 0.0 : curve.steps.back().time;
            st.time = prevTime + std::abs(disp - prevDisp) / o.loadingRate;
            Vec3 f, tq;
            rig.blockContact->calcWrenchOnShape(rig.x, &f, &tq);
            st.force = f.z();
            for (int c = 0; c < nc; ++c) {
                st.gaugePressure.push_back(rig.model->calcChamberGaugePressure(c, rig.x));
                st.volume.push_back(calcChamberVolume(mesh, c, rig.x));
            }
            for (int c = 0; c < nc; ++c) {
                // A chamber's share of its gas body, by volume (equal pressure inside a body).
                const int g = rig.model->getChamberGas(c);
                const double Vg = rig.model->calcGasVolume(g, rig.x, nullptr);
                st.gasMass.push_back(rig.model->getGas(g).getMass() * st.volume[c] / Vg);
            }
            st.newtonIterations = sum.iterations;
            st.residual = sum.residualNorm;
            st.stabilizationEnergy = stabEnergy;
            curve.steps.push_back(st);
            if (observer) observer(st, mesh, rig.x);
            return st.force;
        };

        record(0.0, true, SolveSummary(), 0.0);
        // Moves the block to travel `to` (from the last converged state); on failure the
        // caller shortens the step.
        // With an orifice the gas flows over the step's time while the membrane settles
        // (solveWithFlow). A failed step restores state and gas.
        auto advance = [&](double to, SolveSummary* sum, double* stab) {
            const std::vector<GasChamber> gasBefore = copyGases(*rig.model);
            const Eigen::Matrix3Xd xBefore = rig.x;
            const std::vector<RigidContact::History> history = rig.model->getContactHistory();
            const double dt = std::abs(to - curve.steps.back().displacement) / o.loadingRate;
            placeBlock(rig, top - to);
            if (self) self->updateCandidates(rig.x);
            try {
                if (solveWithFlow(rig, o, gasBefore, dt, sum, stab)) return true;
            } catch (const NumericalError&) {
                // e.g. a gas transfer no chamber could give: the step fails like any other
            }
            setGases(*rig.model, gasBefore);
            rig.x = xBefore;
            rig.model->setContactHistory(history);
            return false;
        };
        // A step that cannot be solved even at the smallest increment ends the branch; the
        // curve keeps what converged and says why it stopped.
        auto fail = [&](const char* branch, double disp) {
            std::ostringstream s;
            s << "no convergence " << branch << " at block travel " << disp * 1e3 << " mm";
            curve.failure = s.str();
        };
        // Loading: displacement control, adaptive, aiming the last step at the peak force.
        double disp = 0.0, ds = o.displacementStep, force = 0.0, stiffnessEstimate = 0.0;
        const double minStep = 5e-5;  // [m] smaller steps rarely rescue a slack curve
        const double maxDisp = top - 0.002;  // the block stops 2 mm above the bed board
        while (force < o.peakForce * (1.0 - 1e-3)) {
            double step = std::min(ds, o.displacementStep);
            if (stiffnessEstimate > 0.0)
                step = std::min(step, 1.05 * (o.peakForce - force) / stiffnessEstimate);
            step = std::max(step, minStep);
            step = std::min(step, maxDisp - disp);  // the last step ends on the stop
            if (step < minStep) {
                // The slack bag is pressed flat under the block: with penalty contact (1 mm
                // of penetration per 10 kPa by default) the last 2 mm cannot be resolved.
                std::ostringstream r;
                r << "bottomed out: the block is within 2 mm of the bed board at block travel "
                  << disp * 1e3 << " mm (" << force << " N)";
                curve.failure = r.str();
                break;
            }
            SolveSummary sum;
            double stab = 0.0;
            if (!advance(disp + step, &sum, &stab)) {
                placeBlock(rig, top - disp);
                ds = 0.5 * step;
                if (ds < minStep) {
                    fail("loading", disp);
                    break;
                }
                continue;
            }
            const double prevForce = force;
            disp += step;
            force = record(disp, true, sum, stab);
            const double k = (force - prevForce) / step;
            if (k > 0.0) stiffnessEstimate = k;
            if (sum.iterations < 6) ds = std::min(2.0 * step, o.displacementStep);
        }
        curve.reachedPeak = force >= o.peakForce * (1.0 - 1e-3);
        // Unloading: back up the same way until the block leaves the bag.
        ds = o.displacementStep;
        while (o.unload && disp > 0.0) {
            const double step = std::min(ds, disp);
            SolveSummary sum;
            double stab = 0.0;
            if (!advance(disp - step, &sum, &stab)) {
                placeBlock(rig, top - disp);
                ds = 0.5 * step;
                if (ds < minStep) {
                    fail("unloading", disp);
                    break;
                }
                continue;
            }
            disp = std::max(disp - step, 0.0);
            if (record(disp, false, sum, stab) <= 0.0) break;  // block has left
            if (sum.iterations < 6) ds = std::min(2.0 * step, o.displacementStep);
        }
        if (disp > 0.0) {
            // Lift the block clear so the next gas mass starts from a free bag; if even that
            // cannot be solved, go back to this mass's unloaded equilibrium (the contacts are
            // frictionless or their history is reset by the return).
            try {
                solveRamp(rig, o, disp, 0.0, [&](double d) { placeBlock(rig, top - d); },
                          "lifting the block after a failed step");
            } catch (const NumericalError&) {
                placeBlock(rig, top + 0.05);
                rig.x = xUnloaded;  // the next ramp rebuilds the self-contact candidates
                rig.model->commitStep(rig.x);
                rig.workspace.reset();
            }
        }
        // How much the stabilisation carried: steps accepted with springs, and the energy the
        // springs held at those states, summed over the steps so far (re-anchoring releases
        // it), against the block's work so far (trapezoidal): the largest ratio along the
        // loading branch.
        {
            double work = 0.0, held = 0.0;
            for (size_t i = 0; i < curve.steps.size(); ++i) {
                const LoadStep& st = curve.steps[i];
                if (st.stabilizationEnergy > 0.0) ++curve.stabilizedSteps;
                if (!st.loading || i == 0) continue;
                const LoadStep& prev = curve.steps[i - 1];
                work += 0.5 * (st.force + prev.force) * (st.displacement - prev.displacement);
                held += st.stabilizationEnergy;
                if (work > 0.0 && held > 0.0)
                    curve.stabilizationShare = std::max(curve.stabilizationShare, held / work);
            }
        }
        // Stiffness over the force range, loading branch.
        const LinearFit lf = calcRangeStiffness(curve.steps, o.stiffnessFrom, o.stiffnessTo);
        curve.stiffness = lf.slope;
        curve.r2 = lf.r2;
        result.curves.push_back(std::move(curve));
    }
    classifyStages(result.curves);
    // k(m) fit in the seed's units: k [N/mm] of m [g].
    std::vector<double> mg, kk;
    for (const LoadCurve& c : result.curves)
        if (std::isfinite(c.stiffness)) mg.push_back(c.gasMass * 1e3), kk.push_back(c.stiffness * 1e-3);
    if (static_cast<int>(mg.size()) > o.polynomialOrder)
        result.kFit = fitPolynomial(mg, kk, o.polynomialOrder);
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
    return result;
}

LinearFit calcRangeStiffness(const std::vector<LoadStep>& steps, double from, double to) {
    // Only a curve that spans the whole range has a stiffness over it.
    std::vector<double> d, f;
    double fmax = 0.0;
    for (const LoadStep& st : steps) {
        if (!st.loading) continue;
        fmax = std::max(fmax, st.force);
        if (st.force >= from && st.force <= to) d.push_back(st.displacement), f.push_back(st.force);
    }
    if (d.size() >= 3 && fmax >= to * (1.0 - 1e-3)) return fitLine(d, f);
    LinearFit none;
    none.slope = none.intercept = none.r2 = std::numeric_limits<double>::quiet_NaN();
    return none;
}

void classifyStages(std::vector<LoadCurve>& curves, double linearR2) {
    // Stage 3: masses below the one with the least stiffness (stiffness rises again as gas is
    // let out). Above it: stage 1 if the 10-35 N range is linear (r2 >= linearR2), else 2.
    double kMin = std::numeric_limits<double>::infinity(), mAtMin = 0.0;
    for (const LoadCurve& c : curves)
        if (std::isfinite(c.stiffness) && c.stiffness < kMin) kMin = c.stiffness, mAtMin = c.gasMass;
    for (LoadCurve& c : curves) {
        if (!std::isfinite(c.stiffness)) {
            c.stage = 0;
        } else if (c.gasMass < mAtMin - 1e-12) {
            c.stage = 3;
        } else {
            c.stage = c.r2 >= linearR2 ? 1 : 2;
        }
    }
}

}  // namespace bags
