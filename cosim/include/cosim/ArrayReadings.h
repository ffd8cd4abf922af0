#pragma once
/// @file What a clinician and an engineer read off the patient on the array between steps:
/// loads per body region (peak and mean interface pressure, contact area, force), the state
/// of every coupled bag (gas mass, pressure, volume, force), the pelvis' and thorax' tilt, and
/// the pressure mat's frame.
///
/// Order of use: after PatientOnArray::step() (or right after construction), call any of
/// them; they read the committed state and change nothing.
///
/// Region loads: every node of a coupled bag with a contact pressure from a segment's shape is
/// placed on that segment (its position in the segment's frame) and given to the segment's
/// body region (body::BodyModel::findRegion()); a node in no region counts under its segment's
/// name. Per region: the peak nodal pressure, the contact area (the nodes' lumped reference
/// areas where the pressure exceeds a threshold, 5 mmHg by default), the mean pressure over
/// that area (the nodes' normal force over it), and the force: the vertical part of the
/// nodes' contact forces (pressure times area along the shape's outward normal), so that the
/// regions' forces add up to PatientOnArray::calcBagForce() (without friction).
///
/// The immersion: the most that a node of the region with a pressure above the area threshold
/// lies below its own height as the bags were inflated at the start
/// (PatientOnArray::getRestHeights()): how far he has pushed the surface down there (on a
/// wedge's slope as on its crest, each point from where it stood).
///
/// The patch peak: the highest normal force of the region's nodes inside any disc of area
/// `patchArea` (in the bed's plane, centred on one of its loaded nodes), divided by that area.
/// Unlike the nodal peak it does not depend on the mesh once the disc holds several nodes:
/// a node's pressure is its force over its lumped area, which at the contact's rim and along
/// the seams changes with the mesh (docs/reduced-bag.md, "Which peak").

#include <bags/Units.h>

#include <limits>
#include <string>
#include <vector>

#include "cosim/PatientOnArray.h"
#include "cosim/PressureMat.h"

