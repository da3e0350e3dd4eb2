#include "ProcessInfo.h"

#include <sys/resource.h>

#include <fstream>
#include <sstream>
#include <string>

namespace cullide::bench {

std::size_t peakResidentKb() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) != 0) continue;
        std::istringstream in(line.substr(6));
        std::size_t kb = 0;
        if (in >> kb) return kb;
    }
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) == 0) return static_cast<std::size_t>(usage.ru_maxrss);
    return 0;
}

}  // namespace cullide::bench
