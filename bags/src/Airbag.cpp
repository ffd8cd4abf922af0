#include <bags/Airbag.h>
#include <bags/Material.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace bags {

namespace {

void require(bool ok, const char* option, double value, const char* valid) {
    if (ok) return;
    std::ostringstream s;
    s << "airbag option '" << option << "' = " << value << " is invalid; " << valid;
    throw std::invalid_argument(s.str());
}

// splitmix64: a fixed, portable generator (std:: distributions differ between libraries).
struct SplitMix64 {
    std::uint64_t state;
    std::uint64_t next() {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  ///< [0, 1)
};

constexpr double kPi = 3.14159265358979323846;

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double s) {
    if (s >= 1.0) return b;
    if (s <= 0.0) return a;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    const Eigen::Quaterniond qa(a.rotation()), qb(b.rotation());
    X.linear() = qa.slerp(s, qb).toRotationMatrix();
    X.translation() = (1.0 - s) * a.translation() + s * b.translation();
    return X;
}

// Pose rotated by the rotation vector w [rad] about Ground axes through its origin and moved
// by t [m].
Eigen::Isometry3d perturbPose(const Eigen::Isometry3d& X, const Vec3& w, const Vec3& t) {
    Eigen::Isometry3d Y = X;
    const double angle = w.norm();
    if (angle > 0.0)
        Y.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() * X.linear();
    Y.translation() += t;
    return Y;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Imperfection

void Imperfection::validate() const {
    require(amplitude >= 0.0 && amplitude <= 0.01, "imperfection.amplitude", amplitude,
            "use 0 to 10 mm (e.g. 0.5 mm)");
}

void applyImperfection(Mesh& mesh, const Imperfection& imp) {
    imp.validate();
    if (imp.amplitude == 0.0) return;
    const int nn = mesh.getNumNodes();
    // Reference vertex normals (area weighted); a node of a seam or of the internal wall gets
    // the mean of its panels' normals (orientation is immaterial for a random offset).
    Eigen::Matrix3Xd normal = Eigen::Matrix3Xd::Zero(3, nn);
    for (int e = 0; e < mesh.getNumTris(); ++e) {
        const Vec3 a = mesh.X.col(mesh.tris(0, e)), b = mesh.X.col(mesh.tris(1, e)),
                   c = mesh.X.col(mesh.tris(2, e));
        Vec3 n = (b - a).cross(c - a);
        // Align with a fixed hemisphere so that the two sides of a shared wall do not cancel.
        const int k = [&] {
            int i;
            n.cwiseAbs().maxCoeff(&i);
            return i;
        }();
        if (n(k) < 0.0) n = -n;
        for (int v = 0; v < 3; ++v) normal.col(mesh.tris(v, e)) += n;
    }
    // Smooth random field: a sum of plane waves, wavelengths 60-240 mm, random directions and
    // phases, drawn in a fixed order from the seed.
    constexpr int kWaves = 12;
    SplitMix64 rng{imp.seed * 0x2545F4914F6CDD1Dull + 0x1234567ull};
    Vec3 k[kWaves];
    double phase[kWaves];
    for (int w = 0; w < kWaves; ++w) {
        const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * kPi * rng.uniform();
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double lambda = 0.060 * std::pow(4.0, rng.uniform());
        k[w] = (2.0 * kPi / lambda) * Vec3(r * std::cos(phi), r * std::sin(phi), z);
        phase[w] = 2.0 * kPi * rng.uniform();
    }
    std::vector<char> support(nn, 0);
    for (int n : mesh.supportNodes) support[n] = 1;
    Eigen::VectorXd f(nn);
    double fmax = 0.0;
    for (int i = 0; i < nn; ++i) {
        double s = 0.0;
        for (int w = 0; w < kWaves; ++w) s += std::sin(k[w].dot(mesh.X.col(i)) + phase[w]);
        f(i) = support[i] ? 0.0 : s;
        fmax = std::max(fmax, std::abs(f(i)));
    }
    if (fmax == 0.0) return;
    for (int i = 0; i < nn; ++i) {
        const double len = normal.col(i).norm();
        if (support[i] || len == 0.0) continue;
        mesh.X.col(i) += (imp.amplitude * f(i) / fmax / len) * normal.col(i);
    }
}

// ---------------------------------------------------------------------------------------------
// AirbagSpec

void AirbagSpec::validate() const {
    if (mesh.getNumNodes() == 0) geometry.validate();
    if (!material) throw std::invalid_argument("airbag option 'material' is not set");
    require(thickness > 0.0 && thickness < 0.01, "thickness", thickness, "use 0 < t < 10 mm");
    require(density >= 0.0, "density", density, "use a density >= 0 kg/m^3");
    require(wrinklingResidual > 0.0 && wrinklingResidual < 0.1, "wrinklingResidual",
            wrinklingResidual, "use 0 < residual < 0.1 (e.g. 1e-3)");
    require(bendingStiffness >= 0.0 && bendingStiffness < 1.0, "bendingStiffness", bendingStiffness,
            "use 0 (a pure membrane) to 1 N m");
    require(gravity.allFinite(), "gravity", gravity.norm(), "use a finite acceleration");
    gas.validate();
    prony.validate();
    if (connection == Connection::Orifice) orifice.validate();
    if (connection == Connection::Orifice && gas.heatTimeConstant > 0.0)
        throw std::invalid_argument(
            "airbag option 'gas.heatTimeConstant' (heat exchange) needs the open connection; "
            "the orifice connection does not carry the heat of the flow");
    imperfection.validate();
    if (!material->isIsotropic())
        for (const Eigen::Isometry3d& X : cluster)
            if (!X.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12))
                throw std::invalid_argument(
                    "airbag option 'cluster': a rotated copy of an anisotropic film's bag (its "
                    "warp follows the bag frame's x); place the copies without rotation");
    bedContact.validate();
    require(selfContactPenalty > 0.0, "selfContactPenalty", selfContactPenalty, "use > 0 Pa/m");
    require(stabilization >= 0.0, "stabilization", stabilization,
            "use a stiffness per area >= 0 Pa/m (0 disables it; e.g. 1e4)");
    require(damping >= 0.0 && std::isfinite(damping), "damping", damping,
            "use a stiffness per area >= 0 Pa/m (0: no damper; e.g. 1e5)");
    require(forceTolerance > 0.0 && forceTolerance <= 1.0, "forceTolerance", forceTolerance,
            "use 0 < tolerance <= 1 N (e.g. 0.05 N)");
    require(threads >= 0 && threads <= 256, "threads", threads, "use 0 (default) to 256");
    if (stepping != Stepping::QuasiStatic) {
        dynamics.validate();
        require(density > 0.0, "density", density,
                "the dynamic stepping moves the film's mass: use a density > 0 kg/m^3");
        if (stepping == Stepping::Relaxed && gas.heatTimeConstant > 0.0)
            throw std::invalid_argument(
                "airbag option 'stepping' = relaxed does not take the gas's heat exchange "
                "(gas.heatTimeConstant = " +
                std::to_string(gas.heatTimeConstant) +
                " s); valid: quasi-static or dynamic stepping with it, or no heat exchange");
    }
    require(cluster.size() <= 64, "cluster", static_cast<double>(cluster.size()),
            "use 0 to 64 bags in one module");
    if (cluster.size() > 1) {
        if (!selfContact)
            throw std::invalid_argument(
                "airbag option 'cluster' places " + std::to_string(cluster.size()) +
                " bags in one module: their walls meet through its self-contact, so "
                "'selfContact' must be on");
        if (connection != Connection::Open)
            throw std::invalid_argument(
                "airbag option 'cluster' needs the open connection (one gas body per bag)");
    }
    if (sharedAir && cluster.size() < 2)
        throw std::invalid_argument(
            "airbag option 'sharedAir' joins the air of a cluster's bags; it needs a cluster of "
            "two or more bags (the cluster has " +
            std::to_string(cluster.size()) + ")");
    solver.validate();
}

// ---------------------------------------------------------------------------------------------
// Airbag

struct Airbag::Snapshot {
    Eigen::Matrix3Xd x;
    std::vector<GasChamber> gases;
    std::vector<RigidContact::History> history;
    ViscousState viscous;  // the film's internal variables (empty without Prony terms)
    std::vector<Eigen::Isometry3d> poses;
    double time = 0.0;
    Eigen::Matrix3Xd v;  // the film's velocity (dynamic stepping; empty: at rest)
    // The film's stable step over the root of its mass scale [s] (0: to be estimated) and the
    // steps advanced since it was estimated: part of the state, so that a step repeated from
    // a commit or a checkpoint is integrated with the same sub-steps.
    double stableStep = 0.0;
    int stableAge = 0;
};

struct Airbag::Impl {
    AirbagSpec spec;
    Mesh mesh;
    std::shared_ptr<MembraneModel> model;
    std::shared_ptr<SelfContact> self;
    std::vector<int> freeNodes;
    struct Shape {
        std::shared_ptr<RigidShape> shape;
        std::shared_ptr<RigidContact> contact;
        Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
    };
    std::vector<Shape> shapes;
    std::unique_ptr<RigidShape> bed;
    std::shared_ptr<RigidContact> bedContact;
    Eigen::Matrix3Xd x;
    // The film's velocity [m/s] (dynamic stepping: at the half sub-steps; zero at rest).
    Eigen::Matrix3Xd v;
    // The film's inertia (dynamic stepping), built at the first dynamic step (it needs every
    // shape's contact penalty for its stable step).
    std::unique_ptr<FilmDynamics> film;
    double stableStep = 0.0;  // as Snapshot::stableStep
    int stableAge = 0;
    // How advance() moves the bag: one of the steppers below the Impl.
    struct Stepper {
        virtual ~Stepper() = default;
        /// From the committed state to the shapes' targets and the gas set, over dt.
        virtual AdvanceSummary advance(Impl& m, double dt, int maxCuts) = 0;
    };
    std::unique_ptr<Stepper> stepper;
    struct QuasiStaticStepper;
    struct DynamicStepper;
    struct RelaxedStepper;
    SolverWorkspace workspace;
    double time = 0.0;
    double meanEdge = 0.0;
    // The bags of the module (one unless AirbagSpec::cluster): node range, chambers and
    // (once inflated) gas bodies of each.
    int numBags = 1;
    int nodesPerBag = 0;
    std::vector<std::vector<int>> bagChambers;
    std::vector<std::vector<int>> bagGases;
    // Gas flow per bag for the following advance() calls.
    std::vector<double> massFlow;
    std::vector<char> hasTarget;
    std::vector<double> targetMass;
    std::shared_ptr<const Snapshot> committed;
    bool inflated = false;
    // The last committed step: node increment and the shapes' translations (predictor).
    Eigen::Matrix3Xd lastIncrement;
    Eigen::VectorXd lastShapeDelta;
    // Where the last converged advance() since the commit ended (empty: none); a repeated
    // advance of the same step starts from it (AirbagSpec::warmStart).
    Eigen::Matrix3Xd lastAdvanced;
    bool wholeStep = false;  // the sub-step being solved is the whole of advance()'s step
    // Newton alone (no damper, no stabilisation springs): the relaxed stepping's first try.
    bool plainNewton = false;

