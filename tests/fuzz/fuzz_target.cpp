// One libFuzzer target per parser: this file is compiled once per format
// with FUZZ_EXT (the file extension the loader dispatches on) and FUZZ_MESH
// (1 for mesh formats). The input bytes become a file that the real loader
// reads. iso::Error is the expected outcome for bad input; a crash, a
// sanitizer report, a hang or any other exception is a finding.
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "io/error.hpp"
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
std::string input_path() {
    static const std::string path = [] {
        char tmpl[] = "/tmp/isoscope-fuzz-XXXXXX";
        const char* dir = ::mkdtemp(tmpl);
        return std::string(dir ? dir : "/tmp") + "/input" FUZZ_EXT;
    }();
    return path;
}
} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    // A header may legitimately announce a large volume; keep the fuzzer's
    // allocations well under its RSS limit (the check itself is what we test).
    ::setenv("ISOSCOPE_MAX_VOLUME_BYTES", "268435456", 0);
    // The VDB reader's child process must give up well inside -timeout.
    ::setenv("ISOSCOPE_VDB_READ_TIMEOUT", "2", 0);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path = input_path();
    {
        std::ofstream f(path, std::ios::binary | std::ios::trunc);
        f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    try {
#if FUZZ_MESH
        const iso::Mesh m = iso::load_mesh(path);
        (void)iso::mesh_stats(m);
#else
        const iso::Volume v = iso::load_volume(path);
        (void)v.value_range();
#endif
    } catch (const iso::Error&) {
        // bad input, reported as it should be
    }
    return 0;
}
