// The core Scene both front ends use, without a GPU: opening volumes and
// meshes (mesh extensions in any case), isosurfaces as handles with
// properties, bounds of what is visible, mesh export, and errors that name
// the operation and the file.
#include "renderer/core/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include <glm/geometric.hpp>

#include "io/color.hpp"
#include "io/error.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

TEST(Scene, VolumeIsosurfacesAreSortedNamedAndColoured) {
    core::Scene s;
    EXPECT_EQ(s.open(test::data("headsq.nhdr")), 0u) << "a volume is not a surface";
    ASSERT_TRUE(s.has_volume());
    const auto ids = s.add_isosurfaces({1150, 500});
    ASSERT_EQ(ids, (std::vector<core::SurfaceId>{1, 2}));
    EXPECT_EQ(s.info(1).name, "iso 500");
    EXPECT_EQ(s.info(2).name, "iso 1150");
    EXPECT_EQ(s.info(1).kind, core::SurfaceInfo::Kind::Iso);
    EXPECT_EQ(s.info(2).value, 1150.0);
    // The default colours, linear RGB, stated here rather than read from the
    // palette under test (as sRGB hex): skin tone outside, bone white inside.
    EXPECT_EQ(s.info(1).color, linear_from_hex("#e0906c")) << "skin-toned outer surface";
    EXPECT_EQ(s.info(2).color, linear_from_hex("#f9f6ec")) << "bone-white inner surface";
    EXPECT_EQ(s.info(1).source, test::data("headsq.nhdr"));
    EXPECT_GT(s.mesh(1).triangles.size(), 10000u);
    EXPECT_EQ(s.sources(), (std::vector<std::string>{test::data("headsq.nhdr")}));
    // An iso value outside the range: an empty surface with a warning.
    const auto empty = s.add_isosurfaces({99999});
    EXPECT_TRUE(s.mesh(empty[0]).empty());
    ASSERT_EQ(s.mesh(empty[0]).warnings.size(), 1u);
    EXPECT_NE(s.mesh(empty[0]).warnings[0].find("outside the volume's value range"), std::string::npos);
}

TEST(Scene, BoundsFollowVisibility) {
    core::Scene s;
    s.open(test::data("headsq.nhdr"));
    s.add_isosurfaces({500, 1150});
    const Bounds both = s.bounds();
    s.info(1).visible = false; // the skin hidden: the bone is inside it
    const Bounds bone = s.bounds();
    EXPECT_GT(bone.min.y, both.min.y);
    EXPECT_LT(bone.max.y, both.max.y);
    s.info(2).visible = false;
    EXPECT_TRUE(s.bounds().empty());
}

TEST(Scene, MeshFilesOpenByExtensionInAnyCase) {
    TempDir dir;
    const std::string upper = dir / "BUNNY.VTP";
    fs::copy_file(test::data("bunny.vtp"), upper);
    for (const std::string& p : {test::data("bunny.vtp"), upper}) {
        core::Scene s;
        const auto id = s.open(p);
        EXPECT_EQ(id, 1u) << p;
        EXPECT_FALSE(s.has_volume()) << p << " must not be read as a volume";
        EXPECT_EQ(s.info(id).kind, core::SurfaceInfo::Kind::Mesh);
        EXPECT_EQ(s.info(id).name, fs::path(p).filename().string());
        EXPECT_GT(s.mesh(id).triangles.size(), 500u);
    }
    EXPECT_TRUE(is_mesh_path("a/b.StL"));
    EXPECT_TRUE(is_mesh_path("x.PLY"));
    EXPECT_FALSE(is_mesh_path("x.nrrd"));
    EXPECT_FALSE(is_mesh_path("stl"));
    EXPECT_EQ(mesh_extensions_text(), ".stl, .ply, .obj or .vtp");
}

