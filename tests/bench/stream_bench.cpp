// Out-of-core extraction against the in-memory one on a 1 GiB volume
// (docs/isosurface.md quotes its line): a 512 x 512 x 2048 int16 ball
// (tests/support/big_ball.hpp) written slice by slice, streamed with a
// 128 MiB budget to PLY, then loaded and extracted in memory by the same
// process (after the streaming, so that the streaming's VmHWM is not raised
// by it). Prints times, the plan, the engine's peak and VmHWM, and both
// triangle counts (they must agree: a difference exits 1).
//
//   stream_bench [--slices 2048] [--budget-mib 128]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "bench_util.hpp"
#include "io/mesh_sink.hpp"
#include "io/volume_io.hpp"
#include "io/volume_stream.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/stream.hpp"
#include "tests/support/big_ball.hpp"

using namespace iso;

int main(int argc, char** argv) {
    int slices = 2048;
    std::size_t budget_mib = 128;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--slices") == 0 && i + 1 < argc) {
            slices = std::atoi(argv[++i]);
        } else if (std::strcmp(argv[i], "--budget-mib") == 0 && i + 1 < argc) {
            budget_mib = std::size_t(std::atoll(argv[++i]));
        } else {
            std::fprintf(stderr,
                         "stream_bench: unknown argument '%s' (usage: stream_bench [--slices N] [--budget-mib M])\n",
                         argv[i]);
            return 2;
        }
    }
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("isoscope-stream-bench-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string in = test::write_big_ball(dir, slices, 0.25, true);
    bench::reset_peak_rss();
    const double base_mib = double(bench::current_rss()) / 1048576.0;
    double t0 = bench::now_s();
    auto src = open_volume_stream(in);
    StreamOptions so;
    so.isos = {500.0};
    so.memory_budget = budget_mib << 20;
    auto sink = make_mesh_sink({(dir / "big.ply").string()});
    const auto st = stream_extract(*src, so, *sink);
    const double ts = bench::now_s() - t0;
    const double hwm_stream = double(bench::peak_rss()) / 1048576.0;
    const auto ms = sink->stats()[0];
    t0 = bench::now_s();
    const Mesh ref = extract_isosurface(load_volume(in), 500.0);
    const double tm = bench::now_s() - t0;
    const double hwm_mem = double(bench::peak_rss()) / 1048576.0;
    std::printf(
        "%.2f GiB int16, iso 500: streamed (budget %zu MiB) %.1f s [index+read %.1f s, extract %.1f s, write %.1f s], "
        "%zu slabs of %d layers (chunk %d), engine peak %.1f MiB, VmHWM %.1f MiB (base %.1f MiB); "
        "in memory (load + extract, no write) %.1f s, VmHWM %.1f MiB; %zu triangles (in memory %zu)\n",
        double(slices) / 2048.0, budget_mib, ts, st.read_seconds, st.extract_seconds, st.write_seconds, st.plan.slabs,
        st.plan.layers_per_slab, st.plan.chunk_size, double(st.peak_bytes) / 1048576.0, hwm_stream, base_mib, tm,
        hwm_mem, std::size_t(ms.triangles), ref.triangles.size());
    std::error_code ec;
    fs::remove_all(dir, ec);
    if (std::size_t(ms.triangles) != ref.triangles.size()) {
        std::fprintf(stderr, "stream_bench: the streamed and in-memory triangle counts differ\n");
        return 1;
    }
    return 0;
}
