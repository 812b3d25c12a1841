// The core Scene both front ends use, without a GPU: opening volumes and
// meshes (mesh extensions in any case), isosurfaces as handles with
// properties, bounds of what is visible, mesh export, and errors that name
// the operation and the file.
#include "renderer/core/scene.hpp"

#include <filesystem>

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
    // palette under test: skin tone outside, bone white inside.
    EXPECT_EQ(s.info(1).color, glm::vec3(0.93f, 0.72f, 0.60f)) << "skin-toned outer surface";
    EXPECT_EQ(s.info(2).color, glm::vec3(0.95f, 0.92f, 0.84f)) << "bone-white inner surface";
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
