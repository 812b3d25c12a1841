// The Surfaces panel of the main window (docs/gui.md "Surfaces panel"):
// presets and an iso value to add an isosurface (in the background, with the
// window's progress dialog and Cancel), and one row per surface: visibility,
// name, colour, opacity, and for isosurfaces an iso slider with its number,
// smoothing, keep-largest and Remove. Moving the slider re-extracts in the
// background without a dialog; the surface on screen stays until the new mesh
// is swapped in on the GUI thread, and the latest value wins. Presentation
// only: extraction, post-processing and the surfaces are the core's
// (core::Scene::extract_isosurface, add_isosurface, replace_surface,
// remove_surface).
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
#include "renderer/surface/postprocess.hpp"

class QComboBox;
class QGridLayout;
class QDoubleSpinBox;
class QCheckBox;
class QLabel;
class QSlider;
class QVBoxLayout;

namespace iso::core {
class Scene;
struct IsolatedComponent;
struct SurfaceInfo;
} // namespace iso::core

namespace iso::gui {

// What a row edits and an undo step of it restores (surface_commands.hpp).
struct SurfaceSettings {
    glm::vec3 color{0.9f};
    float opacity = 1.0f;
    bool visible = true;
    double iso = 0; // the value last asked for (a re-extraction may still run)
    PostProcessOptions post;
};

class SurfacesPanel : public QWidget {
public:
    explicit SurfacesPanel(QWidget* parent = nullptr);
    // Stops the re-extractions still running (they read the scene's volume).
    ~SurfacesPanel() override;

    // The scene the panel edits (null: none). Cancels the previous scene's
    // re-extractions and waits for them (a scene about to be destroyed is no
    // longer read), then makes the rows of the new scene's surfaces.
    void set_scene(core::Scene* scene);

    // "Add surface": the isosurface at `iso` extracted in the background
    // through run_job (progress dialog, Cancel), added on the GUI thread.
    void add_surface(double iso, const PostProcessOptions& post = {});
    // The Isolate tool: the connected component of surface `id` nearest to
    // `at` (LPS mm) becomes a surface of its own, planned in the background
    // through run_job (core::plan_component: components and measurement) and
    // added on the GUI thread (core::add_component); `isolated` reports it.
    void isolate(std::uint32_t id, const glm::dvec3& at);
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

    // ---- undo (surface_commands.hpp makes the steps) ----------------------
    SurfaceSettings settings(std::uint32_t id) const;
    // Shows `s` in the scene and the row, making no undo step; a changed iso
    // value or post-processing re-extracts (set_iso, set_post).
    void apply(std::uint32_t id, const SurfaceSettings& s);
    // Removes the surface and its row, as its Remove button does without `remove_requested`.
    void remove_surface(std::uint32_t id);
    // Puts a removed surface back under its id with its row (core::Scene::restore_surface).
    void restore_surface(std::uint32_t id, Mesh mesh, const core::SurfaceInfo& info);

    // ---- wiring (the main window) ---------------------------------------
    // Runs work on a worker thread with the progress dialog; done on the GUI
    // thread with what the work threw (MainWindow::run_job).
    std::function<void(const QString& title, std::function<void(const ProgressFn&)> work,
                       std::function<void(std::exception_ptr)> done)>
        run_job;
    std::function<bool()> busy;                  // the window waits for a job
    std::function<void(const QString&)> message; // the status bar
    std::function<void(const QString& title, const QString& what, std::exception_ptr)> error; // a dialog
    // The surfaces changed: redraw the 3D view; `outlines`: the slice views' outlines too.
    std::function<void(bool outlines)> changed;
    // A component was isolated (isolate()).
    std::function<void(const core::IsolatedComponent&)> isolated;
    // The user's edits, for the undo stack: "Add surface" added `id`; its
    // Remove button was pressed (unset: the panel removes it); a row changed
    // a setting (`text`: "change opacity of NAME"; `before`: the settings
    // before; `drag`: the slider drag it is part of, 0 for none: the steps of
    // one drag make one undo step).
    std::function<void(std::uint32_t id)> added;
    std::function<void(std::uint32_t id)> remove_requested;
    std::function<void(std::uint32_t id, const QString& text, const SurfaceSettings& before, int drag)> edited;

private:
    struct Row;
    struct Worker;
    void add_row(std::uint32_t id);
    // The lines of a row, each with what its controls do.
    void add_title_line(Row& r, QGridLayout* grid);
    void add_opacity_line(Row& r, QGridLayout* grid);
    void add_iso_line(Row& r, QGridLayout* grid);
    void add_post_line(Row& r, QGridLayout* grid);
    void remove_row(std::uint32_t id);
    Row* find(std::uint32_t id) const;
    void request(Row& r);
    void start(Row& r);
    void finished(std::uint32_t id, const std::shared_ptr<Worker>& w);
    void stop_workers();
    void update_presets();
    void notify(bool outlines);
    void record(std::uint32_t id, const char* what, const SurfaceSettings& before);
    void track_drag(QSlider* slider);

    core::Scene* scene_ = nullptr;
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
};

} // namespace iso::gui
