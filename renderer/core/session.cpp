#include "renderer/core/session.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/geometric.hpp>

#include "io/atomic_file.hpp"
#include "io/color.hpp"
#include "io/error.hpp"
#include "io/read_file.hpp"
#include "io/image.hpp"
#include "renderer/core/structures.hpp"

namespace iso::core {
namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;

namespace {

constexpr const char* kFormat = "isoscope-session";

fs::path normal_absolute(const std::string& p) { return fs::absolute(fs::path(p)).lexically_normal(); }

fs::path session_folder(const std::string& session_path) { return normal_absolute(session_path).parent_path(); }

// Below the session's folder: relative to it (the pair can move together);
// anywhere else: absolute.
std::string stored_path(const std::string& path, const std::string& session_path) {
    const fs::path abs = normal_absolute(path);
    const fs::path rel = abs.lexically_relative(session_folder(session_path));
    if (!rel.empty() && *rel.begin() != "..") return rel.generic_string();
    return abs.string();
}

const char* kind_name(SurfaceInfo::Kind k) {
    switch (k) {
    case SurfaceInfo::Kind::Iso: return "iso";
    case SurfaceInfo::Kind::Label: return "label";
    case SurfaceInfo::Kind::Mesh: return "mesh";
    }
    return "mesh";
}

ordered_json vec_json(const glm::dvec3& v) { return ordered_json::array({v.x, v.y, v.z}); }

ordered_json box_json(const LpsBox& b) { return {{"lo", vec_json(b.lo)}, {"hi", vec_json(b.hi)}}; }

// A cut as Reader::step reads it; numbers written to round-trip exactly,
// so that the part made again is the same.
ordered_json step_json(const PartStep& st) {
    ordered_json o = ordered_json::object();
    if (st.within) o["within"] = box_json(*st.within);
    if (st.keep_at) o["keep_at"] = vec_json(*st.keep_at);
    if (const auto& v = st.outline) {
        ordered_json pts = ordered_json::array(), m = ordered_json::array();
        for (const auto& q : v->outline) pts.push_back({q.x, q.y});
        for (int k = 0; k < 16; ++k) m.push_back(v->view_projection[k / 4][k % 4]);
        o["scissors"] = {{"outline_pixels", pts},
                         {"view_projection", m},
                         {"eye", vec_json(v->eye)},
                         {"image_size", {v->width, v->height}},
                         {"keep", v->keep_inside ? "inside" : "outside"}};
    }
    return o;
}

// Reads one session; every failure names the file and the field.
class Reader {
public:
    explicit Reader(const std::string& path) : path_(path) {}

