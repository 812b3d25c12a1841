#include "app/gui/volume_panel.hpp"

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>

#include "app/gui/tf_editor.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

namespace {
constexpr int kBins = 128;
constexpr std::int64_t kHistogramSamples = 2'000'000; // at most this many voxels read (a regular subsample)
const char* const kModes[] = {"Composite", "MIP", "MinIP"};
const char* const kAxes[] = {"L", "P", "S"};
} // namespace

Clip VolumeState::clip() const {
    Clip c;
    if (crop) c.box = std::pair{glm::min(box.first, box.second), glm::max(box.first, box.second)};
    return c;
}

VolumePanel::VolumePanel(QWidget* parent) : QWidget(parent) {
    setObjectName("volume_panel");
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(6, 6, 6, 6);
    layout->addWidget(make_look_rows());
    editor_ = new TfEditor(this);
    editor_->setObjectName("tf_editor");
    layout->addWidget(editor_, 1);
    auto* hint =
        new QLabel("Drag a point. Double-click: add a point, or pick a point's colour. Right-click: remove.", this);
    hint->setWordWrap(true);
    hint->setObjectName("tf_hint");
    layout->addWidget(hint);
    layout->addWidget(make_crop_rows());
    editor_->on_live = [this](const TransferFunction& tf) {
        state_.look.tf = tf;
        if (changed) changed(state_);
    };
    editor_->on_edit = [this](const QString& text, const TransferFunction& before, const TransferFunction& after) {
        VolumeState b = state_, a = state_;
        b.look.tf = before;
        a.look.tf = after;
        state_ = b; // edit() reports the step from here
        edit(text, a);
    };
    set_scene(nullptr);
}

// Show volume, the preset and the mode.
QWidget* VolumePanel::make_look_rows() {
    auto* box = new QWidget(this);
    auto* grid = new QGridLayout(box);
    grid->setContentsMargins(0, 0, 0, 0);
    show_ = new QCheckBox("Show volume", box);
    show_->setObjectName("volume_show");
    show_->setToolTip("Ray cast the volume in the 3D view through the transfer function below");
    grid->addWidget(show_, 0, 0, 1, 2);
    grid->addWidget(new QLabel("Preset:", box), 1, 0);
    preset_ = new QComboBox(box);
    preset_->setObjectName("volume_preset");
    preset_->setToolTip("Transfer function presets (the CT ones in HU); 'custom': edited below");
    grid->addWidget(preset_, 1, 1);
    grid->addWidget(new QLabel("Mode:", box), 2, 0);
    mode_ = new QComboBox(box);
    mode_->setObjectName("volume_mode");
    mode_->setToolTip("Composite: emission and absorption; MIP / MinIP: the largest / smallest value along each ray");
    for (const char* m : kModes) mode_->addItem(m);
    grid->addWidget(mode_, 2, 1);
    grid->setColumnStretch(1, 1);
    connect(show_, &QCheckBox::toggled, this, [this](bool on) {
        if (showing_) return;
        VolumeState a = state_;
        a.look.enabled = on;
        edit(on ? "Show volume" : "Hide volume", a);
    });
    connect(preset_, &QComboBox::activated, this, [this](int i) { preset_chosen(i); });
    connect(mode_, &QComboBox::currentIndexChanged, this, [this](int i) {
        if (showing_ || i < 0) return;
        VolumeState a = state_;
        a.look.mode = VolumeMode(i);
        edit(QString("Volume mode ") + kModes[i], a);
    });
    return box;
}

