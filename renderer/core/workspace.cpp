#include "renderer/core/workspace.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "io/error.hpp"
#include "renderer/core/presets.hpp"

namespace iso::core {

namespace {

bool same_mesh(const std::shared_ptr<const Mesh>& a, const std::shared_ptr<const Mesh>& b) {
    if (a == b) return true;
    if (!a || !b) return false;
    return a->positions == b->positions && a->triangles == b->triangles;
}

bool same_surfaces(const std::vector<WorkspaceState::Surface>& a, const std::vector<WorkspaceState::Surface>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (a[i].id != b[i].id || !(a[i].info == b[i].info) || !same_mesh(a[i].mesh, b[i].mesh)) return false;
    return true;
}

// The selection after the markups went from `old` to `now`: it stays while
// its markup can only have stayed where it was.
std::optional<std::size_t> kept_selection(std::optional<std::size_t> sel, const MarkupsState& old,
                                          const MarkupsState& now) {
    if (!sel) return sel;
    if (now.markups.size() < old.markups.size() || *sel >= now.markups.size() || *sel >= old.markups.size() ||
        now.markups[*sel].type != old.markups[*sel].type)
        return std::nullopt;
    return sel;
}

// The parts held as plain values (all but the surfaces, which are the
// scene's, and the markups and selection, which keep each other in step):
// copied from one state to another, the one list capture and restore share.
constexpr Parts kPlainParts = Part::Look | Part::Camera | Part::Window | Part::Slices | Part::Layout;
void copy_plain_parts(const WorkspaceState& from, WorkspaceState& to, Parts parts) {
    if (has(parts, Part::Look)) to.look = from.look;
    if (has(parts, Part::Camera)) to.camera = from.camera;
    if (has(parts, Part::Window)) to.window = from.window;
    if (has(parts, Part::Slices)) to.planes = from.planes;
    if (has(parts, Part::Layout)) {
        to.layout = from.layout;
        to.slice_planes_in_3d = from.slice_planes_in_3d;
    }
}

void check_crop(const Clip& clip) {
    if (!clip.box) return;
    const auto& [lo, hi] = *clip.box;
    const char* axis[] = {"L", "P", "S"};
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]))
            throw Error("crop box", std::string("its ") + axis[a] + " bounds are not finite");
        if (lo[a] > hi[a])
            throw Error("crop box", std::string("its ") + axis[a] + " minimum " + std::to_string(lo[a]) +
                                        " mm is above its maximum " + std::to_string(hi[a]) + " mm");
    }
}

} // namespace

bool same_parts(const WorkspaceState& a, const WorkspaceState& b, Parts p) {
    if (has(p, Part::Surfaces) && !same_surfaces(a.surfaces, b.surfaces)) return false;
    if (has(p, Part::Look) && !(a.look == b.look)) return false;
    if (has(p, Part::Camera) && a.camera != b.camera) return false;
    if (has(p, Part::Window) && !(a.window == b.window)) return false;
    if (has(p, Part::Slices) && a.planes != b.planes) return false;
    if (has(p, Part::Layout) && (a.layout != b.layout || a.slice_planes_in_3d != b.slice_planes_in_3d)) return false;
    if (has(p, Part::Markups) && !(a.markups == b.markups)) return false;
    if (has(p, Part::Selection) && a.selected != b.selected) return false;
    return true;
}

bool WorkspaceEdit::merge(const WorkspaceEdit& next) {
    if (merge_key.empty() || next.merge_key != merge_key || next.parts != parts) return false;
    after = next.after;
    return true;
}

Workspace::Workspace(FrameLook look) : scene_(std::make_unique<Scene>()) {
    live_.look = std::move(look);
    saved_ = capture(kEditedParts);
}

Workspace::~Workspace() = default;

// ---- what is open ---------------------------------------------------------------------

void Workspace::reset(std::unique_ptr<Scene> scene, std::string input, std::string series) {
    // The old scene lives until the observers heard of the new one: a view
    // releases its GPU copies through it, a worker reading it stops.
    std::unique_ptr<Scene> old = std::move(scene_);
    scene_ = scene ? std::move(scene) : std::make_unique<Scene>();
    input_ = std::move(input);
    series_ = std::move(series);
    session_path_.clear();
    const FrameLook kept = live_.look;
    const ViewLayout layout = live_.layout;
    const bool planes_in_3d = live_.slice_planes_in_3d;
    live_ = {};
    live_.look = kept;
    live_.layout = layout;
    live_.slice_planes_in_3d = planes_in_3d;
    live_.look.clip = {};
    live_.look.volume.enabled = false;
    live_.look.volume.tf = initial_transfer_function(*scene_);
    if (scene_->has_volume()) {
        live_.planes = default_planes(scene_->volume());
        live_.window = default_window(*scene_);
    }
    saved_ = capture(kEditedParts);
    force_modified_ = false;
    notify(Parts(~0u));
    old.reset();
}