    Session read(const json& root) const {
        if (!root.is_object()) fail("", "the top level is a JSON " + std::string(root.type_name()) + ", not an object");
        const json* format = member(root, "format");
        if (!format || !format->is_string() || format->get<std::string>() != kFormat)
            fail("format", "not an isoscope session (expected \"format\": \"" + std::string(kFormat) + "\")");
        const json* version = member(root, "version");
        if (!version) fail("version", "missing");
        if (!version->is_number_integer())
            fail("version", "must be an integer, not a " + std::string(version->type_name()));
        if (version->get<long long>() != kSessionVersion)
            fail("version", std::to_string(version->get<long long>()) +
                                " is not supported (this isoscope reads version " + std::to_string(kSessionVersion) +
                                ")");
        Session s;
        const json& input = object(root, "input", "input", true);
        s.input = resolve(string(input, "path", "input.path", true));
        if (s.input.empty()) fail("input.path", "is empty");
        s.input_sha256 = string(input, "sha256", "input.sha256", false);
        s.series = string(input, "series", "input.series", false);

        if (const json* list = member(root, "surfaces"); list && !list->is_null()) {
            if (!list->is_array()) fail("surfaces", "must be an array, not a " + std::string(list->type_name()));
            for (std::size_t i = 0; i < list->size(); ++i)
                s.surfaces.push_back(surface((*list)[i], "surfaces[" + std::to_string(i) + "]"));
        }
        if (const json* c = member(root, "camera"); c && !c->is_null()) s.camera = camera(*c);
        if (const json* w = member(root, "window_level"); w && !w->is_null()) {
            if (!w->is_object()) fail("window_level", "must be an object");
            WindowLevel wl;
            wl.center = number(require(*w, "center", "window_level.center"), "window_level.center");
            wl.width = number(require(*w, "width", "window_level.width"), "window_level.width");
            if (!(wl.width > 0)) fail("window_level.width", "must be positive");
            s.window = wl;
        }
        if (const json* v = member(root, "view"); v && !v->is_null()) {
            if (!v->is_object()) fail("view", "must be an object");
            s.ao = boolean(*v, "ao", "view.ao", true) ? AoMethod::Cone : AoMethod::Off;
            // "ao_method": the method when on ("raytraced"; "cone" if absent).
            if (const json* mth = member(*v, "ao_method"); mth && s.ao != AoMethod::Off) {
                const std::string name = mth->is_string() ? mth->get<std::string>() : "";
                if (name != "cone" && name != "raytraced" && name != "reference")
                    fail("view.ao_method", "must be \"cone\" or \"raytraced\"");
                s.ao = ao_method_from_name(name); // "reference": the ray-traced method's former name
            }
            s.transparency = boolean(*v, "transparency", "view.transparency", true);
            s.slice_planes_in_3d = boolean(*v, "slice_planes", "view.slice_planes", false);
        }
        if (const json* l = member(root, "layout"); l && !l->is_null()) {
            s.layout = view_layout_from_name(l->is_string() ? l->get<std::string>() : std::string());
            if (!s.layout)
                fail("layout", "must be \"four_up\", \"conventional\", \"3d\", \"axial\", \"coronal\" or "
                               "\"sagittal\"");
        }
        if (const json* sv = member(root, "slice_views"); sv && !sv->is_null()) s.slice_views = slice_views(*sv);
        if (const json* v = member(root, "volume"); v && !v->is_null()) s.volume = volume(*v);
        if (const json* c = member(root, "clip"); c && !c->is_null()) s.clip_box = clip_box(*c);
        if (const json* m = member(root, "markups"); m && !m->is_null()) {
            try {
                auto f = parse_markups(m->dump(), "markups");
                s.markups = std::move(f.markups);
                for (auto& w : f.warnings) s.warnings.push_back(w);
            } catch (const Error& e) {
                throw Error(path_, e.what());
            }
        }
        return s;
    }

private:
    [[noreturn]] void fail(const std::string& field, const std::string& reason) const {
        throw Error(path_, field.empty() ? reason : field + ": " + reason);
    }

    static const json* member(const json& obj, const char* key) {
        const auto it = obj.find(key);
        return it == obj.end() ? nullptr : &*it;
    }

    const json& require(const json& obj, const char* key, const std::string& field) const {
        const json* v = member(obj, key);
        if (!v) fail(field, "missing");
        return *v;
    }

    const json& object(const json& obj, const char* key, const std::string& field, bool required) const {
        static const json empty = json::object();
        const json* v = member(obj, key);
        if (!v) {
            if (required) fail(field, "missing");
            return empty;
        }
        if (!v->is_object()) fail(field, "must be an object, not a " + std::string(v->type_name()));
        return *v;
    }

    std::string string(const json& obj, const char* key, const std::string& field, bool required) const {
        const json* v = member(obj, key);
        if (!v) {
            if (required) fail(field, "missing");
            return {};
        }
        if (!v->is_string()) fail(field, "must be a string, not a " + std::string(v->type_name()));
        return v->get<std::string>();
    }

    bool boolean(const json& obj, const char* key, const std::string& field, bool fallback) const {
        const json* v = member(obj, key);
        if (!v) return fallback;
        if (!v->is_boolean()) fail(field, "must be true or false, not a " + std::string(v->type_name()));
        return v->get<bool>();
    }

    double number(const json& v, const std::string& field) const {
        if (!v.is_number())
            fail(field, "must be a number, not " +
                            (v.is_null() ? std::string("null (NaN?)") : "a " + std::string(v.type_name())));
        const double d = v.get<double>();
        if (!std::isfinite(d)) fail(field, "is NaN or infinite");
        return d;
    }

