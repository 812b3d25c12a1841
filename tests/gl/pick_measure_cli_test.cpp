// Picking and measuring through the core API and the CLI, on the bundled
// CT: the visible pick through skin at opacity 0.3 is the bone behind it;
// picked positions agree with a ray cast of the written mesh to 1e-3 mm;
// the value there is the trilinear interpolation computed here; a pick's
// JSON has what the issue names; a CT's values are in HU, and the slice
// readout of a picked point says what the pick says; `measure` writes Slicer
// markups that read back, and refuses bad points naming the flag.
#include <cmath>
#include <filesystem>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/core/value_unit.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

// Trilinear interpolation written out here: the volume's samples at the
// eight corners around the continuous index of `lps`.
double trilinear(const Volume& v, const glm::dvec3& lps) {
    const glm::dvec4 c = glm::inverse(v.index_to_lps) * glm::dvec4(lps, 1.0);
    const glm::dvec3 f = glm::floor(glm::dvec3(c));
    const glm::dvec3 t = glm::dvec3(c) - f;
    double sum = 0;
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
                const auto at = [&](int d, int o) {
                    return std::clamp<std::int64_t>(std::int64_t(f[d]) + o, 0, v.dims[std::size_t(d)] - 1);
                };
                const double w = (i ? t.x : 1 - t.x) * (j ? t.y : 1 - t.y) * (k ? t.z : 1 - t.z);
                sum += w * v.value(at(0, i), at(1, j), at(2, k));
            }
    return sum;
}

// The nearest crossing of the ray with the mesh (brute force, double precision).
std::optional<double> ray_cast(const Mesh& m, const Ray& ray) {
    std::optional<double> best;
    for (const auto& tri : m.triangles) {
        const glm::dvec3 a(m.positions[tri[0]]), b(m.positions[tri[1]]), c(m.positions[tri[2]]);
        const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(ray.dir, e2);
        const double det = glm::dot(e1, p);
        if (std::abs(det) < 1e-300) continue;
        const glm::dvec3 s = ray.origin - a, q = glm::cross(s, e1);
        const double u = glm::dot(s, p) / det, v = glm::dot(ray.dir, q) / det, t = glm::dot(e2, q) / det;
        if (u < -1e-9 || v < -1e-9 || u + v > 1 + 1e-9 || t <= 0) continue;
        if (!best || t < *best) best = t;
    }
    return best;
}

core::RenderRequest request() {
    core::RenderRequest req;
    req.width = req.height = 256;
    req.annotations = false;
    return req;
}

} // namespace

TEST(PickCore, ThroughSkinTheVisiblePickIsTheBoneAndPositionsAreExact) {
    core::Scene scene;
    scene.open(test::data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    scene.info(ids[0]).opacity = 0.3f;
    TempDir dir;
    const std::string skin_file = dir / "skin.ply", bone_file = dir / "bone.ply";
    scene.export_mesh(ids[0], skin_file);
    scene.export_mesh(ids[1], bone_file);
    const Mesh written[2] = {load_mesh(skin_file), load_mesh(bone_file)};
    const auto req = request();
    int bone_seen = 0, checked = 0;
    // Pixels across the forehead and cheeks: skin, then bone.
    for (const auto& [x, y] :
         std::vector<std::pair<int, int>>{{128, 70}, {110, 80}, {150, 80}, {96, 120}, {160, 120}}) {
        core::PickRequest p;
        p.x = x;
        p.y = y;
        p.all_layers = true;
        const auto r = core::pick(scene, req, p);
        SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
        ASSERT_TRUE(r.complete);
        ASSERT_GE(r.layers.size(), 2u);
        EXPECT_EQ(r.layers[0].name, "iso 500") << "the skin is nearest";
        ASSERT_TRUE(r.visible);
        if (r.layers[*r.visible].name == "iso 1150") ++bone_seen;
        Camera cam = scene.camera(PatientView::Anterior, 1.0);
        const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5, req.width, req.height);
        for (const auto& l : r.layers) {
            const Mesh& m = written[l.surface == ids[0] ? 0 : 1];
            // The written mesh, ray cast here: the nearest crossing at or beyond this layer's own.
            const double t_layer = glm::dot(l.lps - ray.origin, ray.dir);
            Mesh one;
            one.positions = m.positions;
            one.triangles = {m.triangles[l.triangle]};
            const auto t = ray_cast(one, ray);
            if (!l.on_triangle) continue; // the rasterizer gave an edge pixel to this neighbour
            ASSERT_TRUE(t);
            EXPECT_NEAR(glm::length(ray.origin + *t * ray.dir - l.lps), 0.0, 1e-3)
                << l.name << " triangle " << l.triangle;
            EXPECT_NEAR(t_layer, *t, 1e-3);
            ++checked;
            // The value there: trilinear in the volume, computed here.
            ASSERT_TRUE(l.value);
            EXPECT_NEAR(*l.value, trilinear(scene.volume(), l.lps), 1e-6);
            EXPECT_EQ(l.unit, "") << "headsq has no modality: its values have no unit";
            EXPECT_NEAR(glm::length(l.normal), 1.0, 1e-9);
        }
        // Layers: front to back, shares sum to at most 1.
        double share = 0;
        for (std::size_t i = 0; i < r.layers.size(); ++i) {
            share += r.layers[i].share;
            if (i) {
                EXPECT_GT(r.layers[i].depth_mm, r.layers[i - 1].depth_mm);
            }
        }
        EXPECT_LE(share, 1.0 + 1e-6);
    }
    EXPECT_GE(bone_seen, 4) << "through one skin layer at 0.3 the bone is what is seen";
    EXPECT_GE(checked, 8);
}

