#include "cosim/FilmSection.h"

#include <Eigen/SparseCholesky>

#include <cmath>
#include <stdexcept>
#include <string>

namespace cosim {

namespace {
constexpr int kMaxIterations = 1000;
}  // namespace

void FilmSectionSpec::validate() const {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("FilmSectionSpec: " + what);
    };
    const double chord = (b - a).norm();
    if (!(chord > 0.0)) fail("the anchors a and b must differ");
    if (!(restLength > chord)) fail("restLength must exceed the anchors' distance");
    if (!(stiffness > 0.0)) fail("stiffness (EA) must be > 0");
    if (segments < 4 || segments > 10000) fail("segments must be 4 to 10000");
    if (!(contactPenalty > 0.0)) fail("contactPenalty must be > 0");
}

FilmSection::FilmSection(const FilmSectionSpec& spec) : m_spec(spec) {
    m_spec.validate();
    const int n = m_spec.segments;
    m_l0 = m_spec.restLength / n;
    // The arc of the rest length through a and b: sin(t) / t = chord / length for its half
    // angle t in (0, pi) (bisection), radius chord / (2 sin t).
    const Eigen::Vector2d d = m_spec.b - m_spec.a;
    const double c = d.norm(), ratio = c / m_spec.restLength;
    double lo = 1e-12, hi = M_PI - 1e-12;
    for (int it = 0; it < 200; ++it) {
        const double t = 0.5 * (lo + hi);
        (std::sin(t) / t > ratio ? lo : hi) = t;
    }
    const double theta = 0.5 * (lo + hi), R = c / (2.0 * std::sin(theta));
    const Eigen::Vector2d e = d / c, up(-e.y(), e.x());
    const Eigen::Vector2d centre = 0.5 * (m_spec.a + m_spec.b) - R * std::cos(theta) * up;
    m_x.resize(2, n + 1);
    for (int i = 0; i <= n; ++i) {
        const double phi = -theta + 2.0 * theta * i / n;
        m_x.col(i) = centre + R * (std::sin(phi) * e + std::cos(phi) * up);
    }
    m_x.col(0) = m_spec.a;
    m_x.col(n) = m_spec.b;
}

void FilmSection::addObstacle(Obstacle obstacle) { m_obstacles.push_back(std::move(obstacle)); }

Eigen::VectorXd FilmSection::getFreeCoordinates() const {
    const int n = m_spec.segments;
    Eigen::VectorXd q(2 * (n - 1));
    for (int i = 1; i < n; ++i) q.segment<2>(2 * (i - 1)) = m_x.col(i);
    return q;
}

Eigen::Matrix2Xd FilmSection::nodesOf(const Eigen::VectorXd& q) const {
    Eigen::Matrix2Xd x = m_x;
    for (int i = 1; i < m_spec.segments; ++i) x.col(i) = q.segment<2>(2 * (i - 1));
    return x;
}

