#include <QDialog>
#include <QDialogButtonBox>
#include <QDockWidget>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QTextBrowser>
#include <QToolBar>
#include <QVBoxLayout>

#include "app/gui/help_menu.hpp"

#include <QMainWindow>
#include <QMenuBar>

#include "app/gui/layouts.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/versions.hpp"

namespace iso::gui {

QString about_text(const Viewer* viewer) {
    QString s = "<p><b>isoscope</b>: inspect CT volumes, reconstruct and render isosurfaces, measure.</p><table "
                "cellspacing='6'>";
    for (const auto& [name, version] : core::component_versions())
        s += "<tr><td>" + QString::fromStdString(name) + "</td><td>" + QString::fromStdString(version) + "</td></tr>";
    s += "<tr><td>Qt</td><td>" + QString(qVersion()) + "</td></tr>";
    const std::string gl = viewer ? viewer->gl_renderer() : std::string();
    s += "<tr><td>GL renderer</td><td>" +
         (gl.empty() ? QString("(the 3D view has not drawn yet)") : QString::fromStdString(gl).toHtmlEscaped()) +
         "</td></tr></table>";
    return s;
}

QString bindings_html() {
    const auto section = [](const QString& title, std::initializer_list<std::pair<const char*, const char*>> rows) {
        QString s = "<h3>" + title + "</h3><table cellspacing='4'>";
        for (const auto& [what, does] : rows) s += QString("<tr><td><b>%1</b></td><td>%2</td></tr>").arg(what, does);
        return s + "</table>";
    };
    return section("3D view", {{"Left drag", "rotate about the target"},
                               {"Middle drag", "pan"},
                               {"Right drag / wheel", "zoom (drag up: closer)"},
                               {"Click", "what is there (status bar; the last click stays at its right), "
                                         "and the slice views' crosshair moves there"},
                               {"Drag a placed point", "move it"},
                               {"A P L R S I", "anterior, posterior, left, right, superior, inferior view"},
                               {"O", "ambient occlusion on / off"}}) +
           section("Slice views", {{"Wheel, Page Up / Page Down", "next / previous slice"},
                                   {"Left drag", "window width (drag right: wider) and level (drag up: higher)"},
                                   {"Middle drag", "pan"},
                                   {"Right drag", "zoom about the pressed point"},
                                   {"Click", "move the crosshair (with a tool on: place a point)"},
                                   {"Pointer over a view", "the point, value and voxel under it (bottom left)"},
                                   {"F, double-click, Fit", "re-centre on the volume and zoom to fit"},
                                   {"Slider under a view", "go to a slice (one step per slice)"}}) +
           section("Measuring", {{"Ruler, Angle, Point", "click the points in the 3D view or on a slice"},
                                 {"Escape", "drop the points placed so far"},
                                 {"Delete (Measurements list)", "delete the selected measurement"}}) +
           section("Window", {{"Ctrl+O", "open a file"},
                              {"Ctrl+S", "save the session"},
                              {"Ctrl+1 ... Ctrl+6", "layout: Four-Up, Conventional, 3D only, axial, coronal, "
                                                    "sagittal only"},
                              {"Ctrl+Shift+P", "slice planes in the 3D view on / off"},
                              {"Ctrl+Z / Ctrl+Shift+Z", "undo / redo"},
                              {"F1", "this list"},
                              {"Ctrl+Q", "quit"}});
}

void add_view_menu(QMainWindow& window, Layouts& layouts) {
    // The layouts, then every dock and tool bar, listed when the menu opens (docks are added later too).
    auto* view = window.menuBar()->addMenu("&View");
    view->setObjectName("view_menu");
    view->setToolTipsVisible(true);
    QObject::connect(view, &QMenu::aboutToShow, &window, [&window, &layouts, view] {
        view->clear();
        view->addMenu(layouts.menu()); // View > Layout and the slice planes toggle
        view->addAction(layouts.slice_planes_action());
        view->addSeparator();
        for (auto* dock : window.findChildren<QDockWidget*>()) view->addAction(dock->toggleViewAction());
        view->addSeparator();
        for (auto* bar : window.findChildren<QToolBar*>()) view->addAction(bar->toggleViewAction());
    });
}

void add_help_menu(QMainWindow& window, std::function<QString()> about_text) {
    QMainWindow* w = &window;
    auto* help = w->menuBar()->addMenu("&Help");
    help->setObjectName("help_menu");
    auto* bindings = help->addAction("&Mouse and keyboard", QKeySequence::HelpContents, w, [w] {
        auto* d = new QDialog(w);
        d->setObjectName("bindings_dialog");
        d->setWindowTitle("Mouse and keyboard");
        d->setAttribute(Qt::WA_DeleteOnClose);
        auto* layout = new QVBoxLayout(d);
        auto* text = new QTextBrowser(d);
        text->setHtml(bindings_html());
        layout->addWidget(text);
        auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, d);
        QObject::connect(buttons, &QDialogButtonBox::rejected, d, &QDialog::close);
        layout->addWidget(buttons);
        d->resize(560, 620);
        d->show(); // not modal: it can stay open beside the views
    });
    bindings->setObjectName("help_bindings");
    auto* about = help->addAction("&About isoscope", w, [w, about_text] {
        auto* box = new QMessageBox(QMessageBox::Information, "About isoscope", about_text(), QMessageBox::Close, w);
        box->setObjectName("about_box");
        box->setAttribute(Qt::WA_DeleteOnClose);
        box->open();
    });
    about->setObjectName("help_about");
}

} // namespace iso::gui
