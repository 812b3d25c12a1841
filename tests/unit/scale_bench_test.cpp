// The scaling benchmark's own machinery (tests/bench/scale_volume.hpp and
// proc_monitor.hpp): the generated NIfTI volume read back by our reader and by
// VTK's, its reuse and cancellation, its memory, and the process-tree memory
// monitor against processes of known size.
#include <gtest/gtest.h>

#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNIFTIImageReader.h>
#include <vtkNew.h>
#include <vtkPointData.h>

#include "io/volume_io.hpp"
#include "tests/bench/bench_util.hpp"
#include "tests/bench/proc_monitor.hpp"
#include "tests/bench/scale_volume.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using namespace iso::bench;
using iso::test::read_file;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
    const fs::path d = fs::path(ISOSCOPE_BINARY_DIR) / "test_output" / "scale_bench" / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

constexpr std::uint64_t kMiB = 1 << 20;

} // namespace

// The file is what the header says (our reader: dims, int16, LPS affine with
// 0.1 mm spacing centred on 0) and what the description in scale_volume.hpp
// promises, checked from the spec, not from the generator's code: empty top
// and bottom slabs, air corners, soft tissue at the centre, bone, bright
// objects, and voxels on both sides of the bone threshold inside the body.
TEST(ScaleVolume, ReadBackByOurReaderMatchesTheDescription) {
    const fs::path dir = fresh_dir("content");
    ScaleVolumeParams p;
    p.dims = {160, 144, 128};
    const std::string path = (dir / "ct.nii").string();
    write_scale_volume(p, path);
    EXPECT_EQ(fs::file_size(path), 352u + p.voxels() * 2);
    const Volume v = load_volume(path);
    ASSERT_EQ(v.type, VoxelType::I16);
    EXPECT_EQ(v.dims, p.dims);
    const glm::dmat4 want = scale_volume_affine(p);
    // The affine travels as float32 (sform): 1e-5 mm is float rounding of ~8 mm offsets.
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(v.index_to_lps[c][r], want[c][r], 1e-5) << c << "," << r;
    EXPECT_NEAR(v.spacing().x, 0.1, 1e-7);
    const glm::dvec4 centre = v.index_to_lps * glm::dvec4(79.5, 71.5, 63.5, 1.0); // LPS of the volume's centre
    EXPECT_NEAR(glm::length(glm::dvec3(centre)), 0.0, 1e-5);

    auto s = v.as<std::int16_t>();
    auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return s[v.linear_index(i, j, k)]; };
    // Empty slabs: the body's z semi-axis is 0.40 of the extent, so slices with
    // centres below 0.1 or above 0.9 of the height are air only (-1000, noise sigma 5).
    const std::int64_t nz = p.dims[2];
    int max_in_slabs = -32768, hist_bone = 0, hist_bright = 0, above = 0, below_in_body = 0;
    for (std::int64_t k = 0; k < nz; ++k) {
        const double w = (double(k) + 0.5) / double(nz);
        for (std::int64_t j = 0; j < p.dims[1]; ++j)
            for (std::int64_t i = 0; i < p.dims[0]; ++i) {
                const int x = at(i, j, k);
                if (w < 0.099 || w > 0.901) max_in_slabs = std::max(max_in_slabs, x);
                hist_bone += x > 1000 && x < 1400;
                hist_bright += x > 2000;
                above += x > 300.5;
                below_in_body += x > -500 && x < 300.5;
            }
    }
    EXPECT_LT(max_in_slabs, -900); // 20 sigma of the air noise
    EXPECT_LT(at(0, 0, nz / 2), -900);
    EXPECT_LT(at(p.dims[0] - 1, p.dims[1] - 1, nz / 2), -900);
    EXPECT_GT(at(80, 72, 64), -60); // soft tissue 40 +- 6 sigma (15)
    EXPECT_LT(at(80, 72, 64), 140);
    EXPECT_GT(hist_bone, 10000); // a cortical shell 0.06 thick around a body of ~0.28 of the box
    EXPECT_GT(hist_bright, 0);   // at least one bright object or vessel... bright objects are 2500
    EXPECT_GT(above, 50000);     // the bone threshold has voxels on both sides: real surface
    EXPECT_GT(below_in_body, 200000);
    EXPECT_EQ(v.meta.format, "NIfTI");
}

