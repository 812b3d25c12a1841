// isoscope render as a real process: PNG with embedded metadata, AOVs as EXR,
// transparent background, annotation scale, and a golden image.
#include <cmath>
#include <filesystem>
#include <sstream>

#include "tests/support/image_compare.hpp"
#include "io/image.hpp"
#include "renderer/core/session.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;

namespace {

std::vector<double> numbers(const std::string& s) {
    std::istringstream in(s);
    std::vector<double> v;
    double x;
    while (in >> x) v.push_back(x);
    return v;
}

std::string render(const std::string& args) {
    const auto r = test::run_command(test::cli() + " render " + args, true);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return r.out;
}

} // namespace

TEST(RenderCli, PngWithMetadataAndAnnotations) {
    TempDir dir;
    const std::string out =
        render(test::data("headsq.nhdr") + " --iso 500 --iso 1150 --size 200x150 --stats -o " + (dir / "a.png"));
    EXPECT_NE(out.find("gbuffer"), std::string::npos) << out;
    EXPECT_NE(out.find("overlay"), std::string::npos) << out;
    ImageMetadata meta;
    const Image img = load_image(dir / "a.png", &meta);
    EXPECT_EQ(img.width, 200);
    EXPECT_EQ(img.height, 150);
    auto& t = meta.text;
    EXPECT_EQ(t["isoscope:iso"], "500,1150");
    EXPECT_NE(t["isoscope:legend"].find("iso 500: colour #"), std::string::npos) << t["isoscope:legend"];
    EXPECT_NE(t["isoscope:legend"].find("\niso 1150: colour #"), std::string::npos) << t["isoscope:legend"];
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x96 --no-legend -o " + (dir / "b.png"));
    ImageMetadata without;
    load_image(dir / "b.png", &without);
    EXPECT_EQ(without.text.count("isoscope:legend"), 0u) << "--no-legend";
    EXPECT_NE(t["isoscope:input"].find("headsq.nhdr"), std::string::npos);
    EXPECT_EQ(t["isoscope:input_sha256"].size(), 64u);
    EXPECT_NE(t["isoscope:camera"].find("eye"), std::string::npos);
    const auto view = numbers(t["isoscope:view"]), proj = numbers(t["isoscope:projection"]);
    ASSERT_EQ(view.size(), 16u);
    ASSERT_EQ(proj.size(), 16u);
    // Anterior view: the view matrix's third row is the camera's back direction, +y... i.e. the
    // camera looks along +y (towards posterior), so the eye-space z axis is -y in LPS.
    EXPECT_NEAR(view[1 + 4 * 0], 0.0, 1e-6);  // column-major: element (row 1, col 0)
    EXPECT_NEAR(view[2 + 4 * 1], -1.0, 1e-6); // row 2 (eye z) of column 1 (world y)
    EXPECT_LT(proj[11], 0.0);                 // perspective: clip.w = -z_eye
}

TEST(RenderCli, AovsAreFloatExrWithMetadata) {
    TempDir dir;
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x96 --aov depth -o " + (dir / "d.exr"));
    ImageMetadata meta;
    const Image d = load_image(dir / "d.exr", &meta);
    ASSERT_TRUE(d.is_float);
    EXPECT_EQ(d.channels, 1);
    EXPECT_NE(meta.text["isoscope:aov"].find("depth"), std::string::npos);
    EXPECT_FALSE(meta.text["isoscope:view"].empty());
    const float centre = d.floats[48 * 96 + 48], corner = d.floats[0];
    EXPECT_TRUE(std::isfinite(centre) && centre > 0) << centre;
    EXPECT_TRUE(std::isinf(corner));
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x96 --aov normal -o " + (dir / "n.exr"));
    const Image n = load_image(dir / "n.exr");
    EXPECT_EQ(n.channels, 3);
    const float* c = &n.floats[(48 * 96 + 48) * 3];
    EXPECT_NEAR(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), 1.0, 1e-3);
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x96 --aov id -o " + (dir / "i.exr"));
    EXPECT_EQ(load_image(dir / "i.exr").floats[48 * 96 + 48], 1.0f);
    // A float AOV cannot go to PNG; the error names the file.
    const auto bad = test::run_command(
        test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --aov depth -o " + (dir / "d.png"), true);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.out.find("d.png"), std::string::npos) << bad.out;
}