    Eigen::VectorXd shapeTranslations(const std::vector<Eigen::Isometry3d>& poses) const {
        Eigen::VectorXd t(3 * poses.size());
        for (size_t i = 0; i < poses.size(); ++i) t.segment<3>(3 * i) = poses[i].translation();
        return t;
    }
    std::vector<Eigen::Isometry3d> currentPoses() const {
        std::vector<Eigen::Isometry3d> p;
        for (const Shape& sh : shapes) p.push_back(sh.shape->getPose());
        return p;
    }
    void forgetIncrement() {
        lastIncrement.resize(3, 0);
        lastShapeDelta.resize(0);
        lastAdvanced.resize(3, 0);
    }
    // Starts Newton from where the last converged advance of this step ended, if that has
    // the smaller force residual at the loads now set. True if taken.
    bool warmStart() {
        if (!spec.warmStart || !wholeStep || lastAdvanced.cols() != x.cols()) return false;
        double rWarm = std::numeric_limits<double>::infinity();
        try {
            rWarm = calcFreeResidual(lastAdvanced);
        } catch (const NumericalError&) {
            return false;
        }
        if (!(std::isfinite(rWarm) && rWarm < calcFreeResidual(x))) return false;
        x = lastAdvanced;
        return true;
    }
    // A start for Newton: the last committed step's node increment, scaled by how far the
    // shapes move now along the way they moved then (a secant predictor on a smooth path).
    // Taken only if its force residual is below that of the unmoved state.
    void predict(const std::vector<Eigen::Isometry3d>& start) {
        if (!spec.predictor || lastIncrement.cols() != x.cols() || lastShapeDelta.size() == 0)
            return;
        const Eigen::VectorXd d = shapeTranslations(currentPoses()) - shapeTranslations(start);
        const double last2 = lastShapeDelta.squaredNorm();
        if (!(last2 > 0.0) || d.norm() == 0.0) return;
        const double cosine = d.dot(lastShapeDelta) / (d.norm() * std::sqrt(last2));
        const double ratio = d.dot(lastShapeDelta) / last2;
        if (!(cosine > 0.99 && ratio > 0.0 && ratio <= 4.0)) return;
        const Eigen::Matrix3Xd xPred = x + ratio * lastIncrement;
        double rPred = std::numeric_limits<double>::infinity();
        try {
            rPred = calcFreeResidual(xPred);
        } catch (const NumericalError&) {
            return;
        }
        if (std::isfinite(rPred) && rPred < calcFreeResidual(x)) x = xPred;
    }

    // --- state
    std::vector<GasChamber> copyGases() const {
        std::vector<GasChamber> g;
        for (int i = 0; i < model->getNumGases(); ++i) g.push_back(model->getGas(i));
        return g;
    }
    void setGases(const std::vector<GasChamber>& g) {
        for (size_t i = 0; i < g.size(); ++i) model->updGas(static_cast<int>(i)) = g[i];
    }
    double totalMass() const {
        double m = 0.0;
        for (int g = 0; g < model->getNumGases(); ++g) m += model->getGas(g).getMass();
        return m;
    }
    double bagMass(int b) const {
        if (spec.sharedAir) {
            // Bag b's share of the shared air: its chambers' share of the air's volume.
            if (bagGases[b].empty()) return 0.0;
            const int g = bagGases[b].front();
            double Vb = 0.0;
            for (int c : bagChambers[b]) Vb += calcChamberVolume(mesh, c, x);
            return model->getGas(g).getMass() * Vb / model->calcGasVolume(g, x, nullptr);
        }
        double m = 0.0;
        for (int g : bagGases[b]) m += model->getGas(g).getMass();
        return m;
    }
    // No gas is let in or out of any bag over the following advance().
    bool areFlowsStill() const {
        for (int b = 0; b < numBags; ++b)
            if (massFlow[b] != 0.0 && !(hasTarget[b] && targetMass[b] == bagMass(b))) return false;
        return true;
    }
    // ... over a step of dt: no flow set, and with time passing, none through an orifice
    // between chambers or a leak, and no heat exchange.
    bool isGasStill(double dt) const {
        if (!areFlowsStill()) return false;
        if (dt <= 0.0) return true;
        return (spec.connection != AirbagSpec::Connection::Orifice || model->getNumGases() < 2) &&
               spec.gas.leakConductance == 0.0 && spec.gas.heatTimeConstant == 0.0;
    }
    // Every gas body's volume [m^3] at x.
    std::vector<double> calcAllGasVolumes() const {
        std::vector<double> V(model->getNumGases());
        for (int g = 0; g < model->getNumGases(); ++g) V[g] = model->calcGasVolume(g, x, nullptr);
        return V;
    }
    // Leakage over dt (GasOptions::leakConductance): each gas body loses, at its volume at x
    // held over the step, what its share of the bag's conductance (by volume) lets out.
    void leak(double dt) {
        const double C = spec.gas.leakConductance;
        if (!(C > 0.0) || !(dt > 0.0)) return;
        if (spec.sharedAir) {
            // Every bag's seams leak the shared air: numBags times one bag's conductance.
            const int g = bagGases.front().front();
            const double V = model->calcGasVolume(g, x, nullptr);
            GasChamber& gas = model->updGas(g);
            gas.transferMass(gas.calcLeakTransfer(V, dt, C * numBags), V);
            return;
        }
        for (int b = 0; b < numBags; ++b) {
            double Vsum = 0.0;
            const std::vector<double> V = calcGasVolumes(b, &Vsum);
            for (size_t i = 0; i < V.size(); ++i) {
                GasChamber& g = model->updGas(bagGases[b][i]);
                g.transferMass(g.calcLeakTransfer(V[i], dt, C * V[i] / Vsum), V[i]);
            }
        }
    }
    // A quasi-static change of gas (no time) ends with the gas at the room's temperature at
    // its equilibrium volume: each ramp step seals the gas at the room's temperature at the
    // volume it starts from, and a gas that compresses adiabatically (heat exchange) would
    // leave the last solve warmer or colder. Resealed at the volume reached and solved again
    // Sets a value for a scope and puts the old one back when the scope ends.
    struct ScopedValue {
        ScopedValue(double& ref, double value) : ref(ref), old(ref) { ref = value; }
        ~ScopedValue() { ref = old; }
        double& ref;
        double old;
    };
    // (to the solver's own tolerances) until the temperature is the room's to 1e-5 K.
    void settleAtRoomTemperature() {
        const ScopedValue tight(spec.forceTolerance, spec.solver.absoluteTolerance);
        const double Tr = spec.gas.temperature;
        for (int k = 0; k < 40; ++k) {
            const std::vector<double> V = calcAllGasVolumes();
            double worst = 0.0;
            for (int g = 0; g < model->getNumGases(); ++g)
                worst = std::max(worst, std::abs(model->getGas(g).calcTemperature(V[g]) - Tr));
            if (worst <= 1e-5) return;
            for (int g = 0; g < model->getNumGases(); ++g)
                model->updGas(g).setTemperature(Tr, V[g]);
            SolveSummary sum;
            double stab = 0.0;
            if (self) self->updateCandidates(x);
            if (!trySolve(&sum, &stab, 3, spec.solver))
                throw NumericalError(
                    "no convergence while the gas settles at the room's temperature");
        }
        throw NumericalError("the gas did not settle at the room's temperature in 40 passes");
    }
    // Solves the current loads with the gas exchanging heat with the room over dt [s]
    // (GasOptions::heatTimeConstant) from the `start` gases at volumes V0: each gas's
    // temperature at the end of the step is GasChamber::calcHeatStepTemperature of its start
    // and the volume the equilibrium reaches, found with that equilibrium by fixed-point
    // iteration (each pass reseals the gas on the adiabat through the target temperature at
    // the volume reached and solves again), to 1e-5 K. Every pass is solved to the solver's
    // own tolerances, as solveWithFlow does (a loose tolerance would accept the state unmoved).
    bool solveWithHeat(const std::vector<GasChamber>& start, const std::vector<double>& V0,
                       double dt, SolveSummary* sum, double* stab) {
        const ScopedValue tight(spec.forceTolerance, spec.solver.absoluteTolerance);
        const std::vector<RigidContact::History> history = model->getContactHistory();
        const int n = model->getNumGases();
        for (int k = 0; k < 40; ++k) {
            const std::vector<double> V1 = calcAllGasVolumes();
            std::vector<double> target(n);
            double worst = 0.0;
            for (int g = 0; g < n; ++g) {
                const double T0 = start[g].calcTemperature(V0[g]);
                target[g] = start[g].calcHeatStepTemperature(V0[g], T0, V1[g], dt);
                worst =
                    std::max(worst, std::abs(model->getGas(g).calcTemperature(V1[g]) - target[g]));
            }
            if (worst <= 1e-5) return true;
            for (int g = 0; g < n; ++g) model->updGas(g).setTemperature(target[g], V1[g]);
            model->setContactHistory(history);
            SolveSummary again;
            if (!trySolve(&again, stab, 3, spec.solver)) return false;
            sum->iterations += again.iterations;
            sum->factorizations += again.factorizations;
            sum->residualNorm = again.residualNorm;
        }
        return false;
    }
    std::shared_ptr<Snapshot> snapshot() const {
        auto s = std::make_shared<Snapshot>();
        s->x = x;
        s->gases = copyGases();
        s->history = model->getContactHistory();
        if (model->hasProny()) s->viscous = model->getViscousState();
        for (const Shape& sh : shapes) s->poses.push_back(sh.shape->getPose());
        s->time = time;
        s->v = v;
        s->stableStep = stableStep;
        s->stableAge = stableAge;
        return s;
    }
    // Some contact has the regularised friction law (its history then holds a slip length).
    bool hasRegularisedFriction() const {
        auto regularised = [](const RigidContact& c) {
            return c.getOptions().friction > 0.0 &&
                   c.getOptions().frictionLaw == RigidContact::FrictionLaw::Regularised;
        };
        for (const Shape& sh : shapes)
            if (regularised(*sh.contact)) return true;
        return bedContact && regularised(*bedContact);
    }
    void writeSnapshot(StateWriter& w, const Snapshot& s) const {
        w.mat(s.x);
        w.pod(std::uint64_t(s.gases.size()));
        for (const GasChamber& g : s.gases) g.saveState(w);
        w.pod(std::uint64_t(s.history.size()));
        for (const RigidContact::History& h : s.history) {
            w.pod(std::uint64_t(h.anchor_S.size()));
            for (const Vec3& a : h.anchor_S) w.pod(a.x()), w.pod(a.y()), w.pod(a.z());
            w.vec(h.hasAnchor);
        }
        if (hasRegularisedFriction()) {  // only then: other bags' checkpoints are as before
            w.tag("slip");
            for (const RigidContact::History& h : s.history) w.pod(h.slipLength);
        }
        if (model->hasProny()) {  // only then: checkpoints of an elastic bag are as before
            w.tag("viscous");
            w.mat(s.viscous.branchStrain);
            w.mat(s.viscous.strain);
            w.pod(s.viscous.stepTime);
        }
        w.pod(std::uint64_t(s.poses.size()));
        for (const Eigen::Isometry3d& X : s.poses) w.pose(X);
        w.pod(s.time);
        if (spec.stepping != AirbagSpec::Stepping::QuasiStatic) {  // only then: as before otherwise
            w.tag("velocity");
            Eigen::Matrix3Xd v0 = s.v;
            if (v0.cols() != s.x.cols()) v0.setZero(3, s.x.cols());
            w.mat(v0);
            w.pod(s.stableStep);
            w.pod(s.stableAge);
        }
    }
    // A snapshot as writeSnapshot() wrote it, its sizes checked against this bag's.
    std::shared_ptr<Snapshot> readSnapshot(StateReader& r) const {
        auto s = snapshot();  // the shapes of this bag's state, overwritten below
        r.matOfCols(s->x, x.cols(), "nodes of the bag");
        if (s->x.rows() != 3) StateReader::mismatch("coordinates per node", s->x.rows(), 3);
        const auto ng = r.pod<std::uint64_t>();
        if (ng != s->gases.size()) StateReader::mismatch("gas bodies", ng, s->gases.size());
        for (GasChamber& g : s->gases) g.loadState(r);
        const auto nh = r.pod<std::uint64_t>();
        if (nh != s->history.size()) StateReader::mismatch("contacts", nh, s->history.size());
        for (RigidContact::History& h : s->history) {
            const auto na = r.pod<std::uint64_t>();
            if (na != h.anchor_S.size())
                StateReader::mismatch("nodes of a contact", na, h.anchor_S.size());
            for (Vec3& a : h.anchor_S) {
                const double ax = r.pod<double>(), ay = r.pod<double>(), az = r.pod<double>();
                a = Vec3(ax, ay, az);
            }
            r.vecOfSize(h.hasAnchor, h.anchor_S.size(), "nodes of a contact");
        }
        if (hasRegularisedFriction()) {
            r.tag("slip");
            for (RigidContact::History& h : s->history) r.pod(h.slipLength);
        }
        if (model->hasProny()) {
            r.tag("viscous");
            r.matOfCols(s->viscous.branchStrain, s->viscous.branchStrain.cols(),
                        "viscous branches (Prony terms x elements)");
            r.matOfCols(s->viscous.strain, s->viscous.strain.cols(), "elements of the film");
            r.pod(s->viscous.stepTime);
        }
        const auto np = r.pod<std::uint64_t>();
        if (np != s->poses.size()) StateReader::mismatch("shapes", np, s->poses.size());
        for (Eigen::Isometry3d& X : s->poses) X = r.pose();
        r.pod(s->time);
        if (spec.stepping != AirbagSpec::Stepping::QuasiStatic) {
            r.tag("velocity");
            r.matOfCols(s->v, x.cols(), "nodes of the bag (velocities)");
            r.pod(s->stableStep);
            r.pod(s->stableAge);
        }
        return s;
    }
    void restore(const Snapshot& s) {
        x = s.x;
        setGases(s.gases);
        model->setContactHistory(s.history);
        if (model->hasProny()) model->setViscousState(s.viscous);
        for (size_t i = 0; i < shapes.size(); ++i) shapes[i].shape->setPose(s.poses[i]);
        time = s.time;
        if (s.v.cols() == x.cols())
            v = s.v;
        else
            v.setZero(3, x.cols());
        stableStep = s.stableStep;
        stableAge = s.stableAge;
    }

