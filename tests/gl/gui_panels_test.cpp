// The desktop app's panels and defaults as a new user meets them (docs/gui.md):
// the Surfaces dock scrolling instead of growing the window, the iso number
// kept within the volume's values, the 3D view framing its first surface, the
// series chooser's pre-selection and one DICOM file opening its series, the
// 3D view's hint and the window/level and iso presets following the data, the
// iso slider's steps and the opacity number, and where files are saved.
// Driven in-process through QTest in a real X server (CTest runs this program
// under xvfb-run; it skips without a display). Expected values come from the
// core API (value_range, list_series, Scene::camera, extract_isosurface) or are
// computed here, not read from the widgets.
#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QDir>
#include <QFileInfo>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QLineEdit>
#include <QStandardPaths>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QScreen>
#include <QScrollArea>
#include <QScrollBar>
#include <QSlider>
#include <QSpinBox>
#include <QStandardItemModel>
#include <QStatusBar>
#include <QTableWidget>
#include <QTest>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "app/gui/export_dialog.hpp"
#include "app/gui/load_warnings.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/series_dialog.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/viewer.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/surface/extract.hpp"
#include "gui_test_util.hpp"
#include "tests/support/dicom_fixtures.hpp"

using namespace iso;
namespace fs = std::filesystem;

namespace {
using test::add_through_panel;
using test::wait_until;

// A 33^3 uint8 ball: 229 at the centre voxel, falling to 0 at radius 16 and
// beyond (the values 0..229, no unit).
std::string ball_volume(const fs::path& dir) {
    auto v = Volume::dense({33, 33, 33}, VoxelType::U8, make_affine({1.0, 1.0, 1.0}, {0, 0, 0}));
    std::uint8_t* s = v.as<std::uint8_t>().data();
    for (int k = 0; k < 33; ++k)
        for (int j = 0; j < 33; ++j)
            for (int i = 0; i < 33; ++i) {
                const double r = std::sqrt(double((i - 16) * (i - 16) + (j - 16) * (j - 16) + (k - 16) * (k - 16)));
                s[v.linear_index(i, j, k)] = std::uint8_t(std::lround(229.0 * std::max(0.0, 1.0 - r / 16.0)));
            }
    const std::string path = (dir / "ball.nrrd").string();
    save_volume(v, path);
    return path;
}

void open_and_wait(gui::MainWindow& w, const std::string& path) {
    w.open_path(QString::fromStdString(path));
    ASSERT_TRUE(wait_until([&] { return !w.busy() && w.scene().has_volume(); }, 60000))
        << "not opened: " << w.statusBar()->currentMessage().toStdString();
}

// Whether entry `i` of a combo box can be chosen.
bool item_enabled(QComboBox* combo, int i) {
    return qobject_cast<QStandardItemModel*>(combo->model())->item(i)->isEnabled();
}

QAction* file_action(gui::MainWindow& w, const QString& text) {
    for (QAction* a : w.menuBar()->actions())
        if (a->menu())
            for (QAction* b : a->menu()->actions())
                if (b->text() == text) return b;
    return nullptr;
}

template <class T> T* visible_child(QWidget& w, const char* name) {
    for (auto* d : w.findChildren<T*>(name))
        if (d->isVisible()) return d;
    return nullptr;
}

// Closes the error box the window shows, returning its text (empty: none came).
QString take_error_box(gui::MainWindow& w) {
    QMessageBox* box = nullptr;
    if (!wait_until([&] { return (box = visible_child<QMessageBox>(w, "error")) != nullptr; }, 30000)) return {};
    const QString text = box->text();
    box->close();
    QTest::qWait(50);
    return text;
}
} // namespace

