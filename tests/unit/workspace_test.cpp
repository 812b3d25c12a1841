// The workspace (renderer/core/workspace.hpp) without a display: the
// bundled CT opened into one, a day's edits (a surface added, its iso value
// moved and merged into one step, recoloured, a ruler placed and moved, a
// component isolated), each undone back to the start with the state equal
// at every step, redone, saved and reloaded equal; the notifications and
// the picture key; the refusals.
#include <filesystem>

#include <gtest/gtest.h>

#include "io/color.hpp"
#include "io/error.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/workspace.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

constexpr core::Parts kAll = core::Part::Surfaces | core::Part::Look | core::Part::Markups | core::Part::Selection |
                             core::Part::Window | core::Part::Slices | core::Part::Layout;

std::unique_ptr<core::Scene> bundled_ct() {
    auto s = std::make_unique<core::Scene>();
    s->open(test::data("headsq.nhdr"));
    return s;
}

Markup ruler(glm::dvec3 a, glm::dvec3 b) {
    Markup m;
    m.type = MarkupType::Line;
    m.name = "Vessel gap";
    m.points.resize(2);
    m.points[0].position = a;
    m.points[1].position = b;
    return m;
}

// The workspace with the bundled CT open, and its history.
struct Day {
    core::Workspace ws;
    core::EditHistory history;
    std::vector<core::WorkspaceState> states; // after each step (states[0]: the start)
    std::vector<std::string> texts;

    Day() {
        ws.reset(bundled_ct(), test::data("headsq.nhdr"), "");
        states.push_back(ws.capture(kAll));
    }
    void step(const std::string& text, core::Parts parts, const std::function<void()>& change,
              const std::string& merge_key = {}) {
        core::WorkspaceEdit e = ws.record(text, parts, change, merge_key);
        const bool merges = history.can_undo() && !merge_key.empty() && !texts.empty() && texts.back() == text;
        history.push(std::move(e));
        if (merges) {
            states.back() = ws.capture(kAll);
        } else {
            states.push_back(ws.capture(kAll));
            texts.push_back(text);
        }
    }
};

} // namespace

