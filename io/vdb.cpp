// OpenVDB (.vdb): the first float grid, kept sparse. VDB has no patient
// convention: its world space is taken as LPS millimetres (what we write).
// Our index (0,0,0) is the corner of the grid's active bounding box.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

#include "io/atomic_file.hpp"

#include "io/sparse.hpp"
#include "io/volume_io.hpp"

namespace iso {

namespace {
void init_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}
// OpenVDB's reader is not hardened against malformed files (the fuzzer
// found heap overflows inside it), and no other library reads VDB. So an
// untrusted file is first read in a child process, which writes the grids
// back out through OpenVDB's writer; the parent then reads that copy. A
// crash or a hang in the child becomes an error instead of taking the
// program down. Returns the path of the copy (the caller removes it).
std::string sanitized_copy(const std::string& path) {
    namespace fs = std::filesystem;
    const std::string copy = (fs::temp_directory_path() / ("isoscope-vdb-" + std::to_string(::getpid()) + "-" +
                                                           fs::path(temp_path_for(path)).filename().string()))
                                 .string();
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) throw Error(path, "cannot start the VDB reader process");
    if (pid == 0) {
        // Default dispositions: a handler inherited from the host program
        // (a crash reporter, a fuzzer's timer) must not keep the child alive.
        for (int sig : {SIGALRM, SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
        // A malformed file must not hang the reader forever.
        unsigned limit = 120;
        if (const char* e = std::getenv("ISOSCOPE_VDB_READ_TIMEOUT")) limit = unsigned(std::max(1, std::atoi(e)));
        ::alarm(limit);
        int rc = 1;
        try {
            openvdb::io::File in(path);
            in.open(false);
            openvdb::GridPtrVec grids;
            for (auto it = in.beginName(); it != in.endName(); ++it) grids.push_back(in.readGrid(it.gridName()));
            in.close();
            openvdb::io::File out(copy);
            out.write(grids);
            out.close();
            rc = 0;
        } catch (const std::exception& e) {
            std::FILE* f = std::fopen((copy + ".error").c_str(), "w");
            if (f) {
                std::fputs(e.what(), f);
                std::fclose(f);
            }
            rc = 2;
        }
        ::_exit(rc);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    std::error_code ec;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return copy;
    fs::remove(copy, ec);
    std::string why;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 2) {
        std::ifstream f(copy + ".error");
        std::getline(f, why);
        fs::remove(copy + ".error", ec);
        throw Error(path, "not a readable OpenVDB file: " + why);
    }
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM) throw Error(path, "OpenVDB did not finish reading the file in time (corrupt?)");
    throw Error(path, "OpenVDB's reader failed on this file (corrupt or truncated?)");
}

} // namespace

Volume read_vdb(const std::string& path) {
    init_openvdb();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "no such file");
    if (std::filesystem::file_size(path, ec) == 0) throw Error(path, "file is empty");
    openvdb::FloatGrid::Ptr grid;
    std::string others;
    const std::string copy = sanitized_copy(path);
    struct Remove {
        std::string p;
        ~Remove() { std::error_code e; std::filesystem::remove(p, e); }
    } remove_copy{copy};
    try {
        openvdb::io::File file(copy);
        file.open(/*delayLoad=*/false);
        for (auto it = file.beginName(); it != file.endName(); ++it) {
            auto meta = file.readGridMetadata(it.gridName());
            if (!grid && meta->valueType() == "float") {
                grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(it.gridName()));
            } else {
                others += (others.empty() ? "" : ", ") + it.gridName() + " (" + meta->valueType() + ")";
            }
        }
        file.close();
    } catch (const openvdb::Exception& e) {
        throw Error(path, std::string("not a readable OpenVDB file: ") + e.what());
    } catch (const std::exception& e) {
        throw Error(path, std::string("cannot read: ") + e.what());
    }
    if (!grid) throw Error(path, "no float grid in the file" + (others.empty() ? std::string() : " (grids: " + others + ")"));
    const auto& xf = grid->transform();
    if (!xf.isLinear()) throw Error(path, "grid '" + grid->getName() + "' has a non-linear transform (frustum): unsupported");
    const openvdb::Mat4d vm = xf.baseMap()->getAffineMap()->getMat4();
    // OpenVDB multiplies row vectors (p' = p * M): our column-vector matrix is its transpose.
    glm::dmat4 index_to_world(1.0);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) index_to_world[c][r] = vm(c, r);
    openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
    std::array<std::int64_t, 3> dims{1, 1, 1};
    openvdb::Coord offset(0);
    if (!bbox.empty()) {
        offset = bbox.min();
        const auto d = bbox.dim();
        dims = {d.x(), d.y(), d.z()};
    }
    const glm::dmat4 affine = index_to_world * glm::dmat4(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0), glm::dvec4(0, 0, 1, 0),
                                                           glm::dvec4(offset.x(), offset.y(), offset.z(), 1));
    check_affine(path, affine);
    auto sg = std::make_shared<SparseGrid>();
    sg->grid = grid;
    sg->offset = offset;
    Volume v = Volume::sparse(sg, dims, affine);
    v.meta.source = path;
    v.meta.format = "OpenVDB";
    v.meta.series_description = grid->getName();
    if (!others.empty()) v.meta.warnings.push_back("only the first float grid was loaded; also in the file: " + others);
    warn_non_finite(v);
    return v;
}

void write_vdb(const Volume& v, const std::string& path) {
    init_openvdb();
    openvdb::FloatGrid::Ptr grid;
    openvdb::Coord offset(0);
    if (v.is_sparse()) {
        grid = v.sparse_grid()->grid->deepCopy();
        offset = v.sparse_grid()->offset;
    } else {
        // Samples equal to the most common background (the minimum: air in CT)
        // stay inactive.
        const auto range = v.value_range();
        grid = openvdb::FloatGrid::create(float(range.min));
        auto acc = grid->getAccessor();
        for (std::int64_t k = 0; k < v.dims[2]; ++k)
            for (std::int64_t j = 0; j < v.dims[1]; ++j)
                for (std::int64_t i = 0; i < v.dims[0]; ++i) {
                    const float x = float(v.value(i, j, k));
                    if (x != float(range.min)) acc.setValue(openvdb::Coord(int(i), int(j), int(k)), x);
                }
    }
    // Index space of the grid: ours shifted by `offset`.
    const glm::dmat4 m = v.index_to_lps * glm::dmat4(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0), glm::dvec4(0, 0, 1, 0),
                                                     glm::dvec4(-offset.x(), -offset.y(), -offset.z(), 1));
    openvdb::Mat4d vm;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) vm(c, r) = m[c][r];
    grid->setTransform(openvdb::math::Transform::createLinearTransform(vm));
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    if (grid->getName().empty()) grid->setName("density");
    try {
        openvdb::io::File file(path);
        file.write({grid});
        file.close();
    } catch (const std::exception& e) {
        throw Error(path, std::string("cannot write: ") + e.what());
    }
}

} // namespace iso
