// Structures through the core API and the CLI (renderer/core/structures.hpp):
// an isolated component is the component `measure` lists (the same volume,
// area, bounds, closedness; its uncertainty that of the component), it comes
// back from a session, and the distance between two components or surfaces
// is the brute-force minimum over their triangle pairs and, for two balls,
// the gap between them within the extraction's error.
#include "renderer/core/structures.hpp"

#include <cmath>
#include <filesystem>

#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "io/error.hpp"
#include "io/markups.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/surface_name.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/box_clip.hpp"
#include "renderer/surface/grow.hpp"
#include "renderer/surface/postprocess.hpp"
#include "renderer/surface/scissors.hpp"
#include "renderer/surface/shape.hpp"
#include "io/volume_io.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using namespace iso::test;
using iso::core::SurfaceId;
using iso::core::SurfaceInfo;

namespace {

// Two blurred balls, radii 9 and 5 mm, 26 mm apart (a 12 mm gap), on an
// oblique, anisotropic grid: one isosurface with two components.
const glm::dvec3 kBig{0, 0, 0}, kSmall{26, 0, 0};
constexpr double kRBig = 9.0, kRSmall = 5.0;

void two_balls(core::Scene& scene) {
    const glm::dvec3 centre = 0.5 * (kBig + kSmall);
    const auto dims = dims_for(22, 2, 1.0);
    Volume v = sample_field(dims, oblique_affine(dims, 1.0, centre), [](const glm::dvec3& p) {
        return std::max(ct_edge(kRBig - glm::length(p - kBig), 0.6), ct_edge(kRSmall - glm::length(p - kSmall), 0.6));
    });
    scene.set_volume(std::move(v), "two balls");
}

// Two balls joined by a tube along x (radius 2.5 mm, from the big ball's
// centre to the small one's), on the same oblique, anisotropic grid at
// half the spacing (0.35 x 0.5 x 0.65 mm), and
// the volume of the big ball with the tube up to the plane x = `cut`
// (analytic: the ball, the cylinder beyond the ball's cap it shares, the
// cap once).
constexpr double kTube = 2.5;

void dumbbell(core::Scene& scene) {
    const glm::dvec3 centre = 0.5 * (kBig + kSmall);
    const auto dims = dims_for(22, 2, 0.5);
    Volume v = sample_field(dims, oblique_affine(dims, 0.5, centre), [](const glm::dvec3& p) {
        const double tube = std::min({kTube - std::hypot(p.y - kBig.y, p.z - kBig.z), p.x - kBig.x, kSmall.x - p.x});
        return ct_edge(std::max({kRBig - glm::length(p - kBig), kRSmall - glm::length(p - kSmall), tube}), 0.6);
    });
    scene.set_volume(std::move(v), "dumbbell");
}

double ball_and_tube_to(double cut) {
    const double h0 = std::sqrt(kRBig * kRBig - kTube * kTube), cap = kRBig - h0;
    const double pi = 3.14159265358979323846;
    return 4.0 / 3.0 * pi * kRBig * kRBig * kRBig + pi * kTube * kTube * (cut - h0) -
           pi * cap * cap * (3 * kRBig - cap) / 3;
}

// The phantom `make` builds, written to `dir / name` (for the CLI).
std::string phantom_file(const TempDir& dir, void (*make)(core::Scene&), const std::string& name) {
    core::Scene scene;
    make(scene);
    const std::string path = dir / name;
    save_volume(scene.volume(), path, false);
    return path;
}

} // namespace

// The bar of "structures that touch": the big ball of a dumbbell within a
// box that cuts the tube halfway is a closed part whose volume is the
// analytic ball plus half tube within 0.5 %, cut at the box's left face
// with a cap of the tube's cross-section; the box is kept for sessions.
TEST(Structures, APartWithinABoxIsCutCappedAndMeasuredExactly) {
    core::Scene scene;
    dumbbell(scene);
    const SurfaceId all = scene.add_isosurfaces({kBallIso}).front();
    const auto whole = core::measure_surfaces(scene, {all}).front().measures;
    ASSERT_EQ(whole.components.size(), 1u) << "the tube joins the balls";
    const double cut = 15.0; // halfway along the tube between the balls' surfaces
    const LpsBox box{{-12, -12, -12}, {cut, 12, 12}};
    const auto c = core::isolate_component(scene, all, kBig + glm::dvec3(0, 0, kRBig), box);
    const SurfaceMeasures& m = c.measured.measures;
    EXPECT_TRUE(m.closed);
    const double expected_ml = ball_and_tube_to(cut) / 1000.0;
    std::printf("ball and half tube: %.6f mL, analytic %.6f (%.3f %%), +- %.6f\n", m.volume_ml, expected_ml,
                100.0 * (m.volume_ml / expected_ml - 1.0), m.volume_uncertainty_ml);
    EXPECT_NEAR(m.volume_ml, expected_ml, 0.005 * expected_ml);
    EXPECT_TRUE(std::isfinite(m.volume_uncertainty_ml));
    EXPECT_LE(m.bounds_max.x, cut + 1e-4);
    EXPECT_EQ(scene.info(c.surface).name, "iso 500 component 1 within box");
    ASSERT_TRUE(scene.info(c.surface).post.keep_within.has_value());
    const auto j = core::component_json(scene, c);
    ASSERT_TRUE(j.contains("within"));
    EXPECT_TRUE(j["within"]["cut"].get<bool>());
    ASSERT_EQ(j["within"]["faces_cut"].size(), 1u);
    EXPECT_EQ(j["within"]["faces_cut"][0]["face"], "left");
    const double disc = 3.14159265358979323846 * kTube * kTube;
    EXPECT_NEAR(j["within"]["cap_area_mm2"].get<double>(), disc, 0.03 * disc);
    EXPECT_NEAR(j["volume_ml"].get<double>(), m.volume_ml, 1e-12);
    // Its largest diameter: from the tube's cut rim to the far side of the
    // ball, |rim - centre| + R; its centroid on the tube's axis, at the
    // first moment of ball and half tube over their volume.
    EXPECT_NEAR(j["largest_diameter_mm"].get<double>(), std::hypot(cut, kTube) + kRBig, 0.15);
    {
        const double pi = 3.14159265358979323846, h0 = std::sqrt(kRBig * kRBig - kTube * kTube);
        const auto cap_moment = [&](double x) { return pi * (kRBig * kRBig * x * x / 2 - x * x * x * x / 4); };
        const double moment = pi * kTube * kTube * (cut * cut - h0 * h0) / 2 - (cap_moment(kRBig) - cap_moment(h0));
        const auto& g = j["centroid_lps"];
        ASSERT_FALSE(g.is_null());
        EXPECT_NEAR(g[0].get<double>(), moment / ball_and_tube_to(cut), 0.05);
        EXPECT_NEAR(g[1].get<double>(), 0.0, 0.05);
        EXPECT_NEAR(g[2].get<double>(), 0.0, 0.05);
    }
    // The whole shape on the same grid, for comparison: the cut is as exact as the rest.
    const double pi = 3.14159265358979323846;
    const auto cap = [&](double r) {
        const double h = r - std::sqrt(r * r - kTube * kTube);
        return pi * h * h * (3 * r - h) / 3;
    };
    const double whole_ml =
        (4.0 / 3.0 * pi * (std::pow(kRBig, 3) + std::pow(kRSmall, 3)) +
         pi * kTube * kTube *
             (kSmall.x - std::sqrt(kRBig * kRBig - kTube * kTube) - std::sqrt(kRSmall * kRSmall - kTube * kTube)) -
         cap(kRBig) - cap(kRSmall)) /
        1000.0;
    std::printf("whole dumbbell: %.6f mL, analytic %.6f (%.3f %%)\n", whole.volume_ml, whole_ml,
                100.0 * (whole.volume_ml / whole_ml - 1.0));
    EXPECT_NEAR(whole.volume_ml, whole_ml, 0.005 * whole_ml);
    EXPECT_LE(std::abs(m.volume_ml / expected_ml - 1.0), std::abs(whole.volume_ml / whole_ml - 1.0) + 0.001);
}

