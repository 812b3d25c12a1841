// A deterministic CT-like int16 volume of any size, written slice by slice to
// an uncompressed NIfTI-1 file without ever holding the volume in memory (one
// slice buffer): the input of the out-of-core / MPI scaling benchmark
// (tests/bench/scale_bench.cpp, docs/scaling.md). The files are 2-8 GiB, so a
// sidecar (FILE.json: the generator's parameters, the header's CRC-32, the
// file size and the data's CRC-32) lets later runs reuse them.
//
// Content, in fractions of the volume's extent so that every size has the same
// anatomy (the trabecular texture alone is in voxels, so that the surface per
// active chunk is the same at every size):
//   air -1000 (noise sigma 5) around an ellipsoidal body whose z semi-axis is
//   0.40: the top and bottom 10 % of slices are air only (empty chunks that a
//   streaming extractor should skip); soft tissue 40 (sigma 15); a cortical
//   bone shell 1200 (sigma 30) whose inner side is cancellous bone, a gyroid
//   lattice 300 + 400 g (g in [-1.5, 1.5], period 24 voxels: trabeculae and
//   marrow, the bulk of the surface at bone thresholds); contrast-filled
//   vessels 450 wandering along z inside; a few small bright objects 2500
//   (calcifications, metal). Noise is a hash of (i, j, k, seed), so the values
//   do not depend on the thread count.
//
// Written here rather than taken from a package: no Debian package generates a
// CT phantom to disk slice by slice (ct_phantom.hpp builds one in memory). The
// header itself is nifti_clib's (nifti_image_write_hdr_img2), not hand-made.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nifti1_io.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/progress.hpp"
#include "io/volume.hpp"

namespace iso::bench {

struct ScaleVolumeParams {
    std::array<std::int64_t, 3> dims{256, 256, 256};
    double spacing_mm = 0.1; // micro-CT: a 1024^3 scan is 10 cm across
    unsigned seed = 16;
    int trabecular_period = 24; // voxels (2.4 mm at 0.1 mm: coarse trabecular bone; 16 gave ~1.5x the triangles)
    // Bumped whenever the content changes, so that old files are not reused.
    static constexpr int kVersion = 1;

    nlohmann::json to_json() const {
        return {{"generator", "isoscope scale_volume"},
                {"version", kVersion},
                {"dims", {dims[0], dims[1], dims[2]}},
                {"spacing_mm", spacing_mm},
                {"seed", seed},
                {"trabecular_period", trabecular_period}};
    }
    std::uint64_t voxels() const { return std::uint64_t(dims[0]) * std::uint64_t(dims[1]) * std::uint64_t(dims[2]); }
    std::string name() const {
        return "ct" + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]);
    }
};

// index -> LPS: spacing on the axes, centred on the origin (the reader's
// affine is its RAS counterpart, written as both sform and qform).
inline glm::dmat4 scale_volume_affine(const ScaleVolumeParams& p) {
    const glm::dvec3 sp(p.spacing_mm);
    const glm::dvec3 origin =
        -0.5 * glm::dvec3(double(p.dims[0] - 1), double(p.dims[1] - 1), double(p.dims[2] - 1)) * sp;
    return make_affine(sp, origin);
}

namespace detail {

inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}
// Approximately standard normal (Irwin-Hall of four 16-bit uniforms): one hash per voxel.
inline double hash_normal(std::uint64_t key) {
    const std::uint64_t h = splitmix64(key);
    const double s = double(h & 0xffff) + double((h >> 16) & 0xffff) + double((h >> 32) & 0xffff) + double(h >> 48);
    return (s / 65536.0 - 2.0) * 1.7320508075688772; // variance 4/12 -> 1
}

