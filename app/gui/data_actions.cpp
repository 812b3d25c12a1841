#include "app/gui/data_actions.hpp"

#include <QAction>
#include <QWidget>

#include "renderer/core/scene.hpp"

namespace iso::gui {

namespace {
// What each action or control needs, by object name; the File menu's
// session entries (files.cpp, exports.cpp) are found by their text and named here.
enum class Needs { Data, Volume, Surface, Markup };
struct Entry {
    const char* name;
    Needs needs;
    const char* text = nullptr; // an action without a name yet: its text, '&' left out
};
constexpr Entry kEntries[] = {
    {"save_session", Needs::Data, "Save session..."},
    {"export_image", Needs::Data, "Export image..."},
    {"export_dicom", Needs::Data, "Export to DICOM..."},
    {"save_surfaces", Needs::Surface, "Save surfaces..."},
    {"load_markups", Needs::Data},
    {"save_markups", Needs::Data},
    {"ruler", Needs::Data},
    {"angle", Needs::Data},
    {"point", Needs::Data},
    {"isolate_tool", Needs::Surface},
    {"distance_tool", Needs::Surface},
    {"grow_tool", Needs::Volume},
    {"grow_lo", Needs::Volume},
    {"grow_hi", Needs::Volume},
    {"scissors_tool", Needs::Surface},
    {"scissors_keep_outside", Needs::Surface},
    {"export_label_map", Needs::Surface},
    {"add_surface", Needs::Volume},
    {"add_iso_value", Needs::Volume},
    {"iso_preset", Needs::Volume},
    {"add_smoothing", Needs::Volume},
    {"add_keep_largest", Needs::Volume},
    {"window_preset", Needs::Volume},
    {"window_center", Needs::Volume},
    {"window_width", Needs::Volume},
    {"volume_panel", Needs::Volume},
    {"clear_measurements", Needs::Markup},
};

const char* why_not(Needs n) {
    switch (n) {
    case Needs::Data: return "Open a volume or a mesh first (File > Open)";
    case Needs::Volume: return "Open a volume first (File > Open)";
    case Needs::Surface: return "Add a surface first (Surfaces panel) or open a mesh";
    case Needs::Markup: return "No measurement to delete";
    }
    return "";
}

// The tooltip while enabled is the object's own; while disabled the reason
// comes first (taken off again when it is enabled).
template <class T> void enable(T* o, bool on, Needs needs) {
    const QString reason = why_not(needs);
    QString tip = o->toolTip();
    if (tip.startsWith(reason)) tip = tip.mid(reason.size()).remove(0, 2);
    o->setEnabled(on);
    o->setToolTip(on ? tip : tip.isEmpty() ? reason : reason + ". " + tip);
}
} // namespace

void enable_data_actions(QWidget& window, const core::Workspace& workspace) {
    const core::Scene& scene = workspace.scene();
    const bool volume = scene.has_volume(), surface = !scene.surfaces().empty();
    for (const auto& e : kEntries) {
        const bool on = e.needs == Needs::Volume    ? volume
                        : e.needs == Needs::Surface ? surface
                        : e.needs == Needs::Markup  ? !workspace.markups().empty()
                                                    : volume || surface;
        QAction* a = window.findChild<QAction*>(e.name);
        if (!a && e.text)
            for (QAction* t : window.findChildren<QAction*>())
                if (t->text().remove('&') == e.text) (a = t)->setObjectName(e.name);
        if (a)
            enable(a, on, e.needs);
        else if (auto* w = window.findChild<QWidget*>(e.name))
            enable(w, on, e.needs);
    }
}

} // namespace iso::gui