// An independent reader (VTK's vtkNIFTIImageReader) sees the same samples in
// the same order (our affine has qfac = +1, so VTK does not flip slices).
TEST(ScaleVolume, VtkReaderSeesTheSameSamples) {
    const fs::path dir = fresh_dir("vtk");
    ScaleVolumeParams p;
    p.dims = {50, 40, 30};
    const std::string path = (dir / "ct.nii").string();
    write_scale_volume(p, path);
    const Volume ours = load_volume(path);
    vtkNew<vtkNIFTIImageReader> r;
    r->SetFileName(path.c_str());
    r->Update();
    int d[3];
    r->GetOutput()->GetDimensions(d);
    ASSERT_EQ(d[0], 50);
    ASSERT_EQ(d[1], 40);
    ASSERT_EQ(d[2], 30);
    double sp[3];
    r->GetOutput()->GetSpacing(sp);
    EXPECT_NEAR(sp[0], 0.1, 1e-7);
    auto* arr = r->GetOutput()->GetPointData()->GetScalars();
    ASSERT_EQ(arr->GetDataType(), VTK_SHORT);
    const auto* vals = static_cast<const std::int16_t*>(arr->GetVoidPointer(0));
    const auto s = ours.as<std::int16_t>();
    ASSERT_EQ(std::size_t(arr->GetNumberOfTuples()), s.size());
    EXPECT_TRUE(std::equal(s.begin(), s.end(), vals));
}

// Deterministic: the same parameters give the same bytes (the noise is a hash
// of the voxel index, not of the thread schedule); another seed differs.
TEST(ScaleVolume, DeterministicAndSeeded) {
    const fs::path dir = fresh_dir("determinism");
    ScaleVolumeParams p;
    p.dims = {64, 48, 40};
    const std::uint32_t crc_a = write_scale_volume(p, (dir / "a.nii").string());
    const std::uint32_t crc_b = write_scale_volume(p, (dir / "b.nii").string());
    EXPECT_EQ(crc_a, crc_b);
    EXPECT_EQ(read_file(dir / "a.nii"), read_file(dir / "b.nii"));
    const std::string data = read_file(dir / "a.nii").substr(352);
    EXPECT_EQ(crc_a, std::uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(data.data()), uInt(data.size()))));
    p.seed = 17;
    write_scale_volume(p, (dir / "c.nii").string());
    EXPECT_NE(read_file(dir / "a.nii"), read_file(dir / "c.nii"));
}

// Reuse through the sidecar; a changed header is regenerated; a file we did not
// write is never overwritten.
TEST(ScaleVolume, ReusedWhenTheSidecarMatches) {
    const fs::path dir = fresh_dir("reuse");
    ScaleVolumeParams p;
    p.dims = {40, 40, 40};
    bool reused = true;
    const std::string path = ensure_scale_volume(p, dir.string(), reused);
    EXPECT_FALSE(reused);
    EXPECT_EQ(fs::path(path).filename(), "ct40x40x40.nii");
    ASSERT_TRUE(fs::exists(path + ".json"));
    const auto t0 = fs::last_write_time(path);
    EXPECT_EQ(ensure_scale_volume(p, dir.string(), reused), path);
    EXPECT_TRUE(reused);
    EXPECT_EQ(fs::last_write_time(path), t0);

    // A different generator parameter is not the same file.
    p.trabecular_period = 12;
    ensure_scale_volume(p, dir.string(), reused);
    EXPECT_FALSE(reused);
    p.trabecular_period = ScaleVolumeParams{}.trabecular_period; // back to the default: regenerated again
    ensure_scale_volume(p, dir.string(), reused);
    EXPECT_FALSE(reused);

    // A damaged header (descrip field, byte 150) is noticed by the checksum.
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(150);
        f.put('#');
    }
    ensure_scale_volume(p, dir.string(), reused);
    EXPECT_FALSE(reused);
    const Volume v = load_volume(path); // regenerated and readable
    EXPECT_EQ(v.dims, p.dims);

    // Someone else's file at our name: refused by name, left untouched.
    ScaleVolumeParams q;
    q.dims = {30, 30, 30};
    const fs::path theirs = dir / "ct30x30x30.nii";
    std::ofstream(theirs) << "not ours";
    try {
        ensure_scale_volume(q, dir.string(), reused);
        FAIL() << "overwrote a file without a sidecar";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), theirs.string());
        EXPECT_NE(std::string(e.what()).find("not overwritten"), std::string::npos);
    }
    EXPECT_EQ(read_file(theirs), "not ours");
}