TEST(Workspace, ADayOfEditsUndoesToTheStartRedoesAndSavesAndReloadsEqual) {
    Day d;
    core::Workspace& ws = d.ws;
    ASSERT_TRUE(ws.scene().has_volume());
    EXPECT_FALSE(ws.modified());
    int notified = 0;
    core::Parts seen = 0;
    ws.observe([&](core::Parts p) {
        ++notified;
        seen |= p;
    });

    // A surface at 500, its iso value moved to 600 then 700 (one drag: one
    // step), recoloured.
    core::SurfaceId id = 0;
    d.step("add iso 500", core::Parts(core::Part::Surfaces),
           [&] { id = ws.add_isosurface(ws.scene().extract_isosurface(500), 500); });
    ASSERT_EQ(id, 1u);
    EXPECT_TRUE(core::has(seen, core::Part::Surfaces));
    for (double iso : {600.0, 700.0})
        d.step(
            "iso value", core::Parts(core::Part::Surfaces),
            [&] { ws.replace_surface(id, ws.scene().extract_isosurface(iso), iso, {}); }, "iso 1");
    EXPECT_EQ(d.history.size(), 2u) << "the two steps of one drag merge";
    EXPECT_EQ(ws.scene().info(id).name, "iso 700");
    d.step("colour", core::Parts(core::Part::Surfaces), [&] {
        core::SurfaceInfo info = ws.scene().info(id);
        info.color = linear_from_hex("#cc2020"); // a colour picker's
        ws.set_surface_info(id, info);
    });

    // A ruler placed between two vertices of the surface, then moved.
    const Mesh& m = ws.scene().mesh(id);
    ASSERT_GT(m.positions.size(), 100u);
    const glm::dvec3 a(m.positions.front()), b(m.positions[m.positions.size() / 2]);
    d.step("place ruler", core::Parts(core::Part::Markups), [&] {
        core::MarkupsState s = ws.markups_state();
        s.markups.push_back(ruler(a, b));
        ws.set_markups(s);
    });
    d.step("move ruler", core::Parts(core::Part::Markups), [&] {
        core::MarkupsState s = ws.markups_state();
        s.markups[0].points[1].position += glm::dvec3(5.0, 0.0, 0.0);
        ws.set_markups(s);
    });

    // The component under the ruler's first point isolated: a surface of its
    // own, its parent hidden.
    core::ComponentPlan plan = core::plan_component(ws.scene(), id, a);
    core::SurfaceId part = 0;
    d.step("isolate", core::Parts(core::Part::Surfaces), [&] { part = ws.isolate(plan).isolated.surface; });
    ASSERT_EQ(ws.scene().surfaces().size(), 2u);
    EXPECT_FALSE(ws.scene().info(id).visible);
    EXPECT_TRUE(ws.scene().info(part).visible);
    // Isolating it again (from the parent, or from itself) adds nothing.
    EXPECT_FALSE(ws.isolate(core::plan_component(ws.scene(), id, a)).added);
    EXPECT_FALSE(ws.isolate(core::plan_component(ws.scene(), part, a)).added);
    EXPECT_EQ(ws.scene().surfaces().size(), 2u);
    EXPECT_TRUE(core::same_parts(ws.capture(kAll), d.states.back(), kAll));
    EXPECT_TRUE(ws.modified());
    ASSERT_EQ(d.history.size(), d.states.size() - 1);

    // Undone step by step back to the start: each state equal.
    const auto end = ws.capture(kAll);
    for (std::size_t i = d.history.size(); i-- > 0;) {
        EXPECT_EQ(d.history.undo_text(), d.texts[i]);
        ASSERT_TRUE(d.history.undo(ws));
        EXPECT_TRUE(core::same_parts(ws.capture(kAll), d.states[i], kAll)) << "after undoing " << d.texts[i];
    }
    EXPECT_FALSE(d.history.can_undo());
    EXPECT_TRUE(ws.scene().surfaces().empty());
    EXPECT_FALSE(ws.modified()) << "undone to the state it opened with";
    // Redone to the end.
    while (d.history.redo(ws)) {}
    EXPECT_TRUE(core::same_parts(ws.capture(kAll), end, kAll));
    EXPECT_EQ(ws.scene().info(part).name, "iso 700 component " + std::to_string(plan.component + 1));

    // Saved and reloaded: the same state (the surfaces made again from the volume).
    Camera c;
    c.eye = {10, -400, 20};
    ws.set_camera(c);
    TempDir dir;
    const std::string path = (dir.path() / "day.isoscope.json").string();
    core::save_session(ws.session(), path);
    ws.mark_saved(path);
    EXPECT_FALSE(ws.modified());
    auto back = core::open_workspace(path);
    EXPECT_EQ(back->session_path(), path);
    EXPECT_FALSE(back->modified());
    EXPECT_TRUE(core::same_state(back->session(), ws.session()));
    // (The markups as Slicer's JSON has them: same_state compared them; here their points.)
    ASSERT_EQ(back->markups().size(), 1u);
    EXPECT_EQ(back->markups()[0].name, "Vessel gap");
    EXPECT_EQ(back->markups()[0].points[1].position, ws.markups()[0].points[1].position);
    for (const core::Part p :
         {core::Part::Look, core::Part::Selection, core::Part::Window, core::Part::Slices, core::Part::Layout})
        EXPECT_TRUE(core::same_parts(back->capture(kAll), ws.capture(kAll), core::Parts(p))) << "part " << int(p);
    ASSERT_EQ(back->scene().surfaces(), ws.scene().surfaces());
    for (const core::SurfaceId s : ws.scene().surfaces()) {
        const core::SurfaceInfo &x = back->scene().info(s), &y = ws.scene().info(s);
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.source, y.source);
        EXPECT_EQ(x.color, y.color);
        EXPECT_EQ(x.opacity, y.opacity);
        EXPECT_EQ(x.visible, y.visible);
        EXPECT_EQ(x.value, y.value);
        EXPECT_EQ(x.post, y.post);
        EXPECT_EQ(x.kind, y.kind);
        EXPECT_EQ(x.pickable, y.pickable);
        EXPECT_EQ(back->scene().mesh(s).triangles.size(), ws.scene().mesh(s).triangles.size());
    }
    EXPECT_EQ(back->camera(), ws.camera());
    EXPECT_GT(notified, 10);
}

