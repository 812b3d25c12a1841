#include "renderer/core/api.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <filesystem>
#include <sstream>

#include "renderer/ao/reference.hpp"
#include "renderer/frame/ao_settings.hpp"
#include "renderer/core/image_metadata.hpp"
#include "renderer/core/surface_name.hpp"
#include "renderer/gl/context.hpp"

namespace iso::core {

const char* version() { return ISOSCOPE_VERSION; }

Volume open_volume(const std::string& path, const LoadOptions& opt) { return load_volume(path, opt); }

Mesh open_mesh(const std::string& path) { return load_mesh(path); }

std::vector<SeriesInfo> list_series(const std::string& path) { return list_dicom_series({path}); }

nlohmann::json describe(const Volume& v) {
    using nlohmann::json;
    json j;
    j["source"] = v.meta.source;
    j["format"] = v.meta.format;
    j["dims"] = {v.dims[0], v.dims[1], v.dims[2]};
    j["type"] = voxel_type_name(v.type);
    const auto sp = v.spacing();
    j["spacing"] = {sp.x, sp.y, sp.z};
    json m = json::array();
    for (int r = 0; r < 4; ++r) m.push_back({v.index_to_lps[0][r], v.index_to_lps[1][r], v.index_to_lps[2][r],
                                             v.index_to_lps[3][r]});
    j["index_to_lps"] = m;
    const auto range = v.value_range();
    j["range"] = {range.min, range.max};
    j["nan_count"] = range.nan_count;
    j["inf_count"] = range.inf_count;
    j["memory_bytes"] = v.memory_bytes();
    j["storage"] = v.is_sparse() ? "sparse" : "dense";
    json meta;
    meta["modality"] = v.meta.modality;
    meta["patient_name"] = v.meta.patient_name;
    meta["patient_id"] = v.meta.patient_id;
    meta["study_uid"] = v.meta.study_uid;
    meta["series_uid"] = v.meta.series_uid;
    meta["series_description"] = v.meta.series_description;
    j["metadata"] = meta;
    j["warnings"] = v.meta.warnings;
    if (!v.meta.series.empty()) {
        json s = json::array();
        for (const auto& si : v.meta.series)
            s.push_back({{"uid", si.uid}, {"description", si.description}, {"modality", si.modality},
                         {"number", si.number}, {"dims", si.dims}, {"files", si.files},
                         {"warnings", si.warnings}});
        j["series"] = s;
        j["selected_series"] = v.meta.selected_series;
    }
    return j;
}

namespace {
// The cache folder for AO references (see RenderRequest::cache_dir); empty: none.
std::filesystem::path cache_folder(const std::string& requested) {
    if (requested == "-") return {};
    if (!requested.empty()) return requested;
    if (const char* e = std::getenv("ISOSCOPE_CACHE_DIR"); e && *e) return std::string(e) == "-" ? std::filesystem::path() : e;
    if (const char* e = std::getenv("XDG_CACHE_HOME"); e && *e) return std::filesystem::path(e) / "isoscope";
    if (const char* e = std::getenv("HOME"); e && *e) return std::filesystem::path(e) / ".cache" / "isoscope";
    return {};
}

// The Embree reference for this view, from the cache when the same input,
// surfaces, camera, size, radius and ray count were traced before.
Image ao_reference_cached(Scene& scene, const Camera& cam, const RenderOptions& ro, const std::map<std::string, std::string>& t,
                          const RenderRequest& req, bool& hit) {
    std::ostringstream key;
    key.precision(17);
    key << "ao-reference v1 (Embree, Malley, rotated Hammersley, seed 1)\n"
        << t.at("isoscope:input_sha256") << "\n" << (t.count("isoscope:iso") ? t.at("isoscope:iso") : "") << "\n"
        << t.at("isoscope:camera") << "\n" << ro.width << "x" << ro.height << "\n" << req.ao_radius_mm << "\n" << req.ao_rays;
    const auto dir = cache_folder(req.cache_dir);
    const auto file = dir.empty() ? std::filesystem::path() : dir / "ao" / (sha256_of_string(key.str()) + ".exr");
    std::error_code ec;
    if (!file.empty() && std::filesystem::exists(file, ec)) {
        try {
            Image img = load_image(file.string());
            if (img.is_float && img.channels == 1 && img.width == ro.width && img.height == ro.height) {
                hit = true;
                return img;
            }
        } catch (const Error&) {
            // A damaged cache entry is recomputed and replaced below.
        }
    }
    // The visible points come from the depth and normal AOVs, the occlusion
    // from Embree rays against the same meshes.
    RenderOptions d = ro;
    d.annotations = nullptr;
    d.ao = false;
    d.aov = Aov::Depth;
    const Image depth = scene.render(cam, d).image;
    d.aov = Aov::Normal;
    const Image normal = scene.render(cam, d).image;
    std::vector<const Mesh*> ptrs;
    for (const SurfaceId id : scene.surfaces())
        if (scene.info(id).visible) ptrs.push_back(&scene.mesh(id));
    AoReference reference(ptrs);
    AoReferenceOptions ao;
    ao.radius_mm = req.ao_radius_mm;
    ao.rays = req.ao_rays;
    Image img = reference.image(cam, depth, normal, ao);
    if (!file.empty()) {
        std::filesystem::create_directories(file.parent_path(), ec);
        try {
            ImageMetadata m;
            m.text["isoscope:cache_key"] = key.str();
            save_image(img, file.string(), m);
        } catch (const Error&) {
            // An unwritable cache only costs time.
        }
    }
    return img;
}

} // namespace

RenderOptions frame_options(const RenderRequest& req) {
    RenderOptions ro;
    ro.width = req.width;
    ro.height = req.height;
    ro.aov = req.aov;
    ro.scale = req.scale;
    ro.background = glm::vec4(req.background, req.transparent ? 0.0f : 1.0f);
    ro.flat_shading = req.flat_shading;
    ro.transparency = req.transparency;
    ro.oit_epsilon = req.oit_epsilon;
    if (!(req.oit_memory_mib >= 1.0 && req.oit_memory_mib <= 65536.0))
        throw Error("transparency memory", "expected 1..65536 MiB, got " + std::to_string(req.oit_memory_mib));
    ro.oit_memory_bytes = std::size_t(req.oit_memory_mib * 1048576.0);
    ro.time_passes = req.time_passes;
    ro.pick = req.pick;
    if (req.ao != "off" && req.ao != "cone" && req.ao != "disk" && req.ao != "reference")
        throw Error("ambient occlusion", "method must be off, cone, disk or reference, got '" + req.ao + "'");
    if (req.ao == "reference" && !req.aov_ao)
        throw Error("ambient occlusion reference", "the ray-traced reference is written only as the raw AO term (the ao AOV)");
    if (req.aov_ao && req.ao == "off") throw Error("ao AOV", "needs cone, disk or reference ambient occlusion");
    if (req.ao_frames < 1 || req.ao_frames > 4096)
        throw Error("ambient occlusion frames", "expected 1..4096, got " + std::to_string(req.ao_frames));
    if (req.ao == "cone") {
        ro.ao = !req.aov_ao;
        ro.ao_settings = req.cone;
        ro.ao_settings.radius_mm = req.ao_radius_mm;
        validate(ro.ao_settings);
        if (req.aov_ao) ro.aov = Aov::Ao;
    }
    if (req.ao == "disk") {
        // R lives in ao_settings for both methods (RenderOptions).
        ro.ao = !req.aov_ao;
        ro.ao_method = AoMethod::Disk;
        ro.ao_settings.radius_mm = req.ao_radius_mm;
        validate(ro.ao_settings);
        ro.disk_settings = req.disk;
        validate(ro.disk_settings);
        if (req.aov_ao) ro.aov = Aov::Ao;
        ro.progress = req.progress; // the gather takes seconds: progress and cancel
    }
    return ro;
}

RenderOutput render_input(const std::string& input, const RenderRequest& req) {
    Scene scene;
    LoadOptions lo;
    lo.series = req.series;
    lo.progress = req.progress;
    scene.open(input, lo);
    if (scene.has_volume()) {
        if (req.isos.empty()) throw Error("render " + input, "a volume needs at least one iso value");
        scene.add_isosurfaces(req.isos, {}, {}, req.progress);
    }
    return render_image(scene, req);
}

Camera frame_camera(const Scene& scene, const RenderRequest& req) {
    if (!req.camera) return scene.camera(patient_view_from_name(req.view), double(req.width) / double(req.height));
    Camera cam = *req.camera;
    cam.fit_planes(scene.bounds());
    return cam;
}

RenderOutput render_image(Scene& scene, const RenderRequest& req) {
    const gl::ScopedCurrent context;
    RenderOptions ro = frame_options(req);
    Annotations ann;
    ann.markups = req.markups;
    ann.scale_bar = ann.orientation = req.annotations;
    const bool colour_image = req.aov == Aov::None && !req.aov_ao; // annotations and markups go on it only
    if ((req.annotations || !ann.markups.empty()) && colour_image) ro.annotations = &ann;
    const Camera cam = frame_camera(scene, req);
    // Still frames: each adds new jitter sets to the running mean of the AO.
    for (int f = 1; req.ao == "cone" && f < req.ao_frames; ++f) scene.render(cam, ro);
    auto r = scene.render(cam, ro);
    // One GL context serves every scene of the process: free this one's GPU
    // resources while it is current.
    struct Release {
        Scene& s;
        ~Release() { s.release_gpu(); }
    } release{scene};
    if (r.cancelled) throw Cancelled("disk AO");
    RenderOutput out;
    out.meta = frame_metadata({scene, req, ro, cam, r, colour_image ? &ann : nullptr});
    out.image = std::move(r.image);
    out.stats = std::move(r.stats);
    out.oit = r.oit;
    out.pick = std::move(r.pick);
    out.gl_renderer = r.gl_renderer;
    out.camera = cam;
    if (req.aov_ao && req.ao == "reference") out.image = ao_reference_cached(scene, cam, ro, out.meta.text, req, out.ao_cache_hit);
    return out;
}

} // namespace iso::core
