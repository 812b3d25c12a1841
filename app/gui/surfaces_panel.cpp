// The Surfaces panel (surfaces_panel.hpp): its rows, one named step per line of a row, and the
// background re-extractions behind them.
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

#include "app/gui/slice_view.hpp"
#include "io/error.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

namespace {

// Iso values the panel offers. The bundled head CT (datasets/headsq, VTK's
// "headsq") is not in HU: its skin is at ~500 and its bone at ~1150 (the
// README's command). The HU values are common rules of thumb for calibrated
// CT, not tuned on a dataset here (docs/gui.md); the number edits any of them.
struct IsoPreset {
    const char* name;
    double value;
    bool hu;
};
constexpr IsoPreset kIsoPresets[] = {
    {"skin (headsq)", 500, false}, {"bone (headsq)", 1150, false},
    {"skin", -500, true},          {"soft tissue", 20, true},
    {"bone", 300, true},           {"contrast-filled vessels", 200, true},
};

// " HU" after the numbers of a volume in Hounsfield units (core::value_unit), else nothing.
QString unit_suffix(const core::Scene* scene) {
    const std::string_view unit = scene ? core::value_unit(*scene) : std::string_view{};
    return unit.empty() ? QString() : " " + QString::fromUtf8(unit.data(), qsizetype(unit.size()));
}

bool same_post(const PostProcessOptions& a, const PostProcessOptions& b) {
    return a.smooth == b.smooth && a.decimate == b.decimate && a.keep_largest == b.keep_largest &&
           a.keep_at == b.keep_at;
}

} // namespace

// One re-extraction on its own thread.
struct SurfacesPanel::Worker {
    QThread* thread = nullptr;
    double iso = 0;
    PostProcessOptions post;
    unsigned generation = 0;
    std::atomic<bool> cancel{false};
    Mesh mesh;
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
    std::shared_ptr<Worker> worker;
    int to_slider(double v) const { return int(std::clamp(std::lround((v - lo) / step), 0L, long(steps))); }
    double from_slider(int s) const { return std::min(hi, lo + double(s) * step); }
};

SurfacesPanel::SurfacesPanel(QWidget* parent) : QWidget(parent) {
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
    iso_->setValue(kIsoPresets[0].value);
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
        iso_->setValue(kIsoPresets[p].value);
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
    update_presets();
}

SurfacesPanel::~SurfacesPanel() { stop_workers(); }

