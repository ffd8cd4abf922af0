#pragma once
/// @file Plane-stress incompressible hyperelastic membrane materials and the tension-field
/// (wrinkling) relaxation.
///
/// A membrane material maps the in-plane right Cauchy-Green tensor C (2x2, symmetric,
/// det C > 0) of a thin sheet to its strain energy per unit *reference volume*. Incompressibility
/// with plane stress fixes the thickness stretch: lambda3^2 = C33 = 1 / det C, so
/// I1 = tr C + 1/det C and I2 = det C + tr C / det C.
///
/// Voigt convention used everywhere in bags:
///   S_v = [S11, S22, S12]            second Piola-Kirchhoff stress [Pa]
///   E_v = [E11, E22, 2 E12]          Green-Lagrange strain, E = (C - I)/2
///   D   = dS_v / dE_v                material tangent [Pa], symmetric 3x3
/// so that dW = S_v . dE_v and S = 2 dW/dC.

#include <bags/Types.h>

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace bags {

/// A law written as a polynomial in the plane-stress incompressible invariants,
///   W = C10 x + C20 x^2 + C30 x^3 + C01 (I2 - 3),   x = I1 - 3,
/// its I1 part continued beyond x = continuationLimit with its value, slope and the
/// non-negative part of its curvature there (makeYeoh). Neo-Hooke, Mooney-Rivlin and Yeoh are
/// of this form; the explicit step's force kernel (bags/FilmForce.h) evaluates it inline.
struct InvariantPolynomial {
    double C10 = 0.0, C01 = 0.0, C20 = 0.0, C30 = 0.0;                   ///< [Pa]
    double continuationLimit = std::numeric_limits<double>::infinity();  ///< in I1 - 3 [-]
};

class MembraneMaterial {
  public:
    virtual ~MembraneMaterial() = default;

    /// Strain energy per unit reference volume [J/m^3] at in-plane C; if S (resp. D) is not
    /// null, also the stress S_v [Pa] (resp. tangent D [Pa]) in the Voigt convention above.
    /// @pre C symmetric with det C > 0.
    virtual double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const = 0;

    /// Small-strain shear modulus mu [Pa] (Young's modulus of the sheet is 3 mu).
    virtual double getInitialShearModulus() const = 0;

    /// Short model name, e.g. "yeoh".
    virtual std::string getName() const = 0;

    /// Uniaxial nominal (engineering) stress [Pa] at stretch lambda of an incompressible strip,
    /// P = dW/dlambda with W(lambda, lambda^-1/2).
    virtual double calcUniaxialNominalStress(double lambda) const;

    /// Natural width of a free strip: the squared lateral stretch e2 = lambda2^2 at which the
    /// lateral stress vanishes when the strip is stretched to e1 = lambda1^2, with its first
    /// and second derivatives in e1 (the tension-field law needs them). Default: isotropic
    /// incompressible, e2 = e1^(-1/2); compressible materials override it.
    virtual double calcNaturalWidth(double e1, double* d1, double* d2) const;

    /// False for a material with directions in the sheet (FabricMaterial): its C must be
    /// given in the element frame whose first axis is the warp (MembraneModel builds it so).
    virtual bool isIsotropic() const { return true; }

    /// True (and *law set) if this material is an InvariantPolynomial with the default
    /// natural width; false for any other law.
    virtual bool getInvariantPolynomial(InvariantPolynomial* law) const {
        (void)law;
        return false;
    }

    virtual std::unique_ptr<MembraneMaterial> clone() const = 0;
};

/// The largest I1 - 3 [-] up to which `material` is the law it was fitted as: a Yeoh
/// continued beyond its stable range (makeStableYeoh) is its fitted polynomial only up to
/// InvariantPolynomial::continuationLimit; a tension-field material is its base's. Infinity
/// where no such limit is known (the law holds as written everywhere).
double calcFittedRangeLimit(const MembraneMaterial& material);

/// W = C10 (I1 - 3).  @pre C10 > 0.
std::unique_ptr<MembraneMaterial> makeNeoHookean(double C10);
/// W = C10 (I1 - 3) + C01 (I2 - 3).
std::unique_ptr<MembraneMaterial> makeMooneyRivlin(double C10, double C01);
/// W = C10 (I1 - 3) + C20 (I1 - 3)^2 + C30 (I1 - 3)^3 up to I1 - 3 = continuationLimit;
/// beyond it W goes on with its value, slope and (non-negative part of its) curvature there.
/// A fit with C30 < 0 has W -> -infinity at large I1: the limit keeps the energy bounded below
/// (see makeStableYeoh). Default: the polynomial everywhere.
std::unique_ptr<MembraneMaterial> makeYeoh(
    double C10, double C20, double C30,
    double continuationLimit = std::numeric_limits<double>::infinity());
/// W = sum_i 2 mu_i / alpha_i^2 (l1^a_i + l2^a_i + l3^a_i - 3) (Abaqus convention).
std::unique_ptr<MembraneMaterial> makeOgden(const std::vector<double>& mu,
                                            const std::vector<double>& alpha);

/// Tension-field relaxation of a base material (Pipkin's relaxed energy) plus a small fraction
/// of the base energy as residual stiffness so slack and wrinkled states stay solvable:
///   taut      (lambda2 >= lambda1^-1/2): W = W_base(C)
///   wrinkled  (lambda1 > 1, lambda2 < lambda1^-1/2): W = W_uni(lambda1)
///   slack     (lambda1 <= 1): W = 0
/// where lambda1 >= lambda2 are the in-plane principal stretches and W_uni is the uniaxial
/// energy. The total is W_relaxed + residual * W_base. Energy, S and D are consistent.
class WrinklingMaterial : public MembraneMaterial {
  public:
    WrinklingMaterial(std::unique_ptr<MembraneMaterial> base, double residual = 1e-3);
    /// As above, but the residual term is residual * W_residual with its own material (e.g. a
    /// neo-Hookean of the base's initial shear modulus, which stays convex where a Yeoh with
    /// C30 < 0 does not: in strong biaxial compression, I1 = tr C + 1/det C grows without bound).
    /// @throws std::invalid_argument if residual < 0 or a material is null.
    WrinklingMaterial(std::unique_ptr<MembraneMaterial> base, double residual,
                      std::unique_ptr<MembraneMaterial> residualMaterial);
    WrinklingMaterial(const WrinklingMaterial& other);
    double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const override;
    double getInitialShearModulus() const override;
    std::string getName() const override;
    std::unique_ptr<MembraneMaterial> clone() const override;
    /// 0 taut, 1 wrinkled, 2 slack at C.
    int calcState(const Mat2& C) const;
    const MembraneMaterial& getBase() const { return *m_base; }
    double getResidual() const { return m_residual; }
    /// The material of the residual term (the base unless one was given).
    const MembraneMaterial& getResidualMaterial() const {
        return m_residualMaterial ? *m_residualMaterial : *m_base;
    }
    /// Principal stretches (lambda1 >= lambda2) of the in-plane C [-].
    static void calcPrincipalStretches(const Mat2& C, double* lambda1, double* lambda2);

  private:
    std::unique_ptr<MembraneMaterial> m_base;
    double m_residual;
    std::unique_ptr<MembraneMaterial> m_residualMaterial;  ///< null: the base
};

/// The woven fabric's yarns (docs/materials.md#fabric-anisotropy): two families, warp and
/// weft, at right angles in the sheet, each a fibre that carries tension only.
struct FabricAnisotropy {
    double warpModulus = 0.0;  ///< k_w [Pa]: the warp yarns' tangent modulus in Green strain
    double weftModulus = 0.0;  ///< k_f [Pa]: the weft yarns'
    /// [rad] the warp's angle from the element frame's first axis (MembraneModel aligns that
    /// axis with the panel's reference warp direction), positive about the element normal.
    double angle = 0.0;
    /// Largest modulus accepted [Pa] (a hundred times the seed film's Young's modulus).
    static constexpr double kMaxModulus = 2.0e10;
    /// True if a family has a modulus (zero: the isotropic film, bit for bit).
    bool isOn() const { return warpModulus > 0.0 || weftModulus > 0.0; }
    /// @throws std::invalid_argument naming the member (warpModulus, weftModulus, angle) and
    /// its valid range: moduli 0 to kMaxModulus, |angle| <= pi/2.
    void validate() const;
};

/// An isotropic matrix (the film's law, with or without the tension field) reinforced by two
/// yarn families that carry no compression: the standard reinforcing model with the fibre
/// switched off in compression,
///   W = W_matrix(C) + k_w/2 <E_w>^2 + k_f/2 <E_f>^2,   E_a = (a . C a - 1) / 2,
/// <x> = max(x, 0), a the warp (cos angle, sin angle) and the weft at right angles to it, in
/// the element frame. The stress adds k <E_a> a a^T per family (positive semidefinite), so
/// with a tension-field matrix the sum carries no compression in any direction.
class FabricMaterial : public MembraneMaterial {
  public:
    /// @throws std::invalid_argument if the matrix is null or the yarns are invalid.
    FabricMaterial(std::unique_ptr<MembraneMaterial> matrix, const FabricAnisotropy& yarns);
    FabricMaterial(const FabricMaterial& other);
    double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const override;
    /// The matrix's (the yarns add stiffness along themselves only).
    double getInitialShearModulus() const override;
    std::string getName() const override;
    bool isIsotropic() const override { return false; }
    std::unique_ptr<MembraneMaterial> clone() const override;
    const MembraneMaterial& getMatrix() const { return *m_matrix; }
    const FabricAnisotropy& getYarns() const { return m_yarns; }

  private:
    std::unique_ptr<MembraneMaterial> m_matrix;
    FabricAnisotropy m_yarns;
};

/// The material the membrane elements use: the tension field on the base
/// (WrinklingMaterial(base, residual)); for a FabricMaterial, the tension field on its matrix
/// with the yarns added to it (each part carries no compression).
std::unique_ptr<MembraneMaterial> makeRelaxedMaterial(const MembraneMaterial& base,
                                                      double residual);

}  // namespace bags
