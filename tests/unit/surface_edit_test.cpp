// What the Surfaces panel's iso slider stands on (docs/gui.md "Surfaces
// panel"): the volume's range index (per-chunk min/max) made once and reused
// by later extractions, Scene::extract_isosurface off the GUI thread (the
// scene untouched), and adding, replacing and removing surfaces with stable
// ids. The GPU side (the renderer's copy after replace/remove) is
// tests/gl/scene_surfaces_test.cpp.
#include "renderer/core/scene.hpp"

#include <cmath>
#include <thread>

#include "io/color.hpp"
#include "io/error.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/analysis.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;

namespace {

// Two balls in a 96^3 float volume (value: distance inside the nearer
// ball's surface, mm): most chunks hold no surface at most values.
Volume two_balls() {
    auto v = Volume::dense({96, 96, 96}, VoxelType::F32, make_affine({1.0, 1.0, 1.0}, {0, 0, 0}));
    auto s = v.as<float>();
    for (std::int64_t k = 0; k < 96; ++k)
        for (std::int64_t j = 0; j < 96; ++j)
            for (std::int64_t i = 0; i < 96; ++i) {
                const double a =
                    12.0 - std::sqrt((i - 25.0) * (i - 25.0) + (j - 30.0) * (j - 30.0) + (k - 28.0) * (k - 28.0));
                const double b =
                    9.0 - std::sqrt((i - 70.0) * (i - 70.0) + (j - 64.0) * (j - 64.0) + (k - 66.0) * (k - 66.0));
                s[v.linear_index(i, j, k)] = float(std::max(a, b));
            }
    return v;
}

bool same_mesh(const Mesh& a, const Mesh& b) {
    return a.positions == b.positions && a.triangles == b.triangles && a.normals == b.normals;
}

} // namespace

TEST(RangeIndex, ReusedAcrossExtractionsVisitsOnlyChunksHoldingTheValue) {
    const Volume v = two_balls();
    ExtractOptions opt;
    opt.chunk_size = 16;
    const Extractor first(v, opt);
    const auto index = first.shared_index();
    for (double iso : {0.0, 3.5, -2.0, 8.0}) {
        const Extractor again(v, opt, index);
        EXPECT_EQ(again.shared_index(), index) << "the cached index was not reused";
        ExtractStats st;
        const auto chunked = again.extract(iso, &st);
        std::size_t active = 0;
        for (std::size_t id = 0; id < index->chunk_count(); ++id) active += index->active(id, iso);
        EXPECT_EQ(st.chunks_visited, active) << iso;
        EXPECT_LT(st.chunks_visited, st.chunks_total / 2) << "most chunks hold no surface at " << iso;
        // The same surface a fresh extractor makes.
        const Mesh reused = weld(chunked), fresh = extract_isosurface(v, iso, opt);
        EXPECT_GT(fresh.triangles.size(), 100u) << iso;
        EXPECT_TRUE(same_mesh(reused, fresh)) << iso;
    }
    // The summary is the chunks' true min/max.
    const auto& idx = *index;
    for (std::size_t id = 0; id < idx.chunk_count(); id += 7) {
        const auto c = idx.coords(id);
        double lo = 1e30, hi = -1e30;
        for (std::int64_t k = c[2] * 16; k <= std::min<std::int64_t>(c[2] * 16 + 16, 95); ++k)
            for (std::int64_t j = c[1] * 16; j <= std::min<std::int64_t>(c[1] * 16 + 16, 95); ++j)
                for (std::int64_t i = c[0] * 16; i <= std::min<std::int64_t>(c[0] * 16 + 16, 95); ++i) {
                    const double s = v.as<float>()[v.linear_index(i, j, k)];
                    lo = std::min(lo, s);
                    hi = std::max(hi, s);
                }
        EXPECT_EQ(idx.min(id), lo) << id;
        EXPECT_EQ(idx.max(id), hi) << id;
    }
}

TEST(RangeIndex, AnIndexThatDoesNotFitIsNotUsed) {
    const Volume v = two_balls();
    ExtractOptions opt;
    opt.chunk_size = 16;
    const auto index16 = Extractor(v, opt).shared_index();
    opt.chunk_size = 32;
    const Extractor other_size(v, opt, index16);
    EXPECT_NE(other_size.shared_index(), index16);
    EXPECT_EQ(other_size.index().chunk_size(), 32);
    auto small = Volume::dense({40, 40, 40}, VoxelType::F32, make_affine({1.0, 1.0, 1.0}, {0, 0, 0}));
    opt.chunk_size = 16;
    const Extractor other_volume(small, opt, index16);
    EXPECT_NE(other_volume.shared_index(), index16);
    EXPECT_EQ(other_volume.index().dims(), small.dims);
    // No index: a fresh one.
    EXPECT_NE(Extractor(v, opt, nullptr).shared_index(), nullptr);
}