void SurfacesPanel::notify(bool outlines) {
    if (changed) changed(outlines);
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

void SurfacesPanel::set_scene(core::Scene* scene) {
    stop_workers();
    ++generation_;
    for (auto& r : rows_) delete r->widget;
    rows_.clear();
    scene_ = scene;
    update_presets();
    if (scene_)
        for (auto id : scene_->surfaces()) add_row(id);
}

void SurfacesPanel::update_presets() {
    // CT in Hounsfield units: the HU presets first and the numbers marked HU.
    // Without a unit the HU presets stay listed but disabled, saying why;
    // so does a preset outside the volume's values.
    const QString unit = unit_suffix(scene_);
    const bool hu = !unit.isEmpty();
    const bool volume = scene_ && scene_->has_volume();
    const ValueRange range = volume ? scene_->value_range() : ValueRange{-1e6, 1e6};
    preset_->clear();
    auto* model = qobject_cast<QStandardItemModel*>(preset_->model());
    int first = -1;
    for (int pass = 0; pass < 2; ++pass)
        for (int i = 0; i < int(std::size(kIsoPresets)); ++i) {
            const auto& p = kIsoPresets[i];
            if ((pass == 0) != (p.hu == hu)) continue;
            QString why;
            if (p.hu && !hu)
                why = "For CT in Hounsfield units; this volume's values have no unit";
            else if (p.value < range.min || p.value > range.max)
                why = QString("Outside this volume's values (%1 to %2%3)").arg(range.min).arg(range.max).arg(unit);
            preset_->addItem(QString("%1: %2%3%4")
                                 .arg(p.name)
                                 .arg(p.value)
                                 .arg(p.hu ? " HU" : "")
                                 .arg(p.hu && !hu && volume ? " (CT only)" : ""),
                             i);
            auto* item = model->item(preset_->count() - 1);
            item->setToolTip(why);
            item->setEnabled(why.isEmpty() || !volume);
            if (first < 0 && (why.isEmpty() || !volume)) first = preset_->count() - 1;
        }
    // The number stays within the volume's values, starting at the first
    // preset that fits (none: the middle of the range).
    iso_->setRange(range.min, range.max);
    iso_->setDecimals(range.max - range.min < 10 ? 3 : 1);
    iso_->setSuffix(unit);
    preset_->setPlaceholderText("No preset fits this volume");
    preset_->setCurrentIndex(first); // -1 (none): the placeholder
    iso_->setValue(first >= 0 ? kIsoPresets[preset_->itemData(first).toInt()].value : 0.5 * (range.min + range.max));
    if (volume) {
        range_->setText(QString("Values %1 to %2%3").arg(range.min).arg(range.max).arg(unit));
    } else {
        range_->setText("Open a volume to add surfaces");
    }
}

// ---- adding ----------------------------------------------------------------------------

void SurfacesPanel::add_surface(double iso, const PostProcessOptions& post) {
    if (busy && busy()) {
        if (message) message("Busy: wait for the current task or cancel it");
        return;
    }
    if (!scene_ || !scene_->has_volume()) {
        if (message) message("Open a volume first");
        return;
    }
    if (const auto r = scene_->value_range(); !(iso >= r.min && iso <= r.max)) {
        // No surface would cross it: nothing is added.
        const auto sources = scene_->sources();
        const QString file = sources.empty() ? QString("the volume") : QString::fromStdString(sources.front());
        const QString why = QString("The iso value %1 is outside the values of %2 (%3 to %4%5); "
                                    "no surface would be found there.")
                                .arg(iso)
                                .arg(file)
                                .arg(r.min)
                                .arg(r.max)
                                .arg(unit_suffix(scene_));
        if (message) message("Not added: " + why);
        if (error)
            error("Cannot add the surface", QString("Cannot add the isosurface at %1").arg(iso),
                  std::make_exception_ptr(std::runtime_error(why.toStdString())));
        return;
    }
    // The worker only reads the volume; the mesh joins the scene on the GUI thread.
    auto mesh = std::make_shared<Mesh>();
    core::Scene* s = scene_;
    const unsigned generation = generation_;
    run_job(
        QString("Extracting the isosurface at %1").arg(iso),
        [s, iso, post, mesh](const ProgressFn& progress) { *mesh = s->extract_isosurface(iso, {}, post, progress); },
        [this, s, iso, post, mesh, generation](std::exception_ptr e) {
            if (e) {
                if (error)
                    error("Surface extraction failed", QString("Cannot extract the isosurface at %1").arg(iso), e);
                return;
            }
            if (s != scene_ || generation != generation_) return; // another scene meanwhile
            const std::size_t triangles = mesh->triangles.size();
            const auto id = scene_->add_isosurface(std::move(*mesh), iso, post);
            add_row(id);
            notify(true);
            if (message) message(QString("Added the isosurface at %1: %2 triangles").arg(iso).arg(triangles));
            if (added) added(id);
        });
}

void SurfacesPanel::isolate(std::uint32_t id, const glm::dvec3& at) {
    if (busy && busy()) {
        if (message) message("Busy: wait for the current task or cancel it");
        return;
    }
    if (!scene_ || !scene_->has_surface(id)) return;
    // The worker only reads the scene (the surface's mesh, the volume); the
    // component joins the scene on the GUI thread.
    auto plan = std::make_shared<core::ComponentPlan>();
    core::Scene* s = scene_;
    const unsigned generation = generation_;
    const QString name = QString::fromStdString(scene_->info(id).name);
    run_job(
        "Isolating a component of " + name,
        [s, id, at, plan](const ProgressFn&) { *plan = core::plan_component(*s, id, at); },
        [this, s, plan, generation, name](std::exception_ptr e) {
            if (e) {
                if (error) error("Isolate failed", "Cannot isolate a component of " + name, e);
                return;
            }
            if (s != scene_ || generation != generation_) return; // another scene meanwhile
            const core::IsolatedComponent c = core::add_component(*scene_, std::move(*plan));
            add_row(c.surface);
            notify(true);
            if (message)
                message(QString("Isolated %1 (%2 of %3 components)")
                            .arg(QString::fromStdString(c.measured.name))
                            .arg(c.component + 1)
                            .arg(c.components));
            if (isolated) isolated(c);
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
    const auto& info = scene_->info(id);
    auto row = std::make_unique<Row>();
    Row* r = row.get();
    r->id = id;
    r->wanted = info.value;
    r->wanted_post = info.post;
    r->widget = new QFrame(this);
    r->widget->setObjectName(QString("surface_%1").arg(id));
    r->widget->setFrameShape(QFrame::StyledPanel);
    auto* grid = new QGridLayout(r->widget);
    grid->setContentsMargins(4, 4, 4, 4);
    add_title_line(*r, grid);
    add_opacity_line(*r, grid);
    // Lines 3 and 4, isosurfaces only: the iso slider and number (range: the
    // volume's values), smoothing and keep-largest.
    if (info.kind == core::SurfaceInfo::Kind::Iso && scene_->has_volume()) {
        add_iso_line(*r, grid);
        add_post_line(*r, grid);
    }
    rows_layout_->insertWidget(rows_layout_->count() - 1, r->widget); // above the stretch
    rows_.push_back(std::move(row));
}

// Line 1: visibility and name, colour, Remove.
void SurfacesPanel::add_title_line(Row& r, QGridLayout* grid) {
    const std::uint32_t id = r.id;
    const auto& info = scene_->info(id);
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
        const SurfaceSettings before = settings(id);
        scene_->info(id).visible = on;
        notify(true);
        record(id, "change visibility", before);
    });
    connect(color, &QPushButton::clicked, this, [this, id, paint_button] {
        const QColor c = QColorDialog::getColor(to_qcolor(scene_->info(id).color), this, "Surface colour");
        if (!c.isValid()) return;
        const SurfaceSettings before = settings(id);
        scene_->info(id).color = from_qcolor(c);
        paint_button(c);
        notify(true);
        record(id, "change colour", before);
    });
    connect(remove, &QPushButton::clicked, this, [this, id] {
        if (remove_requested)
            remove_requested(id);
        else
            remove_surface(id);
    });
}

void SurfacesPanel::remove_surface(std::uint32_t id) {
    const QString name = QString::fromStdString(scene_->info(id).name);
    remove_row(id);
    scene_->remove_surface(id);
    notify(true);
    if (message) message("Removed " + name);
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
    opacity->setValue(int(std::lround(scene_->info(id).opacity * 100)));
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
        const SurfaceSettings before = settings(id);
        percent->setValue(v); // the number follows (its own signal then finds nothing to do)
        scene_->info(id).opacity = float(v) / 100.0f;
        notify(false);
        record(id, "change opacity", before);
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
    const double value = scene_->info(id).value;
    const auto range = scene_->value_range();
    const auto type = scene_->volume().type;
    const bool integral = type != VoxelType::F32 && type != VoxelType::F64 && !scene_->volume().is_sparse();
    const double span = std::max(range.max - range.min, 1e-9);
    r.lo = range.min;
    r.hi = range.max;
    r.step = nice_step(span / 1000);
    if (integral) r.step = std::max(r.step, 1.0);
    r.steps = int(std::ceil(span / r.step - 1e-9));
    const QString unit = unit_suffix(scene_);
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
    r.value->setDecimals(integral ? 0 : 3);
    r.value->setSingleStep(r.step);
    r.value->setKeyboardTracking(false); // on Enter, arrows or leaving the box
    r.value->setSuffix(unit);
    r.value->setValue(value);
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
        const SurfaceSettings before = settings(id);
        row->syncing = true;
        row->value->setValue(row->from_slider(s));
        row->syncing = false;
        set_iso(id, row->value->value());
        record(id, "change iso value", before);
    });
    connect(r.value, &QDoubleSpinBox::valueChanged, this, [this, id](double v) {
        Row* row = find(id);
        if (!row || row->syncing) return;
        const SurfaceSettings before = settings(id);
        row->syncing = true;
        row->slider->setValue(row->to_slider(v));
        row->syncing = false;
        set_iso(id, v);
        record(id, "change iso value", before);
    });
}

