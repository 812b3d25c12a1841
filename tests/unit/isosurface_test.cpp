// Chunked marching cubes: agreement with vtkFlyingEdges3D, chunking
// invariance, watertightness, ties, degenerate inputs, incremental updates.
#include "renderer/surface/extract.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>

#include <glm/gtc/matrix_transform.hpp>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkMassProperties.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataAlgorithm.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkShortArray.h>

#include "tests/support/measure_phantoms.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::canonical;
using iso::test::plain_sums;
using iso::test::sample_field;

namespace {

// Distance field of a sphere (inside = larger values, as in CT): value = r - |p - c|.
Volume sphere(std::array<std::int64_t, 3> dims, const glm::dmat4& affine, glm::dvec3 c, double r) {
    return sample_field(dims, affine, [&](glm::dvec3 p) { return r - glm::length(p - c); });
}

// Runs vtkFlyingEdges3D in index space (origin 0, spacing 1) and maps its
// points through the affine ourselves, so any affine can be compared.
// Runs a configured VTK contour filter over `v` in index space (origin 0,
// spacing 1) and maps its points through the affine ourselves, so any affine
// can be compared; mirrored affines reverse the winding as ours do.
// With `margin`, each point is first moved along its edge as our extractor
// moves its vertices (renderer/surface/extract.hpp, kEdgeMargin: t clamped to
// [1/128, 1 - 1/128]); the edge's axis is the coordinate farthest from an
// integer (a point exactly on a sample, a tie, has no edge and stays put).
// `moved` counts the points moved.
Mesh run_in_index_space(vtkPolyDataAlgorithm& filter, vtkDataArray* scalars, const Volume& v, bool margin = false,
                        std::size_t* moved = nullptr) {
    vtkNew<vtkImageData> img;
    img->SetDimensions(int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
    img->GetPointData()->SetScalars(scalars);
    filter.SetInputData(img);
    filter.Update();
    vtkPolyData* pd = filter.GetOutput();
    Mesh m;
    for (vtkIdType i = 0; i < pd->GetNumberOfPoints(); ++i) {
        double p[3];
        pd->GetPoint(i, p);
        if (margin) {
            int axis = 0;
            double best = -1;
            for (int a = 0; a < 3; ++a) {
                const double d = std::abs(p[a] - std::round(p[a]));
                if (d > best) best = d, axis = a;
            }
            const double lo = std::floor(p[axis]), t = p[axis] - lo;
            if (t > 0 && (t < kEdgeMargin || t > 1 - kEdgeMargin)) {
                p[axis] = lo + std::clamp(t, kEdgeMargin, 1 - kEdgeMargin);
                if (moved) ++*moved;
            }
        }
        m.positions.emplace_back(glm::dvec3(v.index_to_lps * glm::dvec4(p[0], p[1], p[2], 1.0)));
    }
    const bool flip = glm::determinant(glm::dmat3(v.index_to_lps)) < 0;
    auto polys = pd->GetPolys();
    polys->InitTraversal();
    vtkIdType npts;
    const vtkIdType* ids;
    while (polys->GetNextCell(npts, ids)) {
        std::array<std::uint32_t, 3> t{std::uint32_t(ids[0]), std::uint32_t(ids[1]), std::uint32_t(ids[2])};
        if (flip) std::swap(t[1], t[2]);
        m.triangles.push_back(t);
    }
    return m;
}

Mesh flying_edges(const Volume& v, double iso, std::size_t* moved = nullptr) {
    vtkNew<vtkFloatArray> arr;
    arr->SetNumberOfTuples(v.voxel_count());
    for (std::int64_t n = 0; n < v.voxel_count(); ++n)
        arr->SetValue(n, float(v.value(n % v.dims[0], (n / v.dims[0]) % v.dims[1], n / (v.dims[0] * v.dims[1]))));
    vtkNew<vtkFlyingEdges3D> fe;
    fe->SetValue(0, iso);
    fe->ComputeNormalsOff();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    return run_in_index_space(*fe, arr, v, true, moved);
}

// Edges used by other than exactly two triangles in opposite directions
// (an edge used twice in each direction, a pinch, counts too).
std::size_t bad_edges(const Mesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    std::size_t bad = 0;
    for (const auto& [e, n] : directed) {
        auto it = directed.find({e.second, e.first});
        const int back = it == directed.end() ? 0 : it->second;
        if (n != 1 || back != 1) ++bad;
    }
    return bad;
}

std::size_t degenerate_triangles(const Mesh& m) {
    std::size_t n = 0;
    for (const auto& t : m.triangles) {
        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        if (glm::length(glm::cross(b - a, c - a)) == 0.0) ++n;
    }
    return n;
}

std::size_t duplicate_positions(const Mesh& m) {
    std::set<std::array<float, 3>> seen;
    std::size_t d = 0;
    for (const auto& p : m.positions)
        if (!seen.insert({p.x, p.y, p.z}).second) ++d;
    return d;
}

glm::dmat4 tilted_affine() {
    glm::dmat4 r = glm::rotate(glm::dmat4(1.0), glm::radians(30.0), glm::normalize(glm::dvec3(1, 2, 0.5)));
    return glm::translate(glm::dmat4(1.0), glm::dvec3(-40, 12, 300)) * r *
           glm::scale(glm::dmat4(1.0), glm::dvec3(0.7, 0.9, 2.5));
}

} // namespace

TEST(Isosurface, MatchesFlyingEdgesOnObliqueAnisotropicSphere) {
    const auto aff = tilted_affine();
    const glm::dvec3 c = glm::dvec3(aff * glm::dvec4(21.5, 17, 9, 1));
    const auto v = sphere({44, 37, 19}, aff, c, 14.3);
    const double iso = 0.123; // ties no sample (floats of a distance field)
    const Mesh ours = extract_isosurface(v, iso, {.chunk_size = 8});
    std::size_t moved = 0;
    const Mesh fe = flying_edges(v, iso, &moved);
    ASSERT_GT(fe.triangles.size(), 500u);
    // A few FE vertices lie within 1/128 of an edge's end; ours are moved there
    // by the edge margin, and so are FE's above.
    std::printf("FE vertices moved by the edge margin: %zu of %zu\n", moved, fe.positions.size());
    EXPECT_GT(moved, 0u) << "the comparison covers the edge margin";
    EXPECT_LT(moved, fe.positions.size() / 20);
    EXPECT_EQ(ours.triangles.size(), fe.triangles.size());
    EXPECT_EQ(ours.positions.size(), fe.positions.size());
    const auto a = plain_sums(ours), b = plain_sums(fe);
    EXPECT_NEAR(a.area, b.area, 1e-5 * b.area);
    EXPECT_NEAR(a.volume_mm3, b.volume_mm3, 1e-5 * b.volume_mm3);
    EXPECT_GT(a.volume_mm3, 0.0) << "triangles must face outward";
    // Same vertices: every one of ours has an FE vertex (moved by the edge
    // margin as ours are) within 1e-5 voxel.
    std::vector<std::array<float, 3>> fe_pos;
    for (auto p : fe.positions) fe_pos.push_back({p.x, p.y, p.z});
    std::sort(fe_pos.begin(), fe_pos.end());
    std::vector<std::array<float, 3>> our_pos;
    for (auto p : ours.positions) our_pos.push_back({p.x, p.y, p.z});
    std::sort(our_pos.begin(), our_pos.end());
    ASSERT_EQ(our_pos.size(), fe_pos.size());
    const double tol = 1e-5 * 0.7 + 1e-4; // 1e-5 voxel plus float rounding of world coordinates ~300 mm
    double worst = 0;
    for (std::size_t i = 0; i < our_pos.size(); ++i)
        for (int k = 0; k < 3; ++k) worst = std::max(worst, double(std::abs(our_pos[i][k] - fe_pos[i][k])));
    EXPECT_LT(worst, tol);
    EXPECT_EQ(bad_edges(ours), 0u);
}

// Single cells checked by hand: one 2x2x2 volume (one cell), spacing
// (0.5, 2, 3) mm and origin (10, -20, 5) in LPS, so index (i, j, k) is at
// (10 + 0.5 i, -20 + 2 j, 5 + 3 k). A sample is inside when it is >= iso
// (extract.cpp, IsoClassifier::inside; here no sample ties the iso value).
// A cut edge's vertex lies where the linear interpolation of its two
// samples reaches iso. Triangles face away from the inside samples.
namespace {

// values[i + 2 j + 4 k]
Volume one_cell(const std::array<float, 8>& values) {
    auto v = Volume::dense({2, 2, 2}, VoxelType::F32, make_affine({0.5, 2.0, 3.0}, {10.0, -20.0, 5.0}));
    for (int n = 0; n < 8; ++n) v.as<float>()[v.linear_index(n & 1, (n >> 1) & 1, n >> 2)] = values[std::size_t(n)];
    return v;
}

glm::dvec3 face_normal(const Mesh& m, const std::array<std::uint32_t, 3>& t) {
    const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
    return glm::cross(b - a, c - a);
}

// Index of the vertex at `p` (within 1e-5 mm), or -1.
int vertex_at(const Mesh& m, glm::dvec3 p) {
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        if (glm::length(glm::dvec3(m.positions[i]) - p) < 1e-5) return int(i);
    return -1;
}

} // namespace

TEST(Isosurface, OneInsideCornerGivesOneHandComputedTriangle) {
    // Corner (0,0,0) = 100 is inside at iso 40; its neighbours along i, j, k
    // are -20, 20 and -140, the other four corners 0. From the corner, the
    // vertex on each edge sits at t = (40 - 100) / (s1 - 100): 1/2 along i,
    // 3/4 along j, 1/4 along k.
    const Mesh m = extract_isosurface(one_cell({100, -20, 20, 0, -140, 0, 0, 0}), 40.0);
    ASSERT_EQ(m.triangles.size(), 1u);
    ASSERT_EQ(m.positions.size(), 3u);
    const glm::dvec3 corner(10, -20, 5);
    const glm::dvec3 on_i(10.25, -20, 5), on_j(10, -18.5, 5),
        on_k(10, -20, 5.75); // index (0.5,0,0), (0,0.75,0), (0,0,0.25)
    const int a = vertex_at(m, on_i), b = vertex_at(m, on_j), c = vertex_at(m, on_k);
    ASSERT_TRUE(a >= 0 && b >= 0 && c >= 0) << "vertices at the hand-computed positions";
    // Facing away from the corner: (on_j - on_i) x (on_k - on_i) = (1.125, 0.1875, 0.375),
    // which points from the corner to the triangle; so the winding is i, j, k (up to rotation).
    auto t = m.triangles[0];
    for (int r = 0; r < 3 && int(t[0]) != a; ++r) std::rotate(t.begin(), t.begin() + 1, t.end());
    EXPECT_EQ(int(t[1]), b);
    EXPECT_EQ(int(t[2]), c);
    const glm::dvec3 n = face_normal(m, m.triangles[0]);
    EXPECT_NEAR(n.x, 1.125, 1e-5);
    EXPECT_NEAR(n.y, 0.1875, 1e-5);
    EXPECT_NEAR(n.z, 0.375, 1e-5);
    EXPECT_GT(glm::dot(n, (on_i + on_j + on_k) / 3.0 - corner), 0.0);
    for (const auto& vn : m.normals) EXPECT_GT(glm::dot(glm::dvec3(vn), n), 0.0) << "gradient normals agree";
}

TEST(Isosurface, TwoAdjacentInsideCornersGiveAHandComputedQuad) {
    // Corners (0,0,0) and (1,0,0) = 100 inside at iso 40, the other six -20:
    // the four edges along j and k from them are cut at t = 1/2, a planar
    // 0.5 mm x sqrt(1 + 1.5^2) mm rectangle parallel to the inside edge.
    const Mesh m = extract_isosurface(one_cell({100, 100, -20, -20, -20, -20, -20, -20}), 40.0);
    ASSERT_EQ(m.triangles.size(), 2u);
    ASSERT_EQ(m.positions.size(), 4u);
    const glm::dvec3 quad[4] = {
        {10, -19, 5}, {10.5, -19, 5}, {10.5, -20, 6.5}, {10, -20, 6.5}}; // index (0,.5,0) (1,.5,0) (1,0,.5) (0,0,.5)
    for (const auto& p : quad) EXPECT_GE(vertex_at(m, p), 0) << p.x << " " << p.y << " " << p.z;
    // Both triangles face away from the inside edge (y = -20, z = 5): along
    // (0, 1.5, 1) / |(0, 1.5, 1)|, perpendicular to the rectangle.
    const glm::dvec3 outward = glm::normalize(glm::dvec3(0, 1.5, 1));
    double area = 0;
    for (const auto& t : m.triangles) {
        const glm::dvec3 n = face_normal(m, t);
        EXPECT_NEAR(glm::dot(glm::normalize(n), outward), 1.0, 1e-9);
        area += 0.5 * glm::length(n);
    }
    EXPECT_NEAR(area, 0.5 * std::sqrt(1 + 1.5 * 1.5), 1e-5) << "the two triangles cover the rectangle once";
    // They share one edge (a diagonal), traversed in opposite directions.
    std::set<std::pair<std::uint32_t, std::uint32_t>> first;
    for (int k = 0; k < 3; ++k) first.insert({m.triangles[0][k], m.triangles[0][(k + 1) % 3]});
    int shared = 0;
    for (int k = 0; k < 3; ++k) shared += first.count({m.triangles[1][(k + 1) % 3], m.triangles[1][k]}) ? 1 : 0;
    EXPECT_EQ(shared, 1);
    EXPECT_EQ(bad_edges(m), 4u) << "an open quad: its four sides are boundary edges";
}

TEST(Isosurface, ChunkingDoesNotChangeTheMesh) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    auto v = Volume::dense({23, 19, 17}, VoxelType::F32, tilted_affine());
    for (auto& x : v.as<float>()) x = u(rng); // noise: every MC case, many chunk borders crossed
    const auto ref = canonical(extract_isosurface(v, 0.5, {.chunk_size = 1000}));
    ASSERT_GT(ref.size(), 1000u);
    for (int c : {2, 3, 5, 8, 16}) {
        const Mesh m = extract_isosurface(v, 0.5, {.chunk_size = c, .threads = 2});
        EXPECT_EQ(canonical(m), ref) << "chunk size " << c;
        EXPECT_EQ(duplicate_positions(m), 0u) << "chunk size " << c;
    }
}