// Eight surfaces: the Surfaces dock scrolls, the window keeps its size (the
// status bar and the Measurements dock stay on it), and removing surfaces
// leaves it so.
TEST(GuiPanels, SurfaceListScrollsAndTheWindowKeepsItsSize) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const std::string ball = ball_volume(dir.path());

    gui::MainWindow w;
    const QRect screen = QApplication::primaryScreen()->availableGeometry();
    w.resize(std::min(1280, screen.width()), std::min(900, screen.height()));
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_and_wait(w, ball);
    QTest::qWait(100);
    const int height = w.height();
    ASSERT_NE(w.surfaces_panel()->findChild<QScrollArea*>("surface_list"), nullptr);

    for (int i = 0; i < 8; ++i) add_through_panel(w, 20.0 + 25.0 * i);
    ASSERT_EQ(w.scene().surfaces().size(), 8u);
    QTest::qWait(200);
    EXPECT_LE(w.height(), height) << "the window grew with the surfaces";
    EXPECT_LE(w.frameGeometry().height(), std::max(screen.height(), height + 100));
    EXPECT_TRUE(w.statusBar()->isVisible());
    EXPECT_LE(w.statusBar()->geometry().bottom(), w.height());
    auto* measurements = w.findChild<QDockWidget*>("measurements");
    if (measurements) EXPECT_GT(measurements->height(), 50);
    const auto out = test::output_dir("gui_panels");
    EXPECT_TRUE(w.grab().save(QString::fromStdString((out / "eight_surfaces.png").string())));

    // ---- the last row is reachable: the list scrolls to it
    auto* scroll = w.surfaces_panel()->findChild<QScrollArea*>("surface_list");
    QWidget* last = w.surfaces_panel()->row(w.scene().surfaces().back());
    ASSERT_NE(last, nullptr);
    // (Once the list's layout has placed the last row: it runs from posted events.)
    const auto in_view = [&] { return QRect(last->mapTo(scroll->viewport(), QPoint(0, 0)), last->size()); };
    EXPECT_TRUE(wait_until(
        [&] {
            scroll->ensureWidgetVisible(last);
            return scroll->viewport()->rect().intersects(in_view());
        },
        5000))
        << "the last row is not scrolled into view: row at " << in_view().y() << ".." << in_view().bottom()
        << ", view 0.." << scroll->viewport()->height() << ", scrolled " << scroll->verticalScrollBar()->value()
        << " of " << scroll->verticalScrollBar()->maximum();
    EXPECT_GT(scroll->verticalScrollBar()->maximum(), 0) << "eight rows fit without scrolling?";
    EXPECT_GT(scroll->verticalScrollBar()->value(), 0);

    // ---- removing four: the window stays within its size
    for (int i = 0; i < 4; ++i) {
        QWidget* row = w.surfaces_panel()->row(w.scene().surfaces().front());
        QTest::mouseClick(row->findChild<QPushButton*>("remove"), Qt::LeftButton);
        QTest::qWait(50);
    }
    ASSERT_EQ(w.scene().surfaces().size(), 4u);
    QTest::qWait(200);
    EXPECT_LE(w.height(), height);
}

