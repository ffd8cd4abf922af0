#pragma once
/// @file A reduced model of one seed bag (the double wedge) as a co-simulation bag, in place of
/// the finite-element bags::Airbag where many fast runs are wanted (controller design).
/// Equations, calibration and validity: docs/reduced-bag.md.
///
/// The model: the bag's gas (mass m, isothermal, one gas body: the chambers share their air
/// through the open connection) and its unloaded top surface h(x, y; m) as a grid of points in
/// the bag frame (below the calibration's first taut mass, that mass's top: a slack film wraps
/// the shapes within the taut bag's enclosure). A shape pressing the bag overlaps the top; at
/// grid point i (area a, projected) its depth is delta_i = -(signed distance of the top point
/// to the shape). Per shape s: the overlap volume V_s = sum a l_i, l_i the length of grid
/// column i inside the shape below the top and above the board (where shapes share a column,
/// the union of their chords, shared by length), its depth d_s = sum a delta_i^2 / sum a
/// delta_i (over delta_i > 0: the overlap's mean depth weighted by depth). The gas:
///   (P + p_amb) (V_free(P) - V_d) = m R T,   V_d = sum_s beta(m, d_s) V_s,   P >= 0,
/// with V_free(P) the unloaded bag's volume at gauge pressure P (from the calibration's
/// unloaded states) and beta the calibrated share of displaced volume (1 below the first taut
/// mass). The contact pressure at
/// a point in contact: q_i = kappa(m, d_s) P w(delta_i) + k_b max(0, -z_i) (w a smoothstep
/// from -skirt d_s to the rim width: the film wraps the shape a little beyond where it cut
/// the unloaded top; the second term the film pressed on the bed board, z_i the contact
/// point's height above it); it acts on the shape's surface over the area a / (-n_z), along
/// the shape's inward normal -n, so the force on the shape is sum_i q_i a / (-n_z) (-n) and its
/// vertical part sum_i q_i a. kappa is the calibrated ratio of contact pressure to gas pressure
/// (it holds the membrane's own share). The tangent is exact for this model (analytic).
///
/// Call protocol: Participant's (cosim/Participant.h) and Bag's (cosim/Bag.h); addShape() and
/// setGasMass() before the coupling starts. Each committed step is checked against the
/// calibration's validity envelope (gas mass, depth, shape curvature radius, tilt); the steps
/// outside it are counted (getEnvelopeCounts()).

#include <bags/Contact.h>
#include <bags/Geometry.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "cosim/Bag.h"

