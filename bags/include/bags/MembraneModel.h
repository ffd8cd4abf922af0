#pragma once
/// @file The airbag's total potential energy: MembraneModel sums membrane strain energy, gas
/// work, follower pressures, gravity and contact into one energy of the nodal positions, with
/// its gradient and tangent (the quasi-static solver of bags/EquilibriumSolver.h minimises it;
/// the explicit step's kernel, bags/FilmForce.h, reads its element data).

#include <bags/Bending.h>
#include <bags/Contact.h>
#include <bags/Gas.h>
#include <bags/Material.h>
#include <bags/Mesh.h>
#include <bags/Types.h>
#include <bags/Viscoelastic.h>

#include <functional>
#include <limits>
#include <memory>
#include <vector>

namespace bags {

/// The film's viscoelastic internal variables (MembraneModel::setProny), per element, at one
/// state: what a snapshot of the bag keeps and a checkpoint writes.
struct ViscousState {
    /// Each Maxwell branch's elastic Green strain q_i per term and element, tensor components
    /// [q11, q22, q12] [-]: column i * triangles + e.
    Eigen::Matrix3Xd branchStrain;
    /// The element's Green strain E at the state, [E11, E22, E12] [-].
    Eigen::Matrix3Xd strain;
    /// [s] length of the step that ended at this state (+inf: a quasi-static change); it fixes
    /// the step potential whose equilibrium the state is.
    double stepTime = std::numeric_limits<double>::infinity();
};

/// The membrane, its gas, pressures and contacts as one energy.
class MembraneModel {
  public:
    MembraneModel(Mesh mesh, std::shared_ptr<const MembraneMaterial> material, double thickness);

    const Mesh& getMesh() const { return m_mesh; }
    double getThickness() const { return m_thickness; }
    const MembraneMaterial& getMaterial() const { return *m_material; }

    /// Self-weight of the sheet: density [kg/m^3], gravity g [m/s^2] in Ground.
    void setGravity(double density, const Vec3& g);

    /// A gas body filling the listed chambers (chambers joined by an open connection share one
    /// pressure). Returns its index. Replaces any prescribed pressure on those chambers.
    int addGas(const GasChamber& gas, const std::vector<int>& chambers);
    GasChamber& updGas(int i) { return m_gases[i].gas; }
    const GasChamber& getGas(int i) const { return m_gases[i].gas; }
    int getNumGases() const { return static_cast<int>(m_gases.size()); }
    const std::vector<int>& getGasChambers(int i) const { return m_gases[i].chambers; }
    /// Prescribed gauge pressure [Pa] on a chamber not filled by a gas (follower load).
    void setChamberPressure(int chamber, double gaugePressure);
    double getChamberPressure(int chamber) const { return m_chamberPressure[chamber]; }
    /// Index of the gas body filling chamber c, or -1 (prescribed pressure).
    int getChamberGas(int chamber) const { return m_chamberGas.at(chamber); }

    /// Viscous-like stabilisation for slack, wrinkling states (as a quasi-static analysis with
    /// automatic stabilisation): adds 1/2 k A_a |x_a - anchor_a|^2 per node, k [Pa/m], A_a the
    /// nodal reference area. The anchor is the last converged state; 0 switches it off.
    void setStabilization(double stiffnessPerArea, const Eigen::Matrix3Xd& anchor);
    /// As above, node i's spring scaled by weight[i] (empty: all 1).
    void setStabilization(double stiffnessPerArea, const Eigen::Matrix3Xd& anchor,
                          std::vector<double> weight);
    double getStabilization() const { return m_stabilization; }
    /// Energy [J] held by the stabilisation at x (a measure of how far x is from a true
    /// equilibrium: its gradient is the artificial force).
    double calcStabilizationEnergy(const Eigen::Matrix3Xd& x) const;

