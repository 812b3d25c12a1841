// Measurements (renderer/surface/analysis.hpp): points, values at points, and the
// area, volume, topology and components of surfaces. Expected answers are
// analytic (balls, slabs, cubes, a tetrahedron, a linear field) or computed
// here independently (trilinear weights written out, triangle sums in a
// plain loop); the phantoms are sampled on an oblique, anisotropic grid
// (tests/unit/measure_phantoms.hpp: 0.7 x 1.0 x 1.3 mm, rotated 25 degrees).
#include "renderer/surface/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <openvdb/openvdb.h>

#include "io/error.hpp"
#include "io/sparse.hpp"
#include "renderer/surface/extract.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using namespace iso::test;

namespace {

double ball_area(double r) { return 4.0 * std::numbers::pi * r * r; }
double ball_ml(double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r / 1000.0; }
// Volume of the part of a ball of radius r beyond a plane at distance d from its centre (a cap).
double cap_ml(double r, double d) {
    const double h = r - d;
    return std::numbers::pi * h * h * (3.0 * r - h) / 3.0 / 1000.0;
}

// An axis-aligned box [lo, hi] as 8 vertices and 12 outward triangles.
Mesh box(glm::dvec3 lo, glm::dvec3 hi) { return test::box_mesh(lo, hi); }

// The same triangles with three vertices of their own each (an STL soup).
Mesh soup(const Mesh& m) {
    Mesh s;
    for (const auto& t : m.triangles) {
        const auto n = std::uint32_t(s.positions.size());
        for (int k = 0; k < 3; ++k) s.positions.push_back(m.positions[t[k]]);
        s.triangles.push_back({n, n + 1, n + 2});
    }
    return s;
}

Mesh merged(const Mesh& a, const Mesh& b) {
    Mesh m = a;
    const auto n = std::uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    for (auto t : b.triangles) m.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
    return m;
}

// The nearest intersection of the line p + s d (s in R) with the mesh on
// either side of p (Moller-Trumbore), as the picking code would find it.
struct Hit {
    double s;
    glm::dvec3 p;
};
std::vector<Hit> line_hits(const Mesh& m, glm::dvec3 p, glm::dvec3 d) {
    std::vector<Hit> hits;
    for (const auto& t : m.triangles) {
        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        const glm::dvec3 e1 = b - a, e2 = c - a, q = glm::cross(d, e2);
        const double det = glm::dot(e1, q);
        if (std::abs(det) < 1e-12) continue;
        const glm::dvec3 o = p - a;
        const double u = glm::dot(o, q) / det;
        const glm::dvec3 r = glm::cross(o, e1);
        const double v = glm::dot(d, r) / det;
        if (u < 0 || v < 0 || u + v > 1) continue;
        const double s = glm::dot(e2, r) / det;
        hits.push_back({s, p + s * d});
    }
    std::sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) { return x.s < y.s; });
    return hits;
}

// A ball phantom: CT-like edge (blur sigma = 0.6 mean voxel), centre moved
// off the grid by `offset` voxels; `margin` mm of background around it.
struct BallCase {
    Volume v;
    glm::dvec3 c{0.0};
};
BallCase ball_case(double scale, double r, glm::dvec3 offset, double sigma_voxels = 0.6) {
    const auto dims = dims_for(r, 3.0 * scale + 2.0, scale);
    const glm::dvec3 centre(-30.0, 45.0, 120.0);
    const glm::dmat4 aff = oblique_affine(dims, scale, centre);
    BallCase b;
    b.c = centre + glm::dmat3(aff) * offset;
    const glm::dvec3 sp = phantom_spacing(scale);
    b.v = ct_ball(dims, aff, b.c, r, sigma_voxels * (sp.x + sp.y + sp.z) / 3.0);
    return b;
}

double rel(double x, double truth) { return (x - truth) / truth; }

} // namespace

// ---- points ----------------------------------------------------------------------------

TEST(MeasurePoints, DistanceAndItsErrors) {
    EXPECT_DOUBLE_EQ(distance_mm({1, 2, 3}, {4, 6, 3}), 5.0);
    EXPECT_DOUBLE_EQ(distance_mm({-30, 45, 120}, {-30, 45, 120}), 0.0);
    EXPECT_THROW(distance_mm({std::nan(""), 0, 0}, {0, 0, 0}), Error);
    EXPECT_THROW(distance_mm({0, 0, 0}, {0, INFINITY, 0}), Error);
}

