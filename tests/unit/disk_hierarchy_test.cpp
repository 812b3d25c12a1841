// Disk hierarchy of disk-based AO (renderer/ao/disk_hierarchy.hpp): the
// tree's invariants on synthetic and real meshes, concatenation, input
// checks, and the CPU evaluation (the model of the compute shaders) against
// exact form factors, the R limit, self-occlusion, convergence of the
// element passes, and the Embree reference.
#include "renderer/ao/disk_hierarchy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "io/error.hpp"
#include "io/mesh.hpp"
#include "renderer/ao/reference.hpp"
#include "renderer/core/scene.hpp"

using namespace iso;

namespace {

using V = glm::dvec3;

// A grid of nu x nv quads (2 triangles each) spanning origin + [0,1]u + [0,1]v;
// front = cross(u, v), vertex normals along it.
void add_grid(Mesh& m, const V& origin, const V& u, const V& v, int nu, int nv) {
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    const glm::vec3 nn(glm::normalize(glm::cross(u, v)));
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            m.positions.emplace_back(origin + (double(i) / nu) * u + (double(j) / nv) * v);
            m.normals.push_back(nn);
        }
    const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (nu + 1) + i); };
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
}

// A closed cube [-s, s]^3 of 6 grids, fronts facing inwards (the walls seen
// from inside) or outwards. Each face has its own vertices (a sharp edge has
// two normals).
Mesh box(double s, int n, bool inward) {
    Mesh m;
    const V e[3] = {V(2 * s, 0, 0), V(0, 2 * s, 0), V(0, 0, 2 * s)};
    for (int axis = 0; axis < 3; ++axis) {
        const V u = e[(axis + 1) % 3], v = e[(axis + 2) % 3];
        const V lo(-s), hi = V(-s) + e[axis];
        // cross(u, v) points along +axis: at the low face that is inwards.
        if (inward) {
            add_grid(m, lo, u, v, n, n);
            add_grid(m, hi, v, u, n, n);
        } else {
            add_grid(m, lo, v, u, n, n);
            add_grid(m, hi, u, v, n, n);
        }
    }
    return m;
}

// UV sphere, outward fronts, radial normals.
Mesh sphere(const V& c, double r, int nu, int nv) {
    Mesh m;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const double th = std::numbers::pi * j / nv, ph = 2 * std::numbers::pi * i / nu;
            const V d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            m.positions.emplace_back(c + r * d);
            m.normals.emplace_back(d);
        }
    const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * nu + (i % nu)); };
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            // Outward winding (theta down from +z, phi counter-clockwise).
            if (j > 0) m.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j)});
            if (j + 1 < nv) m.triangles.push_back({at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)});
        }
    return m;
}

double triangle_area(const Mesh& m, const std::array<std::uint32_t, 3>& t) {
    const V a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
    return 0.5 * glm::length(glm::cross(b - a, c - a));
}

V xyz(const glm::vec4& v) { return V(v.x, v.y, v.z); }

