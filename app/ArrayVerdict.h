#pragma once
/// @file The support verdict of a patient-on-array run (verdict.csv, summary.txt), gathered
/// at every output frame: target tilt reached and when; slid or rolled toward the edge (the
/// centre of mass's lateral travel, an outer bag that carried him and lost him as he moved
/// further out); a bag bottomed out (the inner height left under a pressed node); the relaxed
/// bags' films at their equilibrium; per region the peak pressure and the time above 32 mmHg.
/// Criteria and thresholds: docs/output-layout.md.

#include <bags/Airbag.h>
#include <cosim/ArrayLayout.h>
#include <io/ArrayResults.h>

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

namespace bagsim::app {

class ArrayVerdict {
  public:
    /// @param settleTime [s] frames from it on are judged (all frames if duration is 0)
    /// @param targetTilt [rad] the turn's signed target (0: no turn, its checks n/a)
    ArrayVerdict(const cosim::ArrayLayout& layout, const bags::DoubleWedgeParams& bag,
                 double settleTime, double duration, double targetTilt);
    /// One output frame with the lowest pressed-node height per bag of frame.bags [m].
    void addFrame(const io::ArrayFrame& frame, const std::vector<double>& pressedHeights);
    /// The turn's outcome: when the target tilt was reached (NaN: never), the pelvis tilt
    /// when the turn ended [rad] (NaN: it had not) and whether it went back to supine; the
    /// return is to the zones' setpoint [Pa] when one is given (> 0), else to the masses.
    void setTurn(double reachedTime, double turnedTilt, bool backToSupine, double setpoint = 0.0);
    /// How the bags' films were stepped (bags::AirbagSpec::Stepping) and, for the relaxed
    /// stepping, how many committed bag steps were kept unrelaxed (their film's sub-steps ran
    /// out before its force tolerance), the largest force residual kept [N], its bag.
    void setFilmSteps(bags::AirbagSpec::Stepping stepping, long unrelaxed, double largest,
                      int worstBag, double tolerance);
    /// True when setFilmSteps() was given unrelaxed steps: the run is then partial.
    bool hasUnrelaxedSteps() const { return m_unrelaxed > 0; }
    /// Whether the coupling iterates to a fixed point (the implicit schemes) and how many
    /// macro steps were kept without one at the smallest step (cosim::CouplingOptions::
    /// keepUnconverged), the largest |H(x) - x| kept [N], its tolerance [N] and time [s].
    void setCouplingSteps(bool iterated, long unconverged, double worstResidual,
                          double worstTolerance, double worstTime);
    /// How many macro steps were accepted where their passes stalled within
    /// cosim::CouplingOptions::acceptResidual [N], the largest |H(x) - x| accepted [N] and its
    /// time [s]: said in the 'coupling converged' row, which they do not fail.
    void setAcceptedSteps(long accepted, double worst, double worstTime, double acceptResidual);
    /// The bags' gauge pressures [Pa] standing inflated before he lies on them, least and
    /// highest: judged against the published clinical settings (the 'inflation' row).
    void setRestPressures(double least, double highest);
    /// One output frame's film: the largest use of its material's fitted range over the
    /// finite-element bags (bags::Airbag::calcFittedRangeUse; above 1: beyond it), that
    /// element's principal stretch, its bag, at `time` [s]; every frame from the bags'
    /// inflation on is judged (an input that overstretches the film at rest is outside the
    /// envelope from the start).
    void addFilmRange(double use, double stretch, int bag, double time);
    /// True when a frame's film left its material's fitted range: the run is then partial.
    bool isFilmOutsideItsRange() const { return m_filmUse > 1.0; }
    std::vector<io::VerdictRow> makeRows() const;
    /// What the frames so far left (a checkpoint), and back into a verdict made the same way.
    void saveState(bags::StateWriter& w) const;
    void loadState(bags::StateReader& r);

  private:
    std::vector<cosim::ArrayBag> m_bags;
    int m_columns = 0;
    double m_columnPitch = 0.0, m_innerEdgeLow = 0.0, m_innerEdgeHigh = 0.0;
    double m_settle = 0.0, m_duration = 0.0, m_targetTilt = 0.0;
    double m_reached = 0.0, m_turnedTilt = 0.0;
    bool m_back = false, m_turnKnown = false;
    double m_setpoint = 0.0;  // [Pa] the zones' setpoint a held turn returns to (0: masses)
    bags::AirbagSpec::Stepping m_stepping = bags::AirbagSpec::Stepping::QuasiStatic;
    long m_unrelaxed = 0;
    double m_largestUnrelaxed = 0.0, m_forceTolerance = 0.0;
    int m_unrelaxedBag = -1;
    double m_restLeast = -1.0, m_restHighest = -1.0;                 // -1: not set
    double m_filmUse = -1.0, m_filmStretch = 1.0, m_filmTime = 0.0;  // -1: no frame judged
    int m_filmBag = -1;
    bool m_iterated = true;
    long m_unconverged = 0;
    double m_worstResidual = 0.0, m_worstTolerance = 0.0, m_worstTime = 0.0;
    long m_accepted = 0;
    double m_worstAccepted = 0.0, m_worstAcceptedTime = 0.0, m_acceptResidual = 0.0;
    // the judged window
    bool m_haveRef = false;
    double m_lastTime = 0.0, m_firstTime = 0.0;
    Eigen::Vector3d m_refCom = Eigen::Vector3d::Zero();
    double m_maxTravel = 0.0, m_maxTravelTime = 0.0, m_lastY = 0.0;
    double m_lowestCom = 1e9, m_lowestComTime = 0.0;
    std::map<int, double> m_lastCarriedY;  // outer bag -> his centre's y when it last carried him
    std::map<int, double> m_edgeLost;      // outer bag -> first time it lost him [s]
    double m_minHeight = 1e9, m_minHeightTime = 0.0;
    int m_minHeightBag = -1;
    struct Region {
        double peak = 0.0, peakTime = 0.0, above = 0.0;
        double patchPeak = 0.0, patchAbove = 0.0;  // the patch peak (20 cm^2), its time above
    };
    std::map<std::string, Region> m_regions;
    std::vector<std::string> m_regionOrder;
};

}  // namespace bagsim::app
