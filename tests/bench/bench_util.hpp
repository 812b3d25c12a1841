// Small helpers for the benchmark programs: timing, peak memory, running one
// measurement per child process (so that heap reuse cannot hide a peak).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace iso::bench {

inline double now_s() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

// Peak resident set size of this process so far (VmHWM), bytes.
inline std::size_t peak_rss() {
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
    return 0;
}
inline std::size_t current_rss() {
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
    return 0;
}
// Resets VmHWM to the current RSS (Linux >= 4.0), so a later peak_rss() is
// the peak of what follows.
inline void reset_peak_rss() {
    std::ofstream f("/proc/self/clear_refs");
    f << "5";
}

// "a,b,c" -> {"a", "b", "c"} (a benchmark's list arguments).
inline std::vector<std::string> split_list(const std::string& v) {
    std::vector<std::string> out;
    for (std::size_t p = 0; p != std::string::npos;) {
        const std::size_t q = v.find(',', p);
        out.push_back(v.substr(p, q == std::string::npos ? q : q - p));
        p = q == std::string::npos ? q : q + 1;
    }
    return out;
}

// "WxH" -> width, height; false when it is not that.
inline bool parse_size(const std::string& v, int& width, int& height) {
    return std::sscanf(v.c_str(), "%dx%d", &width, &height) == 2 && width > 0 && height > 0;
}

inline double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Runs a shell command and returns its stdout.
inline std::string capture(const std::string& cmd) {
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return out;
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    ::pclose(p);
    return out;
}

} // namespace iso::bench
