#pragma once
/// @file A bags::Airbag as a co-simulation participant.
///
/// The participant's shapes are the airbag's shapes (index for index): add them to the airbag
/// with bags::Airbag::addShape() and inflate it before the coupling starts. The bag is
/// quasi-static: the shapes' velocities are accepted and not used (the body carries the
/// inertia and any damping). advance(dt) maps to bags::Airbag::advance(dt), commit() and
/// rollback() to the airbag's own; the wrench, its tangent and the pressures are the airbag's.

#include <bags/Airbag.h>

#include <memory>

#include "cosim/Bag.h"

namespace cosim {

class BagParticipant : public Bag {
  public:
    /// Takes the airbag (its shapes added, inflated). @throws std::invalid_argument if null.
    explicit BagParticipant(std::unique_ptr<bags::Airbag> bag, int maxCuts = 6);
    int getNumShapes() const override;
    void setShapeState(int shape, const ShapeState& state) override;
    ParticipantStep advance(double dt) override;
    void commit() override;
    void rollback() override;
    ShapeWrench calcWrench(int shape) const override;
    Mat6 calcWrenchTangent(int shape) const override;
    /// The airbag's calcShapeWrenchTangents(): one factorisation for all the shapes. Where
    /// the bag's tangent is not positive definite, the film-held tangents (counted).
    std::vector<Mat6> calcWrenchTangents(const std::vector<int>& shapes) const override;
    /// The airbag's calcShapeWrenchLinearisation(): per shape a gas column per bag of the
    /// module (film-held tangents counted as above).
    WrenchLinearisation calcWrenchLinearisation(const std::vector<int>& shapes) const override;
    /// The airbag's calcGasInflow() per bag of the module.
    Eigen::VectorXd calcGasInflow(double dt) const override;
    /// How many calcWrenchTangents() and calcWrenchLinearisation() calls gave film-held
    /// tangents (not saved in checkpoints).
    int getNumFilmHeldTangents() const;
    /// Relaxed stepping (bags::AirbagSpec::Stepping::Relaxed): how many committed steps were
    /// kept unrelaxed (the film's sub-steps ran out before its force tolerance), and the
    /// largest force residual [N] one of them was kept with, since the participant was made
    /// or setUnrelaxedTally() (not in saveState(): a run's checkpoint carries them itself).
    long getNumUnrelaxedSteps() const { return m_unrelaxedSteps; }
    double getLargestUnrelaxedResidual() const { return m_largestUnrelaxed; }
    /// Restores the tally above (a resumed run's checkpoint).
    void setUnrelaxedTally(long steps, double largest) {
        m_unrelaxedSteps = steps;
        m_largestUnrelaxed = largest;
    }
    /// With on, calcWrenchTangents() and calcWrenchLinearisation() give the linearisation of
    /// the same state with the shapes' contacts taken frictionless (bags::Airbag's
    /// withoutFriction): the body's linearised load carries no stick springs, and the
    /// tangent-implicit passes hold the friction force as the implicit scheme holds the whole
    /// load (docs/cosim.md#friction-and-the-tangent-schemes). Off by default (the exact
    /// tangent).
    void setLinearisationWithoutFriction(bool on) { m_withoutFriction = on; }
    bool getLinearisationWithoutFriction() const { return m_withoutFriction; }
    Eigen::VectorXd calcContactPressure(int shape) const override;
    /// The airbag's gas is still (bags::Airbag::isGasStill()).
    bool isSteady() const override;
    // Bag: the airbag's own gas, chambers, nodes and nodal areas.
    void setMassFlow(double massFlow) override;
    void setTargetMass(double mass, double rate) override;
    double getGasMass() const override;
    int getNumChambers() const override;
    bags::ChamberState getChamberState(int chamber) const override;
    const Eigen::Matrix3Xd& getPressurePoints() const override;
    Eigen::VectorXd getPressureAreas() const override;
    double calcPotentialEnergy() const override;
    const bags::Mesh* getFilmMesh() const override { return &m_bag->getMesh(); }
    /// The airbag's saveState(), loadState(), resetCaches().
    void saveState(bags::StateWriter& w) const override { m_bag->saveState(w); }
    void loadState(bags::StateReader& r) override { m_bag->loadState(r); }
    void resetCaches() override { m_bag->resetCaches(); }

    const bags::Airbag& getAirbag() const { return *m_bag; }  ///< the wrapped airbag
    bags::Airbag& updAirbag() { return *m_bag; }              ///< the wrapped airbag
    /// The last advance()'s summary.
    const bags::AdvanceSummary& getLastAdvance() const { return m_last; }

  private:
    std::unique_ptr<bags::Airbag> m_bag;
    int m_maxCuts;
    bags::AdvanceSummary m_last;
    mutable Eigen::VectorXd m_areas;  // the mesh's nodal areas, made on first use
    mutable int m_filmHeldTangents = 0;
    long m_unrelaxedSteps = 0;
    double m_largestUnrelaxed = 0.0;
    bool m_withoutFriction = false;
};

}  // namespace cosim
