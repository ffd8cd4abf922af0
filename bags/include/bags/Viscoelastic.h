#pragma once
/// @file Viscoelasticity of the film: a Prony series on the membrane's stress, as Maxwell
/// branches (the generalised Maxwell model).
///
/// The film's material W_L (the tension-field material, whose constants are the *long-term*,
/// relaxed law: a slow tensile test's) carries the equilibrium stress; beside it, per Prony
/// term i and element, a Maxwell branch: a film of the same law scaled by k_i = g_i / g_inf
/// (g_inf = 1 - sum g_i) whose elastic Green strain q_i relaxes through a linear dashpot,
///
///   S = S_L(C) + sum_i k_i S_L(I + 2 q_i),    dq_i/dt = dE/dt - q_i / tau_i.
///
/// For a linear (small-strain) film this is the Prony series: relative to the instantaneous
/// modulus (1 + sum k_i = 1 / g_inf times the long-term one) the relaxation function is
/// G(t) = g_inf + sum g_i exp(-t / tau_i) (the Abaqus convention of relative moduli g_i, with
/// the hyperelastic constants given as long-term moduli). For the nonlinear Yeoh it holds to
/// first order in the branch strain.
///
/// Each branch is a film too: its law is the tension-field law, so it carries no compression.
/// A branch strained in compression (the film unloaded faster than it relaxes) wrinkles, as
/// the film would, instead of pushing: the total stress stays a sum of tension fields and a
/// slack film stays solvable. (A Prony series added to the stress instead, S_L + sum H_i with
/// H_i the convolution of S_L, would put the film in compression when it is unloaded fast, with
/// no stiffness to carry it: on the rig's bag the top film then buckled under the block.)
///
/// Over a step of dt with E linear in time (the exponential integrator, exact for a constant
/// strain rate): q_i(end) = exp(-dt / tau_i) q_i(n) + phi_i (E(end) - E(n)),
/// phi(x) = (1 - exp(-x)) / x, x = dt / tau_i. With the history fixed over the step, q_i is
/// linear in the end strain and the step's energy
///
///   W_L(C) + sum_i (k_i / phi_i) W_L(I + 2 q_i(C))
///
/// has the stress above and the symmetric tangent D_L(C) + sum k_i phi_i D_L(I + 2 q_i): every
/// step is the minimisation of one energy (MembraneModel). dt -> infinity (a quasi-static
/// change) leaves the long-term law with the branches relaxed; dt = 0 the instantaneous one.
/// docs/materials.md#viscoelasticity.

#include <string>
#include <vector>

namespace bags {

struct PronyTerm {
    double g = 0.0;    ///< relative modulus g_i [-] (of the instantaneous modulus)
    double tau = 1.0;  ///< relaxation time [s]
};

/// The film's Prony series (empty: elastic, the model as it was).
struct PronySeries {
    std::vector<PronyTerm> terms;

    static constexpr int kMaxTerms = 8;
    static constexpr double kMaxSum = 0.95;  ///< sum g_i at most (1 / g_inf <= 20)
    static constexpr double kMinTau = 1e-3;  ///< [s]
    static constexpr double kMaxTau = 1e7;   ///< [s] (about four months)

    /// True when a term has g > 0 (terms of g = 0 change nothing and are not evaluated).
    bool isOn() const;
    /// g_inf = 1 - sum g_i [-].
    double getLongTermFraction() const;
    /// Throws std::invalid_argument naming the term and the valid range: 0 <= g_i < 1,
    /// sum g_i <= kMaxSum, kMinTau <= tau_i <= kMaxTau, at most kMaxTerms terms.
    void validate() const;
    /// 1 + sum k_i phi(dt / tau_i): the small-strain stiffness of a step of dt [s] relative to
    /// the long-term law (dt = 0: 1 / g_inf; dt = +inf: 1).
    double calcStepScale(double dt) const;
    /// The relaxation function G(t) / G(0) = g_inf + sum g_i exp(-t / tau_i).
    double calcRelaxation(double t) const;
    /// "g 0.1, tau 20 s; ..." for messages and labels.
    std::string describe() const;
};

/// phi(x) = (1 - exp(-x)) / x, 1 at x = 0 (series below 1e-8), 0 at x = +inf.
double calcPronyPhi(double x);

}  // namespace bags
