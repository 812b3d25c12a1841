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
    return out;
}

} // namespace iso::core