TEST(Isosurface, NoiseSurfaceIsClosedInsideTheVolume) {
    // Random values inside, a border of zeros: every component is closed.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    auto v = Volume::dense({20, 21, 22}, VoxelType::F32, glm::dmat4(1.0));
    for (std::int64_t k = 1; k < 21; ++k)
        for (std::int64_t j = 1; j < 20; ++j)
            for (std::int64_t i = 1; i < 19; ++i) v.as<float>()[v.linear_index(i, j, k)] = u(rng);
    const Mesh m = extract_isosurface(v, 0.5, {.chunk_size = 4});
    EXPECT_EQ(bad_edges(m), 0u);
    EXPECT_EQ(degenerate_triangles(m), 0u);
}

TEST(Isosurface, TiesGiveNoDuplicatesNoDegeneratesNoCracks) {
    // Integer samples 0..3 and iso values equal to them.
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> u(0, 3);
    auto v = Volume::dense({18, 16, 15}, VoxelType::I16, glm::dmat4(1.0));
    for (std::int64_t k = 1; k < 14; ++k)
        for (std::int64_t j = 1; j < 15; ++j)
            for (std::int64_t i = 1; i < 17; ++i) v.as<std::int16_t>()[v.linear_index(i, j, k)] = std::int16_t(u(rng));
    for (double iso : {1.0, 2.0, 3.0}) {
        for (int c : {3, 64}) {
            const Mesh m = extract_isosurface(v, iso, {.chunk_size = c});
            ASSERT_FALSE(m.triangles.empty());
            EXPECT_EQ(degenerate_triangles(m), 0u) << "iso " << iso;
            EXPECT_EQ(duplicate_positions(m), 0u) << "iso " << iso;
            EXPECT_EQ(bad_edges(m), 0u) << "iso " << iso << " chunk " << c;
            for (auto& n : m.normals) EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
        }
    }
}

