#include "renderer/core/structures.hpp"

#include <cmath>
#include <algorithm>
#include <fstream>
#include <limits>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>

#include "io/color.hpp"
#include "io/error.hpp"
#include "io/finite.hpp"
#include "renderer/core/surface_name.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/box_clip.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/voxelize.hpp"
#include "io/atomic_file.hpp"
#include "io/volume_io.hpp"
#include "renderer/surface/shape.hpp"
#include "renderer/surface/postprocess.hpp"

namespace iso::core {

namespace {

nlohmann::json vec(const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

// Where a structure is and how large across (surface/shape.hpp), into its JSON.
void add_shape(nlohmann::json& j, const Mesh& m, bool closed) {
    const ShapeMeasures shape = measure_shape(m, closed);
    j["centroid_lps"] = shape.solid ? vec(shape.centroid) : nlohmann::json(nullptr);
    j["largest_diameter_mm"] = shape.feret_mm;
    j["largest_diameter_points_lps"] = {vec(shape.feret_a), vec(shape.feret_b)};
}

const Mesh& surface_mesh(const Scene& scene, SurfaceId id, const char* what) {
    if (!scene.has_surface(id)) throw Error(what, "there is no surface " + std::to_string(id));
    const Mesh& m = scene.mesh(id);
    if (m.empty()) throw Error(what, scene.info(id).name + " has no triangles");
    return m;
}

// A hue for the n-th isolated component, apart from the skin-to-bone
// palette: saturated, distinct from each other (linear RGB).
glm::vec3 component_color(std::size_t n) {
    static const glm::vec3 kHues[] = {{0.80f, 0.10f, 0.08f}, {0.05f, 0.35f, 0.85f}, {0.10f, 0.60f, 0.12f},
                                      {0.75f, 0.35f, 0.02f}, {0.45f, 0.08f, 0.65f}, {0.02f, 0.55f, 0.55f}};
    return kHues[n % std::size(kHues)];
}

} // namespace

std::vector<SurfaceTree> surface_trees(const Scene& scene, std::vector<std::unique_ptr<TriangleBvh>>& keep) {
    std::vector<SurfaceTree> out;
    for (const SurfaceId id : scene.surfaces()) {
        const SurfaceInfo& info = scene.info(id);
        if (!info.visible || scene.mesh(id).empty()) continue;
        keep.push_back(std::make_unique<TriangleBvh>(scene.mesh(id)));
        out.push_back({id, info.name, keep.back().get(), double(info.opacity), info.pickable});
    }
    return out;
}

SurfacePoint surface_at(const std::vector<SurfaceTree>& trees, const glm::dvec3& lps) {
    if (!finite(lps)) throw Error("surface at a point", "the point is not finite");
    SurfacePoint best;
    best.distance_mm = std::numeric_limits<double>::infinity();
    for (const SurfaceTree& t : trees) {
        if (!t.pickable) continue;
        const NearestPoint n = nearest_point(*t.bvh, lps);
        if (n.distance_mm < best.distance_mm) best = {t.id, n.triangle, n.point, n.distance_mm};
    }
    if (!best.surface) throw Error("surface at a point", "the scene has no visible surface");
    return best;
}

SurfacePoint surface_at(const Scene& scene, const glm::dvec3& lps) {
    if (!finite(lps)) throw Error("surface at a point", "the point is not finite");
    std::vector<std::unique_ptr<TriangleBvh>> keep;
    return surface_at(surface_trees(scene, keep), lps);
}

ComponentPlan plan_component(const Scene& scene, SurfaceId surface, const glm::dvec3& at,
                             const std::optional<LpsBox>& within) {
    if (!finite(at)) throw Error("isolate", "the point is not finite");
    const Mesh& parent = surface_mesh(scene, surface, "isolate");
    const SurfaceInfo& info = scene.info(surface);
    const NearestComponent near = nearest_component(parent, at);
    ComponentPlan plan;
    plan.from = surface;
    plan.component = near.component;
    for (std::uint32_t c : near.triangle_component)
        if (c != std::numeric_limits<std::uint32_t>::max())
            plan.components = std::max<std::size_t>(plan.components, c + 1);
    plan.mesh = component_mesh(parent, near.triangle_component, near.component);
    // Recorded with the surface's post-processing, so that a session (or a
    // moved iso value) makes the same component again from the volume.
    // A part cut by steps already (Scissors): this isolation is one more step after them.
    plan.info = info;
    const bool after_steps = !info.post.steps.empty();
    if (after_steps)
        plan.info.post.steps.push_back(PartStep{within, near.nearest.point, std::nullopt});
    else
        plan.info.post.keep_at = near.nearest.point;
    plan.info.name = info.name + " component " + std::to_string(plan.component + 1);
    if (within) {
        plan.mesh = clip_to_box(plan.mesh, *within);
        // The cut may leave pieces of the component apart in the box: the one at the point.
        if (!plan.mesh.empty()) plan.mesh = component_at(plan.mesh, at);
        if (plan.mesh.empty())
            throw Error("isolate within a box", plan.info.name + " of " + info.name + " has no part within the box");
        if (!after_steps) plan.info.post.keep_within = within;
        plan.info.name += " within box";
    }
    std::size_t isolated = 0;
    for (const SurfaceId id : scene.surfaces()) isolated += kept_at(scene.info(id).post).has_value();
    // As a session stores it (8-bit sRGB), so that the colour on screen is the one saved.
    plan.info.color = linear_from_hex(hex_from_linear(component_color(isolated)));
    plan.info.opacity = 1.0f;
    plan.info.visible = plan.info.pickable = true;
    plan.measures = measure_surface_mesh(scene, plan.info, plan.mesh);
    return plan;
}

ComponentPlan plan_scissors(const Scene& scene, SurfaceId surface, const ScissorsRequest& r) {
    const Mesh& parent = surface_mesh(scene, surface, "scissors");
    if (r.width <= 0 || r.height <= 0) throw Error("scissors", "the view has no size");
    const double aspect = double(r.width) / double(r.height);
    const glm::dmat4 clip = r.camera.projection(aspect) * r.camera.view();
    // The view as the overlay projects and the pick casts rays (image pixels from the top-left).
    const ViewOutline view{r.outline, clip, r.camera.eye, r.width, r.height, r.keep_inside};
    const SurfaceInfo& info = scene.info(surface);
    ComponentPlan plan;
    plan.from = surface;
    plan.mesh = scissors_cut(parent, view).part;
    if (plan.mesh.empty())
        throw Error("scissors",
                    "nothing of " + info.name + " is " + (r.keep_inside ? "inside" : "outside") + " the outline");
    std::size_t cuts = 0, made = 0;
    for (const SurfaceId id : scene.surfaces()) {
        cuts += scene.info(id).name.find(" scissors ") != std::string::npos;
        made += kept_at(scene.info(id).post).has_value() || scene.info(id).kind == SurfaceInfo::Kind::Mesh;
    }
    // The parent's making with this cut after it: a session, or a moved
    // iso value, makes the same part again.
    plan.info = info;
    plan.info.post.steps.push_back(PartStep{std::nullopt, std::nullopt, view});
    plan.info.name = info.name + " scissors " + std::to_string(cuts + 1);
    plan.info.color = linear_from_hex(hex_from_linear(component_color(made + 5)));
    plan.info.opacity = 1.0f;
    plan.info.visible = plan.info.pickable = true;
    plan.measures = measure_surface_mesh(scene, plan.info, plan.mesh);
    return plan;
}

IsolatedComponent add_component(Scene& scene, ComponentPlan plan) {
    IsolatedComponent out;
    out.from = plan.from;
    out.component = plan.component;
    out.components = plan.components;
    out.measured.name = plan.info.name;
    out.measured.kind = plan.info.kind;
    out.measured.value = plan.info.value;
    out.measured.measures = std::move(plan.measures);
    out.surface = out.measured.surface = scene.add_mesh(std::move(plan.mesh), std::move(plan.info));
    return out;
}

IsolatedComponent isolate_component(Scene& scene, SurfaceId surface, const glm::dvec3& at,
                                    const std::optional<LpsBox>& within) {
    return add_component(scene, plan_component(scene, surface, at, within));
}

GrownPlan plan_grown(const Scene& scene, const glm::dvec3& seed, const GrowOptions& options,
                     const ProgressFn& progress) {
    if (!scene.has_volume()) throw Error("grow from a seed", "the input is a mesh: there is no volume to grow in");
    GrownPlan plan;
    GrownStructure& g = plan.grown;
    g.seed = seed;
    g.options = options;
    g.region = grow_region(scene.volume(), seed, options, progress);
    // Padded by a voxel of background all round, so that a region reaching
    // the volume's edge is closed there too (half a voxel beyond its last
    // centres, as its voxels count whole).
    const Volume& mask = g.region.mask;
    const std::array<std::int64_t, 3> d = mask.dims;
    Volume padded = Volume::dense({d[0] + 2, d[1] + 2, d[2] + 2}, VoxelType::U8,
                                  mask.index_to_lps * glm::translate(glm::dmat4(1.0), glm::dvec3(-1.0)));
    {
        const auto from = mask.as<std::uint8_t>();
        auto to = padded.as<std::uint8_t>();
        for (std::int64_t k = 0; k < d[2]; ++k)
            for (std::int64_t j = 0; j < d[1]; ++j)
                for (std::int64_t i = 0; i < d[0]; ++i)
                    to[padded.linear_index(i + 1, j + 1, k + 1)] = from[mask.linear_index(i, j, k)];
    }
    g.region.mask = Volume{};
    const double one = 1.0;
    std::vector<LabelSurface> surfaces = extract_labels(padded, std::span<const double>(&one, 1));
    if (surfaces.empty() || surfaces.front().mesh.empty())
        throw Error("grow from a seed", "the grown region has no surface");
    g.measures = measure_surface(surfaces.front().mesh);
    plan.mesh = std::move(surfaces.front().mesh);
    return plan;
}

SurfaceInfo grown_info(const Scene& scene, const GrownStructure& g) {
    std::size_t grown = 0;
    for (const SurfaceId id : scene.surfaces()) grown += scene.info(id).name.rfind("grown ", 0) == 0;
    SurfaceInfo info;
    info.kind = SurfaceInfo::Kind::Mesh;
    info.name = "grown " + std::to_string(grown + 1);
    info.color = linear_from_hex(hex_from_linear(component_color(grown + 3)));
    info.grown = GrownFrom{g.seed, g.options};
    return info;
}

GrownStructure grow_structure(Scene& scene, const glm::dvec3& seed, const GrowOptions& options,
                              const ProgressFn& progress) {
    GrownPlan plan = plan_grown(scene, seed, options, progress);
    plan.grown.surface = scene.add_mesh(std::move(plan.mesh), grown_info(scene, plan.grown));
    return std::move(plan.grown);
}

nlohmann::json grown_json(const Scene& scene, const GrownStructure& g) {
    const SurfaceMeasures& m = g.measures;
    nlohmann::json j{{"surface", scene.info(g.surface).name},
                     {"seed_lps", vec(g.seed)},
                     {"seed_voxel", {g.region.seed[0], g.region.seed[1], g.region.seed[2]}},
                     {"range", {g.options.lo, g.options.hi}},
                     {"voxels", g.region.voxels},
                     {"boundary_voxels", g.region.boundary_voxels},
                     {"volume_ml", g.region.volume_ml},
                     {"partial_volume_ml", g.region.partial_volume_ml},
                     {"reached_box", g.region.reached_box},
                     {"reached_volume_border", g.region.reached_border},
                     {"surface_area_mm2", m.area_mm2},
                     {"surface_volume_ml", std::abs(m.volume_ml)},
                     {"closed", m.closed}};
    add_shape(j, scene.mesh(g.surface), m.closed);
    j["within"] = g.options.within ? nlohmann::json{vec(g.options.within->lo), vec(g.options.within->hi)}
                                   : nlohmann::json(nullptr);
    return j;
}

LabelMap structures_label_map(const Scene& scene, const std::vector<SurfaceId>& surfaces) {
    if (!scene.has_volume()) throw Error("label map", "the input is a mesh: there is no voxel grid to label");
    if (surfaces.size() > 65535) throw Error("label map", "more than 65535 structures");
    const Volume& v = scene.volume();
    LabelMap out;
    out.labels = Volume::dense(v.dims, VoxelType::U16, v.index_to_lps);
    out.labels.meta.source = v.meta.source;
    auto labels = out.labels.as<std::uint16_t>();
    for (std::size_t k = 0; k < surfaces.size(); ++k) {
        const SurfaceId id = surfaces[k];
        const Mesh& m = surface_mesh(scene, id, "label map");
        LabelMapEntry e{id, std::uint16_t(k + 1), scene.info(id).name, scene.info(id).color, 0};
        e.voxels = voxelize(m, v.index_to_lps, v.dims, labels, e.label);
        out.entries.push_back(e);
    }
    return out;
}

std::string label_map_table(const std::string& path, const std::string& what) {
    for (const std::string ext : {".nii", ".nii.gz"})
        if (path.ends_with(ext)) return path.substr(0, path.size() - ext.size()) + ".ctbl";
    throw Error(what, "a label map is written as NIfTI (.nii or .nii.gz), got '" + path + "'");
}

std::string save_label_map(const LabelMap& m, const std::string& path) {
    const std::string table = label_map_table(path, path);
    save_volume(m.labels, path);
    write_atomically(table, [&](const std::string& tmp) {
        std::ofstream f(tmp);
        f << "# Color table file " << table << "\n# " << m.entries.size() + 1 << " values\n0 Background 0 0 0 0\n";
        for (const auto& e : m.entries) {
            std::string name = e.name;
            std::replace(name.begin(), name.end(), ' ', '_');
            const std::string hex = hex_from_linear(e.color); // #rrggbb, sRGB
            f << e.label << " " << name << " " << std::stoi(hex.substr(1, 2), nullptr, 16) << " "
              << std::stoi(hex.substr(3, 2), nullptr, 16) << " " << std::stoi(hex.substr(5, 2), nullptr, 16)
              << " 255\n";
        }
        if (!f.flush()) throw Error(table, "cannot write");
    });
    return table;
}

SurfaceGap surface_gap(const Scene& scene, SurfaceId a, SurfaceId b, const std::optional<glm::dvec3>& at_a,
                       const std::optional<glm::dvec3>& at_b) {
    const Mesh& ma = surface_mesh(scene, a, "surface distance");
    const Mesh& mb = surface_mesh(scene, b, "surface distance");
    SurfaceGap g;
    g.a = a;
    g.b = b;
    g.name_a = scene.info(a).name;
    g.name_b = scene.info(b).name;
    // One component of a surface: a hierarchy over its triangles only.
    const auto part = [](const Mesh& m, const std::optional<glm::dvec3>& at, std::string& name,
                         std::optional<std::size_t>& component) {
        if (!at) return TriangleBvh(m);
        if (!finite(*at)) throw Error("surface distance", "a component's point is not finite");
        const NearestComponent near = nearest_component(m, *at);
        std::vector<std::uint32_t> tris;
        for (std::uint32_t t = 0; t < near.triangle_component.size(); ++t)
            if (near.triangle_component[t] == near.component) tris.push_back(t);
        name += " component " + std::to_string(near.component + 1);
        component = near.component;
        return TriangleBvh(m, std::move(tris));
    };
    const TriangleBvh ba = part(ma, at_a, g.name_a, g.component_a), bb = part(mb, at_b, g.name_b, g.component_b);
    g.same_structure = a == b && g.component_a == g.component_b;
    g.distance = surface_distance(ba, bb);
    return g;
}

std::vector<LineCrossing> solid_crossings(const std::vector<SurfaceTree>& trees, const glm::dvec3& a,
                                          const glm::dvec3& b, double threshold, double end_tolerance_mm) {
    if (!finite(a) || !finite(b)) throw Error("line crossings", "a point is not finite");
    const double length = glm::length(b - a);
    std::vector<LineCrossing> out;
    for (const SurfaceTree& t : trees) {
        if (t.opacity < threshold) continue;
        double last = -1e300;
        for (const SegmentCrossing& c : segment_crossings(*t.bvh, a, b)) {
            const double along = c.t * length;
            if (along < end_tolerance_mm || along > length - end_tolerance_mm) continue;
            if (along - last < 1e-6) continue; // the same crossing through a shared edge
            last = along;
            out.push_back({t.id, t.name, a + c.t * (b - a), along});
        }
    }
    std::sort(out.begin(), out.end(),
              [](const LineCrossing& x, const LineCrossing& y) { return x.along_mm < y.along_mm; });
    return out;
}

std::vector<LineCrossing> solid_crossings(const Scene& scene, const glm::dvec3& a, const glm::dvec3& b,
                                          double threshold, double end_tolerance_mm) {
    if (!finite(a) || !finite(b)) throw Error("line crossings", "a point is not finite");
    std::vector<std::unique_ptr<TriangleBvh>> keep;
    return solid_crossings(surface_trees(scene, keep), a, b, threshold, end_tolerance_mm);
}

nlohmann::json gap_json(const SurfaceGap& g) {
    return {{"surfaces", {g.name_a, g.name_b}},
            {"distance_mm", g.distance.pair.distance_mm},
            {"points", {vec(g.distance.pair.a), vec(g.distance.pair.b)}},
            {"triangles", {g.distance.triangle_a, g.distance.triangle_b}},
            {"touching", g.distance.touching},
            {"same_structure", g.same_structure},
            {"triangle_pairs_measured", g.distance.triangle_pairs}};
}

nlohmann::json component_json(const Scene& scene, const IsolatedComponent& c) {
    nlohmann::json j = measure_json(scene, {c.measured}, {})["surfaces"][0];
    j["from"] = scene.info(c.from).name;
    j["component"] = c.component + 1;
    j["of_components"] = c.components;
    const auto& post = scene.info(c.surface).post;
    const auto at = kept_at(post);
    j["at"] = at ? vec(*at) : nlohmann::json(nullptr);
    // Where it is and how large across (surface/shape.hpp).
    add_shape(j, scene.mesh(c.surface), c.measured.measures.closed);
    if (post.keep_within) {
        const LpsBox& b = *post.keep_within;
        const auto caps = cap_areas(scene.mesh(c.surface), b);
        nlohmann::json cut = nlohmann::json::array();
        double total = 0;
        for (int f = 0; f < 6; ++f)
            if (caps[std::size_t(f)] > 0) {
                cut.push_back({{"face", box_face_name(f)}, {"cap_area_mm2", caps[std::size_t(f)]}});
                total += caps[std::size_t(f)];
            }
        j["within"] = {
            {"box_lps", {vec(b.lo), vec(b.hi)}}, {"cut", !cut.empty()}, {"faces_cut", cut}, {"cap_area_mm2", total}};
    }
    return j;
}

Markup gap_markup(const SurfaceGap& g) {
    Markup m;
    m.type = MarkupType::Line;
    m.name = g.name_a + " to " + g.name_b;
    MarkupControlPoint p;
    p.position = g.distance.pair.a;
    p.label = m.name + "-1";
    MarkupControlPoint q;
    q.position = g.distance.pair.b;
    q.label = m.name + "-2";
    m.points = {p, q};
    if (auto c = computed_measurement(m)) m.measurements.push_back(*c);
    return m;
}

bool is_part(const SurfaceInfo& info) {
    return info.post.keep_at || info.post.keep_within || !info.post.steps.empty() || info.grown;
}

nlohmann::json part_json(const Scene& scene, SurfaceId id, bool closed) {
    const SurfaceInfo& info = scene.info(id);
    const PostProcessOptions& post = info.post;
    if (!is_part(info)) return nullptr;
    nlohmann::json made = nlohmann::json::array();
    const auto box = [](const LpsBox& b) { return nlohmann::json{vec(b.lo), vec(b.hi)}; };
    if (post.keep_at) made.push_back({{"component_at", vec(*post.keep_at)}});
    if (post.keep_within) made.push_back({{"within_box", box(*post.keep_within)}});
    for (const PartStep& st : post.steps) {
        if (st.within) made.push_back({{"within_box", box(*st.within)}});
        if (st.keep_at) made.push_back({{"component_at", vec(*st.keep_at)}});
        if (st.outline)
            made.push_back({{st.outline->keep_inside ? "scissors_inside" : "scissors_outside",
                             {{"corners", st.outline->outline.size()},
                              {"image_size", {st.outline->width, st.outline->height}},
                              {"eye_lps", vec(st.outline->eye)}}}});
    }
    nlohmann::json j{{"surface", info.name}, {"made", made}};
    if (info.grown) {
        j["grown_from"] = vec(info.grown->seed);
        j["grown_range"] = {info.grown->options.lo, info.grown->options.hi};
    }
    add_shape(j, scene.mesh(id), closed);
    return j;
}

} // namespace iso::core
