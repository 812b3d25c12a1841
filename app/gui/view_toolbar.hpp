// The 3D view's tool bar (docs/gui.md): patient-view buttons
// (A, P, L, R, S, I: Viewer::set_view, as `isoscope render --view`), "Reset
// view" (the anterior view the window opens with, fitted again), an ambient
// occlusion toggle (the look's AO: off, or on with the method its menu
// chooses: cone traced or ray traced) and a transparency toggle
// (FrameLook::transparency: off draws every surface opaque without
// touching the surfaces' opacities). The main window recreates its viewer
// with each scene; the bar keeps the toggles and applies them to each new one.
#pragma once

#include <functional>

#include <QToolBar>

#include "app/gui/viewer.hpp"

class QAction;

namespace iso::gui {

class ViewToolBar : public QToolBar {
public:
    // `viewer` returns the window's current 3D view (null while there is none).
    explicit ViewToolBar(std::function<Viewer*()> viewer, QWidget* parent = nullptr);

    // Gives a newly made viewer the bar's toggles.
    void attach(Viewer& v) const;
    // The bar's toggles applied to `base` (AO off, cone or raytraced; transparency).
    FrameLook look(FrameLook base = ViewerOptions{}.look) const;
    // Sets the AO toggle and method (a session's): off, or on with cone or raytraced.
    void set_ao(AoMethod m);
    QAction* view_action(PatientView v) const { return views_[int(v)]; }
    QAction* reset_action() const { return reset_; }
    QAction* ao_action() const { return ao_; }
    QAction* ao_cone_action() const { return ao_cone_; }
    QAction* ao_raytraced_action() const { return ao_raytraced_; }
    QAction* transparency_action() const { return transparency_; }

private:
    void apply_toggles();
    std::function<Viewer*()> viewer_;
    QAction* views_[6] = {};
    QAction* reset_ = nullptr;
    QAction* ao_ = nullptr;
    QAction* ao_cone_ = nullptr;
    QAction* ao_raytraced_ = nullptr;
    QAction* transparency_ = nullptr;
};

} // namespace iso::gui