// A volume of values 0..229 (no unit): the iso number keeps within them, the
// presets outside them and the HU ones are disabled, and adding 500 is
// refused with a message naming the file, adding nothing.
TEST(GuiPanels, IsoValueStaysWithinTheVolumesValues) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const std::string ball = ball_volume(dir.path());
    const ValueRange range = load_volume(ball).value_range();
    ASSERT_EQ(range.min, 0.0);
    ASSERT_EQ(range.max, 229.0);

    gui::MainWindow w;
    w.resize(1280, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    auto* iso = w.surfaces_panel()->findChild<QDoubleSpinBox*>("add_iso_value");
    ASSERT_NE(iso, nullptr);
    iso->setValue(500); // as the user left it before opening
    open_and_wait(w, ball);
    EXPECT_EQ(iso->minimum(), range.min);
    EXPECT_EQ(iso->maximum(), range.max);
    EXPECT_GE(iso->value(), range.min);
    EXPECT_LE(iso->value(), range.max);
    iso->setValue(500);
    EXPECT_EQ(iso->value(), range.max) << "typed 500 is kept to the volume's values";

    // Presets (core::iso_presets, one rule with the Volume panel): the HU
    // ones are for CT, listed but disabled, saying why; the ones made from
    // this volume's own histogram (Otsu) come first, within its values, and
    // none is named after a dataset.
    auto* presets = w.surfaces_panel()->findChild<QComboBox*>("iso_preset");
    ASSERT_NE(presets, nullptr);
    ASSERT_GT(presets->count(), 4);
    auto* model = qobject_cast<QStandardItemModel*>(presets->model());
    int own = 0;
    for (int i = 0; i < presets->count(); ++i) {
        const QString text = presets->itemText(i);
        EXPECT_FALSE(text.contains("headsq")) << text.toStdString();
        if (text.contains(" HU")) {
            EXPECT_FALSE(item_enabled(presets, i)) << text.toStdString();
            EXPECT_TRUE(model->item(i)->toolTip().contains("Hounsfield")) << model->item(i)->toolTip().toStdString();
            continue;
        }
        ++own;
        EXPECT_TRUE(item_enabled(presets, i)) << text.toStdString();
        const double v = text.section(": ", -1).toDouble();
        EXPECT_GT(v, range.min) << text.toStdString();
        EXPECT_LT(v, range.max) << text.toStdString();
    }
    EXPECT_EQ(own, 2) << "the two-class and three-class Otsu thresholds";
    EXPECT_EQ(presets->currentIndex(), 0);

    // ---- adding 500 (the window's own call, as `isoscope view --iso` would) is refused
    w.surfaces_panel()->add_surface(500);
    EXPECT_FALSE(w.busy());
    const QString box = take_error_box(w);
    EXPECT_TRUE(box.contains("outside")) << box.toStdString();
    EXPECT_TRUE(box.contains(QString::fromStdString(ball))) << box.toStdString();
    EXPECT_TRUE(box.contains("229")) << box.toStdString();
    EXPECT_TRUE(w.scene().surfaces().empty());

    // ---- within the values it adds, as before
    add_through_panel(w, 100);
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    EXPECT_EQ(w.scene().mesh(w.scene().surfaces()[0]).triangles.size(),
              extract_isosurface(load_volume(ball), 100).triangles.size());
}

// The first surface with triangles frames the 3D view (as Reset view would:
// the scene's camera for the anterior view); a later surface leaves the
// user's camera where it is.
TEST(GuiPanels, FirstNonEmptySurfaceFramesThe3DView) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const std::string ball = ball_volume(dir.path());
    const Volume v = load_volume(ball);
    // An iso value that crosses no voxel edge: the first surface is empty.
    const double empty_iso = extract_isosurface(v, 0).triangles.empty() ? 0.0 : 229.0;
    ASSERT_TRUE(extract_isosurface(v, empty_iso).triangles.empty());

    gui::MainWindow w;
    w.resize(1280, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_and_wait(w, ball);
    add_through_panel(w, empty_iso);
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    ASSERT_NE(w.viewer(), nullptr);
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > 0; }, 30000));
    ASSERT_TRUE(w.scene().bounds().empty());

    add_through_panel(w, 100);
    int frames = w.viewer()->frames();
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > frames; }, 30000));
    const double aspect = double(w.viewer()->width()) / double(w.viewer()->height());
    const Camera expected = w.scene().camera(PatientView::Anterior, aspect);
    const Camera& c = w.viewer()->camera();
    const double tol = 1e-6 * w.scene().bounds().radius();
    EXPECT_LT(glm::length(c.eye - expected.eye), tol);
    EXPECT_LT(glm::length(c.target - expected.target), tol);
    EXPECT_LT(glm::length(c.up - expected.up), 1e-9);
    // The ball of iso 100 fills the view: its centre at the target.
    EXPECT_LT(glm::length(c.target - w.scene().bounds().center()), tol);

    // ---- the user's camera stays when another surface comes
    Camera moved = c;
    moved.orbit(30, 10);
    w.viewer()->set_camera(moved);
    add_through_panel(w, 50);
    frames = w.viewer()->frames();
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > frames; }, 30000));
    EXPECT_EQ(w.viewer()->camera().eye, moved.eye);
    EXPECT_EQ(w.viewer()->camera().target, moved.target);
}