TEST(RenderCli, TransparentBackgroundAndScaledAnnotations) {
    TempDir dir;
    render(test::data("headsq.nhdr") + " --iso 500 --size 120x90 --transparent --no-annotations -o " + (dir / "t.png"));
    const Image t = load_image(dir / "t.png");
    ASSERT_EQ(t.channels, 4);
    EXPECT_EQ(t.bytes[3], 0) << "corner is transparent";
    EXPECT_EQ(t.bytes[(45 * 120 + 60) * 4 + 3], 255) << "the head is opaque";
    // The same view at 2x with --scale 2: annotations cover about 4x the pixels.
    auto annotated = [&](int w, int h, float s) {
        const std::string p = dir / ("s" + std::to_string(w) + ".png");
        render(test::data("headsq.nhdr") + " --iso 500 --size " + std::to_string(w) + "x" + std::to_string(h) +
               " --scale " + std::to_string(s) + " -o " + p);
        const Image a = load_image(p);
        std::size_t bright = 0; // the annotation colour (near white-yellow) on the background
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width / 3; ++x) { // left third: orientation letter and scale bar, no head
                const auto* px = &a.bytes[(std::size_t(y) * a.width + x) * 4];
                if (px[0] > 200 && px[1] > 200 && px[2] > 170) ++bright;
            }
        return double(bright);
    };
    const double one = annotated(160, 120, 1.0), two = annotated(320, 240, 2.0);
    ASSERT_GT(one, 20.0);
    EXPECT_NEAR(two / one, 4.0, 1.0);
}

TEST(RenderCli, GoldenImage) {
    // Tolerance: llvmpipe is deterministic, but GPUs rasterize and round
    // differently; allow 1 % of pixels to differ by more than 24/255 in any
    // channel (silhouette edges) and a mean absolute difference of 2/255.
    // Without the legend, which has tests of its own (tests/gl/legend_test.cpp).
    TempDir dir;
    render(test::data("headsq.nhdr") + " --iso 500 --size 160x120 --no-legend -o " + (dir / "actual.png"));
    const std::string golden = std::string(ISOSCOPE_SOURCE_DIR) + "/tests/golden/headsq_skin_anterior_160x120.png";
    EXPECT_TRUE(test::matches_golden(load_image(dir / "actual.png"), golden,
                                     {.off_threshold = 24, .max_off_fraction = 0.01, .max_mean = 2.0}));
    if (test::updating_golden()) GTEST_SKIP() << "golden image written: " << golden;
}

TEST(RenderCli, MeshFilesRenderToo) {
    TempDir dir;
    render(test::data("bunny.vtp") + " --size 96x96 --view anterior -o " + (dir / "bunny.tif"));
    ImageMetadata meta;
    const Image img = load_image(dir / "bunny.tif", &meta);
    EXPECT_EQ(img.width, 96);
    EXPECT_NE(meta.text["isoscope:input"].find("bunny.vtp"), std::string::npos);
    EXPECT_TRUE(meta.text["isoscope:iso"].empty());
}

TEST(RenderCli, RayTracedAoOfTheBundledCt) {
    TempDir dir;
    render(test::data("headsq.nhdr") +
           " --iso 500 --size 64x48 --view left --aov ao --ao raytraced --ao-radius 10 --ao-rays 256 --ao-cache " +
           (dir / "cache") + " -o " + (dir / "ao.exr"));
    ImageMetadata meta;
    const Image ao = load_image(dir / "ao.exr", &meta);
    ASSERT_TRUE(ao.is_float);
    EXPECT_EQ(meta.text["isoscope:ao_radius_mm"], "10");
    std::size_t fg = 0, occluded = 0;
    for (float v : ao.floats) {
        if (std::isnan(v)) continue; // background
        ++fg;
        EXPECT_GE(v, 0.0f);
        EXPECT_LE(v, 1.0f);
        if (v < 0.9f) ++occluded;
    }
    EXPECT_GT(fg, 300u);
    EXPECT_GT(occluded, 10u) << "the ear and the face have folds";
    EXPECT_TRUE(std::isnan(ao.floats[0]));
}

// "reference", the ray-traced method's former name, still works.
TEST(RenderCli, ReferenceAoIsCachedByItsInputs) {
    TempDir dir;
    const std::string args = test::data("headsq.nhdr") +
                             " --iso 500 --size 48x40 --view left --aov ao --ao reference --ao-rays 64 --ao-cache " +
                             (dir / "cache");
    render(args + " -o " + (dir / "a.exr"));
    std::size_t entries = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache")) entries += e.is_regular_file();
    EXPECT_EQ(entries, 1u);
    render(args + " -o " + (dir / "b.exr"));
    EXPECT_EQ(load_image(dir / "a.exr").floats.size(), load_image(dir / "b.exr").floats.size());
    const auto a = load_image(dir / "a.exr"), b = load_image(dir / "b.exr");
    for (std::size_t i = 0; i < a.floats.size(); ++i) {
        if (!std::isnan(a.floats[i])) {
            ASSERT_EQ(a.floats[i], b.floats[i]);
        }
    }
    entries = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache")) entries += e.is_regular_file();
    EXPECT_EQ(entries, 1u) << "the second run hit the cache";
    // Another radius is another entry.
    render(args + " --ao-radius 5 -o " + (dir / "c.exr"));
    entries = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache")) entries += e.is_regular_file();
    EXPECT_EQ(entries, 2u);
}

