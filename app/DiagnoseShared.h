#pragma once
// Shared by bagsim synth-measurement and bagsim diagnose: the seed rig's scenario made ready to
// simulate, and output folders that are never overwritten by surprise.
#include <io/LoadTestScenario.h>

#include <filesystem>
#include <string>
#include <vector>

namespace bagsim::app {

/// With airbag.fill_mass, sizes the bag (a few inflations) so its geometry is fixed before
/// the simulations; prints nothing.
void prepareGeometry(io::LoadTestScenario& sc);

/// Claims an output folder for a command that writes the files `owned` (names; one '*' in a
/// name matches any run of characters): creates it; an existing folder that is not empty is refused (io::InputError)
/// unless `force`, in which case the owned files in it are removed first and others kept.
void claimOutputFolder(const std::filesystem::path& dir, bool force,
                       const std::vector<std::string>& owned);

}  // namespace bagsim::app