namespace {
// A folder of two CT series: a 3-slice scout (series 1, listed first) and an
// 8-slice axial series (series 2).
struct TwoSeries {
    std::string folder;
    std::vector<SeriesInfo> list;
    int axial = -1;
};
TwoSeries write_two_series(const fs::path& dir) {
    TwoSeries t;
    t.folder = (dir / "study").string();
    test::SeriesSpec scout;
    scout.description = "scout";
    scout.series_number = 1;
    scout.nz = 3;
    scout.spacing = {0.7, 0.8, 20.0};
    scout.pattern = "%s/S-%04d.dcm";
    test::SeriesSpec axial;
    axial.description = "axial";
    axial.series_number = 2;
    axial.pattern = "%s/A-%04d.dcm";
    test::write_series(t.folder, scout);
    test::write_series(t.folder, axial);
    t.list = core::list_series(t.folder);
    for (int i = 0; i < int(t.list.size()); ++i)
        if (t.list[std::size_t(i)].description == "axial") t.axial = i;
    return t;
}
} // namespace

// The chooser pre-selects the series fit for 3D, not the scout listed first
// that it warns about; Enter opens that one.
TEST(GuiPanels, SeriesChooserPreselectsTheSeriesFor3D) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const TwoSeries t = write_two_series(dir.path());
    ASSERT_EQ(t.list.size(), 2u);
    ASSERT_NE(t.axial, -1);
    const int scout = 1 - t.axial;
    ASSERT_FALSE(t.list[std::size_t(scout)].for_3d);
    ASSERT_TRUE(t.list[std::size_t(t.axial)].for_3d);

    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(t.folder));
    gui::SeriesDialog* chooser = nullptr;
    ASSERT_TRUE(wait_until([&] { return (chooser = visible_child<gui::SeriesDialog>(w, "series_chooser")); }, 30000));
    const auto rows = chooser->table()->selectionModel()->selectedRows();
    ASSERT_EQ(rows.size(), 1);
    EXPECT_EQ(rows.front().row(), t.axial);
    EXPECT_TRUE(chooser->table()->item(scout, gui::SeriesDialog::Warnings)->text().contains("scout"));

    QTest::keyClick(chooser, Qt::Key_Return);
    ASSERT_TRUE(wait_until([&] { return !w.busy() && w.scene().has_volume(); }, 30000))
        << w.statusBar()->currentMessage().toStdString();
    EXPECT_EQ(w.scene().volume().dims[2], t.list[std::size_t(t.axial)].dims[2]);
    EXPECT_EQ(w.workspace().series(), t.list[std::size_t(t.axial)].uid);
}

