// The Volume panel of the main window (docs/gui.md "Volume panel"), like
// 3D Slicer's Volume Rendering module: "Show volume", a transfer-function
// preset (the CT presets; for a volume that is not CT also a default made
// from its value range), the mode (Composite, MIP, MinIP), the transfer
// function editor (tf_editor.hpp) over the volume's histogram, and a crop
// box (LPS mm) that cuts surfaces and volume alike. Presentation only: it
// holds the 3D view's VolumeLook and Clip; the window applies them to the
// view and makes each edit an undo step.
#pragma once

#include <array>
#include <functional>
#include <utility>

#include <QString>
#include <QWidget>

#include <glm/vec3.hpp>

#include "renderer/volume/transfer_function.hpp"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QPushButton;

namespace iso::core {
class Scene;
}

namespace iso::gui {

class TfEditor;

// What the panel edits and an undo step restores: the volume's look and
// the crop box, with the box kept while cropping is off.
struct VolumeState {
    VolumeLook look;
    bool crop = false;
    std::pair<glm::dvec3, glm::dvec3> box{glm::dvec3(0.0), glm::dvec3(0.0)}; // LPS min, max
    // The clip it gives the frame: the box while cropping, else none.
    Clip clip() const;
    bool operator==(const VolumeState&) const = default;
};

class VolumePanel : public QWidget {
public:
    explicit VolumePanel(QWidget* parent = nullptr);

    // A new scene (null: none): the volume off, its default transfer
    // function, the crop box the volume's box, the histogram made.
    void set_scene(const core::Scene* scene);
    const VolumeState& state() const { return state_; }
    // Shows `s` in the widgets and reports it through `changed` (an undo
    // step, a session).
    void set_state(const VolumeState& s);
    // The transfer function a new volume starts with: "bone" for CT in HU,
    // else default_tf(range).
    TransferFunction initial_tf() const;
    // For values [lo, hi] that are not CT: transparent below a third of the
    // range, rising to a faint warm colour and to opaque white at the top.
    static TransferFunction default_tf(double lo, double hi);
    // The volume is CT in HU with HU-like values: the CT presets fit it.
    bool ct() const { return ct_; }
    TfEditor* editor() const { return editor_; }

    // The state changed (apply it to the 3D view).
    std::function<void(const VolumeState&)> changed;
    // An edit by the user, already shown: one undo step from `before`.
    // `merge`: consecutive edits with the same text may become one step.
    std::function<void(const QString& text, const VolumeState& before, const VolumeState& after, bool merge)> edited;

private:
    QWidget* make_look_rows();
    QWidget* make_crop_rows();
    void fill_presets();
    void show_state();
    void edit(const QString& text, VolumeState after, bool merge = false);
    void preset_chosen(int index);
    void crop_spin_changed(const QString& what);
    void make_histogram();

    const core::Scene* scene_ = nullptr;
    VolumeState state_;
    bool ct_ = false;
    bool showing_ = false; // the widgets are being set from state_: no edits
    std::pair<glm::dvec3, glm::dvec3> volume_box_{glm::dvec3(0.0), glm::dvec3(0.0)};
    QCheckBox* show_ = nullptr;
    QComboBox* preset_ = nullptr;
    QComboBox* mode_ = nullptr;
    TfEditor* editor_ = nullptr;
    QCheckBox* crop_ = nullptr;
    std::array<QDoubleSpinBox*, 6> spins_{}; // L, P, S min; L, P, S max
    QPushButton* fit_ = nullptr;
};

} // namespace iso::gui