    double number_or(const json& obj, const char* key, const std::string& field, double fallback) const {
        const json* v = member(obj, key);
        return v ? number(*v, field) : fallback;
    }

    glm::dvec3 vec3(const json& v, const std::string& field) const {
        if (!v.is_array() || v.size() != 3) fail(field, "must be an array of 3 numbers");
        return {number(v[0], field), number(v[1], field), number(v[2], field)};
    }

    std::string resolve(const std::string& stored) const {
        if (stored.empty()) return stored;
        const fs::path p(stored);
        return (p.is_absolute() ? p : session_folder(path_) / p).lexically_normal().string();
    }

    SessionSurface surface(const json& item, const std::string& where) const {
        if (!item.is_object()) fail(where, "must be an object, not a " + std::string(item.type_name()));
        SessionSurface s;
        const std::string kind = string(item, "kind", where + ".kind", true);
        if (kind == "iso")
            s.kind = SurfaceInfo::Kind::Iso;
        else if (kind == "label")
            s.kind = SurfaceInfo::Kind::Label;
        else if (kind == "mesh")
            s.kind = SurfaceInfo::Kind::Mesh;
        else
            fail(where + ".kind", "'" + kind + "' is not iso, label or mesh");
        if (s.kind != SurfaceInfo::Kind::Mesh)
            s.value = number(require(item, "value", where + ".value"), where + ".value");
        s.name = string(item, "name", where + ".name", false);
        s.source = resolve(string(item, "source", where + ".source", false));
        if (const json* c = member(item, "color")) {
            if (!c->is_string())
                fail(where + ".color", "must be a string \"#rrggbb\", not a " + std::string(c->type_name()));
            s.color = c->get<std::string>();
            try {
                linear_from_hex(s.color);
            } catch (const Error& e) {
                fail(where + ".color", e.reason());
            }
        }
        const double opacity = number_or(item, "opacity", where + ".opacity", 1.0);
        if (opacity < 0.0 || opacity > 1.0) fail(where + ".opacity", "must be between 0 and 1");
        s.opacity = float(opacity);
        s.visible = boolean(item, "visible", where + ".visible", true);
        s.post.smooth = number_or(item, "smoothing", where + ".smoothing", 0.0);
        if (s.post.smooth < 0.0 || s.post.smooth > 1.0) fail(where + ".smoothing", "must be between 0 and 1");
        s.post.decimate = number_or(item, "decimate", where + ".decimate", 0.0);
        if (s.post.decimate < 0.0 || s.post.decimate >= 1.0)
            fail(where + ".decimate", "must be at least 0 and below 1");
        s.post.keep_largest = boolean(item, "keep_largest", where + ".keep_largest", false);
        if (item.contains("keep_at") && !item["keep_at"].is_null())
            s.post.keep_at = vec3(item["keep_at"], where + ".keep_at");
        if (item.contains("keep_within") && !item["keep_within"].is_null())
            s.post.keep_within = box(item["keep_within"], where + ".keep_within");
        if (const json* steps = member(item, "steps"); steps && !steps->is_null()) {
            if (!steps->is_array()) fail(where + ".steps", "must be an array");
            for (std::size_t i = 0; i < steps->size(); ++i)
                s.post.steps.push_back(step((*steps)[i], where + ".steps[" + std::to_string(i) + "]"));
        }
        if (const json* g = member(item, "grown"); g && !g->is_null()) s.grown = grown(*g, where + ".grown");
        return s;
    }

    LpsBox box(const json& b, const std::string& where) const {
        if (!b.is_object()) fail(where, "must be an object {\"lo\": [x,y,z], \"hi\": [x,y,z]}");
        LpsBox box{vec3(b.value("lo", json()), where + ".lo"), vec3(b.value("hi", json()), where + ".hi")};
        for (int i = 0; i < 3; ++i)
            if (!(box.lo[i] < box.hi[i])) fail(where, "lo must be below hi on every axis");
        return box;
    }

