// Manifold surfaces at ties: iso values equal to sample values.
//
// Every volume here is extracted at an iso value that some samples equal
// exactly. For each result we check, from the stored float positions:
//   - no degenerate triangle: no repeated index, and a non-zero area computed
//     in double from the float positions;
//   - no two vertices at the same float position;
//   - every edge is used by exactly two triangles, in opposite directions,
//     except edges on the volume border, used by exactly one (surfaces that
//     reach the border are open there). A mesh edge is a border edge when both
//     its end vertices lie on the same face plane of the volume's index box
//     (index coordinate 0 or dims-1 on the same axis), within kOnFace voxel.
//     A vertex sits strictly inside its lattice edge, at least kMargin from
//     either end, so a vertex whose edge runs along axis a is never within
//     kOnFace of a face plane of axis a: the test is exact;
//   - every vertex is manifold: the edges opposite it in its triangles (its
//     link) form one connected cycle, or one path at the border;
//   - chunked == unchunked (chunk sizes 2..16 and 32) as triangle sets.
// The GPU side (same vertices bit for bit, by key) is in
// tests/gl/gpu_isosurface_test.cpp.
#include "renderer/surface/extract.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkShortArray.h>

#include "io/volume_io.hpp"
#include "renderer/surface/analysis.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::canonical;
using iso::test::plain_sums;

namespace {

// The extractor's edge margin (renderer/surface/extract.hpp): vertices lie in
// [kMargin, 1 - kMargin] of their lattice edge.
constexpr double kMargin = kEdgeMargin;
// A vertex is on a face plane within this many voxels. Well below kMargin
// (1/128), well above the float rounding of the positions mapped back to index
// space (6e-4 voxel at 0.05 mm spacing 300 mm from the origin, the worst case here).
constexpr double kOnFace = kMargin / 4;

struct Report {
    std::size_t triangles = 0, vertices = 0;
    std::size_t repeated_index = 0, zero_area = 0, duplicate_positions = 0;
    std::size_t interior_edges_not_two = 0; // interior edge used by != 2 triangles
    std::size_t edges_over_two = 0;         // any edge used by > 2 triangles (pinches)
    std::size_t border_edges_not_one = 0;   // border edge used by != 1 triangle
    std::size_t misoriented = 0;            // interior edge used twice in the same direction
    std::size_t nonmanifold_vertices = 0;   // link is not one cycle/path
    std::size_t border_edges = 0;
    bool ok() const {
        return repeated_index + zero_area + duplicate_positions + interior_edges_not_two + border_edges_not_one +
                   misoriented + nonmanifold_vertices ==
               0;
    }
};

std::ostream& operator<<(std::ostream& o, const Report& r) {
    return o << "triangles " << r.triangles << ", vertices " << r.vertices << ", repeated index " << r.repeated_index
             << ", zero area " << r.zero_area << ", duplicate positions " << r.duplicate_positions
             << ", interior edges not shared by 2 " << r.interior_edges_not_two
             << " (of which > 2: " << r.edges_over_two << "), border edges not used once " << r.border_edges_not_one
             << " (border edges " << r.border_edges << "), misoriented " << r.misoriented << ", non-manifold vertices "
             << r.nonmanifold_vertices;
}

// Bit mask of the volume faces a vertex lies on: bit 2a (index 0), bit 2a+1 (index dims-1).
std::vector<std::uint8_t> face_masks(const Mesh& m, const Volume& v) {
    const glm::dmat4 inv = glm::inverse(v.index_to_lps);
    std::vector<std::uint8_t> f(m.positions.size(), 0);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const glm::dvec3 q = glm::dvec3(inv * glm::dvec4(glm::dvec3(m.positions[i]), 1.0));
        for (int a = 0; a < 3; ++a) {
            if (std::abs(q[a]) < kOnFace) f[i] |= std::uint8_t(1 << (2 * a));
            if (std::abs(q[a] - double(v.dims[a] - 1)) < kOnFace) f[i] |= std::uint8_t(1 << (2 * a + 1));
        }
    }
    return f;
}

