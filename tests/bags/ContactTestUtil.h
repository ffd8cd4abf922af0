#pragma once
// Helpers shared by the contact tests: small meshes and dense views of an EnergyAccumulator.

#include <bags/Mesh.h>
#include <bags/Types.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <gtest/gtest.h>

#include <functional>
#include <sstream>
#include <string>

namespace bagstest {

/// Keeps a measured figure in the test's XML report (--gtest_output=xml) for the docs.
inline void recordFigure(const std::string& key, double value) {
    std::ostringstream os;
    os.precision(3);
    os << std::scientific << value;
    std::string name = key;  // XML attribute names: no spaces or dashes
    for (char& ch : name)
        if (ch == ' ' || ch == '-') ch = '_';
    ::testing::Test::RecordProperty(name, os.str());
}

/// nx x ny grid of nodes with spacing s at height z (two triangles per cell, normal +z).
inline bags::Mesh makeGridMesh(int nx, int ny, double s, const bags::Vec3& origin) {
    bags::Mesh m;
    m.X.resize(3, nx * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) m.X.col(j * nx + i) = origin + bags::Vec3(i * s, j * s, 0.0);
    m.tris.resize(3, 2 * (nx - 1) * (ny - 1));
    int t = 0;
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
            m.tris.col(t++) << a, b, d;
            m.tris.col(t++) << a, d, c;
        }
    m.triPanel.assign(m.tris.cols(), 0);
    m.panelNames = {"grid"};
    return m;
}

struct Evaluated {
    double energy = 0.0;
    Eigen::VectorXd grad;
    Eigen::MatrixXd hess;
};

/// Runs `add` on a fresh accumulator and returns energy, gradient and the dense Hessian.
inline Evaluated evaluate(
    const std::function<void(const Eigen::Matrix3Xd&, bags::EnergyAccumulator&)>& add,
    const Eigen::Matrix3Xd& x) {
    const int n = static_cast<int>(x.cols());
    bags::EnergyAccumulator acc(n);
    add(x, acc);
    Eigen::SparseMatrix<double> H(3 * n, 3 * n);
    H.setFromTriplets(acc.hess.begin(), acc.hess.end());
    return Evaluated{acc.energy, acc.grad, Eigen::MatrixXd(H)};
}

/// Central differences of the energy (gradient) and of the gradient (Hessian), step h [m].
inline void finiteDifferences(
    const std::function<void(const Eigen::Matrix3Xd&, bags::EnergyAccumulator&)>& add,
    const Eigen::Matrix3Xd& x, double h, Eigen::VectorXd& gradFd, Eigen::MatrixXd& hessFd) {
    const int n = static_cast<int>(x.cols());
    gradFd.resize(3 * n);
    hessFd.resize(3 * n, 3 * n);
    for (int i = 0; i < 3 * n; ++i) {
        Eigen::Matrix3Xd xp = x, xm = x;
        xp(i % 3, i / 3) += h;
        xm(i % 3, i / 3) -= h;
        const Evaluated ep = evaluate(add, xp), em = evaluate(add, xm);
        gradFd[i] = (ep.energy - em.energy) / (2.0 * h);
        hessFd.col(i) = (ep.grad - em.grad) / (2.0 * h);
    }
}

/// A contact law at x and its central differences with step h [m]: the energy, gradient and
/// Hessian the law assembles (ev) against the differences of its energy and gradient.
struct DifferencedContact {
    Evaluated ev;
    Eigen::VectorXd gradFd;
    Eigen::MatrixXd hessFd;
};
template <class Contact>
DifferencedContact differenceContact(const Contact& contact, const Eigen::Matrix3Xd& x, double h) {
    auto add = [&](const Eigen::Matrix3Xd& xx, bags::EnergyAccumulator& acc) {
        contact.addEnergy(xx, acc);
    };
    DifferencedContact d;
    d.ev = evaluate(add, x);
    finiteDifferences(add, x, h, d.gradFd, d.hessFd);
    return d;
}

}  // namespace bagstest
