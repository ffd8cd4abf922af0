// The soft tissue per body site (see Tissue.h; the sources: docs/body.md#soft-tissue).
#include "body/Tissue.h"

#include <stdexcept>

namespace body {

TissueSite getTissueSite(Segment segment) {
    switch (segment) {
        case Segment::Head:
            return TissueSite::Occiput;
        case Segment::UpperTrunk:
            return TissueSite::Scapulae;
        case Segment::MiddleTrunk:
            return TissueSite::Back;
        case Segment::LowerTrunk:
            return TissueSite::Sacrum;
        case Segment::ThighR:
        case Segment::ThighL:
            return TissueSite::Buttocks;
        case Segment::ShankR:
        case Segment::ShankL:
            return TissueSite::Calves;
        case Segment::FootR:
        case Segment::FootL:
            return TissueSite::Heels;
        case Segment::UpperArmR:
        case Segment::ForearmR:
        case Segment::HandR:
        case Segment::UpperArmL:
        case Segment::ForearmL:
        case Segment::HandL:
            return TissueSite::Arms;
    }
    throw std::invalid_argument("getTissueSite: not a segment");
}

const char* getTissueSiteName(TissueSite site) {
    static const char* const names[kTissueSiteCount] = {"occiput",  "scapulae", "back",  "sacrum",
                                                        "buttocks", "calves",   "heels", "arms"};
    return names[static_cast<int>(site)];
}

SoftTissue getPublishedTissue(TissueSite site) {
    // thickness [m], modulus [Pa]; docs/body.md#soft-tissue gives each value's source, what it
    // measured and its spread. A site with no published value read is left rigid.
    switch (site) {
        // Sacral skin and fat, bedridden elderly, 9.7 +- 5.6 mm (n = 55; 22.7 +- 8.4 mm in
        // young women); modulus of gluteal subcutaneous tissue at low load, 26.1 +- 19.0 kPa
        // (Isogai et al. 2022, n = 21).
        case TissueSite::Sacrum:
            return {10e-3, 26e3};
        // Skin to ischial tuberosity supine, MRI, 135.9 +- 8.1 mm (Makhsous et al. 2011,
        // n = 11); gluteal subcutaneous tissue 26.1 kPa at low load (Isogai et al. 2022).
        case TissueSite::Buttocks:
            return {136e-3, 26e3};
        // Heel pad, unloaded, 17.6 +- 2.0 mm (Hsu et al. 1998, young adults; plantar, the
        // posterior pad not found); secant modulus of a heel pad's Ogden fit at the 5-12 kPa of
        // heels on air, 11-36 kPa (inverse FE of one cadaver foot, 2012): 25 kPa.
        case TissueSite::Heels:
            return {18e-3, 25e3};
        // Skin to rib between the scapulae, prone, 27 +- 4 mm (Wada et al. 2025, n = 18);
        // muscle's modulus, gluteal muscle at 5 N, 62.2 +- 10.3 kPa (Isogai et al. 2022).
        case TissueSite::Scapulae:
            return {27e-3, 62e3};
        // Gastrocnemius thickness 13.3 mm (n = 195, over 65 years: muscle alone, a lower
        // bound of the calf's tissue); its shear-wave modulus, E about 15 kPa (10-22).
        case TissueSite::Calves:
            return {13e-3, 15e3};
        // No published value read: the scalp (its skin 1.5 mm), the lumbar back and the arms
        // are left rigid.
        case TissueSite::Occiput:
        case TissueSite::Back:
        case TissueSite::Arms:
            return {};
    }
    throw std::invalid_argument("getPublishedTissue: not a site");
}

std::array<SoftTissue, kTissueSiteCount> getPublishedTissues() {
    std::array<SoftTissue, kTissueSiteCount> t;
    for (int i = 0; i < kTissueSiteCount; ++i) t[size_t(i)] = getPublishedTissue(TissueSite(i));
    return t;
}

std::vector<SoftTissue> makeSegmentTissue(const std::array<SoftTissue, kTissueSiteCount>& perSite) {
    std::vector<SoftTissue> t(kSegmentCount);
    for (int s = 0; s < kSegmentCount; ++s)
        t[size_t(s)] = perSite[size_t(static_cast<int>(getTissueSite(Segment(s))))];
    return t;
}

}  // namespace body
