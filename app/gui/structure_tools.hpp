// Structures in the main window (docs/gui.md "Structures"): the Isolate
// tool (click a surface in the 3D view: the connected component under the
// cursor becomes a surface of its own, 3D Slicer's "keep selected island")
// and the Distance tool (click two surfaces, or two components of one: the
// exact shortest distance between them, drawn as a ruler between the two
// closest points, one undo step). The isolated components are listed with
// their area, volume (mL, with the uncertainty), closed or open and bounds
// in the Measurements dock. Presentation only: the work is the core's
// (core::plan_component / add_component through the Surfaces panel,
// core::surface_gap), off the GUI thread.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <QObject>
#include <QPointF>
#include <QString>

#include <glm/vec3.hpp>

class QAction;
class QTableWidget;

namespace iso::core {
struct IsolatedComponent;
}

namespace iso::gui {

class MainWindow;
class Viewer;

class StructureTools : public QObject {
public:
    enum class Tool { None, Isolate, Distance };
    enum Column { Name = 0, Area = 1, Volume = 2, Closed = 3, Bounds = 4 };

    // Adds the Structures tool bar (Isolate, Distance: checkable, at most
    // one on, and off when a Measure tool is taken) and the table of
    // isolated components (table(): the window puts it in the Measurements dock).
    explicit StructureTools(MainWindow& window);

    Tool tool() const { return tool_; }
    void set_tool(Tool t);
    QAction* isolate_action() const { return isolate_; }
    QAction* distance_action() const { return distance_; }
    QTableWidget* table() const { return table_; }

    // A click of the 3D view: true when the active tool took it.
    bool viewer_click(Viewer& v, QPointF pixel);
    // A component was isolated (the Surfaces panel's report): its row.
    void add_component(const core::IsolatedComponent& c);
    // A new scene: the table and a half-placed distance are cleared; the
    // rows of the scene's isolated components (a session's) are measured again.
    void reset();
    // Distances computed so far (tests wait on it).
    int distances() const { return distances_; }

private:
    void measure_again(const std::vector<std::uint32_t>& ids);
    void measure_distance(std::uint32_t a, const glm::dvec3& at_a, std::uint32_t b, const glm::dvec3& at_b);

    MainWindow& window_;
    QAction* isolate_ = nullptr;
    QAction* distance_ = nullptr;
    QTableWidget* table_ = nullptr;
    Tool tool_ = Tool::None;
    struct First {
        std::uint32_t surface = 0;
        glm::dvec3 at{0.0};
    };
    std::optional<First> first_; // the Distance tool's first click
    int distances_ = 0;
};

} // namespace iso::gui
