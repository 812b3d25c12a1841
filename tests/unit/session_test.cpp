// Session files (renderer/core/session.hpp, docs/sessions.md): what is
// stored and read back, relative and absolute input paths, every refusal
// naming the file and the field, a changed input, the scene a session
// opens, the render request it makes, and `isoscope render --session`'s
// refusals as a real process.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "io/error.hpp"
#include "io/image.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/session.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/postprocess.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::read_file;
using iso::test::TempDir;
using iso::test::write_file;
namespace fs = std::filesystem;

namespace {

Markup line(glm::dvec3 a, glm::dvec3 b, const std::string& name) {
    Markup m;
    m.type = MarkupType::Line;
    m.name = name;
    m.points.resize(2);
    m.points[0].position = a;
    m.points[0].label = name + "-1";
    m.points[1].position = b;
    m.points[1].label = name + "-2";
    return m;
}

core::Session example(const std::string& input) {
    core::Session s;
    s.input = fs::absolute(input).lexically_normal().string();
    core::SessionSurface skin;
    skin.kind = core::SurfaceInfo::Kind::Iso;
    skin.value = 500;
    skin.name = "skin";
    skin.source = s.input;
    skin.color = "#f0b090";
    skin.opacity = 0.3f;
    core::SessionSurface bone = skin;
    bone.value = 1150;
    bone.name = "iso 1150";
    bone.color = "#f2ecd8";
    bone.opacity = 1.0f;
    bone.visible = false;
    bone.post.smooth = 0.25;
    bone.post.keep_largest = true;
    s.surfaces = {skin, bone};
    Camera c;
    c.eye = {12.25, -480.125, 33.0 / 7.0};
    c.target = {100.0 / 3.0, 102.4, -69.75};
    c.up = {0.1, 0.2, 0.97};
    c.fov_y_degrees = 27.5;
    s.camera = c;
    s.window = core::WindowLevel{1963.5, 3926.25};
    s.ao = AoMethod::Off;
    s.transparency = false;
    s.markups = {line({1.5, 2.25, -3.0}, {40.0, 50.0 / 3.0, -60.0}, "ruler")};
    return s;
}

// The message of the iso::Error that loading `text` as a session throws ("" when none).
std::string load_error(const TempDir& dir, const std::string& text) {
    const std::string path = dir / "broken.json";
    write_file(path, text);
    try {
        core::load_session(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(Session, SavedAndLoadedBackExactly) {
    TempDir dir;
    const core::Session s = example(test::data("headsq.nhdr"));
    const std::string path = dir / "sub/s.json";
    fs::create_directories(dir.path() / "sub");
    core::save_session(s, path);
    const auto j = nlohmann::json::parse(read_file(path));
    EXPECT_EQ(j["format"], "isoscope-session");
    EXPECT_EQ(j["version"], core::kSessionVersion);
    // Not below the session's folder: absolute.
    EXPECT_EQ(j["input"]["path"], s.input);
    EXPECT_EQ(j["input"]["sha256"], sha256_of_path(s.input));
    EXPECT_EQ(j["surfaces"][0]["color"], "#f0b090");
    EXPECT_EQ(j["markups"]["markups"][0]["type"], "Line");
    EXPECT_EQ(j["markups"]["markups"][0]["coordinateSystem"], "LPS");

    const core::Session r = core::load_session(path);
    EXPECT_TRUE(r.warnings.empty());
    EXPECT_EQ(r.input, s.input);
    EXPECT_EQ(r.input_sha256, sha256_of_path(s.input));
    ASSERT_EQ(r.surfaces.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(r.surfaces[i].kind, s.surfaces[i].kind);
        EXPECT_EQ(r.surfaces[i].value, s.surfaces[i].value);
        EXPECT_EQ(r.surfaces[i].name, s.surfaces[i].name);
        EXPECT_EQ(r.surfaces[i].source, s.surfaces[i].source);
        EXPECT_EQ(r.surfaces[i].color, s.surfaces[i].color);
        EXPECT_EQ(r.surfaces[i].opacity, s.surfaces[i].opacity);
        EXPECT_EQ(r.surfaces[i].visible, s.surfaces[i].visible);
        EXPECT_EQ(r.surfaces[i].post.smooth, s.surfaces[i].post.smooth);
        EXPECT_EQ(r.surfaces[i].post.keep_largest, s.surfaces[i].post.keep_largest);
    }
    ASSERT_TRUE(r.camera.has_value());
    // Bit for bit: the numbers are written with round-trip precision.
    EXPECT_EQ(r.camera->eye, s.camera->eye);
    EXPECT_EQ(r.camera->target, s.camera->target);
    EXPECT_EQ(r.camera->up, s.camera->up);
    EXPECT_EQ(r.camera->fov_y_degrees, s.camera->fov_y_degrees);
    ASSERT_TRUE(r.window.has_value());
    EXPECT_EQ(r.window->center, 1963.5);
    EXPECT_EQ(r.window->width, 3926.25);
    EXPECT_EQ(r.ao, AoMethod::Off);
    EXPECT_FALSE(r.transparency);
    ASSERT_EQ(r.markups.size(), 1u);
    EXPECT_EQ(r.markups[0].name, "ruler");
    EXPECT_EQ(r.markups[0].points[1].position, s.markups[0].points[1].position);
    EXPECT_EQ(r.markups[0].points[1].label, "ruler-2");
    EXPECT_TRUE(core::same_state(r, s));
    core::Session moved = r;
    moved.camera->eye.x += 1e-9;
    EXPECT_FALSE(core::same_state(moved, s));
}

// Ray-traced AO in the 3D view is saved as view.ao_method "raytraced" (only
// then: other sessions' files are unchanged) and read back; "reference",
// its former name, is read too.
TEST(Session, RayTracedAoIsSavedAndLoadedBack) {
    TempDir dir;
    core::Session s = example(test::data("headsq.nhdr"));
    s.ao = AoMethod::Raytraced;
    core::save_session(s, dir / "rt.json");
    auto j = nlohmann::json::parse(read_file(dir / "rt.json"));
    EXPECT_EQ(j["view"]["ao"], true);
    EXPECT_EQ(j["view"]["ao_method"], "raytraced");
    EXPECT_EQ(core::load_session(dir / "rt.json").ao, AoMethod::Raytraced);
    j["view"]["ao_method"] = "reference";
    write_file(dir / "old.json", j.dump());
    EXPECT_EQ(core::load_session(dir / "old.json").ao, AoMethod::Raytraced);
    s.ao = AoMethod::Cone;
    core::save_session(s, dir / "cone.json");
    j = nlohmann::json::parse(read_file(dir / "cone.json"));
    EXPECT_FALSE(j["view"].contains("ao_method"));
    EXPECT_EQ(core::load_session(dir / "cone.json").ao, AoMethod::Cone);
}

// The volume look (shown, transfer function, mode) and the crop box come
// back exactly and reach the render request; a session without them writes
// no "volume" or "clip" field and loads with none; bad fields are named.
TEST(Session, VolumeLookAndClipBoxAreSavedAndLoadedBack) {
    TempDir dir;
    core::Session s = example(test::data("headsq.nhdr"));
    core::save_session(s, dir / "none.json");
    auto j = nlohmann::json::parse(read_file(dir / "none.json"));
    EXPECT_FALSE(j.contains("volume"));
    EXPECT_FALSE(j.contains("clip"));
    const core::Session none = core::load_session(dir / "none.json");
    EXPECT_FALSE(none.volume.has_value());
    EXPECT_FALSE(none.clip_box.has_value());
    EXPECT_FALSE(core::session_request(none, "", {}).look.volume.enabled);

    VolumeLook v;
    v.enabled = true;
    v.tf = TransferFunction::parse("400:0:#c08060,600:0.05:#e0b090,1000.25:0.0625:#f0d0b0,1200:0.5:#ffffff");
    v.mode = VolumeMode::Mip;
    s.volume = v;
    s.clip_box = std::pair{glm::dvec3(-150.5, 20, -100), glm::dvec3(-40, 180.25, -10)};
    core::save_session(s, dir / "vol.json");
    j = nlohmann::json::parse(read_file(dir / "vol.json"));
    EXPECT_EQ(j["volume"]["mode"], "mip");
    const core::Session back = core::load_session(dir / "vol.json");
    ASSERT_TRUE(back.volume.has_value());
    EXPECT_EQ(*back.volume, v);
    EXPECT_EQ(back.clip_box, s.clip_box);
    EXPECT_TRUE(core::same_state(back, s));
    const auto r = core::session_request(back, "", {});
    EXPECT_TRUE(r.look.volume.enabled);
    EXPECT_EQ(r.look.volume.tf, v.tf);
    EXPECT_EQ(r.look.volume.mode, VolumeMode::Mip);
    EXPECT_EQ(r.look.clip.box, s.clip_box);

    const std::pair<std::function<void(nlohmann::json&)>, std::string> cases[] = {
        {[](auto& x) { x["volume"]["transfer_function"] = "400:2:#ffffff"; }, "volume.transfer_function: "},
        {[](auto& x) { x["volume"].erase("transfer_function"); }, "volume.transfer_function: missing"},
        {[](auto& x) { x["volume"]["mode"] = "max"; }, "volume.mode: must be"},
        {[](auto& x) { x["volume"]["enabled"] = 1; }, "volume.enabled: must be true or false"},
        {[](auto& x) {
             x["clip"]["box"]["min"] = {1, 2};
         },
         "clip.box.min: must be an array of 3 numbers"},
        {[](auto& x) { x["clip"]["box"].erase("max"); }, "clip.box.max: missing"},
        {[](auto& x) {
             x["clip"]["box"]["min"] = {0, 500, 0};
         },
         "clip.box: min must not exceed max"},
    };
    for (const auto& [edit, expect] : cases) {
        auto bad = j;
        edit(bad);
        write_file(dir / "bad.json", bad.dump());
        try {
            core::load_session(dir / "bad.json");
            ADD_FAILURE() << "accepted: " << expect;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
        }
    }
}

// The desktop app's layout, slice views (each plane's origin, pan and
// zoom, the crosshair) and its 3D view's slice planes toggle come back bit
// for bit; a session without them (written before they were stored) still
// loads, with none of them, and writes none of them back.
TEST(Session, LayoutAndSliceViewsAreSavedAndLoadedBack) {
    TempDir dir;
    core::Session s = example(test::data("headsq.nhdr"));
    s.layout = core::ViewLayout::Sagittal;
    s.slice_planes_in_3d = true;
    core::SliceViewsState v;
    v.crosshair = {1.0 / 3.0, -20.5, 47.125};
    for (std::size_t i = 0; i < 3; ++i)
        v.views[i] = {
            {0.1 * double(i), -20.5, 47.125 + double(i)}, {5.0 / 7.0, -1.25 * double(i), 3.5}, 0.3 + 0.1 * double(i)};
    s.slice_views = v;
    const std::string path = dir / "s.json";
    core::save_session(s, path);
    const auto j = nlohmann::json::parse(read_file(path));
    EXPECT_EQ(j["layout"], "sagittal");
    EXPECT_EQ(j["view"]["slice_planes"], true);
    EXPECT_EQ(j["slice_views"]["coronal"]["pixel_mm"], 0.4);
    const core::Session r = core::load_session(path);
    ASSERT_TRUE(r.layout.has_value());
    EXPECT_EQ(*r.layout, core::ViewLayout::Sagittal);
    EXPECT_TRUE(r.slice_planes_in_3d);
    ASSERT_TRUE(r.slice_views.has_value());
    EXPECT_EQ(r.slice_views->crosshair, v.crosshair);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(r.slice_views->views[i].origin, v.views[i].origin);
        EXPECT_EQ(r.slice_views->views[i].center, v.views[i].center);
        EXPECT_EQ(r.slice_views->views[i].pixel_mm, v.views[i].pixel_mm);
    }
    EXPECT_TRUE(core::same_state(r, s));
    core::Session other = r;
    other.layout = core::ViewLayout::FourUp;
    EXPECT_FALSE(core::same_state(other, s));
    other = r;
    other.slice_views->views[2].origin.x += 1.0;
    EXPECT_FALSE(core::same_state(other, s));
    for (const auto l : {core::ViewLayout::FourUp, core::ViewLayout::Conventional, core::ViewLayout::ThreeD,
                         core::ViewLayout::Axial, core::ViewLayout::Coronal, core::ViewLayout::Sagittal})
        EXPECT_EQ(core::view_layout_from_name(core::view_layout_name(l)), l);

    // An older file: no layout, no slice_views, no view.slice_planes.
    auto old = j;
    old.erase("layout");
    old.erase("slice_views");
    old["view"].erase("slice_planes");
    write_file(dir / "old.json", old.dump(2));
    const core::Session o = core::load_session(dir / "old.json");
    EXPECT_FALSE(o.layout.has_value());
    EXPECT_FALSE(o.slice_views.has_value());
    EXPECT_FALSE(o.slice_planes_in_3d);
    EXPECT_EQ(o.camera->eye, s.camera->eye); // the rest as before
    core::save_session(o, dir / "again.json");
    const auto again = nlohmann::json::parse(read_file(dir / "again.json"));
    EXPECT_FALSE(again.contains("layout"));
    EXPECT_FALSE(again.contains("slice_views"));
    EXPECT_FALSE(again["view"].contains("slice_planes"));
}

// Slice views onto a volume's default planes: the crosshair the views mark
// is the one stored, each plane's offset, pan and zoom are the stored ones.
TEST(Session, SliceViewsApplyToTheDefaultPlanes) {
    const Volume vol =
        Volume::dense({8, 10, 12}, VoxelType::F32, make_affine({0.5, 0.75, 1.5}, {-10.0, 20.0, 30.0}, glm::dmat3(1.0)));
    auto planes = core::default_planes(vol);
    const glm::dvec3 cross(-8.5, 23.0, 36.0);
    core::set_crosshair(planes, cross);
    core::set_offset(planes[0], 40.5);         // the axial view on another slice than the crosshair's
    planes[1].center += 3.0 * planes[1].right; // the coronal view panned
    planes[2].pixel_mm = 0.125;                // the sagittal view zoomed
    const core::SliceViewsState st = core::capture_slice_views(planes);
    EXPECT_EQ(st.crosshair, cross);
    auto back = core::default_planes(vol);
    core::apply_slice_views(st, back);
    EXPECT_EQ(core::crosshair_point(back), cross);
    EXPECT_DOUBLE_EQ(back[0].offset_mm(), 40.5);
    EXPECT_EQ(back[1].offset_mm(), cross.y);
    EXPECT_EQ(back[2].offset_mm(), cross.x);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(back[i].origin, planes[i].origin);
        EXPECT_NEAR(glm::length(back[i].center - planes[i].center), 0.0, 1e-12);
        EXPECT_EQ(back[i].pixel_mm, planes[i].pixel_mm);
    }
}

TEST(Session, InputBelowTheSessionFolderIsRelativeAndMovesWithIt) {
    TempDir dir;
    fs::create_directories(dir.path() / "a" / "data");
    for (const char* f : {"headsq.nhdr", "headsq.raw"}) fs::copy_file(test::data(f), dir.path() / "a" / "data" / f);
    core::Session s = example(dir / "a/data/headsq.nhdr");
    core::save_session(s, dir / "a/s.json");
    EXPECT_EQ(nlohmann::json::parse(read_file(dir / "a/s.json"))["input"]["path"], "data/headsq.nhdr");
    EXPECT_EQ(nlohmann::json::parse(read_file(dir / "a/s.json"))["surfaces"][0]["source"], "data/headsq.nhdr");
    fs::rename(dir.path() / "a", dir.path() / "b");
    const auto r = core::load_session(dir / "b/s.json");
    EXPECT_EQ(r.input, (dir.path() / "b" / "data" / "headsq.nhdr").string());
    EXPECT_TRUE(r.warnings.empty());
}

TEST(Session, AChangedInputIsAWarning) {
    TempDir dir;
    for (const char* f : {"headsq.nhdr", "headsq.raw"}) fs::copy_file(test::data(f), dir.path() / f);
    core::save_session(example(dir / "headsq.nhdr"), dir / "s.json");
    EXPECT_TRUE(core::load_session(dir / "s.json").warnings.empty());
    {
        std::ofstream f(dir / "headsq.nhdr", std::ios::app);
        f << "# edited\n";
    }
    const auto r = core::load_session(dir / "s.json");
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_NE(r.warnings[0].find("changed since the session was saved"), std::string::npos) << r.warnings[0];
}

TEST(Session, RefusalsNameTheFileAndTheField) {
    TempDir dir;
    const std::string file = dir / "broken.json";
    core::save_session(example(test::data("headsq.nhdr")), dir / "good.json");
    const std::string good = read_file(dir / "good.json");
    const auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
        auto j = nlohmann::json::parse(good);
        edit(j);
        return j.dump(1);
    };
    struct Case {
        std::string text, expect;
    };
    const Case cases[] = {
        {"", "file is empty"},
        {"{ not json", "not valid JSON"},
        {"[1, 2]", "not an object"},
        {edited([](auto& j) { j.erase("format"); }), "format: not an isoscope session"},
        {edited([](auto& j) { j["version"] = 2; }), "version: 2 is not supported"},
        {edited([](auto& j) { j["version"] = "1"; }), "version: must be an integer"},
        {edited([](auto& j) { j.erase("input"); }), "input: missing"},
        {edited([](auto& j) { j["input"]["path"] = "/no/such/dir/headsq.nhdr"; }),
         "input.path: '/no/such/dir/headsq.nhdr' does not exist"},
        {edited([](auto& j) { j["surfaces"][1]["color"] = "red"; }), "surfaces[1].color: expected #rrggbb"},
        {edited([](auto& j) { j["surfaces"][0]["opacity"] = 1.5; }), "surfaces[0].opacity: must be between 0 and 1"},
        {edited([](auto& j) { j["surfaces"][0]["kind"] = "blob"; }),
         "surfaces[0].kind: 'blob' is not iso, label or mesh"},
        {edited([](auto& j) { j["surfaces"][0].erase("value"); }), "surfaces[0].value: missing"},
        {edited([](auto& j) { j["surfaces"][0]["smoothing"] = -1; }), "surfaces[0].smoothing: must be between 0 and 1"},
        // JSON has no NaN: writers put null (nlohmann does) or an overflowing number.
        {edited([](auto& j) { j["camera"]["eye"][1] = nullptr; }), "camera.eye: must be a number, not null"},
        {edited([](auto& j) {
             j["camera"]["target"] = {1, 2};
         }),
         "camera.target: must be an array of 3 numbers"},
        {edited([](auto& j) { j["camera"]["fov_y_degrees"] = 0; }), "camera.fov_y_degrees: must be between 0 and 180"},
        {edited([](auto& j) {
             j["camera"]["up"] = j["camera"]["target"];
             j["camera"]["eye"] = {0, 0, 0};
         }),
         "camera.up: is zero or along"},
        {edited([](auto& j) { j["window_level"]["width"] = 0; }), "window_level.width: must be positive"},
        {edited([](auto& j) { j["view"]["ao"] = "yes"; }), "view.ao: must be true or false"},
        {edited([](auto& j) { j["view"]["transparency"] = 0; }), "view.transparency: must be true or false"},
        {edited([](auto& j) {
             j["view"]["ao"] = true;
             j["view"]["ao_method"] = "rays";
         }),
         "view.ao_method: must be \"cone\" or \"raytraced\""},
        {edited([](auto& j) { j["layout"] = "six_up"; }), "layout: must be \"four_up\""},
        {edited([](auto& j) { j["view"]["slice_planes"] = 1; }), "view.slice_planes: must be true or false"},
        {edited([](auto& j) {
             j["slice_views"] = {{"crosshair", {1, 2}}};
         }),
         "slice_views.crosshair: must be an array of 3 numbers"},
        {edited([](auto& j) {
             j["slice_views"] = {{"crosshair", {1, 2, 3}}};
         }),
         "slice_views.axial: missing"},
        {edited([](auto& j) {
             const nlohmann::json view = {{"origin", {0, 0, 0}}, {"center", {0, 0, 0}}, {"pixel_mm", 1}};
             j["slice_views"] = {{"crosshair", {1, 2, 3}}, {"axial", view}, {"coronal", view}, {"sagittal", view}};
             j["slice_views"]["coronal"]["pixel_mm"] = 0;
         }),
         "slice_views.coronal.pixel_mm: must be positive"},
        {edited([](auto& j) { j["markups"]["markups"][0]["controlPoints"].erase(1); }),
         "markups: markup 1 (Line 'ruler'): a Line needs 2"},
    };
    for (const auto& c : cases) {
        const std::string msg = load_error(dir, c.text);
        EXPECT_EQ(msg.rfind(file + ": ", 0), 0u) << "names the file: " << msg;
        EXPECT_NE(msg.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in: " << msg;
    }
    // An overflowing number (how some writers put infinity) is refused by the JSON parser.
    std::string inf = good;
    const auto at = inf.find("\"fov_y_degrees\"");
    ASSERT_NE(at, std::string::npos);
    inf.insert(inf.find(':', at) + 1, " 1e999, \"unused\":");
    const std::string msg = load_error(dir, inf);
    EXPECT_EQ(msg.rfind(file + ": not valid JSON", 0), 0u) << msg;
    EXPECT_NE(msg.find("number overflow parsing '1e999'"), std::string::npos) << msg;
    // A missing file names itself.
    try {
        core::load_session(dir / "none.json");
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), dir / "none.json");
    }
}