TEST(PickCore, TheCliPrintsTheIssuesJson) {
    const auto r = test::run_command(
        test::cli() + " pick " + test::data("headsq.nhdr") +
            " --iso 500 --iso 1150 --opacity 0.3 --size 256x256 --at 128,70 --rect 120,60,16,16 --all-layers --json",
        false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_TRUE(j["visible"].is_number());
    const auto& layers = j["layers"];
    ASSERT_GE(layers.size(), 2u);
    for (const char* key :
         {"surface", "iso", "lps", "normal", "triangle", "depth_mm", "alpha", "share", "value", "unit", "voxel"})
        EXPECT_TRUE(layers[0].contains(key)) << key;
    // headsq says no modality: a value, with no unit, and no "hu" key.
    EXPECT_TRUE(layers[0]["value"].is_number());
    EXPECT_TRUE(layers[0]["unit"].is_null());
    EXPECT_FALSE(layers[0].contains("hu"));
    EXPECT_EQ(layers[0]["iso"].get<double>(), 500.0);
    EXPECT_EQ(j["view"].size(), 16u);
    EXPECT_EQ(j["projection"].size(), 16u);
    EXPECT_GT(j["rect"]["triangles"].size(), 10u);
    // Off the image: a clear error naming the pixel.
    const auto off = test::run_command(
        test::cli() + " pick " + test::data("headsq.nhdr") + " --iso 500 --size 64x64 --at 64,3", true);
    EXPECT_EQ(off.exit_code, 1);
    EXPECT_NE(off.out.find("64,3 is outside the 64x64 image"), std::string::npos) << off.out;
    const auto bad = test::run_command(test::cli() + " pick " + test::data("headsq.nhdr") + " --iso 500 --at 3", true);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.out.find("--at"), std::string::npos) << bad.out;
}

namespace {

// headsq's samples under a MetaImage header that says CT.
std::string headsq_as_ct(const TempDir& dir) {
    fs::copy_file(test::data("headsq.raw"), dir / "headsq.raw");
    test::write_file(dir / "ct.mhd", "Modality = MET_MOD_CT\n" + test::read_file(test::data("headsq.mhd")));
    return dir / "ct.mhd";
}

} // namespace