namespace cosim {

/// What a reduced bag is made from: written by the calibration (bench_reduced_bag calibrate),
/// read by io::readReducedBagCalibration().
struct ReducedBagCalibration {
    std::string source;                ///< commit, command and settings that made it (text)
    bags::DoubleWedgeParams geometry;  ///< the bag it describes (sizes, the FE mesh size)
    double gasConstant = 287.0;        ///< specific gas constant R [J/(kg K)]
    double temperature = 296.15;       ///< [K]
    double ambientPressure = 1.0e5;    ///< [Pa] absolute
    double boardPenalty = 1e8;         ///< [Pa/m] the pressed film on the bed board
    double rimWidth = 2e-3;            ///< [m] depth over which the rim pressure rises (w)
    /// The skirt: points of the unloaded top outside a shape but within skirt x (its depth)
    /// of it touch it too (the film wraps the shape beyond where it cut the unloaded top).
    double skirt = 0.0;
    /// The unloaded bag per gas mass (masses ascending) [kg], gauge pressure [Pa], volume [m^3].
    std::vector<double> masses, gaugePressures, volumes;
    /// The top grid in the bag frame: point (ix, iy) at (x0 + ix pitch, y0 + iy pitch).
    int nx = 0, ny = 0;
    double x0 = 0.0, y0 = 0.0, pitch = 0.01;
    /// Per mass: the unloaded top height [m] (nx x ny), NaN where there is no bag.
    std::vector<Eigen::MatrixXd> top;
    /// Depth nodes [m] (ascending, first 0) of the factor tables (masses x depths).
    std::vector<double> depths;
    Eigen::MatrixXd pressureFactor;  ///< kappa: contact pressure / gas pressure
    Eigen::MatrixXd volumeFactor;    ///< beta: displaced volume / overlap volume
    /// The validity envelope: masses [masses.front(), masses.back()], and:
    double depthMax = 0.05;   ///< [m] deepest calibrated depth
    double radiusMin = 0.05;  ///< [m] least curvature radius of the calibration's shapes
    double radiusMax = 0.2;   ///< [m] largest
    double tiltMax = 0.5;     ///< [rad] largest angle of the contact normal from vertical
    /// The panel coupling (docs/reduced-bag.md#a-load-on-one-panel-lifts-the-other): the other
    /// shapes' loads on the bag move a shape's top, per newton of load on a panel, down by
    /// panelSink [m/N] on that panel and up by panelLift [m/N] on the other one. A grid point's
    /// and a load's panel: the steep one at x < the apex's, blended over +-panelBlend [m]
    /// across the ridge. 0 and 0: off (a calibration without the record).
    double panelSink = 0.0, panelLift = 0.0, panelBlend = 0.02;
    /// @throws std::invalid_argument naming the member if sizes or values do not fit.
    void validate() const;
};

/// Coulomb friction of the shapes on the film (docs/reduced-bag.md#friction). Per shape one
/// elastic stick spring with Kelvin-Voigt damping between a point of the shape and an anchor
/// fixed in Ground, in the plane normal to the shape's contact force F_n (magnitude N):
///   s = P (u + tau v),  f = -mu N s / max(|s|, d),  P = I - n n^T,  n = F_n / N,
/// u the point's travel from its anchor, v its velocity. While |s| <= d the film sticks (a
/// spring of mu N / d); beyond it slides at the Coulomb limit mu N. After each committed step
/// the anchor follows a slide (|s| = d, the force unchanged) and the spring moves to the
/// contact's pressure centroid (the shape rolls on the film without slipping).
struct ReducedBagFriction {
    double coefficient = 0.0;    ///< mu (0: frictionless, the default)
    double stickDistance = 0.0;  ///< d [m]: tangential travel to sliding
    double dampingTime = 0.0;    ///< tau [s]: the stick spring's damping over its stiffness
    /// @throws std::invalid_argument naming the member if a value is out of range.
    void validate() const;
};

/// Steps (committed) outside the envelope, per reason.
struct EnvelopeCounts {
    int mass = 0, depth = 0, radius = 0, tilt = 0;
    int steps = 0;  ///< committed steps checked
    double worstMass = 0.0, worstDepth = 0.0, worstRadius = 0.0, worstTilt = 0.0;  ///< SI
    int total() const { return mass + depth + radius + tilt; }
};

/// The reasons counted in `now` and not in `before`, as one warning sentence naming the worst
/// value and the calibrated range ("" if none): for a run's first exit of each kind.
std::string describeNewEnvelopeExits(const EnvelopeCounts& now, const EnvelopeCounts& before,
                                     const ReducedBagCalibration& c);
/// A summary line: how many bag-steps left the envelope, per reason.
std::string describeEnvelopeCounts(const EnvelopeCounts& e, const ReducedBagCalibration& c);

class ReducedBag : public Bag {
  public:
    /// @throws std::invalid_argument if the calibration is invalid.
    ReducedBag(std::shared_ptr<const ReducedBagCalibration> calibration,
               const Eigen::Isometry3d& X_GB);
    /// Adds a shape that may press the bag (shared; moved through setShapeState()).
    int addShape(std::shared_ptr<bags::RigidShape> shape);
    /// Sets the gas mass [kg] now, shapes where they are; commits.
    void setGasMass(double mass);
    /// Friction of the shapes on the film (off by default); before the coupling starts.
    void setFriction(const ReducedBagFriction& friction);
    const ReducedBagFriction& getFriction() const { return m_friction; }
    /// The friction force [N] on a shape (Ground; zero when not anchored or frictionless).
    Vec3 getFrictionForce(int shape) const { return m_results.at(shape).frictionForce; }
    /// Whether a shape's contact slides (|s| > d) in the current state.
    bool isSliding(int shape) const { return m_results.at(shape).sliding; }

    // Participant
    int getNumShapes() const override { return int(m_shapes.size()); }
    void setShapeState(int shape, const ShapeState& state) override;
    ParticipantStep advance(double dt) override;
    void commit() override;
    void rollback() override;
    ShapeWrench calcWrench(int shape) const override;
    Mat6 calcWrenchTangent(int shape) const override;
    Eigen::VectorXd calcContactPressure(int shape) const override;

