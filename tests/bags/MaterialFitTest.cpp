// Material fitting, stability ranges, tensile CSV reading and the polynomial helpers.
#include <bags/MaterialFit.h>
#include <bags/Polynomial.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <sstream>
#include <string>

namespace {

constexpr double kC10 = 31.587917e6, kC20 = -0.76582566e6, kC30 = -3.06587618e6;

/// Noise-free uniaxial data of a material over strains 0..maxStrain (n points).
bags::TensileData makeData(const bags::MembraneMaterial& m, double maxStrain, int n) {
    bags::TensileData d;
    for (int i = 0; i < n; ++i) {
        const double e = maxStrain * i / (n - 1);
        d.strain.push_back(e);
        d.stress.push_back(m.calcUniaxialNominalStress(1.0 + e));
    }
    return d;
}

/// Standard errors of linear least-squares Yeoh constants for stress noise sd `sigma` [Pa]:
/// sqrt(diag(sigma^2 (A^T A)^-1)), A the Yeoh design matrix at the data's stretches.
Eigen::Vector3d calcYeohStandardErrors(const bags::TensileData& d, double sigma) {
    const int n = static_cast<int>(d.strain.size());
    Eigen::MatrixXd A(n, 3);
    for (int i = 0; i < n; ++i) {
        const double l = 1.0 + d.strain[i], B = 2.0 * (l - 1.0 / (l * l));
        const double x = l * l + 2.0 / l - 3.0;
        A.row(i) << B, 2.0 * B * x, 3.0 * B * x * x;
    }
    const Eigen::Matrix3d cov = sigma * sigma * (A.transpose() * A).inverse();
    return cov.diagonal().cwiseSqrt();
}

double yeohUniaxial(double l) {
    const double x = l * l + 2.0 / l - 3.0;
    return 2.0 * (l - 1.0 / (l * l)) * (kC10 + 2.0 * kC20 * x + 3.0 * kC30 * x * x);
}
double yeohEquibiaxial(double l) {
    const double x = 2.0 * l * l + std::pow(l, -4.0) - 3.0;
    return 2.0 * (l - std::pow(l, -5.0)) * (kC10 + 2.0 * kC20 * x + 3.0 * kC30 * x * x);
}
/// Stretch of the first maximum of f on [1, 3], by a scan in steps of 1e-5.
template <class F>
double findPeak(F f) {
    double best = 1.0, fb = f(1.0);
    for (int i = 1; i <= 200000; ++i) {
        const double l = 1.0 + 1e-5 * i, v = f(l);
        if (v < fb) break;
        best = l;
        fb = v;
    }
    return best;
}

}  // namespace

TEST(MaterialFit, LinearModelsRecoverTheirOwnConstantsFromNoiseFreeData) {
    // Reference: data made by the model itself; least squares must return the constants to
    // round-off (1e-8 relative; the Yeoh columns are well conditioned after scaling).
    struct Case {
        bags::MaterialModel model;
        std::vector<double> c;
    };
    for (const Case& k : {Case{bags::MaterialModel::NeoHookean, {0.5e6}},
                          Case{bags::MaterialModel::MooneyRivlin, {0.4e6, 0.1e6}},
                          Case{bags::MaterialModel::MooneyRivlin, {0.6e6, -0.05e6}},
                          Case{bags::MaterialModel::Yeoh, {kC10, kC20, kC30}}}) {
        const auto m = bags::makeMaterial(k.model, k.c);
        const bags::TensileData d = makeData(*m, 0.5, 51);
        const bags::MaterialFitResult r = bags::fitMaterial(d, k.model);
        ASSERT_EQ(r.constants.size(), k.c.size());
        for (std::size_t i = 0; i < k.c.size(); ++i)
            EXPECT_NEAR(r.constants[i], k.c[i], 1e-8 * std::abs(k.c[0]))
                << bags::getMaterialModelName(k.model) << " " << r.names[i];
        EXPECT_GT(r.r2, 1.0 - 1e-14);
        EXPECT_LT(r.rmsError, 1e-6 * 1e6);  // < 1 Pa on stresses up to ~1e7 Pa
        EXPECT_EQ(r.numPoints, 51);
    }
}