TEST(RenderCli, ConeAoAsAnAovAndInTheColourImage) {
    TempDir dir;
    render(test::data("headsq.nhdr") +
           " --iso 500 --size 96x80 --view left --aov ao --ao cone --ao-radius 8 --ao-cones 6 --ao-frames 3 -o " +
           (dir / "ao.exr"));
    ImageMetadata meta;
    const Image ao = load_image(dir / "ao.exr", &meta);
    ASSERT_TRUE(ao.is_float);
    ASSERT_EQ(ao.channels, 1);
    EXPECT_EQ(meta.text["isoscope:ao_radius_mm"], "8");
    EXPECT_NE(meta.text["isoscope:ao"].find("cone"), std::string::npos);
    EXPECT_NE(meta.text["isoscope:ao_parameters"].find("cones 6"), std::string::npos);
    EXPECT_NE(meta.text["isoscope:ao_parameters"].find("frames 3"), std::string::npos);
    std::size_t fg = 0, occluded = 0;
    for (float v : ao.floats) {
        if (std::isnan(v)) continue;
        ++fg;
        ASSERT_GE(v, 0.0f);
        ASSERT_LE(v, 1.0f);
        occluded += v < 0.9f;
    }
    EXPECT_GT(fg, 500u);
    EXPECT_GT(occluded, 10u);
    // In the colour image AO darkens: the mean brightness of the surface drops.
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x80 --view left --no-annotations --ao cone -o " +
           (dir / "on.png"));
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x80 --view left --no-annotations -o " + (dir / "off.png"));
    const Image on = load_image(dir / "on.png"), off = load_image(dir / "off.png");
    ASSERT_EQ(on.bytes.size(), off.bytes.size());
    EXPECT_NE(on.bytes, off.bytes);
    // Bad values are refused with the option's name.
    for (const std::string bad :
         {" --ao cones", " --ao raytraced --ao-error 0", " --aov ao", " --ao cone --ao-cones 0",
          " --ao cone --ao-layers 9", " --ao cone --ao-resolution 0.1", " --ao cone --ao-resolution 2"}) {
        const auto r = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") +
                                             " --iso 500 --size 32x32" + bad + " -o " + (dir / "x.exr"),
                                         true);
        EXPECT_NE(r.exit_code, 0) << bad;
        EXPECT_NE(r.out.find("--ao"), std::string::npos) << bad << ": " << r.out;
        EXPECT_FALSE(std::filesystem::exists(dir / "x.exr")) << bad;
    }
}

// --ao raytraced lights the colour image with the ray-traced term (traced
// once before the frame): darker than no AO where the head folds, and the
// metadata records the method, R, the rays used and the standard error
// reached; the ao AOV of the same settings is the raw term it was lit with.
TEST(RenderCli, RayTracedAoInTheColourImage) {
    TempDir dir;
    const std::string args = test::data("headsq.nhdr") +
                             " --iso 500 --size 96x80 --view left --no-annotations --ao-radius 10 --ao-rays 256 "
                             "--ao-error 0.02 --ao-cache " +
                             (dir / "cache");
    render(args + " --ao raytraced -o " + (dir / "on.png"));
    render(args + " --ao off -o " + (dir / "off.png"));
    ImageMetadata meta;
    const Image on = load_image(dir / "on.png", &meta), off = load_image(dir / "off.png");
    ASSERT_EQ(on.bytes.size(), off.bytes.size());
    EXPECT_NE(meta.text["isoscope:ao"].find("raytraced"), std::string::npos) << meta.text["isoscope:ao"];
    EXPECT_EQ(meta.text["isoscope:ao_radius_mm"], "10");
    EXPECT_EQ(meta.text["isoscope:ao_rays"], "256");
    EXPECT_FALSE(meta.text["isoscope:ao_rays_traced"].empty());
    EXPECT_NE(meta.text["isoscope:ao_rays_per_pixel"].find("max "), std::string::npos);
    EXPECT_NE(meta.text["isoscope:ao_standard_error"].find("max 0.0"), std::string::npos)
        << meta.text["isoscope:ao_standard_error"];
    std::size_t darker = 0;
    for (std::size_t i = 0; i < on.bytes.size(); i += 4) darker += on.bytes[i] + 8 < off.bytes[i];
    EXPECT_GT(darker, 50u) << "folds and the ear read darker";
    // The ao AOV of the same request: the term (from the cache) the image was lit with.
    render(args + " --ao raytraced --aov ao -o " + (dir / "ao.exr"));
    const Image ao = load_image(dir / "ao.exr");
    std::size_t fg = 0;
    for (float v : ao.floats) fg += !std::isnan(v);
    EXPECT_GT(fg, 500u);
}

