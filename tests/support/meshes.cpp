#include "tests/support/meshes.hpp"

namespace iso::test {

std::vector<Tri> canonical(const Mesh& m) {
    std::vector<Tri> out;
    out.reserve(m.triangles.size());
    for (const auto& t : m.triangles) {
        Tri tri;
        for (int k = 0; k < 3; ++k) tri[k] = {m.positions[t[k]].x, m.positions[t[k]].y, m.positions[t[k]].z};
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

} // namespace iso::test
