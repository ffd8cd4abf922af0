#include "cosim/ArrayLayout.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace cosim {

namespace {

bool isAcross(BagOrientation o) {
    return o == BagOrientation::Across || o == BagOrientation::AcrossFlipped;
}

// Flat footprint extents (along Ground x, along Ground y) [m].
Eigen::Vector2d calcExtent(BagOrientation o, const bags::DoubleWedgeParams& bag) {
    return isAcross(o) ? Eigen::Vector2d(bag.width, bag.longSide)
                       : Eigen::Vector2d(bag.longSide, bag.width);
}

// Yaw of the bag frame about Ground z [rad].
double calcYaw(BagOrientation o) {
    switch (o) {
        case BagOrientation::Across:
            return 0.5 * M_PI;
        case BagOrientation::AcrossFlipped:
            return -0.5 * M_PI;
        case BagOrientation::Along:
            return 0.0;
        case BagOrientation::AlongFlipped:
            return M_PI;
    }
    return 0.0;
}

std::string mm(double m) {
    std::ostringstream s;
    s << 1e3 * m << " mm";
    return s.str();
}

[[noreturn]] void fail(const std::string& key, const std::string& what) {
    throw std::invalid_argument("key '" + key + "': " + what);
}

}  // namespace

BagOrientation parseBagOrientation(const std::string& name) {
    if (name == "across") return BagOrientation::Across;
    if (name == "across-flipped") return BagOrientation::AcrossFlipped;
    if (name == "along") return BagOrientation::Along;
    if (name == "along-flipped") return BagOrientation::AlongFlipped;
    throw std::invalid_argument("orientation '" + name +
                                "'; valid: across, across-flipped, along, along-flipped");
}

std::string toString(BagOrientation o) {
    switch (o) {
        case BagOrientation::Across:
            return "across";
        case BagOrientation::AcrossFlipped:
            return "across-flipped";
        case BagOrientation::Along:
            return "along";
        case BagOrientation::AlongFlipped:
            return "along-flipped";
    }
    return "?";
}

BagOrientation ArrayLayout::getOrientation(int row) const {
    if (rowOrientation.empty()) return BagOrientation::Across;
    return rowOrientation[row % rowOrientation.size()];
}

BagOrientation ArrayLayout::getOrientation(int row, int column) const {
    const BagOrientation o = getOrientation(row);
    if (!mirrorColumns || column % 2 == 0) return o;
    switch (o) {
        case BagOrientation::Across:
            return BagOrientation::AcrossFlipped;
        case BagOrientation::AcrossFlipped:
            return BagOrientation::Across;
        case BagOrientation::Along:
            return BagOrientation::AlongFlipped;
        case BagOrientation::AlongFlipped:
            return BagOrientation::Along;
    }
    return o;
}

