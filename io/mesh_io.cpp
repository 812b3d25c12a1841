#include "io/mesh.hpp"
#include "io/error.hpp"
namespace iso {
MeshStats mesh_stats(const Mesh&) { return {}; }
Mesh load_mesh(const std::string& p) { throw Error(p, "mesh reading is being written"); }
void save_mesh(const Mesh&, const std::string& p) { throw Error(p, "mesh writing is being written"); }
}
