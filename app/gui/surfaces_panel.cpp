// The Surfaces panel (surfaces_panel.hpp): its rows, one named step per line of a row, the
// background re-extractions behind them, and the rows following the workspace.
#include "app/gui/surfaces_panel.hpp"

#include <QCheckBox>
#include <QColorDialog>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFrame>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QScrollArea>
#include <QSignalBlocker>
#include <QSpinBox>
#include <QStandardItemModel>
#include <QSlider>
#include <QThread>
#include <QVBoxLayout>

#include <atomic>
#include <stdexcept>
#include <cmath>

#include "app/gui/app_context.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/slice_view.hpp"
#include "io/error.hpp"
#include "renderer/core/presets.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

namespace {

// " HU" after the numbers of a volume in Hounsfield units (core::value_unit), else nothing.
QString unit_suffix(const core::Scene* scene) {
    const std::string_view unit = scene ? core::value_unit(*scene) : std::string_view{};
    return unit.empty() ? QString() : " " + QString::fromUtf8(unit.data(), qsizetype(unit.size()));
}

} // namespace

// One re-extraction on its own thread.
struct SurfacesPanel::Worker {
    QThread* thread = nullptr;
    double iso = 0;
    PostProcessOptions post;
    unsigned generation = 0;
    int drag = 0;          // the slider drag it was asked in (0: none): its edit merges with the drag's others
    const char* what = ""; // "Change iso value of"
    std::atomic<bool> cancel{false};
    core::PreparedMesh mesh; // with its bounds and outline index, worked out here too
    std::exception_ptr error;
};

struct SurfacesPanel::Row {
    std::uint32_t id = 0;
    QFrame* widget = nullptr;
    QSlider* slider = nullptr;
    QDoubleSpinBox* value = nullptr;
    QDoubleSpinBox* smooth = nullptr;
    QCheckBox* largest = nullptr;
    QLabel* busy = nullptr;
    // The slider maps [lo, lo + steps * step] to 0..steps (the last step ends at hi).
    double lo = 0, hi = 0, step = 1;
    int steps = 0;
    bool syncing = false;
    // What the user asked for last, and the re-extraction under way (null: none).
    double wanted = 0;
    PostProcessOptions wanted_post;
    int wanted_drag = 0;
    const char* what = "Change iso value of";
    std::shared_ptr<Worker> worker;
    // The mesh's value and post-processing the row last showed: a change of
    // them from elsewhere (an undo) replaces the row's request.
    double shown_value = 0;
    PostProcessOptions shown_post;
    int decimals = 3; // the iso box's at least: 0 for integer voxels
    // Shows `v` in the iso box with as many decimals as it needs (up to
    // three): a surface at 300.5 on integer voxels reads 300.5, not 301,
    // and leaving the box does not extract it again at the rounded value.
    void show_value(double v) {
        int d = decimals;
        while (d < 3 && std::abs(v * std::pow(10.0, d) - std::round(v * std::pow(10.0, d))) > 1e-6) ++d;
        value->setDecimals(d);
        value->setValue(v);
    }
    int to_slider(double v) const { return int(std::clamp(std::lround((v - lo) / step), 0L, long(steps))); }
    double from_slider(int s) const { return std::min(hi, lo + double(s) * step); }
};

