#include <io/DiagnosisReport.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "SvgPlot.h"

namespace io {

namespace {

using svg::num;
using svg::Series;

std::string esc(const std::string& s) { return svg::escape(s); }

// One chart with axes, ticks and a legend (the reports' shared SVG charts).
std::string plot(const std::string& title, const std::string& xLabel, const std::string& yLabel,
                 const std::vector<Series>& series) {
    svg::PlotOptions o;
    o.title = title;
    o.xLabel = xLabel;
    o.yLabel = yLabel;
    o.width = 460;
    return svg::plot(o, series);
}

// A channel's series in its reporting unit; `x` the displacement [mm] or the time [s].
Series makeSeries(const diagnose::ChannelComparison& ch, bool measured, bool byTime,
                  const std::string& name, const std::string& colour) {
    Series s;
    s.name = name;
    s.colour = colour;
    s.points = measured;
    const double u = diagnose::getChannelUnitScale(ch.kind);
    for (size_t i = 0; i < ch.measured.size(); ++i) {
        s.x.push_back(byTime ? ch.time[i] : ch.displacement[i] * 1e3);
        s.y.push_back((measured ? ch.measured[i] : ch.simulated[i]) / u);
    }
    return s;
}

}  // namespace

std::string formatDiagnosisReportHtml(const DiagnosisInfo& info,
                                      const std::vector<diagnose::TestComparison>& tests,
                                      const diagnose::WhereReport& w,
                                      const diagnose::WhichReport* which) {
    // The curves with the verdict's fit: the pair named, else the best single.
    const diagnose::CandidateResult* best =
        which && which->pairChosen >= 0       ? &which->pairs[which->pairChosen].result
        : which && !which->candidates.empty() ? &which->candidates.front()
                                              : nullptr;
    std::ostringstream os;
    os << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>bagsim diagnosis: "
       << esc(info.measuredFolder) << "</title><style>body{font-family:sans-serif;margin:2em;}"
       << "table{border-collapse:collapse;margin:0.5em 0;}td,th{border:1px solid #ccc;"
       << "padding:2px 8px;text-align:right;}th{background:#eee;}td:first-child{text-align:left;}"
       << "</style></head><body>";
    os << "<h1>Diagnosis of " << esc(info.measuredFolder) << "</h1><p>Scenario "
       << esc(info.scenarioFile) << "; " << esc(info.program) << "; " << info.simulations
       << " simulations, " << num(info.seconds, "%.1f") << " s. See docs/diagnosis.md.</p>";
    if (which)
        os << "<h2>Verdict: " << esc(diagnose::describeVerdict(*which)) << "</h2><p>"
           << esc(which->reason) << "</p>";
    os << "<h2>Where</h2><p>Gap " << num(w.gap) << " (" << esc(diagnose::describeGap(w)) << ")"
       << (w.withinValidation ? ", within the validation uncertainty" : "")
       << ".</p><table><tr><th>channel</th><th>RMSE</th><th>range</th><th>noise</th>"
       << "<th>numerical</th><th>input</th><th>gas mass</th><th>room temperature</th>"
       << "<th>validation</th><th>share of gap</th></tr>";
    for (const auto& c : w.channels) {
        const auto kind = diagnose::getChannelKind(c.channel);
        const double u = diagnose::getChannelUnitScale(kind);
        const std::string un = " " + diagnose::getChannelUnit(kind);
        os << "<tr><td>" << c.channel << "</td><td>" << num(c.rmse / u) << un << "</td><td>"
           << num(c.range / u) << un << "</td><td>" << num(c.noise / u) << un << "</td><td>"
           << num(c.numerical / u) << un << "</td><td>" << num(c.input / u) << un << "</td><td>"
           << num(c.inputGasMass / u) << un << "</td><td>" << num(c.inputTemperature / u) << un
           << "</td><td>" << num(c.validation / u) << un << "</td><td>"
           << (c.channel == "mass" ? std::string("(consistency)")
                                   : num(100 * c.shareOfGap, "%.0f") + " %")
           << "</td></tr>";
    }
    os << "</table><p>Validation uncertainty (ASME V&amp;V 20): the root sum square of the noise, "
       << "the numerical uncertainty, the input uncertainty of a stated imperfection (input) and "
       << "of the protocol's stated gas mass and room temperature (by their sensitivities). "
       << "Stated standard uncertainties: ";
    for (size_t i = 0; i < w.statedInputs.size(); ++i)
        os << (i ? "; " : "")
           << (w.statedInputs[i].input == diagnose::ProtocolInput::GasMass ? "gas mass "
                                                                           : "room temperature ")
           << esc(formatStatedInput(w.statedInputs[i]));
    os << ".</p><table><tr><th>channel, regime</th><th>samples</th><th>RMSE</th><th>bias</th>"
       << "<th>share of the channel's squared error</th></tr>";
    for (const auto& r : w.regimes) {
        if (r.regime == "all") continue;
        const auto kind = diagnose::getChannelKind(r.channel);
        const double u = diagnose::getChannelUnitScale(kind);
        const std::string un = " " + diagnose::getChannelUnit(kind);
        os << "<tr><td>" << r.channel << ", " << esc(r.regime) << "</td><td>" << r.samples
           << "</td><td>" << num(r.rmse / u) << un << "</td><td>" << num(r.bias / u) << un
           << "</td><td>" << num(100 * r.share, "%.0f") << " %</td></tr>";
    }
    os << "</table>";
    if (which) {
        os << "<h2>Which</h2><table><tr><th>effect</th><th>shrink beyond the uncertainty</th>"
           << "<th>shrink of the gap</th><th>score</th><th>parameters (all tests)</th></tr>";
        for (const auto& c : which->candidates) {
            const diagnose::Effect* e = diagnose::findEffect(c.effect);
            std::string params;
            for (size_t k = 0; e && k < c.parameters.size(); ++k)
                params += (k ? ", " : "") + e->parameters[k].name + " " +
                          num(c.parameters[k] / e->parameters[k].siPerUnit) +
                          (e->parameters[k].unit.empty() ? "" : " " + e->parameters[k].unit);
            os << "<tr><td>" << c.effect << "</td><td>" << num(100 * c.excessShrink, "%.1f")
               << " %</td><td>" << num(100 * c.shrink, "%.1f") << " %</td><td>"
               << num(c.score, "%.3f") << "</td><td>" << esc(params) << "</td></tr>";
        }
        os << "</table><h3>Two effects at once</h3><p>Pair stage " << esc(which->pairStageReason)
           << ".</p>";
        if (!which->pairs.empty()) {
            os << "<table><tr><th>pair</th><th>fitted in full</th><th>shrink beyond the "
               << "uncertainty</th><th>of what the single leaves</th><th>gain</th><th>named</th>"
               << "<th>parameters (all tests)</th></tr>";
            for (const auto& p : which->pairs) {
                std::string params;
                size_t k = 0;
                const std::vector<double>& v = p.refined ? p.result.parameters : p.screenParameters;
                for (const std::string& name : {p.first, p.second}) {
                    const diagnose::Effect* e = diagnose::findEffect(name);
                    for (size_t i = 0; e && i < e->parameters.size() && k < v.size(); ++i, ++k)
                        params +=
                            (k ? ", " : "") + name + "." + e->parameters[i].name + " " +
                            num(v[k] / e->parameters[i].siPerUnit) +
                            (e->parameters[i].unit.empty() ? "" : " " + e->parameters[i].unit);
                }
                os << "<tr><td>" << esc(p.first + " + " + p.second) << "</td><td>"
                   << (p.refined ? "yes" : "screened") << "</td><td>"
                   << (p.refined ? num(100 * p.result.excessShrink, "%.1f") + " %" : "-")
                   << "</td><td>"
                   << (p.refined
                           ? num(100 * p.shrinkOverSingle, "%.1f") + " % (" + esc(p.against) + ")"
                           : "-")
                   << "</td><td>" << (p.refined ? num(p.gain, "%.3f") : "-") << "</td><td>"
                   << (p.accepted ? "accepted" : "no") << "</td><td>" << esc(params)
                   << "</td></tr>";
            }
            os << "</table>";
        }
    }
    const bool after = best && best->fitted.size() == tests.size();
    os << "<h2>Curves</h2><p>Dots: measured. Grey: the model as it is."
       << (after ? " Blue: with " + esc(best->effect) + " at the parameters fitted on all tests."
                 : std::string())
       << "</p>";
    for (size_t t = 0; t < tests.size(); ++t) {
        const std::string mass = num(tests[t].gasMass * 1e3, "%.2f") + " g";
        for (size_t c = 0; c < tests[t].channels.size(); ++c) {
            const auto& ch = tests[t].channels[c];
            if (ch.kind == diagnose::ChannelKind::Mass) continue;
            const bool byTime = ch.kind == diagnose::ChannelKind::Pressure;
            std::vector<Series> s = {makeSeries(ch, true, byTime, "measured", "#c00"),
                                     makeSeries(ch, false, byTime, "model", "#888")};
            if (after)
                s.push_back(makeSeries(best->fitted[t].channels[c], false, byTime,
                                       "with " + best->effect, "#06c"));
            const std::string unit = diagnose::getChannelUnit(ch.kind);
            os << plot("test " + std::to_string(t + 1) + " (" + mass +
                           "): " + diagnose::getChannelName(ch.kind),
                       byTime ? "time [s]" : "displacement [mm]",
                       diagnose::getChannelName(ch.kind) + " [" + unit + "]", s);
            // The residuals over time, before and after.
            Series r0, r1;
            r0.name = "model";
            r0.colour = "#888";
            r1.name = after ? "with " + best->effect : "";
            r1.colour = "#06c";
            const double u = diagnose::getChannelUnitScale(ch.kind);
            for (size_t i = 0; i < ch.measured.size(); ++i) {
                r0.x.push_back(ch.time[i]);
                r0.y.push_back((ch.measured[i] - ch.simulated[i]) / u);
                if (after) {
                    const auto& f = best->fitted[t].channels[c];
                    r1.x.push_back(f.time[i]);
                    r1.y.push_back((f.measured[i] - f.simulated[i]) / u);
                }
            }
            std::vector<Series> rs = {r0};
            if (after) rs.push_back(r1);
            os << plot("residual measured - simulated", "time [s]",
                       diagnose::getChannelName(ch.kind) + " [" + unit + "]", rs)
               << "<br>";
        }
    }
    os << "</body></html>\n";
    return os.str();
}

}  // namespace io
