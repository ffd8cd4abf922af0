#include <diagnose/Diagnosis.h>
#include <diagnose/Signatures.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <numeric>
#include <stdexcept>

#include "Format.h"

namespace diagnose {

namespace {

using detail::fmt;
using detail::kNaN;

// One branch of a simulated curve with increasing crosshead displacement.
struct Branch {
    std::vector<double> d, f, p;
    void add(double di, double fi, double pi) {
        if (!d.empty() && !(di > d.back())) {
            // Keep the abscissa increasing: a step that did not advance replaces the last; one
            // that went back (a snap on the branch) is left out.
            if (di >= d.back() - 1e-12) f.back() = fi, p.back() = pi;
            return;
        }
        d.push_back(di), f.push_back(fi), p.push_back(pi);
    }
};

}  // namespace

std::string getChannelName(ChannelKind c) {
    switch (c) {
        case ChannelKind::Force:
            return "force";
        case ChannelKind::Pressure:
            return "pressure";
        case ChannelKind::Bed:
            return "bed";
        default:
            return "mass";
    }
}
ChannelKind getChannelKind(const std::string& name) {
    return name == "force"      ? ChannelKind::Force
           : name == "pressure" ? ChannelKind::Pressure
           : name == "bed"      ? ChannelKind::Bed
                                : ChannelKind::Mass;
}
std::string getChannelUnit(ChannelKind c) {
    switch (c) {
        case ChannelKind::Force:
            return "N";
        case ChannelKind::Pressure:
            return "kPa";
        case ChannelKind::Bed:
            return "mm";
        default:
            return "g";
    }
}
double getChannelUnitScale(ChannelKind c) {
    switch (c) {
        case ChannelKind::Force:
            return 1.0;
        case ChannelKind::Pressure:
            return 1e3;
        default:
            return 1e-3;  // g, mm
    }
}

const GapScale::Scale& GapScale::get(ChannelKind kind) const {
    static const Scale none;
    return kind == ChannelKind::Force      ? force
           : kind == ChannelKind::Pressure ? pressure
           : kind == ChannelKind::Bed      ? bed
                                           : none;
}
GapScale::Scale& GapScale::get(ChannelKind kind) {
    if (kind == ChannelKind::Mass)
        throw std::invalid_argument("the flowmeter's mass is not a channel of the gap");
    return kind == ChannelKind::Force ? force : kind == ChannelKind::Pressure ? pressure : bed;
}

namespace {
int getGapIndex(ChannelKind kind) {
    if (kind == ChannelKind::Mass)
        throw std::invalid_argument("the flowmeter's mass is not a channel of the gap");
    return kind == ChannelKind::Force ? 0 : kind == ChannelKind::Pressure ? 1 : 2;
}
}  // namespace

double GapScale::getUncertainty(ChannelKind kind, int test) const {
    const auto it = testUncertainty.find(test);
    if (it == testUncertainty.end() || kind == ChannelKind::Mass) return getUncertainty(kind);
    return it->second[getGapIndex(kind)];
}

GapScale makeGapScale(const WhereReport& where, const std::vector<TestComparison>& tests) {
    GapScale g;
    double noise[3] = {0.0, 0.0, 0.0};
    for (const ChannelSummary& c : where.channels) {
        const ChannelKind k = getChannelKind(c.channel);
        if (k == ChannelKind::Mass) continue;
        GapScale::Scale& s = g.get(k);
        s.range = c.range;
        s.uncertainty = c.validation;
        noise[getGapIndex(k)] = c.noise;
    }
    for (const TestComparison& t : tests) {
        std::array<double, 3> u = {g.force.uncertainty, g.pressure.uncertainty, g.bed.uncertainty};
        for (size_t c = 0; c < t.channels.size(); ++c) {
            const ChannelKind k = t.channels[c].kind;
            if (k == ChannelKind::Mass) continue;
            auto at = [&](const std::vector<double>& v) { return c < v.size() ? v[c] : 0.0; };
            const double n = noise[getGapIndex(k)];
            u[getGapIndex(k)] = std::sqrt(n * n + std::pow(at(t.numericalUncertainty), 2) +
                                          std::pow(at(t.inputUncertainty), 2) +
                                          std::pow(at(t.inputUncertaintyGasMass), 2) +
                                          std::pow(at(t.inputUncertaintyTemperature), 2));
        }
        g.testUncertainty[t.test] = u;
    }
    return g;
}

TestComparison compareTest(const MeasuredTest& test, int index, const bags::LoadCurve& sim,
                           const RigEffects& rig, double rate) {
    const MachineCurve mc = calcMachineCurve(sim, rig, rate);
    Branch load, unload;
    size_t last = 0;
    for (size_t i = 0; i < mc.time.size(); ++i)
        if (mc.loading[i]) load.add(mc.displacement[i], mc.force[i], mc.pressure[i]), last = i;
    // Unloading from the peak (the last loading state) back towards the rest state.
    std::vector<size_t> un = {last};
    for (size_t i = 0; i < mc.time.size(); ++i)
        if (!mc.loading[i]) un.push_back(i);
    if (!mc.time.empty() && mc.displacement[un.back()] > 0.0) {
        // The block has left the bag: no force, the bag at rest as before loading.
        unload.add(0.0, 0.0, mc.pressure.front());
    }
    for (auto it = un.rbegin(); it != un.rend(); ++it)
        unload.add(mc.displacement[*it], mc.force[*it], mc.pressure[*it]);
    if (unload.d.size() < 2) unload = load;  // no unloading simulated: the loading branch

    TestComparison tc;
    tc.test = index;
    tc.gasMass = test.gasMass;
    const size_t turn = std::max_element(test.displacement.begin(), test.displacement.end()) -
                        test.displacement.begin();
    const double tTurn = test.time[turn];
    auto simAt = [&](double d, bool loading, bool pressure) {
        const Branch& b = loading ? load : unload;
        if (b.d.empty()) return 0.0;
        return pressure ? interpolate(b.d, b.p, d) : std::max(0.0, interpolate(b.d, b.f, d));
    };

    ChannelComparison f;
    f.kind = ChannelKind::Force;
    f.time = test.time;
    f.displacement = test.displacement;
    f.force = test.force;
    f.measured = test.force;
    for (size_t i = 0; i < test.time.size(); ++i) {
        const bool l = test.time[i] <= tTurn;
        f.loading.push_back(l ? 1 : 0);
        f.simulated.push_back(simAt(test.displacement[i], l, false));
    }

    // A channel on its own time base: the machine's displacement and force and the branch at
    // its sample times.
    auto startChannel = [&](ChannelKind kind, const Channel& c) {
        ChannelComparison ch;
        ch.kind = kind;
        ch.time = c.time;
        ch.measured = c.value;
        for (double t : ch.time) {
            ch.displacement.push_back(interpolateClamped(test.time, test.displacement, t));
            ch.force.push_back(interpolateClamped(test.time, test.force, t));
            ch.loading.push_back(t <= tTurn ? 1 : 0);
        }
        return ch;
    };

    ChannelComparison p = startChannel(ChannelKind::Pressure, test.pressure);
    std::vector<double> truePressure;
    for (size_t i = 0; i < p.time.size(); ++i)
        truePressure.push_back(simAt(p.displacement[i], p.loading[i], true));
    p.simulated = applyPressureSensor(p.time, truePressure, rig);

    ChannelComparison m = startChannel(ChannelKind::Mass, test.flowmeter);
    m.simulated.assign(m.time.size(), sim.gasMass + rig.flowmeterOffset);
    tc.channels = {std::move(f), std::move(p), std::move(m)};
    if (!test.bed.empty()) {
        // The bed gauge: the board sinks by the force on it (the block's, as the load cell
        // would read it without its gain) times the bed's compliance.
        ChannelComparison b = startChannel(ChannelKind::Bed, test.bed);
        for (size_t i = 0; i < b.time.size(); ++i)
            b.simulated.push_back(rig.bedCompliance *
                                  simAt(b.displacement[i], b.loading[i], false) /
                                  (1.0 + rig.loadCellGain));
        tc.channels.push_back(std::move(b));
    }
    const size_t nch = tc.channels.size();
    tc.numericalUncertainty.assign(nch, 0.0);
    tc.inputUncertainty.assign(nch, 0.0);
    tc.inputUncertaintyGasMass.assign(nch, 0.0);
    tc.inputUncertaintyTemperature.assign(nch, 0.0);
    return tc;
}

std::string getProtocolInputName(ProtocolInput input) {
    return input == ProtocolInput::GasMass ? "gas_mass" : "room_temperature";
}

std::vector<InputRun> makeInputRuns(const MeasuredData& data, const bags::LoadTestOptions& base) {
    std::vector<InputRun> runs;
    bool mass = false;
    for (const MeasuredTest& t : data.tests) mass = mass || t.gasMassUncertainty > 0.0;
    if (mass && base.gasMasses.size() != data.tests.size())
        throw std::invalid_argument("the simulation's gas masses are not one per test");
    for (int sign : {1, -1}) {
        if (mass) {
            InputRun r;
            r.input = ProtocolInput::GasMass;
            r.sign = sign;
            r.options = base;
            for (size_t i = 0; i < data.tests.size(); ++i)
                r.options.gasMasses[i] += sign * data.tests[i].gasMassUncertainty;
            runs.push_back(std::move(r));
        }
    }
    if (data.protocol.roomTemperatureUncertainty > 0.0)
        for (int sign : {1, -1}) {
            InputRun r;
            r.input = ProtocolInput::RoomTemperature;
            r.sign = sign;
            r.options = base;
            // The gas is at the room's temperature, and relaxes to it with heat exchange.
            r.options.gas.temperature += sign * data.protocol.roomTemperatureUncertainty;
            runs.push_back(std::move(r));
        }
    return runs;
}

std::vector<double> calcSensitivityUncertainty(const TestComparison& plus,
                                               const TestComparison& minus) {
    // Half the central difference is |dS/dx| u at each sample: the RMS difference halved.
    std::vector<double> d = calcSimulatedRmsDifference(plus, minus);
    for (double& v : d) v *= 0.5;
    return d;
}

std::vector<double> combineInputUncertainties(const std::vector<std::vector<double>>& terms) {
    std::vector<double> out;
    for (const std::vector<double>& t : terms) {
        if (out.size() < t.size()) out.resize(t.size(), 0.0);
        for (size_t c = 0; c < t.size(); ++c) out[c] += t[c] * t[c];
    }
    for (double& v : out) v = std::sqrt(v);
    return out;
}

std::vector<bags::LoadTestResult> runLoadTests(
    const std::vector<bags::LoadTestOptions>& runs,
    const std::function<bags::LoadTestResult(const bags::LoadTestOptions&)>& simulate,
    int threads) {
    std::vector<bags::LoadTestResult> out(runs.size());
    std::vector<std::exception_ptr> errors(runs.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::max(1, threads))
    for (int i = 0; i < static_cast<int>(runs.size()); ++i) {
        try {
            out[i] = simulate(runs[i]);
        } catch (...) {
            errors[i] = std::current_exception();
        }
    }
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);  // the first failure by index (e.g. an interrupt)
    return out;
}

