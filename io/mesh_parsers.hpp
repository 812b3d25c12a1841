// Our own readers for the simple mesh formats. VTK 9.1's vtkSTLReader,
// vtkPLYReader and vtkOBJReader crash or exhaust memory on malformed files
// (found by tests/fuzz), and vtkOBJReader reads unparsable numbers as 0, so
// these formats are parsed here with every read bounds-checked. VTP stays
// with VTK's XML reader.
#pragma once

#include <string>

#include "io/mesh.hpp"

namespace iso::detail {

// Each returns the mesh in the file's own coordinates and the text of its
// SPACE= tag ("" when none); throws iso::Error naming `path`.
Mesh parse_stl(const std::string& path, std::string& space);
Mesh parse_ply(const std::string& path, std::string& space);
Mesh parse_obj(const std::string& path, std::string& space);

} // namespace iso::detail
