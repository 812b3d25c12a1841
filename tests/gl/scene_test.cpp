// The core Scene on a real GL context: what a front end edits (visibility,
// colour) shows in the next frame without re-adding anything, and GPU
// resources are released with the context current.
#include "renderer/core/scene.hpp"

#include "renderer/gl/context.hpp"
#include "gl_test.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using SceneGl = test::GlTest;

TEST_F(SceneGl, EditsShowInTheNextFrame) {
    core::Scene s;
    s.open(test::data("headsq.nhdr"));
    s.add_isosurfaces({500, 1150});
    s.info(1).visible = false; // skin hidden: the bone is seen
    RenderOptions o;
    o.width = o.height = 64;
    o.aov = Aov::Id;
    const Camera cam = s.camera(PatientView::Anterior, 1.0);
    auto ids = s.render(cam, o).image;
    std::size_t skin = 0, bone = 0;
    for (const float v : ids.floats) skin += v == 1.0f, bone += v == 2.0f;
    EXPECT_EQ(skin, 0u);
    EXPECT_GT(bone, 200u);
    s.info(1).visible = true;
    ids = s.render(cam, o).image;
    skin = bone = 0;
    for (const float v : ids.floats) skin += v == 1.0f, bone += v == 2.0f;
    EXPECT_GT(skin, 1000u) << "the skin covers the bone again";
    // A colour edit reaches the colour image.
    o.aov = Aov::None;
    const auto red = [&] {
        const auto img = s.render(cam, o).image;
        return test::byte_at(img, 32, 32, 0) - test::byte_at(img, 32, 32, 2);
    };
    s.info(1).color = {0.2f, 0.2f, 0.9f};
    const int blue_skin = red();
    s.info(1).color = {0.9f, 0.2f, 0.2f};
    EXPECT_GT(red(), blue_skin + 100);
    s.release_gpu();
    EXPECT_EQ(s.renderer().object_count(), 0u) << "a new renderer after release";
}
