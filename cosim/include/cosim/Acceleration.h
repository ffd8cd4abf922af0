#pragma once
/// @file Fixed-point accelerations of an implicit coupling: given the interface data x_k an
/// iteration started from and what the participants returned for it, H(x_k), propose
/// x_{k+1}. The residual is r_k = H(x_k) - x_k.
///
/// Order of calls per macro step: beginStep(); next() once per iteration that did not
/// converge; endStep() once the step has converged (an IQN-ILS keeps that step's secant
/// information for later steps when asked to).

#include <bags/StateStream.h>

#include <Eigen/Core>
#include <deque>
#include <memory>
#include <vector>

namespace cosim {

class Accelerator {
  public:
    virtual ~Accelerator() = default;
    virtual void beginStep() = 0;  ///< a new macro step starts
    /// x_{k+1} from x_k and H(x_k) (same size every call within a step).
    virtual Eigen::VectorXd next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) = 0;
    virtual void endStep() = 0;  ///< the step has converged
    /// What it keeps from earlier steps, into a checkpoint (between steps); default: nothing.
    virtual void saveState(bags::StateWriter& w) const { w.tag("accelerator"); }
    virtual void loadState(bags::StateReader& r) { r.tag("accelerator"); }
};

/// x_{k+1} = x_k + omega r_k.
class ConstantRelaxation : public Accelerator {
  public:
    explicit ConstantRelaxation(
        double omega);  ///< @throws std::invalid_argument unless 0 < omega <= 1
    void beginStep() override {}
    Eigen::VectorXd next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) override;
    void endStep() override {}

  private:
    double m_omega;
};

/// Aitken's dynamic relaxation (the vector form of Irons and Tuck): x_{k+1} = x_k + w_k r_k,
/// w_0 = initial relaxation at each step's start, w_k = -w_{k-1} r_{k-1}.(r_k - r_{k-1}) /
/// |r_k - r_{k-1}|^2.
class AitkenRelaxation : public Accelerator {
  public:
    explicit AitkenRelaxation(
        double initialOmega);  ///< @throws std::invalid_argument unless 0 < w <= 1
    void beginStep() override;
    Eigen::VectorXd next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) override;
    void endStep() override {}
    double getOmega() const { return m_omega; }  ///< the last relaxation factor used
  private:
    double m_initial, m_omega;
    Eigen::VectorXd m_rPrev;
    bool m_havePrev = false;
};

/// Interface quasi-Newton with an inverse Jacobian from a least-squares fit (IQN-ILS; Degroote
/// et al. 2009, the Anderson mixing of preCICE): with V = [r_{k} - r_{i}] and W = [H(x_k) -
/// H(x_i)] over the iterations so far (differences of consecutive iterates, newest first, plus
/// the columns of up to `reuseSteps` earlier steps), alpha = argmin |V alpha + r_k| and
/// x_{k+1} = H(x_k) + W alpha. Columns that are nearly dependent on newer ones (the part left
/// after orthogonalising against them below `filter` times their norm) are dropped (QR-1
/// filter). Without columns: x_{k+1} = x_k + initialOmega r_k.
class IQNILS : public Accelerator {
  public:
    /// @throws std::invalid_argument naming the bad option.
    IQNILS(double initialOmega, int reuseSteps = 0, double filter = 1e-10);
    void beginStep() override;
    Eigen::VectorXd next(const Eigen::VectorXd& x, const Eigen::VectorXd& Hx) override;
    void endStep() override;
    int getNumColumnsUsed() const { return m_used; }  ///< columns in the last least-squares fit
    /// The earlier steps' columns (reuseSteps).
    void saveState(bags::StateWriter& w) const override;
    void loadState(bags::StateReader& r) override;

  private:
    double m_initial;
    int m_reuse;
    double m_filter;
    Eigen::VectorXd m_rPrev, m_HxPrev;
    bool m_havePrev = false;
    std::vector<Eigen::VectorXd> m_V, m_W;  // this step's columns, oldest first
    std::deque<std::pair<std::vector<Eigen::VectorXd>, std::vector<Eigen::VectorXd>>> m_old;
    int m_used = 0;
};

}  // namespace cosim