TEST(Isosurface, ConstantSingleSliceAndOutOfRangeAreEmpty) {
    auto c = Volume::dense({8, 8, 8}, VoxelType::I16, glm::dmat4(1.0));
    for (auto& x : c.as<std::int16_t>()) x = 100;
    EXPECT_TRUE(extract_isosurface(c, 50, {}).empty());
    EXPECT_TRUE(extract_isosurface(c, 150, {}).empty());
    EXPECT_TRUE(extract_isosurface(c, 100, {}).empty()); // every sample inside: no surface
    auto slice = Volume::dense({8, 8, 1}, VoxelType::F32, glm::dmat4(1.0));
    slice.as<float>()[slice.linear_index(3, 3, 0)] = 1.f;
    EXPECT_TRUE(extract_isosurface(slice, 0.5, {}).empty());
}

TEST(Isosurface, OneVoxelThickSheetIsClosed) {
    auto v = Volume::dense({10, 10, 10}, VoxelType::U8, glm::dmat4(1.0));
    for (std::int64_t k = 2; k < 8; ++k)
        for (std::int64_t j = 2; j < 8; ++j) v.as<std::uint8_t>()[v.linear_index(5, j, k)] = 200;
    const Mesh m = extract_isosurface(v, 100, {.chunk_size = 5});
    EXPECT_GT(m.triangles.size(), 50u);
    EXPECT_EQ(bad_edges(m), 0u);
    EXPECT_GT(plain_sums(m).volume_mm3, 0.0);
}