namespace cosim {

/// Loads on one body region (or on a segment, for nodes in no region).
struct RegionLoad {
    std::string name;                ///< body::BodyRegion::name, or the segment's name
    double peakPressure = 0.0;       ///< [Pa] highest nodal contact pressure
    double patchPeakPressure = 0.0;  ///< [Pa] highest mean pressure over a patch (file comment)
    double meanPressure = 0.0;       ///< [Pa] normal force over the area (0 with no area)
    double area = 0.0;   ///< [m^2] nodes' areas where the pressure exceeds the threshold
    double force = 0.0;  ///< [N] vertical (Ground +z) part of the contact force
    /// [m] the most a node above the area threshold lies below its height at the start
    /// (file comment); 0 with no such node; NaN on the reduced bag (no film: not measured)
    double immersion = 0.0;
    /// [m^2] nodes' areas where the pressure exceeds kRiskPressure (32 mmHg)
    double areaAtRisk = 0.0;
};

/// [Pa] 32 mmHg, the capillary closing pressure: the clinical reference for pressure-ulcer
/// risk (RegionLoad::areaAtRisk, the verdict's time above it, the report's mat pictures).
constexpr double kRiskPressure = 32.0 * bags::kPascalsPerMmHg;

/// The names loads are reported under: the model's regions in order, then the 16 segments
/// (for nodes in no region). Index i of calcRegionLoads() is name i.
std::vector<std::string> getRegionLoadNames(const body::BodyModel& model);

/// Loads per getRegionLoadNames() entry at the committed state (see the file comment).
/// The patch area of the patch peak by default [m^2]: 20 cm^2, the smallest disc over which
/// the finite-element bags' patch peak agrees between meshes of 20, 15 and 12 mm (within 2 %;
/// docs/reduced-bag.md). Clinical peak pressure indices use about 9-10 cm^2, which needs a
/// finer mesh than the shipped 20 mm.
constexpr double kDefaultPatchArea = 20e-4;

/// Loads per getRegionLoadNames() entry at the committed state (see the file comment).
/// @param areaThreshold [Pa] pressure above which a node's area counts as contact area
/// @param patchArea [m^2] the disc of the patch peak
std::vector<RegionLoad> calcRegionLoads(const PatientOnArray& poa,
                                        double areaThreshold = 5.0 * bags::kPascalsPerMmHg,
                                        double patchArea = kDefaultPatchArea);

/// The highest load inside any disc of area `patchArea` centred on one of the points, over
/// that area [Pa]: points (x, y) [m] in a plane with normal forces f [N]. 0 without points.
double calcPatchPeakPressure(const std::vector<Eigen::Vector2d>& points,
                             const std::vector<double>& forces, double patchArea);

/// State of one coupled bag.
struct BagReading {
    int bag = 0;                 ///< ArrayBag index
    double gasMass = 0.0;        ///< [kg] total
    double gaugePressure = 0.0;  ///< [Pa] volume-weighted over the chambers
    double volume = 0.0;         ///< [m^3] total
    double force = 0.0;          ///< [N] vertical force of the bag on the body
    /// [m] largest depth by which its film and a neighbour's overlap (pass through each
    /// other): PatientOnArray::calcNeighbourOverlaps(); 0 for bags without a film.
    double overlap = 0.0;
    /// [m] the least height above the bed board of a node the body presses
    /// (calcPressedNodeHeights(): the air left under him, the bottoming-out margin's measure);
    /// infinity where none is pressed. Not filled by calcBagReadings().
    double innerHeight = std::numeric_limits<double>::infinity();
};

/// One reading per participant (PatientOnArray::getBagIndices() order).
std::vector<BagReading> calcBagReadings(const PatientOnArray& poa);

/// How far a segment is turned about the bed's long axis [rad]: the angle of its anterior
/// axis (body frame X) from Ground +z, seen along Ground +x; positive when he turns onto his
/// left side (his anterior axis towards Ground -y, his right side raised).
double calcSegmentTilt(const PatientOnArray& poa, body::Segment segment);
/// The same for a model's segment in a state realized to Position.
double calcSegmentTilt(const body::BodyModel& model, const SimTK::State& state,
                       body::Segment segment);

/// The patient's centre of mass [m] in Ground at the committed state.
Eigen::Vector3d calcCentreOfMass(const PatientOnArray& poa);

/// Per participant (getBagIndices() order): the lowest height [m] above the bed board (Ground
/// z = 0, where the bag's base lies) of a node the body presses (contact pressure above
/// `threshold` [Pa]): the inner height of the bag left under him, the bottom film lying on
/// the board. Infinity where no node is pressed.
std::vector<double> calcPressedNodeHeights(const PatientOnArray& poa, double threshold);

/// Largest depth [m] of a film's surface inside a rigid shape between the film's nodes: minus
/// the shape's signed distance at each triangle's centroid and edge midpoints (x: the nodes,
/// Ground, one column per film node); 0 where none lies inside. The finite-element bag's
/// contact acts at its nodes, so a shape narrower than about two elements can pass between
/// them unresisted (docs/cosim.md#shapes-between-the-films-nodes).
double calcFilmPassThrough(const bags::Mesh& film, const Eigen::Matrix3Xd& x,
                           const bags::RigidShape& shape);

/// The deepest pass-through of one coupled bag's film (calcFilmPassThrough()) by a segment.
struct PassThrough {
    int bag = 0;         ///< ArrayBag index
    int segment = -1;    ///< the deepest segment (body::Segment), -1 if none passes
    double depth = 0.0;  ///< [m]
    /// [m] the same segment's deepest film node inside it (the contact's own penetration)
    double nodeDepth = 0.0;
};
/// One per participant (getBagIndices() order) at the committed state, over the pairs;
/// depth 0 and segment -1 for bags without a film (ReducedBag).
std::vector<PassThrough> calcPassThroughs(const PatientOnArray& poa);

/// Clears the mat and adds every coupled bag's nodal contact pressures (all shapes) to it.
void fillPressureMat(const PatientOnArray& poa, PressureMat& mat);

/// A mat over the array's flat footprints (their bounding box), rows x columns sensels.
PressureMatOptions makeArrayMatOptions(const ArrayLayout& layout,
                                       const bags::DoubleWedgeParams& bag, int rows, int columns);

}  // namespace cosim