    // Bag
    void setMassFlow(double massFlow) override;
    void setTargetMass(double mass, double rate) override;
    double getGasMass() const override { return m_cur.mass; }
    int getNumChambers() const override { return 1; }
    bags::ChamberState getChamberState(int chamber) const override;
    const Eigen::Matrix3Xd& getPressurePoints() const override { return m_points; }
    Eigen::VectorXd getPressureAreas() const override { return m_areas; }
    double calcPotentialEnergy() const override;
    void saveState(bags::StateWriter& w) const override;
    void loadState(bags::StateReader& r) override;

    double getGaugePressure() const { return m_cur.pressure; }  ///< [Pa]
    /// The overlap volume V_s [m^3] and the depth d_s [m] of a shape (current state).
    double getOverlapVolume(int shape) const;
    double getDepth(int shape) const;
    /// The shape's projected contact area sum a w_i [m^2] (current state).
    double getContactArea(int shape) const;
    /// One contact sample's share of a shape's wrench (current state), for diagnostics
    /// (bench_reduced_bag lateral): its grid point, whether it is a column sample (the film
    /// under a sunk shape), its depth (under the top the panel coupling moved), blend, share of the column's film, pressures [Pa] (the
    /// gas's kappa P w and the board's), contact point, normal and force [N] (Ground). They add
    /// up to calcWrench() less the friction force (getFrictionForce(), applied at the stick
    /// spring's point).
    struct SampleForce {
        int point = -1;
        bool column = false;
        double delta = 0.0, blend = 0.0, gasPressure = 0.0, boardPressure = 0.0;
        double film = 1.0;   // the shape's share of the column's film (1 alone there)
        double shift = 0.0;  // the top's rise there by the other shapes' loads [m] (coupling)
        Vec3 c = Vec3::Zero(), n = Vec3::Zero(), force = Vec3::Zero();
    };
    std::vector<SampleForce> getSampleForces(int shape) const;
    const EnvelopeCounts& getEnvelopeCounts() const { return m_envelope; }
    const ReducedBagCalibration& getCalibration() const { return *m_cal; }

