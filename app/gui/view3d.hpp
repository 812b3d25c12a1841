// The 3D view's place in the main window (docs/gui.md "3D view"): a hint
// saying what to do next while there is nothing to draw, else the Viewer of
// the workspace's scene. It follows the workspace: a new input makes a new
// Viewer (its GL objects belong to its scene); the surfaces and the look
// (AO, transparency, volume, crop) go to the viewer's options; the camera
// goes both ways (the user's moves into the workspace, a session's or an
// undo's into the view); the slice planes and the crop box are drawn as
// guides.
#pragma once

#include <functional>
#include <vector>

#include <QStackedWidget>

#include "renderer/core/workspace.hpp"

class QLabel;

namespace iso::gui {

class AppContext;
class Viewer;

class View3D : public QStackedWidget {
public:
    View3D(AppContext& context, QWidget* parent = nullptr);
    ~View3D() override;
    // The viewer (null while there is nothing to draw, or no input).
    Viewer* viewer() const { return viewer_; }
    // The hint shown instead (object name "view3d_hint").
    QLabel* hint() const { return hint_; }
    // Each new viewer, before its first frame (the tools attach to it).
    std::vector<std::function<void(Viewer&)>> viewer_made;

private:
    void watched(core::Parts parts);
    void show_or_hint();
    void apply_look();
    void update_guides();
    void drop_viewer();
    void make_spare();
    AppContext& context_;
    QLabel* hint_ = nullptr;
    Viewer* viewer_ = nullptr;
    Viewer* spare_ = nullptr; // made ahead, behind the hint: the next viewer_
    int observer_ = 0;
};

} // namespace iso::gui
