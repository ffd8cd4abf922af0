#pragma once
/// @file What the diagnosis reads off residuals, whatever the instrument (the seed's rig,
/// docs/diagnosis.md#where; a patient on the array, docs/diagnosis.md#a-patient-on-the-array):
/// the sensor noise from the data, the signatures of a series (bias, scale, lag by
/// cross-correlation, drift), a regime's statistics, and the held-out metrics of ASME V&V 20
/// with the area validation metric.

#include <diagnose/Diagnosis.h>

#include <string>
#include <utility>
#include <vector>

namespace diagnose {

/// y(x) by linear interpolation on increasing x, clamped to the end values beyond the range
/// (a record on its own time base).
double interpolateClamped(const std::vector<double>& x, const std::vector<double>& y, double xq);

/// Appends |y[i+1] - 2 y[i] + y[i-1]| of a series sampled at a steady rate.
void addSecondDifferences(const std::vector<double>& y, std::vector<double>& dd);
/// Sensor noise (standard deviation) from second differences: for white noise of sd s they
/// have sd sqrt(6) s; a smooth signal sampled finely adds little, and their median ignores the
/// few samples at a kink. 0 for none.
double calcNoise(std::vector<double> secondDifferences);

/// Cross-correlation lag [s]: the shift of the simulated series s that best matches the
/// measured one m (measured behind simulated > 0), within maxLag, on a uniform resampling of
/// t, refined by a parabola; and the correlation there. NaN for fewer than 8 samples.
std::pair<double, double> calcLag(const std::vector<double>& t, const std::vector<double>& m,
                                  const std::vector<double>& s, double maxLag);

/// Bias (mean residual m - s), scale (m = a + (1 + scale) s by least squares), drift (slope of
/// the residual over t) and lag of a series; loop areas and test are left 0.
Signature calcSeriesSignature(const std::string& channel, const std::vector<double>& t,
                              const std::vector<double>& m, const std::vector<double>& s,
                              double maxLag);

/// RMSE, bias, largest |residual| of one regime's residuals, and their share of `totalSquared`
/// (the channel's sum of squared residuals).
RegimeStats calcRegimeStats(const std::string& channel, const std::string& regime,
                            const std::vector<double>& residuals, double totalSquared);

/// ASME V&V 20's comparison error E = S - D over paired samples (RMSE, mean, largest) and the
/// area validation metric (the Wasserstein-1 distance of the two samples).
GapMetrics calcPairedMetrics(const std::string& channel, const std::vector<double>& measured,
                             const std::vector<double>& simulated);

}  // namespace diagnose
