// Volume ray casting (docs/volume.md), shared by volume.comp (no translucent
// surfaces) and the VOIT resolve (defined VOLUME): per pixel, the ray from
// the eye through the pixel, its interval inside the volume's index box, the
// clip half-spaces and the near plane, ended by the opaque surfaces' depth.
// The resolve calls volume_until(t) before compositing each translucent
// fragment at t and volume_until(ray end) after the list, so volume pieces
// and surfaces are composited in depth order. Every piece [a, b] is divided
// into n = ceil((b - a) / step) equal steps sampled at their midpoints; a
// step of h mm at opacity a per mm transmits (1 - a)^h (the stated model:
// exact for constant values whatever the step). The CPU reference
// (renderer/volume/reference.cpp) samples the same way. Frames averaged
// into an accumulation (the 3D view's still frames, exports) move the
// samples within their steps (sample_offset: 0.5 in the first), so the
// average samples each ray ever finer and the step's banding fades.
//
// Chunks whose value range the transfer function maps to zero opacity
// (occupancy 0, from the extractor's per-chunk min/max) are jumped over:
// the samples keep their places, and the ones skipped would have added
// exactly nothing (alpha 0), so the image is the same bit for bit.
// Expects `acc` (linear RGB, premultiplied) and `transmittance` declared by
// the including shader, and srgb.glsl / shading.glsl included.
layout(binding = 4) uniform sampler3D volume_tex;     // the values (normalized integer or float)
layout(binding = 5) uniform usampler3D occupancy_tex; // per chunk: 1 marched, 0 empty
layout(binding = 6) uniform sampler2D opaque_depth;   // the G-buffer's reversed-Z depth
// clip[0..clip_count): half-spaces (normal, offset): kept where dot(n, p) >= offset;
// tf_bins: per bin of values (tf_bin_map; 256 bins, 4 to a uvec4) a point at
// or below every value of the bin and the one before: where the search for a
// value's segment starts, a step or two before its end.
// tf[2i] = (value, opacity per mm, 0, 0), tf[2i + 1] = (linear RGB, 0).
layout(std430, binding = 11) readonly buffer VolumeTables { vec4 clip_planes[16]; uvec4 tf_bins[64]; vec4 tf[]; };
// Rays met, samples taken, samples skipped (empty chunks), rays ended early.
layout(std430, binding = 12) buffer VolumeCounters { uint vol_rays; uint vol_samples; uint vol_skipped; uint vol_terminated; };

vec3 vol_origin;      // eye, LPS
vec3 vol_dir;         // unit, LPS
vec3 vol_o_idx;       // eye in index space
vec3 vol_d_idx;       // direction in index space (per mm)
float vol_t0 = 0.0, vol_t1 = -1.0; // the kept interval
// The occupied chunk the last sample lay in ends here: until then no lookup.
float vol_chunk_end = -3.0e38;
float vol_at = 0.0;   // composited up to here
uint vol_samples_n = 0u, vol_skipped_n = 0u;
// MIP / MinIP: the extreme sample and whether it was composited yet.
float vol_extreme_t = 0.0;
vec4 vol_extreme_c = vec4(0.0);
bool vol_extreme_pending = false;

vec4 tf_at(float v) {
    uint n = tf_count;
    if (!(v > tf[0].x)) return vec4(tf[1].rgb, tf[0].y);
    if (v >= tf[2u * (n - 1u)].x) return vec4(tf[2u * (n - 1u) + 1u].rgb, tf[2u * (n - 1u)].y);
    uint bin = uint(clamp((v - tf_bin_map.y) * tf_bin_map.x, 0.0, 255.0));
    uint i = tf_bins[bin >> 2u][bin & 3u];
    for (uint k = 0u; k < n; ++k) {   // to the last point at or below v
        if (i + 1u >= n || tf[2u * (i + 1u)].x > v) break;
        ++i;
    }
    vec4 a = tf[2u * i], b = tf[2u * i + 2u];
    float t = (v - a.x) / (b.x - a.x);
    return vec4(mix(tf[2u * i + 1u].rgb, tf[2u * i + 3u].rgb, t), mix(a.y, b.y, t));
}

float vol_value(vec3 idx) {
    return texture(volume_tex, (idx + 0.5) * texel.xyz).r * value_map.x + value_map.y;
}

// The ray's t (mm) at reversed-Z depth d (the G-buffer's, a VOIT node's).
float vol_t_of_depth(float d) {
    float lin = vol_near_far.x * vol_near_far.y / (d * (vol_near_far.y - vol_near_far.x) + vol_near_far.x);
    return lin / dot(vol_dir, forward.xyz);
}

