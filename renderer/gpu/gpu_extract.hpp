// Marching cubes with OpenGL 4.5 compute shaders (shaders/iso/mc.comp), over
// the same chunks as the CPU extractor and with the same conventions, so the
// two give the same vertices and triangles (the GPU numbers vertices in a
// different order; weld() makes one mesh of either). Needs a current GL 4.5
// context (gl::HeadlessContext or the GUI's). Samples travel to the GPU as
// float32, exact for 8/16-bit integer and float32 volumes; other types are
// rounded, which the result states in a warning.
#pragma once

#include <memory>

#include "renderer/surface/extract.hpp"

namespace iso {

struct GpuExtractStats {
    std::size_t batches = 0, chunks = 0;
    std::size_t peak_gpu_bytes = 0; // largest batch's buffers
};

class GpuExtractor {
public:
    // Keeps a reference to `volume`.
    GpuExtractor(const Volume& volume, ExtractOptions opt = {});
    ~GpuExtractor();
    GpuExtractor(const GpuExtractor&) = delete;
    GpuExtractor& operator=(const GpuExtractor&) = delete;

    const ChunkIndex& index() const { return index_; }
    // Chunks per batch: bounded by the options' memory budget.
    ChunkedSurface extract(double iso, GpuExtractStats* stats = nullptr);

private:
    struct Gl;
    const Volume* volume_;
    ExtractOptions opt_;
    ChunkIndex index_;
    std::unique_ptr<Gl> gl_;
};

} // namespace iso