  private:
    struct Sample {  // one grid point inside one shape
        int point;
        double delta;
        Vec3 t, c, n;
        Eigen::Matrix3d dndp;
        double blend = 1.0;  // share of the point (closest surface or down the column)
        // The top point's depth in the shape and its normal (the same point for every shape
        // at this grid point), which decide which shape the column's film touches.
        double topDelta = 0.0;
        Vec3 topN = Vec3::Zero();
        // This shape's share of the column's film where several shapes reach it (1 alone),
        // and its derivative in this shape's pose (the others held).
        double film = 1.0;
        Eigen::Matrix<double, 1, 6> dFilm = Eigen::Matrix<double, 1, 6>::Zero();
        // The panel coupling: delta0 the depth under the unloaded top (delta = delta0 - (n.e)
        // shift with it), shift [m] the top's rise here by the other shapes' loads, dShift its
        // derivative in the gas pressure [m/Pa] (their poses held).
        double delta0 = 0.0, shift = 0.0, dShift = 0.0;
        // A column sample (the film under the shape's underside, t the point inward of it):
        // the column's length from the top point down to the underside, c; 0 for a top sample.
        double column = 0.0;
    };
    // One grid column through one shape: the part of the vertical line through the top point
    // that lies inside the shape, below the top and above the bed board (its length is the
    // column's share of the overlap volume). Its upper end is the top point (topInside) or
    // the shape's upper surface `hi`, its lower end the shape's lower surface `lo` or the
    // board (onBoard); nhi, nlo the outward normals there.
    struct Chord {
        int point = -1;
        bool topInside = false, onBoard = false;
        double length = 0.0;
        Vec3 hi = Vec3::Zero(), nhi = Vec3::Zero(), lo = Vec3::Zero(), nlo = Vec3::Zero();
        // Shapes sharing the column (body segments overlap at joints and where a limb lies
        // on the trunk): the union of their chords U is the column's overlap, shared by their
        // lengths: this one's share is length U / S (S the lengths' sum). B = sum of beta x
        // length over them; hiBounds, loBounds: whether this chord's ends bound the union.
        double share = 1.0, sum = 0.0, betaSum = 0.0;
        bool hiBounds = true, loBounds = true;
    };
    struct ShapeResult {
        std::vector<Sample> samples;
        std::vector<Chord> chords;
        double volume = 0.0, depth = 0.0, area = 0.0;
        double depthSum1 = 0.0, depthSum2 = 0.0;  // sum a b delta, sum a b delta^2
        // The same under the unloaded top (delta0): the depth the displaced volume's beta reads.
        double depth0 = 0.0, depth0Sum1 = 0.0, depth0Sum2 = 0.0;
        // The gas load sum a b film q on the steep and the gentle panel [N] under the unloaded
        // top (the panel coupling's source; it follows the gas pressure, d/dP = load / P).
        std::array<double, 2> panelLoad{};
        int deepest = -1;  // sample index
        ShapeWrench wrench;
        // Friction (with the committed anchor): the normal force F_n (before friction), the
        // shape point p of the spring (Ground), s unprojected (u + tau v) and projected, the
        // friction force; the pressure centroid (Ground) and the normal force's total weight.
        Vec3 normalForce = Vec3::Zero(), point = Vec3::Zero(), raw = Vec3::Zero();
        Vec3 slip = Vec3::Zero(), frictionForce = Vec3::Zero(), centroid = Vec3::Zero();
        double load = 0.0;  // sum of q A over the samples
        bool anchored = false, sliding = false;
    };
    // A shape's friction anchor (committed state): a point fixed on the shape (its frame) and
    // where it was in Ground when the film last held it.
    struct Anchor {
        bool on = false;
        Vec3 onShape = Vec3::Zero(), inGround = Vec3::Zero();
    };
    struct State {
        double mass = 0.0, pressure = 0.0, time = 0.0;
        double flow = 0.0, target = -1.0, rate = 0.0;  // target < 0: flow
    };
    /// The top at a grid point: the unloaded top at the mass, or at the first taut mass of the
    /// calibration below it (the slack film wraps the shapes within the taut bag's top).
    double interpolateTop(int point, double mass) const;
    /// The chord of the column through top point t (Ground) in a shape; false if it misses.
    bool findChord(const bags::RigidShape& shape, const Vec3& t, Chord& chord) const;
    /// The contact weight of a sample at depth delta of a shape whose deepest depth is
    /// `depth`, and its derivatives.
    double calcWeight(double delta, double depth, double* dDelta, double* dDepth) const;
    void evaluate();                     // m_cur.mass and the shapes' poses -> everything
    Eigen::Matrix3Xd calcTop() const;    // the unloaded top at m_cur.mass (Ground), per grid point
    Vec3 calcTopPoint(int point) const;  // one grid point's of calcTop()
    double calcBoardPressure(const Vec3& p) const;     // the board's penalty pressure at p [Pa]
    void buildFootprint(const Eigen::Matrix3Xd& top);  // m_points, m_areas from the samples
    void shareFilm(const Eigen::Matrix3Xd& top);       // each sample's film share (evaluate)
    /// The panel coupling (evaluate, after the gas): each shape's depths under the top moved
    /// by the other shapes' loads; its depth, deepest sample and area again.
    void coupleThePanels();
    void findDeepestAndArea(ShapeResult& r) const;  // r.deepest, r.area from its samples
    double calcFreeVolume(double P, double* dVdP) const;
    double lookup(const Eigen::MatrixXd& table, double mass, double depth, double* dDepth) const;
    double solvePressure(double displaced, double* dPdV) const;
    void checkEnvelope();
    void addFriction(size_t s);  // the friction force onto m_results[s] (evaluate)
    void updateAnchors();        // commit: anchors follow slides and the centroid

    std::shared_ptr<const ReducedBagCalibration> m_cal;
    Eigen::Isometry3d m_X_GB;
    Eigen::Isometry3d m_X_BG;      // its inverse
    std::vector<int> m_gridIndex;  // point -> ix + nx iy
    std::vector<double> m_steep;   // point -> its share of the steep panel (the coupling)
    std::vector<std::shared_ptr<bags::RigidShape>> m_shapes;
    std::vector<Eigen::Isometry3d> m_poses, m_committedPoses;
    std::vector<Vec6> m_velocities, m_committedVelocities;  // per shape (w_GS, v_GS)
    ReducedBagFriction m_friction;
    std::vector<Anchor> m_anchors;  // per shape, committed
    std::vector<ShapeResult> m_results;
    State m_cur, m_committed;
    double m_displaced = 0.0, m_dPdV = 0.0;
    Eigen::Matrix3Xd m_points;     // the grid's tops, then each shape's samples' contact points
    std::vector<int> m_slotStart;  // per shape: its first sample's column in m_points
    Eigen::VectorXd m_areas;
    std::vector<double> m_pVfree, m_Vfree;  // taut unloaded states, ascending pressure
    double m_tautMass = 0.0;                // the calibration's first taut mass [kg]
    EnvelopeCounts m_envelope;
};

}  // namespace cosim
