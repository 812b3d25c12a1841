// The pass graph without a GPU: a recording backend stands in for GL. Checks
// that passes whose outputs nobody needs never execute, that side effects
// keep passes alive, that transient resources are reused when lifetimes do
// not overlap, and that misuse is reported.
#include "renderer/graph/frame_graph.hpp"

#include <map>

#include "io/error.hpp"
#include "test_util.hpp"

using namespace iso::graph;

namespace {

struct RecordingBackend : Backend {
    std::uint64_t next = 1;
    std::map<std::uint64_t, std::string> live;
    std::size_t created = 0, destroyed = 0;
    std::uint64_t create_texture(const TextureDesc&, const std::string& name) override {
        ++created;
        live[next] = name;
        return next++;
    }
    std::uint64_t create_buffer(const BufferDesc&, const std::string& name) override {
        ++created;
        live[next] = name;
        return next++;
    }
    void destroy(std::uint64_t id) override {
        ++destroyed;
        live.erase(id);
    }
};

const TextureDesc kColor{64, 32, Format::RGBA16F};
const TextureDesc kDepth{64, 32, Format::Depth32F};

// The renderer's shape: gbuffer -> (voxelize -> ao) -> lighting -> overlay -> readback.
struct Frame {
    std::vector<std::string> executed;
    TextureHandle depth, normal, ao, lit;
};

void build(FrameGraph& g, Frame& f, bool ao_on, bool readback) {
    struct GB { TextureHandle depth, normal; };
    const auto& gb = g.add_pass<GB>("gbuffer",
        [&](FrameGraph::Builder& b, GB& d) {
            d.depth = b.write(b.create("depth", kDepth));
            d.normal = b.write(b.create("normal", kColor));
        },
        [&](const GB&, const Resources&) { f.executed.push_back("gbuffer"); });
    f.depth = gb.depth;
    f.normal = gb.normal;
    struct Vox { TextureHandle voxels; };
    const auto& vox = g.add_pass<Vox>("voxelize",
        [&](FrameGraph::Builder& b, Vox& d) {
            b.read(gb.depth);
            d.voxels = b.write(b.create("voxels", TextureDesc{64, 32, Format::RGBA32UI, 2}));
        },
        [&](const Vox&, const Resources&) { f.executed.push_back("voxelize"); });
    struct Ao { TextureHandle ao; };
    const auto& ao = g.add_pass<Ao>("cone ao",
        [&](FrameGraph::Builder& b, Ao& d) {
            b.read(vox.voxels);
            b.read(gb.normal);
            d.ao = b.write(b.create("ao", TextureDesc{64, 32, Format::R32F}));
        },
        [&](const Ao&, const Resources&) { f.executed.push_back("cone ao"); });
    f.ao = ao.ao;
    struct Lit { TextureHandle lit; };
    const auto& lit = g.add_pass<Lit>("lighting",
        [&](FrameGraph::Builder& b, Lit& d) {
            b.read(gb.depth);
            b.read(gb.normal);
            if (ao_on) b.read(ao.ao);
            d.lit = b.write(b.create("lit", kColor));
        },
        [&](const Lit&, const Resources&) { f.executed.push_back("lighting"); });
    struct Ov { TextureHandle out; };
    const auto& ov = g.add_pass<Ov>("overlay",
        [&](FrameGraph::Builder& b, Ov& d) {
            b.read(lit.lit);
            d.out = b.write(lit.lit);
        },
        [&](const Ov&, const Resources&) { f.executed.push_back("overlay"); });
    f.lit = ov.out;
    if (readback) {
        struct Rb {};
        g.add_pass<Rb>("readback",
            [&](FrameGraph::Builder& b, Rb&) {
                b.read(ov.out);
                b.side_effect();
            },
            [&](const Rb&, const Resources&) { f.executed.push_back("readback"); });
    }
}

} // namespace

TEST(FrameGraph, AoOffCullsVoxelizationAndConeTracing) {
    FrameGraph g;
    Frame f;
    build(g, f, /*ao_on=*/false, /*readback=*/true);
    RecordingBackend be;
    const auto stats = g.execute(be);
    EXPECT_EQ(f.executed, (std::vector<std::string>{"gbuffer", "lighting", "overlay", "readback"}));
    EXPECT_FALSE(g.ran("voxelize"));
    EXPECT_FALSE(g.ran("cone ao"));
    ASSERT_EQ(stats.passes.size(), 6u);
    EXPECT_FALSE(stats.passes[1].ran);
    EXPECT_EQ(stats.passes[1].bytes_created, 0u);
    EXPECT_EQ(be.live.size(), 0u) << "transient resources are released";
}

