// The View menu (the layouts and the slice planes in 3D, layouts.hpp; show
// or hide each dock and tool bar: a closed dock used to come back only
// through the tool bar's context menu) and the Help menu (the mouse and
// keyboard bindings; About with the versions a bug report needs).
#pragma once

#include <functional>

#include <QString>

class QMainWindow;

namespace iso::gui {

class Layouts;
class Viewer;

void add_view_menu(QMainWindow& window, Layouts& layouts);
void add_help_menu(QMainWindow& window, std::function<QString()> about_text);
// About's text: isoscope's version and its libraries' (core::component_versions),
// Qt's, and the 3D view's GL renderer once it has drawn (`viewer` may be null).
QString about_text(const Viewer* viewer);
// Help > Mouse and keyboard's text (HTML).
QString bindings_html();

} // namespace iso::gui