// One .dcm file opens its whole series from its folder, by the file's UID.
TEST(GuiPanels, OneDicomFileOpensItsSeries) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const TwoSeries t = write_two_series(dir.path());
    ASSERT_NE(t.axial, -1);
    const std::string file = t.folder + "/A-0003.dcm";
    ASSERT_TRUE(fs::exists(file));
    ASSERT_EQ(core::list_series(file).size(), 1u);
    ASSERT_EQ(core::list_series(file)[0].dims[2], 1) << "the file alone is one slice";

    // A file in the folder that once aborted the DICOM reader (issue 42): skipped, and said so.
    const std::string crash =
        std::string(ISOSCOPE_SOURCE_DIR) +
        "/tests/fuzz/regressions/dicom/crash-dicom-crash-314510707ba2abecdd6ccdea964749af198ea78c";
    fs::copy_file(crash, t.folder + "/Z-bad.dcm");

    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_and_wait(w, file);
    const SeriesInfo& axial = t.list[std::size_t(t.axial)];
    // The status bar's warnings are the reader's, loaded here independently.
    LoadOptions opt;
    opt.series = axial.uid;
    const Volume direct = core::open_volume(t.folder, opt);
    auto* warned = w.findChild<gui::LoadWarnings*>("load_warnings");
    ASSERT_NE(warned, nullptr);
    EXPECT_TRUE(warned->isVisible());
    ASSERT_EQ(std::size_t(warned->warnings().size()), direct.meta.warnings.size());
    for (std::size_t i = 0; i < direct.meta.warnings.size(); ++i)
        EXPECT_EQ(warned->warnings()[int(i)].toStdString(), direct.meta.warnings[i]);
    EXPECT_TRUE(warned->toolTip().contains("Z-bad.dcm: malformed DICOM at byte 279"))
        << warned->toolTip().toStdString();
    QTest::mouseClick(warned, Qt::LeftButton);
    auto* list = visible_child<QMessageBox>(w, "load_warnings_list");
    ASSERT_NE(list, nullptr);
    EXPECT_TRUE(list->informativeText().contains("Z-bad.dcm")) << list->informativeText().toStdString();
    list->close();
    EXPECT_EQ(w.scene().volume().dims[0], axial.dims[0]);
    EXPECT_EQ(w.scene().volume().dims[1], axial.dims[1]);
    EXPECT_EQ(w.scene().volume().dims[2], axial.dims[2]);
    EXPECT_EQ(w.workspace().series(), axial.uid);
    EXPECT_EQ(fs::path(w.workspace().input()), fs::absolute(t.folder));
    EXPECT_EQ(visible_child<gui::SeriesDialog>(w, "series_chooser"), nullptr);

    // A file that is not DICOM inside says so, naming the file (no crash, nothing replaced).
    const std::string bad = dir / "broken.dcm";
    std::ofstream(bad) << "not a DICOM file";
    w.open_path(QString::fromStdString(bad));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 30000));
    EXPECT_TRUE(take_error_box(w).contains(QString::fromStdString(bad)));
    EXPECT_EQ(w.workspace().series(), axial.uid);
}

// The 3D view's hint says what to do next; the window preset shows "custom"
// for numbers set by hand; the CT (HU) presets are offered for CT only.
TEST(GuiPanels, HintAndPresetsFollowTheData) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const std::string ball = ball_volume(dir.path());
    gui::MainWindow w;
    w.resize(1280, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    auto* hint = w.findChild<QLabel*>("view3d_hint");
    ASSERT_NE(hint, nullptr);
    EXPECT_TRUE(hint->text().startsWith("Open a volume"));

    open_and_wait(w, ball);
    EXPECT_TRUE(hint->isVisible());
    EXPECT_FALSE(hint->text().contains("Open a volume")) << hint->text().toStdString();
    EXPECT_TRUE(hint->text().contains("Add a surface")) << hint->text().toStdString();

    // ---- window presets: the volume has no unit, so the CT ones are disabled
    auto* preset = w.findChild<QComboBox*>("window_preset");
    auto* center = w.findChild<QDoubleSpinBox*>("window_center");
    ASSERT_NE(preset, nullptr);
    ASSERT_NE(center, nullptr);
    const auto n = int(core::ct_window_presets().size());
    ASSERT_EQ(preset->count(), n + 2); // default, the CT presets, custom
    EXPECT_EQ(preset->currentText(), "default");
    for (int i = 1; i <= n; ++i) EXPECT_FALSE(item_enabled(preset, i)) << preset->itemText(i).toStdString();
    const core::WindowLevel def = core::default_window(w.scene().volume());
    center->setValue(def.center + 17);
    EXPECT_EQ(preset->currentText(), "custom");
    EXPECT_EQ(w.workspace().window().center, def.center + 17);
    preset->setCurrentIndex(0);
    EXPECT_EQ(w.workspace().window().center, def.center);
    EXPECT_EQ(preset->currentText(), "default");

    // ---- a CT series (HU): the CT presets can be chosen, and name their numbers
    test::SeriesSpec ct;
    test::write_series(dir / "ct", ct);
    open_and_wait(w, dir / "ct");
    for (int i = 1; i <= n; ++i) EXPECT_TRUE(item_enabled(preset, i)) << preset->itemText(i).toStdString();
    preset->setCurrentIndex(n); // the last CT preset
    EXPECT_EQ(w.workspace().window().center, core::ct_window_presets()[std::size_t(n - 1)].window.center);
    EXPECT_EQ(w.workspace().window().width, core::ct_window_presets()[std::size_t(n - 1)].window.width);
    auto* width = w.findChild<QDoubleSpinBox*>("window_width");
    width->setValue(width->value() + 1);
    EXPECT_EQ(preset->currentText(), "custom");
    auto* iso_presets = w.surfaces_panel()->findChild<QComboBox*>("iso_preset");
    bool hu_enabled = false;
    for (int i = 0; i < iso_presets->count(); ++i)
        hu_enabled |= iso_presets->itemText(i).contains(" HU") && item_enabled(iso_presets, i);
    EXPECT_TRUE(hu_enabled) << "HU iso presets for CT";

    // ---- every surface hidden: the hint says so
    const ValueRange r = w.scene().value_range();
    add_through_panel(w, 0.5 * (r.min + r.max));
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    EXPECT_FALSE(hint->isVisible());
    QWidget* row = w.surfaces_panel()->row(w.scene().surfaces()[0]);
    row->findChild<QCheckBox*>("visible")->setChecked(false);
    EXPECT_TRUE(hint->isVisible());
    EXPECT_TRUE(hint->text().contains("hidden")) << hint->text().toStdString();
}

