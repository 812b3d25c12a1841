#include "renderer/core/legend.hpp"

#include "renderer/core/scene.hpp"
#include "renderer/core/surface_name.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::core {

std::vector<Annotations::LegendEntry> legend_entries(const Scene& scene, const FrameLook& look) {
    const std::string_view unit = value_unit(scene);
    std::vector<Annotations::LegendEntry> out;
    for (const SurfaceId id : scene.surfaces()) {
        const SurfaceInfo& si = scene.info(id);
        if (!si.visible) continue;
        Annotations::LegendEntry e;
        e.name = si.name;
        e.color = si.color;
        e.opacity = look.transparency ? si.opacity : 1.0f;
        if (si.kind == SurfaceInfo::Kind::Iso) {
            const std::string number = value_text(si.value);
            if (!unit.empty())
                e.value = number + " " + std::string(unit);
            else if (si.name != surface_name(false, si.value))
                e.value = number;
        }
        out.push_back(std::move(e));
    }
    // The ray-cast volume: its mode, the colour where its transfer function
    // is most opaque, and the values its points span.
    const VolumeLook& v = look.volume;
    if (v.enabled && scene.has_volume() && !v.tf.empty()) {
        Annotations::LegendEntry e;
        e.name = v.mode == VolumeMode::Composite ? "volume" : std::string("volume ") + volume_mode_name(v.mode);
        std::size_t most = 0;
        for (std::size_t i = 0; i < v.tf.points().size(); ++i)
            if (v.tf.points()[i].opacity > v.tf.points()[most].opacity) most = i;
        e.color = glm::vec3(v.tf.linear_color(most));
        const std::string span = value_text(v.tf.points().front().value) + "-" + value_text(v.tf.points().back().value);
        e.value = unit.empty() ? span : span + " " + std::string(unit);
        out.push_back(std::move(e));
    }
    return out;
}

} // namespace iso::core
