/// @file The seed's bag read from its words: the scale of the double wedge that a given gas
/// mass just fills (docs/geometry.md).

#include <bags/SeedReading.h>

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bags {

namespace {

void require(bool ok, const std::string& option, double value, const std::string& valid) {
    if (ok) return;
    std::ostringstream s;
    s << "fill mass option '" << option << "' = " << value << " is invalid; " << valid;
    throw std::invalid_argument(s.str());
}

std::string grams(double kg) {
    std::ostringstream s;
    s.precision(4);
    s << kg * 1e3 << " g";
    return s.str();
}

}  // namespace

const char* getFillScalingName(FillScaling scaling) {
    switch (scaling) {
        case FillScaling::Profile:
            return "profile";
        case FillScaling::Uniform:
            return "uniform";
        case FillScaling::Height:
            return "height";
    }
    return "?";
}

int getFillScalingExponent(FillScaling scaling) {
    switch (scaling) {
        case FillScaling::Profile:
            return 2;
        case FillScaling::Uniform:
            return 3;
        case FillScaling::Height:
            return 1;
    }
    return 1;
}

DoubleWedgeParams scaleDoubleWedge(const DoubleWedgeParams& p, FillScaling scaling, double s) {
    DoubleWedgeParams q = p;
    q.shortSide *= s;
    q.height *= s;
    if (scaling != FillScaling::Height) q.longSide *= s;
    if (scaling == FillScaling::Uniform) q.width *= s;
    return q;
}

void changeBagVolume(LoadTestOptions& o, double change) {
    if (!(change >= -kMaxVolumeChange && change <= kMaxVolumeChange)) {
        std::ostringstream s;
        s << "volume change " << change << " is invalid; valid: " << -kMaxVolumeChange << " to "
          << kMaxVolumeChange << " (the bag's volume times 1 + change)";
        throw std::invalid_argument(s.str());
    }
    if (change == 0.0) return;
    LoadTestOptions q = o;
    q.bagScale *= std::cbrt(1.0 + change);
    try {
        q.getBagGeometry().validate();
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("volume change " + std::to_string(change) +
                                    " gives an invalid bag: " + e.what());
    }
    o.bagScale = q.bagScale;
}

void FillMassOptions::validate() const {
    require(probeHigh > probeLow && probeHigh <= 2.0, "probeHigh", probeHigh,
            "use probeLow < probeHigh <= 2 (e.g. 1.06)");
    require(probeLow > 1.0, "probeLow", probeLow,
            "use a multiple above 1 of the expected fill mass (e.g. 1.02)");
    require(tautPressure > 0.0, "tautPressure", tautPressure, "use a gauge pressure > 0 Pa");
    require(tolerance > 0.0, "tolerance", tolerance, "use a mass > 0 kg (e.g. 0.005 g)");
    require(maxEvaluations >= 1 && maxEvaluations <= 20, "maxEvaluations", maxEvaluations,
            "use 1 to 20");
    require(bulgeRatio >= 1.0 && bulgeRatio <= 2.0, "bulgeRatio", bulgeRatio,
            "use 1 to 2 (the seed reading: 1.18)");
}

FillMassMeasurement measureFillMass(const LoadTestOptions& rig, double expectedFillMass,
                                    const FillMassOptions& options) {
    options.validate();
    if (!(expectedFillMass > 0.0 && expectedFillMass < 1.0))
        throw std::invalid_argument("expected fill mass " + grams(expectedFillMass) +
                                    " is invalid; use a mass > 0 (in kg inside)");
    LoadTestOptions o = rig;
    // Only the inflated, unloaded states count: the block barely touches the bag.
    o.connection = LoadTestOptions::Connection::Open;
    // The fill mass is the bag's own, measured alone (not squeezed by neighbours).
    o.neighbours = LoadTestOptions::Neighbours::None;
    o.peakForce = 0.5;
    o.stiffnessFrom = 0.1;
    o.stiffnessTo = 0.4;
    o.unload = false;
    o.polynomialOrder = 1;
    double expected = expectedFillMass;
    for (int attempt = 0;; ++attempt) {
        o.gasMasses = {options.probeHigh * expected, options.probeLow * expected};
        const LoadTestResult res = runLoadTest(o);
        FillMassMeasurement m;
        for (int i = 0; i < 2; ++i) {
            m.probeMass[i] = res.curves[i].gasMass;
            m.probeVolume[i] = res.curves[i].inflatedVolume;
            m.probePressure[i] = res.curves[i].inflatedGaugePressure;
            m.probeHeight[i] = res.curves[i].unloadedHeight;
        }
        if (m.probePressure[1] < options.tautPressure) {
            // The lighter probe is slack: the bag is bigger than expected.
            if (attempt < 3) {
                expected *= 1.2;
                continue;
            }
            throw std::runtime_error("fill mass: the probe state with " + grams(m.probeMass[1]) +
                                     " is still slack; the bag holds far more than expected");
        }
        const double dp = m.probePressure[0] - m.probePressure[1];
        if (!(dp > 0.0))
            throw std::runtime_error("fill mass: the heavier probe is not at the higher pressure");
        const double dVdp = (m.probeVolume[0] - m.probeVolume[1]) / dp;
        m.zeroGaugeVolume = m.probeVolume[1] - dVdp * m.probePressure[1];
        m.fillMass = rig.gas.getAmbientDensity() * m.zeroGaugeVolume;
        m.fillMassFromPressure =
            m.probeMass[1] - m.probePressure[1] * (m.probeMass[0] - m.probeMass[1]) / dp;
        return m;
    }
}

double estimateFillScale(const LoadTestOptions& rig, double targetFillMass, FillScaling scaling,
                         const FillMassOptions& options) {
    const double flat =
        rig.gas.getAmbientDensity() * options.bulgeRatio * rig.geometry.calcFlatVolume();
    return std::pow(targetFillMass / flat, 1.0 / getFillScalingExponent(scaling));
}

FillScaleResult findFillScale(const LoadTestOptions& rig, double targetFillMass,
                              FillScaling scaling, const FillMassOptions& options) {
    options.validate();
    if (!(targetFillMass > 0.0 && targetFillMass < 1.0))
        throw std::invalid_argument("target fill mass " + grams(targetFillMass) +
                                    " is invalid; use a mass > 0 (in kg inside)");
    const auto start = std::chrono::steady_clock::now();
    const double q0 = getFillScalingExponent(scaling);
    FillScaleResult r;
    double s = estimateFillScale(rig, targetFillMass, scaling, options);
    for (int k = 0; k < options.maxEvaluations; ++k) {
        LoadTestOptions o = rig;
        o.geometry = scaleDoubleWedge(rig.geometry, scaling, s);
        o.geometry.validate();
        const FillMassMeasurement m = measureFillMass(o, targetFillMass, options);
        r.scales.push_back(s);
        r.fillMasses.push_back(m.fillMass);
        if (std::abs(m.fillMass - targetFillMass) <= options.tolerance) {
            r.scale = s;
            r.geometry = o.geometry;
            r.measurement = m;
            r.seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            return r;
        }
        // log f = q log s + c: q from the scaling law, then from the last two measurements
        // (kept within a factor of two of the law's, in case round-off dominates).
        double q = q0;
        if (r.scales.size() >= 2) {
            const size_t n = r.scales.size();
            const double ds = std::log(r.scales[n - 1] / r.scales[n - 2]);
            const double df = std::log(r.fillMasses[n - 1] / r.fillMasses[n - 2]);
            if (std::abs(ds) > 1e-9 && df / ds > 0.5 * q0 && df / ds < 2.0 * q0) q = df / ds;
        }
        s *= std::pow(targetFillMass / m.fillMass, 1.0 / q);
    }
    std::ostringstream msg;
    msg << "fill mass: no scale within " << grams(options.tolerance) << " of "
        << grams(targetFillMass) << " in " << options.maxEvaluations << " measurements; last scale "
        << r.scales.back() << " gave " << grams(r.fillMasses.back());
    throw std::runtime_error(msg.str());
}

}  // namespace bags
