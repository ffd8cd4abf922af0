#include <io/PatientDiagnosisReport.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>

#include "JsonText.h"
#include "SvgPlot.h"

namespace io {

namespace {

using json::num;
using json::str;

// The reporting unit and its SI value of a channel of the comparison ("" and 1 if unknown).
std::pair<std::string, double> getUnit(const diagnose::PatientComparison& c,
                                       const std::string& name) {
    const diagnose::PatientChannelComparison* ch = c.find(name);
    return ch ? std::make_pair(ch->unit, ch->unitScale) : std::make_pair(std::string(), 1.0);
}

std::string esc(const std::string& s) { return svg::escape(s); }

// Per frame (mat: the sum over the compared sensels) or per sample, in the channel's unit:
// x time [s], y measured and simulated, for the part `part` (-1: all) of the test `test`.
void makeTimeSeries(const diagnose::PatientChannelComparison& ch, int part, int test,
                    svg::Series& m, svg::Series& s) {
    std::map<double, std::pair<double, double>> at;
    for (size_t i = 0; i < ch.time.size(); ++i) {
        if (part >= 0 && ch.part[i] != part) continue;
        if (ch.getTest(i) != test) continue;
        auto& v = at[ch.time[i]];
        v.first += ch.measured[i] / ch.unitScale;
        v.second += ch.simulated[i] / ch.unitScale;
    }
    for (const auto& [t, v] : at) {
        m.x.push_back(t), m.y.push_back(v.first);
        s.x.push_back(t), s.y.push_back(v.second);
    }
}

}  // namespace

std::string formatPatientDiagnosisJson(const DiagnosisInfo& info,
                                       const diagnose::PatientComparison& c,
                                       const diagnose::WhereReport& w,
                                       const diagnose::WhichReport* which,
                                       const diagnose::PatientFolds& folds) {
    const std::vector<double>& edges = folds.windowEdges;
    auto in = [&](const std::string& channel, double v) {
        return num(v / getUnit(c, channel).second);
    };
    std::ostringstream os;
    os << "{\n  \"format\": \"bagsim diagnosis 1\",\n  \"kind\": \"patient-on-array\",\n"
       << "  \"measured\": " << str(info.measuredFolder) << ",\n"
       << "  \"scenario\": " << str(info.scenarioFile) << ",\n"
       << "  \"program\": " << str(info.program) << ",\n"
       << "  \"command\": " << str(info.commandLine) << ",\n"
       << "  \"simulations\": " << info.simulations << ",\n"
       << "  \"seconds\": " << num(info.seconds, "%.1f") << ",\n  \"time_windows_s\": [";
    for (size_t i = 0; i < edges.size(); ++i) os << (i ? ", " : "") << num(edges[i]);
    os << "],\n  \"fold_kind\": " << str(folds.getKind()) << ",\n  \"tests\": [";
    for (size_t i = 0; i < c.tests.size(); ++i) os << (i ? ", " : "") << str(c.tests[i]);
    os << "],\n  \"subjects\": [";
    for (size_t i = 0; i < c.subjects.size(); ++i) os << (i ? ", " : "") << str(c.subjects[i]);
    os << "],\n  \"test_subjects\": [";
    for (size_t i = 0; i < c.testSubject.size(); ++i)
        os << (i ? ", " : "") << str(c.subjects.at(size_t(c.testSubject[i])));
    os << "],\n  \"where\": {\n    \"gap\": " << num(w.gap)
       << ",\n    \"gap_definition\": \"RMS over the channels of RMSE / measured range\",\n"
       << "    \"within_validation_uncertainty\": " << (w.withinValidation ? "true" : "false")
       << ",\n    \"channels\": [\n";
    for (size_t i = 0; i < w.channels.size(); ++i) {
        const auto& ch = w.channels[i];
        const diagnose::PatientChannelComparison* cc = c.find(ch.channel);
        os << "      {\"channel\": " << str(ch.channel)
           << ", \"unit\": " << str(getUnit(c, ch.channel).first)
           << ", \"samples\": " << (cc ? cc->time.size() : 0)
           << ", \"rmse\": " << in(ch.channel, ch.rmse)
           << ", \"range\": " << in(ch.channel, ch.range)
           << ", \"noise\": " << in(ch.channel, ch.noise)
           << ", \"numerical_uncertainty\": " << in(ch.channel, ch.numerical)
           << ", \"validation_uncertainty\": " << in(ch.channel, ch.validation)
           << ", \"share_of_gap\": " << num(ch.shareOfGap, "%.4f") << "}"
           << (i + 1 < w.channels.size() ? "," : "") << "\n";
    }
    os << "    ],\n    \"regimes\": [\n";
    for (size_t i = 0; i < w.regimes.size(); ++i) {
        const auto& r = w.regimes[i];
        os << "      {\"channel\": " << str(r.channel) << ", \"regime\": " << str(r.regime)
           << ", \"samples\": " << r.samples << ", \"rmse\": " << in(r.channel, r.rmse)
           << ", \"bias\": " << in(r.channel, r.bias)
           << ", \"max_error\": " << in(r.channel, r.maxError)
           << ", \"share\": " << num(r.share, "%.4f") << "}"
           << (i + 1 < w.regimes.size() ? "," : "") << "\n";
    }
    os << "    ],\n    \"signatures\": [\n";
    for (size_t i = 0; i < w.signatures.size(); ++i) {
        const auto& s = w.signatures[i];
        const std::string part = s.part.empty() ? "all" : s.part;
        os << "      {\"channel\": " << str(s.channel) << ", \"part\": " << str(part)
           << ", \"bias\": " << in(s.channel, s.bias) << ", \"scale\": " << num(s.scale, "%.4f")
           << ", \"lag_s\": " << num(s.lag, "%.4f")
           << ", \"lag_correlation\": " << num(s.lagCorrelation, "%.4f")
           << ", \"drift_per_s\": " << in(s.channel, s.drift) << "}"
           << (i + 1 < w.signatures.size() ? "," : "") << "\n";
    }
    os << "    ]\n  }";
    // A subject's fold: the tests it holds out.
    std::function<std::string(int)> heldOutTests;
    if (folds.isBySubject())
        heldOutTests = [&](int fold) {
            std::string s = ", \"held_out_tests\": [";
            const std::vector<int> t = folds.getFoldTests(fold);
            for (size_t k = 0; k < t.size(); ++k)
                s += (k ? ", " : "") + str(c.tests.at(size_t(t[k])));
            return s + "]";
        };
    if (which) {
        os << ",\n  \"candidates\": [\n";
        for (size_t i = 0; i < which->candidates.size(); ++i) {
            const auto& k = which->candidates[i];
            const diagnose::Effect* e = diagnose::findPatientEffect(k.effect);
            os << "    {\"rank\": " << i + 1 << ", \"effect\": " << str(k.effect)
               << ", \"parameters\": "
               << json::formatParameters(e, k.parameters, &k.parameterStdDev) << ", "
               << json::formatGaps(k) << ", \"simulations\": " << k.simulations
               << ",\n     \"heldout_metrics\": {";
            for (size_t m = 0; m < k.heldoutMetricsBefore.size(); ++m) {
                const diagnose::GapMetrics& b = k.heldoutMetricsBefore[m];
                const diagnose::GapMetrics& a = k.heldoutMetricsAfter[m];
                auto metric = [&](const diagnose::GapMetrics& g) {
                    return "{\"rmse\": " + in(g.channel, g.rmse) +
                           ", \"mean_error\": " + in(g.channel, g.meanError) +
                           ", \"max_error\": " + in(g.channel, g.maxError) +
                           ", \"area_validation_metric\": " + in(g.channel, g.areaMetric) + "}";
                };
                os << (m ? ", " : "") << str(b.channel)
                   << ": {\"unit\": " << str(getUnit(c, b.channel).first)
                   << ", \"samples\": " << b.samples << ", \"before\": " << metric(b)
                   << ", \"after\": " << metric(a) << "}";
            }
            os << "},\n     \"folds\": "
               << json::formatFolds(
                      k,
                      [&](const std::vector<double>& v) {
                          return json::formatParameters(e, v, nullptr);
                      },
                      folds.isBySubject() ? "held_out_subject"
                      : folds.isByTest()  ? "held_out_test"
                                          : "held_out_window",
                      folds.isBySubject() ? &folds.subjects
                      : folds.isByTest()  ? &c.tests
                                          : nullptr,
                      heldOutTests)
               << "}" << (i + 1 < which->candidates.size() ? "," : "") << "\n";
        }
        os << "  ],\n  \"confusable\": [";
        for (size_t i = 0; i < which->confusable.size(); ++i)
            os << (i ? ", " : "") << "[" << str(which->confusable[i].first) << ", "
               << str(which->confusable[i].second) << "]";
        os << "],\n  \"verdict\": " << str(which->verdict) << ",\n  \"verdict_effects\": [";
        for (size_t i = 0; i < which->verdictEffects.size(); ++i)
            os << (i ? ", " : "") << str(which->verdictEffects[i]);
        os << "],\n  " << json::formatVerdictQualifiers(*which)
           << ",\n  \"reason\": " << str(which->reason) << "\n}\n";
    } else {
        os << ",\n  \"verdict\": null,\n  \"reason\": \"which effect: not run "
              "(--where-only)\"\n}\n";
    }
    return os.str();
}

std::string formatPatientResidualsCsv(const diagnose::PatientComparison& c, int matColumns) {
    std::ostringstream os;
    const bool tests = c.tests.size() > 1, subjects = !c.subjects.empty();
    os << (subjects ? "subject," : "") << (tests ? "test," : "")
       << "channel,unit,part,time_s,sensel_row,sensel_column,measured,simulated,residual\n";
    for (const diagnose::PatientChannelComparison& ch : c.channels)
        for (size_t i = 0; i < ch.time.size(); ++i) {
            if (subjects)
                os << c.subjects.at(size_t(c.testSubject.at(size_t(ch.getTest(i))))) << ",";
            if (tests) os << c.tests.at(size_t(ch.getTest(i))) << ",";
            os << ch.name << "," << ch.unit << ","
               << (ch.part.empty() ? std::string() : ch.partNames.at(size_t(ch.part[i]))) << ","
               << svg::num(ch.time[i], "%.4f") << ",";
            if (!ch.sensel.empty() && matColumns > 0)
                os << ch.sensel[i] / matColumns + 1 << "," << ch.sensel[i] % matColumns + 1;
            else
                os << ",";
            os << "," << svg::num(ch.measured[i] / ch.unitScale, "%.6g") << ","
               << svg::num(ch.simulated[i] / ch.unitScale, "%.6g") << ","
               << svg::num((ch.measured[i] - ch.simulated[i]) / ch.unitScale, "%.6g") << "\n";
        }
    return os.str();
}

std::string formatPatientDiagnosisReportHtml(const DiagnosisInfo& info,
                                             const diagnose::PatientComparison& c,
                                             const diagnose::WhereReport& w,
                                             const diagnose::WhichReport* which,
                                             const diagnose::PatientComparison* fitted) {
    std::ostringstream os;
    os << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>bagsim diagnosis: "
       << esc(info.measuredFolder) << "</title><style>body{font-family:sans-serif;margin:2em;}"
       << "table{border-collapse:collapse;margin:0.5em 0;}td,th{border:1px solid #ccc;"
       << "padding:2px 8px;text-align:right;}th{background:#eee;}td:first-child{text-align:left;}"
       << "svg{max-width:100%;height:auto;}</style></head><body>\n"
       << "<h1>Diagnosis of a patient on the array</h1>\n<p>" << esc(info.measuredFolder)
       << " against " << esc(info.scenarioFile) << " (" << esc(info.program) << ", "
       << info.simulations << " co-simulations, " << svg::num(info.seconds, "%.0f") << " s)</p>\n";
    if (which)
        os << "<h2>Verdict: " << esc(diagnose::describeVerdict(*which)) << "</h2>\n<p>"
           << esc(which->reason) << "</p>\n";
    os << "<h2>Where</h2>\n<p>gap " << svg::num(w.gap, "%.4f")
       << " (RMS over the channels of RMSE / measured range)"
       << (w.withinValidation ? ", within the validation uncertainty" : "") << "</p>\n"
       << "<table><tr><th>channel</th><th>RMSE</th><th>range</th><th>noise</th><th>numerical</th>"
          "<th>validation</th><th>share of gap</th></tr>\n";
    for (const auto& ch : w.channels) {
        const auto [unit, scale] = getUnit(c, ch.channel);
        auto v = [&](double x) { return svg::num(x / scale, "%.4g") + " " + unit; };
        os << "<tr><td>" << esc(ch.channel) << "</td><td>" << v(ch.rmse) << "</td><td>"
           << v(ch.range) << "</td><td>" << v(ch.noise) << "</td><td>" << v(ch.numerical)
           << "</td><td>" << v(ch.validation) << "</td><td>"
           << svg::num(100 * ch.shareOfGap, "%.0f") << " %</td></tr>\n";
    }
    os << "</table>\n<table><tr><th>channel, regime</th><th>samples</th><th>RMSE</th><th>bias</th>"
          "<th>largest</th><th>share</th></tr>\n";
    for (const auto& r : w.regimes) {
        const auto [unit, scale] = getUnit(c, r.channel);
        os << "<tr><td>" << esc(r.channel + ", " + r.regime) << "</td><td>" << r.samples
           << "</td><td>" << svg::num(r.rmse / scale, "%.4g") << " " << unit << "</td><td>"
           << svg::num(r.bias / scale, "%.4g") << "</td><td>"
           << svg::num(r.maxError / scale, "%.4g") << "</td><td>" << svg::num(100 * r.share, "%.0f")
           << " %</td></tr>\n";
    }
    os << "</table>\n<table><tr><th>signature</th><th>bias</th><th>scale</th><th>lag [s]</th>"
          "<th>drift [/s]</th></tr>\n";
    for (const auto& s : w.signatures) {
        const diagnose::PatientChannelComparison* cc = c.find(s.channel);
        const double scale = cc ? cc->unitScale : 1.0;
        const std::string part = s.part.empty() ? "" : ", " + s.part;
        os << "<tr><td>" << esc(s.channel + part) << "</td><td>" << svg::num(s.bias / scale, "%.4g")
           << " " << (cc ? cc->unit : "") << "</td><td>" << svg::num(s.scale, "%.4f") << "</td><td>"
           << svg::num(s.lag, "%.3f") << "</td><td>" << svg::num(s.drift / scale, "%.4g")
           << "</td></tr>\n";
    }
    os << "</table>\n";
    const bool bySubject = !c.subjects.empty(), byTest = c.tests.size() > 1;
    if (which) {
        os << "<h2>Which</h2>\n<p>Each candidate fitted on all "
           << (bySubject ? "subjects"
               : byTest  ? "tests"
                         : "time windows")
           << " but one and judged on the one left out, in turn"
           << (bySubject ? " (leave one subject out: all tests of the subject)"
               : byTest  ? " (leave one test out)"
                         : "")
           << ".</p>\n"
           << "<table><tr><th>effect</th><th>parameters (all "
           << (bySubject ? "subjects"
               : byTest  ? "tests"
                         : "windows")
           << ")</th>"
              "<th>held-out gap before</th><th>after</th><th>shrink beyond u_val</th><th>score</th>"
              "<th>co-simulations</th></tr>\n";
        for (const auto& k : which->candidates) {
            const diagnose::Effect* e = diagnose::findPatientEffect(k.effect);
            std::string params;
            for (size_t i = 0; e && i < k.parameters.size(); ++i)
                params += (i ? ", " : "") + e->parameters[i].name + " " +
                          svg::num(k.parameters[i] / e->parameters[i].siPerUnit, "%.4g") + " " +
                          e->parameters[i].unit;
            os << "<tr><td>" << esc(k.effect) << "</td><td>" << esc(params) << "</td><td>"
               << svg::num(k.heldoutBefore, "%.4g") << "</td><td>"
               << svg::num(k.heldoutAfter, "%.4g") << "</td><td>"
               << svg::num(100 * k.excessShrink, "%.1f") << " %</td><td>"
               << svg::num(k.score, "%.3f") << "</td><td>" << k.simulations << "</td></tr>\n";
        }
        os << "</table>\n";
    }
    os << "<h2>Over time</h2>\n<p>Measured (dots), the model as it is (grey)"
       << (fitted ? " and with the best candidate at its fit on all windows (blue)" : "")
       << "; the mat as the sum of the compared sensels' pressures.</p>\n";
    // The plots test by test; with subjects, grouped under each subject's heading.
    const int ntests = std::max<int>(1, int(c.tests.size()));
    std::vector<int> order;
    for (size_t s = 0; s < std::max<size_t>(1, c.subjects.size()); ++s)
        for (int t = 0; t < ntests; ++t)
            if (!bySubject || c.testSubject.at(size_t(t)) == int(s)) order.push_back(t);
    int shownSubject = -1;
    for (int t : order) {
        if (bySubject && c.testSubject.at(size_t(t)) != shownSubject) {
            shownSubject = c.testSubject.at(size_t(t));
            os << "<h3>subject " << esc(c.subjects.at(size_t(shownSubject))) << "</h3>\n";
        }
        for (const diagnose::PatientChannelComparison& ch : c.channels) {
            const int parts =
                ch.name == "bag-pressure" ? int(std::min<size_t>(ch.partNames.size(), 6)) : 1;
            for (int p = 0; p < parts; ++p) {
                const int part = ch.name == "bag-pressure" ? p : -1;
                svg::Series m, s, f;
                m.name = "measured", m.colour = "#000", m.points = true;
                s.name = "model as it is", s.colour = "#999";
                makeTimeSeries(ch, part, t, m, s);
                if (m.x.empty()) continue;
                std::vector<svg::Series> series = {s, m};
                const diagnose::PatientChannelComparison* fc =
                    fitted ? fitted->find(ch.name) : nullptr;
                if (fc) {
                    svg::Series fm, fs;
                    makeTimeSeries(*fc, part, t, fm, fs);
                    fs.name = "with the best candidate", fs.colour = "#0072b2";
                    series.push_back(fs);
                }
                svg::PlotOptions o;
                const std::string subject =
                    bySubject
                        ? "subject " + c.subjects.at(size_t(c.testSubject.at(size_t(t)))) + ", "
                        : "";
                o.title = subject + (byTest ? "test " + c.tests[size_t(t)] + ": " : std::string()) +
                          ch.name + (part >= 0 ? ", " + ch.partNames[size_t(part)] : "");
                o.xLabel = "time [s]";
                o.yLabel = (ch.name == "mat" ? "sum of sensels [" : "[") + ch.unit + "]";
                o.width = 460;
                os << svg::plot(o, series) << "\n";
            }
        }
    }
    os << "</body></html>\n";
    return os.str();
}

}  // namespace io
