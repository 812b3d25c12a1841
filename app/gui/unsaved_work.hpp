// The guard of unsaved work (docs/gui.md "Unsaved work", docs/sessions.md
// "Recovery file"): while the workspace has unsaved work, the session is
// written to the recovery file every minute (in the background, as a quiet
// job); a clean exit or a save removes it; at start a recovery file left
// by a crash or a kill is offered back. Closing the window with unsaved
// work asks first (Files::ask_to_save).
#pragma once

#include <functional>
#include <string>
#include <utility>

#include <QObject>
#include <QString>

class QTimer;

namespace iso::gui {

class AppContext;
class Files;

class UnsavedWork : public QObject {
public:
    UnsavedWork(AppContext& context, Files& files);
    ~UnsavedWork() override;

    // Where autosave writes the session: beside the settings
    // (QStandardPaths::AppConfigLocation), recovery.isoscope.json.
    static QString recovery_path();
    // Autosave's period in ms: 60000, or ISOSCOPE_AUTOSAVE_MS when set.
    void set_autosave_interval(int ms);
    int autosaves() const { return autosaves_; } // recovery files written so far
    // When a recovery file exists, offers to restore it (a box named
    // "recovery": Restore opens it as unsaved work, Discard deletes it);
    // ISOSCOPE_RECOVERY=restore or discard answers without asking.
    // `otherwise` runs when there is none or it was discarded.
    void offer_recovery(std::function<void()> otherwise = {});
    // The window may close now: true when nothing is unsaved (the recovery
    // file is removed: a clean exit); else asks, and calls `close_again`
    // once saved or discarded.
    bool may_close(std::function<void()> close_again);

private:
    void autosave();
    void wait_for_autosave();
    void remove_recovery_file();
    AppContext& context_;
    Files& files_;
    QTimer* timer_ = nullptr;
    int observer_ = 0;
    bool edited_since_autosave_ = false, closing_ = false, writing_ = false;
    int autosaves_ = 0;
    std::pair<std::string, std::string> input_hash_; // the input and its SHA-256, hashed once for autosaves
};

} // namespace iso::gui
