#include <diagnose/PatientDiagnosis.h>

#include <bags/Units.h>
#include <diagnose/RigEffects.h>
#include <diagnose/Signatures.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>

#include "Format.h"

namespace diagnose {

namespace {

using detail::fmt;
using detail::kNaN;

constexpr double kMmHg = bags::kPascalsPerMmHg;  // [Pa]
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// The instrument effects' names.
constexpr const char* kBagSensor = "bag-pressure-sensor";
constexpr const char* kMatGain = "mat-gain";

void checkBounds(const Effect& e, const std::vector<double>& v) {
    if (v.size() != e.parameters.size())
        throw std::invalid_argument(e.name + " takes " + std::to_string(e.parameters.size()) +
                                    " parameter(s)");
    for (size_t i = 0; i < v.size(); ++i) {
        const EffectParameter& p = e.parameters[i];
        if (!(v[i] >= p.lower - 1e-12 * std::fabs(p.lower) &&
              v[i] <= p.upper + 1e-12 * std::fabs(p.upper)))
            throw std::invalid_argument(
                e.name + "." + p.name + " " + fmt("%g", v[i] / p.siPerUnit) + " " + p.unit +
                " is outside its bounds " + fmt("%g", p.lower / p.siPerUnit) + " to " +
                fmt("%g", p.upper / p.siPerUnit) + " " + p.unit);
    }
}

// Index of the first element of increasing x after xq, clamped to [1, n - 1]; with the weight of
// x[k - 1]: y(xq) = w y[k - 1] + (1 - w) y[k], clamped to the ends.
std::pair<size_t, double> bracket(const std::vector<double>& x, double xq) {
    if (x.size() < 2 || xq <= x.front()) return {1, 1.0};
    if (xq >= x.back()) return {x.size() - 1, 0.0};
    const size_t k = size_t(std::upper_bound(x.begin(), x.end(), xq) - x.begin());
    return {k, (x[k] - xq) / (x[k] - x[k - 1])};
}

double interpolateFrame(const MatFrames& m, size_t sensel, const std::pair<size_t, double>& b) {
    if (m.time.size() < 2) return m.pressure.at(0)[sensel];
    return b.second * m.pressure[b.first - 1][sensel] +
           (1.0 - b.second) * m.pressure[b.first][sensel];
}

int findWindow(const std::vector<double>& edges, double t) {
    const int n = int(edges.size()) - 1;
    for (int w = 0; w < n; ++w)
        if (t < edges[size_t(w) + 1]) return w;
    return n - 1;
}

}  // namespace

// ------------------------------------------------------------------------- the effects

const std::vector<Effect>& getPatientEffects() {
    static const std::vector<Effect> effects = {
        {kBagSensor,
         "the bags' pressure sensors lag (first order: tubing, filter) and read with a zero offset",
         {{"lag", "s", 1.0, 0.0, PatientInstruments::kMaxBagSensorLag, 0.1, "(the bags' sensors)"},
          {"offset", "kPa", 1e3, -PatientInstruments::kMaxBagSensorOffset,
           PatientInstruments::kMaxBagSensorOffset, 0.5e3, "(the bags' sensors)"}},
         false,
         true,
         "a reference gauge on a bag's own port read beside its sensor"},
        {kMatGain,
         "the pressure mat reads every sensel's pressure times 1 + gain (calibration, creep, "
         "temperature)",
         {{"gain", "", 1.0, -PatientInstruments::kMaxMatGain, PatientInstruments::kMaxMatGain, 0.1,
           "(the mat)"}},
         false,
         true,
         "the mat calibrated under a known pressure (a bladder at a set pressure over it)"},
        {"film-friction",
         "Coulomb friction between his skin or sheet and the bags' films",
         {{"friction", "", 1.0, 0.0, 1.0, 0.4, "bag.body_friction"}},
         true,
         true,
         "a slide test of his sheet on the film (the force that starts it sliding under a "
         "known load)"},
        {"gas-mass-bias",
         "the bags hold another gas mass than the one stated (filling, leaks before the record)",
         {{"offset", "g", 1e-3, -0.5e-3, 0.5e-3, 0.2e-3,
           "array.gas_mass (the stated mass plus this)"}},
         true,
         true,
         "the bags' gas masses metered as they are filled, or their pressures read with no one "
         "on them"},
        {"soft-tissue",
         "soft tissue between his bones and the films: one Winkler layer in every segment, in "
         "place of the scenario's own (each site's published layer by default); 0 mm: the "
         "scenario's own",
         {{"thickness", "mm", 1e-3, 0.0, kMaxTissueThickness, 20e-3, "bag.body_tissue.thickness"},
          {"modulus", "kPa", 1e3, kMinTissueModulus, kMaxTissueModulus, 30e3,
           "bag.body_tissue.modulus"}},
         true,
         true,
         "his tissue's thickness at the sites (ultrasound) and its stiffness (indentation)"},
    };
    return effects;
}

const Effect* findPatientEffect(const std::string& name) {
    return findEffectIn(getPatientEffects(), name);
}

std::string listPatientEffectNames() { return listEffectNamesIn(getPatientEffects()); }

void applyPatientInstrumentEffect(const Effect& effect, const std::vector<double>& v,
                                  PatientInstruments& inst) {
    checkBounds(effect, v);
    if (effect.name == kBagSensor)
        inst.bagSensorLag = v[0], inst.bagSensorOffset = v[1];
    else if (effect.name == kMatGain)
        inst.matGain = v[0];
    else
        throw std::invalid_argument(effect.name + " is not an instrument effect");
}

std::vector<std::pair<std::string, std::string>> getPatientEffectOverrides(
    const Effect& effect, const std::vector<double>& v, double statedGasMass) {
    checkBounds(effect, v);
    if (effect.name == "film-friction") return {{"bag.body_friction", fmt("%.9g", v[0])}};
    if (effect.name == "gas-mass-bias") {
        if (v[0] == 0.0) return {};  // the stated mass: the model as it is
        return {{"array.gas_mass", fmt("%.9g", (statedGasMass + v[0]) * 1e3) + " g"}};
    }
    if (effect.name == "soft-tissue") {
        // The scenario's layer is at least 0.5 mm thick; thinner is the model as it is (the
        // scenario's own tissue: each site's published layer by default, or none).
        if (v[0] < 0.5e-3) return {};
        return {{"bag.body_tissue", "{thickness: " + fmt("%.9g", v[0] * 1e3) +
                                        " mm, modulus: " + fmt("%.9g", v[1] * 1e-3) + " kPa}"}};
    }
    throw std::invalid_argument(effect.name + " does not change the patient's response");
}

PatientChannels readPatientInstruments(const PatientChannels& run, const PatientInstruments& inst) {
    PatientChannels r = run;
    RigEffects sensor;
    sensor.pressureLag = inst.bagSensorLag;
    sensor.pressureOffset = inst.bagSensorOffset;
    for (BagPressureChannel& b : r.bags)
        b.pressure.value = applyPressureSensor(b.pressure.time, b.pressure.value, sensor);
    if (inst.matGain != 0.0)
        for (auto& f : r.mat.pressure)
            for (double& p : f) p *= 1.0 + inst.matGain;
    return r;
}

// ------------------------------------------------------------------------- synthesis

void PatientSynthesisOptions::validate() const {
    if (!(sampleInterval > 0.0)) throw std::invalid_argument("the sample interval must be > 0 s");
    if (!(matInterval > 0.0)) throw std::invalid_argument("the mat's interval must be > 0 s");
    for (double n : {matNoise, tiltNoise, pressureNoise})
        if (!(n >= 0.0)) throw std::invalid_argument("a noise must be >= 0");
}

PatientChannels synthesizePatientChannels(const PatientChannels& run,
                                          const PatientInstruments& inst,
                                          const PatientSynthesisOptions& o) {
    o.validate();
    const PatientChannels r = readPatientInstruments(run, inst);
    std::mt19937_64 rng(o.seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    auto times = [](const std::vector<double>& t, double dt) {
        std::vector<double> s;
        if (t.empty()) return s;
        for (long k = 0;; ++k) {
            const double tk = t.front() + double(k) * dt;
            if (tk > t.back() + 1e-9) break;
            s.push_back(std::min(tk, t.back()));
        }
        return s;
    };
    PatientChannels out;
    if (!r.mat.empty()) {
        out.mat.rows = r.mat.rows, out.mat.columns = r.mat.columns;
        out.mat.time = times(r.mat.time, o.matInterval);
        const size_t per = size_t(r.mat.rows) * size_t(r.mat.columns);
        for (double t : out.mat.time) {
            const auto b = bracket(r.mat.time, t);
            std::vector<double> f(per);
            for (size_t k = 0; k < per; ++k) {
                const double p = interpolateFrame(r.mat, k, b);
                f[k] = p > 0.0 ? std::max(0.0, p + o.matNoise * normal(rng)) : 0.0;
            }
            out.mat.pressure.push_back(std::move(f));
        }
    }
    if (!r.tilt.empty()) {
        out.tilt.time = times(r.tilt.time, o.sampleInterval);
        for (double t : out.tilt.time) {
            if (!r.tilt.pelvis.empty())
                out.tilt.pelvis.push_back(interpolateClamped(r.tilt.time, r.tilt.pelvis, t) +
                                          o.tiltNoise * normal(rng));
            if (!r.tilt.thorax.empty())
                out.tilt.thorax.push_back(interpolateClamped(r.tilt.time, r.tilt.thorax, t) +
                                          o.tiltNoise * normal(rng));
        }
    }
    for (const BagPressureChannel& b : r.bags) {
        BagPressureChannel s;
        s.bag = b.bag;
        s.pressure.time = times(b.pressure.time, o.sampleInterval);
        for (double t : s.pressure.time)
            s.pressure.value.push_back(interpolateClamped(b.pressure.time, b.pressure.value, t) +
                                       o.pressureNoise * normal(rng));
        if (s.pressure.time.size() >= 2) out.bags.push_back(std::move(s));
    }
    return out;
}

// ------------------------------------------------------------------------- where

std::vector<std::vector<size_t>> PatientChannelComparison::partSeries() const {
    std::map<std::pair<int, int>, std::vector<size_t>> by;  // (test, sensel or part)
    const bool mat = !sensel.empty();
    for (size_t i = 0; i < time.size(); ++i)
        by[{getTest(i), mat ? sensel[i] : (part.empty() ? 0 : part[i])}].push_back(i);
    std::vector<std::vector<size_t>> out;
    for (auto& [k, v] : by) {
        std::sort(v.begin(), v.end(), [&](size_t a, size_t b) { return time[a] < time[b]; });
        out.push_back(std::move(v));
    }
    return out;
}

int PatientFolds::findFold(const PatientChannelComparison& c, size_t i) const {
    if (isBySubject()) return testSubject.at(size_t(c.getTest(i)));
    return isByTest() ? c.getTest(i) : findWindow(windowEdges, c.time[i]);
}

std::vector<int> PatientFolds::getFoldTests(int fold) const {
    std::vector<int> out;
    if (isBySubject()) {
        for (size_t t = 0; t < testSubject.size(); ++t)
            if (testSubject[t] == fold) out.push_back(int(t));
    } else if (isByTest()) {
        out.push_back(fold);
    }
    return out;
}

PatientComparison joinPatientComparisons(const std::vector<PatientComparison>& parts,
                                         const std::vector<std::string>& names,
                                         const std::vector<std::string>& subjects) {
    if (parts.size() == 1) return parts.front();
    PatientComparison out;
    out.tests = names;
    for (const std::string& s : subjects) {
        if (s.empty()) continue;
        auto it = std::find(out.subjects.begin(), out.subjects.end(), s);
        if (it == out.subjects.end()) it = out.subjects.insert(out.subjects.end(), s);
        out.testSubject.push_back(int(it - out.subjects.begin()));
    }
    if (out.testSubject.size() != parts.size()) out.subjects.clear(), out.testSubject.clear();
    for (size_t t = 0; t < parts.size(); ++t)
        for (const PatientChannelComparison& ch : parts[t].channels) {
            auto it =
                std::find_if(out.channels.begin(), out.channels.end(),
                             [&](const PatientChannelComparison& c) { return c.name == ch.name; });
            if (it == out.channels.end()) {
                PatientChannelComparison c;
                c.name = ch.name, c.unit = ch.unit, c.unitScale = ch.unitScale;
                out.channels.push_back(std::move(c));
                it = out.channels.end() - 1;
            }
            PatientChannelComparison& j = *it;
            for (size_t i = 0; i < ch.time.size(); ++i) {
                j.time.push_back(ch.time[i]);
                j.measured.push_back(ch.measured[i]);
                j.simulated.push_back(ch.simulated[i]);
                j.test.push_back(int(t));
                if (!ch.frame.empty())
                    j.frame.push_back(ch.frame[i]), j.sensel.push_back(ch.sensel[i]);
                if (ch.part.empty()) continue;
                const std::string& pn = ch.partNames.at(size_t(ch.part[i]));
                auto p = std::find(j.partNames.begin(), j.partNames.end(), pn);
                if (p == j.partNames.end()) p = j.partNames.insert(j.partNames.end(), pn);
                j.part.push_back(int(p - j.partNames.begin()));
            }
        }
    return out;
}

const PatientChannelComparison* PatientComparison::find(const std::string& name) const {
    for (const PatientChannelComparison& c : channels)
        if (c.name == name) return &c;
    return nullptr;
}

PatientComparison comparePatient(const PatientChannels& measured, const PatientChannels& run,
                                 const PatientInstruments& inst, const MatRegions& regions,
                                 const PatientComparison* like) {
    const PatientChannels r = readPatientInstruments(run, inst);
    PatientComparison out;
    const MatFrames& mm = measured.mat;
    if (!mm.empty() && !r.mat.empty()) {
        PatientChannelComparison c;
        c.name = "mat", c.unit = "mmHg", c.unitScale = kMmHg;
        c.partNames = regions.names;
        const size_t per = size_t(mm.rows) * size_t(mm.columns);
        auto add = [&](size_t f, size_t k, double sim) {
            c.time.push_back(mm.time[f]);
            c.measured.push_back(mm.pressure[f][k]);
            c.simulated.push_back(sim);
            c.part.push_back(k < regions.sensel.size() ? regions.sensel[k] : 0);
            c.frame.push_back(int(f));
            c.sensel.push_back(int(k));
        };
        const PatientChannelComparison* lm = like ? like->find("mat") : nullptr;
        if (lm) {
            for (size_t i = 0; i < lm->time.size(); ++i) {
                const size_t f = size_t(lm->frame[i]), k = size_t(lm->sensel[i]);
                add(f, k, interpolateFrame(r.mat, k, bracket(r.mat.time, mm.time[f])));
            }
        } else {
            for (size_t f = 0; f < mm.time.size(); ++f) {
                const auto b = bracket(r.mat.time, mm.time[f]);
                for (size_t k = 0; k < per; ++k) {
                    const double sim = interpolateFrame(r.mat, k, b);
                    if (mm.pressure[f][k] > 0.0 || sim > 0.0) add(f, k, sim);
                }
            }
        }
        out.channels.push_back(std::move(c));
    }
    const TiltChannel& mt = measured.tilt;
    for (int which = 0; which < 2 && !mt.empty() && !r.tilt.empty(); ++which) {
        const std::vector<double>& m = which == 0 ? mt.pelvis : mt.thorax;
        const std::vector<double>& s = which == 0 ? r.tilt.pelvis : r.tilt.thorax;
        if (m.empty() || s.empty()) continue;
        PatientChannelComparison c;
        c.name = which == 0 ? "pelvis-tilt" : "thorax-tilt";
        c.unit = "deg", c.unitScale = kDeg;
        for (size_t i = 0; i < mt.time.size(); ++i) {
            c.time.push_back(mt.time[i]);
            c.measured.push_back(m[i]);
            c.simulated.push_back(interpolateClamped(r.tilt.time, s, mt.time[i]));
        }
        out.channels.push_back(std::move(c));
    }
    PatientChannelComparison bc;
    bc.name = "bag-pressure", bc.unit = "kPa", bc.unitScale = 1e3;
    for (const BagPressureChannel& mb : measured.bags) {
        const auto it = std::find_if(r.bags.begin(), r.bags.end(),
                                     [&](const BagPressureChannel& b) { return b.bag == mb.bag; });
        if (it == r.bags.end() || it->pressure.time.size() < 2)
            continue;  // not simulated: no one over it
        const int part = int(bc.partNames.size());
        bc.partNames.push_back("bag " + std::to_string(mb.bag));
        for (size_t i = 0; i < mb.pressure.time.size(); ++i) {
            bc.time.push_back(mb.pressure.time[i]);
            bc.measured.push_back(mb.pressure.value[i]);
            bc.simulated.push_back(
                interpolateClamped(it->pressure.time, it->pressure.value, mb.pressure.time[i]));
            bc.part.push_back(part);
        }
    }
    if (!bc.time.empty()) out.channels.push_back(std::move(bc));
    return out;
}

std::vector<double> calcPatientSimulatedDifference(const PatientComparison& a,
                                                   const PatientComparison& b) {
    std::vector<double> out;
    for (const PatientChannelComparison& ca : a.channels) {
        const PatientChannelComparison* cb = b.find(ca.name);
        double s = 0.0;
        size_t n = 0;
        if (cb)
            for (size_t i = 0; i < ca.simulated.size() && i < cb->simulated.size(); ++i, ++n)
                s += std::pow(ca.simulated[i] - cb->simulated[i], 2);
        out.push_back(n ? std::sqrt(s / double(n)) : 0.0);
    }
    return out;
}

namespace {

// The samples of one test of a joined channel.
PatientChannelComparison selectTest(const PatientChannelComparison& ch, int test) {
    PatientChannelComparison o;
    o.name = ch.name, o.unit = ch.unit, o.unitScale = ch.unitScale, o.partNames = ch.partNames;
    for (size_t i = 0; i < ch.time.size(); ++i) {
        if (ch.getTest(i) != test) continue;
        o.time.push_back(ch.time[i]);
        o.measured.push_back(ch.measured[i]);
        o.simulated.push_back(ch.simulated[i]);
        if (!ch.part.empty()) o.part.push_back(ch.part[i]);
        if (!ch.frame.empty()) o.frame.push_back(ch.frame[i]), o.sensel.push_back(ch.sensel[i]);
    }
    return o;
}

// One record's signatures of a channel: per bag, or of the channel (the mat: the lag of its
// frame sums); `label` ("" or "test NAME") begins each signature's part.
void addPatientSignatures(const PatientChannelComparison& ch, const std::string& label,
                          double maxLag, std::vector<Signature>& out) {
    if (ch.time.empty()) return;
    auto partOf = [&](const std::string& p) {
        return label.empty() ? p : p.empty() ? label : label + ", " + p;
    };
    if (ch.name == "bag-pressure") {
        for (const auto& idx : ch.partSeries()) {
            std::vector<double> t, m, s;
            for (size_t i : idx)
                t.push_back(ch.time[i]), m.push_back(ch.measured[i]), s.push_back(ch.simulated[i]);
            Signature sg = calcSeriesSignature(ch.name, t, m, s, maxLag);
            sg.test = ch.part[idx.front()];
            sg.part = partOf(ch.partNames.at(size_t(sg.test)));
            out.push_back(sg);
        }
    } else if (ch.name == "mat") {
        Signature sg = calcSeriesSignature(ch.name, ch.time, ch.measured, ch.simulated, maxLag);
        std::map<int, std::array<double, 3>> frames;  // time, sum measured, sum simulated
        for (size_t i = 0; i < ch.time.size(); ++i) {
            auto& f = frames[ch.frame[i]];
            f[0] = ch.time[i], f[1] += ch.measured[i], f[2] += ch.simulated[i];
        }
        std::vector<double> t, m, s;
        for (const auto& [k, f] : frames) t.push_back(f[0]), m.push_back(f[1]), s.push_back(f[2]);
        const auto [lag, corr] = calcLag(t, m, s, maxLag);
        sg.lag = lag, sg.lagCorrelation = corr;
        sg.part = partOf("");
        out.push_back(sg);
    } else {
        Signature sg = calcSeriesSignature(ch.name, ch.time, ch.measured, ch.simulated, maxLag);
        sg.part = partOf("");
        out.push_back(sg);
    }
}

// "test NAME", or with subjects "subject S, test NAME".
std::string getTestLabel(const PatientComparison& c, size_t t) {
    const std::string test = "test " + c.tests.at(t);
    if (c.subjects.empty()) return test;
    return "subject " + c.subjects.at(size_t(c.testSubject.at(t))) + ", " + test;
}

}  // namespace

WhereReport calcPatientWhere(const PatientComparison& c, const std::vector<double>& numerical,
                             const std::vector<double>& edges, double maxLag) {
    WhereReport r;
    std::vector<double> nrmse2;
    for (size_t ci = 0; ci < c.channels.size(); ++ci) {
        const PatientChannelComparison& ch = c.channels[ci];
        std::vector<double> res(ch.time.size());
        double lo = INFINITY, hi = -INFINITY, sumSq = 0.0;
        for (size_t i = 0; i < res.size(); ++i) {
            res[i] = ch.measured[i] - ch.simulated[i];
            lo = std::min(lo, ch.measured[i]);
            hi = std::max(hi, ch.measured[i]);
            sumSq += res[i] * res[i];
        }
        // Regimes: all; by part (the mat's regions, the bags); by time window.
        std::vector<std::vector<double>> byPart(ch.partNames.size());
        std::vector<std::vector<double>> byWindow(edges.size() > 1 ? edges.size() - 1 : 1);
        for (size_t i = 0; i < res.size(); ++i) {
            if (!ch.part.empty() && size_t(ch.part[i]) < byPart.size())
                byPart[size_t(ch.part[i])].push_back(res[i]);
            byWindow[size_t(std::max(0, findWindow(edges, ch.time[i])))].push_back(res[i]);
        }
        r.regimes.push_back(calcRegimeStats(ch.name, "all", res, sumSq));
        for (size_t p = 0; p < byPart.size(); ++p)
            if (!byPart[p].empty())
                r.regimes.push_back(calcRegimeStats(ch.name, ch.partNames[p], byPart[p], sumSq));
        for (size_t w = 0; w < byWindow.size(); ++w)
            r.regimes.push_back(
                calcRegimeStats(ch.name,
                                "time " + fmt("%.3g", edges.size() > 1 ? edges[w] : 0.0) + "-" +
                                    fmt("%.3g s", edges.size() > 1 ? edges[w + 1] : 0.0),
                                byWindow[w], sumSq));
        // By subject (when the tests name them), and by test when a subject has several tests.
        if (!c.subjects.empty()) {
            std::vector<std::vector<double>> bySubject(c.subjects.size());
            for (size_t i = 0; i < res.size(); ++i)
                bySubject.at(size_t(c.testSubject.at(size_t(ch.getTest(i))))).push_back(res[i]);
            for (size_t s = 0; s < bySubject.size(); ++s)
                if (!bySubject[s].empty())
                    r.regimes.push_back(
                        calcRegimeStats(ch.name, "subject " + c.subjects[s], bySubject[s], sumSq));
        }
        if (c.tests.size() > 1 && c.tests.size() > c.subjects.size()) {
            std::vector<std::vector<double>> byTest(c.tests.size());
            for (size_t i = 0; i < res.size(); ++i)
                byTest.at(size_t(ch.getTest(i))).push_back(res[i]);
            for (size_t t = 0; t < byTest.size(); ++t)
                if (!byTest[t].empty())
                    r.regimes.push_back(
                        calcRegimeStats(ch.name, getTestLabel(c, t), byTest[t], sumSq));
        }

        // Noise: second differences of each part's (the mat: each sensel's) series.
        std::vector<double> dd;
        const auto series = ch.partSeries();
        for (const auto& idx : series) {
            std::vector<double> y;
            for (size_t i : idx) y.push_back(ch.measured[i]);
            addSecondDifferences(y, dd);
        }
        if (!std::isfinite(sumSq))  // never a verdict from a residual that is not a number
            throw std::domain_error("the " + ch.name +
                                    " residual is not a finite number (a sample of the measured "
                                    "data or of the simulation too large to square); no verdict "
                                    "can be drawn from it. Check the channel's samples");
        ChannelSummary cs;
        cs.channel = ch.name;
        cs.rmse = res.empty() ? 0.0 : std::sqrt(sumSq / double(res.size()));
        cs.range = res.empty() ? 0.0 : hi - lo;
        cs.noise = calcNoise(dd);
        cs.numerical = ci < numerical.size() ? numerical[ci] : 0.0;
        cs.validation = std::sqrt(cs.noise * cs.noise + cs.numerical * cs.numerical);
        r.channels.push_back(cs);
        nrmse2.push_back(cs.range > 0.0 ? std::pow(cs.rmse / cs.range, 2) : 0.0);

        // Signatures: per bag, and of the channel (the mat: its mean over the compared
        // sensels per frame, for the lag); per test when there are several (a series is one
        // test's record).
        if (c.tests.size() > 1) {
            for (size_t t = 0; t < c.tests.size(); ++t)
                addPatientSignatures(selectTest(ch, int(t)), getTestLabel(c, t), maxLag,
                                     r.signatures);
        } else {
            addPatientSignatures(ch, "", maxLag, r.signatures);
        }
    }
    double sum2 = 0.0;
    for (double v : nrmse2) sum2 += v;
    r.gap = nrmse2.empty() ? 0.0 : std::sqrt(sum2 / double(nrmse2.size()));
    for (size_t k = 0; k < r.channels.size(); ++k)
        r.channels[k].shareOfGap = sum2 > 0.0 ? nrmse2[k] / sum2 : 0.0;
    r.withinValidation = true;
    for (const ChannelSummary& cs : r.channels)
        if (cs.rmse > kExplainedMultiple * cs.validation) r.withinValidation = false;
    return r;
}

double calcPatientGap(const PatientComparison& c, const WhereReport& where,
                      const std::vector<double>& edges, const std::vector<int>& windows,
                      bool beyond) {
    PatientFolds folds;
    folds.windowEdges = edges;
    return calcPatientGap(c, where, folds, windows, beyond);
}

double calcPatientGap(const PatientComparison& c, const WhereReport& where,
                      const PatientFolds& folds, const std::vector<int>& windows, bool beyond) {
    double sum = 0.0;
    int n = 0;
    for (const PatientChannelComparison& ch : c.channels) {
        const auto it = std::find_if(where.channels.begin(), where.channels.end(),
                                     [&](const ChannelSummary& s) { return s.channel == ch.name; });
        if (it == where.channels.end() || !(it->range > 0.0)) continue;
        double ss = 0.0;
        long k = 0;
        for (size_t i = 0; i < ch.time.size(); ++i) {
            const int w = folds.findFold(ch, i);
            if (std::find(windows.begin(), windows.end(), w) == windows.end()) continue;
            ss += std::pow(ch.measured[i] - ch.simulated[i], 2), ++k;
        }
        if (!k) continue;
        double ms = ss / double(k);
        // Beyond the uncertainty: as the rig's, the squared RMSE less the squared validation
        // uncertainty; but a channel the where stage finds consistent (its RMSE within twice
        // its validation uncertainty over the record) has nothing to explain, and counts only
        // what goes beyond that (an effect that makes it worse): a channel that hardly moves
        // (a supine patient's tilt) would otherwise weigh its noise, over few samples, by one
        // over its small range.
        const double allowed =
            it->rmse <= 2.0 * it->validation ? 2.0 * it->validation : it->validation;
        if (beyond) ms = std::max(0.0, ms - allowed * allowed);
        sum += ms / (it->range * it->range);
        ++n;
    }
    return n ? std::sqrt(sum / double(n)) : 0.0;
}

// ------------------------------------------------------------------------- which

namespace {

// A candidate's comparisons at trial values, every test's joined: instrument effects re-read
// each test's baseline run; effects that change the response run the co-simulation of every
// test (cached by value).
class PatientEvaluator {
  public:
    PatientEvaluator(const Effect& e, const std::vector<PatientTestCase>& tests,
                     const std::vector<PatientComparison>& baseParts, const MatRegions& regions,
                     const PatientTestSimulator& simulate)
        : m_effect(e),
          m_tests(tests),
          m_baseParts(baseParts),
          m_regions(regions),
          m_simulate(simulate) {
        for (const PatientTestCase& t : tests)
            m_names.push_back(t.name), m_subjects.push_back(t.subject);
    }

    PatientComparison evaluate(const std::vector<double>& v) {
        std::string key;
        for (double x : v) key += fmt("%.17g", x) + ";";
        auto it = m_cache.find(key);
        if (it != m_cache.end()) return it->second;
        std::vector<PatientComparison> parts;
        PatientInstruments inst;
        if (!m_effect.changesTheBag) applyPatientInstrumentEffect(m_effect, v, inst);
        for (size_t t = 0; t < m_tests.size(); ++t) {
            const PatientTestCase& tc = m_tests[t];
            if (!m_effect.changesTheBag) {
                parts.push_back(comparePatient(tc.measured, tc.baseline, inst, getRegions(tc),
                                               &m_baseParts[t]));
                continue;
            }
            const auto overrides = getPatientEffectOverrides(m_effect, v, tc.statedGasMass);
            std::string label = m_effect.name;
            for (size_t i = 0; i < v.size(); ++i)
                label += "-" + m_effect.parameters[i].name +
                         fmt("%.4g", v[i] / m_effect.parameters[i].siPerUnit);
            const PatientChannels run =
                overrides.empty() ? tc.baseline : m_simulate(int(t), overrides, label);
            if (!overrides.empty()) ++m_runs;
            parts.push_back(comparePatient(tc.measured, run, PatientInstruments(), getRegions(tc),
                                           &m_baseParts[t]));
        }
        PatientComparison joined = joinPatientComparisons(parts, m_names, m_subjects);
        if (!m_effect.changesTheBag) return joined;  // cheap: not kept
        return m_cache.emplace(key, std::move(joined)).first->second;
    }
    int getRuns() const { return m_runs; }

  private:
    const MatRegions& getRegions(const PatientTestCase& tc) const {
        return tc.regions.names.empty() ? m_regions : tc.regions;
    }

    const Effect& m_effect;
    const std::vector<PatientTestCase>& m_tests;
    const std::vector<PatientComparison>& m_baseParts;
    const MatRegions& m_regions;
    const PatientTestSimulator& m_simulate;
    std::vector<std::string> m_names, m_subjects;
    std::map<std::string, PatientComparison> m_cache;
    int m_runs = 0;
};

// The grid of a parameter: `points` values from its lower to its upper bound.
std::vector<double> makeAxis(const EffectParameter& p, int points) {
    std::vector<double> a;
    for (int i = 0; i < points; ++i)
        a.push_back(p.lower + (p.upper - p.lower) * double(i) / double(std::max(1, points - 1)));
    return a;
}

struct PatientFit {
    std::vector<double> values;
    double cost = 0.0;
};

// Fits the effect on the training windows: the cost is the gap (not beyond the uncertainty:
// the plain least squares of the channels' residuals, each normalised by its range) over the
// training windows. Every point of the grid (the tensor product of the axes); instrument
// effects are then refined coordinate by coordinate by golden section within a grid cell.
PatientFit fitPatient(PatientEvaluator& e, const Effect& effect, const WhereReport& where,
                      const PatientFolds& folds, const std::vector<int>& train, int gridPoints) {
    const size_t np = effect.parameters.size();
    const int points = effect.changesTheBag ? gridPoints : 11;
    std::vector<std::vector<double>> axes;
    for (const EffectParameter& p : effect.parameters) axes.push_back(makeAxis(p, points));
    auto cost = [&](const std::vector<double>& v) {
        return std::pow(calcPatientGap(e.evaluate(v), where, folds, train, false), 2);
    };
    PatientFit best;
    best.cost = INFINITY;
    std::vector<size_t> idx(np, 0);
    for (;;) {
        std::vector<double> v(np);
        for (size_t i = 0; i < np; ++i) v[i] = axes[i][idx[i]];
        const double c = cost(v);
        if (c < best.cost) best = {v, c};
        size_t i = 0;
        while (i < np && ++idx[i] == axes[i].size()) idx[i++] = 0;
        if (i == np) break;
    }
    if (effect.changesTheBag) {
        // One parameter: a parabola through the best grid point and its neighbours, and one run
        // at its vertex (a co-simulation each: no further search).
        if (np != 1 || points < 3) return best;
        const std::vector<double>& x = axes[0];
        size_t k = size_t(std::find(x.begin(), x.end(), best.values[0]) - x.begin());
        k = std::min(std::max<size_t>(k, 1), x.size() - 2);
        const double f0 = cost({x[k - 1]}), f1 = cost({x[k]}), f2 = cost({x[k + 1]});
        const double h = x[k + 1] - x[k], den = f0 - 2.0 * f1 + f2;
        if (!(den > 0.0)) return best;
        const double v = std::min(std::max(x[k] + 0.5 * h * (f0 - f2) / den, x.front()), x.back());
        const double fv = cost({v});
        if (fv < best.cost) best = {{v}, fv};
        return best;
    }
    // Sweeps until one gains less than 1e-9 of the cost (at most 20).
    for (int sweep = 0; sweep < 20; ++sweep) {
        const double before = best.cost;
        for (size_t i = 0; i < np; ++i) {
            const EffectParameter& p = effect.parameters[i];
            const double cell = (p.upper - p.lower) / double(points - 1);
            double a = std::max(p.lower, best.values[i] - cell),
                   b = std::min(p.upper, best.values[i] + cell);
            const double g = 0.5 * (std::sqrt(5.0) - 1.0);
            std::vector<double> v = best.values;
            auto at = [&](double x) {
                v[i] = x;
                return cost(v);
            };
            double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = at(x1), f2 = at(x2);
            for (int it = 0; it < 30; ++it) {
                if (f1 < f2)
                    b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = at(x1);
                else
                    a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = at(x2);
            }
            const double x = f1 < f2 ? x1 : x2, f = std::min(f1, f2);
            if (f < best.cost) best.values[i] = x, best.cost = f;
        }
        if (!(before - best.cost > 1e-9 * before)) break;
    }
    return best;
}

}  // namespace

std::vector<PatientComparison> comparePatientTests(const std::vector<PatientTestCase>& tests,
                                                   const MatRegions& regions) {
    std::vector<PatientComparison> out;
    for (const PatientTestCase& t : tests)
        out.push_back(comparePatient(t.measured, t.baseline, {},
                                     t.regions.names.empty() ? regions : t.regions));
    return out;
}

WhichReport calibratePatientCandidates(const PatientChannels& measured,
                                       const PatientChannels& baseline,
                                       const PatientComparison& base, const WhereReport& where,
                                       const MatRegions& regions, const std::vector<double>& edges,
                                       double statedGasMass, const PatientSimulator& simulate,
                                       const PatientCalibrationOptions& o) {
    (void)base;  // the same comparison is made again from the baseline
    PatientFolds folds;
    folds.windowEdges = edges;
    return calibratePatientCandidates(
        {{"", measured, baseline, statedGasMass, "", {}}}, where, regions, folds,
        [&](int, const std::vector<std::pair<std::string, std::string>>& ov,
            const std::string& label) { return simulate(ov, label); },
        o);
}

WhichReport calibratePatientCandidates(const std::vector<PatientTestCase>& tests,
                                       const WhereReport& where, const MatRegions& regions,
                                       const PatientFolds& folds,
                                       const PatientTestSimulator& simulate,
                                       const PatientCalibrationOptions& o) {
    WhichReport report;
    if (tests.empty()) throw std::invalid_argument("no test to calibrate on");
    const std::vector<PatientComparison> baseParts = comparePatientTests(tests, regions);
    std::vector<std::string> names, subjects;
    for (const PatientTestCase& t : tests) names.push_back(t.name), subjects.push_back(t.subject);
    const PatientComparison base = joinPatientComparisons(baseParts, names, subjects);
    std::vector<const Effect*> candidates;
    if (o.candidates.empty()) {
        if (base.find("bag-pressure")) candidates.push_back(findPatientEffect(kBagSensor));
        if (base.find("mat")) candidates.push_back(findPatientEffect(kMatGain));
    } else {
        for (const std::string& n : o.candidates) {
            const Effect* e = findPatientEffect(n);
            if (!e)
                throw std::invalid_argument("'" + n +
                                            "' is not an effect of the patient's library; valid: " +
                                            listPatientEffectNames());
            candidates.push_back(e);
        }
    }
    if ((folds.isByTest() || folds.isBySubject()) && folds.tests != int(tests.size()))
        throw std::invalid_argument("the folds name " + std::to_string(folds.tests) +
                                    " tests, the data " + std::to_string(tests.size()));
    if (folds.isBySubject()) {
        if (folds.testSubject.size() != tests.size())
            throw std::invalid_argument(
                "the folds give " + std::to_string(folds.testSubject.size()) +
                " tests a subject, the data have " + std::to_string(tests.size()));
        for (int s : folds.testSubject)
            if (s < 0 || s >= int(folds.subjects.size()))
                throw std::invalid_argument("a test's subject " + std::to_string(s) +
                                            " is not one of the " +
                                            std::to_string(folds.subjects.size()) + " subjects");
    }
    const int nw = folds.getCount();
    if (nw < 2)
        throw std::invalid_argument("the folds need two time windows, tests or subjects or more");
    std::vector<int> all(static_cast<size_t>(nw), 0);
    for (int w = 0; w < nw; ++w) all[size_t(w)] = w;

    for (const Effect* effect : candidates) {
        PatientEvaluator e(*effect, tests, baseParts, regions, simulate);
        CandidateResult c;
        c.effect = effect->name;
        std::map<std::string, std::array<std::vector<double>, 3>> held;  // measured, before, after
        for (int h = 0; h < nw; ++h) {
            std::vector<int> train;
            for (int w = 0; w < nw; ++w)
                if (w != h) train.push_back(w);
            const PatientFit fit = fitPatient(e, *effect, where, folds, train, o.gridPoints);
            const PatientComparison after = e.evaluate(fit.values);
            FoldResult f;
            f.heldOut = h;
            f.parameters = fit.values;
            f.before = calcPatientGap(base, where, folds, {h}, false);
            f.after = calcPatientGap(after, where, folds, {h}, false);
            f.excessBefore = calcPatientGap(base, where, folds, {h}, true);
            f.excessAfter = calcPatientGap(after, where, folds, {h}, true);
            c.folds.push_back(f);
            for (const PatientChannelComparison& ch : base.channels) {
                const PatientChannelComparison* a = after.find(ch.name);
                auto& hv = held[ch.name];
                for (size_t i = 0; i < ch.time.size(); ++i)
                    if (folds.findFold(ch, i) == h) {
                        hv[0].push_back(ch.measured[i]);
                        hv[1].push_back(ch.simulated[i]);
                        hv[2].push_back(a && i < a->simulated.size() ? a->simulated[i]
                                                                     : ch.simulated[i]);
                    }
            }
        }
        const PatientFit whole = fitPatient(e, *effect, where, folds, all, o.gridPoints);
        c.parameters = whole.values;
        c.parameterStdDev.assign(whole.values.size(), kNaN);
        for (const FoldResult& f : c.folds) {
            c.heldoutBefore += f.before / nw, c.heldoutAfter += f.after / nw;
            c.excessBefore += f.excessBefore / nw, c.excessAfter += f.excessAfter / nw;
        }
        c.shrink = c.heldoutBefore > 0.0 ? 1.0 - c.heldoutAfter / c.heldoutBefore : 0.0;
        c.excessShrink = c.excessBefore > 0.0 ? 1.0 - c.excessAfter / c.excessBefore : 0.0;
        c.score = c.excessShrink - o.parameterPenalty * double(effect->parameters.size());
        c.simulations = e.getRuns();
        for (const PatientChannelComparison& ch : base.channels) {
            const auto& hv = held[ch.name];
            c.heldoutMetricsBefore.push_back(calcPairedMetrics(ch.name, hv[0], hv[1]));
            c.heldoutMetricsAfter.push_back(calcPairedMetrics(ch.name, hv[0], hv[2]));
        }
        report.candidates.push_back(std::move(c));
    }
    std::stable_sort(
        report.candidates.begin(), report.candidates.end(),
        [](const CandidateResult& a, const CandidateResult& b) { return a.score > b.score; });

    // The verdict as the rig's single stage.
    ChannelUncertainties validation;
    for (const ChannelSummary& c : where.channels) validation[c.channel] = c.validation;
    report.confusable = findConfusable(report.candidates, o.explainThreshold, validation);
    const CandidateResult* best = report.candidates.empty() ? nullptr : &report.candidates.front();
    report.pairStageReason = "not run on a patient's data (one effect at a time)";
    if (where.withinValidation) {
        report.verdict = "none";
        report.reason = "every channel's RMSE is within twice its validation uncertainty";
    } else if (best && best->score >= o.explainThreshold) {
        report.verdict = best->effect;
        report.verdictEffects = {best->effect};
        report.reason =
            best->effect + " shrinks the held-out gap beyond the validation uncertainty by " +
            fmt("%.0f", 100 * best->excessShrink) + " % (score " + fmt("%.3f", best->score) +
            ", at least " + fmt("%g", o.explainThreshold) + " needed)";
    } else {
        report.verdict = "unexplained";
        report.reason = best ? "the best candidate, " + best->effect + ", scores " +
                                   fmt("%.3f", best->score) + " (at least " +
                                   fmt("%g", o.explainThreshold) + " needed)"
                             : "no candidate applies to these channels";
    }
    qualifyVerdict(report, validation, getPatientEffects());
    return report;
}

}  // namespace diagnose
