#include "app/gui/volume_panel.hpp"

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QStandardItemModel>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>

#include "app/gui/app_context.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/tf_editor.hpp"
#include "renderer/core/presets.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

namespace {
constexpr int kBins = 128;
const char* const kModes[] = {"Composite", "MIP", "MinIP"};
const char* const kAxes[] = {"L", "P", "S"};
} // namespace

Clip VolumeState::clip() const {
    Clip c;
    if (crop) c.box = box;
    return c;
}

VolumePanel::VolumePanel(AppContext& context, QWidget* parent) : QWidget(parent), context_(context) {
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
    // A drag in the editor shows each step (no undo step), its release is one step from where it began.
    editor_->on_live = [this](const TransferFunction& tf) {
        FrameLook l = context_.workspace.look();
        l.volume.tf = tf;
        showing_tf_ = true;
        context_.workspace.set_look(l);
        showing_tf_ = false;
    };
    editor_->on_edit = [this](const QString& text, const TransferFunction& before, const TransferFunction& after) {
        core::WorkspaceEdit e;
        e.text = text.toStdString();
        e.parts = core::Parts(core::Part::Look);
        e.before.look = e.after.look = context_.workspace.look();
        e.before.look.volume.tf = before;
        e.after.look.volume.tf = after;
        showing_tf_ = true;
        context_.workspace.restore(e.after, e.parts);
        showing_tf_ = false;
        context_.push(std::move(e));
    };
    observer_ = context_.workspace.observe([this](core::Parts p) {
        if (core::has(p, core::Part::Data)) new_data();
        if (p & (core::Part::Data | core::Part::Look)) show_state();
    });
    new_data();
}

VolumePanel::~VolumePanel() { context_.workspace.unobserve(observer_); }

VolumeState VolumePanel::state() const {
    VolumeState s;
    const FrameLook& l = context_.workspace.look();
    s.look = l.volume;
    s.crop = l.clip.box.has_value();
    s.box = l.clip.box.value_or(box_);
    return s;
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
        VolumeState a = state();
        a.look.enabled = on;
        edit(on ? "Show volume" : "Hide volume", a);
    });
    connect(preset_, &QComboBox::activated, this, [this](int i) { preset_chosen(i); });
    connect(mode_, &QComboBox::currentIndexChanged, this, [this](int i) {
        if (showing_ || i < 0) return;
        VolumeState a = state();
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
        VolumeState a = state();
        a.crop = on;
        edit(on ? "Crop" : "No crop", a);
    });
    connect(fit_, &QPushButton::clicked, this, [this] {
        VolumeState a = state();
        a.box = volume_box_;
        if (a == state()) return;
        edit("Fit crop box to volume", a);
    });
    return box;
}

void VolumePanel::crop_spin_changed(const QString& what) {
    if (showing_) return;
    VolumeState a = state();
    for (int i = 0; i < 3; ++i) {
        a.box.first[i] = spins_[std::size_t(i)]->value();
        a.box.second[i] = spins_[std::size_t(i + 3)]->value();
        if (a.box.first[i] > a.box.second[i]) {
            // Inside out: nothing would be left. Said, and the numbers go back.
            context_.status(QString("Crop box: the %1 minimum (%2 mm) cannot be above its maximum (%3 mm)")
                                .arg(kAxes[i])
                                .arg(a.box.first[i])
                                .arg(a.box.second[i]));
            show_state();
            return;
        }
    }
    if (a == state()) return;
    edit(what, a, true); // a run of steps of one number: one undo step
}

// The presets: for a volume CT's presets do not fit (core::ct_in_hu), the
// default made from its value range first and the CT presets listed but
// disabled, saying why; then "custom".
void VolumePanel::fill_presets() {
    preset_->clear();
    if (!ct_) preset_->addItem("default (value range)");
    auto* model = qobject_cast<QStandardItemModel*>(preset_->model());
    for (const auto& name : transfer_function_presets()) {
        preset_->addItem(QString::fromStdString(name));
        if (ct_) continue;
        model->item(preset_->count() - 1)->setEnabled(false);
        model->item(preset_->count() - 1)->setToolTip("For CT in Hounsfield units; this volume's values are not HU");
    }
    preset_->addItem("custom");
}

