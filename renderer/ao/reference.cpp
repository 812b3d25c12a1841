#include "renderer/ao/reference.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "io/error.hpp"
#include "renderer/ao/sequences.hpp"

namespace iso {

struct AoReference::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    double epsilon = 1e-4; // ray origin offset, mm
    // Per mesh (by index; null: empty), Embree's copies of its corners and
    // triangles: hit points in double from the barycentrics.
    std::vector<const float*> vertices;
    std::vector<const unsigned*> indices;
    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

AoReference::AoReference(const std::vector<const Mesh*>& meshes) : impl_(std::make_unique<Impl>()) {
    impl_->device = rtcNewDevice(nullptr);
    if (!impl_->device)
        throw Error("Embree", "cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    Bounds b;
    impl_->vertices.assign(meshes.size(), nullptr);
    impl_->indices.assign(meshes.size(), nullptr);
    for (unsigned mi = 0; mi < meshes.size(); ++mi) {
        const Mesh* m = meshes[mi];
        if (!m || m->triangles.empty()) continue;
        RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), m->positions.size()));
        for (std::size_t i = 0; i < m->positions.size(); ++i) {
            v[3 * i] = m->positions[i].x;
            v[3 * i + 1] = m->positions[i].y;
            v[3 * i + 2] = m->positions[i].z;
            b.add(glm::dvec3(m->positions[i]));
        }
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), m->triangles.size()));
        std::memcpy(idx, m->triangles.data(), m->triangles.size() * 3 * sizeof(unsigned));
        impl_->vertices[mi] = v;
        impl_->indices[mi] = idx;
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(impl_->scene, g, mi); // the hit's geomID is the mesh's index
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(impl_->scene);
    if (const auto e = rtcGetDeviceError(impl_->device); e != RTC_ERROR_NONE)
        throw Error("Embree", "building the scene failed (error " + std::to_string(int(e)) + ")");
    scene_size_ = b.empty() ? 1.0 : std::max(2.0 * b.radius(), 1e-9);
    // Far enough above the surface to leave its own triangle behind in float
    // precision, small against any occluder distance that matters.
    impl_->epsilon = ray_offset();
}

AoReference::~AoReference() = default;

namespace {
// Radical inverse base 2 (Hammersley points), with a per-point rotation
// (Cranley-Patterson) so neighbouring pixels do not share the same directions.
double radical_inverse(unsigned i) { return sequences::radical_inverse2(i); }
double hash01(unsigned x) { return sequences::unit(x); }

// Calls f(direction) for `opt.rays` cosine-distributed directions around n
// (Malley's method over rotated Hammersley points); stops early when f
// returns false.
template <class F>
void for_each_direction(const glm::dvec3& n, const AoReferenceOptions& opt, unsigned pixel_seed, F&& f) {
    // An orthonormal frame around n.
    const glm::dvec3 t =
        glm::normalize(std::abs(n.x) > 0.9 ? glm::cross(n, glm::dvec3(0, 1, 0)) : glm::cross(n, glm::dvec3(1, 0, 0)));
    const glm::dvec3 bt = glm::cross(n, t);
    const double u0 = hash01(opt.seed * 0x9E3779B9u + pixel_seed * 2u),
                 v0 = hash01(opt.seed * 0x85EBCA6Bu + pixel_seed * 2u + 1u);
    for (int i = 0; i < opt.rays; ++i) {
        double u = (i + 0.5) / opt.rays + u0, v = radical_inverse(unsigned(i)) + v0;
        u -= std::floor(u);
        v -= std::floor(v);
        // Malley: a uniform point of the unit disk, lifted to the hemisphere.
        const double r = std::sqrt(u), phi = 2.0 * M_PI * v;
        const double x = r * std::cos(phi), y = r * std::sin(phi), z = std::sqrt(std::max(0.0, 1.0 - u));
        f(x * t + y * bt + z * n);
    }
}

// Runs f(p, n, i) in parallel for every `stride`-th visible pixel of the
// depth/normal AOVs (p: the point in LPS mm, n: unit normal, i: pixel index)
// and returns the image of its results (NaN elsewhere).
template <class F>
Image per_visible_pixel(const Camera& cam, const Image& depth, const Image& normal, const AoReferenceOptions& opt,
                        int stride, F&& f) {
    if (depth.width != normal.width || depth.height != normal.height || depth.channels != 1 || normal.channels != 3)
        throw Error("ao reference", "depth (1 channel) and normal (3 channels) images of the same size are needed");
    if (!(opt.radius_mm > 0) || opt.rays < 1) throw Error("ao reference", "radius and ray count must be positive");
    const int W = depth.width, H = depth.height;
    Image out;
    out.width = W;
    out.height = H;
    out.channels = 1;
    out.is_float = true;
    out.floats.assign(std::size_t(W) * H, std::numeric_limits<float>::quiet_NaN());
    const glm::dvec3 fw = cam.forward(), right = glm::normalize(glm::cross(fw, cam.up)), up = glm::cross(right, fw);
    const double th = std::tan(glm::radians(cam.fov_y_degrees) * 0.5), aspect = double(W) / double(H);
    tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(0, (H + stride - 1) / stride, [&](int yi) {
            const int y = yi * stride;
            for (int x = 0; x < W; x += stride) {
                const std::size_t i = std::size_t(y) * W + x;
                const float D = depth.floats[i];
                if (!std::isfinite(D)) continue;
                const double ndc_x = (x + 0.5) / W * 2.0 - 1.0, ndc_y = 1.0 - (y + 0.5) / H * 2.0;
                const glm::dvec3 dir = fw + right * (ndc_x * th * aspect) + up * (ndc_y * th); // dot(dir, fw) = 1
                const glm::dvec3 p = cam.eye + dir * double(D);
                const glm::dvec3 n(normal.floats[3 * i], normal.floats[3 * i + 1], normal.floats[3 * i + 2]);
                if (!(glm::length(n) > 0.5)) continue;
                out.floats[i] = float(f(p, glm::normalize(n), i));
            }
        });
    });
    return out;
}
} // namespace