TEST(FrameGraph, AoOnRunsEverythingInOrder) {
    FrameGraph g;
    Frame f;
    build(g, f, true, true);
    RecordingBackend be;
    g.execute(be);
    EXPECT_EQ(f.executed, (std::vector<std::string>{"gbuffer", "voxelize", "cone ao", "lighting", "overlay", "readback"}));
}

TEST(FrameGraph, NothingRequestedNothingRuns) {
    FrameGraph g;
    Frame f;
    build(g, f, true, /*readback=*/false);
    RecordingBackend be;
    const auto stats = g.execute(be);
    EXPECT_TRUE(f.executed.empty());
    EXPECT_EQ(be.created, 0u);
    EXPECT_EQ(stats.physical_resources, 0u);
}

TEST(FrameGraph, RequestingAnAovRunsOnlyItsProducers) {
    FrameGraph g;
    Frame f;
    build(g, f, true, false);
    g.request(f.depth); // --aov depth: only the G-buffer is needed
    RecordingBackend be;
    g.execute(be);
    EXPECT_EQ(f.executed, (std::vector<std::string>{"gbuffer"}));
}

TEST(FrameGraph, TransientResourcesAreReusedWhenLifetimesDoNotOverlap) {
    // Three passes in a chain, each making a same-sized texture read only by the next:
    // a (t1) -> b reads t1, makes t2 -> c reads t2, makes t3 -> d reads t3 (side effect).
    FrameGraph g;
    std::vector<std::uint64_t> ids;
    struct T { TextureHandle t; };
    const auto& a = g.add_pass<T>("a", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(b.create("t1", kColor)); },
                                  [&](const T& d, const Resources& r) { ids.push_back(r.get(d.t)); });
    const auto& bb = g.add_pass<T>("b",
        [&](FrameGraph::Builder& b, T& d) {
            b.read(a.t);
            d.t = b.write(b.create("t2", kColor));
        },
        [&](const T& d, const Resources& r) { ids.push_back(r.get(d.t)); });
    const auto& c = g.add_pass<T>("c",
        [&](FrameGraph::Builder& b, T& d) {
            b.read(bb.t);
            d.t = b.write(b.create("t3", kColor));
        },
        [&](const T& d, const Resources& r) { ids.push_back(r.get(d.t)); });
    struct E {};
    g.add_pass<E>("d",
        [&](FrameGraph::Builder& b, E&) {
            b.read(c.t);
            b.side_effect();
        },
        [](const E&, const Resources&) {});
    RecordingBackend be;
    const auto stats = g.execute(be);
    ASSERT_EQ(ids.size(), 3u);
    // t1 is free once b has run, so c's t3 reuses it: two physical textures for three.
    EXPECT_EQ(stats.physical_resources, 2u);
    EXPECT_EQ(ids[2], ids[0]);
    EXPECT_NE(ids[1], ids[0]);
    EXPECT_EQ(stats.peak_bytes, 2 * 64 * 32 * 8u);
    EXPECT_EQ(be.created, be.destroyed);
}

TEST(FrameGraph, ImportedResourcesAreNeverCreatedOrDestroyed) {
    FrameGraph g;
    const auto target = g.import("window", kColor, 777);
    std::uint64_t seen = 0;
    struct W { TextureHandle out; };
    const auto& w = g.add_pass<W>("draw", [&](FrameGraph::Builder& b, W& d) { d.out = b.write(target); },
                                  [&](const W& d, const Resources& r) { seen = r.get(d.out); });
    g.request(w.out);
    RecordingBackend be;
    g.execute(be);
    EXPECT_EQ(seen, 777u);
    EXPECT_EQ(be.created, 0u);
    EXPECT_EQ(be.destroyed, 0u);
}

TEST(FrameGraph, MisuseIsReported) {
    FrameGraph g;
    struct T { TextureHandle t; };
    // Reading a resource nobody wrote.
    EXPECT_THROW(g.add_pass<T>("bad read",
                               [&](FrameGraph::Builder& b, T& d) {
                                   d.t = b.create("x", kColor);
                                   b.read(d.t);
                               },
                               [](const T&, const Resources&) {}),
                 iso::Error);
    // Writing an old version.
    FrameGraph g2;
    const auto& a = g2.add_pass<T>("a", [&](FrameGraph::Builder& b, T& d) { d.t = b.create("x", kColor); },
                                   [](const T&, const Resources&) {});
    const auto first = a.t;
    g2.add_pass<T>("b", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(first); }, [](const T&, const Resources&) {});
    EXPECT_THROW(g2.add_pass<T>("c", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(first); },
                                [](const T&, const Resources&) {}),
                 iso::Error);
    EXPECT_THROW(g2.request(TextureHandle{}), iso::Error);
}
