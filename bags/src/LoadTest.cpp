#include <bags/LoadTest.h>
#include <bags/Airbag.h>
#include <bags/Polynomial.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>

namespace bags {

namespace {

void require(bool ok, const std::string& option, double value, const std::string& valid) {
    if (ok) return;
    std::ostringstream s;
    s << "load test option '" << option << "' = " << value << " is invalid; " << valid;
    throw std::invalid_argument(s.str());
}

constexpr double kBlockHalfHeight = 0.010;  // [m] thickness of the rigid block is irrelevant

double calcTop(const Eigen::Matrix3Xd& x) { return x.row(2).maxCoeff(); }

// Top of the pressed bag (nodes [begin, end)) under the block's footprint [m] (where the
// block first touches).
double calcTopUnderBlock(const Eigen::Matrix3Xd& x, const Vec3& centre, double half, int begin,
                         int end) {
    double top = -std::numeric_limits<double>::infinity();
    for (int i = begin; i < end; ++i)
        if (std::abs(x(0, i) - centre.x()) <= half && std::abs(x(1, i) - centre.y()) <= half)
            top = std::max(top, x(2, i));
    return std::isfinite(top) ? top : calcTop(x);
}

// The load test's one physical early end (io::isCurveFailed() reads its first words).
std::string describeBottomedOut(double disp, double force) {
    std::ostringstream r;
    r << "bottomed out: the block is within 2 mm of the bed board at block travel " << disp * 1e3
      << " mm (" << force << " N)";
    return r.str();
}

// The envelope of a loading: the block presses deeper at a fixed gas mass, so the force of a
// sealed bag rises. Keeps the most force reached in `most`; a fall beyond kForceFallShare of it
// and beyond `floor` marks the curve outside the model's envelope, says so, and returns true
// (the curve stops there).
bool leavesEnvelope(LoadCurve& curve, double disp, double force, double& most, double floor) {
    if (!(force <= most)) {
        most = force;
        return false;
    }
    if (most - force <= std::max(kForceFallShare * most, floor)) return false;
    curve.outsideEnvelope = true;
    std::ostringstream r;
    r << "outside the model's envelope: the block force fell from " << most << " N to " << force
      << " N at block travel " << disp * 1e3
      << " mm while the block pressed deeper at a fixed gas mass, which a sealed bag cannot do "
         "(the film let the block through: a peak force beyond what the bag carries)";
    curve.failure = r.str();
    return true;
}

Eigen::Isometry3d makeBlockPose(const Vec3& centreXY, double zBottom) {
    Eigen::Isometry3d X_GS = Eigen::Isometry3d::Identity();
    X_GS.translation() = Vec3(centreXY.x(), centreXY.y(), zBottom + kBlockHalfHeight);
    return X_GS;
}

}  // namespace

DoubleWedgeParams LoadTestOptions::getBagGeometry() const {
    if (bagScale == 1.0) return geometry;
    DoubleWedgeParams g = geometry;
    g.longSide *= bagScale;
    g.shortSide *= bagScale;
    g.width *= bagScale;
    g.height *= bagScale;
    g.meshSize *= bagScale;
    return g;
}

AirbagSpec makeAirbagSpec(const LoadTestOptions& o) {
    AirbagSpec spec;
    spec.geometry = o.getBagGeometry();
    if (o.bagScale != 1.0) {
        // A similar bag: the geometry's own mesh, every node scaled (the same triangles).
        spec.mesh = makeDoubleWedgeBag(o.geometry);
        spec.mesh.X *= o.bagScale;
    }
    spec.material = o.material;
    spec.thickness = o.thickness;
    spec.density = o.density;
    spec.wrinklingResidual = o.wrinklingResidual;
    spec.prony = o.prony;
    spec.bendingStiffness = o.bendingStiffness;
    spec.gravity = o.gravity ? Vec3(0, 0, -9.81) : Vec3::Zero();
    spec.gas = o.gas;
    spec.connection = o.connection == LoadTestOptions::Connection::Orifice
                          ? AirbagSpec::Connection::Orifice
                          : AirbagSpec::Connection::Open;
    spec.orifice = o.orifice;
    spec.imperfection = o.imperfection;
    spec.bedContact = o.floorContact;
    spec.selfContact = o.selfContact;
    spec.selfContactPenalty = o.blockContact.pressurePenalty;
    spec.solver = o.solver;
    if (spec.solver.maxStep == 0.0) spec.solver.maxStep = spec.geometry.meshSize;
    spec.stabilization = o.stabilization;
    spec.damping = o.damping;
    spec.forceTolerance = calcLoadTestForceTolerance(o);
    spec.threads = o.threads;
    spec.predictor = o.predictor;
    spec.cluster = calcNeighbourPoses(o);
    spec.sharedAir = o.neighbourSharedAir && !spec.cluster.empty();
    spec.stepping = o.stepping;
    if (o.stepping == AirbagSpec::Stepping::Dynamic)
        spec.dynamics = calcLoadTestDynamics(o, o.dynamic.blockSpeed);
    if (o.stepping == AirbagSpec::Stepping::Relaxed) {
        // Pseudo-time: the film's mass scale and damping as the dynamic test's are given.
        spec.dynamics.massScale = o.dynamic.massScale;
        spec.dynamics.damping = o.dynamic.damping;
        spec.dynamics.stepFraction = o.dynamic.stepFraction;
    }
    return spec;
}

DynamicOptions calcLoadTestDynamics(const LoadTestOptions& o, double blockSpeed) {
    const double r = blockSpeed / o.loadingRate;  // film seconds are r test seconds
    DynamicOptions d;
    d.massScale = o.dynamic.massScale * r * r;
    d.damping = o.dynamic.damping / r;
    d.stepFraction = o.dynamic.stepFraction;
    return d;
}

std::vector<Eigen::Isometry3d> calcNeighbourPoses(const LoadTestOptions& o) {
    using N = LoadTestOptions::Neighbours;
    const DoubleWedgeParams g = o.getBagGeometry();
    const double py = g.width + o.neighbourGap;
    const double px = g.longSide + o.neighbourGap;
    std::vector<Vec3> at;
    switch (o.neighbours) {
        case N::None:
            return {};
        case N::Pair:
            at = {Vec3(0, 0, 0), Vec3(0, py, 0)};
            break;
        case N::Row3:
            at = {Vec3(0, 0, 0), Vec3(0, -py, 0), Vec3(0, py, 0)};
            break;
        case N::Block3x3: {
            // The pressed bag (bag 0) at the origin, the block's other positions around it.
            const int pi = o.neighbourPressed[0], pj = o.neighbourPressed[1];
            at = {Vec3(0, 0, 0)};
            for (int i = -1; i <= 1; ++i)
                for (int j = -1; j <= 1; ++j)
                    if (i != pi || j != pj) at.push_back(Vec3((i - pi) * px, (j - pj) * py, 0));
            break;
        }
    }
    std::vector<Eigen::Isometry3d> poses;
    for (const Vec3& p : at) {
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = p;
        poses.push_back(X);
    }
    return poses;
}

double calcLoadTestForceTolerance(const LoadTestOptions& o) {
    // A fraction of the peak force, the peak force counted at most kToleranceForceCap: a large
    // load must never loosen the solve until a wrong answer passes (a 1e6 N peak once let an
    // uninflated bag pass as converged).
    const double t = o.residualTolerance * std::min(o.peakForce, kToleranceForceCap);
    return std::max(t, o.solver.absoluteTolerance);
}

void LoadTestOptions::validate() const {
    geometry.validate();
    if (!material) throw std::invalid_argument("load test option 'material' is not set");
    require(thickness > 0.0 && thickness < 0.01, "thickness", thickness, "use 0 < t < 10 mm");
    require(density >= 0.0, "density", density, "use a density >= 0 kg/m^3");
    require(wrinklingResidual > 0.0 && wrinklingResidual < 0.1, "wrinklingResidual",
            wrinklingResidual, "use 0 < residual < 0.1 (e.g. 1e-3)");
    try {
        prony.validate();
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string("load test option 'prony': ") + e.what());
    }
    gas.validate();
    if (gasMasses.empty()) throw std::invalid_argument("load test option 'gasMasses' is empty");
    for (double m : gasMasses)
        require(m > 0.0 && m < 1.0, "gasMasses", m, "use masses > 0 (in kg inside; e.g. 3.5 g)");
    require(bagScale >= 0.5 && bagScale <= 2.0, "bagScale", bagScale,
            "use 0.5 to 2 (a similar bag, every size times this; 1: as built)");
    getBagGeometry().validate();
    require(blockSize > 0.0 && blockSize <= getBagGeometry().longSide, "blockSize", blockSize,
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
        if (gas.heatTimeConstant > 0.0)
            throw std::invalid_argument(
                "load test option 'gas.heatTimeConstant' (heat exchange) needs the open "
                "connection; the orifice connection does not carry the heat of the flow");
        if (!geometry.diaphragm)
            throw std::invalid_argument(
                "load test option 'connection' = orifice needs the two chambers; set the "
                "geometry's diaphragm (or use the open connection)");
    }
    require(residualTolerance >= 0.0 && residualTolerance <= 0.05, "residualTolerance",
            residualTolerance, "use a fraction of the peak force from 0 to 0.05 (e.g. 1e-3)");
    imperfection.validate();
    require(bendingStiffness >= 0.0 && bendingStiffness < 1.0, "bendingStiffness", bendingStiffness,
            "use 0 (a pure membrane) to 1 N m");
    require(threads >= 0 && threads <= 256, "threads", threads, "use 0 (default) to 256");
    require(lowForceStepFactor >= 1.0 && lowForceStepFactor <= 20.0, "lowForceStepFactor",
            lowForceStepFactor, "use 1 (no larger steps) to 20");
    require(ensemble >= 1 && ensemble <= 64, "ensemble", ensemble,
            "use 1 (one bag) to 64 imperfection seeds");
    if (ensemble > 1 && imperfection.amplitude == 0.0)
        throw std::invalid_argument(
            "load test option 'ensemble' = " + std::to_string(ensemble) +
            " needs an imperfection (amplitude > 0): bags without one are all the same bag");
    require(stabilization >= 0.0, "stabilization", stabilization,
            "use a stiffness per area >= 0 Pa/m (0 disables it; e.g. 1e4)");
    require(damping >= 0.0 && std::isfinite(damping), "damping", damping,
            "use a stiffness per area >= 0 Pa/m (0: no damper; e.g. 1e5)");
    if (neighbours != Neighbours::None) {
        require(neighbourGap > 0.0 && neighbourGap < 0.1, "neighbourGap", neighbourGap,
                "use a gap between the bags' facing panels of 0 < gap < 100 mm (e.g. 5 mm)");
        require(neighbourGasMass >= 0.0 && neighbourGasMass < 1.0, "neighbourGasMass",
                neighbourGasMass,
                "use a gas mass > 0 (in kg inside; e.g. 3.0 g), or 0 for the pressed bag's own");
        for (int k = 0; k < 2; ++k)
            if (neighbourPressed[k] < -1 || neighbourPressed[k] > 1 ||
                (neighbours != Neighbours::Block3x3 && neighbourPressed[k] != 0))
                throw std::invalid_argument(
                    "load test option 'neighbourPressed' = (" +
                    std::to_string(neighbourPressed[0]) + ", " +
                    std::to_string(neighbourPressed[1]) +
                    "): use -1, 0 or 1 along x and across y, within a block3x3 only");
        if (connection != Connection::Open)
            throw std::invalid_argument(
                "load test option 'neighbours' needs the open connection (one gas body per "
                "bag); the orifice connection is not supported among neighbours");
        if (!selfContact)
            throw std::invalid_argument(
                "load test option 'neighbours' needs selfContact: the bags' walls meet "
                "through it");
        if (ensemble > 1)
            throw std::invalid_argument(
                "load test option 'neighbours' does not run with an ensemble (ensemble = " +
                std::to_string(ensemble) + "); use ensemble 1");
    }
    if (stepping == AirbagSpec::Stepping::Relaxed)
        require(density > 0.0, "density", density,
                "the relaxed test moves the film's mass in pseudo-time: use a density > 0 kg/m^3");
    if (stepping == AirbagSpec::Stepping::Dynamic) {
        const Dynamic& d = dynamic;
        require(d.blockSpeed >= loadingRate && d.blockSpeed <= 1.0, "dynamic.blockSpeed",
                d.blockSpeed, "use a speed from the loading rate to 1 m/s (e.g. 20 mm/s)");
        require(d.massScale >= 1.0 && d.massScale <= 1e6, "dynamic.massScale", d.massScale,
                "use 1 (the real film) to 1e6 (e.g. 1000)");
        require(d.damping >= 0.0 && d.damping <= 1e4, "dynamic.damping", d.damping,
                "use 0 to 1e4 per second (e.g. 20 /s)");
        require(d.stepFraction > 0.0 && d.stepFraction <= 1.0, "dynamic.stepFraction",
                d.stepFraction, "use 0 < fraction <= 1 of the stable step (e.g. 0.5)");
        require(d.recordEvery > 0.0 && d.recordEvery <= displacementStep * 4.0,
                "dynamic.recordEvery", d.recordEvery,
                "use 0 < travel <= 4 displacement steps (e.g. 0.25 mm)");
        require(d.kineticShareLimit > 0.0 && d.kineticShareLimit < 1.0, "dynamic.kineticShareLimit",
                d.kineticShareLimit,
                "use a fraction 0 < share < 1 of the block's work (e.g. 0.01)");
        require(d.maxHalvings >= 0 && d.maxHalvings <= 6, "dynamic.maxHalvings", d.maxHalvings,
                "use 0 to 6 halvings of the block speed");
        require(d.rampTravel >= 0.0 && d.rampTravel <= 0.02, "dynamic.rampTravel", d.rampTravel,
                "use 0 (full speed at once) to 20 mm (e.g. 2 mm)");
        require(density > 0.0, "density", density,
                "the dynamic test moves the film's mass: use a density > 0 kg/m^3");
    }
    blockContact.validate();
    floorContact.validate();
    solver.validate();
}

