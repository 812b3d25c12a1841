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
// clip[0..clip_count): half-spaces (normal, offset): kept where dot(n, p) >= offset.
// tf_table: the transfer function's tables (renderer/volume/preintegration.hpp),
// texel i at value tf_lut.x + i / tf_lut.y, read interpolated between texels:
// [0, n) the classification (linear RGB, opacity per mm), [n, 2n) the
// integrals (n = tf_lut.z + 1 texels; E = integral of tau c dv, P = integral
// of tau dv, from the first point). A buffer, not a texture: llvmpipe reads
// it in less time (measured: 8 % of a pre-integrated frame).
layout(std430, binding = 11) readonly buffer VolumeTables { vec4 clip_planes[16]; vec4 tf_table[]; };
// Rays met, samples taken, samples skipped (empty chunks), rays ended early.
layout(std430, binding = 12) buffer VolumeCounters { uint vol_rays; uint vol_samples; uint vol_skipped; uint vol_terminated; };

vec3 vol_origin;      // eye, LPS
vec3 vol_dir;         // unit, LPS
vec3 vol_o_idx;       // eye in index space
vec3 vol_d_idx;       // direction in index space (per mm)
vec3 vol_inv_d;       // 1 / vol_d_idx (3e38 where 0)
vec3 vol_ahead;       // per axis 1 where the ray runs towards higher indices, else 0
float vol_t0 = 0.0, vol_t1 = -1.0; // the kept interval
float vol_at = 0.0;   // composited up to here
uint vol_samples_n = 0u, vol_skipped_n = 0u;
// MIP / MinIP: the extreme sample and whether it was composited yet.
float vol_extreme_t = 0.0;
vec4 vol_extreme_c = vec4(0.0);
bool vol_extreme_pending = false;

// The classification at v: one lookup (constant beyond the points).
vec4 tf_at(float v) {
    float x = clamp((v - tf_lut.x) * tf_lut.y, 0.0, tf_lut.z);
    int i = min(int(x), int(tf_lut.z) - 1);
    return mix(tf_table[i], tf_table[i + 1], x - float(i));
}

// (E, P) at v; beyond the points extended by their constant (tau c, tau).
// (Not the form below with its slope unused: llvmpipe computes the slope
// anyway, 20 % of a pre-integrated frame.)
vec4 tf_integral(float v) {
    if (v <= tf_lut.x) return tf_low_end * (v - tf_lut.x);
    if (v >= tf_lut.w) return tf_top + tf_high_end * (v - tf_lut.w);
    float x = clamp((v - tf_lut.x) * tf_lut.y, 0.0, tf_lut.z);
    int i = min(int(x), int(tf_lut.z) - 1), j = i + int(tf_lut.z) + 1;
    return mix(tf_table[j], tf_table[j + 1], x - float(i));
}

// (E, P) at v, and their slope there, (tau c, tau) averaged over the
// texel's interval (from the same two texels: no further lookup).
vec4 tf_integral(float v, out vec4 slope) {
    float x = clamp((v - tf_lut.x) * tf_lut.y, 0.0, tf_lut.z);
    int i = min(int(x), int(tf_lut.z) - 1), j = i + int(tf_lut.z) + 1;
    vec4 a = tf_table[j], b = tf_table[j + 1];
    slope = v <= tf_lut.x ? tf_low_end : v >= tf_lut.w ? tf_high_end : (b - a) * tf_lut.y;
    if (v <= tf_lut.x) return tf_low_end * (v - tf_lut.x);
    if (v >= tf_lut.w) return tf_top + tf_high_end * (v - tf_lut.w);
    return mix(a, b, x - float(i));
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
    vol_ahead = vec3(greaterThanEqual(vol_d_idx, vec3(0.0)));
    for (int k = 0; k < 3; ++k) vol_inv_d[k] = vol_d_idx[k] == 0.0 ? 3.0e38 : 1.0 / vol_d_idx[k];
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
#ifndef VOLUME_SHADING
    return color;
#else
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
#endif
}

// The chunk a sample lies in, and the ray's t where it leaves that chunk.
// Branch-free (llvmpipe runs this for every sample): the faces ahead on
// each axis, an axis the ray runs parallel to never the nearest.
float vol_chunk_exit(vec3 idx, out bool empty) {
    float S = dims_max.w;
    vec3 c = clamp(floor(idx / S), vec3(0.0), chunk_counts.xyz - 1.0);
    empty = texelFetch(occupancy_tex, ivec3(c), 0).r == 0u;
    vec3 t = ((c + vol_ahead) * S - vol_o_idx) * vol_inv_d;
    return min(min(t.x, t.y), t.z);
}

