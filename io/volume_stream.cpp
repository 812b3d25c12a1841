#include "io/volume_stream.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <vector>

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <glm/gtc/matrix_transform.hpp>

#include "io/sparse.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

glm::dmat4 slab_affine(const glm::dmat4& m, std::int64_t k0) {
    return glm::translate(m, glm::dvec3(0.0, 0.0, double(k0)));
}

void check_range(const VolumeHeader& h, std::int64_t k0, std::int64_t k1) {
    if (k0 < 0 || k1 < k0 || k1 >= h.dims[2])
        throw Error(h.path, "slices " + std::to_string(k0) + ".." + std::to_string(k1) +
                                " requested, the volume has 0.." + std::to_string(h.dims[2] - 1));
}

// Stored samples -> the in-memory type: byte order, then scl_slope/inter as
// read_nifti applies them (D(double(x) * slope + inter)).
void convert(const VolumeHeader& h, std::byte* src, std::size_t count, std::byte* dst) {
    const std::size_t ss = voxel_size(h.stored);
    if (h.swap_bytes && ss > 1)
        for (std::size_t i = 0; i < count; ++i) std::reverse(src + i * ss, src + (i + 1) * ss);
    if (h.nonfinite_to_zero)
        dispatch_voxel_type(h.stored, [&](auto tag) {
            using S = decltype(tag);
            if constexpr (std::is_floating_point_v<S>) {
                S* p = reinterpret_cast<S*>(src);
                for (std::size_t i = 0; i < count; ++i)
                    if (!std::isfinite(p[i])) p[i] = S(0);
            }
            return 0;
        });
    if (!h.rescale && h.type == h.stored) {
        if (src != dst) std::memcpy(dst, src, count * ss);
        return;
    }
    dispatch_voxel_type(h.stored, [&](auto stag) {
        using S = decltype(stag);
        dispatch_voxel_type(h.type, [&](auto dtag) {
            using D = decltype(dtag);
            const S* s = reinterpret_cast<const S*>(src);
            D* d = reinterpret_cast<D*>(dst);
            if (h.rescale)
                for (std::size_t i = 0; i < count; ++i) d[i] = D(double(s[i]) * h.slope + h.inter);
            else
                for (std::size_t i = 0; i < count; ++i) d[i] = D(s[i]);
            return 0;
        });
        return 0;
    });
}

// Slices of a slab, converted 1 MiB at a time (at least a slice) from a reader of stored bytes.
template <class Read> Volume read_converted(const VolumeHeader& h, std::int64_t k0, std::int64_t k1, Read&& read) {
    check_range(h, k0, k1);
    Volume v = Volume::dense({h.dims[0], h.dims[1], k1 - k0 + 1}, h.type, slab_affine(h.index_to_lps, k0));
    v.meta = h.meta;
    const std::size_t slice = std::size_t(h.dims[0] * h.dims[1]);
    const std::size_t ss = voxel_size(h.stored), ds = voxel_size(h.type);
    const bool direct = !h.rescale && h.type == h.stored; // converted in place
    const std::size_t per = std::max<std::size_t>(1, (std::size_t(1) << 20) / std::max<std::size_t>(1, slice * ss));
    std::vector<std::byte> buf;
    for (std::int64_t k = k0; k <= k1; k += std::int64_t(per)) {
        const std::size_t n = std::size_t(std::min<std::int64_t>(std::int64_t(per), k1 - k + 1));
        std::byte* out = v.bytes().data() + std::size_t(k - k0) * slice * ds;
        std::byte* in = out;
        if (!direct) {
            buf.resize(n * slice * ss);
            in = buf.data();
        }
        read(std::uint64_t(k) * slice * ss, in, n * slice * ss);
        convert(h, in, n * slice, out);
    }
    return v;
}

class RawStream final : public VolumeStream {
public:
    explicit RawStream(VolumeHeader h) {
        header_ = std::move(h);
        fd_ = ::open(header_.data_file.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0)
            throw Error(header_.path, "cannot open its data file '" + header_.data_file + "': " + std::strerror(errno));
    }
    ~RawStream() override {
        if (fd_ >= 0) ::close(fd_);
    }
    Volume read_slab(std::int64_t k0, std::int64_t k1) override {
        return read_converted(header_, k0, k1, [&](std::uint64_t at, std::byte* dst, std::size_t n) {
            const std::uint64_t start = header_.data_offset + at;
            std::size_t got = 0;
            while (got < n) {
                const ssize_t r = ::pread(fd_, dst + got, n - got, off_t(start + got));
                if (r < 0 && errno == EINTR) continue;
                if (r < 0) throw Error(header_.path, std::string("read error: ") + std::strerror(errno));
                if (r == 0)
                    throw Error(header_.path, "truncated: " + std::to_string(n) + " bytes expected at offset " +
                                                  std::to_string(start) + " of '" + header_.data_file + "', " +
                                                  std::to_string(got) + " read");
                got += std::size_t(r);
            }
        });
    }

private:
    int fd_ = -1;
};