// The large features, fixed for a parameter set: in normalized coordinates
// u, v, w in [-0.5, 0.5] (voxel centres).
struct Anatomy {
    double ax = 0.44, ay = 0.38, az = 0.40; // body semi-axes
    struct Tube {
        double u0, v0, au, av, fu, fv, r;
    };
    struct Ball {
        double u, v, w, r;
    };
    std::vector<Tube> tubes;
    std::vector<Ball> balls;
    explicit Anatomy(unsigned seed) {
        std::mt19937 rng(seed);
        auto uni = [&] { return double(rng()) / 4294967296.0; }; // portable, unlike uniform_real_distribution
        for (int i = 0; i < 8; ++i)                              // vessels: inside the inner region (rho < 0.55)
            tubes.push_back({(uni() - 0.5) * 0.30, (uni() - 0.5) * 0.25, 0.02 + 0.04 * uni(), 0.02 + 0.04 * uni(),
                             6.0 + 10.0 * uni(), 6.0 + 10.0 * uni(), 0.008 + 0.012 * uni()});
        for (int i = 0; i < 6; ++i)
            balls.push_back({(uni() - 0.5) * 0.35, (uni() - 0.5) * 0.3, (uni() - 0.5) * 0.5, 0.004 + 0.008 * uni()});
    }
};

// Fills one slice (k) of int16 values, x fastest.
inline void fill_slice(const ScaleVolumeParams& p, const Anatomy& a, std::int64_t k, std::int16_t* out,
                       const std::vector<double>& sx, const std::vector<double>& cx, const std::vector<double>& sy,
                       const std::vector<double>& cy) {
    const std::int64_t nx = p.dims[0], ny = p.dims[1], nz = p.dims[2];
    const double w = (double(k) + 0.5) / double(nz) - 0.5;
    const double qz = w / a.az;
    const double two_pi = 6.283185307179586;
    const double sz = std::sin(two_pi * double(k) / p.trabecular_period),
                 cz = std::cos(two_pi * double(k) / p.trabecular_period);
    const double r_out = 0.80 + 0.02 * std::sin(9.0 * w);   // cortical outer surface (normalized radius)
    const double r_mid = r_out - 0.06, r_in = r_out - 0.20; // cortical / cancellous / inner boundaries
    // Tube centres and the balls that cut this slice.
    struct Disc {
        double u, v, r, value;
    };
    std::vector<Disc> discs;
    for (const auto& t : a.tubes)
        discs.push_back({t.u0 + t.au * std::sin(t.fu * w), t.v0 + t.av * std::cos(t.fv * w), t.r, 450.0});
    for (const auto& b : a.balls)
        if (std::abs(w - b.w) < b.r) discs.push_back({b.u, b.v, std::sqrt(b.r * b.r - (w - b.w) * (w - b.w)), 2500.0});
    const std::uint64_t slice_key =
        (std::uint64_t(p.seed) << 48) ^ (std::uint64_t(k) * std::uint64_t(ny) * std::uint64_t(nx));
    tbb::parallel_for(std::int64_t(0), ny, [&](std::int64_t j) {
        std::int16_t* row = out + j * nx;
        const std::uint64_t row_key = slice_key + std::uint64_t(j) * std::uint64_t(nx);
        const double v = (double(j) + 0.5) / double(ny) - 0.5;
        const double qy = v / a.ay;
        const double ryz2 = qy * qy + qz * qz;
        std::int64_t i_lo = nx, i_hi = -1; // body's x range on this row
        if (ryz2 < 1.0) {
            const double half = a.ax * std::sqrt(1.0 - ryz2);
            i_lo = std::max<std::int64_t>(0, std::int64_t(std::ceil((0.5 - half) * double(nx) - 0.5)));
            i_hi = std::min<std::int64_t>(nx - 1, std::int64_t(std::floor((0.5 + half) * double(nx) - 0.5)));
        }
        for (std::int64_t i = 0; i < nx; ++i) {
            double hu;
            if (i < i_lo || i > i_hi) {
                hu = -1000.0 + 5.0 * hash_normal(row_key + std::uint64_t(i));
            } else {
                const double u = (double(i) + 0.5) / double(nx) - 0.5;
                const double qx = u / a.ax;
                const double rho2 = qx * qx + ryz2;
                const double n = hash_normal(row_key + std::uint64_t(i));
                if (rho2 >= r_mid * r_mid && rho2 < r_out * r_out) {
                    hu = 1200.0 + 30.0 * n;
                } else if (rho2 >= r_in * r_in && rho2 < r_mid * r_mid) {
                    const double g =
                        sx[std::size_t(i)] * cy[std::size_t(j)] + sy[std::size_t(j)] * cz + sz * cx[std::size_t(i)];
                    hu = 300.0 + 400.0 * g + 30.0 * n;
                } else {
                    hu = 40.0 + 15.0 * n;
                    if (rho2 < r_in * r_in)
                        for (const auto& d : discs) {
                            const double du = u - d.u, dv = v - d.v;
                            if (du * du + dv * dv < d.r * d.r) hu = std::max(hu, d.value + 30.0 * n);
                        }
                }
            }
            row[i] = std::int16_t(std::lround(std::clamp(hu, -1024.0, 3071.0)));
        }
    });
}