Report check(const Mesh& m, const Volume& v) {
    Report r;
    r.triangles = m.triangles.size();
    r.vertices = m.positions.size();
    {
        std::set<std::array<float, 3>> seen;
        for (const auto& p : m.positions)
            if (!seen.insert({p.x, p.y, p.z}).second) ++r.duplicate_positions;
    }
    const auto faces = face_masks(m, v);
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::array<int, 2>> edges; // (lo, hi) -> uses lo->hi, hi->lo
    std::vector<std::array<std::uint32_t, 3>> link;                              // (vertex, a, b)
    for (const auto& t : m.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            ++r.repeated_index;
            continue;
        }
        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        if (glm::length(glm::cross(b - a, c - a)) == 0.0) ++r.zero_area;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t p = t[k], q = t[(k + 1) % 3];
            auto& e = edges[{std::min(p, q), std::max(p, q)}];
            ++e[p < q ? 0 : 1];
            link.push_back({t[k], t[(k + 1) % 3], t[(k + 2) % 3]});
        }
    }
    for (const auto& [e, uses] : edges) {
        const int n = uses[0] + uses[1];
        if (n > 2) ++r.edges_over_two;
        if (faces[e.first] & faces[e.second]) {
            ++r.border_edges;
            if (n != 1) ++r.border_edges_not_one;
        } else {
            if (n != 2)
                ++r.interior_edges_not_two;
            else if (uses[0] != 1)
                ++r.misoriented;
        }
    }
    // Vertex links: union-find over the link vertices of each vertex.
    std::sort(link.begin(), link.end());
    for (std::size_t i = 0; i < link.size();) {
        std::size_t j = i;
        while (j < link.size() && link[j][0] == link[i][0]) ++j;
        std::map<std::uint32_t, std::uint32_t> parent;
        auto find = [&](std::uint32_t x) {
            while (parent[x] != x) x = parent[x] = parent[parent[x]];
            return x;
        };
        for (std::size_t k = i; k < j; ++k)
            for (int s = 1; s <= 2; ++s) parent.emplace(link[k][s], link[k][s]);
        std::size_t components = parent.size();
        for (std::size_t k = i; k < j; ++k) {
            const auto a = find(link[k][1]), b = find(link[k][2]);
            if (a != b) {
                parent[a] = b;
                --components;
            }
        }
        if (components != 1) ++r.nonmanifold_vertices;
        i = j;
    }
    return r;
}

// Checks one volume at one iso value: manifold, and the same at every chunk size.
void expect_manifold_and_chunk_invariant(const Volume& v, double iso, const std::string& what,
                                         std::size_t min_triangles = 1) {
    const Mesh ref = extract_isosurface(v, iso, {.chunk_size = 1 << 20, .threads = 1});
    const Report r = check(ref, v);
    EXPECT_TRUE(r.ok()) << what << " iso " << iso << ": " << r;
    EXPECT_GE(r.triangles, min_triangles) << what << " iso " << iso;
    const auto cref = canonical(ref);
    for (int c : {2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 32}) {
        const Mesh m = extract_isosurface(v, iso, {.chunk_size = c, .threads = 2});
        EXPECT_EQ(m.positions.size(), ref.positions.size()) << what << " iso " << iso << " chunk " << c;
        EXPECT_TRUE(canonical(m) == cref) << what << " iso " << iso << " chunk " << c;
    }
}

Volume int_volume(std::array<std::int64_t, 3> dims, const glm::dmat4& aff = glm::dmat4(1.0)) {
    return Volume::dense(dims, VoxelType::I16, aff);
}
std::int16_t& at(Volume& v, std::int64_t i, std::int64_t j, std::int64_t k) {
    return v.as<std::int16_t>()[v.linear_index(i, j, k)];
}

Volume headsq() { return read_nrrd(test::data("headsq.nhdr")); }