    // A cut made on the surface (PartStep): {"within": box, "keep_at": [x,y,z], "scissors": {...}}.
    PartStep step(const json& o, const std::string& where) const {
        if (!o.is_object()) fail(where, "must be an object");
        PartStep st;
        if (const json* b = member(o, "within"); b && !b->is_null()) st.within = box(*b, where + ".within");
        if (const json* a = member(o, "keep_at"); a && !a->is_null()) st.keep_at = vec3(*a, where + ".keep_at");
        if (const json* c = member(o, "scissors"); c && !c->is_null()) st.outline = scissors(*c, where + ".scissors");
        if (!st.within && !st.keep_at && !st.outline) fail(where, "has none of within, keep_at and scissors");
        return st;
    }

    ViewOutline scissors(const json& c, const std::string& where) const {
        if (!c.is_object()) fail(where, "must be an object");
        ViewOutline v;
        const json& pts = require(c, "outline_pixels", where + ".outline_pixels");
        if (!pts.is_array() || pts.size() < 3) fail(where + ".outline_pixels", "must be an array of 3 or more [x, y]");
        for (const json& q : pts) {
            if (!q.is_array() || q.size() != 2) fail(where + ".outline_pixels", "each point must be [x, y]");
            v.outline.push_back({number(q[0], where + ".outline_pixels"), number(q[1], where + ".outline_pixels")});
        }
        const json& m = require(c, "view_projection", where + ".view_projection");
        if (!m.is_array() || m.size() != 16) fail(where + ".view_projection", "must be 16 numbers (column-major)");
        for (int k = 0; k < 16; ++k)
            v.view_projection[k / 4][k % 4] = number(m[std::size_t(k)], where + ".view_projection");
        v.eye = vec3(require(c, "eye", where + ".eye"), where + ".eye");
        const json& size = require(c, "image_size", where + ".image_size");
        if (!size.is_array() || size.size() != 2 || !size[0].is_number_integer() || !size[1].is_number_integer() ||
            size[0].get<long long>() < 1 || size[1].get<long long>() < 1 || size[0].get<long long>() > 1 << 16 ||
            size[1].get<long long>() > 1 << 16)
            fail(where + ".image_size", "must be [width, height], whole numbers from 1 to 65536");
        v.width = int(size[0].get<long long>());
        v.height = int(size[1].get<long long>());
        const std::string keep = string(c, "keep", where + ".keep", true);
        if (keep != "inside" && keep != "outside") fail(where + ".keep", "must be \"inside\" or \"outside\"");
        v.keep_inside = keep == "inside";
        return v;
    }

    GrownFrom grown(const json& g, const std::string& where) const {
        if (!g.is_object()) fail(where, "must be an object");
        GrownFrom out;
        out.seed = vec3(require(g, "seed", where + ".seed"), where + ".seed");
        const json& r = require(g, "range", where + ".range");
        if (!r.is_array() || r.size() != 2) fail(where + ".range", "must be [lo, hi]");
        out.options.lo = number(r[0], where + ".range");
        out.options.hi = number(r[1], where + ".range");
        if (!(out.options.lo <= out.options.hi)) fail(where + ".range", "lo must not be above hi");
        if (const json* b = member(g, "within"); b && !b->is_null()) out.options.within = box(*b, where + ".within");
        return out;
    }

    SliceViewsState slice_views(const json& sv) const {
        if (!sv.is_object()) fail("slice_views", "must be an object, not a " + std::string(sv.type_name()));
        SliceViewsState out;
        out.crosshair = vec3(require(sv, "crosshair", "slice_views.crosshair"), "slice_views.crosshair");
        for (std::size_t i = 0; i < 3; ++i) {
            const std::string name = slice_orientation_name(SliceOrientation(i)), where = "slice_views." + name;
            const json& view = object(sv, name.c_str(), where, true);
            SliceViewState& v = out.views[i];
            v.origin = vec3(require(view, "origin", where + ".origin"), where + ".origin");
            v.center = vec3(require(view, "center", where + ".center"), where + ".center");
            v.pixel_mm = number(require(view, "pixel_mm", where + ".pixel_mm"), where + ".pixel_mm");
            if (!(v.pixel_mm > 0.0)) fail(where + ".pixel_mm", "must be positive");
        }
        return out;
    }