TEST(Isosurface, NaNSamplesAreOutside) {
    auto v = sphere({16, 16, 16}, glm::dmat4(1.0), {7.5, 7.5, 7.5}, 5.0);
    const Mesh ref = extract_isosurface(v, 0.0, {});
    // NaN everywhere outside the sphere: same surface.
    for (auto& x : v.as<float>())
        if (x < -1.5f) x = std::nanf("");
    const Mesh m = extract_isosurface(v, 0.0, {.chunk_size = 4});
    EXPECT_EQ(m.triangles.size(), ref.triangles.size());
    for (auto& p : m.positions) EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    EXPECT_NEAR(plain_sums(m).area, plain_sums(ref).area, 1e-9 * plain_sums(ref).area);
}

TEST(Isosurface, MirroredAffineStillFacesOutward) {
    const auto aff = glm::scale(glm::dmat4(1.0), glm::dvec3(-1.0, 1.0, 1.0)); // NIfTI-style flip
    const auto v = sphere({16, 16, 16}, aff, {-7.5, 7.5, 7.5}, 5.0);
    const Mesh m = extract_isosurface(v, 0.0, {});
    EXPECT_NEAR(plain_sums(m).volume_mm3, 4.0 / 3.0 * M_PI * 125.0, 0.03 * 4.0 / 3.0 * M_PI * 125.0);
}

