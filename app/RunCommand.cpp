// (under construction)
#include "Commands.h"
#include <iostream>
namespace bagsim::app {
int runRunCommand(int, char**) {
    std::cerr << "bagsim: this command is not built yet\n";
    return 1;
}
}  // namespace bagsim::app
