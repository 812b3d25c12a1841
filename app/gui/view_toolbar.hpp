// The 3D view's tool bar (docs/gui.md): patient-view buttons
// (A, P, L, R, S, I: Viewer::set_view, as `isoscope render --view`), "Reset
// view" (the anterior view the window opens with, fitted again), an ambient
// occlusion toggle (the look's AO: off, or on with the method its menu
// chooses: cone traced or ray traced) and a transparency toggle
// (FrameLook::transparency: off draws every surface opaque without
// touching the surfaces' opacities). The toggles show and set the
// workspace's look (view settings, not undo steps); every 3D view draws it.
#pragma once

#include <functional>

#include <QToolBar>

#include "app/gui/viewer.hpp"

class QAction;

namespace iso::gui {

class AppContext;

class ViewToolBar : public QToolBar {
public:
    explicit ViewToolBar(AppContext& context, QWidget* parent = nullptr);
    ~ViewToolBar() override;

    // The bar's toggles applied to `base` (AO off, cone or raytraced; transparency).
    FrameLook look(FrameLook base = ViewerOptions{}.look) const;
    // Sets the workspace's AO method: off, cone or raytraced (the toggles follow).
    void set_ao(AoMethod m);
    QAction* view_action(PatientView v) const { return views_[int(v)]; }
    QAction* reset_action() const { return reset_; }
    QAction* ao_action() const { return ao_; }
    QAction* ao_cone_action() const { return ao_cone_; }
    QAction* ao_raytraced_action() const { return ao_raytraced_; }
    QAction* transparency_action() const { return transparency_; }

private:
    void apply_toggles();
    void show_look();
    AppContext& context_;
    int observer_ = 0;
    bool showing_ = false;
    QAction* views_[6] = {};
    QAction* reset_ = nullptr;
    QAction* ao_ = nullptr;
    QAction* ao_cone_ = nullptr;
    QAction* ao_raytraced_ = nullptr;
    QAction* transparency_ = nullptr;
};

} // namespace iso::gui
