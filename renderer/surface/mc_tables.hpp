// Marching-cubes case tables shared by the CPU and GPU extractors.
//
// The triangulation is VTK's (vtkMarchingCubesTriangleCases, the table that
// vtkMarchingCubes and vtkFlyingEdges3D both use), read at start-up through
// VTK's public API rather than copied: using the very same table is what makes
// our output comparable triangle-for-triangle with Flying Edges.
//
// Cube corners (MC numbering): 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0)
//                              4 (0,0,1) 5 (1,0,1) 6 (1,1,1) 7 (0,1,1)
// A corner is inside when its sample >= iso (as in VTK). Case index bit c is
// set when corner c is inside.
#pragma once

#include <array>
#include <cstdint>

namespace iso::mc {

struct Edge {
    std::uint8_t corner0, corner1; // corner0 is the lower-index end
    std::uint8_t dx, dy, dz;       // offset of corner0 from the cell origin
    std::uint8_t axis;             // 0 x, 1 y, 2 z
};

struct Tables {
    // Up to 5 triangles of 3 edge ids each; -1 terminates.
    std::array<std::array<std::int8_t, 16>, 256> tri_edges;
    std::array<std::uint8_t, 256> tri_count;
    std::array<Edge, 12> edges;
    std::array<std::array<std::uint8_t, 3>, 8> corners;
};

// Built once, thread-safe.
const Tables& tables();

} // namespace iso::mc
