// The ambient-occlusion settings of a frame, in one place (docs/ao.md): the
// cone tracer's (ConeAoSettings) and the disk hierarchy's (DiskAoSettings),
// each described once in a table (name, member, range, help, command-line
// option) that drives their validation, their comparison, the image
// metadata and the CLI's options and error messages; and the slicemap as the
// cone tracer's voxelization is read back (tests, the voxel-grid reference).
// A leaf: no GL, no pass, no Renderer.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include <glm/mat4x4.hpp>

namespace iso {

struct ConeAoSettings {
    double radius_mm = 10.0; // R_max: occluders farther than this do not count
    int cones = 8;           // over the hemisphere, rotated to the normal
    int spheres = 5;         // per cone, sized to its cross-section, up to R_max
    int samples = 8;         // Poisson-disk columns per sphere
    double strength = 1.0;   // AO = 1 - strength * occlusion
    int layers = 2;          // slicemap z resolution: 128 bits per layer (1..8)
    double grid_scale = 1.0; // slicemap texels per image pixel (0.125..2)
    int jitter_sets = 8;     // precomputed distributions, one per pixel by a screen hash
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
    double attenuation = 0.0; // o_i /= 1 + attenuation * (t_i / R)^2
    double bias = 1.0;        // tangent-plane offset, in voxel/texel footprints
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
    bool temporal = true; // accumulate new jitter sets while camera and scene are still
    bool operator==(const ConeAoSettings&) const = default;
};

// The chapter's tunables. Only the two epsilons are given as numbers in the
// chapter; the others are free parameters it demonstrates (its figure 10),
// here at the values that leave Bunnell's method unchanged.
struct DiskAoSettings {
    // visibleQuad's snap: a vertex whose signed distance to the tangent plane
    // is within this (scene units, mm here) is taken as on the plane (chapter:
    // `const float epsilon = 1e-6`).
    double clip_epsilon = 1e-6;
    // Traversal depth: descend into an element's children while
    // d^2 < traversal_epsilon * area (chapter: "epsilon = 8 in all
    // experiments"). Used by the hierarchy, not by these kernels. 16:
    // measured per vertex against Embree at R = 10 mm (disk_ao_cpu_bench,
    // docs/ao.md): RMSE 0.0326 -> 0.0285 on the CT skin, 0.0405 -> 0.0301 on
    // the bunny for ~20% more gather time; 32 and beyond gain < 0.002.
    double traversal_epsilon = 16.0;
    // contribution /= 1 + distance_attenuation * d^2 (chapter, listing 4).
    // 0 = no attenuation (Bunnell).
    double distance_attenuation = 0.0;
    // contribution *= pow(element term, triangle_attenuation) (chapter,
    // listing 5). 1 = Bunnell's plain modulation by the emitter's term.
    double triangle_attenuation = 1.0;
    // Convergence: occlusion = min_scale * min(o0, o1) + max_scale * max(o0, o1)
    // over the last two iterations (chapter, listing 3, "a weighted minimum").
    // The chapter gives no numbers; 0.7 / 0.3 (weights adding up to 1, the
    // minimum dominating) is the usual choice of its implementations.
    double min_scale = 0.7;
    double max_scale = 0.3;
    // Element passes (per-disk occlusion, each modulated by the previous
    // pass's terms) before the final gather; the blend uses the last two.
    // 0: none, the gather sums unmodulated form factors (clamped to 1). 0 is
    // the default because it measured best at the AO radius R = 10 mm: the R
    // limit leaves few overlapping occluders to correct for, and the
    // modulation then removes more true occlusion than double counting adds
    // (per-vertex RMSE against Embree, CT skin: 0.0285 with 0 passes, 0.118
    // with 2 passes at the chapter's t = 1 and 0.7 / 0.3; the best with
    // passes, t = 0.1 and min_scale 1, 0.0352; docs/ao.md).
    int passes = 0;
    // Self-occlusion: the receiver is moved to p + receiver_offset * R * n
    // before the gather (R = the AO radius), so that its own disk (then
    // straight below it) and its own triangles (below or seen edge-on) add
    // nothing, without needing the receiver's triangle id (a pixel has
    // none). Relative to R so that it scales with the scene (docs/ao.md,
    // "Disk AO: hierarchy and CPU evaluation").
    double receiver_offset = 1e-3;
    bool operator==(const DiskAoSettings&) const = default; // FrameLook compares itself with it
};

// One setting of S as the table describes it: `name` is how errors
// ("cone AO setting cones"), the image metadata ("cones 8") and sessions
// call it; `option` the CLI's long option ("ao-cones"; empty: none of its
// own); [lo, hi] the accepted range (booleans: none); `help` the option's text.
template <class S> struct AoSetting {
    const char* name;
    std::variant<double S::*, int S::*, bool S::*> member;
    double lo, hi;
    const char* option;
    const char* help;
};

// The tables, in the order the metadata lists them.
const std::vector<AoSetting<ConeAoSettings>>& cone_ao_settings();
const std::vector<AoSetting<DiskAoSettings>>& disk_ao_settings();

// "cone AO setting " / "disk AO setting ": the prefix of the `where` of a
// setting's error, so that a front end can map it back to the setting.
extern const char* const kConeAoSettingPrefix;
extern const char* const kDiskAoSettingPrefix;

// Check every setting's range; throw iso::Error(prefix + name, ...) naming
// the first one out of range (NaN included).
void validate(const ConeAoSettings& s);
void validate(const DiskAoSettings& s);

// Every tabled member equal (the disk hierarchy's element terms depend on all of them).
bool same_settings(const DiskAoSettings& a, const DiskAoSettings& b);

// A setting's number as the metadata and the errors write it: %.9g (every
// float exactly, doubles to 9 significant digits).
std::string number_text(double v);

// "name value; name value; ..." of every tabled setting (doubles as %.9g,
// booleans on/off), for the image metadata.
std::string settings_text(const ConeAoSettings& s);
std::string settings_text(const DiskAoSettings& s);

// The slicemap as read back from the GPU: bit b of texel (x, y) is voxel b
// along z between z_near and z_far (linear depth, mm), rows bottom-up as GL
// stores them; words[((y * width + x) * layers + l) * 4 + c] holds bits
// 128 l + 32 c .. +31.
struct SliceMap {
    int width = 0, height = 0, layers = 0;
    double z_near = 0, z_far = 0; // mm along the view axis
    glm::dmat4 view{1.0}, projection{1.0};
    std::vector<std::uint32_t> words;
    int bits() const { return 128 * layers; }
    double voxel_length() const { return (z_far - z_near) / bits(); }
    bool bit(int x, int y, int b) const {
        const std::size_t w =
            (std::size_t(y) * std::size_t(width) + std::size_t(x)) * std::size_t(layers) * 4 + std::size_t(b / 32);
        return (words[w] >> (b % 32)) & 1u;
    }
    bool empty() const { return words.empty(); }
};

} // namespace iso