TEST(MaterialFit, OgdenRecoversTwoTermConstantsFromNoiseFreeData) {
    // Reference: 2-term Ogden data (mu = 0.8, 0.05 MPa; alpha = 1.8, 6.0) over 0-100 % strain.
    // The multi-start bounded fit must reproduce the curve to 1e-6 of its peak and the
    // constants to 1e-3 relative (Ogden constants are less well determined than the curve).
    const std::vector<double> mu = {0.8e6, 0.05e6}, alpha = {1.8, 6.0};
    const auto m = bags::makeOgden(mu, alpha);
    const bags::TensileData d = makeData(*m, 1.0, 81);
    const bags::MaterialFitResult r = bags::fitMaterial(d, bags::MaterialModel::Ogden);
    const double peak = d.stress.back();
    EXPECT_LT(r.rmsError, 1e-6 * peak);
    ASSERT_EQ(r.constants.size(), 4u);
    // Order the fitted terms by alpha.
    int a = r.constants[1] < r.constants[3] ? 0 : 2, b = 2 - a;
    EXPECT_NEAR(r.constants[a], mu[0], 1e-3 * mu[0]);
    EXPECT_NEAR(r.constants[a + 1], alpha[0], 1e-3 * alpha[0]);
    EXPECT_NEAR(r.constants[b], mu[1], 1e-3 * mu[1]);
    EXPECT_NEAR(r.constants[b + 1], alpha[1], 1e-3 * alpha[1]);
    EXPECT_GT(r.ogdenStarts, 10);
}

TEST(MaterialFit, OgdenStableTermsGiveNonNegativeMuAndADruckerStableModel) {
    // Yeoh data whose curve turns over cannot be followed by stable Ogden terms. With the
    // constraint every fitted mu_i must be >= 0, which makes each term convex in the log
    // strains, so the fitted model must pass the Drucker check on every path up to the scan
    // limit (3). Without it, the fit is free to take a negative mu_i.
    const auto m = bags::makeYeoh(kC10, kC20, kC30);
    const bags::TensileData d = makeData(*m, 0.5, 51);
    for (int terms : {2, 3}) {
        bags::MaterialFitOptions o;
        o.ogdenTerms = terms;
        const bags::MaterialFitResult r = bags::fitMaterial(d, bags::MaterialModel::Ogden, o);
        ASSERT_EQ(static_cast<int>(r.constants.size()), 2 * terms);
        for (int j = 0; j < terms; ++j) EXPECT_GE(r.constants[2 * j], 0.0) << "term " << j;
        EXPECT_EQ(r.stability.uniaxial.drucker, 3.0);
        EXPECT_EQ(r.stability.planar.drucker, 3.0);
        EXPECT_EQ(r.stability.equibiaxial.drucker, 3.0);
        EXPECT_GT(r.r2, 0.99);
    }
    bags::MaterialFitOptions free;
    free.ogdenStableTerms = false;
    const bags::MaterialFitResult rf = bags::fitMaterial(d, bags::MaterialModel::Ogden, free);
    EXPECT_LT(std::min(rf.constants[0], rf.constants[2]), 0.0);
}

TEST(MaterialFit, YeohWithNoiseRecoversConstantsWithinFourStandardErrors) {
    // Reference: seed Yeoh data (0-50 % strain, 101 points) plus Gaussian noise sd 0.15 MPa.
    // Each constant must lie within 4 of its least-squares standard errors (computed here from
    // the design matrix), and the RMS residual near the noise level (0.8 to 1.2 sd).
    const auto m = bags::makeYeoh(kC10, kC20, kC30);
    bags::TensileData d = makeData(*m, 0.5, 101);
    const double sigma = 0.15e6;
    std::mt19937 rng(42);
    std::normal_distribution<double> noise(0.0, sigma);
    for (std::size_t i = 1; i < d.stress.size(); ++i) d.stress[i] += noise(rng);
    const bags::MaterialFitResult r = bags::fitMaterial(d, bags::MaterialModel::Yeoh);
    const Eigen::Vector3d se = calcYeohStandardErrors(d, sigma);
    const double ref[3] = {kC10, kC20, kC30};
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.constants[i], ref[i], 4.0 * se(i)) << r.names[i];
    EXPECT_GT(r.rmsError, 0.8 * sigma);
    EXPECT_LT(r.rmsError, 1.2 * sigma);
}

