#include "renderer/core/image_metadata.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "io/color.hpp"
#include "io/markups.hpp"
#include "renderer/core/surface_name.hpp"
#include "renderer/frame/ao_settings.hpp"

namespace iso::core {

namespace {

using Text = std::map<std::string, std::string>;

std::vector<float> flat(const glm::dmat4& m) {
    std::vector<float> v;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) v.push_back(float(m[c][r]));
    return v;
}

// Files as absolute paths and their SHA-256, one a line each.
void add_files(Text& t, const std::vector<std::string>& files, const char* key, const char* hash_key) {
    std::string paths, sums;
    for (const auto& f : files) {
        paths += (paths.empty() ? "" : "\n") + std::filesystem::absolute(f).string();
        sums += (sums.empty() ? "" : "\n") + sha256_of_path(f);
    }
    if (files.empty()) return;
    t[key] = paths;
    t[hash_key] = sums;
}

// The markup files, and what was drawn, one markup a line: type, name,
// points, the value shown (ASCII: "deg" for the degree sign).
void add_markups(Text& t, const FrameRecord& f) {
    if (!f.annotations || f.annotations->markups.empty()) return;
    add_files(t, f.req.markups_files, "isoscope:markups", "isoscope:markups_sha256");
    std::string drawn;
    for (const auto& m : f.annotations->markups) {
        std::size_t defined = 0;
        for (const auto& p : m.points) defined += p.status == PositionStatus::Defined;
        std::string value = markup_measurement_text(m);
        if (const auto deg = value.find("\xC2\xB0"); deg != std::string::npos) value.replace(deg, 2, " deg");
        drawn += (drawn.empty() ? "" : "\n") + std::string(markup_type_name(m.type)) +
                 (m.name.empty() ? "" : " '" + m.name + "'") + ": " + std::to_string(defined) + " defined point(s)" +
                 (value.empty() ? "" : ", " + value);
    }
    t["isoscope:markups_drawn"] = drawn;
}

// The legend, one row a line: name, value, colour (sRGB hex) and opacity;
// and a note when the image had no place for it, or for only its first rows.
void add_legend(Text& t, const FrameRecord& f) {
    if (!f.annotations || f.annotations->legend.empty()) return;
    std::string rows;
    for (const auto& e : f.annotations->legend) {
        char opacity[32];
        std::snprintf(opacity, sizeof opacity, "opacity %.0f %%", double(e.opacity) * 100.0);
        rows += (rows.empty() ? "" : "\n") + e.name + ": " + (e.value.empty() ? "" : e.value + ", ") + "colour " +
                hex_from_linear(e.color) + ", " + opacity;
    }
    t["isoscope:legend"] = rows;
    // Legend rows with a swatch are entries; the one without, "+ K more" (annotations.hpp).
    bool drawn = false;
    std::size_t entries = 0;
    for (const auto& l : f.result.labels) {
        drawn = drawn || l.legend;
        entries += l.legend && l.swatch_hi.x > l.swatch_lo.x;
    }
    const std::string size = std::to_string(f.options.width) + "x" + std::to_string(f.options.height);
    if (!drawn)
        t["isoscope:legend_note"] =
            "not drawn: no place for it clear of the orientation letters and the scale bar at " + size;
    else if (entries < f.annotations->legend.size())
        t["isoscope:legend_note"] = "the first " + std::to_string(entries) + " of " +
                                    std::to_string(f.annotations->legend.size()) +
                                    " rows drawn, then \"+ K more\": no place for all at " + size;
}

std::string iso_values_text(const Scene& scene) {
    std::string isos;
    for (const SurfaceId id : scene.surfaces())
        if (scene.info(id).kind == SurfaceInfo::Kind::Iso)
            isos += (isos.empty() ? "" : ",") + value_text(scene.info(id).value);
    return isos;
}

std::string camera_text(const Camera& cam) {
    std::ostringstream cs;
    cs.precision(9);
    cs << "eye " << cam.eye.x << ' ' << cam.eye.y << ' ' << cam.eye.z << "; target " << cam.target.x << ' '
       << cam.target.y << ' ' << cam.target.z << "; up " << cam.up.x << ' ' << cam.up.y << ' ' << cam.up.z
       << "; fov_y_degrees " << cam.fov_y_degrees << "; near " << cam.near_plane << "; far " << cam.far_plane
       << "; depth reversed-Z [0,1]";
    return cs.str();
}

// Each visible surface: name, linear albedo, opacity.
std::string surfaces_text(const Scene& scene) {
    std::string surfaces;
    for (const SurfaceId id : scene.surfaces()) {
        const auto& si = scene.info(id);
        if (!si.visible) continue;
        char b[160];
        std::snprintf(b, sizeof b, "%s%s: albedo %.6g %.6g %.6g, opacity %.6g", surfaces.empty() ? "" : "; ",
                      si.name.c_str(), si.color.r, si.color.g, si.color.b, si.opacity);
        surfaces += b;
    }
    return surfaces;
}

void add_shading(Text& t, const FrameRecord& f) {
    const auto& req = f.req;
    const FrameLook& look = req.look;
    t["isoscope:shading"] = look.flat_shading ? "flat (albedo only)" : "lit";
    if (!look.transparency) t["isoscope:transparency"] = "off: every surface drawn opaque, whatever its opacity";
    const auto& oit = f.result.oit;
    if (oit.fragments > 0) {
        t["isoscope:transparency"] =
            "VOIT per-pixel fragment lists, front to back, epsilon " + std::to_string(look.oit_epsilon) + "; " +
            std::to_string(oit.fragments) + " fragments" +
            (oit.merged ? ", " + std::to_string(oit.merged) + " merged past the memory cap (error at most " +
                              std::to_string(oit.merge_error_max) + " per channel)"
                        : std::string());
    }
    if (look.volume.enabled) {
        const VolumeLook& v = look.volume;
        t["isoscope:volume_transfer_function"] = v.tf.text();
        t["isoscope:volume"] =
            std::string("ray cast, ") + volume_mode_name(v.mode) +
            "; opacity per mm, colours sRGB interpolated in linear light; step " +
            number_text(f.result.volume.step_mm) + " mm (" + number_text(v.step) + " voxel), " +
            (v.mode == VolumeMode::Composite ? std::string(volume_integration_name(v.integration)) + " segments; "
                                             : std::string()) +
            (v.shading && !look.flat_shading ? "gradient shading" : "flat (unshaded)") +
            (v.skip_empty ? "; empty chunks skipped" : "");
    }
    if (look.clip.active()) t["isoscope:clip"] = look.clip.text() + " (LPS mm)";
    if (req.aov != Aov::None && req.aov != Aov::Ao)
        t["isoscope:aov"] = std::string(req.aov == Aov::Depth    ? "depth (mm along the view axis)"
                                        : req.aov == Aov::Normal ? "normal (LPS)"
                                                                 : "id") +
                            "; of the nearest opaque surface (translucent surfaces are not in the AOVs)";
}

// Ray-traced AO: the definition, the stop rule and where it stopped.
void add_raytraced(Text& t, const RaytracedAo& rt) {
    const auto& s = rt.stats;
    t["isoscope:ao"] = "raytraced (Embree: primary ray through each pixel centre; cosine-weighted hemisphere about the "
                       "hit triangle's geometric normal, facing the camera)";
    t["isoscope:ao_parameters"] = "rays added in batches until every pixel's standard error is at most " +
                                  number_text(rt.target_se) + ", at most " + std::to_string(rt.max_rays) +
                                  " rays per pixel" + (rt.cache_hit ? "; from the cache" : "");
    t["isoscope:ao_rays"] = std::to_string(rt.max_rays);
    t["isoscope:ao_rays_traced"] = std::to_string(s.rays);
    t["isoscope:ao_rays_per_pixel"] = "min " + std::to_string(s.rays_min) + ", mean " +
                                      number_text(s.pixels ? double(s.rays) / s.pixels : 0.0) + ", max " +
                                      std::to_string(s.rays_max);
    t["isoscope:ao_standard_error"] = "max " + number_text(s.se_max) + "; " + std::to_string(s.capped) + " of " +
                                      std::to_string(s.pixels) + " pixels stopped by the ray cap above the target";
}

// The AO method and every one of its settings (from the settings' tables).
void add_ambient_occlusion(Text& t, const FrameRecord& f) {
    const FrameLook& look = f.req.look;
    if (look.ao != AoMethod::Off) t["isoscope:ao_radius_mm"] = number_text(look.cone.radius_mm);
    if (look.ao == AoMethod::Cone) {
        t["isoscope:ao"] = "cone (cone tracing in a solid slicemap voxelization)";
        t["isoscope:ao_parameters"] = settings_text(look.cone) + "; frames " + std::to_string(look.ao_frames);
    }
    if (look.ao == AoMethod::Disk) {
        t["isoscope:ao"] = "disk (disk hierarchy with exact near triangles, GPU Gems 3 ch. 12)";
        t["isoscope:ao_parameters"] = settings_text(look.disk);
    }
    if (look.ao == AoMethod::Raytraced && f.raytraced) add_raytraced(t, *f.raytraced);
    if (f.req.aov == Aov::Ao)
        t["isoscope:aov"] = "ao (1 = unoccluded; cosine-weighted visibility within the radius; NaN = background)";
}

} // namespace

