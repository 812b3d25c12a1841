// The Surfaces panel of the main window (docs/gui.md "Surfaces panel"):
// presets and an iso value to add an isosurface (in the background, with the
// window's progress dialog and Cancel), and one row per surface of the
// workspace: visibility, name, colour, opacity, and for isosurfaces an iso
// slider with its number, smoothing, keep-largest and Remove. Every change
// is an edit of the workspace (one undo step; the steps of one slider drag
// merge into one). Moving the slider re-extracts in the background without
// a dialog; the surface on screen stays until the new mesh is swapped in on
// the GUI thread (that swap is the edit), and the latest value wins. The rows
// follow the workspace: an undone edit, an isolated component or a session
// shows in them. Presentation only: extraction and post-processing are the
// core's (core::Scene::extract_isosurface), the surfaces the workspace's.
#pragma once

#include <exception>
#include <functional>
#include <memory>
#include <vector>

#include <QString>
#include <QWidget>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/progress.hpp"
#include "renderer/core/workspace.hpp"
#include "renderer/surface/postprocess.hpp"

class QComboBox;
class QGridLayout;
class QDoubleSpinBox;
class QCheckBox;
class QLabel;
class QSlider;
class QVBoxLayout;

namespace iso::gui {

class AppContext;

class SurfacesPanel : public QWidget {
public:
    SurfacesPanel(AppContext& context, QWidget* parent = nullptr);
    // Stops the re-extractions still running (they read the scene's volume).
    ~SurfacesPanel() override;

    // "Add surface": the isosurface at `iso` extracted in the background
    // (progress dialog, Cancel), added on the GUI thread as one undo step.
    void add_surface(double iso, const PostProcessOptions& post = {});
    // What a surface's row does when its iso slider or number moves, or its
    // smoothing / keep-largest change: re-extract in the background; the
    // latest request wins (a running one is cancelled through its ProgressFn).
    void set_iso(std::uint32_t id, double value);
    void set_post(std::uint32_t id, const PostProcessOptions& post);
    // A re-extraction runs or waits for surface `id` (0: for any surface).
    bool reextracting(std::uint32_t id = 0) const;
    // Meshes swapped into the scene by re-extractions so far.
    int swaps() const { return swaps_; }
    // The row of a surface (children: visible, color, opacity, iso_slider,
    // iso_value, smoothing, keep_largest, remove, busy); null if none.
    QWidget* row(std::uint32_t id) const;

private:
    struct Row;
    struct Worker;
    void watched(core::Parts parts);
    void sync_rows();
    void show_row(Row& r);
    void add_row(std::uint32_t id);
    // The lines of a row, each with what its controls do.
    void add_title_line(Row& r, QGridLayout* grid);
    void add_opacity_line(Row& r, QGridLayout* grid);
    void add_iso_line(Row& r, QGridLayout* grid);
    void add_post_line(Row& r, QGridLayout* grid);
    Row* find(std::uint32_t id) const;
    void request(Row& r);
    void start(Row& r);
    void finished(std::uint32_t id, const std::shared_ptr<Worker>& w);
    void stop_workers();
    void update_presets();
    // One undo step of surface `id`'s settings (colour, opacity, visibility):
    // `change` edits a copy of its info; `what`: "change opacity".
    void edit_info(std::uint32_t id, const char* what, const std::function<void(core::SurfaceInfo&)>& change);
    QString merge_key(const char* what, std::uint32_t id) const;
    void track_drag(QSlider* slider);

    AppContext& context_;
    int observer_ = 0;
    QComboBox* preset_ = nullptr;
    QDoubleSpinBox* iso_ = nullptr;
    QDoubleSpinBox* smooth_ = nullptr;
    QCheckBox* largest_ = nullptr;
    QLabel* range_ = nullptr;
    QVBoxLayout* rows_layout_ = nullptr;
    std::vector<std::unique_ptr<Row>> rows_;
    std::vector<std::shared_ptr<Worker>> workers_; // every re-extraction thread still running
    unsigned generation_ = 0;                      // bumped per scene: late results of an old one are dropped
    int swaps_ = 0;
    int drag_ = 0, drags_ = 0; // the slider drag under way (0: none), drags so far
    std::vector<double> preset_values_;
};

} // namespace iso::gui