TEST(MaterialFit, ShippedTensileDataGivesBackTheSeedYeohWithinItsNoise) {
    // data/tensile/tpu-coated-nylon.csv is synthesised from the seed's Yeoh constants with
    // noise sd 0.15 MPa (data/tensile/README.md): the refit must be within 4 standard errors.
    const bags::TensileData d =
        bags::readTensileCsv(std::string(BAGSIM_SOURCE_DIR) + "/data/tensile/tpu-coated-nylon.csv");
    ASSERT_EQ(d.strain.size(), 101u);
    EXPECT_DOUBLE_EQ(d.stress[100], 58.3153e6);  // last row, MPa column converted to Pa
    const bags::MaterialFitResult r = bags::fitMaterial(d, bags::MaterialModel::Yeoh);
    const Eigen::Vector3d se = calcYeohStandardErrors(d, 0.15e6);
    const double ref[3] = {kC10, kC20, kC30};
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.constants[i], ref[i], 4.0 * se(i)) << r.names[i];
    EXPECT_GT(r.r2, 0.999);
}

TEST(MaterialFit, SeedYeohStableRangeEndsAtTheClosedFormStressPeaks) {
    // Reference: the uniaxial and equibiaxial nominal stresses of the seed Yeoh (closed forms)
    // peak at the stretches found by a 1e-5 scan here; the monotone limits must match them to
    // within the 1e-3 scan step (+ 1e-5).
    const auto m = bags::makeYeoh(kC10, kC20, kC30);
    const bags::StabilityRange s = bags::calcStabilityRange(*m, 3.0, 1e-3);
    const double uPeak = findPeak(yeohUniaxial), ePeak = findPeak(yeohEquibiaxial);
    EXPECT_NEAR(s.uniaxial.monotone, uPeak, 1.1e-3);
    EXPECT_NEAR(s.equibiaxial.monotone, ePeak, 1.1e-3);
    EXPECT_LT(s.getStable(), 1.3);  // the equibiaxial peak (1.286) limits it
    EXPECT_GT(s.getStable(), 1.0);
}

TEST(MaterialFit, NeoHookeanIsStableOverTheWholeScan) {
    const auto m = bags::makeNeoHookean(1e6);
    const bags::StabilityRange s = bags::calcStabilityRange(*m, 4.0, 1e-2);
    EXPECT_EQ(s.getStable(), 4.0);
    EXPECT_EQ(s.maxChecked, 4.0);
}

TEST(MaterialFit, ScenarioSnippetCarriesTheConstantsInMegapascals) {
    bags::MaterialFitResult r;
    r.model = bags::MaterialModel::Yeoh;
    r.names = bags::getConstantNames(r.model);
    r.constants = {kC10, kC20, kC30};
    // Keys of the scenario's membrane section, as io/src/LoadTestScenario.cpp reads them.
    EXPECT_EQ(r.formatScenarioYaml("  "),
              "  model: yeoh\n  C10: 31.58792 MPa\n"
              "  C20: -0.7658257 MPa\n  C30: -3.065876 MPa\n");
    r.model = bags::MaterialModel::Ogden;
    r.names = bags::getConstantNames(r.model, 2);
    r.constants = {1.2e6, 7.5, 0.3e6, -3.0};
    EXPECT_EQ(r.formatScenarioYaml(), "model: ogden\nmu: [1.2 MPa, 0.3 MPa]\nalpha: [7.5, -3]\n");
}