bool AoReference::occluded(const glm::dvec3& org, const glm::dvec3& d, double tfar) const {
    RTCRay ray;
    ray.org_x = float(org.x);
    ray.org_y = float(org.y);
    ray.org_z = float(org.z);
    ray.dir_x = float(d.x);
    ray.dir_y = float(d.y);
    ray.dir_z = float(d.z);
    ray.tnear = 0.0f;
    ray.tfar = float(tfar);
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(impl_->scene, &ctx, &ray);
    return ray.tfar < 0.0f; // Embree sets tfar to -inf on a hit
}

AoReference::Hit AoReference::intersect(const glm::dvec3& org, const glm::dvec3& d, double tnear, double tfar) const {
    RTCRayHit rh;
    rh.ray.org_x = float(org.x);
    rh.ray.org_y = float(org.y);
    rh.ray.org_z = float(org.z);
    rh.ray.dir_x = float(d.x);
    rh.ray.dir_y = float(d.y);
    rh.ray.dir_z = float(d.z);
    rh.ray.tnear = float(tnear);
    rh.ray.tfar = float(tfar);
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(impl_->scene, &ctx, &rh);
    Hit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    const glm::dvec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    const double len = glm::length(ng);
    if (!(len > 0)) return h; // a degenerate triangle has no normal
    h.hit = true;
    h.t = rh.ray.tfar;
    h.normal = ng / len;
    h.mesh = rh.hit.geomID;
    h.triangle = rh.hit.primID;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    // On the triangle itself, in double: org + t dir carries the float error
    // of t (~1e-4 mm at 1 m), more than the smallest ray offsets tested.
    const unsigned* tri = impl_->indices[h.mesh] + 3 * std::size_t(h.triangle);
    const float* v = impl_->vertices[h.mesh];
    const auto corner = [&](int c) { return glm::dvec3(v[3 * tri[c]], v[3 * tri[c] + 1], v[3 * tri[c] + 2]); };
    h.point = (1.0 - h.u - h.v) * corner(0) + h.u * corner(1) + h.v * corner(2);
    return h;
}

double AoReference::at(const glm::dvec3& p, const glm::dvec3& n_in, const AoReferenceOptions& opt,
                       unsigned pixel_seed) const {
    const glm::dvec3 n = glm::normalize(n_in);
    const glm::dvec3 origin = p + n * impl_->epsilon;
    int unoccluded = 0;
    for_each_direction(n, opt, pixel_seed, [&](const glm::dvec3& d) {
        if (!occluded(origin, d, opt.radius_mm)) ++unoccluded;
    });
    return double(unoccluded) / double(opt.rays);
}

Image AoReference::image(const Camera& cam, const Image& depth, const Image& normal,
                         const AoReferenceOptions& opt) const {
    return per_visible_pixel(cam, depth, normal, opt, 1, [&](const glm::dvec3& p, const glm::dvec3& n, std::size_t i) {
        return at(p, n, opt, unsigned(i));
    });
}

Image voxel_ao_image(const SliceMap& sm, const Camera& cam, const Image& depth, const Image& normal,
                     const AoReferenceOptions& opt, double bias, int stride) {
    if (sm.empty()) throw Error("voxel ao reference", "no slicemap (render with read_slicemap)");
    if (stride < 1) throw Error("voxel ao reference", "stride must be >= 1");
    const double dz = sm.voxel_length();
    const double p00 = sm.projection[0][0], p11 = sm.projection[1][1];
    const glm::dmat3 rot(sm.view);
    return per_visible_pixel(
        cam, depth, normal, opt, stride, [&](const glm::dvec3& pw, const glm::dvec3& nw, std::size_t i) {
            // Eye space, as the cone-tracing shader works (camera looks down -z).
            const glm::dvec3 p = glm::dvec3(sm.view * glm::dvec4(pw, 1.0));
            const glm::dvec3 n = glm::normalize(rot * nw);
            const double D = -p.z;
            const double texel_w = 2.0 * D / (p11 * sm.height);
            // The same raised tangent plane as the shader: the surface's own voxels do not occlude.
            const double beta = bias * (std::abs(n.z) * dz + 0.5 * (std::abs(n.x) + std::abs(n.y)) * texel_w);
            const double step = 0.5 * std::min(dz, texel_w);
            int unoccluded = 0;
            for_each_direction(n, opt, unsigned(i), [&](const glm::dvec3& d) {
                for (double t = step; t <= opt.radius_mm; t += step) {
                    const glm::dvec3 q = p + t * d;
                    if (glm::dot(n, q - p) <= beta) continue;
                    const double Dq = -q.z;
                    if (Dq <= 0) return;
                    const int x = int(std::floor((p00 * q.x / Dq * 0.5 + 0.5) * sm.width));
                    const int y = int(std::floor((p11 * q.y / Dq * 0.5 + 0.5) * sm.height));
                    const int b = int(std::floor((Dq - sm.z_near) / dz));
                    if (x < 0 || y < 0 || x >= sm.width || y >= sm.height || b < 0 || b >= sm.bits()) continue;
                    if (sm.bit(x, y, b)) return; // blocked
                }
                ++unoccluded;
            });
            return double(unoccluded) / double(opt.rays);
        });
}

} // namespace iso
