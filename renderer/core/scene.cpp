#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <optional>

#include "io/color.hpp"
#include "io/error.hpp"
#include "renderer/core/surface_name.hpp"

namespace iso::core {

struct Scene::Impl {
    struct Entry {
        SurfaceInfo info;
        std::shared_ptr<const Mesh> mesh; // shared with snapshots: replaced, never changed in place
        std::shared_ptr<SurfaceLod> lod;  // the mesh's levels of detail (built when a frame first asks)
        Bounds bounds;
        std::uint64_t version = 0;                        // a new one with each mesh (and removal)
        bool removed = false;                             // the id stays taken: ids equal the renderer's object ids
        std::shared_ptr<const OutlineIndex> outline = {}; // its blocks' bounds for slice outlines (made on first use)
    };
    std::vector<Entry> surfaces;
    std::uint64_t versions = 0;
    SnapshotRenderer gpu;
    // Meshes the surfaces had (an undo step may bring one back) with what
    // was worked out for them: taken again, not worked out again.
    struct Known {
        std::weak_ptr<const Mesh> mesh;
        Bounds bounds;
        std::shared_ptr<const OutlineIndex> outline;
    };
    std::vector<Known> known;
    // A new mesh for `e` (null: removed), with its bounds and outline index when known.
    void set_mesh(Entry& e, PreparedMesh m) {
        std::erase_if(known, [](const Known& k) { return k.mesh.expired(); });
        if (e.mesh) known.push_back({e.mesh, e.bounds, e.outline});
        if (m.mesh && !m.bounds)
            for (const Known& k : known)
                if (k.mesh.lock() == m.mesh) {
                    m.bounds = k.bounds;
                    if (!m.outline) m.outline = k.outline;
                }
        if (m.mesh && !m.bounds) {
            Bounds b;
            for (const auto& p : m.mesh->positions) b.add(glm::dvec3(p));
            m.bounds = b;
        }
        e.bounds = m.mesh ? *m.bounds : Bounds{};
        e.outline = m.mesh ? std::move(m.outline) : nullptr;
        e.lod = m.mesh ? std::make_shared<SurfaceLod>(m.mesh) : nullptr;
        e.mesh = std::move(m.mesh);
        e.version = ++versions;
    }
    void set_mesh(Entry& e, std::shared_ptr<const Mesh> m) {
        PreparedMesh p;
        p.mesh = std::move(m);
        set_mesh(e, std::move(p));
    }
    std::shared_ptr<const Volume> volume; // shared with snapshots: replaced, never changed in place
    std::uint64_t volume_version = 0;
    std::string volume_source;
    std::vector<std::string> sources;
    // Computed once per volume, read by extractions on worker threads.
    mutable std::mutex cache_mutex;
    mutable std::shared_ptr<const ChunkIndex> index;
    mutable std::optional<ValueRange> range;