TEST(Structures, ABoxAroundTheWholeComponentCutsNothingAndOneApartFromItIsRefused) {
    core::Scene scene;
    two_balls(scene);
    const SurfaceId both = scene.add_isosurfaces({kBallIso}).front();
    const glm::dvec3 at = kSmall + glm::dvec3(0, 0, kRSmall);
    const auto plain = core::isolate_component(scene, both, at);
    const auto boxed = core::isolate_component(scene, both, at, LpsBox{kSmall - 8.0, kSmall + 8.0});
    EXPECT_EQ(boxed.measured.measures.triangles, plain.measured.measures.triangles);
    EXPECT_NEAR(boxed.measured.measures.volume_ml, plain.measured.measures.volume_ml, 1e-12);
    EXPECT_FALSE(core::component_json(scene, boxed)["within"]["cut"].get<bool>());
    try {
        core::isolate_component(scene, both, at, LpsBox{{100, 100, 100}, {110, 110, 110}});
        ADD_FAILURE() << "a box apart from the component was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no part within the box"), std::string::npos) << e.what();
    }
}

// A box cutting a ball on two sides: a closed slab whose caps are the
// ball's cross-sections there; the part comes back from a session.
TEST(Structures, ASlabOfABallIsClosedAndComesBackFromASession) {
    core::Scene scene;
    two_balls(scene);
    const SurfaceId both = scene.add_isosurfaces({kBallIso}).front();
    const LpsBox slab{{-20, -20, -3}, {20, 20, 4}};
    const auto c = core::isolate_component(scene, both, kBig, slab);
    EXPECT_TRUE(c.measured.measures.closed);
    const double pi = 3.14159265358979323846;
    // The ball's slab between z = -3 and 4: pi (R^2 z - z^3 / 3) between them.
    const auto f = [&](double z) { return pi * (kRBig * kRBig * z - z * z * z / 3.0); };
    const double expected_ml = (f(4) - f(-3)) / 1000.0;
    // On this coarser grid (1 mm) the ball itself measures -0.3 %; the slab's
    // equator band has more surface per volume.
    EXPECT_NEAR(c.measured.measures.volume_ml, expected_ml, 0.01 * expected_ml);
    // The cut adds nothing of its own: the slab and what lies below and
    // above it make up the whole component, to rounding.
    const Mesh ball = component_at(scene.mesh(both), kBig);
    double parts = measure_surface(clip_to_box(ball, slab)).volume_ml;
    parts += measure_surface(clip_to_box(ball, LpsBox{{-20, -20, -20}, {20, 20, -3}})).volume_ml;
    parts += measure_surface(clip_to_box(ball, LpsBox{{-20, -20, 4}, {20, 20, 20}})).volume_ml;
    EXPECT_NEAR(parts, measure_surface(ball).volume_ml, 1e-6 * measure_surface(ball).volume_ml);
    // The largest diameter is the largest distance between any two vertices (brute force).
    {
        const Mesh& part = scene.mesh(c.surface);
        double best = 0;
        for (std::size_t a = 0; a < part.positions.size(); ++a)
            for (std::size_t b = a + 1; b < part.positions.size(); ++b)
                best = std::max(best, glm::distance(glm::dvec3(part.positions[a]), glm::dvec3(part.positions[b])));
        const ShapeMeasures shape = measure_shape(part, true);
        EXPECT_DOUBLE_EQ(shape.feret_mm, best);
        EXPECT_LE(shape.hull_vertices, part.positions.size()); // a convex slab: most of them
        EXPECT_TRUE(shape.solid);
    }
    const auto caps = cap_areas(scene.mesh(c.surface), slab);
    EXPECT_NEAR(caps[4], pi * (kRBig * kRBig - 9.0), 0.02 * pi * kRBig * kRBig);  // inferior, z = -3
    EXPECT_NEAR(caps[5], pi * (kRBig * kRBig - 16.0), 0.02 * pi * kRBig * kRBig); // superior, z = 4
    TempDir dir;
    const std::string volume = dir / "balls.nrrd", path = dir / "s.json";
    save_volume(scene.volume(), volume, false);
    core::Scene reopened;
    reopened.open(volume);
    const SurfaceId again_both = reopened.add_isosurfaces({kBallIso}).front();
    const auto part = core::isolate_component(reopened, again_both, kBig, slab);
    core::save_session(core::capture_session(reopened, volume, "", std::nullopt, std::nullopt, FrameLook{}, {}), path);
    const auto again = core::open_session(path);
    ASSERT_EQ(again.surfaces.size(), 2u);
    const auto& info = again.scene->info(again.surfaces[1]);
    ASSERT_TRUE(info.post.keep_within.has_value());
    EXPECT_EQ(*info.post.keep_within, slab);
    EXPECT_NEAR(measure_surface(again.scene->mesh(again.surfaces[1])).volume_ml, part.measured.measures.volume_ml,
                1e-9);
}

