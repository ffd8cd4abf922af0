#include <io/ArrayResults.h>
#include <io/ResultFiles.h>
#include <io/Results.h>

namespace io {

std::vector<ResultCsv> getResultCsvs(const std::string& kind) {
    if (kind == "seed-load-test")
        return {{kLoadDisplacementCsv, kLoadDisplacementHeader, ""},
                {kStiffnessCsv, kStiffnessHeader, ""},
                {kRigReadingsCsv, kRigReadingsHeader, "with a rig section"}};
    if (kind == "patient-on-support") return {{kRegionLoadsCsv, kRegionLoadsHeader, ""}};
    if (kind == "patient-on-array")
        return {{kRegionsCsv, kRegionsHeader, ""},
                {kBagsCsv, kBagsHeader, ""},
                {kTiltCsv, kTiltHeader, ""},
                {kBodyCsv, kBodyHeader, ""},
                {kEventsCsv, kEventsHeader, ""},
                {kPneumaticsCsv, kPneumaticsHeader, "with a pneumatics section"},
                {kVerdictCsv, kVerdictHeader, ""}};
    return {};
}

std::vector<std::string> splitResultHeader(const std::string& header) {
    std::vector<std::string> out(1);
    for (char c : header) {
        if (c == ',')
            out.emplace_back();
        else
            out.back() += c;
    }
    return out;
}

}  // namespace io