// Cancelled from the progress callback: Cancelled is thrown, nothing is left
// at the path, no temporary stays behind.
TEST(ScaleVolume, CancelLeavesNothing) {
    const fs::path dir = fresh_dir("cancel");
    ScaleVolumeParams p;
    p.dims = {64, 64, 64};
    int calls = 0;
    double last = -1;
    EXPECT_THROW(write_scale_volume(p, (dir / "ct.nii").string(),
                                    [&](double f, std::string_view) {
                                        EXPECT_GT(f, last);
                                        last = f;
                                        return ++calls < 5;
                                    }),
                 Cancelled);
    EXPECT_EQ(calls, 5);
    EXPECT_TRUE(fs::is_empty(dir));
}

// One slice buffer, never the volume: generating a 256^3 volume (32 MiB)
// raises this process's peak RSS by far less than the volume. Bound: 8 MiB
// (a 128 KiB slice, TBB's workers and their stacks, the C library's buffers);
// holding the volume would add 32 MiB. Pages in the page cache are not RSS.
TEST(ScaleVolume, MemoryIsOneSliceNotTheVolume) {
    const fs::path dir = fresh_dir("memory");
    ScaleVolumeParams p;
    p.dims = {256, 256, 256};
    write_scale_volume(p, (dir / "warm.nii").string(), {}); // first use of TBB's threads etc.
    fs::remove(dir / "warm.nii");
    const std::size_t base = current_rss();
    reset_peak_rss();
    write_scale_volume(p, (dir / "ct.nii").string());
    const std::size_t peak = peak_rss();
    EXPECT_LT(peak > base ? peak - base : 0, 8 * kMiB)
        << "base " << base / kMiB << " MiB, peak " << peak / kMiB << " MiB";
    EXPECT_EQ(fs::file_size(dir / "ct.nii"), 352u + p.voxels() * 2);
}

namespace {

// In a forked child: touch `mib` MiB of anonymous memory (mmap, not malloc:
// only async-signal-safe calls after fork in a threaded process).
void touch_mib(std::size_t mib) {
    void* m = ::mmap(nullptr, mib * kMiB, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) ::_exit(9);
    std::memset(m, 1, mib * kMiB);
}

// This process's resident bytes from /proc/self/statm with system calls only
// (safe after fork): a forked child starts with less than its parent's RSS
// (file pages are not copied, they fault in again), so each process reports
// its own starting point.
std::uint64_t statm_rss() {
    const int fd = ::open("/proc/self/statm", O_RDONLY);
    char buf[128];
    const ssize_t n = fd >= 0 ? ::read(fd, buf, sizeof buf - 1) : -1;
    if (fd >= 0) ::close(fd);
    if (n <= 0) return 0;
    buf[n] = 0;
    const char* p = buf;
    while (*p && *p != ' ') ++p; // skip "size"
    std::uint64_t pages = 0;
    for (++p; *p >= '0' && *p <= '9'; ++p) pages = pages * 10 + std::uint64_t(*p - '0');
    return pages * std::uint64_t(::sysconf(_SC_PAGESIZE));
}

} // namespace