    Entry& at(SurfaceId id, const char* op) {
        if (id == 0 || id > surfaces.size() || surfaces[id - 1].removed)
            throw Error(op, "no surface with id " + std::to_string(id) +
                                (id != 0 && id <= surfaces.size() ? " (it was removed)" : ""));
        return surfaces[id - 1];
    }
    // The cached range index when it fits `opt`, else a fresh one (kept for
    // next time). Made outside the lock: other threads asking meanwhile wait for nothing.
    Extractor extractor(const Volume& v, const ExtractOptions& opt) const {
        std::shared_ptr<const ChunkIndex> cached;
        {
            std::lock_guard lock(cache_mutex);
            cached = index;
        }
        Extractor x(v, opt, cached);
        if (x.shared_index() != cached) {
            std::lock_guard lock(cache_mutex);
            index = x.shared_index();
        }
        return x;
    }
};

PreparedMesh::PreparedMesh(Mesh m) : mesh(std::make_shared<const Mesh>(std::move(m))) {}

PreparedMesh prepare_mesh(Mesh m) {
    PreparedMesh p(std::move(m));
    Bounds b;
    for (const auto& v : p.mesh->positions) b.add(glm::dvec3(v));
    p.bounds = b;
    p.outline = std::make_shared<const OutlineIndex>(outline_index(*p.mesh));
    return p;
}

Scene::Scene() : impl_(std::make_unique<Impl>()) {}
Scene::~Scene() = default;

SurfaceId Scene::open(const std::string& path, const LoadOptions& opt) {
    if (is_mesh_path(path)) {
        SurfaceInfo info;
        info.name = std::filesystem::path(path).filename().string();
        info.source = path;
        info.color = surface_color(0, 1);
        const SurfaceId id = add_mesh(load_mesh(path), info);
        impl_->sources.push_back(path);
        return id;
    }
    set_volume(load_volume(path, opt), path);
    return 0;
}

void Scene::set_volume(Volume v, const std::string& source) {
    {
        std::lock_guard lock(impl_->cache_mutex);
        impl_->index.reset();
        impl_->range.reset();
    }
    impl_->volume = std::make_shared<const Volume>(std::move(v));
    impl_->volume_version = ++impl_->versions;
    impl_->volume_source = source;
    impl_->sources.push_back(source);
}

bool Scene::has_volume() const { return impl_->volume != nullptr; }

const Volume& Scene::volume() const {
    if (!impl_->volume) throw Error("Scene::volume", "no volume is open");
    return *impl_->volume;
}

std::shared_ptr<const Volume> Scene::shared_volume() const { return impl_->volume; }

const std::string& Scene::volume_source() const { return impl_->volume_source; }

namespace {

// Extraction is most of the work; post-processing shares the rest of the bar.
void postprocess_all(std::vector<Mesh>& meshes, const PostProcessOptions& post, const ProgressFn& progress,
                     double share) {
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        const double base = share + (1.0 - share) * double(i) / double(meshes.size());
        ProgressFn pp;
        if (progress)
            pp = [&](double f, std::string_view stage) {
                return progress(base + f * (1.0 - share) / double(meshes.size()), stage);
            };
        auto warnings = meshes[i].warnings;
        meshes[i] = postprocess(meshes[i], post, pp);
        meshes[i].warnings = std::move(warnings);
    }
}

void warn_outside_range(Mesh& m, double iso, const ValueRange& range) {
    if (iso > range.max || iso <= range.min) {
        char w[160];
        std::snprintf(w, sizeof w, "iso value %g is outside the volume's value range [%g, %g]: the surface is empty",
                      iso, range.min, range.max);
        m.warnings.push_back(w);
    }
}

// Adds the seconds since `t` to `*to` (when the caller asked for them) and restarts `t`.
void lap(std::chrono::steady_clock::time_point& t, double* to) {
    const auto now = std::chrono::steady_clock::now();
    if (to) *to += std::chrono::duration<double>(now - t).count();
    t = now;
}

ExtractOptions with_share(ExtractOptions eo, const ProgressFn& progress, double share) {
    if (progress)
        eo.progress = [progress, share](double f, std::string_view stage) { return progress(f * share, stage); };
    return eo;
}

} // namespace

std::vector<SurfaceId> Scene::add_isosurfaces(std::vector<double> isos, const ExtractOptions& extract,
                                              const PostProcessOptions& post, ProgressFn progress,
                                              ExtractSeconds* seconds) {
    const Volume& v = volume();
    if (isos.empty()) throw Error("isosurface extraction of " + impl_->volume_source, "no iso value given");
    std::sort(isos.begin(), isos.end());
    const bool pp = needs_postprocess(post);
    const double share = pp ? 0.6 : 1.0;
    std::vector<Mesh> meshes;
    auto t = std::chrono::steady_clock::now();
    {
        const Extractor x = impl_->extractor(v, with_share(extract, progress, share));
        lap(t, seconds ? &seconds->index : nullptr);
        auto chunked = x.extract(isos);
        lap(t, seconds ? &seconds->extract : nullptr);
        for (auto& c : chunked) {
            meshes.push_back(weld(c, x.options().threads));
            c = ChunkedSurface{}; // free the chunks as soon as they are welded
        }
        lap(t, seconds ? &seconds->weld : nullptr);
    }
    const auto range = value_range();
    lap(t, seconds ? &seconds->index : nullptr);
    for (std::size_t i = 0; i < meshes.size(); ++i) warn_outside_range(meshes[i], isos[i], range);
    if (pp) postprocess_all(meshes, post, progress, share);
    lap(t, seconds && pp ? &seconds->postprocess : nullptr);
    report(progress, 1.0, "done", "isosurface extraction");
    return add_extracted(std::move(meshes), SurfaceInfo::Kind::Iso, isos, post);
}