void addInputUncertainties(const MeasuredData& data, const std::vector<InputRun>& runs,
                           const std::vector<bags::LoadTestResult>& results, const RigEffects& rig,
                           double rate, std::vector<TestComparison>& tests) {
    for (ProtocolInput input : {ProtocolInput::GasMass, ProtocolInput::RoomTemperature}) {
        int plus = -1, minus = -1;
        for (size_t r = 0; r < runs.size(); ++r)
            if (runs[r].input == input) (runs[r].sign > 0 ? plus : minus) = static_cast<int>(r);
        if (plus < 0 || minus < 0) continue;
        for (TestComparison& t : tests) {
            const MeasuredTest& m = data.tests[t.test];
            const std::vector<double> u = calcSensitivityUncertainty(
                compareTest(m, t.test, results[plus].curves[t.test], rig, rate),
                compareTest(m, t.test, results[minus].curves[t.test], rig, rate));
            (input == ProtocolInput::GasMass ? t.inputUncertaintyGasMass
                                             : t.inputUncertaintyTemperature) = u;
        }
    }
}

std::vector<WhereReport::StatedInput> describeInputs(const MeasuredData& data) {
    WhereReport::StatedInput mass, temperature;
    mass.input = ProtocolInput::GasMass;
    for (const MeasuredTest& t : data.tests) {
        mass.stated = mass.stated || t.gasMassUncertaintyStated;
        mass.values.push_back(t.gasMassUncertainty);
    }
    temperature.input = ProtocolInput::RoomTemperature;
    temperature.stated = data.protocol.roomTemperatureUncertaintyStated;
    temperature.values = {data.protocol.roomTemperatureUncertainty};
    return {mass, temperature};
}

