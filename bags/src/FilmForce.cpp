// The explicit step's force kernel (bags/FilmForce.h). The formulas are the general path's
// (MembraneModel::addMembraneEnergy, WrinklingMaterial, the invariant laws of Material.cpp,
// FabricMaterial, MembraneModel::addBranches, DiscreteBending, calcChamberVolume) written for
// the stress and the force alone; tests/bags/FilmForceTest.cpp holds them equal to roundoff.
#include <bags/FilmForce.h>

#include <bags/Bending.h>
#include <bags/Material.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace bags {

namespace {

// atan(x) for 0 <= x <= 0.66: Moshier's rational approximation (Methods and Programs for
// Mathematical Functions, 1989), within about 1 ulp.
inline double calcAtanReduced(double x) {
    const double z = x * x;
    const double p = ((((-8.750608600031904122785e-01 * z - 1.615753718733365076637e+01) * z -
                        7.500855792314704667340e+01) *
                           z -
                       1.228866684490136173410e+02) *
                          z -
                      6.485021904942025371773e+01);
    const double q = (((((z + 2.485846490142306297962e+01) * z + 1.650270098316988542046e+02) * z +
                        4.328810604912902668951e+02) *
                           z +
                       4.853903996359136964868e+02) *
                          z +
                      1.945506571482613964425e+02);
    return x * (z * p / q) + x;
}

}  // namespace

double calcAtan2(double y, double x) {
    // Reduced to t = min / max of |y|, |x| in [0, 1], then to [0, 0.66] by
    // atan t = pi/4 + atan((t - 1) / (t + 1)); pi/2 and pi carry their low bits.
    constexpr double kPi2Low = 6.123233995736765886130e-17;  // pi/2 - double(pi/2)
    const double ay = std::abs(y), ax = std::abs(x);
    if (ay == 0.0 && ax == 0.0) return 0.0;
    const bool swap = ay > ax;
    const double t = swap ? ax / ay : ay / ax;
    double a = t > 0.66 ? 0.25 * M_PI + (calcAtanReduced((t - 1.0) / (t + 1.0)) + 0.5 * kPi2Low)
                        : calcAtanReduced(t);
    if (swap) a = 0.5 * M_PI - a + kPi2Low;
    if (x < 0.0) a = M_PI - a + 2.0 * kPi2Low;
    return std::copysign(a, y);
}

namespace {

// An InvariantPolynomial with its continuation's constants.
struct Polynomial {
    double C10 = 0.0, C01 = 0.0, C20 = 0.0, C30 = 0.0;
    double limit = std::numeric_limits<double>::infinity();
    double Wc = 0.0, W1c = 0.0, k = 0.0;  // W, dW/dI1 and max(d2W/dI1^2, 0) at the limit

    explicit Polynomial(const InvariantPolynomial& p = InvariantPolynomial())
        : C10(p.C10), C01(p.C01), C20(p.C20), C30(p.C30), limit(p.continuationLimit) {
        if (std::isfinite(limit)) {
            const double x = limit;
            W1c = C10 + 2.0 * C20 * x + 3.0 * C30 * x * x;
            k = std::max(2.0 * C20 + 6.0 * C30 * x, 0.0);
            Wc = x * (C10 + x * (C20 + x * C30));
        }
    }

    // The Voigt stress S [Pa] at c = [C11, C22, C12]; with E, W [J/m^3] into *W.
    template <bool E>
    void stress(double c1, double c2, double c3, double* S, double* W) const {
        const double tr = c1 + c2, J = c1 * c2 - c3 * c3;
        const double iJ = 1.0 / J, iJ2 = iJ * iJ;
        const double x = tr + iJ - 3.0;
        double W1;
        if (x <= limit) {
            W1 = C10 + 2.0 * C20 * x + 3.0 * C30 * x * x;
            if (E) *W = x * (C10 + x * (C20 + x * C30));
        } else {
            const double dx = x - limit;
            W1 = W1c + k * dx;
            if (E) *W = Wc + dx * (W1c + 0.5 * k * dx);
        }
        // dI1/dc = dtr - dJ / J^2, dI2/dc = dJ + dtr / J - tr dJ / J^2, dJ = [c2, c1, -2 c3];
        // S = T (W1 dI1 + W2 dI2), T = diag(2, 2, 1).
        double g1 = W1 * (1.0 - iJ2 * c2), g2 = W1 * (1.0 - iJ2 * c1), g3 = W1 * (2.0 * iJ2 * c3);
        if (C01 != 0.0) {
            const double t = tr * iJ2;
            g1 += C01 * (c2 + iJ - t * c2);
            g2 += C01 * (c1 + iJ - t * c1);
            g3 += C01 * (-2.0 * c3 + 2.0 * t * c3);
            if (E) *W += C01 * (J + tr * iJ - 3.0);
        }
        S[0] = 2.0 * g1;
        S[1] = 2.0 * g2;
        S[2] = g3;
    }
};

}  // namespace