    /// Adds a contact term; the model shares ownership.
    void addRigidContact(std::shared_ptr<RigidContact> contact);
    void setSelfContact(std::shared_ptr<SelfContact> contact) {
        m_selfContact = std::move(contact);
    }
    std::shared_ptr<SelfContact> getSelfContact() const { return m_selfContact; }
    bool isConservative() const;
    /// Bending stiffness D [N m] of the sheet (DiscreteBending: plate law, nu = 0.5, seams
    /// bend with their reference angle as rest angle); 0 (the default) switches it off.
    /// calcPlateBendingStiffness() gives the homogeneous film's value.
    void setBendingStiffness(double D);
    double getBendingStiffness() const {
        return m_bending ? m_bending->getOptions().stiffness : 0.0;
    }
    /// Threads of the element loops: 0 the OpenMP default, 1 single-threaded. The results are
    /// bit-identical for any value (fixed chunks merged in a fixed order).
    void setNumThreads(int threads) { m_threads = threads; }
    int getNumThreads() const { return m_threads; }
    /// The elements' fixed chunks (0: one below 4000 triangles, 16 above): each chunk sums on
    /// its own and the chunks merge in order, so the bits depend on the chunks, never on the
    /// threads. More chunks let a small bag's step use several threads (the dynamic stepping
    /// of a bag alone) at the price of other roundoff.
    void setElementChunks(int chunks) { m_elementChunks = chunks; }
    int getElementChunks() const { return m_elementChunks; }

    /// Viscoelastic film (bags/Viscoelastic.h): the material is the long-term law, and every
    /// element carries a Maxwell branch per Prony term. An empty series (or all g = 0)
    /// switches it off: the energy is then the elastic one, bit for bit. Starts relaxed at the
    /// reference state.
    /// @throws std::invalid_argument if the series is invalid.
    void setProny(const PronySeries& prony);
    const PronySeries& getProny() const { return m_prony; }
    bool hasProny() const { return m_viscous; }
    /// Sets the step potential of a step of dt [s] (+inf: quasi-static) from the current
    /// internal variables.
    void beginViscousStep(double dt);
    /// Advances the internal variables to the end of the step begun last, at x (converged);
    /// the step potential stays. No-op without Prony terms.
    void endViscousStep(const Eigen::Matrix3Xd& x);
    /// Relaxed at x: no branch strain, the quasi-static step's potential.
    void resetViscousState(const Eigen::Matrix3Xd& x);
    const ViscousState& getViscousState() const { return m_viscousState; }
    /// Makes a state current, with the potential of the step that ended there.
    /// @throws std::invalid_argument if its sizes are not this model's.
    void setViscousState(const ViscousState& state);
    /// True if no branch is strained (a relaxed film stays as it is over time).
    bool isViscouslyRelaxed() const;
    /// The film's stress S_v [Pa] of triangle e at x under the current step potential (the
    /// material's stress without Prony terms).
    Eigen::Vector3d calcElementStress(const Eigen::Matrix3Xd& x, int e) const;
    /// The in-plane right Cauchy-Green tensor C of triangle e at x (in its element frame).
    Mat2 calcElementC(const Eigen::Matrix3Xd& x, int e) const;

