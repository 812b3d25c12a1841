#include "app/gui/structure_tools.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <tuple>

#include <QAction>
#include <QActionGroup>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QLineF>
#include <QPolygonF>
#include <QRectF>
#include <QSignalBlocker>
#include <QHeaderView>
#include <QMainWindow>
#include <QTableWidget>
#include <QTimer>
#include <QToolBar>

#include "app/gui/app_context.hpp"
#include "app/gui/column_fit.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/workspace.hpp"

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

// A row of the table: a structure's visibility (the box), colour and name,
// its measurement and shape; a grown region's volume is its voxels'
// (`region`), with the partial-volume uncertainty.
void add_row(QTableWidget* t, const core::SurfaceInfo& info, const core::SurfaceMeasurement& m,
             const ShapeMeasures& shape, const GrownRegion* region) {
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
    QTableWidgetItem* name = t->item(row, StructureTools::Name);
    name->setFlags(name->flags() | Qt::ItemIsUserCheckable);
    name->setCheckState(info.visible ? Qt::Checked : Qt::Unchecked);
    name->setData(Qt::DecorationRole, to_qcolor(info.color));
    name->setData(Qt::UserRole, m.surface);
    name->setToolTip(name->text() + ": tick to show, untick to hide (3D view and slice outlines)");
    cell(StructureTools::Area, with_uncertainty(s.area_mm2, s.area_uncertainty_mm2, 1, QString::fromUtf8("mm\u00b2")));
    // Never a negative volume: the wall of a cavity says what it encloses (encloses_cavity).
    const QString at_least = s.volume_kind == VolumeKind::LowerBound ? QString::fromUtf8("\u2265 ") : QString();
    if (region)
        cell(StructureTools::Volume, with_uncertainty(region->volume_ml, region->partial_volume_ml, 3, "mL") +
                                         QString(" (%1 voxels)").arg(region->voxels));
    else if (s.volume_kind == VolumeKind::Undefined)
        cell(StructureTools::Volume, "undefined (inconsistent orientation)");
    else if (encloses_cavity(s.volume_ml))
        cell(StructureTools::Volume,
             with_uncertainty(-s.volume_ml, s.volume_uncertainty_ml, 3, "mL", "encloses a cavity of " + at_least));
    else
        cell(StructureTools::Volume, with_uncertainty(s.volume_ml, s.volume_uncertainty_ml, 3, "mL", at_least));
    cell(StructureTools::Closed, s.closed ? "closed" : "open");
    cell(StructureTools::Diameter, number(shape.feret_mm, 2) + " mm");
    cell(StructureTools::Centroid, shape.solid ? point_text(shape.centroid) : QString("(open surface)"));
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
    grow_ = bar->addAction("Grow");
    grow_->setObjectName("grow_tool");
    grow_->setToolTip("Click a point in the 3D view or a slice view: the voxels joined to it whose values lie within "
                      "the range (and within the crop box when it is on) become a closed surface of their own, "
                      "measured by its voxels in the Measurements panel (Edit > Undo takes it back)");
    bar->addWidget(new QLabel(" range "));
    for (QDoubleSpinBox** box : {&grow_lo_, &grow_hi_}) {
        *box = new QDoubleSpinBox;
        (*box)->setRange(-1e9, 1e9);
        (*box)->setDecimals(1);
        (*box)->setKeyboardTracking(false);
        bar->addWidget(*box);
    }
    grow_lo_->setObjectName("grow_lo");
    grow_hi_->setObjectName("grow_hi");
    grow_lo_->setToolTip("Grow: the lowest value grown through");
    grow_hi_->setToolTip("Grow: the highest value grown through");
    scissors_ = bar->addAction("Scissors");
    scissors_->setObjectName("scissors_tool");
    scissors_->setToolTip("Drag an outline on the 3D view: the structure it encloses most of is cut along the view "
                          "direction, keeping what is inside the outline (or outside it, with Keep outside), capped "
                          "and measured as a surface of its own (Edit > Undo takes it back)");
    keep_outside_ = bar->addAction("Keep outside");
    keep_outside_->setObjectName("scissors_keep_outside");
    keep_outside_->setCheckable(true);
    keep_outside_->setToolTip("Scissors: keep what is outside the outline instead of what is inside");
    for (QAction* a : {isolate_, distance_, grow_, scissors_}) a->setCheckable(true);
    // Each action turns its tool on, and off when it was the one on.
    for (const auto& [action, tool] : {std::pair{isolate_, Tool::Isolate}, std::pair{distance_, Tool::Distance},
                                       std::pair{grow_, Tool::Grow}, std::pair{scissors_, Tool::Scissors}})
        QObject::connect(action, &QAction::toggled, this, [this, tool = tool](bool on) {
            if (on)
                set_tool(tool);
            else if (tool_ == tool)
                set_tool(Tool::None);
        });
    table_ = new QTableWidget(0, Columns);
    table_->setObjectName("structures_table");
    table_->setHorizontalHeaderLabels(
        {"Structure", "Area", "Volume", "Closed", "Diameter", "Centroid", "Bounds (LPS mm)"});
    // Short headers in a narrow dock; what they mean in their tooltips.
    table_->horizontalHeaderItem(Diameter)->setToolTip("The largest diameter (3D Feret): the longest segment between "
                                                       "two points of the structure");
    table_->horizontalHeaderItem(Centroid)->setToolTip("The centroid of the enclosed solid, LPS mm");
    // Within the dock's width: the widest columns give way, elided (whole in the tooltips).
    fit_ = new ColumnFit(table_);
    table_->verticalHeader()->hide();
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
    table_->setMinimumHeight(5 * table_->fontMetrics().height()); // a few rows visible, not one
    // The Structure cell's box shows or hides it (3D Slicer's segment list's eye), one undo step.
    QObject::connect(table_, &QTableWidget::itemChanged, this, [this](QTableWidgetItem* item) {
        core::Workspace& w = context_.workspace;
        const core::SurfaceId id = item->data(Qt::UserRole).toUInt();
        if (item->column() != Name || !w.scene().has_surface(id)) return;
        core::SurfaceInfo info = w.scene().info(id);
        info.visible = item->checkState() == Qt::Checked;
        if (info.visible == w.scene().info(id).visible) return;
        context_.edit(QString(info.visible ? "Show " : "Hide ") + QString::fromStdString(info.name),
                      core::Parts(core::Part::Surfaces), [&] { w.set_surface_info(id, info); });
    });
    // One tool at a time across the window: another one taken turns these off.
    context.tool_changed.push_back([this](AppContext::Tool t) {
        if (t != AppContext::Tool::Isolate && t != AppContext::Tool::Distance && t != AppContext::Tool::Grow &&
            t != AppContext::Tool::Scissors && tool_ != Tool::None)
            set_tool(Tool::None);
    });
    // The table lists the workspace's isolated components, measured off the GUI thread.
    observer_ = context.workspace.observe([this](core::Parts p) {
        if (core::has(p, core::Part::Data)) {
            set_tool(Tool::None);
            update_grow_range();
        }
        if (p & (core::Part::Data | core::Part::Surfaces)) QTimer::singleShot(0, this, [this] { update_table(); });
    });
}

