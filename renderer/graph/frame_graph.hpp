// The pass graph (docs/pass_graph.md). Each frame, passes are declared with
// the resources they create, read and write; then
//  - compile() culls every pass whose outputs nobody needs (a pass is needed
//    when it writes a resource that is requested for this frame, that a
//    needed pass reads, or when it has a side effect such as a read-back to
//    the CPU) and works out each resource's lifetime, touching no GPU, so the
//    renderer's real frame is tested without one;
//  - execute() takes transient resources for the needed passes from a
//    ResourcePool (resource_pool.hpp: kept across frames, keyed by
//    descriptor; resources whose lifetimes do not overlap share one object),
//    runs the needed passes in declaration order, gives the resources back
//    and records per-pass statistics (ran or culled, wall time, bytes of
//    resources created).
// History resources persist across frames under a name (the AO slicemap and
// accumulation); a pass learns from Resources::fresh() that one was just
// (re)made and holds nothing yet.
// Modelled on Filament's FrameGraph: typed handles, descriptor structs,
// [[nodiscard]] writes that return the new version of a resource.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace iso::graph {

enum class Format : std::uint8_t { RGBA8, RGBA16F, RGBA32F, R32F, RG16F, R32UI, RG32UI, RGBA32UI, Depth32F };
std::size_t bytes_per_pixel(Format f);

// depth > 1: a 3D texture; array (or layers > 1): a 2D array texture of
// `layers` layers (shaders sampling an array need one even of one layer).
struct TextureDesc {
    int width = 1, height = 1;
    Format format = Format::RGBA8;
    int layers = 1;
    int depth = 1;
    bool array = false;
    int samples = 1; // > 1: a multisample 2D texture (samples per pixel)
    bool operator==(const TextureDesc&) const = default;
};
std::size_t bytes_of(const TextureDesc& d);
struct BufferDesc {
    std::size_t bytes = 0;
    bool operator==(const BufferDesc&) const = default;
};

// A typed handle to one version of a virtual resource.
template <class Desc> struct Handle {
    std::uint32_t index = 0xFFFFFFFFu; // into the graph's resource table
    std::uint32_t version = 0;
    bool valid() const { return index != 0xFFFFFFFFu; }
    bool operator==(const Handle&) const = default;
};
using TextureHandle = Handle<TextureDesc>;
using BufferHandle = Handle<BufferDesc>;

// What the graph asks of the GPU (or of a test double).
class Backend {
public:
    virtual ~Backend() = default;
    // Returns an opaque id of a new physical resource.
    virtual std::uint64_t create_texture(const TextureDesc& d, const std::string& name) = 0;
    virtual std::uint64_t create_buffer(const BufferDesc& d, const std::string& name) = 0;
    virtual void destroy(std::uint64_t id) = 0;
};

struct PassStats {
    std::string name;
    bool ran = false;
    double ms = 0;                 // wall time of execute (callers glFinish inside when timing GPU work)
    std::size_t bytes_created = 0; // physical resources created for this pass's first uses
};

struct FrameStats {
    std::vector<PassStats> passes;
    std::size_t physical_resources = 0; // created this frame (not taken from the pool)
    std::size_t reused_resources = 0;   // taken from the pool (kept from earlier frames or passes)
    std::size_t virtual_resources = 0;  // declared this frame (non-imported)
    std::size_t peak_bytes = 0;         // physical transient resources in use at once this frame
};

class FrameGraph;
class ResourcePool;

// Handed to a pass's execute step: physical ids of its resources.
class Resources {
public:
    std::uint64_t get(TextureHandle h) const;
    std::uint64_t get(BufferHandle h) const;
    const TextureDesc& desc(TextureHandle h) const;
    const BufferDesc& desc(BufferHandle h) const;
    // A history resource that was (re)made this frame: its contents are undefined.
    bool fresh(TextureHandle h) const;
    bool fresh(BufferHandle h) const;

private:
    friend class FrameGraph;
    explicit Resources(const FrameGraph& g) : g_(g) {}
    const FrameGraph& g_;
};

class FrameGraph {
    struct Resource; // below

public:
    class Builder {
    public:
        TextureHandle create(const std::string& name, const TextureDesc& d);
        BufferHandle create(const std::string& name, const BufferDesc& d);
        TextureHandle read(TextureHandle h);
        BufferHandle read(BufferHandle h);
        // Writing makes a new version; later readers must use the returned handle.
        [[nodiscard]] TextureHandle write(TextureHandle h);
        [[nodiscard]] BufferHandle write(BufferHandle h);
        // The pass must run even if nothing reads what it writes (read-back, export).
        void side_effect();