    /// Total potential energy and its derivatives at x, added into acc.
    void addEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    /// Only the membrane: its elements (strain energy, internal forces, material+geometric
    /// tangent) and its bending (DiscreteBending, if a bending stiffness is set).
    void addMembraneEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    /// Everything but the membrane: pressures, gases (sparse part), gravity, contact.
    void addLoadEnergy(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const;
    /// The gas bodies' volumes (sum of their chambers) [m^3] and gradients, for the solver.
    double calcGasVolume(int gas, const Eigen::Matrix3Xd& x, Eigen::VectorXd* grad) const;
    /// Gauge pressure [Pa] of chamber c at x (gas law or prescribed).
    double calcChamberGaugePressure(int c, const Eigen::Matrix3Xd& x) const;

    /// Dofs that are fixed (support nodes, Mesh::fixedDofs), sorted.
    const std::vector<int>& getFixedDofs() const { return m_fixedDofs; }
    /// Starts a step of dt [s] from x in every rigid contact (RigidContact::beginStep).
    void beginContactStep(const Eigen::Matrix3Xd& x, double dt);
    /// Commits contact history at a converged x.
    void commitStep(const Eigen::Matrix3Xd& x);
    /// Snapshot of every rigid contact's friction history, and its restore (abandoned steps).
    std::vector<RigidContact::History> getContactHistory() const;
    void setContactHistory(const std::vector<RigidContact::History>& h);

    /// The reference directions an anisotropic film's warp is taken from, in the mesh's frame
    /// (default: x, the double wedge's long side, and z, its height): in each panel's plane
    /// the projection of `axis`, or of `fallback` where `axis` is within 30 degrees of the
    /// panel's normal (docs/materials.md#fabric-anisotropy). No effect on an isotropic film.
    /// @throws std::invalid_argument for a zero direction or two within 30 degrees.
    void setWarpAxes(const Vec3& axis, const Vec3& fallback);
    const Vec3& getWarpAxis() const { return m_warpAxis; }          ///< as set (setWarpAxes)
    const Vec3& getWarpFallback() const { return m_warpFallback; }  ///< as set (setWarpAxes)
    /// Unit warp direction per triangle in the reference configuration (the rule above).
    std::vector<Vec3> calcWarpDirections() const;

    /// Membrane state per triangle: 0 taut, 1 wrinkled, 2 slack (needs a WrinklingMaterial;
    /// of a FabricMaterial, its matrix's).
    std::vector<int> calcWrinkleStates(const Eigen::Matrix3Xd& x) const;
    /// Largest in-plane principal Cauchy stress per triangle [Pa].
    Eigen::VectorXd calcPrincipalStress(const Eigen::Matrix3Xd& x) const;

  private:
    friend class FilmForce;  // the explicit step's kernel reads the element data and state
    struct GasBody {
        GasChamber gas;
        std::vector<int> chambers;
    };
    void precompute();
    void precomputeFrames();  ///< m_DmInv and m_area0 (the element frames)

    Mesh m_mesh;
    std::shared_ptr<const MembraneMaterial> m_material;
    double m_thickness;
    double m_density = 0.0;
    Vec3 m_gravity = Vec3::Zero();
    std::vector<GasBody> m_gases;
    std::vector<int> m_chamberGas;          ///< gas index per chamber or -1
    std::vector<double> m_chamberPressure;  ///< prescribed gauge pressure per chamber [Pa]
    std::vector<std::shared_ptr<RigidContact>> m_contacts;
    std::shared_ptr<SelfContact> m_selfContact;
    std::vector<int> m_fixedDofs;
    std::shared_ptr<const DiscreteBending> m_bending;  ///< null: no bending
    Vec3 m_warpAxis = Vec3::UnitX();  ///< an anisotropic film's warp reference (setWarpAxes)
    Vec3 m_warpFallback = Vec3::UnitZ();
    int m_threads = 0;             ///< 0: OpenMP default
    int m_elementChunks = 0;       ///< setElementChunks (0: by size)
    double m_stabilization = 0.0;  ///< [Pa/m]
    Eigen::Matrix3Xd m_anchor;
    std::vector<double> m_stabilizationWeight;  ///< per node; empty: all 1
    Eigen::VectorXd m_nodalArea;                ///< [m^2]
    // Per triangle: inverse of the reference edge matrix in a local 2D frame, reference area.
    std::vector<Eigen::Matrix2d> m_DmInv;
    std::vector<double> m_area0;
    Eigen::VectorXd m_nodalMass;  ///< [kg]
    // Viscoelasticity (setProny): the series, its state and the current step's potential:
    // per term phi_i (0: the branch is gone), the branch's energy weight k_i / phi_i, and per
    // term and element the constant c of the branch strain q_i(C) = phi_i E(C) + c.
    PronySeries m_prony;
    bool m_viscous = false;
    ViscousState m_viscousState;
    std::vector<double> m_viscousPhi, m_viscousWeight;
    Eigen::Matrix3Xd m_viscousOffset;
    double m_viscousStepTime = std::numeric_limits<double>::infinity();
    void setViscousStep(double dt);
    /// Adds the branches' energy, stress and tangent of element e at C (false: a branch
    /// strain with det(I + 2 q) <= 0).
    bool addBranches(int e, const Mat2& C, double* W, Eigen::Vector3d* S, Eigen::Matrix3d* D) const;
};

}  // namespace bags
