// GPU resources that live across frames (modelled on Filament's
// ResourceAllocator): the frame graph takes its transient textures and
// buffers from here and gives them back when their last pass has run; a
// given-back resource waits, keyed by its descriptor, for the next request of
// the same descriptor (later in the frame or in a later frame) and is
// destroyed once it has waited `max_age` frames. History resources persist
// under a name until their descriptor changes or they go unused for
// `max_history_age` frames. In a steady state (same view size and settings)
// a frame creates nothing: stats() says so, and the tests read it.
// GPU-agnostic: objects are made and destroyed through a Backend.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "renderer/graph/frame_graph.hpp"

namespace iso::graph {

class ResourcePool {
public:
    explicit ResourcePool(Backend& backend, int max_age = 3, int max_history_age = 120);
    ~ResourcePool(); // destroys every resource it holds
    ResourcePool(const ResourcePool&) = delete;
    ResourcePool& operator=(const ResourcePool&) = delete;

    // A resource of this descriptor: one that waits in the pool, or a new one.
    // `created` (optional) says which.
    std::uint64_t acquire(const TextureDesc& d, const std::string& name, bool* created = nullptr);
    std::uint64_t acquire(const BufferDesc& d, const std::string& name, bool* created = nullptr);
    // Gives an acquired resource back (asserts it was acquired).
    void release(std::uint64_t id);

    // The history resource `name` with this descriptor; `fresh` says it was
    // (re)made now and holds nothing yet.
    std::uint64_t history(const std::string& name, const TextureDesc& d, bool* fresh = nullptr);
    std::uint64_t history(const std::string& name, const BufferDesc& d, bool* fresh = nullptr);
    // Does a history resource `name` with this descriptor exist (kept contents)?
    bool has_history(const std::string& name, const TextureDesc& d) const;
    bool has_history(const std::string& name, const BufferDesc& d) const;
    void drop_history(const std::string& name);

    // Ages waiting resources and destroys those older than max_age frames,
    // and history unused for max_history_age frames. Call once per frame.
    void end_frame();

    struct Stats {
        std::size_t created = 0, reused = 0, destroyed = 0; // cumulative
        std::size_t live = 0, waiting = 0, history = 0;     // now
        std::size_t live_bytes = 0;                         // all resources held now
        std::uint64_t frames = 0;
    };
    const Stats& stats() const { return stats_; }
    Backend& backend() { return backend_; }

private:
    struct Entry {
        bool texture = true;
        TextureDesc t;
        BufferDesc b;
        std::uint64_t id = 0;
        std::uint64_t last_used = 0; // frame number
        std::string name;            // of the first virtual resource it backed in the frame it was last used
        std::uint64_t named_in = ~std::uint64_t(0); // the frame `name` was set in
    };
    std::uint64_t take(const Entry& want, const std::string& name, bool* created);
    std::uint64_t make(const Entry& want, const std::string& name);
    void destroy(const Entry& e);
    std::uint64_t history_of(const std::string& name, const Entry& want, bool* fresh);

    Backend& backend_;
    int max_age_, max_history_age_;
    std::vector<Entry> waiting_;
    std::map<std::uint64_t, Entry> in_use_;
    std::map<std::string, Entry> history_;
    Stats stats_;
};

} // namespace iso::graph