TEST(Structures, TheCliMeasuresAPartWithinABox) {
    TempDir dir;
    const std::string volume = phantom_file(dir, dumbbell, "dumbbell.nrrd");
    const auto r = run_command(cli() + " measure " + volume +
                                   " --iso 500 --component-at 0,0,9 --within box=-12,-12,-12,15,12,12 --json",
                               false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["components"].size(), 1u);
    const auto& c = j["components"][0];
    EXPECT_TRUE(c["closed"].get<bool>());
    EXPECT_NEAR(c["volume_ml"].get<double>(), ball_and_tube_to(15.0) / 1000.0, 0.005 * ball_and_tube_to(15.0) / 1000.0);
    EXPECT_EQ(c["within"]["faces_cut"][0]["face"], "left");
    const auto text = run_command(
        cli() + " measure " + volume + " --iso 500 --component-at 0,0,9 --within box=-12,-12,-12,15,12,12", false);
    EXPECT_NE(text.out.find("within the box, cut at its left face"), std::string::npos) << text.out;
    for (const char* bad : {"box=1,2,3", "box=0,0,0,0,5,5", "cube=0,0,0,1,1,1", "box=a,b,c,d,e,f"}) {
        const auto b =
            run_command(cli() + " measure " + volume + " --iso 500 --component-at 0,0,9 --within " + bad, true);
        EXPECT_EQ(b.exit_code, 1) << bad;
        EXPECT_NE(b.out.find("--within"), std::string::npos) << bad << ": " << b.out;
    }
}

// Grown from a seed: a bright ball (1000 HU) touching a dimmer vessel
// (600 HU) along x. At iso 500 the two are one component; grown through
// 800 and up from the ball's centre, the region is the ball alone, its
// voxel volume within the stated partial-volume uncertainty of 4/3 pi r^3,
// and its surface closed; with a box the region stops at the box.
TEST(Structures, AGrownRegionSeparatesABallFromTheVesselItTouches) {
    core::Scene scene;
    const auto dims = dims_for(16, 2, 0.7);
    Volume v = sample_field(dims, oblique_affine(dims, 0.7, kBig), [](const glm::dvec3& p) {
        const double ball = ct_edge(kRBig - glm::length(p - kBig), 0.6) / 1000.0;
        const double vessel = ct_edge(3.0 - std::hypot(p.y, p.z), 0.6) / 1000.0 * (p.x > 0 ? 1.0 : 0.0);
        return std::max(1000.0 * ball, 600.0 * vessel);
    });
    scene.set_volume(std::move(v), "ball and vessel");
    const SurfaceId iso = scene.add_isosurfaces({300.0}).front();
    ASSERT_EQ(core::measure_surfaces(scene, {iso}).front().measures.components.size(), 1u) << "touching at 300";
    GrowOptions o;
    o.lo = 800;
    o.hi = 5000;
    const auto g = core::grow_structure(scene, kBig, o);
    const double pi = 3.14159265358979323846, ball_ml = 4.0 / 3.0 * pi * std::pow(kRBig, 3) / 1000.0;
    std::printf("grown ball: %.4f mL +- %.4f (%zu voxels, %zu on the boundary), analytic %.4f; surface %.4f mL\n",
                g.region.volume_ml, g.region.partial_volume_ml, g.region.voxels, g.region.boundary_voxels, ball_ml,
                g.measures.volume_ml);
    // The 800 level of the ball's edge lies inside its 500 boundary.
    const double r800 = kRBig - 0.505; // ct_edge = 800 where erf(d / (sqrt(2) 0.6)) = 0.6: d = 0.505 mm
    const double grown_ml = 4.0 / 3.0 * pi * std::pow(r800, 3) / 1000.0;
    EXPECT_NEAR(g.region.volume_ml, grown_ml, g.region.partial_volume_ml);
    EXPECT_LT(g.region.volume_ml, ball_ml) << "the vessel is left out";
    EXPECT_FALSE(g.region.reached_border);
    EXPECT_FALSE(g.region.reached_box);
    EXPECT_TRUE(g.measures.closed);
    EXPECT_NEAR(g.measures.volume_ml, g.region.volume_ml, g.region.partial_volume_ml);
    EXPECT_EQ(scene.info(g.surface).name, "grown 1");
    const auto j = core::grown_json(scene, g);
    EXPECT_EQ(j["voxels"].get<std::size_t>(), g.region.voxels);
    EXPECT_NEAR(j["largest_diameter_mm"].get<double>(), 2 * r800, 1.5);
    // Through 500 and up, the vessel is grown into too: far larger.
    o.lo = 500;
    const auto both = core::grow_structure(scene, kBig, o);
    EXPECT_GT(both.region.volume_ml, g.region.volume_ml + 0.1); // + the vessel out to the edge (about 0.15 mL)
    EXPECT_TRUE(both.region.reached_border) << "the vessel runs to the volume's edge";
    // Within a box that cuts the ball at x = 2: stopped there.
    o.lo = 800;
    o.within = LpsBox{{-20, -20, -20}, {2, 20, 20}};
    const auto cut = core::grow_structure(scene, kBig, o);
    EXPECT_TRUE(cut.region.reached_box);
    EXPECT_LT(cut.region.volume_ml, 0.75 * g.region.volume_ml);
    EXPECT_GT(cut.region.volume_ml, 0.5 * g.region.volume_ml);
    EXPECT_EQ(scene.info(cut.surface).name, "grown 3");
    // Refused: a seed outside the volume, outside the range, outside the box; an empty range.
    const auto refused = [&](const glm::dvec3& seed, GrowOptions opt, const char* why) {
        try {
            core::grow_structure(scene, seed, opt);
            ADD_FAILURE() << "accepted: " << why;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    GrowOptions plain;
    plain.lo = 800;
    plain.hi = 5000;
    refused(kBig + glm::dvec3(500, 0, 0), plain, "outside the volume");
    refused(kBig + glm::dvec3(0, 0, 15), plain, "is outside the range 800 to 5000");
    refused(kBig, GrowOptions{800, 5000, LpsBox{{5, 5, 5}, {9, 9, 9}}}, "outside the box");
    refused(kBig, GrowOptions{900, 800, std::nullopt}, "is empty");
}

TEST(Structures, TheCliGrowsARegionFromASeed) {
    TempDir dir;
    const std::string volume = phantom_file(dir, two_balls, "balls.nrrd");
    const auto r = run_command(cli() + " measure " + volume + " --grow-from 0,0,0 --grow-range 500,5000 --json", false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["grown"].size(), 1u);
    const auto& g = j["grown"][0];
    const double pi = 3.14159265358979323846, ball_ml = 4.0 / 3.0 * pi * std::pow(kRBig, 3) / 1000.0;
    EXPECT_NEAR(g["volume_ml"].get<double>(), ball_ml, g["partial_volume_ml"].get<double>());
    EXPECT_TRUE(g["closed"].get<bool>());
    EXPECT_EQ(g["surface"], "grown 1");
    const auto bad = run_command(cli() + " measure " + volume + " --grow-from 0,0,0", true);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.out.find("--grow-range"), std::string::npos) << bad.out;
    // The structures as a label map, and a name that is no NIfTI refused before any work.
    const std::string labels = dir / "grown.nii.gz";
    const auto written = run_command(cli() + " measure " + volume +
                                         " --grow-from 0,0,0 --grow-range 500,5000 --label-map " + labels + " --json",
                                     false);
    ASSERT_EQ(written.exit_code, 0) << written.out;
    EXPECT_EQ(nlohmann::json::parse(written.out)["label_map"]["labels"][0]["voxels"], g["voxels"]);
    EXPECT_TRUE(std::filesystem::exists(labels));
    EXPECT_TRUE(std::filesystem::exists(dir / "grown.ctbl"));
    const auto png = run_command(
        cli() + " measure " + volume + " --grow-from 0,0,0 --grow-range 500,5000 --label-map " + (dir / "a.png"), true);
    EXPECT_EQ(png.exit_code, 1);
    EXPECT_NE(png.out.find("--label-map"), std::string::npos) << png.out;
    // A value at a point needs no isosurface either.
    const auto value = run_command(cli() + " measure " + volume + " --value 0,0,0", false);
    EXPECT_EQ(value.exit_code, 0) << value.out;
    EXPECT_NE(value.out.find("value 1000"), std::string::npos) << value.out;
}

// The label map: a grown region's surface voxelized gives back exactly its
// voxels; a ball's isosurface the voxels whose centres it encloses (their
// volume that of the surface within half a voxel of its area); read back
// from the NIfTI on the volume's grid, with the colour table beside it.
TEST(Structures, TheLabelMapHoldsEachStructuresVoxels) {
    core::Scene scene;
    two_balls(scene);
    const SurfaceId both = scene.add_isosurfaces({kBallIso}).front();
    const auto small = core::isolate_component(scene, both, kSmall + glm::dvec3(0, 0, kRSmall));
    GrowOptions o;
    o.lo = 500;
    o.hi = 5000;
    const auto grown = core::grow_structure(scene, kBig, o);
    const auto map = core::structures_label_map(scene, {small.surface, grown.surface});
    ASSERT_EQ(map.entries.size(), 2u);
    EXPECT_EQ(map.entries[1].voxels, grown.region.voxels) << "the grown voxels, exactly";
    const double voxel_ml = grown.region.voxel_mm3 / 1000.0;
    const auto& sm = small.measured.measures;
    const double half_voxel_shell_ml = 0.5 * sm.area_mm2 * std::cbrt(grown.region.voxel_mm3) / 1000.0;
    EXPECT_NEAR(double(map.entries[0].voxels) * voxel_ml, sm.volume_ml, half_voxel_shell_ml);
    // Each voxel's label: none inside both, so the counts are the map's.
    std::size_t count[3] = {0, 0, 0};
    for (const auto l : map.labels.as<std::uint16_t>()) ++count[std::min<std::uint16_t>(l, 2)];
    EXPECT_EQ(count[1], map.entries[0].voxels);
    EXPECT_EQ(count[2], map.entries[1].voxels);
    TempDir dir;
    const std::string path = dir / "structures.nii.gz";
    const std::string table = core::save_label_map(map, path);
    EXPECT_EQ(table, dir / "structures.ctbl");
    const Volume back = load_volume(path);
    EXPECT_EQ(back.dims, scene.volume().dims);
    EXPECT_EQ(back.type, VoxelType::U16);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) EXPECT_NEAR(back.index_to_lps[c][r], scene.volume().index_to_lps[c][r], 1e-4);
    EXPECT_TRUE(std::equal(back.as<std::uint16_t>().begin(), back.as<std::uint16_t>().end(),
                           map.labels.as<std::uint16_t>().begin()));
    const std::string ctbl = read_file(table);
    EXPECT_NE(ctbl.find("1 iso_500_component_2 "), std::string::npos) << ctbl;
    EXPECT_NE(ctbl.find("2 grown_1 "), std::string::npos) << ctbl;
    EXPECT_THROW(core::save_label_map(map, dir / "structures.png"), Error);
}

