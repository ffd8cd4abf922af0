#pragma once
/// @file Fitting membrane materials to a uniaxial tensile test of the sheet, and the stretch
/// range where a material stays stable.
///
/// Order of use: readTensileCsv() (or fill a TensileData), MaterialFitOptions::validate(), then
/// fitMaterial() per model. The result holds the constants, the fit error, the stable range and
/// the material in the form a scenario takes (formatScenarioYaml()).
///
/// The test is taken as a uniaxial strip of an incompressible isotropic sheet: stretch
/// lambda = 1 + engineering strain, lateral stretches lambda^-1/2, nominal stress
/// P = dW/dlambda. Neo-Hookean, Mooney-Rivlin and Yeoh are linear in their constants and are
/// fitted by linear least squares (QR); Ogden is fitted by bounded nonlinear least squares
/// (Ceres, several starts).

#include <bags/Material.h>

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace bags {

/// A uniaxial tensile test: engineering strain and engineering (nominal) stress.
struct TensileData {
    std::vector<double> strain;  ///< engineering strain lambda - 1 [-]
    std::vector<double> stress;  ///< force / undeformed cross-section [Pa]
    std::vector<int> lines;      ///< 1-based line of each point in its file (0 if not from a file)
    std::string source;          ///< file name (for messages), "" if none
};

/// Parses a tensile CSV: '#' comment lines and blank lines are skipped; the first other line is
/// the header, naming two columns: strain then stress. Units come from the arguments or, if
/// they are "", from the header: strain column "strain" (fraction) or "strain_percent" /
/// "strain_%" (percent); stress column "stress_MPa", "stress_kPa" or "stress_Pa".
/// @param strainUnit "fraction", "percent" or "" (from the header)
/// @param stressUnit "Pa", "kPa", "MPa" or "" (from the header)
/// @param name file name used in messages
/// @throws std::invalid_argument "name:line: column 'c': ..." naming what is wrong and what is
///   valid (a non-numeric or non-finite cell, a wrong number of cells, an unknown unit, a
///   strain <= -100 %, no data rows).
TensileData parseTensileCsv(std::istream& in, const std::string& name,
                            const std::string& strainUnit = "", const std::string& stressUnit = "");
/// Reads a file with parseTensileCsv(). @throws std::invalid_argument also if it cannot be read.
TensileData readTensileCsv(const std::string& path, const std::string& strainUnit = "",
                           const std::string& stressUnit = "");

enum class MaterialModel { NeoHookean, MooneyRivlin, Yeoh, Ogden };

/// "neo-hookean", "mooney-rivlin", "yeoh", "ogden" (as on the command line and in scenarios).
std::string getMaterialModelName(MaterialModel model);
/// Inverse of getMaterialModelName(). @throws std::invalid_argument listing the valid names.
MaterialModel parseMaterialModel(const std::string& name);
/// All models in the order neo-Hookean, Mooney-Rivlin, Yeoh, Ogden.
std::vector<MaterialModel> getMaterialModels();

/// Names of a model's constants, in the order makeMaterial() takes them: C10; C10 C01;
/// C10 C20 C30; mu1 alpha1 mu2 alpha2 ... (ogdenTerms pairs).
std::vector<std::string> getConstantNames(MaterialModel model, int ogdenTerms = 2);
/// True for constants in [Pa] (C.., mu..), false for the dimensionless alpha_i.
bool isStressConstant(const std::string& constantName);
/// Builds a material from constants in getConstantNames() order ([Pa] for stresses).
/// @throws std::invalid_argument for a wrong count or constants the model rejects.
std::unique_ptr<MembraneMaterial> makeMaterial(MaterialModel model,
                                               const std::vector<double>& constants);

struct MaterialFitOptions {
    int ogdenTerms = 2;             ///< number of Ogden terms N, 1 to 3
    double ogdenAlphaBound = 20.0;  ///< bound on the Ogden exponents |alpha_i| [-]
    /// Constrain every Ogden mu_i >= 0. In this (Abaqus) convention a term's energy
    /// 2 mu_i / alpha_i^2 sum_j (exp(alpha_i eps_j) - 1) has the log-strain Hessian
    /// 2 mu_i diag(exp(alpha_i eps_j)), so mu_i >= 0 for all i makes the model Drucker-stable
    /// at every stretch (Ogden's "mu_p alpha_p > 0" is the same condition in his convention).
    bool ogdenStableTerms = true;
    double stabilityMaxStretch = 3.0;  ///< stability scanned for stretches 1 to this [-]
    double stabilityStep = 1e-3;       ///< stretch increment of that scan [-]
    /// @throws std::invalid_argument naming the option and what is valid.
    void validate() const;
};

/// Largest stretch from 1 up to which a criterion holds on a path of the taut membrane
/// (equal to the scan limit if it holds throughout).
struct PathStability {
    /// Drucker: the tangent of the in-plane principal Kirchhoff stresses with respect to the
    /// principal log strains (plane stress, incompressible) is positive definite [-].
    double drucker = 0.0;
    /// The nominal (engineering) stress along the path rises with the stretch [-].
    double monotone = 0.0;
    /// The more restrictive of the two [-].
    double getStable() const;
};

/// Stability of the taut membrane along the three tension paths that bound its states
/// (positive definiteness of D = dS/dE is not used: it fails for perfectly stable materials,
/// e.g. Mooney-Rivlin, whose second Piola-Kirchhoff stress falls at large stretch):
/// uniaxial (lambda, lambda^-1/2), planar (lambda, 1) and equibiaxial (lambda, lambda). Compression
/// is not scanned: under the tension-field law it is carried as a wrinkled uniaxial state.
struct StabilityRange {
    PathStability uniaxial;
    PathStability planar;
    PathStability equibiaxial;
    double maxChecked = 0.0;  ///< the scan limit [-]
    /// The stretch up to which the material is stable on all three paths [-].
    double getStable() const;
};

/// Scans the three paths from stretch 1 to maxStretch in steps of `step`; a limit is the last
/// stretch before the first failure, found to within `step`.
StabilityRange calcStabilityRange(const MembraneMaterial& material, double maxStretch = 3.0,
                                  double step = 1e-3);

/// I1 - 3 at which a Yeoh material (C10, C20, C30) first leaves its stable range on the
/// uniaxial, planar or equibiaxial path (calcStabilityRange scanned to stretch 3 in steps of
/// 1e-3; the last stable stretch, to within the step).
/// - Energy unbounded below (C30 < 0, or C30 == 0 and C20 < 0): always finite and below x0,
///   the positive root of dW/dI1 = C10 + 2 C20 x + 3 C30 x^2 (the equibiaxial stress peaks
///   before it). If the scan to stretch 3 finds nothing, it is repeated up to the equibiaxial
///   stretch sqrt((x0 + 3) / 2), which reaches x0, in steps of 1e-3 or, if larger, a 1e5th of
///   the range.
/// - Otherwise: infinity if the material stays stable up to stretch 3. A finite value may then
///   be the start of a band only (e.g. C20 < 0 < C30 is stable again beyond it).
double calcYeohStableLimit(double C10, double C20, double C30);

/// A Yeoh material whose energy is bounded below, for solvers whose trial states may
/// overstretch elements (a Newton line search accepts an energy that falls without bound).
/// - Energy unbounded below (C30 < 0, or C30 == 0 and C20 < 0): the polynomial up to
///   I1 - 3 = calcYeohStableLimit() (finite, with dW/dI1 > 0 there), continued linearly in I1
///   beyond it (makeYeoh with that limit): the same response wherever the fit is stable, an
///   energy that rises beyond.
/// - Otherwise (C30 > 0, or C30 == 0 and C20 >= 0): the plain polynomial, makeYeoh(C10, C20,
///   C30), even where it is unstable in a middle band: its energy is bounded below already,
///   and the large-strain stiffening of C30 > 0 is kept.
std::unique_ptr<MembraneMaterial> makeStableYeoh(double C10, double C20, double C30);

/// Outcome of fitting one model to one data set.
struct MaterialFitResult {
    MaterialModel model = MaterialModel::NeoHookean;
    std::vector<std::string> names;  ///< constant names, getConstantNames() order
    std::vector<double> constants;   ///< [Pa] for stresses, [-] for alpha_i
    double rmsError = 0.0;           ///< root-mean-square stress residual [Pa]
    double maxError = 0.0;           ///< largest absolute stress residual [Pa]
    double r2 = 0.0;                 ///< coefficient of determination of the stress
    int numPoints = 0;               ///< data points used
    double minStrain = 0.0;          ///< data range [-]
    double maxStrain = 0.0;          ///< [-]
    StabilityRange stability;        ///< of the fitted material
    int ogdenStarts = 0;             ///< Ogden: starts tried (0 for the linear models)

    /// The fitted material.
    std::unique_ptr<MembraneMaterial> makeMaterial() const;
    /// Engineering stress [Pa] of the fitted model at an engineering strain [-].
    double calcStress(double strain) const;
    /// The keys of a scenario's `membrane:` section that set the material, one per line, each
    /// line starting with `indent`, e.g.
    ///   model: yeoh
    ///   C10: 31.58792 MPa
    ///   C20: -0.7658257 MPa
    ///   C30: -3.065876 MPa
    /// and for Ogden: `mu: [1.2 MPa, 0.3 MPa]`, `alpha: [7.5, -3]`. Seven significant digits.
    std::string formatScenarioYaml(const std::string& indent = "") const;
};

/// Least-squares fit of the nominal stress of a uniaxial strip to the data.
/// @throws std::invalid_argument if the options are invalid, there are fewer points with
///   nonzero strain than constants + 1, or the best fit violates the model's own requirement
///   (e.g. a negative initial shear modulus), saying which.
MaterialFitResult fitMaterial(const TensileData& data, MaterialModel model,
                              const MaterialFitOptions& options = {});

}  // namespace bags
