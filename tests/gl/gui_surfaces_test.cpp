// The Surfaces panel (docs/gui.md "Surfaces panel") driven
// in-process through QTest in a real X server (CTest runs this program under
// xvfb-run; it skips without a display). Expected values come from the core API
// (extract_isosurface, postprocess, measure_surface), not from the panel.
#include <QApplication>
#include <QCheckBox>
#include <QColorDialog>
#include <QDoubleSpinBox>
#include <QMessageBox>
#include <QProgressDialog>
#include <QPushButton>
#include <QSlider>
#include <QStatusBar>
#include <QTest>
#include <QTimer>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "app/gui/files.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/viewer.hpp"
#include "io/color.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/postprocess.hpp"
#include "gui_test_util.hpp"

using namespace iso;

namespace {
using test::add_through_panel;
using test::wait_until;

using test::child;

// A frame drawn after now, without error.
void expect_new_frame(gui::MainWindow& w, int frames_before) {
    ASSERT_NE(w.viewer(), nullptr);
    ASSERT_TRUE(
        wait_until([&] { return w.viewer()->frames() > frames_before || !w.viewer()->error().empty(); }, 60000));
    EXPECT_TRUE(w.viewer()->error().empty()) << w.viewer()->error();
}

// Answers the next colour dialog (QColorDialog::getColor runs its own event
// loop): `shown` gets the colour it opened with; then it picks `pick`, or is
// cancelled when `pick` is not valid.
void answer_colour_dialog(QWidget& owner, const QColor& pick, QString& shown) {
    auto* timer = new QTimer(&owner);
    QObject::connect(timer, &QTimer::timeout, timer, [timer, pick, &shown] {
        auto* dialog = qobject_cast<QColorDialog*>(QApplication::activeModalWidget());
        if (!dialog || !dialog->isVisible()) return;
        timer->stop();
        timer->deleteLater();
        shown = dialog->currentColor().name();
        if (pick.isValid()) {
            dialog->setCurrentColor(pick);
            dialog->accept();
        } else {
            dialog->reject();
        }
    });
    timer->start(20);
}

// A 512 x 512 x 400 int16 CT-sized volume (a ball of 1000 in 0, a linear
// ramp across its surface), written raw: extracting it takes long enough to
// press Cancel (the range index alone reads all 200 MB).
std::string big_volume(const std::filesystem::path& dir) {
    auto v = Volume::dense({512, 512, 400}, VoxelType::I16, make_affine({0.7, 0.7, 1.0}, {0, 0, 0}));
    std::int16_t* s = v.as<std::int16_t>().data(); // zero-filled; only the ball's box is written
    for (std::int64_t k = 73; k < 328; ++k)
        for (std::int64_t j = 75; j < 437; ++j) {
            std::int16_t* row = s + v.linear_index(0, j, k);
            const double jk = (j - 256.0) * (j - 256.0) + (k - 200.0) * (k - 200.0) * 2.0;
            for (std::int64_t i = 75; i < 437; ++i) {
                const double r = std::sqrt((i - 256.0) * (i - 256.0) + jk);
                row[i] = std::int16_t(std::clamp((180.0 - r) * 50.0, 0.0, 1000.0));
            }
        }
    const std::string path = (dir / "big.nrrd").string();
    save_volume(v, path, /*compress=*/false);
    return path;
}
} // namespace