TEST(Workspace, NotificationsCarryWhatChangedAndThePictureKeyFollowsOnlyThePicture) {
    core::Workspace ws;
    ws.reset(bundled_ct(), test::data("headsq.nhdr"), "");
    std::vector<core::Parts> got;
    const int h = ws.observe([&](core::Parts p) { got.push_back(p); });
    const auto key = ws.picture_key();
    ws.set_window({100, 200});
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0], core::Parts(core::Part::Window));
    EXPECT_EQ(ws.picture_key(), key) << "the window/level does not change the 3D picture";
    ws.set_window({100, 200});
    EXPECT_EQ(got.size(), 1u) << "no change, no notification";
    FrameLook look = ws.look();
    look.transparency = !look.transparency;
    ws.set_look(look);
    EXPECT_EQ(got.back(), core::Parts(core::Part::Look));
    EXPECT_NE(ws.picture_key(), key);
    ws.set_crosshair(ws.scene().volume_bounds().min + glm::dvec3(10.0));
    EXPECT_EQ(got.back(), core::Parts(core::Part::Slices));
    // Selecting a markup that a removal takes away clears the selection, and says so.
    core::MarkupsState s;
    s.markups = {ruler({0, 0, 0}, {1, 0, 0}), ruler({0, 0, 0}, {0, 1, 0})};
    ws.set_markups(s);
    ws.select(1);
    EXPECT_EQ(got.back(), core::Parts(core::Part::Selection));
    s.markups.pop_back();
    ws.set_markups(s);
    EXPECT_EQ(got.back(), core::Part::Markups | core::Part::Selection);
    EXPECT_FALSE(ws.selected());
    ws.unobserve(h);
    ws.set_window({0, 10});
    EXPECT_EQ(got.size(), 6u) << "not heard once unobserved";
}

TEST(Workspace, ACropBoxInsideOutIsRefusedAndAFailedEditLeavesNothingBehind) {
    core::Workspace ws;
    ws.reset(bundled_ct(), test::data("headsq.nhdr"), "");
    const Bounds b = ws.scene().volume_bounds();
    FrameLook look = ws.look();
    look.clip.box = {b.max, b.min}; // min > max on every axis
    try {
        ws.set_look(look);
        FAIL() << "an inside-out crop box was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("crop box"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("minimum"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(ws.look().clip.box);
    // An edit that throws half-way is put back whole.
    const auto before = ws.capture(kAll);
    EXPECT_THROW(ws.record("two things", core::Part::Surfaces | core::Part::Look,
                           [&] {
                               ws.add_isosurface(ws.scene().extract_isosurface(500), 500);
                               ws.set_look(look);
                           }),
                 Error);
    EXPECT_TRUE(core::same_parts(ws.capture(kAll), before, kAll));
    EXPECT_TRUE(ws.scene().surfaces().empty());
}

TEST(Workspace, ANewVolumeStartsWithItsDefaultsAndKeepsTheViewToggles) {
    core::Workspace ws;
    EXPECT_FALSE(ws.has_data());
    ws.reset(bundled_ct(), test::data("headsq.nhdr"), "");
    FrameLook look = ws.look();
    look.ao = AoMethod::Off;
    look.volume.enabled = true;
    look.clip.box = {ws.scene().volume_bounds().min, ws.scene().volume_bounds().max};
    ws.set_look(look);
    ws.set_markups({{ruler({0, 0, 0}, {1, 0, 0})}, {}});
    EXPECT_TRUE(ws.modified());
    ws.reset(bundled_ct(), test::data("headsq.nhdr"), "");
    EXPECT_EQ(ws.look().ao, AoMethod::Off) << "the AO toggle is the view's";
    EXPECT_FALSE(ws.look().volume.enabled);
    EXPECT_FALSE(ws.look().clip.box);
    EXPECT_FALSE(ws.look().volume.tf.empty());
    EXPECT_TRUE(ws.markups().empty());
    EXPECT_FALSE(ws.modified());
    EXPECT_EQ(ws.window(), core::default_window(ws.scene().volume()));
    EXPECT_EQ(ws.planes(), core::default_planes(ws.scene().volume()));
}