// Where a run of empty chunks the ray is in (its chunk's exit t_exit) ends:
// the chunks after it are looked up while they are empty, up to b. A value
// at a chunk's face belongs to both chunks' ranges (they share the face's
// voxels), so the run's ranges join into one interval the tables map to
// nothing, and a segment between two of its points adds nothing either.
float vol_empty_run_exit(float t_exit, float b) {
    for (int i = 0; i < 64 && t_exit < b; ++i) {
        bool empty;
        float next = vol_chunk_exit(vol_o_idx + (t_exit + 0.01 * step_mm) * vol_d_idx, empty);
        if (!empty || !(next > t_exit)) break;
        t_exit = next;
    }
    return t_exit;
}

#ifndef VOLUME_PREINTEGRATED
// The sampled march over [a, b]: n equal steps, each sample's
// classification held over its step (the stated model's sampling). One
// round per chunk the ray meets: its occupancy looked up once, then its
// samples (an inner loop with no lookup: llvmpipe would run a lookup's
// code for every sample, taken or not); an empty chunk's samples are
// skipped: they would have added exactly nothing.
void volume_sampled(float a, float b) {
    float n = ceil((b - a) / step_mm), h = (b - a) / n, k = 0.0;
    for (float round = 0.0; k < n && round < n; round += 1.0) {
        if (transmittance < vol_epsilon) break;
        float end = n;
        if (skip_empty) {
            bool empty;
            float t_exit = vol_chunk_exit(vol_o_idx + (a + (k + sample_offset) * h) * vol_d_idx, empty);
            if (empty) t_exit = vol_empty_run_exit(t_exit, b);
            // The first sample at or beyond the chunk's exit (a hair early:
            // a sample found still inside is looked up again next round).
            end = min(n, max(k + 1.0, ceil((t_exit - a) / h - sample_offset - 1e-3)));
            if (empty) {
                vol_skipped_n += uint(end - k);
                k = end;
                continue;
            }
        }
        for (; k < end; k += 1.0) {
            if (transmittance < vol_epsilon) break;
            vec3 idx = vol_o_idx + (a + (k + sample_offset) * h) * vol_d_idx;
            ++vol_samples_n;
            float v = vol_value(idx);
            if (v <= tf_clear.x || v >= tf_clear.y) continue;   // opacity 0: no lookup
            vec4 c = tf_at(v);
            if (c.a <= 0.0) continue;
            float keep = exp2(h * log2(1.0 - c.a));   // (1 - a)^h
            acc += transmittance * (1.0 - keep) * vol_shaded(idx, c.rgb);
            transmittance *= keep;
        }
    }
}

#else
// A piece of a pre-integrated segment, hh mm, value linear from va to vb
// (integrals Ia, Ib): its tau-weighted colour and transmittance. Within a
// texel's width of a constant value, the integrals' slope given (at the
// piece's back value; the last piece's at its front) instead: their
// difference would cancel. TransferTables::segment, on the CPU.
vec4 preint_piece(float va, float vb, vec4 Ia, vec4 Ib, vec4 slope, float hh) {
    float dv = vb - va;
    bool flat_ = !(abs(dv) >= tf_width);
    vec4 d = flat_ ? slope : (Ib - Ia) * (1.0 / dv);   // (tau c, tau), averaged
    return vec4(d.w > 0.0 ? d.rgb * (1.0 / d.w) : vec3(0.0), exp(-hh * d.w));
}

// One segment of len mm from value v0 to v1 (integrals I0, I1), vp and v2
// the points' values before and after it: the values inside it from the
// cubic through the four (Catmull-Rom) at 1/4, 1/2, 3/4, kept between v0
// and v1, linear between them (TransferTables::inner_values and segment).
void preint_segment(float vp, float v0, float v1, float v2, vec4 I0, vec4 I1, float len, vec3 idx_mid) {
    float lo = min(v0, v1), hi = max(v0, v1);
    vec3 t = vec3(0.25, 0.5, 0.75), t2 = t * t;
    vec3 q = 0.5 * ((-vp + 3.0 * v0 - 3.0 * v1 + v2) * t2 * t + (2.0 * vp - 5.0 * v0 + 4.0 * v1 - v2) * t2 +
                    (v1 - vp) * t + 2.0 * v0);
    q = clamp(q, lo, hi);
    vec4 s1, s2, s3;
    vec4 J1 = tf_integral(q.x, s1), J2 = tf_integral(q.y, s2), J3 = tf_integral(q.z, s3);
    float l = 0.25 * len;
    vec4 p1 = preint_piece(v0, q.x, I0, J1, s1, l), p2 = preint_piece(q.x, q.y, J1, J2, s2, l);
    vec4 p3 = preint_piece(q.y, q.z, J2, J3, s3, l), p4 = preint_piece(q.z, v1, J3, I1, s3, l);
    vec3 emit = (1.0 - p1.a) * p1.rgb +
                p1.a * ((1.0 - p2.a) * p2.rgb + p2.a * ((1.0 - p3.a) * p3.rgb + p3.a * (1.0 - p4.a) * p4.rgb));
    float keep = p1.a * p2.a * p3.a * p4.a;
#ifdef VOLUME_SHADING
    if (keep < 1.0) emit = (1.0 - keep) * vol_shaded(idx_mid, emit / (1.0 - keep));
#endif
    acc += transmittance * emit;
    transmittance *= keep;
}