    // Sets bag b's gas mass, shared among its gas bodies at equal pressure (a body's share
    // is its volume's share at a fixed temperature), each resealed at its current volume.
    void setBagGasMass(int b, double m) {
        double Vsum = 0.0;
        const std::vector<double> V = calcGasVolumes(b, &Vsum);
        for (size_t i = 0; i < V.size(); ++i)
            model->updGas(bagGases[b][i]).setMass(m * V[i] / Vsum, V[i]);
    }
    // Gas [kg] the flows set let into bag b over dt from the current state (Airbag::calcGasInflow).
    double calcGasInflow(int b, double dt) const {
        double dm = massFlow[b] * dt;
        if (hasTarget[b]) {
            const double left = targetMass[b] - bagMass(b);
            dm = std::abs(dm) >= std::abs(left) ? left : std::copysign(std::abs(dm), left);
        }
        return dm;
    }
    // d(grad E)/d m_b at x [3N]: minus the gas's nodal force per unit of mass added to bag b
    // as addBagGasMass() adds it (p_i V_i / (m_i Vsum) dV_i/dx over its gas bodies: each
    // body's absolute pressure scales with its mass at its volume, GasChamber::transferMass).
    Eigen::VectorXd calcGasMassDerivative(int b) const {
        Eigen::VectorXd d = Eigen::VectorXd::Zero(3 * mesh.getNumNodes()), grad;
        double Vsum = 0.0;
        const std::vector<double> V = calcGasVolumes(b, &Vsum);
        for (size_t i = 0; i < V.size(); ++i) {
            const GasChamber& gas = model->getGas(bagGases[b][i]);
            if (!(gas.getMass() > 0.0)) continue;
            model->calcGasVolume(bagGases[b][i], x, &grad);
            d -= gas.calcPressure(V[i]) * V[i] / (gas.getMass() * Vsum) * grad;
        }
        return d;
    }
    // The wrench linearisation of `shapes` at x (Airbag::calcShapeWrenchLinearisation()); the
    // gas columns only if `gas`; film-held tangents where the bag's tangent is not positive
    // definite if `allowFilmHeld`, else the NumericalError.
    // B = d(grad E)/dq at fixed x; the bag re-equilibrates, dx/dq = -K^-1 B, hence
    // dW/dq = dW/dq|_x - (dW/dx) K^-1 B, and frictionless W = -dE_c/dq so dW/dx = -B^T. The
    // gas likewise: dx/dm_b = -K^-1 d(grad E)/dm_b, dW/dm_b = (dW/dx) dx/dm_b. One K for all.
    // withoutFriction: the body shapes' contacts taken frictionless (the friction history
    // kept), the rest of the bag as it is.
    Airbag::WrenchLinearisation linearise(const std::vector<int>& which, bool gas,
                                          bool allowFilmHeld, bool withoutFriction = false) const {
        // Without friction: the body shapes' contacts evaluated frictionless while the
        // linearisation is built (their friction history kept), then restored.
        struct Restore {
            const std::vector<Shape>& sh;
            bool on;
            ~Restore() {
                if (on)
                    for (const Shape& s : sh) s.contact->setFrictionSuppressed(false);
            }
        } restore{shapes, withoutFriction};
        if (withoutFriction)
            for (const Shape& s : shapes) s.contact->setFrictionSuppressed(true);
        Airbag::WrenchLinearisation lin;
        lin.pose.assign(which.size(), Eigen::Matrix<double, 6, 6>::Zero());
        if (gas)
            lin.gas.assign(which.size(),
                           Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, numBags));
        std::vector<int> pressing;  // indices into `which`
        for (size_t k = 0; k < which.size(); ++k)
            if (shapes.at(which[k]).contact->getNumActive(x) > 0) pressing.push_back(int(k));
        if (pressing.empty()) return lin;
        const int nPose = 6 * int(pressing.size());
        Eigen::MatrixXd B(3 * mesh.getNumNodes(), nPose + (gas ? numBags : 0));
        for (size_t j = 0; j < pressing.size(); ++j)
            B.middleCols<6>(6 * j) =
                calcContactPoseDerivative(which[pressing[j]], &lin.pose[pressing[j]]);
        if (gas)
            for (int b = 0; b < numBags; ++b) B.col(nPose + b) = calcGasMassDerivative(b);
        Eigen::MatrixXd Y;
        try {
            Y = solveTangent(*model, x, B);
        } catch (const NumericalError&) {
            if (!allowFilmHeld) throw;
            lin.filmHeld = true;  // pose: dW/dq at fixed nodes; gas: zero
            // Without friction (the coupling's passes hold the friction force): zero, the
            // whole load held over the step. The film-held tangent is the contact's penalty
            // stiffness (about 1e6 N/m on a segment), too stiff a spring for the body's step
            // (docs/cosim.md#friction-and-the-tangent-schemes).
            if (withoutFriction)
                for (auto& m : lin.pose) m.setZero();
            return lin;
        }
        for (size_t j = 0; j < pressing.size(); ++j) {
            const RigidContact& c = *shapes.at(which[pressing[j]]).contact;
            // Frictionless, dW/dx = -B^T (the wrench is minus the contact energy's derivative by
            // the pose); with friction the tangential force is a law, and dW/dx is its own.
            Eigen::Matrix<double, 6, Eigen::Dynamic> dWdx;
            if (c.isConservative())
                dWdx = -B.middleCols<6>(6 * j).transpose();
            else
                dWdx = c.calcWrenchNodeDerivative(x);
            lin.pose[pressing[j]] -= dWdx * Y.middleCols<6>(6 * j);
            if (gas) lin.gas[pressing[j]] = -dWdx * Y.rightCols(numBags);
        }
        return lin;
    }
    // Adds dm [kg] to bag b's gas bodies in proportion to their volumes at x.
    void addBagGasMass(int b, double dm) {
        if (dm == 0.0) return;
        double Vsum = 0.0;
        const std::vector<double> V = calcGasVolumes(b, &Vsum);
        for (size_t i = 0; i < V.size(); ++i)
            model->updGas(bagGases[b][i]).transferMass(dm * V[i] / Vsum, V[i]);
    }
    // The volume [m^3] at x of each of bag b's gas bodies, and their sum.
    std::vector<double> calcGasVolumes(int b, double* sum) const {
        std::vector<double> V(bagGases[b].size());
        *sum = 0.0;
        for (size_t i = 0; i < V.size(); ++i)
            *sum += V[i] = model->calcGasVolume(bagGases[b][i], x, nullptr);
        return V;
    }
    // Takes every bag quasi-statically from its gas mass now to masses[b], the bags' masses
    // moving in proportion (the ramp's parameter is the mass of the bag that changes most).
    void rampGasMasses(const std::vector<double>& masses) {
        if (spec.sharedAir) {
            // One body of air: its mass goes to the masses' sum.
            double to = 0.0;
            for (double mb : masses) to += mb;
            solveRamp(
                totalMass(), to, [&](double m) { setBagGasMass(0, m); }, "changing the gas mass");
            return;
        }
        std::vector<double> from(numBags);
        int ref = 0;
        for (int b = 0; b < numBags; ++b) {
            from[b] = bagMass(b);
            if (std::abs(masses[b] - from[b]) > std::abs(masses[ref] - from[ref])) ref = b;
        }
        const double span = masses[ref] - from[ref];
        solveRamp(
            from[ref], masses[ref],
            [&](double m) {
                // The way along; span 0: no bag changes, every mass stays.
                const double f = span == 0.0 ? 1.0 : (m - from[ref]) / span;
                for (int b = 0; b < numBags; ++b)
                    setBagGasMass(b, b == ref ? m : from[b] + f * (masses[b] - from[b]));
            },
            "changing the gas mass");
    }

    // --- solving
    // Newton from xs under the model's current stabilisation; false if it does not converge.
    bool runNewton(Eigen::Matrix3Xd& xs, SolveSummary* sum, const SolverOptions& base) {
        SolverOptions so = base;
        if (so.maxStep == 0.0) so.maxStep = meanEdge;  // trust limit: about one element
        so.absoluteTolerance = std::max(so.absoluteTolerance, spec.forceTolerance);
        // Non-smooth self contact can stall Newton a little above the tolerance: accept a
        // residual below the bag's force tolerance then.
        if (so.acceptableResidual == 0.0) so.acceptableResidual = spec.forceTolerance;
        try {
            const int before = sum->iterations, fBefore = sum->factorizations;
            *sum = solveEquilibrium(*model, xs, so, &workspace);
            sum->iterations += before;  // summed over the solves of one step
            sum->factorizations += fBefore;
            return sum->converged;
        } catch (const NumericalError&) {
            return false;
        }
    }

    // The damper's weight per node: 1 on film that is not taut, 0 on taut film and where a
    // rigid shape or the bed presses the node at `at` (the contact holds those nodes; a damper
    // there would add to the force the shape feels).
    std::vector<double> calcDampingWeights(const Eigen::Matrix3Xd& at) const {
        // Film that is slack or wrinkled somewhere around the node: taut film has a definite
        // tangent of its own.
        std::vector<double> w(mesh.getNumNodes(), 0.0);
        const std::vector<int> states = model->calcWrinkleStates(at);
        for (int e = 0; e < mesh.getNumTris(); ++e)
            if (states[e] != 0)
                for (int k = 0; k < 3; ++k) w[mesh.tris(k, e)] = 1.0;
        auto clear = [&](const RigidContact& c) {
            const Eigen::VectorXd p = c.calcNodalPressure(at);
            for (int i = 0; i < p.size(); ++i)
                if (p(i) > 0.0) w[i] = 0.0;
        };
        for (const Shape& sh : shapes) clear(*sh.contact);
        if (bedContact) clear(*bedContact);
        return w;
    }

