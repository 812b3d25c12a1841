// NIfTI-1 (.nii, .nii.gz, and .hdr/.img pairs) through nifti_clib, the
// reference implementation. Orientation follows the standard: the sform
// when sform_code > 0, else the qform when qform_code > 0, else pixdim
// scaling ("method 1", orientation unknown). NIfTI world space is RAS, so
// the matrix is turned to LPS with diag(-1, -1, 1, 1).
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <type_traits>

#include <fcntl.h>
#include <nifti1_io.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>
#include <zlib.h>

#include "io/volume_io.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

struct NimDeleter {
    void operator()(nifti_image* n) const { nifti_image_free(n); }
};
using NimPtr = std::unique_ptr<nifti_image, NimDeleter>;

VoxelType nifti_voxel_type(const std::string& path, int dt) {
    switch (dt) {
    case DT_INT8: return VoxelType::I8;
    case DT_UINT8: return VoxelType::U8;
    case DT_INT16: return VoxelType::I16;
    case DT_UINT16: return VoxelType::U16;
    case DT_INT32: return VoxelType::I32;
    case DT_UINT32: return VoxelType::U32;
    case DT_FLOAT32: return VoxelType::F32;
    case DT_FLOAT64: return VoxelType::F64;
    default: break;
    }
    const char* name = nifti_datatype_string(dt);
    throw Error(path, std::string("unsupported voxel type ") + (name ? name : "?") + " (datatype " +
                          std::to_string(dt) +
                          "); supported: int8, uint8, int16, uint16, int32, uint32, float32, float64");
}

int nifti_type(VoxelType t) {
    switch (t) {
    case VoxelType::I8: return DT_INT8;
    case VoxelType::U8: return DT_UINT8;
    case VoxelType::I16: return DT_INT16;
    case VoxelType::U16: return DT_UINT16;
    case VoxelType::I32: return DT_INT32;
    case VoxelType::U32: return DT_UINT32;
    case VoxelType::F32: return DT_FLOAT32;
    case VoxelType::F64: return DT_FLOAT64;
    }
    return DT_UNKNOWN;
}

glm::dmat4 from_mat44(const mat44& a) {
    glm::dmat4 m(1.0);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m[c][r] = a.m[r][c];
    return m;
}

mat44 to_mat44(const glm::dmat4& m) {
    mat44 a;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) a.m[r][c] = float(m[c][r]);
    return a;
}

bool ends_with(const std::string& s, const char* suffix) {
    const std::size_t n = std::strlen(suffix);
    return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

// Stored values times slope plus intercept: integral results that fit the
// stored type stay in it, anything else becomes float32.
template <class T> void rescale_into(const T* src, Volume& dst, double slope, double inter) {
    dispatch_voxel_type(dst.type, [&](auto tag) {
        using D = decltype(tag);
        auto out = dst.as<D>();
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = D(double(src[i]) * slope + inter);
        return 0;
    });
}

} // namespace

namespace {
NimPtr read_nim_header(const std::string& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path, "no such file");
    if (fs::file_size(path, ec) == 0) throw Error(path, "file is empty");
    nifti_set_debug_level(0);
    NimPtr nim(nifti_image_read(path.c_str(), 0)); // header only
    if (!nim) throw Error(path, "not a readable NIfTI-1 file (bad or truncated header)");
    return nim;
}