void ArrayLayout::validate(const bags::DoubleWedgeParams& bag) const {
    if (rows < 1) fail("array.rows", std::to_string(rows) + "; valid: 1 or more");
    if (columns < 1) fail("array.columns", std::to_string(columns) + "; valid: 1 or more");
    if (!centre.allFinite()) fail("array.centre", "not finite; valid: a bed point [x, y] in m");
    // Neighbouring rows: half of each one's extent along x must fit in the pitch.
    for (int r = 0; r + 1 < rows; ++r) {
        const double need = 0.5 * (calcExtent(getOrientation(r), bag).x() +
                                   calcExtent(getOrientation(r + 1), bag).x());
        if (!(rowPitch >= need - 1e-12)) {
            std::ostringstream s;
            s << mm(rowPitch) << " is less than the " << mm(need) << " that rows " << r << " ("
              << toString(getOrientation(r)) << ") and " << r + 1 << " ("
              << toString(getOrientation(r + 1))
              << ") take along the bed: their bags would overlap; valid: " << mm(need)
              << " or more";
            fail("array.row_pitch", s.str());
        }
    }
    if (columns > 1)
        for (int r = 0; r < rows; ++r) {
            const double need = calcExtent(getOrientation(r), bag).y();
            if (!(columnPitch >= need - 1e-12)) {
                std::ostringstream s;
                s << mm(columnPitch) << " is less than the " << mm(need) << " a bag of row " << r
                  << " (" << toString(getOrientation(r))
                  << ") takes across the bed: neighbouring columns would overlap; valid: "
                  << mm(need) << " or more";
                fail("array.column_pitch", s.str());
            }
        }
    std::set<std::string> names;
    std::vector<int> owner(static_cast<size_t>(rows) * columns, -1);
    for (size_t g = 0; g < groups.size(); ++g) {
        const BagGroup& G = groups[g];
        const std::string key = "array.groups[" + std::to_string(g) + "]";
        if (G.name.empty()) fail(key + ".name", "empty; valid: a unique name");
        if (!names.insert(G.name).second)
            fail(key + ".name", "'" + G.name + "' names two groups; valid: a unique name");
        for (int r : G.rows)
            if (r < 0 || r >= rows)
                fail(key + ".rows", "row " + std::to_string(r) + " of group '" + G.name +
                                        "'; valid: 0 to " + std::to_string(rows - 1));
        for (int c : G.columns)
            if (c < 0 || c >= columns)
                fail(key + ".columns", "column " + std::to_string(c) + " of group '" + G.name +
                                           "'; valid: 0 to " + std::to_string(columns - 1));
        if (!(G.gasMass > 0.0) || !std::isfinite(G.gasMass)) {
            std::ostringstream s;
            s << G.gasMass * 1e3 << " g for group '" << G.name << "'; valid: a positive mass";
            fail(key + ".gas_mass", s.str());
        }
        for (int r = 0; r < rows; ++r) {
            if (!G.rows.empty() && std::find(G.rows.begin(), G.rows.end(), r) == G.rows.end())
                continue;
            for (int c = 0; c < columns; ++c) {
                if (!G.columns.empty() &&
                    std::find(G.columns.begin(), G.columns.end(), c) == G.columns.end())
                    continue;
                int& o = owner[static_cast<size_t>(r) * columns + c];
                if (o >= 0)
                    fail(key, "the bag at row " + std::to_string(r) + ", column " +
                                  std::to_string(c) + " is in group '" + groups[o].name +
                                  "' and in group '" + G.name +
                                  "'; valid: each bag in at most one group");
                o = int(g);
            }
        }
    }
    for (size_t i = 0; i < owner.size(); ++i)
        if (owner[i] < 0 && !(gasMass > 0.0 && std::isfinite(gasMass))) {
            std::ostringstream s;
            s << gasMass * 1e3 << " g, and the bag at row " << i / columns << ", column "
              << i % columns << " is in no group; valid: a positive mass";
            fail("array.gas_mass", s.str());
        }
}

std::vector<ArrayBag> makeArrayBags(const ArrayLayout& layout, const bags::DoubleWedgeParams& bag) {
    bag.validate();
    layout.validate(bag);
    std::vector<ArrayBag> out;
    out.reserve(static_cast<size_t>(layout.rows) * layout.columns);
    // The flat footprint's centre in the bag frame.
    const Eigen::Vector3d c_B(0.5 * bag.longSide, 0.0, 0.0);
    for (int r = 0; r < layout.rows; ++r)
        for (int c = 0; c < layout.columns; ++c) {
            ArrayBag b;
            b.index = r * layout.columns + c;
            b.row = r;
            b.column = c;
            b.orientation = layout.getOrientation(r, c);
            const Eigen::Vector2d cell =
                layout.centre +
                Eigen::Vector2d((r - 0.5 * (layout.rows - 1)) * layout.rowPitch,
                                (c - 0.5 * (layout.columns - 1)) * layout.columnPitch);
            const Eigen::Matrix3d R =
                Eigen::AngleAxisd(calcYaw(b.orientation), Eigen::Vector3d::UnitZ())
                    .toRotationMatrix();
            b.X_GB.linear() = R;
            b.X_GB.translation() = Eigen::Vector3d(cell.x(), cell.y(), 0.0) - R * c_B;
            const Eigen::Vector2d half = 0.5 * calcExtent(b.orientation, bag);
            b.footprintMin = cell - half;
            b.footprintMax = cell + half;
            b.gasMass = layout.gasMass;
            for (size_t g = 0; g < layout.groups.size(); ++g) {
                const BagGroup& G = layout.groups[g];
                const bool inRows =
                    G.rows.empty() || std::find(G.rows.begin(), G.rows.end(), r) != G.rows.end();
                const bool inCols =
                    G.columns.empty() ||
                    std::find(G.columns.begin(), G.columns.end(), c) != G.columns.end();
                if (inRows && inCols) {
                    b.group = int(g);
                    b.gasMass = G.gasMass;
                }
            }
            out.push_back(b);
        }
    return out;
}

int findArrayBag(const std::vector<ArrayBag>& bags, const Eigen::Vector2d& p) {
    for (const ArrayBag& b : bags)
        if ((p.array() >= b.footprintMin.array()).all() &&
            (p.array() <= b.footprintMax.array()).all())
            return b.index;
    return -1;
}

}  // namespace cosim