struct FilmForce::Law {
    enum Kind { Generic, Plain, TensionField } kind = Generic;
    const MembraneMaterial* material = nullptr;  // the whole law (Generic, and the branches')
    Polynomial base;                             // Plain: the law; TensionField: its base
    double residual = 0.0;
    bool ownResidual = false;  // the residual term has its own law
    Polynomial residualLaw;
    bool yarns = false;  // fabric yarns on top of the matrix
    double kw = 0.0, kf = 0.0, aw1 = 0.0, aw2 = 0.0, af1 = 0.0, af2 = 0.0;

    explicit Law(const MembraneMaterial& m) : material(&m) {
        const MembraneMaterial* matrix = &m;
        if (const auto* fabric = dynamic_cast<const FabricMaterial*>(&m)) {
            const FabricAnisotropy& y = fabric->getYarns();
            yarns = true;
            kw = y.warpModulus;
            kf = y.weftModulus;
            // As FabricMaterial's addYarn computes them.
            aw1 = std::cos(y.angle);
            aw2 = std::sin(y.angle);
            af1 = std::cos(y.angle + 0.5 * M_PI);
            af2 = std::sin(y.angle + 0.5 * M_PI);
            matrix = &fabric->getMatrix();
        }
        InvariantPolynomial p, r;
        if (const auto* w = dynamic_cast<const WrinklingMaterial*>(matrix)) {
            const bool own = &w->getResidualMaterial() != &w->getBase();
            if (w->getBase().getInvariantPolynomial(&p) &&
                (!own || w->getResidualMaterial().getInvariantPolynomial(&r))) {
                kind = TensionField;
                base = Polynomial(p);
                residual = w->getResidual();
                ownResidual = own;
                if (own) residualLaw = Polynomial(r);
            }
        } else if (matrix->getInvariantPolynomial(&p)) {
            kind = Plain;
            base = Polynomial(p);
        }
        if (kind == Generic) yarns = false;  // the virtual call has them
    }

    // The Voigt stress S at c (det > 0 checked by the caller); with E, W into *W.
    template <bool E>
    void stress(double c1, double c2, double c3, double* S, double* W) const {
        if (kind == Generic) {
            Mat2 C;
            C << c1, c3, c3, c2;
            Eigen::Vector3d Sv;
            const double w = material->calcEnergy(C, &Sv, nullptr);
            if (E) *W = w;
            S[0] = Sv(0), S[1] = Sv(1), S[2] = Sv(2);
            return;
        }
        if (kind == Plain) {
            base.stress<E>(c1, c2, c3, S, W);
        } else {
            tensionField<E>(c1, c2, c3, S, W);
        }
        if (yarns) {
            addYarn<E>(c1, c2, c3, kw, aw1, aw2, S, W);
            addYarn<E>(c1, c2, c3, kf, af1, af2, S, W);
        }
    }