TEST(Session, SavingKeepsTheOldFileWholeOnFailure) {
    TempDir dir;
    core::Session s = example(test::data("headsq.nhdr"));
    core::save_session(s, dir / "s.json");
    const std::string before = read_file(dir / "s.json");
    s.markups[0].points.pop_back(); // a Line with one point cannot be written
    EXPECT_THROW(core::save_session(s, dir / "s.json"), Error);
    EXPECT_EQ(read_file(dir / "s.json"), before);
    EXPECT_THROW(core::save_session(s, dir / "no/such/folder/s.json"), Error);
}

TEST(Session, OpensItsSceneAndCapturesItBack) {
    TempDir dir;
    core::Session s = example(test::data("headsq.nhdr")); // the bone smoothed (0.25) and kept largest
    core::save_session(s, dir / "s.json");
    double last = -1;
    bool monotonic = true;
    const auto opened = core::open_session(dir / "s.json", [&](double f, std::string_view) {
        monotonic &= f >= last - 1e-12;
        last = f;
        return true;
    });
    EXPECT_TRUE(monotonic);
    const core::Scene& scene = *opened.scene;
    ASSERT_TRUE(scene.has_volume());
    ASSERT_EQ(opened.surfaces.size(), 2u);
    ASSERT_EQ(scene.surfaces(), opened.surfaces);
    for (std::size_t i = 0; i < 2; ++i) {
        const auto& info = scene.info(opened.surfaces[i]);
        EXPECT_EQ(info.kind, core::SurfaceInfo::Kind::Iso);
        EXPECT_EQ(info.value, s.surfaces[i].value);
        EXPECT_EQ(info.name, s.surfaces[i].name);
        // The hex colour decoded by the published sRGB formula (IEC 61966-2-1), written out here.
        for (int c = 0; c < 3; ++c) {
            const double code = std::stoi(s.surfaces[i].color.substr(1 + 2 * std::size_t(c), 2), nullptr, 16) / 255.0;
            const double linear = code <= 0.04045 ? code / 12.92 : std::pow((code + 0.055) / 1.055, 2.4);
            EXPECT_NEAR(info.color[c], linear, 1e-6) << s.surfaces[i].color << " channel " << c;
        }
        EXPECT_EQ(info.opacity, s.surfaces[i].opacity);
        EXPECT_EQ(info.visible, s.surfaces[i].visible);
        EXPECT_EQ(info.post.smooth, s.surfaces[i].post.smooth);
        EXPECT_EQ(info.post.keep_largest, s.surfaces[i].post.keep_largest);
        // A fresh extraction of the file through the library's free functions
        // (not the Scene that opened the session): load, extract, post-process.
        Mesh expected = extract_isosurface(load_volume(s.input), s.surfaces[i].value);
        if (needs_postprocess(s.surfaces[i].post)) expected = postprocess(expected, s.surfaces[i].post);
        EXPECT_EQ(scene.mesh(opened.surfaces[i]).triangles.size(), expected.triangles.size());
        EXPECT_GT(expected.triangles.size(), 10000u);
    }
    // What the scene shows, captured again, is the same state.
    FrameLook view;
    view.ao = opened.session.ao;
    view.transparency = opened.session.transparency;
    const auto back = core::capture_session(scene, opened.session.input, opened.session.series, opened.session.camera,
                                            opened.session.window, view, opened.session.markups);
    EXPECT_TRUE(core::same_state(back, s));

    // Cancelled through the progress function.
    EXPECT_THROW(core::open_session(dir / "s.json", [](double, std::string_view) { return false; }), Cancelled);

    // A mesh surface on a volume input is refused, naming the session, the input and the surface.
    s.surfaces[0].kind = core::SurfaceInfo::Kind::Mesh;
    core::save_session(s, dir / "mesh.json");
    try {
        core::open_session(dir / "mesh.json");
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), dir / "mesh.json");
        EXPECT_NE(std::string(e.what()).find(s.input + ": surface 1 ('skin'): a mesh surface"), std::string::npos)
            << e.what();
    }
}

