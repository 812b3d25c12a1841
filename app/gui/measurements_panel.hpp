// The Measurements dock (docs/gui.md "Pick and measure"): a table
// of the workspace's markups (rulers, angles, point
// lists, and what a loaded .mrk.json holds) with the name (editable), the
// kind, the value (mm or degrees, computed by the core from the points each
// time the markups change), the surface each point lies on
// (core::surface_at), what a ruler passes through (core::solid_crossings)
// and a delete button; a point list's points have rows of their own (label,
// value of the volume there, surface, LPS). Selecting a row selects the
// markup (highlighted in the views; the slice views go to its point).
// File > Save markups... / Load markups... through io/markups.hpp (3D
// Slicer's .mrk.json, LPS), errors in a dialog naming the file; loading a
// file some markups came from asks whether to replace them. Every edit is
// an undo step (AppContext::edit). Presentation only.
#pragma once

#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include <QDockWidget>
#include <QString>

#include <glm/vec3.hpp>

#include "io/markups.hpp"

class QTableWidget;
class QTimer;

namespace iso::gui {

class AppContext;
class ColumnFit;

class MeasurementsPanel : public QDockWidget {
public:
    enum Column { Name = 0, Kind = 1, Value = 2, Surface = 3, Notes = 4, Delete = 5 };

    explicit MeasurementsPanel(AppContext& context);
    ~MeasurementsPanel() override;

    // Rebuilds the table from the workspace's markups (their changes call it).
    void refresh();
    // refresh() once the surfaces rest (a slider being dragged changes them
    // at every step; the surface and notes columns query every point).
    void refresh_soon();
    // Selects the row of the workspace's selected markup (none: no row).
    void show_selection();
    QTableWidget* table() const { return table_; }
    // The row of a markup (point -1) or of one of a point list's points; -1: none.
    int row_of(std::size_t markup, int point = -1) const;
    // Surface and crossing answers the table still waits for (shown as "...").
    bool looking_up() const { return looking_up_ || !surface_waiting_.empty() || !crossings_waiting_.empty(); }

    // The file dialogs of File > Save markups... / Load markups....
    void save_dialog();
    void load_dialog();
    // Writes every markup to `path` (replaced whole or not at all); the
    // markups are then from that file too. False on failure, after an error
    // dialog that names the file and the reason.
    bool save(const QString& path);
    // Adds the markups of `path` to the window's, one undo step. When some
    // of the window's markups came from that file (loaded from or saved to
    // it), a question box (object name "reload", opened, not exec'd) asks
    // first: Replace (those markups give way to the file's, in their place),
    // Add (both stay) or Cancel. False on failure, after an error dialog.
    bool load(const QString& path);

private:
    struct Row {
        std::size_t markup = 0;
        int point = -1; // a point list's point; -1: the markup's row
    };
    void add_markup_rows(std::size_t index, const Markup& m);
    void add_row(const Row& r, const std::array<QString, 5>& text, const QString& tooltip);
    void rename(int row, const QString& name);
    void remove(int row);
    void selection_changed();
    enum class LoadMode { Add, Replace };
    void add_loaded(const MarkupsFile& f, const QString& path, LoadMode mode);
    // The names of the surfaces the points lie on (within 0.5 mm), and what a
    // ruler's line passes through, cached per point while the scene's
    // surfaces stay as they were (the core builds a search tree per query).
    QString surface_text(const glm::dvec3& p);
    QString crossings_text(const Markup& m);
    void check_cache();
    // Above kInlineTriangles in the visible surfaces the answers are worked
    // out off the GUI thread (a quiet job that keeps the search trees while
    // the meshes stay: at 32 M triangles a tree takes seconds to build), the
    // table showing "..." until they arrive.
    static constexpr std::size_t kInlineTriangles = 2'000'000;
    bool answers_later() const;
    void look_up_later();
    std::set<std::array<double, 3>> surface_waiting_;
    std::set<std::array<double, 6>> crossings_waiting_;
    bool looking_up_ = false;
    struct Trees; // the search trees a lookup builds, kept for the next
    std::shared_ptr<Trees> trees_;

    AppContext& context_;
    int observer_ = 0;
    QTableWidget* table_ = nullptr;
    ColumnFit* fit_ = nullptr;
    QTimer* refresh_timer_ = nullptr;
    std::vector<Row> rows_;
    bool filling_ = false;  // the table is being rebuilt: its item changes are not edits
    bool renaming_ = false; // a rename from the table: the table already shows it
    std::string cache_key_; // the scene's surfaces the cache holds answers for
    std::map<std::array<double, 3>, QString> surface_cache_;
    std::map<std::array<double, 6>, QString> crossings_cache_;
};

} // namespace iso::gui