    // Pipkin's relaxed energy of the base plus the residual (Wrinkling.cpp).
    template <bool E>
    void tensionField(double c1, double c2, double c3, double* S, double* W) const {
        const double m = 0.5 * (c1 + c2), h = 0.5 * (c1 - c2);
        const double r = std::sqrt(std::max(h * h + c3 * c3, 0.0));
        const double e1 = m + r, e2 = m - r;
        const bool slack = e1 <= 1.0;
        // Wrinkled: e2 below the natural width e1^-1/2, i.e. e2^2 e1 < 1 (e2 > 0: C is
        // positive definite).
        const bool wrinkled = !slack && e2 * e2 * e1 < 1.0;
        if (!ownResidual && !wrinkled) {
            const double f = (slack ? 0.0 : 1.0) + residual;
            if (f == 0.0) {
                S[0] = S[1] = S[2] = 0.0;
                if (E) *W = 0.0;
                return;
            }
            base.stress<E>(c1, c2, c3, S, W);
            S[0] *= f, S[1] *= f, S[2] *= f;
            if (E) *W *= f;
            return;
        }
        S[0] = S[1] = S[2] = 0.0;
        if (E) *W = 0.0;
        if (wrinkled) {
            // w(e1) = W_base(diag(e1, n(e1))); S = w'(e1) T de1/dc.
            const double n = 1.0 / std::sqrt(e1);  // the natural width
            double Su[3], Wu = 0.0;
            base.stress<E>(e1, n, 0.0, Su, &Wu);
            const double n1 = -0.5 * n / e1;
            const double w1 = 0.5 * Su[0] + 0.5 * n1 * Su[1];
            const double i2r = 1.0 / (2.0 * r);
            S[0] = w1 * 2.0 * (0.5 + h * i2r);
            S[1] = w1 * 2.0 * (0.5 - h * i2r);
            S[2] = w1 * (2.0 * c3 * i2r);
            if (E) *W = Wu;
        } else if (!slack) {
            base.stress<E>(c1, c2, c3, S, W);
        }
        if (residual > 0.0) {
            double Sr[3], Wr = 0.0;
            (ownResidual ? residualLaw : base).stress<E>(c1, c2, c3, Sr, &Wr);
            S[0] += residual * Sr[0], S[1] += residual * Sr[1], S[2] += residual * Sr[2];
            if (E) *W += residual * Wr;
        }
    }

    template <bool E>
    static void addYarn(double c1, double c2, double c3, double k, double a1, double a2, double* S,
                        double* W) {
        if (!(k > 0.0)) return;
        const double Ey = 0.5 * (a1 * a1 * c1 + a2 * a2 * c2 + 2.0 * a1 * a2 * c3 - 1.0);
        if (!(Ey > 0.0)) return;
        S[0] += k * Ey * (a1 * a1);
        S[1] += k * Ey * (a2 * a2);
        S[2] += k * Ey * (a1 * a2);
        if (E) *W += 0.5 * k * Ey * Ey;
    }
};

