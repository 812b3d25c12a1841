// The Volume panel of the main window (docs/gui.md "Volume panel"), like
// 3D Slicer's Volume Rendering module: "Show volume", a transfer-function
// preset (the CT presets; for a volume that is not CT also a default made
// from its value range), the mode (Composite, MIP, MinIP), the transfer
// function editor (tf_editor.hpp) over the volume's histogram, and a crop
// box (LPS mm) that cuts surfaces and volume alike. It shows the
// workspace's look (its volume and crop box) and each of its changes is an
// edit of it (one undo step; a spin box's run of steps merges into one).
// Which presets fit is the core's rule (core/presets.hpp).
#pragma once

#include <array>
#include <cstdint>
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

#include "renderer/core/workspace.hpp"

namespace iso::gui {

class AppContext;
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
    VolumePanel(AppContext& context, QWidget* parent = nullptr);
    ~VolumePanel() override;

    // The workspace's volume look and crop box (the box kept while cropping is off).
    VolumeState state() const;
    // Sets it in the workspace without an undo step (a script, a test).
    void set_state(const VolumeState& s);
    // CT's presets fit the volume (core::ct_in_hu).
    bool ct() const { return ct_; }
    TfEditor* editor() const { return editor_; }

private:
    QWidget* make_look_rows();
    QWidget* make_crop_rows();
    void fill_presets();
    void show_state();
    void edit(const QString& text, VolumeState after, bool merge = false);
    void preset_chosen(int index);
    void crop_spin_changed(const QString& what);
    void make_histogram();
    void new_data();

    AppContext& context_;
    int observer_ = 0;
    std::pair<glm::dvec3, glm::dvec3> box_{glm::dvec3(0.0), glm::dvec3(0.0)}; // the box while cropping is off
    bool ct_ = false;
    std::uint64_t histogram_generation_ = 0; // the latest histogram asked for (make_histogram)
    bool showing_ = false;                   // the widgets are being set from the workspace: no edits
    bool showing_tf_ = false;                // the editor's own change: it shows it already
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
