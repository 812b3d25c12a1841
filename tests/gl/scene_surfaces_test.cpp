// Surfaces replaced and removed after the scene was drawn (the Surfaces
// panel's iso slider and Remove): the renderer's GPU copy follows in the next
// frame, in the same object id (the id AOV and picking report surface ids),
// a removed surface draws nothing, and a restored one (an undone removal) draws again.
#include "renderer/core/scene.hpp"

#include "renderer/gl/context.hpp"
#include "gl_test.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using SceneSurfacesGl = test::GlTest;

namespace {
std::size_t count_id(const Image& ids, float id) {
    std::size_t n = 0;
    for (const float v : ids.floats) n += v == id;
    return n;
}

// headsq's skin (500) and bone (1150); a 96 x 96 id AOV from the front.
void head_skin_and_bone(core::Scene& s, RenderOptions& o, Camera& cam) {
    s.open(test::data("headsq.nhdr"));
    s.add_isosurface(s.extract_isosurface(500), 500);
    s.add_isosurface(s.extract_isosurface(1150), 1150);
    o.width = o.height = 96;
    o.aov = Aov::Id;
    cam = s.camera(PatientView::Anterior, 1.0);
}
} // namespace

TEST_F(SceneSurfacesGl, ReplacedAndRemovedSurfacesShowInTheNextFrame) {
    core::Scene s;
    RenderOptions o;
    Camera cam;
    head_skin_and_bone(s, o, cam);
    const core::SurfaceId skin = 1, bone = 2;
    const auto objects_before = [&] { return s.renderer().object_count(); };
    auto ids = s.render(cam, o).image;
    const std::size_t skin_px = count_id(ids, float(skin));
    EXPECT_GT(skin_px, 1000u);
    const std::size_t bone_px = count_id(ids, float(bone)); // where the skin does not hide it
    EXPECT_EQ(objects_before(), 2u);

    // Replace the skin by an empty mesh: the bone shows through, in its own id.
    s.replace_surface(skin, Mesh{}, 99999, {});
    ids = s.render(cam, o).image;
    EXPECT_EQ(count_id(ids, float(skin)), 0u) << "the old skin is still drawn";
    EXPECT_GT(count_id(ids, float(bone)), bone_px + 1000);
    EXPECT_EQ(s.renderer().object_count(), 2u) << "replaced in place, not added";

    // And back to a real skin: drawn again, under the same id.
    s.replace_surface(skin, s.extract_isosurface(500), 500, {});
    ids = s.render(cam, o).image;
    EXPECT_EQ(count_id(ids, float(skin)), skin_px);
    EXPECT_EQ(count_id(ids, float(bone)), bone_px);

    // Remove the skin: the bone shows, ids stay; a surface added later gets id 3 in the renderer too.
    s.remove_surface(skin);
    ids = s.render(cam, o).image;
    EXPECT_EQ(count_id(ids, float(skin)), 0u);
    EXPECT_GT(count_id(ids, float(bone)), 1000u);
    const auto again = s.add_isosurface(s.extract_isosurface(500), 500);
    EXPECT_EQ(again, 3u);
    ids = s.render(cam, o).image;
    EXPECT_EQ(count_id(ids, float(again)), skin_px) << "the new skin under its own id";
    EXPECT_EQ(count_id(ids, float(skin)), 0u);
    EXPECT_EQ(s.renderer().object_count(), 3u);

    // A surface removed before it was ever drawn still keeps the ids aligned.
    const auto never = s.add_isosurface(s.extract_isosurface(800), 800);
    s.remove_surface(never);
    const auto after = s.add_isosurface(s.extract_isosurface(1150), 1150, {}, glm::vec3(1, 0, 0));
    s.remove_surface(again);
    s.remove_surface(bone);
    ids = s.render(cam, o).image;
    EXPECT_GT(count_id(ids, float(after)), 1000u);
    for (float gone : {1.0f, 2.0f, 3.0f, 4.0f}) EXPECT_EQ(count_id(ids, gone), 0u) << gone;

    // After the context's resources are released, everything is uploaded again in id order.
    s.release_gpu();
    ids = s.render(cam, o).image;
    EXPECT_GT(count_id(ids, float(after)), 1000u);
    EXPECT_EQ(s.renderer().object_count(), 5u);
}

TEST_F(SceneSurfacesGl, RestoredSurfaceDrawsAgainUnderItsId) {
    // An undone removal (the desktop app's Edit > Undo): the GPU copy dropped
    // by the removal is uploaded again into the same object id.
    core::Scene s;
    RenderOptions o;
    Camera cam;
    head_skin_and_bone(s, o, cam);
    const core::SurfaceId skin = 1, bone = 2;
    auto ids = s.render(cam, o).image;
    const std::size_t skin_px = count_id(ids, float(skin)), bone_px = count_id(ids, float(bone));
    ASSERT_GT(skin_px, 1000u);

    Mesh kept = s.mesh(skin);
    const core::SurfaceInfo info = s.info(skin);
    s.remove_surface(skin);
    ids = s.render(cam, o).image;
    ASSERT_EQ(count_id(ids, float(skin)), 0u);
    s.restore_surface(skin, std::move(kept), info);
    ids = s.render(cam, o).image;
    EXPECT_EQ(count_id(ids, float(skin)), skin_px) << "drawn again, under its id";
    EXPECT_EQ(count_id(ids, float(bone)), bone_px);
    EXPECT_EQ(s.renderer().object_count(), 2u) << "in its old slot, not added";

    // Removed and restored between two frames: drawn as before.
    kept = s.mesh(bone);
    const core::SurfaceInfo bone_info = s.info(bone);
    s.remove_surface(bone);
    s.restore_surface(bone, std::move(kept), bone_info);
    ids = s.render(cam, o).image;
    EXPECT_EQ(count_id(ids, float(bone)), bone_px);
}