TEST(Structures, AnIsolatedComponentIsTheComponentMeasureLists) {
    core::Scene scene;
    two_balls(scene);
    const SurfaceId both = scene.add_isosurfaces({kBallIso}).front();
    const auto whole = core::measure_surfaces(scene, {both}).front().measures;
    ASSERT_EQ(whole.components.size(), 2u);
    // A point just outside the small ball: its component is the second by volume.
    const auto c = core::isolate_component(scene, both, kSmall + glm::dvec3(0, 0, kRSmall + 0.4));
    EXPECT_EQ(c.component, 1u);
    EXPECT_EQ(c.components, 2u);
    EXPECT_EQ(scene.info(c.surface).name, "iso 500 component 2");
    EXPECT_EQ(scene.info(c.surface).kind, SurfaceInfo::Kind::Iso);
    const SurfacePart& part = whole.components[1];
    const SurfaceMeasures& m = c.measured.measures;
    EXPECT_EQ(m.triangles, part.triangles);
    EXPECT_NEAR(m.volume_ml, part.volume_ml, 1e-12 * part.volume_ml);
    EXPECT_NEAR(m.area_mm2, part.area_mm2, 1e-9 * part.area_mm2);
    EXPECT_EQ(m.bounds_min, part.bounds_min);
    EXPECT_EQ(m.bounds_max, part.bounds_max);
    EXPECT_TRUE(m.closed);
    EXPECT_EQ(m.components.size(), 1u);
    // Its uncertainty is the component's, not the whole surface's against the whole coarse surface.
    ASSERT_TRUE(std::isfinite(m.volume_uncertainty_ml));
    EXPECT_NEAR(m.volume_uncertainty_ml, part.volume_uncertainty_ml, 1e-9);
    EXPECT_NEAR(m.area_uncertainty_mm2, part.area_uncertainty_mm2, 1e-6);
    // And about the ball's volume: 4/3 pi r^3, within its uncertainty.
    const double ball_ml = 4.0 / 3.0 * 3.14159265358979 * std::pow(kRSmall, 3) / 1000.0;
    EXPECT_NEAR(m.volume_ml, ball_ml, m.volume_uncertainty_ml);
    // The parent stays.
    EXPECT_EQ(core::measure_surfaces(scene, {both}).front().measures.components.size(), 2u);
}

