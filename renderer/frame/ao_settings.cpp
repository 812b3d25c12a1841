#include "renderer/frame/ao_settings.hpp"

#include <cmath>
#include <cstdio>

#include "io/error.hpp"

namespace iso {

const char* const kConeAoSettingPrefix = "cone AO setting ";
const char* const kDiskAoSettingPrefix = "disk AO setting ";

// The ranges are those the passes and the hierarchy are correct and useful
// for; the reasons of the less obvious ones are beside them.
const std::vector<AoSetting<ConeAoSettings>>& cone_ao_settings() {
    using S = ConeAoSettings;
    static const std::vector<AoSetting<S>> table = {
        // R is the frame's, shared with disk AO: the CLI's --ao-radius sets it.
        {"radius", &S::radius_mm, 1e-6, 1e6, "", "AO radius R in mm"},
        {"cones", &S::cones, 1, 64, "ao-cones", "Cones over the hemisphere (cone AO)"},
        {"spheres", &S::spheres, 1, 32, "ao-spheres", "Spheres per cone (cone AO)"},
        {"samples", &S::samples, 1, 64, "ao-samples", "Poisson-disk columns per sphere (cone AO)"},
        {"strength", &S::strength, 0, 4, "ao-strength", "AO = 1 - strength * occlusion (cone AO)"},
        {"layers", &S::layers, 1, 8, "ao-layers", "Slicemap depth: 128 z-voxels per layer, 1..8 (cone AO)"},
        {"grid", &S::grid_scale, 0.125, 2, "ao-grid", "Slicemap texels per image pixel, 0.125..2 (cone AO)"},
        {"jitter_sets", &S::jitter_sets, 1, 64, "ao-jitter",
         "Jitter distributions chosen per pixel by a screen hash (cone AO)"},
        {"ray_weight", &S::ray_weight, 0, 1, "ao-ray-weight",
         "Sphere occlusion: 0 occupied volume fraction, 1 blocked-ray fraction of a cutting plane (cone AO)"},
        {"axis_weight", &S::axis_weight, 0, 1, "ao-axis-weight",
         "Also march each cone's axis as a ray; a cone whose axis is blocked counts as at least this blocked, 0 off, "
         "default 1 "
         "(cone AO)"},
        {"persistence", &S::persistence, 0, 1, "ao-persistence",
         "Sphere combination along a cone: 0 independent absorbers, 1 one solid (cone AO)"},
        {"attenuation", &S::attenuation, 0, 100, "", "Sphere occlusion /= 1 + attenuation (t / R)^2"},
        {"bias", &S::bias, 0, 16, "", "Tangent-plane offset in voxel footprints"},
        {"surface_voxels", &S::surface_voxels, 0, 1, "ao-surface-voxels",
         "Also set the voxels next to every surface, so walls thinner than a voxel occlude; slower voxelization (cone "
         "AO)"},
        {"resolution", &S::resolution, 0.25, 1, "ao-resolution",
         "Cone-pass pixels per image pixel, 0.25..1; below 1 a bilateral upsampling follows (cone AO)"},
        {"guard", &S::guard, 0, 0.5, "ao-guard",
         "Largest guard band around the view, fraction of the viewport per side, for occluders just off screen; 0 none "
         "(cone AO)"},
    };
    return table;
}

const std::vector<AoSetting<DiskAoSettings>>& disk_ao_settings() {
    using S = DiskAoSettings;
    static const std::vector<AoSetting<S>> table = {
        {"passes", &S::passes, 0, 16, "ao-disk-passes",
         "Element passes before the gather, 0..16; 0: none, unmodulated form factors (disk AO; default 0)"},
        // 0 would gather only root disks; beyond ~1e4 every node is opened down
        // to the triangles (exact but O(triangles) per pixel).
        {"traversal_epsilon", &S::traversal_epsilon, 0, 1e4, "ao-disk-epsilon",
         "Traversal: open an element while distance^2 < epsilon x area, 0..10000 (disk AO; default 16)"},
        // The chapter's 1e-6 mm up to a tenth of a mm (a larger snap would flatten real geometry).
        {"clip_epsilon", &S::clip_epsilon, 0, 0.1, "ao-disk-clip-epsilon",
         "Tangent-plane snap in mm, 0..0.1 (disk AO; default 1e-6)"},
        {"distance_attenuation", &S::distance_attenuation, 0, 100, "ao-disk-distance-k",
         "Distance attenuation 1/(1 + k d^2), k 0..100 (disk AO; default 0)"},
        {"triangle_attenuation", &S::triangle_attenuation, 0, 16, "ao-disk-triangle-t",
         "Triangle attenuation: emitter term^t, t 0..16 (disk AO; default 1)"},
        // Both weights together are the CLI's --ao-disk-blend MIN,MAX (app/cli/frame_options.cpp).
        {"blend_min", &S::min_scale, 0, 1, "",
         "Convergence blend: weight of the smaller of the last two passes (disk AO; default 0.7)"},
        {"blend_max", &S::max_scale, 0, 1, "",
         "Convergence blend: weight of the larger of the last two passes (disk AO; default 0.3)"},
        // 0 lets a receiver see its own disk; beyond a tenth of R it floats visibly off the surface.
        {"receiver_offset", &S::receiver_offset, 0, 0.1, "ao-disk-offset",
         "Receiver raised along its normal by this x R against self-occlusion, 0..0.1 (disk AO; default 0.001)"},
    };
    return table;
}

std::string number_text(double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%.9g", v);
    return b;
}

namespace {

template <class S> void validate_table(const S& s, const std::vector<AoSetting<S>>& table, const char* prefix) {
    for (const auto& t : table) {
        double v = 0;
        if (const auto* d = std::get_if<double S::*>(&t.member))
            v = s.**d;
        else if (const auto* i = std::get_if<int S::*>(&t.member))
            v = s.**i;
        else
            continue;                  // a boolean has no range
        if (!(v >= t.lo && v <= t.hi)) // also rejects NaN
            throw Error(prefix + std::string(t.name), "value " + number_text(v) + " is out of range [" +
                                                          number_text(t.lo) + ", " + number_text(t.hi) + "]");
    }
}

template <class S> std::string table_text(const S& s, const std::vector<AoSetting<S>>& table, bool skip_radius) {
    std::string out;
    for (const auto& t : table) {
        if (skip_radius && std::string(t.name) == "radius") continue; // the metadata's own isoscope:ao_radius_mm
        std::string value;
        if (const auto* d = std::get_if<double S::*>(&t.member))
            value = number_text(s.**d);
        else if (const auto* i = std::get_if<int S::*>(&t.member))
            value = std::to_string(s.**i);
        else
            value = s.*std::get<bool S::*>(t.member) ? "on" : "off";
        out += (out.empty() ? "" : "; ") + std::string(t.name) + " " + value;
    }
    return out;
}

} // namespace

void validate(const ConeAoSettings& s) { validate_table(s, cone_ao_settings(), kConeAoSettingPrefix); }
void validate(const DiskAoSettings& s) { validate_table(s, disk_ao_settings(), kDiskAoSettingPrefix); }

bool same_settings(const DiskAoSettings& a, const DiskAoSettings& b) {
    for (const auto& t : disk_ao_settings()) {
        const bool same = std::visit([&](auto member) { return a.*member == b.*member; }, t.member);
        if (!same) return false;
    }
    return true;
}

std::string settings_text(const ConeAoSettings& s) { return table_text(s, cone_ao_settings(), true); }
std::string settings_text(const DiskAoSettings& s) { return table_text(s, disk_ao_settings(), false); }

} // namespace iso