// Every structural invariant of one build (or a concatenation of builds of
// `meshes`).
void check_structure(const DiskHierarchy& h, const std::vector<const Mesh*>& meshes) {
    const auto n = static_cast<std::int32_t>(h.nodes.size());
    ASSERT_GT(n, 0);
    ASSERT_EQ(h.node_level.size(), h.nodes.size());
    ASSERT_EQ(h.roots.size(), meshes.size());
    // Trees follow one another: root k's skip is root k+1 (or the end).
    for (std::size_t k = 0; k < h.roots.size(); ++k) {
        EXPECT_EQ(h.node_level[static_cast<std::size_t>(h.roots[k])], 0);
        EXPECT_EQ(h.nodes[static_cast<std::size_t>(h.roots[k])].links.x, k + 1 < h.roots.size() ? h.roots[k + 1] : n);
    }
    EXPECT_EQ(h.roots[0], 0);
    int deepest = 0;
    std::int32_t leaves = 0;
    std::vector<int> owner_seen(h.triangles.size() / 3, 0);
    for (std::int32_t i = 0; i < n; ++i) {
        const DiskNode& node = h.nodes[static_cast<std::size_t>(i)];
        const std::int32_t skip = node.links.x;
        ASSERT_GT(skip, i);
        ASSERT_LE(skip, n);
        deepest = std::max(deepest, h.node_level[static_cast<std::size_t>(i)]);
        const double len = glm::length(V(node.normal_bound.x, node.normal_bound.y, node.normal_bound.z));
        EXPECT_TRUE(len == 0.0 || std::abs(len - 1.0) < 1e-5) << "node " << i;
        if (node.links.y < 0) {
            ++leaves;
            EXPECT_EQ(skip, i + 1);
            for (std::int32_t t = node.links.z; t < node.links.z + node.links.w; ++t)
                ++owner_seen[static_cast<std::size_t>(t)];
            // A leaf's bound holds its disk and its triangles.
            const double r = std::sqrt(node.centre_area.w / std::numbers::pi);
            EXPECT_LE(r, node.normal_bound.w * (1 + 1e-6) + 1e-12);
            for (std::int32_t t = node.links.z; t < node.links.z + node.links.w; ++t)
                for (int k = 0; k < 3; ++k)
                    EXPECT_LE(
                        glm::length(xyz(h.triangles[static_cast<std::size_t>(3 * t + k)]) - xyz(node.centre_area)),
                        node.normal_bound.w * (1 + 1e-6) + 1e-9);
            continue;
        }
        // Parent: children chained by skip from i + 1 exactly to skip, 2-4 of them,
        // one level deeper, areas adding up.
        EXPECT_EQ(node.links.y, i + 1);
        EXPECT_EQ(node.links.z, 0);
        EXPECT_EQ(node.links.w, 0);
        int children = 0;
        double area = 0.0;
        std::int32_t c = node.links.y;
        for (; c < skip; c = h.nodes[static_cast<std::size_t>(c)].links.x) {
            ++children;
            area += h.nodes[static_cast<std::size_t>(c)].centre_area.w;
            EXPECT_EQ(h.node_level[static_cast<std::size_t>(c)], h.node_level[static_cast<std::size_t>(i)] + 1);
        }
        EXPECT_EQ(c, skip) << "children of " << i << " overrun the subtree";
        EXPECT_GE(children, 2);
        EXPECT_LE(children, 4);
        EXPECT_NEAR(area, node.centre_area.w, 1e-5 * std::max(area, 1e-30));
        // Every leaf below (disk and triangles) inside this node's bound.
        const V centre = xyz(node.centre_area);
        for (std::int32_t j = i + 1; j < skip; ++j) {
            const DiskNode& leaf = h.nodes[static_cast<std::size_t>(j)];
            if (leaf.links.y >= 0) continue;
            const double reach =
                glm::length(xyz(leaf.centre_area) - centre) + std::sqrt(leaf.centre_area.w / std::numbers::pi);
            EXPECT_LE(reach, node.normal_bound.w * (1 + 1e-5) + 1e-9) << "leaf " << j << " outside node " << i;
            for (std::int32_t t = leaf.links.z; t < leaf.links.z + leaf.links.w; ++t)
                for (int k = 0; k < 3; ++k)
                    EXPECT_LE(glm::length(xyz(h.triangles[static_cast<std::size_t>(3 * t + k)]) - centre),
                              node.normal_bound.w * (1 + 1e-5) + 1e-9);
        }
    }
    EXPECT_EQ(h.levels, deepest + 1);
    // Each triangle owned exactly once; the stored triangles are the meshes'
    // (as a multiset of corner triples), areas adding up to the meshes'.
    for (std::size_t t = 0; t < owner_seen.size(); ++t) ASSERT_EQ(owner_seen[t], 1) << "triangle " << t;
    std::vector<std::array<float, 9>> stored, expected;
    double mesh_area = 0.0, root_area = 0.0;
    std::size_t vertices = 0, referenced = 0;
    for (const Mesh* m : meshes) {
        for (const auto& t : m->triangles) {
            std::array<float, 9> a{};
            for (int k = 0; k < 3; ++k)
                for (int d = 0; d < 3; ++d)
                    a[static_cast<std::size_t>(3 * k + d)] = m->positions[t[static_cast<std::size_t>(k)]][d];
            expected.push_back(a);
            mesh_area += triangle_area(*m, t);
        }
        std::vector<char> used(m->positions.size(), 0);
        for (const auto& t : m->triangles)
            for (auto v : t) used[v] = 1;
        for (std::size_t v = 0; v < m->positions.size(); ++v) {
            const std::int32_t leaf = h.vertex_node[vertices + v];
            if (!used[v]) {
                EXPECT_EQ(leaf, -1);
                continue;
            }
            ++referenced;
            ASSERT_GE(leaf, 0);
            EXPECT_LT(h.nodes[static_cast<std::size_t>(leaf)].links.y, 0);
            EXPECT_EQ(glm::vec3(h.nodes[static_cast<std::size_t>(leaf)].centre_area), m->positions[v]);
        }
        vertices += m->positions.size();
    }
    ASSERT_EQ(h.vertex_node.size(), vertices);
    EXPECT_EQ(static_cast<std::size_t>(leaves), referenced);
    for (std::size_t t = 0; t < h.triangles.size() / 3; ++t) {
        std::array<float, 9> a{};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                a[static_cast<std::size_t>(3 * k + d)] = h.triangles[3 * t + static_cast<std::size_t>(k)][d];
        stored.push_back(a);
    }
    std::sort(stored.begin(), stored.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(stored, expected);
    for (const std::int32_t r : h.roots) root_area += h.nodes[static_cast<std::size_t>(r)].centre_area.w;
    EXPECT_NEAR(root_area, mesh_area, 1e-5 * mesh_area);
}

Mesh load_bunny() { return load_mesh(std::string(ISOSCOPE_DATA_DIR) + "/bunny.vtp"); }

// Exact form factor from a point at height h above the centre of a square of
// side 2a (facing it): four corner rectangles.
double centred_square_ff(double a, double h) {
    const double x = a / h, s = x / std::sqrt(1 + x * x);
    return 4.0 / std::numbers::pi * s * std::atan(s);
}

} // namespace