TEST(MeasurePoints, DistanceBetweenPointsPickedOnTwoParallelSlabs) {
    // Two slabs 5 mm thick, 7 mm apart, their normal oblique to the grid:
    // the field is a piecewise linear ramp of the signed distance, linear
    // across every cell the surface crosses, so marching cubes places the
    // slab faces exactly (to float rounding).
    const double scale = 1.0;
    const std::array<std::int64_t, 3> dims{48, 36, 30};
    const glm::dvec3 centre(10.0, -20.0, 80.0);
    const glm::dmat4 aff = oblique_affine(dims, scale, centre);
    const glm::dvec3 n = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
    const glm::dvec3 o = centre - 8.5 * n; // d = 0 on the first slab's near face
    const Volume v = sample_field(dims, aff, [&](const glm::dvec3& p) {
        const double d = glm::dot(p - o, n);
        return 100.0 * std::max(std::min(d, 5.0 - d), std::min(d - 12.0, 17.0 - d));
    });
    const Mesh m = extract_isosurface(v, 0.0);
    // Picked points: where a line through the gap along the normal, at a few
    // places across the slabs, meets the two facing surfaces.
    const glm::dvec3 side = glm::normalize(glm::cross(n, glm::dvec3(1, 0, 0)));
    const glm::dvec3 side2 = glm::cross(n, side);
    for (const glm::dvec3& shift : {glm::dvec3(0.0), 3.3 * side, -4.1 * side + 2.2 * side2}) {
        const glm::dvec3 mid = centre + shift; // d = 8.5: inside the gap
        auto hits = line_hits(m, mid, n);
        const auto below = std::find_if(hits.rbegin(), hits.rend(), [](const Hit& h) { return h.s < 0; });
        const auto above = std::find_if(hits.begin(), hits.end(), [](const Hit& h) { return h.s > 0; });
        ASSERT_TRUE(below != hits.rend() && above != hits.end());
        EXPECT_NEAR(distance_mm(below->p, above->p), 7.0, 1e-4);
        // And to the far faces of both slabs: 5 + 7 + 5 mm.
        EXPECT_NEAR(distance_mm(hits.front().p, hits.back().p), 17.0, 1e-4);
    }
    // The surface itself: four parallel sheets (two faces per slab), each
    // cut by the volume's border, open.
    const auto s = measure_surface(m);
    EXPECT_EQ(s.components.size(), 4u);
    for (const auto& c : s.components) EXPECT_EQ(c.boundary_loops, 1u);
    EXPECT_FALSE(s.closed);
    EXPECT_EQ(s.volume_kind, VolumeKind::LowerBound);
}

TEST(MeasurePoints, KnownAngles) {
    // Two rays from a vertex in an oblique plane, at known angles.
    const glm::dvec3 vtx(-30.0, 45.0, 120.0);
    const glm::dmat3 rot = phantom_rotation();
    const glm::dvec3 e1 = rot[0], e2 = rot[1];
    for (double deg : {90.0, 30.0, 1e-3, 45.0, 120.0, 179.999, 180.0, 0.0}) {
        const double t = glm::radians(deg);
        const glm::dvec3 a = vtx + 12.5 * e1, c = vtx + 3.0 * (std::cos(t) * e1 + std::sin(t) * e2);
        EXPECT_NEAR(angle_deg(a, vtx, c), deg, 1e-9) << deg;
        EXPECT_NEAR(angle_deg(c, vtx, a), deg, 1e-9) << "symmetric";
    }
    // A right angle from points picked on the two faces and the edge of the box [0,4]^3 (x = 4 face, y = 4 face).
    EXPECT_NEAR(angle_deg({4, 1, 2}, {4, 4, 2}, {1, 4, 2}), 90.0, 1e-12);
}

TEST(MeasurePoints, DegenerateAngleIsAClearError) {
    const glm::dvec3 v(1, 2, 3);
    try {
        angle_deg(v, v, {4, 5, 6});
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), "angle");
        EXPECT_NE(e.reason().find("coincides with the vertex"), std::string::npos) << e.reason();
    }
    EXPECT_THROW(angle_deg({4, 5, 6}, v, v + glm::dvec3(1e-12, 0, 0)), Error);
    EXPECT_THROW(angle_deg({4, 5, 6}, v, {NAN, 0, 0}), Error);
    // Nearly coincident but not: still an answer.
    EXPECT_NEAR(angle_deg(v + glm::dvec3(1e-6, 0, 0), v, v + glm::dvec3(0, 1e-6, 0)), 90.0, 1e-9);
}

namespace {

// Random int16 "HU" on the oblique grid.
Volume random_hu(std::array<std::int64_t, 3> dims) {
    auto v = Volume::dense(dims, VoxelType::I16, oblique_affine(dims, 1.0, {5.0, -7.0, 60.0}));
    std::mt19937 rng(99);
    std::uniform_int_distribution<int> hu(-1000, 2000);
    for (auto& s : v.as<std::int16_t>()) s = std::int16_t(hu(rng));
    return v;
}

// Trilinear interpolation written out as the eight weighted corners.
double trilinear_by_hand(const Volume& v, glm::dvec3 x) {
    const std::int64_t i = std::int64_t(std::floor(x.x)), j = std::int64_t(std::floor(x.y)),
                       k = std::int64_t(std::floor(x.z));
    const double fx = x.x - double(i), fy = x.y - double(j), fz = x.z - double(k);
    double sum = 0;
    for (int c = 0; c < 8; ++c) {
        const int di = c & 1, dj = (c >> 1) & 1, dk = c >> 2;
        const double w = (di ? fx : 1 - fx) * (dj ? fy : 1 - fy) * (dk ? fz : 1 - fz);
        if (w != 0) sum += w * v.value(i + di, j + dj, k + dk);
    }
    return sum;
}

} // namespace