StructureTools::~StructureTools() { context_.workspace.unobserve(observer_); }

void StructureTools::set_tool(Tool t) {
    tool_ = t;
    first_.reset();
    const QSignalBlocker b1(isolate_), b2(distance_), b3(grow_), b4(scissors_);
    isolate_->setChecked(t == Tool::Isolate);
    distance_->setChecked(t == Tool::Distance);
    grow_->setChecked(t == Tool::Grow);
    scissors_->setChecked(t == Tool::Scissors);
    const AppContext::Tool mine = t == Tool::Isolate    ? AppContext::Tool::Isolate
                                  : t == Tool::Distance ? AppContext::Tool::Distance
                                  : t == Tool::Grow     ? AppContext::Tool::Grow
                                                        : AppContext::Tool::Scissors;
    const AppContext::Tool now = context_.tool();
    if (t != Tool::None)
        context_.set_tool(mine);
    else if (now == AppContext::Tool::Isolate || now == AppContext::Tool::Distance || now == AppContext::Tool::Grow ||
             now == AppContext::Tool::Scissors)
        context_.set_tool(AppContext::Tool::None);
    if (t == Tool::Scissors)
        context_.status(
            "Scissors: drag an outline around what to keep on the 3D view (Keep outside: what to cut away)");
    if (t == Tool::Isolate) context_.status("Isolate: click a surface in the 3D view");
    if (t == Tool::Distance) context_.status("Distance: click the first structure in the 3D view");
    if (t == Tool::Grow) {
        update_grow_range();
        context_.status("Grow: click a point of the structure in the 3D view or a slice view (values within the "
                        "range on the Structures tool bar)");
    }
}