Mesh Scene::extract_isosurface(double iso, const ExtractOptions& extract, const PostProcessOptions& post,
                               ProgressFn progress) const {
    const Volume& v = volume();
    const bool pp = needs_postprocess(post);
    const double share = pp ? 0.6 : 1.0;
    Mesh m;
    {
        const Extractor x = impl_->extractor(v, with_share(extract, progress, share));
        m = weld(x.extract(iso), x.options().threads);
    }
    warn_outside_range(m, iso, value_range());
    if (pp) {
        std::vector<Mesh> one;
        one.push_back(std::move(m));
        postprocess_all(one, post, progress, share);
        m = std::move(one[0]);
    }
    report(progress, 1.0, "done", "isosurface extraction");
    return m;
}

ValueRange Scene::value_range() const {
    const Volume& v = volume();
    {
        std::lock_guard lock(impl_->cache_mutex);
        if (impl_->range) return *impl_->range;
    }
    const ValueRange r = v.value_range(); // outside the lock: an index being made elsewhere does not wait
    std::lock_guard lock(impl_->cache_mutex);
    impl_->range = r;
    return r;
}

SurfaceId Scene::add_isosurface(PreparedMesh m, double iso, const PostProcessOptions& post,
                                std::optional<glm::vec3> color) {
    SurfaceInfo info;
    info.name = surface_name(false, iso);
    info.kind = SurfaceInfo::Kind::Iso;
    info.value = iso;
    info.source = impl_->volume_source;
    info.post = post;
    // The first skin-toned, the next bone white, then distinct hues.
    const std::size_t n = surfaces().size();
    info.color = color ? *color : surface_color(n, std::max<std::size_t>(n + 1, 2));
    return add_mesh(std::move(m), info);
}

void Scene::replace_surface(SurfaceId id, PreparedMesh m, double value, const PostProcessOptions& post) {
    auto& e = impl_->at(id, "Scene::replace_surface");
    // The automatic "iso <old>" follows the value, and so does a part's
    // "iso <old> scissors 1" (its rest is the part's own).
    const std::string was = surface_name(false, e.info.value);
    if (e.info.kind == SurfaceInfo::Kind::Iso && e.info.name == was)
        e.info.name = surface_name(false, value);
    else if (e.info.kind == SurfaceInfo::Kind::Iso && keeps_a_part(e.info.post) && e.info.name.rfind(was + " ", 0) == 0)
        e.info.name = surface_name(false, value) + e.info.name.substr(was.size());
    e.info.value = value;
    e.info.post = post;
    impl_->set_mesh(e, std::move(m));
}

void Scene::remove_surface(SurfaceId id) {
    auto& e = impl_->at(id, "Scene::remove_surface");
    e.removed = true;
    impl_->set_mesh(e, std::shared_ptr<const Mesh>());
}

void Scene::restore_surface(SurfaceId id, Mesh m, SurfaceInfo info) {
    if (id == 0 || id > impl_->surfaces.size())
        throw Error("Scene::restore_surface", "no surface with id " + std::to_string(id) + " was ever added");
    auto& e = impl_->surfaces[id - 1];
    if (!e.removed) throw Error("Scene::restore_surface", "surface " + std::to_string(id) + " is not removed");
    if (!(info.opacity >= 0.0f && info.opacity <= 1.0f))
        throw Error("Scene::restore_surface", "opacity of '" + info.name + "' must be between 0 and 1");
    e.info = std::move(info);
    impl_->set_mesh(e, std::make_shared<const Mesh>(std::move(m))); // uploaded again into the same object id
    e.removed = false;
}

std::shared_ptr<const Mesh> Scene::shared_mesh(SurfaceId id) const { return impl_->at(id, "Scene::mesh").mesh; }