TEST(MeasureValue, TrilinearAtObliquePointsMatchesTheWeightsByHand) {
    const Volume v = random_hu({9, 8, 7});
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int n = 0; n < 200; ++n) {
        const glm::dvec3 x(u(rng) * 8.0, u(rng) * 7.0, u(rng) * 6.0); // inside the voxel centres' hull
        const glm::dvec3 p = v.index_to_world(x);
        const auto s = sample_volume(v, p);
        ASSERT_TRUE(s);
        EXPECT_NEAR(s->value, trilinear_by_hand(v, x), 1e-9);
        EXPECT_NEAR(glm::length(s->index - x), 0.0, 1e-9);
        EXPECT_FALSE(s->clamped);
        // The nearest voxel: its centre is the nearest of all centres.
        const std::array<std::int64_t, 3> want{std::llround(x.x), std::llround(x.y), std::llround(x.z)};
        EXPECT_EQ(s->voxel, want);
        EXPECT_NEAR(glm::length(s->voxel_lps - v.index_to_world(glm::dvec3(want[0], want[1], want[2]))), 0.0, 1e-9);
        EXPECT_EQ(s->voxel_value, v.value(want[0], want[1], want[2]));
    }
    // At a voxel centre: that voxel's value exactly.
    const auto c = sample_volume(v, v.index_to_world({3, 4, 5}));
    ASSERT_TRUE(c);
    EXPECT_DOUBLE_EQ(c->value, v.value(3, 4, 5));
}

TEST(MeasureValue, LinearFieldIsReproducedExactlyInLps) {
    // Trilinear interpolation reproduces any linear function of position:
    // checked in LPS, independent of how the code maps LPS to an index.
    const std::array<std::int64_t, 3> dims{12, 10, 8};
    const glm::dmat4 aff = oblique_affine(dims, 1.0, {5.0, -7.0, 60.0});
    auto hu = [](const glm::dvec3& p) { return 3.0 * p.x - 2.0 * p.y + 0.5 * p.z + 7.0; };
    const Volume v = sample_field(dims, aff, hu); // float32 samples
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int n = 0; n < 100; ++n) {
        const glm::dvec3 p = v.index_to_world({u(rng) * 11.0, u(rng) * 9.0, u(rng) * 7.0});
        const auto s = sample_volume(v, p);
        ASSERT_TRUE(s);
        EXPECT_NEAR(s->value, hu(p), 1e-4); // float32 samples of values ~100
    }
}

TEST(MeasureValue, OutsideTheGridIsNoValueAndTheOuterHalfVoxelIsClamped) {
    const Volume v = random_hu({6, 5, 4});
    // Beyond the voxels' extent ([-0.5, n - 0.5] in index): nothing.
    for (const glm::dvec3& x : {glm::dvec3(-0.51, 2, 2), glm::dvec3(5.51, 2, 2), glm::dvec3(2, -3, 2),
                                glm::dvec3(2, 2, 3.6), glm::dvec3(1e6, 0, 0)})
        EXPECT_FALSE(sample_volume(v, v.index_to_world(x))) << x.x << " " << x.y << " " << x.z;
    // In the outer half voxel: clamped to the border samples.
    const auto s = sample_volume(v, v.index_to_world({-0.4, 2.4, 3.3}));
    ASSERT_TRUE(s);
    EXPECT_TRUE(s->clamped);
    EXPECT_NEAR(s->value, trilinear_by_hand(v, {0.0, 2.4, 3.0}), 1e-9);
    EXPECT_EQ(s->voxel, (std::array<std::int64_t, 3>{0, 2, 3}));
    // Non-finite points are an error, not "outside".
    EXPECT_THROW(sample_volume(v, {NAN, 0, 0}), Error);
    // An empty volume has no value anywhere.
    EXPECT_FALSE(sample_volume(Volume{}, {0, 0, 0}));
}

TEST(MeasureValue, NaNSpreadsOnlyWhereItHasWeight) {
    auto v = Volume::dense({3, 3, 3}, VoxelType::F32, oblique_affine({3, 3, 3}, 1.0, {0, 0, 0}));
    for (auto& s : v.as<float>()) s = 10.0f;
    v.as<float>()[v.linear_index(2, 1, 1)] = NAN;
    EXPECT_DOUBLE_EQ(sample_volume(v, v.index_to_world({1, 1, 1}))->value, 10.0);
    EXPECT_DOUBLE_EQ(sample_volume(v, v.index_to_world({1.0, 0.5, 1.0}))->value, 10.0);
    EXPECT_TRUE(std::isnan(sample_volume(v, v.index_to_world({1.5, 1.0, 1.0}))->value));
}

TEST(MeasureValue, SparseVolumesAnswerAsDense) {
    const Volume dense = random_hu({7, 6, 5});
    auto grid = openvdb::FloatGrid::create(-1000.0f);
    auto acc = grid->getAccessor();
    const openvdb::Coord offset(100, -50, 7); // our index (0,0,0) is the grid's `offset`
    for (int k = 0; k < 5; ++k)
        for (int j = 0; j < 6; ++j)
            for (int i = 0; i < 7; ++i) acc.setValue(openvdb::Coord(i, j, k) + offset, float(dense.value(i, j, k)));
    auto sg = std::make_shared<SparseGrid>();
    sg->grid = grid;
    sg->offset = offset;
    const Volume sparse = Volume::sparse(sg, dense.dims, dense.index_to_lps);
    ASSERT_TRUE(sparse.is_sparse());
    for (const glm::dvec3& x :
         {glm::dvec3(0.3, 4.9, 2.2), glm::dvec3(6, 5, 4), glm::dvec3(-0.3, 0, 0), glm::dvec3(3.5, 2.5, 1.5)}) {
        const auto a = sample_volume(dense, dense.index_to_world(x)),
                   b = sample_volume(sparse, sparse.index_to_world(x));
        ASSERT_TRUE(a && b);
        EXPECT_NEAR(a->value, b->value, 1e-9);
        EXPECT_EQ(a->voxel, b->voxel);
    }
    EXPECT_FALSE(sample_volume(sparse, sparse.index_to_world({7.6, 0, 0})));
}