// Crop, the box's L, P, S min and max (LPS mm) and Fit to volume.
QWidget* VolumePanel::make_crop_rows() {
    auto* box = new QWidget(this);
    auto* grid = new QGridLayout(box);
    grid->setContentsMargins(0, 0, 0, 0);
    crop_ = new QCheckBox("Crop", box);
    crop_->setObjectName("volume_crop");
    crop_->setToolTip("Cut the volume and the surfaces to the box (LPS mm); its edges are drawn in the 3D view");
    grid->addWidget(crop_, 0, 0, 1, 2);
    fit_ = new QPushButton("Fit to volume", box);
    fit_->setObjectName("crop_fit");
    fit_->setToolTip("The crop box back to the volume's box");
    grid->addWidget(fit_, 0, 2);
    grid->addWidget(new QLabel("min (mm)", box), 1, 1);
    grid->addWidget(new QLabel("max (mm)", box), 1, 2);
    for (int a = 0; a < 3; ++a) {
        auto* label = new QLabel(kAxes[a], box);
        label->setToolTip(a == 0 ? "Left (LPS x)" : a == 1 ? "Posterior (LPS y)" : "Superior (LPS z)");
        grid->addWidget(label, 2 + a, 0);
        for (int m = 0; m < 2; ++m) {
            auto* s = new QDoubleSpinBox(box);
            s->setObjectName(QString("crop_%1_%2").arg(QChar(kAxes[a][0]).toLower()).arg(m ? "max" : "min"));
            s->setDecimals(1);
            s->setSingleStep(1.0);
            s->setKeyboardTracking(false);
            s->setToolTip(QString("The crop box's %1 %2 (LPS mm; %3)")
                              .arg(m ? "largest" : "smallest")
                              .arg(kAxes[a])
                              .arg(a == 0   ? "towards the patient's left"
                                   : a == 1 ? "towards the back"
                                            : "upwards"));
            spins_[std::size_t(a + 3 * m)] = s;
            grid->addWidget(s, 2 + a, 1 + m);
            const QString what = QString("Crop box %1 %2").arg(kAxes[a]).arg(m ? "max" : "min");
            connect(s, &QDoubleSpinBox::valueChanged, this, [this, what] { crop_spin_changed(what); });
        }
    }
    grid->setColumnStretch(1, 1);
    grid->setColumnStretch(2, 1);
    connect(crop_, &QCheckBox::toggled, this, [this](bool on) {
        if (showing_) return;
        VolumeState a = state_;
        a.crop = on;
        edit(on ? "Crop" : "No crop", a);
    });
    connect(fit_, &QPushButton::clicked, this, [this] {
        VolumeState a = state_;
        a.box = volume_box_;
        if (a == state_) return;
        edit("Fit crop box to volume", a);
    });
    return box;
}

void VolumePanel::crop_spin_changed(const QString& what) {
    if (showing_) return;
    VolumeState a = state_;
    for (int i = 0; i < 3; ++i) {
        a.box.first[i] = spins_[std::size_t(i)]->value();
        a.box.second[i] = spins_[std::size_t(i + 3)]->value();
    }
    if (a == state_) return;
    edit(what, a, true); // a run of steps of one number: one undo step
}

TransferFunction VolumePanel::default_tf(double lo, double hi) {
    if (!(hi > lo)) hi = lo + 1;
    const auto at = [&](double f) { return lo + f * (hi - lo); };
    return TransferFunction({{at(0.0), 0.0, "#000000"},
                             {at(0.3), 0.0, "#c08060"},
                             {at(0.5), 0.02, "#e0b090"},
                             {at(0.8), 0.2, "#f0e0c8"},
                             {at(1.0), 0.5, "#ffffff"}});
}

TransferFunction VolumePanel::initial_tf() const {
    if (ct_) return transfer_function_from("bone");
    if (!scene_ || !scene_->has_volume()) return transfer_function_from("bone");
    const ValueRange r = scene_->value_range();
    return default_tf(r.min, r.max);
}

// The presets that fit the volume: the default from its range first for
// a volume that is not CT, then the CT presets, and "custom".
void VolumePanel::fill_presets() {
    preset_->clear();
    if (!ct_) preset_->addItem("default (value range)");
    for (const auto& name : transfer_function_presets()) preset_->addItem(QString::fromStdString(name));
    preset_->addItem("custom");
}