VolumeHeader header_of(const std::string& path, const nifti_image* nim) {
    if (nim->dim[0] < 2 || nim->dim[0] > 7)
        throw Error(path, "dim[0] = " + std::to_string(nim->dim[0]) + " is invalid");
    for (int a = 4; a <= nim->dim[0]; ++a)
        if (nim->dim[a] > 1)
            throw Error(path, "has " + std::to_string(nim->dim[a]) + " samples along dimension " + std::to_string(a) +
                                  " (time/vector data): only 3D scalar volumes are supported");
    VolumeHeader h;
    h.path = path;
    h.format = VolumeFormat::Nifti;
    h.stored = nifti_voxel_type(path, nim->datatype);
    h.dims = {nim->nx, nim->ny, std::max(nim->nz, 1)};
    checked_byte_size(path, h.dims, h.stored);

    glm::dmat4 ras(1.0);
    if (nim->sform_code > 0) {
        ras = from_mat44(nim->sto_xyz);
    } else if (nim->qform_code > 0) {
        ras = from_mat44(nim->qto_xyz);
    } else {
        for (int a = 0; a < 3; ++a) ras[a][a] = nim->pixdim[a + 1] > 0 ? nim->pixdim[a + 1] : 1.0;
        h.meta.warnings.push_back(
            "no sform or qform (both codes 0): orientation unknown, pixdim spacing on RAS axes assumed");
    }
    h.index_to_lps = ras_to_lps(ras);
    check_affine(path, h.index_to_lps);

    // Uncompressed: the data must be in the file before anything is read.
    const std::size_t bytes = std::size_t(h.stored_bytes());
    h.data_file = nim->iname ? nim->iname : path;
    h.data_offset = std::uint64_t(std::max(nim->iname_offset, 0));
    h.encoding = ends_with(h.data_file, ".gz") ? DataEncoding::Gzip : DataEncoding::Raw;
    h.swap_bytes = nim->byteorder != nifti_short_order();
    h.nonfinite_to_zero = h.stored == VoxelType::F32 || h.stored == VoxelType::F64;
    if (h.encoding == DataEncoding::Raw) {
        std::error_code ec;
        const auto isize = fs::file_size(h.data_file, ec);
        if (ec) throw Error(path, "data file '" + h.data_file + "' does not exist");
        if (isize < std::uintmax_t(nim->iname_offset) + bytes)
            throw Error(path, "truncated: the header announces " + std::to_string(bytes) +
                                  " bytes of data after offset " + std::to_string(nim->iname_offset) +
                                  ", the file has " + std::to_string(isize) + " bytes");
    }

    h.slope = nim->scl_slope;
    h.inter = nim->scl_inter;
    h.rescale = std::isfinite(h.slope) && h.slope != 0.0 && (h.slope != 1.0 || h.inter != 0.0);
    h.type = h.stored;
    if (h.rescale) {
        const bool integral_params = h.slope == std::floor(h.slope) && h.inter == std::floor(h.inter);
        const bool stored_int = h.stored != VoxelType::F32 && h.stored != VoxelType::F64;
        if (!(integral_params && stored_int)) {
            h.type = VoxelType::F32;
        } else {
            // Integral rescale of integers: read_nifti keeps the stored type
            // when the rescaled samples fit it, which only the samples tell.
            // From the header alone: the stored type if its whole range maps
            // into it, else int32 if that holds it, else float64; the values
            // (as doubles) are the same in every case.
            dispatch_voxel_type(h.stored, [&](auto tag) {
                using T = decltype(tag);
                const double a = double(std::numeric_limits<T>::lowest()) * h.slope + h.inter;
                const double b = double(std::numeric_limits<T>::max()) * h.slope + h.inter;
                const double lo = std::min(a, b), hi = std::max(a, b);
                auto fits = [&](double l, double u) { return lo >= l && hi <= u; };
                if (fits(double(std::numeric_limits<T>::lowest()), double(std::numeric_limits<T>::max())))
                    h.type = h.stored;
                else if (fits(double(std::numeric_limits<std::int32_t>::lowest()),
                              double(std::numeric_limits<std::int32_t>::max())))
                    h.type = VoxelType::I32;
                else
                    h.type = VoxelType::F64;
                return 0;
            });
        }
    }
    h.meta.source = path;
    h.meta.format = "NIfTI";
    if (nim->descrip[0]) h.meta.series_description = std::string(nim->descrip, strnlen(nim->descrip, 80));
    return h;
}

