// Reading a volume slab by slab, for volumes larger than memory
// (docs/isosurface.md, "Out of core").
//
// open_volume_stream() reads only the header (read_volume_header(): the same
// parsing as the in-memory readers) and returns a source of k-slabs: any range
// of k-slices [k0, k1] as a dense iso::Volume whose samples are those the
// in-memory reader gives (same type, same rescale) and whose affine is the
// whole volume's times translate(0, 0, k0).
//
// Formats:
//  - uncompressed NIfTI-1 (.nii, .hdr/.img), NRRD raw (.nrrd, .nhdr), MetaImage
//    raw (.mha, .mhd): read with pread() at the slab's offset (not mmap: mapped
//    pages would count as resident memory), byte-swapped when the file's byte
//    order is not the machine's;
//  - NRRD gzip: read forward with zlib; a request for slices before the
//    current position restarts the stream from the file's start (costly:
//    the streaming driver asks for slabs in increasing k);
//  - OpenVDB: loaded whole when twice its grid's memory fits
//    `in_memory_limit` (slabs are then windows of the sparse grid, no copy),
//    else read slab by slab: each slab by the isolating child process, which
//    reads the tree's topology with delayed loading, clips it to the slab and
//    reads only the leaves left (read_vdb_slab); slabs come back sparse. The
//    child holds the topology (resident_bytes()) and the slab's leaves;
//  - everything else (DICOM folders, .nii.gz, VTI, zlib-compressed MetaImage,
//    NRRD with several data files) is loaded whole when its in-memory
//    size fits `in_memory_limit`, else iso::Error says it cannot be streamed.
// Truncated raw data is an iso::Error naming the file with expected and
// actual bytes, at open time (before any output is written).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "io/volume.hpp"
#include "io/volume_io.hpp"

namespace iso {

class VolumeStream {
public:
    virtual ~VolumeStream() = default;
    const VolumeHeader& header() const { return header_; }
    // k-slices [k0, k1] (0 <= k0 <= k1 < dims[2]): dims nx x ny x (k1 - k0 + 1).
    virtual Volume read_slab(std::int64_t k0, std::int64_t k1) = 0;
    // Only forward reading is cheap (gzip): slabs should come in increasing k.
    virtual bool sequential() const { return false; }
    // Memory this source holds itself (a volume loaded whole; the last slices
    // read of a gzip stream, which the next slab's halo reuses).
    virtual std::size_t resident_bytes() const { return 0; }
    // How often a gzip stream went back to its start (a slab before the last one's halo).
    virtual std::size_t restarts() const { return 0; }
    // The largest resident memory of a separate reading process (OpenVDB's
    // isolating child), 0 when the source reads in this process.
    virtual std::size_t reader_peak_bytes() const { return 0; }
    // True when the samples are read from the file slab by slab.
    virtual bool streaming() const { return true; }

protected:
    VolumeHeader header_;
};

// `in_memory_limit`: formats that cannot stream are loaded whole when their
// size (from the header, or the file size) is at most this many bytes; 0:
// never (iso::Error naming the file and why it cannot be streamed).
std::unique_ptr<VolumeStream> open_volume_stream(const std::string& path, std::size_t in_memory_limit = 0,
                                                 const LoadOptions& opt = {});

} // namespace iso