    double calcFreeResidual(const Eigen::Matrix3Xd& xs) const {
        EnergyAccumulator acc(static_cast<int>(xs.cols()));
        acc.wantHessian = false;
        model->addEnergy(xs, acc);
        for (int d : model->getFixedDofs()) acc.grad(d) = 0.0;
        return acc.grad.norm();
    }

    // Damped step: dampers on the film that is not taut, anchored at the step's start (a
    // pseudo-time step). Where that solve was easy (smooth film) the damper-free equilibrium
    // is a few iterations away: it is taken, the damper's bias gone. Otherwise the damped
    // state is kept once the force the dampers hold is below the force tolerance; until then
    // the dampers are re-anchored at it and the loads solved again (up to kRelaxations
    // pseudo-time steps). *work: the dampers' work (force k A dx times dx, twice what a
    // spring anchored at the start holds), summed. False: the undamped path follows.
    bool solveDamped(Eigen::Matrix3Xd& xs, SolveSummary* sum, double* work,
                     const SolverOptions& so) {
        constexpr int kEasySolve = 4, kRelaxations = 8;
        *work = 0.0;
        Eigen::Matrix3Xd anchor = x;
        for (int r = 0; r < kRelaxations; ++r) {
            const int before = sum->iterations;
            model->setStabilization(spec.damping, anchor, calcDampingWeights(anchor));
            const bool ok = runNewton(xs, sum, so);
            if (ok) *work += 2.0 * model->calcStabilizationEnergy(xs);
            model->setStabilization(0.0, x);
            if (!ok) return false;
            if (sum->iterations - before <= kEasySolve) {
                SolverOptions quick = so;
                quick.maxIterations = kEasySolve;
                Eigen::Matrix3Xd free = xs;
                SolveSummary relaxed = *sum;
                if (runNewton(free, &relaxed, quick)) {
                    *sum = relaxed;
                    xs = free;
                    *work = 0.0;
                    return true;
                }
                sum->iterations = relaxed.iterations;
                sum->factorizations = relaxed.factorizations;
            }
            sum->residualNorm = calcFreeResidual(xs);
            if (sum->residualNorm <= spec.forceTolerance) return true;
            anchor = xs;
        }
        return false;
    }

    // Solves the current loads starting from x. If Newton fails, retries with the
    // stabilisation springs anchored at x (slack, wrinkling states), at up to `levels`
    // stiffnesses (1x, 10x, 100x). A stabilised state is then relaxed: the springs are
    // re-anchored at it and the step solved again (a pseudo-time step towards the true
    // equilibrium), up to kRelaxations times, each time first trying without springs.
    // *stabEnergy is the energy the springs hold at the accepted state: zero when the step ends
    // on a spring-free equilibrium. On success x is updated and contact history committed.
    bool trySolve(SolveSummary* sum, double* stabEnergy, int levels, const SolverOptions& so) {
        constexpr int kRelaxations = 4;
        *sum = SolveSummary();
        *stabEnergy = 0.0;
        auto accept = [&](const Eigen::Matrix3Xd& xs, double energy) {
            x = xs;
            model->commitStep(xs);
            *stabEnergy = energy;
            return true;
        };
        Eigen::Matrix3Xd xs = x;
        if (!plainNewton && spec.damping > 0.0 && solveDamped(xs, sum, stabEnergy, so))
            return accept(xs, *stabEnergy);
        xs = x;
        if (runNewton(xs, sum, so)) return accept(xs, 0.0);
        if (plainNewton || spec.stabilization <= 0.0) return false;
        for (int level = 0; level < levels; ++level) {
            const double k = spec.stabilization * std::pow(10.0, level);
            xs = x;
            model->setStabilization(k, xs);
            const bool ok = runNewton(xs, sum, so);
            double energy = ok ? model->calcStabilizationEnergy(xs) : 0.0;
            model->setStabilization(0.0, x);
            if (!ok) continue;
            SolveSummary acceptedSum = *sum;
            for (int r = 0; r < kRelaxations; ++r) {
                Eigen::Matrix3Xd free = xs;
                if (runNewton(free, sum, so)) return accept(free, 0.0);
                Eigen::Matrix3Xd next = xs;
                model->setStabilization(k, xs);
                const bool relaxed = runNewton(next, sum, so);
                const double e = relaxed ? model->calcStabilizationEnergy(next) : 0.0;
                model->setStabilization(0.0, x);
                if (!relaxed) break;
                xs = next;
                energy = e;
                acceptedSum = *sum;
            }
            const int iterations = sum->iterations, factorizations = sum->factorizations;
            *sum = acceptedSum;
            sum->iterations = iterations;
            sum->factorizations = factorizations;
            sum->residualNorm = calcFreeResidual(xs);
            return accept(xs, energy);
        }
        return false;
    }

    // Mass [kg] the orifice passes from body 0 to body 1 during dt from the `start` masses
    // (backward Euler, volumes held at x).
    double calcTransfer(const std::vector<GasChamber>& start, double dt) const {
        return calcOrificeTransfer(spec.orifice, start[0], model->calcGasVolume(0, x, nullptr),
                                   start[1], model->calcGasVolume(1, x, nullptr), dt);
    }
    void moveGas(const std::vector<GasChamber>& start, double dm) {
        setGases(start);
        model->updGas(0).transferMass(-dm, model->calcGasVolume(0, x, nullptr));
        model->updGas(1).transferMass(dm, model->calcGasVolume(1, x, nullptr));
    }

    // Solves the current loads with the gas flowing through the orifice over dt [s] from the
    // `start` gas states: the transferred mass dm and the membrane's equilibrium are found
    // together by a secant iteration on R(dm) = dm - T(dm), T the backward-Euler transfer at
    // the volumes of the equilibrium reached with dm. Every iterate is solved to the solver's
    // own tolerances (under the loose force tolerance a state close to the last one would be
    // accepted unmoved and T evaluated at unchanged volumes: 48.5 Pa instead of 52.8 Pa after
    // the settle of a 0.01 mm orifice) and starts from the step's friction history. Open
    // connection or dt = 0: a plain solve.
    bool solveWithFlow(const std::vector<GasChamber>& start, double dt, SolveSummary* sum,
                       double* stab) {
        if (spec.connection != AirbagSpec::Connection::Orifice || model->getNumGases() < 2 ||
            dt <= 0.0)
            return trySolve(sum, stab, 3, spec.solver);
        const double tolerance = spec.forceTolerance;
        spec.forceTolerance = spec.solver.absoluteTolerance;  // strict: see above
        struct Restore {
            double& t;
            double v;
            ~Restore() { t = v; }
        } restore{spec.forceTolerance, tolerance};
        const std::vector<RigidContact::History> history = model->getContactHistory();
        const double dmMax = 0.99 * start[0].getMass(), dmMin = -0.99 * start[1].getMass();
        double dm = calcTransfer(start, dt);  // predictor: last volumes
        double dmPrev = 0.0, rPrev = 0.0;
        for (int k = 0; k < 30; ++k) {
            dm = std::clamp(dm, dmMin, dmMax);
            model->setContactHistory(history);
            moveGas(start, dm);
            if (!trySolve(sum, stab, 3, spec.solver)) return false;
            const double t = calcTransfer(start, dt);
            const double r = dm - t;
            if (std::abs(r) <=
                1e-4 * std::abs(t) + 1e-12 * (start[0].getMass() + start[1].getMass())) {
                moveGas(start, t);  // gas at the final volumes
                return true;
            }
            const double next = (k == 0 || r == rPrev) ? t : dm - r * (dm - dmPrev) / (r - rPrev);
            dmPrev = dm;
            rPrev = r;
            dm = next;
        }
        return false;
    }

    // Ramps a scalar load parameter from s0 to s1 (apply(s) sets the loads), halving the
    // increment on failure; always solves at least once. Each solve starts with the
    // self-contact candidates rebuilt at the current state and may use the springs at up to
    // 100 times their stiffness.
    template <class Apply>
    void solveRamp(double s0, double s1, const Apply& apply, const char* what) {
        // Several bags ramp in at least kClusterRampSteps steps: their walls then meet a
        // little at a time rather than deep inside each other.
        constexpr int kClusterRampSteps = 16;
        const double dsMax = numBags > 1 ? (s1 - s0) / kClusterRampSteps : s1 - s0;
        double s = s0, ds = dsMax;
        int cuts = 0;
        bool solved = false;
        while (!solved || s != s1) {
            // The last increment lands on s1 exactly. An increment below s's roundoff (a ramp
            // over a span of a few ulps: a cluster's masses already at their values but for
            // roundoff) would leave s where it is for ever: it goes to s1 at once.
            const bool last = std::abs(s1 - s) <= std::abs(ds) * (1.0 + 1e-9) || s + ds == s;
            const double next = last ? s1 : s + ds;
            apply(next);
            SolveSummary sum;
            double stab = 0.0;
            if (self) self->updateCandidates(x);
            model->beginContactStep(x, 0.0);  // no time passes: Coulomb's limit
            if (trySolve(&sum, &stab, 3, spec.solver) && recheckCandidates(&sum)) {
                s = next;
                solved = true;
                if (sum.iterations < 8)
                    ds = std::abs(2.0 * ds) < std::abs(dsMax) ? 2.0 * ds : dsMax;
            } else {
                apply(s);
                ds *= 0.5;
                if (++cuts > 30) throw NumericalError(std::string("no convergence while ") + what);
            }
        }
    }

    // A solve that moved some node further than the self-contact's candidate list covers
    // (half its margin) may have brought it near a wall unseen: a slack bag's top wall onto
    // its bottom wall, or a neighbour's wall. The candidates are then rebuilt at the solved
    // state and the loads solved again, up to kRechecks times. False if a re-solve fails.
    // (On the seed's 2.0 g curve 86 of 110 steps ended with a stale list before this.)
    static constexpr int kRechecks = 6;
    bool recheckCandidates(SolveSummary* sum) {
        for (int r = 0; r < kRechecks && self && !self->isCandidateListValid(x); ++r) {
            self->updateCandidates(x);
            SolveSummary again;
            double stab = 0.0;
            if (!trySolve(&again, &stab, 3, spec.solver)) return false;
            sum->iterations += again.iterations;
            sum->factorizations += again.factorizations;
            sum->residualNorm = again.residualNorm;
        }
        return true;
    }

