#include "tests/support/transparency_reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "io/error.hpp"

namespace iso {

double srgb_encode(double c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055; }

namespace {

struct Hit {
    float t;
    unsigned geom, prim;
};

// The context the intersection filter records into (Embree passes the
// context pointer it was given, so it can be extended).
struct CollectContext {
    RTCIntersectContext base;
    std::vector<Hit>* hits;
};

void collect(const RTCFilterFunctionNArguments* args) {
    auto* ctx = reinterpret_cast<CollectContext*>(args->context);
    // Embree's accessors take non-const pointers; they only read here.
    auto* ray = const_cast<RTCRayN*>(args->ray);
    auto* hit = const_cast<RTCHitN*>(args->hit);
    ctx->hits->push_back(
        {RTCRayN_tfar(ray, args->N, 0), RTCHitN_geomID(hit, args->N, 0), RTCHitN_primID(hit, args->N, 0)});
    args->valid[0] = 0; // reject: the ray goes on to the next surface
}

struct Scene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    ~Scene() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

} // namespace

TransparencyImage transparency_reference(const std::vector<ReferenceSurface>& surfaces, const Camera& camera, int width,
                                         int height, const glm::dvec3& background, int threads) {
    if (width < 1 || height < 1) throw Error("transparency_reference", "empty image");
    Scene s;
    s.device = rtcNewDevice(nullptr);
    if (!s.device) throw Error("Embree", "cannot create a device");
    s.scene = rtcNewScene(s.device);
    rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION | RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_HIGH);
    std::vector<unsigned> surface_of_geom;
    for (std::size_t si = 0; si < surfaces.size(); ++si) {
        const Mesh* m = surfaces[si].mesh;
        if (!m || m->triangles.empty()) continue;
        RTCGeometry g = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), m->positions.size()));
        std::memcpy(v, m->positions.data(), m->positions.size() * 3 * sizeof(float));
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), m->triangles.size()));
        std::memcpy(idx, m->triangles.data(), m->triangles.size() * 3 * sizeof(unsigned));
        rtcCommitGeometry(g);
        const unsigned id = rtcAttachGeometry(s.scene, g);
        rtcReleaseGeometry(g);
        if (surface_of_geom.size() <= id) surface_of_geom.resize(id + 1);
        surface_of_geom[id] = unsigned(si);
    }
    rtcCommitScene(s.scene);
    if (rtcGetDeviceError(s.device) != RTC_ERROR_NONE) throw Error("Embree", "building the scene failed");

    TransparencyImage out;
    out.width = width;
    out.height = height;
    const std::size_t n = std::size_t(width) * std::size_t(height);
    out.linear.assign(n, background);
    out.foreground.assign(n, 0);
    out.hits.assign(n, 0);
    const glm::dvec3 forward = camera.forward();
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(0, height, [&](int py) {
            std::vector<Hit> hits;
            for (int px = 0; px < width; ++px) {
                const glm::dvec3 dir = camera.pixel_ray(px + 0.5, py + 0.5, width, height).dir;
                RTCRayHit rh{};
                rh.ray.org_x = float(camera.eye.x);
                rh.ray.org_y = float(camera.eye.y);
                rh.ray.org_z = float(camera.eye.z);
                rh.ray.dir_x = float(dir.x);
                rh.ray.dir_y = float(dir.y);
                rh.ray.dir_z = float(dir.z);
                rh.ray.tnear = 0.0f;
                rh.ray.tfar = std::numeric_limits<float>::infinity();
                rh.ray.mask = 0xFFFFFFFFu;
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                hits.clear();
                CollectContext ctx;
                rtcInitIntersectContext(&ctx.base);
                ctx.base.filter = collect;
                ctx.hits = &hits;
                rtcIntersect1(s.scene, &ctx.base, &rh);
                // Clip to the near and far planes along the view axis.
                const double axial = glm::dot(dir, forward);
                std::erase_if(hits, [&](const Hit& h) {
                    const double d = double(h.t) * axial;
                    return d < camera.near_plane || d > camera.far_plane;
                });
                std::sort(hits.begin(), hits.end(), [](const Hit& p, const Hit& q) {
                    if (p.t != q.t) return p.t < q.t;
                    if (p.geom != q.geom) return p.geom < q.geom;
                    return p.prim < q.prim;
                });
                // A ray through a shared edge or vertex can report both
                // triangles of one crossing: keep one hit per surface there.
                hits.erase(std::unique(hits.begin(), hits.end(),
                                       [](const Hit& p, const Hit& q) {
                                           return p.geom == q.geom && std::abs(double(p.t) - double(q.t)) <=
                                                                          1e-6 * std::max(1.0, double(p.t));
                                       }),
                           hits.end());
                const std::size_t i = std::size_t(py) * std::size_t(width) + std::size_t(px);
                if (hits.empty()) continue;
                out.foreground[i] = 1;
                out.hits[i] = std::uint32_t(hits.size());
                glm::dvec3 c(0.0);
                double T = 1.0;
                for (const Hit& h : hits) {
                    const ReferenceSurface& srf = surfaces[surface_of_geom[h.geom]];
                    const double alpha = std::clamp(double(srf.opacity), 0.0, 1.0);
                    c += T * alpha * glm::dvec3(srf.color);
                    T *= 1.0 - alpha;
                    if (T == 0.0) break;
                }
                out.linear[i] = c + T * background;
            }
        });
    });
    return out;
}

} // namespace iso