// The range a new volume starts with: from the lowest visible isosurface's
// value (what the user sees as the structure's edge; the volume's middle
// value without one) to the volume's largest value.
void StructureTools::update_grow_range() {
    const core::Scene& scene = context_.workspace.scene();
    if (!scene.has_volume()) {
        grow_range_for_ = nullptr;
        return;
    }
    if (grow_range_for_ == &scene.volume()) return; // the user's range stays
    grow_range_for_ = &scene.volume();
    const ValueRange range = scene.value_range();
    const double vmin = range.min, vmax = range.max;
    double lo = 0.5 * (vmin + vmax);
    bool found = false;
    for (const auto id : scene.surfaces()) {
        const core::SurfaceInfo& info = scene.info(id);
        if (info.kind != core::SurfaceInfo::Kind::Iso || !info.visible) continue;
        lo = found ? std::min(lo, info.value) : info.value;
        found = true;
    }
    set_grow_range(lo, vmax);
}

void StructureTools::set_grow_range(double lo, double hi) {
    grow_lo_->setValue(lo);
    grow_hi_->setValue(hi);
}

std::pair<double, double> StructureTools::grow_range() const { return {grow_lo_->value(), grow_hi_->value()}; }

bool StructureTools::slice_click(const glm::dvec3& lps) {
    if (tool_ != Tool::Grow) return false;
    if (!context_.busy(true)) grow(lps);
    return true;
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
    if (tool_ == Tool::Grow) {
        // A surface or the ray-cast volume: the seed is what was clicked, a
        // little inside it (seed_within) when the point lies on an isosurface.
        if (!r.visible || !context_.workspace.scene().has_volume()) {
            context_.status("Grow: no structure there: click a surface or the volume");
            return true;
        }
        const auto [lo, hi] = grow_range();
        const auto seed =
            seed_within(context_.workspace.scene().volume(), r.layers[*r.visible].lps, v.camera().forward(), lo, hi);
        grow(seed ? *seed : r.layers[*r.visible].lps); // without one, grow says why (the value there)
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

bool StructureTools::outline_press(Viewer& v, QPointF pixel) {
    if (tool_ != Tool::Scissors || context_.busy(true)) return false;
    outline_ = {pixel};
    outlined_ = &v;
    v.set_sketch(outline_);
    return true;
}

void StructureTools::outline_move(QPointF pixel) {
    if (!outlined_ || outline_.empty()) return;
    if (QLineF(outline_.back(), pixel).length() < 2.0) return; // a point every 2 pixels is plenty
    outline_.push_back(pixel);
    outlined_->set_sketch(outline_);
}

// The outline closed: the surface most of whose visible pixels it encloses
// (a pick over its bounding rectangle lists them) is cut.
void StructureTools::outline_release(Viewer& v, QPointF pixel, bool dragged) {
    std::vector<QPointF> outline = std::move(outline_);
    outline_.clear();
    v.set_sketch({});
    if (!dragged || outline.size() < 3) {
        context_.status("Scissors: drag an outline around what to keep");
        return;
    }
    if (QLineF(outline.back(), pixel).length() >= 2.0) outline.push_back(pixel);
    QRectF box = QPolygonF(QVector<QPointF>(outline.begin(), outline.end())).boundingRect();
    const QSize size = v.image_size();
    box = box.intersected(QRectF(0, 0, size.width(), size.height()));
    core::PickResult r;
    try {
        r = v.pick_at(box.center(), PickRegion{int(box.left()), int(box.top()), int(std::ceil(box.width())),
                                               int(std::ceil(box.height()))});
    } catch (const std::exception& e) {
        context_.status(QString("Scissors: ") + e.what());
        return;
    }
    std::map<std::uint32_t, std::size_t> pixels;
    for (const auto& t : r.triangles) pixels[t.surface] += t.pixels;
    std::uint32_t id = 0;
    for (const auto& [surface, n] : pixels)
        if (!id || n > pixels[id]) id = surface;
    if (!id) {
        context_.status("Scissors: no surface within the outline");
        return;
    }
    core::ScissorsRequest req;
    for (const QPointF& q : outline) req.outline.push_back({q.x(), q.y()});
    req.camera = v.camera();
    req.width = size.width();
    req.height = size.height();
    req.keep_inside = !keep_outside_->isChecked();
    cut(id, std::move(req));
}

void StructureTools::cut(std::uint32_t id, core::ScissorsRequest req) {
    core::Workspace& w = context_.workspace;
    if (!w.scene().has_surface(id)) return;
    auto plan = std::make_shared<core::ComponentPlan>();
    const std::shared_ptr<const Mesh> mesh = w.scene().shared_mesh(id);
    const core::Scene* scene = &w.scene();
    const QString name = QString::fromStdString(w.scene().info(id).name);
    context_.jobs.run(
        "Cutting " + name + " with the scissors", false,
        [scene, id, req, plan](const ProgressFn&) { *plan = core::plan_scissors(*scene, id, req); },
        [this, scene, mesh, id, plan, name](std::exception_ptr e) {
            core::Workspace& w = context_.workspace;
            ++cuts_;
            if (e) {
                context_.error("Scissors failed", "Cannot cut " + name, e);
                return;
            }
            if (scene != &w.scene() || !w.scene().has_surface(id) || w.scene().shared_mesh(id) != mesh) return;
            const QString part = QString::fromStdString(plan->info.name);
            core::SurfaceId made = 0;
            context_.edit("Scissors " + part, core::Parts(core::Part::Surfaces), [&] {
                made = w.add_mesh(std::move(plan->mesh), plan->info);
                core::SurfaceInfo parent = w.scene().info(id);
                parent.visible = false; // what is left on screen is the part
                w.set_surface_info(id, parent);
            });
            if (!made) return;
            const SurfaceMeasures& m = plan->measures;
            // An open part's volume is a lower bound, as the table says it.
            const QString at_least = m.volume_kind == VolumeKind::LowerBound ? QString::fromUtf8("\u2265 ") : QString();
            context_.status(part + ": " + at_least + number(std::abs(m.volume_ml), 3) + " mL, " +
                            (m.closed ? "closed" : "open") + " (Edit > Undo takes it back)");
            update_table();
        });
}

// Grow from `seed`: the region planned off the GUI thread
// (core::plan_grown: the flood fill, its surface and measures), added as a
// surface of its own in one undo step.
void StructureTools::grow(const glm::dvec3& seed) {
    core::Workspace& w = context_.workspace;
    if (!w.scene().has_volume()) return;
    GrowOptions o;
    std::tie(o.lo, o.hi) = grow_range();
    if (const auto& box = w.look().clip.box) o.within = LpsBox{box->first, box->second};
    auto plan = std::make_shared<core::GrownPlan>();
    const core::Scene* scene = &w.scene();
    const iso::Volume* volume = &w.scene().volume();
    context_.jobs.run(
        QString("Growing a region from %1 (values %2 to %3%4)")
            .arg(point_text(seed), number(o.lo, 1), number(o.hi, 1), o.within ? ", within the crop box" : ""),
        false, [scene, seed, o, plan](const ProgressFn& p) { *plan = core::plan_grown(*scene, seed, o, p); },
        [this, scene, volume, plan](std::exception_ptr e) {
            core::Workspace& w = context_.workspace;
            ++grown_;
            if (e) {
                context_.error("Grow failed", "Cannot grow a region from that point", e);
                return;
            }
            // Another volume meanwhile: the region is of what was.
            if (scene != &w.scene() || !w.scene().has_volume() || &w.scene().volume() != volume) return;
            const core::SurfaceInfo info = core::grown_info(w.scene(), plan->grown);
            core::SurfaceId id = 0;
            context_.edit("Grow " + QString::fromStdString(info.name), core::Parts(core::Part::Surfaces),
                          [&] { id = w.add_mesh(std::move(plan->mesh), info); });
            if (id == 0) return;
            GrownRegion& r = plan->grown.region;
            QString where;
            if (r.reached_box) where += ", stopped at the crop box";
            if (r.reached_border) where += ", reached the volume's edge";
            context_.status(QString::fromStdString(info.name) + ": " +
                            with_uncertainty(r.volume_ml, r.partial_volume_ml, 3, "mL") +
                            QString(" (%1 voxels)").arg(r.voxels) + where + " (Edit > Undo takes it back)");
            grown_regions_.insert_or_assign(id, std::make_pair(w.scene().shared_mesh(id), std::move(r)));
            update_table();
        });
}

// The rows: the workspace's parts (isolated components, parts cut by a box
// or the scissors, grown regions: made here or by a session), each measured
// once per mesh off the GUI thread; a grown region as it was grown by its
// voxels (its region grown again when it came from a session).
void StructureTools::update_table() {
    const core::Scene& scene = context_.workspace.scene();
    std::vector<core::SurfaceId> ids, unmeasured;
    const auto whole_region = [&](core::SurfaceId id) {
        const auto& info = scene.info(id);
        return info.grown && !keeps_a_part(info.post);
    };
    const auto grown = [&](core::SurfaceId id) -> const GrownRegion* {
        const auto it = grown_regions_.find(id);
        return whole_region(id) && it != grown_regions_.end() && it->second.first == scene.shared_mesh(id)
                   ? &it->second.second
                   : nullptr;
    };
    for (const auto id : scene.surfaces()) {
        if (!core::is_part(scene.info(id))) continue;
        ids.push_back(id);
        const auto it = measured_.find(id);
        if (it == measured_.end() || it->second.mesh != scene.shared_mesh(id) || (whole_region(id) && !grown(id)))
            unmeasured.push_back(id);
    }
    const QSignalBlocker filling(table_); // rows made are no edits
    table_->setRowCount(0);
    struct Refit {
        ColumnFit* f;
        ~Refit() { f->refit(); }
    } refit{fit_};
    for (const auto id : ids)
        if (const auto it = measured_.find(id); it != measured_.end() && it->second.mesh == scene.shared_mesh(id)) {
            core::SurfaceMeasurement m = it->second.m;
            m.name = scene.info(id).name;
            m.surface = id;
            add_row(table_, scene.info(id), m, it->second.shape, grown(id));
        }
    if (unmeasured.empty() || measuring_ || context_.busy()) return;
    measuring_ = true;
    auto out = std::make_shared<std::vector<Measured>>();
    struct Job {
        std::shared_ptr<const Mesh> mesh;
        std::optional<GrownFrom> regrow; // a whole grown region not measured by its voxels yet
    };
    std::vector<Job> jobs;
    for (const auto id : unmeasured)
        jobs.push_back({scene.shared_mesh(id), whole_region(id) && !grown(id) ? scene.info(id).grown : std::nullopt});
    const core::Scene* s = &scene;
    context_.jobs.run(
        "Measuring the structures", false,
        [s, unmeasured, out, jobs](const ProgressFn&) {
            const auto measured = core::measure_surfaces(*s, unmeasured);
            for (std::size_t i = 0; i < measured.size(); ++i) {
                Measured m{jobs[i].mesh, measured[i], measure_shape(*jobs[i].mesh, measured[i].measures.closed), {}};
                if (const auto& g = jobs[i].regrow) {
                    m.region = grow_region(s->volume(), g->seed, g->options);
                    m.region->mask = iso::Volume{}; // the count is what is kept, not the voxels
                }
                out->push_back(std::move(m));
            }
        },
        [this, s, out, unmeasured](std::exception_ptr e) {
            measuring_ = false;
            if (e || s != &context_.workspace.scene()) return;
            for (std::size_t i = 0; i < out->size(); ++i) {
                Measured& m = (*out)[i];
                if (m.region)
                    grown_regions_.insert_or_assign(unmeasured[i], std::make_pair(m.mesh, std::move(*m.region)));
                m.region.reset();
                measured_[unmeasured[i]] = std::move(m);
            }
            update_table();
        });
}

} // namespace iso::gui