TEST(Structures, AnIsolatedComponentComesBackFromASession) {
    core::Scene scene;
    const std::string volume = data("headsq.nhdr");
    scene.open(volume);
    const SurfaceId bone = scene.add_isosurfaces({1150}).front();
    const Mesh& m = scene.mesh(bone);
    const glm::dvec3 at(m.positions[m.triangles[m.triangles.size() / 2][0]]);
    const auto c = core::isolate_component(scene, bone, at);
    TempDir dir;
    const std::string path = dir / "s.json";
    core::save_session(core::capture_session(scene, volume, "", std::nullopt, std::nullopt, FrameLook{}, {}), path);
    const auto again = core::open_session(path);
    ASSERT_EQ(again.surfaces.size(), 2u);
    const Mesh& back = again.scene->mesh(again.surfaces[1]);
    EXPECT_EQ(back.triangles.size(), scene.mesh(c.surface).triangles.size());
    EXPECT_EQ(again.scene->info(again.surfaces[1]).name, scene.info(c.surface).name);
    EXPECT_NEAR(measure_surface(back).volume_ml, c.measured.measures.volume_ml, 1e-12);
}

TEST(Structures, DistanceBetweenComponentsIsTheBruteForceMinimumAndTheGap) {
    core::Scene scene;
    two_balls(scene);
    const SurfaceId both = scene.add_isosurfaces({kBallIso}).front();
    const auto g = core::surface_gap(scene, both, both, kBig + glm::dvec3(kRBig, 0, 0), kSmall);
    EXPECT_EQ(g.name_a, "iso 500 component 1");
    EXPECT_EQ(g.name_b, "iso 500 component 2");
    // Brute force over the two components' triangles.
    const auto comps = triangle_components(scene.mesh(both));
    const Mesh big = component_mesh(scene.mesh(both), comps, 0), small = component_mesh(scene.mesh(both), comps, 1);
    const SurfaceDistance brute = surface_distance_brute_force(big, small);
    EXPECT_EQ(g.distance.pair.distance_mm, brute.pair.distance_mm);
    // The balls' gap (12 mm), within the extraction's error of each surface (well under a voxel).
    EXPECT_NEAR(g.distance.pair.distance_mm, 26.0 - kRBig - kRSmall, 0.15);
    EXPECT_NEAR(g.distance.pair.a.y, 0.0, 1.0);
    EXPECT_NEAR(g.distance.pair.b.x, kSmall.x - kRSmall, 0.15);
    // The same surface against itself: it touches.
    EXPECT_TRUE(core::surface_gap(scene, both, both).distance.touching);
    // As a Slicer line between the two points.
    const Markup line = core::gap_markup(g);
    EXPECT_EQ(line.type, MarkupType::Line);
    ASSERT_EQ(line.measurements.size(), 1u);
    EXPECT_NEAR(*line.measurements[0].value, g.distance.pair.distance_mm, 1e-12);
    EXPECT_THROW(core::surface_gap(scene, both, 99), Error);
}

TEST(Structures, TheCliIsolatesAndMeasuresDistances) {
    core::Scene scene;
    scene.open(data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    const Mesh& m = scene.mesh(ids[1]);
    const glm::dvec3 at(m.positions[m.triangles[m.triangles.size() / 3][1]]);
    const auto comps = triangle_components(m);
    const std::uint32_t k = comps[m.triangles.size() / 3];
    char point[128];
    std::snprintf(point, sizeof point, "%.9g,%.9g,%.9g", at.x, at.y, at.z);
    TempDir dir;
    const std::string out = dir / "gap.mrk.json";
    const auto r = run_command(cli() + " measure " + data("headsq.nhdr") + " --iso 500 --iso 1150 --component-at " +
                                   point + " --surface-distance 'iso 500' 'iso 1150' --json -o " + out,
                               false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["components"].size(), 1u);
    const auto& c = j["components"][0];
    EXPECT_EQ(c["from"], "iso 1150");
    EXPECT_EQ(c["component"].get<std::size_t>(), k + 1);
    // The component measure lists for the whole bone surface, to the digit.
    const auto& listed = j["surfaces"][1]["components"][k];
    EXPECT_NEAR(c["volume_ml"].get<double>(), listed["volume_ml"].get<double>(),
                1e-12 * std::abs(listed["volume_ml"].get<double>()) + 1e-15);
    EXPECT_EQ(c["triangles"], listed["triangles"]);
    EXPECT_EQ(c["closed"], listed["closed"]);
    ASSERT_EQ(j["surface_distances"].size(), 1u);
    const auto& d = j["surface_distances"][0];
    EXPECT_GE(d["distance_mm"].get<double>(), 0.0);
    const auto markups = load_markups(out);
    ASSERT_EQ(markups.markups.size(), 1u);
    EXPECT_EQ(markups.markups[0].name, "iso 500 to iso 1150");
    EXPECT_NEAR(*markups.markups[0].measurements[0].value, d["distance_mm"].get<double>(), 1e-9);
    // A name that is no surface: the flag, the name and the choices.
    const auto bad = run_command(
        cli() + " measure " + data("headsq.nhdr") + " --iso 500 --surface-distance 'iso 9' 'iso 500'", true);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.out.find("no surface is named 'iso 9'"), std::string::npos) << bad.out;
}