// --ao disk (docs/ao.md, "Disk AO on the GPU"): the same one-channel float
// EXR as cone AO, with the method, R and every tunable in the metadata;
// finite values in [0, 1] on the surface, NaN on the background; AO darkens
// the colour image; bad tunables are refused naming the flag.
TEST(RenderCli, DiskAoAsAnAovAndInTheColourImage) {
    TempDir dir;
    render(test::data("headsq.nhdr") +
           " --iso 500 --size 96x80 --view left --aov ao --ao disk --ao-radius 8 --ao-disk-passes 3 " +
           "--ao-disk-epsilon 6 --ao-disk-distance-k 0.01 --ao-disk-triangle-t 1.5 --ao-disk-blend 0.6,0.4 -o " +
           (dir / "ao.exr"));
    ImageMetadata meta;
    const Image ao = load_image(dir / "ao.exr", &meta);
    ASSERT_TRUE(ao.is_float);
    ASSERT_EQ(ao.channels, 1);
    EXPECT_EQ(meta.text["isoscope:ao_radius_mm"], "8");
    EXPECT_NE(meta.text["isoscope:ao"].find("disk"), std::string::npos);
    const std::string params = meta.text["isoscope:ao_parameters"];
    for (const char* p : {"passes 3", "traversal_epsilon 6", "clip_epsilon 1e-06", "distance_attenuation 0.01",
                          "triangle_attenuation 1.5", "blend_min 0.6", "blend_max 0.4"})
        EXPECT_NE(params.find(p), std::string::npos) << p << " in " << params;
    std::size_t fg = 0, occluded = 0;
    for (float v : ao.floats) {
        if (std::isnan(v)) continue;
        ++fg;
        ASSERT_TRUE(std::isfinite(v));
        ASSERT_GE(v, 0.0f);
        ASSERT_LE(v, 1.0f);
        occluded += v < 0.9f;
    }
    EXPECT_GT(fg, 500u);
    EXPECT_GT(occluded, 10u);
    EXPECT_TRUE(std::isnan(ao.floats[0])) << "the corner is background";
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x80 --view left --no-annotations --ao disk -o " +
           (dir / "on.png"));
    render(test::data("headsq.nhdr") + " --iso 500 --size 96x80 --view left --no-annotations -o " + (dir / "off.png"));
    const Image on = load_image(dir / "on.png"), off = load_image(dir / "off.png");
    ASSERT_EQ(on.bytes.size(), off.bytes.size());
    EXPECT_NE(on.bytes, off.bytes);
    for (const std::string bad :
         {" --ao disks", " --ao disk --ao-disk-passes -1", " --ao disk --ao-disk-passes 17",
          " --ao disk --ao-disk-epsilon -1", " --ao disk --ao-disk-triangle-t 20", " --ao disk --ao-disk-blend 0.7",
          " --ao disk --ao-disk-blend 2,0.3", " --ao disk --ao-disk-distance-k -0.5"}) {
        const auto r = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") +
                                             " --iso 500 --size 32x32" + bad + " -o " + (dir / "x.exr"),
                                         true);
        EXPECT_NE(r.exit_code, 0) << bad;
        EXPECT_NE(r.out.find("--ao"), std::string::npos) << bad << ": " << r.out;
        EXPECT_FALSE(std::filesystem::exists(dir / "x.exr")) << bad;
    }
}

