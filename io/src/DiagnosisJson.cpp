#include <io/DiagnosisJson.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "JsonText.h"

namespace io {

namespace {

using diagnose::getChannelKind;
using json::formatFolds;
using json::formatGaps;
using json::formatParameters;
using json::formatVerdictQualifiers;
using json::num;
using json::str;

// A channel value [SI] in the channel's unit.
double inUnit(const std::string& channel, double v) {
    return v / diagnose::getChannelUnitScale(getChannelKind(channel));
}

// A pair's parameters, the first effect's then the second's, each named "effect.parameter".
std::string formatPairParameters(const diagnose::PairResult& p, const std::vector<double>& v,
                                 const std::vector<double>* sd) {
    std::ostringstream os;
    os << "{";
    size_t k = 0;
    for (const std::string& name : {p.first, p.second}) {
        const diagnose::Effect* e = diagnose::findEffect(name);
        for (size_t i = 0; e && i < e->parameters.size() && k < v.size(); ++i, ++k) {
            const diagnose::EffectParameter& q = e->parameters[i];
            os << (k ? ", " : "") << str(name + "." + q.name)
               << ": {\"value\": " << num(v[k] / q.siPerUnit);
            if (sd && k < sd->size()) os << ", \"std_dev\": " << num((*sd)[k] / q.siPerUnit);
            os << ", \"unit\": " << str(q.unit) << "}";
        }
    }
    return os.str() + "}";
}

std::string formatMetric(const diagnose::GapMetrics& g) {
    return "{\"rmse\": " + num(inUnit(g.channel, g.rmse)) +
           ", \"mean_error\": " + num(inUnit(g.channel, g.meanError)) +
           ", \"max_error\": " + num(inUnit(g.channel, g.maxError)) +
           ", \"area_validation_metric\": " + num(inUnit(g.channel, g.areaMetric)) + "}";
}

// Per channel, before and after, over every test when held out; with the channel's
// validation uncertainty from the where report.
std::string formatMetrics(const diagnose::CandidateResult& c, const diagnose::WhereReport& w) {
    std::ostringstream os;
    os << "{";
    for (size_t i = 0; i < c.heldoutMetricsBefore.size(); ++i) {
        const diagnose::GapMetrics& b = c.heldoutMetricsBefore[i];
        double uval = NAN;
        for (const auto& ch : w.channels)
            if (ch.channel == b.channel) uval = ch.validation;
        os << (i ? ", " : "") << str(b.channel)
           << ": {\"unit\": " << str(diagnose::getChannelUnit(getChannelKind(b.channel)))
           << ", \"samples\": " << b.samples
           << ", \"validation_uncertainty\": " << num(inUnit(b.channel, uval))
           << ", \"before\": " << formatMetric(b) << ", \"after\": "
           << (i < c.heldoutMetricsAfter.size() ? formatMetric(c.heldoutMetricsAfter[i])
                                                : std::string("null"))
           << "}";
    }
    return os.str() + "}";
}

// The stiffness curve beside the simulated one, stiffness in N/mm.
std::string formatStiffness(const diagnose::StiffnessComparison& k) {
    std::ostringstream os;
    os << "{\"unit\": \"N/mm\", \"scale\": " << num(k.scale, "%.4f")
       << ", \"missing\": " << k.missing << ", \"stages_agreeing\": " << k.stagesAgreeing
       << ", \"stages_compared\": " << k.stagesCompared
       << ", \"least_stiffness_gas_mass_g\": {\"measured\": " << num(k.leastMeasured * 1e3)
       << ", \"simulated\": " << num(k.leastSimulated * 1e3) << "},\n    \"regimes\": [";
    for (size_t i = 0; i < k.regimes.size(); ++i) {
        const auto& r = k.regimes[i];
        os << (i ? ", " : "") << "{\"regime\": " << str(r.regime) << ", \"points\": " << r.points
           << ", \"rmse\": " << num(r.rmse * 1e-3) << ", \"bias\": " << num(r.bias * 1e-3)
           << ", \"relative\": " << num(r.relative, "%.4f")
           << ", \"share\": " << num(r.share, "%.4f") << "}";
    }
    os << "],\n    \"points\": [";
    for (size_t i = 0; i < k.points.size(); ++i) {
        const auto& p = k.points[i];
        os << (i ? ",\n      " : "\n      ") << "{\"gas_mass_g\": " << num(p.gasMass * 1e3)
           << ", \"measured\": " << num(p.measured * 1e-3)
           << ", \"simulated\": " << num(p.simulated * 1e-3)
           << ", \"measured_stage\": " << p.measuredStage
           << ", \"simulated_stage\": " << p.simulatedStage << ", \"note\": " << str(p.note) << "}";
    }
    return os.str() + "]}";
}

// The which part on a stiffness curve: its candidates ranked (as the tests', held out by gas
// mass), those not applicable, the transformations that are the same on a curve, the verdict.
std::string formatCurveWhich(const diagnose::StiffnessWhich& w) {
    std::ostringstream os;
    std::vector<std::string> masses;
    for (double m : w.gasMasses) masses.push_back(num(m * 1e3) + " g");
    os << "{\"unit\": \"N/mm\", \"gas_masses_g\": [";
    for (size_t i = 0; i < w.gasMasses.size(); ++i)
        os << (i ? ", " : "") << num(w.gasMasses[i] * 1e3);
    os << "], \"range\": " << num(w.range * 1e-3) << ", \"rmse\": " << num(w.rmse * 1e-3)
       << ", \"validation_uncertainty\": " << num(w.validation * 1e-3)
       << ", \"validation_uncertainty_is\": " << str(w.validationWhat)
       << ", \"within_validation_uncertainty\": " << (w.withinValidation ? "true" : "false")
       << ",\n    \"candidates\": [\n";
    for (size_t i = 0; i < w.which.candidates.size(); ++i) {
        const auto& c = w.which.candidates[i];
        const diagnose::Effect* e = diagnose::findEffect(c.effect);
        double interp = NAN;
        for (const auto& [name, v] : w.interpolationErrors)
            if (name == c.effect) interp = v;
        os << "      {\"rank\": " << i + 1 << ", \"effect\": " << str(c.effect)
           << ", \"parameters\": " << formatParameters(e, c.parameters, &c.parameterStdDev) << ", "
           << formatGaps(c) << ", \"simulations\": " << c.simulations
           << ", \"interpolation_error\": " << num(interp * 1e-3)
           << ",\n       \"heldout_metrics\": {";
        if (!c.heldoutMetricsBefore.empty()) {
            const auto& b = c.heldoutMetricsBefore[0];
            auto metric = [](const diagnose::GapMetrics& g) {
                return "{\"rmse\": " + num(g.rmse * 1e-3) +
                       ", \"mean_error\": " + num(g.meanError * 1e-3) +
                       ", \"max_error\": " + num(g.maxError * 1e-3) +
                       ", \"area_validation_metric\": " + num(g.areaMetric * 1e-3) + "}";
            };
            os << "\"stiffness\": {\"unit\": \"N/mm\", \"samples\": " << b.samples
               << ", \"validation_uncertainty\": " << num(w.validation * 1e-3)
               << ", \"before\": " << metric(b) << ", \"after\": "
               << (c.heldoutMetricsAfter.empty() ? std::string("null")
                                                 : metric(c.heldoutMetricsAfter[0]))
               << "}";
        }
        os << "},\n       \"folds\": "
           << formatFolds(
                  c, [&](const std::vector<double>& v) { return formatParameters(e, v, nullptr); },
                  "held_out_gas_mass", &masses)
           << "}" << (i + 1 < w.which.candidates.size() ? "," : "") << "\n";
    }
    os << "    ],\n    \"confusable\": [";
    for (size_t i = 0; i < w.which.confusable.size(); ++i)
        os << (i ? ", " : "") << "[" << str(w.which.confusable[i].first) << ", "
           << str(w.which.confusable[i].second) << "]";
    os << "],\n    \"same_on_a_curve\": [";
    for (size_t i = 0; i < w.identical.size(); ++i)
        os << (i ? ", " : "") << "{\"effects\": [" << str(w.identical[i].first.first) << ", "
           << str(w.identical[i].first.second) << "], \"why\": " << str(w.identical[i].second)
           << "}";
    os << "],\n    \"not_applicable\": [";
    for (size_t i = 0; i < w.notApplicable.size(); ++i)
        os << (i ? ",\n      " : "\n      ") << "{\"effect\": " << str(w.notApplicable[i].effect)
           << ", \"why\": " << str(w.notApplicable[i].why) << "}";
    os << "],\n    \"verdict\": " << str(w.which.verdict) << ", \"verdict_effects\": [";
    for (size_t i = 0; i < w.which.verdictEffects.size(); ++i)
        os << (i ? ", " : "") << str(w.which.verdictEffects[i]);
    os << "], " << formatVerdictQualifiers(w.which) << ", \"reason\": " << str(w.which.reason)
       << "}";
    return os.str();
}

// The protocol's stated input uncertainties (the where report's statedInputs).
std::string formatStatedInputs(const diagnose::WhereReport& w) {
    std::ostringstream os;
    os << "[";
    for (size_t i = 0; i < w.statedInputs.size(); ++i) {
        const auto& s = w.statedInputs[i];
        const bool mass = s.input == diagnose::ProtocolInput::GasMass;
        os << (i ? ",\n      " : "\n      ")
           << "{\"input\": " << str(diagnose::getProtocolInputName(s.input))
           << ", \"stated\": " << (s.stated ? "true" : "false")
           << ", \"unit\": " << str(mass ? "g" : "K") << ", \"standard_uncertainty\": [";
        for (size_t k = 0; k < s.values.size(); ++k)
            os << (k ? ", " : "") << num(s.values[k] * (mass ? 1e3 : 1.0));
        os << "], \"per\": " << str(mass ? "test" : "protocol")
           << ", \"text\": " << str(formatStatedInput(s)) << "}";
    }
    return os.str() + "\n    ]";
}

}  // namespace

std::string formatStatedInput(const diagnose::WhereReport::StatedInput& s) {
    if (!s.stated || s.values.empty()) return "not stated";
    const bool mass = s.input == diagnose::ProtocolInput::GasMass;
    auto one = [&](double v) {
        char b[64];
        std::snprintf(b, sizeof b, "%.4g %s", mass ? v * 1e3 : v, mass ? "g" : "K");
        return std::string(b);
    };
    if (!mass) return one(s.values[0]);
    bool same = true;
    for (double v : s.values) same = same && v == s.values[0];
    if (same) return one(s.values[0]) + (s.values.size() > 1 ? " (every test)" : "");
    std::string t;
    for (double v : s.values) t += (t.empty() ? "" : ", ") + one(v);
    return t + " (per test)";
}

std::string formatDiagnosisJson(const DiagnosisInfo& info, const diagnose::WhereReport& w,
                                const diagnose::WhichReport* which,
                                const diagnose::StiffnessComparison* stiffness,
                                const diagnose::StiffnessWhich* curveWhich,
                                const std::string& curveNotRun) {
    std::ostringstream os;
    os << "{\n  \"format\": \"bagsim diagnosis 1\",\n"
       << "  \"measured\": " << str(info.measuredFolder) << ",\n"
       << "  \"scenario\": " << str(info.scenarioFile) << ",\n"
       << "  \"program\": " << str(info.program) << ",\n"
       << "  \"command\": " << str(info.commandLine) << ",\n"
       << "  \"simulations\": " << info.simulations << ",\n"
       << "  \"seconds\": " << num(info.seconds, "%.1f") << ",\n";
    if (stiffness) {
        os << "  \"stiffness\": " << formatStiffness(*stiffness) << ",\n";
        if (curveWhich)
            os << "  \"stiffness_which\": " << formatCurveWhich(*curveWhich) << ",\n";
        else
            os << "  \"stiffness_which\": null,\n  \"stiffness_which_not_run\": "
               << str(curveNotRun) << ",\n";
    }
    if (w.channels.empty()) {
        os << "  \"where\": null,\n";
        if (curveWhich) {
            os << "  \"verdict\": " << str(curveWhich->which.verdict)
               << ",\n  \"verdict_effects\": [";
            for (size_t i = 0; i < curveWhich->which.verdictEffects.size(); ++i)
                os << (i ? ", " : "") << str(curveWhich->which.verdictEffects[i]);
            os << "],\n  " << formatVerdictQualifiers(curveWhich->which)
               << ",\n  \"reason\": " << str("the stiffness curve's: " + curveWhich->which.reason)
               << "\n}\n";
        } else {
            os << "  \"verdict\": null,\n  \"reason\": "
               << str("which effect: not run (" +
                      (curveNotRun.empty() ? std::string("--where-only") : curveNotRun) + ")")
               << "\n}\n";
        }
        return os.str();
    }
    os << "  \"where\": {\n    \"gap\": " << num(w.gap)
       << ",\n    \"gap_definition\": " << str(diagnose::describeGap(w)) << ",\n"
       << "    \"within_validation_uncertainty\": " << (w.withinValidation ? "true" : "false")
       << ",\n    \"channels\": [\n";
    for (size_t i = 0; i < w.channels.size(); ++i) {
        const auto& c = w.channels[i];
        os << "      {\"channel\": " << str(c.channel)
           << ", \"unit\": " << str(diagnose::getChannelUnit(getChannelKind(c.channel)))
           << ", \"rmse\": " << num(inUnit(c.channel, c.rmse))
           << ", \"range\": " << num(inUnit(c.channel, c.range))
           << ", \"noise\": " << num(inUnit(c.channel, c.noise))
           << ", \"numerical_uncertainty\": " << num(inUnit(c.channel, c.numerical))
           << ", \"numerical_uncertainty_mesh\": " << num(inUnit(c.channel, c.numericalMesh))
           << ", \"input_uncertainty\": " << num(inUnit(c.channel, c.input))
           << ", \"input_uncertainty_gas_mass\": " << num(inUnit(c.channel, c.inputGasMass))
           << ", \"input_uncertainty_temperature\": " << num(inUnit(c.channel, c.inputTemperature))
           << ", \"validation_uncertainty\": " << num(inUnit(c.channel, c.validation))
           << ", \"share_of_gap\": " << num(c.shareOfGap, "%.4f") << "}"
           << (i + 1 < w.channels.size() ? "," : "") << "\n";
    }
    os << "    ],\n    \"stated_input_uncertainties\": " << formatStatedInputs(w)
       << ",\n    \"regimes\": [\n";
    for (size_t i = 0; i < w.regimes.size(); ++i) {
        const auto& r = w.regimes[i];
        os << "      {\"channel\": " << str(r.channel) << ", \"regime\": " << str(r.regime)
           << ", \"samples\": " << r.samples << ", \"rmse\": " << num(inUnit(r.channel, r.rmse))
           << ", \"bias\": " << num(inUnit(r.channel, r.bias))
           << ", \"max_error\": " << num(inUnit(r.channel, r.maxError))
           << ", \"share\": " << num(r.share, "%.4f") << "}"
           << (i + 1 < w.regimes.size() ? "," : "") << "\n";
    }
    os << "    ],\n    \"signatures\": [\n";
    for (size_t i = 0; i < w.signatures.size(); ++i) {
        const auto& s = w.signatures[i];
        os << "      {\"channel\": " << str(s.channel) << ", \"test\": " << s.test + 1
           << ", \"gas_mass_g\": " << num(s.gasMass * 1e3)
           << ", \"bias\": " << num(inUnit(s.channel, s.bias))
           << ", \"scale\": " << num(s.scale, "%.4f") << ", \"lag_s\": " << num(s.lag, "%.3f")
           << ", \"lag_correlation\": " << num(s.lagCorrelation, "%.4f")
           << ", \"loop_area_measured\": " << num(inUnit(s.channel, s.loopAreaMeasured) * 1e3)
           << ", \"loop_area_simulated\": " << num(inUnit(s.channel, s.loopAreaSimulated) * 1e3)
           << ", \"loop_area_unit\": "
           << str(diagnose::getChannelUnit(getChannelKind(s.channel)) + " mm")
           << ", \"drift_per_s\": " << num(inUnit(s.channel, s.drift)) << "}"
           << (i + 1 < w.signatures.size() ? "," : "") << "\n";
    }
    os << "    ]\n  }";
    if (which) {
        os << ",\n  \"candidates\": [\n";
        for (size_t i = 0; i < which->candidates.size(); ++i) {
            const auto& c = which->candidates[i];
            const diagnose::Effect* e = diagnose::findEffect(c.effect);
            os << "    {\"rank\": " << i + 1 << ", \"effect\": " << str(c.effect)
               << ", \"parameters\": " << formatParameters(e, c.parameters, &c.parameterStdDev)
               << ", " << formatGaps(c) << ", \"simulations\": " << c.simulations
               << ",\n     \"heldout_metrics\": " << formatMetrics(c, w)
               << ",\n     \"folds\": " << formatFolds(c, [&](const std::vector<double>& v) {
                      return formatParameters(e, v, nullptr);
                  });
            os << "}" << (i + 1 < which->candidates.size() ? "," : "") << "\n";
        }
        os << "  ],\n";
        const diagnose::CandidateResult* best =
            which->candidates.empty() ? nullptr : &which->candidates.front();
        os << "  \"heldout_before\": " << num(best ? best->heldoutBefore : NAN) << ",\n"
           << "  \"heldout_after\": " << num(best ? best->heldoutAfter : NAN) << ",\n"
           << "  \"shrink\": " << num(best ? best->shrink : NAN, "%.4f") << ",\n"
           << "  \"excess_shrink\": " << num(best ? best->excessShrink : NAN, "%.4f") << ",\n"
           << "  \"confusable\": [";
        for (size_t i = 0; i < which->confusable.size(); ++i)
            os << (i ? ", " : "") << "[" << str(which->confusable[i].first) << ", "
               << str(which->confusable[i].second) << "]";
        os << "],\n  \"confusable_pairs\": [";
        for (size_t i = 0; i < which->confusablePairs.size(); ++i)
            os << (i ? ", " : "") << "[" << str(which->confusablePairs[i].first) << ", "
               << str(which->confusablePairs[i].second) << "]";
        os << "],\n  \"pair_stage\": {\"ran\": " << (which->pairStageRan ? "true" : "false")
           << ", \"reason\": " << str(which->pairStageReason)
           << ", \"simulations\": " << which->pairSimulations << ", \"pairs\": [";
        for (size_t i = 0; i < which->pairs.size(); ++i) {
            const diagnose::PairResult& p = which->pairs[i];
            const diagnose::CandidateResult& c = p.result;
            os << (i ? "," : "") << "\n    {\"effects\": [" << str(p.first) << ", " << str(p.second)
               << "], \"refined\": " << (p.refined ? "true" : "false")
               << ", \"screen_cost\": " << num(p.screenCost) << ", \"screen_parameters\": "
               << formatPairParameters(p, p.screenParameters, nullptr);
            if (p.refined) {
                os << ",\n     \"parameters\": "
                   << formatPairParameters(p, c.parameters, &c.parameterStdDev) << ", "
                   << formatGaps(c) << ",\n     \"against\": " << str(p.against)
                   << ", \"single_excess_after\": " << num(p.singleExcessAfter)
                   << ", \"shrink_over_single\": " << num(p.shrinkOverSingle, "%.4f")
                   << ", \"extra_penalty\": " << num(p.extraPenalty, "%.4f")
                   << ", \"gain\": " << num(p.gain, "%.4f")
                   << ",\n     \"heldout_metrics\": " << formatMetrics(c, w)
                   << ",\n     \"folds\": " << formatFolds(c, [&](const std::vector<double>& v) {
                          return formatPairParameters(p, v, nullptr);
                      });
            }
            os << ", \"simulations\": " << c.simulations
               << ", \"accepted\": " << (p.accepted ? "true" : "false")
               << ", \"why\": " << str(p.why) << "}";
        }
        os << "]},\n  \"verdict\": " << str(which->verdict) << ",\n  \"verdict_effects\": [";
        for (size_t i = 0; i < which->verdictEffects.size(); ++i)
            os << (i ? ", " : "") << str(which->verdictEffects[i]);
        os << "],\n  " << formatVerdictQualifiers(*which)
           << ",\n  \"reason\": " << str(which->reason) << "\n";
    } else {
        os << ",\n  \"verdict\": null,\n  \"reason\": \"which effect: not run (--where-only or one "
              "test)\"\n";
    }
    os << "}\n";
    return os.str();
}

std::string formatResidualsCsv(const std::vector<diagnose::TestComparison>& tests) {
    std::ostringstream os;
    os << "test,gas_mass_g,channel,unit,time_s,displacement_mm,branch,measured,simulated,"
          "residual\n";
    for (const auto& t : tests)
        for (const auto& ch : t.channels) {
            const std::string name = diagnose::getChannelName(ch.kind);
            const double u = diagnose::getChannelUnitScale(ch.kind);
            for (size_t i = 0; i < ch.measured.size(); ++i)
                os << t.test + 1 << "," << num(t.gasMass * 1e3) << "," << name << ","
                   << diagnose::getChannelUnit(ch.kind) << "," << num(ch.time[i]) << ","
                   << num(ch.displacement[i] * 1e3) << ","
                   << (ch.loading[i] ? "loading" : "unloading") << "," << num(ch.measured[i] / u)
                   << "," << num(ch.simulated[i] / u) << ","
                   << num((ch.measured[i] - ch.simulated[i]) / u) << "\n";
        }
    return os.str();
}

std::string formatStiffnessCsv(const diagnose::StiffnessComparison& k) {
    std::ostringstream os;
    os << "gas_mass_g,measured_N_per_mm,simulated_N_per_mm,difference_N_per_mm,measured_stage,"
          "simulated_stage,note\n";
    for (const auto& p : k.points) {
        const bool has = std::isfinite(p.simulated);
        std::string note = p.note;
        for (char& c : note)
            if (c == ',' || c == '\n') c = ';';
        os << num(p.gasMass * 1e3) << "," << num(p.measured * 1e-3) << ","
           << (has ? num(p.simulated * 1e-3) : "") << ","
           << (has ? num((p.measured - p.simulated) * 1e-3) : "") << "," << p.measuredStage << ","
           << p.simulatedStage << "," << note << "\n";
    }
    return os.str();
}

}  // namespace io