WhereReport calcWhere(const std::vector<TestComparison>& tests, const WhereOptions& o) {
    WhereReport r;
    if (tests.empty()) return r;
    const size_t nch = tests[0].channels.size();
    for (const TestComparison& t : tests)
        for (size_t c = 0; c < nch; ++c)
            if (t.channels.size() != nch || t.channels[c].kind != tests[0].channels[c].kind)
                throw std::invalid_argument("the tests' channels differ (test " +
                                            std::to_string(t.test + 1) +
                                            "); valid: the same channels in every test");
    std::vector<double> nrmse2(nch, 0.0);  // per channel; 0 for the mass and a flat channel
    size_t inGap = 0;
    for (size_t c = 0; c < nch; ++c) {
        const ChannelKind kind = tests[0].channels[c].kind;
        const std::string name = getChannelName(kind);
        // Regimes, each a family whose shares add up to 1.
        std::map<std::string, std::vector<double>> regimes;
        std::vector<std::string> order;
        auto add = [&](const std::string& regime, double res) {
            auto it = regimes.find(regime);
            if (it == regimes.end()) {
                order.push_back(regime);
                it = regimes.emplace(regime, std::vector<double>()).first;
            }
            it->second.push_back(res);
        };
        double lo = INFINITY, hi = -INFINITY, travel = 0.0, numSum = 0.0, meshSum = 0.0,
               inSum = 0.0, sumSq = 0.0;
        double massSum = 0.0, tempSum = 0.0;  // the stated inputs' terms, weighted by samples
        long numN = 0, inN = 0, total = 0;
        std::vector<double> secondDifferences;
        for (const TestComparison& t : tests) {
            const ChannelComparison& ch = t.channels[c];
            const std::string mass = "gas mass " + fmt("%.2f g", t.gasMass * 1e3);
            const double t0 = ch.time.empty() ? 0.0 : ch.time.front();
            const double span = ch.time.empty() ? 0.0 : ch.time.back() - t0;
            for (size_t i = 0; i < ch.measured.size(); ++i) {
                const double res = ch.measured[i] - ch.simulated[i];
                lo = std::min(lo, ch.measured[i]);
                hi = std::max(hi, ch.measured[i]);
                travel = std::max(travel, ch.displacement[i]);
                sumSq += res * res;
                ++total;
                add("all", res);
                add(mass, res);
                add(ch.loading[i] ? "loading" : "unloading", res);
                const double fi = ch.force[i];
                add(fi < o.loadFrom  ? "load below " + fmt("%g N", o.loadFrom)
                    : fi <= o.loadTo ? "load " + fmt("%g", o.loadFrom) + "-" + fmt("%g N", o.loadTo)
                                     : "load above " + fmt("%g N", o.loadTo),
                    res);
                // Time windows: thirds of each test's record (drift, warming, settling).
                const int third = span > 0.0 ? std::min(2, int(3.0 * (ch.time[i] - t0) / span)) : 0;
                add("time " +
                        std::string(third == 0   ? "first"
                                    : third == 1 ? "middle"
                                                 : "last") +
                        " third",
                    res);
            }
            addSecondDifferences(ch.measured, secondDifferences);
            if (c < t.numericalUncertainty.size()) {
                numSum += t.numericalUncertainty[c] * t.numericalUncertainty[c];
                if (c < t.numericalUncertaintyMesh.size())
                    meshSum += t.numericalUncertaintyMesh[c] * t.numericalUncertaintyMesh[c];
                ++numN;
            }
            if (c < t.inputUncertainty.size()) {
                inSum += t.inputUncertainty[c] * t.inputUncertainty[c];
                ++inN;
            }
            // Each test's term is an RMS over its samples: the channel's is the RMS over all.
            const double n = static_cast<double>(ch.measured.size());
            if (c < t.inputUncertaintyGasMass.size())
                massSum += n * t.inputUncertaintyGasMass[c] * t.inputUncertaintyGasMass[c];
            if (c < t.inputUncertaintyTemperature.size())
                tempSum += n * t.inputUncertaintyTemperature[c] * t.inputUncertaintyTemperature[c];

            // Signatures of this test.
            Signature s = calcSeriesSignature(name, ch.time, ch.measured, ch.simulated, o.maxLag);
            s.test = t.test;
            s.gasMass = t.gasMass;
            for (size_t i = 1; i < ch.measured.size(); ++i) {
                const double dd = ch.displacement[i] - ch.displacement[i - 1];
                s.loopAreaMeasured += 0.5 * (ch.measured[i] + ch.measured[i - 1]) * dd;
                s.loopAreaSimulated += 0.5 * (ch.simulated[i] + ch.simulated[i - 1]) * dd;
            }
            r.signatures.push_back(s);
        }
        // A residual that is not a finite number (a sample of 1e200 squares to infinity) must
        // never reach a verdict: infinity against an infinite uncertainty compares as "within".
        if (!std::isfinite(sumSq)) {
            double worst = -1.0, when = 0.0;
            size_t which = 0;
            for (const TestComparison& t : tests) {
                const ChannelComparison& ch = t.channels[c];
                for (size_t i = 0; i < ch.measured.size(); ++i) {
                    const double a = std::max(std::abs(ch.measured[i]), std::abs(ch.simulated[i]));
                    if (!(a <= worst)) worst = a, when = ch.time[i], which = size_t(t.test);
                }
            }
            throw std::domain_error("the " + name + " residual is not a finite number: test " +
                                    std::to_string(which + 1) + fmt(" at %g s", when) +
                                    " has a sample of " + fmt("%g", worst) +
                                    " (in SI); no verdict can be drawn from it. Check that "
                                    "sample in the measured data");
        }
        ChannelSummary cs;
        cs.channel = name;
        cs.rmse = total ? std::sqrt(sumSq / double(total)) : 0.0;
        cs.range = kind == ChannelKind::Bed ? travel : hi - lo;
        cs.noise = calcNoise(secondDifferences);
        cs.numerical = numN ? std::sqrt(numSum / double(numN)) : 0.0;
        cs.numericalMesh = numN ? std::sqrt(meshSum / double(numN)) : 0.0;
        cs.input = inN ? std::sqrt(inSum / double(inN)) : 0.0;
        cs.inputGasMass = total ? std::sqrt(massSum / double(total)) : 0.0;
        cs.inputTemperature = total ? std::sqrt(tempSum / double(total)) : 0.0;
        cs.validation = std::sqrt(cs.noise * cs.noise + cs.numerical * cs.numerical +
                                  cs.input * cs.input + cs.inputGasMass * cs.inputGasMass +
                                  cs.inputTemperature * cs.inputTemperature);
        r.channels.push_back(cs);
        if (kind != ChannelKind::Mass && cs.range > 0.0)
            nrmse2[c] = std::pow(cs.rmse / cs.range, 2), ++inGap;
        for (const std::string& g : order)
            r.regimes.push_back(calcRegimeStats(name, g, regimes[g], sumSq));
    }
    const double sum2 = std::accumulate(nrmse2.begin(), nrmse2.end(), 0.0);
    r.gap = inGap ? std::sqrt(sum2 / double(inGap)) : 0.0;
    for (size_t c = 0; c < nch; ++c) r.channels[c].shareOfGap = sum2 > 0.0 ? nrmse2[c] / sum2 : 0.0;
    r.withinValidation = true;
    for (const ChannelSummary& cs : r.channels)
        if (cs.channel != "mass" && cs.rmse > kExplainedMultiple * cs.validation)
            r.withinValidation = false;
    return r;
}