// ---- surfaces with exact answers ---------------------------------------------------------

TEST(MeasureSurface, TetrahedronFarFromTheOriginIsExact) {
    // Corner at (1000, -2000, 1500) mm: the volume is summed relative to the
    // bounding box's centre, so no digits are lost to the coordinates.
    const double a = 3.0, b = 4.0, c = 5.0;
    const glm::vec3 o(1000.0f, -2000.0f, 1500.0f);
    Mesh m;
    m.positions = {o, o + glm::vec3(a, 0, 0), o + glm::vec3(0, b, 0), o + glm::vec3(0, 0, c)};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    const auto s = measure_surface(m);
    const double area = (a * b + b * c + a * c) / 2.0 + 0.5 * std::sqrt(a * a * b * b + b * b * c * c + c * c * a * a);
    EXPECT_NEAR(s.area_mm2, area, 1e-12 * area);
    EXPECT_NEAR(s.volume_ml, a * b * c / 6.0 / 1000.0, 1e-15);
    EXPECT_EQ(s.volume_kind, VolumeKind::Enclosed);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.vertices, 4u);
    EXPECT_EQ(s.boundary_edges + s.non_manifold_edges + s.misoriented_edges + s.degenerate_triangles, 0u);
    ASSERT_EQ(s.components.size(), 1u);
    EXPECT_EQ(s.bounds_min, glm::dvec3(o));
    EXPECT_EQ(s.bounds_max, glm::dvec3(o) + glm::dvec3(a, b, c));
    EXPECT_TRUE(std::isnan(s.area_uncertainty_mm2)) << "no uncertainty without a volume";
    EXPECT_TRUE(s.warnings.empty());
}

TEST(MeasureSurface, CubeIndexedOrAsTriangleSoup) {
    const Mesh cube = box({-1, 2, 10}, {1, 4, 12}); // side 2: area 24 mm^2, volume 8 mm^3
    for (const Mesh& m : {cube, soup(cube)}) {
        const auto s = measure_surface(m);
        EXPECT_DOUBLE_EQ(s.area_mm2, 24.0);
        EXPECT_NEAR(s.volume_ml, 0.008, 1e-15);
        EXPECT_TRUE(s.closed);
        EXPECT_EQ(s.vertices, 8u) << "welded by position";
        EXPECT_EQ(s.components.size(), 1u);
        EXPECT_EQ(s.boundary_edges, 0u);
    }
    // Inside out: a negative enclosed volume (a cavity's orientation).
    Mesh inv = cube;
    for (auto& t : inv.triangles) std::swap(t[1], t[2]);
    const auto s = measure_surface(inv);
    EXPECT_NEAR(s.volume_ml, -0.008, 1e-15);
    EXPECT_EQ(s.volume_kind, VolumeKind::Enclosed);
}

TEST(MeasureSurface, OpenBoxIsALowerBoundWithItsBoundaryLoop) {
    Mesh m = box({0, 0, 0}, {2, 3, 4});
    // Remove the top face (z = 4: vertices 4..7 = {4,5,7,6}).
    m.triangles.erase(m.triangles.begin() + 2, m.triangles.begin() + 4);
    const auto s = measure_surface(m);
    EXPECT_FALSE(s.closed);
    EXPECT_EQ(s.volume_kind, VolumeKind::LowerBound);
    EXPECT_EQ(s.boundary_edges, 4u);
    EXPECT_EQ(s.boundary_loops, 1u);
    EXPECT_DOUBLE_EQ(s.boundary_length_mm, 10.0);
    // The planar loop capped by a fan: exactly the box.
    EXPECT_NEAR(s.volume_ml, 0.024, 1e-15);
    EXPECT_DOUBLE_EQ(s.area_mm2, 2 * (6 + 8 + 12) - 6.0);
    ASSERT_EQ(s.components.size(), 1u);
    EXPECT_FALSE(s.components[0].closed);
    EXPECT_EQ(s.components[0].boundary_loops, 1u);
    ASSERT_FALSE(s.warnings.empty());
    EXPECT_NE(s.warnings[0].find("lower bound"), std::string::npos);
    // A single triangle: open, one loop, its cap is itself: volume 0.
    Mesh tri;
    tri.positions = {{0, 0, 0}, {3, 0, 0}, {0, 4, 0}};
    tri.triangles = {{0, 1, 2}};
    const auto t = measure_surface(tri);
    EXPECT_DOUBLE_EQ(t.area_mm2, 6.0);
    EXPECT_DOUBLE_EQ(t.boundary_length_mm, 12.0);
    EXPECT_EQ(t.boundary_loops, 1u);
    EXPECT_EQ(t.volume_ml, 0.0);
}

