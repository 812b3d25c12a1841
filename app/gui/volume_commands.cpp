// The Volume dock (volume_panel.hpp) in the main window: its edits as
// steps of the window's undo stack (one per edit; the steps of one spin
// box's run merge), and its state applied to the 3D view (the look's
// volume and clip, the crop box's edges drawn by the overlay). MainWindow
// members kept out of main_window.cpp.
#include <QDockWidget>
#include <QStatusBar>
#include <QUndoCommand>
#include <QUndoStack>

#include "app/gui/main_window.hpp"
#include "app/gui/viewer.hpp"
#include "app/gui/volume_panel.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"

namespace iso::gui {

namespace {
constexpr int kVolumeEditId = 0x701e; // QUndoCommand::id of the edits that may merge

class VolumeCommand : public QUndoCommand {
public:
    VolumeCommand(MainWindow& w, const QString& text, VolumeState before, VolumeState after, bool merge)
        : QUndoCommand(text), window_(w), before_(std::move(before)), after_(std::move(after)), merge_(merge) {}
    int id() const override { return merge_ ? kVolumeEditId : -1; }
    bool mergeWith(const QUndoCommand* other) override {
        const auto* o = dynamic_cast<const VolumeCommand*>(other);
        if (!o || !o->merge_ || o->text() != text()) return false;
        after_ = o->after_;
        return true;
    }
    void undo() override {
        window_.volume_panel()->set_state(before_);
        window_.statusBar()->showMessage("Undone: " + text());
    }
    void redo() override {
        // push() runs redo() once for the edit already shown.
        if (first_) {
            first_ = false;
            return;
        }
        window_.volume_panel()->set_state(after_);
        window_.statusBar()->showMessage("Redone: " + text());
    }

private:
    MainWindow& window_;
    VolumeState before_, after_;
    bool merge_ = false;
    bool first_ = true;
};
} // namespace

void MainWindow::add_volume_dock(QDockWidget* below) {
    auto* dock = new QDockWidget("Volume", this);
    dock->setObjectName("volume");
    volume_ = new VolumePanel(dock);
    volume_->changed = [this](const VolumeState&) { update_3d(); };
    volume_->edited = [this](const QString& text, const VolumeState& before, const VolumeState& after, bool merge) {
        undo_->push(new VolumeCommand(*this, text, before, after, merge));
        statusBar()->showMessage(text);
    };
    dock->setWidget(volume_);
    addDockWidget(Qt::RightDockWidgetArea, dock);
    tabifyDockWidget(below, dock);
    below->raise(); // the Surfaces tab in front; the Volume tab beside it
}

// The 3D view's look takes the panel's volume and clip (the view redraws
// only when they changed).
void MainWindow::apply_volume() {
    if (!viewer_) return;
    ViewerOptions o = viewer_->options();
    const VolumeState& s = volume_->state();
    VolumeLook v = s.look;
    v.enabled = s.look.enabled && scene_->has_volume();
    if (o.look.volume == v && o.look.clip == s.clip()) return;
    o.look.volume = v;
    o.look.clip = s.clip();
    viewer_->set_options(o);
}

// A session's volume look and crop box; what it lacks stays as a new
// volume has it (off, the default transfer function, no crop).
void MainWindow::restore_volume(const core::Session& s) {
    if (!scene_->has_volume()) return;
    VolumeState v = volume_->state();
    if (s.volume) {
        v.look.enabled = s.volume->enabled;
        v.look.tf = s.volume->tf;
        v.look.mode = s.volume->mode;
    }
    if (s.clip_box) {
        v.crop = true;
        v.box = *s.clip_box;
    }
    volume_->set_state(v);
}

// The crop box's 12 edges while cropping, in the overlay's lines.
std::vector<Annotations::Line> MainWindow::crop_box_lines() const {
    std::vector<Annotations::Line> lines;
    const Clip clip = volume_->state().clip();
    if (!clip.box || !scene_->has_volume()) return lines;
    const auto [lo, hi] = *clip.box;
    const glm::vec4 colour(1.0f, 0.55f, 0.1f, 1.0f); // orange: none of the slice planes' colours
    const auto corner = [&](int i) {
        return glm::dvec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    };
    for (int i = 0; i < 8; ++i)
        for (int bit : {1, 2, 4})
            if (!(i & bit)) lines.push_back({corner(i), corner(i | bit), colour});
    return lines;
}

} // namespace iso::gui
