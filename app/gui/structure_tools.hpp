// Structures in the main window (docs/gui.md "Structures"): the Isolate
// tool (click a surface in the 3D view: the connected component under the
// cursor becomes a surface of its own and its parent is hidden, 3D Slicer's
// "keep selected island", one undo step; a component isolated already is
// shown, not added twice) and the Distance tool (click two separate
// structures, two surfaces or two components of one: the exact shortest
// distance between them, drawn as a ruler between the two closest points,
// one undo step; two clicks on one connected structure are refused). The
// workspace's isolated components are listed with their area, volume (mL,
// with the uncertainty), closed or open and bounds in the Measurements
// dock. Presentation only: the work is the core's (core::plan_component,
// core::Workspace::isolate, core::surface_gap), off the GUI thread.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <QObject>
#include <QPointF>
#include <QString>

#include <glm/vec3.hpp>

class QAction;
class QTableWidget;

#include "io/mesh.hpp"
#include "renderer/core/measure.hpp"

namespace iso::gui {

class AppContext;
class ColumnFit;
class Viewer;

class StructureTools : public QObject {
public:
    enum class Tool { None, Isolate, Distance };
    enum Column { Name = 0, Area = 1, Volume = 2, Closed = 3, Bounds = 4 };

    // Adds the Structures tool bar (Isolate, Distance: checkable, at most
    // one on, and off when another tool is taken) and the table of
    // isolated components (table(): the window puts it in the Measurements dock).
    explicit StructureTools(AppContext& context);
    ~StructureTools() override;

    Tool tool() const { return tool_; }
    void set_tool(Tool t);
    QAction* isolate_action() const { return isolate_; }
    QAction* distance_action() const { return distance_; }
    QTableWidget* table() const { return table_; }

    // A click of the 3D view: true when the active tool took it.
    bool viewer_click(Viewer& v, QPointF pixel);
    // Isolate's work for surface `id` at `at` (what a click does).
    void isolate(std::uint32_t id, const glm::dvec3& at);
    // Distances and isolations finished so far, refused or failed ones too (tests wait on them).
    int distances() const { return distances_; }
    int isolations() const { return isolations_; }

private:
    void update_table();
    void measure_distance(std::uint32_t a, const glm::dvec3& at_a, std::uint32_t b, const glm::dvec3& at_b);

    AppContext& context_;
    int observer_ = 0;
    QAction* isolate_ = nullptr;
    QAction* distance_ = nullptr;
    QTableWidget* table_ = nullptr;
    ColumnFit* fit_ = nullptr;
    Tool tool_ = Tool::None;
    struct First {
        std::uint32_t surface = 0;
        glm::dvec3 at{0.0};
    };
    std::optional<First> first_; // the Distance tool's first click
    int distances_ = 0, isolations_ = 0;
    // Each isolated surface's measurement, with the mesh it was made of.
    std::map<std::uint32_t, std::pair<std::shared_ptr<const Mesh>, core::SurfaceMeasurement>> measured_;
    bool measuring_ = false;
};

} // namespace iso::gui