TEST(RenderCli, VolumeRenderingFromTheCommandLine) {
    TempDir dir;
    const std::string tf = "400:0:#c08060,600:0.05:#e0b090,1000:0.05:#f0d0b0,1200:0.5:#ffffff";
    const std::string out =
        render(test::data("headsq.nhdr") + " --volume '" + tf +
               "' --iso 1150 --opacity 0.4 --size 120x100 --view left --stats -o " + (dir / "v.png"));
    EXPECT_NE(out.find("volume: step 0.750 mm"), std::string::npos) << out;
    EXPECT_NE(out.find("oit_resolve"), std::string::npos) << out; // marched inside the resolve
    ImageMetadata meta;
    const Image img = load_image(dir / "v.png", &meta);
    EXPECT_EQ(img.width, 120);
    EXPECT_EQ(meta.text["isoscope:volume_transfer_function"], tf);
    EXPECT_NE(meta.text["isoscope:volume"].find("composite"), std::string::npos);
    EXPECT_NE(meta.text["isoscope:legend"].find("volume"), std::string::npos) << meta.text["isoscope:legend"];
    // A volume alone (no --iso), a preset, MIP and a clip.
    render(test::data("headsq.nhdr") +
           " --volume bone --volume-mode mip --clip box=-150,0,-140,0,200,0 --size 64x64 -o " + (dir / "m.png"));
    ImageMetadata mip;
    load_image(dir / "m.png", &mip);
    EXPECT_NE(mip.text["isoscope:volume"].find("mip"), std::string::npos);
    EXPECT_EQ(mip.text["isoscope:clip"], "box=-150,0,-140,0,200,0 (LPS mm)");
    // Errors name the flag and the reason; nothing is written.
    for (const auto& [args, want] : std::vector<std::pair<std::string, std::string>>{
             {"--volume bones", "--volume: 'bones' is neither a preset"},
             {"--volume 1:2:#ffffff", "--volume: point 1: opacity per mm must be in 0..1"},
             {"--volume bone --volume-mode max", "--volume-mode: must be composite, mip or minip"},
             {"--volume bone --clip box=1,2,3", "--clip: 'box=1,2,3' needs 6 numbers"}}) {
        const auto r = test::run_command(
            test::cli() + " render " + test::data("headsq.nhdr") + " " + args + " -o " + (dir / "bad.png"), true);
        EXPECT_EQ(r.exit_code, 1) << args;
        EXPECT_NE(r.out.find(want), std::string::npos) << r.out;
        EXPECT_FALSE(std::filesystem::exists(dir / "bad.png"));
    }
    const auto mesh = test::run_command(
        test::cli() + " render " + test::data("bunny.vtp") + " --volume bone -o " + (dir / "bad.png"), true);
    EXPECT_NE(mesh.out.find("no volume to ray cast: the input is a mesh"), std::string::npos) << mesh.out;
    // A pick on the volume alone lands in it.
    const auto pick = test::run_command(test::cli() + " pick " + test::data("headsq.nhdr") + " --volume '" + tf +
                                            "' --view left --size 120x100 --at 60,50 --json",
                                        true);
    EXPECT_NE(pick.out.find("\"layer\": \"volume\""), std::string::npos) << pick.out;
}

TEST(RenderCli, SessionVolumeAndTheFlagsThatReplaceIt) {
    TempDir dir;
    core::Session s;
    s.input = std::filesystem::absolute(test::data("headsq.nhdr")).lexically_normal().string();
    VolumeLook v;
    v.enabled = true;
    v.tf = TransferFunction::parse("400:0:#c08060,1200:0.3:#ffffff");
    s.volume = v;
    s.clip_box = std::pair{glm::dvec3(-150, 0, -140), glm::dvec3(0, 200, 0)};
    core::save_session(s, dir / "s.json");
    const auto meta_of = [&](const std::string& args) {
        render("--session " + (dir / "s.json") + " --size 48x48 " + args + " -o " + (dir / "o.png"));
        ImageMetadata m;
        load_image(dir / "o.png", &m);
        return m.text;
    };
    auto t = meta_of("");
    EXPECT_EQ(t["isoscope:volume_transfer_function"], "400:0:#c08060,1200:0.3:#ffffff");
    EXPECT_EQ(t["isoscope:clip"], "box=-150,0,-140,0,200,0 (LPS mm)");
    t = meta_of("--volume-mode mip"); // the mode alone: the session's transfer function stays
    EXPECT_EQ(t["isoscope:volume_transfer_function"], "400:0:#c08060,1200:0.3:#ffffff");
    EXPECT_NE(t["isoscope:volume"].find("mip"), std::string::npos);
    t = meta_of("--volume bone --clip box=-100,0,-100,0,100,0");
    EXPECT_EQ(t["isoscope:volume_transfer_function"], transfer_function_from("bone").text());
    EXPECT_EQ(t["isoscope:clip"], "box=-100,0,-100,0,100,0 (LPS mm)");
}
