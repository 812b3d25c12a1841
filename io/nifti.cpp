// NIfTI-1 (.nii, .nii.gz, and .hdr/.img pairs) through nifti_clib, the
// reference implementation. Orientation follows the standard: the sform
// when sform_code > 0, else the qform when qform_code > 0, else pixdim
// scaling ("method 1", orientation unknown). NIfTI world space is RAS, so
// the matrix is turned to LPS with diag(-1, -1, 1, 1).
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>

#include <nifti1_io.h>
#include <zlib.h>

#include "io/volume_io.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

struct NimDeleter { void operator()(nifti_image* n) const { nifti_image_free(n); } };
using NimPtr = std::unique_ptr<nifti_image, NimDeleter>;

VoxelType voxel_type(const std::string& path, int dt) {
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
    throw Error(path, std::string("unsupported voxel type ") + (name ? name : "?") + " (datatype " + std::to_string(dt) +
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

Volume read_nifti(const std::string& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path, "no such file");
    if (fs::file_size(path, ec) == 0) throw Error(path, "file is empty");
    nifti_set_debug_level(0);
    NimPtr nim(nifti_image_read(path.c_str(), 0)); // header only
    if (!nim) throw Error(path, "not a readable NIfTI-1 file (bad or truncated header)");
    if (nim->dim[0] < 2 || nim->dim[0] > 7) throw Error(path, "dim[0] = " + std::to_string(nim->dim[0]) + " is invalid");
    for (int a = 4; a <= nim->dim[0]; ++a)
        if (nim->dim[a] > 1)
            throw Error(path, "has " + std::to_string(nim->dim[a]) + " samples along dimension " + std::to_string(a) +
                                  " (time/vector data): only 3D scalar volumes are supported");
    const VoxelType stored = voxel_type(path, nim->datatype);
    std::array<std::int64_t, 3> dims{nim->nx, nim->ny, std::max(nim->nz, 1)};
    checked_byte_size(path, dims, stored);

    std::vector<std::string> warnings;
    glm::dmat4 ras(1.0);
    if (nim->sform_code > 0) {
        ras = from_mat44(nim->sto_xyz);
    } else if (nim->qform_code > 0) {
        ras = from_mat44(nim->qto_xyz);
    } else {
        for (int a = 0; a < 3; ++a) ras[a][a] = nim->pixdim[a + 1] > 0 ? nim->pixdim[a + 1] : 1.0;
        warnings.push_back("no sform or qform (both codes 0): orientation unknown, pixdim spacing on RAS axes assumed");
    }
    const glm::dmat4 lps = ras_to_lps(ras);
    check_affine(path, lps);

    // Uncompressed: the data must be in the file before anything is read.
    const std::size_t bytes = std::size_t(dims[0] * dims[1] * dims[2]) * voxel_size(stored);
    if (nim->iname && !ends_with(nim->iname, ".gz")) {
        const auto isize = fs::file_size(nim->iname, ec);
        if (ec) throw Error(path, std::string("data file '") + nim->iname + "' does not exist");
        if (isize < std::uintmax_t(nim->iname_offset) + bytes)
            throw Error(path, "truncated: the header announces " + std::to_string(bytes) + " bytes of data after offset " +
                                  std::to_string(nim->iname_offset) + ", the file has " + std::to_string(isize) + " bytes");
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
        if (gzclose_r(gz) != Z_OK || bad) throw Error(path, "corrupt or truncated gzip data" + (why.empty() ? "" : " (" + why + ")"));
        if (total < std::uintmax_t(nim->iname_offset) + bytes)
            throw Error(path, "truncated: " + std::to_string(bytes) + " bytes of data expected after offset " +
                                  std::to_string(nim->iname_offset) + ", the decompressed file has " + std::to_string(total));
    }
    if (nifti_image_load(nim.get()) != 0 || !nim->data)
        throw Error(path, "cannot read the data (truncated or corrupt file)");

    double slope = nim->scl_slope, inter = nim->scl_inter;
    const bool rescale = std::isfinite(slope) && slope != 0.0 && (slope != 1.0 || inter != 0.0);
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
    Volume v = Volume::dense(dims, type, lps);
    if (rescale) {
        dispatch_voxel_type(stored, [&](auto tag) {
            using T = decltype(tag);
            rescale_into(static_cast<const T*>(nim->data), v, slope, inter);
            return 0;
        });
    } else {
        std::memcpy(v.bytes().data(), nim->data, bytes);
    }
    v.meta.source = path;
    v.meta.format = "NIfTI";
    v.meta.warnings = std::move(warnings);
    if (nim->descrip[0]) v.meta.series_description = std::string(nim->descrip, strnlen(nim->descrip, 80));
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
    if (nifti_set_filenames(nim.get(), path.c_str(), 0, 1) != 0) throw Error(path, "not a NIfTI file name (.nii or .nii.gz)");
    nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
    // nifti_image_free() frees `data`: give it a copy it may own.
    nim->data = std::malloc(v.bytes().size());
    if (!nim->data) throw Error(path, "out of memory");
    std::memcpy(nim->data, v.bytes().data(), v.bytes().size());
    nifti_image_write(nim.get()); // reports failure only on stderr: check the result
    std::error_code ec;
    if (!fs::is_regular_file(path, ec) || fs::file_size(path, ec) < 348) throw Error(path, "writing the NIfTI file failed");
}

} // namespace iso