    VolumeLook volume(const json& v) const {
        if (!v.is_object()) fail("volume", "must be an object, not a " + std::string(v.type_name()));
        VolumeLook look;
        look.enabled = boolean(v, "enabled", "volume.enabled", false);
        try {
            look.tf = TransferFunction::parse(string(v, "transfer_function", "volume.transfer_function", true));
        } catch (const Error& e) {
            fail("volume.transfer_function", e.reason());
        }
        const std::string mode = string(v, "mode", "volume.mode", false);
        if (!mode.empty()) {
            try {
                look.mode = volume_mode_from_name(mode);
            } catch (const Error&) {
                fail("volume.mode", "must be \"composite\", \"mip\" or \"minip\", not \"" + mode + "\"");
            }
        }
        return look;
    }

    std::pair<glm::dvec3, glm::dvec3> clip_box(const json& c) const {
        if (!c.is_object()) fail("clip", "must be an object, not a " + std::string(c.type_name()));
        const json& box = object(c, "box", "clip.box", true);
        const glm::dvec3 lo = vec3(require(box, "min", "clip.box.min"), "clip.box.min");
        const glm::dvec3 hi = vec3(require(box, "max", "clip.box.max"), "clip.box.max");
        for (int i = 0; i < 3; ++i)
            if (lo[i] > hi[i]) fail("clip.box", "min must not exceed max on any axis");
        return {lo, hi};
    }

    Camera camera(const json& c) const {
        if (!c.is_object()) fail("camera", "must be an object, not a " + std::string(c.type_name()));
        Camera cam;
        cam.eye = vec3(require(c, "eye", "camera.eye"), "camera.eye");
        cam.target = vec3(require(c, "target", "camera.target"), "camera.target");
        cam.up = vec3(require(c, "up", "camera.up"), "camera.up");
        cam.fov_y_degrees = number(require(c, "fov_y_degrees", "camera.fov_y_degrees"), "camera.fov_y_degrees");
        if (!(cam.fov_y_degrees > 0.0 && cam.fov_y_degrees < 180.0))
            fail("camera.fov_y_degrees", "must be between 0 and 180");
        const glm::dvec3 forward = cam.target - cam.eye;
        if (!(glm::length(forward) > 0.0)) fail("camera", "eye and target are the same point");
        if (!(glm::length(glm::cross(forward, cam.up)) > 1e-12 * glm::length(forward) * glm::length(cam.up)))
            fail("camera.up", "is zero or along the viewing direction");
        return cam;
    }

