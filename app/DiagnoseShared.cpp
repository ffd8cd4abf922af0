#include "DiagnoseShared.h"

#include <bags/SeedReading.h>
#include <io/InputError.h>
#include <io/Units.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>

#include "Interrupt.h"

namespace bagsim::app {

namespace fs = std::filesystem;

std::string takeOptionValue(int argc, char** argv, int& i) {
    if (i + 1 >= argc) throw UsageError(std::string(argv[i]) + " needs a value");
    if (argv[i + 1][0] == '\0')
        throw UsageError(std::string(argv[i]) + " needs a value, not an empty one");
    return argv[++i];
}

bool printHelpIfAsked(int argc, char** argv, const char* help) {
    for (int i = 0; i < argc; ++i)
        if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
            std::cout << help;
            return true;
        }
    return false;
}

int runCommandMain(const std::string& command, const char* help, int argc, char** argv,
                   const std::function<int(int, char**)>& run) {
    if (printHelpIfAsked(argc, argv, help)) return 0;
    const InterruptGuard guard;
    try {
        return run(argc, argv);
    } catch (const UsageError& e) {
        std::cerr << command << ": " << e.what() << " (see --help)\n";
        return 2;
    } catch (const io::InputError& e) {
        std::cerr << command << ": error: " << e.what() << "\n";
        return 2;
    } catch (const Interrupted& e) {
        std::cerr << command << ": " << e.what() << "; nothing written\n";
        return getInterruptExitCode(e.signal);
    } catch (const std::exception& e) {
        if (getInterruptSignal()) {
            std::cerr << command << ": interrupted; nothing written\n";
            return getInterruptExitCode(getInterruptSignal());
        }
        std::cerr << command << ": failed: " << e.what() << "\n";
        return 1;
    }
}

void prepareGeometry(io::LoadTestScenario& sc) { io::applyBagSizing(sc); }

/// The smallest finer mesh parseFinerMesh takes [m].
constexpr double kMinFinerMesh = 0.005;

double parseFinerMesh(const std::string& option, const std::string& text, double written) {
    if (text.empty()) return 0.0;
    const std::string valid = "valid: a length finer than the scenario's airbag.mesh_size (" +
                              io::formatSignificant(written, "mm") + ") and at least " +
                              io::formatSignificant(kMinFinerMesh, "mm") + " (e.g. 20mm)";
    double h = 0.0;
    try {
        h = io::parseQuantity(text, io::Dimension::Length);
    } catch (const io::UnitError& ex) {
        throw UsageError(option + " '" + text + "': " + ex.what() + "; " + valid);
    }
    if (!(h < written))
        throw UsageError(option + " '" + text +
                         "' is not finer than the scenario's "
                         "airbag.mesh_size (" +
                         io::formatSignificant(written, "mm") + "); " + valid);
    if (!(h >= kMinFinerMesh)) throw UsageError(option + " '" + text + "' is too fine; " + valid);
    return h;
}

void applyFinerMesh(const std::string& option, const std::string& text, double finer,
                    double written, bags::LoadTestOptions& o) {
    o.geometry.meshSize = finer * o.geometry.meshSize / written;
    const double nodes = io::estimateNumNodes(o.geometry);
    if (nodes > io::kMaxMeshNodes)
        throw UsageError(option + " '" + text + "' gives a mesh of about " +
                         fmt("%.0f", std::round(nodes / 1000) * 1000) +
                         " nodes for this airbag; at most " + std::to_string(io::kMaxMeshNodes) +
                         " are allowed; valid: a coarser mesh, below the scenario's " +
                         io::formatSignificant(written, "mm"));
}

void claimOutputFolder(const fs::path& dir, bool force, const std::vector<std::string>& owned) {
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        if (!fs::is_directory(dir, ec))
            throw io::InputError(
                dir.string(), 0, "",
                "the output path exists and is not a folder; choose another --out");
        if (!fs::is_empty(dir, ec)) {
            if (!force)
                throw io::InputError(dir.string(), 0, "",
                                     "the output folder exists and is not empty; pass --force to "
                                     "replace this command's files in it, or choose another --out");
            for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
                const std::string name = e.path().filename().string();
                for (const std::string& o : owned) {
                    // One '*' matches any run of characters ("test*-machine.csv").
                    const size_t star = o.find('*');
                    const bool match =
                        star == std::string::npos
                            ? name == o
                            : name.size() >= o.size() - 1 &&
                                  name.compare(0, star, o, 0, star) == 0 &&
                                  name.compare(name.size() - (o.size() - star - 1),
                                               o.size() - star - 1, o, star + 1) == 0;
                    if (match) {
                        fs::remove(e.path(), ec);
                        break;
                    }
                }
            }
        }
    }
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir, ec))
        throw io::InputError(dir.string(), 0, "",
                             "cannot create the output folder (" + ec.message() + ")");
}

void writeOutputFile(const fs::path& dir, const std::string& name, const std::string& text) {
    const fs::path f = dir / name, tmp = dir / (name + ".tmp");
    {
        std::ofstream o(tmp);
        o << text;
        if (!o.flush()) throw std::runtime_error("cannot write " + f.string());
    }
    fs::rename(tmp, f);
}

}  // namespace bagsim::app
