// The steps of the streaming driver (stream.cpp, docs/isosurface.md "Out of
// core"): the memory meter, the slab jobs of a plan, and reading, extracting
// and welding/writing one slab. The pipeline (stream_pipeline.hpp) runs the
// steps one after another or on three threads at once.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "io/mesh_sink.hpp"
#include "io/volume_stream.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/stream.hpp"

namespace iso::detail {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Part [a, b] of `progress` (empty when it is). Keeps a reference to it.
ProgressFn progress_part(const ProgressFn& progress, double a, double b);

// What the steps hold, counted as they allocate and free (from three
// threads with overlap): its high-water mark is StreamStats::peak_bytes.
class MemoryMeter {
public:
    void add(std::size_t n);
    void sub(std::size_t n) { now_.fetch_sub(n); }
    void transient(std::size_t n) { add(n), sub(n); }
    // Something counted as `was` bytes now holds `now`.
    void change(std::size_t was, std::size_t now) {
        if (now > was)
            add(now - was);
        else
            sub(was - now);
    }
    std::size_t peak() const { return peak_.load(); }

private:
    std::atomic<std::size_t> now_{0}, peak_{0};
};

// A slab of the plan with active chunks.
struct SlabJob {
    std::size_t piece = 0;        // piece number (slab of the plan)
    std::size_t a = 0, b = 0;     // its chunk ids [a, b)
    std::vector<std::size_t> ids; // its active chunks
    std::int64_t k0 = 0, k1 = 0;  // its samples, halo included
    double f0 = 0, f1 = 0;        // its share of the progress
};

// The slabs with active chunks, in order (the others are skipped unread).
struct SlabSchedule {
    std::vector<SlabJob> jobs;
    std::vector<std::size_t> job_of; // per slab of the plan: its job, or kSkipped
    static constexpr std::size_t kSkipped = std::size_t(-1);
    // The job of slab i of the plan, or null for a slab skipped unread.
    const SlabJob* job(std::size_t i) const { return job_of[i] == kSkipped ? nullptr : &jobs[job_of[i]]; }
    // The job list's own memory, held throughout.
    std::size_t memory_bytes() const;
};

// `index_share`: the index pass's share of the progress (the slabs share the rest).
SlabSchedule schedule_slabs(const VolumeHeader& h, const StreamPlan& plan, const ChunkIndex& index,
                            const std::vector<double>& values, const StreamOptions& opt, double index_share);

struct Slab {
    Volume samples;
    std::size_t bytes = 0; // as counted
};

// A slab's chunk meshes, one chunked surface per value.
struct SlabOutput {
    const SlabJob* job = nullptr;
    std::vector<ChunkedSurface> surfaces;
    std::size_t bytes = 0; // as counted
};

// Seconds each step was busy (StreamStats).
struct StepSeconds {
    double read = 0, extract = 0, weld = 0, write = 0, analysis = 0;
};

// Reading, extracting and welding/writing one slab, each counting what it
// holds on the meter. read() may run on one thread, extract() on another and
// write() on a third at once (each adds to its own StepSeconds member).
class SlabSteps {
public:
    // `opt`: as stream_extract() uses them (the source's share taken from
    // the budget); `values`: the iso values or labels, one per surface.
    SlabSteps(VolumeStream& src, MeshSink& sink, std::shared_ptr<const ChunkIndex> index, const StreamOptions& opt,
              const std::vector<double>& values, MemoryMeter& meter);

    // The layers' samples and their gradient halo (counted before the read,
    // which allocates them at once).
    Slab read(const SlabJob& j);
    // A slab that is read and not extracted (the caller is leaving).
    void discard(Slab&& s) { meter_.sub(s.bytes); }
    // Extracts the slab's chunks; the samples are freed at once. `failed`
    // (optional): the reader or the writer failed, the extraction stops at
    // its next progress check.
    SlabOutput extract(const SlabJob& j, Slab&& slab, const std::atomic<bool>* failed);
    // Welds each surface's piece, names its seam vertices and hands it to
    // the sink. `stop` (optional): give up between surfaces (another step failed).
    void write(SlabOutput&& out, const std::atomic<bool>* stop);

    StepSeconds seconds;

private:
    // A surface's non-empty chunks of one slab, about to be welded.
    struct Piece {
        ChunkedSurface surface;
        std::vector<std::size_t> ids; // their chunk ids
        std::size_t bytes = 0;        // as counted
    };
    void write_surface(SlabOutput& out, std::size_t s);
    Piece take_piece(SlabOutput& out, std::size_t s);
    MeshPiece weld_piece(const Piece& piece, const SlabJob& j, std::size_t s);
    void add_seams(MeshPiece& mp, const Piece& piece, const WeldMap& map, const SlabJob& j) const;

    VolumeStream& src_;
    MeshSink& sink_;
    std::shared_ptr<const ChunkIndex> index_;
    const StreamOptions& opt_;
    const std::vector<double>& values_;
    MemoryMeter& meter_;
    ExtractOptions eo_;
    int threads_ = 1;
    std::size_t sink_bytes_ = 0; // the sink's seam maps, as counted
};

} // namespace iso::detail
