// The window/level tool bar of the slice views (docs/gui.md "Slice
// views"): presets ("default", the CT ones from Radiopaedia's table for
// volumes in HU, "custom"), centre and width. It shows the workspace's
// window/level and sets it; a left drag in a slice view sets it too.
#pragma once

#include <QToolBar>

#include "renderer/core/workspace.hpp"

class QComboBox;
class QDoubleSpinBox;

namespace iso::gui {

class AppContext;

class WindowLevelBar : public QToolBar {
public:
    explicit WindowLevelBar(AppContext& context, QWidget* parent = nullptr);
    ~WindowLevelBar() override;
    QComboBox* presets() const { return preset_; }

private:
    void watched(core::Parts parts);
    void show_window();
    AppContext& context_;
    QComboBox* preset_ = nullptr;
    QDoubleSpinBox* center_ = nullptr;
    QDoubleSpinBox* width_ = nullptr;
    bool showing_ = false;
    int observer_ = 0;
};

} // namespace iso::gui