void Scene::set_surface(SurfaceId id, std::shared_ptr<const Mesh> m, SurfaceInfo info) {
    if (id == 0 || id > impl_->surfaces.size())
        throw Error("Scene::set_surface", "no surface with id " + std::to_string(id) + " was ever added");
    if (!m) throw Error("Scene::set_surface", "surface " + std::to_string(id) + " needs a mesh");
    if (!(info.opacity >= 0.0f && info.opacity <= 1.0f))
        throw Error("Scene::set_surface", "opacity of '" + info.name + "' must be between 0 and 1");
    auto& e = impl_->surfaces[id - 1];
    if (e.removed || e.mesh != m) impl_->set_mesh(e, std::move(m));
    e.removed = false;
    e.info = std::move(info);
}

bool Scene::has_surface(SurfaceId id) const {
    return id != 0 && id <= impl_->surfaces.size() && !impl_->surfaces[id - 1].removed;
}

std::vector<SurfaceId> Scene::add_label_surfaces(const std::vector<double>& labels, const ExtractOptions& extract,
                                                 const PostProcessOptions& post, ProgressFn progress,
                                                 ExtractSeconds* seconds) {
    const Volume& v = volume();
    const bool pp = needs_postprocess(post);
    const double share = pp ? 0.6 : 1.0;
    auto found = extract_labels(v, labels, with_share(extract, progress, share), seconds);
    std::vector<Mesh> meshes;
    for (auto& ls : found) meshes.push_back(std::move(ls.mesh));
    auto t = std::chrono::steady_clock::now();
    if (pp) postprocess_all(meshes, post, progress, share);
    lap(t, seconds && pp ? &seconds->postprocess : nullptr);
    report(progress, 1.0, "done", "label surface extraction");
    std::vector<double> values;
    for (const auto& ls : found) values.push_back(ls.label);
    return add_extracted(std::move(meshes), SurfaceInfo::Kind::Label, values, post);
}

std::vector<SurfaceId> Scene::add_extracted(std::vector<Mesh> meshes, SurfaceInfo::Kind kind,
                                            const std::vector<double>& values, const PostProcessOptions& post) {
    std::vector<SurfaceId> ids;
    const bool iso = kind == SurfaceInfo::Kind::Iso;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        SurfaceInfo info;
        info.name = surface_name(!iso, values[i]);
        info.kind = kind;
        info.value = values[i];
        info.post = post;
        info.source = impl_->volume_source;
        // Isosurfaces skin to bone; labels from the palette's distinct hues.
        info.color = iso ? surface_color(i, meshes.size()) : surface_color(i + 2, meshes.size() + 2);
        ids.push_back(add_mesh(std::move(meshes[i]), info));
    }
    return ids;
}

SurfaceId Scene::add_mesh(PreparedMesh m, SurfaceInfo info) {
    if (!(info.opacity >= 0.0f && info.opacity <= 1.0f))
        throw Error("Scene::add_mesh", "opacity of '" + info.name + "' must be between 0 and 1");
    if (!m.mesh) throw Error("Scene::add_mesh", "'" + info.name + "' has no mesh");
    impl_->surfaces.push_back({std::move(info), nullptr, nullptr, Bounds{}, 0, false});
    impl_->set_mesh(impl_->surfaces.back(), std::move(m));
    return SurfaceId(impl_->surfaces.size());
}

std::vector<SurfaceId> Scene::surfaces() const {
    std::vector<SurfaceId> ids;
    ids.reserve(impl_->surfaces.size());
    for (std::size_t i = 0; i < impl_->surfaces.size(); ++i)
        if (!impl_->surfaces[i].removed) ids.push_back(SurfaceId(i + 1));
    return ids;
}

SurfaceInfo& Scene::info(SurfaceId id) { return impl_->at(id, "Scene::info").info; }
const SurfaceInfo& Scene::info(SurfaceId id) const { return impl_->at(id, "Scene::info").info; }
const Mesh& Scene::mesh(SurfaceId id) const { return *impl_->at(id, "Scene::mesh").mesh; }

std::shared_ptr<const OutlineIndex> Scene::outline_index(SurfaceId id) const {
    auto& e = impl_->at(id, "Scene::outline_index");
    if (!e.outline) e.outline = std::make_shared<const OutlineIndex>(iso::core::outline_index(*e.mesh));
    return e.outline;
}

