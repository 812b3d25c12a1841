// The one volume type of isoscope.
//
// A volume is a regular grid of scalar samples, i fastest then j then k
// (x-fastest, as VTK, NRRD, NIfTI and DICOM pixel data store it), plus a 4x4
// affine that maps a continuous index (i, j, k, 1) to LPS millimetres. The
// affine carries spacing, origin and direction cosines; for a gantry-tilted
// DICOM series it is sheared so that every voxel is where the scanner put it.
//
// Values are stored after rescale (CT in Hounsfield units). Storage is either
// dense (one contiguous buffer) or sparse (an OpenVDB float grid kept as it was
// read; see sparse.hpp); `dims` and `index_to_lps` describe both the same way.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace iso {

enum class VoxelType : std::uint8_t { U8, I8, U16, I16, U32, I32, F32, F64 };

std::size_t voxel_size(VoxelType t);
const char* voxel_type_name(VoxelType t); // "uint8", "int16", "float32", ...

template <class T> constexpr VoxelType voxel_type_of();
template <> constexpr VoxelType voxel_type_of<std::uint8_t>() { return VoxelType::U8; }
template <> constexpr VoxelType voxel_type_of<std::int8_t>() { return VoxelType::I8; }
template <> constexpr VoxelType voxel_type_of<std::uint16_t>() { return VoxelType::U16; }
template <> constexpr VoxelType voxel_type_of<std::int16_t>() { return VoxelType::I16; }
template <> constexpr VoxelType voxel_type_of<std::uint32_t>() { return VoxelType::U32; }
template <> constexpr VoxelType voxel_type_of<std::int32_t>() { return VoxelType::I32; }
template <> constexpr VoxelType voxel_type_of<float>() { return VoxelType::F32; }
template <> constexpr VoxelType voxel_type_of<double>() { return VoxelType::F64; }

// Calls f(T{}) with T the C++ type of `t`.
template <class F> decltype(auto) dispatch_voxel_type(VoxelType t, F&& f) {
    switch (t) {
    case VoxelType::U8: return f(std::uint8_t{});
    case VoxelType::I8: return f(std::int8_t{});
    case VoxelType::U16: return f(std::uint16_t{});
    case VoxelType::I16: return f(std::int16_t{});
    case VoxelType::U32: return f(std::uint32_t{});
    case VoxelType::I32: return f(std::int32_t{});
    case VoxelType::F32: return f(float{});
    case VoxelType::F64: return f(double{});
    }
    return f(float{}); // unreachable
}

// One DICOM series found in a folder (listed by `isoscope info`).
struct SeriesInfo {
    std::string uid;         // SeriesInstanceUID (plus a suffix when split)
    std::string description; // SeriesDescription
    std::string modality;
    int number = 0; // SeriesNumber
    std::array<int, 3> dims{0, 0, 0};
    std::size_t files = 0;
    // What loading it would warn about, from the headers alone (missing
    // slices, uneven spacing, gantry tilt, a scout, geometry that cannot be
    // loaded): the series chooser shows them before anything is read.
    std::vector<std::string> warnings;
    // Fit for a 3D reconstruction: loadable and not a scout/localizer (both
    // also said in `warnings`).
    bool for_3d = true;
};

struct Metadata {
    std::string source;   // file or folder it was read from
    std::string format;   // "DICOM", "NIfTI", "NRRD", "MetaImage", "VTI", "OpenVDB"
    std::string modality; // "CT", "MR", ... when the format says
    std::string patient_name, patient_id, study_uid, series_uid, series_description;
    std::string reference_file;        // DICOM: a file of the series read (what derived objects copy)
    std::vector<SeriesInfo> series;    // every series in a DICOM folder
    int selected_series = -1;          // index into `series` that was loaded
    std::vector<std::string> warnings; // non-fatal findings (NaN counts, gaps, tilt, ...)
};

struct ValueRange {
    double min = 0, max = 0;
    std::size_t nan_count = 0, inf_count = 0; // non-finite samples, excluded from min/max
};

struct SparseGrid; // OpenVDB grid wrapper, sparse.hpp

class Volume {
public:
    Volume() = default;

    // Dense volume of the given type, zero-filled. Throws iso::Error when the
    // size overflows or cannot be allocated.
    static Volume dense(std::array<std::int64_t, 3> dims, VoxelType type, const glm::dmat4& index_to_lps);
    static Volume sparse(std::shared_ptr<const SparseGrid> grid, std::array<std::int64_t, 3> dims,
                         const glm::dmat4& index_to_lps);

    std::array<std::int64_t, 3> dims{0, 0, 0};
    VoxelType type = VoxelType::F32;
    glm::dmat4 index_to_lps{1.0};
    Metadata meta;

    bool is_sparse() const { return sparse_ != nullptr; }
    std::int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
    // Bytes held by the samples (dense buffer or sparse tree's memory use).
    std::size_t memory_bytes() const;

    // Dense storage; precondition: !is_sparse().
    std::span<std::byte> bytes() { return {data_.get(), byte_size_}; }
    std::span<const std::byte> bytes() const { return {data_.get(), byte_size_}; }
    template <class T> std::span<T> as() { return {reinterpret_cast<T*>(data_.get()), byte_size_ / sizeof(T)}; }
    template <class T> std::span<const T> as() const {
        return {reinterpret_cast<const T*>(data_.get()), byte_size_ / sizeof(T)};
    }
    std::size_t linear_index(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return static_cast<std::size_t>(i + dims[0] * (j + dims[1] * k));
    }
    // Sample as double (dense or sparse).
    double value(std::int64_t i, std::int64_t j, std::int64_t k) const;

    const std::shared_ptr<const SparseGrid>& sparse_grid() const { return sparse_; }

    // Voxel spacing in mm: the lengths of the affine's first three columns.
    glm::dvec3 spacing() const;
    glm::dvec3 index_to_world(const glm::dvec3& ijk) const;

    ValueRange value_range() const;

private:
    struct FreeDeleter {
        void operator()(std::byte* p) const;
    };
    std::unique_ptr<std::byte[], FreeDeleter> data_;
    std::size_t byte_size_ = 0;
    std::shared_ptr<const SparseGrid> sparse_;
};

// Checks a header's geometry before anything is allocated; throws iso::Error
// naming `file`: non-positive or overflowing dimensions, a byte size beyond
// `max_bytes`, zero/negative/non-finite spacing, non-orthogonal or degenerate
// direction cosines (tolerance: |cos| <= 1e-4 between columns).
std::size_t checked_byte_size(const std::string& file, std::array<std::int64_t, 3> dims, VoxelType type);
void check_affine(const std::string& file, const glm::dmat4& index_to_lps, bool allow_shear = false);

// Scans for NaN/Inf in floating-point volumes and appends a warning with the counts.
void warn_non_finite(Volume& v);

// Builds index->LPS from spacing, origin and direction cosines (columns = axis
// directions in LPS).
glm::dmat4 make_affine(const glm::dvec3& spacing, const glm::dvec3& origin_lps,
                       const glm::dmat3& directions = glm::dmat3(1.0));

// RAS <-> LPS: negate x and y of world coordinates.
glm::dmat4 ras_to_lps(const glm::dmat4& index_to_ras);

} // namespace iso