// ---------------------------------------------------------------- structure

TEST(DiskHierarchyBuild, GridInvariants) {
    Mesh m;
    add_grid(m, V(-1, -2, 0.5), V(3, 0, 0), V(0, 2, 0), 13, 7);
    const DiskHierarchy h = build_disk_hierarchy(m);
    check_structure(h, {&m});
    // Vertex disks: interior vertices of a uniform grid carry 6 triangles' thirds = one cell.
    const double cell = (3.0 / 13) * (2.0 / 7);
    const std::int32_t interior = h.vertex_node[static_cast<std::size_t>(3 * 14 + 5)];
    EXPECT_NEAR(h.nodes[static_cast<std::size_t>(interior)].centre_area.w, cell, 1e-6);
    // A flat sheet: every normal +z, the root's too.
    EXPECT_NEAR(h.nodes[0].normal_bound.z, 1.0f, 1e-6);
}

TEST(DiskHierarchyBuild, BunnyInvariants) {
    const Mesh m = load_bunny();
    ASSERT_GE(m.triangles.size(), 1000u);
    const DiskHierarchy h = build_disk_hierarchy(m);
    check_structure(h, {&m});
    // Median splits into up to 4: depth near log4 of the leaf count, at most log2.
    EXPECT_LE(h.levels, 2 + static_cast<int>(std::ceil(std::log2(static_cast<double>(m.positions.size())))));
}

