// Disk hierarchy of disk-based AO (see disk_hierarchy.hpp; docs/ao.md,
// "Disk AO: hierarchy and CPU evaluation").
//
// The build runs once per surface on the CPU (double sums, float results in
// the GPU layout). The evaluation (disk_occlusion, disk_element_terms) is the
// model of the compute shaders, line by line: float arithmetic, the float
// instantiations of the kernels, a stackless traversal by skip pointers, no
// recursion. disk_occlusion_t<double> is the same code in double, kept for
// the float-against-double test only.
#include "renderer/ao/disk_hierarchy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <numbers>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "io/error.hpp"

namespace iso {

namespace {

// ---------------------------------------------------------------- build

struct Builder {
    const std::vector<glm::dvec3>& centre; // per vertex
    std::vector<std::int32_t>& order;      // referenced vertices, permuted by the splits
    std::vector<DiskNode>& nodes;
    std::vector<std::int32_t>& level;
    std::vector<std::int32_t>& leaf_vertex; // node -> vertex (-1 parent)

    // Splits order[lo, hi) at its median along the longest axis of the
    // centres' bounding box; returns the split position.
    std::size_t split(std::size_t lo, std::size_t hi) {
        glm::dvec3 mn(std::numeric_limits<double>::max()), mx(-std::numeric_limits<double>::max());
        for (std::size_t i = lo; i < hi; ++i) {
            mn = glm::min(mn, centre[order[i]]);
            mx = glm::max(mx, centre[order[i]]);
        }
        const glm::dvec3 ext = mx - mn;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const std::size_t mid = lo + (hi - lo) / 2;
        // Ties broken by vertex index: the build is deterministic.
        std::nth_element(order.begin() + lo, order.begin() + mid, order.begin() + hi,
                         [&](std::int32_t a, std::int32_t b) {
                             const double ca = centre[a][axis], cb = centre[b][axis];
                             return ca < cb || (ca == cb && a < b);
                         });
        return mid;
    }