TEST(RangeIndex, UpdateCopiesTheSharedIndexOnWrite) {
    Volume v = two_balls();
    ExtractOptions opt;
    opt.chunk_size = 16;
    Extractor x(v, opt);
    const auto before = x.shared_index();
    const double max0 = before->max(0);
    // Paint a bright box into chunk 0.
    for (std::int64_t k = 2; k < 6; ++k)
        for (std::int64_t j = 2; j < 6; ++j)
            for (std::int64_t i = 2; i < 6; ++i) v.as<float>()[v.linear_index(i, j, k)] = 50.0f;
    IndexBox box;
    box.lo = {2, 2, 2};
    box.hi = {5, 5, 5};
    auto s = x.extract(0.0);
    std::span<ChunkedSurface> one(&s, 1);
    x.update(box, one);
    EXPECT_EQ(x.index().max(0), 50.0);
    EXPECT_EQ(before->max(0), max0) << "an index another extractor shares changed under it";
    EXPECT_NE(x.shared_index(), before);
}

TEST(SurfaceEdit, ExtractLeavesTheSceneAloneAndMatchesTheCore) {
    core::Scene s;
    s.open(test::data("headsq.nhdr"));
    const Mesh m = s.extract_isosurface(500);
    EXPECT_TRUE(s.surfaces().empty()) << "extraction added a surface";
    EXPECT_TRUE(same_mesh(m, extract_isosurface(s.volume(), 500)));
    // With post-processing: keep-largest leaves one component.
    PostProcessOptions largest;
    largest.keep_largest = true;
    const Mesh one = s.extract_isosurface(1150, {}, largest);
    EXPECT_GT(measure_surface(extract_isosurface(s.volume(), 1150)).components.size(), 1u);
    EXPECT_EQ(measure_surface(one).components.size(), 1u);
    // Outside the range: empty, with the scene's warning.
    const Mesh none = s.extract_isosurface(1e6);
    EXPECT_TRUE(none.empty());
    ASSERT_EQ(none.warnings.size(), 1u);
    EXPECT_NE(none.warnings[0].find("outside the volume's value range"), std::string::npos);
    const auto r = s.value_range();
    const auto expected = s.volume().value_range();
    EXPECT_EQ(r.min, expected.min);
    EXPECT_EQ(r.max, expected.max);
    // Cancel through the progress function.
    EXPECT_THROW(s.extract_isosurface(500, {}, {}, [](double, std::string_view) { return false; }), Cancelled);
    EXPECT_TRUE(s.surfaces().empty());
    // No volume: a clear error.
    core::Scene empty;
    EXPECT_THROW(empty.extract_isosurface(500), Error);
}