TEST(MeasureSurface, FlippedTriangleMakesTheVolumeUndefined) {
    Mesh m = box({0, 0, 0}, {1, 1, 1});
    std::swap(m.triangles[5][1], m.triangles[5][2]);
    const auto s = measure_surface(m);
    EXPECT_EQ(s.misoriented_edges, 3u);
    EXPECT_EQ(s.volume_kind, VolumeKind::Undefined);
    EXPECT_TRUE(std::isnan(s.volume_ml));
    EXPECT_TRUE(s.closed) << "no holes, only orientation";
    EXPECT_DOUBLE_EQ(s.area_mm2, 6.0);
    ASSERT_FALSE(s.warnings.empty());
    EXPECT_NE(s.warnings[0].find("not consistently oriented"), std::string::npos);
}

TEST(MeasureSurface, TwoCubesSharingAnEdgeAreClosedButNonManifold) {
    const Mesh m = merged(box({0, 0, 0}, {1, 1, 1}), box({1, 1, 0}, {2, 2, 1}));
    const auto s = measure_surface(m);
    EXPECT_EQ(s.non_manifold_edges, 1u);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.volume_kind, VolumeKind::Enclosed);
    EXPECT_NEAR(s.volume_ml, 0.002, 1e-15);
    EXPECT_EQ(s.components.size(), 1u) << "connected through the shared vertices";
    EXPECT_EQ(s.vertices, 14u);
}

TEST(MeasureSurface, DegenerateTrianglesGiveNoNaN) {
    Mesh m = box({0, 0, 0}, {1, 1, 1});
    // A triangle naming one vertex twice, one with three vertices at one
    // position (distinct indices), one with three collinear vertices.
    m.triangles.push_back({0, 0, 7});
    const auto n = std::uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(),
                       {glm::vec3(0.5f, 0.5f, 0.5f), glm::vec3(0.5f, 0.5f, 0.5f), glm::vec3(0.5f, 0.5f, 0.5f)});
    m.triangles.push_back({n, n + 1, n + 2});
    m.positions.insert(m.positions.end(), {glm::vec3(5, 5, 5), glm::vec3(6, 6, 6), glm::vec3(7, 7, 7)});
    m.triangles.push_back({n + 3, n + 4, n + 5});
    const auto s = measure_surface(m);
    EXPECT_EQ(s.degenerate_triangles, 3u);
    EXPECT_DOUBLE_EQ(s.area_mm2, 6.0);
    EXPECT_FALSE(std::isnan(s.volume_ml));
    for (const auto& c : s.components) {
        EXPECT_FALSE(std::isnan(c.area_mm2));
        EXPECT_FALSE(std::isnan(c.volume_ml));
    }
    // The cube is closed; the collinear triangle is open (a sliver with zero area and volume).
    EXPECT_EQ(s.components.size(), 3u);
    EXPECT_NEAR(s.components[0].volume_ml, 0.001, 1e-15);
    EXPECT_TRUE(s.components[0].closed);
    // Only degenerate triangles.
    Mesh d;
    d.positions = {{1, 1, 1}, {1, 1, 1}, {2, 2, 2}};
    d.triangles = {{0, 1, 2}, {0, 0, 0}};
    const auto z = measure_surface(d);
    EXPECT_EQ(z.area_mm2, 0.0);
    EXPECT_EQ(z.volume_ml, 0.0);
    EXPECT_EQ(z.degenerate_triangles, 2u);
}

TEST(MeasureSurface, BadInputIsAnError) {
    Mesh m = box({0, 0, 0}, {1, 1, 1});
    m.triangles.push_back({0, 1, 99});
    try {
        measure_surface(m);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), "surface measure");
        EXPECT_NE(e.reason().find("triangle 12 names vertex 99 of 8"), std::string::npos) << e.reason();
    }
    Mesh n = box({0, 0, 0}, {1, 1, 1});
    n.positions[3].y = NAN;
    EXPECT_THROW(measure_surface(n), Error);
    const auto e = measure_surface(Mesh{});
    EXPECT_EQ(e.triangles, 0u);
    EXPECT_EQ(e.area_mm2, 0.0);
    EXPECT_EQ(e.volume_ml, 0.0);
    EXPECT_TRUE(e.components.empty());
}

TEST(MeasureSurface, SameResultOnAnyThreadCount) {
    const auto b = ball_case(0.5, 12.0, {0.2, 0.1, 0.3});
    const Mesh m = extract_isosurface(b.v, kBallIso);
    const auto one = measure_surface(m, {.threads = 1}), two = measure_surface(m, {.threads = 2}),
               any = measure_surface(m);
    EXPECT_EQ(one.area_mm2, two.area_mm2);
    EXPECT_EQ(one.volume_ml, two.volume_ml);
    EXPECT_EQ(one.area_mm2, any.area_mm2);
    EXPECT_EQ(one.volume_ml, any.volume_ml);
    const auto p = plain_sums(m);
    EXPECT_NEAR(one.area_mm2, p.area, 1e-9 * p.area);
    EXPECT_NEAR(one.volume_ml, p.volume_mm3 / 1000.0, 1e-7 * p.volume_mm3 / 1000.0);
    // As an STL triangle soup: welded back to the same surface.
    const auto s = measure_surface(soup(m));
    EXPECT_EQ(s.vertices, m.positions.size());
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.components.size(), 1u);
    EXPECT_NEAR(s.area_mm2, one.area_mm2, 1e-12 * one.area_mm2);
    EXPECT_NEAR(s.volume_ml, one.volume_ml, 1e-12 * one.volume_ml);
}

// ---- isosurfaces of analytic phantoms ------------------------------------------------------