std::string describeGap(const WhereReport& where) {
    for (const ChannelSummary& c : where.channels)
        if (getChannelKind(c.channel) == ChannelKind::Bed)
            return "RMS over force, pressure and the bed gauge of RMSE / measured range (the "
                   "bed's: the crosshead's travel)";
    return "RMS over force and pressure of RMSE / measured range";
}

double calcGap(const std::vector<TestComparison>& tests, const std::vector<int>& which,
               const GapScale& scale, bool beyondUncertainty) {
    const ChannelKind kinds[] = {ChannelKind::Force, ChannelKind::Pressure, ChannelKind::Bed};
    double sum = 0.0;
    int counted = 0;
    for (ChannelKind kind : kinds) {
        double s = 0.0, uu = 0.0;  // squared residuals; samples times squared uncertainty
        long n = 0;
        for (int w : which)
            for (const ChannelComparison& ch : tests[w].channels) {
                if (ch.kind != kind) continue;
                for (size_t i = 0; i < ch.measured.size(); ++i)
                    s += std::pow(ch.measured[i] - ch.simulated[i], 2), ++n;
                if (beyondUncertainty)
                    uu += double(ch.measured.size()) *
                          std::pow(scale.getUncertainty(kind, tests[w].test), 2);
            }
        const double range = scale.getRange(kind);
        if (n == 0 || !(range > 0.0)) continue;  // no bed gauge; a flat channel (as calcWhere)
        ++counted;
        sum += std::max(0.0, (s - uu) / double(n)) / (range * range);
    }
    return counted ? std::sqrt(sum / double(counted)) : 0.0;
}