// vtkFlyingEdges3D's triangle and point counts on an int16 volume. It also
// treats samples >= iso as inside and gives each cut edge one point, but puts
// that point on the sample at a tie (zero-area triangles, coincident points).
std::pair<std::size_t, std::size_t> flying_edges_counts(const Volume& v, double iso) {
    vtkNew<vtkShortArray> arr;
    arr->SetNumberOfTuples(v.voxel_count());
    for (std::int64_t n = 0; n < v.voxel_count(); ++n) arr->SetValue(n, v.as<std::int16_t>()[std::size_t(n)]);
    vtkNew<vtkImageData> img;
    img->SetDimensions(int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
    img->GetPointData()->SetScalars(arr);
    vtkNew<vtkFlyingEdges3D> fe;
    fe->SetInputData(img);
    fe->SetValue(0, iso);
    fe->ComputeNormalsOff();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    fe->Update();
    return {std::size_t(fe->GetOutput()->GetNumberOfPolys()), std::size_t(fe->GetOutput()->GetNumberOfPoints())};
}

} // namespace

// Every one of the 256 marching-cubes cases with ties: cell c (0..255) gets
// its own 2x2x2 block of samples, corner n inside (== iso) where bit n of c
// is set and outside (iso - 1) otherwise; blocks are 3 samples apart, the
// samples between them outside, so each case is a closed piece of its own
// (and, with a second layout, the same cases packed with no gap so that
// neighbouring cases share faces).
TEST(Ties, All256CasesWithTies) {
    const double iso = 300;
    for (int gap : {1, 0}) {
        const int stride = 2 + gap;
        auto v = int_volume({16 * stride + 2, 16 * stride + 2, 2 + 2});
        for (auto& x : v.as<std::int16_t>()) x = std::int16_t(iso - 1);
        for (int c = 0; c < 256; ++c) {
            const std::int64_t i0 = 1 + stride * (c % 16), j0 = 1 + stride * (c / 16);
            for (int n = 0; n < 8; ++n)
                if (c & (1 << n)) {
                    // VTK corner order: 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0), 4..7 the same at z + 1.
                    static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
                    at(v, i0 + off[n][0], j0 + off[n][1], 1 + off[n][2]) = std::int16_t(iso);
                }
        }
        expect_manifold_and_chunk_invariant(v, iso, "256 cases gap " + std::to_string(gap), 1000);
    }
}

// Checkerboards: values alternate between a tie and a lower value (every
// inside sample a tie, every cell ambiguous), and a three-level pattern
// iso - 1, iso, iso + 1. The surfaces reach the volume border: open there.
TEST(Ties, Checkerboards) {
    auto v = int_volume({13, 12, 11});
    for (std::int64_t k = 0; k < 11; ++k)
        for (std::int64_t j = 0; j < 12; ++j)
            for (std::int64_t i = 0; i < 13; ++i) at(v, i, j, k) = std::int16_t((i + j + k) % 2 ? 500 : 499);
    expect_manifold_and_chunk_invariant(v, 500, "checkerboard", 1000);
    for (std::int64_t k = 0; k < 11; ++k)
        for (std::int64_t j = 0; j < 12; ++j)
            for (std::int64_t i = 0; i < 13; ++i) at(v, i, j, k) = std::int16_t(499 + (i + 2 * j + k) % 3);
    expect_manifold_and_chunk_invariant(v, 500, "three-level checkerboard", 1000);
    expect_manifold_and_chunk_invariant(v, 501, "three-level checkerboard", 1000);
}