// On a CT the pick's value is in HU (JSON: "unit": "HU"), and the slice
// views' readout of the picked point (sample_at_pixel at that point's pixel
// of each plane through it) gives the same value and the same text.
TEST(PickCore, ACtPickIsInHuAndTheSliceReadoutAgrees) {
    TempDir dir;
    core::Scene scene;
    scene.open(headsq_as_ct(dir));
    scene.add_isosurfaces({500, 1150});
    core::PickRequest p;
    p.x = 128;
    p.y = 70;
    const auto r = core::pick(scene, request(), p);
    ASSERT_TRUE(r.visible);
    const core::PickLayer& l = r.layers[*r.visible];
    ASSERT_TRUE(l.value);
    EXPECT_EQ(l.unit, "HU");
    const auto j = core::pick_json(r)["layers"][*r.visible];
    EXPECT_EQ(j["value"].get<double>(), *l.value);
    EXPECT_EQ(j["unit"], "HU");
    EXPECT_FALSE(j.contains("hu"));
    const std::string readout = core::value_readout(*l.value, l.unit);
    EXPECT_NE(readout.find(" HU"), std::string::npos) << readout;

    const Volume& v = scene.volume();
    auto planes = core::default_planes(v);
    core::set_crosshair(planes, l.lps);
    for (const auto& plane : planes) {
        SCOPED_TRACE(core::slice_orientation_name(plane.orientation));
        const core::SliceGrid g = core::slice_grid(plane, 300, 200);
        const core::SlicePoint at = core::lps_to_pixel(g, l.lps);
        EXPECT_NEAR(at.distance_mm, 0.0, 1e-9);
        const auto s = core::sample_at_pixel(v, g, at.pixel);
        ASSERT_TRUE(s);
        EXPECT_NEAR(s->value, *l.value, 1e-6);
        EXPECT_EQ(core::value_readout(s->value, core::value_unit(v)), readout);
    }
}

TEST(MeasureCli, SurfacesPointsAndSlicerMarkups) {
    TempDir dir;
    const std::string out = dir / "m.mrk.json";
    const auto r = test::run_command(
        test::cli() + " measure " + test::data("headsq.nhdr") +
            " --iso 1150 --distance 0,0,0 30,40,0 --angle 10,0,0 0,0,0 0,0,10 --hu -98.9,20,-12 --json -o " + out,
        false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["surfaces"].size(), 1u);
    const auto& s = j["surfaces"][0];
    EXPECT_GT(s["area_mm2"].get<double>(), 1000.0);
    EXPECT_EQ(s["closed"].get<bool>(), false) << "the skull is cut by the scan's border";
    EXPECT_EQ(s["volume_kind"].get<std::string>(), "lower bound");
    EXPECT_GT(s["boundary"]["length_mm"].get<double>(), 0.0);
    EXPECT_TRUE(s["volume_uncertainty_ml"].is_number());
    EXPECT_NEAR(j["distances"][0]["distance_mm"].get<double>(), 50.0, 1e-9);
    EXPECT_NEAR(j["angles"][0]["angle_deg"].get<double>(), 90.0, 1e-9);
    EXPECT_TRUE(j["values"][0]["value"].is_number());
    EXPECT_TRUE(j["values"][0]["unit"].is_null()) << "headsq says no modality";
    // --value is the option's name, --hu its earlier one: the same point, the same text.
    const std::string measure = test::cli() + " measure " + test::data("headsq.nhdr") + " --iso 1150";
    const auto by_value = test::run_command(measure + " --value -98.9,20,-12", false);
    const auto by_hu = test::run_command(measure + " --hu -98.9,20,-12", false);
    ASSERT_EQ(by_value.exit_code, 0) << by_value.out;
    ASSERT_EQ(by_hu.exit_code, 0) << by_hu.out;
    EXPECT_EQ(by_value.out, by_hu.out);
    const std::string last = "\n" + core::value_readout(j["values"][0]["value"].get<double>(), "") + "\n";
    ASSERT_GE(by_value.out.size(), last.size());
    EXPECT_EQ(by_value.out.substr(by_value.out.size() - last.size()), last) << by_value.out;
    const MarkupsFile f = load_markups(out);
    ASSERT_EQ(f.markups.size(), 3u);
    EXPECT_EQ(f.markups[0].type, MarkupType::Line);
    ASSERT_FALSE(f.markups[0].measurements.empty());
    EXPECT_NEAR(*f.markups[0].measurements[0].value, 50.0, 1e-9);
    EXPECT_EQ(f.markups[1].type, MarkupType::Angle);
    EXPECT_NEAR(*f.markups[1].measurements[0].value, 90.0, 1e-9);
    EXPECT_EQ(f.markups[2].type, MarkupType::Fiducial);
    // A bad point names the flag and writes nothing.
    const std::string bad_out = dir / "bad.mrk.json";
    const auto bad = test::run_command(
        test::cli() + " measure " + test::data("headsq.nhdr") + " --iso 1150 --distance 0,0 1,1,1 -o " + bad_out, true);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.out.find("--distance: expected a point x,y,z in LPS mm, got '0,0'"), std::string::npos) << bad.out;
    EXPECT_FALSE(fs::exists(bad_out));
}