    const std::string& path_;
};

} // namespace

const char* view_layout_name(ViewLayout l) {
    switch (l) {
    case ViewLayout::FourUp: return "four_up";
    case ViewLayout::Conventional: return "conventional";
    case ViewLayout::ThreeD: return "3d";
    case ViewLayout::Axial: return "axial";
    case ViewLayout::Coronal: return "coronal";
    case ViewLayout::Sagittal: return "sagittal";
    }
    return "four_up";
}

std::optional<ViewLayout> view_layout_from_name(const std::string& name) {
    for (const ViewLayout l : {ViewLayout::FourUp, ViewLayout::Conventional, ViewLayout::ThreeD, ViewLayout::Axial,
                               ViewLayout::Coronal, ViewLayout::Sagittal})
        if (name == view_layout_name(l)) return l;
    return std::nullopt;
}

SliceViewsState capture_slice_views(const std::array<SlicePlane, 3>& planes) {
    SliceViewsState s;
    s.crosshair = crosshair_point(planes);
    for (std::size_t i = 0; i < 3; ++i) s.views[i] = {planes[i].origin, planes[i].center, planes[i].pixel_mm};
    return s;
}

void apply_slice_views(const SliceViewsState& s, std::array<SlicePlane, 3>& planes) {
    set_crosshair(planes, s.crosshair);
    for (std::size_t i = 0; i < 3; ++i) {
        SlicePlane& p = planes[i];
        const SliceViewState& v = s.views[i];
        p.origin = v.origin;
        p.center = v.center + glm::dot(v.origin - v.center, p.normal) * p.normal; // on the plane
        if (v.pixel_mm > 0.0 && std::isfinite(v.pixel_mm)) p.pixel_mm = v.pixel_mm;
    }
}

Session capture_session(const Scene& scene, const std::string& input, const std::string& series,
                        const std::optional<Camera>& camera, const std::optional<WindowLevel>& window,
                        const FrameLook& view, std::vector<Markup> markups) {
    Session s;
    s.input = input.empty() ? std::string() : normal_absolute(input).string();
    s.series = series;
    for (const SurfaceId id : scene.surfaces()) {
        const auto& info = scene.info(id);
        SessionSurface ss;
        ss.kind = info.kind;
        ss.value = info.value;
        ss.name = info.name;
        ss.source = info.source.empty() ? s.input : normal_absolute(info.source).string();
        ss.color = hex_from_linear(info.color);
        ss.opacity = info.opacity;
        ss.visible = info.visible;
        ss.post = info.post;
        ss.grown = info.grown;
        s.surfaces.push_back(std::move(ss));
    }
    s.camera = camera;
    s.window = window;
    // The 3D view draws cone AO, ray-traced AO (refined while still) or none.
    s.ao = view.ao == AoMethod::Raytraced ? AoMethod::Raytraced
           : view.ao == AoMethod::Off     ? AoMethod::Off
                                          : AoMethod::Cone;
    s.transparency = view.transparency;
    if (!view.volume.tf.empty()) {
        VolumeLook v;
        v.enabled = view.volume.enabled;
        v.tf = view.volume.tf;
        v.mode = view.volume.mode;
        s.volume = v;
    }
    s.clip_box = view.clip.box;
    s.markups = std::move(markups);
    return s;
}

ordered_json session_json(const Session& s, const std::string& session_path) {
    ordered_json j;
    j["format"] = kFormat;
    j["version"] = kSessionVersion;
    j["input"] = {{"path", stored_path(s.input, session_path)}, {"sha256", s.input_sha256}, {"series", s.series}};
    j["surfaces"] = ordered_json::array();
    for (const auto& ss : s.surfaces) {
        ordered_json o;
        o["kind"] = kind_name(ss.kind);
        if (ss.kind != SurfaceInfo::Kind::Mesh) o["value"] = ss.value;
        o["name"] = ss.name;
        o["source"] = ss.source.empty() ? std::string() : stored_path(ss.source, session_path);
        o["color"] = ss.color;
        o["opacity"] = double(ss.opacity);
        o["visible"] = ss.visible;
        if (ss.kind != SurfaceInfo::Kind::Mesh) {
            o["smoothing"] = ss.post.smooth;
            o["decimate"] = ss.post.decimate;
            o["keep_largest"] = ss.post.keep_largest;
        }
        if (ss.post.keep_at) o["keep_at"] = vec_json(*ss.post.keep_at);
        if (ss.post.keep_within) o["keep_within"] = box_json(*ss.post.keep_within);
        if (!ss.post.steps.empty()) {
            o["steps"] = ordered_json::array();
            for (const PartStep& st : ss.post.steps) o["steps"].push_back(step_json(st));
        }
        if (const auto& g = ss.grown)
            o["grown"] = {{"seed", vec_json(g->seed)},
                          {"range", {g->options.lo, g->options.hi}},
                          {"within", g->options.within ? box_json(*g->options.within) : ordered_json(nullptr)}};
        j["surfaces"].push_back(o);
    }
    if (s.camera)
        j["camera"] = {{"eye", vec_json(s.camera->eye)},
                       {"target", vec_json(s.camera->target)},
                       {"up", vec_json(s.camera->up)},
                       {"fov_y_degrees", s.camera->fov_y_degrees}};
    else
        j["camera"] = nullptr;
    if (s.window)
        j["window_level"] = {{"center", s.window->center}, {"width", s.window->width}};
    else
        j["window_level"] = nullptr;
    j["view"] = {{"ao", s.ao != AoMethod::Off}, {"transparency", s.transparency}};
    if (s.ao == AoMethod::Raytraced) j["view"]["ao_method"] = "raytraced";
    if (s.slice_planes_in_3d) j["view"]["slice_planes"] = true; // written only when on, as ao_method
    if (s.markups.empty()) {
        j["markups"] = nullptr;
    } else {
        MarkupsFile f;
        f.markups = s.markups;
        j["markups"] = ordered_json::parse(markups_json_text(f, session_path + ": markups"));
    }
    // The desktop app's layout and slice views, when it recorded them.
    if (s.layout) j["layout"] = view_layout_name(*s.layout);
    if (s.slice_views) {
        ordered_json sv;
        sv["crosshair"] = vec_json(s.slice_views->crosshair);
        for (std::size_t i = 0; i < 3; ++i) {
            const SliceViewState& v = s.slice_views->views[i];
            sv[slice_orientation_name(SliceOrientation(i))] = {
                {"origin", vec_json(v.origin)}, {"center", vec_json(v.center)}, {"pixel_mm", v.pixel_mm}};
        }
        j["slice_views"] = sv;
    }
    // The volume and the crop box, when there are any (else no field: files as before).
    if (s.volume)
        j["volume"] = {{"enabled", s.volume->enabled},
                       {"transfer_function", s.volume->tf.text()},
                       {"mode", volume_mode_name(s.volume->mode)}};
    if (s.clip_box)
        j["clip"] = {{"box", {{"min", vec_json(s.clip_box->first)}, {"max", vec_json(s.clip_box->second)}}}};
    return j;
}

Session session_from_json(const json& j, const std::string& session_path) { return Reader(session_path).read(j); }

void save_session(const Session& s, const std::string& path) {
    check_writable_destination(path);
    if (s.input.empty()) throw Error(path, "nothing is open: a session needs an input");
    Session copy = s;
    if (copy.input_sha256.empty()) copy.input_sha256 = sha256_of_path(copy.input);
    std::string text;
    try {
        text = session_json(copy, path).dump(2) + "\n";
    } catch (const ordered_json::exception& e) {
        throw Error(path, std::string("a name or label is not valid UTF-8 (") + e.what() + ")");
    }
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error(path, "cannot create the file");
        out.write(text.data(), std::streamsize(text.size()));
        out.flush();
        if (!out) throw Error(path, "write failed (disk full?)");
    });
}