TEST(Structures, ALineThroughASolidSurfaceSaysWhichAndWhere) {
    core::Scene scene;
    two_balls(scene);
    const SurfaceId both = scene.add_isosurfaces({kBallIso}).front();
    // From left of the big ball to right of the small one, through both: four crossings.
    auto x = core::solid_crossings(scene, {-20, 0, 0}, {40, 0, 0});
    ASSERT_EQ(x.size(), 4u);
    const double expect[] = {-kRBig, kRBig, kSmall.x - kRSmall, kSmall.x + kRSmall};
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(x[i].surface, both);
        EXPECT_NEAR(x[i].point.x, expect[i], 0.15);
        EXPECT_NEAR(x[i].along_mm, expect[i] + 20.0, 0.15);
    }
    // Ends on the surface are where the points lie, not crossings: a ruler
    // from the big ball's surface to the small one's crosses nothing.
    const auto a = core::surface_at(scene, {kRBig + 1, 0, 0}),
               b = core::surface_at(scene, {kSmall.x - kRSmall - 1, 0, 0});
    EXPECT_TRUE(core::solid_crossings(scene, a.point, b.point).empty());
    // Translucent (0.3, below the pick's threshold) or hidden: seen through, not crossed.
    scene.info(both).opacity = 0.3f;
    EXPECT_TRUE(core::solid_crossings(scene, {-20, 0, 0}, {40, 0, 0}).empty());
    EXPECT_EQ(core::solid_crossings(scene, {-20, 0, 0}, {40, 0, 0}, 0.25).size(), 4u);
}

// ---- Scissors (renderer/surface/scissors.hpp) ----------------------------------------

namespace {

// A view straight down LPS +z onto the x-y plane, 1 pixel per mm:
// orthographic (parallel rays), or perspective from an eye 80 mm in front.
OutlineSweep ortho_z() {
    return {[](const glm::dvec3& p) { return std::optional<glm::dvec2>(glm::dvec2(p.x, p.y)); },
            [](const glm::dvec2& q) { return std::make_pair(glm::dvec3(q, -100.0), glm::dvec3(0, 0, 1)); }};
}
OutlineSweep perspective_z() {
    const glm::dvec3 eye(4, 1, -80);
    return {[eye](const glm::dvec3& p) -> std::optional<glm::dvec2> {
                const double d = p.z - eye.z;
                if (d <= 0) return std::nullopt;
                return glm::dvec2(eye.x + (p.x - eye.x) * 80 / d, eye.y + (p.y - eye.y) * 80 / d);
            },
            [eye](const glm::dvec2& q) {
                // The image plane is z = 0: the ray from the eye through (q, 0).
                return std::make_pair(eye, glm::normalize(glm::dvec3(q, 0.0) - eye));
            }};
}

double polygon_area(const std::vector<glm::dvec2>& p, const std::vector<std::array<std::size_t, 3>>& tris) {
    double a = 0;
    for (const auto& t : tris) {
        const glm::dvec2 u = p[t[1]] - p[t[0]], v = p[t[2]] - p[t[0]];
        const double twice = u.x * v.y - u.y * v.x;
        EXPECT_GT(twice, 0) << "each triangle counter-clockwise and not flat";
        a += 0.5 * twice;
    }
    return a;
}

} // namespace

// Ear clipping covers a non-convex polygon and a rectangle with a hole
// (joined by a bridge) exactly; the outline's checks.
TEST(Scissors, TheOutlinesGeometry) {
    // An L, clockwise: 4 triangles of area 3.
    const std::vector<glm::dvec2> l{{0, 0}, {0, 2}, {1, 2}, {1, 1}, {2, 1}, {2, 0}};
    const auto t = triangulate_polygon(l);
    EXPECT_EQ(t.size(), 4u);
    EXPECT_NEAR(polygon_area(l, t), 3.0, 1e-12);
    // A 10 x 10 square with a 2 x 2 hole, bridged: area 96.
    const std::vector<glm::dvec2> holed{{10, 5}, {10, 10}, {0, 10}, {0, 0}, {10, 0}, {10, 5},
                                        {6, 5},  {6, 4},   {4, 4},  {4, 6}, {6, 6},  {6, 5}};
    EXPECT_NEAR(polygon_area(holed, triangulate_polygon(holed)), 96.0, 1e-9);
    // A pointer's outline: points along the sides go, the corners stay.
    std::vector<glm::dvec2> drawn;
    for (int i = 0; i < 10; ++i) drawn.push_back({i, 0.01 * (i % 2)});
    for (int i = 0; i < 10; ++i) drawn.push_back({10, i});
    drawn.push_back({0, 10});
    EXPECT_EQ(simplify_outline(drawn, 0.5).size(), 4u);
    // A bow tie crosses itself; a square does not.
    EXPECT_TRUE(outline_crosses_itself({{0, 0}, {2, 2}, {2, 0}, {0, 2}}));
    EXPECT_FALSE(outline_crosses_itself({{0, 0}, {2, 0}, {2, 2}, {0, 2}}));
    Mesh none;
    EXPECT_THROW(scissors_cut(none, {{0, 0}, {2, 2}, {2, 0}, {0, 2}}, ortho_z(), true), Error);
    EXPECT_THROW(scissors_cut(none, {{0, 0}, {1, 1}}, ortho_z(), true), Error);
}

// The bar's dumbbell cut by scissors seen from above: a non-convex outline
// (a notch cut into it away from the shape) around the big ball, whose
// right side crosses the tube halfway, keeps the ball and half the tube:
// closed, within 0.5 % of the analytic volume and within 1e-6 of the box
// cut at the same plane; inside and outside add up to the whole; and a
// notch through the ball itself, swept in perspective, the same.
TEST(Scissors, AnOutlineSweptThroughTheDumbbellCutsItExactly) {
    core::Scene scene;
    dumbbell(scene);
    const SurfaceId all = scene.add_isosurfaces({kBallIso}).front();
    const Mesh& whole = scene.mesh(all);
    const SurfaceMeasures w = measure_surface(whole);
    ASSERT_TRUE(w.closed);
    const double cut = 15.0;
    // Around the big ball, its right side at x = cut, a notch from below away from the shape.
    const std::vector<glm::dvec2> outline{{-14, -14}, {-2, -14}, {0, -12}, {2, -14}, {cut, -14}, {cut, 14}, {-14, 14}};
    const ScissorsCut in = scissors_cut(whole, outline, ortho_z(), true);
    const SurfaceMeasures m = measure_surface(in.part);
    EXPECT_TRUE(m.closed);
    EXPECT_GT(in.pieces, 3u);
    const double expected_ml = ball_and_tube_to(cut) / 1000.0;
    const SurfaceMeasures box = measure_surface(clip_to_box(whole, LpsBox{{-20, -20, -20}, {cut, 20, 20}}));
    std::printf("scissors: ball and half tube %.6f mL, analytic %.6f (%.3f %%), box cut %.6f; %zu pieces\n",
                m.volume_ml, expected_ml, 100.0 * (m.volume_ml / expected_ml - 1.0), box.volume_ml, in.pieces);
    EXPECT_NEAR(m.volume_ml, expected_ml, 0.005 * expected_ml);
    EXPECT_NEAR(m.volume_ml, box.volume_ml, 1e-6 * box.volume_ml);
    EXPECT_NEAR(m.area_mm2, box.area_mm2, 1e-4 * box.area_mm2);
    const SurfaceMeasures out = measure_surface(scissors_cut(whole, outline, ortho_z(), false).part);
    EXPECT_TRUE(out.closed);
    EXPECT_NEAR(m.volume_ml + out.volume_ml, w.volume_ml, 1e-6 * w.volume_ml);

    // A notch into the ball from above, in perspective: both sides closed, adding up.
    const std::vector<glm::dvec2> notched{{-14, -14}, {cut, -14}, {cut, 14}, {3, 14}, {-1, 2}, {-5, 14}, {-14, 14}};
    for (const bool inside : {true, false}) {
        const ScissorsCut c = scissors_cut(whole, notched, perspective_z(), inside);
        const SurfaceMeasures s = measure_surface(c.part);
        const SurfaceMeasures other = measure_surface(scissors_cut(whole, notched, perspective_z(), !inside).part);
        std::printf("perspective notch, %s: %.6f mL (+ %.6f = %.6f of %.6f), %zu pieces, %zu with a part\n",
                    inside ? "inside" : "outside", s.volume_ml, other.volume_ml, s.volume_ml + other.volume_ml,
                    w.volume_ml, c.pieces, c.pieces_with_part);
        EXPECT_TRUE(s.closed);
        EXPECT_GT(s.volume_ml, 0.05 * w.volume_ml);
        EXPECT_NEAR(s.volume_ml + other.volume_ml, w.volume_ml, 1e-6 * w.volume_ml);
    }
}

