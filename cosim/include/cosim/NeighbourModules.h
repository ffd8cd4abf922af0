#pragma once
/// @file Neighbouring bags of an array that touch: how far their films overlap when each bag
/// is solved on its own, which bags may meet once inflated, and a bag of a module (several
/// bags solved as one bags::Airbag, AirbagSpec::cluster) as the patient-on-array model reads
/// and drives it. docs/cosim.md#contact-between-neighbouring-bags.
///
/// Each bag of an array is its own participant by default: inflated neighbours bulge through
/// each other's films unseen. With PatientOnArrayOptions::neighbourContact the bags whose
/// inflated extents may meet are grouped (findTouchingGroups) and each group is one module:
/// one participant whose bags touch through the module's self-contact, each keeping its own
/// gas; modules still run in parallel.

#include <bags/Airbag.h>

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "cosim/ArrayLayout.h"
#include "cosim/BagParticipant.h"

namespace cosim {

/// Largest depth [m] by which a node of one film lies inside the other bag: a node of A
/// enclosed by B's chambers (winding number of B's chamber triangles above 1/2), its distance
/// to B's nearest triangle; and the same with A and B swapped. 0 if no node lies inside.
/// `filmA`'s triangles and chambers index the columns of xA (Ground [m]); likewise B.
double calcFilmOverlap(const bags::Mesh& filmA, const Eigen::Matrix3Xd& xA, const bags::Mesh& filmB,
                       const Eigen::Matrix3Xd& xB);

/// The bags that may touch, grouped: the connected components of the graph in which two bags
/// are joined when their boxes (each bag's inflated extent on the bed, Ground x and y [m]),
/// grown by `margin` [m] on every side, overlap. Each group lists indices into `boxes` in
/// increasing order; groups are ordered by their first index.
std::vector<std::vector<int>> findTouchingGroups(const std::vector<Eigen::AlignedBox2d>& boxes,
                                                 double margin);

/// The inflated bag's extent on the bed in its own frame B (x, y [m]): one bag of `spec`
/// (X_GB ignored) inflated to `mass` [kg] with nothing on it, the bounding box of its nodes.
/// @throws bags::NumericalError if it cannot be inflated.
Eigen::AlignedBox2d calcInflatedExtent(const bags::AirbagSpec& spec, double mass);

/// Bag b of a module (a BagParticipant whose airbag holds several bags): its gas, chambers,
/// nodes and contact shapes, read from and set on the module. Its shapes are module shapes
/// added with bags::Airbag::addShape(shape, options, b), so their wrenches and pressures are
/// this bag's. The module is the participant the coupling advances, commits, rolls back and
/// checkpoints; advance(), commit(), rollback(), saveState(), loadState() and
/// calcPotentialEnergy() of the bag throw std::logic_error (the module's count).
class ModuleBag : public Bag {
  public:
    /// @param module the module (outlives this); @param bag its bag index in the module
    ModuleBag(BagParticipant& module, int bag);
    /// Adds module shape `moduleShape` (of this bag) as this bag's next shape; returns its index.
    int addModuleShape(int moduleShape);
    int getModuleShape(int shape) const { return m_shapes.at(size_t(shape)); }
    int getBagInModule() const { return m_bag; }

    int getNumShapes() const override { return int(m_shapes.size()); }
    void setShapeState(int shape, const ShapeState& state) override;
    ParticipantStep advance(double dt) override;
    void commit() override;
    void rollback() override;
    ShapeWrench calcWrench(int shape) const override;
    Mat6 calcWrenchTangent(int shape) const override;
    Eigen::VectorXd calcContactPressure(int shape) const override;
    bool isSteady() const override;
    void setMassFlow(double massFlow) override;
    void setTargetMass(double mass, double rate) override;
    double getGasMass() const override;
    int getNumChambers() const override;
    bags::ChamberState getChamberState(int chamber) const override;
    const Eigen::Matrix3Xd& getPressurePoints() const override;
    Eigen::VectorXd getPressureAreas() const override;
    const bags::Mesh* getFilmMesh() const override { return &m_film; }
    double calcPotentialEnergy() const override;
    void saveState(bags::StateWriter& w) const override;
    void loadState(bags::StateReader& r) override;

  private:
    BagParticipant& m_module;
    int m_bag;
    int m_first = 0, m_count = 0;  // its nodes in the module
    std::vector<int> m_shapes;     // module shape per shape
    bags::Mesh m_film;             // its triangles and chambers, indexed as its nodes
    mutable Eigen::Matrix3Xd m_points;
};

/// The finite-element bags of an array as co-simulation participants: one bags::Airbag per
/// bag, or with neighbourContact one per group of bags that may touch (findTouchingGroups()
/// on each bag's inflated extent, calcInflatedExtent() at `mass`, placed at its cell and grown
/// by `margin`), each group of two or more a module (AirbagSpec::cluster, the bags at their
/// cells' poses in Ground) read per bag through ModuleBag.
struct ArrayParticipants {
    std::vector<std::vector<int>> modules;  ///< per participant: its bags (positions)
    std::vector<std::unique_ptr<BagParticipant>> participants;
    std::vector<std::unique_ptr<ModuleBag>> moduleBags;
    std::vector<Bag*> bags;          ///< per bag: its participant, or its ModuleBag
    std::vector<int> participantOf;  ///< per bag
    /// Adds a shape touching bag `bag` only (set-up, before inflate()). Returns the shape's
    /// index on the bag (getBag()'s shapes); *participantShape its index on the participant.
    int addShape(int bag, std::shared_ptr<bags::RigidShape> shape,
                 const bags::RigidContact::Options& options, int* participantShape);
    /// Inflates every bag to its mass [kg] (per bag).
    void inflate(const std::vector<double>& masses);
};

/// @param cells the array's bags; @param coupled the cells that take part (ArrayBag indices,
/// bag position i is cells[coupled[i]]); @param spec every bag's spec (X_GB and cluster are
/// set here); @param mass [kg] at which the inflated extent is measured (neighbourContact)
/// @throws std::invalid_argument if neighbourContact is asked without spec.selfContact.
ArrayParticipants makeArrayParticipants(const std::vector<ArrayBag>& cells,
                                        const std::vector<int>& coupled,
                                        const bags::AirbagSpec& spec, bool neighbourContact,
                                        double margin, double mass);

}  // namespace cosim
