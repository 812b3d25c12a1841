#include "renderer/core/pick.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include <glm/glm.hpp>

#include "io/error.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/surface/analysis.hpp"

namespace iso::core {

namespace {

struct Crossing {
    double t = 0;
    glm::dvec3 bary{0.0};
    bool inside = true;
};

// The ray against the triangle's plane, in double precision (Möller-Trumbore
// without the early outs): where it meets the plane and the barycentric
// coordinates there, so a ray the rasterizer gave to this triangle across
// an edge still lands on its plane, flagged.
std::optional<Crossing> cross_triangle(const Ray& ray, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(ray.dir, e2);
    const double det = glm::dot(e1, p);
    if (!(std::abs(det) > 1e-300)) return std::nullopt; // degenerate, or seen edge-on
    const glm::dvec3 s = ray.origin - a, q = glm::cross(s, e1);
    const double u = glm::dot(s, p) / det, v = glm::dot(ray.dir, q) / det;
    Crossing x;
    x.t = glm::dot(e2, q) / det;
    x.bary = {1.0 - u - v, u, v};
    x.inside = u >= 0 && v >= 0 && u + v <= 1;
    return x;
}

std::vector<double> column_major(const glm::dmat4& m) {
    std::vector<double> v;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) v.push_back(m[c][r]);
    return v;
}

void validate(const PickRequest& p, int width, int height) {
    if (p.x < 0 || p.y < 0 || p.x >= width || p.y >= height)
        throw Error("pick", "pixel " + std::to_string(p.x) + "," + std::to_string(p.y) + " is outside the " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
    if (!(p.threshold > 0.0 && p.threshold <= 1.0))
        throw Error("pick threshold", "expected a value in (0, 1], got " + std::to_string(p.threshold));
}

bool has_rect(const PickRequest& p) { return p.rect.width > 0 && p.rect.height > 0; }

// Where a click lands: the first fragment (front to back) whose surface's
// own opacity reaches the threshold, else the nearest one; none without
// fragments. Not the accumulated alpha: two translucent skins (0.3 each)
// reach 0.51 at the back of the head, and the click would land there
// (docs/picking.md, "Where a click lands").
// Unpickable surfaces are passed through.
const PickFragment* visible_fragment(const std::vector<PickFragment>& fragments, double threshold, const Scene& scene) {
    const PickFragment* nearest = nullptr;
    for (const PickFragment& f : fragments) {
        if (!scene.info(f.object).pickable) {
            if (f.alpha >= 1.0f) break;
            continue;
        }
        if (double(f.alpha) >= threshold) return &f;
        if (!nearest) nearest = &f;
    }
    return nearest;
}

} // namespace

PickRegion pick_region(const PickRequest& p) {
    // One region holds the pixel and the rectangle.
    int x0 = p.x, y0 = p.y, x1 = p.x + 1, y1 = p.y + 1;
    if (has_rect(p)) {
        x0 = std::min(x0, p.rect.x);
        y0 = std::min(y0, p.rect.y);
        x1 = std::max(x1, p.rect.x + p.rect.width);
        y1 = std::max(y1, p.rect.y + p.rect.height);
    }
    return PickRegion{x0, y0, x1 - x0, y1 - y0};
}

PickResult pick(Scene& scene, const RenderRequest& req, const PickRequest& p) {
    const gl::ScopedCurrent context;
    // One GL context serves every scene of the process: free this one's GPU
    // resources while it is current.
    struct Release {
        Scene& s;
        ~Release() { s.release_gpu(); }
    } release{scene};
    return pick_in_frame(scene, frame_camera(scene, req), frame_options(req), p);
}

PickResult pick_in_frame(Scene& scene, const Camera& camera, RenderOptions opt, const PickRequest& p) {
    validate(p, opt.width, opt.height);
    opt.pick = pick_region(p);
    opt.image = false; // the lists are the output: no lighting, VOIT resolve or read-back
    const auto t0 = std::chrono::steady_clock::now();
    const RenderResult frame = scene.render(camera, opt);
    PickResult out = resolve_pick(scene, camera, opt.width, opt.height, frame.pick, p, &opt.look);
    out.frame_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

PickResult resolve_pick(const Scene& scene, const Camera& camera, int width, int height, const PickList& list,
                        const PickRequest& p, const FrameLook* look) {
    validate(p, width, height);
    const bool rect = has_rect(p);
    PickResult out;
    out.x = p.x;
    out.y = p.y;
    out.width = width;
    out.height = height;
    out.view = camera.view();
    out.projection = camera.projection(double(width) / double(height));
    if (rect) {
        out.rect = {std::max(p.rect.x, 0), std::max(p.rect.y, 0), 0, 0};
        out.rect.width = std::max(std::min(p.rect.x + p.rect.width, width) - out.rect.x, 0);
        out.rect.height = std::max(std::min(p.rect.y + p.rect.height, height) - out.rect.y, 0);
    }
    // The list must hold what is asked: a frame rendered for another pick cannot answer this one.
    const auto holds = [&](int x, int y, int w, int h) {
        return x >= list.region.x && y >= list.region.y && x + w <= list.region.x + list.region.width &&
               y + h <= list.region.y + list.region.height;
    };
    if (list.pixels.size() !=
            std::size_t(std::max(list.region.width, 0)) * std::size_t(std::max(list.region.height, 0)) ||
        !holds(p.x, p.y, 1, 1) ||
        (out.rect.width > 0 && out.rect.height > 0 && !holds(out.rect.x, out.rect.y, out.rect.width, out.rect.height)))
        throw Error("pick", "the frame's pick lists (region " + std::to_string(list.region.x) + "," +
                                std::to_string(list.region.y) + " " + std::to_string(list.region.width) + "x" +
                                std::to_string(list.region.height) + ") do not cover pixel " + std::to_string(p.x) +
                                "," + std::to_string(p.y) + (rect ? " and its rectangle" : ""));
    out.complete = list.offered <= list.capacity;
    const auto at = [&](int x, int y) -> const std::vector<PickFragment>& {
        return list
            .pixels[std::size_t(y - list.region.y) * std::size_t(list.region.width) + std::size_t(x - list.region.x)];
    };
    // The pixel's layers: down to the first opaque one (nothing behind it
    // reaches the pixel), or to the visible one unless all are asked for.
    const Ray ray = camera.pixel_ray(p.x + 0.5, p.y + 0.5, width, height);
    const glm::dvec3 forward = camera.forward();
    const Volume* volume = scene.has_volume() ? &scene.volume() : nullptr;
    const std::vector<PickFragment>& fragments = at(p.x, p.y);
    // Where the click lands: the one rule, which the rectangle's pixels follow too.
    const PickFragment* seen = visible_fragment(fragments, p.threshold, scene);
    for (const PickFragment& f : fragments) {
        // An unpickable surface is drawn but passed through; an opaque one
        // still hides everything behind it.
        if (!scene.info(f.object).pickable) {
            if (f.alpha >= 1.0f) break;
            continue;
        }
        PickLayer l;
        l.surface = f.object;
        const SurfaceInfo& info = scene.info(f.object);
        l.name = info.name;
        l.kind = info.kind;
        l.surface_value = info.value;
        l.triangle = f.primitive;
        l.alpha = f.alpha;
        l.share = double(f.transmittance) * double(f.alpha);
        l.accumulated_alpha = 1.0 - double(f.transmittance) * (1.0 - double(f.alpha));
        const Mesh& mesh = scene.mesh(f.object);
        if (f.primitive >= mesh.triangles.size())
            throw Error("pick", "triangle " + std::to_string(f.primitive) + " is not in " + info.name);
        const auto& tri = mesh.triangles[f.primitive];
        const glm::dvec3 a(mesh.positions[tri[0]]), b(mesh.positions[tri[1]]), c(mesh.positions[tri[2]]);
        if (const auto x = cross_triangle(ray, a, b, c)) {
            l.lps = ray.origin + x->t * ray.dir;
            l.barycentric = x->bary;
            l.on_triangle = x->inside;
            l.depth_mm = x->t * glm::dot(ray.dir, forward);
        } else { // seen exactly edge-on: the triangle's centroid
            l.lps = (a + b + c) / 3.0;
            l.barycentric = glm::dvec3(1.0 / 3.0);
            l.on_triangle = false;
            l.depth_mm = glm::dot(l.lps - ray.origin, forward);
        }
        glm::dvec3 n = glm::cross(b - a, c - a);
        if (!mesh.normals.empty())
            n = l.barycentric.x * glm::dvec3(mesh.normals[tri[0]]) +
                l.barycentric.y * glm::dvec3(mesh.normals[tri[1]]) + l.barycentric.z * glm::dvec3(mesh.normals[tri[2]]);
        l.normal = glm::length(n) > 0 ? glm::normalize(n) : n;
        if (volume && info.kind != SurfaceInfo::Kind::Mesh)
            if (const auto s = sample_volume(*volume, l.lps)) {
                l.value = s->value;
                l.unit = value_unit(*volume);
                l.voxel = s->voxel;
            }
        if (&f == seen) out.visible = out.layers.size();
        out.layers.push_back(std::move(l));
        if (f.alpha >= 1.0f) break;
        // Without all_layers the list ends at a solid visible layer (with
        // only translucent ones it runs on: they are all seen through).
        if (&f == seen && double(f.alpha) >= p.threshold && !p.all_layers) break;
    }
    if (rect) {
        std::map<std::pair<SurfaceId, std::uint32_t>, std::size_t> seen;
        for (int y = out.rect.y; y < out.rect.y + out.rect.height; ++y)
            for (int x = out.rect.x; x < out.rect.x + out.rect.width; ++x) {
                // The pixel's visible layer, by the same rule.
                if (const PickFragment* f = visible_fragment(at(x, y), p.threshold, scene))
                    ++seen[{f->object, f->primitive}];
            }
        for (const auto& [k, n] : seen) out.triangles.push_back({k.first, k.second, n});
        std::stable_sort(out.triangles.begin(), out.triangles.end(),
                         [](const PickedTriangle& a, const PickedTriangle& b) { return a.pixels > b.pixels; });
    }
    if (look && look->volume.enabled && volume) add_volume_layer(out, scene, camera, list, p, *look);
    return out;
}

nlohmann::json pick_json(const PickResult& r) {
    using nlohmann::json;
    const auto vec = [](const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); };
    json layers = json::array();
    for (const auto& l : r.layers) {
        json j;
        j["layer"] = l.volume ? "volume" : "surface";
        j["surface"] = l.name;
        j["surface_id"] = l.surface;
        j["iso"] = l.kind == SurfaceInfo::Kind::Iso ? json(l.surface_value) : json(nullptr);
        if (l.kind == SurfaceInfo::Kind::Label) j["label"] = l.surface_value;
        j["lps"] = vec(l.lps);
        j["normal"] = vec(l.normal);
        j["triangle"] = l.triangle;
        j["on_triangle"] = l.on_triangle;
        j["depth_mm"] = l.depth_mm;
        j["alpha"] = l.alpha;
        j["share"] = l.share;
        j["value"] = l.value ? json(*l.value) : json(nullptr);
        j["unit"] = l.unit.empty() ? json(nullptr) : json(l.unit);
        j["voxel"] = l.voxel ? json::array({(*l.voxel)[0], (*l.voxel)[1], (*l.voxel)[2]}) : json(nullptr);
        layers.push_back(std::move(j));
    }
    json j;
    j["pixel"] = {r.x, r.y};
    j["image"] = {r.width, r.height};
    j["visible"] = r.visible ? json(*r.visible) : json(nullptr);
    j["layers"] = std::move(layers);
    j["view"] = column_major(r.view);
    j["projection"] = column_major(r.projection);
    j["coordinates"] = "LPS mm";
    j["complete"] = r.complete;
    if (r.rect.width > 0 && r.rect.height > 0) {
        json tris = json::array();
        for (const auto& t : r.triangles)
            tris.push_back({{"surface_id", t.surface}, {"triangle", t.triangle}, {"pixels", t.pixels}});
        j["rect"] = {{"x", r.rect.x},
                     {"y", r.rect.y},
                     {"width", r.rect.width},
                     {"height", r.rect.height},
                     {"triangles", std::move(tris)}};
    }
    j["frame_ms"] = r.frame_ms;
    return j;
}

} // namespace iso::core
