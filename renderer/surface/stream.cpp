// The streaming driver (stream.hpp): the index pass, then the plan's slabs
// through the read, extract and write steps (stream_steps.hpp) run by the
// pipeline (stream_pipeline.hpp); the planner is in stream_plan.cpp.
#include "renderer/surface/stream.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "renderer/surface/stream_pipeline.hpp"
#include "renderer/surface/stream_plan.hpp"
#include "renderer/surface/stream_steps.hpp"

namespace iso {

std::shared_ptr<const ChunkIndex> build_chunk_index(VolumeStream& src, int chunk_size, std::size_t memory_budget,
                                                    const ProgressFn& progress, std::vector<double>* labels_out) {
    const VolumeHeader& h = src.header();
    ChunkSummaries sum(h.dims, chunk_size, h.type);
    const std::size_t chunks = std::size_t(sum.counts[0]) * sum.counts[1] * sum.counts[2];
    const std::int64_t per = detail::index_pass_slabs(h, chunks, memory_budget).per;
    std::set<double> labels;
    for (std::int64_t k0 = 0; k0 < h.dims[2]; k0 += per) {
        const std::int64_t k1 = std::min(k0 + per - 1, h.dims[2] - 1);
        report(progress, double(k0) / double(h.dims[2]), "indexing volume", "streaming");
        const Volume slab = src.read_slab(k0, k1);
        sum.add({&slab, h.dims, k0, h.index_to_lps});
        if (labels_out) {
            for (double v : distinct_labels(slab)) labels.insert(v);
            if (labels.size() > 4096)
                throw Error(h.path, "has more than 4096 distinct values: it does not look like a label map");
        }
    }
    report(progress, 1.0, "indexing volume", "streaming");
    if (labels_out) labels_out->assign(labels.begin(), labels.end());
    return std::make_shared<const ChunkIndex>(sum.finish());
}

namespace {

using detail::Clock;
using detail::mib;
using detail::seconds_since;

// The options as the driver uses them: checked, the labels sorted and
// unique, and what the source holds (a volume loaded whole, a gzip stream's
// last slices) taken from the budget.
StreamOptions checked_options(const VolumeStream& src, const StreamOptions& in) {
    StreamOptions opt = in;
    if (!opt.labels && opt.isos.empty()) throw Error("streaming", "no iso value");
    for (double v : opt.isos)
        if (!std::isfinite(v)) throw Error("extract", "iso value is not a finite number");
    if (opt.index && opt.index->dims() != src.header().dims)
        throw Error("streaming", "the given chunk index is of another volume");
    if (opt.labels) {
        std::sort(opt.label_values.begin(), opt.label_values.end());
        opt.label_values.erase(std::unique(opt.label_values.begin(), opt.label_values.end()), opt.label_values.end());
    }
    if (src.resident_bytes() >= opt.memory_budget)
        throw Error("memory budget", mib(opt.memory_budget) + " is less than the " + mib(src.resident_bytes()) +
                                         " the volume's source holds");
    opt.memory_budget -= src.resident_bytes();
    return opt;
}

// The index pass, `share` of the progress; finds the labels when none are
// given. Its time and what it held go into `st`.
std::shared_ptr<const ChunkIndex> index_pass(VolumeStream& src, StreamOptions& opt, double share, StreamStats& st) {
    const VolumeHeader& h = src.header();
    const bool find_labels = opt.labels && opt.label_values.empty();
    const StreamPlan pre = plan_stream(h, opt, nullptr);
    const auto t = Clock::now();
    std::vector<double> found;
    auto index = build_chunk_index(src, pre.chunk_size, opt.memory_budget,
                                   detail::progress_part(opt.progress, 0.0, share), find_labels ? &found : nullptr);
    if (find_labels) opt.label_values = found;
    st.index_pass = true;
    st.index_seconds = seconds_since(t);
    st.read_seconds += st.index_seconds;
    // The index pass held its index, a read buffer and slabs of as many slices as fit.
    const detail::IndexPassSlabs ip = detail::index_pass_slabs(h, index->chunk_count(), opt.memory_budget);
    st.peak_bytes =
        std::max(st.peak_bytes, ip.fixed + src.resident_bytes() +
                                    std::min<std::size_t>(std::size_t(ip.per), std::size_t(h.dims[2])) * ip.slice);
    return index;
}

// The slabs of the plan through the steps; the seconds, counts and peak go into `st`.
void run_slabs(VolumeStream& src, MeshSink& sink, const std::shared_ptr<const ChunkIndex>& index,
               const StreamOptions& opt, double index_share, StreamStats& st) {
    const StreamPlan& plan = st.plan;
    const char* stage = opt.labels ? "extracting label surfaces" : "extracting isosurface";
    const std::vector<double>& values = opt.labels ? opt.label_values : opt.isos;
    const detail::SlabSchedule schedule = detail::schedule_slabs(src.header(), plan, *index, values, opt, index_share);
    detail::MemoryMeter meter;
    meter.add(detail::index_bytes(index->chunk_count()) + src.resident_bytes());
    meter.add(schedule.memory_bytes());
    detail::SlabSteps steps(src, sink, index, opt, values, meter);
    detail::SlabPipeline pipeline(steps, schedule, [&](std::size_t i) {
        report(opt.progress, index_share + (1.0 - index_share) * double(i) / double(plan.slabs), stage, "streaming");
    });
    pipeline.run(plan.overlap);
    const detail::PipelineCounts& n = pipeline.counts();
    st.slabs_read = n.slabs_read;
    st.slabs_skipped = n.slabs_skipped;
    st.chunks_visited = n.chunks_visited;
    st.read_seconds += steps.seconds.read;
    st.extract_seconds = steps.seconds.extract;
    st.weld_seconds = steps.seconds.weld;
    st.write_seconds = steps.seconds.write;
    st.analysis_seconds = steps.seconds.analysis;
    st.wait_seconds = n.wait_seconds;
    st.peak_bytes = std::max(st.peak_bytes, meter.peak());
    st.source_restarts = src.restarts();
    report(opt.progress, 1.0, stage, "streaming");
}

} // namespace

StreamStats stream_extract(VolumeStream& src, const StreamOptions& opt_in, MeshSink& sink) {
    StreamOptions opt = checked_options(src, opt_in);
    StreamStats st;
    const double index_share = opt.index ? 0.0 : 0.3; // the index pass's share of the progress
    const std::shared_ptr<const ChunkIndex> index = opt.index ? opt.index : index_pass(src, opt, index_share, st);
    const std::vector<double>& values = opt.labels ? opt.label_values : opt.isos;
    st.values = values;
    st.plan = plan_stream(src.header(), opt, index.get());
    if (!st.plan.fits)
        st.warnings.push_back("the surface's estimated size in one chunk layer does not fit " + mib(opt.memory_budget) +
                              " with the samples: slabs of one layer, the output may exceed the budget (raise the "
                              "memory budget or lower the chunk size)");
    sink.begin(values.size(), st.plan.slabs, opt.extract.normals);
    if (values.empty() || st.plan.slabs == 0) {
        report(opt.progress, 1.0, "extracting isosurface", "streaming");
        sink.finish();
        return st;
    }
    run_slabs(src, sink, index, opt, index_share, st);
    const auto t = Clock::now();
    sink.finish();
    st.write_seconds += seconds_since(t);
    return st;
}

} // namespace iso
