// Structures in the main window (docs/gui.md "Structures"): the Isolate
// tool (click a surface in the 3D view: the connected component under the
// cursor becomes a surface of its own and its parent is hidden, 3D Slicer's
// "keep selected island", one undo step; a component isolated already is
// shown, not added twice) and the Distance tool (click two separate
// structures, two surfaces or two components of one: the exact shortest
// distance between them, drawn as a ruler between the two closest points,
// one undo step; two clicks on one connected structure are refused) and
// the Grow tool (click a point in the 3D view or a slice view: the voxels
// joined to it whose values lie within the tool bar's range, within the
// crop box when it is on, become a closed surface of their own, "grown
// <n>": 3D Slicer's Grow from seeds / threshold flood fill, one undo step).
// The workspace's parts (isolated components, parts cut by a box or the
// Scissors, grown regions; made here or by a session, which keeps how each
// was made) are listed in the Measurements dock as 3D Slicer lists
// segments: a box that shows or hides each (one undo step), its colour and
// name, then its area, volume (mL, with the uncertainty; a grown region's
// by its voxels), closed or open, largest diameter, centroid and bounds. Presentation only: the work is the core's (core::plan_component,
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
#include <QPointer>
#include <QString>

#include <glm/vec3.hpp>

class QAction;
class QDoubleSpinBox;
class QTableWidget;

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/surface/grow.hpp"
#include "renderer/surface/shape.hpp"

namespace iso::gui {

class AppContext;
class ColumnFit;
class Viewer;

class StructureTools : public QObject {
public:
    enum class Tool { None, Isolate, Distance, Grow, Scissors };
    enum Column { Name = 0, Area = 1, Volume = 2, Closed = 3, Diameter = 4, Centroid = 5, Bounds = 6, Columns = 7 };

    // Adds the Structures tool bar (Isolate, Distance: checkable, at most
    // one on, and off when another tool is taken) and the table of
    // isolated components (table(): the window puts it in the Measurements dock).
    explicit StructureTools(AppContext& context);
    ~StructureTools() override;

    Tool tool() const { return tool_; }
    void set_tool(Tool t);
    QAction* isolate_action() const { return isolate_; }
    QAction* distance_action() const { return distance_; }
    QAction* grow_action() const { return grow_; }
    QAction* scissors_action() const { return scissors_; }
    // Scissors keeps the outside of the outline (the tool bar's "Keep outside"); else the inside.
    QAction* keep_outside_action() const { return keep_outside_; }
    // The Grow tool's range (the tool bar's two numbers, volume units).
    void set_grow_range(double lo, double hi);
    std::pair<double, double> grow_range() const;
    QTableWidget* table() const { return table_; }

    // A click of the 3D view: true when the active tool took it.
    bool viewer_click(Viewer& v, QPointF pixel);
    // Scissors: a press in the 3D view starts an outline (true: taken), the
    // drag draws it, the release closes it and cuts the surface most of
    // whose visible pixels it encloses (core::plan_scissors off the GUI
    // thread; the part a surface of its own, its parent hidden, one undo step).
    bool outline_press(Viewer& v, QPointF pixel);
    void outline_move(QPointF pixel);
    void outline_release(Viewer& v, QPointF pixel, bool dragged);
    // Scissors' work on surface `id` (what a release does).
    void cut(std::uint32_t id, core::ScissorsRequest r);
    int cuts() const { return cuts_; } // finished so far, refused or failed ones too
    // A click of a slice view at `lps`: true when the active tool took it
    // (Grow seeds there).
    bool slice_click(const glm::dvec3& lps);
    // Isolate's work for surface `id` at `at` (what a click does).
    void isolate(std::uint32_t id, const glm::dvec3& at);
    // Grow's work: the region joined to `seed` within the range (and the
    // crop box when it is on) made a surface of its own, one undo step.
    void grow(const glm::dvec3& seed);
    int grown() const { return grown_; } // grows finished so far, refused or failed ones too
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
    QAction* grow_ = nullptr;
    QAction* scissors_ = nullptr;
    QAction* keep_outside_ = nullptr;
    std::vector<QPointF> outline_; // image pixels, while a drag draws it
    QPointer<Viewer> outlined_;
    QDoubleSpinBox* grow_lo_ = nullptr;
    QDoubleSpinBox* grow_hi_ = nullptr;
    QTableWidget* table_ = nullptr;
    ColumnFit* fit_ = nullptr;
    Tool tool_ = Tool::None;
    struct First {
        std::uint32_t surface = 0;
        glm::dvec3 at{0.0};
    };
    std::optional<First> first_; // the Distance tool's first click
    int distances_ = 0, isolations_ = 0, grown_ = 0, cuts_ = 0;
    void update_grow_range();
    // Each listed surface's measurement and shape, with the mesh it was made of.
    struct Measured {
        std::shared_ptr<const Mesh> mesh;
        core::SurfaceMeasurement m;
        ShapeMeasures shape;
        std::optional<GrownRegion> region; // a grown region grown again (a session's), on its way to grown_regions_
    };
    std::map<std::uint32_t, Measured> measured_;
    // Grown regions (SurfaceInfo::grown, not cut since): their voxel
    // measurement (the count, with the partial-volume uncertainty), by
    // surface, with the mesh they made.
    std::map<std::uint32_t, std::pair<std::shared_ptr<const Mesh>, GrownRegion>> grown_regions_;
    const iso::Volume* grow_range_for_ = nullptr; // the volume the range was set for
    bool measuring_ = false;
};

} // namespace iso::gui
