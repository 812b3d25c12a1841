// Marching cubes on the GPU (gpu_extract.hpp, docs/isosurface.md): batches of
// active chunks, their halo samples uploaded, five compute passes, the
// chunks' vertices and triangles read back.
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

// The chunks of one batch as the shaders read them.
struct Batch {
    std::vector<ChunkGpu> info;   // per chunk: box, halo box, offsets into samples/slots/vertices/triangles
    std::vector<float> samples;   // the chunks' halo blocks, one after the other
    std::uint32_t slot_total = 0; // one slot per sample and axis (an edge along x/y/z)
    std::uint32_t max_pts = 0, max_cells = 0;
};

// The chunks `ids`: their boxes (samples [p0, p0 + np), and one more on
// every side where the volume has it: the halo), and their halo samples with
// NaN/Inf substituted as on the CPU.
Batch gather_batch(const Volume& v, const ChunkIndex& index, const std::size_t* ids, std::size_t nb) {
    const int C = index.chunk_size();
    Batch batch;
    batch.info.resize(nb);
    for (std::size_t b = 0; b < nb; ++b) {
        const auto c = index.coords(ids[b]);
        ChunkGpu& ci = batch.info[b];
        for (int a = 0; a < 3; ++a) {
            const std::int64_t p0 = std::int64_t(c[a]) * C, p1 = std::min<std::int64_t>(p0 + C, v.dims[a] - 1);
            const std::int64_t lo = std::max<std::int64_t>(p0 - 1, 0),
                               hi = std::min<std::int64_t>(p1 + 1, v.dims[a] - 1);
            ci.p0[a] = int(p0);
            ci.np[a] = int(p1 - p0 + 1);
            ci.blo[a] = int(lo);
            ci.bn[a] = int(hi - lo + 1);
        }
        ci.p0[3] = ci.np[3] = ci.blo[3] = ci.bn[3] = 0;
        ci.offs[0] = std::uint32_t(batch.samples.size());
        ci.offs[1] = batch.slot_total;
        const std::uint32_t np = std::uint32_t(ci.np[0] * ci.np[1] * ci.np[2]);
        batch.slot_total += 3 * np; // one slot per edge along x/y/z
        batch.max_pts = std::max(batch.max_pts, np);
        batch.max_cells = std::max(batch.max_cells, std::uint32_t((ci.np[0] - 1) * (ci.np[1] - 1) * (ci.np[2] - 1)));
        for (int z = 0; z < ci.bn[2]; ++z)
            for (int y = 0; y < ci.bn[1]; ++y)
                for (int x = 0; x < ci.bn[0]; ++x) {
                    double s = v.value(ci.blo[0] + x, ci.blo[1] + y, ci.blo[2] + z);
                    if (std::isnan(s))
                        s = index.nan_value();
                    else if (std::isinf(s))
                        s = s > 0 ? index.highest() : index.lowest();
                    batch.samples.push_back(float(s));
                }
    }
    return batch;
}

// A counting pass's per-chunk counts (read back) and their exclusive prefix sums.
struct Bases {
    std::vector<std::uint32_t> base, count;
    std::uint32_t total = 0;
};

Bases chunk_bases(const gl::Buffer& counts, std::size_t nb) {
    Bases b{std::vector<std::uint32_t>(nb), counts.read_all<std::uint32_t>()};
    for (std::size_t i = 0; i < nb; ++i) {
        b.base[i] = b.total;
        b.total += b.count[i];
    }
    return b;
}

// What a batch's passes wrote, read back: chunk b's vertices are
// [verts.base[b], + verts.count[b]), its triangles likewise in tris.
struct BatchOutput {
    Bases verts, tris;
    std::vector<glm::vec3> positions, normals;
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> border;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::size_t gpu_bytes = 0; // the batch's buffers
};
} // namespace

struct GpuExtractor::Gl {
    gl::Program pass[kPasses];
    gl::Buffer table, edges;

    void set_uniforms(const Volume& v, double iso, int chunk_size, bool normals);
    BatchOutput run(Batch& batch, bool normals);
};