std::vector<double> getSeedStiffnessPolynomial() {
    return {-0.945, 8.394, -25.707, 32.714, -17.181, 6.196};
}

namespace {

LoadTestResult runOneLoadTest(const LoadTestOptions& o, const LoadTestObserver& observer) {
    const auto wallStart = std::chrono::steady_clock::now();
    Airbag bag(makeAirbagSpec(o));
    const Mesh& mesh = bag.getMesh();
    const bool cluster = o.neighbours != LoadTestOptions::Neighbours::None;
    // The pressed bag is bag 0 of a cluster: its nodes and chambers are the ones measured.
    const auto [pressedBegin, pressedEnd] =
        cluster ? bag.getBagNodes(0) : std::pair<int, int>(0, static_cast<int>(mesh.X.cols()));
    std::vector<int> chambers;
    if (cluster) {
        chambers = bag.getBagChambers(0);
    } else {
        for (int c = 0; c < bag.getNumChambers(); ++c) chambers.push_back(c);
    }
    // Per-bag gas masses of curve k: the pressed bag's, then its neighbours'.
    const int nBags = cluster ? static_cast<int>(calcNeighbourPoses(o).size()) : 1;
    auto bagMasses = [&](size_t k) {
        std::vector<double> m(nBags,
                              o.neighbourGasMass > 0.0 ? o.neighbourGasMass : o.gasMasses[k]);
        m[0] = o.gasMasses[k];
        return m;
    };
    // Block above the pressed bag's apex ridge, parked well clear while inflating.
    Vec3 blockCentreXY = Vec3::Zero();
    {
        int top = pressedBegin;
        for (int i = pressedBegin; i < pressedEnd; ++i)
            if (mesh.X(2, i) > mesh.X(2, top)) top = i;
        blockCentreXY = Vec3(mesh.X(0, top), 0.0, 0.0);
    }
    auto blockShape = std::shared_ptr<RigidShape>(
        makeBox(Vec3(0.5 * o.blockSize, 0.5 * o.blockSize, kBlockHalfHeight),
                std::min(1e-3, 0.1 * o.blockSize)));
    blockShape->setPose(makeBlockPose(blockCentreXY, calcTop(mesh.X) + 0.2));
    const int block = bag.addShape(blockShape, o.blockContact);

    if (cluster) {
        bag.inflate(bagMasses(0));
    } else {
        bag.inflate(o.gasMasses.front());
    }

    LoadTestResult result;
    std::shared_ptr<const Airbag::Snapshot> lastUnloaded;  // the last curve's state before loading
    for (size_t k = 0; k < o.gasMasses.size(); ++k) {
        LoadCurve curve;
        curve.gasMass = o.gasMasses[k];
        // Park the block well clear. A slack bag released from a deep press may be left in a
        // stabilised, folded state whose relaxation cannot be solved: it then goes back to
        // its state before that curve's loading (an equilibrium, block clear).
        // A set-up that cannot be solved (parking, the gas change, the settling) ends this
        // curve as failed, with its reason and no steps; the next mass is tried from the last
        // curve's unloaded state, so the curves already done keep their results.
        try {
            bag.setShapePose(block,
                             makeBlockPose(blockCentreXY, calcTop(bag.getPositions()) + 0.05));
            if (!bag.advance(0.0, 12).converged) {
                if (!lastUnloaded) throw NumericalError("no convergence while parking the block");
                bag.setSnapshot(lastUnloaded);
                bag.setShapePose(block,
                                 makeBlockPose(blockCentreXY, calcTop(bag.getPositions()) + 0.05));
                if (!bag.advance(0.0, 12).converged)
                    throw NumericalError("no convergence while parking the block");
            }
            bag.commit();
            // Let the gas out (or in) to this curve's mass, block clear.
            if (cluster) {
                bag.changeGasMass(bagMasses(k));
            } else {
                bag.changeGasMass(curve.gasMass);
            }
            if (o.connection == LoadTestOptions::Connection::Orifice && o.settleTime > 0.0) {
                // Before loading, the chambers settle towards one pressure (a long wait, 1000 s
                // by default). Backward Euler in steps doubling in length (0.98 s first of 10):
                // the pressure difference falls fastest at the start. On the 20 mm rig with a
                // 0.01 mm orifice one step leaves 53.34 Pa, 10 steps 52.7988 Pa, 40 steps
                // 52.7982 Pa (tests/bags/LoadTestTest.cpp).
                const int n = o.settleSteps;
                const double first = o.settleTime / (std::pow(2.0, n) - 1.0);
                for (int i = 0; i < n; ++i) {
                    if (!bag.advance(first * std::pow(2.0, i), 0).converged)
                        throw NumericalError(
                            "no convergence while the chambers settle through the orifice");
                    bag.commit();
                }
            }
        } catch (const NumericalError& e) {
            if (!lastUnloaded) throw;
            bag.setSnapshot(lastUnloaded);
            curve.failure = std::string("before loading: ") + e.what();
            curve.failed = true;
            // Never reached: its unloaded state is unknown, not zero.
            const double nan = std::numeric_limits<double>::quiet_NaN();
            curve.stiffness = curve.r2 = nan;
            curve.unloadedHeight = curve.inflatedVolume = curve.inflatedGaugePressure = nan;
            result.curves.push_back(std::move(curve));
            continue;
        }
        const double top = calcTopUnderBlock(bag.getPositions(), blockCentreXY, 0.5 * o.blockSize,
                                             pressedBegin, pressedEnd);
        curve.unloadedHeight = top;
        curve.inflatedVolume = 0.0;
        for (int c : chambers) curve.inflatedVolume += bag.getChamberState(c).volume;
        curve.inflatedGaugePressure = bag.getChamberState(chambers.front()).gaugePressure;
        const auto unloaded = bag.getSnapshot();
        lastUnloaded = unloaded;

        // A dynamic curve's loading may be run again at half the block speed: its steps are
        // held back from the observer until it is kept.
        const bool dynamic = o.stepping == AirbagSpec::Stepping::Dynamic;
        bool holding = dynamic && o.dynamic.maxHalvings > 0;
        std::vector<std::pair<LoadStep, Eigen::Matrix3Xd>> held;
        auto record = [&](double disp, bool loading, const AdvanceSummary& sum) {
            LoadStep st;
            st.curve = static_cast<int>(k);
            st.step = static_cast<int>(curve.steps.size());
            st.loading = loading;
            st.displacement = disp;
            const double prevDisp = curve.steps.empty() ? 0.0 : curve.steps.back().displacement;
            const double prevTime = curve.steps.empty() ? 0.0 : curve.steps.back().time;
            st.time = prevTime + std::abs(disp - prevDisp) / o.loadingRate;
            st.force = bag.calcShapeWrench(block).force.z();
            for (int c : chambers) {
                const ChamberState cs = bag.getChamberState(c);
                st.gaugePressure.push_back(cs.gaugePressure);
                st.volume.push_back(cs.volume);
                st.gasMass.push_back(cs.mass);
            }
            st.newtonIterations = sum.newtonIterations;
            st.factorizations = sum.factorizations;
            st.residual = sum.residual;
            st.stabilizationEnergy = sum.stabilizationEnergy;
            st.kineticEnergy = sum.kineticEnergy;
            st.substeps = sum.substeps;
            curve.steps.push_back(st);
            if (holding)
                held.emplace_back(st, bag.getPositions());
            else if (observer)
                observer(st, mesh, bag.getPositions());
            return st.force;
        };

        record(0.0, true, AdvanceSummary());
        // Moves the block to travel `to` from the last converged state, over the test's time;
        // the bag restores itself when the step fails (the caller shortens it).
        auto advance = [&](double to, AdvanceSummary* sum) {
            const double dt = std::abs(to - curve.steps.back().displacement) / o.loadingRate;
            bag.setShapePose(block, makeBlockPose(blockCentreXY, top - to));
            *sum = bag.advance(dt, 0);
            // A relaxed step whose sub-steps ran out is no equilibrium: the step is cut as a
            // Newton solve that failed would be.
            const bool ok = sum->converged && !sum->unrelaxed;
            if (ok) bag.commit();
            return ok;
        };
        // A fold snapping through under the block: step over it (stepOverSnap), counted.
        auto snapOver = [&](double from, double tried, double dir, double limit,
                            AdvanceSummary* sum) {
            if (!o.stepOverSnaps) return -1.0;
            const double to = stepOverSnap([&](double t) { return advance(t, sum); }, from, tried,
                                           dir, limit, o.displacementStep);
            if (to >= 0.0) {
                ++curve.snaps;
                curve.snapTravel += std::abs(to - from);
            }
            return to;
        };
        // A loading failure is kept when the unloading from there fails too.
        auto fail = [&](const char* branch, double disp) {
            std::ostringstream s;
            if (!curve.failure.empty()) s << curve.failure << "; then ";
            s << "no convergence " << branch << " at block travel " << disp * 1e3 << " mm";
            curve.failure = s.str();
            curve.failed = true;
        };
        double disp = 0.0;
        if (dynamic) {
            // The block moves on without stopping; the bag sub-cycles its film through each
            // recorded stretch of travel. Along the loading the block slows down (halving its
            // pace, at most maxHalvings times) while the film's kinetic energy is more than
            // half its limit of the block's work so far, and speeds up again while it is below
            // an eighth of it. A curve whose share still broke the limit is run again at half
            // the block speed.
            const LoadTestOptions::Dynamic& dy = o.dynamic;
            double speed = dy.blockSpeed;
            int slower = 0;     // halvings of the pace now
            int calm = 0;       // records in a row with the share below an eighth of its limit
            double pace = 0.0;  // the pace the bag is set to
            // The block's pace over a stretch of travel ending `travel` past the last turn:
            // up to speed over rampTravel, halved `slower` times.
            auto setPace = [&](double travel) {
                const double f =
                    dy.rampTravel > 0.0 ? std::clamp(travel / dy.rampTravel, 1.0 / 16.0, 1.0) : 1.0;
                const double want = f * speed * std::ldexp(1.0, -slower);
                if (want != pace) bag.setDynamicOptions(calcLoadTestDynamics(o, want));
                pace = want;
                curve.blockSpeed = std::min(curve.blockSpeed, pace / f);
            };
            for (int halving = 0;; ++halving) {
                curve.blockSpeed = speed;
                pace = 0.0;
                slower = calm = 0;
                double work = 0.0;
                // The block brought down to the film from where it was parked at once (no
                // time: a quasi-static change), not swept down through the step.
                bag.setShapePose(block, makeBlockPose(blockCentreXY, top));
                if (!bag.advance(0.0, 12).converged) {
                    fail("loading", 0.0);
                    break;
                }
                bag.commit();
                disp = 0.0;
                double force = 0.0, stiffnessEstimate = 0.0, most = 0.0;
                const double maxDisp = top - 0.002;  // the block stops 2 mm above the bed board
                while (force < o.peakForce * (1.0 - 1e-3)) {
                    double step = dy.recordEvery;
                    if (stiffnessEstimate > 0.0 && force >= 0.5 * o.stiffnessFrom)
                        step = std::min(step,
                                        std::max(0.2 * dy.recordEvery,
                                                 1.05 * (o.peakForce - force) / stiffnessEstimate));
                    step = std::min(step, maxDisp - disp);
                    if (step < 1e-6) {
                        curve.failure = describeBottomedOut(disp, force);
                        break;
                    }
                    AdvanceSummary sum;
                    setPace(disp + step);
                    if (!advance(disp + step, &sum)) {
                        fail("loading", disp);
                        break;
                    }
                    const double prevForce = force;
                    disp += step;
                    force = record(disp, true, sum);
                    if (leavesEnvelope(curve, disp, force, most, o.stiffnessFrom)) break;
                    const double kk = (force - prevForce) / step;
                    if (kk > 0.0 && force >= 0.25 * o.stiffnessFrom) stiffnessEstimate = kk;
                    // The pace. While a slack bag folds in under next to no force the block's
                    // work is next to nothing: the share is taken of at least the work of half
                    // the stiffness range's start over a millimetre (there the folds the
                    // stiffness range will see are laid).
                    work += 0.5 * (force + prevForce) * step;
                    {
                        const double share =
                            sum.kineticEnergy / std::max(work, 0.5 * o.stiffnessFrom * 1e-3);
                        if (share > 0.5 * dy.kineticShareLimit && slower < dy.maxHalvings) {
                            ++slower;
                            calm = 0;
                        } else if (share < 0.125 * dy.kineticShareLimit && slower > 0) {
                            if (++calm >= 8) --slower, calm = 0;
                        } else {
                            calm = 0;
                        }
                    }
                }
                curve.reachedPeak = force >= o.peakForce * (1.0 - 1e-3);
                // The kinetic energy's share of the block's work so far, along the loading.
                double share = 0.0, lastShare = 0.0;
                bool inRange = false;
                work = 0.0;
                for (size_t i = 1; i < curve.steps.size() && curve.steps[i].loading; ++i) {
                    const LoadStep& st = curve.steps[i];
                    const LoadStep& prev = curve.steps[i - 1];
                    work += 0.5 * (st.force + prev.force) * (st.displacement - prev.displacement);
                    lastShare = work > 0.0 ? st.kineticEnergy / work : 0.0;
                    inRange = inRange || st.force >= o.stiffnessFrom;
                    if (inRange) share = std::max(share, lastShare);
                }
                curve.kineticShare = inRange ? share : lastShare;
                if (curve.kineticShare <= dy.kineticShareLimit || halving >= dy.maxHalvings ||
                    curve.failed || curve.outsideEnvelope)
                    break;
                // Again at half the speed, from the unloaded state.
                bag.setSnapshot(unloaded);
                held.clear();
                curve.steps.clear();
                curve.failure.clear();
                record(0.0, true, AdvanceSummary());
                speed *= 0.5;
            }
            // The loading kept: its steps to the observer.
            holding = false;
            if (observer)
                for (const auto& [st, x] : held) observer(st, mesh, x);
            held.clear();
            // Unloading: back up until the block leaves the bag.
            const double turn = disp;
            while (o.unload && !curve.failed && !curve.outsideEnvelope && disp > 0.0) {
                const double step = std::min(dy.recordEvery, disp);
                AdvanceSummary sum;
                setPace(turn - disp + step);
                if (!advance(disp - step, &sum)) {
                    fail("unloading", disp);
                    break;
                }
                disp = std::max(disp - step, 0.0);
                if (record(disp, false, sum) <= 0.0) break;  // block has left
            }
            if (curve.kineticShare > dy.kineticShareLimit) {
                curve.quasiStatic = false;
                std::ostringstream r;
                if (!curve.failure.empty()) r << curve.failure << "; ";
                r << "not quasi-static: the film's kinetic energy reached "
                  << curve.kineticShare * 100.0 << " % of the block's work (limit "
                  << dy.kineticShareLimit * 100.0 << " %) at a block speed of "
                  << curve.blockSpeed * 1e3 << " mm/s";
                curve.failure = r.str();
            }
        } else {
            // Loading: displacement control, adaptive, aiming the last step at the peak force.
            double ds = o.displacementStep, force = 0.0, stiffnessEstimate = 0.0, most = 0.0;
            const double minStep = 5e-5;         // [m] smaller steps rarely rescue a slack curve
            const double maxDisp = top - 0.002;  // the block stops 2 mm above the bed board
            while (force < o.peakForce * (1.0 - 1e-3)) {
                // Far below the stiffness range (a slack bag folding in under almost no force) the
                // step may grow to lowForceStepFactor times the target, as long as the force it
                // predicts stays below half the range's start.
                const bool low = force < 0.25 * o.stiffnessFrom;
                double step = std::min(
                    ds, low ? o.lowForceStepFactor * o.displacementStep : o.displacementStep);
                if (low && stiffnessEstimate > 0.0)
                    step = std::min(step,
                                    std::max(o.displacementStep,
                                             (0.5 * o.stiffnessFrom - force) / stiffnessEstimate));
                if (stiffnessEstimate > 0.0)
                    step = std::min(step, 1.05 * (o.peakForce - force) / stiffnessEstimate);
                step = std::max(step, minStep);
                step = std::min(step, maxDisp - disp);  // the last step ends on the stop
                if (step < minStep) {
                    // The slack bag is pressed flat under the block: with penalty contact (1 mm
                    // of penetration per 10 kPa by default) the last 2 mm cannot be resolved.
                    curve.failure = describeBottomedOut(disp, force);
                    break;
                }
                AdvanceSummary sum;
                if (!advance(disp + step, &sum)) {
                    ds = 0.5 * step;
                    if (ds >= minStep) continue;
                    const double to = snapOver(disp, step, +1.0, maxDisp, &sum);
                    if (to < 0.0) {
                        fail("loading", disp);
                        break;
                    }
                    step = to - disp;
                    ds = o.displacementStep;
                }
                const double prevForce = force;
                disp += step;
                force = record(disp, true, sum);
                if (leavesEnvelope(curve, disp, force, most, o.stiffnessFrom)) break;
                const double kk = (force - prevForce) / step;
                if (kk > 0.0) stiffnessEstimate = kk;
                if (sum.newtonIterations < 6)
                    ds = std::min(2.0 * step,
                                  (force < 0.25 * o.stiffnessFrom ? o.lowForceStepFactor : 1.0) *
                                      o.displacementStep);
            }
            curve.reachedPeak = force >= o.peakForce * (1.0 - 1e-3);
            // Unloading: back up the same way until the block leaves the bag.
            ds = o.displacementStep;
            double unloadForce = force;
            while (o.unload && !curve.outsideEnvelope && disp > 0.0) {
                const double cap =
                    (unloadForce < 0.25 * o.stiffnessFrom ? o.lowForceStepFactor : 1.0) *
                    o.displacementStep;
                double step = std::min({ds, cap, disp});
                AdvanceSummary sum;
                if (!advance(disp - step, &sum)) {
                    ds = 0.5 * step;
                    if (ds >= minStep) continue;
                    const double to = snapOver(disp, step, -1.0, 0.0, &sum);
                    if (to < 0.0) {
                        fail("unloading", disp);
                        break;
                    }
                    step = disp - to;
                    ds = o.displacementStep;
                }
                disp = std::max(disp - step, 0.0);
                unloadForce = record(disp, false, sum);
                if (unloadForce <= 0.0) break;  // block has left
                if (sum.newtonIterations < 6) ds = 2.0 * step;
            }
        }
        if (disp > 0.0) {
            // Lift the block clear so the next gas mass starts from a free bag, in steps the
            // bag cuts; if even that cannot be solved, go back to this mass's unloaded state.
            bag.setShapePose(block, makeBlockPose(blockCentreXY, top));
            const AdvanceSummary lift = bag.advance(disp / o.loadingRate, 12);
            if (lift.converged) {
                bag.commit();
            } else {
                bag.setSnapshot(unloaded);
            }
        }
        // How much the stabilisation carried: steps accepted with springs, and the energy the
        // springs held at those states, summed over the steps so far, against the block's
        // work so far (trapezoidal): the largest ratio along the loading branch from where the
        // force reaches the stiffness range (before it the block's work is next to nothing and
        // any ratio is large), or at the loading's end if it never does.
        {
            double work = 0.0, held = 0.0;
            bool inRange = false;
            for (size_t i = 0; i < curve.steps.size(); ++i) {
                const LoadStep& st = curve.steps[i];
                if (st.stabilizationEnergy > 0.0) ++curve.stabilizedSteps;
                if (!st.loading || i == 0) continue;
                const LoadStep& prev = curve.steps[i - 1];
                work += 0.5 * (st.force + prev.force) * (st.displacement - prev.displacement);
                held += st.stabilizationEnergy;
                inRange = inRange || st.force >= o.stiffnessFrom;
                if (inRange && work > 0.0 && held > 0.0)
                    curve.stabilizationShare = std::max(curve.stabilizationShare, held / work);
            }
            if (!inRange && work > 0.0) curve.stabilizationShare = held / work;
        }
        const LinearFit lf = calcRangeStiffness(curve.steps, o.stiffnessFrom, o.stiffnessTo);
        curve.stiffness = lf.slope;
        curve.r2 = lf.r2;
        result.curves.push_back(std::move(curve));
    }
    classifyStages(result.curves);
    // k(m) fit in the seed's units: k [N/mm] of m [g].
    std::vector<double> mg, kk;
    for (const LoadCurve& c : result.curves)
        if (std::isfinite(c.stiffness))
            mg.push_back(c.gasMass * 1e3), kk.push_back(c.stiffness * 1e-3);
    if (static_cast<int>(mg.size()) > o.polynomialOrder)
        result.kFit = fitPolynomial(mg, kk, o.polynomialOrder);
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
    for (LoadCurve& c : result.curves) c.stiffnessMin = c.stiffnessMax = c.stiffness;
    return result;
}

}  // namespace

