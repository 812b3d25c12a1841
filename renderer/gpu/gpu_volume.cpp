// The volume's 3D texture and chunk occupancy (gpu_volume.hpp).
#include "renderer/gpu/gpu_volume.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "io/error.hpp"

namespace iso {

void GpuVolume::set(std::shared_ptr<const Volume> v, std::shared_ptr<const ChunkIndex> index) {
    volume_ = std::move(v);
    index_ = std::move(index);
    texture_ = gl::Texture{};
    occupancy_ = gl::Texture{};
    occupancy_valid_ = false;
    input_.tables.reset();
}

namespace {

// How a voxel type goes to the GPU: the texture's format and the map from
// its normalized texel back to the value.
struct TexelFormat {
    GLenum internal = GL_R32F, format = GL_RED, type = GL_FLOAT;
    std::size_t bytes = 4;
    float scale = 1, offset = 0;
};

TexelFormat texel_format(const Volume& v) {
    if (v.is_sparse()) return {};
    switch (v.type) {
    case VoxelType::U8: return {GL_R8, GL_RED, GL_UNSIGNED_BYTE, 1, 255.0f, 0.0f};
    case VoxelType::U16: return {GL_R16, GL_RED, GL_UNSIGNED_SHORT, 2, 65535.0f, 0.0f};
    // int16 (CT) shifted by 32768 into uint16: every value exact, -32768 included.
    case VoxelType::I16: return {GL_R16, GL_RED, GL_UNSIGNED_SHORT, 2, 65535.0f, -32768.0f};
    default: return {};
    }
}

// Slice k of the volume in the texture's format.
void convert_slice(const Volume& v, const ChunkIndex& index, const TexelFormat& f, std::int64_t k,
                   std::vector<unsigned char>& out) {
    const std::size_t n = std::size_t(v.dims[0] * v.dims[1]);
    out.resize(n * f.bytes);
    if (!v.is_sparse() && (v.type == VoxelType::U8 || v.type == VoxelType::U16)) {
        std::memcpy(out.data(), v.bytes().data() + std::size_t(k) * n * f.bytes, n * f.bytes);
        return;
    }
    if (!v.is_sparse() && v.type == VoxelType::I16) {
        const std::int16_t* src = v.as<std::int16_t>().data() + std::size_t(k) * n;
        auto* dst = reinterpret_cast<std::uint16_t*>(out.data());
        for (std::size_t i = 0; i < n; ++i) dst[i] = std::uint16_t(std::int32_t(src[i]) + 32768);
        return;
    }
    // Floats may hold NaN and Inf: as the range index has them (a substitute below every finite value, clamps).
    const bool floating = v.is_sparse() || v.type == VoxelType::F32 || v.type == VoxelType::F64;
    auto* dst = reinterpret_cast<float*>(out.data());
    for (std::int64_t j = 0, i = 0; j < v.dims[1]; ++j)
        for (std::int64_t x = 0; x < v.dims[0]; ++x, ++i) {
            const double s = v.value(x, j, k);
            dst[i] = !floating       ? float(s)
                     : std::isnan(s) ? float(index.nan_value())
                                     : float(std::clamp(s, index.lowest(), index.highest()));
        }
}

} // namespace

void GpuVolume::upload() {
    const Volume& v = *volume_;
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_size);
    for (int a = 0; a < 3; ++a)
        if (v.dims[a] > max_size)
            throw Error(v.meta.source.empty() ? "volume rendering" : v.meta.source,
                        "the volume is " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" +
                            std::to_string(v.dims[2]) + " voxels; this GL's 3D textures hold at most " +
                            std::to_string(max_size) + " per axis");
    if (!index_) index_ = std::make_shared<const ChunkIndex>(v, 32);
    const TexelFormat f = texel_format(v);
    texture_ = gl::Texture::create_3d(f.internal, int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
    const GLuint t = texture_.id();
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        glTextureParameteri(t, w, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    std::vector<unsigned char> slice;
    for (std::int64_t k = 0; k < v.dims[2]; ++k) {
        convert_slice(v, *index_, f, k, slice);
        glTextureSubImage3D(t, 0, 0, 0, GLint(k), GLsizei(v.dims[0]), GLsizei(v.dims[1]), 1, f.format, f.type,
                            slice.data());
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    input_ = passes::VolumeInput{};
    input_.texture = t;
    input_.dims = glm::ivec3(int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
    input_.index_to_lps = v.index_to_lps;
    input_.value_map = {f.scale, f.offset};
    input_.chunk_size = index_->chunk_size();
    const auto counts = index_->counts();
    input_.chunk_counts = glm::ivec3(counts[0], counts[1], counts[2]);
    const glm::dvec3 s = v.spacing();
    input_.min_spacing = std::min({s.x, s.y, s.z});
    input_.texture_bytes = std::uint64_t(v.voxel_count()) * f.bytes;
    input_.uploaded = true;
    occupancy_ = gl::Texture::create_3d(GL_R8UI, counts[0], counts[1], counts[2]);
    input_.occupancy = occupancy_.id();
    occupancy_valid_ = false;
}

const passes::VolumeInput& GpuVolume::prepare(const VolumeLook& look) {
    if (!volume_) throw Error("volume rendering", "there is no volume to render (the input is a mesh)");
    input_.uploaded = false;
    if (!texture_.id()) upload();
    // The transfer function's tables: made again only when it changes.
    if (!input_.tables || !(input_.tables->function() == look.tf))
        input_.tables = std::make_shared<const TransferTables>(look.tf);
    if (!occupancy_valid_ || !(occupancy_for_.tf == look.tf) || occupancy_for_.mode != look.mode) {
        const auto occupied = occupied_chunks(look, index_->mins(), index_->maxs());
        input_.empty_chunks = std::size_t(std::count(occupied.begin(), occupied.end(), 0));
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTextureSubImage3D(occupancy_.id(), 0, 0, 0, 0, input_.chunk_counts.x, input_.chunk_counts.y,
                            input_.chunk_counts.z, GL_RED_INTEGER, GL_UNSIGNED_BYTE, occupied.data());
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        occupancy_for_ = look;
        occupancy_valid_ = true;
    }
    return input_;
}

} // namespace iso