// Through the core, on a camera: an outline around the whole image keeps
// the whole surface (and leaves nothing outside: refused); one around the
// left half of the image and its outside add up to the whole. Named
// "<parent> scissors <n>", measured closed.
TEST(Scissors, TheCoreCutsASurfaceAsTheCameraSeesIt) {
    core::Scene scene;
    dumbbell(scene);
    const SurfaceId all = scene.add_isosurfaces({kBallIso}).front();
    const SurfaceMeasures w = measure_surface(scene.mesh(all));
    core::ScissorsRequest r;
    r.width = 320;
    r.height = 240;
    r.camera = scene.camera(PatientView::Anterior, double(r.width) / r.height);
    r.outline = {{-5, -5}, {325, -5}, {325, 245}, {-5, 245}};
    const core::ComponentPlan everything = core::plan_scissors(scene, all, r);
    EXPECT_EQ(everything.info.name, "iso 500 scissors 1");
    EXPECT_TRUE(everything.measures.closed);
    EXPECT_NEAR(everything.measures.volume_ml, w.volume_ml, 1e-6 * w.volume_ml);
    r.keep_inside = false;
    EXPECT_THROW(core::plan_scissors(scene, all, r), Error);
    r.outline = {{-5, -5}, {160.3, -5}, {160.3, 245}, {-5, 245}};
    double sum = 0;
    for (const bool inside : {true, false}) {
        r.keep_inside = inside;
        const core::ComponentPlan half = core::plan_scissors(scene, all, r);
        EXPECT_TRUE(half.measures.closed);
        EXPECT_GT(half.measures.volume_ml, 0.1 * w.volume_ml);
        sum += half.measures.volume_ml;
    }
    EXPECT_NEAR(sum, w.volume_ml, 1e-6 * w.volume_ml);
}

// A click on a ball's isosurface seeds inside it: along the view ray into
// the ball, a point whose nearest voxel is within the range (grow_region
// grows from it); looking out of the ball, none within three voxels.
TEST(Structures, ASeedOnTheSurfaceIsFoundJustInside) {
    core::Scene scene;
    two_balls(scene);
    const Volume& v = scene.volume();
    const double hi = scene.value_range().max;
    const glm::dvec3 on = kBig + glm::dvec3(kRBig, 0, 0);
    const auto seed = seed_within(v, on, {-1, 0, 0}, kBallIso, hi);
    ASSERT_TRUE(seed.has_value());
    EXPECT_LT(glm::length(*seed - on), 3.0);
    GrowOptions o;
    o.lo = kBallIso;
    o.hi = hi;
    EXPECT_GT(grow_region(v, *seed, o).voxels, 0u);
    EXPECT_FALSE(seed_within(v, on + glm::dvec3(1.5, 0, 0), {1, 0, 0}, kBallIso, hi).has_value());
}

