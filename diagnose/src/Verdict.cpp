// What a verdict can say (docs/diagnosis.md#what-a-verdict-says): whether the named effect
// explains the gap or only part of it, and which rivals these data cannot tell from it.
#include <diagnose/Diagnosis.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "Format.h"

namespace diagnose {

using detail::fmt;

double calcResidualRatio(const CandidateResult& c, const ChannelUncertainties& validation,
                         std::string* channel) {
    double ratio = detail::kNaN;
    std::string which;
    for (const GapMetrics& m : c.heldoutMetricsAfter) {
        const auto u = validation.find(m.channel);
        if (u == validation.end() || !(u->second > 0.0)) continue;
        const double scale = std::hypot(u->second, c.predictionUncertainty);
        const double q = std::isfinite(m.rmse) ? m.rmse / scale : INFINITY;
        if (which.empty() || q > ratio) ratio = q, which = m.channel;
    }
    if (channel) *channel = which;
    return ratio;
}

namespace {

bool explainsFully(double residualRatio) { return residualRatio <= kExplainedMultiple; }

}  // namespace

std::vector<std::pair<std::string, std::string>> findConfusable(
    const std::vector<CandidateResult>& candidates, double threshold,
    const ChannelUncertainties& validation) {
    std::vector<std::pair<std::string, std::string>> out;
    for (size_t i = 0; i < candidates.size(); ++i)
        for (size_t j = i + 1; j < candidates.size(); ++j) {
            const CandidateResult &a = candidates[i], &b = candidates[j];
            // One of the two explains (reaches the threshold), the other explains nearly as
            // much, and neither leaves, held out, a residual the other does not: the better
            // named alone would be a confident name these data do not give.
            if (std::max(a.score, b.score) >= threshold &&
                std::fabs(a.excessShrink - b.excessShrink) < kRivalMargin &&
                explainsFully(calcResidualRatio(a, validation)) ==
                    explainsFully(calcResidualRatio(b, validation)))
                out.push_back({a.effect, b.effect});
        }
    return out;
}

namespace {

// The effects an explanation names: "a" or "a + b".
std::set<std::string> splitEffects(const std::string& explanation) {
    std::set<std::string> out;
    size_t from = 0;
    for (;;) {
        const size_t at = explanation.find(" + ", from);
        out.insert(
            explanation.substr(from, at == std::string::npos ? std::string::npos : at - from));
        if (at == std::string::npos) return out;
        from = at + 3;
    }
}

const CandidateResult* findNamed(const WhichReport& r) {
    if (r.verdictEffects.size() == 2 && r.pairChosen >= 0 &&
        r.pairChosen < static_cast<int>(r.pairs.size()))
        return &r.pairs[static_cast<size_t>(r.pairChosen)].result;
    for (const CandidateResult& c : r.candidates)
        if (c.effect == r.verdictEffects.front()) return &c;
    return nullptr;
}

}  // namespace

void qualifyVerdict(WhichReport& r, const ChannelUncertainties& validation,
                    const std::vector<Effect>& library) {
    r.explained.clear();
    r.residualRatio = detail::kNaN;
    r.residualChannel.clear();
    r.rivals.clear();
    r.tellApart.clear();
    if (r.verdictEffects.empty()) return;
    const CandidateResult* named = findNamed(r);
    const std::string best = named ? named->effect : r.verdict;

    // How much the named explanation leaves, held out: the largest channel's RMSE over its
    // validation uncertainty. A channel that is not a finite number leaves everything.
    if (named) r.residualRatio = calcResidualRatio(*named, validation, &r.residualChannel);
    r.explained = explainsFully(r.residualRatio) ? "fully" : "partly";

    // The rivals: for a single, the candidates confusable with it; for a pair, the accepted
    // pairs that gain about as much and explain alike (a pair that leaves a residual the named
    // one does not is told apart, as findConfusable tells singles).
    const bool pair = r.verdictEffects.size() == 2;
    for (const auto& [a, b] : pair ? r.confusablePairs : r.confusable) {
        const std::string other = a == best ? b : b == best ? a : std::string();
        if (other.empty()) continue;
        if (pair) {
            const PairResult* p = nullptr;
            for (const PairResult& q : r.pairs)
                if (q.result.effect == other) p = &q;
            if (p && explainsFully(calcResidualRatio(p->result, validation)) !=
                         explainsFully(r.residualRatio))
                continue;
        }
        r.rivals.push_back(other);
    }
    std::string names = best;
    for (const std::string& rival : r.rivals) names += " or " + rival;
    r.verdict = names;

    // What tells them apart: the effects that differ between the named explanation and a
    // rival, each with the measurement that isolates it.
    if (!r.rivals.empty()) {
        const std::set<std::string> mine = splitEffects(best);
        std::vector<std::string> differing;
        auto add = [&](const std::string& e) {
            if (std::find(differing.begin(), differing.end(), e) == differing.end())
                differing.push_back(e);
        };
        for (const std::string& rival : r.rivals) {
            const std::set<std::string> theirs = splitEffects(rival);
            for (const std::string& e : mine)
                if (!theirs.count(e)) add(e);
            for (const std::string& e : theirs)
                if (!mine.count(e)) add(e);
        }
        for (const std::string& e : differing) {
            const Effect* effect = findEffectIn(library, e);
            if (!effect || effect->isolatedBy.empty()) continue;
            r.tellApart += (r.tellApart.empty() ? "" : "; ") + e + ": " + effect->isolatedBy;
        }
        if (!r.tellApart.empty()) r.tellApart = "what would tell them apart: " + r.tellApart;
    }

    std::string head = (r.explained == "partly" ? "partly explained by " : "explained by ") + names;
    if (!r.rivals.empty())
        head +=
            " (these data do not tell them apart: their shrinks of the held-out gap beyond "
            "the uncertainty are within " +
            fmt("%g", kRivalMargin) + ")";
    if (std::isfinite(r.residualRatio))
        head += ": held out, " + std::string(pair ? "the pair" : best) + " leaves the " +
                r.residualChannel + " at " + fmt("%.3g", r.residualRatio) +
                " times its validation uncertainty (" +
                (r.residualRatio <= kExplainedMultiple ? "within " : "beyond ") +
                fmt("%g", kExplainedMultiple) + " times" +
                (r.residualRatio <= kExplainedMultiple
                     ? ")"
                     : ": a residual remains that it does not explain)");
    else if (!r.residualChannel.empty())
        head += ": held out, the " + r.residualChannel + "'s residual is not a finite number";
    else
        head += ": its held-out residual could not be measured (a fold's simulation failed)";
    r.reason = head + "; " + r.reason;
    if (!r.tellApart.empty()) r.reason += "; " + r.tellApart;
}

std::string describeVerdict(const WhichReport& r) {
    return r.explained == "partly" ? r.verdict + ", partly explained" : r.verdict;
}

}  // namespace diagnose