Session read_session(const std::string& path) {
    const std::string text = read_file(path);
    if (text.empty()) throw Error(path, "file is empty");
    json root;
    try {
        root = json::parse(text);
    } catch (const json::exception& e) {
        throw Error(path, std::string("not valid JSON: ") + e.what());
    }
    return session_from_json(root, path);
}

Session load_session(const std::string& path) {
    Session s = read_session(path);
    std::error_code ec;
    if (!fs::exists(s.input, ec)) throw Error(path, "input.path: '" + s.input + "' does not exist");
    if (!s.input_sha256.empty() && sha256_of_path(s.input) != s.input_sha256)
        s.warnings.push_back(s.input +
                             " changed since the session was saved (its SHA-256 differs): the surfaces may differ");
    return s;
}

bool same_state(const Session& a, const Session& b) {
    // Compared as stored next to each other: paths, colours and numbers as written.
    const std::string where = (fs::temp_directory_path() / "same_state.json").string();
    auto ja = session_json(a, where), jb = session_json(b, where);
    ja["input"]["sha256"] = jb["input"]["sha256"] = "";
    return ja == jb;
}

namespace {

// What a mesh surface keeps of its parent (a mesh has no smoothing of its own).
PostProcessOptions part_only(const PostProcessOptions& post) {
    PostProcessOptions part;
    part.keep_at = post.keep_at;
    part.keep_within = post.keep_within;
    part.steps = post.steps;
    return part;
}

// A grown region grown again from its seed, then cut as it was.
SurfaceId add_grown(Scene& scene, const SessionSurface& ss, const std::string& input, const std::string& where,
                    const ProgressFn& progress) {
    if (!scene.has_volume()) throw Error(input, where + ": a grown region, but the input is not a volume");
    GrownPlan g = plan_grown(scene, ss.grown->seed, ss.grown->options, progress);
    SurfaceInfo info = grown_info(scene, g.grown);
    info.post = part_only(ss.post);
    return scene.add_mesh(needs_postprocess(info.post) ? postprocess(g.mesh, info.post) : std::move(g.mesh), info);
}

} // namespace

