// Volume loading and saving, dispatched on the file name (or a folder, for
// DICOM). Every loader returns a whole volume or throws iso::Error naming the
// file and the reason: nothing half-loads.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "io/progress.hpp"
#include "io/volume.hpp"

namespace iso {

struct LoadOptions {
    // DICOM: which series to load when a folder holds several, by index into
    // the listing ("0", "1", ...) or by SeriesInstanceUID. Empty: the only
    // series, or an error listing them when there are several.
    std::string series;
    ProgressFn progress;
};

enum class VolumeFormat { Unknown, Dicom, Nifti, Nrrd, MetaImage, Vti, Vdb };
VolumeFormat volume_format_of(const std::string& path); // by extension; folders are DICOM
const char* volume_format_name(VolumeFormat f);

// `path` is a file or a folder (DICOM).
Volume load_volume(const std::string& path, const LoadOptions& opt = {});
// An explicit list of DICOM files (one or more series).
Volume load_dicom_files(const std::vector<std::string>& files, const LoadOptions& opt = {});

// Writes .nrrd/.nhdr (NRRD, gzip for .nrrd unless `compress` is false) or
// .nii/.nii.gz (NIfTI-1). Writes to a temporary file first and renames it, so
// an existing file is never left half-written.
void save_volume(const Volume& v, const std::string& path, bool compress = true);

// What a volume file's header says, read without its samples: what `isoscope
// info --header-only` shows and what io/volume_stream.hpp streams from. The
// in-memory readers parse their headers through the same functions, so the
// geometry, type and rescale are the same whichever way a file is read.
enum class DataEncoding { Raw, Gzip, Other };
struct VolumeHeader {
    std::string path;
    VolumeFormat format = VolumeFormat::Unknown;
    std::array<std::int64_t, 3> dims{0, 0, 0};
    VoxelType stored = VoxelType::U8; // as in the file
    VoxelType type = VoxelType::U8;   // in memory, after rescale (see rescale)
    glm::dmat4 index_to_lps{1.0};
    Metadata meta; // source, format, description, warnings
    // NIfTI scl_slope/scl_inter: samples are stored * slope + inter, converted to `type`.
    bool rescale = false;
    double slope = 1.0, inter = 0.0;
    // Where the samples are: a file (the header's own for attached data), the
    // byte offset of the first sample, the encoding, and whether the bytes
    // are in the other byte order than this machine's.
    std::string data_file;
    std::uint64_t data_offset = 0;
    DataEncoding encoding = DataEncoding::Raw;
    bool swap_bytes = false;
    // nifti_clib replaces NaN and +/-Inf float samples by 0 when it reads
    // them (nifti_read_buffer); a reader of the raw bytes must do the same.
    bool nonfinite_to_zero = false;
    // What else a slab costs while it is read and held, besides its samples
    // (OpenVDB read slab by slab: the slab's leaf nodes in the reading child,
    // and the sparse slab's node overhead; leaves reach up to 7 voxels beyond
    // the slab): reader_bytes_per_voxel more per voxel, over
    // reader_extra_slices more slices. Zero for the other readers.
    double reader_bytes_per_voxel = 0.0;
    std::int64_t reader_extra_slices = 0;
    // Memory a slab of `slices` k-slices costs: its samples and the above.
    std::uint64_t slab_memory_bytes(std::int64_t slices) const {
        const std::uint64_t slice = std::uint64_t(dims[0] * dims[1]);
        if (reader_bytes_per_voxel == 0.0 && reader_extra_slices == 0)
            return slice * std::uint64_t(slices) * voxel_size(type);
        return std::uint64_t(std::ceil(double(slice) * double(slices + reader_extra_slices) *
                                       (double(voxel_size(type)) + reader_bytes_per_voxel)));
    }
    std::uint64_t stored_bytes() const { return std::uint64_t(dims[0] * dims[1] * dims[2]) * voxel_size(stored); }
    std::uint64_t memory_bytes() const { return std::uint64_t(dims[0] * dims[1] * dims[2]) * voxel_size(type); }
};

// Dispatch on the file name. NIfTI, NRRD and MetaImage headers are parsed (and
// raw data checked for truncation against the file size); other formats
// (DICOM, VTI) throw iso::Error saying their header cannot be read alone;
// OpenVDB's header is its grid's metadata and topology (read_vdb_header).
VolumeHeader read_volume_header(const std::string& path);
VolumeHeader read_nifti_header(const std::string& path);
VolumeHeader read_nrrd_header(const std::string& path);
VolumeHeader read_metaimage_header(const std::string& path);

// ---- per-format entry points (io/<format>.cpp) ------------------------------
std::vector<SeriesInfo> list_dicom_series(const std::vector<std::string>& files_or_folder);
Volume read_dicom(const std::vector<std::string>& files_or_folder, const LoadOptions& opt);
Volume read_nifti(const std::string& path);
void write_nifti(const Volume& v, const std::string& path);
Volume read_nrrd(const std::string& path);
void write_nrrd(const Volume& v, const std::string& path, bool compress);
Volume read_metaimage(const std::string& path);
Volume read_vti(const std::string& path);
Volume read_vdb(const std::string& path);
// OpenVDB read slab by slab (io/volume_stream.cpp), for a VDB too large to
// load whole. Every read runs OpenVDB's reader in the isolating child process
// (as read_vdb does). The header: the first float grid's name, geometry (the
// same index space and affine as read_vdb: our (0,0,0) is the corner of the
// grid's active bounding box) and what reading costs, from the grid's
// metadata and topology (no leaf values are read).
struct VdbHeader {
    VolumeHeader header;                         // format Vdb, F32, encoding Other
    std::string grid;                            // its name in the file
    std::array<std::int64_t, 3> offset{0, 0, 0}; // the grid index of our (0,0,0)
    std::uint64_t topology_bytes = 0;            // the tree without leaf values: what the child holds to read any slab
    std::uint64_t grid_bytes = 0;                // the grid loaded whole (topology and the values of every leaf)
};
VdbHeader read_vdb_header(const std::string& path);
// k-slices [k0, k1] of the grid as a sparse volume (dims[0] x dims[1] x
// (k1 - k0 + 1), the affine times translate(0, 0, k0)): in the child, the
// tree's topology is read (delayed loading: leaf values stay in the mapped
// file), clipped to the slab and a one-voxel border, and only the remaining
// leaves' values are read and handed back through a pipe. `child_peak`, when
// given, receives the child's peak resident memory (VmHWM).
Volume read_vdb_slab(const VdbHeader& h, std::int64_t k0, std::int64_t k1, std::size_t* child_peak = nullptr);
void write_vdb(const Volume& v, const std::string& path); // for tests and round trips

} // namespace iso