TEST(Isosurface, NormalsAreWorldSpaceForAnisotropicRotatedGrids) {
    const auto aff = tilted_affine();
    const glm::dvec3 c = glm::dvec3(aff * glm::dvec4(21.5, 17, 9, 1));
    const auto v = sphere({44, 37, 19}, aff, c, 14.3);
    const Mesh m = extract_isosurface(v, 0.0, {});
    ASSERT_EQ(m.normals.size(), m.positions.size());
    double worst = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const glm::dvec3 radial = glm::normalize(glm::dvec3(m.positions[i]) - c);
        worst = std::max(worst, std::acos(std::clamp(glm::dot(radial, glm::dvec3(m.normals[i])), -1.0, 1.0)));
    }
    // Central differences on a 2.5 mm x 0.7 mm grid: a few degrees at most.
    EXPECT_LT(worst * 180.0 / M_PI, 6.0);
}

TEST(Isosurface, IncrementalEqualsFull) {
    auto v = sphere({40, 36, 30}, tilted_affine(), glm::dvec3(tilted_affine() * glm::dvec4(20, 18, 15, 1)), 12.0);
    Extractor x(v, {.chunk_size = 8});
    auto surf = x.extract(0.0);
    // Edit: a box set to a high value (a "paint" stroke) crossing chunk borders.
    IndexBox box{{5, 6, 7}, {13, 17, 9}};
    for (auto k = box.lo[2]; k <= box.hi[2]; ++k)
        for (auto j = box.lo[1]; j <= box.hi[1]; ++j)
            for (auto i = box.lo[0]; i <= box.hi[0]; ++i) v.as<float>()[v.linear_index(i, j, k)] = 5.0f;
    std::span<ChunkedSurface> one(&surf, 1);
    const auto redone = x.update(box, one);
    EXPECT_LT(redone.size(), x.index().chunk_count());
    EXPECT_EQ(canonical(weld(surf)), canonical(extract_isosurface(v, 0.0, {.chunk_size = 8})));
}