// zlib reads gzip forward only; gzrewind() restarts from the stream's start.
class GzipStream final : public VolumeStream {
public:
    explicit GzipStream(VolumeHeader h) {
        header_ = std::move(h);
        const int fd = ::open(header_.data_file.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0)
            throw Error(header_.path, "cannot open its data file '" + header_.data_file + "': " + std::strerror(errno));
        if (::lseek(fd, off_t(header_.data_offset), SEEK_SET) < 0) {
            ::close(fd);
            throw Error(header_.path, "cannot seek to the gzip data");
        }
        gz_ = gzdopen(fd, "rb"); // owns fd from here; gzrewind() goes back to this offset
        if (!gz_) {
            ::close(fd);
            throw Error(header_.path, "cannot open the gzip data");
        }
        gzbuffer(gz_, 1 << 20);
    }
    ~GzipStream() override {
        if (gz_) gzclose_r(gz_);
    }
    bool sequential() const override { return true; }
    Volume read_slab(std::int64_t k0, std::int64_t k1) override {
        return read_converted(header_, k0, k1, [&](std::uint64_t at, std::byte* dst, std::size_t n) {
            // Consecutive slabs overlap by their gradient halo (a few slices):
            // those come from the copy of the last bytes read, not a restart.
            if (at < pos_ && at >= pos_ - tail_.size()) {
                const std::size_t from = tail_.size() - std::size_t(pos_ - at);
                const std::size_t m = std::min<std::size_t>(n, std::size_t(pos_ - at));
                std::memcpy(dst, tail_.data() + from, m);
                at += m;
                dst += m;
                n -= m;
                if (n == 0) return;
            }
            if (at < pos_) {
                if (gzrewind(gz_) != 0) throw Error(header_.path, "cannot restart the gzip stream");
                pos_ = 0;
                tail_.clear();
                ++restarts_;
            }
            std::vector<std::byte> skip;
            while (pos_ < at) {
                skip.resize(std::size_t(std::min<std::uint64_t>(at - pos_, 1 << 20)));
                pos_ += std::uint64_t(get(skip.data(), skip.size(), at));
            }
            get(dst, n, at);
            pos_ += n;
            // Keep the last few slices read.
            const std::size_t keep =
                std::size_t(kTailSlices * header_.dims[0] * header_.dims[1]) * voxel_size(header_.stored);
            if (n >= keep) {
                tail_.assign(dst + (n - keep), dst + n);
            } else {
                tail_.insert(tail_.end(), dst, dst + n);
                if (tail_.size() > keep)
                    tail_.erase(tail_.begin(), tail_.begin() + std::ptrdiff_t(tail_.size() - keep));
            }
        });
    }
    std::size_t restarts() const override { return restarts_; }
    std::size_t resident_bytes() const override {
        return std::size_t(kTailSlices * header_.dims[0] * header_.dims[1]) * voxel_size(header_.stored);
    }

private:
    std::size_t get(std::byte* dst, std::size_t n, std::uint64_t at) {
        std::size_t got = 0;
        while (got < n) {
            const unsigned ask = unsigned(std::min<std::size_t>(n - got, std::size_t(1) << 30));
            const int r = gzread(gz_, dst + got, ask);
            if (r < 0) {
                int err = 0;
                const char* msg = gzerror(gz_, &err);
                throw Error(header_.path, std::string("corrupt gzip data: ") + (msg ? msg : "?"));
            }
            if (r == 0)
                throw Error(header_.path, "truncated gzip data: " + std::to_string(header_.stored_bytes()) +
                                              " bytes expected, the stream ends after " + std::to_string(pos_ + got));
            got += std::size_t(r);
        }
        return got;
    }
    static constexpr std::int64_t kTailSlices = 4; // >= the overlap of consecutive slabs (3 slices)
    gzFile gz_ = nullptr;
    std::uint64_t pos_ = 0;
    std::vector<std::byte> tail_; // the last bytes read (stored, unconverted)
    std::size_t restarts_ = 0;
};