// Sets up pixel p's ray; false when it misses the (clipped) volume.
bool volume_begin(ivec2 p) {
    vec2 ndc = (vec2(p) + 0.5) / vec2(vol_image_size) * 2.0 - 1.0;
    vec4 a = inverse_view_projection * vec4(ndc, 1.0, 1.0), b = inverse_view_projection * vec4(ndc, 0.5, 1.0);
    vol_origin = eye.xyz;
    vol_dir = normalize(b.xyz / b.w - a.xyz / a.w);
    vol_o_idx = (lps_to_index * vec4(vol_origin, 1.0)).xyz;
    vol_d_idx = (lps_to_index * vec4(vol_dir, 0.0)).xyz;
    float cosine = dot(vol_dir, forward.xyz);
    float t0 = vol_near_far.x / cosine, t1 = vol_t_of_depth(texelFetch(opaque_depth, p, 0).r);
    for (int k = 0; k < 3; ++k) {
        if (vol_d_idx[k] == 0.0) {
            if (vol_o_idx[k] < 0.0 || vol_o_idx[k] > dims_max[k]) return false;
            continue;
        }
        float ta = -vol_o_idx[k] / vol_d_idx[k], tb = (dims_max[k] - vol_o_idx[k]) / vol_d_idx[k];
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
    for (uint c = 0u; c < clip_count; ++c) {
        float s = dot(clip_planes[c].xyz, vol_dir), r = clip_planes[c].w - dot(clip_planes[c].xyz, vol_origin);
        if (s == 0.0) {
            if (r > 0.0) return false;
        } else if (s > 0.0) {
            t0 = max(t0, r / s);
        } else {
            t1 = min(t1, r / s);
        }
    }
    if (!(t0 < t1)) return false;
    vol_t0 = t0;
    vol_t1 = t1;
    vol_at = t0;
    if (mode != 0u) {
        // MIP / MinIP: n + 1 samples over the whole interval, ends included.
        float n = max(1.0, ceil((t1 - t0) / step_mm)), h = (t1 - t0) / n;
        float best = mode == 1u ? -3.0e38 : 3.0e38;
        for (float k = 0.0; k <= n; k += 1.0) {
            float t = clamp(t0 + (k + sample_offset - 0.5) * h, t0, t1), v = vol_value(vol_o_idx + t * vol_d_idx);
            if (mode == 1u ? v > best : v < best) {
                best = v;
                vol_extreme_t = t;
            }
        }
        vol_samples_n += uint(n) + 1u;
        vol_extreme_c = tf_at(best);
        vol_extreme_pending = true;
    }
    return true;
}

// Linear colour of a sample with opacity: the transfer function's, shaded
// by the gradient's direction where the gradient is strong enough.
vec3 vol_shaded(vec3 idx, vec3 color) {
    if (!shading) return color;
    vec3 g;
    for (int k = 0; k < 3; ++k) {
        vec3 e = vec3(0.0);
        e[k] = 1.0;
        g[k] = 0.5 * (vol_value(min(idx + e, dims_max.xyz)) - vol_value(max(idx - e, vec3(0.0))));
    }
    vec3 n = gradient_to_view * g;   // per mm, view space
    float len = length(n);
    if (!(len > 0.0)) return color;
    n /= len;
    if (n.z < 0.0) n = -n;   // towards the viewer: the side the ray sees
    return mix(color, shade(n, color, false, 1.0), clamp(len / gradient_ref, 0.0, 1.0));
}

// The chunk a sample lies in, and the ray's t where it leaves that chunk.
float vol_chunk_exit(vec3 idx, out bool empty) {
    float S = dims_max.w;
    vec3 c = clamp(floor(idx / S), vec3(0.0), chunk_counts.xyz - 1.0);
    empty = texelFetch(occupancy_tex, ivec3(c), 0).r == 0u;
    float t_exit = 3.0e38;
    for (int k = 0; k < 3; ++k) {
        if (vol_d_idx[k] == 0.0) continue;
        float face = vol_d_idx[k] > 0.0 ? (c[k] + 1.0) * S : c[k] * S;
        t_exit = min(t_exit, (face - vol_o_idx[k]) / vol_d_idx[k]);
    }
    return t_exit;
}

// Composites the volume over [vol_at, min(t, end)].
void volume_until(float t) {
    float b = min(t, vol_t1);
    if (mode != 0u) {
        if (vol_extreme_pending && vol_extreme_t <= b) {
            acc += transmittance * vol_extreme_c.a * vol_extreme_c.rgb;
            transmittance *= 1.0 - vol_extreme_c.a;
            vol_extreme_pending = false;
        }
        return;
    }
    float a = vol_at;
    if (!(b > a) || transmittance < vol_epsilon) return;
    vol_at = b;
    float n = ceil((b - a) / step_mm), h = (b - a) / n;
    for (float k = 0.0; k < n; k += 1.0) {
        if (transmittance < vol_epsilon) break;
        float ts = a + (k + sample_offset) * h;
        vec3 idx = vol_o_idx + ts * vol_d_idx;
        if (skip_empty && !(ts < vol_chunk_end)) {
            bool empty;
            float t_exit = vol_chunk_exit(idx, empty);
            vol_chunk_end = empty ? -3.0e38 : t_exit;   // an occupied chunk's samples need no lookup
            if (empty) {
                // The first sample at or beyond the chunk's exit (a hair early:
                // a sample found still inside is skipped again next time round).
                float next = max(k + 1.0, ceil((t_exit - a) / h - sample_offset - 1e-3));
                vol_skipped_n += uint(min(next, n) - k);
                k = next - 1.0;
                continue;
            }
        }
        ++vol_samples_n;
        vec4 c = tf_at(vol_value(idx));
        if (c.a <= 0.0) continue;
        float keep = exp2(h * log2(1.0 - c.a));   // (1 - a)^h
        acc += transmittance * (1.0 - keep) * vol_shaded(idx, c.rgb);
        transmittance *= keep;
    }
}

// The statistics of this pixel's ray.
void volume_end() {
    atomicAdd(vol_rays, 1u);
    atomicAdd(vol_samples, vol_samples_n);
    atomicAdd(vol_skipped, vol_skipped_n);
    if (transmittance < vol_epsilon) atomicAdd(vol_terminated, 1u);
}
