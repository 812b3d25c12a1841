// The small headless core API that the CLI and the GUI call. It holds no
// presentation (no printing, no widgets) and no file-format code of its own.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "io/volume_io.hpp"

namespace iso::core {

const char* version();

// Loads a volume (file or DICOM folder). Throws iso::Error.
Volume open_volume(const std::string& path, const LoadOptions& opt = {});
Mesh open_mesh(const std::string& path);

// Lists the DICOM series of a folder or file without loading pixel data.
std::vector<SeriesInfo> list_series(const std::string& path);

// What `isoscope info` shows, as one JSON object: dims, spacing,
// index_to_lps (row-major 4x4), range, type, memory_bytes, format, source,
// storage (dense/sparse), metadata, warnings and, for DICOM, the series list.
nlohmann::json describe(const Volume& v);

} // namespace iso::core