// Two notifications: reset()'s (new data: the views start afresh, the slice
// views fit their default planes), then the session's parts over it (the
// slice views keep the session's framing because it comes after their fit).
void Workspace::adopt(OpenedSession opened, const std::string& session_path) {
    const Session& s = opened.session;
    reset(std::move(opened.scene), s.input, s.series);
    if (s.window) live_.window = *s.window;
    if (s.layout) live_.layout = *s.layout;
    live_.slice_planes_in_3d = s.slice_planes_in_3d;
    if (s.slice_views && scene_->has_volume()) apply_slice_views(*s.slice_views, live_.planes);
    live_.markups.markups = s.markups;
    live_.markups.sources.assign(s.markups.size(), {});
    live_.look.ao = s.ao;
    live_.look.transparency = s.transparency;
    if (s.volume && scene_->has_volume()) {
        live_.look.volume.enabled = s.volume->enabled;
        live_.look.volume.tf = s.volume->tf;
        live_.look.volume.mode = s.volume->mode;
    }
    if (scene_->has_volume()) live_.look.clip.box = s.clip_box;
    live_.camera = s.camera;
    session_path_ = session_path;
    saved_ = capture(kEditedParts);
    force_modified_ = session_path.empty();
    notify(Parts(~0u) & ~Parts(Part::Data)); // the data's notification was reset()'s
}

Session Workspace::session() const {
    std::optional<WindowLevel> window;
    if (scene_->has_volume()) window = live_.window;
    Session s = capture_session(*scene_, input_, series_, live_.camera, window, live_.look, live_.markups.markups);
    s.layout = live_.layout;
    s.slice_planes_in_3d = live_.slice_planes_in_3d;
    if (scene_->has_volume()) s.slice_views = capture_slice_views(live_.planes);
    return s;
}

void Workspace::mark_saved(const std::string& path) {
    session_path_ = path;
    saved_ = capture(kEditedParts);
    force_modified_ = false;
    notify(Parts(Part::File));
}

bool Workspace::modified() const {
    if (force_modified_) return true;
    const WorkspaceState now = capture(kEditedParts);
    // Of the look, what the Volume panel edits: the view's AO and
    // transparency toggles are view settings (kept, not edits).
    return !same_parts(saved_, now, kEditedParts & ~Parts(Part::Look)) || !(saved_.look.volume == now.look.volume) ||
           !(saved_.look.clip == now.look.clip);
}

void Workspace::mark_unsaved() {
    force_modified_ = true;
    notify(Parts(Part::File));
}

WorkspaceState Workspace::capture(Parts parts) const {
    WorkspaceState s;
    if (has(parts, Part::Surfaces))
        for (const SurfaceId id : scene_->surfaces())
            s.surfaces.push_back({id, scene_->info(id), scene_->shared_mesh(id)});
    copy_plain_parts(live_, s, parts & kPlainParts);
    if (has(parts, Part::Markups)) s.markups = live_.markups;
    if (has(parts, Part::Selection)) s.selected = live_.selected;
    return s;
}

// ---- parts, changed -------------------------------------------------------------------

void Workspace::set_look(const FrameLook& look) {
    validate(look);
    check_crop(look.clip);
    if (look == live_.look) return;
    live_.look = look;
    notify(Parts(Part::Look));
}

void Workspace::set_camera(const Camera& c) {
    if (live_.camera == c) return;
    live_.camera = c;
    notify(Parts(Part::Camera));
}

void Workspace::set_window(const WindowLevel& w) {
    if (!std::isfinite(w.center) || !std::isfinite(w.width) || w.width < 0)
        throw Error("window/level", "the window's centre and width must be finite, the width not negative");
    if (w == live_.window) return;
    live_.window = w;
    notify(Parts(Part::Window));
}

void Workspace::set_planes(const std::array<SlicePlane, 3>& planes) {
    if (planes == live_.planes) return;
    live_.planes = planes;
    notify(Parts(Part::Slices));
}

