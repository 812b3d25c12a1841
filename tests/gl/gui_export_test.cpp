// Sessions and export in the desktop app (docs/gui.md "Sessions and
// export", docs/sessions.md), driven in-process through QTest under
// xvfb-run (as CTest runs this program; it skips without a display). The
// exported image is compared pixel by pixel with `isoscope render
// --session` run as a process; the reopened session with the core's state
// of the first window; the saved surface with the core's mesh.
#include <QAction>
#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QElapsedTimer>
#include <QLabel>
#include <QLineEdit>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QMimeData>
#include <QPushButton>
#include <QSpinBox>
#include <QStatusBar>
#include <QTest>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>
#include <algorithm>

#include "app/gui/export_dialog.hpp"
#include "app/gui/files.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/view_toolbar.hpp"
#include "app/gui/viewer.hpp"
#include "gui_test_util.hpp"
#include "tests/support/pixels.hpp"
#include "io/image.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"

#include <vtkDICOMReader.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>

using namespace iso;
namespace fs = std::filesystem;

namespace {
using test::differing;
using test::wait_until;

QAction* file_action(QMainWindow& w, const QString& text) {
    for (auto* a : w.menuBar()->findChildren<QAction*>())
        if (a->text() == text) return a;
    return nullptr;
}

template <class T> T* wait_for_child(QWidget& w, const char* name) {
    T* found = nullptr;
    wait_until([&] { return (found = w.findChild<T*>(name)) && found->isVisible(); }, 10000);
    return found;
}

// Seconds since the test began, per step (stdout: where the time goes under Xvfb and llvmpipe).
void step(const QElapsedTimer& t, const char* what) { std::printf("%6.2f s  %s\n", t.elapsed() / 1000.0, what); }

void screenshot(QWidget& w, const std::string& name) {
    QTest::qWait(100);
    const auto path = test::output_dir("gui_export") / name;
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString(path.string())));
    std::printf("screenshot: %s\n", path.c_str());
}
} // namespace

