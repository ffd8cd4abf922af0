#pragma once
/// @file The patient (body::BodyModel) lying on an array of airbags (ArrayLayout), coupled:
/// every segment's contact shape is registered, as its own bags::RigidShape, on each bag that
/// findShapeBagPairs() says it may touch, and linked to the segment's frame on the body side.
/// The patient is placed in the spec's posture at the height where the first of his shapes
/// touches the first bag node (bisected), released at rest, and falls onto the bags and
/// settles under gravity through the coupling (stepAdaptive()).
///
/// Order of use: construct (builds the model, the bags, inflates them, finds the touching
/// height and initializes the coupling; it can take a while: one inflation per bag), then
/// step() per macro step; read the bags' force on the body and the mechanical energy between
/// steps.
///
/// Only the bags with at least one shape over them take part in the coupling (a bag no shape
/// can reach carries nothing); getBagIndices() lists them (ArrayBag::index).

#include <bags/Airbag.h>
#include <body/BodyModel.h>
#include <body/SupportContact.h>
#include <body/Tissue.h>

#include <memory>
#include <vector>

#include "cosim/ArrayLayout.h"
#include "cosim/BagParticipant.h"
#include "cosim/BodyParticipant.h"
#include "cosim/Coupling.h"
#include "cosim/ReducedBag.h"
#include "cosim/ShapeBagPairs.h"

namespace cosim {

struct PatientOnArrayOptions {
    ArrayLayout layout;  ///< the array (validated against bag.geometry)
    /// Every bag's spec: geometry, material, tolerances (X_GB is set per bag from the layout).
    bags::AirbagSpec bag;
    /// The bags' model: the finite-element bags::Airbag (BagParticipant), or the reduced
    /// model (ReducedBag) from `reduced`, a calibration of that same bag.
    enum class BagModel { FiniteElement, Reduced };
    BagModel model = BagModel::FiniteElement;
    std::shared_ptr<const ReducedBagCalibration> reduced;  ///< Reduced: required
    bags::RigidContact::Options contact;  ///< contact of the body's shapes with the membranes
    /// Per segment (body::Segment order, body::kSegmentCount entries): the soft-tissue layer
    /// of its shape on the films (body/Tissue.h), in place of `contact`'s tissueThickness and
    /// tissueModulus for that segment; a rigid entry (thickness 0) leaves that segment bare.
    /// Empty: `contact`'s layer (none by default) for every segment. Finite-element bags only.
    std::vector<body::SoftTissue> segmentTissue;
    /// The contact options of one segment's shape: `contact` with its segmentTissue layer.
    bags::RigidContact::Options getSegmentContact(body::Segment segment) const;
    /// Reduced bags with body friction (contact.friction > 0, its coefficient): the stick
    /// spring's travel to sliding and its damping time (ReducedBagFriction,
    /// docs/reduced-bag.md#friction). The coefficient here is ignored.
    ReducedBagFriction reducedFriction = makeReducedFriction();
    static ReducedBagFriction makeReducedFriction() {
        ReducedBagFriction f;
        f.stickDistance = 5e-3;
        f.dampingTime = 0.02;
        return f;
    }
    double pairMargin = 0.03;  ///< [m] findShapeBagPairs() margin around each flat footprint
    double dropHeight = 0.0;   ///< [m] released this far above the touching height
    body::BodyModelOptions body;
    /// The bed board under the bags as the body feels it where it presses through a bag (a
    /// slack or bottomed bag, or the body beside the array): body::PlaneSupport at z = 0,
    /// stiffer than the default support (1e7 Pa/m: 2 mm under 20 kPa) so that a body on the
    /// board is on a hard surface. The bags rest on the board on their own (their base
    /// nodes); this is only the body's side. Its friction is the stick-slip law (an elastic
    /// stick spring per patch, 1 mm to Coulomb's limit). boardContact false: no board for the
    /// body (it may then sink through slack bags and below the board).
    bool boardContact = true;
    body::PlaneSupportOptions board = makeBoardOptions();
    static body::PlaneSupportOptions makeBoardOptions() {
        body::PlaneSupportOptions o;
        o.height = 0.0;
        o.stiffness = 1.0e7;
        o.damping = 2.0e5;
        // No creep of a hand resting on the board, and the body's steps stay long there
        // (docs/performance.md#the-reduced-bag).
        o.frictionLaw = body::SupportFrictionLaw::StickSlip;
        return o;
    }
    /// Neighbouring bags touch (docs/cosim.md#contact-between-neighbouring-bags): the bags
    /// whose inflated extents, grown by neighbourMargin, meet are solved as one module (one
    /// participant, a bags::Airbag with AirbagSpec::cluster), their films kept apart by the
    /// module's self-contact (bag.selfContact must be on; finite-element bags only). Off:
    /// every bag is its own participant and neighbours' films pass through each other.
    bool neighbourContact = false;
    /// [m] added on every side of a bag's inflated extent when grouping (the patient squashes
    /// a bag outwards, gas flows in).
    double neighbourMargin = 0.003;
    /// [kg] the grouping measures a bag's inflated extent (calcInflatedExtent()) at the
    /// largest gas mass of the coupled bags in the layout, or at this mass if larger (a
    /// scenario gives the largest target mass of its gas commands).
    double neighbourMass = 0.0;
    BodyIntegratorOptions integrator;
    CouplingOptions coupling;
    /// @throws std::invalid_argument naming the option (the layout's errors name their keys).
    void validate() const;
};

/// Every segment's contact-shape bounding sphere in Ground (centre [m], radius [m]), segment
/// order, at a state realized to Position: what findShapeBagPairs() takes.
void calcSegmentBounds(const body::BodyModel& model, const SimTK::State& state,
                       std::vector<Eigen::Vector3d>& centres, std::vector<double>& radii);

/// The segments (body::Segment indices) with no bag of the layout under them in the spec's
/// posture and position: a patient who lies (partly) off the array. Builds the body model
/// only, no bag, so a scenario reader can refuse such a patient before anything runs.
/// @throws std::invalid_argument if spec or options are invalid.
std::vector<int> findSegmentsOffArray(const body::PatientSpec& spec,
                                      const PatientOnArrayOptions& options);

class PatientOnArray {
  public:
    /// Builds and initializes everything (see the file comment).
    /// @throws std::invalid_argument if spec or options are invalid, or if a segment has no
    /// bag under it (the patient lies off the array; the error names the segments).
    PatientOnArray(const body::PatientSpec& spec, const PatientOnArrayOptions& options);
    ~PatientOnArray();
    PatientOnArray(const PatientOnArray&) = delete;
    PatientOnArray& operator=(const PatientOnArray&) = delete;

