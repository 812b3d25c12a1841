#include "app/gui/app_context.hpp"

#include <QMainWindow>
#include <QMessageBox>
#include <QStatusBar>
#include <QUndoStack>

#include "app/gui/jobs.hpp"
#include "io/error.hpp"

namespace iso::gui {

namespace {
constexpr int kMergingEdit = 0x3d17; // QUndoCommand::id of the edits that may merge
}

AppContext::AppContext(core::Workspace& w, QUndoStack& u, Jobs& j, QMainWindow& win)
    : workspace(w), undo(u), jobs(j), window(win) {}

void AppContext::status(const QString& text) const { window.statusBar()->showMessage(text); }

QString AppContext::status_text() const { return window.statusBar()->currentMessage(); }

void AppContext::error(const QString& title, const QString& what, std::exception_ptr e) const {
    QString reason;
    try {
        std::rethrow_exception(e);
    } catch (const Cancelled&) {
        status(what + ": cancelled");
        return;
    } catch (const std::exception& ex) {
        reason = QString::fromStdString(ex.what());
    } catch (...) {
        reason = "unknown error";
    }
    error(title, what, reason);
}

void AppContext::error(const QString& title, const QString& what, const QString& reason) const {
    status(what + ": failed");
    auto* box = new QMessageBox(QMessageBox::Critical, title, what + "\n\n" + reason, QMessageBox::Ok, &window);
    box->setObjectName("error");
    box->setAttribute(Qt::WA_DeleteOnClose);
    box->open();
}

bool AppContext::busy(bool say) const {
    if (!jobs.busy()) return false;
    if (say) status("Busy: wait for the current task or cancel it");
    return true;
}

bool AppContext::edit(const QString& text, core::Parts parts, const std::function<void()>& change,
                      const QString& merge) {
    core::WorkspaceEdit e;
    try {
        e = workspace.record(text.toStdString(), parts, change, merge.toStdString());
    } catch (const Error&) {
        error("Cannot " + text.left(1).toLower() + text.mid(1), "Cannot " + text.left(1).toLower() + text.mid(1),
              std::current_exception());
        return false;
    }
    push(std::move(e));
    return true;
}

void AppContext::push(core::WorkspaceEdit e) {
    if (core::Workspace::unchanged(e)) return;
    undo.push(new WorkspaceCommand(*this, std::move(e)));
}

void AppContext::set_tool(Tool t) {
    if (t == tool_) return;
    tool_ = t;
    const auto observers = tool_changed;
    for (const auto& f : observers) f(t);
}

// ---- the command --------------------------------------------------------------------

WorkspaceCommand::WorkspaceCommand(AppContext& context, core::WorkspaceEdit e)
    : QUndoCommand(QString::fromStdString(e.text)), context_(context), edit_(std::move(e)) {}

int WorkspaceCommand::id() const { return edit_.merge_key.empty() ? -1 : kMergingEdit; }

bool WorkspaceCommand::mergeWith(const QUndoCommand* other) {
    const auto* o = dynamic_cast<const WorkspaceCommand*>(other);
    if (!o || o->text() != text() || !edit_.merge(o->edit_)) return false;
    setObsolete(core::Workspace::unchanged(edit_)); // a run back to where it began: no step
    return true;
}

void WorkspaceCommand::undo() {
    context_.workspace.restore(edit_.before, edit_.parts);
    context_.status("Undone: " + text());
}

void WorkspaceCommand::redo() {
    if (first_) { // the edit is on screen already
        first_ = false;
        return;
    }
    context_.workspace.restore(edit_.after, edit_.parts);
    context_.status("Redone: " + text());
}

} // namespace iso::gui
