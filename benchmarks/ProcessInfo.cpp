#include "ProcessInfo.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cullide::bench {
namespace {

/// The value of `key` ("Cpus_allowed_list:") in a /proc status file, trimmed; empty when absent.
std::string statusField(const std::string& path, const std::string& key) {
    std::ifstream status(path);
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind(key, 0) != 0) continue;
        std::istringstream in(line.substr(key.size()));
        std::string value;
        in >> value;
        return value;
    }
    return {};
}

/// utime + stime of /proc/.../stat in ms (fields 14 and 15; the name in parentheses may hold spaces), or -1.
double statCpuMs(const std::string& path) {
    std::ifstream stat(path);
    std::string line;
    if (!std::getline(stat, line)) return -1.0;
    const std::size_t close = line.rfind(')');
    if (close == std::string::npos) return -1.0;
    std::istringstream in(line.substr(close + 1));
    std::string field;
    for (int i = 3; i <= 13 && in >> field; ++i) {  // state (3) ... cmajflt (13)
    }
    unsigned long long utime = 0, stime = 0;
    if (!(in >> utime >> stime)) return -1.0;
    const long ticks = sysconf(_SC_CLK_TCK);
    return ticks > 0 ? 1000.0 * static_cast<double>(utime + stime) / static_cast<double>(ticks) : -1.0;
}

}  // namespace

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

std::vector<ThreadUse> threadUse() {
    std::vector<ThreadUse> threads;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task", error)) {
        const std::string dir = entry.path().string();
        ThreadUse t;
        std::ifstream comm(dir + "/comm");
        std::getline(comm, t.name);
        t.cpuMs = statCpuMs(dir + "/stat");
        t.cpus = statusField(dir + "/status", "Cpus_allowed_list:");
        if (t.cpuMs >= 0.0) threads.push_back(t);  // a thread that ended meanwhile is left out
    }
    std::sort(threads.begin(), threads.end(), [](const ThreadUse& a, const ThreadUse& b) { return a.cpuMs > b.cpuMs; });
    return threads;
}

long minorFaults() {
    rusage usage{};
    return getrusage(RUSAGE_SELF, &usage) == 0 ? usage.ru_minflt : 0;
}

std::string cpusAllowed() { return statusField("/proc/thread-self/status", "Cpus_allowed_list:"); }

}  // namespace cullide::bench
