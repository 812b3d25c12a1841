// The frame's options of `render`, `pick` and `view` (frame_options.hpp).
#include "app/cli/frame_options.hpp"

#include <cstdio>
#include <type_traits>
#include <variant>

#include "renderer/frame/ao_settings.hpp"

namespace iso::cli {

// One option per setting of the AO settings' tables (renderer/frame/ao_settings.hpp)
// that has one, with its range and help.
template <class S> void add_ao_options(CLI::App* cmd, S& s, const std::vector<iso::AoSetting<S>>& table) {
    for (const auto& t : table) {
        if (!*t.option) continue;
        std::visit(
            [&](auto member) {
                auto* o = cmd->add_option(std::string("--") + t.option, s.*member, t.help);
                if constexpr (!std::is_same_v<std::decay_t<decltype(s.*member)>, bool>)
                    o->check(CLI::Range(t.lo, t.hi));
            },
            t.member);
    }
}

void add_cone_options(CLI::App* cmd, iso::ConeAoSettings& c) { add_ao_options(cmd, c, iso::cone_ao_settings()); }

namespace {

// Disk-AO tunables (docs/ao.md, "Disk AO on the GPU"), defaults
// DiskAoSettings' (measured against Embree by the CPU benchmark), and
// --ao-disk-blend MIN,MAX for both blend weights at once (parse_disk_blend).
void add_disk_options(CLI::App* cmd, iso::DiskAoSettings& d, std::string& blend) {
    add_ao_options(cmd, d, iso::disk_ao_settings());
    cmd->add_option("--ao-disk-blend", blend,
                    "Convergence blend weights MIN,MAX of the last two passes (disk AO; default 0.7,0.3)");
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

void add_volume_options(CLI::App* cmd, std::string& volume, std::string& mode) {
    cmd->add_option("--volume", volume,
                    "Ray cast the volume with this transfer function: a preset (bone, vessels, skin, soft tissue) or "
                    "value:opacity:#rrggbb,... (opacity per mm, piecewise linear; combinable with --iso)");
    cmd->add_option("--volume-mode", mode, "Volume rendering: composite (default), mip or minip");
}

void apply_volume_options(const std::string& volume, const std::string& mode, iso::VolumeLook& look) {
    if (!volume.empty()) {
        look.enabled = true;
        look.tf = iso::transfer_function_from(volume);
    }
    look.mode = iso::volume_mode_from_name(mode);
}

void add_frame_options(CLI::App* c, FrameArgs& a, bool input_required) {
    auto& req = a.req;
    auto* in = c->add_option("input", a.in, "Volume file, DICOM folder, or mesh (" + iso::mesh_extensions_text() + ")");
    if (input_required) in->required();
    c->add_option("--iso", req.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--view", req.view, "anterior, posterior, left, right, superior or inferior");
    c->add_option("--size", a.size, "Image size WxH (default 1024x1024)");
    c->add_option("--ao", a.ao,
                  "Ambient occlusion: off, cone (cone tracing), disk (disk hierarchy, high quality for stills), or "
                  "raytraced (Embree ray tracing, the ground truth; 'reference' is its former name)");
    c->add_option("--ao-radius", req.look.cone.radius_mm, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    add_cone_options(c, req.look.cone);
    add_disk_options(c, req.look.disk, a.disk_blend);
    c->add_option("--ao-frames", req.look.ao_frames, "Still frames accumulated with new jitter sets (cone AO)")
        ->check(CLI::Range(1, 4096));
    c->add_option("--series", req.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--aa-samples", req.look.aa.samples,
                  "Anti-aliasing: DSRAA visibility sub-samples per pixel, 1 (off), 2, 4 or 8 (default 4)");
    c->add_option("--aa-frames", req.look.aa.frames,
                  "Anti-aliasing: jittered frames averaged at most (default 64; 1: one frame)");
    c->add_option("--aa-tolerance", req.look.aa.tolerance,
                  "Anti-aliasing: stop averaging when the image changes by less (RMS, sRGB 0..1; default 0.04)");
    c->add_flag("--no-aa", a.no_aa, "No anti-aliasing: one sample per pixel, one frame");
    add_look_options(c, a.look);
    c->add_option("--oit-epsilon", req.look.oit_epsilon,
                  "Translucent surfaces: stop compositing a pixel below this transmittance (default 1/512)")
        ->check(CLI::Range(0.0, 0.999));
    add_volume_options(c, a.volume, a.volume_mode);
    c->add_option("--volume-step", req.look.volume.step,
                  "Volume rendering: sample step in voxels of the smallest spacing (default 0.5)")
        ->check(CLI::Range(0.01, 8.0));
    c->add_option("--volume-integration", a.volume_integration,
                  "Volume rendering between samples: preintegrated (default: each segment integrated for values "
                  "varying linearly along it, accurate at large steps) or sampled (each sample held over its step)")
        ->check(CLI::IsMember({"preintegrated", "sampled"}));
    c->add_flag("--no-empty-skipping", a.no_empty_skipping,
                "Volume rendering: march every chunk, also those the transfer function leaves empty (checks)");
    c->add_option("--clip", a.clip,
                  "Cut surfaces and volume: box=x0,y0,z0,x1,y1,z1 or plane=px,py,pz,nx,ny,nz (LPS mm; the side the "
                  "normal points to is kept; repeatable)")
        ->allow_extra_args(false);
    c->add_option("--oit-memory", req.look.oit_memory_mib,
                  "Translucent surfaces: fragment pool cap in MiB (default 256)")
        ->check(CLI::Range(1.0, 65536.0));
    c->add_option("--lod", a.lod,
                  "Levels of detail of large surfaces: auto (default: coarser where the error projects to at most "
                  "--lod-error pixels) or off (every triangle)")
        ->check(CLI::IsMember({"auto", "off"}));
    c->add_option("--lod-error", req.look.lod.error_px,
                  "Levels of detail: the largest projected geometric error, pixels (default 0.5)")
        ->check(CLI::Range(0.01, 64.0));
    c->add_option("--culling", a.culling,
                  "Levels of detail: cull clusters outside the view, facing away or hidden (on, default) or not (off)")
        ->check(CLI::IsMember({"on", "off"}));
}

iso::core::RenderRequest frame_request(const FrameArgs& a) {
    iso::core::RenderRequest req = a.req;
    if (std::sscanf(a.size.c_str(), "%dx%d", &req.width, &req.height) != 2 || req.width < 1 || req.height < 1)
        throw iso::Error("--size", "expected WxH, e.g. 1920x1080, got '" + a.size + "'");
    req.look.ao = iso::ao_method_from_name(a.ao);
    parse_disk_blend(a.disk_blend, req.look.disk);
    req.progress = progress_bar();
    if (!a.look.background.empty()) req.look.background = hex_option("--background", a.look.background);
    req.look.flat_shading = a.look.shading == "flat";
    apply_volume_options(a.volume, a.volume_mode, req.look.volume);
    req.look.volume.skip_empty = !a.no_empty_skipping;
    req.look.volume.integration = iso::volume_integration_from_name(a.volume_integration);
    for (const auto& c : a.clip) req.look.clip.add(c);
    req.look.lod.enabled = a.lod != "off";
    req.look.lod.culling = a.culling != "off";
    if (a.no_aa) {
        req.look.aa.samples = 1;
        req.look.aa.frames = 1;
    }
    return req;
}

} // namespace iso::cli