// Uncompressed samples in this host's byte order, not rescaled: read straight
// into the volume, in parallel pieces of 64 MiB (two threads fault in and
// copy twice as fast), instead of into nifti_clib's buffer and then copied:
// half the memory touched, which on a 2 GiB volume was seconds of page faults
// (issue 39). The same samples as nifti_image_load gives: it sets NaN and
// infinite float samples to 0 (nifti_read_buffer), and so does this.
Volume read_raw_samples(const VolumeHeader& h) {
    Volume v = Volume::dense(h.dims, h.stored, h.index_to_lps);
    const int fd = ::open(h.data_file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(h.path, "cannot open its data file '" + h.data_file + "': " + std::strerror(errno));
    std::byte* const data = v.bytes().data();
    const std::size_t n = v.bytes().size(), piece = std::size_t(64) << 20;
    std::atomic<int> error{0};
    tbb::parallel_for(std::size_t(0), (n + piece - 1) / piece, [&](std::size_t i) {
        const std::size_t b = i * piece, e = std::min(n, b + piece);
        for (std::size_t at = b; at < e && error.load() == 0;) {
            const ssize_t r = ::pread(fd, data + at, e - at, off_t(h.data_offset + at));
            if (r < 0 && errno == EINTR) continue;
            if (r <= 0) error = r < 0 ? errno : -1; // -1: the file ended early
            at += r > 0 ? std::size_t(r) : 0;
        }
    });
    ::close(fd);
    if (!error)
        dispatch_voxel_type(h.stored, [&](auto tag) {
            using T = decltype(tag);
            if constexpr (std::is_floating_point_v<T>) {
                const auto s = v.as<T>();
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s.size(), 1 << 16), [&](const auto& r) {
                    for (std::size_t i = r.begin(); i != r.end(); ++i)
                        if (!std::isfinite(s[i])) s[i] = T(0);
                });
            }
            return 0;
        });
    if (error)
        throw Error(h.path, error < 0 ? std::string("truncated: the data ends before ") + std::to_string(n) + " bytes"
                                      : std::string("cannot read the data: ") + std::strerror(error.load()));
    return v;
}
} // namespace

VolumeHeader read_nifti_header(const std::string& path) {
    NimPtr nim = read_nim_header(path);
    return header_of(path, nim.get());
}

