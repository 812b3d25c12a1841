#include "app/gui/measurements_panel.hpp"

#include <QApplication>
#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QHeaderView>
#include <QMainWindow>
#include <QMessageBox>
#include <QStatusBar>
#include <QTableWidget>
#include <QTimer>
#include <QToolButton>
#include <QPushButton>
#include <QShortcut>

#include <algorithm>
#include <cstdint>

#include "app/gui/app_context.hpp"
#include "app/gui/column_fit.hpp"
#include "app/gui/files.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/measure_tools.hpp"
#include "io/error.hpp"
#include "io/markups.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/surface/closest.hpp"

namespace iso::gui {

namespace {

// A point within this of a surface lies on it (a pick's point is on it up to rounding).
constexpr double kOnSurfaceMm = 0.5;

// The name of the surface a point lies on (within kOnSurfaceMm), "off
// surface", or "-" without a visible surface.
QString surface_text_of(const std::vector<core::SurfaceTree>& trees, const glm::dvec3& p) {
    try {
        const core::SurfacePoint s = core::surface_at(trees, p);
        for (const auto& t : trees)
            if (t.id == s.surface && s.distance_mm <= kOnSurfaceMm) return QString::fromStdString(t.name);
        return "off surface";
    } catch (const Error&) {
        return "-"; // no visible surface
    }
}

// "passes through iso 1150 at 22.3 mm, ..." for a ruler from a to b; empty when it passes through nothing.
QString crossings_text_of(const std::vector<core::SurfaceTree>& trees, const glm::dvec3& a, const glm::dvec3& b) {
    QStringList parts;
    try {
        for (const core::LineCrossing& c : core::solid_crossings(trees, a, b))
            parts << QString("%1 at %2 mm").arg(QString::fromStdString(c.name)).arg(c.along_mm, 0, 'f', 1);
    } catch (const Error&) {
        // Not finite points (a damaged file): nothing to say about them.
    }
    return parts.isEmpty() ? QString() : "passes through " + parts.join(", ");
}

QString kind_text(MarkupType t) {
    switch (t) {
    case MarkupType::Fiducial: return "Point list";
    case MarkupType::Line: return "Line";
    case MarkupType::Angle: return "Angle";
    case MarkupType::Curve: return "Curve";
    case MarkupType::ClosedCurve: return "Closed curve";
    }
    return {};
}

// Lines and angles: computed from the points (io/markups.hpp, the values the
// writer stores and Slicer shows). Others: their points, and a curve's length
// as the file stored it (isoscope does not rebuild Slicer's spline).
QString value_text(const Markup& m) {
    if (const auto meas = computed_measurement(m)) {
        if (!meas->value) return "-";
        return m.type == MarkupType::Line ? QString("%1 mm").arg(*meas->value, 0, 'f', 2)
                                          : QString("%1%2").arg(*meas->value, 0, 'f', 2).arg(QChar(0x00B0));
    }
    for (const auto& s : m.measurements)
        if (s.name == "length" && s.value)
            return QString("%1 %2 (stored)").arg(*s.value, 0, 'f', 2).arg(QString::fromStdString(s.units));
    if (m.type == MarkupType::Fiducial)
        return QString("%1 point%2").arg(m.points.size()).arg(m.points.size() == 1 ? "" : "s");
    return QString("%1 point(s)").arg(m.points.size());
}

} // namespace

MeasurementsPanel::MeasurementsPanel(AppContext& context)
    : QDockWidget("Measurements", &context.window), context_(context) {
    setObjectName("measurements");
    table_ = new QTableWidget(0, 6, this);
    table_->setObjectName("measurements_table");
    table_->setHorizontalHeaderLabels({"Name", "Kind", "Value", "On surface", "Notes", ""});
    table_->verticalHeader()->setVisible(false);
    auto* header = table_->horizontalHeader();
    for (int c : {Name, Kind, Value, Surface, Notes, Delete})
        header->setSectionResizeMode(c, QHeaderView::ResizeToContents);
    // Within the dock's width: the widest columns give way, elided (whole in the tooltips).
    fit_ = new ColumnFit(table_);
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
    table_->setSelectionMode(QAbstractItemView::SingleSelection);
    table_->setEditTriggers(QAbstractItemView::DoubleClicked | QAbstractItemView::EditKeyPressed |
                            QAbstractItemView::AnyKeyPressed);
    connect(table_, &QTableWidget::itemChanged, this, [this](QTableWidgetItem* item) {
        if (filling_ || item->column() != Name) return;
        rename(item->row(), item->text());
    });
    connect(table_, &QTableWidget::itemSelectionChanged, this, [this] { selection_changed(); });
    // Delete (or Backspace) on a row deletes it, as its button does; not while a name is being edited.
    for (const auto key : {Qt::Key_Delete, Qt::Key_Backspace}) {
        auto* del = new QShortcut(QKeySequence(key), table_, nullptr, nullptr, Qt::WidgetShortcut);
        connect(del, &QShortcut::activated, this, [this] {
            const auto rows = table_->selectionModel()->selectedRows();
            if (!rows.isEmpty()) remove(rows.front().row());
        });
    }
    refresh_timer_ = new QTimer(this);
    refresh_timer_->setSingleShot(true);
    refresh_timer_->setInterval(300);
    connect(refresh_timer_, &QTimer::timeout, this, [this] {
        // A name being typed (its editor has the focus): later.
        const QWidget* focus = QApplication::focusWidget();
        if (focus && focus != table_ && table_->isAncestorOf(focus))
            refresh_timer_->start();
        else
            refresh();
    });
    setWidget(table_);
    // The table follows the markups and the selection; what the points lie
    // on follows the surfaces, once they rest.
    observer_ = context_.workspace.observe([this](core::Parts p) {
        if (p & (core::Part::Data | core::Part::Markups)) {
            refresh();
        } else {
            if (core::has(p, core::Part::Selection)) show_selection();
            if (core::has(p, core::Part::Surfaces)) refresh_soon();
        }
    });
    refresh();
}

MeasurementsPanel::~MeasurementsPanel() { context_.workspace.unobserve(observer_); }

void MeasurementsPanel::add_row(const Row& r, const std::array<QString, 5>& text, const QString& tooltip) {
    const int row = table_->rowCount();
    table_->insertRow(row);
    rows_.push_back(r);
    for (int col = Name; col <= Notes; ++col) {
        auto* item = new QTableWidgetItem(text[std::size_t(col)]);
        if (col != Name) item->setFlags(item->flags() & ~Qt::ItemIsEditable);
        item->setToolTip(col == Name ? "Double-click to rename"
                         : col == Notes
                             ? (tooltip.isEmpty() ? text[std::size_t(col)] : text[std::size_t(col)] + "\n" + tooltip)
                             : tooltip);
        table_->setItem(row, col, item);
    }
    auto* del = new QToolButton(table_);
    del->setObjectName("delete");
    del->setText(QString(QChar(0x2715)));
    del->setToolTip(r.point < 0 ? "Delete this measurement" : "Delete this point");
    del->setAutoRaise(true);
    // Queued: the button goes with the table's rebuild.
    connect(del, &QToolButton::clicked, this,
            [this, row] { QTimer::singleShot(0, this, [this, row] { remove(row); }); });
    table_->setCellWidget(row, Delete, del);
}

void MeasurementsPanel::add_markup_rows(std::size_t index, const Markup& m) {
    const bool has_volume = context_.workspace.scene().has_volume();
    QStringList on;
    for (const auto& p : m.points)
        if (p.status == PositionStatus::Defined) on << surface_text(p.position);
    const bool list = m.type == MarkupType::Fiducial;
    add_row({index, -1},
            {QString::fromStdString(m.name), kind_text(m.type), value_text(m), list ? QString() : on.join(" / "),
             crossings_text(m)},
            list ? QString() : "The surface each point lies on (within 0.5 mm), in the order of the points");
    if (!list) return;
    // A point list's points: label, the volume's value, surface, position.
    for (std::size_t k = 0; k < m.points.size(); ++k) {
        const MarkupControlPoint& p = m.points[k];
        if (p.status != PositionStatus::Defined) {
            add_row({index, int(k)}, {QString::fromStdString(p.label), "Point", "-", "-", "no position"}, {});
            continue;
        }
        QString value = "-";
        if (has_volume) {
            const auto v = core::value_at(context_.workspace.scene(), p.position);
            value =
                v ? QString::fromStdString(core::value_readout(v->value, core::value_unit(context_.workspace.scene())))
                  : QString("outside the volume");
        }
        add_row({index, int(k)},
                {QString::fromStdString(p.label), "Point", value, surface_text(p.position), lps_text(p.position)}, {});
    }
}

void MeasurementsPanel::refresh() {
    if (renaming_) return; // the table shows the new name already
    refresh_timer_->stop();
    filling_ = true;
    check_cache();
    const auto& markups = context_.workspace.markups();
    table_->setRowCount(0);
    rows_.clear();
    for (std::size_t i = 0; i < markups.size(); ++i) add_markup_rows(i, markups[i]);
    fit_->refit();
    filling_ = false;
    show_selection();
}

void MeasurementsPanel::refresh_soon() {
    if (!context_.workspace.markups().empty()) refresh_timer_->start();
}

int MeasurementsPanel::row_of(std::size_t markup, int point) const {
    for (std::size_t r = 0; r < rows_.size(); ++r)
        if (rows_[r].markup == markup && rows_[r].point == point) return int(r);
    return -1;
}

void MeasurementsPanel::show_selection() {
    const auto sel = context_.workspace.selected();
    const int row = sel ? row_of(*sel) : -1;
    // Already on a row of that markup (a point list's point): stays.
    const auto current = table_->selectionModel()->selectedRows();
    if (row >= 0 && !current.isEmpty() && std::size_t(current.front().row()) < rows_.size() &&
        rows_[std::size_t(current.front().row())].markup == *sel)
        return;
    const bool was = filling_;
    filling_ = true; // not a user's selection
    if (row < 0)
        table_->clearSelection();
    else
        table_->selectRow(row);
    filling_ = was;
}

void MeasurementsPanel::selection_changed() {
    if (filling_) return;
    const auto selected = table_->selectionModel()->selectedRows();
    core::Workspace& w = context_.workspace;
    if (selected.isEmpty() || std::size_t(selected.front().row()) >= rows_.size()) {
        w.select(std::nullopt);
        return;
    }
    // The markup selected (highlighted in the views); the slice views go to
    // its first point, or to the point list's point of the row. The 3D
    // view's camera stays (a selection is no change of the figure).
    const Row r = rows_[std::size_t(selected.front().row())];
    w.select(r.markup);
    const Markup& m = w.markups()[r.markup];
    const auto first = std::find_if(m.points.begin(), m.points.end(),
                                    [](const MarkupControlPoint& p) { return p.status == PositionStatus::Defined; });
    const MarkupControlPoint* p = r.point >= 0              ? &m.points[std::size_t(r.point)]
                                  : first != m.points.end() ? &*first
                                                            : nullptr;
    if (p && p->status == PositionStatus::Defined) w.set_crosshair(p->position);
}

void MeasurementsPanel::rename(int row, const QString& name) {
    if (row < 0 || std::size_t(row) >= rows_.size()) return;
    const Row r = rows_[std::size_t(row)];
    MarkupsState s = context_.workspace.markups_state();
    if (r.markup >= s.markups.size()) return;
    Markup& m = s.markups[r.markup];
    QString old;
    if (r.point < 0) {
        old = QString::fromStdString(m.name);
        m.name = name.toStdString();
    } else {
        auto& p = m.points[std::size_t(r.point)];
        old = QString::fromStdString(p.label);
        p.label = name.toStdString();
    }
    if (old == name) return;
    renaming_ = true;
    context_.edit("Rename " + (old.isEmpty() ? QString("measurement") : old), core::Parts(core::Part::Markups),
                  [&] { context_.workspace.set_markups(std::move(s)); });
    renaming_ = false;
}

void MeasurementsPanel::remove(int row) {
    if (row < 0 || std::size_t(row) >= rows_.size()) return;
    const Row r = rows_[std::size_t(row)];
    MarkupsState s = context_.workspace.markups_state();
    if (r.markup >= s.markups.size()) return;
    QString name;
    if (r.point < 0) {
        name = QString::fromStdString(s.markups[r.markup].name);
        s.markups.erase(s.markups.begin() + std::ptrdiff_t(r.markup));
        s.sources.erase(s.sources.begin() + std::ptrdiff_t(r.markup));
    } else {
        auto& pts = s.markups[r.markup].points;
        name = QString::fromStdString(pts[std::size_t(r.point)].label);
        pts.erase(pts.begin() + r.point);
    }
    if (name.isEmpty()) name = r.point < 0 ? QString("the measurement") : QString("the point");
    context_.edit("Delete " + name, core::Parts(core::Part::Markups),
                  [&] { context_.workspace.set_markups(std::move(s)); });
    context_.status("Deleted " + name + " (Edit > Undo brings it back)");
}

// ---- where the points lie ------------------------------------------------------------

void MeasurementsPanel::check_cache() {
    // The answers hold while the surfaces do: which, their meshes, visibility and opacity.
    std::string key;
    const core::Scene& scene = context_.workspace.scene();
    for (const auto id : scene.surfaces()) {
        const auto& info = scene.info(id);
        const auto& mesh = scene.mesh(id);
        key += std::to_string(id) + info.name + (info.visible ? "v" : "h") + (info.pickable ? "p" : "n") +
               std::to_string(info.opacity) + "/" + std::to_string(mesh.triangles.size()) + "@" +
               std::to_string(reinterpret_cast<std::uintptr_t>(mesh.triangles.data())) + ";";
    }
    if (key == cache_key_) return;
    cache_key_ = key;
    surface_waiting_.clear();
    crossings_waiting_.clear();
    surface_cache_.clear();
    crossings_cache_.clear();
}

struct MeasurementsPanel::Trees {
    std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::shared_ptr<TriangleBvh>>> by_mesh;
};

bool MeasurementsPanel::answers_later() const {
    const core::Scene& scene = context_.workspace.scene();
    std::size_t triangles = 0;
    for (const auto id : scene.surfaces())
        if (scene.info(id).visible) triangles += scene.mesh(id).triangles.size();
    return triangles > kInlineTriangles;
}

// The waiting points and lines, answered on a worker from the surfaces as
// they are now (their meshes are shared and never change in place); the
// answers are kept if the surfaces are still those when they arrive.
void MeasurementsPanel::look_up_later() {
    if (looking_up_ || (surface_waiting_.empty() && crossings_waiting_.empty())) return;
    looking_up_ = true;
    const core::Scene& scene = context_.workspace.scene();
    struct Surface {
        core::SurfaceId id;
        std::string name;
        std::shared_ptr<const Mesh> mesh;
        double opacity;
        bool pickable;
    };
    std::vector<Surface> surfaces;
    for (const auto id : scene.surfaces()) {
        const auto& info = scene.info(id);
        if (info.visible && !scene.mesh(id).empty())
            surfaces.push_back({id, info.name, scene.shared_mesh(id), double(info.opacity), info.pickable});
    }
    if (!trees_) trees_ = std::make_shared<Trees>();
    auto points = std::make_shared<std::vector<std::pair<std::array<double, 3>, QString>>>();
    auto lines = std::make_shared<std::vector<std::pair<std::array<double, 6>, QString>>>();
    for (const auto& k : surface_waiting_) points->push_back({k, {}});
    for (const auto& k : crossings_waiting_) lines->push_back({k, {}});
    const std::string key = cache_key_;
    context_.jobs.run(
        "Finding the surfaces the measurements lie on",
        [trees = trees_, surfaces, points, lines](const ProgressFn&) {
            std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::shared_ptr<TriangleBvh>>> kept;
            std::vector<core::SurfaceTree> list;
            for (const Surface& s : surfaces) {
                auto it = trees->by_mesh.find(s.mesh.get());
                auto tree = it != trees->by_mesh.end() ? it->second.second : std::make_shared<TriangleBvh>(*s.mesh);
                kept[s.mesh.get()] = {s.mesh, tree};
                list.push_back({s.id, s.name, tree.get(), s.opacity, s.pickable});
            }
            trees->by_mesh = std::move(kept); // the trees of meshes gone go
            for (auto& [k, text] : *points) text = surface_text_of(list, {k[0], k[1], k[2]});
            for (auto& [k, text] : *lines) text = crossings_text_of(list, {k[0], k[1], k[2]}, {k[3], k[4], k[5]});
        },
        [this, key, points, lines](std::exception_ptr) {
            looking_up_ = false;
            check_cache();
            if (key == cache_key_) {
                for (const auto& [k, text] : *points) {
                    surface_cache_[k] = text;
                    surface_waiting_.erase(k);
                }
                for (const auto& [k, text] : *lines) {
                    crossings_cache_[k] = text;
                    crossings_waiting_.erase(k);
                }
            }
            refresh_soon();
        },
        Jobs::Options{false, true});
}

QString MeasurementsPanel::surface_text(const glm::dvec3& p) {
    const std::array<double, 3> key{p.x, p.y, p.z};
    if (const auto it = surface_cache_.find(key); it != surface_cache_.end()) return it->second;
    // While a point is dragged, only the points already known (each query builds a search tree).
    if (context_.editing_markup()) return "...";
    if (answers_later()) {
        surface_waiting_.insert(key);
        QTimer::singleShot(0, this, [this] { look_up_later(); });
        return "...";
    }
    std::vector<std::unique_ptr<TriangleBvh>> keep;
    return surface_cache_[key] = surface_text_of(core::surface_trees(context_.workspace.scene(), keep), p);
}

QString MeasurementsPanel::crossings_text(const Markup& m) {
    if (m.type != MarkupType::Line || m.points.size() != 2 || m.points[0].status != PositionStatus::Defined ||
        m.points[1].status != PositionStatus::Defined)
        return {};
    const glm::dvec3 a = m.points[0].position, b = m.points[1].position;
    const std::array<double, 6> key{a.x, a.y, a.z, b.x, b.y, b.z};
    if (const auto it = crossings_cache_.find(key); it != crossings_cache_.end()) return it->second;
    if (context_.editing_markup()) return "...";
    if (answers_later()) {
        crossings_waiting_.insert(key);
        QTimer::singleShot(0, this, [this] { look_up_later(); });
        return "...";
    }
    std::vector<std::unique_ptr<TriangleBvh>> keep;
    return crossings_cache_[key] = crossings_text_of(core::surface_trees(context_.workspace.scene(), keep), a, b);
}

bool MeasurementsPanel::save(const QString& path) {
    const QString what = "Cannot save markups to " + path;
    if (context_.workspace.markups().empty()) {
        context_.error("Markups", what, "there are no measurements to save");
        return false;
    }
    try {
        MarkupsFile f;
        f.markups = context_.workspace.markups();
        save_markups(f, path.toStdString());
    } catch (const std::exception& e) {
        context_.error("Markups", what, QString::fromStdString(e.what()));
        return false;
    }
    // The file holds them now: loading it again asks whether to replace them.
    MarkupsState s = context_.workspace.markups_state();
    const QString file = QFileInfo(path).canonicalFilePath();
    for (auto& from : s.sources)
        if (std::find(from.begin(), from.end(), file.toStdString()) == from.end()) from.push_back(file.toStdString());
    context_.workspace.set_markups(std::move(s));
    context_.status(QString("Saved %1 measurement(s) to %2").arg(context_.workspace.markups().size()).arg(path));
    return true;
}

bool MeasurementsPanel::load(const QString& path) {
    MarkupsFile f;
    try {
        f = load_markups(path.toStdString());
    } catch (const std::exception& e) {
        context_.error("Markups", "Cannot load markups from " + path, QString::fromStdString(e.what()));
        return false;
    }
    // Slicer does not write names: it names a node after its file.
    QString stem = QFileInfo(path).fileName();
    for (const char* suffix : {".mrk.json", ".json"})
        if (stem.endsWith(suffix, Qt::CaseInsensitive)) {
            stem.chop(int(std::string_view(suffix).size()));
            break;
        }
    int unnamed = 0;
    for (auto& m : f.markups)
        if (m.name.empty()) m.name = (unnamed++ ? QString("%1 %2").arg(stem).arg(unnamed) : stem).toStdString();
    // By the file's canonical path (the same file however it is named), not
    // by comparing names and points: a markup moved or renamed since still
    // came from the file, and two files may hold equal markups.
    const QString file = QFileInfo(path).canonicalFilePath();
    const auto& sources = context_.workspace.markups_state().sources;
    const auto from_file = std::count_if(sources.begin(), sources.end(), [&](const std::vector<std::string>& s) {
        return std::find(s.begin(), s.end(), file.toStdString()) != s.end();
    });
    if (from_file == 0) {
        add_loaded(f, path, LoadMode::Add);
        return true;
    }
    auto* box = new QMessageBox(
        QMessageBox::Question, "Load markups",
        QString("%1 measurement(s) came from %2 (loaded from it or saved to it).\n\nReplace: they give way to the "
                "%3 the file holds now.\nAdd: the file's %3 are added, and they stay.")
            .arg(from_file)
            .arg(QFileInfo(path).fileName())
            .arg(f.markups.size()),
        QMessageBox::NoButton, &context_.window);
    box->setObjectName("reload");
    auto* replace = box->addButton("Replace", QMessageBox::AcceptRole);
    replace->setObjectName("replace");
    auto* add = box->addButton("Add", QMessageBox::YesRole);
    add->setObjectName("add");
    box->addButton(QMessageBox::Cancel)->setObjectName("cancel");
    box->setDefaultButton(replace);
    box->setAttribute(Qt::WA_DeleteOnClose);
    connect(box, &QMessageBox::buttonClicked, this, [this, f, path, replace, add](QAbstractButton* b) {
        if (b == replace)
            add_loaded(f, path, LoadMode::Replace);
        else if (b == add)
            add_loaded(f, path, LoadMode::Add);
        else
            context_.status("Loading " + path + ": cancelled");
    });
    box->open(); // window-modal, not exec(): the event loop (and tests) go on
    return true;
}

void MeasurementsPanel::add_loaded(const MarkupsFile& f, const QString& path, LoadMode mode) {
    const QString file = QFileInfo(path).canonicalFilePath();
    const MarkupsState& now = context_.workspace.markups_state();
    MarkupsState s;
    std::optional<std::size_t> at; // Replace: where the first of the file's markups was
    for (std::size_t i = 0; i < now.markups.size(); ++i) {
        if (mode == LoadMode::Replace &&
            std::find(now.sources[i].begin(), now.sources[i].end(), file.toStdString()) != now.sources[i].end()) {
            if (!at) at = s.markups.size();
            continue;
        }
        s.markups.push_back(now.markups[i]);
        s.sources.push_back(now.sources[i]);
    }
    const std::size_t dropped = now.markups.size() - s.markups.size();
    const std::size_t pos = at.value_or(s.markups.size());
    s.markups.insert(s.markups.begin() + std::ptrdiff_t(pos), f.markups.begin(), f.markups.end());
    s.sources.insert(s.sources.begin() + std::ptrdiff_t(pos), f.markups.size(),
                     std::vector<std::string>{file.toStdString()});
    const QString name = QFileInfo(path).fileName();
    context_.edit((mode == LoadMode::Replace ? "Replace markups from " : "Load markups from ") + name,
                  core::Parts(core::Part::Markups), [&] { context_.workspace.set_markups(std::move(s)); });
    QString msg =
        mode == LoadMode::Replace
            ? QString("Replaced %1 measurement(s) with the %2 of %3").arg(dropped).arg(f.markups.size()).arg(path)
            : QString("Loaded %1 measurement(s) from %2").arg(f.markups.size()).arg(path);
    for (const auto& w : f.warnings) msg += "; " + QString::fromStdString(w);
    context_.status(msg);
}

void MeasurementsPanel::save_dialog() {
    const QString start = QDir(Files::start_folder("markups")).filePath("measurements.mrk.json");
    QString f = QFileDialog::getSaveFileName(&context_.window, "Save markups", start, "3D Slicer markups (*.mrk.json)");
    if (f.isEmpty()) return;
    if (!f.endsWith(".json", Qt::CaseInsensitive)) f += ".mrk.json";
    if (save(f)) Files::remember_folder("markups", f);
}

void MeasurementsPanel::load_dialog() {
    const QString f = QFileDialog::getOpenFileName(&context_.window, "Load markups", Files::start_folder("markups"),
                                                   "3D Slicer markups (*.mrk.json *.json);;All files (*)");
    if (!f.isEmpty()) load(f);
}

} // namespace iso::gui
