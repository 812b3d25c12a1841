// The desktop app's one kind of background job (docs/gui.md "Background
// work"): work on a worker thread with a progress dialog (after 300 ms)
// whose Cancel reaches the work through its ProgressFn, and a result
// handed to the GUI thread. Loading, extraction, isolation, distances,
// saving and exports all run through it; autosave uses it without a dialog
// (a quiet job). (The 3D view's still frames have a thread of their own with
// its GL context, still_frames.hpp; a surface row's re-extractions, the
// latest value winning, run on threads of the Surfaces panel.) At most one job with a dialog at a time:
// busy() says whether one runs, and the window's edits wait for it.
#pragma once

#include <exception>
#include <functional>
#include <memory>
#include <vector>

#include <QObject>
#include <QString>

#include "io/progress.hpp"

class QWidget;

namespace iso::gui {

class Jobs : public QObject {
public:
    // Dialogs are window-modal over `window` (not the owner: the window's
    // model owns the jobs, and outlives its widgets).
    explicit Jobs(QWidget* window);
    // Every worker still running is cancelled and waited for.
    ~Jobs() override;

    struct Options {
        // Cancel closes the dialog at once and drops the result (the work
        // touches nothing the window shares and may not check its ProgressFn).
        bool abandonable = false;
        // No dialog, not counted by busy() (autosave): the work must not
        // touch what the window edits.
        bool quiet = false;
    };
    // Runs `work` on a worker thread; `done` runs on the GUI thread with
    // what the work threw (null: success) unless the job was abandoned.
    void run(const QString& title, std::function<void(const ProgressFn&)> work,
             std::function<void(std::exception_ptr)> done, Options options);
    void run(const QString& title, bool abandonable, std::function<void(const ProgressFn&)> work,
             std::function<void(std::exception_ptr)> done) {
        run(title, std::move(work), std::move(done), Options{abandonable, false});
    }
    // A job with a dialog runs (the window waits for it).
    bool busy() const { return current_ != nullptr; }
    // Quiet jobs still running.
    int quiet_running() const;
    // Waits for the workers (abandoned ones too; `quiet_only`: the quiet
    // ones), cancelling them first when `cancel` (the window is going, or
    // what they read is); their `done` does not run.
    void wait_all(bool cancel, bool quiet_only = false);
    // Said when a job was cancelled or ended (the status bar).
    std::function<void(const QString&)> message;

private:
    struct Job;
    void finish(const std::shared_ptr<Job>& job);
    void cancel_pressed(Job* j);
    QWidget* window_;
    std::shared_ptr<Job> current_;              // the job the window waits for
    std::vector<std::shared_ptr<Job>> running_; // every worker still running
};

} // namespace iso::gui