OpenedSession open_session(const Session& s, const ProgressFn& progress) {
    OpenedSession o;
    o.session = s;
    o.scene = std::make_unique<Scene>();
    Scene& scene = *o.scene;
    // The load is a third of the bar, the surfaces the rest.
    const std::size_t n = s.surfaces.size();
    const auto part = [&](double from, double to) -> ProgressFn {
        if (!progress) return {};
        return
            [progress, from, to](double f, std::string_view stage) { return progress(from + f * (to - from), stage); };
    };
    LoadOptions lo;
    lo.series = s.series;
    lo.progress = part(0.0, n ? 0.3 : 1.0);
    scene.open(s.input, lo);
    std::vector<SurfaceId> meshes = scene.surfaces(); // a mesh input's surface
    std::size_t next_mesh = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const auto& ss = s.surfaces[i];
        const auto where =
            "surface " + std::to_string(i + 1) + (ss.name.empty() ? std::string() : " ('" + ss.name + "')");
        const ProgressFn p = part(0.3 + 0.7 * double(i) / double(n), 0.3 + 0.7 * double(i + 1) / double(n));
        std::vector<SurfaceId> ids;
        if (ss.grown) {
            ids = {add_grown(scene, ss, s.input, where, p)};
        } else if (ss.kind == SurfaceInfo::Kind::Mesh && keeps_a_part(ss.post) && !meshes.empty()) {
            // A part (a component, within a box, cut) of the mesh input: made again from it.
            SurfaceInfo info = scene.info(meshes.front());
            info.post = ss.post;
            ids = {scene.add_mesh(postprocess(scene.mesh(meshes.front()), part_only(ss.post)), info)};
        } else if (ss.kind == SurfaceInfo::Kind::Mesh) {
            if (next_mesh >= meshes.size())
                throw Error(s.input, where + ": a mesh surface, but the input is not a mesh file");
            ids = {meshes[next_mesh++]};
        } else if (!scene.has_volume()) {
            throw Error(s.input,
                        where + ": an " + std::string(kind_name(ss.kind)) + " surface, but the input is not a volume");
        } else if (ss.kind == SurfaceInfo::Kind::Iso) {
            ids = {scene.add_isosurface(scene.extract_isosurface(ss.value, {}, ss.post, p), ss.value, ss.post)};
        } else {
            ids = scene.add_label_surfaces({ss.value}, {}, ss.post, p);
            if (ids.empty()) throw Error(s.input, where + ": the volume has no label " + std::to_string(ss.value));
        }
        for (const SurfaceId id : ids) {
            auto& info = scene.info(id);
            if (!ss.name.empty()) info.name = ss.name;
            info.color = linear_from_hex(ss.color);
            info.opacity = ss.opacity;
            info.visible = ss.visible;
            o.surfaces.push_back(id);
        }
    }
    return o;
}

OpenedSession open_session(const std::string& path, const ProgressFn& progress) {
    Session s = load_session(path);
    try {
        return open_session(s, progress);
    } catch (const Cancelled&) {
        throw;
    } catch (const Error& e) {
        // The input's own error (a damaged file, a surface it cannot have), under the session's name.
        throw Error(path, e.what());
    }
}

RenderRequest session_request(const Session& s, const std::string& session_file, RenderRequest frame,
                              const SessionParts& take) {
    if (take.camera) frame.camera = s.camera;
    if (take.markups) frame.markups.insert(frame.markups.end(), s.markups.begin(), s.markups.end());
    if (take.ao) frame.look.ao = s.ao;
    frame.look.transparency = s.transparency;
    if (s.volume) {
        frame.look.volume.enabled = s.volume->enabled;
        frame.look.volume.tf = s.volume->tf;
        frame.look.volume.mode = s.volume->mode;
    }
    if (s.clip_box) frame.look.clip.box = s.clip_box;
    frame.session_file = session_file;
    return frame;
}

} // namespace iso::core