FilmForce::FilmForce(const MembraneModel& model) : m_model(&model) {
    const Mesh& mesh = model.getMesh();
    const int nt = mesh.getNumTris(), nn = mesh.getNumNodes();
    if (static_cast<int>(model.m_DmInv.size()) != nt ||
        static_cast<int>(model.m_area0.size()) != nt)
        throw std::invalid_argument("FilmForce: the model's element frames are not set");
    m_law = std::make_shared<const Law>(model.getMaterial());

    // Elements and their chambers.
    std::vector<std::vector<std::pair<int, int>>> chambersOf(nt);
    for (int c = 0; c < static_cast<int>(mesh.chambers.size()); ++c)
        for (size_t i = 0; i < mesh.chambers[c].tris.size(); ++i)
            chambersOf[mesh.chambers[c].tris[i]].emplace_back(c, mesh.chambers[c].signs[i]);
    m_elements.resize(nt);
    m_inChamber.assign(nt, 0);
    m_triChamberStart.assign(nt + 1, 0);
    for (int e = 0; e < nt; ++e) {
        Element& el = m_elements[e];
        for (int a = 0; a < 3; ++a) el.n[a] = mesh.tris(a, e);
        const Mat2& DmInv = model.m_DmInv[e];
        el.d1x = DmInv(0, 0), el.d1y = DmInv(0, 1);
        el.d2x = DmInv(1, 0), el.d2y = DmInv(1, 1);
        el.vol = model.m_area0[e] * model.getThickness();
        m_triChamberStart[e] = static_cast<int>(m_triChamber.size());
        for (const auto& cs : chambersOf[e]) {
            m_triChamber.push_back(cs.first);
            m_triChamberSign.push_back(cs.second);
        }
        m_inChamber[e] = chambersOf[e].empty() ? 0 : 1;
    }
    m_triChamberStart[nt] = static_cast<int>(m_triChamber.size());

    // Hinges: nodes, rest angle, wing triangles with their normals' signs, and each
    // triangle's view of the hinges on its edges.
    int nh = 0;
    m_triHinges.assign(nt, TriHinges());
    if (model.m_bending) {
        const DiscreteBending& b = *model.m_bending;
        nh = b.getNumHinges();
        m_hinges.resize(nh);
        std::vector<std::vector<int>> trisOf(nn);
        for (int e = 0; e < nt; ++e)
            for (int a = 0; a < 3; ++a) trisOf[mesh.tris(a, e)].push_back(e);
        auto findTri = [&](int p, int q, int r) {  // the triangle of nodes p, q, r
            for (int t : trisOf[p]) {
                int found = 0;
                for (int a = 0; a < 3; ++a)
                    found += mesh.tris(a, t) == p || mesh.tris(a, t) == q || mesh.tris(a, t) == r;
                if (found == 3) return t;
            }
            throw std::logic_error("FilmForce: a hinge's wing is no triangle of the mesh");
        };
        auto normal = [&](int t) {
            const Vec3 X0 = mesh.X.col(mesh.tris(0, t));
            return Vec3((Vec3(mesh.X.col(mesh.tris(1, t))) - X0)
                            .cross(Vec3(mesh.X.col(mesh.tris(2, t))) - X0));
        };
        for (int h = 0; h < nh; ++h) {
            HingeData& hd = m_hinges[h];
            const std::array<int, 4>& n = b.getHingeNodes(h);
            for (int k = 0; k < 4; ++k) hd.n[k] = n[k];
            hd.cosRest = std::cos(b.getRestAngle(h));
            hd.sinRest = std::sin(b.getRestAngle(h));
            // The hinge's wing normals NA = e x a and NB = b x e (calcHingeAngle) are the
            // wing triangles' own normals, or their opposites.
            const Vec3 X0 = mesh.X.col(n[0]), E = Vec3(mesh.X.col(n[1])) - X0;
            const Vec3 NA = E.cross(Vec3(mesh.X.col(n[2])) - X0);
            const Vec3 NB = (Vec3(mesh.X.col(n[3])) - X0).cross(E);
            for (int w = 0; w < 2; ++w) {
                const int t = findTri(n[0], n[1], n[2 + w]);
                const double sign = normal(t).dot(w == 0 ? NA : NB) > 0.0 ? 1.0 : -1.0;
                hd.tri[w] = t;
                hd.sign[w] = sign;
                int opposite = 0;
                while (mesh.tris(opposite, t) != n[2 + w]) ++opposite;
                TriHinges& th = m_triHinges[t];
                if (th.hinge[opposite] >= 0)
                    throw std::logic_error("FilmForce: a triangle's edge in two hinges");
                th.hinge[opposite] = h;
                th.sign[opposite] = sign;
                th.wing[opposite] = static_cast<unsigned char>(w);
                for (int a = 0; a < 3; ++a) {
                    if (mesh.tris(a, t) == n[0]) th.edge0[opposite] = static_cast<unsigned char>(a);
                    if (mesh.tris(a, t) == n[1]) th.edge1[opposite] = static_cast<unsigned char>(a);
                }
            }
        }
        // The stiffness rows, summed in triplet order, sorted by column.
        std::vector<std::vector<std::pair<int, double>>> rows(nh);
        for (const Triplet& t : b.calcHingeStiffness()) {
            auto& row = rows[t.row()];
            auto it = std::find_if(row.begin(), row.end(), [&](const std::pair<int, double>& p) {
                return p.first == t.col();
            });
            if (it == row.end())
                row.emplace_back(t.col(), t.value());
            else
                it->second += t.value();
        }
        m_couplingStart.assign(1, 0);
        for (auto& row : rows) {
            std::sort(row.begin(), row.end());
            for (const auto& p : row) {
                m_couplingHinge.push_back(p.first);
                m_coupling.push_back(p.second);
            }
            m_couplingStart.push_back(static_cast<int>(m_couplingHinge.size()));
        }
    }

    // The nodes' element slots, in element order.
    m_nodeElemStart.assign(nn + 1, 0);
    for (int e = 0; e < nt; ++e)
        for (int a = 0; a < 3; ++a) ++m_nodeElemStart[m_elements[e].n[a] + 1];
    for (int i = 0; i < nn; ++i) m_nodeElemStart[i + 1] += m_nodeElemStart[i];
    m_nodeElemSlot.resize(3 * nt);
    {
        std::vector<int> fill(m_nodeElemStart.begin(), m_nodeElemStart.end() - 1);
        for (int e = 0; e < nt; ++e)
            for (int a = 0; a < 3; ++a) m_nodeElemSlot[fill[m_elements[e].n[a]]++] = 9 * e + 3 * a;
    }

    m_elemForce.assign(9 * static_cast<size_t>(nt), 0.0);
    m_elemEnergy.assign(nt, 0.0);
    m_volume6.assign(nt, 0.0);
    m_triNormal.assign(3 * static_cast<size_t>(nt), 0.0);
    m_hingeShape.assign(3 * static_cast<size_t>(nh), 0.0);
    m_dtheta.assign(nh, 0.0);
    m_moment.assign(nh, 0.0);
    m_wingScale.assign(nh, 0.0);
    m_chamberCoef.assign(mesh.chambers.size(), 0.0);
}

