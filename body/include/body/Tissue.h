#pragma once
/// @file The soft tissue between a segment's bone and the support, per body site: the
/// thickness and the compressive modulus of a layer that lies inside the segment's contact
/// shape (the shape is the skin; the rigid core lies the thickness below it). The values are
/// published measurements of adults (docs/body.md#soft-tissue, each with its source); they
/// are the patient's default physics on the bags (bags::RigidContact::Options::tissueThickness
/// and tissueModulus per segment).

#include <array>
#include <string>
#include <vector>

#include "body/Anthropometry.h"

namespace body {

/// Where a segment meets the support lying down, and so whose tissue its layer is.
enum class TissueSite {
    Occiput,   ///< the head: scalp over the occipital bone
    Scapulae,  ///< the thorax: skin, fat and muscle over the scapulae
    Back,      ///< the abdomen segment's back: the lumbar paraspinal tissue
    Sacrum,    ///< the pelvis: skin and fat over the sacrum
    Buttocks,  ///< the thighs' roots: the gluteal tissue under the ischial tuberosities
    Calves,    ///< the shanks: the posterior calf
    Heels,     ///< the feet: the heel pad
    Arms,      ///< upper arms, forearms and hands
};
constexpr int kTissueSiteCount = 8;

/// A layer's thickness [m] and effective compressive (Young's) modulus [Pa]; thickness 0: no
/// layer (a rigid shape).
struct SoftTissue {
    double thickness = 0.0;
    double modulus = 0.0;
    bool isRigid() const { return !(thickness > 0.0); }
};

/// The site whose tissue a segment carries.
TissueSite getTissueSite(Segment segment);
/// The scenario name of a site ("occiput", "scapulae", "back", "sacrum", "buttocks", "calves",
/// "heels", "arms").
const char* getTissueSiteName(TissueSite site);
/// The published default of a site (docs/body.md#soft-tissue).
SoftTissue getPublishedTissue(TissueSite site);
/// Every segment's layer (body::Segment order, kSegmentCount entries) from one per site.
std::vector<SoftTissue> makeSegmentTissue(const std::array<SoftTissue, kTissueSiteCount>& perSite);
/// The published default of every site.
std::array<SoftTissue, kTissueSiteCount> getPublishedTissues();

}  // namespace body
