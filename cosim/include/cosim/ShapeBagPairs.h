#pragma once
/// @file Which bags of an array each body contact shape may touch, from where the shapes lie:
/// the links the coupling needs (a shape is added to every bag it may touch), and the shapes
/// no bag is under (a patient off the array).

#include <Eigen/Core>
#include <vector>

#include "cosim/ArrayLayout.h"

namespace cosim {

/// Shape `shape` may touch bag `bag`.
struct ShapeBagPair {
    int shape = 0;
    int bag = 0;
};

/// Pairs every shape (bounding sphere: centre in Ground [m], radius [m]) with every bag whose
/// flat footprint, grown by `margin` [m] on every side (the inflated bag bulges past its
/// footprint, and the shape moves during the run), meets the disc the sphere casts on the bed.
/// Sorted by shape, then bag. @throws std::invalid_argument if the sizes differ or a radius
/// or the margin is negative.
std::vector<ShapeBagPair> findShapeBagPairs(const std::vector<Eigen::Vector3d>& centres_G,
                                            const std::vector<double>& radii,
                                            const std::vector<ArrayBag>& bags, double margin);

/// The shapes that no pair holds (nothing under them), ascending.
std::vector<int> findUnsupportedShapes(int numShapes, const std::vector<ShapeBagPair>& pairs);

}  // namespace cosim