bool FilmForce::isLawInline() const { return m_law->kind != Law::Generic; }

int FilmForce::getNumThreads() const {
#ifdef _OPENMP
    const MembraneModel& model = *m_model;
    const bool chunked = model.getElementChunks() > 1 ||
                         (model.getElementChunks() == 0 && model.getMesh().getNumTris() > 4000);
    if (!chunked) return 1;
    return model.getNumThreads() > 0 ? model.getNumThreads() : omp_get_max_threads();
#else
    return 1;
#endif
}

void FilmForce::addGradient(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc,
                            bool withEnergy) const {
    if (withEnergy)
        addGradientImpl<true>(x, acc);
    else
        addGradientImpl<false>(x, acc);
}

template <bool E>
void FilmForce::addGradientImpl(const Eigen::Matrix3Xd& x, EnergyAccumulator& acc) const {
    const MembraneModel& model = *m_model;
    const Mesh& mesh = model.getMesh();
    const int nt = static_cast<int>(m_elements.size());
    const int nh = static_cast<int>(m_hinges.size());
    const int nn = mesh.getNumNodes();
    const int nc = static_cast<int>(mesh.chambers.size());
    if (x.cols() != nn)
        throw std::invalid_argument("FilmForce::addGradient: x has " + std::to_string(x.cols()) +
                                    " nodes, the mesh " + std::to_string(nn));
    if (acc.grad.size() == 0) acc.grad.setZero(3 * nn);

    const Law& law = *m_law;
    const bool viscous = model.m_viscous;
    const int nk = viscous ? static_cast<int>(model.m_viscousPhi.size()) : 0;
    const double* phi = viscous ? model.m_viscousPhi.data() : nullptr;
    const double* weight = viscous ? model.m_viscousWeight.data() : nullptr;
    const double* offset = viscous ? model.m_viscousOffset.data() : nullptr;
    bool pressed = false;  // some chamber has a pressure
    for (int c = 0; c < nc; ++c)
        if (model.m_chamberGas[c] >= 0 || model.m_chamberPressure[c] != 0.0) pressed = true;

    const double* X = x.data();
    const Element* elements = m_elements.data();
    const HingeData* hinges = m_hinges.data();
    const TriHinges* triHinges = m_triHinges.data();
    double* elemForce = m_elemForce.data();
    double* elemEnergy = m_elemEnergy.data();
    double* volume6 = m_volume6.data();
    double* triNormal = m_triNormal.data();
    double* hingeShape = m_hingeShape.data();
    double* dtheta = m_dtheta.data();
    double* moment = m_moment.data();
    double* wingScale = m_wingScale.data();
    double* chamberCoef = m_chamberCoef.data();
    double* grad = acc.grad.data();

    int badElement = nt;
    bool badGas = false;
    double gasEnergy = 0.0;
    const int nthreads = getNumThreads();
    // One thread adds each element's slots to the nodes as it finishes them, in element
    // order: the order in which the nodes gather them on several threads (the same bits).
    const bool gather = nthreads > 1;
#pragma omp parallel num_threads(nthreads) if (nthreads > 1)
    {
        // 1. Elements: stress and nodal forces, volume terms, normals.
#pragma omp for schedule(static) reduction(min : badElement)
        for (int e = 0; e < nt; ++e) {
            const Element& el = elements[e];
            const double* x0 = X + 3 * el.n[0];
            const double* x1 = X + 3 * el.n[1];
            const double* x2 = X + 3 * el.n[2];
            double a[3], b[3], f1[3], f2[3];  // edges; the columns of F = sum_a x_a dN_a^T
            for (int i = 0; i < 3; ++i) {
                a[i] = x1[i] - x0[i], b[i] = x2[i] - x0[i];
                f1[i] = a[i] * el.d1x + b[i] * el.d2x;
                f2[i] = a[i] * el.d1y + b[i] * el.d2y;
            }
            double* out = elemForce + 9 * static_cast<size_t>(e);
            double* u = triNormal + 3 * static_cast<size_t>(e);
            if (m_inChamber[e]) {
                const Vec3 y0(x0[0], x0[1], x0[2]), y1(x1[0], x1[1], x1[2]),
                    y2(x2[0], x2[1], x2[2]);
                volume6[e] = y0.dot(y1.cross(y2));
            }
            if (nh > 0) {
                // N / |N|^2, N = (x1 - x0) x (x2 - x0): the hinges' wing terms.
                const double N0 = a[1] * b[2] - a[2] * b[1], N1 = a[2] * b[0] - a[0] * b[2],
                             N2 = a[0] * b[1] - a[1] * b[0];
                const double iN = 1.0 / (N0 * N0 + N1 * N1 + N2 * N2);
                u[0] = N0 * iN, u[1] = N1 * iN, u[2] = N2 * iN;
            }
            const double c1 = f1[0] * f1[0] + f1[1] * f1[1] + f1[2] * f1[2];
            const double c2 = f2[0] * f2[0] + f2[1] * f2[1] + f2[2] * f2[2];
            const double c3 = f1[0] * f2[0] + f1[1] * f2[1] + f1[2] * f2[2];
            if (!(c1 * c2 - c3 * c3 > 1e-12)) {
                badElement = std::min(badElement, e);
                for (int i = 0; i < 9; ++i) out[i] = 0.0;
                u[0] = u[1] = u[2] = 0.0;
                continue;
            }
            double S[3], W = 0.0;
            law.stress<E>(c1, c2, c3, S, &W);
            bool ok = true;
            for (int i = 0; i < nk; ++i) {
                if (!(phi[i] > 0.0)) continue;
                // The branch's elastic strain q = phi E + c, its C = I + 2 q (addBranches).
                const double* c = offset + 3 * (static_cast<size_t>(i) * nt + e);
                const double q1 = phi[i] * (0.5 * (c1 - 1.0)) + c[0];
                const double q2 = phi[i] * (0.5 * (c2 - 1.0)) + c[1];
                const double q3 = phi[i] * (0.5 * c3) + c[2];
                const double b1 = 1.0 + 2.0 * q1, b2 = 1.0 + 2.0 * q2, b3 = 2.0 * q3;
                if (!(b1 * b2 - b3 * b3 > 1e-12)) {
                    ok = false;
                    break;
                }
                double Sb[3], Wb = 0.0;
                law.stress<E>(b1, b2, b3, Sb, &Wb);
                const double wp = weight[i] * phi[i];
                S[0] += wp * Sb[0], S[1] += wp * Sb[1], S[2] += wp * Sb[2];
                if (E) W += weight[i] * Wb;
            }
            if (!ok) {
                badElement = std::min(badElement, e);
                for (int i = 0; i < 9; ++i) out[i] = 0.0;
                continue;
            }
            if (E) elemEnergy[e] = el.vol * W;
            // P = F S (the first Piola stress), node a's force vol P dN_a.
            double p1[3], p2[3];
            for (int i = 0; i < 3; ++i) {
                p1[i] = el.vol * (S[0] * f1[i] + S[2] * f2[i]);
                p2[i] = el.vol * (S[2] * f1[i] + S[1] * f2[i]);
            }
            for (int i = 0; i < 3; ++i) {
                const double g1 = el.d1x * p1[i] + el.d1y * p2[i];
                const double g2 = el.d2x * p1[i] + el.d2y * p2[i];
                out[3 + i] = g1;
                out[6 + i] = g2;
                out[i] = -(g1 + g2);
            }
        }

        // 2. Hinges: the angle's change from rest (calcHingeAngle with the wing normals
        // NA = sign N / |N|^2 |NA|^2: atan2 is blind to their positive scales).
#pragma omp for schedule(static) nowait
        for (int h = 0; h < nh; ++h) {
            const HingeData& hd = hinges[h];
            const double* x0 = X + 3 * hd.n[0];
            const double* x1 = X + 3 * hd.n[1];
            const double* x2 = X + 3 * hd.n[2];
            const double* x3 = X + 3 * hd.n[3];
            const double* uA0 = triNormal + 3 * static_cast<size_t>(hd.tri[0]);
            const double* uB0 = triNormal + 3 * static_cast<size_t>(hd.tri[1]);
            double e[3], uA[3], uB[3];
            for (int i = 0; i < 3; ++i) {
                e[i] = x1[i] - x0[i];
                uA[i] = hd.sign[0] * uA0[i];
                uB[i] = hd.sign[1] * uB0[i];
            }
            const double L2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2], L = std::sqrt(L2);
            const double s = (uA[1] * uB[2] - uA[2] * uB[1]) * e[0] +
                             (uA[2] * uB[0] - uA[0] * uB[2]) * e[1] +
                             (uA[0] * uB[1] - uA[1] * uB[0]) * e[2];
            const double c = L * (uA[0] * uB[0] + uA[1] * uB[1] + uA[2] * uB[2]);
            // The change from rest by the rest angle's rotation: on the branch nearest rest.
            dtheta[h] = calcAtan2(s * hd.cosRest - c * hd.sinRest, c * hd.cosRest + s * hd.sinRest);
            const double iL2 = 1.0 / L2;
            double* shape = hingeShape + 3 * static_cast<size_t>(h);
            shape[0] = L;
            shape[1] =
                ((x2[0] - x0[0]) * e[0] + (x2[1] - x0[1]) * e[1] + (x2[2] - x0[2]) * e[2]) * iL2;
            shape[2] =
                ((x3[0] - x0[0]) * e[0] + (x3[1] - x0[1]) * e[1] + (x3[2] - x0[2]) * e[2]) * iL2;
        }

        // 3. The chambers' volumes in their fixed order, and their pressures.
#pragma omp single
        if (pressed) {
            for (int c = 0; c < nc; ++c) chamberCoef[c] = 0.0;
            auto chamberVolume = [&](int c) {
                const ChamberBoundary& ch = mesh.chambers[c];
                double v6 = 0.0;
                for (size_t i = 0; i < ch.tris.size(); ++i) v6 += ch.signs[i] * volume6[ch.tris[i]];
                return v6 * (1.0 / 6.0);
            };
            for (int c = 0; c < nc; ++c)
                if (model.m_chamberGas[c] < 0 && model.m_chamberPressure[c] != 0.0) {
                    chamberCoef[c] = -model.m_chamberPressure[c] / 6.0;
                    if (E) gasEnergy -= model.m_chamberPressure[c] * chamberVolume(c);
                }
            for (const MembraneModel::GasBody& gb : model.m_gases) {
                double V = 0.0;
                for (int c : gb.chambers) V += chamberVolume(c);
                if (!(V > 0.0)) {
                    badGas = true;
                    continue;
                }
                const double pg = gb.gas.calcGaugePressure(V);
                if (E) gasEnergy -= gb.gas.calcWorkPotential(V);
                for (int c : gb.chambers) chamberCoef[c] = -pg / 6.0;
            }
        }
        // (the single's barrier: every hinge angle is done)

        // 3. Hinges: the moments, and the wings' scale -moment L.
#pragma omp for schedule(static)
        for (int h = 0; h < nh; ++h) {
            double m = 0.0;
            for (int k = m_couplingStart[h]; k < m_couplingStart[h + 1]; ++k)
                m += m_coupling[k] * dtheta[m_couplingHinge[k]];
            moment[h] = m;
            wingScale[h] = -m * hingeShape[3 * static_cast<size_t>(h)];
        }

        // 4. Elements: the pressures' forces (calcChamberVolume's gradient) and the hinges'
        // on their wings: the wing of hinge h in triangle T takes f = -moment L dtheta/dx_far
        // = (-moment L) sign N / |N|^2 at its far node, -(1 - alpha) f and -alpha f at the
        // hinge's x0 and x1.
#pragma omp for schedule(static)
        for (int e = 0; e < nt; ++e) {
            const Element& el = elements[e];
            double* out = elemForce + 9 * static_cast<size_t>(e);
            if (pressed && m_inChamber[e]) {
                double f = 0.0;
                for (int k = m_triChamberStart[e]; k < m_triChamberStart[e + 1]; ++k)
                    f += m_triChamberSign[k] * chamberCoef[m_triChamber[k]];
                const Vec3 y0 = x.col(el.n[0]), y1 = x.col(el.n[1]), y2 = x.col(el.n[2]);
                const Vec3 c0 = y1.cross(y2), c1 = y2.cross(y0), c2 = y0.cross(y1);
                for (int i = 0; i < 3; ++i) {
                    out[i] += f * c0(i);
                    out[3 + i] += f * c1(i);
                    out[6 + i] += f * c2(i);
                }
            }
            if (nh > 0) {
                // Every wing force of the triangle is along its N / |N|^2: sum the vertices'
                // factors first.
                const TriHinges& th = triHinges[e];
                double beta[3] = {0.0, 0.0, 0.0};
                for (int k = 0; k < 3; ++k) {
                    const int h = th.hinge[k];
                    if (h < 0) continue;
                    const double w = wingScale[h] * th.sign[k];
                    const double alpha = hingeShape[3 * static_cast<size_t>(h) + 1 + th.wing[k]];
                    beta[k] += w;
                    beta[th.edge0[k]] -= (1.0 - alpha) * w;
                    beta[th.edge1[k]] -= alpha * w;
                }
                const double* u = triNormal + 3 * static_cast<size_t>(e);
                for (int a = 0; a < 3; ++a)
                    for (int i = 0; i < 3; ++i) out[3 * a + i] += beta[a] * u[i];
            }
            if (!gather)
                for (int a = 0; a < 3; ++a) {
                    double* g = grad + 3 * el.n[a];
                    g[0] += out[3 * a], g[1] += out[3 * a + 1], g[2] += out[3 * a + 2];
                }
        }

        // 5. Nodes: their slots in element order.
        if (gather) {
#pragma omp for schedule(static)
            for (int i = 0; i < nn; ++i) {
                double g0 = grad[3 * i], g1 = grad[3 * i + 1], g2 = grad[3 * i + 2];
                for (int k = m_nodeElemStart[i]; k < m_nodeElemStart[i + 1]; ++k) {
                    const double* f = elemForce + m_nodeElemSlot[k];
                    g0 += f[0], g1 += f[1], g2 += f[2];
                }
                grad[3 * i] = g0, grad[3 * i + 1] = g1, grad[3 * i + 2] = g2;
            }
        }
    }
    if (badElement < nt)
        throw NumericalError(
            "membrane element " + std::to_string(badElement) + " collapsed (det C <= 0)", -1, -1,
            badElement);
    if (badGas) throw NumericalError("gas volume became non-positive");

    double energy = std::numeric_limits<double>::quiet_NaN();
    if (E) {
        energy = gasEnergy;
        for (int e = 0; e < nt; ++e) energy += elemEnergy[e];
        for (int h = 0; h < nh; ++h) energy += 0.5 * dtheta[h] * moment[h];
    }

    // Gravity, stabilisation and the contacts (MembraneModel::addLoadEnergy's).
    const double e0 = acc.energy;
    acc.energy = 0.0;
    if (model.m_density > 0.0 && model.m_gravity.squaredNorm() > 0.0)
        for (int i = 0; i < nn; ++i) {
            if (E) acc.energy -= model.m_nodalMass(i) * model.m_gravity.dot(x.col(i));
            acc.grad.segment<3>(3 * i) -= model.m_nodalMass(i) * model.m_gravity;
        }
    if (model.m_stabilization > 0.0) {
        for (int i = 0; i < nn; ++i) {
            const double k =
                model.m_stabilization * model.m_nodalArea(i) *
                (model.m_stabilizationWeight.empty() ? 1.0 : model.m_stabilizationWeight[i]);
            if (k == 0.0) continue;
            const Vec3 d = x.col(i) - model.m_anchor.col(i);
            if (E) acc.energy += 0.5 * k * d.squaredNorm();
            acc.grad.segment<3>(3 * i) += k * d;
        }
    }
    const bool wantG = acc.wantGradient, wantH = acc.wantHessian;
    acc.wantGradient = true;
    acc.wantHessian = false;
    for (const auto& c : model.m_contacts) c->addEnergy(x, acc);
    if (model.m_selfContact) model.m_selfContact->addEnergy(x, acc);
    acc.wantGradient = wantG;
    acc.wantHessian = wantH;
    acc.energy = E ? e0 + energy + acc.energy : energy;
}

}  // namespace bags
