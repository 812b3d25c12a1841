#include "renderer/surface/mc_tables.hpp"

#include <vtkMarchingCubesTriangleCases.h>

namespace iso::mc {

namespace {
Tables build() {
    Tables t{};
    t.corners = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};
    // VTK's MC edge numbering (vtkMarchingCubes): corner pairs.
    const std::uint8_t pairs[12][2] = {{0, 1}, {1, 2}, {3, 2}, {0, 3}, {4, 5}, {5, 6},
                                       {7, 6}, {4, 7}, {0, 4}, {1, 5}, {3, 7}, {2, 6}};
    for (int e = 0; e < 12; ++e) {
        const auto& a = t.corners[pairs[e][0]];
        const auto& b = t.corners[pairs[e][1]];
        Edge E{};
        E.corner0 = pairs[e][0];
        E.corner1 = pairs[e][1];
        E.dx = a[0];
        E.dy = a[1];
        E.dz = a[2];
        E.axis = b[0] != a[0] ? 0 : (b[1] != a[1] ? 1 : 2);
        t.edges[e] = E;
    }
    vtkMarchingCubesTriangleCases* cases = vtkMarchingCubesTriangleCases::GetCases();
    for (int c = 0; c < 256; ++c) {
        int n = 0;
        for (int k = 0; k < 16; ++k) t.tri_edges[c][k] = -1;
        for (const auto* e = cases[c].edges; e[0] > -1 && n < 5; e += 3, ++n)
            for (int k = 0; k < 3; ++k) t.tri_edges[c][3 * n + k] = static_cast<std::int8_t>(e[k]);
        t.tri_count[c] = static_cast<std::uint8_t>(n);
    }
    return t;
}
} // namespace

const Tables& tables() {
    static const Tables t = build();
    return t;
}

} // namespace iso::mc
