// Every shader and resource variant of the AO passes runs on a real context:
// slicemap layers 1..8 (one layer is still an array texture: the cone shader
// samples usampler2DArray), traced at full and coarser resolution, with and
// without a guard band. Each gives an AO image with values in [0, 1] on the
// surface, NaN on the background, and no GL error.
#include <cmath>

#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/gpu/renderer.hpp"
#include "gl_test.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using PassVariants = test::GlTest;

TEST_F(PassVariants, AoForEveryLayerCountAndResolution) {
    // A block standing on a slab: the crease around its foot is occluded.
    const int n = 24;
    auto v = Volume::dense({n, n, n}, VoxelType::F32, make_affine(glm::dvec3(2.0), glm::dvec3(-24.0)));
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const bool a = i > 1 && i < 22 && j > 1 && j < 22 && k > 2 && k < 7;
                const bool b = i > 8 && i < 15 && j > 8 && j < 15 && k >= 7 && k < 18;
                v.as<float>()[v.linear_index(i, j, k)] = (a || b) ? 1.0f : 0.0f;
            }
    Renderer ren;
    ren.add(extract_isosurface(v, 0.5, {}), {});
    Bounds b = ren.bounds();
    for (const bool zoomed : {false, true}) {
        Camera cam;
        cam.set_view(PatientView::Superior, b);
        cam.fit(b, 1.0);
        if (zoomed) cam.zoom(1.8); // the scene reaches beyond the view: a guard band
        cam.fit_planes(b);
        for (int layers = 1; layers <= 8; ++layers)
            for (const double resolution : {1.0, 0.5, 0.25}) {
                RenderOptions o;
                o.width = o.height = 64;
                o.aov = Aov::Ao;
                o.look.ao = AoMethod::Cone;
                o.look.cone.radius_mm = 8;
                o.look.cone.layers = layers;
                o.look.cone.resolution = resolution;
                SCOPED_TRACE("layers " + std::to_string(layers) + ", resolution " + std::to_string(resolution) +
                             (zoomed ? ", zoomed" : ""));
                const auto r = ren.render(cam, o);
                EXPECT_EQ(zoomed, r.ao_guard > 0);
                std::size_t on = 0, occluded = 0;
                for (const float a : r.image.floats) {
                    if (std::isnan(a)) continue;
                    ++on;
                    EXPECT_TRUE(a >= 0.0f && a <= 1.0f) << a;
                    occluded += a < 0.9f;
                }
                EXPECT_GT(on, 200u);
                EXPECT_GT(occluded, 5u) << "the crease is darkened";
                EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
            }
    }
}