TEST(MeasureIsosurface, BallAtOneMillimetreIsWithinHalfAPercentAndItsUncertainty) {
    // Radius 15 mm on the 0.7 x 1.0 x 1.3 mm oblique grid, blur 0.6 voxel.
    // The MC volume error of a ball goes as (h / R)^2 (inscribed surface):
    // -0.64 % at R = 10 voxels, so 0.5 % holds from R = 11.3 voxels.
    const double r = 15.0;
    const auto b = ball_case(1.0, r, {0.31, 0.17, 0.43});
    const auto s = measure_isosurface(b.v, kBallIso);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.volume_kind, VolumeKind::Enclosed);
    ASSERT_EQ(s.components.size(), 1u);
    EXPECT_EQ(s.non_manifold_edges + s.misoriented_edges + s.degenerate_triangles, 0u);
    const double ev = rel(s.volume_ml, ball_ml(r)), ea = rel(s.area_mm2, ball_area(r));
    EXPECT_LT(std::abs(ev), 0.005);
    EXPECT_LT(std::abs(ea), 0.005);
    // The stated uncertainty covers the true error, and is not vacuous.
    EXPECT_GE(s.volume_uncertainty_ml, std::abs(s.volume_ml - ball_ml(r)));
    EXPECT_GE(s.area_uncertainty_mm2, std::abs(s.area_mm2 - ball_area(r)));
    EXPECT_LT(s.volume_uncertainty_ml, 0.02 * ball_ml(r));
    EXPECT_LT(s.area_uncertainty_mm2, 0.02 * ball_area(r));
    EXPECT_EQ(s.components[0].volume_uncertainty_ml, s.volume_uncertainty_ml);
    EXPECT_GT(s.edge_fraction_spread, kResolvedEdgeSpread);
    EXPECT_TRUE(s.warnings.empty()) << s.warnings[0];
    // Bounds: the ball's box, to within a voxel.
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(s.bounds_min[a], b.c[a] - r, 1.3);
        EXPECT_NEAR(s.bounds_max[a], b.c[a] + r, 1.3);
    }
}

// The ball of radius 10 at 1 mm misses 0.5 % by marching cubes alone
// (-0.64 %, as VTK's Flying Edges + vtkMassProperties); the Richardson
// extrapolation from the coarse grid removes the h^2 term.
TEST(MeasureIsosurface, ExtrapolatedBallVolumeIsWithinHalfAPercentAtTenVoxels) {
    const double r = 10.0;
    const auto b = ball_case(1.0, r, {0.31, 0.17, 0.43});
    const auto s = measure_isosurface(b.v, kBallIso);
    const double plain = rel(s.volume_ml, ball_ml(r)), ex = rel(s.volume_extrapolated_ml, ball_ml(r));
    std::printf("ball r = 10 at 1 mm: volume %+.3f %%, extrapolated %+.3f %%; area %+.3f %%, extrapolated %+.3f %%\n",
                100 * plain, 100 * ex, 100 * rel(s.area_mm2, ball_area(r)),
                100 * rel(s.area_extrapolated_mm2, ball_area(r)));
    EXPECT_GT(std::abs(plain), 0.005) << "marching cubes alone misses 0.5 % here";
    EXPECT_LT(std::abs(ex), 0.005);
    EXPECT_LT(std::abs(ex), 0.5 * std::abs(plain));
    EXPECT_LT(std::abs(rel(s.area_extrapolated_mm2, ball_area(r))), 0.005);
    // A plain mesh has no coarse grid: nothing to extrapolate from.
    EXPECT_TRUE(std::isnan(measure_surface(extract_isosurface(b.v, kBallIso, {})).volume_extrapolated_ml));
}

TEST(MeasureIsosurface, BallErrorFallsAsTheVoxelsShrink) {
    const double r = 10.0;
    double last_v = 1e9, last_a = 1e9, last_uv = 1e9;
    for (double scale : {2.0, 1.0, 0.5}) {
        const auto b = ball_case(scale, r, {0.31, 0.17, 0.43});
        const auto s = measure_isosurface(b.v, kBallIso);
        const double ev = std::abs(rel(s.volume_ml, ball_ml(r))), ea = std::abs(rel(s.area_mm2, ball_area(r)));
        EXPECT_LT(ev, last_v) << scale;
        EXPECT_LT(ea, last_a) << scale;
        EXPECT_LT(s.volume_uncertainty_ml, last_uv) << scale;
        EXPECT_GE(s.volume_uncertainty_ml, std::abs(s.volume_ml - ball_ml(r))) << scale;
        EXPECT_GE(s.area_uncertainty_mm2, std::abs(s.area_mm2 - ball_area(r))) << scale;
        last_v = ev;
        last_a = ea;
        last_uv = s.volume_uncertainty_ml;
    }
    // Second order in the voxel size: from 2 to 0.5 mm the volume error drops by more than 10x.
    EXPECT_LT(last_v, 0.003);
}

TEST(MeasureIsosurface, UncertaintyCoversTheErrorOnRandomBalls) {
    // The benchmark runs many more (docs/measure.md); here a few at 1 mm.
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> radius(5.0, 18.0), frac(-0.5, 0.5);
    for (int n = 0; n < 8; ++n) {
        const double r = radius(rng);
        const auto b = ball_case(1.0, r, {frac(rng), frac(rng), frac(rng)});
        const auto s = measure_isosurface(b.v, kBallIso);
        EXPECT_GE(s.volume_uncertainty_ml, std::abs(s.volume_ml - ball_ml(r))) << "r = " << r;
        EXPECT_GE(s.area_uncertainty_mm2, std::abs(s.area_mm2 - ball_area(r))) << "r = " << r;
    }
}