TEST(Isosurface, SeveralIsoValuesInOnePass) {
    const auto v = sphere({24, 24, 24}, glm::dmat4(1.0), {11.5, 11.5, 11.5}, 9.0);
    const double isos[] = {0.0, 3.0};
    const auto meshes = extract_isosurfaces(v, isos, {.chunk_size = 6});
    ASSERT_EQ(meshes.size(), 2u);
    EXPECT_EQ(canonical(meshes[0]), canonical(extract_isosurface(v, 0.0, {})));
    EXPECT_EQ(canonical(meshes[1]), canonical(extract_isosurface(v, 3.0, {})));
    EXPECT_GT(plain_sums(meshes[0]).volume_mm3, plain_sums(meshes[1]).volume_mm3);
}

TEST(Isosurface, CancelStops) {
    const auto v = sphere({64, 64, 64}, glm::dmat4(1.0), {31.5, 31.5, 31.5}, 25.0);
    ExtractOptions opt;
    opt.chunk_size = 4;
    opt.progress = [](double, std::string_view) { return false; };
    EXPECT_THROW(extract_isosurface(v, 0.0, opt), Cancelled);
}

namespace {
// Runs vtkDiscreteFlyingEdges3D for one label, in index space mapped through the affine.
Mesh discrete_flying_edges(const Volume& v, double label);
} // namespace

#include <vtkDiscreteFlyingEdges3D.h>

namespace {
Mesh discrete_flying_edges(const Volume& v, double label) {
    vtkNew<vtkShortArray> arr;
    arr->SetNumberOfTuples(v.voxel_count());
    for (std::int64_t n = 0; n < v.voxel_count(); ++n) arr->SetValue(n, v.as<std::int16_t>()[std::size_t(n)]);
    vtkNew<vtkDiscreteFlyingEdges3D> fe;
    fe->SetValue(0, label);
    fe->ComputeNormalsOff();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    return run_in_index_space(*fe, arr, v);
}
} // namespace

