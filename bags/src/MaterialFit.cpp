// Fitting membrane materials to uniaxial tensile data, and their stable stretch range.
#include <bags/MaterialFit.h>
#include <bags/Text.h>
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace bags {

namespace {

std::vector<std::string> splitCsv(const std::string& line) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream is(line);
    while (std::getline(is, cell, ',')) cells.push_back(trimBlanks(cell));
    if (!line.empty() && line.back() == ',') cells.push_back("");
    return cells;
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string formatG(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

[[noreturn]] void failAt(const std::string& name, int line, const std::string& what) {
    throw std::invalid_argument(name + ":" + std::to_string(line) + ": " + what);
}

/// Strain scale (1 or 0.01) from a unit name, or 0 if unknown.
double findStrainScale(const std::string& unit) {
    const std::string u = lower(unit);
    if (u == "fraction" || u == "-" || u == "1") return 1.0;
    if (u == "percent" || u == "%" || u == "pct") return 0.01;
    return 0.0;
}

/// Stress scale to Pa from a unit name (case as written: MPa, kPa, Pa, GPa), or 0 if unknown.
double findStressScale(const std::string& unit) {
    if (unit == "Pa") return 1.0;
    if (unit == "kPa") return 1e3;
    if (unit == "MPa" || unit == "N/mm2" || unit == "N/mm^2") return 1e6;
    if (unit == "GPa") return 1e9;
    return 0.0;
}

/// Unit written after the first '_' of a column name ("stress_MPa" -> "MPa"), "" if none.
std::string getHeaderUnit(const std::string& column) {
    const auto p = column.find('_');
    return p == std::string::npos ? "" : column.substr(p + 1);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Tensile CSV

TensileData parseTensileCsv(std::istream& in, const std::string& name,
                            const std::string& strainUnit, const std::string& stressUnit) {
    if (!strainUnit.empty() && findStrainScale(strainUnit) == 0.0)
        throw std::invalid_argument(name + ": strain unit '" + strainUnit +
                                    "' is unknown; valid: percent, fraction");
    if (!stressUnit.empty() && findStressScale(stressUnit) == 0.0)
        throw std::invalid_argument(name + ": stress unit '" + stressUnit +
                                    "' is unknown; valid: MPa, kPa, Pa");
    TensileData data;
    data.source = name;
    std::string raw;
    int lineNo = 0;
    bool haveHeader = false;
    double strainScale = 0.0, stressScale = 0.0;
    std::vector<std::string> columns;
    while (std::getline(in, raw)) {
        ++lineNo;
        if (lineNo == 1 && raw.rfind("\xEF\xBB\xBF", 0) == 0) raw.erase(0, 3);  // UTF-8 BOM
        const std::string line = trimBlanks(raw);
        if (line.empty() || line[0] == '#') continue;
        const std::vector<std::string> cells = splitCsv(line);
        if (!haveHeader) {
            haveHeader = true;
            columns = cells;
            const std::string want =
                "a header naming two columns, strain then stress, e.g. "
                "'strain,stress_MPa' or 'strain_percent,stress_kPa'";
            if (cells.size() != 2)
                failAt(name, lineNo,
                       "header has " + std::to_string(cells.size()) + " columns; expected " + want);
            if (lower(cells[0]).rfind("strain", 0) != 0 || lower(cells[1]).rfind("stress", 0) != 0)
                failAt(name, lineNo, "header '" + line + "' is not " + want);
            // Units: the caller's, else the header's.
            const std::string hs = getHeaderUnit(cells[0]);
            const std::string hp = getHeaderUnit(cells[1]);
            const double hsScale = hs.empty() ? 1.0 : findStrainScale(hs);
            const double hpScale = hp.empty() ? 0.0 : findStressScale(hp);
            if (!hs.empty() && hsScale == 0.0 && strainUnit.empty())
                failAt(name, lineNo,
                       "column 1 '" + cells[0] + "': unknown strain unit '" + hs +
                           "'; valid: strain (fraction), strain_percent");
            if (!hp.empty() && hpScale == 0.0 && stressUnit.empty())
                failAt(name, lineNo,
                       "column 2 '" + cells[1] + "': unknown stress unit '" + hp +
                           "'; valid: stress_MPa, stress_kPa, stress_Pa");
            strainScale = strainUnit.empty() ? hsScale : findStrainScale(strainUnit);
            stressScale = stressUnit.empty() ? hpScale : findStressScale(stressUnit);
            if (!strainUnit.empty() && !hs.empty() && hsScale != 0.0 && hsScale != strainScale)
                failAt(name, lineNo,
                       "column 1 '" + cells[0] + "' says " + hs + " but strain unit '" +
                           strainUnit + "' was asked for; make them agree");
            if (!stressUnit.empty() && !hp.empty() && hpScale != 0.0 && hpScale != stressScale)
                failAt(name, lineNo,
                       "column 2 '" + cells[1] + "' says " + hp + " but stress unit '" +
                           stressUnit + "' was asked for; make them agree");
            if (stressScale == 0.0)
                failAt(name, lineNo,
                       "column 2 '" + cells[1] +
                           "' gives no stress unit; name it stress_MPa, stress_kPa "
                           "or stress_Pa, or give the unit (--stress-unit)");
            continue;
        }
        if (cells.size() != 2)
            failAt(name, lineNo,
                   "has " + std::to_string(cells.size()) + " cells; expected 2 (" + columns[0] +
                       "," + columns[1] + ")");
        double v[2];
        for (int c = 0; c < 2; ++c) {
            const std::string& cell = cells[c];
            char* end = nullptr;
            v[c] = cell.empty() ? 0.0 : std::strtod(cell.c_str(), &end);
            if (cell.empty() || end != cell.c_str() + cell.size() || !std::isfinite(v[c]))
                failAt(name, lineNo,
                       "column " + std::to_string(c + 1) + " '" + columns[c] + "': '" + cell +
                           "' is not a finite number; valid: a decimal number "
                           "such as 12.5 or 1.2e-3");
        }
        const double strain = v[0] * strainScale;
        if (!(strain > -1.0))
            failAt(name, lineNo,
                   "column 1 '" + columns[0] + "': strain " + cells[0] +
                       " means a stretch <= 0; valid: strain > -100 %");
        data.strain.push_back(strain);
        data.stress.push_back(v[1] * stressScale);
        data.lines.push_back(lineNo);
    }
    if (!haveHeader) throw std::invalid_argument(name + ": no header and no data (empty file?)");
    if (data.strain.empty())
        throw std::invalid_argument(name + ":" + std::to_string(lineNo) +
                                    ": no data rows after the header");
    return data;
}

TensileData readTensileCsv(const std::string& path, const std::string& strainUnit,
                           const std::string& stressUnit) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument(path + ": cannot open the file for reading");
    return parseTensileCsv(in, path, strainUnit, stressUnit);
}

// ---------------------------------------------------------------------------------------------
// Models and constants

std::string getMaterialModelName(MaterialModel model) {
    switch (model) {
        case MaterialModel::NeoHookean:
            return "neo-hookean";
        case MaterialModel::MooneyRivlin:
            return "mooney-rivlin";
        case MaterialModel::Yeoh:
            return "yeoh";
        case MaterialModel::Ogden:
            return "ogden";
    }
    return "?";
}

std::vector<MaterialModel> getMaterialModels() {
    return {MaterialModel::NeoHookean, MaterialModel::MooneyRivlin, MaterialModel::Yeoh,
            MaterialModel::Ogden};
}

MaterialModel parseMaterialModel(const std::string& name) {
    for (MaterialModel m : getMaterialModels())
        if (getMaterialModelName(m) == name) return m;
    throw std::invalid_argument("unknown material model '" + name +
                                "'; valid: neo-hookean, mooney-rivlin, yeoh, ogden");
}

std::vector<std::string> getConstantNames(MaterialModel model, int ogdenTerms) {
    switch (model) {
        case MaterialModel::NeoHookean:
            return {"C10"};
        case MaterialModel::MooneyRivlin:
            return {"C10", "C01"};
        case MaterialModel::Yeoh:
            return {"C10", "C20", "C30"};
        case MaterialModel::Ogden: {
            std::vector<std::string> n;
            for (int i = 1; i <= ogdenTerms; ++i) {
                n.push_back("mu" + std::to_string(i));
                n.push_back("alpha" + std::to_string(i));
            }
            return n;
        }
    }
    return {};
}

bool isStressConstant(const std::string& constantName) {
    return constantName.rfind("alpha", 0) != 0;
}

std::unique_ptr<MembraneMaterial> makeMaterial(MaterialModel model, const std::vector<double>& c) {
    const std::size_t n = c.size();
    auto need = [&](std::size_t k) {
        if (n != k)
            throw std::invalid_argument(getMaterialModelName(model) + " takes " +
                                        std::to_string(k) + " constants, got " + std::to_string(n));
    };
    switch (model) {
        case MaterialModel::NeoHookean:
            need(1);
            return makeNeoHookean(c[0]);
        case MaterialModel::MooneyRivlin:
            need(2);
            return makeMooneyRivlin(c[0], c[1]);
        case MaterialModel::Yeoh:
            need(3);
            return makeYeoh(c[0], c[1], c[2]);
        case MaterialModel::Ogden: {
            if (n == 0 || n % 2 != 0)
                throw std::invalid_argument("ogden takes pairs mu_i, alpha_i; got " +
                                            std::to_string(n) + " constants");
            std::vector<double> mu, alpha;
            for (std::size_t i = 0; i < n; i += 2) {
                mu.push_back(c[i]);
                alpha.push_back(c[i + 1]);
            }
            return makeOgden(mu, alpha);
        }
    }
    throw std::invalid_argument("unknown material model");
}

// ---------------------------------------------------------------------------------------------
// Stability

void MaterialFitOptions::validate() const {
    if (ogdenTerms < 1 || ogdenTerms > 3)
        throw std::invalid_argument("ogdenTerms = " + std::to_string(ogdenTerms) +
                                    "; valid: 1, 2 or 3");
    if (!(ogdenAlphaBound >= 1.0) || !std::isfinite(ogdenAlphaBound))
        throw std::invalid_argument("ogdenAlphaBound = " + std::to_string(ogdenAlphaBound) +
                                    "; valid: a finite value >= 1 (e.g. 20)");
    if (!(stabilityMaxStretch > 1.0) || !std::isfinite(stabilityMaxStretch))
        throw std::invalid_argument("stabilityMaxStretch = " + std::to_string(stabilityMaxStretch) +
                                    "; valid: a finite stretch > 1 (e.g. 3)");
    if (!(stabilityStep > 0.0) || stabilityStep > 0.1 * (stabilityMaxStretch - 1.0))
        throw std::invalid_argument("stabilityStep = " + std::to_string(stabilityStep) +
                                    "; valid: > 0 and at most a tenth of the scanned range");
}

double PathStability::getStable() const { return std::min(drucker, monotone); }

double StabilityRange::getStable() const {
    return std::min({uniaxial.getStable(), planar.getStable(), equibiaxial.getStable()});
}

StabilityRange calcStabilityRange(const MembraneMaterial& material, double maxStretch,
                                  double step) {
    if (!(maxStretch > 1.0) || !(step > 0.0))
        throw std::invalid_argument("calcStabilityRange: need maxStretch > 1 and step > 0");
    StabilityRange range;
    range.maxChecked = maxStretch;
    for (int path = 0; path < 3; ++path) {
        PathStability ps;
        ps.drucker = ps.monotone = maxStretch;
        bool druckerOk = true, monotoneOk = true;
        const int n = static_cast<int>(std::ceil((maxStretch - 1.0) / step - 1e-9));
        double prev = 1.0;
        for (int k = 1; k <= n && (druckerOk || monotoneOk); ++k) {
            const double l = std::min(1.0 + k * step, maxStretch);
            // Path: C = diag(c1, c2); E_v' and E_v'' along it.
            double c2;
            Eigen::Vector3d dE, ddE;
            if (path == 0) {  // uniaxial
                c2 = 1.0 / l;
                dE << l, -0.5 / (l * l), 0.0;
                ddE << 1.0, 1.0 / (l * l * l), 0.0;
            } else if (path == 1) {  // planar
                c2 = 1.0;
                dE << l, 0.0, 0.0;
                ddE << 1.0, 0.0, 0.0;
            } else {  // equibiaxial
                c2 = l * l;
                dE << l, l, 0.0;
                ddE << 1.0, 1.0, 0.0;
            }
            Mat2 C = Mat2::Zero();
            C(0, 0) = l * l;
            C(1, 1) = c2;
            Eigen::Vector3d S;
            Eigen::Matrix3d D;
            material.calcEnergy(C, &S, &D);
            if (druckerOk) {
                // W as a function of the principal log strains: H_ij = D_ij C_i C_j +
                // delta_ij 2 S_i C_i (principal frame, so the Voigt normal block is enough).
                Eigen::Matrix2d H;
                const double Cd[2] = {C(0, 0), C(1, 1)};
                for (int i = 0; i < 2; ++i)
                    for (int j = 0; j < 2; ++j)
                        H(i, j) = D(i, j) * Cd[i] * Cd[j] + (i == j ? 2.0 * S(i) * Cd[i] : 0.0);
                const double hmin =
                    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(H, Eigen::EigenvaluesOnly)
                        .eigenvalues()(0);
                if (!(hmin > 0.0)) {
                    druckerOk = false;
                    ps.drucker = prev;
                }
            }
            if (monotoneOk) {
                const double d2W = dE.dot(D * dE) + S.dot(ddE);
                if (!(d2W > 0.0)) {
                    monotoneOk = false;
                    ps.monotone = prev;
                }
            }
            prev = l;
        }
        (path == 0 ? range.uniaxial : path == 1 ? range.planar : range.equibiaxial) = ps;
    }
    return range;
}

// ---------------------------------------------------------------------------------------------
// Fitting

namespace {

/// Ogden uniaxial basis: P = sum_j mu_j b(l; alpha_j), b = 2/alpha (l^(alpha-1) - l^(-alpha/2-1)).
/// Near alpha = 0 (an exponent may cross zero while the fit runs) the limit is used:
/// b = (3 L + 3/4 alpha L^2) / l + O(alpha^2), L = ln l.
double ogdenBasis(double l, double a) {
    if (std::abs(a) < 1e-7) return (3.0 + 0.75 * a * std::log(l)) * std::log(l) / l;
    return 2.0 / a * (std::pow(l, a - 1.0) - std::pow(l, -0.5 * a - 1.0));
}
double ogdenBasisDa(double l, double a) {
    if (std::abs(a) < 1e-7) return 0.75 * std::log(l) * std::log(l) / l;
    const double u = std::pow(l, a - 1.0), v = std::pow(l, -0.5 * a - 1.0);
    return -2.0 / (a * a) * (u - v) + 2.0 / a * std::log(l) * (u + 0.5 * v);
}

/// Residuals (P_model - P_data) / scale over all points; one parameter block [mu_1..mu_N,
/// alpha_1..alpha_N] with mu in units of `scale`.
class OgdenCost : public ceres::CostFunction {
  public:
    OgdenCost(const std::vector<double>& l, const std::vector<double>& P, int terms)
        : m_l(l), m_P(P), m_terms(terms) {
        set_num_residuals(static_cast<int>(l.size()));
        mutable_parameter_block_sizes()->push_back(2 * terms);
    }
    bool Evaluate(double const* const* x, double* res, double** jac) const override {
        const int N = m_terms, n = static_cast<int>(m_l.size());
        for (int i = 0; i < n; ++i) {
            double P = 0.0;
            for (int j = 0; j < N; ++j) {
                const double b = ogdenBasis(m_l[i], x[0][N + j]);
                P += x[0][j] * b;
                if (jac && jac[0]) {
                    jac[0][i * 2 * N + j] = b;
                    jac[0][i * 2 * N + N + j] = x[0][j] * ogdenBasisDa(m_l[i], x[0][N + j]);
                }
            }
            res[i] = P - m_P[i];
            if (!std::isfinite(res[i])) return false;
        }
        return true;
    }

  private:
    const std::vector<double>& m_l;
    const std::vector<double>& m_P;
    int m_terms;
};

struct OgdenFit {
    std::vector<double> mu, alpha;  // mu in Pa
    double sse = std::numeric_limits<double>::infinity();
    int starts = 0;
};

OgdenFit fitOgden(const std::vector<double>& l, const std::vector<double>& P,
                  const MaterialFitOptions& o) {
    const int N = o.ogdenTerms, n = static_cast<int>(l.size());
    double scale = 0.0;
    for (double v : P) scale = std::max(scale, std::abs(v));
    if (!(scale > 0.0)) scale = 1.0;
    std::vector<double> Ps(P.size());
    for (std::size_t i = 0; i < P.size(); ++i) Ps[i] = P[i] / scale;

    // Starting exponents: every increasing N-tuple from a fixed set within the bound.
    std::vector<double> cand;
    for (double a : {-16.0, -8.0, -4.0, -2.0, -1.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0})
        if (std::abs(a) <= o.ogdenAlphaBound) cand.push_back(a);
    std::vector<std::vector<double>> starts;
    const int K = static_cast<int>(cand.size());
    for (int i = 0; i < K; ++i) {
        if (N == 1) starts.push_back({cand[i]});
        for (int j = i + 1; j < K && N >= 2; ++j) {
            if (N == 2) starts.push_back({cand[i], cand[j]});
            for (int k = j + 1; k < K && N == 3; ++k) starts.push_back({cand[i], cand[j], cand[k]});
        }
    }

    OgdenFit best;
    best.starts = static_cast<int>(starts.size());
    for (const std::vector<double>& a0 : starts) {
        // mu for these exponents by linear least squares, kept >= 0 if the terms must be stable.
        Eigen::MatrixXd A(n, N);
        Eigen::VectorXd b(n);
        for (int i = 0; i < n; ++i) {
            for (int j = 0; j < N; ++j) A(i, j) = ogdenBasis(l[i], a0[j]);
            b(i) = Ps[i];
        }
        const Eigen::VectorXd p0 = A.colPivHouseholderQr().solve(b);
        std::vector<double> x(2 * N);
        for (int j = 0; j < N; ++j) {
            x[j] = std::isfinite(p0(j)) ? p0(j) : 0.1;
            if (o.ogdenStableTerms && x[j] < 1e-6) x[j] = 1e-6;
            x[N + j] = a0[j];
        }
        ceres::Problem::Options po;
        po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
        ceres::Problem problem(po);
        problem.AddResidualBlock(new OgdenCost(l, Ps, N), nullptr, x.data());
        for (int j = 0; j < N; ++j) {
            if (o.ogdenStableTerms) problem.SetParameterLowerBound(x.data(), j, 0.0);
            problem.SetParameterLowerBound(x.data(), N + j, -o.ogdenAlphaBound);
            problem.SetParameterUpperBound(x.data(), N + j, o.ogdenAlphaBound);
        }
        ceres::Solver::Options so;
        so.linear_solver_type = ceres::DENSE_QR;
        so.max_num_iterations = 200;
        so.function_tolerance = 1e-14;
        so.gradient_tolerance = 1e-14;
        so.parameter_tolerance = 1e-12;
        so.logging_type = ceres::SILENT;
        so.minimizer_progress_to_stdout = false;
        so.num_threads = 1;
        ceres::Solver::Summary summary;
        ceres::Solve(so, &problem, &summary);
        if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) continue;
        const double sse = 2.0 * summary.final_cost * scale * scale;
        bool ok = true;
        double mu0 = 0.0;
        for (int j = 0; j < N; ++j) {
            if (x[N + j] == 0.0 || !std::isfinite(x[j])) ok = false;
            mu0 += x[j];
        }
        if (!ok || !(mu0 > 0.0)) continue;
        if (sse < best.sse) {
            best.sse = sse;
            best.mu.assign(x.begin(), x.begin() + N);
            for (double& v : best.mu) v *= scale;
            best.alpha.assign(x.begin() + N, x.end());
        }
    }
    return best;
}

}  // namespace

MaterialFitResult fitMaterial(const TensileData& data, MaterialModel model,
                              const MaterialFitOptions& options) {
    options.validate();
    const std::string src = data.source.empty() ? std::string("tensile data") : data.source;
    if (data.strain.size() != data.stress.size())
        throw std::invalid_argument(src + ": " + std::to_string(data.strain.size()) +
                                    " strains but " + std::to_string(data.stress.size()) +
                                    " stresses");
    MaterialFitResult r;
    r.model = model;
    r.names = getConstantNames(model, options.ogdenTerms);
    const int numConstants = static_cast<int>(r.names.size());
    std::vector<double> l, P;
    int nonzero = 0;
    for (std::size_t i = 0; i < data.strain.size(); ++i) {
        if (!(data.strain[i] > -1.0) || !std::isfinite(data.stress[i]))
            throw std::invalid_argument(src + ": point " + std::to_string(i + 1) +
                                        " has strain <= -100 % or a non-finite stress");
        l.push_back(1.0 + data.strain[i]);
        P.push_back(data.stress[i]);
        if (data.strain[i] != 0.0) ++nonzero;
    }
    if (nonzero < numConstants + 1)
        throw std::invalid_argument(
            src + ": " + std::to_string(nonzero) + " data points with nonzero strain; the " +
            getMaterialModelName(model) + " model has " + std::to_string(numConstants) +
            " constants and needs at least " + std::to_string(numConstants + 1));
    const int n = static_cast<int>(l.size());
    r.numPoints = n;
    r.minStrain = *std::min_element(data.strain.begin(), data.strain.end());
    r.maxStrain = *std::max_element(data.strain.begin(), data.strain.end());

    if (model == MaterialModel::Ogden) {
        const OgdenFit f = fitOgden(l, P, options);
        if (f.mu.empty())
            throw std::invalid_argument(src +
                                        ": no Ogden fit with a positive initial shear "
                                        "modulus was found (is the stress increasing?)");
        r.ogdenStarts = f.starts;
        for (int j = 0; j < options.ogdenTerms; ++j) {
            r.constants.push_back(f.mu[j]);
            r.constants.push_back(f.alpha[j]);
        }
    } else {
        // P = 2 (l - l^-2) (W1 + W2 / l) is linear in the constants.
        Eigen::MatrixXd A(n, numConstants);
        Eigen::VectorXd b(n);
        for (int i = 0; i < n; ++i) {
            const double li = l[i], B = 2.0 * (li - 1.0 / (li * li));
            const double x = li * li + 2.0 / li - 3.0;
            if (model == MaterialModel::NeoHookean) {
                A(i, 0) = B;
            } else if (model == MaterialModel::MooneyRivlin) {
                A(i, 0) = B;
                A(i, 1) = B / li;
            } else {
                A(i, 0) = B;
                A(i, 1) = 2.0 * B * x;
                A(i, 2) = 3.0 * B * x * x;
            }
            b(i) = P[i];
        }
        // Scale the columns to unit norm: the Yeoh columns differ by orders of magnitude.
        Eigen::VectorXd colScale(numConstants);
        for (int j = 0; j < numConstants; ++j) {
            colScale(j) = A.col(j).norm();
            if (!(colScale(j) > 0.0)) colScale(j) = 1.0;
            A.col(j) /= colScale(j);
        }
        const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b).cwiseQuotient(colScale);
        r.constants.assign(c.data(), c.data() + numConstants);
    }

    std::unique_ptr<MembraneMaterial> mat;
    try {
        mat = r.makeMaterial();
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(src + ": the least-squares " + getMaterialModelName(model) +
                                    " fit is not a valid material: " + e.what());
    }
    double mean = 0.0;
    for (double v : P) mean += v;
    mean /= n;
    double sse = 0.0, sst = 0.0;
    for (int i = 0; i < n; ++i) {
        const double e = mat->calcUniaxialNominalStress(l[i]) - P[i];
        sse += e * e;
        sst += (P[i] - mean) * (P[i] - mean);
        r.maxError = std::max(r.maxError, std::abs(e));
    }
    r.rmsError = std::sqrt(sse / n);
    r.r2 = sst > 0.0 ? 1.0 - sse / sst : 1.0;
    r.stability = calcStabilityRange(*mat, options.stabilityMaxStretch, options.stabilityStep);
    return r;
}

std::unique_ptr<MembraneMaterial> MaterialFitResult::makeMaterial() const {
    return bags::makeMaterial(model, constants);
}

double MaterialFitResult::calcStress(double strain) const {
    return makeMaterial()->calcUniaxialNominalStress(1.0 + strain);
}

std::string MaterialFitResult::formatScenarioYaml(const std::string& indent) const {
    std::ostringstream os;
    os << indent << "model: " << getMaterialModelName(model) << "\n";
    if (model == MaterialModel::Ogden) {
        os << indent << "mu: [";
        for (std::size_t i = 0; i < constants.size(); i += 2)
            os << (i ? ", " : "") << formatG(constants[i] * 1e-6, 7) << " MPa";
        os << "]\n" << indent << "alpha: [";
        for (std::size_t i = 1; i < constants.size(); i += 2)
            os << (i > 1 ? ", " : "") << formatG(constants[i], 7);
        os << "]\n";
    } else {
        for (std::size_t i = 0; i < constants.size(); ++i)
            os << indent << names[i] << ": " << formatG(constants[i] * 1e-6, 7) << " MPa\n";
    }
    return os.str();
}

namespace {

/// True if W = C10 x + C20 x^2 + C30 x^3 (x = I1 - 3 >= 0) falls to minus infinity.
bool isYeohEnergyUnbounded(double C20, double C30) {
    return C30 < 0.0 || (C30 == 0.0 && C20 < 0.0);
}

/// The positive root x0 of dW/dI1 = C10 + 2 C20 x + 3 C30 x^2 (C10 > 0) for an unbounded
/// energy (isYeohEnergyUnbounded), in the form free of cancellation.
double calcYeohSlopeRoot(double C10, double C20, double C30) {
    if (C30 == 0.0) return -C10 / (2.0 * C20);
    const double sq = std::sqrt(C20 * C20 - 3.0 * C10 * C30);  // > |C20| since C10 C30 < 0
    return C20 >= 0.0 ? (C20 + sq) / (-3.0 * C30) : C10 / (sq - C20);
}

/// I1 - 3 at the smallest last stable stretch over the three paths of a scan; infinity if
/// every path stays stable up to the scan limit.
double calcLimitFromRange(const StabilityRange& r) {
    double limit = std::numeric_limits<double>::infinity();
    const double lu = r.uniaxial.getStable(), lp = r.planar.getStable(),
                 le = r.equibiaxial.getStable();
    if (lu < r.maxChecked) limit = std::min(limit, lu * lu + 2.0 / lu - 3.0);
    if (lp < r.maxChecked) limit = std::min(limit, lp * lp + 1.0 / (lp * lp) - 2.0);
    if (le < r.maxChecked) limit = std::min(limit, 2.0 * le * le + 1.0 / (le * le * le * le) - 3.0);
    return limit;
}

}  // namespace

double calcYeohStableLimit(double C10, double C20, double C30) {
    const auto raw = makeYeoh(C10, C20, C30);
    double limit = calcLimitFromRange(calcStabilityRange(*raw, 3.0, 1e-3));
    if (!isYeohEnergyUnbounded(C20, C30)) return limit;
    // Unbounded energy: W1 = dW/dI1 falls to zero at x0 and stays negative beyond with
    // W11 < 0, so the equibiaxial nominal stress 4 (l - l^-5) W1 is positive before x0 and
    // decreasing from x0 on; the path's monotone check therefore fails before x0. The path
    // reaches x0 no later than le0 = sqrt((x0 + 3) / 2) (2 l^2 + l^-4 - 3 >= 2 l^2 - 3): scan
    // there if the first scan (to stretch 3) found nothing, with at most 1e5 steps.
    const double x0 = calcYeohSlopeRoot(C10, C20, C30);
    const double le0 = std::sqrt(0.5 * (x0 + 3.0));
    if (std::isinf(limit) && le0 > 3.0)
        limit =
            calcLimitFromRange(calcStabilityRange(*raw, le0, std::max(1e-3, (le0 - 1.0) / 1e5)));
    // Not reached by the argument above; kept so the limit is always finite with W1 > 0.
    if (!(limit < x0)) limit = 0.5 * x0;
    return limit;
}

std::unique_ptr<MembraneMaterial> makeStableYeoh(double C10, double C20, double C30) {
    // A bounded energy keeps its polynomial: a fit unstable only in a middle band (C20 < 0,
    // C30 > 0) stiffens again beyond it, which a continuation from the band would discard.
    if (!isYeohEnergyUnbounded(C20, C30)) return makeYeoh(C10, C20, C30);
    return makeYeoh(C10, C20, C30, calcYeohStableLimit(C10, C20, C30));
}

}  // namespace bags
