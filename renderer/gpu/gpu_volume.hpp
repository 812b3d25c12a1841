// The volume on the GPU for ray casting (docs/volume.md): its values as a
// 3D texture, made once per volume and kept across frames (16-bit where the
// data is: int16 and uint16 exactly, as normalized integers; 8-bit as
// such; wider integers and floats as 32-bit floats, NaN as the range
// index's substitute, Inf clamped), and the occupancy of its chunks under
// the frame's transfer function, from the per-chunk min/max index the
// extractor builds (made here when none is handed over), remade only when
// the transfer function or mode changes; the transfer function's tables
// (preintegration.hpp), remade when it changes. Needs the GL context current.
#pragma once

#include <memory>
#include <vector>

#include "io/volume.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/surface/extract.hpp"

namespace iso {

class GpuVolume {
public:
    // A new volume (null: none); its texture is made on the first frame that draws it.
    void set(std::shared_ptr<const Volume> v, std::shared_ptr<const ChunkIndex> index);
    bool has_volume() const { return volume_ != nullptr; }
    // The frame's input for `look` (uploading what is new). Throws
    // iso::Error naming the volume when the GL cannot hold it.
    const passes::VolumeInput& prepare(const VolumeLook& look);

private:
    void upload();
    std::shared_ptr<const Volume> volume_;
    std::shared_ptr<const ChunkIndex> index_;
    gl::Texture texture_, occupancy_;
    VolumeLook occupancy_for_;
    bool occupancy_valid_ = false;
    passes::VolumeInput input_;
};

} // namespace iso
