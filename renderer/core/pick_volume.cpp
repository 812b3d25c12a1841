// The volume's layer of a pick (pick.hpp, add_volume_layer): the pixel's
// ray marched on the CPU through the stated model with the frame's surfaces
// at their depths, as the GPU composites them.
#include <algorithm>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/core/pick.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/volume/reference.hpp"

namespace iso::core {

void add_volume_layer(PickResult& r, const Scene& scene, const Camera& camera, const PickList& list,
                      const PickRequest& p, const FrameLook& look) {
    if (!look.volume.enabled || !scene.has_volume()) return;
    const Volume& v = scene.volume();
    const Ray ray = camera.pixel_ray(p.x + 0.5, p.y + 0.5, r.width, r.height);
    const double cosine = glm::dot(ray.dir, camera.forward());
    // The pixel's surfaces, each at its ray distance: the volume is cut
    // into pieces between them and ends at the first opaque one.
    std::vector<RayLayer> layers;
    const auto& fragments = list.pixels[std::size_t(p.y - list.region.y) * std::size_t(list.region.width) +
                                        std::size_t(p.x - list.region.x)];
    for (const PickFragment& f : fragments) {
        layers.push_back({camera.linear_depth(f.depth) / cosine, glm::dvec3(0.0), double(f.alpha)});
        if (f.alpha >= 1.0f) break;
    }
    const VolumeSampler sampler(v, scene.value_range());
    const double step = look.volume.step * sampler.min_spacing();
    const RayResult m = march_ray(sampler, look.volume, look.clip, ray.origin, ray.dir, camera.near_plane / cosine,
                                  camera.far_plane / cosine, layers, step);
    if (!m.t_half) return;
    PickLayer l;
    l.volume = true;
    l.name = "volume";
    l.lps = ray.origin + *m.t_half * ray.dir;
    l.depth_mm = *m.t_half * cosine;
    l.alpha = 0.5;
    l.accumulated_alpha = 0.5;
    l.on_triangle = false;
    if (const auto s = sample_volume(v, l.lps)) {
        l.value = s->value;
        l.voxel = s->voxel;
    } else {
        l.value = m.value_half;
    }
    l.unit = value_unit(v);
    // Its place among the surface layers, by depth. The click's rule: the
    // first layer whose own opacity reaches the threshold (the volume's layer
    // is where it reaches 0.5), else the nearest: it is visible when in front
    // of a visible surface that reaches the threshold, or when none does.
    const auto at =
        std::find_if(r.layers.begin(), r.layers.end(), [&](const PickLayer& s) { return s.depth_mm > l.depth_mm; });
    const std::size_t index = std::size_t(at - r.layers.begin());
    const bool surface_reaches = r.visible && r.layers[*r.visible].alpha >= p.threshold;
    const bool in_front = !surface_reaches || index <= *r.visible;
    if (!in_front && !p.all_layers && index >= r.layers.size()) return;
    r.layers.insert(at, std::move(l));
    if (in_front) {
        r.visible = index;
        if (!p.all_layers) r.layers.resize(index + 1);
    }
}

} // namespace iso::core