// Plateaus: a constant block equal to iso inside lower values (the surface
// hugs the block kEdgeMargin outside it), the same block with a core of
// higher values, a plateau at iso around a higher core inside higher
// surroundings (a tie layer between two inside regions: no surface from it),
// and a plateau reaching the volume border.
TEST(Ties, Plateaus) {
    auto v = int_volume({14, 13, 12});
    for (auto& x : v.as<std::int16_t>()) x = 100;
    for (std::int64_t k = 3; k < 9; ++k)
        for (std::int64_t j = 2; j < 10; ++j)
            for (std::int64_t i = 4; i < 11; ++i) at(v, i, j, k) = 300;
    expect_manifold_and_chunk_invariant(v, 300, "plateau in lower values", 100);
    {
        // The surface is the block's boundary pushed out by the margin, its
        // edges and corners chamfered: the volume it encloses lies between the
        // block's (samples 7 x 8 x 6 span 6 x 7 x 5 cells) and that of the
        // block grown by the margin on every side.
        const Mesh m = extract_isosurface(v, 300, {});
        const double vol = plain_sums(m).volume_mm3;
        EXPECT_GT(vol, 6.0 * 7.0 * 5.0);
        EXPECT_LT(vol, (6.0 + 2 * kMargin) * (7.0 + 2 * kMargin) * (5.0 + 2 * kMargin));
    }
    for (std::int64_t k = 5; k < 7; ++k)
        for (std::int64_t j = 4; j < 8; ++j)
            for (std::int64_t i = 6; i < 9; ++i) at(v, i, j, k) = 900;
    expect_manifold_and_chunk_invariant(v, 300, "plateau with a higher core", 100);
    // Higher surroundings: the plateau at iso is inside, like everything else.
    for (auto& x : v.as<std::int16_t>())
        if (x == 100) x = 1000;
    EXPECT_TRUE(extract_isosurface(v, 300, {}).empty()) << "every sample is inside";
    // A plateau touching three faces of the volume, in lower values.
    for (auto& x : v.as<std::int16_t>()) x = 100;
    for (std::int64_t k = 0; k < 6; ++k)
        for (std::int64_t j = 0; j < 7; ++j)
            for (std::int64_t i = 0; i < 9; ++i) at(v, i, j, k) = 300;
    expect_manifold_and_chunk_invariant(v, 300, "plateau on the border", 50);
    const Report r = check(extract_isosurface(v, 300, {}), v);
    EXPECT_GT(r.border_edges, 0u) << "open at the volume border";
}

// Single voxels equal to iso in lower values: a tiny closed surface each
// (an octahedron kEdgeMargin voxel around the sample); two tie voxels
// touching along an edge or at a corner (the configurations that pinched).
TEST(Ties, SingleVoxels) {
    auto v = int_volume({12, 12, 12});
    for (auto& x : v.as<std::int16_t>()) x = 7;
    at(v, 3, 3, 3) = 10;
    {
        const Mesh m = extract_isosurface(v, 10, {});
        EXPECT_EQ(m.triangles.size(), 8u) << "one octahedron";
        EXPECT_TRUE(check(m, v).ok()) << check(m, v);
        // An octahedron with half-diagonal 1 - (1 - margin) = margin: volume 4/3 margin^3.
        EXPECT_NEAR(plain_sums(m).volume_mm3, 4.0 / 3.0 * std::pow(kMargin, 3), 1e-3 * std::pow(kMargin, 3));
    }
    at(v, 8, 3, 3) = 10;
    at(v, 9, 4, 3) = 10; // edge-adjacent to (8,3,3) across a face diagonal
    at(v, 4, 8, 8) = 10;
    at(v, 5, 9, 9) = 10;  // corner-adjacent
    at(v, 0, 0, 0) = 10;  // on a volume corner: open
    at(v, 11, 5, 6) = 10; // on a volume face
    expect_manifold_and_chunk_invariant(v, 10, "single voxels", 40);
}

