// The Surfaces panel's undo steps on the main window's undo stack (docs/gui.md
// "Undo"): adding a surface, removing one, and the edits of a row (visibility,
// colour, opacity, iso value, smoothing, keep-largest). The steps of one
// slider drag merge into one. Surface ids stay what they were: an undone
// removal puts the surface back under its id (core::Scene::restore_surface),
// so the steps before and after it still name the right surface.
// MainWindow::wire_surface_undo, kept out of main_window.cpp.
#include <QStatusBar>
#include <QUndoCommand>
#include <QUndoStack>

#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "renderer/core/scene.hpp"

namespace iso::gui {

namespace {

constexpr int kSurfaceEditId = 0x5eed; // QUndoCommand::id of the edits that may merge

// The base of the steps: the window (status bar) and the panel; push()
// runs redo() once for an edit already made, which says what it did.
class SurfaceCommand : public QUndoCommand {
public:
    SurfaceCommand(MainWindow& w, const QString& text) : QUndoCommand(text), window_(w) {}

protected:
    SurfacesPanel& panel() { return *window_.surfaces_panel(); }
    core::Scene& scene() { return window_.scene(); }
    // False the first time (the edit is already on screen).
    bool redoing() {
        if (first_) {
            first_ = false;
            return false;
        }
        return true;
    }
    void say(const char* what) { window_.statusBar()->showMessage(what + text()); }

private:
    MainWindow& window_;
    bool first_ = true;
};

// A row's edit: the settings before and after.
class EditCommand : public SurfaceCommand {
public:
    EditCommand(MainWindow& w, std::uint32_t id, const QString& text, const SurfaceSettings& before, int drag)
        : SurfaceCommand(w, text), id_(id), drag_(drag), before_(before), after_(panel().settings(id)) {}
    int id() const override { return kSurfaceEditId; }
    bool mergeWith(const QUndoCommand* other) override {
        // One slider drag, one step.
        const auto* o = dynamic_cast<const EditCommand*>(other);
        if (!o || drag_ == 0 || o->drag_ != drag_ || o->id_ != id_ || o->text() != text()) return false;
        after_ = o->after_;
        return true;
    }
    void undo() override {
        panel().apply(id_, before_);
        say("Undone: ");
    }
    void redo() override {
        if (!redoing()) return;
        panel().apply(id_, after_);
        say("Redone: ");
    }

private:
    std::uint32_t id_;
    int drag_;
    SurfaceSettings before_, after_;
};

// Adding (`add`) or removing a surface: the one undone keeps its mesh and properties.
class AddRemoveCommand : public SurfaceCommand {
public:
    AddRemoveCommand(MainWindow& w, std::uint32_t id, bool add)
        : SurfaceCommand(w, (add ? "add " : "remove ") + QString::fromStdString(w.scene().info(id).name)), id_(id),
          add_(add) {}
    void undo() override {
        add_ ? take() : put_back();
        say("Undone: ");
    }
    void redo() override {
        const bool again = redoing();
        if (add_ && !again) return; // added already
        add_ ? put_back() : take();
        if (again) say("Redone: ");
    }

private:
    void take() {
        mesh_ = scene().mesh(id_);
        info_ = scene().info(id_);
        panel().remove_surface(id_);
    }
    void put_back() { panel().restore_surface(id_, std::move(mesh_), info_); }

    std::uint32_t id_;
    bool add_;
    Mesh mesh_;
    core::SurfaceInfo info_;
};

} // namespace

void MainWindow::wire_surface_undo() {
    surfaces_->added = [this](std::uint32_t id) { undo_->push(new AddRemoveCommand(*this, id, true)); };
    surfaces_->remove_requested = [this](std::uint32_t id) { undo_->push(new AddRemoveCommand(*this, id, false)); };
    surfaces_->edited = [this](std::uint32_t id, const QString& text, const SurfaceSettings& before, int drag) {
        undo_->push(new EditCommand(*this, id, text, before, drag));
    };
}

} // namespace iso::gui