TEST(MaterialFit, TooFewPointsAndUnknownModelsAreRejected) {
    bags::TensileData d;
    d.source = "t.csv";
    d.strain = {0.0, 0.1, 0.2, 0.3};
    d.stress = {0.0, 1e6, 2e6, 2.9e6};
    try {
        bags::fitMaterial(d, bags::MaterialModel::Yeoh);
        FAIL() << "3 nonzero-strain points fitted 3 constants + 1";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("needs at least 4"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(bags::fitMaterial(d, bags::MaterialModel::MooneyRivlin));
    try {
        bags::parseMaterialModel("yoeh");
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("neo-hookean, mooney-rivlin, yeoh, ogden"),
                  std::string::npos);
    }
    bags::MaterialFitOptions o;
    o.ogdenTerms = 4;
    EXPECT_THROW(o.validate(), std::invalid_argument);
}

TEST(TensileCsv, ReadsUnitsFromHeaderOrArguments) {
    std::istringstream a("# comment\n\nstrain_percent,stress_kPa\n0,0\n10,500\n20,900\n");
    const bags::TensileData d = bags::parseTensileCsv(a, "a.csv");
    ASSERT_EQ(d.strain.size(), 3u);
    EXPECT_DOUBLE_EQ(d.strain[1], 0.1);
    EXPECT_DOUBLE_EQ(d.stress[2], 900e3);
    EXPECT_EQ(d.lines[0], 4);
    std::istringstream b("\xEF\xBB\xBFstrain,stress\r\n0.1,2.5\r\n");  // BOM, CRLF
    const bags::TensileData e = bags::parseTensileCsv(b, "b.csv", "fraction", "MPa");
    EXPECT_DOUBLE_EQ(e.stress[0], 2.5e6);
}

TEST(TensileCsv, ErrorsNameFileLineColumnAndWhatIsValid) {
    auto message = [](const std::string& text, const std::string& strainUnit = "",
                      const std::string& stressUnit = "") {
        std::istringstream in(text);
        try {
            bags::parseTensileCsv(in, "x.csv", strainUnit, stressUnit);
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(message("strain,stress_MPa\n0.1,1\n0.2,abc\n"),
              "x.csv:3: column 2 'stress_MPa': 'abc' is not a finite number; valid: a decimal "
              "number such as 12.5 or 1.2e-3");
    EXPECT_EQ(message("# c\nstrain,stress_MPa\n0.1\n"),
              "x.csv:3: has 1 cells; expected 2 (strain,stress_MPa)");
    EXPECT_NE(message("0.1,2\n").find("x.csv:1: header '0.1,2' is not a header"),
              std::string::npos);
    EXPECT_NE(
        message("strain,stress\n0.1,2\n").find("x.csv:1: column 2 'stress' gives no stress unit"),
        std::string::npos);
    EXPECT_NE(message("strain,stress_psi\n0.1,2\n").find("unknown stress unit 'psi'"),
              std::string::npos);
    EXPECT_NE(message("strain,stress_MPa\n-1.5,2\n").find("x.csv:2: column 1 'strain'"),
              std::string::npos);
    EXPECT_NE(message("strain,stress_MPa\n").find("no data rows"), std::string::npos);
    EXPECT_NE(message("strain,stress_MPa\n0.1,1\n", "", "Pa").find("make them agree"),
              std::string::npos);
    EXPECT_NE(message("strain,stress_MPa\n0.1,1\n", "percentage").find("valid: percent, fraction"),
              std::string::npos);
}

TEST(Polynomial, FitRecoversTheSeedStiffnessPolynomialFromItsValues) {
    // Reference: the seed's k(m) coefficients (highest power first); fitting an order-5
    // polynomial to its exact values at 1.0..3.5 g must give them back to 1e-8 absolute.
    const std::vector<double> c = {-0.945, 8.394, -25.707, 32.714, -17.181, 6.196};
    std::vector<double> x, y;
    for (int i = 0; i <= 10; ++i) {
        x.push_back(1.0 + 0.25 * i);
        y.push_back(bags::evalPolynomial(c, x.back()));
    }
    const std::vector<double> f = bags::fitPolynomial(x, y, 5);
    ASSERT_EQ(f.size(), 6u);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(f[i], c[i], 1e-8) << "c" << i + 1;
    EXPECT_DOUBLE_EQ(bags::evalPolynomial({2.0, -3.0, 1.0}, 2.0), 3.0);  // 2*4 - 6 + 1
    EXPECT_THROW(bags::fitPolynomial({1.0, 2.0}, {1.0, 2.0}, 2), std::invalid_argument);
}

TEST(Polynomial, FitLineGivesSlopeInterceptAndR2) {
    // Reference, by hand: (0,0), (1,1), (2,1): slope 1/2, intercept 1/6, SSE 1/6, SST 2/3,
    // r2 = 0.75.
    const bags::LinearFit f = bags::fitLine({0.0, 1.0, 2.0}, {0.0, 1.0, 1.0});
    EXPECT_NEAR(f.slope, 0.5, 1e-15);
    EXPECT_NEAR(f.intercept, 1.0 / 6.0, 1e-15);
    EXPECT_NEAR(f.r2, 0.75, 1e-15);
    EXPECT_THROW(bags::fitLine({1.0, 1.0}, {1.0, 2.0}), std::invalid_argument);
}
