#include "app/gui/view_toolbar.hpp"

#include <QAction>
#include <QActionGroup>
#include <QMenu>
#include <QSignalBlocker>
#include <QToolButton>

#include "app/gui/app_context.hpp"

namespace iso::gui {

ViewToolBar::ViewToolBar(AppContext& context, QWidget* parent) : QToolBar("3D view", parent), context_(context) {
    setObjectName("view_toolbar");
    struct Button {
        PatientView view;
        const char* label;
        const char* tip;
    };
    // The letters of `isoscope render --view` and Slicer's 3D view buttons.
    static const Button buttons[] = {
        {PatientView::Anterior, "A", "View from the front (anterior)"},
        {PatientView::Posterior, "P", "View from the back (posterior)"},
        {PatientView::Left, "L", "View from the patient's left"},
        {PatientView::Right, "R", "View from the patient's right"},
        {PatientView::Superior, "S", "View from above (superior)"},
        {PatientView::Inferior, "I", "View from below (inferior)"},
    };
    for (const auto& b : buttons) {
        QAction* a = addAction(b.label);
        a->setToolTip(b.tip);
        a->setObjectName(QString("view_") + patient_view_name(b.view));
        const PatientView v = b.view;
        connect(a, &QAction::triggered, this, [this, v] {
            if (Viewer* w = context_.viewer()) w->set_view(v);
        });
        views_[int(v)] = a;
    }
    reset_ = addAction("Reset view");
    reset_->setObjectName("reset_view");
    reset_->setToolTip("Back to the anterior view, fitted to the visible surfaces");
    connect(reset_, &QAction::triggered, this, [this] {
        if (Viewer* w = context_.viewer()) w->set_view(PatientView::Anterior);
    });
    addSeparator();
    ao_ = addAction("AO");
    ao_->setObjectName("ambient_occlusion");
    ao_->setToolTip("Ambient occlusion: cone traced, or ray traced (refined while the view is still); the arrow "
                    "chooses");
    ao_->setCheckable(true);
    ao_->setChecked(ViewerOptions{}.look.ao != AoMethod::Off);
    auto* methods = new QMenu(this);
    auto* group = new QActionGroup(methods);
    ao_cone_ = methods->addAction("Cone traced (interactive)");
    ao_cone_->setObjectName("ao_cone");
    ao_raytraced_ = methods->addAction("Ray traced (refines while the view is still)");
    ao_raytraced_->setObjectName("ao_raytraced");
    for (QAction* a : {ao_cone_, ao_raytraced_}) {
        a->setCheckable(true);
        group->addAction(a);
    }
    ao_cone_->setChecked(true);
    ao_->setMenu(methods);
    if (auto* b = qobject_cast<QToolButton*>(widgetForAction(ao_))) b->setPopupMode(QToolButton::MenuButtonPopup);
    connect(group, &QActionGroup::triggered, this, [this] {
        ao_->setChecked(true); // choosing a method turns AO on
        apply_toggles();
    });
    transparency_ = addAction("Transparency");
    transparency_->setObjectName("transparency");
    transparency_->setToolTip("Draw surfaces with their opacity; off: every surface opaque");
    transparency_->setCheckable(true);
    transparency_->setChecked(ViewerOptions{}.look.transparency);
    connect(ao_, &QAction::toggled, this, [this] { apply_toggles(); });
    connect(transparency_, &QAction::toggled, this, [this] { apply_toggles(); });
    observer_ = context_.workspace.observe([this](core::Parts p) {
        if (p & core::Parts(core::Part::Look)) show_look();
    });
    show_look();
}

ViewToolBar::~ViewToolBar() { context_.workspace.unobserve(observer_); }

FrameLook ViewToolBar::look(FrameLook base) const {
    base.ao = !ao_->isChecked() ? AoMethod::Off : ao_raytraced_->isChecked() ? AoMethod::Raytraced : AoMethod::Cone;
    base.transparency = transparency_->isChecked();
    return base;
}

void ViewToolBar::set_ao(AoMethod m) {
    FrameLook l = context_.workspace.look();
    l.ao = m;
    context_.workspace.set_look(l);
}

// The toggles into the workspace's look (a view setting: no undo step).
void ViewToolBar::apply_toggles() {
    if (showing_) return;
    context_.workspace.set_look(look(context_.workspace.look()));
}

// The workspace's look in the toggles (a session's, the O key's).
void ViewToolBar::show_look() {
    const FrameLook& l = context_.workspace.look();
    showing_ = true;
    if (l.ao == AoMethod::Raytraced) ao_raytraced_->setChecked(true);
    if (l.ao == AoMethod::Cone) ao_cone_->setChecked(true);
    ao_->setChecked(l.ao != AoMethod::Off);
    transparency_->setChecked(l.transparency);
    showing_ = false;
}

} // namespace iso::gui