TEST(GuiSurfaces, AddOpacitySliderLargestRemoveAndCancel) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_surfaces_test", dir / "config");
    const auto out = test::output_dir("gui_surfaces");

    gui::MainWindow w;
    w.resize(1500, 1000);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    auto* panel = w.surfaces_panel();
    ASSERT_NE(panel, nullptr);

    const std::string headsq = test::data("headsq.nhdr");
    w.open_path(QString::fromStdString(headsq));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    ASSERT_TRUE(w.scene().has_volume());
    const Volume& v = w.scene().volume();

    // ---- add skin (500) and bone (1150) through the panel's Add button
    add_through_panel(w, 500);
    add_through_panel(w, 1150);
    const auto ids = w.scene().surfaces();
    ASSERT_EQ(ids.size(), 2u) << w.statusBar()->currentMessage().toStdString();
    const auto skin = ids[0], bone = ids[1];
    EXPECT_EQ(w.scene().info(skin).value, 500.0);
    EXPECT_EQ(w.scene().info(bone).value, 1150.0);
    EXPECT_EQ(w.scene().info(skin).kind, core::SurfaceInfo::Kind::Iso);
    EXPECT_EQ(w.scene().mesh(skin).triangles.size(), extract_isosurface(v, 500).triangles.size());
    EXPECT_EQ(w.scene().mesh(bone).triangles.size(), extract_isosurface(v, 1150).triangles.size());
    ASSERT_NE(panel->row(skin), nullptr);
    ASSERT_NE(panel->row(bone), nullptr);
    expect_new_frame(w, 0);

    // ---- skin opacity 0.3 through its row's slider
    auto* opacity = child<QSlider>(panel->row(skin), "opacity");
    ASSERT_NE(opacity, nullptr);
    opacity->setValue(30);
    EXPECT_FLOAT_EQ(w.scene().info(skin).opacity, 0.3f);
    EXPECT_FLOAT_EQ(w.scene().info(bone).opacity, 1.0f);
    expect_new_frame(w, w.viewer()->frames());
    QTest::qWait(100);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "skin_0.3_bone.png").string())));

    // ---- move skin's iso slider: 550, 580, 600 in quick succession (a drag)
    auto* slider = child<QSlider>(panel->row(skin), "iso_slider");
    auto* number = child<QDoubleSpinBox>(panel->row(skin), "iso_value");
    ASSERT_NE(slider, nullptr);
    ASSERT_NE(number, nullptr);
    // The slider spans the volume's values.
    const auto range = v.value_range();
    EXPECT_EQ(number->minimum(), range.min);
    EXPECT_EQ(number->maximum(), range.max);
    EXPECT_EQ(number->value(), 500.0);
    const std::size_t skin_tris_500 = w.scene().mesh(skin).triangles.size();
    const int swaps = panel->swaps();
    // headsq's values 0..3926: slider steps of 5, the round step nearest a
    // thousandth of the range (docs/gui.md, "Surfaces panel").
    const int at500 = slider->value();
    for (int d : {10, 16, 20}) slider->setValue(at500 + d);
    EXPECT_EQ(number->value(), 600.0) << "the number follows the slider";
    // Not done on the GUI thread: the old surface is still the scene's until the swap.
    EXPECT_TRUE(panel->reextracting(skin));
    EXPECT_EQ(w.scene().info(skin).value, 500.0);
    EXPECT_EQ(w.scene().mesh(skin).triangles.size(), skin_tris_500);
    int frames = w.viewer()->frames();
    ASSERT_TRUE(wait_until([&] { return !panel->reextracting(); }, 60000)) << "the re-extraction did not end";
    EXPECT_EQ(panel->swaps(), swaps + 1) << "only the latest value is swapped in";
    EXPECT_EQ(w.scene().info(skin).value, 600.0);
    EXPECT_EQ(w.scene().info(skin).name, "iso 600");
    EXPECT_FLOAT_EQ(w.scene().info(skin).opacity, 0.3f) << "the row's settings stay";
    {
        const Mesh fresh = extract_isosurface(v, 600);
        const Mesh& shown = w.scene().mesh(skin);
        EXPECT_EQ(shown.triangles.size(), fresh.triangles.size());
        EXPECT_NEAR(measure_surface(shown).area_mm2, measure_surface(fresh).area_mm2,
                    1e-6 * measure_surface(fresh).area_mm2);
    }
    expect_new_frame(w, frames);

    // ---- the number box moves the slider and re-extracts too
    number->setValue(650);
    EXPECT_EQ(slider->value(), at500 + 30);
    ASSERT_TRUE(wait_until([&] { return !panel->reextracting(); }, 60000));
    EXPECT_EQ(w.scene().info(skin).value, 650.0);
    EXPECT_EQ(w.scene().mesh(skin).triangles.size(), extract_isosurface(v, 650).triangles.size());

    // ---- keep-largest on the bone: one component, as the core's post-processing gives
    {
        const Mesh raw = extract_isosurface(v, 1150);
        ASSERT_GT(measure_surface(raw).components.size(), 1u) << "headsq's bone has islands";
        PostProcessOptions largest;
        largest.keep_largest = true;
        const Mesh expected = postprocess(raw, largest);
        auto* keep = child<QCheckBox>(panel->row(bone), "keep_largest");
        ASSERT_NE(keep, nullptr);
        frames = w.viewer()->frames();
        keep->setChecked(true);
        ASSERT_TRUE(wait_until([&] { return !panel->reextracting(); }, 60000));
        EXPECT_TRUE(w.scene().info(bone).post.keep_largest);
        EXPECT_EQ(measure_surface(w.scene().mesh(bone)).components.size(), 1u);
        EXPECT_EQ(w.scene().mesh(bone).triangles.size(), expected.triangles.size());
        expect_new_frame(w, frames);
    }
    QTest::qWait(100);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "skin_650_bone_largest.png").string())));

    // ---- remove the bone: gone from the scene and the panel; the skin keeps its id
    frames = w.viewer()->frames();
    auto* remove = child<QPushButton>(panel->row(bone), "remove");
    ASSERT_NE(remove, nullptr);
    QTest::mouseClick(remove, Qt::LeftButton);
    EXPECT_EQ(w.scene().surfaces(), (std::vector<core::SurfaceId>{skin}));
    EXPECT_FALSE(w.scene().has_surface(bone));
    EXPECT_EQ(panel->row(bone), nullptr);
    expect_new_frame(w, frames);
    QTest::qWait(100);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "bone_removed.png").string())));
    std::printf("screenshots: %s\n", out.c_str());

    // ---- a new file while a re-extraction runs: the worker stops before the
    // old scene goes, its result is dropped, the new scene starts without rows
    {
        const core::Scene* old_scene = &w.scene();
        slider->setValue(at500 + 300);
        ASSERT_TRUE(panel->reextracting(skin));
        w.open_path(QString::fromStdString(headsq));
        ASSERT_TRUE(wait_until([&] { return &w.scene() != old_scene && !w.busy(); }, 60000))
            << "the load did not finish";
        EXPECT_FALSE(panel->reextracting());
        EXPECT_EQ(panel->row(skin), nullptr);
        EXPECT_TRUE(w.scene().surfaces().empty());
        QTest::qWait(100); // a late result of the old scene's worker would arrive here
        EXPECT_TRUE(w.scene().surfaces().empty());
    }

    // ---- cancel a long extraction: no surface, no error dialog, the window usable
    const std::string big = big_volume(dir.path());
    w.open_path(QString::fromStdString(big));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    ASSERT_EQ(w.scene().volume().dims, (std::array<std::int64_t, 3>{512, 512, 400}));
    EXPECT_TRUE(w.scene().surfaces().empty());
    w.surfaces_panel()->add_surface(500);
    ASSERT_TRUE(w.busy());
    QProgressDialog* progress = nullptr;
    for (auto* d : w.findChildren<QProgressDialog*>("progress"))
        if (d->labelText().contains("Extracting")) progress = d;
    ASSERT_NE(progress, nullptr);
    auto* cancel = progress->findChild<QPushButton*>();
    ASSERT_NE(cancel, nullptr);
    cancel->click(); // the dialog's Cancel button
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 30000)) << "the cancelled extraction did not stop";
    EXPECT_TRUE(w.scene().surfaces().empty()) << "a cancelled extraction added a surface";
    EXPECT_TRUE(w.statusBar()->currentMessage().contains("cancelled")) << w.statusBar()->currentMessage().toStdString();
    QTest::qWait(100);
    EXPECT_EQ(w.findChild<QMessageBox*>("error"), nullptr) << "an error dialog for a cancel";
    // Usable: a click in a slice view answers.
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    QTest::mouseClick(axial, Qt::LeftButton, {}, QPoint(axial->width() / 2, axial->height() / 2));
    EXPECT_EQ(w.statusBar()->currentMessage().left(5), "LPS (");
}

