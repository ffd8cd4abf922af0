#include <diagnose/Synthesis.h>

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

namespace diagnose {

void SynthesisOptions::validate() const {
    auto require = [](bool ok, const char* name, double v, const char* valid) {
        if (ok) return;
        std::ostringstream s;
        s << "synthesis option '" << name << "' = " << v << " is invalid; " << valid;
        throw std::invalid_argument(s.str());
    };
    require(sampleInterval > 0.0 && sampleInterval <= 60.0, "sampleInterval", sampleInterval,
            "use 0 < interval <= 60 s");
    for (const auto& [name, v] :
         {std::pair<const char*, double>{"displacementNoise", displacementNoise},
          {"forceNoise", forceNoise},
          {"pressureNoise", pressureNoise},
          {"massNoise", massNoise},
          {"bedNoise", bedNoise}})
        require(v >= 0.0 && std::isfinite(v), name, v, "use a standard deviation >= 0");
}

MeasuredData synthesizeMeasurement(const std::vector<bags::LoadCurve>& truth,
                                   const std::vector<double>& readings, const RigEffects& rig,
                                   const Protocol& protocol, const SynthesisOptions& o) {
    o.validate();
    rig.validate();
    if (readings.size() != truth.size())
        throw std::invalid_argument("one flowmeter reading per truth curve is needed");
    std::mt19937_64 rng(o.seed);
    auto noise = [&](double sd) {
        return sd > 0.0 ? std::normal_distribution<double>(0.0, sd)(rng) : 0.0;
    };
    MeasuredData data;
    data.protocol = protocol;
    for (size_t k = 0; k < truth.size(); ++k) {
        const MachineCurve mc = calcMachineCurve(truth[k], rig, protocol.rate);
        if (mc.time.size() < 2)
            throw std::invalid_argument("truth curve " + std::to_string(k + 1) +
                                        " has fewer than two steps");
        MeasuredTest t;
        t.gasMass = readings[k];
        const double end = mc.time.back();
        const long n = static_cast<long>(std::floor(end / o.sampleInterval + 1e-9)) + 1;
        // The sensor's lag is integrated on a grid ten times finer than the samples.
        const int sub = 10;
        std::vector<double> fineT, fineP;
        for (long i = 0; i <= (n - 1) * sub; ++i) {
            const double ti = i * o.sampleInterval / sub;
            fineT.push_back(ti);
            fineP.push_back(interpolate(mc.time, mc.pressure, ti));
        }
        const std::vector<double> sensed = applyPressureSensor(fineT, fineP, rig);
        for (long i = 0; i < n; ++i) {
            const double ti = i * o.sampleInterval;
            t.time.push_back(ti);
            t.displacement.push_back(interpolate(mc.time, mc.displacement, ti) +
                                     noise(o.displacementNoise));
            t.force.push_back(interpolate(mc.time, mc.force, ti) + noise(o.forceNoise));
            t.pressure.time.push_back(ti);
            t.pressure.value.push_back(sensed[i * sub] + noise(o.pressureNoise));
            t.flowmeter.time.push_back(ti);
            t.flowmeter.value.push_back(truth[k].gasMass + rig.flowmeterOffset +
                                        noise(o.massNoise));
            if (o.bedGauge) {
                t.bed.time.push_back(ti);
                t.bed.value.push_back(interpolate(mc.time, mc.bedSink, ti) + noise(o.bedNoise));
            }
        }
        data.tests.push_back(std::move(t));
    }
    return data;
}

}  // namespace diagnose