void Workspace::set_crosshair(const glm::dvec3& lps, std::optional<SliceOrientation> keep) {
    if (!scene_->has_volume()) return;
    std::array<SlicePlane, 3> p = live_.planes;
    std::optional<SlicePlane> kept;
    if (keep) kept = p[std::size_t(*keep)];
    core::set_crosshair(p, lps);
    if (kept) { // its crosshair moves to the point, its slice stays
        auto& k = p[std::size_t(*keep)];
        k.center = kept->center;
        set_offset(k, kept->offset_mm());
    }
    set_planes(p);
}

void Workspace::set_layout(ViewLayout l) {
    if (l == live_.layout) return;
    live_.layout = l;
    notify(Parts(Part::Layout));
}

void Workspace::set_slice_planes_in_3d(bool on) {
    if (on == live_.slice_planes_in_3d) return;
    live_.slice_planes_in_3d = on;
    notify(Parts(Part::Layout));
}

void Workspace::set_markups(MarkupsState m) {
    m.sources.resize(m.markups.size());
    const auto sel = kept_selection(live_.selected, live_.markups, m);
    Parts parts = Parts(Part::Markups);
    if (sel != live_.selected) parts |= Part::Selection;
    live_.markups = std::move(m);
    live_.selected = sel;
    notify(parts);
}

void Workspace::select(std::optional<std::size_t> index) {
    if (index && *index >= live_.markups.markups.size()) index.reset();
    if (index == live_.selected) return;
    live_.selected = index;
    notify(Parts(Part::Selection));
}

// ---- surfaces -----------------------------------------------------------------------

SurfaceId Workspace::add_isosurface(PreparedMesh m, double iso, const PostProcessOptions& post,
                                    std::optional<glm::vec3> color) {
    const SurfaceId id = scene_->add_isosurface(std::move(m), iso, post, color);
    notify(Parts(Part::Surfaces));
    return id;
}

SurfaceId Workspace::add_mesh(PreparedMesh m, SurfaceInfo info) {
    const SurfaceId id = scene_->add_mesh(std::move(m), std::move(info));
    notify(Parts(Part::Surfaces));
    return id;
}

void Workspace::set_surface_info(SurfaceId id, const SurfaceInfo& info) {
    SurfaceInfo& now = scene_->info(id);
    if (!(info.opacity >= 0.0f && info.opacity <= 1.0f))
        throw Error("surface '" + now.name + "'", "the opacity must be between 0 and 1");
    SurfaceInfo next = info;
    // What the mesh was made with stays the mesh's.
    next.kind = now.kind;
    next.value = now.value;
    next.source = now.source;
    next.post = now.post;
    if (next == now) return;
    now = std::move(next);
    notify(Parts(Part::Surfaces));
}

void Workspace::replace_surface(SurfaceId id, PreparedMesh m, double value, const PostProcessOptions& post) {
    scene_->replace_surface(id, std::move(m), value, post);
    notify(Parts(Part::Surfaces));
}

void Workspace::remove_surface(SurfaceId id) {
    scene_->remove_surface(id);
    notify(Parts(Part::Surfaces));
}

std::optional<SurfaceId> Workspace::existing_component(const ComponentPlan& plan) const {
    // A single isolated component isolated again (within the same box, or none) is itself.
    if (scene_->has_surface(plan.from) && plan.components == 1 && kept_at(scene_->info(plan.from).post) &&
        scene_->info(plan.from).post.keep_within == plan.info.post.keep_within &&
        (plan.info.post.steps.empty() || !plan.info.post.steps.back().within))
        return plan.from;
    for (const SurfaceId id : scene_->surfaces()) {
        if (id == plan.from) continue;
        const SurfaceInfo& info = scene_->info(id);
        if (!kept_at(info.post) || info.kind != plan.info.kind || info.value != plan.info.value) continue;
        const Mesh& m = scene_->mesh(id);
        if (m.positions == plan.mesh.positions && m.triangles == plan.mesh.triangles) return id;
    }
    return std::nullopt;
}

Workspace::Isolation Workspace::isolate(ComponentPlan plan) {
    Isolation out;
    if (const auto existing = existing_component(plan)) {
        out.added = false;
        out.isolated.surface = out.isolated.measured.surface = *existing;
        out.isolated.from = plan.from;
        out.isolated.component = plan.component;
        out.isolated.components = plan.components;
        const SurfaceInfo& info = scene_->info(*existing);
        out.isolated.measured.name = info.name;
        out.isolated.measured.kind = info.kind;
        out.isolated.measured.value = info.value;
        out.isolated.measured.measures = std::move(plan.measures);
    } else {
        out.isolated = add_component(*scene_, std::move(plan));
    }
    // The structure alone on screen: it shown, its parent hidden.
    scene_->info(out.isolated.surface).visible = true;
    if (out.isolated.from != out.isolated.surface && scene_->has_surface(out.isolated.from))
        scene_->info(out.isolated.from).visible = false;
    notify(Parts(Part::Surfaces));
    return out;
}

