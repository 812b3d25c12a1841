// The renderer's real frame (build_frame() in renderer/passes/build_frame.hpp), compiled without a
// GPU for each configuration: which passes run is decided by the graph's
// culling from what the frame reads, never by the caller. No GL context: the
// passes' GL work would only run in execute().
#include "renderer/passes/build_frame.hpp"

#include <algorithm>

#include "io/error.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using Passes = std::vector<std::string>;

namespace {

struct NullBackend : graph::Backend {
    std::uint64_t next = 1;
    std::uint64_t create_texture(const graph::TextureDesc&, const std::string&) override { return next++; }
    std::uint64_t create_buffer(const graph::BufferDesc&, const std::string&) override { return next++; }
    void destroy(std::uint64_t) override {}
};

struct Compiled {
    Passes running;
};

Compiled compile(const RenderOptions& opt, const RenderHooks& hooks = {}, float second_opacity = 1.0f,
                 const passes::VolumeInput* volume = nullptr) {
    NullBackend be;
    graph::ResourcePool pool(be);
    passes::AoHistory history;
    RenderResult result;
    Bounds b;
    b.add({-50, -50, -50});
    b.add({50, 50, 50});
    Camera cam;
    cam.set_view(PatientView::Anterior, b);
    cam.fit(b, double(opt.width) / opt.height);
    passes::FrameContext ctx =
        passes::make_context(cam, opt, {{0, 36, 1, glm::vec3(1), 1.0f}, {0, 36, 2, glm::vec3(1), second_opacity}}, b);
    ctx.hooks = hooks;
    ctx.pool = &pool;
    ctx.ao = &history;
    ctx.result = &result;
    ctx.volume = volume; // the renderer sets it only for colour images of a look with the volume on
    graph::FrameGraph fg;
    passes::build_frame(fg, ctx);
    fg.compile();
    Compiled c;
    c.running = fg.running_passes();
    return c;
}

// Without anti-aliasing, so the lists below are about their own passes
// (AntiAliasingAddsItsPassesToColourFramesOnly has the AA passes).
RenderOptions options() {
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.look.aa.samples = 1;
    return o;
}

} // namespace

TEST(Frame, TheVolumeIsMarchedByItsOwnPassOrInsideTheVoitResolve) {
    RenderOptions o = options();
    o.look.volume.enabled = true;
    o.look.volume.tf = TransferFunction::parse("0:0.1:#ffffff");
    const passes::VolumeInput volume;
    EXPECT_EQ(compile(o, {}, 1.0f, &volume).running, (Passes{"gbuffer", "lighting", "volume", "readback"}));
    // With a translucent surface the resolve marches it between the fragments: no pass of its own.
    EXPECT_EQ(compile(o, {}, 0.5f, &volume).running,
              (Passes{"gbuffer", "lighting", "oit_fragments", "oit_resolve", "readback"}));
    // An AOV has no volume in it.
    o.aov = Aov::Depth;
    EXPECT_EQ(compile(o, {}, 1.0f, &volume).running, (Passes{"gbuffer", "readback"}));
}

TEST(Frame, AntiAliasingAddsItsPassesToColourFramesOnly) {
    RenderOptions o = options();
    o.look.aa.samples = 4; // the default
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "lighting", "dsraa", "readback"}));
    o.accumulate = true; // the view's still frames, exports
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "lighting", "dsraa", "accumulate", "readback"}));
    o.look.aa.samples = 1;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "lighting", "accumulate", "readback"}));
    // AOVs and picks read pixel centres: no sub-samples, no average.
    o.look.aa.samples = 4;
    o.aov = Aov::Depth;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "readback"}));
    o.aov = Aov::None;
    o.image = false;
    o.pick = PickRegion{1, 1, 2, 2};
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "pick_resolve", "read_pick"}));
}

TEST(Frame, OpaqueColourWithoutAoRunsGbufferLightingReadback) {
    EXPECT_EQ(compile(options()).running, (Passes{"gbuffer", "lighting", "readback"}));
}

