#pragma once
// Private to the io library: the JSON text diagnosis.json is made of, shared by the rig's
// (DiagnosisJson.cpp) and the patient's (PatientDiagnosisReport.cpp).
#include <diagnose/Diagnosis.h>
#include <diagnose/Effects.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace io::json {

/// A number as JSON ("null" for NaN or infinity), printf format f.
inline std::string num(double v, const char* f = "%.6g") {
    if (!std::isfinite(v)) return "null";
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

inline std::string str(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\')
            o += '\\', o += c;
        else if (c == '\n')
            o += "\\n";
        else if (static_cast<unsigned char>(c) < 0x20)
            o += ' ';
        else
            o += c;
    }
    return o + "\"";
}

/// An effect's parameters in their units: {"name": {"value": v, "std_dev": s, "unit": u}}.
inline std::string formatParameters(const diagnose::Effect* e, const std::vector<double>& v,
                                    const std::vector<double>* sd) {
    std::ostringstream os;
    os << "{";
    for (size_t i = 0; i < v.size(); ++i) {
        const std::string name = e ? e->parameters[i].name : "p" + std::to_string(i);
        const double s = e ? e->parameters[i].siPerUnit : 1.0;
        os << (i ? ", " : "") << str(name) << ": {\"value\": " << num(v[i] / s);
        if (sd && i < sd->size()) os << ", \"std_dev\": " << num((*sd)[i] / s);
        os << ", \"unit\": " << str(e ? e->parameters[i].unit : "") << "}";
    }
    return os.str() + "}";
}

/// What a verdict can say (diagnose::qualifyVerdict): "explained" ("fully", "partly" or null
/// when no effect is named), "residual_ratio" and "residual_channel", "rivals", "tell_apart".
inline std::string formatVerdictQualifiers(const diagnose::WhichReport& w) {
    std::string rivals;
    for (const std::string& r : w.rivals) rivals += (rivals.empty() ? "" : ", ") + str(r);
    return "\"explained\": " + (w.explained.empty() ? std::string("null") : str(w.explained)) +
           ", \"residual_ratio\": " + num(w.residualRatio, "%.4g") + ", \"residual_channel\": " +
           (w.residualChannel.empty() ? std::string("null") : str(w.residualChannel)) +
           ", \"rivals\": [" + rivals +
           "], \"tell_apart\": " + (w.tellApart.empty() ? std::string("null") : str(w.tellApart));
}

// The held-out gaps of a candidate or pair: before and after, whole and beyond the
// uncertainty, their shrinks and the score.
inline std::string formatGaps(const diagnose::CandidateResult& c) {
    return "\"heldout_before\": " + num(c.heldoutBefore) +
           ", \"heldout_after\": " + num(c.heldoutAfter) +
           ", \"shrink\": " + num(c.shrink, "%.4f") +
           ", \"excess_before\": " + num(c.excessBefore) +
           ", \"excess_after\": " + num(c.excessAfter) +
           ", \"excess_shrink\": " + num(c.excessShrink, "%.4f") +
           ", \"score\": " + num(c.score, "%.4f");
}

// Per fold: the test (or time window, or subject: heldOutKey) held out, counted from 1 or by
// name, what `more` adds about it (", \"key\": value"; null: nothing), the parameters fitted
// without it, the gaps before and after.
inline std::string formatFolds(
    const diagnose::CandidateResult& c,
    const std::function<std::string(const std::vector<double>&)>& parameters,
    const char* heldOutKey = "held_out_test",
    const std::vector<std::string>* heldOutNames = nullptr,
    const std::function<std::string(int)>& more = nullptr) {
    std::ostringstream os;
    os << "[";
    for (size_t k = 0; k < c.folds.size(); ++k) {
        const auto& f = c.folds[k];
        os << (k ? ", " : "") << "{" << str(heldOutKey) << ": "
           << (heldOutNames ? str(heldOutNames->at(size_t(f.heldOut)))
                            : std::to_string(f.heldOut + 1))
           << (more ? more(f.heldOut) : std::string())
           << ", \"parameters\": " << parameters(f.parameters) << ", \"before\": " << num(f.before)
           << ", \"after\": " << num(f.after) << ", \"excess_before\": " << num(f.excessBefore)
           << ", \"excess_after\": " << num(f.excessAfter) << "}";
    }
    return os.str() + "]";
}

}  // namespace io::json