TEST(MeasureIsosurface, SharpEdgesAreFlagged) {
    // A binary ball (a mask): every vertex at mid-edge, the area biased
    // upward by about 10 %, which the grid comparison cannot see; the spread
    // of edge fractions says so.
    const std::array<std::int64_t, 3> dims = dims_for(10.0, 3.0, 1.0);
    const glm::dvec3 c(-30.0, 45.0, 120.0);
    const Volume v = sample_field(dims, oblique_affine(dims, 1.0, c),
                                  [&](const glm::dvec3& p) { return glm::length(p - c) <= 10.0 ? 1000.0 : 0.0; });
    const auto s = measure_isosurface(v, kBallIso);
    EXPECT_LT(s.edge_fraction_spread, 0.05);
    EXPECT_GT(rel(s.area_mm2, ball_area(10.0)), 0.05) << "the staircase bias this flag is about";
    ASSERT_FALSE(s.warnings.empty());
    EXPECT_NE(s.warnings.back().find("sharper than the voxel grid resolves"), std::string::npos);
    // A well-blurred ball is not flagged.
    const auto b = ball_case(1.0, 10.0, {0, 0, 0}, 1.0);
    EXPECT_GT(measure_isosurface(b.v, kBallIso).edge_fraction_spread, 0.9);
}

TEST(MeasureIsosurface, BallCutByTheVolumeBorderIsOpenAndABound) {
    // Ball of radius 12 whose centre is 5 mm inside the grid's first i
    // plane (the plane of the i = 0 voxel centres, where the surface ends).
    const double r = 12.0, d = 5.0, scale = 1.0;
    auto dims = dims_for(r, 4.0, scale);
    const glm::dvec3 centre(-30.0, 45.0, 120.0);
    const glm::dmat4 aff = oblique_affine(dims, scale, centre);
    const glm::dvec3 n_i = glm::normalize(glm::dvec3(aff[0])); // i direction (unit)
    const glm::dvec3 plane = glm::dvec3(aff[3]);               // on the i = 0 plane
    // Put the centre at the grid centre's j, k but d from the plane along i.
    const glm::dvec3 c = centre - glm::dot(centre - plane, n_i) * n_i + d * n_i;
    const glm::dvec3 sp = phantom_spacing(scale);
    const Volume v = ct_ball(dims, aff, c, r, 0.6 * (sp.x + sp.y + sp.z) / 3.0);
    const auto s = measure_isosurface(v, kBallIso);
    EXPECT_FALSE(s.closed);
    EXPECT_EQ(s.volume_kind, VolumeKind::LowerBound);
    EXPECT_EQ(s.boundary_loops, 1u);
    ASSERT_EQ(s.components.size(), 1u);
    EXPECT_EQ(s.components[0].volume_kind, VolumeKind::LowerBound);
    // The boundary: the circle where the plane cuts the ball.
    const double rho = std::sqrt(r * r - d * d);
    EXPECT_NEAR(s.boundary_length_mm, 2 * std::numbers::pi * rho, 0.01 * 2 * std::numbers::pi * rho);
    // The capped volume: the ball without the cap beyond the plane; less than the ball.
    const double inside = ball_ml(r) - cap_ml(r, d);
    EXPECT_NEAR(s.volume_ml, inside, 0.01 * inside);
    EXPECT_GE(s.volume_uncertainty_ml, std::abs(s.volume_ml - inside));
    EXPECT_LT(s.volume_ml, ball_ml(r));
    bool warned = false;
    for (const auto& w : s.warnings) warned |= w.find("lower bound") != std::string::npos;
    EXPECT_TRUE(warned);
}

TEST(MeasureIsosurface, TwoBallsAreTwoComponentsByVolume) {
    const double r1 = 6.0, r2 = 9.0, scale = 1.0;
    const std::array<std::int64_t, 3> dims{60, 40, 30};
    const glm::dvec3 centre(-30.0, 45.0, 120.0);
    const glm::dmat4 aff = oblique_affine(dims, scale, centre);
    const glm::dvec3 c1 = centre + glm::dmat3(aff) * glm::dvec3(-15.2, 0.3, 0.1);
    const glm::dvec3 c2 = centre + glm::dmat3(aff) * glm::dvec3(12.4, -0.2, 0.4);
    const Volume v = sample_field(dims, aff, [&](const glm::dvec3& p) {
        return std::max(ct_edge(r1 - glm::length(p - c1), 0.6), ct_edge(r2 - glm::length(p - c2), 0.6));
    });
    const auto s = measure_isosurface(v, kBallIso);
    ASSERT_EQ(s.components.size(), 2u);
    EXPECT_TRUE(s.closed);
    const auto &big = s.components[0], &small = s.components[1];
    EXPECT_NEAR(big.volume_ml, ball_ml(r2), 0.01 * ball_ml(r2));
    EXPECT_NEAR(small.volume_ml, ball_ml(r1), 0.02 * ball_ml(r1));
    EXPECT_NEAR(big.area_mm2, ball_area(r2), 0.01 * ball_area(r2));
    EXPECT_NEAR(small.area_mm2, ball_area(r1), 0.02 * ball_area(r1));
    EXPECT_GE(big.volume_uncertainty_ml, std::abs(big.volume_ml - ball_ml(r2)));
    EXPECT_GE(small.volume_uncertainty_ml, std::abs(small.volume_ml - ball_ml(r1)));
    EXPECT_GE(small.area_uncertainty_mm2, std::abs(small.area_mm2 - ball_area(r1)));
    EXPECT_LT(small.volume_uncertainty_ml, 0.1 * ball_ml(r1)) << "matched to its own coarse component";
    EXPECT_NEAR(s.volume_ml, big.volume_ml + small.volume_ml, 1e-12);
    EXPECT_EQ(big.triangles + small.triangles, s.triangles);
    // Each component's box is its ball's.
    EXPECT_NEAR(glm::length(0.5 * (big.bounds_min + big.bounds_max) - c2), 0.0, 0.5);
    EXPECT_NEAR(glm::length(0.5 * (small.bounds_min + small.bounds_max) - c1), 0.0, 0.5);
}