// A colour picked in a row's colour dialog is the colour the scene shades
// with in linear light (the sRGB transfer, not a gamma curve), opens the
// dialog again as the same colour, and is saved in a session as picked.
TEST(GuiSurfaces, PickedColourIsStoredAndSavedAsPicked) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_surfaces_test", dir / "config");
    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(test::data("headsq.nhdr")));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    add_through_panel(w, 1150);
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    const auto id = w.scene().surfaces()[0];
    auto* button = child<QPushButton>(w.surfaces_panel()->row(id), "color");
    ASSERT_NE(button, nullptr);

    QString shown;
    answer_colour_dialog(w, QColor("#1a1a1a"), shown);
    QTest::mouseClick(button, Qt::LeftButton);
    ASSERT_TRUE(wait_until([&] { return !shown.isEmpty(); }, 10000)) << "no colour dialog";
    const float linear = float(linear_from_srgb(0x1a / 255.0));
    EXPECT_NEAR(linear, 0.0103298, 1e-7); // the published sRGB curve at 26/255
    EXPECT_EQ(w.scene().info(id).color, glm::vec3(linear));
    EXPECT_TRUE(button->styleSheet().contains("#1a1a1a")) << button->styleSheet().toStdString();

    // Opened again it starts from the colour picked; Cancel leaves it.
    shown.clear();
    answer_colour_dialog(w, QColor(), shown);
    QTest::mouseClick(button, Qt::LeftButton);
    ASSERT_TRUE(wait_until([&] { return !shown.isEmpty(); }, 10000)) << "no colour dialog";
    EXPECT_EQ(shown.toStdString(), "#1a1a1a");
    EXPECT_EQ(w.scene().info(id).color, glm::vec3(linear));

    const std::string session = dir / "picked.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    std::ifstream in(session);
    ASSERT_TRUE(in) << w.statusBar()->currentMessage().toStdString();
    const auto j = nlohmann::json::parse(in);
    ASSERT_EQ(j.at("surfaces").size(), 1u);
    EXPECT_EQ(j["surfaces"][0].at("color"), "#1a1a1a");
}

// An iso value between two integers, the usual choice on integer voxels
// (no voxel sits on it): the row shows it as it is (300.5 once read 301),
// and leaving its box (which extracts a changed value again) changes
// nothing.
TEST(GuiSurfaces, AHalfwayIsoValueOnIntegerVoxelsIsShownAsItIs) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_surfaces_test", dir / "config");
    gui::MainWindow w;
    w.resize(1500, 1000);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(test::data("headsq.nhdr")));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    add_through_panel(w, 500.5);
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    const auto id = w.scene().surfaces()[0];
    EXPECT_EQ(w.scene().info(id).value, 500.5);
    auto* number = child<QDoubleSpinBox>(w.surfaces_panel()->row(id), "iso_value");
    ASSERT_NE(number, nullptr);
    EXPECT_EQ(number->value(), 500.5);
    EXPECT_TRUE(number->text().startsWith("500.5")) << number->text().toStdString();
    const int swaps = w.surfaces_panel()->swaps();
    emit number->editingFinished();
    QTest::qWait(50);
    EXPECT_FALSE(w.surfaces_panel()->reextracting(id));
    EXPECT_EQ(w.surfaces_panel()->swaps(), swaps);
    EXPECT_EQ(w.scene().info(id).value, 500.5);
}
