#include "cosim/ShapeBagPairs.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace cosim {

std::vector<ShapeBagPair> findShapeBagPairs(const std::vector<Eigen::Vector3d>& centres_G,
                                            const std::vector<double>& radii,
                                            const std::vector<ArrayBag>& bags, double margin) {
    if (centres_G.size() != radii.size()) {
        std::ostringstream s;
        s << "findShapeBagPairs: " << centres_G.size() << " centres and " << radii.size()
          << " radii; valid: one radius per centre";
        throw std::invalid_argument(s.str());
    }
    if (!(margin >= 0.0))
        throw std::invalid_argument("findShapeBagPairs: margin " + std::to_string(margin) +
                                    " m; valid: 0 m or more");
    std::vector<ShapeBagPair> pairs;
    for (size_t s = 0; s < centres_G.size(); ++s) {
        if (!(radii[s] >= 0.0))
            throw std::invalid_argument("findShapeBagPairs: radius of shape " + std::to_string(s) +
                                        " is negative; valid: 0 m or more");
        const Eigen::Vector2d c = centres_G[s].head<2>();
        for (const ArrayBag& b : bags) {
            // Distance from the disc's centre to the grown rectangle.
            const Eigen::Vector2d lo = b.footprintMin.array() - margin;
            const Eigen::Vector2d hi = b.footprintMax.array() + margin;
            const Eigen::Vector2d nearest = c.cwiseMax(lo).cwiseMin(hi);
            if ((c - nearest).norm() <= radii[s]) pairs.push_back(ShapeBagPair{int(s), b.index});
        }
    }
    return pairs;
}

std::vector<int> findUnsupportedShapes(int numShapes, const std::vector<ShapeBagPair>& pairs) {
    std::vector<char> held(std::max(numShapes, 0), 0);
    for (const ShapeBagPair& p : pairs)
        if (p.shape >= 0 && p.shape < numShapes) held[p.shape] = 1;
    std::vector<int> out;
    for (int s = 0; s < numShapes; ++s)
        if (!held[s]) out.push_back(s);
    return out;
}

}  // namespace cosim
