// Exact geometric kernels of disk-based ambient occlusion
// (`--ao disk`): Bunnell's disk hierarchy as improved by Hoberock & Jia,
// "High-Quality Ambient Occlusion", GPU Gems 3 ch. 12 (docs/ao.md, "Disk AO:
// exact kernels").
//
// Hand-written: no Debian package provides these AO kernels.
//
// Written to be ported line by line to GLSL compute shaders: templates over
// the scalar (float or double, both instantiated in disk_geometry.cpp) on
// GLM vectors, whose functions (dot, cross, length, min, max, clamp, atan,
// pow) are GLSL's; fixed-size arrays, no allocation, no recursion, no
// exceptions, and every division guarded so that no input (degenerate
// triangles, a vertex at the receiver, a zero normal) produces NaN or Inf.
//
// Conventions shared by every function:
// - The receiver is a point p with unit normal n. "Above" its tangent plane
//   means dot(n, x - p) > 0.
// - A polygon's winding defines its front face: the right-hand normal
//   cross(v1 - v0, v2 - v0) points out of the front. A polygon whose front
//   faces the receiver gives a positive form factor, its back a negative one
//   of the same magnitude.
// - Occlusion terms are in [0, 1]; AO (accessibility) = 1 - occlusion.
#pragma once

#include <glm/vec3.hpp>

#include "renderer/frame/ao_settings.hpp"

namespace iso {

// The visible part of a triangle above a tangent plane (the chapter's
// visibleQuad).
//
// Signed distances s_i = dot(n, v_i - p), each snapped to exactly 0 when
// |s_i| <= epsilon. The 27 sign patterns (s_i in {-, 0, +}) reduce to:
// - no s_i > 0 (the 2^3 = 8 patterns of 0 and -, including all three on the
//   plane): invisible. The part above the plane has no area.
// - some s_i > 0: the triangle clipped to the closed half-space s >= 0,
//   walking its edges in order v0 -> v1 -> v2 -> v0: every vertex with
//   s >= 0 is kept, and where an edge's endpoints have strictly opposite
//   signs the point v_a + s_a / (s_a - s_b) (v_b - v_a) on the plane is
//   inserted. That gives 3 points (a triangle) when no vertex is below (7
//   patterns) or one is above and the others below or on the plane, at least
//   one below (9 patterns), and 4 (a quad) when two are above and one below
//   (3 patterns).
// The output keeps the triangle's winding (so the form factor's sign is
// kept) and is convex (a triangle cut by a half-space).
//
// Output convention (the chapter's): 4 points q[0..3]. A triangle repeats its
// last point (q[3] == q[2]); invisible sets all four to p (so the quad has no
// area and no form factor) with count 0. `count` (0, 3 or 4) and `visible`
// say the same explicitly.
template <typename T> struct ClippedQuad {
    glm::vec<3, T> q[4];
    int count = 0;        // distinct points: 0 (invisible), 3 or 4
    bool visible = false; // count > 0
};

template <typename T>
ClippedQuad<T> clip_to_tangent_plane(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& v0,
                                     const glm::vec<3, T>& v1, const glm::vec<3, T>& v2,
                                     T epsilon = T(DiskAoSettings{}.clip_epsilon));

// Signed distance used by the clipping, dot(n, v - p) (subtracting first is
// better conditioned than dot(n, v) - dot(n, p) far from the origin), snapped
// to 0 within epsilon.
template <typename T>
T snapped_plane_distance(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& v, T epsilon);

// Exact form factor from a differential area at p with unit normal n to the
// planar polygon q[0..count-1] (any count; the clipped quad has 4), by the
// contour integral
//   F = 1/(2 pi) * sum_i theta_i * dot(n, g_i),
//   theta_i = angle between r_i = q_i - p and r_{i+1} (atan2(|c|, r_i.r_{i+1}),
//             better conditioned than the chapter's acos for small angles),
//   g_i     = c / |c|, c = cross(r_{i+1}, r_i): the unit normal of the plane
//             through p and the edge.
// With cross(r_{i+1}, r_i) (not r_i x r_{i+1}) a polygon whose front faces p
// gives F > 0. F is the cosine-weighted (projected) solid angle / pi, so a
// front-facing polygon wholly above the tangent plane that fills the view
// gives 1. The formula counts parts below the tangent plane negatively:
// clip first (clipped_triangle_form_factor).
// Degenerate edges contribute 0: zero length, an endpoint at p, or an edge
// whose line passes through p (sine of the angle at p <= 1e-12); so do repeated
// points (the chapter's triangle-as-quad). No input gives NaN or Inf.
// A polygon whose plane contains p (seen edge-on, zero solid angle) gives 0
// up to rounding when p is outside it; with p inside it or at a vertex the
// contour sum is the one-sided limit (dot(n, N) inside, times the polygon's
// angle at p / 2 pi at a vertex), not 0: the gather must exclude the
// receiver's own triangles.
template <typename T>
T polygon_form_factor(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>* q, int count);

// clip_to_tangent_plane, then polygon_form_factor of the visible quad (0 if
// invisible): the chapter's point-to-triangle term, before attenuation.
template <typename T>
T clipped_triangle_form_factor(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& v0,
                               const glm::vec<3, T>& v1, const glm::vec<3, T>& v2,
                               T epsilon = T(DiskAoSettings{}.clip_epsilon));

// Bunnell's disk approximation (GPU Gems 2 ch. 14) of the form factor from
// the receiver (p, n) to an emitter disk of area A at c with unit normal m:
//   v = (c - p) / d, d = |c - p|,
//   F = A * cos_e * cos_r / (pi d^2 + A),
//   cos_r = max(dot(n, v), 0), cos_e = max(dot(m, -v), 0).
// On the axis (both cosines 1) this is exact: R^2 / (h^2 + R^2) for a disk
// of radius R at height h. Far away it tends to the exact A cos_e cos_r /
// (pi d^2) with relative error O(A / d^2). A disk whose back faces p, or that
// lies below the tangent plane, gives 0 (front-facing only, unlike the signed
// polygon_form_factor). c == p gives 0.
template <typename T>
T disk_form_factor(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& c, const glm::vec<3, T>& m,
                   T area);

// Distance attenuation (chapter, listing 4): the factor 1 / (1 + k d^2) that
// multiplies an element's contribution; d2 = squared distance to it, k >= 0.
template <typename T> T distance_attenuation(T d2, T k = T(DiskAoSettings{}.distance_attenuation));

// Triangle attenuation (chapter, listing 5): the factor pow(e, t) that
// multiplies a triangle's form factor, e = the element's term from the
// previous iteration clamped to [0, 1] (Bunnell stores accessibility, 1 =
// unoccluded, so an unoccluded emitter is not attenuated), t >= 0. Written
// out for e = 0 (pow(0, t) is undefined in GLSL for t <= 0): 0 for t > 0, 1
// for t == 0.
template <typename T> T triangle_attenuation(T element_term, T t = T(DiskAoSettings{}.triangle_attenuation));

// Convergence (chapter, listing 3): the weighted blend of the last two
// iterations' values o0, o1 of one element, min_scale * min + max_scale * max.
// Symmetric in o0, o1, so an iteration that alternates between two solutions
// gives the same value whichever of them came last.
template <typename T>
T converge_blend(T o0, T o1, T min_scale = T(DiskAoSettings{}.min_scale), T max_scale = T(DiskAoSettings{}.max_scale));

} // namespace iso