SurfacesPanel::SurfacesPanel(AppContext& context, QWidget* parent) : QWidget(parent), context_(context) {
    auto* col = new QVBoxLayout(this);
    preset_ = new QComboBox(this);
    preset_->setObjectName("iso_preset");
    preset_->setToolTip("Iso value presets (skin, bone, ... for CT in HU); choosing one fills in the iso value");
    col->addWidget(preset_);
    auto* add_row = new QHBoxLayout;
    add_row->addWidget(new QLabel("Iso value"));
    iso_ = new QDoubleSpinBox(this);
    iso_->setObjectName("add_iso_value");
    iso_->setToolTip("The value the new surface passes through (within the volume's values)");
    iso_->setRange(-1e6, 1e6);
    iso_->setDecimals(1);
    add_row->addWidget(iso_, 1);
    auto* add = new QPushButton("Add surface", this);
    add->setObjectName("add_surface");
    add->setToolTip("Extract the isosurface at this value in the background and show it");
    add_row->addWidget(add);
    col->addLayout(add_row);
    auto* options = new QHBoxLayout;
    options->addWidget(new QLabel("Smoothing"));
    smooth_ = new QDoubleSpinBox(this);
    smooth_->setObjectName("add_smoothing");
    smooth_->setRange(0, 1);
    smooth_->setSingleStep(0.1);
    smooth_->setDecimals(2);
    smooth_->setToolTip("Windowed-sinc smoothing factor, 0 (off) to 1 (strong), as 3D Slicer's");
    options->addWidget(smooth_);
    largest_ = new QCheckBox("Keep largest", this);
    largest_->setObjectName("add_keep_largest");
    largest_->setToolTip("Keep only the largest connected piece of the surface");
    options->addWidget(largest_);
    options->addStretch(1);
    col->addLayout(options);
    range_ = new QLabel(this);
    range_->setObjectName("value_range");
    col->addWidget(range_);
    connect(preset_, &QComboBox::activated, this, [this](int i) {
        const int p = preset_->itemData(i).toInt();
        if (p >= 0 && std::size_t(p) < preset_values_.size()) iso_->setValue(preset_values_[std::size_t(p)]);
    });
    connect(add, &QPushButton::clicked, this, [this] {
        PostProcessOptions post;
        post.smooth = smooth_->value();
        post.keep_largest = largest_->isChecked();
        add_surface(iso_->value(), post);
    });
    // The rows scroll: any number of surfaces fits the dock, and the dock
    // (so the window) does not grow with them.
    auto* list = new QWidget;
    list->setObjectName("surface_rows");
    rows_layout_ = new QVBoxLayout(list);
    rows_layout_->setContentsMargins(0, 0, 0, 0);
    rows_layout_->addStretch(1);
    auto* scroll = new QScrollArea(this);
    scroll->setObjectName("surface_list");
    scroll->setWidgetResizable(true);
    scroll->setFrameShape(QFrame::NoFrame);
    scroll->setWidget(list);
    scroll->setMinimumHeight(9 * fontMetrics().height()); // about one row
    col->addWidget(scroll, 1);
    observer_ = context_.workspace.observe([this](core::Parts p) { watched(p); });
    update_presets();
    sync_rows();
}

SurfacesPanel::~SurfacesPanel() {
    context_.workspace.unobserve(observer_);
    stop_workers();
}

// ---- following the workspace ------------------------------------------------------------

void SurfacesPanel::watched(core::Parts parts) {
    if (core::has(parts, core::Part::Data)) {
        // The workers read the old scene's volume: they end before it goes.
        stop_workers();
        ++generation_;
        for (auto& r : rows_) delete r->widget;
        rows_.clear();
        update_presets();
    }
    if (parts & (core::Part::Data | core::Part::Surfaces)) sync_rows();
}

// One row per surface, in the scene's order, each showing its surface.
void SurfacesPanel::sync_rows() {
    const core::Scene& scene = context_.workspace.scene();
    const auto ids = scene.surfaces();
    for (std::size_t i = 0; i < rows_.size();)
        if (std::find(ids.begin(), ids.end(), rows_[i]->id) == ids.end()) {
            // A re-extraction still running for it stops; its result is dropped.
            if (rows_[i]->worker) rows_[i]->worker->cancel = true;
            rows_[i]->widget->hide();
            rows_[i]->widget->deleteLater();
            rows_.erase(rows_.begin() + std::ptrdiff_t(i));
        } else {
            ++i;
        }
    for (std::size_t i = 0; i < ids.size(); ++i) {
        if (!find(ids[i])) add_row(ids[i]);
        Row* r = find(ids[i]);
        rows_layout_->removeWidget(r->widget);
        rows_layout_->insertWidget(int(i), r->widget); // the scene's order, above the stretch
        show_row(*r);
    }
}

