// OpenVDB (.vdb): the first float grid, kept sparse. VDB has no patient
// convention: its world space is taken as LPS millimetres (what we write).
// Our index (0,0,0) is the corner of the grid's active bounding box.
//
// OpenVDB's reader is not hardened against malformed files (the fuzzer found
// heap overflows inside it), and no other library reads VDB. So every read of
// a user's file runs in a child process (io/child_process.hpp), which hands
// the grid back through a pipe in OpenVDB's own stream format (written by
// OpenVDB's writer, so this process only parses what OpenVDB itself
// produced): a crash, a hang or an exception in the reader becomes an
// iso::Error naming the file instead of taking the program down.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <istream>
#include <mutex>
#include <ostream>
#include <sstream>

#include <ext/stdio_filebuf.h> // std::ostream over the pipe to the reading program (libstdc++)

#include <glm/gtc/matrix_transform.hpp>
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>

#include "io/child_process.hpp"
#include "io/process.hpp"
#include "io/sparse.hpp"
#include "io/volume_io.hpp"

namespace iso {

namespace {
void init_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

constexpr const char* kChildFlag = "--isoscope-openvdb-reader";
// Memory of a float leaf node per voxel it covers: 512 values, the value and
// child masks and node overhead, about 4.3 bytes (the slab planner's price
// and the reading child's memory cap).
constexpr double kLeafBytesPerVoxel = 4.3;
// A grid stream written without compression: it only crosses a pipe.
constexpr std::uint32_t kPipeCompression = openvdb::io::COMPRESS_NONE;

// ---- in the child ------------------------------------------------------------

// The first float grid's name; the others listed as "name (type), ...".
std::string first_float_grid(openvdb::io::File& in, std::string& others) {
    std::string found;
    for (auto it = in.beginName(); it != in.endName(); ++it) {
        const auto meta = in.readGridMetadata(it.gridName());
        if (found.empty() && meta->valueType() == "float")
            found = it.gridName();
        else
            others += (others.empty() ? "" : ", ") + it.gridName() + " (" + meta->valueType() + ")";
    }
    if (found.empty())
        throw std::runtime_error("no float grid in the file" +
                                 (others.empty() ? std::string() : " (grids: " + others + ")"));
    return found;
}

openvdb::FloatGrid::Ptr read_float_grid(openvdb::io::File& in, const std::string& name) {
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(in.readGrid(name));
    if (!grid) throw std::runtime_error("grid '" + name + "' is not a float grid");
    if (!grid->transform().isLinear())
        throw std::runtime_error("grid '" + name + "' has a non-linear transform (frustum): unsupported");
    return grid;
}

void send_grid(const openvdb::FloatGrid::Ptr& grid) {
    __gnu_cxx::stdio_filebuf<char> buf(kChildOutFd, std::ios::out, 1 << 16);
    std::ostream os(&buf);
    openvdb::io::Stream out(os);
    out.setCompression(kPipeCompression);
    out.write(openvdb::GridCPtrVec{grid});
    os.flush();
    if (!os) throw std::runtime_error("cannot hand the grid back to the reading program");
}

// argv: as run_child passes it, then the mode, the path and the mode's
// arguments. Returns the exit status: 0 done, 2 an error whose message went
// to kChildStatusFd.
int child_main(int argc, char** argv) {
    child_begin(argv);
    argv += kChildFirstArg - 2; // argv[2] the mode, argv[3] the path, as argc counts them below
    argc -= kChildFirstArg - 2;
    const std::string mode = argv[2], path = argv[3];
    try {
        openvdb::initialize();
        std::string others;
        if (mode == "whole" && argc == 4) {
            // The first float grid, read whole (no delayed loading: no mapping of the file).
            openvdb::io::File in(path);
            in.open(false);
            const std::string name = first_float_grid(in, others);
            const auto grid = read_float_grid(in, name);
            in.close();
            send_grid(grid);
            child_write(kChildStatusFd, "ok\n" + others);
            return 0;
        }
        if (mode == "header" && argc == 4) {
            // Topology only: with delayed loading the leaf values stay in the mapped file.
            openvdb::io::File in(path);
            in.open(true);
            const std::string name = first_float_grid(in, others);
            const auto grid = read_float_grid(in, name);
            const std::uint64_t topology = grid->memUsage();
            const std::uint64_t values =
                std::uint64_t(grid->tree().leafCount()) * openvdb::FloatTree::LeafNodeType::SIZE * sizeof(float);
            const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
            const openvdb::Mat4d m = grid->transform().baseMap()->getAffineMap()->getMat4();
            std::ostringstream o;
            o.precision(17);
            o << name << "\n" << others << "\n" << (box.empty() ? 0 : 1);
            for (int a = 0; a < 3; ++a) o << " " << box.min()[a];
            for (int a = 0; a < 3; ++a) o << " " << box.max()[a];
            o << "\n";
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) o << m(r, c) << (c == 3 ? "\n" : " ");
            o << topology << " " << topology + values << "\n";
            child_write(kChildOutFd, o.str());
            child_write(kChildStatusFd, "ok\n");
            return 0;
        }
        if (mode == "slab" && argc == 11) {
            // The topology with delayed loading, clipped to the index box: the
            // nodes outside are dropped unread, the leaves crossing the box's
            // faces are read and cleared outside it, then writing the grid
            // reads the values of the leaves left.
            openvdb::Coord lo, hi;
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::atoi(argv[5 + a]);
                hi[a] = std::atoi(argv[8 + a]);
            }
            openvdb::io::File in(path);
            in.open(true);
            const auto grid = read_float_grid(in, argv[4]);
            grid->clip(openvdb::CoordBBox(lo, hi));
            send_grid(grid);
            child_write(kChildStatusFd, "ok " + std::to_string(process_status_bytes("VmHWM:")) + "\n");
            return 0;
        }
        child_write(kChildStatusFd, "the OpenVDB reader process was started with unknown arguments");
        return 3;
    } catch (const openvdb::Exception& e) {
        child_write(kChildStatusFd, std::string("not a readable OpenVDB file: ") + e.what());
        return 2;
    } catch (const std::exception& e) {
        child_write(kChildStatusFd, e.what());
        return 2;
    }
}