// The bundled CT's bone surface (iso 1150, 78k triangles), as ao_bench
// loads it: every invariant on a real marching-cubes surface.
TEST(DiskHierarchyBuild, CtBoneInvariants) {
    core::Scene scene;
    scene.open(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr");
    const auto ids = scene.add_isosurfaces({1150.0});
    ASSERT_EQ(ids.size(), 1u);
    const Mesh& m = scene.mesh(ids[0]);
    ASSERT_GT(m.triangles.size(), 50000u);
    const DiskHierarchy h = build_disk_hierarchy(m);
    check_structure(h, {&m});
    std::printf("ct bone: %zu triangles, %zu nodes, %d levels\n", m.triangles.size(), h.nodes.size(), h.levels);
    EXPECT_LE(h.levels, 2 + static_cast<int>(std::ceil(std::log2(static_cast<double>(m.positions.size())))));
}

TEST(DiskHierarchyBuild, ClosedBoxRootNormalCancels) {
    const Mesh m = box(1.0, 4, false);
    const DiskHierarchy h = build_disk_hierarchy(m);
    check_structure(h, {&m});
    EXPECT_EQ(glm::vec3(h.nodes[0].normal_bound), glm::vec3(0.0f)); // opposite faces cancel exactly
    EXPECT_NEAR(h.nodes[0].centre_area.w, 24.0, 1e-4);
}

TEST(DiskHierarchyBuild, MeshWithoutNormalsGetsFaceNormals) {
    Mesh m;
    add_grid(m, V(0), V(0, 1, 0), V(0, 0, 1), 3, 3); // front +x
    m.normals.clear();
    const DiskHierarchy h = build_disk_hierarchy(m);
    for (const auto& node : h.nodes) EXPECT_NEAR(node.normal_bound.x, 1.0f, 1e-6);
}

TEST(DiskHierarchyBuild, RejectsBadInput) {
    Mesh empty;
    EXPECT_THROW(build_disk_hierarchy(empty), Error);
    Mesh nan;
    add_grid(nan, V(0), V(1, 0, 0), V(0, 1, 0), 2, 2);
    nan.positions[4].y = std::nanf("");
    try {
        build_disk_hierarchy(nan);
        FAIL() << "NaN position accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("vertex 4"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
    }
    Mesh inf;
    add_grid(inf, V(0), V(1, 0, 0), V(0, 1, 0), 2, 2);
    inf.positions[0].x = INFINITY;
    EXPECT_THROW(build_disk_hierarchy(inf), Error);
    Mesh bad_index;
    add_grid(bad_index, V(0), V(1, 0, 0), V(0, 1, 0), 2, 2);
    bad_index.triangles[1][2] = 1000;
    EXPECT_THROW(build_disk_hierarchy(bad_index), Error);
}

TEST(DiskHierarchyBuild, DegenerateTrianglesAndZeroAreaPart) {
    Mesh m;
    add_grid(m, V(0), V(1, 0, 0), V(0, 1, 0), 4, 4);
    // A zero-area part: a collinear fan and a triangle with a repeated vertex,
    // on their own vertices (no normals for them: the mesh loses its normals).
    m.normals.clear();
    const auto b = static_cast<std::uint32_t>(m.positions.size());
    for (int i = 0; i < 4; ++i) m.positions.emplace_back(0.5 + 0.1 * i, 0.5, 0.3);
    m.triangles.push_back({b, b + 1, b + 2});
    m.triangles.push_back({b + 1, b + 2, b + 3});
    m.triangles.push_back({b + 3, b + 3, b});
    // An unreferenced vertex.
    m.positions.emplace_back(9, 9, 9);
    const DiskHierarchy h = build_disk_hierarchy(m);
    check_structure(h, {&m});
    EXPECT_EQ(h.vertex_node.back(), -1);
    for (int i = 0; i < 4; ++i) {
        const DiskNode& leaf = h.nodes[static_cast<std::size_t>(h.vertex_node[b + static_cast<std::uint32_t>(i)])];
        EXPECT_EQ(leaf.centre_area.w, 0.0f);
        EXPECT_EQ(glm::vec3(leaf.normal_bound), glm::vec3(0.0f));
    }
    DiskAoSettings s;
    s.passes = 3;
    const auto terms = disk_element_terms(h, s, 2.0);
    for (float t : terms) EXPECT_TRUE(std::isfinite(t) && t >= 0.0f && t <= 1.0f);
    // Receivers on the degenerate part and at it: finite.
    for (const V& p : {V(0.6, 0.5, 0.3), V(0.5, 0.5, 0.0), V(0.55, 0.5, 0.31)})
        for (const V& n : {V(0, 0, 1), V(0, 0, -1), V(1, 0, 0)}) {
            const double o = disk_occlusion(h, p, n, terms, s, 2.0);
            EXPECT_TRUE(std::isfinite(o) && o >= 0.0 && o <= 1.0);
        }
    // A mesh that is all zero-area: builds, occludes nothing.
    Mesh flat;
    for (int i = 0; i < 5; ++i) flat.positions.emplace_back(i, 0, 0);
    flat.triangles = {{0, 1, 2}, {2, 3, 4}, {1, 1, 1}};
    const DiskHierarchy hf = build_disk_hierarchy(flat);
    check_structure(hf, {&flat});
    EXPECT_EQ(hf.nodes[0].centre_area.w, 0.0f);
    EXPECT_EQ(disk_occlusion(hf, V(2, 0.5, 0), V(0, -1, 0), {}, s, 10.0), 0.0);
    for (float t : disk_element_terms(hf, s, 10.0)) EXPECT_EQ(t, 1.0f);
}

TEST(DiskHierarchyBuild, ConcatenateOffsets) {
    Mesh a;
    add_grid(a, V(0), V(1, 0, 0), V(0, 1, 0), 5, 3);
    const Mesh b = load_bunny();
    Mesh c = sphere(V(5, 0, 0), 1.0, 12, 6);
    const DiskHierarchy ha = build_disk_hierarchy(a), hb = build_disk_hierarchy(b), hc = build_disk_hierarchy(c);
    const DiskHierarchy h = concatenate({&ha, &hb, &hc});
    check_structure(h, {&a, &b, &c});
    const auto na = static_cast<std::int32_t>(ha.nodes.size()), nb = static_cast<std::int32_t>(hb.nodes.size());
    EXPECT_EQ(h.roots, (std::vector<std::int32_t>{0, na, na + nb}));
    const auto ta = static_cast<std::int32_t>(ha.triangles.size() / 3);
    for (std::int32_t i = 0; i < nb; ++i) {
        const DiskNode& o = hb.nodes[static_cast<std::size_t>(i)];
        const DiskNode& x = h.nodes[static_cast<std::size_t>(na + i)];
        EXPECT_EQ(x.centre_area, o.centre_area);
        EXPECT_EQ(x.normal_bound, o.normal_bound);
        EXPECT_EQ(x.links.x, o.links.x + na);
        EXPECT_EQ(x.links.y, o.links.y < 0 ? -1 : o.links.y + na);
        EXPECT_EQ(x.links.z, o.links.y < 0 ? o.links.z + ta : 0);
        EXPECT_EQ(x.links.w, o.links.w);
    }
    EXPECT_EQ(h.levels, std::max({ha.levels, hb.levels, hc.levels}));
    EXPECT_THROW(concatenate({&ha, nullptr}), Error);
    // One traversal from node 0 covers every tree: a receiver that sees both
    // the grid (front +z, below-left of it) and the sphere gets the sum of
    // the two (first pass, no modulation; small, so no clamping).
    const DiskHierarchy hac = concatenate({&ha, &hc});
    DiskAoSettings s;
    const V p(2.0, 0.5, 1.5), n = glm::normalize(V(0.6, 0, -1.0));
    const double both = disk_occlusion(hac, p, n, {}, s, 100.0);
    const double only_sphere = disk_occlusion(hc, p, n, {}, s, 100.0);
    const double only_grid = disk_occlusion(ha, p, n, {}, s, 100.0);
    EXPECT_GT(only_sphere, 0.01);
    EXPECT_GT(only_grid, 0.01);
    EXPECT_NEAR(both, only_sphere + only_grid, 1e-6);
}

// ---------------------------------------------------------------- evaluation

namespace {

DiskAoSettings all_triangles() {
    DiskAoSettings s;
    s.traversal_epsilon = 1e30; // always near: every leaf as its triangles
    s.receiver_offset = 0.0;
    return s;
}

// Sum of the clipped front-facing triangles' exact form factors, in double,
// straight over the mesh: what the triangle path must add up to.
double brute_force(const Mesh& m, const V& p, const V& n) {
    double sum = 0.0;
    for (const auto& t : m.triangles)
        sum += std::max(
            clipped_triangle_form_factor(p, n, V(m.positions[t[0]]), V(m.positions[t[1]]), V(m.positions[t[2]])), 0.0);
    return std::min(sum, 1.0);
}

} // namespace

// The triangle path visits every triangle exactly once: equal to the brute
// force sum over the mesh. Float against double: the shader's precision,
// 2e-5 (float form factors of ~1000 triangles, each rounding ~1e-7 relative).
TEST(DiskOcclusion, TrianglePathEqualsBruteForce) {
    Mesh m;
    add_grid(m, V(-1, -1, 0), V(2, 0, 0), V(0, 2, 0), 16, 16);
    const DiskHierarchy h = build_disk_hierarchy(m);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    for (int k = 0; k < 40; ++k) {
        const V p(u(rng), u(rng), 0.05 + std::abs(u(rng)));
        const V n = glm::normalize(V(u(rng), u(rng), -1.0 + 0.5 * u(rng)));
        const double expected = brute_force(m, p, n);
        EXPECT_NEAR(disk_occlusion(h, p, n, {}, all_triangles(), 1e3), expected, 2e-5) << k;
        EXPECT_NEAR(disk_occlusion_double(h, p, n, {}, all_triangles(), 1e3), expected, 1e-12) << k;
    }
}

// Above the centre of a 4 x 4 square at height 1: the exact closed form via
// the triangle path (2e-5: float), and with the chapter's traversal
// (epsilon 8: the far leaves and parents as disks) within 0.03 of it (the
// disk approximation's error: measured 0.023 low here, the leaves just
// beyond sqrt(8 A) being where Bunnell's disk is worst); the default
// epsilon 16 within 0.015 (measured 0.012).
TEST(DiskOcclusion, SquareAboveCentreMatchesClosedForm) {
    Mesh m;
    add_grid(m, V(-2, -2, 0), V(4, 0, 0), V(0, 4, 0), 32, 32);
    const DiskHierarchy h = build_disk_hierarchy(m);
    const double exact = centred_square_ff(2.0, 1.0);
    const V p(0, 0, 1), n(0, 0, -1);
    EXPECT_NEAR(disk_occlusion(h, p, n, {}, all_triangles(), 100.0), exact, 2e-5);
    DiskAoSettings s;
    s.receiver_offset = 0.0;
    s.traversal_epsilon = 8.0;
    const double chapter = disk_occlusion(h, p, n, {}, s, 100.0);
    s.traversal_epsilon = 16.0;
    const double ours = disk_occlusion(h, p, n, {}, s, 100.0);
    std::printf("square: epsilon 16 %.5f\n", ours);
    EXPECT_NEAR(ours, exact, 0.015); // measured 0.012 low
    EXPECT_GT(ours, chapter);
    std::printf("square: exact %.5f, epsilon 8 %.5f\n", exact, chapter);
    EXPECT_NEAR(chapter, exact, 0.03);
    EXPECT_LT(chapter, exact);
}

// Far field: a unit square at distance 10 is one disk (the root): within
// the disk approximation's O(A / d^2) of the exact form factor (1.5 (r/d)^2
// relative, r = sqrt(A / pi), docs/ao.md).
TEST(DiskOcclusion, FarFieldIsTheDiskApproximation) {
    Mesh m;
    add_grid(m, V(-0.5, -0.5, 0), V(1, 0, 0), V(0, 1, 0), 8, 8);
    const DiskHierarchy h = build_disk_hierarchy(m);
    DiskAoSettings s;
    s.receiver_offset = 0.0;
    const double d = 10.0;
    const double exact = centred_square_ff(0.5, d);
    const double got = disk_occlusion(h, V(0, 0, d), V(0, 0, -1), {}, s, 100.0);
    EXPECT_NEAR(got, exact, 1.5 * (1.0 / std::numbers::pi) / (d * d) * exact);
    EXPECT_NEAR(got, 1.0 / (std::numbers::pi * d * d + 1.0), 1e-6); // exactly the root disk
}

// The radius: elements count by their centre's distance (triangles: their
// centroid), subtrees wholly beyond R are skipped, parents straddling R are
// opened. A unit square of 8 x 8 cells facing the receiver at distance 5:
// R above every centroid's distance: the full value (up to the leaf disks'
// sum against the root's one disk when R holds the whole root: 2e-3
// relative); R below every one: 0; in between: monotone in R.
TEST(DiskOcclusion, RadiusLimitsOccluders) {
    Mesh m;
    add_grid(m, V(-0.5, -0.5, 0), V(1, 0, 0), V(0, 1, 0), 8, 8);
    const DiskHierarchy h = build_disk_hierarchy(m);
    DiskAoSettings s;
    s.receiver_offset = 0.0;
    const V p(0, 0, 5), n(0, 0, -1);
    const double full = disk_occlusion(h, p, n, {}, s, 1000.0);
    EXPECT_GT(full, 0.01);
    EXPECT_NEAR(disk_occlusion(h, p, n, {}, s, std::sqrt(25.0 + 0.5) + 1e-3), full,
                2e-3 * full);                                   // just inside (corners)
    EXPECT_EQ(disk_occlusion(h, p, n, {}, s, 5.0 - 1e-3), 0.0); // just outside (centre)
    double last = 0.0;
    for (double r = 5.0; r <= 5.06; r += 0.002) {
        const double o = disk_occlusion(h, p, n, {}, s, r);
        EXPECT_GE(o, last - 1e-7) << r;
        last = o;
    }
    EXPECT_NEAR(last, full, 2e-3 * full);
    // Near a leaf (its triangles): a triangle counts iff its centroid is within R.
    DiskAoSettings tri = all_triangles();
    const V q(0, 0, 0.3);
    const double all = disk_occlusion(h, q, n, {}, tri, 10.0);
    double inside = 0.0;
    const double r = 0.45;
    for (const auto& t : m.triangles) {
        const V a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        if (glm::length((a + b + c) / 3.0 - q) <= r)
            inside += std::max(clipped_triangle_form_factor(q, n, a, b, c), 0.0);
    }
    EXPECT_NEAR(disk_occlusion(h, q, n, {}, tri, r), inside, 2e-5);
    EXPECT_LT(inside, all - 0.05);
}

// Self-occlusion: a receiver at a vertex of a convex or flat surface sees
// nothing of it (its own disk and triangles lie below the raised receiver).
// Inside a triangle of a sphere with the interpolated (radial) normal, its
// own and neighbouring triangles rise above the tangent plane only in the
// lune between the two planes: (1 - cos a) / 2 with a the angle between the
// face and the radial normal.
TEST(DiskOcclusion, NoSelfOcclusion) {
    const Mesh ball = sphere(V(1, 2, 3), 2.0, 32, 16);
    const DiskHierarchy h = build_disk_hierarchy(ball);
    DiskAoSettings s;
    s.passes = 3;
    const auto terms = disk_element_terms(h, s, 1.0);
    for (float t : terms) EXPECT_EQ(t, 1.0f);
    for (std::size_t v = 0; v < ball.positions.size(); v += 7)
        EXPECT_EQ(disk_occlusion(h, V(ball.positions[v]), V(ball.normals[v]), terms, s, 1.0), 0.0) << v;
    double worst = 0.0, bound = 0.0;
    for (std::size_t t = 0; t < ball.triangles.size(); t += 5) {
        const auto& tri = ball.triangles[t];
        const V a(ball.positions[tri[0]]), b(ball.positions[tri[1]]), c(ball.positions[tri[2]]);
        const V p = 0.2 * a + 0.3 * b + 0.5 * c;
        const V n = glm::normalize(p - V(1, 2, 3));
        const double cos_a = std::abs(glm::dot(n, glm::normalize(glm::cross(b - a, c - a))));
        worst = std::max(worst, disk_occlusion(h, p, n, terms, s, 1.0));
        bound = std::max(bound, (1.0 - cos_a) / 2.0);
    }
    EXPECT_LE(worst, bound);
    EXPECT_LT(worst, 0.01);
    Mesh flat;
    add_grid(flat, V(0), V(3, 0, 0), V(0, 3, 0), 9, 9);
    const DiskHierarchy hf = build_disk_hierarchy(flat);
    for (std::size_t v = 0; v < flat.positions.size(); ++v)
        EXPECT_EQ(disk_occlusion(hf, V(flat.positions[v]), V(0, 0, 1), {}, s, 1.0), 0.0);
}

// The shader's float against double, on a real mesh with modulation:
// 1e-4 (the float sum of a few hundred terms).
TEST(DiskOcclusion, FloatAgainstDoubleOnBunny) {
    const Mesh m = load_bunny();
    const DiskHierarchy h = build_disk_hierarchy(m);
    const Mesh* mp = &m;
    double size = 0.0;
    for (const auto& p : mp->positions) size = std::max(size, double(glm::length(p - mp->positions[0])));
    DiskAoSettings s;
    const double R = 0.1 * size;
    s.passes = 1;
    const auto terms = disk_element_terms(h, s, R);
    double worst = 0.0, mean = 0.0;
    int count = 0;
    for (std::size_t v = 0; v < m.positions.size(); v += 5) {
        if (h.vertex_node[v] < 0) continue;
        const V n(glm::vec3(h.nodes[static_cast<std::size_t>(h.vertex_node[v])].normal_bound));
        if (glm::length(n) < 0.5) continue;
        const double f = disk_occlusion(h, V(m.positions[v]), n, terms, s, R);
        const double d = disk_occlusion_double(h, V(m.positions[v]), n, terms, s, R);
        worst = std::max(worst, std::abs(f - d));
        mean += f;
        ++count;
    }
    std::printf("bunny float-double: worst %.2e over %d vertices, mean occlusion %.3f\n", worst, count, mean / count);
    EXPECT_LT(worst, 1e-4);
    EXPECT_GT(mean / count, 0.01);
}

// ---------------------------------------------------------------- element passes

namespace {

// The vertex of `m` nearest to q.
std::size_t nearest_vertex(const Mesh& m, const V& q) {
    std::size_t best = 0;
    for (std::size_t v = 1; v < m.positions.size(); ++v)
        if (glm::length(V(m.positions[v]) - q) < glm::length(V(m.positions[best]) - q)) best = v;
    return best;
}

} // namespace

// Convergence inside a closed box (walls facing inwards, side 2, 12 x 12
// cells a wall): receivers at the centre of the floor, near an edge and near
// a corner, against the Embree reference (4096 rays: standard error <=
// 0.008) at the same points.
// - R = 10 (beyond the box: every ray hits a wall, exact AO = 0): the passes
//   alternate between "everything occluded" and "nothing occluded" (the
//   2-cycle of Bunnell's iteration on a closed scene: x' = 1 - x with the
//   walls' form factors adding up to 1, decaying slowly towards its fixed
//   point 0.5: measured leaf AO 0, 0.93, 0.01, 0.89, 0.05, 0.85); the blend
//   of the last two is nearly the same whichever pass ends (within 0.03
//   from 2 to 6 passes, measured 0.028) but biased: the chapter's 0.7 / 0.3
//   weights leave AO near 0.3 where 0 is exact (docs/ao.md, limits).
// - R = 0.75 (occluders within R only: the floor's centre sees none, the
//   edge and corner some): stable from 2 to 6 passes within 0.03; the first
//   pass (no modulation) equals Embree within 0.02 (the walls do not overlap
//   as seen from the receiver, so the plain sum of form factors is exact),
//   and the modulated passes overestimate AO: within 0.14 of Embree
//   (measured 0.125 at the corner).
// Without element passes (DiskAoSettings' default) the gather's clamped sum
// is within 0.03 of Embree at every receiver for both radii.
TEST(DiskElementPasses, ClosedBoxConvergence) {
    const Mesh m = box(1.0, 12, true);
    const DiskHierarchy h = build_disk_hierarchy(m);
    const AoReference reference({&m});
    const std::vector<V> targets = {V(0, 0, -1), V(0.9, 0, -1), V(0.9, 0.9, -1)};
    for (const double R : {10.0, 0.75}) {
        AoReferenceOptions opt;
        opt.radius_mm = R;
        opt.rays = 4096;
        DiskAoSettings s;
        s.passes = 6;
        std::vector<std::vector<float>> per_pass;
        disk_element_passes(h, s, R, &per_pass);
        ASSERT_EQ(per_pass.size(), 6u);
        for (const V& target : targets) {
            const std::size_t v = nearest_vertex(m, target);
            const V p(m.positions[v]), n(m.normals[v]);
            const auto leaf = static_cast<std::size_t>(h.vertex_node[v]);
            const double exact = reference.at(p, n, opt);
            std::printf("R %.2f at (%.1f %.1f %.1f): Embree %.3f; passes' leaf AO", R, target.x, target.y, target.z,
                        exact);
            for (const auto& t : per_pass) std::printf(" %.3f", t[leaf]);
            std::printf("; blended + gather:");
            std::vector<double> finals;
            for (int k = 1; k <= 6; ++k) {
                DiskAoSettings sk = s;
                sk.passes = k;
                const auto terms = disk_element_terms(h, sk, R);
                finals.push_back(1.0 - disk_occlusion(h, p, n, terms, sk, R));
                std::printf(" %.3f", finals.back());
            }
            // No element passes (the default): the plain sum of form factors,
            // clamped: exact where the walls do not overlap in view and
            // where they fill it (R = 10: the clamp gives 0).
            DiskAoSettings s0 = s;
            s0.passes = 0;
            const double plain = 1.0 - disk_occlusion(h, p, n, disk_element_terms(h, s0, R), s0, R);
            std::printf("; no passes: %.3f\n", plain);
            EXPECT_NEAR(plain, exact, 0.03);
            for (int k = 2; k < 6; ++k) EXPECT_NEAR(finals[k], finals[1], 0.03) << "passes " << k + 1;
            if (R > 5) {
                // The 2-cycle: odd passes ~all occluded, even ~open.
                for (int k = 0; k < 6; k += 2) {
                    EXPECT_LT(per_pass[k][leaf], 0.1f) << k;
                    EXPECT_GT(per_pass[k + 1][leaf], 0.7f) << k;
                }
                EXPECT_LT(exact, 0.01);
                EXPECT_NEAR(finals[1], 0.3, 0.1);
            } else {
                EXPECT_NEAR(per_pass[0][leaf], exact, 0.02);
                EXPECT_NEAR(finals[1], exact, 0.14);
                EXPECT_GE(finals[1], exact - 0.02);
            }
        }
    }
}

// A receiver on the inside of the surface (its normal against its
// triangles' winding, as interpolated normals of thin marching-cubes
// structures are): inside a box whose walls face outwards, the ray-traced
// reference sees the walls' back faces. disk_occlusion (front faces only)
// sees nothing; disk_occlusion_sided, told the receiver's geometric normal,
// counts back faces and matches Embree (4096 rays) within 0.03 as the
// front-facing gather does in the mirrored box (ClosedBoxConvergence). A
// receiver on the outside gets exactly disk_occlusion.
TEST(DiskOcclusion, SidedReceiverInsideTheSolid) {
    const Mesh m = box(1.0, 12, false);
    const DiskHierarchy h = build_disk_hierarchy(m);
    const AoReference reference({&m});
    DiskAoSettings s;
    for (const double R : {10.0, 0.75})
        for (const V& target : {V(0, 0, -1), V(0.9, 0, -1), V(0.9, 0.9, -1)}) {
            const std::size_t v = nearest_vertex(m, target);
            const V p(m.positions[v]), face(0, 0, -1), n(0, 0, 1); // floor: outward -z, receiver normal into the box
            AoReferenceOptions opt;
            opt.radius_mm = R;
            opt.rays = 4096;
            const double exact = reference.at(p, n, opt);
            const double front = 1.0 - disk_occlusion(h, p, n, {}, s, R);
            const double sided = 1.0 - disk_occlusion_sided(h, p, n, face, {}, s, R);
            std::printf("outward box, R %.2f at (%.1f %.1f %.1f): Embree %.3f, front faces %.3f, sided %.3f\n", R,
                        target.x, target.y, target.z, exact, front, sided);
            EXPECT_EQ(front, 1.0);
            EXPECT_NEAR(sided, exact, 0.03);
        }
    // Outside: the same as disk_occlusion, bit for bit.
    const Mesh ball = sphere(V(0, 0, -2.5), 1.0, 24, 12);
    const DiskHierarchy hb = build_disk_hierarchy(ball);
    const DiskHierarchy both = concatenate({&h, &hb});
    const V p(0.2, 0.1, -1.0), n = glm::normalize(V(0.1, 0, -1));
    EXPECT_GT(disk_occlusion(both, p, n, {}, s, 5.0), 0.01);
    EXPECT_EQ(disk_occlusion_sided(both, p, n, V(0, 0, -1), {}, s, 5.0), disk_occlusion(both, p, n, {}, s, 5.0));
}
