#include "renderer/graph/frame_graph.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <type_traits>

#include "io/error.hpp"
#include "renderer/graph/resource_pool.hpp"

namespace iso::graph {

std::size_t bytes_per_pixel(Format f) {
    switch (f) {
    case Format::RGBA8:
    case Format::R32F:
    case Format::R32UI:
    case Format::Depth32F:
    case Format::RG16F: return 4;
    case Format::RGBA16F:
    case Format::RG32UI: return 8;
    case Format::RGBA32F:
    case Format::RGBA32UI: return 16;
    }
    return 4;
}

std::size_t bytes_of(const TextureDesc& d) {
    return std::size_t(d.width) * std::size_t(d.height) * std::size_t(d.layers) * std::size_t(d.depth) *
           std::size_t(d.samples) * bytes_per_pixel(d.format);
}

// ---- Builder -------------------------------------------------------------------

std::uint32_t FrameGraph::Builder::create_resource(Resource r) {
    const auto i = g_.add_resource(std::move(r));
    g_.passes_[pass_].creates.push_back(i);
    return i;
}

void FrameGraph::Builder::read_resource(std::uint32_t index, std::uint32_t version, bool texture) {
    g_.check(index, version, texture, "FrameGraph::Builder::read");
    const auto& r = g_.resources_[index];
    if (version == 0 && !r.imported && !r.history)
        throw Error("pass '" + g_.passes_[pass_].name + "'", "reads '" + r.name + "' before any pass wrote it");
    g_.passes_[pass_].reads.push_back({index, version});
}

std::uint32_t FrameGraph::Builder::write_resource(std::uint32_t index, std::uint32_t version, bool texture) {
    g_.check(index, version, texture, "FrameGraph::Builder::write");
    auto& r = g_.resources_[index];
    if (version != r.version)
        throw Error("pass '" + g_.passes_[pass_].name + "'", "writes an old version of '" + r.name + "'");
    ++r.version;
    g_.passes_[pass_].writes.push_back({index, r.version});
    return r.version;
}

TextureHandle FrameGraph::Builder::create(const std::string& name, const TextureDesc& d) {
    Resource r;
    r.name = name;
    r.tdesc = d;
    return {create_resource(std::move(r)), 0};
}

BufferHandle FrameGraph::Builder::create(const std::string& name, const BufferDesc& d) {
    Resource r;
    r.name = name;
    r.texture = false;
    r.bdesc = d;
    return {create_resource(std::move(r)), 0};
}

TextureHandle FrameGraph::Builder::read(TextureHandle h) {
    read_resource(h.index, h.version, true);
    return h;
}

BufferHandle FrameGraph::Builder::read(BufferHandle h) {
    read_resource(h.index, h.version, false);
    return h;
}

TextureHandle FrameGraph::Builder::write(TextureHandle h) {
    return {h.index, write_resource(h.index, h.version, true)};
}

BufferHandle FrameGraph::Builder::write(BufferHandle h) { return {h.index, write_resource(h.index, h.version, false)}; }

void FrameGraph::Builder::side_effect() { g_.passes_[pass_].side_effect = true; }

// ---- Resources -------------------------------------------------------------------

std::uint64_t Resources::get(TextureHandle h) const { return g_.resources_.at(h.index).physical; }
std::uint64_t Resources::get(BufferHandle h) const { return g_.resources_.at(h.index).physical; }
const TextureDesc& Resources::desc(TextureHandle h) const { return g_.resources_.at(h.index).tdesc; }
const BufferDesc& Resources::desc(BufferHandle h) const { return g_.resources_.at(h.index).bdesc; }
bool Resources::fresh(TextureHandle h) const { return g_.resources_.at(h.index).fresh; }
bool Resources::fresh(BufferHandle h) const { return g_.resources_.at(h.index).fresh; }

// ---- FrameGraph ----------------------------------------------------------------------

std::uint32_t FrameGraph::add_resource(Resource r) {
    resources_.push_back(std::move(r));
    return std::uint32_t(resources_.size() - 1);
}

void FrameGraph::check(std::uint32_t index, std::uint32_t version, bool texture, const char* what) const {
    // `what` names the function that was called with the bad handle.
    if (index >= resources_.size()) throw Error(what, "invalid handle (index " + std::to_string(index) + ")");
    const auto& r = resources_[index];
    if (r.texture != texture) throw Error(what, "handle kind mismatch for '" + r.name + "'");
    if (version > r.version) throw Error(what, "handle of '" + r.name + "' has a version that does not exist");
}

namespace {
template <class Desc> void set_desc(auto& r, const Desc& d) {
    if constexpr (std::is_same_v<Desc, TextureDesc>) {
        r.tdesc = d;
    } else {
        r.texture = false;
        r.bdesc = d;
    }
}
} // namespace

// Imported (physical given) or history (physical from the pool's named store).
template <class Desc>
Handle<Desc> FrameGraph::declare(const std::string& name, const Desc& d, bool history, std::uint64_t physical) {
    Resource r;
    r.name = name;
    set_desc(r, d);
    r.imported = !history;
    r.history = history;
    r.physical = physical;
    return {add_resource(std::move(r)), 0};
}

TextureHandle FrameGraph::import(const std::string& name, const TextureDesc& d, std::uint64_t physical) {
    return declare(name, d, false, physical);
}
BufferHandle FrameGraph::import(const std::string& name, const BufferDesc& d, std::uint64_t physical) {
    return declare(name, d, false, physical);
}
TextureHandle FrameGraph::history(const std::string& name, const TextureDesc& d) { return declare(name, d, true, 0); }
BufferHandle FrameGraph::history(const std::string& name, const BufferDesc& d) { return declare(name, d, true, 0); }

void FrameGraph::request(TextureHandle h) {
    check(h.index, h.version, true, "FrameGraph::request");
    requested_.push_back({h.index, h.version});
}

void FrameGraph::request(BufferHandle h) {
    check(h.index, h.version, false, "FrameGraph::request");
    requested_.push_back({h.index, h.version});
}

void FrameGraph::cull() {
    // Who produced each (resource, version)?
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> producer;
    for (std::uint32_t p = 0; p < passes_.size(); ++p)
        for (const auto& w : passes_[p].writes) producer[{w.resource, w.version}] = p;
    std::vector<std::uint32_t> work;
    auto need_version = [&](const Access& a) {
        auto it = producer.find({a.resource, a.version});
        if (it != producer.end() && !passes_[it->second].needed) {
            passes_[it->second].needed = true;
            work.push_back(it->second);
        }
    };
    for (const auto& a : requested_) need_version(a);
    for (std::uint32_t p = 0; p < passes_.size(); ++p)
        if (passes_[p].side_effect && !passes_[p].needed) {
            passes_[p].needed = true;
            work.push_back(p);
        }
    while (!work.empty()) {
        const auto p = work.back();
        work.pop_back();
        for (const auto& r : passes_[p].reads) need_version(r);
        // A pass that writes version v > 1 builds on version v - 1 only if it
        // read it; writes alone do not pull earlier writers in.
    }
}

void FrameGraph::compile() {
    if (compiled_) return;
    cull();
    // Lifetimes over the needed passes only.
    for (auto& r : resources_) r.first_use = r.last_use = -1;
    for (std::uint32_t p = 0; p < passes_.size(); ++p) {
        if (!passes_[p].needed) continue;
        auto touch = [&](std::uint32_t i) {
            auto& r = resources_[i];
            if (r.first_use < 0) r.first_use = p;
            r.last_use = p;
        };
        for (auto i : passes_[p].creates) touch(i);
        for (const auto& a : passes_[p].reads) touch(a.resource);
        for (const auto& a : passes_[p].writes) touch(a.resource);
    }
    // Requested resources stay alive to the end (the caller reads them).
    const std::int64_t end = std::int64_t(passes_.size());
    for (const auto& a : requested_)
        if (resources_[a.resource].first_use >= 0) resources_[a.resource].last_use = end;
    compiled_ = true;
}

bool FrameGraph::will_run(const std::string& pass) const {
    if (!compiled_) throw Error("FrameGraph::will_run", "called before compile()");
    for (const auto& p : passes_)
        if (p.name == pass) return p.needed;
    return false;
}

std::vector<std::string> FrameGraph::running_passes() const {
    if (!compiled_) throw Error("FrameGraph::running_passes", "called before compile()");
    std::vector<std::string> names;
    for (const auto& p : passes_)
        if (p.needed) names.push_back(p.name);
    return names;
}

FrameStats FrameGraph::execute(ResourcePool& pool) {
    if (executed_) throw Error("FrameGraph::execute", "a frame graph runs once; declare a new one for the next frame");
    executed_ = true;
    compile();
    FrameStats stats;
    for (const auto& r : resources_) stats.virtual_resources += r.imported || r.history ? 0 : 1;
    std::size_t live_bytes = 0;
    auto acquire = [&](Resource& r, PassStats& ps) {
        bool created = false;
        if (r.history) {
            r.physical = r.texture ? pool.history(r.name, r.tdesc, &created) : pool.history(r.name, r.bdesc, &created);
            r.fresh = created;
        } else {
            r.physical = r.texture ? pool.acquire(r.tdesc, r.name, &created) : pool.acquire(r.bdesc, r.name, &created);
            live_bytes += r.texture ? bytes_of(r.tdesc) : r.bdesc.bytes;
            stats.peak_bytes = std::max(stats.peak_bytes, live_bytes);
        }
        if (created) {
            ps.bytes_created += r.texture ? bytes_of(r.tdesc) : r.bdesc.bytes;
            ++stats.physical_resources;
        } else {
            ++stats.reused_resources;
        }
    };

    Resources res(*this);
    for (std::uint32_t p = 0; p < passes_.size(); ++p) {
        PassStats ps;
        ps.name = passes_[p].name;
        if (passes_[p].needed) {
            for (auto& r : resources_)
                if (!r.imported && r.first_use == p) acquire(r, ps);
            const auto t0 = std::chrono::steady_clock::now();
            passes_[p].run(res);
            if (epilogue_) epilogue_();
            ps.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            ps.ran = true;
            for (auto& r : resources_)
                if (!r.imported && !r.history && r.last_use == p) {
                    pool.release(r.physical);
                    live_bytes -= r.texture ? bytes_of(r.tdesc) : r.bdesc.bytes;
                }
        }
        stats.passes.push_back(ps);
    }
    // Requested resources (last use past the final pass) go back now: the
    // caller has read them inside a side-effect pass or does not need them.
    for (auto& r : resources_)
        if (!r.imported && !r.history && r.last_use == std::int64_t(passes_.size())) pool.release(r.physical);
    pool.end_frame();
    return stats;
}

bool FrameGraph::ran(const std::string& pass) const {
    for (const auto& p : passes_)
        if (p.name == pass) return p.needed;
    return false;
}

} // namespace iso::graph
