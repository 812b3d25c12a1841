// Mesh <-> vtkPolyData, for the VTK readers, writers and filters we use.
#pragma once

#include <string>

#include <vtkSmartPointer.h>

#include "io/mesh.hpp"

class vtkPolyData;

namespace iso {

// Points, triangles, point normals ("Normals") and, when `with_colors`,
// RGBA point colours.
vtkSmartPointer<vtkPolyData> to_polydata(const Mesh& m, bool with_colors = true);

// Triangulates polygons and strips (lines and vertices are dropped); reads
// point normals and 3/4-component unsigned char colours. Throws iso::Error
// naming `where` for non-finite coordinates or out-of-range indices.
Mesh from_polydata(vtkPolyData* pd, const std::string& where);

} // namespace iso
