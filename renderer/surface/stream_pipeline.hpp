// Runs the streaming driver's steps (stream_steps.hpp) over the slabs of a
// plan: one after another, or overlapped (StreamOptions::overlap) with a
// reader thread, the extraction on the caller's thread and a writer thread
// (docs/isosurface.md, "Overlapped steps").
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "renderer/surface/stream_steps.hpp"

namespace iso::detail {

struct PipelineCounts {
    std::size_t slabs_read = 0, slabs_skipped = 0, chunks_visited = 0;
    double wait_seconds = 0; // the extraction waiting for the reader or the writer
};

class SlabPipeline {
public:
    // `begin_slab(i)` is called before slab i of the plan (progress; it may
    // throw iso::Cancelled), skipped slabs included.
    SlabPipeline(SlabSteps& steps, const SlabSchedule& schedule, std::function<void(std::size_t)> begin_slab);
    ~SlabPipeline() { stop_and_join(); }
    SlabPipeline(const SlabPipeline&) = delete;
    SlabPipeline& operator=(const SlabPipeline&) = delete;

    // Every way out of run() (an error, a cancel) has joined both threads
    // first; the reader's or the writer's error is rethrown as it was thrown.
    void run(bool overlap);
    const PipelineCounts& counts() const { return counts_; }

private:
    const SlabJob* begin(std::size_t i);
    void run_serial();
    void run_overlapped();
    void read_all();
    void write_all();
    Slab take_slab();
    void hand_over(SlabOutput&& out);
    void drain();
    void close_and_join();
    void stop_and_join();
    void fail(std::exception_ptr& slot);
    void rethrow_failure();

    SlabSteps& steps_;
    const SlabSchedule& schedule_;
    std::function<void(std::size_t)> begin_slab_;
    PipelineCounts counts_;

    // The hand-overs (overlapped only). Each holds one item and a step waits
    // for the next one to take it, so at most two slabs of samples (the one
    // extracted, the next being read) and two slabs' output (one being welded
    // and written, the next being extracted) exist at once, as the planner
    // counted.
    std::mutex m_;
    std::condition_variable cv_;
    std::atomic<bool> stop_{false};   // the caller is leaving (an error, a cancel)
    std::atomic<bool> failed_{false}; // the reader or the writer failed: the extraction stops
    std::size_t taken_ = 0;           // slabs the extraction has taken from the reader
    std::optional<Slab> ready_;       // the slab read and not yet taken
    std::exception_ptr read_error_;
    std::optional<SlabOutput> handed_; // the output handed to the writer and not yet taken
    bool writing_ = false, closed_ = false;
    std::exception_ptr write_error_;
    std::thread reader_, writer_;
};

} // namespace iso::detail