// Point k of the pre-integrated march over [a, b] (n steps of h; s the
// frame's shift, 0 in the first frame; b is point K): a, the interior
// points a + (k - s) h, b, and one point beyond each end (read only for
// the shape of the values, as the texture clamps).
float preint_point(float k, float a, float b, float h, float s, float K) {
    if (k <= 0.0) return a + k * h;
    if (k >= K) return b + (k - K) * h;
    return a + (k - s) * h;
}

// The pre-integrated march over [a, b] (preintegration.hpp), one fetch per
// point: every segment between two points integrated in quarters, its
// inner values from the cubic through the segment's ends and their
// neighbours (Catmull-Rom), kept between the ends. Each fetch is a point
// ahead of the segment it completes.
//
// Skipping: a point in an empty chunk (F) is fetched; once the one after it
// is, the march jumps ahead to the chunk's last point but one. Segments
// with both ends in the chunk add exactly nothing (their values, inner ones
// included, stay within the chunk's range, which the tables map to nothing:
// the occupancy is widened by a texel), so the ones jumped over, and the
// two composited from the jump's stale values, would have added nothing,
// and every other segment sees its true neighbours: the image is the same.
void volume_preintegrated(float a, float b) {
    float n = ceil((b - a) / step_mm), h = (b - a) / n, o = fract(sample_offset + 0.5);
    float s = o > 0.0 ? 1.0 - o : 0.0, K = o > 0.0 ? n + 1.0 : n;
    // Points k - 3 .. k - 1 of the loop's k: vp, v0 (at t0), v1 (at t1).
    float t0 = a, t1 = preint_point(1.0, a, b, h, s, K);
    float vp = vol_value(vol_o_idx + (a - h) * vol_d_idx), v0 = vol_value(vol_o_idx + a * vol_d_idx);
    float v1 = vol_value(vol_o_idx + t1 * vol_d_idx);
    vec4 I0 = tf_integral(v0), I1 = tf_integral(v1);
    vol_samples_n += 3u;
    float k = 2.0;
    // One round per chunk the points meet (as the sampled march): a lookup,
    // then the points in the chunk without one.
    for (float round = 0.0; k <= K + 1.0 && round <= K + 1.0; round += 1.0) {
        if (transmittance < vol_epsilon) break;
        float end = K + 2.0, jump_to = -1.0;
        if (skip_empty && k < K) {
            bool empty;
            float t_exit = vol_chunk_exit(vol_o_idx + preint_point(k, a, b, h, s, K) * vol_d_idx, empty);
            if (empty) t_exit = vol_empty_run_exit(t_exit, b);
            // The chunk's last point (a hair early).
            float last = max(k, min(floor((t_exit - a) / h + s - 1e-3), K));
            end = last + 1.0;
            if (empty && last - 1.0 > k + 2.0) {
                end = k + 2.0;   // this point and the next, then on to the last but one
                jump_to = last - 1.0;
            }
        }
        for (; k < end; k += 1.0) {
            if (transmittance < vol_epsilon) break;
            float t2 = preint_point(k, a, b, h, s, K);
            float v2 = vol_value(vol_o_idx + t2 * vol_d_idx);
            ++vol_samples_n;
            // Both ends where the opacity is 0 on one side: the segment adds nothing.
            if (!(max(v0, v1) <= tf_clear.x || min(v0, v1) >= tf_clear.y))
                preint_segment(vp, v0, v1, v2, I0, I1, t1 - t0, vol_o_idx + 0.5 * (t0 + t1) * vol_d_idx);
            vp = v0;
            v0 = v1;
            v1 = v2;
            t0 = t1;
            t1 = t2;
            I0 = I1;
            I1 = tf_integral(v2);
        }
        if (jump_to > k) {
            vol_skipped_n += uint(jump_to - k);
            k = jump_to;
        }
    }
}

#endif

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
#ifdef VOLUME_PREINTEGRATED
    volume_preintegrated(a, b);
#else
    volume_sampled(a, b);
#endif
}

// The statistics of this pixel's ray.
void volume_end() {
    atomicAdd(vol_rays, 1u);
    atomicAdd(vol_samples, vol_samples_n);
    atomicAdd(vol_skipped, vol_skipped_n);
    if (transmittance < vol_epsilon) atomicAdd(vol_terminated, 1u);
}