    // One (sub-)step from the current state: shapes to the poses at fraction s1 of the way
    // from `from` to their targets, gas flow over dt. Restores everything on failure.
    bool solveSubstep(const std::vector<Eigen::Isometry3d>& from, double s1, double dt,
                      AdvanceSummary* out) {
        const std::shared_ptr<Snapshot> before = snapshot();
        // The film's step potential over dt (viscoelastic film; restored with `before`), and
        // the slip of the regularised friction measured from here.
        model->beginViscousStep(dt);
        model->beginContactStep(x, dt);
        // Nothing to solve when no gas moves, the film has no strained viscous branch to relax
        // over the time, and every shape that moves touches the bag neither before nor after: the
        // energy of the state is unchanged, so is the state.
        // A bag nothing touches costs next to nothing, and a released bag that was accepted
        // with stabilisation springs is not re-solved just because a shape moved away.
        const bool gasStill = isGasStill(dt) && (dt == 0.0 || model->isViscouslyRelaxed());
        bool untouched = gasStill;
        for (size_t i = 0; i < shapes.size() && untouched; ++i)
            untouched = shapes[i].contact->getNumActive(x) == 0;
        for (size_t i = 0; i < shapes.size(); ++i)
            shapes[i].shape->setPose(interpolatePose(from[i], shapes[i].target, s1));
        for (size_t i = 0; i < shapes.size() && untouched; ++i)
            untouched = shapes[i].contact->getNumActive(x) == 0;
        // Untouched: a true equilibrium stands as it is. A state that was accepted with the
        // stabilisation springs (not an equilibrium) is relaxed by a solve, as any step; if
        // that fails it stands too: nothing acting on the bag has changed.
        double untouchedResidual = 0.0;
        if (untouched) {
            untouchedResidual = calcFreeResidual(x);
            if (untouchedResidual <= spec.forceTolerance) {
                ++out->substeps;
                out->residual = untouchedResidual;
                out->stabilizationEnergy = 0.0;
                model->endViscousStep(x);
                time += dt;
                return true;
            }
        }
        SolveSummary sum;
        double stab = 0.0;
        // From the state at `before` (its shapes at their poses): gas moved over dt, Newton from
        // the warm start (if `warm` and taken) or the predictor's start. True if solved.
        // *warmed: the warm start was taken.
        auto attempt = [&](bool warm, bool* warmed) {
            *warmed = false;
            try {
                // Gas in or out of each bag over the step, at the volumes of the start of the step.
                for (int b = 0; b < numBags; ++b) addBagGasMass(b, calcGasInflow(b, dt));
                leak(dt);
                const bool heat = spec.gas.heatTimeConstant > 0.0 && dt > 0.0;
                const std::vector<GasChamber> heatStart =
                    heat ? copyGases() : std::vector<GasChamber>();
                const std::vector<double> heatV0 =
                    heat ? calcAllGasVolumes() : std::vector<double>();
                *warmed = warm && warmStart();
                if (!*warmed) predict(before->poses);
                if (self) self->updateCandidates(x);
                bool solved = solveWithFlow(copyGases(), dt, &sum, &stab);
                if (solved && heat) solved = solveWithHeat(heatStart, heatV0, dt, &sum, &stab);
                if (solved) solved = recheckCandidates(&sum);
                return solved;
            } catch (const NumericalError&) {
                return false;  // e.g. a gas transfer no chamber could give
            }
        };
        bool warmed = false;
        bool ok = attempt(true, &warmed);
        if (warmed && (!ok || stab > 0.0)) {
            // The warm start did not end on an equilibrium: a state held by the stabilisation
            // springs (anchored where Newton starts) depends on that start, here the last
            // pass's end, so the bag would answer the same poses differently from pass to
            // pass and an implicit coupling could not converge. Solved again from the start a
            // first pass takes, whose answer is the poses' alone.
            out->newtonIterations += sum.iterations;
            out->factorizations += sum.factorizations;
            restore(*before);
            model->beginViscousStep(dt);
            model->beginContactStep(x, dt);
            for (size_t i = 0; i < shapes.size(); ++i)
                shapes[i].shape->setPose(interpolatePose(from[i], shapes[i].target, s1));
            ok = attempt(false, &warmed);
        }
        out->newtonIterations += sum.iterations;
        out->factorizations += sum.factorizations;
        if (!ok && untouched) {
            restore(*before);
            for (size_t i = 0; i < shapes.size(); ++i)
                shapes[i].shape->setPose(interpolatePose(from[i], shapes[i].target, s1));
            ++out->substeps;
            out->residual = untouchedResidual;
            out->stabilizationEnergy = 0.0;
            model->endViscousStep(x);
            time += dt;
            return true;
        }
        if (!ok) {
            restore(*before);
            return false;
        }
        ++out->substeps;
        out->residual = sum.residualNorm;
        out->stabilizationEnergy = stab;
        model->endViscousStep(x);
        time += dt;
        return true;
    }

    // Contact-force gradient dg/dq [3N x 6] of shape i's contact w.r.t. its pose (rotation
    // about Ground axes through its origin, translation), by central differences at x.
    Eigen::MatrixXd calcContactPoseDerivative(int i, Eigen::Matrix<double, 6, 6>* dWdq) const {
        const Shape& sh = shapes[i];
        const Eigen::Isometry3d X0 = sh.shape->getPose();
        const double hRot = 1e-6, hLin = 1e-7;  // [rad], [m]
        Eigen::MatrixXd B(3 * mesh.getNumNodes(), 6);
        for (int j = 0; j < 6; ++j) {
            const double h = j < 3 ? hRot : hLin;
            Vec3 w = Vec3::Zero(), t = Vec3::Zero();
            (j < 3 ? w : t)(j % 3) = h;
            Eigen::VectorXd g[2];
            Vec3 F[2], T[2];
            for (int side = 0; side < 2; ++side) {
                const double sgn = side == 0 ? 1.0 : -1.0;
                sh.shape->setPose(perturbPose(X0, sgn * w, sgn * t));
                EnergyAccumulator acc(mesh.getNumNodes());
                acc.wantHessian = false;
                sh.contact->addEnergy(x, acc);
                g[side] = acc.grad;
                sh.contact->calcWrenchOnShape(x, &F[side], &T[side]);
            }
            sh.shape->setPose(X0);
            B.col(j) = (g[0] - g[1]) / (2.0 * h);
            dWdq->col(j).head<3>() = (T[0] - T[1]) / (2.0 * h);
            dWdq->col(j).tail<3>() = (F[0] - F[1]) / (2.0 * h);
        }
        return B;
    }
};

// ---------------------------------------------------------------------------------------------
// Steppers: how advance() goes from the committed state over a step of time.

// An equilibrium at the step's end: Newton from the committed state, the step cut in halves
// while a sub-step fails (each with the retry chain of Impl::solveSubstep).
struct Airbag::Impl::QuasiStaticStepper : Airbag::Impl::Stepper {
    AdvanceSummary advance(Impl& m, double dt, int maxCuts) override {
        AdvanceSummary out;
        // Start from the committed state (a repeated advance of one macro step starts over).
        m.restore(*m.committed);
        std::vector<Eigen::Isometry3d> from = m.currentPoses();
        double s = 0.0, ds = 1.0;
        int cuts = 0;
        while (s < 1.0) {
            const double s1 = (ds >= 1.0 - s - 1e-12) ? 1.0 : s + ds;
            m.wholeStep = s == 0.0 && s1 == 1.0;
            if (m.solveSubstep(from, s1, dt * (s1 - s), &out)) {
                s = s1;
                if (cuts > 0) ds = std::min(2.0 * ds, 1.0);
            } else {
                if (++cuts > maxCuts) {
                    m.restore(*m.committed);
                    out.converged = false;
                    return out;
                }
                ds *= 0.5;
            }
        }
        out.converged = true;
        m.v.setZero(3, m.x.cols());  // an equilibrium is at rest
        // A warm start only from an equilibrium: a state the springs hold is no start to share.
        if (out.stabilizationEnergy > 0.0)
            m.lastAdvanced.resize(3, 0);
        else
            m.lastAdvanced = m.x;
        return out;
    }
};

// The film in time (bags/Dynamics.h): explicit damped central differences in sub-steps of a
// fraction of the stable step, the shapes' poses interpolated across the step, the gas flows,
// leakage, orifice transfer and heat exchange integrated per sub-step, the friction history
// and the film's viscous branches advanced per sub-step. A step of no time is a quasi-static
// change. A bag nothing touches, whose gas and film are still and which is at rest, sleeps
// (nothing is integrated) and wakes when a shape touches it or its gas moves.
struct Airbag::Impl::DynamicStepper : Airbag::Impl::Stepper {
    static constexpr int kStableRefresh = 8;
    QuasiStaticStepper quasiStatic;
    EnergyAccumulator acc;

    // [Pa/m] the stiffest penalty per area that may press a node.
    static double maxContactPenalty(const Impl& m) {
        auto stiffest = [](const RigidContact::Options& o) {
            return o.pressurePenalty *
                   std::max(1.0, o.friction > 0.0 ? o.stickStiffnessRatio : 0.0);
        };
        double k = m.bedContact ? stiffest(m.spec.bedContact) : 0.0;
        for (const Shape& sh : m.shapes) k = std::max(k, stiffest(sh.contact->getOptions()));
        // A node against a facet: the facet's nodes share the node's force, a node may
        // meet more than one facet.
        if (m.self) k = std::max(k, 2.0 * m.spec.selfContactPenalty);
        return k;
    }

    // The film's inertia, built at the first step that moves it.
    static void ensureFilm(Impl& m) {
        if (!m.film)
            m.film = std::make_unique<FilmDynamics>(*m.model, m.spec.density, m.spec.dynamics,
                                                    maxContactPenalty(m), m.spec.material);
    }
    static bool isUntouched(const Impl& m) {
        for (const Shape& sh : m.shapes)
            if (sh.contact->getNumActive(m.x) > 0) return false;
        return true;
    }
    // Asleep over dt: at rest, gas and film still (`still`), untouched before and after. Then
    // the shapes are at their targets, the time moved on and true returned; otherwise nothing
    // has changed.
    static bool trySleep(Impl& m, const std::vector<Eigen::Isometry3d>& from, double dt, bool still,
                         AdvanceSummary* out) {
        if (!(still && m.v.isZero(0.0) && isUntouched(m))) return false;
        for (size_t i = 0; i < m.shapes.size(); ++i) m.shapes[i].shape->setPose(m.shapes[i].target);
        if (isUntouched(m)) {
            m.time += dt;
            out->converged = true;
            out->residual = m.calcFreeResidual(m.x);
            return true;
        }
        for (size_t i = 0; i < m.shapes.size(); ++i) m.shapes[i].shape->setPose(from[i]);
        return false;
    }
    // The stable step over the root of the mass scale, estimated again every kStableRefresh
    // steps (a tangent assembly costs tens of sub-steps); *age its steps since. Kept in the
    // state (m.stableStep, m.stableAge) by the caller once the step is accepted.
    static double calcStablePerRoot(Impl& m, int* age) {
        const double root = std::sqrt(m.spec.dynamics.massScale);
        double perRoot = m.stableStep;
        *age = m.stableAge;
        if (!(perRoot > 0.0) || *age >= kStableRefresh) {
            perRoot = m.film->calcStableStep(m.x) / root;
            *age = 0;
        }
        return perRoot;
    }

    AdvanceSummary advance(Impl& m, double dt, int maxCuts) override {
        if (dt == 0.0) return quasiStatic.advance(m, dt, maxCuts);
        m.restore(*m.committed);
        ensureFilm(m);
        const std::vector<Eigen::Isometry3d> from = m.currentPoses();
        AdvanceSummary out;
        const bool still = m.isGasStill(dt) && m.model->isViscouslyRelaxed();
        if (trySleep(m, from, dt, still, &out)) return out;
        int age = 0;
        const double perRoot = calcStablePerRoot(m, &age);
        const double stable = perRoot * std::sqrt(m.spec.dynamics.massScale);
        for (int cut = 0; cut <= maxCuts; ++cut) {
            const double hMax = stable * m.spec.dynamics.stepFraction * std::pow(0.5, cut);
            const long n = std::max(1L, static_cast<long>(std::ceil(dt / hMax - 1e-9)));
            const double h = dt / static_cast<double>(n);
            if (integrate(m, from, dt, n, h, &out)) {
                m.stableStep = perRoot;
                m.stableAge = age + 1;
                out.converged = true;
                out.substeps = static_cast<int>(std::min<long>(n, std::numeric_limits<int>::max()));
                out.substep = h;
                out.kineticEnergy = m.film->calcKineticEnergy(m.v);
                out.residual = m.calcFreeResidual(m.x);
                // Falls asleep: untouched, still, and moving less than 0.1 um over such a step.
                double vmax = 0.0;
                for (int i = 0; i < m.v.cols(); ++i) vmax = std::max(vmax, m.v.col(i).norm());
                if (still && isUntouched(m) && vmax * dt < 1e-7 &&
                    out.residual <= m.spec.forceTolerance)
                    m.v.setZero();
                return out;
            }
            m.restore(*m.committed);
        }
        out.converged = false;
        return out;
    }

