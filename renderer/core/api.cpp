#include "renderer/core/api.hpp"

#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "renderer/core/image_metadata.hpp"
#include "renderer/core/raytraced_ao.hpp"
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
    for (int r = 0; r < 4; ++r)
        m.push_back({v.index_to_lps[0][r], v.index_to_lps[1][r], v.index_to_lps[2][r], v.index_to_lps[3][r]});
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
            s.push_back({{"uid", si.uid},
                         {"description", si.description},
                         {"modality", si.modality},
                         {"number", si.number},
                         {"dims", si.dims},
                         {"files", si.files},
                         {"warnings", si.warnings}});
        j["series"] = s;
        j["selected_series"] = v.meta.selected_series;
    }
    return j;
}

namespace {
// The cache folder for ray-traced AO terms (see RenderRequest::cache_dir); empty: none.
std::filesystem::path cache_folder(const std::string& requested) {
    if (requested == "-") return {};
    if (!requested.empty()) return requested;
    if (const char* e = std::getenv("ISOSCOPE_CACHE_DIR"); e && *e)
        return std::string(e) == "-" ? std::filesystem::path() : e;
    if (const char* e = std::getenv("XDG_CACHE_HOME"); e && *e) return std::filesystem::path(e) / "isoscope";
    if (const char* e = std::getenv("HOME"); e && *e) return std::filesystem::path(e) / ".cache" / "isoscope";
    return {};
}

// Ray-traced AO (look.ao raytraced): traced once, before the frame or
// frames are drawn, and set in their options so that every one lights with
// it (and the ao AOV reads it raw). The other AOVs do not read it.
std::optional<RaytracedAo> raytraced_term(const Scene& scene, const Camera& cam, const RenderRequest& req,
                                          const RenderOptions& ro) {
    if (req.look.ao != AoMethod::Raytraced || (req.aov != Aov::None && req.aov != Aov::Ao)) return std::nullopt;
    std::optional<RaytracedAo> rt = raytraced_ao(scene, cam, ro.width, ro.height, req.look, scene_key_text(scene, cam),
                                                 cache_folder(req.cache_dir).string(), req.progress);
    return rt;
}

} // namespace

RenderOptions frame_options(const RenderRequest& req) {
    validate(req.look);
    const AoMethod method = req.look.ao;
    if (req.aov == Aov::Ao && method == AoMethod::Off)
        throw Error("ao AOV", "needs cone, disk or raytraced ambient occlusion");
    RenderOptions ro;
    ro.width = req.width;
    ro.height = req.height;
    ro.look = req.look;
    ro.aov = req.aov;
    ro.scale = req.scale;
    ro.time_passes = req.time_passes;
    ro.pick = req.pick;
    if (method == AoMethod::Disk) ro.progress = req.progress; // the gather takes seconds: progress and cancel
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
    // One GL context serves every scene of the process: free this one's GPU
    // resources while it is current, also when a frame throws.
    struct Release {
        Scene& s;
        ~Release() { s.release_gpu(); }
    } release{scene};
    RenderOptions ro = frame_options(req);
    Annotations ann;
    ann.markups = req.markups;
    ann.scale_bar = ann.orientation = req.annotations;
    const bool colour_image = req.aov == Aov::None; // annotations and markups go on it only
    if ((req.annotations || !ann.markups.empty()) && colour_image) ro.annotations = &ann;
    const Camera cam = frame_camera(scene, req);
    const std::optional<RaytracedAo> raytraced = raytraced_term(scene, cam, req, ro);
    if (raytraced) ro.ao_image = &raytraced->image;
    // Still frames: each adds new jitter sets to the running mean of the AO.
    for (int f = 1; req.look.ao == AoMethod::Cone && f < req.look.ao_frames; ++f) scene.render(cam, ro);
    auto r = scene.render(cam, ro);
    if (r.cancelled) throw Cancelled("disk AO");
    RenderOutput out;
    out.meta =
        frame_metadata({scene, req, ro, cam, r, colour_image ? &ann : nullptr, raytraced ? &*raytraced : nullptr});
    out.image = std::move(r.image);
    out.stats = std::move(r.stats);
    out.oit = r.oit;
    out.pick = std::move(r.pick);
    out.labels = std::move(r.labels);
    out.gl_renderer = r.gl_renderer;
    out.camera = cam;
    if (raytraced) out.ao_cache_hit = raytraced->cache_hit;
    return out;
}

} // namespace iso::core
