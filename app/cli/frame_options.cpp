// The frame's options of `render`, `pick` and `view` (frame_options.hpp).
#include "app/cli/frame_options.hpp"

#include <cstdio>

namespace iso::cli {

void add_cone_options(CLI::App* cmd, iso::ConeAoSettings& c) {
    cmd->add_option("--ao-cones", c.cones, "Cones over the hemisphere (cone AO)")->check(CLI::Range(1, 64));
    cmd->add_option("--ao-spheres", c.spheres, "Spheres per cone (cone AO)")->check(CLI::Range(1, 32));
    cmd->add_option("--ao-samples", c.samples, "Poisson-disk columns per sphere (cone AO)")->check(CLI::Range(1, 64));
    cmd->add_option("--ao-strength", c.strength, "AO = 1 - strength * occlusion (cone AO)")->check(CLI::Range(0.0, 4.0));
    cmd->add_option("--ao-layers", c.layers, "Slicemap depth: 128 z-voxels per layer, 1..8 (cone AO)")->check(CLI::Range(1, 8));
    cmd->add_option("--ao-grid", c.grid_scale, "Slicemap texels per image pixel, 0.125..2 (cone AO)")->check(CLI::Range(0.125, 2.0));
    cmd->add_option("--ao-jitter", c.jitter_sets, "Jitter distributions chosen per pixel by a screen hash (cone AO)")->check(CLI::Range(1, 64));
    cmd->add_option("--ao-persistence", c.persistence, "Sphere combination along a cone: 0 independent absorbers, 1 one solid (cone AO)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--ao-ray-weight", c.ray_weight,
                    "Sphere occlusion: 0 occupied volume fraction, 1 blocked-ray fraction of a cutting plane (cone AO)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--ao-axis-weight", c.axis_weight,
                    "Also march each cone's axis as a ray; a cone whose axis is blocked counts as at least this blocked, 0 off, default 1 (cone AO)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--ao-surface-voxels", c.surface_voxels,
                    "Also set the voxels next to every surface, so walls thinner than a voxel occlude; slower voxelization (cone AO)");
    cmd->add_option("--ao-resolution", c.resolution, "Cone-pass pixels per image pixel, 0.25..1; below 1 a bilateral upsampling follows (cone AO)")
        ->check(CLI::Range(0.25, 1.0));
    cmd->add_option("--ao-guard", c.guard,
                    "Largest guard band around the view, fraction of the viewport per side, for occluders just off screen; 0 none (cone AO)")
        ->check(CLI::Range(0.0, 0.5));
}

// Disk-AO tunables (docs/ao.md, "Disk AO on the GPU"), defaults
// DiskAoSettings' (measured against Embree by the CPU benchmark). --ao-disk-blend takes "MIN,MAX" (the weights

namespace {

void add_disk_options(CLI::App* cmd, iso::DiskAoSettings& d, std::string& blend) {
    cmd->add_option("--ao-disk-passes", d.passes, "Element passes before the gather, 0..16; 0: none, unmodulated form factors (disk AO; default 0)")
        ->check(CLI::Range(0, 16));
    cmd->add_option("--ao-disk-epsilon", d.traversal_epsilon,
                    "Traversal: open an element while distance^2 < epsilon x area, 0..10000 (disk AO; default 16)")
        ->check(CLI::Range(0.0, 1e4));
    cmd->add_option("--ao-disk-clip-epsilon", d.clip_epsilon, "Tangent-plane snap in mm, 0..0.1 (disk AO; default 1e-6)")
        ->check(CLI::Range(0.0, 0.1));
    cmd->add_option("--ao-disk-distance-k", d.distance_attenuation, "Distance attenuation 1/(1 + k d^2), k 0..100 (disk AO; default 0)")
        ->check(CLI::Range(0.0, 100.0));
    cmd->add_option("--ao-disk-triangle-t", d.triangle_attenuation,
                    "Triangle attenuation: emitter term^t, t 0..16 (disk AO; default 1)")
        ->check(CLI::Range(0.0, 16.0));
    cmd->add_option("--ao-disk-offset", d.receiver_offset,
                    "Receiver raised along its normal by this x R against self-occlusion, 0..0.1 (disk AO; default 0.001)")
        ->check(CLI::Range(0.0, 0.1));
    cmd->add_option("--ao-disk-blend", blend, "Convergence blend weights MIN,MAX of the last two passes (disk AO; default 0.7,0.3)");
}

// "MIN,MAX" of --ao-disk-blend into the settings (empty: unchanged).
void parse_disk_blend(const std::string& text, iso::DiskAoSettings& d) {
    if (text.empty()) return;
    double lo = 0, hi = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%lf,%lf%c", &lo, &hi, &tail) != 2)
        throw iso::Error("--ao-disk-blend", "expected MIN,MAX weights, e.g. 0.7,0.3, got '" + text + "'");
    if (!(lo >= 0 && lo <= 1 && hi >= 0 && hi <= 1))
        throw iso::Error("--ao-disk-blend", "weights must be in 0..1, got '" + text + "'");
    d.min_scale = lo;
    d.max_scale = hi;
}

} // namespace

void add_frame_options(CLI::App* c, FrameArgs& a, bool input_required) {
    auto* in = c->add_option("input", a.in, "Volume file, DICOM folder, or mesh (" + iso::mesh_extensions_text() + ")");
    if (input_required) in->required();
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--view", a.view, "anterior, posterior, left, right, superior or inferior");
    c->add_option("--size", a.size, "Image size WxH (default 1024x1024)");
    c->add_option("--ao", a.ao,
                  "Ambient occlusion: off, cone (cone tracing), disk (disk hierarchy, high quality for stills), or reference (Embree ray "
                  "tracing; with --aov ao)");
    c->add_option("--ao-radius", a.ao_radius, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    add_cone_options(c, a.cone);
    add_disk_options(c, a.disk, a.disk_blend);
    c->add_option("--ao-frames", a.ao_frames, "Still frames accumulated with new jitter sets (cone AO)")->check(CLI::Range(1, 4096));
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    add_look_options(c, a.look);
    c->add_option("--oit-epsilon", a.oit_epsilon, "Translucent surfaces: stop compositing a pixel below this transmittance (default 1/512)")
        ->check(CLI::Range(0.0, 0.999));
    c->add_option("--oit-memory", a.oit_memory, "Translucent surfaces: fragment pool cap in MiB (default 256)")->check(CLI::Range(1.0, 65536.0));
}

iso::core::RenderRequest frame_request(const FrameArgs& a) {
    iso::core::RenderRequest req;
    req.view = a.view;
    if (std::sscanf(a.size.c_str(), "%dx%d", &req.width, &req.height) != 2 || req.width < 1 || req.height < 1)
        throw iso::Error("--size", "expected WxH, e.g. 1920x1080, got '" + a.size + "'");
    req.ao = a.ao;
    req.ao_radius_mm = a.ao_radius;
    req.cone = a.cone;
    req.disk = a.disk;
    parse_disk_blend(a.disk_blend, req.disk);
    req.ao_frames = a.ao_frames;
    req.progress = progress_bar();
    if (!a.look.background.empty()) req.background = hex_option("--background", a.look.background);
    req.flat_shading = a.look.shading == "flat";
    req.oit_epsilon = a.oit_epsilon;
    req.oit_memory_mib = a.oit_memory;
    return req;
}

} // namespace iso::cli
