// The G-buffer layout table drives the shader: the linked gbuffer program's
// outputs sit at the table's locations, and every channel with an AOV reads
// back what the shader wrote there (exact for the id channel).
#include "renderer/passes/gbuffer_layout.hpp"

#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/gpu/renderer.hpp"
#include "renderer/surface/extract.hpp"
#include "gl_test.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using GBufferLayout = test::GlTest;

TEST_F(GBufferLayout, ShaderOutputsSitAtTheTablesLocations) {
    auto prog = gl::Program::from_files({"render/gbuffer.vert", "render/gbuffer.frag"}, passes::gbuffer_defines());
    GLint location = 0;
    for (const auto& c : passes::kGBufferLayout) {
        const std::string out = std::string("out_") + c.name;
        EXPECT_EQ(glGetProgramResourceLocation(prog.id(), GL_PROGRAM_OUTPUT, out.c_str()), location++) << out;
    }
    EXPECT_EQ(passes::gbuffer_defines(), "#define GB_NORMAL 0\n#define GB_ID 1\n#define GB_ALBEDO 2\n");
}

TEST_F(GBufferLayout, EveryAovChannelReadsBack) {
    // A plate facing the camera at the anterior side (normal -y in LPS).
    Mesh m;
    m.positions = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
    m.normals.assign(4, {0, -1, 0});
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    Renderer ren;
    ren.add(m, {});
    ren.add(m, {}); // a second object behind nothing: the same plate, drawn second (ties keep the first)
    Bounds b = ren.bounds();
    Camera cam;
    cam.set_view(PatientView::Anterior, b);
    cam.fit(b, 1.0);
    for (const auto& c : passes::kGBufferLayout) {
        if (c.aov == Aov::None) continue;
        RenderOptions o;
        o.width = o.height = 16;
        o.aov = c.aov;
        const Image img = ren.render(cam, o).image;
        const float* centre = &img.floats[(8 * 16 + 8) * img.channels];
        if (c.aov == Aov::Id) {
            EXPECT_EQ(centre[0], 1.0f) << "reversed-Z GREATER: the first of two coplanar plates wins";
            EXPECT_EQ(img.floats[0], 0.0f) << "background";
        } else {
            EXPECT_NEAR(centre[1], -1.0f, 1e-3) << c.name;
        }
    }
}