TEST(GuiExport, ExportSaveOpenSessionAndSurfaces) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_export_test", dir / "config");
    QElapsedTimer clock;
    clock.start();

    gui::MainWindow w;
    w.resize(1400, 1000);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));

    // ---- the bundled CT, skin and bone
    w.open_path(QString::fromStdString(test::data("headsq.nhdr")));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    ASSERT_TRUE(w.scene().has_volume()) << w.statusBar()->currentMessage().toStdString();
    for (double iso : {500.0, 1150.0}) {
        w.surfaces_panel()->add_surface(iso);
        ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 120000));
    }
    const auto ids = w.scene().surfaces();
    ASSERT_EQ(ids.size(), 2u);
    // The bone kept largest (the Surfaces panel's re-extraction): sessions carry it.
    PostProcessOptions largest;
    largest.keep_largest = true;
    w.surfaces_panel()->set_post(ids[1], largest);
    ASSERT_TRUE(wait_until(
        [&] { return !w.surfaces_panel()->reextracting() && w.scene().info(ids[1]).post.keep_largest; }, 60000));
    step(clock, "opened headsq, added skin and bone");
    // Skin at 0.3 through the core (the Surfaces panel is another part's).
    {
        core::SurfaceInfo info = w.scene().info(ids[0]);
        info.opacity = 0.3f;
        w.workspace().set_surface_info(ids[0], info);
    }
    ASSERT_NE(w.viewer(), nullptr);
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > 0; }, 60000));
    // Rotate the 3D view.
    Camera orbited = w.viewer()->camera();
    orbited.orbit(40, 25);
    w.viewer()->set_camera(orbited);
    // A ruler through the measurements' hook.
    Markup ruler;
    ruler.type = MarkupType::Line;
    ruler.name = "ruler";
    ruler.points.resize(2);
    ruler.points[0].position = orbited.target + glm::dvec3(-50, 0, 30);
    ruler.points[1].position = orbited.target + glm::dvec3(45, -10, -20);
    w.workspace().set_markups({{ruler}, {}});
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > 2; }, 60000));
    screenshot(w, "window.png");
    step(clock, "skin 0.3, orbited, ruler drawn");

    // ---- File > Export image through its dialog
    QAction* export_action = file_action(w, "&Export image...");
    ASSERT_NE(export_action, nullptr);
    export_action->trigger();
    auto* dialog = wait_for_child<gui::ExportDialog>(w, "export_dialog");
    ASSERT_NE(dialog, nullptr);
    // Defaults: the 3D view's size and AO.
    EXPECT_EQ(dialog->findChild<QSpinBox*>("width")->value(), w.viewer()->image_size().width());
    EXPECT_EQ(dialog->findChild<QComboBox*>("ao")->currentData().toString(), "cone");
    // The high-quality still method is offered (disk AO, docs/ao.md).
    EXPECT_GE(dialog->findChild<QComboBox*>("ao")->findData("disk"), 0);
    // ... and the ray-traced ground truth (docs/ao.md).
    EXPECT_GE(dialog->findChild<QComboBox*>("ao")->findData("raytraced"), 0);
    screenshot(*dialog, "export_dialog.png");
    const std::string image = dir / "export.png";
    dialog->findChild<QSpinBox*>("width")->setValue(360);
    dialog->findChild<QSpinBox*>("height")->setValue(270);
    auto* file = dialog->findChild<QLineEdit*>("file");
    // A wrong extension is refused in the dialog.
    file->setText(QString::fromStdString(dir / "export.jpg"));
    auto* ok = dialog->findChild<QDialogButtonBox*>()->button(QDialogButtonBox::Ok);
    QTest::mouseClick(ok, Qt::LeftButton);
    EXPECT_TRUE(dialog->isVisible());
    EXPECT_TRUE(dialog->findChild<QLabel*>("problem")->isVisible());
    file->setText(QString::fromStdString(image));
    QTest::mouseClick(ok, Qt::LeftButton);
    ASSERT_TRUE(
        wait_until([&] { return !w.busy() && w.findChild<gui::ExportDialog*>("export_dialog") == nullptr; }, 120000));
    ASSERT_TRUE(fs::exists(image)) << w.statusBar()->currentMessage().toStdString();
    step(clock, "exported through the dialog");
    const auto out = test::output_dir("gui_export");
    fs::copy_file(image, out / "export.png", fs::copy_options::overwrite_existing);
    // No session saved yet: the state went next to the image, and the metadata names it.
    const std::string beside = image + ".session.json";
    ASSERT_TRUE(fs::exists(beside));
    ImageMetadata meta;
    const Image exported = load_image(image, &meta);
    EXPECT_EQ(exported.width, 360);
    EXPECT_EQ(meta.text["isoscope:session"], beside);
    EXPECT_EQ(meta.text["isoscope:session_sha256"], sha256_of_path(beside));
    EXPECT_NE(meta.text["isoscope:markups_drawn"].find("Line 'ruler'"), std::string::npos);
    // The session beside it holds the window's state.
    {
        const auto s = core::load_session(beside);
        ASSERT_EQ(s.surfaces.size(), 2u);
        EXPECT_EQ(s.surfaces[0].opacity, 0.3f);
        ASSERT_TRUE(s.camera.has_value());
        EXPECT_EQ(s.camera->eye, orbited.eye);
    }

    // ---- exactly what `isoscope render --session` writes for it
    const std::string cli_image = dir / "cli.png";
    const auto r =
        test::run_command(test::cli() + " render --session " + beside + " --size 360x270 -o " + cli_image, true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    step(clock, "isoscope render --session");
    fs::copy_file(cli_image, out / "cli.png", fs::copy_options::overwrite_existing);
    ImageMetadata cli_meta;
    const Image cli = load_image(cli_image, &cli_meta);
    EXPECT_EQ(differing(exported, cli), 0u) << "the export and isoscope render --session differ";
    EXPECT_EQ(cli_meta.text["isoscope:session"], meta.text["isoscope:session"]);
    EXPECT_EQ(cli_meta.text["isoscope:session_sha256"], meta.text["isoscope:session_sha256"]);
    EXPECT_EQ(cli_meta.text["isoscope:camera"], meta.text["isoscope:camera"]);

    // ---- File > Save session (with the view bar's transparency off); an unchanged state's export names it
    ASSERT_NE(w.view_toolbar(), nullptr);
    w.view_toolbar()->transparency_action()->trigger();
    ASSERT_FALSE(w.viewer()->options().look.transparency);
    const std::string session = dir / "study.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    ASSERT_TRUE(fs::exists(session)) << w.statusBar()->currentMessage().toStdString();
    EXPECT_EQ(w.workspace().session_path(), session);
    core::RenderRequest small;
    small.width = 96;
    small.height = 72;
    core::SessionParts parts;
    parts.ao = false; // small.look.ao: off
    w.files()->export_image(QString::fromStdString(dir / "again.png"), small, parts);
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 120000));
    ImageMetadata again;
    load_image(dir / "again.png", &again);
    EXPECT_EQ(again.text["isoscope:session"], session);
    EXPECT_FALSE(fs::exists(dir / "again.png.session.json"));
    step(clock, "saved the session, exported the unchanged state");
    // An export into a folder that does not exist: a dialog names the file, nothing is written.
    {
        const std::string nowhere = dir / "no/such/folder/x.png";
        w.files()->export_image(QString::fromStdString(nowhere), small, parts);
        ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
        QMessageBox* box = nullptr;
        ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>("error")) && box->isVisible(); }, 10000));
        EXPECT_TRUE(box->text().contains(QString::fromStdString(nowhere))) << box->text().toStdString();
        box->close();
        QTest::qWait(50);
        EXPECT_FALSE(fs::exists(dir / "no"));
    }

    // ---- File > Save surfaces: the bone as PLY, read back by the core
    QAction* surfaces_action = file_action(w, "Save s&urfaces...");
    ASSERT_NE(surfaces_action, nullptr);
    surfaces_action->trigger();
    auto* sd = wait_for_child<gui::SaveSurfacesDialog>(w, "save_surfaces_dialog");
    ASSERT_NE(sd, nullptr);
    sd->findChild<QComboBox*>("surface")->setCurrentIndex(1);
    sd->findChild<QComboBox*>("format")->setCurrentIndex(1); // PLY
    auto* mesh_file = sd->findChild<QLineEdit*>("file");
    EXPECT_TRUE(mesh_file->text().endsWith("/headsq-iso1150.ply")) << mesh_file->text().toStdString();
    const std::string ply = dir / "bone.ply";
    mesh_file->setText(QString::fromStdString(ply));
    QTest::mouseClick(sd->findChild<QDialogButtonBox*>()->button(QDialogButtonBox::Ok), Qt::LeftButton);
    ASSERT_TRUE(wait_until([&] { return !w.busy() && fs::exists(ply); }, 60000))
        << w.statusBar()->currentMessage().toStdString();
    EXPECT_EQ(core::open_mesh(ply).triangles.size(), w.scene().mesh(ids[1]).triangles.size());
    step(clock, "saved the bone as PLY");

    // ---- File > Open session in a fresh window: the same surfaces, camera, markups
    gui::MainWindow w2;
    w2.resize(1200, 900);
    w2.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w2));
    w2.open_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w2.busy(); }, 120000));
    ASSERT_EQ(w2.scene().surfaces().size(), 2u) << w2.statusBar()->currentMessage().toStdString();
    step(clock, "opened the session in a fresh window");
    EXPECT_EQ(w2.workspace().input(), fs::absolute(test::data("headsq.nhdr")).lexically_normal().string());
    for (std::size_t i = 0; i < 2; ++i) {
        const auto& a = w.scene().info(ids[i]);
        const auto& b = w2.scene().info(w2.scene().surfaces()[i]);
        EXPECT_EQ(b.value, a.value);
        EXPECT_EQ(b.name, a.name);
        // Stored as #rrggbb: the nearest 8-bit sRGB colour.
        EXPECT_EQ(core::hex_from_linear(b.color), core::hex_from_linear(a.color));
        EXPECT_NEAR(b.color.r, a.color.r, 0.01f);
        EXPECT_EQ(b.opacity, a.opacity);
        EXPECT_EQ(b.visible, a.visible);
        EXPECT_EQ(b.post.keep_largest, a.post.keep_largest);
        EXPECT_EQ(w2.scene().mesh(w2.scene().surfaces()[i]).triangles.size(), w.scene().mesh(ids[i]).triangles.size());
    }
    ASSERT_NE(w2.viewer(), nullptr);
    ASSERT_TRUE(wait_until([&] { return w2.viewer()->frames() > 0; }, 60000));
    const Camera& c2 = w2.viewer()->camera();
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(c2.eye[k], orbited.eye[k], 1e-9);
        EXPECT_NEAR(c2.target[k], orbited.target[k], 1e-9);
        EXPECT_NEAR(c2.up[k], orbited.up[k], 1e-9);
    }
    EXPECT_NEAR(c2.fov_y_degrees, orbited.fov_y_degrees, 1e-9);
    EXPECT_EQ(w2.viewer()->options().look.ao, w.viewer()->options().look.ao);
    EXPECT_FALSE(w2.viewer()->options().look.transparency);
    EXPECT_FALSE(w2.view_toolbar()->transparency_action()->isChecked());
    EXPECT_EQ(w2.workspace().window().center, w.workspace().window().center);
    EXPECT_EQ(w2.workspace().window().width, w.workspace().window().width);
    ASSERT_EQ(w2.workspace().markups().size(), 1u);
    EXPECT_EQ(w2.workspace().markups()[0].name, "ruler");
    for (int p = 0; p < 2; ++p)
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(w2.workspace().markups()[0].points[p].position[k], ruler.points[p].position[k], 1e-9);
    EXPECT_EQ(w2.workspace().session_path(), session);
    EXPECT_TRUE(core::same_state(w2.workspace().session(), w.workspace().session()));
    screenshot(w2, "reopened.png");

    // ---- a broken session: a dialog names the file and the field, the window stays
    const std::string broken = dir / "broken.json";
    {
        std::ifstream in(session);
        auto j = nlohmann::json::parse(in);
        j["surfaces"][1]["color"] = "bone white";
        std::ofstream(broken) << j.dump(2);
    }
    const core::Scene* shown = &w2.scene();
    w2.open_session(QString::fromStdString(broken));
    ASSERT_TRUE(wait_until([&] { return !w2.busy(); }, 60000));
    QMessageBox* box = nullptr;
    ASSERT_TRUE(wait_until([&] { return (box = w2.findChild<QMessageBox*>("error")) && box->isVisible(); }, 10000));
    EXPECT_TRUE(box->text().contains(QString::fromStdString(broken))) << box->text().toStdString();
    EXPECT_TRUE(box->text().contains("surfaces[1].color")) << box->text().toStdString();
    std::printf("error dialog: %s\n", box->text().toStdString().c_str());
    screenshot(w2, "broken_session.png");
    box->close();
    QTest::qWait(50);
    EXPECT_TRUE(w2.isVisible());
    EXPECT_EQ(&w2.scene(), shown);
    EXPECT_EQ(w2.scene().surfaces().size(), 2u);
    EXPECT_EQ(w2.workspace().session_path(), session);
    step(clock, "broken session refused");

    // ---- a session dropped on the window opens as a session
    {
        QMimeData mime;
        mime.setUrls({QUrl::fromLocalFile(QString::fromStdString(session))});
        QDragEnterEvent enter(QPoint(200, 200), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
        static_cast<QObject&>(w2).event(&enter);
        QDropEvent drop(QPointF(200, 200), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
        static_cast<QObject&>(w2).event(&drop);
        ASSERT_TRUE(wait_until([&] { return &w2.scene() != shown && !w2.busy(); }, 60000))
            << w2.statusBar()->currentMessage().toStdString();
        EXPECT_EQ(w2.scene().surfaces().size(), 2u);
        EXPECT_EQ(w2.workspace().markups().size(), 1u);
        EXPECT_EQ(w2.workspace().session_path(), session);
    }
    step(clock, "dropped session opened");
}

// File > Export to DICOM: the figure joins the open series' study, one series
// for the session (a second export adds an image to it, also in another
// folder); the pixels are what `isoscope render --session ... --dicom` writes
// for the same session, read back with vtk-dicom.
TEST(GuiExport, ExportToDicomJoinsTheStudyInOneSeriesPerSession) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_export_test", dir / "config");
    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(test::data("dicom-mr-forearm")));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    ASSERT_TRUE(w.scene().has_volume()) << w.statusBar()->currentMessage().toStdString();
    w.surfaces_panel()->add_surface(200);
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    const std::string session = dir / "forearm.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));

    auto export_into = [&](const std::string& folder) {
        QAction* action = file_action(w, "Export to &DICOM...");
        ASSERT_NE(action, nullptr);
        action->trigger();
        auto* d = wait_for_child<gui::ExportDialog>(w, "export_dicom_dialog");
        ASSERT_NE(d, nullptr);
        EXPECT_FALSE(d->findChild<QCheckBox*>("transparent")->isVisible()) << "a Secondary Capture is RGB";
        d->findChild<QSpinBox*>("width")->setValue(160);
        d->findChild<QSpinBox*>("height")->setValue(120);
        d->findChild<QComboBox*>("ao")->setCurrentIndex(0); // off
        d->findChild<QLineEdit*>("file")->setText(QString::fromStdString(folder));
        QTest::mouseClick(d->findChild<QDialogButtonBox*>()->button(QDialogButtonBox::Ok), Qt::LeftButton);
        ASSERT_TRUE(wait_until(
            [&] { return !w.busy() && w.findChild<gui::ExportDialog*>("export_dicom_dialog") == nullptr; }, 120000));
    };
    export_into(dir / "pacs");
    export_into(dir / "pacs");
    export_into(dir / "elsewhere");
    auto files = [](const std::string& folder) {
        std::vector<std::string> v;
        for (const auto& e : fs::directory_iterator(folder)) v.push_back(e.path().string());
        std::sort(v.begin(), v.end());
        return v;
    };
    const auto pacs = files(dir / "pacs"), elsewhere = files(dir / "elsewhere");
    ASSERT_EQ(pacs.size(), 2u) << w.statusBar()->currentMessage().toStdString();
    ASSERT_EQ(elsewhere.size(), 1u);
    // Read back by vtk-dicom: the core's study, one series, numbered images.
    // Read back by DCMTK: the core's study, one series, numbered images.
    std::vector<std::string> dumps;
    for (const auto& f : {pacs[0], pacs[1], elsewhere[0]}) {
        const auto back = test::run_command("dcmdump +P StudyInstanceUID +P SeriesInstanceUID +P InstanceNumber " + f);
        ASSERT_EQ(back.exit_code, 0) << back.out << " (./setup.sh --tests installs dcmtk)";
        dumps.push_back(back.out);
    }
    const std::string study = w.scene().volume().meta.study_uid;
    auto series_line = [](const std::string& d) { return d.substr(d.find("(0020,000e)"), 80); };
    for (const auto& d : dumps) {
        EXPECT_NE(d.find("[" + study + "]"), std::string::npos) << d;
        EXPECT_EQ(series_line(d), series_line(dumps[0])) << "one series for the session";
    }
    EXPECT_NE(dumps[0].find("IS [1]"), std::string::npos) << dumps[0];
    EXPECT_NE(dumps[1].find("IS [2]"), std::string::npos) << dumps[1];
    EXPECT_NE(w.statusBar()->currentMessage().indexOf("in the source's study"), -1)
        << w.statusBar()->currentMessage().toStdString();

    // The same session through the command line: the same pixels.
    const auto r = test::run_command(
        test::cli() + " render --session " + session + " --size 160x120 --ao off --dicom " + (dir / "cli"), true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto cli = files(dir / "cli");
    ASSERT_EQ(cli.size(), 1u);
    auto pixels = [](const std::string& f) {
        vtkNew<vtkDICOMReader> reader;
        reader->SetFileName(f.c_str());
        reader->Update();
        auto* a = reader->GetOutput()->GetPointData()->GetScalars();
        return std::vector<unsigned char>(static_cast<unsigned char*>(a->GetVoidPointer(0)),
                                          static_cast<unsigned char*>(a->GetVoidPointer(0)) + a->GetNumberOfValues());
    };
    const auto a = pixels(pacs[0]), b = pixels(cli[0]);
    ASSERT_EQ(a.size(), std::size_t(160 * 120 * 3));
    EXPECT_TRUE(a == b) << "File > Export to DICOM and isoscope render --session --dicom differ";
}
