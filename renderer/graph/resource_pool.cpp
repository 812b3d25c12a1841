#include "renderer/graph/resource_pool.hpp"

#include <algorithm>
#include <cassert>

#include "io/error.hpp"

namespace iso::graph {

namespace {
bool same(const bool texture, const TextureDesc& t, const BufferDesc& b, const bool texture2, const TextureDesc& t2,
          const BufferDesc& b2) {
    return texture == texture2 && (texture ? t == t2 : b == b2);
}
} // namespace

ResourcePool::ResourcePool(Backend& backend, int max_age, int max_history_age)
    : backend_(backend), max_age_(max_age), max_history_age_(max_history_age) {}

ResourcePool::~ResourcePool() {
    for (const auto& e : waiting_) backend_.destroy(e.id);
    for (const auto& [id, e] : in_use_) backend_.destroy(id);
    for (const auto& [name, e] : history_) backend_.destroy(e.id);
}

std::uint64_t ResourcePool::make(const Entry& want, const std::string& name) {
    const std::uint64_t id =
        want.texture ? backend_.create_texture(want.t, name) : backend_.create_buffer(want.b, name);
    ++stats_.created;
    stats_.live_bytes += want.texture ? bytes_of(want.t) : want.b.bytes;
    ++stats_.live;
    return id;
}

void ResourcePool::destroy(const Entry& e) {
    backend_.destroy(e.id);
    ++stats_.destroyed;
    stats_.live_bytes -= e.texture ? bytes_of(e.t) : e.b.bytes;
    --stats_.live;
}

std::uint64_t ResourcePool::take(const Entry& want, const std::string& name, bool* created) {
    // Preferably the one this name had last time: frame after frame each
    // virtual resource then gets the same object, and what is cached by
    // object (framebuffers) stays valid. Else any of the descriptor.
    auto pick = waiting_.end();
    for (auto it = waiting_.begin(); it != waiting_.end(); ++it)
        if (same(it->texture, it->t, it->b, want.texture, want.t, want.b)) {
            if (pick == waiting_.end() || it->name == name) pick = it;
            if (it->name == name) break;
        }
    if (pick != waiting_.end()) {
        Entry e = *pick;
        waiting_.erase(pick);
        --stats_.waiting;
        ++stats_.reused;
        // An object that backs several resources in one frame (one's last
        // use before another's first) keeps the first one's name, so next
        // frame that one finds it again and the later ones take what is left.
        if (e.named_in != stats_.frames) {
            e.name = name;
            e.named_in = stats_.frames;
        }
        in_use_.emplace(e.id, e);
        if (created) *created = false;
        return e.id;
    }
    Entry e = want;
    e.name = name;
    e.named_in = stats_.frames;
    e.id = make(want, name);
    in_use_.emplace(e.id, e);
    if (created) *created = true;
    return e.id;
}

std::uint64_t ResourcePool::acquire(const TextureDesc& d, const std::string& name, bool* created) {
    Entry e;
    e.t = d;
    return take(e, name, created);
}

std::uint64_t ResourcePool::acquire(const BufferDesc& d, const std::string& name, bool* created) {
    Entry e;
    e.texture = false;
    e.b = d;
    return take(e, name, created);
}

void ResourcePool::release(std::uint64_t id) {
    const auto it = in_use_.find(id);
    if (it == in_use_.end())
        throw Error("ResourcePool::release", "resource " + std::to_string(id) + " was not acquired from this pool");
    Entry e = it->second;
    in_use_.erase(it);
    e.last_used = stats_.frames;
    waiting_.push_back(e);
    ++stats_.waiting;
}

std::uint64_t ResourcePool::history_of(const std::string& name, const Entry& want, bool* fresh) {
    auto it = history_.find(name);
    if (it != history_.end() && same(it->second.texture, it->second.t, it->second.b, want.texture, want.t, want.b)) {
        it->second.last_used = stats_.frames;
        if (fresh) *fresh = false;
        return it->second.id;
    }
    if (it != history_.end()) {
        destroy(it->second);
        history_.erase(it);
        --stats_.history;
    }
    Entry e = want;
    e.id = make(want, name);
    e.last_used = stats_.frames;
    history_.emplace(name, e);
    ++stats_.history;
    if (fresh) *fresh = true;
    return e.id;
}

std::uint64_t ResourcePool::history(const std::string& name, const TextureDesc& d, bool* fresh) {
    Entry e;
    e.t = d;
    return history_of(name, e, fresh);
}

std::uint64_t ResourcePool::history(const std::string& name, const BufferDesc& d, bool* fresh) {
    Entry e;
    e.texture = false;
    e.b = d;
    return history_of(name, e, fresh);
}

bool ResourcePool::has_history(const std::string& name, const TextureDesc& d) const {
    const auto it = history_.find(name);
    return it != history_.end() && it->second.texture && it->second.t == d;
}

bool ResourcePool::has_history(const std::string& name, const BufferDesc& d) const {
    const auto it = history_.find(name);
    return it != history_.end() && !it->second.texture && it->second.b == d;
}

void ResourcePool::drop_history(const std::string& name) {
    const auto it = history_.find(name);
    if (it == history_.end()) return;
    destroy(it->second);
    history_.erase(it);
    --stats_.history;
}

void ResourcePool::end_frame() {
    const std::uint64_t now = stats_.frames;
    for (auto it = waiting_.begin(); it != waiting_.end();) {
        if (now - it->last_used >= std::uint64_t(max_age_)) {
            destroy(*it);
            it = waiting_.erase(it);
            --stats_.waiting;
        } else {
            ++it;
        }
    }
    for (auto it = history_.begin(); it != history_.end();) {
        if (now - it->second.last_used >= std::uint64_t(max_history_age_)) {
            destroy(it->second);
            it = history_.erase(it);
            --stats_.history;
        } else {
            ++it;
        }
    }
    ++stats_.frames;
}

} // namespace iso::graph