// The row's controls from its surface, making no edit of their own.
void SurfacesPanel::show_row(Row& r) {
    const core::SurfaceInfo& info = context_.workspace.scene().info(r.id);
    r.syncing = true;
    if (auto* visible = r.widget->findChild<QCheckBox*>("visible")) {
        const QSignalBlocker block(visible);
        visible->setChecked(info.visible);
        visible->setText(QString::fromStdString(info.name));
    }
    if (auto* color = r.widget->findChild<QPushButton*>("color"))
        color->setStyleSheet("background-color: " + to_qcolor(info.color).name());
    if (auto* opacity = r.widget->findChild<QSlider*>("opacity")) {
        const QSignalBlocker block(opacity);
        opacity->setValue(int(std::lround(info.opacity * 100)));
        if (auto* percent = r.widget->findChild<QSpinBox*>("opacity_value")) {
            const QSignalBlocker block_number(percent);
            percent->setValue(opacity->value());
        }
    }
    if (r.slider && (info.value != r.shown_value || !(info.post == r.shown_post))) {
        // Changed from elsewhere (an undo, a redo): that is what the row asks for now.
        if (r.worker) r.worker->cancel = true;
        r.wanted = info.value;
        r.wanted_post = info.post;
        r.show_value(info.value);
        r.slider->setValue(r.to_slider(info.value));
        r.smooth->setValue(info.post.smooth);
        r.largest->setChecked(info.post.keep_largest);
    }
    r.shown_value = info.value;
    r.shown_post = info.post;
    r.syncing = false;
}

void SurfacesPanel::edit_info(std::uint32_t id, const char* what,
                              const std::function<void(core::SurfaceInfo&)>& change) {
    core::Workspace& w = context_.workspace;
    if (!w.scene().has_surface(id)) return;
    core::SurfaceInfo info = w.scene().info(id);
    change(info);
    const QString text = QString(what) + " " + QString::fromStdString(info.name);
    context_.edit(
        text, core::Parts(core::Part::Surfaces), [&] { w.set_surface_info(id, info); },
        drag_ ? merge_key(what, id) : QString());
}

QString SurfacesPanel::merge_key(const char* what, std::uint32_t id) const {
    return QString("%1 %2 drag %3").arg(what).arg(id).arg(drag_);
}

// ---- the scene ------------------------------------------------------------------------

void SurfacesPanel::stop_workers() {
    // The workers read the scene's volume: they end before it may go. Each
    // stops at its next progress call.
    for (auto& w : workers_) w->cancel = true;
    for (auto& w : workers_) {
        QObject::disconnect(w->thread, nullptr, this, nullptr);
        w->thread->wait();
        delete w->thread;
        w->thread = nullptr;
    }
    workers_.clear();
}

// The presets the core offers for this volume (core::iso_presets: CT's in
// HU, or thresholds of its own histogram), the first that fits chosen.
void SurfacesPanel::update_presets() {
    const core::Scene& scene = context_.workspace.scene();
    const QString unit = unit_suffix(&scene);
    const bool volume = scene.has_volume();
    const ValueRange range = volume ? scene.value_range() : ValueRange{-1e6, 1e6};
    const auto presets = core::iso_presets(scene);
    preset_->clear();
    preset_values_.clear();
    auto* model = qobject_cast<QStandardItemModel*>(preset_->model());
    int first = -1;
    for (const auto& p : presets) {
        preset_->addItem(QString("%1: %2%3").arg(QString::fromStdString(p.name)).arg(p.value).arg(p.hu ? " HU" : ""),
                         int(preset_values_.size()));
        preset_values_.push_back(p.value);
        auto* item = model->item(preset_->count() - 1);
        item->setToolTip(QString::fromStdString(p.why_not));
        item->setEnabled(p.enabled);
        if (first < 0 && p.enabled) first = preset_->count() - 1;
    }
    // The number stays within the volume's values, starting at the first
    // preset that fits (none: the middle of the range).
    iso_->setRange(range.min, range.max);
    iso_->setDecimals(range.max - range.min < 10 ? 3 : 1);
    iso_->setSuffix(unit);
    preset_->setPlaceholderText(volume ? "No preset fits this volume" : "Open a volume first");
    preset_->setCurrentIndex(first); // -1 (none): the placeholder
    iso_->setValue(first >= 0 ? preset_values_[std::size_t(first)] : 0.5 * (range.min + range.max));
    range_->setText(volume ? QString("Values %1 to %2%3").arg(range.min).arg(range.max).arg(unit)
                           : QString("Open a volume to add surfaces"));
}

// ---- adding ----------------------------------------------------------------------------

