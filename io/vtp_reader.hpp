// VTK XML PolyData (.vtp) read by VTK in a child process (see vtp_reader.cpp).
#pragma once

#include <cstdint>
#include <string>

#include "io/mesh.hpp"

namespace iso::detail {

// The mesh in `path` (a .vtp of `file_size` bytes) and its SPACE tag
// (`space`, empty without one). Throws iso::Error naming the file.
Mesh read_vtp(const std::string& path, std::string& space, std::uint64_t file_size);

} // namespace iso::detail