// ---- edits --------------------------------------------------------------------------

WorkspaceEdit Workspace::record(std::string text, Parts parts, const std::function<void()>& change,
                                std::string merge_key) {
    WorkspaceEdit e;
    e.text = std::move(text);
    e.parts = parts;
    e.merge_key = std::move(merge_key);
    e.before = capture(parts);
    try {
        change();
    } catch (...) {
        restore(e.before, parts);
        throw;
    }
    e.after = capture(parts);
    return e;
}

void Workspace::restore_surfaces(const std::vector<WorkspaceState::Surface>& surfaces) {
    for (const SurfaceId id : scene_->surfaces())
        if (std::none_of(surfaces.begin(), surfaces.end(), [id](const auto& s) { return s.id == id; }))
            scene_->remove_surface(id);
    for (const auto& s : surfaces) scene_->set_surface(s.id, s.mesh, s.info);
}

void Workspace::restore(const WorkspaceState& s, Parts parts) {
    if (has(parts, Part::Surfaces)) restore_surfaces(s.surfaces);
    copy_plain_parts(s, live_, parts & kPlainParts);
    if (has(parts, Part::Markups)) {
        if (!has(parts, Part::Selection)) {
            const auto sel = kept_selection(live_.selected, live_.markups, s.markups);
            if (sel != live_.selected) parts |= Part::Selection;
            live_.selected = sel;
        }
        live_.markups = s.markups;
    }
    if (has(parts, Part::Selection)) live_.selected = s.selected;
    notify(parts);
}

// ---- observers ----------------------------------------------------------------------

std::uint64_t Workspace::revision(Parts parts) const {
    std::uint64_t r = 0;
    for (std::size_t bit = 0; bit < revisions_.size(); ++bit)
        if (parts & (Parts(1) << bit)) r += revisions_[bit];
    return r;
}

int Workspace::observe(Observer o) {
    observers_.emplace_back(next_observer_, std::move(o));
    return next_observer_++;
}

void Workspace::unobserve(int handle) {
    std::erase_if(observers_, [handle](const auto& p) { return p.first == handle; });
}

void Workspace::notify(Parts parts) {
    ++notifications_;
    for (std::size_t bit = 0; bit < revisions_.size(); ++bit)
        if (parts & (Parts(1) << bit)) ++revisions_[bit];
    // A change an observer makes while hearing of another is told after it,
    // so that every observer hears of the changes in the order they happened.
    if (notifying_) {
        pending_ |= parts;
        return;
    }
    notifying_ = true;
    struct Done {
        bool& flag;
        ~Done() { flag = false; }
    } done{notifying_};
    for (Parts next = parts; next; next = std::exchange(pending_, 0)) {
        // A copy: an observer may observe or unobserve.
        const auto observers = observers_;
        for (const auto& [handle, o] : observers)
            if (std::any_of(observers_.begin(), observers_.end(), [h = handle](const auto& p) { return p.first == h; }))
                o(next);
    }
}

std::unique_ptr<Workspace> open_workspace(const std::string& session_path, FrameLook look, const ProgressFn& progress) {
    auto w = std::make_unique<Workspace>(std::move(look));
    w->adopt(open_session(session_path, progress), session_path);
    return w;
}

// ---- history --------------------------------------------------------------------------

void EditHistory::push(WorkspaceEdit e) {
    edits_.resize(index_);
    if (!edits_.empty() && edits_.back().merge(e)) return;
    edits_.push_back(std::move(e));
    index_ = edits_.size();
}

std::string EditHistory::undo_text() const { return can_undo() ? edits_[index_ - 1].text : std::string(); }
std::string EditHistory::redo_text() const { return can_redo() ? edits_[index_].text : std::string(); }

bool EditHistory::undo(Workspace& w) {
    if (!can_undo()) return false;
    --index_;
    w.restore(edits_[index_].before, edits_[index_].parts);
    return true;
}

bool EditHistory::redo(Workspace& w) {
    if (!can_redo()) return false;
    w.restore(edits_[index_].after, edits_[index_].parts);
    ++index_;
    return true;
}

void EditHistory::clear() {
    edits_.clear();
    index_ = 0;
}

} // namespace iso::core
