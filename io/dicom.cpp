#include "io/volume_io.hpp"
namespace iso {
std::vector<SeriesInfo> list_dicom_series(const std::vector<std::string>& f) { throw Error(f.empty() ? "" : f[0], "DICOM reading is being written"); }
Volume read_dicom(const std::vector<std::string>& f, const LoadOptions&) { throw Error(f.empty() ? "" : f[0], "DICOM reading is being written"); }
}
