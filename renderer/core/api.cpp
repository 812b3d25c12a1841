#include "renderer/core/api.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "io/error.hpp"
#include "renderer/core/image_metadata.hpp"
#include "renderer/core/legend.hpp"
#include "renderer/core/raytraced_ao.hpp"
#include "renderer/gl/context.hpp"

#include "isoscope_commit.hpp" // generated: ISOSCOPE_COMMIT

namespace iso::core {

const char* version() { return ISOSCOPE_VERSION; }

const char* commit() { return ISOSCOPE_COMMIT; }

Volume open_volume(const std::string& path, const LoadOptions& opt) { return load_volume(path, opt); }

Mesh open_mesh(const std::string& path) { return load_mesh(path); }

std::vector<SeriesInfo> list_series(const std::string& path) { return list_dicom_series({path}); }

int suggested_series(const std::vector<SeriesInfo>& list) {
    const bool any_3d = std::any_of(list.begin(), list.end(), [](const SeriesInfo& s) { return s.for_3d; });
    int best = -1;
    for (int i = 0; i < int(list.size()); ++i) {
        const SeriesInfo& s = list[std::size_t(i)];
        if (any_3d && !s.for_3d) continue;
        if (best < 0 || s.files > list[std::size_t(best)].files) best = i;
    }
    return best;
}

std::optional<SeriesOfFile> dicom_series_of_file(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec) || volume_format_of(path) != VolumeFormat::Dicom) return {};
    try {
        const auto list = list_dicom_series({path});
        if (list.size() != 1 || list.front().uid.empty()) return {};
        const auto folder = std::filesystem::absolute(path).parent_path();
        return SeriesOfFile{folder.string(), list.front().uid};
    } catch (const Error&) {
        return {}; // loading the file itself reports what is wrong with it
    }
}

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

// The largest channel difference per pixel between two RGBA8 images, in
// sRGB units (0..1): its RMS over the pixels that differ at all (0: none).
double changed_rms(const Image& a, const Image& b) {
    if (a.bytes.size() != b.bytes.size() || a.channels != 4) return 1.0;
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i + 3 < a.bytes.size(); i += 4) {
        int d = 0;
        for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(int(a.bytes[i + c]) - int(b.bytes[i + c])));
        if (d == 0) continue;
        sum += (d / 255.0) * (d / 255.0);
        ++n;
    }
    return n ? std::sqrt(sum / double(n)) : 0.0;
}

} // namespace

std::string Convergence::text() const {
    std::ostringstream t;
    t.precision(3);
    if (samples > 1)
        t << "DSRAA " << samples << " sub-samples per pixel";
    else
        t << "1 sample per pixel";
    if (frames > 1)
        t << "; " << frames << " jittered frames averaged (the frames after the first: 1 sample each; last change "
          << change << " sRGB)";
    return t.str();
}

RenderResult render_converged(Scene& scene, const Camera& cam, RenderOptions ro, const RenderRequest& req,
                              Convergence& out) {
    const AntiAliasing aa = ro.look.aa; // frame_options' (the volume's check mode samples pixel centres)
    const bool colour = ro.aov == Aov::None && ro.image;
    // Cone AO's still frames each add new jitter sets to the running mean of the AO.
    const int ao_frames = req.look.ao == AoMethod::Cone ? req.look.ao_frames : 1;
    const int most = std::max(colour ? aa.frames : 1, ao_frames);
    ro.accumulate = colour && aa.frames > 1;
    Image previous; // the mean at the last check, half as many frames
    RenderResult r;
    for (int n = 1;; ++n) {
        ro.restart_accumulation = n == 1;
        r = scene.render(cam, ro);
        if (r.cancelled) throw Cancelled("disk AO");
        out.frames = n;
        if (n == 1) {
            out.samples = r.aa_samples;
            out.first.stats = r.stats;
            out.first.lod = r.lod;
        }
        if (n >= most) break;
        report(req.progress, double(n) / most, "anti-aliasing", "render");
        // At 2, 4, 8, ... frames the mean of n against that of n / 2; stops from 4 on.
        if (!ro.accumulate || (n & (n - 1)) != 0) continue;
        if (!previous.bytes.empty()) {
            out.change = changed_rms(previous, r.image);
            if (n >= 4 && out.change <= aa.tolerance && n >= ao_frames) break;
        }
        previous = r.image;
    }
    return r;
}

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
    // Volume rendering with flat shading is the check mode of the stated
    // model (docs/volume.md): each pixel is the ray through its centre, as a
    // point-sampled reference march draws it, so no sub-samples or jitter.
    if (req.look.volume.enabled && req.look.flat_shading) {
        ro.look.aa.samples = 1;
        ro.look.aa.frames = 1;
    }
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
        if (req.isos.empty() && !req.look.volume.enabled)
            throw Error("render " + input, "a volume needs at least one iso value or volume rendering");
        if (!req.isos.empty()) scene.add_isosurfaces(req.isos, {}, {}, req.progress);
    }
    return render_image(scene, req);
}

Camera frame_camera(const Scene& scene, const RenderRequest& req) {
    if (!req.camera)
        return scene.camera(patient_view_from_name(req.view), double(req.width) / double(req.height), req.look);
    Camera cam = *req.camera;
    cam.fit_planes(scene.bounds(req.look));
    return cam;
}

RenderOutput render_image(Scene& scene, const RenderRequest& req) {
    if (req.look.volume.enabled && !scene.has_volume())
        throw Error("volume rendering", "there is no volume to ray cast: the input is a mesh");
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
    if (req.annotations && req.legend) ann.legend = legend_entries(scene, req.look);
    const bool colour_image = req.aov == Aov::None; // annotations and markups go on it only
    if ((req.annotations || !ann.markups.empty()) && colour_image) ro.annotations = &ann;
    const Camera cam = frame_camera(scene, req);
    const std::optional<RaytracedAo> raytraced = raytraced_term(scene, cam, req, ro);
    if (raytraced) ro.ao_image = &raytraced->image;
    Convergence aa;
    auto r = render_converged(scene, cam, ro, req, aa);
    RenderOutput out;
    out.meta =
        frame_metadata({scene, req, ro, cam, r, colour_image ? &ann : nullptr, raytraced ? &*raytraced : nullptr});
    if (colour_image) out.meta.text["isoscope:antialiasing"] = aa.text();
    out.aa_frames = aa.frames;
    out.aa_change = aa.change;
    out.image = std::move(r.image);
    out.stats = std::move(r.stats);
    out.oit = r.oit;
    out.volume = r.volume;
    out.lod = r.lod;
    out.lod_first = aa.first.lod;
    out.lod.build_seconds = aa.first.lod.build_seconds;
    out.first_stats = aa.first.stats;
    out.pick = std::move(r.pick);
    out.labels = std::move(r.labels);
    out.gl_renderer = r.gl_renderer;
    out.camera = cam;
    if (raytraced) out.ao_cache_hit = raytraced->cache_hit;
    return out;
}

} // namespace iso::core