std::string scene_key_text(const Scene& scene, const Camera& cam) {
    std::string sums;
    for (const auto& f : scene.sources()) sums += sha256_of_path(f) + "\n";
    return sums + iso_values_text(scene) + "\n" + surfaces_text(scene) + "\n" + camera_text(cam);
}

ImageMetadata frame_metadata(const FrameRecord& f) {
    ImageMetadata meta;
    auto& t = meta.text;
    t["isoscope:version"] = version();
    t["isoscope:commit"] = commit();
    // The inputs: one path (and its SHA-256) each, joined by newlines (both keys even when there is none).
    t["isoscope:input"] = t["isoscope:input_sha256"] = "";
    add_files(t, f.scene.sources(), "isoscope:input", "isoscope:input_sha256");
    add_markups(t, f);
    add_legend(t, f);
    if (const auto isos = iso_values_text(f.scene); !isos.empty()) t["isoscope:iso"] = isos;
    t["isoscope:view_name"] = f.req.camera ? "the request's camera" : f.req.view;
    if (!f.req.session_file.empty()) {
        t["isoscope:session"] = std::filesystem::absolute(f.req.session_file).lexically_normal().string();
        t["isoscope:session_sha256"] = sha256_of_path(f.req.session_file);
    }
    t["isoscope:camera"] = camera_text(f.camera);
    t["isoscope:world"] = "LPS millimetres";
    t["isoscope:renderer"] = f.result.gl_renderer;
    t["isoscope:surfaces"] = surfaces_text(f.scene);
    add_shading(t, f);
    add_ambient_occlusion(t, f);
    meta.float_arrays["isoscope:view"] = flat(f.camera.view());
    meta.float_arrays["isoscope:projection"] = flat(f.camera.projection(double(f.req.width) / double(f.req.height)));
    return meta;
}

} // namespace iso::core