// Run before main() in every program that links this file; only a process
// started by run_reader() (first argument kChildFlag) is taken over. glibc
// passes argc and argv to ELF constructors.
__attribute__((constructor)) void child_entry(int argc, char** argv, char**) {
    if (is_child(argc, argv, kChildFlag)) {
        // No exit handlers, no static destructors of a program that never started.
        ::_exit(child_main(argc, argv));
    }
}

// ---- in the reading program ------------------------------------------------------

// Runs the child reader (mode first, then the path and the mode's
// arguments), allowed to allocate `cap` bytes; see run_child.
std::string run_reader(const std::string& path, std::vector<std::string> args, std::size_t cap,
                       const std::function<void(std::istream&)>& consume) {
    ChildJob job;
    job.flag = kChildFlag;
    job.path = path;
    job.args = std::move(args);
    job.memory_cap = cap;
    job.reader = "OpenVDB's reader";
    job.memory_env = "ISOSCOPE_VDB_READ_MEMORY";
    job.timeout_env = "ISOSCOPE_VDB_READ_TIMEOUT";
    return run_child(job, consume);
}

openvdb::FloatGrid::Ptr receive_grid(std::istream& is) {
    // No delayed loading: it would copy the stream into a temporary file.
    openvdb::io::Stream in(is, /*delayLoad=*/false);
    const auto grids = in.getGrids();
    if (!grids || grids->size() != 1) throw std::runtime_error("expected one grid");
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>((*grids)[0]);
    if (!grid) throw std::runtime_error("not a float grid");
    return grid;
}

// OpenVDB multiplies row vectors (p' = p * M): our column-vector matrix is
// its transpose. Index (0,0,0) moved to the grid index `offset`.
glm::dmat4 to_lps(const openvdb::Mat4d& vm, const std::array<std::int64_t, 3>& offset) {
    glm::dmat4 index_to_world(1.0);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) index_to_world[c][r] = vm(c, r);
    return glm::translate(index_to_world, glm::dvec3(double(offset[0]), double(offset[1]), double(offset[2])));
}

void check_file(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "no such file");
    if (std::filesystem::file_size(path, ec) == 0) throw Error(path, "file is empty");
}

} // namespace

Volume read_vdb(const std::string& path) {
    init_openvdb();
    check_file(path);
    openvdb::FloatGrid::Ptr grid;
    const std::string others = run_reader(path, {"whole", path}, default_child_memory_cap("ISOSCOPE_VDB_READ_MEMORY"),
                                          [&](std::istream& is) { grid = receive_grid(is); });
    const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
    std::array<std::int64_t, 3> dims{1, 1, 1}, offset{0, 0, 0};
    if (!bbox.empty()) {
        const auto d = bbox.dim();
        dims = {d.x(), d.y(), d.z()};
        offset = {bbox.min().x(), bbox.min().y(), bbox.min().z()};
    }
    const glm::dmat4 affine = to_lps(grid->transform().baseMap()->getAffineMap()->getMat4(), offset);
    check_affine(path, affine);
    auto sg = std::make_shared<SparseGrid>();
    sg->grid = grid;
    sg->offset = openvdb::Coord(int(offset[0]), int(offset[1]), int(offset[2]));
    Volume v = Volume::sparse(sg, dims, affine);
    v.meta.source = path;
    v.meta.format = "OpenVDB";
    v.meta.series_description = grid->getName();
    if (!others.empty()) v.meta.warnings.push_back("only the first float grid was loaded; also in the file: " + others);
    warn_non_finite(v);
    return v;
}