void VolumePanel::preset_chosen(int index) {
    if (showing_ || index < 0 || index == preset_->count() - 1) return;
    VolumeState a = state();
    const QString name = preset_->itemText(index);
    if (!ct_ && index == 0)
        a.look.tf = core::initial_transfer_function(context_.workspace.scene());
    else
        a.look.tf = transfer_function_from(name.toStdString());
    if (a == state()) return;
    edit("Volume preset " + name, a);
}

// New data: the presets that fit it, the crop box's ranges, the histogram.
void VolumePanel::new_data() {
    const core::Scene& scene = context_.workspace.scene();
    ct_ = core::ct_in_hu(scene);
    const Bounds b = scene.has_volume() ? scene.volume_bounds() : Bounds{};
    volume_box_ = b.empty() ? std::pair{glm::dvec3(0.0), glm::dvec3(0.0)} : std::pair{b.min, b.max};
    box_ = volume_box_;
    for (int i = 0; i < 6; ++i) {
        const int a = i % 3;
        const double margin = std::max(1.0, volume_box_.second[a] - volume_box_.first[a]);
        spins_[std::size_t(i)]->blockSignals(true);
        spins_[std::size_t(i)]->setRange(volume_box_.first[a] - margin, volume_box_.second[a] + margin);
        spins_[std::size_t(i)]->blockSignals(false);
    }
    fill_presets();
    make_histogram();
}

// Counts over the volume's value range from a regular subsample of at
// most 2 M voxels (core::value_histogram), as a quiet job: on a 2 GiB volume its
// samples are cache misses all over memory (20-40 ms of the GUI thread at
// each open, gui_massive_bench). The editor shows none until it arrives; a
// newer volume's histogram wins.
void VolumePanel::make_histogram() {
    const std::uint64_t generation = ++histogram_generation_;
    const core::Scene& scene = context_.workspace.scene();
    editor_->set_histogram({}, 0, 1);
    if (!scene.has_volume()) return;
    const ValueRange r = scene.value_range();
    const double lo = r.min, hi = r.min + (r.max > r.min ? r.max - r.min : 1.0);
    // Shared, never changed in place: the job reads it while the scene may move on.
    std::shared_ptr<const Volume> volume = scene.snapshot().volume;
    auto counts = std::make_shared<std::vector<double>>();
    context_.jobs.run(
        "Histogram",
        [volume, lo, hi, counts](const ProgressFn&) { *counts = core::value_histogram(*volume, lo, hi, kBins); },
        [this, generation, lo, hi, counts](std::exception_ptr failed) {
            if (!failed && generation == histogram_generation_) editor_->set_histogram(std::move(*counts), lo, hi);
        },
        Jobs::Options{false, true});
}

void VolumePanel::set_state(const VolumeState& s) {
    box_ = s.box;
    FrameLook l = context_.workspace.look();
    l.volume = s.look;
    l.clip = s.clip();
    context_.workspace.set_look(l);
}

// The widgets from the workspace's look (no edits while they are set).
void VolumePanel::show_state() {
    const VolumeState st = state();
    showing_ = true;
    show_->setChecked(st.look.enabled);
    mode_->setCurrentIndex(int(st.look.mode));
    int preset = preset_->count() - 1; // custom
    for (int i = 0; i + 1 < preset_->count(); ++i) {
        const TransferFunction tf = !ct_ && i == 0 ? core::initial_transfer_function(context_.workspace.scene())
                                                   : transfer_function_from(preset_->itemText(i).toStdString());
        if (tf == st.look.tf) preset = i;
    }
    preset_->setCurrentIndex(preset);
    if (!showing_tf_) editor_->set_tf(st.look.tf); // not under the editor's own drag
    crop_->setChecked(st.crop);
    for (int i = 0; i < 3; ++i) {
        spins_[std::size_t(i)]->setValue(st.box.first[i]);
        spins_[std::size_t(i + 3)]->setValue(st.box.second[i]);
    }
    showing_ = false;
}

void VolumePanel::edit(const QString& text, VolumeState after, bool merge) {
    box_ = after.box;
    FrameLook l = context_.workspace.look();
    l.volume = after.look;
    l.clip = after.clip();
    context_.edit(
        text, core::Parts(core::Part::Look), [&] { context_.workspace.set_look(l); },
        merge ? "volume " + text : QString());
}

} // namespace iso::gui