// The monitor against a process tree of known sizes: a child that touches
// 64 MiB and a grandchild that touches 32 MiB (like mpirun and its ranks).
// Each process reports its RSS through a pipe before touching and after
// (what it touched, plus what the sanitizers map for it: AddressSanitizer's
// memset reads the range's shadow, an eighth of it, resident on some
// kernels); the monitor's peak must be the RSS after, within 4 MiB (page
// tables, the stack, libc pages touched after the report), and at least
// what was touched above the RSS before. Both hold their memory for 0.6 s,
// so the total at one poll is both peaks together, within 8 MiB. Reading
// VmPeak (virtual) or VmRSS at the end instead of VmHWM would fail these.
TEST(ProcMonitor, PeaksOfAChildAndAGrandchild) {
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::close(fds[0]);
        const pid_t g = ::fork(); // before touching: the grandchild does not inherit the 64 MiB
        if (g == 0) {
            const std::uint64_t rec[2] = {1, statm_rss()};
            if (::write(fds[1], rec, sizeof rec) != sizeof rec) ::_exit(8);
            touch_mib(32);
            const std::uint64_t after[2] = {3, statm_rss()};
            if (::write(fds[1], after, sizeof after) != sizeof after) ::_exit(8);
            ::usleep(600000);
            ::_exit(0);
        }
        const std::uint64_t rec[2] = {0, statm_rss()};
        if (::write(fds[1], rec, sizeof rec) != sizeof rec) ::_exit(8);
        touch_mib(64);
        const std::uint64_t after[2] = {2, statm_rss()};
        if (::write(fds[1], after, sizeof after) != sizeof after) ::_exit(8);
        ::usleep(600000);
        int st = 0;
        ::waitpid(g, &st, 0);
        ::_exit(WIFEXITED(st) && WEXITSTATUS(st) == 0 ? 0 : 5);
    }
    ::close(fds[1]);
    MeasuredRun r;
    monitor_tree(pid, r, 20, 30, nullptr);
    double start[2] = {-1, -1}, after[2] = {-1, -1}; // child, grandchild
    std::uint64_t rec[2];
    while (::read(fds[0], rec, sizeof rec) == sizeof rec)
        if (rec[0] < 2)
            start[rec[0]] = double(rec[1]) / kMiB;
        else if (rec[0] < 4)
            after[rec[0] - 2] = double(rec[1]) / kMiB;
    ::close(fds[0]);
    ASSERT_GT(start[0], 0);
    ASSERT_GT(start[1], 0);
    ASSERT_GT(after[0], 0);
    ASSERT_GT(after[1], 0);
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_GE(r.wall_s, 0.6);
    EXPECT_GT(r.polls, 10);
    ASSERT_EQ(r.procs.size(), 2u);
    EXPECT_EQ(r.procs[0].pid, pid);
    // Touched is resident: the RSS after is at least the RSS before plus it.
    EXPECT_GE(after[0], start[0] + 64 - 0.5);
    EXPECT_GE(after[1], start[1] + 32 - 0.5);
    EXPECT_NEAR(double(r.procs[0].hwm) / kMiB, after[0], 4) << "child: " << start[0] << " MiB before touching";
    EXPECT_NEAR(double(r.procs[1].hwm) / kMiB, after[1], 4) << "grandchild: " << start[1] << " MiB before touching";
    EXPECT_NEAR(double(r.child_maxrss) / kMiB, after[0], 4);
    EXPECT_NEAR(double(r.total_peak) / kMiB, after[0] + after[1], 8);
    EXPECT_EQ(r.sum_of_peaks, r.procs[0].hwm + r.procs[1].hwm);
}

// Exit codes, a program that does not exist, and a time limit that kills the
// whole process group (the shell and its sleeping child).
TEST(ProcMonitor, FailuresAreRecordedNotFatal) {
    const fs::path dir = fresh_dir("monitor");
    const std::string o = (dir / "out.txt").string(), e = (dir / "err.txt").string();
    auto r = run_measured({"/bin/sh", "-c", "echo 12 triangles; echo oops >&2; exit 3"}, o, e);
    EXPECT_TRUE(r.started);
    EXPECT_EQ(r.exit_code, 3);
    EXPECT_EQ(read_file(o), "12 triangles\n");
    EXPECT_EQ(read_file(e), "oops\n");

    r = run_measured({"/nonexistent/isoscope", "mesh"}, o, e);
    EXPECT_FALSE(r.started);
    EXPECT_NE(r.error.find("/nonexistent/isoscope"), std::string::npos) << r.error;

    const double t0 = now_s();
    r = run_measured({"/bin/sh", "-c", "sleep 30 & wait"}, o, e, 20, 0.5);
    EXPECT_TRUE(r.timed_out);
    EXPECT_EQ(r.exit_code, 128 + SIGTERM);
    EXPECT_LT(now_s() - t0, 10.0);
    EXPECT_GE(r.procs.size(), 2u); // the shell and its sleep were both seen
    // by their names after exec (a process first seen between fork and exec has the shell's name)
    EXPECT_TRUE(std::any_of(r.procs.begin(), r.procs.end(), [](const ProcPeak& p) { return p.comm == "sleep"; }));
}