void SurfacesPanel::add_surface(double iso, const PostProcessOptions& post) {
    if (context_.busy(true)) return;
    core::Workspace& ws = context_.workspace;
    if (!ws.scene().has_volume()) {
        context_.status("Open a volume first");
        return;
    }
    if (const auto r = ws.scene().value_range(); !(iso >= r.min && iso <= r.max)) {
        // No surface would cross it: nothing is added.
        const QString file = QString::fromStdString(ws.scene().volume_source());
        const QString why = QString("The iso value %1 is outside the values of %2 (%3 to %4%5); "
                                    "no surface would be found there.")
                                .arg(iso)
                                .arg(file.isEmpty() ? QString("the volume") : file)
                                .arg(r.min)
                                .arg(r.max)
                                .arg(unit_suffix(&ws.scene()));
        context_.status("Not added: " + why);
        context_.error("Cannot add the surface", QString("Cannot add the isosurface at %1").arg(iso), why);
        return;
    }
    // The worker only reads the volume, and works out what the scene keeps
    // beside the mesh (bounds, outline index); the mesh joins the scene on the GUI thread.
    auto mesh = std::make_shared<core::PreparedMesh>();
    const core::Scene* s = &ws.scene();
    const unsigned generation = generation_;
    context_.jobs.run(
        QString("Extracting the isosurface at %1").arg(iso), false,
        [s, iso, post, mesh](const ProgressFn& progress) {
            *mesh = core::prepare_mesh(s->extract_isosurface(iso, {}, post, progress));
        },
        [this, s, iso, post, mesh, generation](std::exception_ptr e) {
            if (e) {
                context_.error("Surface extraction failed", QString("Cannot extract the isosurface at %1").arg(iso), e);
                return;
            }
            core::Workspace& ws = context_.workspace;
            if (s != &ws.scene() || generation != generation_) return; // another scene meanwhile
            const std::size_t triangles = mesh->mesh->triangles.size();
            context_.edit(QString("Add iso %1").arg(iso), core::Parts(core::Part::Surfaces),
                          [&] { ws.add_isosurface(std::move(*mesh), iso, post); });
            context_.status(QString("Added the isosurface at %1: %2 triangles").arg(iso).arg(triangles));
        });
}

// ---- rows ------------------------------------------------------------------------------

SurfacesPanel::Row* SurfacesPanel::find(std::uint32_t id) const {
    for (const auto& r : rows_)
        if (r->id == id) return r.get();
    return nullptr;
}

QWidget* SurfacesPanel::row(std::uint32_t id) const {
    const Row* r = find(id);
    return r ? r->widget : nullptr;
}

void SurfacesPanel::add_row(std::uint32_t id) {
    const core::Scene& scene = context_.workspace.scene();
    const auto& info = scene.info(id);
    auto row = std::make_unique<Row>();
    Row* r = row.get();
    r->id = id;
    r->wanted = r->shown_value = info.value;
    r->wanted_post = r->shown_post = info.post;
    r->widget = new QFrame(this);
    r->widget->setObjectName(QString("surface_%1").arg(id));
    r->widget->setFrameShape(QFrame::StyledPanel);
    auto* grid = new QGridLayout(r->widget);
    grid->setContentsMargins(4, 4, 4, 4);
    add_title_line(*r, grid);
    add_opacity_line(*r, grid);
    // Lines 3 and 4, isosurfaces only: the iso slider and number (range: the
    // volume's values), smoothing and keep-largest.
    if (info.kind == core::SurfaceInfo::Kind::Iso && scene.has_volume()) {
        add_iso_line(*r, grid);
        add_post_line(*r, grid);
    }
    rows_layout_->insertWidget(rows_layout_->count() - 1, r->widget); // above the stretch
    rows_.push_back(std::move(row));
}

// Line 1: visibility and name, colour, Remove.
void SurfacesPanel::add_title_line(Row& r, QGridLayout* grid) {
    const std::uint32_t id = r.id;
    const auto& info = context_.workspace.scene().info(id);
    auto* visible = new QCheckBox(QString::fromStdString(info.name), r.widget);
    visible->setObjectName("visible");
    visible->setToolTip("Show or hide this surface (3D view and slice outlines)");
    visible->setChecked(info.visible);
    auto* color = new QPushButton(r.widget);
    color->setObjectName("color");
    color->setFixedSize(24, 20);
    color->setToolTip("The surface's colour: click to choose another");
    const auto paint_button = [color](const QColor& c) { color->setStyleSheet("background-color: " + c.name()); };
    paint_button(to_qcolor(info.color));
    auto* remove = new QPushButton("Remove", r.widget);
    remove->setObjectName("remove");
    remove->setToolTip("Remove this surface (Edit > Undo brings it back)");
    auto* line1 = new QHBoxLayout;
    line1->addWidget(visible, 1);
    line1->addWidget(color);
    line1->addWidget(remove);
    grid->addLayout(line1, 0, 0, 1, 3);

    connect(visible, &QCheckBox::toggled, this, [this, id](bool on) {
        edit_info(id, on ? "Show" : "Hide", [on](core::SurfaceInfo& i) { i.visible = on; });
    });
    connect(color, &QPushButton::clicked, this, [this, id] {
        const QColor c =
            QColorDialog::getColor(to_qcolor(context_.workspace.scene().info(id).color), this, "Surface colour");
        if (c.isValid()) edit_info(id, "Change colour of", [c](core::SurfaceInfo& i) { i.color = from_qcolor(c); });
    });
    connect(remove, &QPushButton::clicked, this, [this, id] {
        core::Workspace& w = context_.workspace;
        if (!w.scene().has_surface(id)) return;
        const QString name = QString::fromStdString(w.scene().info(id).name);
        if (context_.edit("Remove " + name, core::Parts(core::Part::Surfaces), [&] { w.remove_surface(id); }))
            context_.status("Removed " + name + " (Edit > Undo brings it back)");
    });
}

