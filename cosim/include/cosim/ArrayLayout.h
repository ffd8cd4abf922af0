#pragma once
/// @file An array of airbags on the bed board: where each bag stands, which way it faces and
/// the gas it holds, from a layout of rows and columns with named groups.
///
/// Ground: z up, the bed board z = 0, head towards +x (as body/Posture.h). Rows run across
/// the bed and follow each other along x (row 0 at the foot end, the smallest x); columns
/// follow each other along y (column 0 at the smallest y). Indices here start at 0; bag
/// index = row * columns + column.
///
/// Order of use: fill an ArrayLayout (io reads it from a scenario's `array` section),
/// validate() it against the bag's geometry, then makeArrayBags() gives every bag's pose
/// (AirbagSpec::X_GB) and gas mass. Errors name the scenario key (`array.row_pitch`, ...) and
/// what would be valid; io adds the file and line.

#include <bags/Geometry.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace cosim {

/// Which way a bag faces. The double wedge's base runs along its frame's x (long side, from
/// the steep chamber at x = 0 to the gentle end at x = longSide) and its width along y.
enum class BagOrientation {
    Across,         ///< long side across the bed, frame x along Ground +y
    AcrossFlipped,  ///< long side across the bed, frame x along Ground -y
    Along,          ///< long side along the bed, frame x along Ground +x
    AlongFlipped,   ///< long side along the bed, frame x along Ground -x
};
/// "across", "across-flipped", "along", "along-flipped" (throws std::invalid_argument listing
/// them).
BagOrientation parseBagOrientation(const std::string& name);
std::string toString(BagOrientation orientation);

/// Bags selected by rows and columns (empty: all) that share a gas mass.
struct BagGroup {
    std::string name;          ///< unique, e.g. "left", "odd-rows", "trunk"
    std::vector<int> rows;     ///< row indices (empty: every row)
    std::vector<int> columns;  ///< column indices (empty: every column)
    double gasMass = 0.0;      ///< [kg] per bag of the group
};

struct ArrayLayout {
    int rows = 1;              ///< along the bed (x)
    int columns = 1;           ///< across the bed (y)
    double rowPitch = 0.0;     ///< [m] between row centres along x (unused for one row)
    double columnPitch = 0.0;  ///< [m] between column centres along y (unused for one column)
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< [m] (x, y) of the array's centre
    /// Orientation per row, repeated cyclically over the rows: {Across} for all rows alike,
    /// {Across, AcrossFlipped} for wedges that alternate. Empty: Across.
    std::vector<BagOrientation> rowOrientation;
    /// Odd columns turned half a turn from their row's orientation (across <-> across-flipped,
    /// along <-> along-flipped): the double wedge is symmetric across its width, so they are
    /// the mirror images of the even columns about the bed's long axis, and a patient lying
    /// across two columns lies on a surface symmetric left to right.
    bool mirrorColumns = false;
    double gasMass = 0.0;          ///< [kg] per bag not in a group
    std::vector<BagGroup> groups;  ///< a bag may be in at most one group

    /// Checks counts, pitches (neighbouring bags' flat footprints must not overlap), groups
    /// (names unique, rows and columns in range, no bag in two groups) and gas masses (every
    /// bag's positive). @throws std::invalid_argument naming the key and what would be valid.
    void validate(const bags::DoubleWedgeParams& bag) const;
    BagOrientation getOrientation(int row) const;  ///< the row's orientation
    /// The orientation of the bag at (row, column): the row's, turned for odd columns when
    /// mirrorColumns is set.
    BagOrientation getOrientation(int row, int column) const;
};

/// One bag of the array.
struct ArrayBag {
    int index = 0, row = 0, column = 0;
    BagOrientation orientation = BagOrientation::Across;
    Eigen::Isometry3d X_GB = Eigen::Isometry3d::Identity();  ///< bag frame in Ground
    double gasMass = 0.0;                                    ///< [kg]
    int group = -1;  ///< index into ArrayLayout::groups, -1 for none
    /// The flat footprint on the bed board [m]: Ground x and y ranges.
    Eigen::Vector2d footprintMin = Eigen::Vector2d::Zero(), footprintMax = Eigen::Vector2d::Zero();
};

/// Every bag of a validated layout, index = row * columns + column; each bag's flat footprint
/// (longSide x width) centred on its cell. @throws std::invalid_argument as validate().
std::vector<ArrayBag> makeArrayBags(const ArrayLayout& layout, const bags::DoubleWedgeParams& bag);

/// The index of the bag whose flat footprint holds the bed point (x, y), or -1.
int findArrayBag(const std::vector<ArrayBag>& bags, const Eigen::Vector2d& p_xy);

}  // namespace cosim
