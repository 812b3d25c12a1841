// The versions of isoscope and of the libraries it is built with: what an
// About box, `isoscope --version` and a bug report show. Runtime versions
// where the library says them at runtime (VTK, oneTBB, OpenImageIO), else
// the version of the headers it was built against (OpenVDB, Embree).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace iso::core {

// (component, version), isoscope first.
std::vector<std::pair<std::string, std::string>> component_versions();

} // namespace iso::core
