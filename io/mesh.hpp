// Triangle meshes: positions in LPS millimetres, optional per-vertex normals
// and colours, indexed triangles.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace iso {

struct Mesh {
    std::vector<glm::vec3> positions; // LPS mm
    std::vector<glm::vec3> normals;   // empty or one per position, unit length
    std::vector<glm::u8vec4> colors;  // empty or one per position, RGBA8
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<std::string> warnings; // non-fatal findings while reading

    bool empty() const { return triangles.empty(); }
};

struct MeshStats {
    std::size_t vertices = 0, triangles = 0;
    glm::dvec3 bounds_min{0.0}, bounds_max{0.0};
    double area = 0;   // mm^2
    double volume = 0; // signed enclosed volume, mm^3 (positive when outward-facing)
};
MeshStats mesh_stats(const Mesh& m);

// One triangle's terms of a surface's statistics, its corners taken relative
// to `o` (a, b, c): area; det = a . (b x c), six times the signed volume of
// the tetrahedron (o, p0, p1, p2); moment = a x b + b x c + c x a. Summed over
// a closed surface, det / 6 is its volume; summed over pieces taken about
// different origins, the volume about another point q is
// volume - (q - o) . moment / 6 (volume_moved). mesh_stats, the streaming
// sinks and the piece summaries (renderer/surface/components) all use it.
struct TriangleTerms {
    double area = 0, det = 0;
    glm::dvec3 moment{0.0};
};
TriangleTerms triangle_terms(const glm::dvec3& o, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2);
// The signed volume `volume` (with moment sum `moment`) taken about `from`, about `to`.
double volume_moved(double volume, const glm::dvec3& moment, const glm::dvec3& from, const glm::dvec3& to);

// The mesh file extensions isoscope reads and writes, lower case with the
// dot: .stl (binary; ASCII read too), .ply, .obj, .vtp. The one list: the
// readers, the writers and the front ends all ask it.
const std::vector<std::string>& mesh_extensions();
// Does the path's extension (any case: .STL too) name a mesh format?
bool is_mesh_path(const std::string& path);
// "'.stl', '.ply', '.obj' or '.vtp'", for messages.
std::string mesh_extensions_text();

// Formats by extension (mesh_extensions()).
// Readers convert to LPS when the file says it is in RAS (Slicer's
// "SPACE=RAS" comment); files that say nothing are taken as LPS.
Mesh load_mesh(const std::string& path);
// Writers tag the file as LPS where the format has a header or comment.
// Writes to a temporary file and renames it into place.
void save_mesh(const Mesh& m, const std::string& path);

} // namespace iso
