// Every input that once crashed, aborted or exhausted a reader
// (tests/fuzz/regressions/TARGET/) and every fuzz seed
// (tests/fuzz/corpus/TARGET/) is read again by the real loader, as the fuzz
// target reads it, in the release and sanitizer builds alike: it must load or
// give an iso::Error, nothing else. (The fuzz smoke replays them too, in its
// instrumented build; this is the same check on every test run.)
#include <filesystem>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "io/error.hpp"
#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "io/volume_io.hpp"
#include "tests/support/test_util.hpp"

using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

enum class Kind { Volume, Mesh, Markups };

struct Target {
    const char* ext;
    Kind kind;
};

// As tests/fuzz/CMakeLists.txt builds the fuzz targets.
const std::map<std::string, Target> kTargets = {
    {"nrrd", {".nrrd", Kind::Volume}},
    {"nifti", {".nii", Kind::Volume}},
    {"metaimage", {".mha", Kind::Volume}},
    {"vti", {".vti", Kind::Volume}},
    {"vdb", {".vdb", Kind::Volume}},
    {"dicom", {".dcm", Kind::Volume}},
    {"stl", {".stl", Kind::Mesh}},
    {"ply", {".ply", Kind::Mesh}},
    {"obj", {".obj", Kind::Mesh}},
    {"vtp", {".vtp", Kind::Mesh}},
    {"markups", {".mrk.json", Kind::Markups}},
};

// Reads `file` as the fuzz target `target` does; returns "ok" or the error.
std::string read_as(const std::string& target, const fs::path& file, const TempDir& tmp) {
    const Target& t = kTargets.at(target);
    const std::string path = tmp / (std::string("input") + t.ext);
    fs::copy_file(file, path, fs::copy_options::overwrite_existing);
    try {
        switch (t.kind) {
        case Kind::Volume: (void)iso::load_volume(path).value_range(); break;
        case Kind::Mesh: (void)iso::mesh_stats(iso::load_mesh(path)); break;
        case Kind::Markups: (void)iso::load_markups(path); break;
        }
    } catch (const iso::Error& e) {
        return e.reason();
    }
    return "ok";
}

// Replays every file under tests/fuzz/<folder>/TARGET/; returns how many.
int replay(const std::string& folder) {
    // As the fuzz targets set them: a header may claim a huge volume (the
    // reader refuses it instead of allocating), and the VDB reader's child
    // gives up on a hanging file after 2 s, not 120.
    ::setenv("ISOSCOPE_MAX_VOLUME_BYTES", "268435456", 0);
    ::setenv("ISOSCOPE_VDB_READ_TIMEOUT", "2", 0);
    ::setenv("ISOSCOPE_VTP_READ_TIMEOUT", "2", 0);
    const fs::path root = fs::path(ISOSCOPE_SOURCE_DIR) / "tests/fuzz" / folder;
    TempDir tmp;
    int n = 0;
    for (const auto& dir : fs::directory_iterator(root)) {
        if (!dir.is_directory()) continue; // a README
        const std::string target = dir.path().filename().string();
        if (!kTargets.count(target)) {
            ADD_FAILURE() << dir.path() << " is not a fuzz target's folder";
            continue;
        }
        for (const auto& f : fs::directory_iterator(dir.path())) {
            // What exploration reached is the fuzz smoke's to replay (hundreds of files).
            if (f.path().filename().string().rfind("explored-", 0) == 0) continue;
            SCOPED_TRACE(f.path().string());
            const std::string outcome = read_as(target, f.path(), tmp);
            EXPECT_FALSE(outcome.empty());
            ++n;
        }
    }
    return n;
}

} // namespace

TEST(FuzzRegressions, EveryInputThatOnceCrashedIsReadOrRefused) { EXPECT_GE(replay("regressions"), 25); }

TEST(FuzzRegressions, EverySeedIsReadOrRefused) { EXPECT_GE(replay("corpus"), 9); }

TEST(FuzzRegressions, TheDicomFileThatAbortedIsRefusedWithItsOffset) {
    TempDir tmp;
    const fs::path f = fs::path(ISOSCOPE_SOURCE_DIR) /
                       "tests/fuzz/regressions/dicom/crash-dicom-crash-314510707ba2abecdd6ccdea964749af198ea78c";
    const std::string outcome = read_as("dicom", f, tmp);
    EXPECT_EQ(outcome.rfind("malformed DICOM at byte ", 0), 0u) << outcome;
}