double stepOverSnap(const std::function<bool(double)>& tryTravel, double from, double tried,
                    double dir, double limit, double displacementStep) {
    for (const double n : {1.0, 2.0, 4.0}) {
        double to = from + dir * n * displacementStep;
        to = dir > 0.0 ? std::min(to, limit) : std::max(to, limit);
        if (std::abs(to - from) <= tried * (1.0 + 1e-12)) continue;  // no longer than the failed
        if (tryTravel(to)) return to;
    }
    return -1.0;
}

LoadTestResult runLoadTest(const LoadTestOptions& o, const LoadTestObserver& observer) {
    o.validate();
    const auto wallStart = std::chrono::steady_clock::now();
    LoadTestResult result = runOneLoadTest(o, observer);
    if (o.ensemble > 1) {
        // The other bags of the ensemble, one thread each; their curves only give the spread.
        const int n = o.ensemble - 1;
        std::vector<LoadTestResult> members(n);
        std::vector<std::string> errors(n);
#pragma omp parallel for schedule(dynamic, 1)
        for (int i = 0; i < n; ++i) {
            LoadTestOptions m = o;
            m.ensemble = 1;
            m.threads = 1;
            m.imperfection.seed = o.imperfection.seed + 1 + static_cast<std::uint64_t>(i);
            try {
                members[i] = runOneLoadTest(m, {});
            } catch (const std::exception& e) {
                errors[i] = e.what();
            }
        }
        for (int i = 0; i < n; ++i)
            if (!errors[i].empty())
                throw NumericalError("ensemble bag with imperfection seed " +
                                     std::to_string(o.imperfection.seed + 1 + i) + ": " +
                                     errors[i]);
        for (size_t c = 0; c < result.curves.size(); ++c) {
            LoadCurve& curve = result.curves[c];
            curve.ensembleSize = o.ensemble;
            for (const LoadTestResult& m : members) {
                const double k = m.curves[c].stiffness;
                if (!std::isfinite(k) || !std::isfinite(curve.stiffnessMin)) {
                    curve.stiffnessMin = curve.stiffnessMax = std::nan("");
                    continue;
                }
                curve.stiffnessMin = std::min(curve.stiffnessMin, k);
                curve.stiffnessMax = std::max(curve.stiffnessMax, k);
            }
        }
    }
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
        if (std::isfinite(c.stiffness) && c.stiffness < kMin)
            kMin = c.stiffness, mAtMin = c.gasMass;
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
