#include "cosim/PressureMat.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cosim {

void PressureMatOptions::validate() const {
    auto fail = [](const std::string& key, const std::string& what) {
        throw std::invalid_argument("PressureMatOptions: " + key + " " + what);
    };
    if (rows < 1) fail("rows", "= " + std::to_string(rows) + "; valid: 1 or more");
    if (columns < 1) fail("columns", "= " + std::to_string(columns) + "; valid: 1 or more");
    if (!origin.allFinite()) fail("origin", "is not finite; valid: a bed point [m]");
    if (!(size.x() > 0.0 && size.y() > 0.0) || !size.allFinite()) {
        std::ostringstream s;
        s << "= (" << size.x() << ", " << size.y() << ") m; valid: positive extents";
        fail("size", s.str());
    }
}

PressureMat::PressureMat(const PressureMatOptions& options) : m_options(options) {
    options.validate();
    m_pressure = Eigen::MatrixXd::Zero(options.rows, options.columns);
}

void PressureMat::clear() {
    m_pressure.setZero();
    m_offMat = 0.0;
}

double PressureMat::getSenselArea() const {
    return m_options.size.x() / m_options.rows * (m_options.size.y() / m_options.columns);
}

double PressureMat::calcTotalForce() const { return m_pressure.sum() * getSenselArea(); }

void PressureMat::addNodalPressures(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& pressure,
                                    const Eigen::VectorXd& nodalArea) {
    if (pressure.size() != x.cols() || nodalArea.size() != x.cols()) {
        std::ostringstream s;
        s << "PressureMat::addNodalPressures: " << x.cols() << " nodes, " << pressure.size()
          << " pressures, " << nodalArea.size() << " areas; valid: one of each per node";
        throw std::invalid_argument(s.str());
    }
    const PressureMatOptions& o = m_options;
    const double px = o.size.x() / o.rows, py = o.size.y() / o.columns;
    const double toPressure = 1.0 / (px * py);
    // Bilinear weights along one axis between sensel centres; clamped beyond the outer ones.
    auto split = [](double u, int n, int& i0, int& i1, double& w1) {
        const double s = u - 0.5;  // in sensel pitches from the first centre
        if (s <= 0.0) {
            i0 = i1 = 0;
            w1 = 0.0;
        } else if (s >= n - 1) {
            i0 = i1 = n - 1;
            w1 = 0.0;
        } else {
            i0 = std::min(int(std::floor(s)), n - 2);
            i1 = i0 + 1;
            w1 = s - i0;
        }
    };
    for (int i = 0; i < x.cols(); ++i) {
        const double f = pressure(i) * nodalArea(i);
        if (f == 0.0) continue;
        const double u = (x(0, i) - o.origin.x()) / px, v = (x(1, i) - o.origin.y()) / py;
        if (!(u >= 0.0 && u <= o.rows && v >= 0.0 && v <= o.columns)) {
            m_offMat += f;
            continue;
        }
        int r0, r1, c0, c1;
        double wr, wc;
        split(u, o.rows, r0, r1, wr);
        split(v, o.columns, c0, c1, wc);
        const double p = f * toPressure;
        m_pressure(r0, c0) += p * (1 - wr) * (1 - wc);
        m_pressure(r1, c0) += p * wr * (1 - wc);
        m_pressure(r0, c1) += p * (1 - wr) * wc;
        m_pressure(r1, c1) += p * wr * wc;
    }
}

}  // namespace cosim