TEST(Frame, AoOnRunsTheConeChainBeforeLighting) {
    RenderOptions o = options();
    o.look.ao = AoMethod::Cone;
    EXPECT_EQ(compile(o).running,
              (Passes{"gbuffer", "zrange", "voxelize", "cone_ao", "ao_upsample", "lighting", "readback"}));
    o.look.cone.resolution = 1.0; // traced at full size: no upsampling
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "zrange", "voxelize", "cone_ao", "lighting", "readback"}));
    EXPECT_EQ(compile(o, {.read_slicemap = true}).running,
              (Passes{"gbuffer", "zrange", "voxelize", "cone_ao", "read_slicemap", "lighting", "readback"}));
}

// Disk AO (docs/ao.md, "Disk AO on the GPU"): its chain replaces the cone
// chain; a first frame builds the hierarchy and runs the element passes;
// with a depth AOV nothing of it runs; bad disk settings are refused only
// when disk AO is asked for.
TEST(Frame, DiskAoRunsItsOwnChainInsteadOfTheCones) {
    RenderOptions o = options();
    o.look.ao = AoMethod::Disk;
    // Default: no element passes (passes = 0).
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "disk_build", "disk_gather", "lighting", "readback"}));
    o.look.disk.passes = 2;
    EXPECT_EQ(compile(o).running,
              (Passes{"gbuffer", "disk_build", "disk_elements", "disk_gather", "lighting", "readback"}));
    o.aov = Aov::Depth;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "readback"}));
    o.aov = Aov::Ao; // the raw term, without lighting
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "disk_build", "disk_elements", "disk_gather", "readback"}));
    o.aov = Aov::None;
    o.look.disk.passes = -1;
    o.look.ao = AoMethod::Cone;
    EXPECT_EQ(compile(o).running,
              (Passes{"gbuffer", "zrange", "voxelize", "cone_ao", "ao_upsample", "lighting", "readback"}))
        << "cone AO: the disk settings are not checked";
    o.look.ao = AoMethod::Disk;
    try {
        compile(o);
        ADD_FAILURE() << "passes = -1 was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("passes"), std::string::npos) << e.what();
    }
}

// The ao AOV needs AO: a method the GL frame computes, or the ray-traced image given.
TEST(Frame, TheAoAovNeedsAGlAoMethodOrTheRayTracedImage) {
    RenderOptions o = options();
    o.aov = Aov::Ao;
    for (const AoMethod m : {AoMethod::Off, AoMethod::Raytraced}) {
        o.look.ao = m;
        EXPECT_THROW(compile(o), Error) << ao_method_name(m);
    }
    Image ao;
    ao.width = o.width;
    ao.height = o.height;
    ao.channels = 1;
    ao.is_float = true;
    ao.floats.assign(std::size_t(o.width) * o.height, 1.0f);
    o.ao_image = &ao;
    EXPECT_EQ(compile(o).running, (Passes{"ao_import", "readback"})) << "the raw term needs no G-buffer";
    ao.width = o.width + 1; // not the frame's size
    EXPECT_THROW(compile(o), Error);
}

// Ray-traced AO: the image computed outside the frame is uploaded and lit
// with; the cone and disk chains are culled, and translucent surfaces go
// without AO (no cone chain for them either).
TEST(Frame, RayTracedAoImportsItsImageAndCullsTheAoChains) {
    RenderOptions o = options();
    o.look.ao = AoMethod::Raytraced;
    EXPECT_THROW(compile(o), Error) << "no AO image";
    Image ao;
    ao.width = o.width;
    ao.height = o.height;
    ao.channels = 1;
    ao.is_float = true;
    ao.floats.assign(std::size_t(o.width) * o.height, 0.5f);
    o.ao_image = &ao;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "ao_import", "lighting", "readback"}));
    o.aov = Aov::Depth; // reads no AO: nothing imported
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "readback"}));
    o.ao_image = nullptr; // nor needed
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "readback"}));
    o.aov = Aov::None;
    o.ao_image = &ao;
    const Passes t = compile(o, {}, 0.5f).running; // the second object translucent
    EXPECT_EQ(std::count(t.begin(), t.end(), "ao_import"), 1);
    EXPECT_EQ(std::count(t.begin(), t.end(), "oit_resolve"), 1);
    for (const char* chain : {"zrange", "voxelize", "cone_ao", "ao_upsample", "oit_ao", "disk_gather"})
        EXPECT_EQ(std::count(t.begin(), t.end(), chain), 0) << chain;
}

