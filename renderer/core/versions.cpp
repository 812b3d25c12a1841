#include "renderer/core/versions.hpp"

#include <embree3/rtcore_config.h>
#include <oneapi/tbb/version.h>
#include <openvdb/version.h>
#include <vtkVersion.h>

#include "io/image.hpp"
#include "renderer/core/api.hpp"

namespace iso::core {

std::vector<std::pair<std::string, std::string>> component_versions() {
    const int oiio = image_library_version(); // 10000 * major + 100 * minor + patch
    return {{"isoscope", std::string(version()) + " (commit " + commit() + ")"},
            {"VTK", vtkVersion::GetVTKVersion()},
            {"OpenVDB", openvdb::getLibraryVersionString()},
            {"Embree", RTC_VERSION_STRING},
            {"oneTBB", TBB_runtime_version()},
            {"OpenImageIO", oiio < 0 ? std::string("not loaded (the image module is missing)")
                                     : std::to_string(oiio / 10000) + "." + std::to_string(oiio / 100 % 100) + "." +
                                           std::to_string(oiio % 100)}};
}

} // namespace iso::core