    private:
        friend class FrameGraph;
        Builder(FrameGraph& g, std::uint32_t pass) : g_(g), pass_(pass) {}
        std::uint32_t create_resource(Resource r);
        void read_resource(std::uint32_t index, std::uint32_t version, bool texture);
        std::uint32_t write_resource(std::uint32_t index, std::uint32_t version, bool texture);
        FrameGraph& g_;
        std::uint32_t pass_;
    };

    FrameGraph() = default;
    FrameGraph(const FrameGraph&) = delete;
    FrameGraph& operator=(const FrameGraph&) = delete;

    // Adds a pass. `setup(Builder&, Data&)` runs now; `execute(const Data&,
    // const Resources&)` runs in execute() if the pass is not culled.
    template <class Data, class Setup, class Execute>
    const Data& add_pass(const std::string& name, Setup&& setup, Execute&& execute) {
        auto data = std::make_shared<Data>();
        const std::uint32_t index = std::uint32_t(passes_.size());
        passes_.push_back(Pass{name});
        Builder b(*this, index);
        setup(b, *data);
        passes_[index].run = [data, exec = std::forward<Execute>(execute)](const Resources& r) { exec(*data, r); };
        passes_[index].keep_alive = data;
        return *data;
    }

    // A resource that lives outside the graph (e.g. the window's framebuffer,
    // a mesh's vertex buffer): never allocated or freed by the graph.
    TextureHandle import(const std::string& name, const TextureDesc& d, std::uint64_t physical);
    BufferHandle import(const std::string& name, const BufferDesc& d, std::uint64_t physical);
    // A resource that persists across frames in the pool under `name`; made
    // when first needed or when its descriptor changes, and only if a needed
    // pass uses it. Passes read what earlier frames wrote to it.
    TextureHandle history(const std::string& name, const TextureDesc& d);
    BufferHandle history(const std::string& name, const BufferDesc& d);

    // This frame's requested outputs: what must be computed.
    void request(TextureHandle h);
    void request(BufferHandle h);

    // Culls and computes lifetimes; no GPU work. Graph misuse (reading what
    // nothing wrote, writing an old version) throws iso::Error naming the
    // pass when it is declared.
    void compile();
    // After compile(): will the named pass run? (false for unknown names)
    bool will_run(const std::string& pass) const;
    // After compile(): names of the passes that will run, in order.
    std::vector<std::string> running_passes() const;

    // compile() if not yet, then takes resources from the pool, runs the
    // needed passes and gives transient resources back. Once per graph.
    FrameStats execute(ResourcePool& pool);

    // Runs at the end of every executed pass, inside its timed region (the GL
    // renderer passes glFinish here when per-pass times are asked for: GL
    // calls return before the GPU is done).
    void set_pass_epilogue(std::function<void()> f) { epilogue_ = std::move(f); }

    // After execute(): was the named pass run?
    bool ran(const std::string& pass) const;

private:
    friend class Resources;
    struct Resource {
        std::string name;
        bool texture = true;
        TextureDesc tdesc;
        BufferDesc bdesc;
        bool imported = false;
        bool history = false;
        bool fresh = false;
        std::uint64_t physical = 0;
        std::uint32_t version = 0;
        std::int64_t producer_of_version = -1; // pass that wrote the latest version (bookkeeping)
        std::int64_t first_use = -1, last_use = -1;
        std::uint32_t refcount = 0;
    };
    struct Access {
        std::uint32_t resource, version;
    };
    struct Pass {
        std::string name;
        std::vector<std::uint32_t> creates;
        std::vector<Access> reads, writes;
        bool side_effect = false;
        bool needed = false;
        std::function<void(const Resources&)> run;
        std::shared_ptr<void> keep_alive;
    };
    std::uint32_t add_resource(Resource r);
    template <class Desc>
    Handle<Desc> declare(const std::string& name, const Desc& d, bool history, std::uint64_t physical);
    void check(std::uint32_t index, std::uint32_t version, bool texture, const char* what) const;
    void cull();
    bool compiled_ = false, executed_ = false;

    std::vector<Resource> resources_;
    std::vector<Pass> passes_;
    std::vector<Access> requested_;
    std::function<void()> epilogue_;
};

} // namespace iso::graph
