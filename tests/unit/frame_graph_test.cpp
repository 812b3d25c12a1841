// The pass graph and its resource pool without a GPU: a recording backend
// stands in for GL. Checks that transient resources are reused when
// lifetimes do not overlap and across frames, that waiting resources are
// evicted by age, that history resources persist (and say when they are
// fresh), and that misuse is reported with the function's name. The
// renderer's real frame is compiled in frame_test.cpp.
#include "renderer/graph/frame_graph.hpp"
#include "renderer/graph/resource_pool.hpp"

#include <map>

#include "io/error.hpp"
#include "tests/support/test_util.hpp"

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

} // namespace

TEST(FrameGraph, TransientResourcesAreReusedWhenLifetimesDoNotOverlap) {
    // Three passes in a chain, each making a same-sized texture read only by the next:
    // a (t1) -> b reads t1, makes t2 -> c reads t2, makes t3 -> d reads t3 (side effect).
    FrameGraph g;
    std::vector<std::uint64_t> ids;
    struct T {
        TextureHandle t;
    };
    const auto& a = g.add_pass<T>(
        "a", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(b.create("t1", kColor)); },
        [&](const T& d, const Resources& r) { ids.push_back(r.get(d.t)); });
    const auto& bb = g.add_pass<T>(
        "b",
        [&](FrameGraph::Builder& b, T& d) {
            b.read(a.t);
            d.t = b.write(b.create("t2", kColor));
        },
        [&](const T& d, const Resources& r) { ids.push_back(r.get(d.t)); });
    const auto& c = g.add_pass<T>(
        "c",
        [&](FrameGraph::Builder& b, T& d) {
            b.read(bb.t);
            d.t = b.write(b.create("t3", kColor));
        },
        [&](const T& d, const Resources& r) { ids.push_back(r.get(d.t)); });
    struct E {};
    g.add_pass<E>(
        "d",
        [&](FrameGraph::Builder& b, E&) {
            b.read(c.t);
            b.side_effect();
        },
        [](const E&, const Resources&) {});
    RecordingBackend be;
    ResourcePool pool(be);
    const auto stats = g.execute(pool);
    ASSERT_EQ(ids.size(), 3u);
    // t1 is free once b has run, so c's t3 reuses it: two physical textures for three.
    EXPECT_EQ(stats.physical_resources, 2u);
    EXPECT_EQ(ids[2], ids[0]);
    EXPECT_NE(ids[1], ids[0]);
    EXPECT_EQ(stats.peak_bytes, 2 * 64 * 32 * 8u);
    EXPECT_EQ(be.created, 2u);
    EXPECT_EQ(pool.stats().waiting, 2u) << "given back to the pool, kept for the next frame";
}

TEST(FrameGraph, ImportedResourcesAreNeverCreatedOrDestroyed) {
    FrameGraph g;
    const auto target = g.import("window", kColor, 777);
    std::uint64_t seen = 0;
    struct W {
        TextureHandle out;
    };
    const auto& w = g.add_pass<W>(
        "draw", [&](FrameGraph::Builder& b, W& d) { d.out = b.write(target); },
        [&](const W& d, const Resources& r) { seen = r.get(d.out); });
    g.request(w.out);
    RecordingBackend be;
    ResourcePool pool(be);
    g.execute(pool);
    EXPECT_EQ(seen, 777u);
    EXPECT_EQ(be.created, 0u);
    EXPECT_EQ(be.destroyed, 0u);
}

TEST(FrameGraph, MisuseIsReported) {
    FrameGraph g;
    struct T {
        TextureHandle t;
    };
    // Reading a resource nobody wrote.
    EXPECT_THROW(g.add_pass<T>(
                     "bad read",
                     [&](FrameGraph::Builder& b, T& d) {
                         d.t = b.create("x", kColor);
                         b.read(d.t);
                     },
                     [](const T&, const Resources&) {}),
                 iso::Error);
    // Writing an old version.
    FrameGraph g2;
    const auto& a = g2.add_pass<T>(
        "a", [&](FrameGraph::Builder& b, T& d) { d.t = b.create("x", kColor); }, [](const T&, const Resources&) {});
    const auto first = a.t;
    g2.add_pass<T>(
        "b", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(first); }, [](const T&, const Resources&) {});
    EXPECT_THROW(
        g2.add_pass<T>(
            "c", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(first); }, [](const T&, const Resources&) {}),
        iso::Error);
    try {
        g2.request(TextureHandle{});
        ADD_FAILURE() << "an invalid handle was accepted";
    } catch (const iso::Error& e) {
        EXPECT_NE(std::string(e.what()).find("FrameGraph::request"), std::string::npos) << e.what();
    }
    // Asking before compiling, executing twice.
    EXPECT_THROW(g2.will_run("a"), iso::Error);
    RecordingBackend be;
    ResourcePool pool(be);
    g2.execute(pool);
    EXPECT_THROW(g2.execute(pool), iso::Error);
    EXPECT_THROW(pool.release(12345), iso::Error);
}

namespace {

// One frame: "make" creates a texture of `desc` that "use" reads (a side effect).
FrameStats one_frame(ResourcePool& pool, const TextureDesc& desc, std::uint64_t* seen = nullptr) {
    FrameGraph g;
    struct T {
        TextureHandle t;
    };
    const auto& a = g.add_pass<T>(
        "make", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(b.create("t", desc)); },
        [&](const T& d, const Resources& r) {
            if (seen) *seen = r.get(d.t);
        });
    g.add_pass<T>(
        "use",
        [&](FrameGraph::Builder& b, T& d) {
            d.t = b.read(a.t);
            b.side_effect();
        },
        [](const T&, const Resources&) {});
    return g.execute(pool);
}

} // namespace

