#include "app/gui/structure_tools.hpp"

#include <cmath>
#include <map>
#include <memory>

#include <QAction>
#include <QActionGroup>
#include <QHeaderView>
#include <QMainWindow>
#include <QTableWidget>
#include <QTimer>
#include <QToolBar>

#include "app/gui/app_context.hpp"
#include "app/gui/column_fit.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/structures.hpp"

namespace iso::gui {

namespace {

QString number(double v, int decimals) { return QString::number(v, 'f', decimals); }

// "1234.5 ± 12.3 mm²", "12.345 ± 0.120 mL" (≥ for a lower bound), the
// uncertainty left out where there is none.
QString with_uncertainty(double v, double u, int decimals, const QString& unit, const QString& prefix = {}) {
    QString s = prefix + number(v, decimals);
    if (std::isfinite(u)) s += QString::fromUtf8(" \u00b1 ") + number(u, decimals);
    return s + " " + unit;
}

QString point_text(const glm::dvec3& p) {
    return "(" + number(p.x, 1) + ", " + number(p.y, 1) + ", " + number(p.z, 1) + ")";
}

void add_row(QTableWidget* t, const core::SurfaceMeasurement& m) {
    const SurfaceMeasures& s = m.measures;
    const int row = t->rowCount();
    t->insertRow(row);
    const auto cell = [&](int col, const QString& text) {
        auto* item = new QTableWidgetItem(text);
        item->setToolTip(text);
        item->setFlags(Qt::ItemIsSelectable | Qt::ItemIsEnabled);
        t->setItem(row, col, item);
    };
    cell(StructureTools::Name, QString::fromStdString(m.name));
    cell(StructureTools::Area, with_uncertainty(s.area_mm2, s.area_uncertainty_mm2, 1, QString::fromUtf8("mm\u00b2")));
    // Never a negative volume: the wall of a cavity says what it encloses (encloses_cavity).
    const QString at_least = s.volume_kind == VolumeKind::LowerBound ? QString::fromUtf8("\u2265 ") : QString();
    if (s.volume_kind == VolumeKind::Undefined)
        cell(StructureTools::Volume, "undefined (inconsistent orientation)");
    else if (encloses_cavity(s.volume_ml))
        cell(StructureTools::Volume,
             with_uncertainty(-s.volume_ml, s.volume_uncertainty_ml, 3, "mL", "encloses a cavity of " + at_least));
    else
        cell(StructureTools::Volume, with_uncertainty(s.volume_ml, s.volume_uncertainty_ml, 3, "mL", at_least));
    cell(StructureTools::Closed, s.closed ? "closed" : "open");
    cell(StructureTools::Bounds, point_text(s.bounds_min) + QString::fromUtf8(" \u2013 ") + point_text(s.bounds_max));
}

} // namespace

StructureTools::StructureTools(AppContext& context) : QObject(&context.window), context_(context) {
    QToolBar* bar = context.window.addToolBar("Structures");
    bar->setObjectName("structure_toolbar");
    isolate_ = bar->addAction("Isolate");
    isolate_->setObjectName("isolate_tool");
    isolate_->setToolTip("Click a surface in the 3D view: the connected piece under the cursor becomes a surface of "
                         "its own (its parent hidden; Edit > Undo takes it back), measured in the Measurements panel");
    distance_ = bar->addAction("Distance");
    distance_->setObjectName("distance_tool");
    distance_->setToolTip("Click two separate structures (two surfaces, or two pieces of one) in the 3D view: their "
                          "shortest distance, drawn as a ruler between the closest points");
    for (QAction* a : {isolate_, distance_}) a->setCheckable(true);
    QObject::connect(isolate_, &QAction::toggled, this, [this](bool on) {
        if (on)
            set_tool(Tool::Isolate);
        else if (tool_ == Tool::Isolate)
            set_tool(Tool::None);
    });
    QObject::connect(distance_, &QAction::toggled, this, [this](bool on) {
        if (on)
            set_tool(Tool::Distance);
        else if (tool_ == Tool::Distance)
            set_tool(Tool::None);
    });
    table_ = new QTableWidget(0, 5);
    table_->setObjectName("structures_table");
    table_->setHorizontalHeaderLabels({"Isolated structure", "Area", "Volume", "Closed", "Bounds (LPS mm)"});
    // Within the dock's width: the widest columns give way, elided (whole in the tooltips).
    fit_ = new ColumnFit(table_);
    table_->verticalHeader()->hide();
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
    table_->setMinimumHeight(5 * table_->fontMetrics().height()); // a few rows visible, not one
    // One tool at a time across the window: another one taken turns these off.
    context.tool_changed.push_back([this](AppContext::Tool t) {
        if (t != AppContext::Tool::Isolate && t != AppContext::Tool::Distance && tool_ != Tool::None)
            set_tool(Tool::None);
    });
    // The table lists the workspace's isolated components, measured off the GUI thread.
    observer_ = context.workspace.observe([this](core::Parts p) {
        if (core::has(p, core::Part::Data)) set_tool(Tool::None);
        if (p & (core::Part::Data | core::Part::Surfaces)) QTimer::singleShot(0, this, [this] { update_table(); });
    });
}

StructureTools::~StructureTools() { context_.workspace.unobserve(observer_); }

void StructureTools::set_tool(Tool t) {
    tool_ = t;
    first_.reset();
    const QSignalBlocker b1(isolate_), b2(distance_);
    isolate_->setChecked(t == Tool::Isolate);
    distance_->setChecked(t == Tool::Distance);
    if (t != Tool::None)
        context_.set_tool(t == Tool::Isolate ? AppContext::Tool::Isolate : AppContext::Tool::Distance);
    else if (context_.tool() == AppContext::Tool::Isolate || context_.tool() == AppContext::Tool::Distance)
        context_.set_tool(AppContext::Tool::None);
    if (t == Tool::Isolate) context_.status("Isolate: click a surface in the 3D view");
    if (t == Tool::Distance) context_.status("Distance: click the first structure in the 3D view");
}

bool StructureTools::viewer_click(Viewer& v, QPointF pixel) {
    if (tool_ == Tool::None) return false;
    if (context_.busy(true)) return true;
    core::PickResult r;
    try {
        r = v.pick_at(pixel);
    } catch (const std::exception& e) {
        context_.status(QString("Pick failed: ") + e.what());
        return true;
    }
    if (!r.visible || r.layers[*r.visible].volume) {
        context_.status("No surface there: click a surface");
        return true;
    }
    const core::PickLayer& l = r.layers[*r.visible];
    if (tool_ == Tool::Isolate) {
        isolate(l.surface, l.lps);
        return true;
    }
    if (!first_) {
        first_ = First{l.surface, l.lps};
        context_.status(QString::fromStdString("Distance from " + l.name) + ": click the second structure");
        return true;
    }
    const First a = *first_;
    first_.reset();
    measure_distance(a.surface, a.at, l.surface, l.lps);
    return true;
}

// The connected component under the click, planned off the GUI thread
// (core::plan_component: components and measurement), made a surface of
// its own in one undo step (core::Workspace::isolate: its parent hidden;
// a component that is a surface already is shown, not added again). With
// the crop box on, only the part of the component within it, cut and
// capped (3D Slicer's islands within an ROI; docs/measure.md "Structures
// within a box").
void StructureTools::isolate(std::uint32_t id, const glm::dvec3& at) {
    core::Workspace& w = context_.workspace;
    if (!w.scene().has_surface(id)) return;
    auto plan = std::make_shared<core::ComponentPlan>();
    const std::shared_ptr<const Mesh> mesh = w.scene().shared_mesh(id);
    const core::Scene* scene = &w.scene();
    const QString name = QString::fromStdString(w.scene().info(id).name);
    std::optional<LpsBox> within;
    if (const auto& box = w.look().clip.box) within = LpsBox{box->first, box->second};
    context_.jobs.run(
        "Isolating a component of " + name + (within ? " within the crop box" : ""), false,
        [scene, id, at, plan, within](const ProgressFn&) { *plan = core::plan_component(*scene, id, at, within); },
        [this, scene, mesh, id, plan, name](std::exception_ptr e) {
            core::Workspace& w = context_.workspace;
            if (e) {
                context_.error("Isolate failed", "Cannot isolate a component of " + name, e);
                return;
            }
            // Another scene, or the surface changed meanwhile: the plan is of what was.
            if (scene != &w.scene() || !w.scene().has_surface(id) || w.scene().shared_mesh(id) != mesh) return;
            core::Workspace::Isolation done;
            const QString part = QString::fromStdString(plan->info.name);
            context_.edit("Isolate " + part, core::Parts(core::Part::Surfaces),
                          [&] { done = w.isolate(std::move(*plan)); });
            const QString shown = QString::fromStdString(w.scene().info(done.isolated.surface).name);
            context_.status(done.added ? QString("Isolated %1 (%2 of %3 components; Edit > Undo takes it back)")
                                             .arg(shown)
                                             .arg(done.isolated.component + 1)
                                             .arg(done.isolated.components)
                                       : QString("%1 is one structure already: shown, not added again").arg(shown));
            ++isolations_;
        });
}

void StructureTools::measure_distance(std::uint32_t a, const glm::dvec3& at_a, std::uint32_t b,
                                      const glm::dvec3& at_b) {
    auto gap = std::make_shared<core::SurfaceGap>();
    const core::Scene* scene = &context_.workspace.scene();
    // The components under the two clicks (of one surface or two).
    context_.jobs.run(
        "Measuring the shortest distance", false,
        [scene, gap, a, b, at_a, at_b](const ProgressFn&) { *gap = core::surface_gap(*scene, a, b, at_a, at_b); },
        [this, gap, scene](std::exception_ptr e) {
            ++distances_;
            if (e || scene != &context_.workspace.scene()) {
                if (e) context_.error("Distance failed", "The distance could not be measured", e);
                return;
            }
            if (gap->same_structure) {
                // No gap between a structure and itself: no 0 mm ruler.
                context_.status(QString::fromStdString("Both clicks are on one connected structure (" + gap->name_a +
                                                       "): no distance between them. Click two separate "
                                                       "structures, or cut them apart first"));
                return;
            }
            MarkupsState after = context_.workspace.markups_state();
            after.markups.push_back(core::gap_markup(*gap));
            after.sources.emplace_back();
            context_.edit("Add distance", core::Parts(core::Part::Markups),
                          [&] { context_.workspace.set_markups(std::move(after)); });
            context_.status(QString::fromStdString(gap->name_a + " to " + gap->name_b) + ": " +
                            number(gap->distance.pair.distance_mm, 3) + " mm" +
                            (gap->distance.touching ? " (they touch or cross)" : ""));
        });
}

// The rows: the workspace's isolated components (surfaces made by Isolate,
// or a session's), each measured once per mesh (off the GUI thread).
void StructureTools::update_table() {
    const core::Scene& scene = context_.workspace.scene();
    std::vector<core::SurfaceId> ids, unmeasured;
    for (const auto id : scene.surfaces()) {
        if (!scene.info(id).post.keep_at) continue;
        ids.push_back(id);
        const auto it = measured_.find(id);
        if (it == measured_.end() || it->second.first != scene.shared_mesh(id)) unmeasured.push_back(id);
    }
    table_->setRowCount(0);
    struct Refit {
        ColumnFit* f;
        ~Refit() { f->refit(); }
    } refit{fit_};
    for (const auto id : ids)
        if (const auto it = measured_.find(id); it != measured_.end() && it->second.first == scene.shared_mesh(id)) {
            core::SurfaceMeasurement m = it->second.second;
            m.name = scene.info(id).name;
            add_row(table_, m);
        }
    if (unmeasured.empty() || measuring_ || context_.busy()) return;
    measuring_ = true;
    auto out = std::make_shared<std::vector<core::SurfaceMeasurement>>();
    std::vector<std::shared_ptr<const Mesh>> meshes;
    for (const auto id : unmeasured) meshes.push_back(scene.shared_mesh(id));
    const core::Scene* s = &scene;
    context_.jobs.run(
        "Measuring the isolated structures", false,
        [s, unmeasured, out](const ProgressFn&) { *out = core::measure_surfaces(*s, unmeasured); },
        [this, s, out, meshes](std::exception_ptr e) {
            measuring_ = false;
            if (e || s != &context_.workspace.scene()) return;
            for (std::size_t i = 0; i < out->size(); ++i) measured_[(*out)[i].surface] = {meshes[i], (*out)[i]};
            update_table();
        });
}

} // namespace iso::gui