TEST(Frame, AnAovRunsOnlyItsProducers) {
    RenderOptions o = options();
    o.look.ao = AoMethod::Cone; // on, but a depth AOV does not read it
    for (const Aov aov : {Aov::Depth, Aov::Normal, Aov::Id}) {
        o.aov = aov;
        EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "readback"})) << int(aov);
    }
    o.aov = Aov::Ao; // the raw AO term without lighting
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "zrange", "voxelize", "cone_ao", "ao_upsample", "readback"}));
}

TEST(Frame, AnnotationsAddTheOverlayAndPresentReplacesTheReadback) {
    RenderOptions o = options();
    Annotations ann;
    o.annotations = &ann;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "lighting", "overlay", "readback"}));
    o.aov = Aov::Depth; // annotations go on the colour image only
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "readback"}));
    o.aov = Aov::None;
    o.present = true;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "lighting", "overlay", "present"}));
}

TEST(Frame, BadAoSettingsAreRefusedOnlyWhenAoIsAskedFor) {
    RenderOptions o = options();
    o.look.cone.cones = 0;
    EXPECT_EQ(compile(o).running, (Passes{"gbuffer", "lighting", "readback"}));
    o.look.ao = AoMethod::Cone;
    try {
        compile(o);
        ADD_FAILURE() << "cones = 0 was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cones"), std::string::npos) << e.what();
    }
}

TEST(Frame, TranslucentObjectsAddTheListPassesAndAovsCullThem) {
    RenderOptions o = options();
    EXPECT_EQ(compile(o, {}, 0.4f).running,
              (Passes{"gbuffer", "lighting", "oit_fragments", "oit_resolve", "readback"}));
    EXPECT_EQ(compile(o, {.read_oit_lists = true}, 0.4f).running,
              (Passes{"gbuffer", "lighting", "oit_fragments", "read_oit_lists", "oit_resolve", "readback"}));
    o.look.ao = AoMethod::Cone; // AO of the opaque surfaces still runs under the glass
    EXPECT_EQ(compile(o, {}, 0.4f).running,
              (Passes{"gbuffer", "zrange", "voxelize", "cone_ao", "ao_upsample", "lighting", "oit_fragments",
                      "oit_sort", "oit_ao", "oit_resolve", "readback"}));
    o.aov = Aov::Depth; // the AOVs describe the opaque surfaces: no list is built
    EXPECT_EQ(compile(o, {}, 0.4f).running, (Passes{"gbuffer", "readback"}));
    o = options();
    EXPECT_EQ(compile(o, {}, 1.0f).running, (Passes{"gbuffer", "lighting", "readback"}))
        << "all opaque: no list passes";
}

TEST(Frame, APickOnlyFrameRunsNoLightingResolveOrReadback) {
    RenderOptions o = options();
    o.pick = PickRegion{10, 10, 1, 1};
    // Riding on a colour frame, the pick adds its passes to the whole chain.
    EXPECT_EQ(compile(o, {}, 0.4f).running,
              (Passes{"gbuffer", "lighting", "oit_fragments", "oit_resolve", "pick_resolve", "read_pick", "readback"}));
    // Without an image output only the geometry passes that list the fragments and the pick itself run,
    // even with AO and annotations asked for (nothing reads them).
    o.image = false;
    o.look.ao = AoMethod::Cone;
    Annotations ann;
    o.annotations = &ann;
    EXPECT_EQ(compile(o, {}, 0.4f).running, (Passes{"gbuffer", "oit_fragments", "pick_resolve", "read_pick"}));
    EXPECT_EQ(compile(o, {}, 1.0f).running, (Passes{"gbuffer", "pick_resolve", "read_pick"}))
        << "all opaque: no list pass";
}