TEST(ResourcePool, SteadyFramesCreateNothingAfterTheFirst) {
    RecordingBackend be;
    ResourcePool pool(be);
    std::uint64_t first = 0, later = 0;
    EXPECT_EQ(one_frame(pool, kColor, &first).physical_resources, 1u);
    for (int f = 0; f < 10; ++f) {
        const auto s = one_frame(pool, kColor, &later);
        EXPECT_EQ(s.physical_resources, 0u);
        EXPECT_EQ(s.reused_resources, 1u);
        EXPECT_EQ(later, first);
    }
    EXPECT_EQ(be.created, 1u);
    EXPECT_EQ(pool.stats().reused, 10u);
    EXPECT_EQ(pool.stats().frames, 11u);
}

TEST(ResourcePool, WaitingResourcesAreEvictedByAge) {
    RecordingBackend be;
    ResourcePool pool(be, /*max_age=*/3);
    one_frame(pool, kColor);
    const TextureDesc other{128, 64, Format::RGBA8};
    // A resize: the old texture waits, unused, and goes after 3 frames.
    one_frame(pool, other);
    EXPECT_EQ(be.live.size(), 2u);
    one_frame(pool, other);
    EXPECT_EQ(be.live.size(), 2u) << "evicted before it waited 3 frames";
    one_frame(pool, other);
    EXPECT_EQ(be.live.size(), 1u) << "the old size was evicted";
    EXPECT_EQ(pool.stats().destroyed, 1u);
    EXPECT_EQ(pool.stats().live_bytes, 128u * 64u * 4u);
}

TEST(ResourcePool, HistoryPersistsAndSaysWhenItIsFresh) {
    RecordingBackend be;
    ResourcePool pool(be);
    const TextureDesc arr{16, 8, Format::RGBA32UI, 4};
    auto frame_in = [](ResourcePool& in, const TextureDesc& d, bool* fresh, std::uint64_t* id) {
        FrameGraph g;
        const auto h = g.history("accum", d);
        struct T {
            TextureHandle t;
        };
        g.add_pass<T>(
            "accumulate",
            [&](FrameGraph::Builder& b, T& t) {
                t.t = b.write(b.read(h));
                b.side_effect();
            },
            [&](const T& t, const Resources& r) {
                *fresh = r.fresh(t.t);
                *id = r.get(t.t);
            });
        g.execute(in);
    };
    auto frame = [&](const TextureDesc& d, bool* fresh, std::uint64_t* id) { frame_in(pool, d, fresh, id); };
    bool fresh = false;
    std::uint64_t a = 0, b = 0;
    frame(arr, &fresh, &a);
    EXPECT_TRUE(fresh);
    frame(arr, &fresh, &b);
    EXPECT_FALSE(fresh);
    EXPECT_EQ(a, b);
    EXPECT_TRUE(pool.has_history("accum", arr));
    EXPECT_EQ(pool.stats().live_bytes, 16u * 8u * 4u * 16u) << "layers count";
    // A new descriptor replaces it.
    frame(TextureDesc{16, 8, Format::RGBA32UI, 2}, &fresh, &b);
    EXPECT_TRUE(fresh);
    EXPECT_EQ(be.live.size(), 1u);
    // A history declared but never needed is never made.
    ResourcePool short_lived(be, 3, 2);
    FrameGraph g;
    g.history("unused", arr);
    g.execute(short_lived);
    EXPECT_EQ(short_lived.stats().history, 0u);
    // History unused for max_history_age (2) frames is evicted: it survives
    // one frame that does not use it and goes at the end of the second.
    frame_in(short_lived, arr, &fresh, &a);
    EXPECT_TRUE(fresh);
    EXPECT_EQ(short_lived.stats().history, 1u);
    const std::size_t destroyed = short_lived.stats().destroyed;
    one_frame(short_lived, kColor);
    EXPECT_TRUE(short_lived.has_history("accum", arr)) << "evicted after one unused frame";
    EXPECT_EQ(short_lived.stats().history, 1u);
    one_frame(short_lived, kColor);
    EXPECT_FALSE(short_lived.has_history("accum", arr)) << "kept after max_history_age unused frames";
    EXPECT_EQ(short_lived.stats().history, 0u);
    EXPECT_EQ(short_lived.stats().destroyed, destroyed + 1);
    // Used again: made afresh.
    frame_in(short_lived, arr, &fresh, &b);
    EXPECT_TRUE(fresh);
}

TEST(FrameGraph, CompileCullsWithoutRunningAnything) {
    FrameGraph g;
    struct T {
        TextureHandle t;
    };
    int runs = 0;
    const auto& a = g.add_pass<T>(
        "a", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(b.create("x", kColor)); },
        [&](const T&, const Resources&) { ++runs; });
    g.add_pass<T>(
        "orphan", [&](FrameGraph::Builder& b, T& d) { d.t = b.write(b.create("y", kColor)); },
        [&](const T&, const Resources&) { ++runs; });
    g.add_pass<T>(
        "sink",
        [&](FrameGraph::Builder& b, T& d) {
            d.t = b.read(a.t);
            b.side_effect();
        },
        [&](const T&, const Resources&) { ++runs; });
    g.compile();
    EXPECT_EQ(g.running_passes(), (std::vector<std::string>{"a", "sink"}));
    EXPECT_FALSE(g.will_run("orphan"));
    EXPECT_EQ(runs, 0);
}
