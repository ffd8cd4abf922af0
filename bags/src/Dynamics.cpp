#include <bags/Dynamics.h>

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bags {

void DynamicOptions::validate() const {
    auto fail = [](const char* name, double v, const char* valid) {
        std::ostringstream s;
        s << "dynamic option '" << name << "' = " << v << " is invalid; " << valid;
        throw std::invalid_argument(s.str());
    };
    if (!(massScale >= 1.0 && massScale <= 1e12))
        fail("massScale", massScale, "use 1 (the real film) to 1e12 (e.g. 1000)");
    if (!(damping >= 0.0 && std::isfinite(damping)))
        fail("damping", damping, "use a rate >= 0 per second (e.g. 20 /s)");
    if (!(stepFraction > 0.0 && stepFraction <= 1.0))
        fail("stepFraction", stepFraction, "use 0 < fraction <= 1 of the stable step (e.g. 0.5)");
    if (!(relaxSubsteps >= 1 && relaxSubsteps <= 10000000))
        fail("relaxSubsteps", relaxSubsteps, "use 1 to 1e7 sub-steps a step (e.g. 4000)");
    if (!(relaxPace > 0.0 && relaxPace <= 10.0))
        fail("relaxPace", relaxPace, "use a pace > 0 up to 10 m/s (e.g. 0.02 m/s)");
    if (!(newtonPolish >= 0 && newtonPolish <= 1000))
        fail("newtonPolish", newtonPolish, "use 0 (none) to 1000 Newton iterations (e.g. 30)");
}

FilmDynamics::FilmDynamics(const MembraneModel& model, double density,
                           const DynamicOptions& options, double contactPenalty,
                           std::shared_ptr<const MembraneMaterial> tautMaterial)
    : m_model(&model), m_options(options), m_contactPenalty(contactPenalty) {
    options.validate();
    if (tautMaterial) {
        m_taut = std::make_unique<MembraneModel>(model.getMesh(), std::move(tautMaterial),
                                                 model.getThickness());
        m_taut->setWarpAxes(model.getWarpAxis(), model.getWarpFallback());
        if (model.getBendingStiffness() > 0.0)
            m_taut->setBendingStiffness(model.getBendingStiffness());
        m_taut->setNumThreads(model.getNumThreads());
    }
    if (!(density > 0.0))
        throw std::invalid_argument(
            "FilmDynamics: the film needs a density > 0 kg/m^3 to move in time");
    const Mesh& mesh = model.getMesh();
    m_areaDensity = density * model.getThickness() * options.massScale;
    const Eigen::VectorXd area = mesh.calcNodalAreas();
    const int nn = mesh.getNumNodes();
    m_mass.resize(3 * nn);
    for (int i = 0; i < nn; ++i) m_mass.segment<3>(3 * i).setConstant(m_areaDensity * area(i));
    for (int d : model.getFixedDofs()) m_mass(d) = 0.0;
    m_invMass = Eigen::VectorXd::Zero(3 * nn);
    for (int d = 0; d < 3 * nn; ++d)
        if (m_mass(d) > 0.0) m_invMass(d) = 1.0 / m_mass(d);
}

double FilmDynamics::calcStableStep(const Eigen::Matrix3Xd& x) const {
    const int nn = static_cast<int>(x.cols());
    // Gershgorin: every eigenvalue of M^-1 K lies below max_i sum_j |K_ij| / m_i (K assembled,
    // duplicates summed first). K = K_film + K_loads, and |K|'s row sums are at most the
    // terms' row sums added.
    auto rowSums = [&](const std::vector<Triplet>& triplets) {
        Eigen::SparseMatrix<double> K(3 * nn, 3 * nn);
        K.setFromTriplets(triplets.begin(), triplets.end());
        Eigen::VectorXd r = Eigen::VectorXd::Zero(3 * nn);
        for (int k = 0; k < K.outerSize(); ++k)
            for (Eigen::SparseMatrix<double>::InnerIterator it(K, k); it; ++it)
                r(it.row()) += std::abs(it.value());
        return r;
    };
    EnergyAccumulator film(nn), loads(nn);
    m_model->addMembraneEnergy(x, film);
    m_model->addLoadEnergy(x, loads);
    Eigen::VectorXd rowSum = rowSums(film.hess);
    if (m_taut) {
        EnergyAccumulator taut(nn);
        m_taut->addMembraneEnergy(x, taut);
        rowSum = rowSum.cwiseMax(rowSums(taut.hess));
    }
    rowSum += rowSums(loads.hess);
    // The gas bodies' dense terms -dp/dV g g^T: row i sums |dp/dV| |g_i| |g|_1.
    Eigen::VectorXd g;
    for (int b = 0; b < m_model->getNumGases(); ++b) {
        const double V = m_model->calcGasVolume(b, x, &g);
        const double dpdV = std::abs(m_model->getGas(b).calcPressureDerivative(V));
        rowSum += dpdV * g.lpNorm<1>() * g.cwiseAbs();
    }
    double lambda = 0.0;
    for (int d = 0; d < 3 * nn; ++d) lambda = std::max(lambda, rowSum(d) * m_invMass(d));
    // A pressed node's penalty spring, k A_i on a mass rho t S A_i, adds k / (rho t S).
    lambda += m_contactPenalty / m_areaDensity;
    if (!(lambda > 0.0) || !std::isfinite(lambda))
        throw NumericalError("the film's stable step cannot be estimated (no finite stiffness)");
    return 2.0 / std::sqrt(lambda);
}

double FilmDynamics::step(Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v, double h,
                          EnergyAccumulator& acc) const {
    const double r2 = calcForce(x, acc);
    update(x, v, h, acc);
    return r2;
}

double FilmDynamics::calcForce(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    if (!m_force) m_force = std::make_unique<FilmForce>(*m_model);
    acc.wantHessian = false;
    acc.resize(static_cast<int>(x.cols()));
    m_force->addGradient(x, acc);
    const double* g = acc.grad.data();
    const double* im = m_invMass.data();
    double r2 = 0.0;
    for (Eigen::Index d = 0; d < acc.grad.size(); ++d)
        if (im[d] > 0.0) r2 += g[d] * g[d];
    return r2;
}

void FilmDynamics::update(Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& v, double h,
                          const EnergyAccumulator& acc) const {
    const int nn = static_cast<int>(x.cols());
    const double a = 0.5 * m_options.damping * h;
    const double keep = (1.0 - a) / (1.0 + a), push = h / (1.0 + a);
    double* vv = v.data();
    double* xx = x.data();
    const double* g = acc.grad.data();
    const double* im = m_invMass.data();
    for (int d = 0; d < 3 * nn; ++d) {
        vv[d] = im[d] > 0.0 ? keep * vv[d] - push * im[d] * g[d] : 0.0;
        xx[d] += h * vv[d];
    }
}

double FilmDynamics::calcKineticEnergy(const Eigen::Matrix3Xd& v) const {
    const Eigen::Map<const Eigen::VectorXd> vv(v.data(), v.size());
    return 0.5 * vv.cwiseProduct(vv).dot(m_mass);
}

}  // namespace bags