Bounds Scene::bounds() const {
    Bounds b;
    for (const auto& e : impl_->surfaces)
        if (!e.removed && e.info.visible && !e.bounds.empty()) {
            b.add(e.bounds.min);
            b.add(e.bounds.max);
        }
    return b;
}

std::vector<std::string> Scene::sources() const { return impl_->sources; }

Camera Scene::camera(PatientView view, double aspect) const { return camera(view, aspect, FrameLook{}); }

Bounds Scene::bounds(const FrameLook& look) const {
    Bounds b = bounds();
    if (!look.volume.enabled || !impl_->volume) return b;
    Bounds v = volume_bounds();
    if (look.clip.box) {
        v.min = glm::max(v.min, look.clip.box->first);
        v.max = glm::min(v.max, look.clip.box->second);
    }
    if (!v.empty()) {
        b.add(v.min);
        b.add(v.max);
    }
    return b;
}

Camera Scene::camera(PatientView view, double aspect, const FrameLook& look) const {
    const Bounds b = bounds(look);
    Camera c;
    c.set_view(view, b);
    c.fit(b, aspect);
    return c;
}

SceneSnapshot Scene::snapshot() const {
    SceneSnapshot s;
    s.surfaces.reserve(impl_->surfaces.size());
    for (const auto& e : impl_->surfaces) {
        SceneObject o;
        o.name = e.info.name;
        o.color = e.info.color;
        o.opacity = e.info.opacity;
        o.visible = e.info.visible && !e.removed;
        o.pickable = e.info.pickable && !e.removed;
        s.surfaces.push_back({e.mesh, e.version, std::move(o), e.lod}); // a removed slot has neither
    }
    s.bounds = bounds();
    if (impl_->volume) {
        s.volume = impl_->volume;
        s.volume_version = impl_->volume_version;
        std::lock_guard lock(impl_->cache_mutex);
        s.volume_index = impl_->index;
    }
    return s;
}

Bounds Scene::volume_bounds() const {
    Bounds b;
    if (!impl_->volume) return b;
    const Volume& v = *impl_->volume;
    for (int c = 0; c < 8; ++c)
        b.add(v.index_to_world(glm::dvec3((c & 1) ? double(v.dims[0] - 1) : 0.0, (c & 2) ? double(v.dims[1] - 1) : 0.0,
                                          (c & 4) ? double(v.dims[2] - 1) : 0.0)));
    return b;
}

RenderResult Scene::render(const Camera& camera, const RenderOptions& opt) {
    return impl_->gpu.render(snapshot(), camera, opt);
}

void Scene::release_gpu() { impl_->gpu.release(); }

bool Scene::has_gpu_data() const { return impl_->gpu.started(); }

void Scene::set_background_lod(bool on) { impl_->gpu.set_background_lod(on); }

bool Scene::lod_ready(SurfaceId id) const {
    const auto& e = impl_->surfaces.at(id - 1);
    return e.lod && e.lod->get() != nullptr;
}

Renderer& Scene::renderer() { return impl_->gpu.renderer(); }

SnapshotRenderer::SnapshotRenderer() = default;
SnapshotRenderer::~SnapshotRenderer() = default;

Renderer& SnapshotRenderer::renderer() {
    if (!renderer_) {
        renderer_ = std::make_unique<Renderer>();
        uploaded_.clear();
        volume_version_ = 0;
    }
    return *renderer_;
}

void SnapshotRenderer::release() {
    renderer_.reset();
    uploaded_.clear();
    lod_uploaded_.clear();
    volume_version_ = 0;
}

RenderResult SnapshotRenderer::render(const SceneSnapshot& s, const Camera& camera, const RenderOptions& opt) {
    Renderer& ren = renderer();
    // Upload what is new or changed, drop what was removed; carry the
    // properties a front end may have edited. Every slot keeps its place, so
    // the renderer's object ids (id AOV, picking) equal the surface ids.
    static const Mesh empty;
    for (std::size_t i = 0; i < s.surfaces.size(); ++i) {
        const auto& e = s.surfaces[i];
        if (i == uploaded_.size()) {
            ren.add(e.mesh ? *e.mesh : empty, e.object);
            uploaded_.push_back(e.version);
        } else if (uploaded_[i] != e.version) {
            if (e.mesh)
                ren.replace(std::uint32_t(i + 1), *e.mesh);
            else
                ren.remove(std::uint32_t(i + 1));
            uploaded_[i] = e.version;
        }
        ren.object(std::uint32_t(i + 1)) = e.object;
    }
    const double lod_seconds = upload_lod(s, opt);
    if (s.volume && s.volume_version != volume_version_) {
        ren.set_volume(s.volume, s.volume_index);
        volume_version_ = s.volume_version;
    }
    RenderResult r = ren.render(camera, opt);
    r.lod.build_seconds = lod_seconds;
    return r;
}