    // Pre-order: the node's index is taken before its children are built, so
    // the first child is index + 1 and skip is the size after the subtree.
    // Recursion depth is log2 of the vertex count (median splits).
    void build(std::size_t lo, std::size_t hi, int depth) {
        const auto index = static_cast<std::int32_t>(nodes.size());
        nodes.emplace_back();
        level.push_back(depth);
        if (hi - lo == 1) {
            leaf_vertex.push_back(order[lo]);
            nodes[index].links = glm::ivec4(index + 1, -1, 0, 0);
            return;
        }
        leaf_vertex.push_back(-1);
        // Up to 4 children: the median split, then each half's own median
        // split (on its own longest axis) when it has two or more leaves.
        std::size_t cuts[5];
        int count = 0;
        const std::size_t mid = split(lo, hi);
        cuts[count++] = lo;
        if (mid - lo >= 2) cuts[count++] = split(lo, mid);
        cuts[count++] = mid;
        if (hi - mid >= 2) cuts[count++] = split(mid, hi);
        cuts[count] = hi;
        for (int c = 0; c < count; ++c) build(cuts[c], cuts[c + 1], depth + 1);
        nodes[index].links = glm::ivec4(static_cast<std::int32_t>(nodes.size()), index + 1, 0, 0);
    }
};

constexpr const char* kBuildWhere = "disk AO hierarchy";

// Throws for a mesh without triangles, a non-finite vertex or a triangle
// that names a missing vertex.
void check_mesh(const Mesh& mesh) {
    if (mesh.triangles.empty()) throw Error(kBuildWhere, "the mesh has no triangles");
    const std::size_t nv = mesh.positions.size();
    for (std::size_t i = 0; i < nv; ++i) {
        const glm::vec3& q = mesh.positions[i];
        if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
            throw Error(kBuildWhere, "vertex " + std::to_string(i) + " has a non-finite position");
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (const std::uint32_t v : mesh.triangles[t])
            if (v >= nv)
                throw Error(kBuildWhere, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                                             " of " + std::to_string(nv));
}

// The leaves' disks, per vertex: centre, area and unit normal (zero: no
// direction); and the vertices that triangles reference, in index order.
struct VertexDisks {
    std::vector<double> area;
    std::vector<glm::dvec3> centre, normal;
    std::vector<std::int32_t> order;
};

// A third of the adjacent triangles' areas; the mesh's normal where it has
// a usable one, else the area-weighted face normal. Double sums.
VertexDisks vertex_disks(const Mesh& mesh) {
    const std::size_t nv = mesh.positions.size();
    const bool has_normals = mesh.normals.size() == nv;
    VertexDisks d{
        std::vector<double>(nv, 0.0), std::vector<glm::dvec3>(nv), std::vector<glm::dvec3>(nv, glm::dvec3(0.0)), {}};
    std::vector<glm::dvec3> face_normal(nv, glm::dvec3(0.0));
    std::vector<char> referenced(nv, 0);
    for (const auto& tri : mesh.triangles) {
        const glm::dvec3 a(mesh.positions[tri[0]]), b(mesh.positions[tri[1]]), c(mesh.positions[tri[2]]);
        const glm::dvec3 cr = glm::cross(b - a, c - a); // 2 x area x unit normal
        const double tri_area = 0.5 * glm::length(cr);
        for (const std::uint32_t v : tri) {
            d.area[v] += tri_area / 3.0;
            face_normal[v] += 0.5 * cr;
            referenced[v] = 1;
        }
    }
    d.order.reserve(nv);
    for (std::size_t v = 0; v < nv; ++v) {
        d.centre[v] = glm::dvec3(mesh.positions[v]);
        if (!referenced[v]) continue;
        d.order.push_back(static_cast<std::int32_t>(v));
        glm::dvec3 nn(0.0);
        if (has_normals) {
            nn = glm::dvec3(mesh.normals[v]);
            if (!std::isfinite(nn.x) || !std::isfinite(nn.y) || !std::isfinite(nn.z)) nn = glm::dvec3(0.0);
        }
        if (glm::dot(nn, nn) < 1e-24) nn = face_normal[v];
        const double l = glm::length(nn);
        d.normal[v] = l > 1e-300 ? nn / l : glm::dvec3(0.0); // zero: no direction (all adjacent triangles degenerate)
    }
    return d;
}

// Triangles: each owned by the leaf of its first corner (any corner's leaf
// lies on the triangle, and a fixed rule needs no search), grouped by
// owning leaf in node order into h.triangles. Counting sort; returns the
// offsets: node i owns triangles [owned[i], owned[i + 1]).
std::vector<std::int32_t> own_triangles(const Mesh& mesh, DiskHierarchy& h) {
    const auto node_count = static_cast<std::int32_t>(h.nodes.size());
    std::vector<std::int32_t> owned(static_cast<std::size_t>(node_count) + 1, 0);
    for (const auto& tri : mesh.triangles) ++owned[static_cast<std::size_t>(h.vertex_node[tri[0]]) + 1];
    for (std::int32_t i = 0; i < node_count; ++i)
        owned[static_cast<std::size_t>(i) + 1] += owned[static_cast<std::size_t>(i)];
    std::vector<std::int32_t> cursor(owned.begin(), owned.end() - 1);
    h.triangles.assign(3 * mesh.triangles.size(), glm::vec4(0.0f));
    for (const auto& tri : mesh.triangles) {
        const auto slot = static_cast<std::size_t>(cursor[static_cast<std::size_t>(h.vertex_node[tri[0]])]++);
        for (int k = 0; k < 3; ++k)
            h.triangles[3 * slot + static_cast<std::size_t>(k)] = glm::vec4(mesh.positions[tri[k]], 0.0f);
    }
    return owned;
}

// Leaves: centre, area, normal; bound = the farther of the disk's rim and
// its owned triangles' corners (so a subtree's bound holds its triangles
// too, which the R test relies on). Returns each node's reach (leaves only;
// 0 for parents).
std::vector<double> fill_leaves(const VertexDisks& d, const std::vector<std::int32_t>& leaf_vertex,
                                const std::vector<std::int32_t>& owned, DiskHierarchy& h) {
    const auto node_count = static_cast<std::int32_t>(h.nodes.size());
    std::vector<double> leaf_reach(static_cast<std::size_t>(node_count), 0.0);
    for (std::int32_t i = 0; i < node_count; ++i) {
        const auto iu = static_cast<std::size_t>(i);
        const std::int32_t v = leaf_vertex[iu];
        if (v < 0) continue;
        const auto vu = static_cast<std::size_t>(v);
        DiskNode& node = h.nodes[iu];
        double reach = std::sqrt(d.area[vu] / std::numbers::pi);
        const std::int32_t first = owned[iu], end = owned[iu + 1];
        for (std::int32_t t = first; t < end; ++t)
            for (int k = 0; k < 3; ++k)
                reach = std::max(
                    reach,
                    glm::length(glm::dvec3(glm::vec3(
                                    h.triangles[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(k)])) -
                                d.centre[vu]));
        leaf_reach[iu] = reach;
        node.centre_area = glm::vec4(glm::vec3(d.centre[vu]), static_cast<float>(d.area[vu]));
        node.normal_bound = glm::vec4(glm::vec3(d.normal[vu]), static_cast<float>(reach));
        node.links.z = first;
        node.links.w = end - first;
    }
    return leaf_reach;
}

// Parents, children before parents (reverse pre-order): area-weighted
// centre and normal sums in double over the children's sums; plain mean
// of the leaves' centres when the subtree has no area.
void fill_parents(const VertexDisks& d, const std::vector<std::int32_t>& leaf_vertex,
                  const std::vector<double>& leaf_reach, DiskHierarchy& h) {
    const auto node_count = static_cast<std::int32_t>(h.nodes.size());
    std::vector<glm::dvec3> sum_c(static_cast<std::size_t>(node_count)), sum_n(static_cast<std::size_t>(node_count)),
        sum_plain(static_cast<std::size_t>(node_count));
    std::vector<double> sum_a(static_cast<std::size_t>(node_count)), leaves(static_cast<std::size_t>(node_count));
    for (std::int32_t i = node_count - 1; i >= 0; --i) {
        const auto iu = static_cast<std::size_t>(i);
        DiskNode& node = h.nodes[iu];
        const std::int32_t v = leaf_vertex[iu];
        if (v >= 0) {
            const auto vu = static_cast<std::size_t>(v);
            sum_a[iu] = d.area[vu];
            sum_c[iu] = d.area[vu] * d.centre[vu];
            sum_n[iu] = d.area[vu] * d.normal[vu];
            sum_plain[iu] = d.centre[vu];
            leaves[iu] = 1.0;
            continue;
        }
        glm::dvec3 c(0.0), nn(0.0), plain(0.0);
        double a = 0.0, l = 0.0;
        for (std::int32_t ch = node.links.y; ch < node.links.x; ch = h.nodes[static_cast<std::size_t>(ch)].links.x) {
            const auto cu = static_cast<std::size_t>(ch);
            c += sum_c[cu];
            nn += sum_n[cu];
            a += sum_a[cu];
            plain += sum_plain[cu];
            l += leaves[cu];
        }
        sum_c[iu] = c;
        sum_n[iu] = nn;
        sum_a[iu] = a;
        sum_plain[iu] = plain;
        leaves[iu] = l;
        const glm::dvec3 centre_p = a > 0.0 ? c / a : plain / l;
        const double nl = glm::length(nn);
        // Zero when the leaves' normals cancel (a closed surface's root).
        const glm::dvec3 normal_p = nl > 1e-12 * std::max(a, 1e-300) ? nn / nl : glm::dvec3(0.0);
        // Bound: the farthest leaf reach below, over the leaves of the
        // subtree (exact, not the looser sphere-of-spheres). The float
        // centre is the one stored, so the bound holds in float too; the
        // 1 + 1e-6 covers float rounding of the stored radius.
        const glm::dvec3 centre_f = glm::dvec3(glm::vec3(centre_p));
        double bound = 0.0;
        for (std::int32_t j = i + 1; j < node.links.x; ++j) {
            const auto ju = static_cast<std::size_t>(j);
            if (leaf_vertex[ju] < 0) continue;
            bound =
                std::max(bound, glm::length(glm::dvec3(glm::vec3(d.centre[static_cast<std::size_t>(leaf_vertex[ju])])) -
                                            centre_f) +
                                    leaf_reach[ju]);
        }
        node.centre_area = glm::vec4(glm::vec3(centre_p), static_cast<float>(a));
        node.normal_bound = glm::vec4(glm::vec3(normal_p), static_cast<float>(bound * (1.0 + 1e-6)));
    }
}

// ---------------------------------------------------------------- evaluation

// The traversal for one receiver, in T (float: the shader; double: the test
// reference). Each line maps onto the GLSL of the gather shader.
// side: +1 front faces occlude (a receiver outside the solid), -1 back faces
// (a receiver whose normal points into the solid; disk_occlusion_sided).
template <typename T>
T disk_occlusion_t(const DiskHierarchy& h, const glm::vec<3, T>& p_in, const glm::vec<3, T>& n,
                   const std::vector<float>& node_term, const DiskAoSettings& s, T radius, T side = T(1)) {
    using V = glm::vec<3, T>;
    const T R = std::max(radius, T(0));
    const T R2 = R * R;
    const T eps = T(s.traversal_epsilon);
    const T k = T(s.distance_attenuation);
    const T t = T(s.triangle_attenuation);
    const T clip_eps = T(s.clip_epsilon);
    const bool modulate = !node_term.empty();
    // Self-occlusion: receiver raised along its normal (DiskAoSettings::receiver_offset).
    const V p = p_in + T(s.receiver_offset) * R * n;

    T occlusion = T(0);
    const auto count = static_cast<std::int32_t>(h.nodes.size());
    std::int32_t i = 0;
    while (i < count) {
        const DiskNode& node = h.nodes[static_cast<std::size_t>(i)];
        const V c(node.centre_area.x, node.centre_area.y, node.centre_area.z);
        const T area = T(node.centre_area.w);
        const V m(node.normal_bound.x, node.normal_bound.y, node.normal_bound.z);
        const T bound = T(node.normal_bound.w);
        const std::int32_t skip = node.links.x;
        const std::int32_t child = node.links.y;
        const V v = c - p;
        const T d2 = glm::dot(v, v);
        // Wholly beyond R: nothing below can occlude.
        if (d2 >= (R + bound) * (R + bound)) {
            i = skip;
            continue;
        }
        const T term = modulate ? T(node_term[static_cast<std::size_t>(i)]) : T(1);
        const T modulation = triangle_attenuation(term, t);
        const bool near = d2 < eps * area;
        if (child >= 0) {
            // A parent is used as one disk only when far (d^2 >= eps A) and
            // wholly within R; near or straddling R: its children.
            const bool inside = bound <= R && d2 <= (R - bound) * (R - bound);
            if (near || !inside) {
                i = child;
                continue;
            }
            occlusion += disk_form_factor(p, n, c, side * m, area) * modulation * distance_attenuation(d2, k);
            i = skip;
            continue;
        }
        if (near) {
            // Its triangles, clipped to the tangent plane, exact form factor;
            // front faces only (like the disks); each counted when its
            // centroid is within R.
            const std::int32_t first = node.links.z;
            const std::int32_t end = first + node.links.w;
            for (std::int32_t tri = first; tri < end; ++tri) {
                const glm::vec4& a = h.triangles[static_cast<std::size_t>(3 * tri)];
                const glm::vec4& b = h.triangles[static_cast<std::size_t>(3 * tri + 1)];
                const glm::vec4& e = h.triangles[static_cast<std::size_t>(3 * tri + 2)];
                const V v0(a.x, a.y, a.z), v1(b.x, b.y, b.z), v2(e.x, e.y, e.z);
                const V g = (v0 + v1 + v2) * (T(1) / T(3)) - p;
                const T g2 = glm::dot(g, g);
                if (g2 > R2) continue;
                const T ff = std::max(side * clipped_triangle_form_factor(p, n, v0, v1, v2, clip_eps), T(0));
                occlusion += ff * modulation * distance_attenuation(g2, k);
            }
        } else if (d2 <= R2) {
            occlusion += disk_form_factor(p, n, c, side * m, area) * modulation * distance_attenuation(d2, k);
        }
        i = skip;
    }
    return std::clamp(occlusion, T(0), T(1));
}

// Parents' terms: area-weighted mean of their leaves' terms (plain mean of
// the leaves when the area is 0). Children are visited by skip pointers from
// first child to the parent's skip; nodes in reverse pre-order, so children
// are done before their parent. Sums in double (CPU only: the GPU does this
// level by level with node_level).
void fill_parent_terms(const DiskHierarchy& h, std::vector<float>& term, std::vector<double>& weight_sum,
                       std::vector<double>& leaf_count) {
    const auto n = static_cast<std::int32_t>(h.nodes.size());
    for (std::int32_t i = n - 1; i >= 0; --i) {
        const DiskNode& node = h.nodes[static_cast<std::size_t>(i)];
        if (node.links.y < 0) {
            weight_sum[static_cast<std::size_t>(i)] = node.centre_area.w;
            leaf_count[static_cast<std::size_t>(i)] = 1.0;
            continue;
        }
        double area = 0.0, weighted = 0.0, leaves = 0.0, plain = 0.0;
        for (std::int32_t c = node.links.y; c < node.links.x; c = h.nodes[static_cast<std::size_t>(c)].links.x) {
            const auto cu = static_cast<std::size_t>(c);
            area += weight_sum[cu];
            weighted += weight_sum[cu] * term[cu];
            leaves += leaf_count[cu];
            plain += leaf_count[cu] * term[cu];
        }
        weight_sum[static_cast<std::size_t>(i)] = area;
        leaf_count[static_cast<std::size_t>(i)] = leaves;
        term[static_cast<std::size_t>(i)] =
            static_cast<float>(area > 0.0 ? weighted / area : (leaves > 0.0 ? plain / leaves : 1.0));
    }
}

} // namespace

DiskHierarchy build_disk_hierarchy(const Mesh& mesh) {
    check_mesh(mesh);
    VertexDisks disks = vertex_disks(mesh);
    DiskHierarchy h;
    std::vector<std::int32_t> leaf_vertex; // node -> vertex (-1: a parent)
    h.nodes.reserve(2 * disks.order.size());
    Builder builder{disks.centre, disks.order, h.nodes, h.node_level, leaf_vertex};
    builder.build(0, disks.order.size(), 0);
    h.vertex_node.assign(mesh.positions.size(), -1);
    for (std::size_t i = 0; i < h.nodes.size(); ++i)
        if (leaf_vertex[i] >= 0) h.vertex_node[static_cast<std::size_t>(leaf_vertex[i])] = static_cast<std::int32_t>(i);
    const std::vector<std::int32_t> owned = own_triangles(mesh, h);
    const std::vector<double> leaf_reach = fill_leaves(disks, leaf_vertex, owned, h);
    fill_parents(disks, leaf_vertex, leaf_reach, h);
    h.roots = {0};
    h.levels = 1 + *std::max_element(h.node_level.begin(), h.node_level.end());
    return h;
}

DiskHierarchy concatenate(const std::vector<const DiskHierarchy*>& parts) {
    DiskHierarchy out;
    for (std::size_t k = 0; k < parts.size(); ++k) {
        const DiskHierarchy* part = parts[k];
        if (part == nullptr) throw Error("disk AO hierarchy", "concatenate: part " + std::to_string(k) + " is null");
        const auto node_offset = static_cast<std::int32_t>(out.nodes.size());
        const auto tri_offset = static_cast<std::int32_t>(out.triangles.size() / 3);
        for (DiskNode node : part->nodes) {
            node.links.x += node_offset;
            if (node.links.y >= 0)
                node.links.y += node_offset;
            else
                node.links.z += tri_offset;
            out.nodes.push_back(node);
        }
        for (const std::int32_t r : part->roots) out.roots.push_back(r + node_offset);
        out.triangles.insert(out.triangles.end(), part->triangles.begin(), part->triangles.end());
        // Vertices of the parts one after another (the parts' meshes concatenated).
        for (const std::int32_t v : part->vertex_node) out.vertex_node.push_back(v < 0 ? -1 : v + node_offset);
        out.node_level.insert(out.node_level.end(), part->node_level.begin(), part->node_level.end());
        out.levels = std::max(out.levels, part->levels);
    }
    return out;
}

double disk_occlusion(const DiskHierarchy& h, const glm::dvec3& p, const glm::dvec3& n,
                      const std::vector<float>& node_term, const DiskAoSettings& s, double radius) {
    return static_cast<double>(
        disk_occlusion_t<float>(h, glm::vec3(p), glm::vec3(n), node_term, s, static_cast<float>(radius)));
}

double disk_occlusion_sided(const DiskHierarchy& h, const glm::dvec3& p, const glm::dvec3& n,
                            const glm::dvec3& face_normal, const std::vector<float>& node_term, const DiskAoSettings& s,
                            double radius) {
    const float side = glm::dot(glm::vec3(n), glm::vec3(face_normal)) < 0.0f ? -1.0f : 1.0f;
    return static_cast<double>(
        disk_occlusion_t<float>(h, glm::vec3(p), glm::vec3(n), node_term, s, static_cast<float>(radius), side));
}

double disk_occlusion_double(const DiskHierarchy& h, const glm::dvec3& p, const glm::dvec3& n,
                             const std::vector<float>& node_term, const DiskAoSettings& s, double radius) {
    return disk_occlusion_t<double>(h, p, n, node_term, s, radius);
}

std::vector<float> disk_element_passes(const DiskHierarchy& h, const DiskAoSettings& s, double radius,
                                       std::vector<std::vector<float>>* per_pass) {
    const std::size_t n = h.nodes.size();
    std::vector<std::int32_t> leaves;
    for (std::size_t i = 0; i < n; ++i)
        if (h.nodes[i].links.y < 0) leaves.push_back(static_cast<std::int32_t>(i));
    std::vector<double> weight(n), count(n);
    // No element passes: every term 1, the gather is the plain (clamped) sum
    // of form factors.
    if (s.passes <= 0) return std::vector<float>(n, 1.0f);
    const int passes = s.passes;

    // Leaf occlusion of the last two passes (pass 1 unmodulated).
    std::vector<float> previous_occ(n, 0.0f), occ(n, 0.0f);
    std::vector<float> term; // empty: all 1, the first pass
    for (int pass = 0; pass < passes; ++pass) {
        previous_occ.swap(occ);
        tbb::parallel_for(std::size_t(0), leaves.size(), [&](std::size_t li) {
            const DiskNode& node = h.nodes[static_cast<std::size_t>(leaves[li])];
            const glm::vec3 c(node.centre_area), m(node.normal_bound);
            occ[static_cast<std::size_t>(leaves[li])] =
                static_cast<float>(disk_occlusion(h, glm::dvec3(c), glm::dvec3(m), term, s, radius));
        });
        term.assign(n, 1.0f);
        for (const std::int32_t l : leaves) term[static_cast<std::size_t>(l)] = 1.0f - occ[static_cast<std::size_t>(l)];
        fill_parent_terms(h, term, weight, count);
        if (per_pass) per_pass->push_back(term);
    }
    if (passes >= 2) {
        // The chapter's weighted minimum of the last two passes' occlusion.
        term.assign(n, 1.0f);
        for (const std::int32_t l : leaves) {
            const auto lu = static_cast<std::size_t>(l);
            const float o = converge_blend(previous_occ[lu], occ[lu], static_cast<float>(s.min_scale),
                                           static_cast<float>(s.max_scale));
            term[lu] = 1.0f - std::clamp(o, 0.0f, 1.0f);
        }
        fill_parent_terms(h, term, weight, count);
    }
    return term;
}

std::vector<float> disk_element_terms(const DiskHierarchy& h, const DiskAoSettings& s, double radius) {
    return disk_element_passes(h, s, radius, nullptr);
}

} // namespace iso