std::vector<double> calcSimulatedRmsDifference(const TestComparison& a, const TestComparison& b) {
    std::vector<double> out;
    for (size_t c = 0; c < a.channels.size() && c < b.channels.size(); ++c) {
        const auto& x = a.channels[c].simulated;
        const auto& y = b.channels[c].simulated;
        double s = 0.0;
        const size_t n = std::min(x.size(), y.size());
        for (size_t k = 0; k < n; ++k) s += (x[k] - y[k]) * (x[k] - y[k]);
        out.push_back(n ? std::sqrt(s / double(n)) : 0.0);
    }
    return out;
}

std::vector<GapMetrics> calcGapMetrics(const std::vector<TestComparison>& tests) {
    std::vector<GapMetrics> out;
    for (ChannelKind kind : {ChannelKind::Force, ChannelKind::Pressure, ChannelKind::Bed}) {
        std::vector<double> d, sim;
        for (const TestComparison& t : tests)
            for (const ChannelComparison& ch : t.channels) {
                if (ch.kind != kind) continue;
                d.insert(d.end(), ch.measured.begin(), ch.measured.end());
                sim.insert(sim.end(), ch.simulated.begin(), ch.simulated.end());
            }
        if (d.empty() && kind == ChannelKind::Bed) continue;  // no bed gauge
        out.push_back(calcPairedMetrics(getChannelName(kind), d, sim));
    }
    return out;
}

}  // namespace diagnose