TEST(Scene, ExportedMeshesRoundTripInLps) {
    TempDir dir;
    core::Scene s;
    s.open(test::data("headsq.nhdr"));
    const auto id = s.add_isosurfaces({1150}).at(0);
    for (const std::string ext : {".stl", ".ply", ".obj", ".vtp"}) {
        const std::string p = dir / ("bone" + ext);
        s.export_mesh(id, p);
        const Mesh m = load_mesh(p);
        EXPECT_EQ(m.triangles.size(), s.mesh(id).triangles.size()) << ext;
        const auto a = mesh_stats(m), b = mesh_stats(s.mesh(id));
        EXPECT_NEAR(a.bounds_min.x, b.bounds_min.x, 1e-3) << ext;
        EXPECT_NEAR(a.bounds_max.z, b.bounds_max.z, 1e-3) << ext;
    }
}

TEST(Scene, ErrorsNameTheOperationAndTheFile) {
    core::Scene s;
    const auto expect_error = [](auto&& f, const std::string& where, const std::string& what) {
        try {
            f();
            ADD_FAILURE() << "no error; expected " << where;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
            EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos)
                << "no command-line flags in core errors: " << e.what();
        }
    };
    expect_error([&] { s.add_isosurfaces({500}); }, "Scene::volume", "no volume");
    expect_error([&] { s.info(3); }, "Scene::info", "no surface with id 3");
    expect_error([&] { s.open("/no/such/head.nrrd"); }, "/no/such/head.nrrd", "");
    expect_error([&] { s.open("/no/such/mesh.STL"); }, "/no/such/mesh.STL", "");
    s.open(test::data("headsq.nhdr"));
    expect_error([&] { s.add_isosurfaces({}); }, test::data("headsq.nhdr"), "no iso value");
    core::SurfaceInfo bad;
    bad.name = "glass";
    bad.opacity = 1.5f;
    expect_error([&] { s.add_mesh(Mesh{}, bad); }, "Scene::add_mesh", "opacity of 'glass'");
    EXPECT_TRUE(s.surfaces().empty()) << "nothing half-added";
}

namespace {
// CIE L*a*b* (D65) of a linear RGB colour, computed here (sRGB primaries),
// not by the palette's code.
glm::dvec3 lab_of(const glm::vec3& linear) {
    const double r = linear.r, g = linear.g, b = linear.b;
    const double x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
    const double y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    const double z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
    const auto f = [](double t) { return t > 0.008856 ? std::cbrt(t) : 7.787 * t + 16.0 / 116.0; };
    return {116 * f(y) - 16, 500 * (f(x) - f(y)), 200 * (f(y) - f(z))};
}
double delta_e(const glm::vec3& a, const glm::vec3& b) { return glm::length(lab_of(a) - lab_of(b)); }
} // namespace

// The default colours, as surfaces are added one by one: each clearly apart
// from the one before (skin and bone too, whose outlines share the slices'
// grey), none repeated within the first 12, and the generated ones after
// them still apart from their neighbour and from every earlier one.
TEST(Scene, DefaultColoursAreDistinct) {
    constexpr std::size_t n = 40;
    std::vector<glm::vec3> c;
    for (std::size_t i = 0; i < n; ++i) c.push_back(core::surface_color(i, std::max<std::size_t>(i + 1, 2)));
    EXPECT_GT(delta_e(c[0], c[1]), 40.0) << "skin and bone";
    for (std::size_t i = 0; i + 1 < n; ++i)
        EXPECT_GT(delta_e(c[i], c[i + 1]), 25.0) << "surfaces " << i << ", " << i + 1;
    for (std::size_t i = 0; i < 12; ++i)
        for (std::size_t j = i + 1; j < 12; ++j) EXPECT_GT(delta_e(c[i], c[j]), 20.0) << "surfaces " << i << ", " << j;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j) EXPECT_GT(delta_e(c[i], c[j]), 4.0) << "surfaces " << i << ", " << j;
    // A lone surface is bone.
    EXPECT_EQ(core::surface_color(0, 1), c[1]);
}