TEST(SurfaceEdit, AddReplaceRemoveKeepIdsStable) {
    core::Scene s;
    s.open(test::data("headsq.nhdr"));
    PostProcessOptions smooth;
    smooth.smooth = 0.5;
    const auto skin = s.add_isosurface(s.extract_isosurface(500), 500);
    const auto bone = s.add_isosurface(s.extract_isosurface(1150, {}, smooth), 1150, smooth);
    const auto third = s.add_isosurface(s.extract_isosurface(800), 800, {}, glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_EQ(skin, 1u);
    EXPECT_EQ(bone, 2u);
    EXPECT_EQ(third, 3u);
    EXPECT_EQ(s.info(skin).name, "iso 500");
    EXPECT_EQ(s.info(skin).kind, core::SurfaceInfo::Kind::Iso);
    EXPECT_EQ(s.info(skin).source, test::data("headsq.nhdr"));
    // The default colours, linear RGB, stated here rather than read from the palette under test.
    EXPECT_EQ(s.info(skin).color, linear_from_hex("#e0906c")) << "the first skin-toned";
    EXPECT_EQ(s.info(bone).color, linear_from_hex("#f9f6ec")) << "then bone white";
    EXPECT_EQ(s.info(third).color, glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_EQ(s.info(bone).post.smooth, 0.5);

    // Replace: a new mesh and value; colour, opacity, visibility stay; the automatic name follows.
    s.info(skin).opacity = 0.3f;
    s.info(skin).color = {0.5f, 0.5f, 0.5f};
    PostProcessOptions largest;
    largest.keep_largest = true;
    s.replace_surface(skin, s.extract_isosurface(600, {}, largest), 600, largest);
    EXPECT_EQ(s.info(skin).value, 600.0);
    EXPECT_EQ(s.info(skin).name, "iso 600");
    EXPECT_TRUE(s.info(skin).post.keep_largest);
    EXPECT_EQ(s.info(skin).opacity, 0.3f);
    EXPECT_EQ(s.info(skin).color, glm::vec3(0.5f));
    EXPECT_EQ(measure_surface(s.mesh(skin)).components.size(), 1u);
    // A name the user gave stays.
    s.info(bone).name = "skull";
    s.replace_surface(bone, s.extract_isosurface(1200), 1200, {});
    EXPECT_EQ(s.info(bone).name, "skull");
    EXPECT_EQ(s.mesh(bone).triangles.size(), extract_isosurface(s.volume(), 1200).triangles.size());

    // Bounds follow the new mesh.
    s.info(bone).visible = false;
    s.info(third).visible = false;
    Bounds expected;
    for (const auto& p : s.mesh(skin).positions) expected.add(glm::dvec3(p));
    EXPECT_EQ(s.bounds().min, expected.min);
    EXPECT_EQ(s.bounds().max, expected.max);
    s.info(bone).visible = true;
    s.info(third).visible = true;

    // Remove: gone from the list, its id not reused, the others keep theirs.
    s.remove_surface(bone);
    EXPECT_EQ(s.surfaces(), (std::vector<core::SurfaceId>{skin, third}));
    EXPECT_FALSE(s.has_surface(bone));
    EXPECT_TRUE(s.has_surface(third));
    EXPECT_THROW(s.info(bone), Error);
    EXPECT_THROW(s.mesh(bone), Error);
    EXPECT_THROW(s.replace_surface(bone, Mesh{}, 1, {}), Error);
    EXPECT_THROW(s.remove_surface(bone), Error);
    EXPECT_EQ(s.info(third).value, 800.0);
    const auto fourth = s.add_isosurface(s.extract_isosurface(900), 900);
    EXPECT_EQ(fourth, 4u) << "a removed id is never reused";
    EXPECT_THROW(s.info(0), Error);
    EXPECT_THROW(s.info(99), Error);
}

TEST(SurfaceEdit, RestoreARemovedSurfaceUnderItsId) {
    // An undone removal: the surface comes back with its id, place, mesh and properties.
    core::Scene s;
    s.set_volume(two_balls(), "two balls");
    const auto a = s.add_isosurface(s.extract_isosurface(0), 0);
    const auto b = s.add_isosurface(s.extract_isosurface(4), 4);
    const auto c = s.add_isosurface(s.extract_isosurface(8), 8);
    s.info(b).opacity = 0.25f;
    s.info(b).color = glm::vec3(0.1f, 0.2f, 0.3f);
    s.info(b).visible = false;
    const core::SurfaceInfo kept = s.info(b);
    Mesh mesh = s.mesh(b);
    const std::size_t triangles = mesh.triangles.size();
    EXPECT_THROW(s.restore_surface(b, mesh, kept), Error) << "not removed";
    s.remove_surface(b);
    EXPECT_THROW(s.restore_surface(0, mesh, kept), Error);
    EXPECT_THROW(s.restore_surface(9, mesh, kept), Error) << "never added";
    core::SurfaceInfo bad = kept;
    bad.opacity = 2;
    EXPECT_THROW(s.restore_surface(b, mesh, bad), Error);
    EXPECT_FALSE(s.has_surface(b));
    s.restore_surface(b, std::move(mesh), kept);
    EXPECT_TRUE(s.has_surface(b));
    EXPECT_EQ(s.surfaces(), (std::vector<core::SurfaceId>{a, b, c})) << "back in its place";
    EXPECT_EQ(s.mesh(b).triangles.size(), triangles);
    EXPECT_EQ(s.info(b).opacity, 0.25f);
    EXPECT_EQ(s.info(b).color, glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_FALSE(s.info(b).visible);
    EXPECT_EQ(s.info(b).value, 4.0);
    EXPECT_EQ(s.add_isosurface(Mesh{}, 2), 4u) << "ids stay unique";
    s.info(b).visible = true;
    Bounds expected;
    for (const auto id : {a, b, c})
        for (const auto& p : s.mesh(id).positions) expected.add(glm::dvec3(p));
    EXPECT_EQ(s.bounds().min, expected.min) << "its bounds count again";
    EXPECT_EQ(s.bounds().max, expected.max);
}

TEST(SurfaceEdit, ExtractOnAWorkerWhileTheSceneIsEdited) {
    // The panel's pattern: a worker extracts while the GUI thread edits the
    // surfaces and swaps meshes in.
    core::Scene s;
    s.open(test::data("headsq.nhdr"));
    const auto skin = s.add_isosurface(s.extract_isosurface(500), 500);
    std::vector<Mesh> made(6);
    std::thread worker([&] {
        for (std::size_t i = 0; i < made.size(); ++i) made[i] = s.extract_isosurface(600 + 50.0 * double(i));
    });
    for (int i = 0; i < 50; ++i) {
        const auto id = s.add_isosurface(Mesh{}, 100 + i);
        s.info(skin).opacity = float(i % 10) / 10.0f;
        s.remove_surface(id);
    }
    worker.join();
    for (std::size_t i = 0; i < made.size(); ++i) {
        EXPECT_TRUE(same_mesh(made[i], extract_isosurface(s.volume(), 600 + 50.0 * double(i)))) << i;
        s.replace_surface(skin, std::move(made[i]), 600 + 50.0 * double(i), {});
    }
    EXPECT_EQ(s.surfaces().size(), 1u);
    EXPECT_EQ(s.info(skin).value, 850.0);
}