// Random small integers 0..3 at iso 1, 2 and 3: every configuration of ties,
// with a zero frame (closed surfaces) and without (open at the border).
TEST(Ties, IntegerNoise) {
    std::mt19937 rng(16);
    std::uniform_int_distribution<int> u(0, 3);
    for (bool frame : {true, false}) {
        auto v = int_volume({19, 17, 16});
        for (std::int64_t k = 0; k < 16; ++k)
            for (std::int64_t j = 0; j < 17; ++j)
                for (std::int64_t i = 0; i < 19; ++i) {
                    const bool edge = i == 0 || j == 0 || k == 0 || i == 18 || j == 16 || k == 15;
                    at(v, i, j, k) = std::int16_t(frame && edge ? 0 : u(rng));
                }
        for (double iso : {1.0, 2.0, 3.0})
            expect_manifold_and_chunk_invariant(v, iso, frame ? "noise in a zero frame" : "noise", 1000);
    }
}

// A float volume with exact ties, including values that are not dyadic
// (0.1f): the iso value is the float sample's exact double value. And samples
// a hair away from the iso value (not ties): the vertex would be 1e-7 of an
// edge from a sample, which float positions cannot tell apart; the margin
// applies there too.
TEST(Ties, FloatTiesAndNearTies) {
    std::mt19937 rng(17);
    const float values[] = {0.0f, 0.1f, 0.2f, 0.3f};
    std::uniform_int_distribution<int> u(0, 3);
    auto v = Volume::dense({15, 14, 13}, VoxelType::F32, glm::dmat4(1.0));
    for (auto& x : v.as<float>()) x = values[u(rng)];
    expect_manifold_and_chunk_invariant(v, double(0.1f), "float ties", 500);
    expect_manifold_and_chunk_invariant(v, double(0.2f), "float ties", 500);
    // Near ties: 0.2f nudged up and down by one ulp, iso exactly 0.2f.
    for (auto& x : v.as<float>())
        if (x == 0.2f) x = std::nextafter(0.2f, u(rng) % 2 ? 1.0f : 0.0f);
    expect_manifold_and_chunk_invariant(v, double(0.2f), "float near ties", 500);
}

// The float32 argument: 0.05 mm voxels, anisotropic and oblique, about 300 mm
// from the origin, where float coordinates are 3e-5 mm apart. The margin of
// 1/128 of an edge (>= 3.9e-4 mm here, 13 float steps) keeps every vertex
// distinct and every triangle non-degenerate after the positions are stored
// as float.
TEST(Ties, SmallObliqueVoxelsFarFromTheOrigin) {
    const glm::dmat4 aff = glm::translate(glm::dmat4(1.0), glm::dvec3(-180, 150, 300)) *
                           glm::rotate(glm::dmat4(1.0), glm::radians(33.0), glm::normalize(glm::dvec3(1, 2, 0.5))) *
                           glm::scale(glm::dmat4(1.0), glm::dvec3(0.05, 0.06, 0.08));
    std::mt19937 rng(18);
    std::uniform_int_distribution<int> u(0, 3);
    auto v = int_volume({17, 15, 14}, aff);
    for (auto& x : v.as<std::int16_t>()) x = std::int16_t(u(rng));
    for (double iso : {1.0, 2.0}) expect_manifold_and_chunk_invariant(v, iso, "oblique 0.05 mm at 300 mm", 1000);
}