TEST(Isosurface, LabelMapOneSurfacePerLabelInOnePass) {
    // Three touching boxes with labels 1, 2, 5 in a background of 0.
    auto v = Volume::dense({20, 18, 16}, VoxelType::I16, glm::dmat4(1.0));
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 2; k < 14; ++k)
        for (std::int64_t j = 2; j < 16; ++j)
            for (std::int64_t i = 2; i < 18; ++i) s[v.linear_index(i, j, k)] = i < 8 ? 1 : (i < 13 ? 2 : 5);
    EXPECT_EQ(distinct_labels(v), (std::vector<double>{1, 2, 5}));
    const auto surfaces = extract_labels(v, {}, {.chunk_size = 5});
    ASSERT_EQ(surfaces.size(), 3u);
    for (const auto& ls : surfaces) {
        const Mesh fe = discrete_flying_edges(v, ls.label);
        EXPECT_EQ(ls.mesh.triangles.size(), fe.triangles.size()) << "label " << ls.label;
        EXPECT_EQ(bad_edges(ls.mesh), 0u) << "label " << ls.label;
        EXPECT_NEAR(plain_sums(ls.mesh).area, plain_sums(fe).area, 1e-9 * plain_sums(fe).area) << "label " << ls.label;
        EXPECT_GT(plain_sums(ls.mesh).volume_mm3, 0.0) << "label " << ls.label;
    }
    // Label 2 spans 5 x 14 x 12 samples. With vertices at edge midpoints the
    // surface is that box (faces half a sample out) with every edge chamfered
    // by a right prism of cross-section 1/8 and each corner giving back 1/12:
    // V = 5*14*12 - (4*(5+14+12))/8 + 8/12.
    EXPECT_NEAR(plain_sums(surfaces[1].mesh).volume_mm3, 5.0 * 14.0 * 12.0 - 4.0 * (5 + 14 + 12) / 8.0 + 8.0 / 12.0,
                1e-9);
}

#include "renderer/surface/postprocess.hpp"

TEST(Postprocess, SmoothDecimateKeepLargest) {
    // Two spheres of different sizes.
    auto v = sample_field({48, 32, 32}, glm::dmat4(1.0), [](glm::dvec3 p) {
        return std::max(10.0 - glm::length(p - glm::dvec3(15, 15.5, 15.5)),
                        5.0 - glm::length(p - glm::dvec3(38, 15.5, 15.5)));
    });
    const Mesh m = extract_isosurface(v, 0.0, {});
    const auto base = plain_sums(m);

    const Mesh largest = postprocess(m, {.keep_largest = true});
    EXPECT_LT(largest.triangles.size(), m.triangles.size());
    EXPECT_NEAR(plain_sums(largest).volume_mm3, 4.0 / 3.0 * M_PI * 1000.0, 0.02 * 4.0 / 3.0 * M_PI * 1000.0);
    EXPECT_EQ(bad_edges(largest), 0u);

    const Mesh dec = postprocess(m, {.decimate = 0.75});
    EXPECT_LT(dec.triangles.size(), m.triangles.size() * 0.3);
    EXPECT_NEAR(plain_sums(dec).volume_mm3, base.volume_mm3, 0.03 * base.volume_mm3);
    EXPECT_GT(plain_sums(dec).volume_mm3, 0.0) << "orientation kept";

    const Mesh smooth = postprocess(m, {.smooth = 0.5});
    EXPECT_EQ(smooth.triangles.size(), m.triangles.size());
    EXPECT_EQ(smooth.normals.size(), smooth.positions.size());
    EXPECT_NEAR(plain_sums(smooth).volume_mm3, base.volume_mm3, 0.03 * base.volume_mm3);
    EXPECT_LT(plain_sums(smooth).area, base.area) << "smoothing removes the staircase";

    EXPECT_THROW(postprocess(m, {.smooth = 2.0}), Error);
    EXPECT_THROW(postprocess(m, {.decimate = 1.0}), Error);
    EXPECT_TRUE(postprocess(Mesh{}, {.smooth = 0.5}).empty());
}

TEST(Isosurface, TinyMemoryBudgetStillExtractsTheSameMesh) {
    const auto v = sphere({40, 40, 40}, glm::dmat4(1.0), {19.5, 19.5, 19.5}, 15.0);
    const auto ref = canonical(extract_isosurface(v, 0.0, {.chunk_size = 32}));
    ExtractOptions opt;
    opt.chunk_size = 32;
    opt.threads = 2;
    opt.memory_budget = 100 << 10; // far below two threads' scratch at 32^3
    Extractor x(v, opt);
    EXPECT_LT(x.options().chunk_size, 32);
    EXPECT_EQ(x.options().threads, 1);
    ExtractStats st;
    const Mesh m = weld(x.extract(0.0, &st));
    EXPECT_LE(st.peak_scratch_bytes, opt.memory_budget);
    EXPECT_EQ(canonical(m), ref);
}
