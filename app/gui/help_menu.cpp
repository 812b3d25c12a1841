// The View menu (the layout and the slice planes in 3D, layouts.cpp; show or
// hide each dock and tool bar; a closed dock used to come back only through
// the tool bar's context menu) and the Help menu
// (the mouse and keyboard bindings; About with the versions a bug report
// needs). Part of MainWindow (main_window.hpp).
#include <QDialog>
#include <QDialogButtonBox>
#include <QDockWidget>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QTextBrowser>
#include <QToolBar>
#include <QVBoxLayout>

#include "app/gui/main_window.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/versions.hpp"

namespace iso::gui {

QString MainWindow::about_text() const {
    QString s = "<p><b>isoscope</b>: inspect CT volumes, reconstruct and render isosurfaces, measure.</p><table "
                "cellspacing='6'>";
    for (const auto& [name, version] : core::component_versions())
        s += "<tr><td>" + QString::fromStdString(name) + "</td><td>" + QString::fromStdString(version) + "</td></tr>";
    s += "<tr><td>Qt</td><td>" + QString(qVersion()) + "</td></tr>";
    const std::string gl = viewer_ ? viewer_->gl_renderer() : std::string();
    s += "<tr><td>GL renderer</td><td>" +
         (gl.empty() ? QString("(the 3D view has not drawn yet)") : QString::fromStdString(gl).toHtmlEscaped()) +
         "</td></tr></table>";
    return s;
}

QString MainWindow::bindings_html() {
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

void MainWindow::add_view_and_help_menus() {
    // ---- View: the layouts, then every dock and tool bar, listed when the menu opens (docks are added later too)
    auto* view = menuBar()->addMenu("&View");
    view->setObjectName("view_menu");
    add_layout_actions(view);
    connect(view, &QMenu::aboutToShow, this, [this, view] {
        view->clear();
        view->addMenu(layout_menu_); // View > Layout and the slice planes toggle: layouts.cpp
        view->addAction(slice_planes_3d_);
        view->addSeparator();
        for (auto* dock : findChildren<QDockWidget*>()) view->addAction(dock->toggleViewAction());
        view->addSeparator();
        for (auto* bar : findChildren<QToolBar*>()) view->addAction(bar->toggleViewAction());
    });
    // ---- Help
    auto* help = menuBar()->addMenu("&Help");
    help->setObjectName("help_menu");
    auto* bindings = help->addAction("&Mouse and keyboard", QKeySequence::HelpContents, this, [this] {
        auto* d = new QDialog(this);
        d->setObjectName("bindings_dialog");
        d->setWindowTitle("Mouse and keyboard");
        d->setAttribute(Qt::WA_DeleteOnClose);
        auto* layout = new QVBoxLayout(d);
        auto* text = new QTextBrowser(d);
        text->setHtml(bindings_html());
        layout->addWidget(text);
        auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, d);
        connect(buttons, &QDialogButtonBox::rejected, d, &QDialog::close);
        layout->addWidget(buttons);
        d->resize(560, 620);
        d->show(); // not modal: it can stay open beside the views
    });
    bindings->setObjectName("help_bindings");
    auto* about = help->addAction("&About isoscope", this, [this] {
        auto* box = new QMessageBox(QMessageBox::Information, "About isoscope", about_text(), QMessageBox::Close, this);
        box->setObjectName("about_box");
        box->setAttribute(Qt::WA_DeleteOnClose);
        box->open();
    });
    about->setObjectName("help_about");
}

} // namespace iso::gui