// A volume loaded whole (formats that cannot stream); slabs are copies, or
// windows of a sparse grid.
class MemoryStream final : public VolumeStream {
public:
    explicit MemoryStream(Volume v) : v_(std::move(v)) {
        header_.path = v_.meta.source;
        header_.dims = v_.dims;
        header_.stored = header_.type = v_.is_sparse() ? VoxelType::F32 : v_.type;
        header_.index_to_lps = v_.index_to_lps;
        header_.meta = v_.meta;
        header_.encoding = DataEncoding::Other;
    }
    bool streaming() const override { return false; }
    std::size_t resident_bytes() const override { return v_.memory_bytes(); }
    Volume read_slab(std::int64_t k0, std::int64_t k1) override {
        check_range(header_, k0, k1);
        const std::array<std::int64_t, 3> dims{v_.dims[0], v_.dims[1], k1 - k0 + 1};
        if (v_.is_sparse()) {
            auto g = std::make_shared<SparseGrid>(*v_.sparse_grid());
            g->offset = g->offset + openvdb::Coord(0, 0, int(k0));
            Volume s = Volume::sparse(std::move(g), dims, slab_affine(v_.index_to_lps, k0));
            s.meta = v_.meta;
            return s;
        }
        Volume s = Volume::dense(dims, v_.type, slab_affine(v_.index_to_lps, k0));
        s.meta = v_.meta;
        const std::size_t slice = std::size_t(v_.dims[0] * v_.dims[1]) * voxel_size(v_.type);
        std::memcpy(s.bytes().data(), v_.bytes().data() + std::size_t(k0) * slice, std::size_t(k1 - k0 + 1) * slice);
        return s;
    }

private:
    Volume v_;
};

// An OpenVDB grid too large to load whole: each slab is read by the
// isolating child process (read_vdb_slab: the tree's topology, clipped to the
// slab, and only the leaves left) and handed back sparse.
class VdbStream final : public VolumeStream {
public:
    explicit VdbStream(VdbHeader h) : vdb_(std::move(h)) { header_ = vdb_.header; }
    // While a slab is read, the child holds the grid's topology.
    std::size_t resident_bytes() const override { return std::size_t(vdb_.topology_bytes); }
    std::size_t reader_peak_bytes() const override { return reader_peak_; }
    Volume read_slab(std::int64_t k0, std::int64_t k1) override {
        check_range(header_, k0, k1);
        std::size_t peak = 0;
        Volume v = read_vdb_slab(vdb_, k0, k1, &peak);
        reader_peak_ = std::max(reader_peak_, peak);
        return v;
    }

private:
    VdbHeader vdb_;
    std::size_t reader_peak_ = 0;
};

std::uintmax_t size_on_disk(const std::string& path) {
    std::error_code ec;
    if (fs::is_regular_file(path, ec)) return fs::file_size(path, ec);
    std::uintmax_t n = 0;
    for (auto it = fs::recursive_directory_iterator(path, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec))
        if (it->is_regular_file(ec)) n += it->file_size(ec);
    return n;
}

} // namespace

std::unique_ptr<VolumeStream> open_volume_stream(const std::string& path, std::size_t in_memory_limit,
                                                 const LoadOptions& opt) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(path, "no such file or folder");
    const VolumeFormat f = volume_format_of(path);
    std::string why;
    std::uintmax_t need = 0;
    if (f == VolumeFormat::Nifti || f == VolumeFormat::Nrrd || f == VolumeFormat::MetaImage) {
        VolumeHeader h = read_volume_header(path);
        if (h.encoding == DataEncoding::Raw) return std::make_unique<RawStream>(std::move(h));
        if (h.encoding == DataEncoding::Gzip && f == VolumeFormat::Nrrd)
            return std::make_unique<GzipStream>(std::move(h));
        why = f == VolumeFormat::Nifti       ? "gzip-compressed NIfTI (.nii.gz) is not streamed: decompress it to .nii"
              : f == VolumeFormat::MetaImage ? "zlib-compressed MetaImage is not streamed: write it uncompressed"
                                             : "NRRD with this encoding or several data files is not streamed";
        need = h.memory_bytes();
    } else if (f == VolumeFormat::Vdb) {
        // Loaded whole (and sliced sparse) when it fits: reading it whole holds
        // the grid twice for a moment (in the reading child and here).
        VdbHeader h = read_vdb_header(path);
        if (in_memory_limit == 0 || 2 * h.grid_bytes > in_memory_limit)
            return std::make_unique<VdbStream>(std::move(h));
    } else {
        why = std::string(volume_format_name(f)) +
              " volumes are not streamed (NIfTI, NRRD raw/gzip, MetaImage raw and OpenVDB are)";
        need = size_on_disk(path);
    }
    if (in_memory_limit == 0 || need > in_memory_limit)
        throw Error(path, "cannot be streamed: " + why + "; loading it whole needs about " +
                              std::to_string(need >> 20) + " MiB, more than the " +
                              std::to_string(in_memory_limit >> 20) + " MiB allowed");
    return std::make_unique<MemoryStream>(load_volume(path, opt));
}

} // namespace iso
