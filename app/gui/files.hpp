// The File menu (docs/gui.md "Opening", "Sessions and export"): opening
// files, DICOM folders (the series chooser for a folder of several), recent
// files and sessions in the background; saving the session; exporting the
// figure as an image or into DICOM; saving surfaces; and the Save /
// Discard / Cancel question before unsaved work would be lost. What they
// do is the core's (renderer/core/session.hpp, api.hpp, scene.hpp); the
// state they read and replace is the workspace's.
#pragma once

#include <functional>

#include <QObject>
#include <QString>

class QMenu;

namespace iso::core {
struct RenderRequest;
struct SessionParts;
} // namespace iso::core

namespace iso::gui {

class AppContext;

class Files : public QObject {
public:
    explicit Files(AppContext& context);

    // File: Open file, Open DICOM folder, Recent files, sessions, exports, Quit.
    void add_menu(QMenu* file);
    // File > Load markups / Save markups (the Measurements panel's dialogs,
    // given by the window: the panel uses start_folder in turn).
    void add_markups_actions(std::function<void()> load, std::function<void()> save);

    // Loads a volume file, DICOM folder or mesh in the background (progress
    // dialog with Cancel); on success the workspace holds it, on failure a
    // dialog names the file and the reason. `series`: the DICOM series
    // (index or UID); empty: the only one (a folder of several lists them
    // first and asks which; one DICOM file stands for its series).
    void open_path(const QString& path, const QString& series = {});
    // A dropped or named file: a session (.json but .mrk.json) or data,
    // after asking about unsaved work.
    void open_any(const QString& path);
    // File > Open session / Save session, in the background. A save marks the
    // state saved; `then` runs after a successful save. `recovered`: the
    // recovery file, opened as unsaved work (no session file named).
    void open_session(const QString& path, bool recovered = false);
    void save_session(const QString& path, std::function<void()> then = {});
    // File > Export image: renders the state as `isoscope render --session`
    // does (the session file it names: the current one when the state is
    // unchanged since it was saved or opened, else PATH.session.json next to the image).
    void export_image(const QString& path, const core::RenderRequest& frame, const core::SessionParts& take);
    // File > Export to DICOM: the figure as a Secondary Capture into
    // `folder` (core::export_dicom), in this session's series.
    void export_dicom(const QString& folder, const core::RenderRequest& frame, const core::SessionParts& take);
    // File > Save surfaces: one surface in LPS mm (.stl, .ply, .obj, .vtp).
    void save_surface(std::uint32_t id, const QString& path);
    // File > Export label map: the visible surfaces as labels 1..N on the
    // volume's grid (core::structures_label_map; .nii or .nii.gz, LPS, with
    // Slicer's colour table beside it), in the background.
    void export_label_map(const QString& path);

    // Runs `proceed` at once when nothing is unsaved; else asks first (a
    // window-modal box named "unsaved": Save, Discard, Cancel): Save saves
    // the session (to the current session file, else where a file dialog
    // says) and proceeds only when that succeeded; Discard proceeds (and
    // `discarded` runs first); Cancel does nothing. `doing` says what would
    // discard it ("quitting").
    void ask_to_save(const QString& doing, std::function<void()> proceed);
    std::function<void()> discarded;

    // The folder a save dialog of a kind starts in (docs/gui.md "Where files
    // are saved"): the folder last used for that kind, else the documents
    // folder, else the home folder. Kinds: "session", "export", "dicom",
    // "surface", "markups".
    static QString start_folder(const char* kind);
    static void remember_folder(const char* kind, const QString& file_or_folder);

private:
    // Something is open (else the status bar says to open something first).
    bool data_open() const;
    // Where a Save session dialog starts: the session file, else the data's
    // name in the folder last used for sessions (start_folder).
    QString session_save_start() const;
    void choose_series(const QString& folder);
    void load(const QString& path, const QString& series);
    void loaded(const QString& path);
    void remember_recent(const QString& path);
    void rebuild_recent_menu();
    void open_file_dialog();
    void open_folder_dialog();
    void add_session_actions(QMenu* file);
    void add_export_actions(QMenu* file);
    void export_image_dialog();
    void export_dicom_dialog();
    void save_surfaces_dialog();
    void export_label_map_dialog();

    AppContext& context_;
    QMenu* recent_menu_ = nullptr;
    QString dicom_series_; // the series this session's DICOM figures go to (set by the first)
};

} // namespace iso::gui
