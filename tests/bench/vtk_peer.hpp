// What the VTK peer programs of the benchmarks (ssao_peer, oit_peer) share:
// quantiles of frame times, "X,Y,Z" arguments, and the GL renderer's name.
#pragma once

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <vtkRenderWindow.h>

namespace iso::vtk_peer {

inline double quantile(std::vector<double> v, double q = 0.5) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

inline bool vec3(const std::string& s, double out[3]) { return std::sscanf(s.c_str(), "%lf,%lf,%lf", &out[0], &out[1], &out[2]) == 3; }

// "OpenGL renderer string" of the window's context, or "unknown".
inline std::string renderer_name(vtkRenderWindow* win) {
    const char* caps = win->ReportCapabilities();
    if (!caps) return "unknown";
    const std::string c = caps;
    const auto p = c.find("OpenGL renderer string:");
    if (p == std::string::npos) return "unknown";
    std::string r = c.substr(p + 23, c.find('\n', p) - p - 23);
    r.erase(0, r.find_first_not_of(' '));
    return r;
}

} // namespace iso::vtk_peer