Volume read_nifti(const std::string& path) {
    NimPtr nim = read_nim_header(path);
    const VolumeHeader h = header_of(path, nim.get());
    const auto dims = h.dims;
    const VoxelType stored = h.stored;
    const std::size_t bytes = std::size_t(h.stored_bytes());
    if (h.encoding == DataEncoding::Raw && !h.swap_bytes && !h.rescale) {
        Volume v = read_raw_samples(h);
        v.meta = h.meta;
        warn_non_finite(v);
        return v;
    }
    if (nim->iname && ends_with(nim->iname, ".gz")) {
        // nifti_clib does not notice a gzip stream that ends early: decompress
        // once through zlib, which checks the length and CRC at the end.
        gzFile gz = gzopen(nim->iname, "rb");
        if (!gz) throw Error(path, "cannot open the compressed data");
        std::vector<char> buf(1 << 16);
        std::uintmax_t total = 0;
        int n;
        while ((n = gzread(gz, buf.data(), unsigned(buf.size()))) > 0) total += std::uintmax_t(n);
        int err = 0;
        const char* msg = gzerror(gz, &err);
        const bool bad = n < 0 || (err != Z_OK && err != Z_BUF_ERROR);
        const std::string why = msg ? msg : "";
        if (gzclose_r(gz) != Z_OK || bad)
            throw Error(path, "corrupt or truncated gzip data" + (why.empty() ? "" : " (" + why + ")"));
        if (total < std::uintmax_t(nim->iname_offset) + bytes)
            throw Error(path, "truncated: " + std::to_string(bytes) + " bytes of data expected after offset " +
                                  std::to_string(nim->iname_offset) + ", the decompressed file has " +
                                  std::to_string(total));
    }
    if (nifti_image_load(nim.get()) != 0 || !nim->data)
        throw Error(path, "cannot read the data (truncated or corrupt file)");

    const double slope = h.slope, inter = h.inter;
    const bool rescale = h.rescale;
    VoxelType type = stored;
    if (rescale) {
        const bool integral_params = slope == std::floor(slope) && inter == std::floor(inter);
        const bool stored_int = stored != VoxelType::F32 && stored != VoxelType::F64;
        if (!(integral_params && stored_int)) type = VoxelType::F32;
        if (type == stored && stored_int) {
            // Integral rescale: keep the type only if the whole range fits.
            dispatch_voxel_type(stored, [&](auto tag) {
                using T = decltype(tag);
                const T* s = static_cast<const T*>(nim->data);
                for (std::size_t i = 0; i < std::size_t(dims[0] * dims[1] * dims[2]); ++i) {
                    const double x = double(s[i]) * slope + inter;
                    if (x < double(std::numeric_limits<T>::lowest()) || x > double(std::numeric_limits<T>::max())) {
                        type = VoxelType::F32;
                        break;
                    }
                }
                return 0;
            });
        }
    }
    Volume v = Volume::dense(dims, type, h.index_to_lps);
    if (rescale) {
        dispatch_voxel_type(stored, [&](auto tag) {
            using T = decltype(tag);
            rescale_into(static_cast<const T*>(nim->data), v, slope, inter);
            return 0;
        });
    } else {
        std::memcpy(v.bytes().data(), nim->data, bytes);
    }
    v.meta = h.meta;
    warn_non_finite(v);
    return v;
}

void write_nifti(const Volume& v, const std::string& path) {
    if (v.is_sparse()) throw Error(path, "sparse volumes are written as .vdb, not NIfTI");
    for (auto d : v.dims)
        if (d > std::numeric_limits<short>::max()) throw Error(path, "NIfTI-1 dimensions are limited to 32767");
    const int dims[8] = {3, int(v.dims[0]), int(v.dims[1]), int(v.dims[2]), 1, 1, 1, 1};
    NimPtr nim(nifti_make_new_nim(dims, nifti_type(v.type), 0));
    if (!nim) throw Error(path, "cannot create a NIfTI header");
    const glm::dmat4 ras = ras_to_lps(v.index_to_lps); // the flip is its own inverse
    const auto sp = v.spacing();
    nim->dx = nim->pixdim[1] = float(sp.x);
    nim->dy = nim->pixdim[2] = float(sp.y);
    nim->dz = nim->pixdim[3] = float(sp.z);
    nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->sto_xyz = to_mat44(ras);
    nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
    nifti_mat44_to_quatern(nim->sto_xyz, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x,
                           &nim->qoffset_y, &nim->qoffset_z, nullptr, nullptr, nullptr, &nim->qfac);
    nim->xyz_units = NIFTI_UNITS_MM;
    std::strncpy(nim->descrip, "isoscope", sizeof nim->descrip - 1);
    if (nifti_set_filenames(nim.get(), path.c_str(), 0, 1) != 0)
        throw Error(path, "not a NIfTI file name (.nii or .nii.gz)");
    nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
    // nifti_image_free() frees `data`: give it a copy it may own.
    nim->data = std::malloc(v.bytes().size());
    if (!nim->data) throw Error(path, "out of memory");
    std::memcpy(nim->data, v.bytes().data(), v.bytes().size());
    nifti_image_write(nim.get()); // reports failure only on stderr: check the result
    std::error_code ec;
    if (!fs::is_regular_file(path, ec) || fs::file_size(path, ec) < 348)
        throw Error(path, "writing the NIfTI file failed");
}

} // namespace iso