// Line 2: opacity, 0..100 %: a slider and a number, kept in step.
void SurfacesPanel::add_opacity_line(Row& r, QGridLayout* grid) {
    const std::uint32_t id = r.id;
    grid->addWidget(new QLabel("Opacity"), 1, 0);
    auto* opacity = new QSlider(Qt::Horizontal, r.widget);
    opacity->setObjectName("opacity");
    opacity->setToolTip("Opacity: 100 % opaque; lower shows what lies behind (exact order-independent transparency)");
    opacity->setRange(0, 100);
    opacity->setPageStep(10);
    opacity->setValue(int(std::lround(context_.workspace.scene().info(id).opacity * 100)));
    auto* percent = new QSpinBox(r.widget);
    percent->setObjectName("opacity_value");
    percent->setToolTip("Opacity in per cent");
    percent->setRange(0, 100);
    percent->setSuffix(" %");
    percent->setValue(opacity->value());
    grid->addWidget(opacity, 1, 1);
    grid->addWidget(percent, 1, 2);
    track_drag(opacity);
    connect(opacity, &QSlider::valueChanged, this, [this, id, percent](int v) {
        Row* row = find(id);
        if (!row || row->syncing) return;
        {
            const QSignalBlocker block(percent);
            percent->setValue(v); // the number follows
        }
        edit_info(id, "Change opacity of", [v](core::SurfaceInfo& i) { i.opacity = float(v) / 100.0f; });
    });
    connect(percent, &QSpinBox::valueChanged, opacity, &QSlider::setValue);
}

namespace {
// The nearest of 1, 2, 5 times a power of ten to `x` > 0.
double nice_step(double x) {
    const double p = std::pow(10.0, std::floor(std::log10(x)));
    double best = p;
    for (double m : {2.0, 5.0, 10.0})
        if (std::abs(std::log(m * p / x)) < std::abs(std::log(best / x))) best = m * p;
    return best;
}
} // namespace