double FilmSection::calcEnergy(const Eigen::VectorXd& q, double P, Eigen::VectorXd* g,
                               Eigen::MatrixXd* H) const {
    const int n = m_spec.segments, dofs = 2 * (n - 1);
    const Eigen::Matrix2Xd x = nodesOf(q);
    const double EA = m_spec.stiffness, k = m_spec.contactPenalty;
    if (g) g->setZero(dofs);
    if (H) H->setZero(dofs, dofs);
    auto dof = [](int node) { return 2 * (node - 1); };  // the first of a free node's two
    auto free = [n](int node) { return node > 0 && node < n; };
    double energy = 0.0;
    // The segments: EA (l - l0)^2 / (2 l0); d/dd = T u, d2/dd2 = EA / l0 u u^T + T / l (I - u u^T).
    for (int s = 0; s < n; ++s) {
        const Eigen::Vector2d d = x.col(s + 1) - x.col(s);
        const double l = d.norm(), T = EA * (l - m_l0) / m_l0;
        energy += 0.5 * EA * (l - m_l0) * (l - m_l0) / m_l0;
        const Eigen::Vector2d u = d / l;
        const Eigen::Vector2d f = T * u;
        const Eigen::Matrix2d K = EA / m_l0 * u * u.transpose() +
                                  T / l * (Eigen::Matrix2d::Identity() - u * u.transpose());
        const int ends[2] = {s, s + 1};
        const double sign[2] = {-1.0, 1.0};
        for (int p = 0; p < 2; ++p) {
            if (!free(ends[p])) continue;
            if (g) g->segment<2>(dof(ends[p])) += sign[p] * f;
            if (H)
                for (int r = 0; r < 2; ++r)
                    if (free(ends[r]))
                        H->block<2, 2>(dof(ends[p]), dof(ends[r])) += sign[p] * sign[r] * K;
        }
    }
    // The gas: -P A, A = -1/2 sum (y_i z_{i+1} - y_{i+1} z_i) over the closed polygon.
    double area = 0.0;
    for (int i = 0; i <= n; ++i) {
        const int j = i == n ? 0 : i + 1;
        area -= 0.5 * (x(0, i) * x(1, j) - x(0, j) * x(1, i));
    }
    energy -= P * area;
    for (int i = 1; i < n; ++i) {
        if (g) {
            (*g)[dof(i)] -= P * -0.5 * (x(1, i + 1) - x(1, i - 1));
            (*g)[dof(i) + 1] -= P * 0.5 * (x(0, i + 1) - x(0, i - 1));
        }
        if (H) {  // d2A/dy_i dz_{i+1} = -1/2, d2A/dy_i dz_{i-1} = +1/2 (and symmetric)
            if (free(i + 1)) {
                (*H)(dof(i), dof(i + 1) + 1) -= P * -0.5;
                (*H)(dof(i + 1) + 1, dof(i)) -= P * -0.5;
            }
            if (free(i - 1)) {
                (*H)(dof(i), dof(i - 1) + 1) -= P * 0.5;
                (*H)(dof(i - 1) + 1, dof(i)) -= P * 0.5;
            }
        }
    }
    // Contact: k w pen^2 / 2 per node and obstacle (and the board), w the rest tributary length.
    for (int i = 1; i < n; ++i) {
        const Eigen::Vector2d p = x.col(i);
        auto add = [&](double pen, const Eigen::Vector2d& dpen, const Eigen::Matrix2d& ddpen) {
            if (!(pen > 0.0)) return;
            double f1 = 0.0, f2 = 0.0;
            energy += k * m_l0 * calcContactLaw(pen, &f1, &f2);
            if (g) g->segment<2>(dof(i)) += k * m_l0 * f1 * dpen;
            if (H)
                H->block<2, 2>(dof(i), dof(i)) +=
                    k * m_l0 * (f2 * dpen * dpen.transpose() + f1 * ddpen);
        };
        for (const Obstacle& o : m_obstacles) {
            Eigen::Vector2d nrm;
            Eigen::Matrix2d dndp;
            const double phi = o(p, &nrm, &dndp);
            add(-phi, -nrm, -dndp);
        }
        // (p = (y, z): p.y() is the height z)
        if (m_spec.board) add(-p.y(), Eigen::Vector2d(0.0, -1.0), Eigen::Matrix2d::Zero());
    }
    return energy;
}

double FilmSection::calcContactLaw(double pen, double* d1, double* d2) {
    // Per unit penalty: e'' = min(pen / eps, 1), so that Newton's model does not jump where a
    // node touches: e = pen^3 / (6 eps) up to eps, then pen^2 / 2 - eps pen / 2 + eps^2 / 6.
    constexpr double eps = kContactRounding;
    if (pen <= eps) {
        if (d1) *d1 = pen * pen / (2.0 * eps);
        if (d2) *d2 = pen / eps;
        return pen * pen * pen / (6.0 * eps);
    }
    if (d1) *d1 = pen - 0.5 * eps;
    if (d2) *d2 = 1.0;
    return 0.5 * pen * pen - 0.5 * eps * pen + eps * eps / 6.0;
}

