#pragma once
// bagsim diagnose on a measured stiffness curve k(m): the model's curve at the measured masses,
// then (the which part) each candidate's grid of curves, cached on disk, and the candidates
// fitted leaving one gas mass out (diagnose/StiffnessWhich.h; docs/diagnosis.md).
#include <diagnose/MeasuredData.h>
#include <diagnose/Stiffness.h>
#include <diagnose/StiffnessWhich.h>
#include <io/LoadTestScenario.h>

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace bagsim::app {

struct CurveRunOptions {
    std::filesystem::path cache;          ///< the cache folder (created when needed)
    int threads = 1;                      ///< curves run at once
    double shiftStep = 0.125e-3;          ///< [kg] the dense curve's mass step
    int volumePoints = 9;                 ///< bag-volume's grid over its bounds (odd: 0 in it)
    std::vector<std::string> candidates;  ///< empty: the library
    bool quiet = false;                   ///< no progress on stderr
};

/// The model's curve at the measured masses, let down from the largest, loading only (found
/// in the cache if there); `runs` counts the load tests run (not those found).
bags::LoadTestResult runModelCurve(const diagnose::MeasuredData& data,
                                   const io::LoadTestScenario& sc, const CurveRunOptions& o,
                                   int& runs);

/// The which part on the curve: the candidates' grids (from the cache, else run `threads` at
/// a time and cached as each ends), then diagnose::calibrateStiffnessCandidates.
diagnose::StiffnessWhich runCurveWhich(const diagnose::MeasuredData& data,
                                       const io::LoadTestScenario& sc,
                                       const bags::LoadTestResult& model,
                                       const diagnose::StiffnessComparison& comparison,
                                       const CurveRunOptions& o, int& runs);

/// Prints the candidates ranked, those not applicable and the verdict's reason.
void printCurveWhich(const diagnose::StiffnessWhich& w, std::ostream& out);

}  // namespace bagsim::app