    // n sub-steps of h from the current state; false (state unspecified) on a blow-up.
    bool integrate(Impl& m, const std::vector<Eigen::Isometry3d>& from, double dt, long n, double h,
                   AdvanceSummary* out) {
        (void)out;
        const bool orifice =
            m.spec.connection == AirbagSpec::Connection::Orifice && m.model->getNumGases() >= 2;
        const bool heat = m.spec.gas.heatTimeConstant > 0.0;
        const int ng = m.model->getNumGases();
        std::vector<GasChamber> heatStart;
        std::vector<double> heatV0;
        try {
            for (long k = 0; k < n; ++k) {
                const double s1 =
                    k + 1 == n ? 1.0 : static_cast<double>(k + 1) / static_cast<double>(n);
                for (size_t i = 0; i < m.shapes.size(); ++i)
                    m.shapes[i].shape->setPose(interpolatePose(from[i], m.shapes[i].target, s1));
                // Gas over the sub-step at the volumes of its start.
                for (int b = 0; b < m.numBags; ++b) m.addBagGasMass(b, m.calcGasInflow(b, h));
                m.leak(h);
                if (orifice) {
                    const std::vector<GasChamber> start = m.copyGases();
                    m.moveGas(start, m.calcTransfer(start, h));
                }
                if (heat) {
                    heatStart = m.copyGases();
                    heatV0 = m.calcAllGasVolumes();
                }
                m.model->beginViscousStep(h);
                m.model->beginContactStep(m.x, h);
                if (m.self && !m.self->isCandidateListValid(m.x)) m.self->updateCandidates(m.x);
                m.film->step(m.x, m.v, h, acc);
                m.model->commitStep(m.x);
                m.model->endViscousStep(m.x);
                if (heat) {
                    const std::vector<double> V1 = m.calcAllGasVolumes();
                    for (int g = 0; g < ng; ++g) {
                        const double T0 = heatStart[g].calcTemperature(heatV0[g]);
                        m.model->updGas(g).setTemperature(
                            heatStart[g].calcHeatStepTemperature(heatV0[g], T0, V1[g], h), V1[g]);
                    }
                }
                if ((k & 63) == 63 && !m.x.allFinite()) return false;
            }
        } catch (const NumericalError&) {
            return false;
        }
        if (!m.x.allFinite() || !m.v.allFinite()) return false;
        m.time += dt;
        return true;
    }
};

// The quasi-static step's equilibrium by dynamic relaxation (AirbagSpec::Stepping::Relaxed,
// docs/solver.md#relaxed-stepping-the-equilibrium-found-by-the-film-in-time-for-the-patients-bags).
// The step's time passes at its start as in the quasi-static stepping: gas flows and leakage, the orifice's transfer (explicit, at the start's
// pressures), the friction's slip and the viscous branches' step potential. Then the film's
// damped explicit dynamics run in pseudo-time: the shapes moved to their poses at the
// relaxation pace, then held there while the film relaxes, its velocity zeroed at every peak
// of its kinetic energy (kinetic damping), until the force residual is within the tolerance.
// What touches the bag feels the equilibrium's forces, never the film's (scaled) inertia. A
// relaxed step ends at rest; one whose sub-steps ran out keeps its pseudo-velocity (the next
// step goes on from there).
struct Airbag::Impl::RelaxedStepper : Airbag::Impl::DynamicStepper {
    double reach = -1.0;  // [m] half the bag's reference diagonal: a turn's lever

    AdvanceSummary advance(Impl& m, double dt, int maxCuts) override {
        if (dt == 0.0) return quasiStatic.advance(m, dt, maxCuts);
        int newton = 0, factorizations = 0;
        if (m.spec.dynamics.newtonFirst) {
            // Where the film has an equilibrium near the last, Newton finds it in a few
            // iterations (a taut bag): tried first, alone (the step cut as the quasi-static
            // stepping cuts it, but no damper and no springs).
            struct PlainNewton {  // on for this try only, whatever leaves it
                bool& on;
                explicit PlainNewton(bool& f) : on(f) { on = true; }
                ~PlainNewton() { on = false; }
            };
            AdvanceSummary q;
            {
                const PlainNewton plain(m.plainNewton);
                q = quasiStatic.advance(m, dt, maxCuts);
            }
            if (q.converged) return q;
            newton = q.newtonIterations;
            factorizations = q.factorizations;
        }
        AdvanceSummary out = relaxStep(m, dt, maxCuts);
        out.newtonIterations += newton;
        out.factorizations += factorizations;
        if (out.converged && out.unrelaxed && m.spec.dynamics.quasiStaticFallback) {
            // Neither the relaxation nor the polish got there: the quasi-static stepping's
            // retries (damped steps, springs, cuts) may, from the committed state. Its answer
            // is kept if it finds one; else the relaxed state, marked.
            const std::shared_ptr<Snapshot> relaxed = m.snapshot();  // velocity, time, poses too
            AdvanceSummary q = quasiStatic.advance(m, dt, maxCuts);
            q.newtonIterations += out.newtonIterations;
            q.factorizations += out.factorizations;
            if (q.converged) {
                q.substeps += out.substeps;
                return q;
            }
            m.restore(*relaxed);
            out.newtonIterations = q.newtonIterations;
            out.factorizations = q.factorizations;
        }
        return out;
    }

