// The window's actions and controls that need something open (docs/gui.md
// "What needs data"): disabled, their tooltip saying why, until a volume, a
// surface or a measurement exists. Found by their object names under `window`.
#pragma once

#include "renderer/core/workspace.hpp"

class QWidget;

namespace iso::gui {

void enable_data_actions(QWidget& window, const core::Workspace& workspace);

} // namespace iso::gui