TEST(Session, RenderRequest) {
    const core::Session s = example(test::data("headsq.nhdr"));
    core::RenderRequest o;
    o.width = 640;
    o.height = 480;
    o.scale = 2;
    o.annotations = false;
    o.look.transparent_background = true;
    o.look.ao = AoMethod::Disk;
    o.look.cone.radius_mm = 7;
    auto r = core::session_request(s, "x.json", o);
    // The caller's frame...
    EXPECT_EQ(r.width, 640);
    EXPECT_EQ(r.height, 480);
    EXPECT_EQ(r.scale, 2.0f);
    EXPECT_FALSE(r.annotations);
    EXPECT_TRUE(r.look.transparent_background);
    EXPECT_EQ(r.look.cone.radius_mm, 7);
    // ... with the session's camera, markups, AO method and transparency toggle.
    ASSERT_TRUE(r.camera.has_value());
    EXPECT_EQ(r.camera->eye, s.camera->eye);
    EXPECT_EQ(r.markups.size(), 1u);
    EXPECT_EQ(r.look.ao, AoMethod::Off); // example() turns the 3D view's AO off
    EXPECT_FALSE(r.look.transparency);
    EXPECT_EQ(r.session_file, "x.json");
    core::SessionParts take;
    take.markups = take.ao = take.camera = false;
    r = core::session_request(s, "", o, take);
    EXPECT_TRUE(r.markups.empty());
    EXPECT_EQ(r.look.ao, AoMethod::Disk);
    EXPECT_FALSE(r.camera.has_value());
    EXPECT_FALSE(r.look.transparency) << "the transparency toggle is always the session's";
}

