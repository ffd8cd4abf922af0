#pragma once
/// @file One bag of an array as the patient-on-array model drives it: a co-simulation
/// participant (cosim/Participant.h, same call protocol) that also holds gas, which the time
/// loop changes between steps, and whose contact pressures lie at points with areas, which
/// the pressure mat and the region loads read.
///
/// Two implementations: BagParticipant (the finite-element bags::Airbag; its points are the
/// mesh nodes, their areas the lumped reference areas) and ReducedBag (a calibrated reduced
/// model; its points are a grid on the bag's top, docs/reduced-bag.md).
///
/// The pressure footprint: calcContactPressure(shape)[i] [Pa] acts at getPressurePoints()
/// column i over getPressureAreas()[i] [m^2], along the shape's inward normal there, so
/// that sum_i p_i A_i n_i is the contact force on the shape. All read at the current state.

#include <bags/Airbag.h>

#include "cosim/Participant.h"

namespace cosim {

class Bag : public Participant {
  public:
    // --- gas, set between steps (taken over the following advance() calls)
    /// Gas mass flow into the bag [kg/s] (negative: out).
    virtual void setMassFlow(double massFlow) = 0;
    /// Flow at |rate| [kg/s] until the bag's gas mass is `mass` [kg], then none.
    virtual void setTargetMass(double mass, double rate) = 0;
    virtual double getGasMass() const = 0;  ///< [kg] at the current state
    virtual int getNumChambers() const = 0;
    /// Gauge pressure, volume and gas mass of a chamber at the current state.
    virtual bags::ChamberState getChamberState(int chamber) const = 0;

    // --- the pressure footprint (see the file comment)
    /// Points [m] (Ground, 3 x N) where calcContactPressure() acts, at the current state.
    virtual const Eigen::Matrix3Xd& getPressurePoints() const = 0;
    /// Area [m^2] each point carries (N).
    virtual Eigen::VectorXd getPressureAreas() const = 0;

    /// The bag's film as a mesh whose nodes are getPressurePoints()' columns (triangles,
    /// panels, chambers; its X is the reference state), or null for a bag without a film
    /// (ReducedBag). Used to draw the bags and to measure how far neighbours' films overlap.
    virtual const bags::Mesh* getFilmMesh() const { return nullptr; }

    /// The bag's potential energy [J] at the current state (membrane, gas, its weight,
    /// contact with the shapes), up to a constant: for energy balances.
    virtual double calcPotentialEnergy() const = 0;

    // --- checkpoints (bags/StateStream.h), between steps
    /// Writes everything that decides what the bag does next (its current and committed
    /// states, gas flows, whatever it carries from step to step).
    virtual void saveState(bags::StateWriter& w) const = 0;
    /// Reads what saveState() wrote into a bag built the same way (shapes added, inflated).
    /// @throws bags::StateError if the checkpoint is of another bag.
    virtual void loadState(bags::StateReader& r) = 0;
    /// Forgets caches that shape the roundoff of later steps (bags::Airbag::resetCaches()):
    /// called at every checkpoint of a run that checkpoints. Default: none.
    virtual void resetCaches() {}
};

}  // namespace cosim
