// The streaming driver's pipeline (stream_pipeline.hpp). std::thread and a
// condition variable rather than a TBB flow graph: the reader blocks in
// pread()/zlib and must not take one of the TBB threads that extraction and
// welding use.
#include "renderer/surface/stream_pipeline.hpp"

namespace iso {

namespace {

std::atomic<std::size_t> g_threads_running{0};
// Counts a pipeline thread from its start to the end of its function.
struct Running {
    Running() { ++g_threads_running; }
    ~Running() { --g_threads_running; }
};

} // namespace

std::size_t stream_threads_running() { return g_threads_running.load(); }

namespace detail {

SlabPipeline::SlabPipeline(SlabSteps& steps, const SlabSchedule& schedule, std::function<void(std::size_t)> begin_slab)
    : steps_(steps), schedule_(schedule), begin_slab_(std::move(begin_slab)) {}

void SlabPipeline::run(bool overlap) {
    if (overlap)
        run_overlapped();
    else
        run_serial();
}

const SlabJob* SlabPipeline::begin(std::size_t i) {
    begin_slab_(i);
    const SlabJob* j = schedule_.job(i);
    if (!j) ++counts_.slabs_skipped;
    return j;
}

void SlabPipeline::run_serial() {
    for (std::size_t i = 0; i < schedule_.job_of.size(); ++i) {
        const SlabJob* j = begin(i);
        if (!j) continue;
        Slab slab = steps_.read(*j);
        ++counts_.slabs_read;
        counts_.chunks_visited += j->ids.size();
        steps_.write(steps_.extract(*j, std::move(slab), nullptr), nullptr);
    }
}

void SlabPipeline::run_overlapped() {
    // Any way out of here stops and joins both threads first.
    struct Joiner {
        SlabPipeline& p;
        ~Joiner() { p.stop_and_join(); }
    } joiner{*this};
    reader_ = std::thread([this] { read_all(); });
    writer_ = std::thread([this] { write_all(); });
    try {
        for (std::size_t i = 0; i < schedule_.job_of.size(); ++i) {
            const SlabJob* j = begin(i);
            if (!j) continue;
            Slab slab = take_slab();
            ++counts_.slabs_read;
            counts_.chunks_visited += j->ids.size();
            SlabOutput out = steps_.extract(*j, std::move(slab), &failed_);
            drain();
            rethrow_failure();
            hand_over(std::move(out));
        }
        drain();
        rethrow_failure();
        close_and_join();
        rethrow_failure();
    } catch (const Cancelled&) {
        // The extraction stopped because the reader or the writer failed: their error, not a cancel.
        rethrow_failure();
        throw;
    }
}

// The reader thread: slab n is read once slab n-1 has been taken (the extraction holds it).
void SlabPipeline::read_all() {
    const Running running;
    try {
        for (std::size_t n = 0; n < schedule_.jobs.size(); ++n) {
            {
                std::unique_lock l(m_);
                cv_.wait(l, [&] { return stop_ || taken_ >= n; });
                if (stop_) return;
            }
            Slab s = steps_.read(schedule_.jobs[n]);
            {
                std::lock_guard l(m_);
                if (stop_) {
                    steps_.discard(std::move(s));
                    return;
                }
                ready_ = std::move(s);
            }
            cv_.notify_all();
        }
    } catch (...) {
        fail(read_error_);
    }
}

// The writer thread: writes what it is handed until the pipeline closes.
void SlabPipeline::write_all() {
    const Running running;
    try {
        for (;;) {
            std::optional<SlabOutput> out;
            {
                std::unique_lock l(m_);
                cv_.wait(l, [&] { return stop_ || handed_ || closed_; });
                if (stop_ || !handed_) return;
                out = std::move(handed_);
                handed_.reset();
                writing_ = true;
            }
            steps_.write(std::move(*out), &stop_);
            {
                std::lock_guard l(m_);
                writing_ = false;
            }
            cv_.notify_all();
        }
    } catch (...) {
        fail(write_error_);
    }
}

// The next slab from the reader (waiting for it), or the reader's or the writer's error.
Slab SlabPipeline::take_slab() {
    Slab slab;
    {
        const auto t = Clock::now();
        std::unique_lock l(m_);
        cv_.wait(l, [&] { return ready_ || read_error_ || write_error_; });
        counts_.wait_seconds += seconds_since(t);
        if (!ready_) {
            l.unlock();
            rethrow_failure();
        }
        slab = std::move(*ready_);
        ready_.reset();
        ++taken_;
    }
    cv_.notify_all();
    return slab;
}

void SlabPipeline::hand_over(SlabOutput&& out) {
    {
        std::lock_guard l(m_);
        handed_ = std::move(out);
    }
    cv_.notify_all();
}

// Waits until the writer has written what it was handed.
void SlabPipeline::drain() {
    const auto t = Clock::now();
    std::unique_lock l(m_);
    cv_.wait(l, [&] { return write_error_ || (!handed_ && !writing_); });
    counts_.wait_seconds += seconds_since(t);
}

// Every slab is written: the writer ends, and the reader has read every job.
void SlabPipeline::close_and_join() {
    {
        std::lock_guard l(m_);
        closed_ = true;
    }
    cv_.notify_all();
    writer_.join();
    reader_.join();
}

void SlabPipeline::stop_and_join() {
    {
        std::lock_guard l(m_);
        stop_ = true;
    }
    cv_.notify_all();
    if (reader_.joinable()) reader_.join();
    if (writer_.joinable()) writer_.join();
}

void SlabPipeline::fail(std::exception_ptr& slot) {
    {
        std::lock_guard l(m_);
        slot = std::current_exception();
    }
    failed_ = true;
    cv_.notify_all();
}

// The writer's error, else the reader's, as it was thrown (iso::Error, Cancelled, bad_alloc ...).
void SlabPipeline::rethrow_failure() {
    std::lock_guard l(m_);
    if (write_error_) std::rethrow_exception(write_error_);
    if (read_error_) std::rethrow_exception(read_error_);
}

} // namespace detail

} // namespace iso