inline std::uint32_t crc_of_prefix(const std::string& path, std::size_t n) {
    std::ifstream f(path, std::ios::binary);
    std::vector<char> buf(n);
    f.read(buf.data(), std::streamsize(n));
    if (std::size_t(f.gcount()) != n) return 0;
    return std::uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(buf.data()), uInt(n)));
}

constexpr std::size_t kNiftiVoxOffset = 352; // NIfTI-1 single file: 348-byte header + 4-byte extender

} // namespace detail

// Writes the volume to `path` (.nii), atomically (a temporary renamed into
// place). Returns the CRC-32 of the data. Progress per slice; cancellable.
inline std::uint32_t write_scale_volume(const ScaleVolumeParams& p, const std::string& path,
                                        const ProgressFn& progress = {}) {
    for (auto d : p.dims)
        if (d < 2 || d > 32767) throw Error(path, "scale volume dimensions must be 2..32767 (NIfTI-1)");
    if (p.trabecular_period < 2) throw Error(path, "trabecular period must be >= 2 voxels");
    const std::int64_t nx = p.dims[0], ny = p.dims[1], nz = p.dims[2];
    const detail::Anatomy anatomy(p.seed);
    const double two_pi = 6.283185307179586;
    std::vector<double> sx(static_cast<std::size_t>(nx)), cx(static_cast<std::size_t>(nx));
    std::vector<double> sy(static_cast<std::size_t>(ny)), cy(static_cast<std::size_t>(ny));
    for (std::int64_t i = 0; i < nx; ++i) {
        sx[std::size_t(i)] = std::sin(two_pi * double(i) / p.trabecular_period);
        cx[std::size_t(i)] = std::cos(two_pi * double(i) / p.trabecular_period);
    }
    for (std::int64_t j = 0; j < ny; ++j) {
        sy[std::size_t(j)] = std::sin(two_pi * double(j) / p.trabecular_period);
        cy[std::size_t(j)] = std::cos(two_pi * double(j) / p.trabecular_period);
    }
    std::uint32_t data_crc = 0;
    write_atomically(path, [&](const std::string& tmp) {
        const int dims[8] = {3, int(nx), int(ny), int(nz), 1, 1, 1, 1};
        nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 0); // header only: no data buffer
        if (!nim) throw Error(path, "cannot create a NIfTI header");
        struct Free {
            nifti_image* n;
            ~Free() { nifti_image_free(n); }
        } free_nim{nim};
        const glm::dmat4 ras = ras_to_lps(scale_volume_affine(p)); // the flip is its own inverse
        nim->dx = nim->pixdim[1] = float(p.spacing_mm);
        nim->dy = nim->pixdim[2] = float(p.spacing_mm);
        nim->dz = nim->pixdim[3] = float(p.spacing_mm);
        nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) nim->sto_xyz.m[r][c] = float(ras[c][r]);
        nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
        nifti_mat44_to_quatern(nim->sto_xyz, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x,
                               &nim->qoffset_y, &nim->qoffset_z, nullptr, nullptr, nullptr, &nim->qfac);
        nim->xyz_units = NIFTI_UNITS_MM;
        nim->cal_min = -1024;
        nim->cal_max = 3071;
        std::strncpy(nim->descrip, "isoscope scale_bench synthetic micro-CT", sizeof nim->descrip - 1);
        if (nifti_set_filenames(nim, tmp.c_str(), 0, 1) != 0) throw Error(path, "not a NIfTI file name (.nii)");
        nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
        // Header only, file left open (write_opts 2: no data, leave open).
        znzFile fp = nifti_image_write_hdr_img2(nim, 2, "wb", nullptr, nullptr);
        if (znz_isnull(fp)) throw Error(path, "cannot write the NIfTI header");
        struct Close {
            znzFile f;
            ~Close() {
                if (!znz_isnull(f)) znzclose(f);
            }
        } close_fp{fp};
        if (znzseek(fp, long(nim->iname_offset), SEEK_SET) != 0 || nim->iname_offset != int(detail::kNiftiVoxOffset))
            throw Error(path, "unexpected NIfTI data offset " + std::to_string(nim->iname_offset));
        std::vector<std::int16_t> slice(std::size_t(nx * ny));
        for (std::int64_t k = 0; k < nz; ++k) {
            detail::fill_slice(p, anatomy, k, slice.data(), sx, cx, sy, cy);
            const std::size_t bytes = slice.size() * sizeof(std::int16_t);
            data_crc = std::uint32_t(crc32_z(data_crc, reinterpret_cast<const Bytef*>(slice.data()), bytes));
            if (znzwrite(slice.data(), 1, bytes, fp) != bytes)
                throw Error(path, "write failed at slice " + std::to_string(k) + " (disk full?)");
            report(progress, double(k + 1) / double(nz), "generating the CT volume", "scale volume");
        }
        znzclose(fp);
        close_fp.f = nullptr;
        std::error_code ec;
        const auto size = std::filesystem::file_size(tmp, ec);
        if (ec || size != detail::kNiftiVoxOffset + p.voxels() * 2)
            throw Error(path, "written file has " + std::to_string(size) + " bytes, expected " +
                                  std::to_string(detail::kNiftiVoxOffset + p.voxels() * 2));
    });
    return data_crc;
}