// Line 3: the iso number (and the "extracting..." label of a re-extraction
// under way); line 4: the iso slider across the whole row, kept in step
// with the number. The slider moves in steps of a round increment near a
// thousandth of the volume's range (at least 1 for integer voxels); a page
// (a click beside the handle, Page Up/Down) is about a twentieth.
void SurfacesPanel::add_iso_line(Row& r, QGridLayout* grid) {
    const std::uint32_t id = r.id;
    const core::Scene& scene = context_.workspace.scene();
    const double value = scene.info(id).value;
    const auto range = scene.value_range();
    const auto type = scene.volume().type;
    const bool integral = type != VoxelType::F32 && type != VoxelType::F64 && !scene.volume().is_sparse();
    const double span = std::max(range.max - range.min, 1e-9);
    r.lo = range.min;
    r.hi = range.max;
    r.step = nice_step(span / 1000);
    if (integral) r.step = std::max(r.step, 1.0);
    r.steps = int(std::ceil(span / r.step - 1e-9));
    const QString unit = unit_suffix(&scene);
    grid->addWidget(new QLabel("Iso"), 2, 0);
    r.slider = new QSlider(Qt::Horizontal, r.widget);
    r.slider->setObjectName("iso_slider");
    r.slider->setRange(0, r.steps);
    r.slider->setSingleStep(1);
    r.slider->setPageStep(std::max(1, int(std::lround(nice_step(span / 20) / r.step))));
    r.slider->setValue(r.to_slider(value));
    r.slider->setToolTip(QString("Iso value, %1 to %2%3, in steps of %4; Page Up/Down: %5")
                             .arg(range.min)
                             .arg(range.max)
                             .arg(unit)
                             .arg(r.step)
                             .arg(r.slider->pageStep() * r.step));
    r.value = new QDoubleSpinBox(r.widget);
    r.value->setObjectName("iso_value");
    r.value->setToolTip("This surface's iso value: Enter, the arrows or leaving the box extract it again");
    r.value->setRange(range.min, range.max);
    r.decimals = integral ? 0 : 3;
    r.value->setSingleStep(r.step);
    r.value->setKeyboardTracking(false); // on Enter, arrows or leaving the box
    r.value->setSuffix(unit);
    r.show_value(value);
    r.busy = new QLabel("extracting...", r.widget);
    r.busy->setObjectName("busy");
    r.busy->setVisible(false);
    auto* line3 = new QHBoxLayout;
    line3->addWidget(r.value);
    line3->addWidget(r.busy, 1);
    grid->addLayout(line3, 2, 1, 1, 2);
    grid->addWidget(r.slider, 3, 0, 1, 3);

    track_drag(r.slider);
    connect(r.slider, &QSlider::valueChanged, this, [this, id](int s) {
        Row* row = find(id);
        if (!row || row->syncing) return;
        row->syncing = true;
        row->value->setValue(row->from_slider(s));
        row->syncing = false;
        set_iso(id, row->value->value());
    });
    connect(r.value, &QDoubleSpinBox::valueChanged, this, [this, id](double v) {
        Row* row = find(id);
        if (!row || row->syncing) return;
        row->syncing = true;
        row->slider->setValue(row->to_slider(v));
        row->syncing = false;
        set_iso(id, v);
    });
}

// Line 4: smoothing and keep-largest, the post-processing a re-extraction applies.
void SurfacesPanel::add_post_line(Row& r, QGridLayout* grid) {
    const std::uint32_t id = r.id;
    const PostProcessOptions& post = context_.workspace.scene().info(id).post;
    grid->addWidget(new QLabel("Smoothing"), 4, 0);
    r.smooth = new QDoubleSpinBox(r.widget);
    r.smooth->setObjectName("smoothing");
    r.smooth->setRange(0, 1);
    r.smooth->setSingleStep(0.1);
    r.smooth->setDecimals(2);
    r.smooth->setKeyboardTracking(false);
    r.smooth->setValue(post.smooth);
    r.smooth->setToolTip("Windowed-sinc smoothing factor, 0 (off) to 1 (strong), as 3D Slicer's");
    r.largest = new QCheckBox("Keep largest", r.widget);
    r.largest->setObjectName("keep_largest");
    r.largest->setToolTip("Keep only the largest connected piece of the surface");
    r.largest->setChecked(post.keep_largest);
    auto* line4 = new QHBoxLayout;
    line4->addWidget(r.smooth);
    line4->addWidget(r.largest);
    line4->addStretch(1);
    grid->addLayout(line4, 4, 1, 1, 2);

    const auto post_changed = [this, id] {
        Row* row = find(id);
        if (!row || row->syncing) return;
        PostProcessOptions p = row->wanted_post;
        p.smooth = row->smooth->value();
        p.keep_largest = row->largest->isChecked();
        set_post(id, p);
    };
    connect(r.smooth, &QDoubleSpinBox::valueChanged, this, post_changed);
    connect(r.largest, &QCheckBox::toggled, this, post_changed);
}

// ---- re-extraction ---------------------------------------------------------------------

void SurfacesPanel::set_iso(std::uint32_t id, double value) {
    Row* r = find(id);
    if (!r || !r->slider) return;
    if (r->value->value() != value) {
        // Called directly (not from the row's controls): show the value.
        r->syncing = true;
        r->show_value(value);
        r->slider->setValue(r->to_slider(value));
        r->syncing = false;
    }
    r->wanted = value;
    r->wanted_drag = drag_;
    r->what = "Change iso value of";
    request(*r);
}

