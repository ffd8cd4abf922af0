#pragma once
// Shared by bagsim synth-measurement and bagsim diagnose: the seed rig's scenario made ready to
// simulate, output folders that are never overwritten by surprise, and the command's main with
// its messages and exit statuses. UsageError, fmt, takeOptionValue and printHelpIfAsked serve
// bagsim fit-material too.
#include <io/LoadTestScenario.h>

#include "Format.h"

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace bagsim::app {

/// A user mistake on the command line: printed with the command's prefix, exit status 2.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The value of the option argv[i]: argv[++i]; a UsageError ("--out needs a value")
/// if there is none.
std::string takeOptionValue(int argc, char** argv, int& i);

/// If argv holds --help or -h: prints `help` to stdout and returns true.
bool printHelpIfAsked(int argc, char** argv, const char* help);

/// The main of synth-measurement and diagnose: --help, else `run` under an InterruptGuard.
/// Messages start with `command` ("bagsim diagnose"); exit status 2 for a UsageError (" (see
/// --help)") or an io::InputError, that of the signal when interrupted ("; nothing written"),
/// 1 for another failure; else what `run` returns.
int runCommandMain(const std::string& command, const char* help, int argc, char** argv,
                   const std::function<int(int, char**)>& run);

/// Fixes the bag's geometry before the simulations (io::applyBagSizing: airbag.fill_mass's
/// sizing, a few inflations, then airbag.volume_change); prints nothing.
void prepareGeometry(io::LoadTestScenario& sc);

/// A finer mesh for one run beside the scenario's (synth-measurement's --truth-mesh,
/// diagnose's --mesh-check): `text`, the value of `option`, read as a length finer than the
/// scenario's airbag.mesh_size `written` [m] and at least 5 mm; 0 when `text` is empty.
/// @throws UsageError naming the option, the value and what is valid.
double parseFinerMesh(const std::string& option, const std::string& text, double written);

/// Sets `o`'s mesh to the finer size `finer` [m] as the sizing (fill mass, volume change)
/// scaled the written `written` [m] into o's; refused (UsageError) beyond the node limit.
void applyFinerMesh(const std::string& option, const std::string& text, double finer,
                    double written, bags::LoadTestOptions& o);

/// Claims an output folder for a command that writes the files `owned` (names; one '*' in a
/// name matches any run of characters): creates it; an existing folder that is not empty is refused (io::InputError)
/// unless `force`, in which case the owned files in it are removed first and others kept.
void claimOutputFolder(const std::filesystem::path& dir, bool force,
                       const std::vector<std::string>& owned);

}  // namespace bagsim::app

namespace bagsim::app {

/// Writes `name` into the output folder through a temporary file renamed into place.
/// @throws std::runtime_error if it cannot be written.
void writeOutputFile(const std::filesystem::path& dir, const std::string& name,
                     const std::string& text);

}  // namespace bagsim::app
