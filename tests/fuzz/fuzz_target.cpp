// One libFuzzer target per parser: this file is compiled once per format
// with FUZZ_EXT (the file extension the loader dispatches on) and one of
// FUZZ_VOLUME, FUZZ_MESH or FUZZ_MARKUPS (the loader). The input bytes become
// a file that the real loader reads. iso::Error is the expected outcome for
// bad input; a crash, a sanitizer report, a hang or any other exception is a
// finding. Markups also check that whatever was read is written and read back
// the same (the writer and the reader agree on what a valid file is).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "io/error.hpp"
#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "io/volume_io.hpp"

// Production builds get std::bad_alloc from `new` for impossible sizes (the
// loaders turn it into iso::Error); under ASan such a request aborts instead.
// These replacements restore the production behaviour above 1 GiB so that a
// library allocating what a corrupt header claims is tested as users meet it.
namespace {
constexpr std::size_t kMaxAllocation = std::size_t(1) << 30;
void* allocate(std::size_t n) {
    if (n > kMaxAllocation) throw std::bad_alloc();
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
} // namespace
void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {
// Where the input is written for the loader. The deterministic smoke names
// the folder (ISOSCOPE_FUZZ_INPUT_DIR, the same on every machine): a path
// the loaders compare may reach libFuzzer's table of compared bytes, and a
// random one would make two runs of the same commit mutate differently.
// Otherwise a fresh folder of its own (parallel workers share nothing).
std::string input_path() {
    static const std::string path = [] {
        if (const char* dir = std::getenv("ISOSCOPE_FUZZ_INPUT_DIR"); dir && *dir) {
            std::filesystem::create_directories(dir);
            return std::string(dir) + "/input" FUZZ_EXT;
        }
        char tmpl[] = "/tmp/isoscope-fuzz-XXXXXX";
        const char* dir = ::mkdtemp(tmpl);
        return std::string(dir ? dir : "/tmp") + "/input" FUZZ_EXT;
    }();
    return path;
}

#if defined(FUZZ_MARKUPS)
[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "markups round trip: %s\n", what.c_str());
    std::abort();
}

// A file the reader accepted is written (curves excepted: read only) and
// read back with the same markups, points and positions.
void round_trip(const iso::MarkupsFile& f) {
    for (const auto& m : f.markups) {
        (void)iso::computed_measurement(m);
        if (m.type == iso::MarkupType::Curve || m.type == iso::MarkupType::ClosedCurve) return;
    }
    const std::string out = input_path() + ".out.mrk.json";
    iso::MarkupsFile g;
    try {
        iso::save_markups(f, out);
        g = iso::load_markups(out);
    } catch (const iso::Error& e) {
        finding(std::string("a file that was read could not be written and read back: ") + e.what());
    }
    if (g.markups.size() != f.markups.size()) finding("markup count changed");
    for (std::size_t i = 0; i < f.markups.size(); ++i) {
        const auto &a = f.markups[i], &b = g.markups[i];
        if (a.type != b.type || a.name != b.name || a.points.size() != b.points.size()) finding("markup changed");
        for (std::size_t k = 0; k < a.points.size(); ++k)
            if (a.points[k].status != b.points[k].status || a.points[k].label != b.points[k].label ||
                (a.points[k].status == iso::PositionStatus::Defined && a.points[k].position != b.points[k].position))
                finding("control point changed");
    }
}
#endif
} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    // A header may legitimately announce a large volume; keep the fuzzer's
    // allocations well under its RSS limit (the check itself is what we test).
    ::setenv("ISOSCOPE_MAX_VOLUME_BYTES", "268435456", 0);
    // The VDB and VTP readers' child processes must give up well inside -timeout.
    ::setenv("ISOSCOPE_VDB_READ_TIMEOUT", "2", 0);
    ::setenv("ISOSCOPE_VTP_READ_TIMEOUT", "2", 0);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path = input_path();
    {
        std::ofstream f(path, std::ios::binary | std::ios::trunc);
        f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    try {
#if defined(FUZZ_MESH)
        const iso::Mesh m = iso::load_mesh(path);
        (void)iso::mesh_stats(m);
#elif defined(FUZZ_MARKUPS)
        round_trip(iso::load_markups(path));
#else
        const iso::Volume v = iso::load_volume(path);
        (void)v.value_range();
#endif
    } catch (const iso::Error&) {
        // bad input, reported as it should be
    }
    return 0;
}