TEST(MeasureIsosurface, HollowBallHasANegativeCavity) {
    // A shell between radii 6 and 11: outer surface (positive volume) and
    // inner surface facing inward (a cavity, negative), in that order.
    const double r0 = 6.0, r1 = 11.0;
    const auto dims = dims_for(r1, 3.0, 1.0);
    const glm::dvec3 c(-30.0, 45.0, 120.0);
    const Volume v = sample_field(dims, oblique_affine(dims, 1.0, c), [&](const glm::dvec3& p) {
        const double q = glm::length(p - c);
        return ct_edge(std::min(r1 - q, q - r0), 0.6);
    });
    const auto s = measure_isosurface(v, kBallIso);
    ASSERT_EQ(s.components.size(), 2u);
    EXPECT_NEAR(s.components[0].volume_ml, ball_ml(r1), 0.01 * ball_ml(r1));
    EXPECT_NEAR(s.components[1].volume_ml, -ball_ml(r0), 0.02 * ball_ml(r0));
    EXPECT_NEAR(s.volume_ml, ball_ml(r1) - ball_ml(r0), 0.01 * ball_ml(r1));
    EXPECT_GE(s.volume_uncertainty_ml, std::abs(s.volume_ml - (ball_ml(r1) - ball_ml(r0))));
}

TEST(MeasureIsosurface, CoarseGridSpansTheSameExtent) {
    const Volume v = random_hu({9, 8, 3});
    glm::dvec3 ratio;
    const Volume c = coarsen_2x(v, &ratio);
    EXPECT_EQ(c.dims, (std::array<std::int64_t, 3>{5, 5, 2}));
    EXPECT_DOUBLE_EQ(ratio.x, 2.0);
    EXPECT_DOUBLE_EQ(ratio.y, 7.0 / 4.0);
    EXPECT_DOUBLE_EQ(ratio.z, 2.0);
    // First and last samples keep their positions and values.
    for (const auto& [ci, fi] :
         std::vector<std::pair<glm::dvec3, glm::dvec3>>{{{0, 0, 0}, {0, 0, 0}}, {{4, 4, 1}, {8, 7, 2}}}) {
        EXPECT_NEAR(glm::length(c.index_to_world(ci) - v.index_to_world(fi)), 0.0, 1e-9);
        EXPECT_NEAR(c.value(std::int64_t(ci.x), std::int64_t(ci.y), std::int64_t(ci.z)),
                    v.value(std::int64_t(fi.x), std::int64_t(fi.y), std::int64_t(fi.z)), 1e-3);
    }
    // Inner samples are the trilinear interpolation at their position.
    EXPECT_NEAR(c.value(2, 3, 1), trilinear_by_hand(v, {4.0, 3 * 7.0 / 4.0, 2.0}), 1e-3);
}

TEST(MeasureIsosurface, AStructureNearTheVoxelSizeIsAsUncertainAsItIsLarge) {
    // A ball of radius 1.1 mm next to one of 8 mm on the 1 mm grid: the small
    // one is resolved by a handful of voxels, and at twice the voxel size it
    // vanishes or is unrecognisable, so its uncertainty is of its own size.
    const std::array<std::int64_t, 3> dims{50, 30, 24};
    const glm::dvec3 centre(-30.0, 45.0, 120.0);
    const glm::dmat4 aff = oblique_affine(dims, 1.0, centre);
    const glm::dvec3 c1 = centre + glm::dmat3(aff) * glm::dvec3(-15.3, 0.2, 0.1);
    const glm::dvec3 c2 = centre + glm::dmat3(aff) * glm::dvec3(10.1, -0.3, 0.2);
    const Volume v = sample_field(dims, aff, [&](const glm::dvec3& p) {
        return std::max(ct_edge(1.1 - glm::length(p - c1), 0.6), ct_edge(8.0 - glm::length(p - c2), 0.6));
    });
    const auto s = measure_isosurface(v, kBallIso);
    ASSERT_EQ(s.components.size(), 2u);
    const auto& tiny = s.components[1];
    EXPECT_GT(tiny.volume_uncertainty_ml, 0.3 * tiny.volume_ml);
    EXPECT_GE(tiny.volume_uncertainty_ml, std::abs(tiny.volume_ml - ball_ml(1.1)));
    EXPECT_LT(s.components[0].volume_uncertainty_ml, 0.05 * s.components[0].volume_ml);
}