    AdvanceSummary relaxStep(Impl& m, double dt, int maxCuts) {
        m.restore(*m.committed);
        ensureFilm(m);
        if (reach < 0.0) {
            const Eigen::Matrix3Xd& X = m.model->getMesh().X;
            reach = 0.5 * (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
        }
        const std::vector<Eigen::Isometry3d> from = m.currentPoses();
        AdvanceSummary out;
        const bool still = m.isGasStill(dt) && m.model->isViscouslyRelaxed();
        if (trySleep(m, from, dt, still, &out)) return out;
        const DynamicOptions& o = m.spec.dynamics;
        int age = 0;
        const double perRoot = calcStablePerRoot(m, &age);
        // The pace holds the film's response the same at any mass scale.
        const double pace = o.relaxPace * std::sqrt(1000.0 / o.massScale);
        double travel = 0.0;
        for (size_t i = 0; i < m.shapes.size(); ++i) {
            const Eigen::AngleAxisd turn(
                Eigen::Matrix3d(m.shapes[i].target.linear() * from[i].linear().transpose()));
            travel =
                std::max(travel, (m.shapes[i].target.translation() - from[i].translation()).norm() +
                                     std::abs(turn.angle()) * reach);
        }
        // The way to a first touch is free: the ramp starts at the last fraction of the
        // travel at which no shape touches the film (bisection), so that a shape brought from
        // afar is not swept in at the pace all the way, nor faster than the pace into the film.
        double s0 = 0.0;
        if (travel > 0.0 && isUntouched(m)) {
            double lo = 0.0, hi = 1.0;
            for (int i = 0; i < 24 && (hi - lo) * travel >
                                          pace * perRoot * std::sqrt(o.massScale) * o.stepFraction;
                 ++i) {
                const double mid = 0.5 * (lo + hi);
                for (size_t j = 0; j < m.shapes.size(); ++j)
                    m.shapes[j].shape->setPose(interpolatePose(from[j], m.shapes[j].target, mid));
                (isUntouched(m) ? lo : hi) = mid;
            }
            for (size_t j = 0; j < m.shapes.size(); ++j) m.shapes[j].shape->setPose(from[j]);
            s0 = lo;
        }
        for (int cut = 0; cut <= maxCuts; ++cut) {
            const double h = perRoot * std::sqrt(o.massScale) * o.stepFraction * std::pow(0.5, cut);
            if (relax(m, from, dt, h, s0, (1.0 - s0) * travel / (pace * h), &out)) {
                m.stableStep = perRoot;
                m.stableAge = age + 1;
                return out;
            }
            m.restore(*m.committed);
            out = AdvanceSummary();
        }
        out.converged = false;
        return out;
    }

    // The step of dt relaxed in sub-steps of h, the shapes moved from fraction s0 of the way
    // to their poses in `ramp` sub-steps (at least one); then up to relaxSubsteps more. False
    // (state unspecified) if the film could not be evaluated.
    bool relax(Impl& m, const std::vector<Eigen::Isometry3d>& from, double dt, double h, double s0,
               double ramp, AdvanceSummary* out) {
        const DynamicOptions& o = m.spec.dynamics;
        const long nRamp = std::max(1L, static_cast<long>(std::ceil(ramp - 1e-9)));
        const double tol2 = m.spec.forceTolerance * m.spec.forceTolerance;
        try {
            for (int b = 0; b < m.numBags; ++b) m.addBagGasMass(b, m.calcGasInflow(b, dt));
            m.leak(dt);
            if (m.spec.connection == AirbagSpec::Connection::Orifice &&
                m.model->getNumGases() >= 2) {
                const std::vector<GasChamber> start = m.copyGases();
                m.moveGas(start, m.calcTransfer(start, dt));
            }
            m.model->beginViscousStep(dt);
            m.model->beginContactStep(m.x, dt);
            double r2 = 0.0, kePrev = 0.0;
            long k = 0;
            bool relaxed = false;
            int polish = 0;
            // Newton alone from the relaxed state, at most newtonPolish iterations (the
            // self-contact candidates rechecked): relaxation converges slowly in a crumpled
            // film's softest modes, Newton fast once in its basin. True (x at its equilibrium)
            // if it converged.
            auto tryPolish = [&] {
                SolverOptions so = m.spec.solver;
                so.maxIterations = std::min(so.maxIterations, o.newtonPolish);
                Eigen::Matrix3Xd xs = m.x;
                SolveSummary ns;
                bool ok = m.runNewton(xs, &ns, so);
                for (int r = 0;
                     ok && m.self && !m.self->isCandidateListValid(xs) && r < Impl::kRechecks;
                     ++r) {
                    m.self->updateCandidates(xs);
                    ok = m.runNewton(xs, &ns, so);
                }
                polish += ns.iterations;
                out->factorizations += ns.factorizations;
                if (!ok) return false;
                m.x = xs;
                r2 = ns.residualNorm * ns.residualNorm;
                return true;
            };
            for (;; ++k) {
                if (k <= nRamp) {
                    const double s1 = k >= nRamp ? 1.0
                                                 : s0 + (1.0 - s0) * static_cast<double>(k) /
                                                            static_cast<double>(nRamp);
                    for (size_t i = 0; i < m.shapes.size(); ++i)
                        m.shapes[i].shape->setPose(
                            interpolatePose(from[i], m.shapes[i].target, s1));
                }
                if (m.self && !m.self->isCandidateListValid(m.x)) m.self->updateCandidates(m.x);
                r2 = m.film->calcForce(m.x, acc);
                if (!std::isfinite(r2)) return false;
                if (k >= nRamp && r2 <= tol2) {
                    relaxed = true;
                    break;
                }
                if (k >= nRamp + o.relaxSubsteps) break;
                m.film->update(m.x, m.v, h, acc);
                const double ke = m.film->calcKineticEnergy(m.v);
                if (ke < kePrev) {
                    m.v.setZero();  // past a peak of the kinetic energy: start again at rest
                    kePrev = 0.0;
                } else {
                    kePrev = ke;
                }
            }
            // The sub-steps ran out: Newton from where they left the film.
            if (!relaxed && o.newtonPolish > 0) relaxed = tryPolish();
            m.model->commitStep(m.x);
            m.model->endViscousStep(m.x);
            if (relaxed) m.v.setZero();  // an equilibrium, at rest
            m.time += dt;
            out->converged = true;
            out->newtonIterations += polish;
            out->unrelaxed = !relaxed;
            out->substeps = static_cast<int>(std::min<long>(k, std::numeric_limits<int>::max()));
            out->substep = h;
            out->residual = std::sqrt(r2);
            out->kineticEnergy = m.film->calcKineticEnergy(m.v);
            return m.x.allFinite();
        } catch (const NumericalError&) {
            return false;
        }
    }
};

Airbag::Airbag(const AirbagSpec& spec) : m_impl(std::make_unique<Impl>()) {
    spec.validate();
    Impl& m = *m_impl;
    m.spec = spec;
    Mesh mesh = spec.mesh.getNumNodes() > 0 ? spec.mesh : makeDoubleWedgeBag(spec.geometry);
    const int chambersPerBag = static_cast<int>(mesh.chambers.size());
    m.nodesPerBag = mesh.getNumNodes();
    if (!spec.cluster.empty()) {
        mesh = placeCopies(mesh, spec.cluster);
        m.numBags = static_cast<int>(spec.cluster.size());
    }
    m.bagChambers.resize(m.numBags);
    for (int b = 0; b < m.numBags; ++b)
        for (int c = 0; c < chambersPerBag; ++c) m.bagChambers[b].push_back(b * chambersPerBag + c);
    m.bagGases.resize(m.numBags);
    m.massFlow.assign(m.numBags, 0.0);
    m.hasTarget.assign(m.numBags, 0);
    m.targetMass.assign(m.numBags, 0.0);
    applyImperfection(mesh, spec.imperfection);
    for (int i = 0; i < mesh.getNumNodes(); ++i) mesh.X.col(i) = spec.X_GB * Vec3(mesh.X.col(i));
    m.mesh = mesh;
    m.meanEdge = calcMeshQuality(mesh).meanEdge;
    std::shared_ptr<const MembraneMaterial> material =
        makeRelaxedMaterial(*spec.material, spec.wrinklingResidual);
    m.model = std::make_shared<MembraneModel>(mesh, material, spec.thickness);
    // A woven film's warp runs along the bag frame's x (the long side), or its z in a panel
    // across it (docs/materials.md#fabric-anisotropy).
    if (!material->isIsotropic())
        m.model->setWarpAxes(spec.X_GB.linear() * Vec3::UnitX(),
                             spec.X_GB.linear() * Vec3::UnitZ());
    if (spec.density > 0.0 && spec.gravity.squaredNorm() > 0.0)
        m.model->setGravity(spec.density, spec.gravity);
    if (spec.bendingStiffness > 0.0) m.model->setBendingStiffness(spec.bendingStiffness);
    if (spec.prony.isOn()) m.model->setProny(spec.prony);
    m.model->setNumThreads(spec.threads);
    // A bag stepped in time evaluates its forces every sub-step: its elements in chunks, which
    // lets the force kernel (bags/FilmForce.h) and the general path's element loop share the
    // threads (the same bits on any number of threads; the general path's roundoff unlike one
    // chunk's, the kernel's the same).
    if (spec.stepping != AirbagSpec::Stepping::QuasiStatic && mesh.getNumTris() >= 256)
        m.model->setElementChunks(8);
    std::vector<char> isSupport(mesh.getNumNodes(), 0);
    for (int n : mesh.supportNodes) isSupport[n] = 1;
    for (int n = 0; n < mesh.getNumNodes(); ++n)
        if (!isSupport[n]) m.freeNodes.push_back(n);
    if (spec.bedBoard) {
        m.bed = makePlane();
        m.bed->setPose(spec.X_GB);
        m.bedContact = std::make_shared<RigidContact>(mesh, m.freeNodes, *m.bed, spec.bedContact);
        m.model->addRigidContact(m.bedContact);
    }
    if (spec.selfContact) {
        SelfContact::Options so;
        so.pressurePenalty = spec.selfContactPenalty;
        so.thickness = std::max(2.0 * spec.thickness, 0.5e-3);
        if (m.numBags > 1) {
            // Neighbours start apart and bulge towards each other: a wider search margin,
            // pressure and gas ramps in small steps, and candidates re-checked after each
            // solve, so that walls meet before they could pass through each other.
            so.candidateMargin = std::max(so.candidateMargin, 0.5 * m.meanEdge);
        }
        m.self = std::make_shared<SelfContact>(mesh, so);

        m.model->setSelfContact(m.self);
    }
    m.x = mesh.X;
    m.v.setZero(3, mesh.getNumNodes());
    m.committed = m.snapshot();
    m.lastAdvanced.resize(3, 0);
    if (spec.stepping == AirbagSpec::Stepping::Dynamic)
        m.stepper = std::make_unique<Impl::DynamicStepper>();
    else if (spec.stepping == AirbagSpec::Stepping::Relaxed)
        m.stepper = std::make_unique<Impl::RelaxedStepper>();
    else
        m.stepper = std::make_unique<Impl::QuasiStaticStepper>();
}

Airbag::~Airbag() = default;
Airbag::Airbag(Airbag&&) noexcept = default;
Airbag& Airbag::operator=(Airbag&&) noexcept = default;

int Airbag::addShape(std::shared_ptr<RigidShape> shape, const RigidContact::Options& options) {
    return addShape(std::move(shape), options, -1);
}

int Airbag::addShape(std::shared_ptr<RigidShape> shape, const RigidContact::Options& options,
                     int bag) {
    if (!shape) throw std::invalid_argument("Airbag::addShape: no shape");
    Impl& m = *m_impl;
    std::vector<int> nodes;
    if (bag < 0) {
        nodes = m.freeNodes;
    } else {
        const std::pair<int, int> range = getBagNodes(bag);
        for (int n : m.freeNodes)
            if (n >= range.first && n < range.second) nodes.push_back(n);
    }
    Impl::Shape s;
    s.contact = std::make_shared<RigidContact>(m.mesh, std::move(nodes), *shape, options);
    s.target = shape->getPose();
    s.shape = std::move(shape);
    m.model->addRigidContact(s.contact);
    m.shapes.push_back(std::move(s));
    m.workspace.reset();
    m.film.reset();  // its stable step counts every shape's penalty
    m.stableStep = 0.0;
    m.committed = m.snapshot();
    return static_cast<int>(m.shapes.size()) - 1;
}

int Airbag::getNumShapes() const { return static_cast<int>(m_impl->shapes.size()); }

void Airbag::inflate(double mass) { inflate(std::vector<double>(m_impl->numBags, mass)); }

namespace {
void checkMasses(const std::vector<double>& masses, int numBags, const char* what) {
    if (static_cast<int>(masses.size()) != numBags)
        throw std::invalid_argument(std::string(what) + ": give one gas mass per bag (" +
                                    std::to_string(numBags) + ", got " +
                                    std::to_string(masses.size()) + ")");
    for (double mass : masses)
        if (!(mass > 0.0 && mass < 1.0))
            throw std::invalid_argument(std::string(what) + ": use a gas mass > 0 and < 1 kg");
}
}  // namespace

void Airbag::inflate(const std::vector<double>& masses) {
    Impl& m = *m_impl;
    checkMasses(masses, m.numBags, "Airbag::inflate");
    if (m.inflated) throw std::logic_error("Airbag::inflate called twice");
    // A prescribed pressure ramp shapes the flat panels, then the gas takes over. Each bag
    // goes to the pressure its gas would have in its flat panels; with several bags the ramp's
    // parameter is the highest of these, the others following in proportion.
    std::vector<double> pTarget(m.numBags);
    for (int b = 0; b < m.numBags; ++b) {
        double Vflat = 0.0;
        for (int c : m.bagChambers[b]) Vflat += calcChamberVolume(m.mesh, c, m.x);
        GasChamber probe(m.spec.gas, masses[b]);
        probe.seal(Vflat);
        pTarget[b] = std::clamp(probe.calcGaugePressure(Vflat), 200.0, 5000.0);
    }
    rampAndSeal(pTarget);
    changeGasMass(masses);
}

void Airbag::inflateToPressure(double gaugePressure) {
    Impl& m = *m_impl;
    if (!(gaugePressure > 0.0 && gaugePressure <= 1e6))
        throw std::invalid_argument(
            "Airbag::inflateToPressure: use a gauge pressure > 0 and "
            "<= 1 MPa (e.g. 4 kPa)");
    if (m.inflated) throw std::logic_error("Airbag::inflateToPressure after the bag was inflated");
    rampAndSeal(std::vector<double>(m.numBags, gaugePressure));
    // The gas sealed at the ramp's end holds the film where the prescribed pressure did: the
    // same state, now solved and committed with the gas as the bag's own load.
    std::vector<double> masses(m.numBags);
    for (int b = 0; b < m.numBags; ++b) masses[b] = getGasMass(b);
    changeGasMass(masses);
}

void Airbag::rampAndSeal(std::vector<double> pTarget) {
    Impl& m = *m_impl;
    const Mesh& mesh = m.mesh;
    for (size_t i = 0; i < m.shapes.size(); ++i) m.shapes[i].target = m.shapes[i].shape->getPose();
    double pMax = 0.0;
    for (double p : pTarget) pMax = std::max(pMax, p);
    if (m.spec.sharedAir) pTarget.assign(m.numBags, pMax);  // one air: one pressure
    m.solveRamp(
        0.0, pMax,
        [&](double p) {
            for (int b = 0; b < m.numBags; ++b)
                for (int c : m.bagChambers[b])
                    m.model->setChamberPressure(c,
                                                pTarget[b] == pMax ? p : p * (pTarget[b] / pMax));
        },
        "inflating the airbag");
    for (int c = 0; c < static_cast<int>(mesh.chambers.size()); ++c)
        m.model->setChamberPressure(c, 0.0);
    // Seal the gas that is in each bag at this pressure (one body per bag, or one per chamber
    // behind orifices); the mass ramp then takes it to its value in steps it can cut.
    auto sealGas = [&](int b, const std::vector<int>& chambers) {
        double V = 0.0;
        for (int c : chambers) V += calcChamberVolume(mesh, c, m.x);
        const GasOptions& g = m.spec.gas;
        const double mSeal =
            (g.ambientPressure + pTarget[b]) * V / (g.getSpecificGasConstant() * g.temperature);
        GasChamber gas(g, mSeal);
        gas.seal(V);
        m.bagGases[b].push_back(m.model->addGas(gas, chambers));
    };
    if (m.spec.sharedAir) {
        // One body of air over every bag's chambers, each bag pointing at it.
        std::vector<int> all;
        for (int b = 0; b < m.numBags; ++b)
            all.insert(all.end(), m.bagChambers[b].begin(), m.bagChambers[b].end());
        sealGas(0, all);
        for (int b = 1; b < m.numBags; ++b) m.bagGases[b] = m.bagGases[0];
    }
    for (int b = 0; b < m.numBags && !m.spec.sharedAir; ++b) {
        const std::vector<int>& chambers = m.bagChambers[b];
        if (m.spec.connection == AirbagSpec::Connection::Orifice && chambers.size() >= 2) {
            for (int c : chambers) sealGas(b, {c});
        } else {
            sealGas(b, chambers);
        }
    }
    m.inflated = true;
}

void Airbag::changeGasMass(double mass) {
    changeGasMass(std::vector<double>(m_impl->numBags, mass));
}

void Airbag::changeGasMass(const std::vector<double>& masses) {
    Impl& m = *m_impl;
    if (!m.inflated) throw std::logic_error("Airbag::changeGasMass before inflate");
    checkMasses(masses, m.numBags, "Airbag::changeGasMass");
    // Quasi-static (no time, infinitely slow): the film's long-term law, ending relaxed.
    m.model->beginViscousStep(std::numeric_limits<double>::infinity());
    m.rampGasMasses(masses);
    if (m.spec.gas.heatTimeConstant > 0.0) m.settleAtRoomTemperature();
    m.model->resetViscousState(m.x);
    m.v.setZero(3, m.x.cols());  // a quasi-static change ends at rest
    m.committed = m.snapshot();
    m.forgetIncrement();
}

void Airbag::setMassFlow(double massFlow) {
    for (int b = 0; b < m_impl->numBags; ++b) setMassFlow(b, massFlow);
}

void Airbag::setMassFlow(int bag, double massFlow) {
    if (!std::isfinite(massFlow)) throw std::invalid_argument("Airbag::setMassFlow: not finite");
    Impl& m = *m_impl;
    m.massFlow.at(bag) = massFlow;
    m.hasTarget.at(bag) = 0;
}

void Airbag::setTargetMass(double mass, double rate) {
    for (int b = 0; b < m_impl->numBags; ++b) setTargetMass(b, mass, rate);
}

void Airbag::setTargetMass(int bag, double mass, double rate) {
    if (!(mass > 0.0 && mass < 1.0) || !(rate > 0.0) || !std::isfinite(rate))
        throw std::invalid_argument(
            "Airbag::setTargetMass: use a mass > 0 and < 1 kg and a positive rate");
    Impl& m = *m_impl;
    if (m.spec.sharedAir)
        throw std::logic_error(
            "Airbag::setTargetMass: the bags share their air (AirbagSpec::sharedAir); a bag's "
            "own target mass has no meaning, set flows (setMassFlow) instead");
    m.massFlow.at(bag) = rate;
    m.hasTarget.at(bag) = 1;
    m.targetMass.at(bag) = mass;
}

double Airbag::getTotalGasMass() const { return m_impl->totalMass(); }
double Airbag::getGasMass(int bag) const { return m_impl->bagMass(checkBag(bag)); }
int Airbag::getNumBags() const { return m_impl->numBags; }

double Airbag::calcFittedRangeUse(double* stretch) const {
    const Impl& m = *m_impl;
    const MembraneMaterial& material = m.model->getMaterial();
    const double limit = calcFittedRangeLimit(material);
    // With a tension field the law is evaluated only where the film is taut (at C) or
    // wrinkled (uniaxially, at its largest stretch); slack film carries nothing.
    const auto* tensionField = dynamic_cast<const WrinklingMaterial*>(&material);
    double use = 0.0, best = 1.0;
    if (std::isfinite(limit) && limit > 0.0) {
        for (int e = 0; e < m.model->getMesh().getNumTris(); ++e) {
            const Mat2 C = m.model->calcElementC(m.x, e);
            const double det = C.determinant();
            if (!(det > 0.0)) continue;
            double l1 = 1.0, l2 = 1.0;
            WrinklingMaterial::calcPrincipalStretches(C, &l1, &l2);
            double x = C.trace() + 1.0 / det - 3.0;  // I1 - 3, plane stress incompressible
            const int state =
                tensionField ? tensionField->calcState(C) : 0;  // taut, wrinkled, slack
            if (state == 2)
                x = 0.0;
            else if (state == 1)
                x = l1 * l1 + 2.0 / l1 - 3.0;  // uniaxial at its largest stretch
            if (x / limit > use) {
                use = x / limit;
                best = l1;
            }
        }
    }
    if (stretch) *stretch = best;
    return use;
}

int Airbag::checkBag(int bag) const {
    if (bag < 0 || bag >= m_impl->numBags)
        throw std::out_of_range("Airbag: bag " + std::to_string(bag) + " of " +
                                std::to_string(m_impl->numBags));
    return bag;
}

std::pair<int, int> Airbag::getBagNodes(int bag) const {
    const Impl& m = *m_impl;
    checkBag(bag);
    return {bag * m.nodesPerBag, (bag + 1) * m.nodesPerBag};
}

const std::vector<int>& Airbag::getBagChambers(int bag) const {
    return m_impl->bagChambers[checkBag(bag)];
}

Vec3 Airbag::calcNeighbourForce(int bag) const {
    // The self-contact energy depends on relative positions only: within one bag its forces
    // sum to zero, so what is left on a bag's nodes comes from the other bags.
    const Impl& m = *m_impl;
    const auto [begin, end] = getBagNodes(bag);
    Vec3 f = Vec3::Zero();
    if (!m.self) return f;
    EnergyAccumulator acc(m.mesh.getNumNodes());
    acc.wantHessian = false;
    m.self->addEnergy(m.x, acc);
    for (int i = begin; i < end; ++i) f -= acc.grad.segment<3>(3 * i);
    return f;
}

void Airbag::setShapePose(int shape, const Eigen::Isometry3d& X_GS) {
    m_impl->shapes.at(shape).target = X_GS;
}

const Eigen::Isometry3d& Airbag::getShapePose(int shape) const {
    return m_impl->shapes.at(shape).shape->getPose();
}

AdvanceSummary Airbag::advance(double dt, int maxCuts) {
    Impl& m = *m_impl;
    if (!m.inflated) throw std::logic_error("Airbag::advance before inflate");
    if (!(dt >= 0.0) || !std::isfinite(dt))
        throw std::invalid_argument("Airbag::advance: use a time step >= 0 s");
    return m.stepper->advance(m, dt, maxCuts);
}

void Airbag::commit() {
    Impl& m = *m_impl;
    if (m.committed && m.committed->x.cols() == m.x.cols()) {
        m.lastIncrement = m.x - m.committed->x;
        m.lastShapeDelta =
            m.shapeTranslations(m.currentPoses()) - m.shapeTranslations(m.committed->poses);
    }
    m.committed = m.snapshot();
}

void Airbag::rollback() {
    m_impl->restore(*m_impl->committed);
    m_impl->workspace.reset();
    m_impl->forgetIncrement();
}

std::shared_ptr<const Airbag::Snapshot> Airbag::getSnapshot() const { return m_impl->snapshot(); }

void Airbag::setSnapshot(const std::shared_ptr<const Snapshot>& snapshot) {
    if (!snapshot) throw std::invalid_argument("Airbag::setSnapshot: no snapshot");
    m_impl->committed = snapshot;
    m_impl->restore(*snapshot);
    m_impl->workspace.reset();
    m_impl->forgetIncrement();
}

double Airbag::getTime() const { return m_impl->time; }

void Airbag::setDynamicOptions(const DynamicOptions& options) {
    Impl& m = *m_impl;
    if (m.spec.stepping == AirbagSpec::Stepping::QuasiStatic)
        throw std::logic_error("Airbag::setDynamicOptions on a quasi-statically stepped bag");
    options.validate();
    m.spec.dynamics = options;
    m.film.reset();  // rebuilt with the new masses at the next step
}

double Airbag::calcKineticEnergy() const {
    const Impl& m = *m_impl;
    if (m.spec.stepping == AirbagSpec::Stepping::QuasiStatic) return 0.0;
    return FilmDynamics(*m.model, m.spec.density, m.spec.dynamics, 0.0).calcKineticEnergy(m.v);
}

void Airbag::saveState(StateWriter& w) const {
    const Impl& m = *m_impl;
    if (!m.inflated) throw std::logic_error("Airbag::saveState before inflate");
    w.tag("airbag");
    m.writeSnapshot(w, *m.snapshot());
    m.writeSnapshot(w, *m.committed);
    for (const Impl::Shape& sh : m.shapes) w.pose(sh.target);
    w.vec(m.massFlow);
    w.vec(m.hasTarget);
    w.vec(m.targetMass);
    w.mat(m.lastIncrement);
    w.mat(m.lastShapeDelta);
    w.mat(m.lastAdvanced);
    w.pod(m.self != nullptr);
    if (m.self) m.self->saveState(w);
}

void Airbag::loadState(StateReader& r) {
    Impl& m = *m_impl;
    if (!m.inflated) throw std::logic_error("Airbag::loadState before inflate");
    r.tag("airbag");
    const std::shared_ptr<Snapshot> current = m.readSnapshot(r);
    const std::shared_ptr<Snapshot> committed = m.readSnapshot(r);
    for (Impl::Shape& sh : m.shapes) sh.target = r.pose();
    r.vecOfSize(m.massFlow, size_t(m.numBags), "bags of the module");
    r.vecOfSize(m.hasTarget, size_t(m.numBags), "bags of the module");
    r.vecOfSize(m.targetMass, size_t(m.numBags), "bags of the module");
    r.mat(m.lastIncrement);
    r.mat(m.lastShapeDelta);
    r.mat(m.lastAdvanced);
    if (r.pod<bool>() != (m.self != nullptr))
        throw StateError("checkpoint: the bag's self-contact is on in one, off in the other");
    if (m.self) m.self->loadState(r);
    m.committed = committed;
    m.restore(*current);
    resetCaches();
}

void Airbag::resetCaches() { m_impl->workspace = SolverWorkspace(); }

Wrench Airbag::calcShapeWrench(int shape) const {
    Wrench w;
    m_impl->shapes.at(shape).contact->calcWrenchOnShape(m_impl->x, &w.force, &w.torque);
    return w;
}

Eigen::Matrix<double, 6, 6> Airbag::calcShapeWrenchTangent(int shape) const {
    return calcShapeWrenchTangents({shape}).front();
}

std::vector<Eigen::Matrix<double, 6, 6>> Airbag::calcShapeWrenchTangents(
    const std::vector<int>& shapes) const {
    return calcShapeWrenchTangents(shapes, nullptr);
}

std::vector<Eigen::Matrix<double, 6, 6>> Airbag::calcShapeWrenchTangents(
    const std::vector<int>& shapes, bool* filmHeld, bool withoutFriction) const {
    Airbag::WrenchLinearisation lin =
        m_impl->linearise(shapes, false, filmHeld != nullptr, withoutFriction);
    if (filmHeld) *filmHeld = lin.filmHeld;
    return std::move(lin.pose);
}

Airbag::WrenchLinearisation Airbag::calcShapeWrenchLinearisation(const std::vector<int>& shapes,
                                                                 bool withoutFriction) const {
    return m_impl->linearise(shapes, true, true, withoutFriction);
}

double Airbag::calcGasInflow(int bag, double dt) const {
    return m_impl->calcGasInflow(checkBag(bag), dt);
}

Eigen::VectorXd Airbag::calcShapeContactPressure(int shape) const {
    return m_impl->shapes.at(shape).contact->calcNodalPressure(m_impl->x);
}

Vec3 Airbag::calcBedForce() const {
    Vec3 f = Vec3::Zero(), t;
    if (m_impl->bedContact) m_impl->bedContact->calcWrenchOnShape(m_impl->x, &f, &t);
    return f;
}

bool Airbag::isGasStill() const {
    return m_impl->isGasStill(1.0) && m_impl->model->isViscouslyRelaxed();
}

int Airbag::getNumChambers() const { return static_cast<int>(m_impl->mesh.chambers.size()); }

ChamberState Airbag::getChamberState(int c) const {
    const Impl& m = *m_impl;
    ChamberState s;
    s.volume = calcChamberVolume(m.mesh, c, m.x);
    s.gaugePressure = m.model->calcChamberGaugePressure(c, m.x);
    const int g = m.model->getChamberGas(c);
    if (g >= 0) {
        const double Vg = m.model->calcGasVolume(g, m.x, nullptr);
        s.mass = m.model->getGas(g).getMass() * s.volume / Vg;
    }
    return s;
}

const Mesh& Airbag::getMesh() const { return m_impl->mesh; }
const Eigen::Matrix3Xd& Airbag::getPositions() const { return m_impl->x; }
const AirbagSpec& Airbag::getSpec() const { return m_impl->spec; }
const MembraneModel& Airbag::getModel() const { return *m_impl->model; }
double Airbag::calcResidual() const { return m_impl->calcFreeResidual(m_impl->x); }

}  // namespace bags
