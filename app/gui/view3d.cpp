#include "app/gui/view3d.hpp"

#include <QLabel>

#include <utility>

#include "app/gui/app_context.hpp"
#include "app/gui/crop_box.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"

namespace iso::gui {

namespace {
constexpr core::Parts kGuideParts = core::Part::Slices | core::Part::Layout | core::Part::Look;
}

View3D::View3D(AppContext& context, QWidget* parent) : QStackedWidget(parent), context_(context) {
    hint_ = new QLabel(this);
    hint_->setObjectName("view3d_hint");
    hint_->setAlignment(Qt::AlignCenter);
    hint_->setWordWrap(true);
    addWidget(hint_);
    setMinimumSize(320, 240);
    observer_ = context_.workspace.observe([this](core::Parts p) { watched(p); });
    make_spare();
    show_or_hint();
}

View3D::~View3D() {
    context_.workspace.unobserve(observer_);
    drop_viewer();
}

void View3D::drop_viewer() {
    for (Viewer** v : {&viewer_, &spare_}) {
        if (!*v) continue;
        removeWidget(*v);
        delete *v; // releases its GL objects through the scene it drew
        *v = nullptr;
    }
}

// A viewer of the workspace's scene made before anything is drawn (at
// start, and when new data comes) and kept behind the hint, so the first
// surface appears in a widget that is there already. (It was an OpenGL
// widget once, and the first of those switched the window to OpenGL
// composition; the view paints images now, docs/gui.md.)
void View3D::make_spare() {
    if (spare_ || viewer_) return;
    ViewerOptions o;
    o.look = context_.workspace.look();
    spare_ = new Viewer(context_.workspace, PatientView::Anterior, o);
    spare_->setObjectName("viewer");
    addWidget(spare_);
}

void View3D::watched(core::Parts parts) {
    // The viewer's GL objects belong to the old scene, alive until the observers heard.
    if (core::has(parts, core::Part::Data)) {
        drop_viewer();
        make_spare();
    }
    if (parts & (core::Part::Data | core::Part::Surfaces | core::Part::Look)) show_or_hint();
    if (!viewer_) return;
    if (parts & (core::Part::Look | core::Part::Data)) apply_look();
    const auto& camera = context_.workspace.camera();
    if (core::has(parts, core::Part::Camera) && camera && !(*camera == viewer_->camera())) viewer_->set_camera(*camera);
    if (parts & (kGuideParts | core::Part::Data)) update_guides();
}

// The viewer when something is drawn (a visible surface, or the volume
// shown), else the hint saying what to do next.
void View3D::show_or_hint() {
    const core::Workspace& w = context_.workspace;
    const core::Scene& scene = w.scene();
    bool any_visible = false;
    for (auto id : scene.surfaces()) any_visible |= scene.info(id).visible;
    const bool volume_shown = scene.has_volume() && w.look().volume.enabled;
    if (!any_visible && !volume_shown) {
        // The camera frames the visible surfaces and the volume when it is
        // shown: with neither there is nothing to frame.
        hint_->setText(!w.has_data() || (!scene.has_volume() && scene.surfaces().empty())
                           ? "Open a volume (File > Open, or drop a file or folder here),\nthen add a surface in the "
                             "Surfaces panel."
                       : scene.surfaces().empty()
                           ? "Add a surface in the Surfaces panel (a preset or an iso value,\nthen Add surface), or "
                             "tick Show volume in the Volume panel,\nto see it here."
                           : "Every surface is hidden: tick one in the Surfaces panel\n(or Show volume in the Volume "
                             "panel) to see it here.");
        setCurrentWidget(hint_);
        return;
    }
    if (!viewer_) {
        make_spare();
        viewer_ = std::exchange(spare_, nullptr); // its look: apply_look below
        if (w.camera()) viewer_->set_camera(*w.camera());
        viewer_->on_options_changed = [this](Viewer& v) { // the O key: AO on or off
            FrameLook look = context_.workspace.look();
            look.ao = v.options().look.ao;
            context_.workspace.set_look(look);
        };
        for (const auto& f : viewer_made) f(*viewer_);
        update_guides();
    }
    apply_look();
    setCurrentWidget(viewer_);
    // Framed now where the viewer has its place in the stack already (its
    // aspect is the one it will draw with), else by its first paint.
    if (viewer_->geometry() == contentsRect()) viewer_->frame_now();
    viewer_->update();
}

// The workspace's look (the volume drawn only when there is one); the view redraws only when it changed.
void View3D::apply_look() {
    ViewerOptions o = viewer_->options();
    FrameLook look = context_.workspace.look();
    look.volume.enabled = look.volume.enabled && context_.workspace.scene().has_volume();
    if (o.look == look) return;
    o.look = look;
    viewer_->set_options(o);
}

// The slice planes' outlines and the crosshair (View > Slice planes in 3D),
// and the crop box's 12 edges and its 6 face handles while cropping.
void View3D::update_guides() {
    const core::Workspace& w = context_.workspace;
    const core::Scene& scene = w.scene();
    std::vector<Annotations::Line> lines;
    std::vector<glm::dvec3> points;
    if (w.slice_planes_in_3d() && scene.has_volume()) {
        for (const auto& plane : w.planes()) {
            const auto outline = core::slice_outline_3d(scene.volume(), plane);
            const glm::vec4 colour(core::slice_color(plane.orientation), 1.0f);
            for (std::size_t i = 0; i < outline.size(); ++i)
                lines.push_back({outline[i], outline[(i + 1) % outline.size()], colour});
        }
        points.push_back(core::crosshair_point(w.planes()));
    }
    if (const auto& box = w.look().clip.box; box && scene.has_volume()) {
        const glm::vec4 colour(1.0f, 0.55f, 0.1f, 1.0f); // orange: none of the slice planes' colours
        const auto corner = core::box_corners(*box);
        for (std::size_t i = 0; i < 8; ++i)
            for (std::size_t bit : {1u, 2u, 4u})
                if (!(i & bit)) lines.push_back({corner[i], corner[i | bit], colour});
        // The handles a drag moves the faces by (CropBoxTool).
        for (const auto& [face, centre] : CropBoxTool::face_centres(*box)) points.push_back(centre);
    }
    viewer_->set_guides(std::move(lines), std::move(points));
}

} // namespace iso::gui