TEST(SessionCli, RefusalsNameTheSessionAndTheFlag) {
    TempDir dir;
    const auto run = [](const std::string& args) { return test::run_command(test::cli() + " render " + args, true); };
    auto r = run("--session " + (dir / "none.json") + " -o " + (dir / "x.png"));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find(dir / "none.json"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("no such file"), std::string::npos) << r.out;

    core::save_session(example(test::data("headsq.nhdr")), dir / "s.json");
    auto j = nlohmann::json::parse(read_file(dir / "s.json"));
    j["surfaces"][0]["color"] = "#12345";
    write_file(dir / "bad.json", j.dump());
    r = run("--session " + (dir / "bad.json") + " -o " + (dir / "x.png"));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find(dir / "bad.json" + ": surfaces[0].color: expected #rrggbb"), std::string::npos) << r.out;

    r = run(test::data("headsq.nhdr") + " --session " + (dir / "s.json") + " -o " + (dir / "x.png"));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("--session: the session names its input"), std::string::npos) << r.out;
    r = run("--session " + (dir / "s.json") + " --iso 300 -o " + (dir / "x.png"));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("--iso: the session holds the surfaces"), std::string::npos) << r.out;
    r = run("-o " + (dir / "x.png"));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("give an INPUT (or --session FILE)"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir / "x.png"));
}