void SurfacesPanel::set_post(std::uint32_t id, const PostProcessOptions& post) {
    Row* r = find(id);
    if (!r || !r->slider) return;
    r->syncing = true;
    r->smooth->setValue(post.smooth);
    r->largest->setChecked(post.keep_largest);
    r->syncing = false;
    r->what = post.keep_largest != r->wanted_post.keep_largest ? "Change keep largest of" : "Change smoothing of";
    r->wanted_post = post;
    r->wanted_drag = 0;
    request(*r);
}

bool SurfacesPanel::reextracting(std::uint32_t id) const {
    for (const auto& r : rows_)
        if ((id == 0 || r->id == id) && r->worker) return true;
    return false;
}

void SurfacesPanel::request(Row& r) {
    if (r.worker) {
        // The latest value wins: stop the running one (its ProgressFn says
        // no); when it has ended, finished() starts the wanted value.
        if (r.worker->iso != r.wanted || !(r.worker->post == r.wanted_post)) r.worker->cancel = true;
        return;
    }
    const auto& info = context_.workspace.scene().info(r.id);
    if (info.value == r.wanted && info.post == r.wanted_post) return; // already shown
    start(r);
}

void SurfacesPanel::start(Row& r) {
    auto w = std::make_shared<Worker>();
    w->iso = r.wanted;
    w->post = r.wanted_post;
    w->generation = generation_;
    w->drag = r.wanted_drag;
    w->what = r.what;
    Worker* raw = w.get();
    const core::Scene* s = &context_.workspace.scene();
    // Reads only the volume and its cached range index (core::Scene::extract_isosurface):
    // the views keep drawing the scene meanwhile.
    w->thread = QThread::create([raw, s] {
        try {
            raw->mesh = core::prepare_mesh(s->extract_isosurface(
                raw->iso, {}, raw->post, [raw](double, std::string_view) { return !raw->cancel.load(); }));
        } catch (...) {
            raw->error = std::current_exception();
        }
    });
    const std::uint32_t id = r.id;
    connect(w->thread, &QThread::finished, this, [this, id, w] { finished(id, w); });
    r.worker = w;
    workers_.push_back(w);
    r.busy->setVisible(true);
    w->thread->start();
}

void SurfacesPanel::finished(std::uint32_t id, const std::shared_ptr<Worker>& w) {
    if (!w->thread) return; // stop_workers() already waited for it and deleted its thread
    std::erase(workers_, w);
    w->thread->deleteLater();
    w->thread = nullptr;
    if (w->generation != generation_) return;
    Row* r = find(id);
    if (!r || r->worker != w) return; // removed meanwhile
    r->worker.reset();
    const bool current = w->iso == r->wanted && w->post == r->wanted_post;
    if (w->error) {
        bool cancelled = false;
        try {
            std::rethrow_exception(w->error);
        } catch (const Cancelled&) {
            cancelled = true;
        } catch (...) {}
        if (!cancelled && current)
            context_.error("Surface extraction failed", QString("Cannot extract the isosurface at %1").arg(w->iso),
                           w->error);
    } else if (current) {
        // Swap the new mesh in on the GUI thread, one undo step (the steps
        // of one slider drag merge); the next frame uploads it.
        core::Workspace& ws = context_.workspace;
        const QString name = QString::fromStdString(ws.scene().info(id).name);
        r->shown_value = w->iso; // the panel's own change: the row keeps its request
        r->shown_post = w->post;
        context_.edit(
            QString(w->what) + " " + name, core::Parts(core::Part::Surfaces),
            [&] { ws.replace_surface(id, std::move(w->mesh), w->iso, w->post); },
            w->drag ? QString("%1 %2 drag %3").arg(w->what).arg(id).arg(w->drag) : QString());
        ++swaps_;
        r = find(id); // the edit's notification may have rebuilt rows
        if (!r) return;
        context_.status(QString("%1: %2 triangles")
                            .arg(QString::fromStdString(ws.scene().info(id).name))
                            .arg(ws.scene().mesh(id).triangles.size()));
    }
    // A newer value came in meanwhile: extract it now (unless it is what is shown).
    if (!current) {
        const auto& info = context_.workspace.scene().info(id);
        if (info.value != r->wanted || !(info.post == r->wanted_post)) {
            start(*r);
            return;
        }
    }
    r->busy->setVisible(false);
}

void SurfacesPanel::track_drag(QSlider* slider) {
    connect(slider, &QSlider::sliderPressed, this, [this] { drag_ = ++drags_; });
    connect(slider, &QSlider::sliderReleased, this, [this] { drag_ = 0; });
}

} // namespace iso::gui
