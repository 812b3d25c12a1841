// A large int16 volume for the streaming tests and benchmark: a 512 x 512 x nz
// ball written slice by slice (never held whole) as a detached NRRD header
// and its raw data.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace iso::test {

// Writes dir/big.nhdr and dir/big.raw (slices dz mm apart, 0.5 mm pixels);
// `wobble` adds a ripple. Returns the header's path.
inline std::string write_big_ball(const std::filesystem::path& dir, int nz, double dz, bool wobble) {
    const int nx = 512, ny = 512;
    {
        std::ofstream h(dir / "big.nhdr");
        h << "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 512 512 " << nz
          << "\nspace directions: (0.5,0,0) (0,0.5,0) (0,0," << dz
          << ")\nkinds: domain domain domain\nendian: little\n"
             "encoding: raw\nspace origin: (0,0,0)\ndata file: big.raw\n";
    }
    std::ofstream d(dir / "big.raw", std::ios::binary);
    std::vector<std::int16_t> slice(std::size_t(nx) * ny);
    for (int k = 0; k < nz; ++k) {
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const double x = i - 255.5, y = j - 255.5, z = (k - 0.5 * (nz - 1)) * dz / 0.5;
                double f = 1000.0 - 4.0 * std::sqrt(x * x + y * y + z * z);
                if (wobble) f += 30.0 * std::sin(0.05 * i) * std::cos(0.07 * j + 0.01 * k);
                slice[std::size_t(j) * nx + i] = std::int16_t(f);
            }
        d.write(reinterpret_cast<const char*>(slice.data()), std::streamsize(slice.size() * 2));
    }
    return (dir / "big.nhdr").string();
}

} // namespace iso::test