// Line 4: smoothing and keep-largest, the post-processing a re-extraction applies.
void SurfacesPanel::add_post_line(Row& r, QGridLayout* grid) {
    const std::uint32_t id = r.id;
    const PostProcessOptions& post = scene_->info(id).post;
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
        const SurfaceSettings before = settings(id);
        PostProcessOptions p = row->wanted_post;
        p.smooth = row->smooth->value();
        p.keep_largest = row->largest->isChecked();
        set_post(id, p);
        record(id, p.keep_largest != before.post.keep_largest ? "change keep largest" : "change smoothing", before);
    };
    connect(r.smooth, &QDoubleSpinBox::valueChanged, this, post_changed);
    connect(r.largest, &QCheckBox::toggled, this, post_changed);
}

void SurfacesPanel::remove_row(std::uint32_t id) {
    for (auto it = rows_.begin(); it != rows_.end(); ++it)
        if ((*it)->id == id) {
            // A re-extraction still running for it stops; its result is dropped.
            if ((*it)->worker) (*it)->worker->cancel = true;
            (*it)->widget->deleteLater();
            rows_.erase(it);
            return;
        }
}

// ---- re-extraction ---------------------------------------------------------------------

void SurfacesPanel::set_iso(std::uint32_t id, double value) {
    Row* r = find(id);
    if (!r || !r->slider) return;
    if (r->value->value() != value) {
        // Called directly (not from the row's controls): show the value.
        r->syncing = true;
        r->value->setValue(value);
        r->slider->setValue(r->to_slider(value));
        r->syncing = false;
    }
    r->wanted = value;
    request(*r);
}

