#include "cosim/BagParticipant.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace cosim {

BagParticipant::BagParticipant(std::unique_ptr<bags::Airbag> bag, int maxCuts)
    : m_bag(std::move(bag)), m_maxCuts(maxCuts) {
    if (!m_bag) throw std::invalid_argument("BagParticipant: the airbag is null");
    if (maxCuts < 0)
        throw std::invalid_argument("BagParticipant: maxCuts = " + std::to_string(maxCuts) +
                                    "; valid: 0 or more");
}

int BagParticipant::getNumShapes() const { return m_bag->getNumShapes(); }

void BagParticipant::setShapeState(int shape, const ShapeState& state) {
    m_bag->setShapePose(shape, state.X_GS);
}

ParticipantStep BagParticipant::advance(double dt) {
    m_last = m_bag->advance(dt, m_maxCuts);
    ParticipantStep s;
    s.converged = m_last.converged;
    s.solverIterations = m_last.newtonIterations;
    s.unresolvedForce = m_last.unrelaxed ? m_last.residual : 0.0;
    return s;
}

void BagParticipant::commit() {
    if (m_last.unrelaxed) {  // counted once: a commit without a new advance does not count it
        ++m_unrelaxedSteps;
        m_largestUnrelaxed = std::max(m_largestUnrelaxed, m_last.residual);
        m_last.unrelaxed = false;
    }
    m_bag->commit();
}
void BagParticipant::rollback() { m_bag->rollback(); }

ShapeWrench BagParticipant::calcWrench(int shape) const {
    const bags::Wrench w = m_bag->calcShapeWrench(shape);
    ShapeWrench out;
    out.torque = w.torque;
    out.force = w.force;
    return out;
}

Mat6 BagParticipant::calcWrenchTangent(int shape) const {
    return calcWrenchTangents({shape}).front();
}

std::vector<Mat6> BagParticipant::calcWrenchTangents(const std::vector<int>& shapes) const {
    // A bag whose tangent is not positive definite (at or past a limit point, or held by the
    // stabilisation springs) has no re-equilibrated answer to a small move: the body gets the
    // film-held tangent, the contact's own stiffness (the stiff side: a linearised load that
    // over-resists, never one that pulls the body in). The implicit schemes' passes correct
    // the load; the one-pass tangent scheme keeps it for that step.
    bool filmHeld = false;
    std::vector<Mat6> T = m_bag->calcShapeWrenchTangents(shapes, &filmHeld, m_withoutFriction);
    if (filmHeld) ++m_filmHeldTangents;
    return T;
}

Participant::WrenchLinearisation BagParticipant::calcWrenchLinearisation(
    const std::vector<int>& shapes) const {
    bags::Airbag::WrenchLinearisation b =
        m_bag->calcShapeWrenchLinearisation(shapes, m_withoutFriction);
    if (b.filmHeld) ++m_filmHeldTangents;
    return {std::move(b.pose), std::move(b.gas)};
}

Eigen::VectorXd BagParticipant::calcGasInflow(double dt) const {
    Eigen::VectorXd dm(m_bag->getNumBags());
    for (int b = 0; b < m_bag->getNumBags(); ++b) dm(b) = m_bag->calcGasInflow(b, dt);
    return dm;
}

int BagParticipant::getNumFilmHeldTangents() const { return m_filmHeldTangents; }

Eigen::VectorXd BagParticipant::calcContactPressure(int shape) const {
    return m_bag->calcShapeContactPressure(shape);
}

bool BagParticipant::isSteady() const { return m_bag->isGasStill(); }
void BagParticipant::setMassFlow(double massFlow) { m_bag->setMassFlow(massFlow); }
void BagParticipant::setTargetMass(double mass, double rate) { m_bag->setTargetMass(mass, rate); }
double BagParticipant::getGasMass() const { return m_bag->getTotalGasMass(); }
int BagParticipant::getNumChambers() const { return m_bag->getNumChambers(); }
bags::ChamberState BagParticipant::getChamberState(int chamber) const {
    return m_bag->getChamberState(chamber);
}
const Eigen::Matrix3Xd& BagParticipant::getPressurePoints() const { return m_bag->getPositions(); }
Eigen::VectorXd BagParticipant::getPressureAreas() const {
    if (m_areas.size() == 0) m_areas = m_bag->getMesh().calcNodalAreas();
    return m_areas;
}
double BagParticipant::calcPotentialEnergy() const {
    bags::EnergyAccumulator acc(m_bag->getMesh().getNumNodes());
    acc.wantGradient = false;
    acc.wantHessian = false;
    m_bag->getModel().addEnergy(m_bag->getPositions(), acc);
    return acc.energy;
}

}  // namespace cosim
