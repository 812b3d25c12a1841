#include "renderer/gpu/gpu_extract.hpp"

#include <algorithm>
#include <cstring>

#include <glm/glm.hpp>

#include "io/sparse.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/surface/mc_tables.hpp"

namespace iso {

namespace {
struct alignas(16) ChunkGpu {
    std::int32_t p0[4], np[4], blo[4], bn[4];
    std::uint32_t offs[4];
};
static_assert(sizeof(ChunkGpu) == 80);
constexpr int kPasses = 5;
constexpr GLuint kLocal = 64;
} // namespace

struct GpuExtractor::Gl {
    gl::Program pass[kPasses];
    gl::Buffer table, edges;
};

GpuExtractor::GpuExtractor(const Volume& volume, ExtractOptions opt)
    : volume_(&volume), opt_(std::move(opt)), index_(volume, opt_.chunk_size, opt_.threads), gl_(std::make_unique<Gl>()) {
    for (int p = 0; p < kPasses; ++p)
        gl_->pass[p] = gl::Program::from_files({"iso/mc.comp"}, "#define PASS " + std::to_string(p + 1));
    const auto& t = mc::tables();
    std::vector<std::int32_t> tri(256 * 16);
    for (int c = 0; c < 256; ++c)
        for (int k = 0; k < 16; ++k) tri[std::size_t(c * 16 + k)] = t.tri_edges[std::size_t(c)][std::size_t(k)];
    gl_->table = gl::Buffer::from<std::int32_t>(tri);
    std::vector<std::int32_t> e(12 * 4);
    for (int i = 0; i < 12; ++i) {
        e[std::size_t(4 * i + 0)] = t.edges[std::size_t(i)].dx;
        e[std::size_t(4 * i + 1)] = t.edges[std::size_t(i)].dy;
        e[std::size_t(4 * i + 2)] = t.edges[std::size_t(i)].dz;
        e[std::size_t(4 * i + 3)] = t.edges[std::size_t(i)].axis;
    }
    gl_->edges = gl::Buffer::from<std::int32_t>(e);
}

GpuExtractor::~GpuExtractor() = default;

ChunkedSurface GpuExtractor::extract(double iso, GpuExtractStats* stats) {
    if (!std::isfinite(iso)) throw Error("extract", "iso value is not a finite number");
    const Volume& v = *volume_;
    const int C = index_.chunk_size();
    ChunkedSurface out;
    out.iso = iso;
    out.chunks.resize(index_.chunk_count());
    std::vector<std::size_t> active;
    for (std::size_t id = 0; id < index_.chunk_count(); ++id)
        if (index_.active(id, iso)) active.push_back(id);

    const std::size_t halo = std::size_t(C + 3) * (C + 3) * (C + 3), pts = std::size_t(C + 1) * (C + 1) * (C + 1);
    const std::size_t per_chunk = halo * 4 + pts * 16;
    const std::size_t batch = std::max<std::size_t>(1, std::min<std::size_t>(256, opt_.memory_budget / 2 / per_chunk));

    const glm::dmat3 lin(v.index_to_lps);
    const glm::dmat3 nm = glm::transpose(glm::inverse(lin));
    for (auto& p : gl_->pass) {
        glProgramUniformMatrix4dv(p.id(), p.uniform("index_to_lps"), 1, GL_FALSE, &v.index_to_lps[0][0]);
        glProgramUniformMatrix3dv(p.id(), p.uniform("normal_matrix"), 1, GL_FALSE, &nm[0][0]);
        glProgramUniform1d(p.id(), p.uniform("iso"), iso);
        glProgramUniform1d(p.id(), p.uniform("edge_margin"), kEdgeMargin); // the CPU's clamp of t (extract.hpp)
        glProgramUniform3i(p.id(), p.uniform("dims"), int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
        glProgramUniform1i(p.id(), p.uniform("chunk_size"), C);
        glProgramUniform1i(p.id(), p.uniform("flip"), glm::determinant(lin) < 0 ? 1 : 0);
        glProgramUniform1i(p.id(), p.uniform("want_normals"), opt_.normals ? 1 : 0);
    }
    const bool exact = v.is_sparse() || v.type == VoxelType::U8 || v.type == VoxelType::I8 ||
                       v.type == VoxelType::U16 || v.type == VoxelType::I16 || v.type == VoxelType::F32;

    for (std::size_t first = 0; first < active.size(); first += batch) {
        const std::size_t nb = std::min(batch, active.size() - first);
        std::vector<ChunkGpu> info(nb);
        std::vector<float> samples;
        std::uint32_t slot_total = 0, max_pts = 0, max_cells = 0;
        for (std::size_t b = 0; b < nb; ++b) {
            const auto c = index_.coords(active[first + b]);
            ChunkGpu& ci = info[b];
            for (int a = 0; a < 3; ++a) {
                const std::int64_t p0 = std::int64_t(c[a]) * C, p1 = std::min<std::int64_t>(p0 + C, v.dims[a] - 1);
                const std::int64_t lo = std::max<std::int64_t>(p0 - 1, 0), hi = std::min<std::int64_t>(p1 + 1, v.dims[a] - 1);
                ci.p0[a] = int(p0);
                ci.np[a] = int(p1 - p0 + 1);
                ci.blo[a] = int(lo);
                ci.bn[a] = int(hi - lo + 1);
            }
            ci.p0[3] = ci.np[3] = ci.blo[3] = ci.bn[3] = 0;
            ci.offs[0] = std::uint32_t(samples.size());
            ci.offs[1] = slot_total;
            const std::uint32_t np = std::uint32_t(ci.np[0] * ci.np[1] * ci.np[2]);
            slot_total += 3 * np; // one slot per edge along x/y/z
            max_pts = std::max(max_pts, np);
            max_cells = std::max(max_cells, std::uint32_t((ci.np[0] - 1) * (ci.np[1] - 1) * (ci.np[2] - 1)));
            // The halo block, NaN/Inf substituted as on the CPU.
            for (int z = 0; z < ci.bn[2]; ++z)
                for (int y = 0; y < ci.bn[1]; ++y)
                    for (int x = 0; x < ci.bn[0]; ++x) {
                        double s = v.value(ci.blo[0] + x, ci.blo[1] + y, ci.blo[2] + z);
                        if (std::isnan(s)) s = index_.nan_value();
                        else if (std::isinf(s)) s = s > 0 ? index_.highest() : index_.lowest();
                        samples.push_back(float(s));
                    }
        }
        gl::Buffer sbuf = gl::Buffer::from<float>(samples);
        gl::Buffer cbuf = gl::Buffer::from<ChunkGpu>(info);
        gl::Buffer slots(std::size_t(slot_total) * 4);
        slots.clear_u32(0);
        gl::Buffer counts(nb * 4);
        sbuf.bind_base(GL_SHADER_STORAGE_BUFFER, 0);
        cbuf.bind_base(GL_SHADER_STORAGE_BUFFER, 1);
        slots.bind_base(GL_SHADER_STORAGE_BUFFER, 2);
        counts.bind_base(GL_SHADER_STORAGE_BUFFER, 3);
        gl_->table.bind_base(GL_SHADER_STORAGE_BUFFER, 9);
        gl_->edges.bind_base(GL_SHADER_STORAGE_BUFFER, 10);

        auto run = [&](int p, std::uint32_t items) {
            gl_->pass[p].use();
            glDispatchCompute((items + kLocal - 1) / kLocal, GLuint(nb), 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        };
        // Counts -> per-chunk bases on the CPU (small arrays), then the writing passes.
        auto bases = [&](std::uint32_t* total) {
            auto n = counts.read_all<std::uint32_t>();
            std::vector<std::uint32_t> base(nb);
            std::uint32_t sum = 0;
            for (std::size_t b = 0; b < nb; ++b) {
                base[b] = sum;
                sum += n[b];
            }
            *total = sum;
            return std::make_pair(base, n);
        };
        counts.clear_u32(0);
        run(0, 3 * max_pts);
        run(1, 3 * max_pts);
        std::uint32_t nverts = 0;
        auto [vbase, vcount] = bases(&nverts);
        for (std::size_t b = 0; b < nb; ++b) info[b].offs[2] = vbase[b];
        cbuf.upload(0, info.size() * sizeof(ChunkGpu), info.data());
        gl::Buffer pos(std::size_t(nverts) * 12), nrm(std::size_t(nverts) * 12), keys(std::size_t(nverts) * 8),
            border(std::size_t(nverts) * 4);
        pos.bind_base(GL_SHADER_STORAGE_BUFFER, 4);
        nrm.bind_base(GL_SHADER_STORAGE_BUFFER, 5);
        keys.bind_base(GL_SHADER_STORAGE_BUFFER, 6);
        border.bind_base(GL_SHADER_STORAGE_BUFFER, 7);
        counts.clear_u32(0);
        run(2, 3 * max_pts);
        counts.clear_u32(0);
        run(3, max_cells);
        std::uint32_t ntris = 0;
        auto [tbase, tcount] = bases(&ntris);
        for (std::size_t b = 0; b < nb; ++b) info[b].offs[3] = tbase[b];
        cbuf.upload(0, info.size() * sizeof(ChunkGpu), info.data());
        gl::Buffer tris(std::size_t(ntris) * 12);
        tris.bind_base(GL_SHADER_STORAGE_BUFFER, 8);
        counts.clear_u32(0);
        run(4, max_cells);

        const auto P = pos.read_all<glm::vec3>();
        const auto N = opt_.normals ? nrm.read_all<glm::vec3>() : std::vector<glm::vec3>{};
        const auto K = keys.read_all<std::uint64_t>();
        const auto B = border.read_all<std::uint32_t>();
        const auto T = tris.read_all<std::array<std::uint32_t, 3>>();
        for (std::size_t b = 0; b < nb; ++b) {
            ChunkMesh& m = out.chunks[active[first + b]];
            m.positions.assign(P.begin() + vbase[b], P.begin() + vbase[b] + vcount[b]);
            if (opt_.normals) m.normals.assign(N.begin() + vbase[b], N.begin() + vbase[b] + vcount[b]);
            m.triangles.assign(T.begin() + tbase[b], T.begin() + tbase[b] + tcount[b]);
            if (opt_.keep_keys) m.keys.assign(K.begin() + vbase[b], K.begin() + vbase[b] + vcount[b]);
            for (std::uint32_t i = 0; i < vcount[b]; ++i)
                if (B[vbase[b] + i]) m.border.emplace_back(K[vbase[b] + i], i);
        }
        if (stats) {
            ++stats->batches;
            stats->chunks += nb;
            stats->peak_gpu_bytes = std::max(stats->peak_gpu_bytes, sbuf.size() + slots.size() + pos.size() * 2 +
                                                                          keys.size() + border.size() + tris.size());
        }
        report(opt_.progress, double(first + nb) / double(active.size()), "extracting isosurface (GPU)", "gpu extract");
    }
    if (!exact)
        out.warnings.push_back(std::string("samples of type ") + voxel_type_name(v.type) +
                               " were rounded to float32 for the GPU");
    return out;
}

} // namespace iso