void SurfacesPanel::set_post(std::uint32_t id, const PostProcessOptions& post) {
    Row* r = find(id);
    if (!r || !r->slider) return;
    r->syncing = true;
    r->smooth->setValue(post.smooth);
    r->largest->setChecked(post.keep_largest);
    r->syncing = false;
    r->wanted_post = post;
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
        if (r.worker->iso != r.wanted || !same_post(r.worker->post, r.wanted_post)) r.worker->cancel = true;
        return;
    }
    const auto& info = scene_->info(r.id);
    if (info.value == r.wanted && same_post(info.post, r.wanted_post)) return; // already shown
    start(r);
}

void SurfacesPanel::start(Row& r) {
    auto w = std::make_shared<Worker>();
    w->iso = r.wanted;
    w->post = r.wanted_post;
    w->generation = generation_;
    Worker* raw = w.get();
    const core::Scene* s = scene_;
    // Reads only the volume and its cached range index (core::Scene::extract_isosurface):
    // the views keep drawing the scene meanwhile.
    w->thread = QThread::create([raw, s] {
        try {
            raw->mesh = s->extract_isosurface(raw->iso, {}, raw->post,
                                              [raw](double, std::string_view) { return !raw->cancel.load(); });
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
    const bool current = w->iso == r->wanted && same_post(w->post, r->wanted_post);
    if (w->error) {
        bool cancelled = false;
        try {
            std::rethrow_exception(w->error);
        } catch (const Cancelled&) {
            cancelled = true;
        } catch (...) {}
        if (!cancelled && current && error)
            error("Surface extraction failed", QString("Cannot extract the isosurface at %1").arg(w->iso), w->error);
    } else if (current) {
        // Swap the new mesh in on the GUI thread; the next frame uploads it.
        scene_->replace_surface(id, std::move(w->mesh), w->iso, w->post);
        ++swaps_;
        if (auto* visible = r->widget->findChild<QCheckBox*>("visible"))
            visible->setText(QString::fromStdString(scene_->info(id).name));
        notify(true);
        if (message)
            message(QString("%1: %2 triangles")
                        .arg(QString::fromStdString(scene_->info(id).name))
                        .arg(scene_->mesh(id).triangles.size()));
    }
    // A newer value came in meanwhile: extract it now (unless it is what is shown).
    if (!current) {
        const auto& info = scene_->info(id);
        if (info.value != r->wanted || !same_post(info.post, r->wanted_post)) {
            start(*r);
            return;
        }
    }
    r->busy->setVisible(false);
}

// ---- undo ------------------------------------------------------------------------------

SurfaceSettings SurfacesPanel::settings(std::uint32_t id) const {
    const auto& info = scene_->info(id);
    SurfaceSettings s{info.color, info.opacity, info.visible, info.value, info.post};
    if (const Row* r = find(id)) { // what the user asked for last, perhaps still extracting
        s.iso = r->wanted;
        s.post = r->wanted_post;
    }
    return s;
}

void SurfacesPanel::apply(std::uint32_t id, const SurfaceSettings& s) {
    Row* r = find(id);
    if (!r || !scene_->has_surface(id)) return;
    auto& info = scene_->info(id);
    info.color = s.color;
    info.opacity = s.opacity;
    info.visible = s.visible;
    // The row's controls show it without making an edit of their own.
    if (auto* visible = r->widget->findChild<QCheckBox*>("visible")) {
        const QSignalBlocker block(visible);
        visible->setChecked(s.visible);
    }
    if (auto* color = r->widget->findChild<QPushButton*>("color"))
        color->setStyleSheet("background-color: " + to_qcolor(s.color).name());
    if (auto* opacity = r->widget->findChild<QSlider*>("opacity")) {
        const QSignalBlocker block(opacity);
        opacity->setValue(int(std::lround(s.opacity * 100)));
        if (auto* percent = r->widget->findChild<QSpinBox*>("opacity_value")) {
            const QSignalBlocker block_number(percent);
            percent->setValue(opacity->value());
        }
    }
    if (r->slider) {
        if (s.iso != r->wanted) set_iso(id, s.iso);
        if (!same_post(s.post, r->wanted_post)) set_post(id, s.post);
    }
    notify(true);
}

void SurfacesPanel::restore_surface(std::uint32_t id, Mesh mesh, const core::SurfaceInfo& info) {
    scene_->restore_surface(id, std::move(mesh), info);
    add_row(id);
    // Back in its place among the rows: before the row of the next surface in the scene's order.
    const auto ids = scene_->surfaces();
    for (auto it = std::find(ids.begin(), ids.end(), id); it != ids.end(); ++it)
        if (const Row* next = *it != id ? find(*it) : nullptr) {
            QWidget* w = find(id)->widget;
            rows_layout_->removeWidget(w);
            rows_layout_->insertWidget(rows_layout_->indexOf(next->widget), w);
            break;
        }
    notify(true);
}

void SurfacesPanel::record(std::uint32_t id, const char* what, const SurfaceSettings& before) {
    if (edited) edited(id, QString(what) + " of " + QString::fromStdString(scene_->info(id).name), before, drag_);
}

void SurfacesPanel::track_drag(QSlider* slider) {
    connect(slider, &QSlider::sliderPressed, this, [this] { drag_ = ++drags_; });
    connect(slider, &QSlider::sliderReleased, this, [this] { drag_ = 0; });
}

} // namespace iso::gui