// The iso slider runs across its row in round steps (a thousandth of the
// range or so; a page a twentieth), so a drag moves the value a few units a
// pixel on the bundled CT; the opacity has a number kept in step with its slider.
TEST(GuiPanels, IsoSliderStepsAndOpacityNumber) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const std::string headsq = test::data("headsq.nhdr");
    const ValueRange range = load_volume(headsq).value_range();
    const double span = range.max - range.min;

    gui::MainWindow w;
    w.resize(1280, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_and_wait(w, headsq);
    add_through_panel(w, 1150);
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    const auto id = w.scene().surfaces()[0];
    auto* panel = w.surfaces_panel();
    QWidget* row = panel->row(id);
    auto* slider = row->findChild<QSlider*>("iso_slider");
    auto* value = row->findChild<QDoubleSpinBox*>("iso_value");
    ASSERT_NE(slider, nullptr);
    ASSERT_NE(value, nullptr);
    QTest::qWait(100);

    // The slider spans the row (not squeezed beside the number).
    EXPECT_GT(slider->width(), row->width() * 3 / 4) << slider->width() << " of " << row->width();
    // One step: a round increment of at most a 500th of the range; a page larger.
    slider->setFocus();
    const double before = value->value();
    QTest::keyClick(slider, Qt::Key_Right);
    const double step = value->value() - before;
    EXPECT_GT(step, 0);
    EXPECT_LE(step, span / 500);
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
    EXPECT_TRUE(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 || std::abs(mantissa - 5) < 1e-9)
        << step;
    QTest::keyClick(slider, Qt::Key_PageUp);
    const double page = value->value() - before - step;
    EXPECT_GE(page, 10 * step);
    EXPECT_LE(page, span / 10);
    // A drag moves the value by the range over the groove's width a pixel:
    // the whole row's width leaves it under 15 units a pixel on headsq.
    EXPECT_LT(span / slider->width(), 15.0) << "units a pixel";

    // ---- opacity: the number follows the slider, and the slider and scene the number
    auto* opacity = row->findChild<QSlider*>("opacity");
    auto* percent = row->findChild<QSpinBox*>("opacity_value");
    ASSERT_NE(opacity, nullptr);
    ASSERT_NE(percent, nullptr);
    EXPECT_EQ(percent->value(), int(std::lround(w.scene().info(id).opacity * 100)));
    opacity->setValue(70);
    EXPECT_EQ(percent->value(), 70);
    EXPECT_FLOAT_EQ(w.scene().info(id).opacity, 0.7f);
    percent->setValue(40);
    EXPECT_EQ(opacity->value(), 40);
    EXPECT_FLOAT_EQ(w.scene().info(id).opacity, 0.4f);
    ASSERT_TRUE(wait_until([&] { return !panel->reextracting(); }, 60000));
    const auto out = test::output_dir("gui_panels");
    EXPECT_TRUE(w.grab().save(QString::fromStdString((out / "iso_row.png").string())));
}