void VolumePanel::preset_chosen(int index) {
    if (showing_ || index < 0 || index == preset_->count() - 1) return;
    VolumeState a = state_;
    const QString name = preset_->itemText(index);
    if (!ct_ && index == 0)
        a.look.tf = initial_tf();
    else
        a.look.tf = transfer_function_from(name.toStdString());
    if (a == state_) return;
    edit("Volume preset " + name, a);
}

void VolumePanel::set_scene(const core::Scene* scene) {
    scene_ = scene && scene->has_volume() ? scene : nullptr;
    ct_ = false;
    if (scene_) {
        const ValueRange r = scene_->value_range();
        ct_ = !core::value_unit(*scene_).empty() && r.min >= -1100 && r.max <= 5000;
    }
    const Bounds b = scene_ ? scene_->volume_bounds() : Bounds{};
    volume_box_ = b.empty() ? std::pair{glm::dvec3(0.0), glm::dvec3(0.0)} : std::pair{b.min, b.max};
    for (int i = 0; i < 6; ++i) {
        const int a = i % 3;
        const double margin = std::max(1.0, volume_box_.second[a] - volume_box_.first[a]);
        spins_[std::size_t(i)]->blockSignals(true);
        spins_[std::size_t(i)]->setRange(volume_box_.first[a] - margin, volume_box_.second[a] + margin);
        spins_[std::size_t(i)]->blockSignals(false);
    }
    fill_presets();
    make_histogram();
    VolumeState s;
    s.look.tf = initial_tf();
    s.box = volume_box_;
    set_state(s);
}

// Counts over the volume's value range from a regular subsample of at
// most kHistogramSamples voxels (cheap enough for the GUI thread).
void VolumePanel::make_histogram() {
    if (!scene_) {
        editor_->set_histogram({}, 0, 1);
        return;
    }
    const Volume& v = scene_->volume();
    const ValueRange r = scene_->value_range();
    const double n = double(std::max<std::int64_t>(1, v.voxel_count()));
    const auto stride = std::max<std::int64_t>(1, std::int64_t(std::ceil(std::cbrt(n / double(kHistogramSamples)))));
    std::vector<double> counts(kBins, 0.0);
    const double width = r.max > r.min ? r.max - r.min : 1.0;
    for (std::int64_t k = 0; k < v.dims[2]; k += stride)
        for (std::int64_t j = 0; j < v.dims[1]; j += stride)
            for (std::int64_t i = 0; i < v.dims[0]; i += stride) {
                const double x = v.value(i, j, k);
                if (!std::isfinite(x)) continue;
                counts[std::size_t(std::clamp(int((x - r.min) / width * kBins), 0, kBins - 1))] += 1;
            }
    editor_->set_histogram(std::move(counts), r.min, r.min + width);
}

void VolumePanel::set_state(const VolumeState& s) {
    state_ = s;
    show_state();
    if (changed) changed(state_);
}

// The widgets from state_ (no edits while they are set).
void VolumePanel::show_state() {
    showing_ = true;
    show_->setChecked(state_.look.enabled);
    mode_->setCurrentIndex(int(state_.look.mode));
    int preset = preset_->count() - 1; // custom
    for (int i = 0; i + 1 < preset_->count(); ++i) {
        const TransferFunction tf =
            !ct_ && i == 0 ? initial_tf() : transfer_function_from(preset_->itemText(i).toStdString());
        if (tf == state_.look.tf) preset = i;
    }
    preset_->setCurrentIndex(preset);
    editor_->set_tf(state_.look.tf);
    crop_->setChecked(state_.crop);
    for (int i = 0; i < 3; ++i) {
        spins_[std::size_t(i)]->setValue(state_.box.first[i]);
        spins_[std::size_t(i + 3)]->setValue(state_.box.second[i]);
    }
    showing_ = false;
}

void VolumePanel::edit(const QString& text, VolumeState after, bool merge) {
    const VolumeState before = state_;
    state_ = std::move(after);
    show_state();
    if (changed) changed(state_);
    if (edited) edited(text, before, state_, merge);
}

} // namespace iso::gui