// Hands the renderer the levels of detail of the large visible surfaces
// that the frame asks for, building them first (or starting them in the
// background) when nobody has yet; returns the seconds spent building here.
double SnapshotRenderer::upload_lod(const SceneSnapshot& s, const RenderOptions& opt) {
    double seconds = 0.0;
    lod_uploaded_.resize(s.surfaces.size(), nullptr);
    for (std::size_t i = 0; i < s.surfaces.size(); ++i) {
        const auto& e = s.surfaces[i];
        if (!e.lod || !e.mesh || !e.object.visible) continue;
        if (lod_uploaded_[i] && renderer_->has_lod(std::uint32_t(i + 1))) continue;
        if (!opt.look.lod.enabled || opt.pick || e.mesh->triangles.size() < opt.look.lod.min_triangles) continue;
        auto l = e.lod->get();
        if (!l && background_lod_) e.lod->build_in_background();
        if (!l && !background_lod_) {
            seconds += e.lod->build_now();
            l = e.lod->get();
        }
        if (!l) continue;
        renderer_->set_lod(std::uint32_t(i + 1), *l);
        lod_uploaded_[i] = l.get();
    }
    return seconds;
}

void Scene::export_mesh(SurfaceId id, const std::string& path) const { save_mesh(mesh(id), path); }

void export_image(const Image& image, const ImageMetadata& meta, const std::string& path) {
    save_image(image, path, meta);
}

DicomCaptureResult export_dicom(const Scene& scene, const Image& image, const ImageMetadata& meta,
                                const std::string& dir, const DicomCaptureOptions& opt) {
    Metadata source;
    if (scene.has_volume()) {
        source = scene.volume().meta;
    } else if (const auto it = meta.text.find("isoscope:input"); it != meta.text.end()) {
        source.source = it->second.substr(0, it->second.find('\n')); // a mesh: its (first) file
    }
    return write_dicom_capture(image, meta, source, dir, opt);
}

glm::vec3 surface_color(std::size_t index, std::size_t count) {
    // Outer surfaces (lower CT values) skin-toned, inner ones bone white, then
    // ten other hues: each clearly apart from the one before it, on the slices'
    // grey too (CIE76 delta E 48 between skin and bone, 28 or more between any two).
    static const char* const palette[] = {"#e0906c", "#f9f6ec", "#d03a30", "#3a7bd5", "#4caf50", "#e0b020",
                                          "#8e44ad", "#20b8c8", "#e040a0", "#8a9a30", "#f07820", "#305080"};
    constexpr std::size_t n = std::size(palette);
    if (count == 1) return linear_from_hex(palette[1]);
    if (index < n) return linear_from_hex(palette[index]);
    // Beyond the palette: hues a golden angle apart, saturation and value
    // alternating, so neighbours differ and none repeats.
    const std::size_t j = index - n;
    const double h = std::fmod(0.05 + double(j) * 0.618033988749895, 1.0) * 6.0;
    const double sat = j % 2 ? 0.55 : 0.75, val = j % 3 == 1 ? 0.70 : 0.95;
    const double f = h - std::floor(h), p = val * (1 - sat), q = val * (1 - sat * f), t = val * (1 - sat * (1 - f));
    const glm::dvec3 rgb[] = {{val, t, p}, {q, val, p}, {p, val, t}, {p, q, val}, {t, p, val}, {val, p, q}};
    const glm::dvec3 c = rgb[int(h) % 6];
    return glm::vec3(float(linear_from_srgb(c.r)), float(linear_from_srgb(c.g)), float(linear_from_srgb(c.b)));
}

} // namespace iso::core
