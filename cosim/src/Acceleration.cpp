#include "cosim/Acceleration.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cosim {

namespace {

void checkOmega(const char* who, double omega) {
    if (!(omega > 0.0 && omega <= 1.0)) {
        std::ostringstream s;
        s << who << ": relaxation " << omega << "; valid: 0 < relaxation <= 1";
        throw std::invalid_argument(s.str());
    }
}

void checkSizes(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) {
    if (x.size() != Hx.size())
        throw std::invalid_argument("Accelerator: x and H(x) differ in size");
}

}  // namespace

ConstantRelaxation::ConstantRelaxation(double omega) : m_omega(omega) {
    checkOmega("ConstantRelaxation", omega);
}

Eigen::VectorXd ConstantRelaxation::next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) {
    checkSizes(x, Hx);
    return x + m_omega * (Hx - x);
}

AitkenRelaxation::AitkenRelaxation(double initialOmega)
    : m_initial(initialOmega), m_omega(initialOmega) {
    checkOmega("AitkenRelaxation", initialOmega);
}

void AitkenRelaxation::beginStep() {
    m_havePrev = false;
    m_omega = m_initial;
}

Eigen::VectorXd AitkenRelaxation::next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) {
    checkSizes(x, Hx);
    const Eigen::VectorXd r = Hx - x;
    if (m_havePrev) {
        const Eigen::VectorXd dr = r - m_rPrev;
        const double den = dr.squaredNorm();
        // Two equal residuals: the secant says nothing; keep the last factor.
        if (den > 0.0) m_omega = -m_omega * m_rPrev.dot(dr) / den;
    }
    m_rPrev = r;
    m_havePrev = true;
    return x + m_omega * r;
}

IQNILS::IQNILS(double initialOmega, int reuseSteps, double filter)
    : m_initial(initialOmega), m_reuse(reuseSteps), m_filter(filter) {
    checkOmega("IQNILS", initialOmega);
    if (reuseSteps < 0)
        throw std::invalid_argument("IQNILS: reuseSteps = " + std::to_string(reuseSteps) +
                                    "; valid: 0 or more");
    if (!(filter >= 0.0 && filter < 1.0)) {
        std::ostringstream s;
        s << "IQNILS: filter = " << filter << "; valid: 0 <= filter < 1";
        throw std::invalid_argument(s.str());
    }
}

void IQNILS::beginStep() {
    m_havePrev = false;
    m_V.clear();
    m_W.clear();
}

void IQNILS::endStep() {
    if (m_reuse > 0 && !m_V.empty()) {
        m_old.emplace_front(m_V, m_W);
        while (int(m_old.size()) > m_reuse) m_old.pop_back();
    }
    m_V.clear();
    m_W.clear();
    m_havePrev = false;
}

Eigen::VectorXd IQNILS::next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) {
    checkSizes(x, Hx);
    const Eigen::VectorXd r = Hx - x;
    if (m_havePrev) {
        m_V.push_back(r - m_rPrev);
        m_W.push_back(Hx - m_HxPrev);
    }
    m_rPrev = r;
    m_HxPrev = Hx;
    m_havePrev = true;

    // Columns newest first: this step's, then the reused steps' (newest step first).
    std::vector<const Eigen::VectorXd*> V, W;
    for (int i = int(m_V.size()) - 1; i >= 0; --i) {
        V.push_back(&m_V[i]);
        W.push_back(&m_W[i]);
    }
    for (const auto& step : m_old)
        for (int i = int(step.first.size()) - 1; i >= 0; --i) {
            if (step.first[i].size() != r.size()) continue;
            V.push_back(&step.first[i]);
            W.push_back(&step.second[i]);
        }

    // Modified Gram-Schmidt (twice) of V, newest first, dropping dependent columns: V_kept =
    // Q R with R upper triangular.
    const int n = int(r.size());
    std::vector<Eigen::VectorXd> Q;
    std::vector<int> kept;
    Eigen::MatrixXd R = Eigen::MatrixXd::Zero(std::min<int>(V.size(), n), V.size());
    for (int j = 0; j < int(V.size()) && int(Q.size()) < n; ++j) {
        Eigen::VectorXd v = *V[j];
        const double norm0 = v.norm();
        if (!(norm0 > 0.0)) continue;
        Eigen::VectorXd coef = Eigen::VectorXd::Zero(Q.size());
        for (int pass = 0; pass < 2; ++pass)
            for (int q = 0; q < int(Q.size()); ++q) {
                const double c = Q[q].dot(v);
                coef(q) += c;
                v -= c * Q[q];
            }
        const double rest = v.norm();
        if (rest <= m_filter * norm0) continue;
        const int k = int(Q.size());
        for (int q = 0; q < k; ++q) R(q, k) = coef(q);
        R(k, k) = rest;
        Q.push_back(v / rest);
        kept.push_back(j);
    }
    m_used = int(kept.size());
    if (kept.empty()) return x + m_initial * r;
    const int m = int(kept.size());
    Eigen::VectorXd rhs(m);
    for (int q = 0; q < m; ++q) rhs(q) = -Q[q].dot(r);
    const Eigen::VectorXd alpha = R.topLeftCorner(m, m).triangularView<Eigen::Upper>().solve(rhs);
    Eigen::VectorXd out = Hx;
    for (int q = 0; q < m; ++q) out += alpha(q) * *W[kept[q]];
    return out;
}

void IQNILS::saveState(bags::StateWriter& w) const {
    w.tag("iqn-ils");
    w.pod(std::uint64_t(m_old.size()));
    for (const auto& step : m_old) {
        for (const std::vector<Eigen::VectorXd>* cols : {&step.first, &step.second}) {
            w.pod(std::uint64_t(cols->size()));
            for (const Eigen::VectorXd& c : *cols) w.mat(c);
        }
    }
}

void IQNILS::loadState(bags::StateReader& r) {
    r.tag("iqn-ils");
    m_old.clear();
    const auto n = r.pod<std::uint64_t>();
    for (std::uint64_t k = 0; k < n; ++k) {
        std::pair<std::vector<Eigen::VectorXd>, std::vector<Eigen::VectorXd>> step;
        for (std::vector<Eigen::VectorXd>* cols : {&step.first, &step.second}) {
            cols->resize(r.pod<std::uint64_t>());
            for (Eigen::VectorXd& c : *cols) r.mat(c);
        }
        m_old.push_back(std::move(step));
    }
    m_V.clear();
    m_W.clear();
    m_havePrev = false;
}

}  // namespace cosim