int FilmSection::solve(double P) {
    if (!(P > 0.0)) throw std::invalid_argument("FilmSection::solve: pressure must be > 0");
    Eigen::VectorXd q = getFreeCoordinates(), g;
    Eigen::MatrixXd H;
    // (converged when every node's force is within 1e-6 of the gas's force on a segment,
    // P l0: the contact's kinks keep Newton from going much below that in roundoff)
    const double tol = 1e-6 * P * m_l0;
    for (int it = 0; it < kMaxIterations; ++it) {
        const double e = calcEnergy(q, P, &g, &H);
        if (g.lpNorm<Eigen::Infinity>() < tol) {
            m_x = nodesOf(q);
            return it;
        }
        // Newton's step, shifted towards steepest descent where H is not positive definite.
        Eigen::VectorXd step;
        double shift = 0.0;
        const double scale = H.diagonal().cwiseAbs().maxCoeff();
        // (H is banded: each node couples with its neighbours only)
        const Eigen::SparseMatrix<double> Hs = H.sparseView();
        Eigen::SparseMatrix<double> I(H.rows(), H.cols());
        I.setIdentity();
        for (int k = 0; k < 30; ++k) {
            Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(Hs + shift * I);
            if (llt.info() == Eigen::Success) {
                step = llt.solve(-g);
                if (step.allFinite() && g.dot(step) < 0.0) break;
                step.resize(0);
            }
            shift = shift == 0.0 ? 1e-8 * scale : 10.0 * shift;
        }
        if (step.size() == 0) throw std::runtime_error("FilmSection::solve: no descent step");
        double t = 1.0;
        const double slope = g.dot(step);
        for (int k = 0; k < 40; ++k, t *= 0.5)
            if (calcEnergy(q + t * step, P, nullptr, nullptr) <= e + 1e-4 * t * slope) break;
        q += t * step;
    }
    throw std::runtime_error("FilmSection::solve: no convergence in " +
                             std::to_string(kMaxIterations) + " Newton iterations");
}

double FilmSection::calcArea() const {
    const int n = m_spec.segments;
    double area = 0.0;
    for (int i = 0; i <= n; ++i) {
        const int j = i == n ? 0 : i + 1;
        area -= 0.5 * (m_x(0, i) * m_x(1, j) - m_x(0, j) * m_x(1, i));
    }
    return area;
}

double FilmSection::calcLength() const {
    double l = 0.0;
    for (int s = 0; s < m_spec.segments; ++s) l += (m_x.col(s + 1) - m_x.col(s)).norm();
    return l;
}

Eigen::VectorXd FilmSection::calcTensions() const {
    Eigen::VectorXd T(m_spec.segments);
    for (int s = 0; s < m_spec.segments; ++s)
        T[s] = m_spec.stiffness * ((m_x.col(s + 1) - m_x.col(s)).norm() - m_l0) / m_l0;
    return T;
}

Eigen::VectorXd FilmSection::calcContactPressures() const {
    const int n = m_spec.segments;
    Eigen::VectorXd q = Eigen::VectorXd::Zero(n + 1);
    for (int i = 1; i < n; ++i) {
        const Eigen::Vector2d p = m_x.col(i);
        double f = 0.0;  // the penalty's force over the rest tributary length
        auto add = [&](double pen) {
            double f1 = 0.0;
            if (pen > 0.0) calcContactLaw(pen, &f1, nullptr);
            f += m_spec.contactPenalty * f1;
        };
        for (const Obstacle& o : m_obstacles) add(-o(p, nullptr, nullptr));
        if (m_spec.board) add(-p.y());
        // per length of the stretched film
        const double w = 0.5 * ((m_x.col(i + 1) - p).norm() + (p - m_x.col(i - 1)).norm());
        q[i] = f * m_l0 / w;
    }
    return q;
}

}  // namespace cosim
