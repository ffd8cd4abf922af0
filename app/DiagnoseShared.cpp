#include "DiagnoseShared.h"

#include <bags/SeedReading.h>
#include <io/InputError.h>

namespace bagsim::app {

namespace fs = std::filesystem;

void prepareGeometry(io::LoadTestScenario& sc) {
    if (!(sc.fillMass > 0.0)) return;
    const bags::FillScaleResult fs = bags::findFillScale(sc.options, sc.fillMass, sc.fillScaling);
    sc.options.geometry = fs.geometry;
    sc.fillMass = 0.0;
}

void claimOutputFolder(const fs::path& dir, bool force, const std::vector<std::string>& owned) {
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        if (!fs::is_directory(dir, ec))
            throw io::InputError(dir.string(), 0, "",
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
        throw io::InputError(dir.string(), 0, "", "cannot create the output folder (" + ec.message() + ")");
}

}  // namespace bagsim::app