void GpuExtractor::Gl::set_uniforms(const Volume& v, double iso, int chunk_size, bool normals) {
    const glm::dmat3 lin(v.index_to_lps);
    const glm::dmat3 nm = glm::transpose(glm::inverse(lin));
    for (auto& p : pass) {
        glProgramUniformMatrix4dv(p.id(), p.uniform("index_to_lps"), 1, GL_FALSE, &v.index_to_lps[0][0]);
        glProgramUniformMatrix3dv(p.id(), p.uniform("normal_matrix"), 1, GL_FALSE, &nm[0][0]);
        glProgramUniform1d(p.id(), p.uniform("iso"), iso);
        glProgramUniform1d(p.id(), p.uniform("edge_margin"), kEdgeMargin); // the CPU's clamp of t (extract.hpp)
        glProgramUniform3i(p.id(), p.uniform("dims"), int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
        glProgramUniform1i(p.id(), p.uniform("chunk_size"), chunk_size);
        glProgramUniform1i(p.id(), p.uniform("flip"), glm::determinant(lin) < 0 ? 1 : 0);
        glProgramUniform1i(p.id(), p.uniform("want_normals"), normals ? 1 : 0);
    }
}

// The five passes over one batch: vertices counted (passes 1-2), their
// per-chunk bases computed on the CPU (small arrays), vertices written and
// cells counted (3-4), triangle bases, triangles written (5); then the results read back.
BatchOutput GpuExtractor::Gl::run(Batch& batch, bool normals) {
    const std::size_t nb = batch.info.size();
    auto& info = batch.info;
    gl::Buffer sbuf = gl::Buffer::from<float>(batch.samples);
    gl::Buffer cbuf = gl::Buffer::from<ChunkGpu>(info);
    gl::Buffer slots(std::size_t(batch.slot_total) * 4);
    slots.clear_u32(0);
    gl::Buffer counts(nb * 4);
    sbuf.bind_base(GL_SHADER_STORAGE_BUFFER, 0);
    cbuf.bind_base(GL_SHADER_STORAGE_BUFFER, 1);
    slots.bind_base(GL_SHADER_STORAGE_BUFFER, 2);
    counts.bind_base(GL_SHADER_STORAGE_BUFFER, 3);
    table.bind_base(GL_SHADER_STORAGE_BUFFER, 9);
    edges.bind_base(GL_SHADER_STORAGE_BUFFER, 10);

    auto dispatch = [&](int p, std::uint32_t items) {
        pass[p].use();
        glDispatchCompute((items + kLocal - 1) / kLocal, GLuint(nb), 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    };
    BatchOutput out;
    counts.clear_u32(0);
    dispatch(0, 3 * batch.max_pts);
    dispatch(1, 3 * batch.max_pts);
    out.verts = chunk_bases(counts, nb);
    for (std::size_t b = 0; b < nb; ++b) info[b].offs[2] = out.verts.base[b];
    cbuf.upload(0, info.size() * sizeof(ChunkGpu), info.data());
    const std::uint32_t nverts = out.verts.total;
    gl::Buffer pos(std::size_t(nverts) * 12), nrm(std::size_t(nverts) * 12), keys(std::size_t(nverts) * 8),
        border(std::size_t(nverts) * 4);
    pos.bind_base(GL_SHADER_STORAGE_BUFFER, 4);
    nrm.bind_base(GL_SHADER_STORAGE_BUFFER, 5);
    keys.bind_base(GL_SHADER_STORAGE_BUFFER, 6);
    border.bind_base(GL_SHADER_STORAGE_BUFFER, 7);
    counts.clear_u32(0);
    dispatch(2, 3 * batch.max_pts);
    counts.clear_u32(0);
    dispatch(3, batch.max_cells);
    out.tris = chunk_bases(counts, nb);
    for (std::size_t b = 0; b < nb; ++b) info[b].offs[3] = out.tris.base[b];
    cbuf.upload(0, info.size() * sizeof(ChunkGpu), info.data());
    gl::Buffer tris(std::size_t(out.tris.total) * 12);
    tris.bind_base(GL_SHADER_STORAGE_BUFFER, 8);
    counts.clear_u32(0);
    dispatch(4, batch.max_cells);

    out.positions = pos.read_all<glm::vec3>();
    if (normals) out.normals = nrm.read_all<glm::vec3>();
    out.keys = keys.read_all<std::uint64_t>();
    out.border = border.read_all<std::uint32_t>();
    out.triangles = tris.read_all<std::array<std::uint32_t, 3>>();
    out.gpu_bytes = sbuf.size() + slots.size() + pos.size() * 2 + keys.size() + border.size() + tris.size();
    return out;
}

namespace {
// Chunk b of the batch from its range of the read-back arrays.
void store_chunk(const BatchOutput& r, std::size_t b, const ExtractOptions& opt, ChunkMesh& m) {
    const std::uint32_t vbase = r.verts.base[b], vcount = r.verts.count[b];
    const std::uint32_t tbase = r.tris.base[b], tcount = r.tris.count[b];
    m.positions.assign(r.positions.begin() + vbase, r.positions.begin() + vbase + vcount);
    if (opt.normals) m.normals.assign(r.normals.begin() + vbase, r.normals.begin() + vbase + vcount);
    m.triangles.assign(r.triangles.begin() + tbase, r.triangles.begin() + tbase + tcount);
    if (opt.keep_keys) m.keys.assign(r.keys.begin() + vbase, r.keys.begin() + vbase + vcount);
    for (std::uint32_t i = 0; i < vcount; ++i)
        if (r.border[vbase + i]) m.border.emplace_back(r.keys[vbase + i], i);
}
} // namespace

GpuExtractor::GpuExtractor(const Volume& volume, ExtractOptions opt)
    : volume_(&volume), opt_(std::move(opt)), index_(volume, opt_.chunk_size, opt_.threads),
      gl_(std::make_unique<Gl>()) {
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

    gl_->set_uniforms(v, iso, C, opt_.normals);
    const bool exact = v.is_sparse() || v.type == VoxelType::U8 || v.type == VoxelType::I8 ||
                       v.type == VoxelType::U16 || v.type == VoxelType::I16 || v.type == VoxelType::F32;

    for (std::size_t first = 0; first < active.size(); first += batch) {
        const std::size_t nb = std::min(batch, active.size() - first);
        Batch chunks = gather_batch(v, index_, active.data() + first, nb);
        const BatchOutput r = gl_->run(chunks, opt_.normals);
        for (std::size_t b = 0; b < nb; ++b) store_chunk(r, b, opt_, out.chunks[active[first + b]]);
        if (stats) {
            ++stats->batches;
            stats->chunks += nb;
            stats->peak_gpu_bytes = std::max(stats->peak_gpu_bytes, r.gpu_bytes);
        }
        report(opt_.progress, double(first + nb) / double(active.size()), "extracting isosurface (GPU)", "gpu extract");
    }
    if (!exact)
        out.warnings.push_back(std::string("samples of type ") + voxel_type_name(v.type) +
                               " were rounded to float32 for the GPU");
    return out;
}

} // namespace iso
