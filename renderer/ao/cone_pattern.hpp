// Cone-traced ambient occlusion in a screen-aligned solid voxelization
// (docs/ao.md). The GL passes live in
// renderer/passes/ (ambient_occlusion.cpp and the files it calls); this header holds their settings, the CPU side of the sample
// patterns (cone directions, Poisson-disk columns, jitter sets) and the
// slicemap as read back for tests and for the voxel-grid reference.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

namespace iso {

struct ConeAoSettings {
    double radius_mm = 10.0;   // R_max: occluders farther than this do not count
    int cones = 8;             // over the hemisphere, rotated to the normal
    int spheres = 5;           // per cone, sized to its cross-section, up to R_max
    int samples = 8;           // Poisson-disk columns per sphere
    double strength = 1.0;     // AO = 1 - strength * occlusion
    int layers = 2;            // slicemap z resolution: 128 bits per layer (1..8)
    double grid_scale = 1.0;   // slicemap texels per image pixel (0.125..2)
    int jitter_sets = 8;       // precomputed distributions, one per pixel by a screen hash
    // A sphere's occlusion: 0 = the occupied fraction of its volume (the
    // thesis), 1 = the fraction of rays crossing it that a plane cutting off
    // that volume blocks, averaged over the plane's orientation
    // (sqrt(o) (1.15 - 0.15 o)); volume alone under-darkens creases and thin
    // walls. See docs/ao.md.
    double ray_weight = 0.5;
    // Axis probes: the cone's axis is also marched as a ray (five voxel
    // probes per sphere) and a cone whose axis meets a set voxel counts as at
    // least this much blocked; 0: off. The default 1 brings CT bone from
    // 0.095 to 0.080 RMSE and the thin phantom from 0.077 to 0.065 (skin
    // 0.037 -> 0.036) at 1.1-1.3x the AO passes' time, at the bulky bunny's
    // expense (0.023 -> 0.037): our users' surfaces are CT (docs/ao.md,
    // "Thin structures").
    double axis_weight = 1.0;
    // How sphere occlusions along a cone combine, front to back: 0 = as
    // independent absorbers (unoccluded *= 1 - o_i), 1 = as one persistent
    // solid (blocked = max o_i). Solids (bone, skin) occlude the same rays in
    // successive spheres, so the product over-darkens; see docs/ao.md.
    double persistence = 1.0;
    double attenuation = 0.0;  // o_i /= 1 + attenuation * (t_i / R)^2
    double bias = 1.0;         // tangent-plane offset, in voxel/texel footprints
    // Surface voxels: after the solid (voxel centre inside) voxelization, a
    // second, OR-blended draw sets the voxels next to every surface on its
    // solid's side, so walls thinner than a voxel in z still occlude. Off by
    // default: on llvmpipe it costs 1.7-5x the voxelization and did not lower
    // the error of the scenes measured (docs/ao.md, "Thin structures").
    bool surface_voxels = false;
    // Cone-pass pixels per frame pixel along each axis (0.25..1). Below 1 the
    // cones are traced on a coarser image and brought back to full size by a
    // joint bilateral (depth-plane and normal aware) upsampling pass.
    double resolution = 0.5;
    // Guard band: when the scene reaches beyond the viewport, the slicemap
    // covers up to this fraction of the viewport more on each side (as much
    // as R needs at the scene's nearest depth), so occluders just off screen
    // still count. 0: none.
    double guard = 0.15;
    bool temporal = true;      // accumulate new jitter sets while camera and scene are still
    bool operator==(const ConeAoSettings&) const = default;
};

// Checks ranges; throws iso::Error naming the offending setting.
void validate(const ConeAoSettings& s);

// Cone axes in the tangent frame (z = normal), cosine-weighted and of equal
// projected-disk area (Malley's method over a sunflower partition of the unit
// disk); w = sine of the half-angle, chosen so the cones' solid angles add up
// to the hemisphere.
std::vector<glm::vec4> cone_directions(int n);

// n points in the unit disk, pairwise at least ~0.8 of the densest packing
// distance apart (dart throwing with a shrinking radius), deterministic in `seed`.
std::vector<glm::vec2> poisson_disk(int n, std::uint32_t seed);

// Everything the cone-tracing shader reads from its pattern buffer for one
// frame: [cones][sets: (cos a, sin a, sphere offset, 0)][sets x samples: (x, y, 0, 0)].
// Successive frames (frame = 0, 1, ...) give new, independent jitter sets.
std::vector<glm::vec4> cone_pattern(const ConeAoSettings& s, std::uint32_t frame);

// The slicemap as read back from the GPU: bit b of texel (x, y) is voxel b
// along z between z_near and z_far (linear depth, mm), rows bottom-up as GL
// stores them; words[((y * width + x) * layers + l) * 4 + c] holds bits
// 128 l + 32 c .. +31.
struct SliceMap {
    int width = 0, height = 0, layers = 0;
    double z_near = 0, z_far = 0;      // mm along the view axis
    glm::dmat4 view{1.0}, projection{1.0};
    std::vector<std::uint32_t> words;
    int bits() const { return 128 * layers; }
    double voxel_length() const { return (z_far - z_near) / bits(); }
    bool bit(int x, int y, int b) const {
        const std::size_t w = (std::size_t(y) * std::size_t(width) + std::size_t(x)) * std::size_t(layers) * 4 + std::size_t(b / 32);
        return (words[w] >> (b % 32)) & 1u;
    }
    bool empty() const { return words.empty(); }
};

} // namespace iso
