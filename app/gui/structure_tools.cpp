#include "app/gui/structure_tools.hpp"

#include <cmath>
#include <memory>

#include <QAction>
#include <QActionGroup>
#include <QHeaderView>
#include <QStatusBar>
#include <QTableWidget>
#include <QTimer>
#include <QToolBar>

#include "app/gui/main_window.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/surfaces_panel.hpp"
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
        item->setFlags(Qt::ItemIsSelectable | Qt::ItemIsEnabled);
        t->setItem(row, col, item);
    };
    cell(StructureTools::Name, QString::fromStdString(m.name));
    cell(StructureTools::Area, with_uncertainty(s.area_mm2, s.area_uncertainty_mm2, 1, QString::fromUtf8("mm\u00b2")));
    if (s.volume_kind == VolumeKind::Undefined)
        cell(StructureTools::Volume, "undefined (inconsistent orientation)");
    else
        cell(StructureTools::Volume,
             with_uncertainty(s.volume_ml, s.volume_uncertainty_ml, 3, "mL",
                              s.volume_kind == VolumeKind::LowerBound ? QString::fromUtf8("\u2265 ") : QString()));
    cell(StructureTools::Closed, s.closed ? "closed" : "open");
    cell(StructureTools::Bounds, point_text(s.bounds_min) + QString::fromUtf8(" \u2013 ") + point_text(s.bounds_max));
}

} // namespace

StructureTools::StructureTools(MainWindow& window) : QObject(&window), window_(window) {
    QToolBar* bar = window.addToolBar("Structures");
    bar->setObjectName("structure_toolbar");
    isolate_ = bar->addAction("Isolate");
    isolate_->setObjectName("isolate_tool");
    isolate_->setToolTip("Click a surface in the 3D view: the connected piece under the cursor becomes a surface of "
                         "its own, measured in the Measurements panel");
    distance_ = bar->addAction("Distance");
    distance_->setObjectName("distance_tool");
    distance_->setToolTip("Click two surfaces (or two pieces of one) in the 3D view: their shortest distance, drawn "
                          "as a ruler between the closest points");
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
    table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
    table_->verticalHeader()->hide();
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
}

void StructureTools::set_tool(Tool t) {
    tool_ = t;
    first_.reset();
    const QSignalBlocker b1(isolate_), b2(distance_);
    isolate_->setChecked(t == Tool::Isolate);
    distance_->setChecked(t == Tool::Distance);
    // One tool at a time across the window: a structure tool turns the Measure tools off.
    if (t != Tool::None && window_.measure_tools()) window_.measure_tools()->set_tool(MeasureTools::Tool::None);
    if (t == Tool::Isolate) window_.statusBar()->showMessage("Isolate: click a surface in the 3D view");
    if (t == Tool::Distance) window_.statusBar()->showMessage("Distance: click the first surface in the 3D view");
}

bool StructureTools::viewer_click(Viewer& v, QPointF pixel) {
    if (tool_ == Tool::None) return false;
    core::PickResult r;
    try {
        r = v.pick_at(pixel);
    } catch (const std::exception& e) {
        window_.statusBar()->showMessage(QString("Pick failed: ") + e.what());
        return true;
    }
    if (!r.visible) {
        window_.statusBar()->showMessage("No surface there: click a surface");
        return true;
    }
    const core::PickLayer& l = r.layers[*r.visible];
    if (tool_ == Tool::Isolate) {
        window_.surfaces_panel()->isolate(l.surface, l.lps);
        return true;
    }
    if (!first_) {
        first_ = First{l.surface, l.lps};
        window_.statusBar()->showMessage(QString::fromStdString("Distance from " + l.name) +
                                         ": click the second surface");
        return true;
    }
    const First a = *first_;
    first_.reset();
    measure_distance(a.surface, a.at, l.surface, l.lps);
    return true;
}

void StructureTools::measure_distance(std::uint32_t a, const glm::dvec3& at_a, std::uint32_t b,
                                      const glm::dvec3& at_b) {
    auto gap = std::make_shared<core::SurfaceGap>();
    const core::Scene* scene = &window_.scene();
    // The components under the two clicks (of one surface or two).
    window_.surfaces_panel()->run_job(
        "Measuring the shortest distance",
        [scene, gap, a, b, at_a, at_b](const ProgressFn&) { *gap = core::surface_gap(*scene, a, b, at_a, at_b); },
        [this, gap, scene](std::exception_ptr e) {
            if (e || scene != &window_.scene()) {
                if (e) window_.statusBar()->showMessage("The distance could not be measured");
                return;
            }
            MarkupsState after = window_.markups_state();
            after.markups.push_back(core::gap_markup(*gap));
            after.sources.emplace_back();
            window_.edit_markups("Add distance", std::move(after));
            ++distances_;
            window_.statusBar()->showMessage(QString::fromStdString(gap->name_a + " to " + gap->name_b) + ": " +
                                             number(gap->distance.pair.distance_mm, 3) + " mm" +
                                             (gap->distance.touching ? " (they touch or cross)" : ""));
        });
}

void StructureTools::add_component(const core::IsolatedComponent& c) { add_row(table_, c.measured); }

void StructureTools::reset() {
    set_tool(Tool::None);
    table_->setRowCount(0);
    // A session's isolated components: measured again, off the GUI thread.
    std::vector<core::SurfaceId> ids;
    for (const auto id : window_.scene().surfaces())
        if (window_.scene().info(id).post.keep_at) ids.push_back(id);
    if (ids.empty()) return;
    // After the job that made the scene has finished (one job at a time).
    QTimer::singleShot(0, this, [this, ids] { measure_again(ids); });
}

void StructureTools::measure_again(const std::vector<std::uint32_t>& ids) {
    if (window_.busy()) return;
    auto measured = std::make_shared<std::vector<core::SurfaceMeasurement>>();
    const core::Scene* scene = &window_.scene();
    window_.surfaces_panel()->run_job(
        "Measuring the isolated structures",
        [scene, ids, measured](const ProgressFn&) { *measured = core::measure_surfaces(*scene, ids); },
        [this, scene, measured](std::exception_ptr e) {
            if (e || scene != &window_.scene()) return;
            for (const auto& m : *measured) add_row(table_, m);
        });
}

} // namespace iso::gui
