// What the desktop app's tools and panels share (docs/gui.md "Model and
// commands", style.md 12): the workspace they show and edit, the one undo
// stack every edit goes through (one command type, WorkspaceCommand), the
// background jobs, the status bar and error dialogs, the views, and the
// interaction tool that is on. Tools and panels get this and never the
// main window: they read the workspace, observe its changes and send it
// edits; the window only arranges them.
#pragma once

#include <array>
#include <exception>
#include <functional>
#include <vector>

#include <QString>
#include <QUndoCommand>

#include "renderer/core/slices.hpp"
#include "renderer/core/workspace.hpp"

class QMainWindow;
class QUndoStack;

namespace iso::gui {

class Jobs;
class SliceView;
class Viewer;

using core::MarkupsState;

class AppContext {
public:
    AppContext(core::Workspace& workspace, QUndoStack& undo, Jobs& jobs, QMainWindow& window);

    core::Workspace& workspace;
    QUndoStack& undo;
    Jobs& jobs;
    QMainWindow& window; // tool bars, docks and dialogs go on it

    // The status bar's passing message, and an error dialog (named "error",
    // opened, not exec'd) saying `what` and the exception's reason
    // (iso::Cancelled: "WHAT: cancelled" in the status bar only).
    void status(const QString& text) const;
    QString status_text() const;
    void error(const QString& title, const QString& what, std::exception_ptr e) const;
    void error(const QString& title, const QString& what, const QString& reason) const; // a reason of our own
    // A job with a dialog runs: edits wait (the status bar says so when `say`).
    bool busy(bool say = false) const;

    // One step of Edit > Undo: `change` (workspace setters) recorded as an
    // edit of `parts` and pushed; `merge` not empty: the next edit with the
    // same key merges into this one (a slider drag). An edit that changed
    // nothing is not pushed. An iso::Error from `change` leaves the parts as
    // they were and is shown (false).
    bool edit(const QString& text, core::Parts parts, const std::function<void()>& change, const QString& merge = {});
    // An edit already recorded (the live steps of a drag, committed at the release).
    void push(core::WorkspaceEdit e);

    // The views (the window sets them): the 3D view (null while none) and the slice views.
    std::function<Viewer*()> viewer = [] { return static_cast<Viewer*>(nullptr); };
    std::array<SliceView*, 3> slices{};
    SliceView* slice_view(core::SliceOrientation o) const { return slices[std::size_t(o)]; }

    // The interaction tool that takes clicks in the views: one at a time
    // across the window (the Measure and Structures tool bars follow it).
    enum class Tool { None, Ruler, Angle, Point, Isolate, Distance, Grow, Scissors };
    Tool tool() const { return tool_; }
    void set_tool(Tool t);
    std::vector<std::function<void(Tool)>> tool_changed;
    // A markup point is being dragged (tables wait with what they compute per point).
    std::function<bool()> editing_markup = [] { return false; };

private:
    Tool tool_ = Tool::None;
};

// The one undo command: a workspace edit (before and after of the parts it
// touched). push() runs redo() once for an edit already made: it does
// nothing then. The steps of one control's run merge (WorkspaceEdit::merge);
// a run that ends where it began is dropped (obsolete).
class WorkspaceCommand : public QUndoCommand {
public:
    WorkspaceCommand(AppContext& context, core::WorkspaceEdit e);
    int id() const override;
    bool mergeWith(const QUndoCommand* other) override;
    void undo() override;
    void redo() override;
    const core::WorkspaceEdit& edit() const { return edit_; }

private:
    AppContext& context_;
    core::WorkspaceEdit edit_;
    bool first_ = true;
};

} // namespace iso::gui