    /// One macro step, halved while it fails (Coupling::stepAdaptive()).
    StepSummary step();
    /// One macro step as step(), ending at `limit` [s] at the latest (a gas command's start,
    /// the run's end; Coupling::stepAdaptive(limit)): a fixed step shortened to end there is
    /// restored afterwards unless it had to be cut; an adaptive one ends exactly at `limit`.
    StepSummary stepUntil(double limit);
    double getTime() const;  ///< [s] since the release

    /// Vertical force [N] the bags exert on the body, summed over every link (last step).
    double calcBagForce() const;
    /// The same per bag of getBagIndices() [N].
    std::vector<double> calcBagForces() const;
    /// Vertical force [N] the bed board exerts on the body directly (pressed through a bag,
    /// or beside the array) at the current state; 0 without boardContact.
    double calcBoardForce() const;
    /// The body's weight m g [N] with the model's gravity.
    double getWeight() const;
    /// Mechanical energy [J]: the body's kinetic and potential energy (gravity, joint springs
    /// as Simbody reports them) plus every coupled bag's total potential energy (membrane,
    /// gas, its own weight, contact with the shapes) at its current state.
    double calcEnergy() const;
    /// Largest speed [m/s] of a segment's origin.
    double calcMaxSpeed() const;
    /// Height [m] of the body's lowest point above the bed board at release, and the
    /// touching height found by bisection (equal unless dropHeight > 0).
    double getReleaseClearance() const;

    /// Reduced bags: their committed steps outside the calibration's validity envelope,
    /// summed over the bags (a step with k bags outside counts k); zero for finite elements.
    EnvelopeCounts getEnvelopeCounts() const;

    const std::vector<ShapeBagPair>& getPairs() const;  ///< shape = segment, bag = ArrayBag index
    const std::vector<int>& getBagIndices() const;      ///< ArrayBag index per coupled bag
    /// One link per pair (link i is pair i), in bag terms: body shape, the bag (its position
    /// in getBagIndices()), and the shape's index on that bag (getBag(), for its contact
    /// pressures). Without neighbourContact these are the coupling's own links.
    const std::vector<Link>& getLinks() const;
    const body::BodyModel& getModel() const;
    const BodyParticipant& getBody() const;
    /// Coupled bag i (getBagIndices() order): a BagParticipant (finite elements), a ReducedBag
    /// (PatientOnArrayOptions::model), or with neighbourContact a ModuleBag (a bag of a
    /// module: it reads and sets its module's state; the module is the participant).
    const Bag& getBag(int bag) const;
    /// Coupled bag i, to set its gas flow between steps (GasSchedule::apply()).
    Bag& updBag(int bag);
    /// The coupling's participants as groups of coupled bags (positions in getBagIndices()):
    /// one bag each, or with neighbourContact the bags of each module.
    const std::vector<std::vector<int>>& getModules() const;
    /// Largest depth [m] by which a node of one coupled bag's film lies inside a neighbouring
    /// coupled bag, per coupled bag, at the current state (calcFilmOverlap() with every bag
    /// whose nodes' bounding box meets its own); 0 for bags without a film.
    std::vector<double> calcNeighbourOverlaps() const;
    /// Coupled bag i's pressure points' heights [m] above the bed board as inflated at the
    /// start, before he lay on it (getPressurePoints()' z once the bags were inflated to their
    /// masses, the patient parked above them): the surface from which his immersion is
    /// measured (RegionLoad::immersion).
    const Eigen::VectorXd& getRestHeights(int bag) const;
    /// Pair i's shape (getPairs()) posed where the body's segment is at the committed state:
    /// a new shape for measurements (calcPassThroughs()); the bags' own are the coupling's.
    std::shared_ptr<bags::RigidShape> makePairShape(int pair) const;
    Coupling& updCoupling();

    // --- checkpoints (bags/StateStream.h), between steps
    /// Writes the body, every bag and the coupling. Call resetCaches() where it is taken.
    void saveState(bags::StateWriter& w) const;
    /// Reads what saveState() wrote into a PatientOnArray built from the same spec and
    /// options (the bags inflated again by the constructor are replaced), then resetCaches().
    /// @throws bags::StateError if the checkpoint is of another patient or array.
    void loadState(bags::StateReader& r);
    /// Every bag's Bag::resetCaches().
    void resetCaches();

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cosim
