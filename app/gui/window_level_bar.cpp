#include "app/gui/window_level_bar.hpp"

#include <QComboBox>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QStandardItemModel>

#include <cmath>

#include "app/gui/app_context.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

namespace {
// The CT presets are in Hounsfield units: for a volume without that unit
// (core::value_unit) they stay listed but disabled, saying why.
void enable_ct_window_presets(QComboBox* combo, bool hu) {
    auto* model = qobject_cast<QStandardItemModel*>(combo->model());
    for (int i = 1; i + 1 < combo->count(); ++i) {
        model->item(i)->setEnabled(hu);
        model->item(i)->setToolTip(hu ? QString() : "For CT in Hounsfield units; this volume's values have no unit");
    }
}

// The entry that names window `w`: "default" (the volume's default window),
// a CT preset (HU volumes only), else "custom" (the last entry).
int window_preset_index(const QComboBox* combo, const core::WindowLevel& w, const core::Scene& scene) {
    const auto same = [&w](const core::WindowLevel& o) {
        return std::abs(o.center - w.center) < 0.05 && std::abs(o.width - w.width) < 0.05;
    };
    if (!scene.has_volume()) return 0;
    if (same(core::default_window(scene))) return 0;
    if (!core::value_unit(scene).empty()) {
        const auto presets = core::ct_window_presets();
        for (std::size_t i = 0; i < presets.size(); ++i)
            if (same(presets[i].window)) return int(i) + 1;
    }
    return combo->count() - 1;
}
} // namespace

WindowLevelBar::WindowLevelBar(AppContext& context, QWidget* parent)
    : QToolBar("Window/level", parent), context_(context) {
    setObjectName("window_level");
    addWidget(new QLabel(" Window: "));
    preset_ = new QComboBox(this);
    preset_->setObjectName("window_preset");
    preset_->setToolTip("Window presets of the slice views (CT ones for volumes in HU); 'custom': set by hand");
    preset_->addItem("default");
    for (const auto& p : core::ct_window_presets())
        preset_->addItem(QString("%1 (W %2 / L %3)")
                             .arg(QString::fromUtf8(p.name.data(), qsizetype(p.name.size())))
                             .arg(p.window.width)
                             .arg(p.window.center));
    preset_->addItem("custom"); // numbers set by hand or a drag
    addWidget(preset_);
    addWidget(new QLabel(" Level (center): "));
    center_ = new QDoubleSpinBox(this);
    center_->setObjectName("window_center");
    center_->setToolTip("Window level: the value shown mid-grey (a left drag up or down in a slice view changes it)");
    center_->setRange(-1e6, 1e6);
    center_->setDecimals(1);
    addWidget(center_);
    addWidget(new QLabel(" Width: "));
    width_ = new QDoubleSpinBox(this);
    width_->setObjectName("window_width");
    width_->setToolTip("Window width: the range of values from black to white (a left drag left or right changes it)");
    width_->setRange(0, 2e6);
    width_->setDecimals(1);
    addWidget(width_);
    connect(preset_, &QComboBox::currentIndexChanged, this, [this](int index) {
        if (showing_ || index < 0 || index == preset_->count() - 1) return;
        const core::Scene& scene = context_.workspace.scene();
        if (index == 0) {
            if (scene.has_volume()) context_.workspace.set_window(core::default_window(scene));
            return;
        }
        context_.workspace.set_window(core::ct_window_presets()[std::size_t(index - 1)].window);
    });
    const auto spin_changed = [this] {
        if (!showing_) context_.workspace.set_window({center_->value(), width_->value()});
    };
    connect(center_, &QDoubleSpinBox::valueChanged, this, spin_changed);
    connect(width_, &QDoubleSpinBox::valueChanged, this, spin_changed);
    observer_ = context_.workspace.observe([this](core::Parts p) { watched(p); });
    show_window();
}

WindowLevelBar::~WindowLevelBar() { context_.workspace.unobserve(observer_); }

void WindowLevelBar::watched(core::Parts parts) {
    if (core::has(parts, core::Part::Data))
        enable_ct_window_presets(preset_, !core::value_unit(context_.workspace.scene()).empty());
    if (parts & (core::Part::Data | core::Part::Window)) show_window();
}

void WindowLevelBar::show_window() {
    const core::WindowLevel& w = context_.workspace.window();
    showing_ = true;
    center_->setValue(w.center);
    width_->setValue(w.width);
    preset_->setCurrentIndex(window_preset_index(preset_, w, context_.workspace.scene()));
    showing_ = false;
}

} // namespace iso::gui