// Save dialogs start in the folder last used for their kind, else in the
// documents folder, named after the data; never in the data's folder (a
// read-only share, issue 38).
TEST(GuiPanels, SaveDialogsStartInTheLastFolderUsedElseTheDocumentsFolder) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_panels_test", dir / "config");
    const QString d = QString::fromStdString(dir.path().string());
    const QString last = QString::fromStdString(dir / "last");
    fs::create_directories(dir / "last");
    fs::create_directories(dir / "data");
    fs::copy_file(test::data("headsq.nhdr"), dir / "data/headsq.nhdr");
    fs::copy_file(test::data("headsq.raw"), dir / "data/headsq.raw");
    const QString headsq = d + "/data/headsq.nhdr";

    EXPECT_EQ(gui::data_name(headsq), "headsq");
    EXPECT_EQ(gui::data_name(d + "/data/ct.nii.gz"), "ct");
    EXPECT_EQ(gui::data_name(d + "/data"), "data");
    // Where a save dialog starts: the folder last used for that kind, else
    // the documents folder (else home), never the data's folder (a
    // read-only share would fail).
    const QString documents = QStandardPaths::writableLocation(QStandardPaths::DocumentsLocation);
    const QString first = QFileInfo(documents).isDir() ? documents : QDir::homePath();
    EXPECT_EQ(gui::Files::start_folder("surface"), first);
    gui::Files::remember_folder("export", last + "/figure.png");
    EXPECT_EQ(gui::Files::start_folder("export"), last);
    EXPECT_EQ(gui::Files::start_folder("surface"), first) << "each kind its own";
    fs::create_directories(dir / "gone");
    gui::Files::remember_folder("dicom", d + "/gone");
    EXPECT_EQ(gui::Files::start_folder("dicom"), d + "/gone");
    fs::remove(dir / "gone");
    EXPECT_EQ(gui::Files::start_folder("dicom"), first) << "a folder that went: the documents folder";
    EXPECT_EQ(gui::surface_file_stem("iso 500"), "iso500");
    EXPECT_EQ(gui::surface_file_stem("iso 12.5"), "iso12.5");
    EXPECT_EQ(gui::surface_file_stem("a/b"), "a-b");

    // ---- the dialogs start there
    gui::MainWindow w;
    w.resize(1280, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_and_wait(w, headsq.toStdString());
    add_through_panel(w, 500);
    QAction* save = file_action(w, "Save s&urfaces...");
    ASSERT_NE(save, nullptr);
    save->trigger();
    gui::SaveSurfacesDialog* sd = nullptr;
    ASSERT_TRUE(
        wait_until([&] { return (sd = visible_child<gui::SaveSurfacesDialog>(w, "save_surfaces_dialog")); }, 30000));
    EXPECT_EQ(sd->findChild<QLineEdit*>("file")->text(), QDir(first).filePath("headsq-iso500.stl"));
    sd->reject();
    QAction* exp = file_action(w, "&Export image...");
    ASSERT_NE(exp, nullptr);
    exp->trigger();
    gui::ExportDialog* ed = nullptr;
    ASSERT_TRUE(wait_until([&] { return (ed = visible_child<gui::ExportDialog>(w, "export_dialog")); }, 30000));
    EXPECT_EQ(ed->findChild<QLineEdit*>("file")->text(), last + "/headsq.png") << "the last folder exported to";
    ed->reject();
}