// DIR/<name>.nii for these parameters: reused when its sidecar (same
// parameters, header CRC-32 and size) says it is ours and unchanged, else
// (re)generated. `reused` tells which.
inline std::string ensure_scale_volume(const ScaleVolumeParams& p, const std::string& dir, bool& reused,
                                       const ProgressFn& progress = {}) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw Error(dir, "cannot create the data folder: " + ec.message());
    const std::string path = (fs::path(dir) / (p.name() + ".nii")).string();
    const std::string side = path + ".json";
    const std::uint64_t size = detail::kNiftiVoxOffset + p.voxels() * 2;
    reused = false;
    if (fs::exists(side, ec) && fs::exists(path, ec)) {
        try {
            nlohmann::json j;
            std::ifstream(side) >> j;
            if (j.at("params") == p.to_json() && j.at("bytes").get<std::uint64_t>() == size &&
                fs::file_size(path) == size &&
                j.at("header_crc32").get<std::uint32_t>() == detail::crc_of_prefix(path, detail::kNiftiVoxOffset)) {
                reused = true;
                return path;
            }
        } catch (const std::exception&) {
            // an unreadable sidecar: regenerate
        }
    }
    if (fs::exists(path, ec)) {
        // Only a file that a sidecar of ours names is replaced (a different
        // generator version or parameters); anything else is the user's.
        if (!fs::exists(side, ec))
            throw Error(path, "exists and was not written by scale_bench (no sidecar): not overwritten");
        fs::remove(side, ec);
    }
    const auto space = fs::space(dir, ec);
    if (!ec && space.available < size + (std::uint64_t(1) << 30))
        throw Error(dir, "needs " + std::to_string(size >> 20) + " MiB for " + p.name() + ".nii (+1 GiB spare), " +
                             std::to_string(space.available >> 20) + " MiB free");
    const std::uint32_t data_crc = write_scale_volume(p, path, progress);
    const nlohmann::json j = {{"params", p.to_json()},
                              {"bytes", size},
                              {"header_crc32", detail::crc_of_prefix(path, detail::kNiftiVoxOffset)},
                              {"data_crc32", data_crc}};
    write_atomically(side, [&](const std::string& tmp) {
        std::ofstream f(tmp);
        f << j.dump(2) << "\n";
        if (!f.flush()) throw Error(side, "cannot write the sidecar");
    });
    return path;
}

} // namespace iso::bench