// Every part a user makes is kept with how it was made (PostProcessOptions
// steps, SurfaceInfo::grown), so a session makes the same parts again: a
// scissors cut of the isosurface, the big ball isolated from that cut (a
// step after the cut), a region grown from a seed and a scissors cut of
// that region. Each comes back with the same triangles and volume; the cut
// follows a moved iso value (made again from the new surface).
TEST(Structures, CutsAndGrownRegionsComeBackFromASessionAndFollowTheIsoValue) {
    TempDir dir;
    const std::string volume = phantom_file(dir, dumbbell, "dumbbell.nrrd"), path = dir / "s.json";
    core::Scene scene;
    scene.open(volume);
    const SurfaceId all = scene.add_isosurfaces({kBallIso}).front();
    core::ScissorsRequest r;
    r.width = 320;
    r.height = 240;
    r.camera = scene.camera(PatientView::Anterior, double(r.width) / r.height);
    r.outline = {{-5, -5}, {170.3, -5}, {150.1, 245}, {-5, 245}}; // a slanted cut through the tube
    const auto cut = core::add_component(scene, core::plan_scissors(scene, all, r));
    ASSERT_EQ(scene.info(cut.surface).post.steps.size(), 1u);
    EXPECT_EQ(scene.info(cut.surface).kind, SurfaceInfo::Kind::Iso); // it has the parent's iso value
    const auto ball = core::isolate_component(scene, cut.surface, kBig);
    ASSERT_EQ(scene.info(ball.surface).post.steps.size(), 2u); // the isolation is a step after the cut
    EXPECT_FALSE(scene.info(ball.surface).post.keep_at.has_value());
    GrowOptions o;
    o.lo = kBallIso;
    o.hi = scene.value_range().max;
    const auto grown = core::grow_structure(scene, kBig, o);
    ASSERT_TRUE(scene.info(grown.surface).grown.has_value());
    EXPECT_EQ(scene.info(grown.surface).grown->seed, kBig);
    r.keep_inside = false;
    const auto grown_cut = core::add_component(scene, core::plan_scissors(scene, grown.surface, r));
    EXPECT_TRUE(scene.info(grown_cut.surface).grown.has_value());

    core::save_session(core::capture_session(scene, volume, "", std::nullopt, std::nullopt, FrameLook{}, {}), path);
    const auto again = core::open_session(path);
    const auto ids = scene.surfaces();
    ASSERT_EQ(again.surfaces.size(), ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
        SCOPED_TRACE(scene.info(ids[i]).name);
        const SurfaceInfo& was = scene.info(ids[i]);
        const SurfaceInfo& is = again.scene->info(again.surfaces[i]);
        EXPECT_EQ(is.name, was.name);
        EXPECT_EQ(is.post, was.post);
        EXPECT_EQ(is.grown, was.grown);
        const Mesh& a = scene.mesh(ids[i]);
        const Mesh& b = again.scene->mesh(again.surfaces[i]);
        EXPECT_EQ(b.triangles.size(), a.triangles.size());
        const double va = measure_surface(a).volume_ml;
        EXPECT_NEAR(measure_surface(b).volume_ml, va, 1e-9 * std::abs(va));
        EXPECT_TRUE(measure_surface(b).closed);
    }
    // A moved iso value: the same cut of the new surface, part of it and closed.
    const double iso2 = kBallIso + 0.25 * (scene.value_range().max - kBallIso);
    const Mesh whole2 = scene.extract_isosurface(iso2);
    const Mesh cut2 = scene.extract_isosurface(iso2, {}, scene.info(cut.surface).post);
    const SurfaceMeasures w2 = measure_surface(whole2), c2 = measure_surface(cut2);
    EXPECT_TRUE(c2.closed);
    EXPECT_GT(c2.volume_ml, 0.3 * w2.volume_ml);
    EXPECT_LT(c2.volume_ml, 0.95 * w2.volume_ml);
    EXPECT_NE(c2.volume_ml, measure_surface(scene.mesh(cut.surface)).volume_ml);
    // `isoscope measure --session`: the same surfaces and volumes, each part with its making and shape.
    {
        const auto r = run_command(cli() + " measure --session " + path + " --json 2>/dev/null");
        ASSERT_EQ(r.exit_code, 0) << r.out;
        const auto mj = nlohmann::json::parse(r.out);
        ASSERT_EQ(mj["surfaces"].size(), ids.size());
        for (std::size_t i = 0; i < ids.size(); ++i) {
            const auto& s = mj["surfaces"][i];
            SCOPED_TRACE(s["surface"].get<std::string>());
            EXPECT_EQ(s["surface"], scene.info(ids[i]).name);
            const double v = measure_surface(scene.mesh(ids[i])).volume_ml;
            EXPECT_NEAR(s["volume_ml"].get<double>(), v, 1e-9 * std::abs(v));
            EXPECT_EQ(s.contains("part"), i > 0); // the whole isosurface is no part
        }
        const auto& ball_part = mj["surfaces"][2]["part"];
        ASSERT_EQ(ball_part["made"].size(), 2u);
        EXPECT_TRUE(ball_part["made"][0].contains("scissors_inside"));
        EXPECT_TRUE(ball_part["made"][1].contains("component_at"));
        EXPECT_NEAR(ball_part["largest_diameter_mm"].get<double>(),
                    measure_shape(scene.mesh(ball.surface), true).feret_mm, 1e-9);
        EXPECT_EQ(mj["surfaces"][3]["part"]["grown_range"][0].get<double>(), o.lo);
        // Two of the session's parts by name: their exact distance.
        const auto gap =
            run_command(cli() + " measure --session " + path + " --surface-distance '" + scene.info(ball.surface).name +
                        "' '" + scene.info(grown_cut.surface).name + "' --json 2>/dev/null");
        ASSERT_EQ(gap.exit_code, 0) << gap.out;
        const auto gj = nlohmann::json::parse(gap.out)["surface_distances"];
        ASSERT_EQ(gj.size(), 1u);
        EXPECT_NEAR(gj[0]["distance_mm"].get<double>(),
                    core::surface_gap(scene, ball.surface, grown_cut.surface).distance.pair.distance_mm, 1e-9);
        const auto both = run_command(cli() + " measure " + volume + " --session " + path + " 2>&1");
        EXPECT_NE(both.exit_code, 0);
        EXPECT_NE(both.out.find("not both"), std::string::npos) << both.out;
    }
    // A session whose cut is damaged says where.
    nlohmann::json j = nlohmann::json::parse(read_file(path));
    j["surfaces"][1]["steps"][0]["scissors"]["keep"] = "both";
    write_file(path, j.dump());
    const std::string why = error_of([&] { core::load_session(path); });
    EXPECT_NE(why.find("surfaces[1].steps[0].scissors.keep"), std::string::npos) << why;
    // As the desktop app's slider does it: the part's name follows the value, its own rest stays.
    const std::string rest = scene.info(cut.surface).name.substr(core::surface_name(false, kBallIso).size());
    scene.replace_surface(cut.surface, cut2, iso2, scene.info(cut.surface).post);
    EXPECT_EQ(scene.info(cut.surface).name, core::surface_name(false, iso2) + rest);
    EXPECT_EQ(rest, " scissors 1");
}

// What the scene keeps beside a mesh, worked out on a worker
// (prepare_mesh), is what it works out itself; an undone removal takes back
// the index it had, not a new one.
TEST(Structures, APreparedMeshHasTheScenesBoundsAndOutlineIndex) {
    core::Scene scene;
    two_balls(scene);
    Mesh m = scene.extract_isosurface(kBallIso);
    const core::PreparedMesh p = core::prepare_mesh(m);
    const SurfaceId plain = scene.add_mesh(std::move(m), SurfaceInfo{});
    const SurfaceId prepared = scene.add_mesh(p, SurfaceInfo{});
    EXPECT_EQ(scene.outline_index(prepared), p.outline);
    const auto ip = scene.outline_index(plain);
    EXPECT_EQ(ip->lo, p.outline->lo);
    EXPECT_EQ(ip->hi, p.outline->hi);
    EXPECT_EQ(p.bounds->min, scene.bounds().min);
    EXPECT_EQ(p.bounds->max, scene.bounds().max);
    const auto mesh = scene.shared_mesh(prepared);
    const SurfaceInfo info = scene.info(prepared);
    scene.remove_surface(prepared);
    scene.set_surface(prepared, mesh, info);
    EXPECT_EQ(scene.outline_index(prepared), p.outline);
}