// The bundled CT (int16, 64 x 64 x 93, 3.2 x 3.2 x 1.5 mm) at 500 and 1150,
// values many of its samples equal. Prints the figures in docs/isosurface.md
// (triangles, area, volume, extraction time, how far the margin moves vertices).
TEST(Ties, BundledCtAt500And1150) {
    const Volume v = headsq();
    for (double iso : {500.0, 1150.0}) {
        std::size_t ties = 0;
        for (std::int64_t n = 0; n < v.voxel_count(); ++n) ties += v.as<std::int16_t>()[std::size_t(n)] == iso;
        EXPECT_GT(ties, 10u) << "the test needs ties";
        expect_manifold_and_chunk_invariant(v, iso, "headsq", 10000);
        // Figures: median of 5 extractions (default options, normals included).
        std::vector<double> ms;
        Mesh m;
        for (int rep = 0; rep < 5; ++rep) {
            const auto t0 = std::chrono::steady_clock::now();
            m = extract_isosurface(v, iso, {});
            ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        }
        std::sort(ms.begin(), ms.end());
        const auto s = plain_sums(m);
        const Report r = check(m, v);
        // How far the margin moves vertices: each vertex's key names its edge;
        // the unclamped vertex is at t = (iso - s0) / (s1 - s0).
        const auto cs = Extractor(v, {.keep_keys = true}).extract(iso);
        std::size_t moved = 0, total = 0, moved_ties = 0, on_sample = 0;
        double worst = 0, worst_mm = 0;
        for (const auto& c : cs.chunks)
            for (std::size_t i = 0; i < c.keys.size(); ++i) {
                const std::uint64_t lin = c.keys[i] / 4;
                const int axis = int(c.keys[i] % 4);
                if (axis == 3) { // the old extractor's vertex on a sample
                    ++on_sample;
                    continue;
                }
                const std::int64_t x = std::int64_t(lin % std::uint64_t(v.dims[0])),
                                   y = std::int64_t((lin / std::uint64_t(v.dims[0])) % std::uint64_t(v.dims[1])),
                                   z = std::int64_t(lin / std::uint64_t(v.dims[0] * v.dims[1]));
                glm::dvec3 e(0.0);
                e[axis] = 1;
                const double s0 = v.value(x, y, z), s1 = v.value(x + (axis == 0), y + (axis == 1), z + (axis == 2));
                const double t = std::clamp((iso - s0) / (s1 - s0), 0.0, 1.0);
                const glm::dvec3 exact = v.index_to_world(glm::dvec3(x, y, z) + t * e);
                const glm::dvec3 got(c.positions[i]);
                const glm::dvec3 idx = glm::dvec3(glm::inverse(v.index_to_lps) * glm::dvec4(got, 1.0));
                const double d = std::abs(idx[axis] - (double(glm::dvec3(x, y, z)[axis]) + t));
                ++total;
                if (t < kMargin || t > 1 - kMargin) {
                    ++moved;
                    moved_ties += s0 == iso || s1 == iso;
                }
                worst = std::max(worst, d);
                worst_mm = std::max(worst_mm, glm::length(got - exact));
            }
        EXPECT_EQ(on_sample, 0u) << "every vertex is on an edge, none on a sample";
        const auto [fe_tris, fe_points] = flying_edges_counts(v, iso);
        EXPECT_EQ(m.triangles.size(), fe_tris) << "the same triangles as Flying Edges, none dropped";
        EXPECT_EQ(m.positions.size(), fe_points) << "one vertex per cut edge, as Flying Edges";
        EXPECT_LE(worst, kMargin + 1e-5) << "no vertex moves by more than the margin (1e-5: float rounding)";
        // Components, and the tiny ones (an isolated tied sample gives an
        // octahedron 1/128 voxel across: area ~1e-3 mm² here).
        const auto meas = measure_surface(m);
        std::size_t tiny = 0;
        for (const auto& part : meas.components) tiny += part.area_mm2 < 0.01;
        std::printf("headsq iso %g: %zu components (%zu with area < 0.01 mm2)\n", iso, meas.components.size(), tiny);
        std::printf("headsq iso %g: %zu triangles, %zu vertices, area %.2f mm2, volume %.1f mm3, %zu ties, "
                    "edges used > 2 times %zu, interior edges not 2 %zu, non-manifold vertices %zu, zero-area %zu, "
                    "extract %.1f ms (median of 5); Flying Edges %zu triangles; %zu vertices on samples; margin moved "
                    "%zu of %zu vertices (%zu on tie edges), "
                    "max %.5f voxel along the edge, %.4f mm\n",
                    iso, m.triangles.size(), m.positions.size(), s.area, s.volume_mm3, ties, r.edges_over_two,
                    r.interior_edges_not_two, r.nonmanifold_vertices, r.zero_area, ms[2], fe_tris, on_sample, moved,
                    total, moved_ties, worst, worst_mm);
    }
}