VdbHeader read_vdb_header(const std::string& path) {
    init_openvdb();
    check_file(path);
    std::string text;
    run_reader(path, {"header", path}, default_child_memory_cap("ISOSCOPE_VDB_READ_MEMORY"),
               [&](std::istream& is) { text.assign(std::istreambuf_iterator<char>(is), {}); });
    VdbHeader h;
    std::istringstream in(text);
    std::string others;
    int nonempty = 0;
    std::int64_t lo[3], hi[3];
    openvdb::Mat4d vm;
    std::getline(in, h.grid);
    std::getline(in, others);
    in >> nonempty >> lo[0] >> lo[1] >> lo[2] >> hi[0] >> hi[1] >> hi[2];
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) in >> vm(r, c);
    in >> h.topology_bytes >> h.grid_bytes;
    if (!in) throw Error(path, "the VDB reader process gave no grid description");
    VolumeHeader& vh = h.header;
    vh.dims = {1, 1, 1};
    if (nonempty) {
        h.offset = {lo[0], lo[1], lo[2]};
        vh.dims = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
    }
    vh.path = vh.data_file = path;
    vh.format = VolumeFormat::Vdb;
    vh.stored = vh.type = VoxelType::F32;
    vh.encoding = DataEncoding::Other;
    vh.index_to_lps = to_lps(vm, h.offset);
    check_affine(path, vh.index_to_lps);
    // A slab costs its leaves twice (in the reading child, and sparse here):
    // kLeafBytesPerVoxel each, over the
    // leaves' reach beyond the slab: 8 more voxels along x and y on each side
    // and 18 more slices (the box's border and the leaves around it).
    const double reach = double(vh.dims[0] + 16) * double(vh.dims[1] + 16) / (double(vh.dims[0]) * double(vh.dims[1]));
    vh.reader_bytes_per_voxel = 2 * kLeafBytesPerVoxel * reach - double(voxel_size(vh.type));
    vh.reader_extra_slices = 18;
    vh.meta.source = path;
    vh.meta.format = "OpenVDB";
    vh.meta.series_description = h.grid;
    if (!others.empty()) vh.meta.warnings.push_back("only the first float grid is read; also in the file: " + others);
    return h;
}

Volume read_vdb_slab(const VdbHeader& h, std::int64_t k0, std::int64_t k1, std::size_t* child_peak) {
    const VolumeHeader& vh = h.header;
    if (k0 < 0 || k1 < k0 || k1 >= vh.dims[2])
        throw Error(vh.path, "slab [" + std::to_string(k0) + ", " + std::to_string(k1) + "] is outside the volume's " +
                                 std::to_string(vh.dims[2]) + " slices");
    init_openvdb();
    // The slab's index box and a one-voxel border (as much of the grid as a
    // window of the whole grid would let the extraction see around it).
    const std::int64_t lo[3] = {h.offset[0] - 1, h.offset[1] - 1, h.offset[2] + k0 - 1};
    const std::int64_t hi[3] = {h.offset[0] + vh.dims[0], h.offset[1] + vh.dims[1], h.offset[2] + k1 + 1};
    std::vector<std::string> args{"slab", vh.path, h.grid};
    for (std::int64_t c : lo) args.push_back(std::to_string(c));
    for (std::int64_t c : hi) args.push_back(std::to_string(c));
    openvdb::FloatGrid::Ptr grid;
    // The child holds the topology (twice, for a moment, while clipping) and
    // the leaves meeting the box (leaves are 8^3: up to 7 voxels beyond each
    // face; kLeafBytesPerVoxel), once more while it writes them out.
    const double leaves =
        double(hi[0] - lo[0] + 16) * double(hi[1] - lo[1] + 16) * double(hi[2] - lo[2] + 16) * kLeafBytesPerVoxel;
    const std::size_t cap = std::size_t(2 * double(h.topology_bytes) + 2 * leaves) + (std::size_t(256) << 20);
    const std::string status = run_reader(vh.path, args, cap, [&](std::istream& is) { grid = receive_grid(is); });
    if (child_peak) *child_peak = std::size_t(std::strtoull(status.c_str(), nullptr, 10));
    auto sg = std::make_shared<SparseGrid>();
    sg->grid = grid;
    sg->offset = openvdb::Coord(int(h.offset[0]), int(h.offset[1]), int(h.offset[2] + k0));
    Volume v = Volume::sparse(std::move(sg), {vh.dims[0], vh.dims[1], k1 - k0 + 1},
                              glm::translate(vh.index_to_lps, glm::dvec3(0.0, 0.0, double(k0))));
    v.meta = vh.meta;
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
    const glm::dmat4 m =
        v.index_to_lps * glm::dmat4(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0), glm::dvec4(0, 0, 1, 0),
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
