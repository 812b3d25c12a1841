// Picking benchmark: the latency of our pick, which rides on a
// frame (the frame's geometry passes list the pixel's fragments, then the
// pixel's ray meets the listed triangles in double precision), against
// VTK 9.1's vtkHardwareSelector (selection passes rendered for the pick) and
// vtkCellPicker (a CPU ray cast through a vtkCellLocator built once), on the
// same meshes, camera, image size and pixels, in the same run (VTK under
// xvfb-run through pick_peer). And what each returns: our visible layer
// (the first surface whose own opacity reaches 0.5, else the nearest: the
// bone through 0.3 skin, the front skin where no bone lies behind) and first layer, VTK's picked cell and point (the nearest surface,
// whatever its opacity), each against a double-precision ray cast of the
// written meshes (every crossing of the pixel centre's ray, the same
// opacity rule).
//
// Our times, per pick, alternating A/B so that drift cancels, each frame
// presented into an offscreen framebuffer and the GPU finished:
//   (a) the frame without a pick,
//   (b) the frame with the pick riding on it, to the resolved result
//       (the lists read back, the layers' exact points),
//   (c) = (b) - (a) of the same pair: what the pick adds to its frame;
//   (d) a click or hover in the 3D view: a frame that only picks (no image
//       output, so the graph culls lighting, the VOIT resolve and the
//       read-back), to the resolved result, against
//   (e) the same frame reading the colour image back, as the view's picks
//       did before;
// and core::pick (the API the CLI calls): the scene is uploaded and freed
// on each call, so it is not a per-pick latency of a live view.
// Also: frames in blocks all without or all with a pick (does switching
// cost anything?), and per-pass times (time_passes) without and with a pick
// (where the added cost goes).
//
//   pick_bench [--out DIR] [--sizes 512,1024] [--picks 20] [--reps 3] [--api-picks 5] [--pass-frames 8] [--seed 13] [--peer PATH]
// Prints markdown tables, writes pick_bench.csv and pick_latency.png in DIR.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "bench_util.hpp"
#include "io/error.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"

using namespace iso;

namespace {

struct Args {
    std::string out = "bench-results", peer = ISOSCOPE_PICK_PEER;
    std::vector<int> sizes{512, 1024};
    int picks = 20, reps = 3, api_picks = 5, pass_frames = 8, block_frames = 6, block_pairs = 3;
    unsigned seed = 13;
};

constexpr double kThreshold = 0.5; // the visible layer, as core::PickRequest's default
const char* const kSurfaceNames[] = {"skin", "bone"};

std::string surface_name(int s) { return s >= 0 && s < 2 ? kSurfaceNames[s] : s < 0 ? "none" : "?"; }

// ---- the double-precision reference ------------------------------------------

// The triangles of the written meshes, ready for the ray cast.
struct RefTriangle {
    glm::dvec3 a, e1, e2;
    int surface;
    std::uint32_t index;
};

struct Hit {
    double t = 0;
    int surface = -1;
    std::uint32_t triangle = 0;
    glm::dvec3 lps{0.0};
};

// Every crossing of the ray with the meshes, nearest first (ties by surface,
// then triangle, as the pick sorts); Möller-Trumbore in double precision.
std::vector<Hit> ray_cast(const std::vector<RefTriangle>& tris, const Ray& ray) {
    std::vector<Hit> hits;
    for (const auto& tr : tris) {
        const glm::dvec3 p = glm::cross(ray.dir, tr.e2);
        const double det = glm::dot(tr.e1, p);
        if (std::abs(det) < 1e-300) continue;
        const glm::dvec3 s = ray.origin - tr.a;
        const double u = glm::dot(s, p) / det;
        if (u < 0 || u > 1) continue;
        const glm::dvec3 q = glm::cross(s, tr.e1);
        const double v = glm::dot(ray.dir, q) / det;
        if (v < 0 || u + v > 1) continue;
        const double t = glm::dot(tr.e2, q) / det;
        if (t <= 0) continue;
        hits.push_back({t, tr.surface, tr.index, ray.origin + t * ray.dir});
    }
    std::sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) {
        return std::tie(x.t, x.surface, x.triangle) < std::tie(y.t, y.surface, y.triangle);
    });
    return hits;
}

// The visible crossing by the pick's rule: the first whose surface's own
// opacity reaches the threshold, else the first crossing; nothing behind an
// opaque one counts.
std::optional<Hit> visible_hit(const std::vector<Hit>& hits, const std::vector<float>& opacity) {
    for (const Hit& h : hits)
        if (opacity[std::size_t(h.surface)] >= kThreshold) return h;
    if (hits.empty()) return std::nullopt;
    return hits.front();
}

// ---- our pick, resolved as core::pick resolves it ------------------------------

struct Layer {
    int surface = -1;
    std::uint32_t triangle = 0;
    glm::dvec3 lps{0.0};
    bool on_triangle = true;
};
struct OurPick {
    std::vector<Layer> layers;
    std::optional<std::size_t> visible;
};

// Our pick as the core resolves it (core::resolve_pick: the pixel's ray
// meets each listed triangle in double precision), as the bench records it
// (surfaces 0-based).
OurPick resolve(const core::Scene& scene, const PickList& list, const Camera& cam, int x, int y, int size) {
    core::PickRequest p;
    p.x = x;
    p.y = y;
    p.threshold = kThreshold;
    const core::PickResult r = core::resolve_pick(scene, cam, size, size, list, p);
    OurPick out;
    out.visible = r.visible;
    for (const auto& l : r.layers) out.layers.push_back({int(l.surface) - 1, l.triangle, l.lps, l.on_triangle});
    return out;
}

// The point where the pixel's ray meets a triangle's plane (for the
// selector, which returns a cell and no point).
std::optional<glm::dvec3> ray_on_triangle(const Mesh& m, std::uint32_t k, const Ray& ray) {
    if (k >= m.triangles.size()) return std::nullopt;
    const auto& tri = m.triangles[k];
    const glm::dvec3 a(m.positions[tri[0]]), b(m.positions[tri[1]]), c(m.positions[tri[2]]);
    const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(ray.dir, e2);
    const double det = glm::dot(e1, p);
    if (!(std::abs(det) > 1e-300)) return std::nullopt;
    const glm::dvec3 q = glm::cross(ray.origin - a, e1);
    return ray.origin + (glm::dot(e2, q) / det) * ray.dir;
}

// ---- results ----------------------------------------------------------------------

struct PickRow {
    int x = 0, y = 0;
    std::vector<Hit> ref;
    std::optional<Hit> ref_visible;
    std::vector<double> a, b, c;                 // ms per repetition
    std::vector<double> click_only, click_image; // a click's frame without and with an image output (d, e)
    OurPick ours;
    std::optional<double> api_ms, api_frame_ms;
    std::optional<glm::dvec3> api_lps;
    int api_surface = -1;
    std::optional<std::uint32_t> api_triangle;
    // VTK
    double cp_ms = 0, sel_ms = 0; // medians over the repetitions
    std::vector<double> cp_all, sel_all;
    int cp_surface = -1, sel_surface = -1;
    long long cp_cell = -1, sel_cell = -1;
    std::optional<glm::dvec3> cp_point, sel_point;
};

// Median, quartiles (nearest rank) and extremes.
struct Stat {
    double median = 0, p25 = 0, p75 = 0, min = 0, max = 0;
    std::size_t n = 0;
};
Stat stat(std::vector<double> v) {
    Stat s;
    if (v.empty()) return s;
    s.median = bench::median(v);
    std::sort(v.begin(), v.end());
    const auto q = [&](double f) { return v[std::min(v.size() - 1, std::size_t(f * double(v.size())))]; };
    s.p25 = q(0.25);
    s.p75 = q(0.75);
    s.min = v.front();
    s.max = v.back();
    s.n = v.size();
    return s;
}

std::string v3(const glm::dvec3& v) {
    std::ostringstream s;
    s.precision(17);
    s << v.x << "," << v.y << "," << v.z;
    return s.str();
}

std::string fmt_lps(const glm::dvec3& v) {
    char b[96];
    std::snprintf(b, sizeof b, "(%.2f, %.2f, %.2f)", v.x, v.y, v.z);
    return b;
}

std::string fmt_ms(double v) {
    char b[32];
    std::snprintf(b, sizeof b, v < 1 ? "%.3f" : "%.2f", v);
    return b;
}

std::string fmt_dist(double d) {
    char b[32];
    if (d < 1e-3)
        std::snprintf(b, sizeof b, "%.1e", d);
    else
        std::snprintf(b, sizeof b, "%.3f", d);
    return b;
}

} // namespace

int main(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string s = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("pick_bench", s + " needs a value");
            return argv[++i];
        };
        try {
            if (s == "--out")
                a.out = next();
            else if (s == "--picks")
                a.picks = std::stoi(next());
            else if (s == "--reps")
                a.reps = std::stoi(next());
            else if (s == "--api-picks")
                a.api_picks = std::stoi(next());
            else if (s == "--pass-frames")
                a.pass_frames = std::stoi(next());
            else if (s == "--seed")
                a.seed = unsigned(std::stoul(next()));
            else if (s == "--peer")
                a.peer = next();
            else if (s == "--sizes") {
                a.sizes.clear();
                std::stringstream ss(next());
                for (std::string t; std::getline(ss, t, ',');) a.sizes.push_back(std::stoi(t));
            } else {
                std::cerr << "usage: pick_bench [--out DIR] [--sizes 512,1024] [--picks 20] [--reps 3] [--api-picks 5] "
                             "[--pass-frames 8] [--seed 13] [--peer PATH]\n";
                return 2;
            }
        } catch (const std::exception& e) {
            std::cerr << "pick_bench: " << e.what() << "\n";
            return 2;
        }
    }
    try {
        const double t_start = bench::now_s();
        std::filesystem::create_directories(a.out);
        // The scene: the bundled CT's skin (iso 500, opacity 0.3) over its bone (iso 1150, opaque).
        core::Scene scene;
        scene.open(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr");
        const auto ids = scene.add_isosurfaces({500, 1150});
        if (ids.size() != 2) throw Error("pick_bench", "expected two isosurfaces");
        scene.info(ids[0]).opacity = 0.3f;
        scene.info(ids[1]).opacity = 1.0f;
        const std::vector<float> opacity{0.3f, 1.0f};
        // The meshes as written for VTK, read back: the reference casts against these.
        std::vector<std::string> files;
        std::vector<Mesh> written;
        std::size_t triangles = 0;
        bool same_as_ours = true;
        for (std::size_t i = 0; i < ids.size(); ++i) {
            files.push_back(a.out + "/pick_" + kSurfaceNames[i] + ".ply");
            scene.export_mesh(ids[i], files.back());
            written.push_back(load_mesh(files.back()));
            const Mesh& m = scene.mesh(ids[i]);
            same_as_ours =
                same_as_ours && written.back().positions == m.positions && written.back().triangles == m.triangles;
            triangles += m.triangles.size();
        }
        std::vector<RefTriangle> ref_tris;
        for (std::size_t s = 0; s < written.size(); ++s)
            for (std::size_t k = 0; k < written[s].triangles.size(); ++k) {
                const auto& t = written[s].triangles[k];
                const glm::dvec3 p0(written[s].positions[t[0]]), p1(written[s].positions[t[1]]),
                    p2(written[s].positions[t[2]]);
                ref_tris.push_back({p0, p1 - p0, p2 - p0, int(s), std::uint32_t(k)});
            }

        gl::HeadlessContext ctx;
        ctx.make_current();
        std::string gl_renderer;
        std::ofstream csv(a.out + "/pick_bench.csv");
        csv << "size,x,y,method,ms,surface,triangle,lps_x,lps_y,lps_z,ref,ref_surface,ref_triangle,dist_ref_mm\n";
        csv.precision(10);
        struct SizeSummary {
            int size;
            std::vector<std::pair<std::string, Stat>> latency;
        };
        std::vector<SizeSummary> summaries;
        std::string vtk_renderer;
        for (const int S : a.sizes) {
            const Camera cam = scene.camera(PatientView::Anterior, 1.0);
            // Pick pixels: seeded random pixels whose ray meets the head (the reference decides).
            std::vector<PickRow> rows;
            std::mt19937 rng(a.seed + unsigned(S));
            std::uniform_int_distribution<int> coord(0, S - 1);
            for (int tries = 0; int(rows.size()) < a.picks && tries < 100000; ++tries) {
                PickRow r;
                r.x = coord(rng);
                r.y = coord(rng);
                r.ref = ray_cast(ref_tris, cam.pixel_ray(r.x + 0.5, r.y + 0.5, S, S));
                if (r.ref.empty()) continue;
                r.ref_visible = visible_hit(r.ref, opacity);
                rows.push_back(std::move(r));
            }
            if (rows.empty()) throw Error("pick_bench", "no pixel of the image sees the head");
            std::cerr << "[pick_bench] " << S << "x" << S << ": " << rows.size() << " pick pixels\n";
            // Ours at the renderer level: one renderer kept across the picks, frames presented offscreen.
            auto target = gl::Texture::create_2d(GL_RGBA8, S, S);
            auto fb = gl::Framebuffer::create();
            fb.attach(GL_COLOR_ATTACHMENT0, target);
            RenderOptions plain;
            plain.width = plain.height = S;
            plain.present = true;
            plain.target_framebuffer = fb.id();
            const auto frame = [&](const PickRow* p) {
                RenderOptions o = plain;
                if (p) o.pick = PickRegion{p->x, p->y, 1, 1};
                const double t0 = bench::now_s();
                RenderResult r = scene.render(cam, o);
                glFinish();
                OurPick picked;
                if (p) picked = resolve(scene, r.pick, cam, p->x, p->y, S);
                const double ms = 1000.0 * (bench::now_s() - t0);
                if (gl_renderer.empty()) gl_renderer = r.gl_renderer;
                return std::make_pair(ms, picked);
            };
            for (int w = 0; w < 2; ++w) frame(nullptr), frame(&rows[0]); // shaders compile, pools fill
            for (int rep = 0; rep < a.reps; ++rep)
                for (std::size_t i = 0; i < rows.size(); ++i) {
                    PickRow& r = rows[i];
                    double ta = 0, tb = 0;
                    if ((rep + i) % 2 == 0) {
                        ta = frame(nullptr).first;
                        auto [ms, p] = frame(&r);
                        tb = ms;
                        r.ours = p;
                    } else {
                        auto [ms, p] = frame(&r);
                        tb = ms;
                        r.ours = p;
                        ta = frame(nullptr).first;
                    }
                    r.a.push_back(ta);
                    r.b.push_back(tb);
                    r.c.push_back(tb - ta);
                }
            // A click or hover in the 3D view (core::pick_in_frame): a frame that only picks, whose graph culls
            // lighting, the VOIT resolve and the read-back (d), against the same frame reading the colour image
            // back as the view's picks did before (e); alternating, each to the resolved result.
            const auto click = [&](const PickRow& p, bool image) {
                RenderOptions o = plain;
                o.present = false;
                o.target_framebuffer = 0;
                o.image = image;
                o.pick = PickRegion{p.x, p.y, 1, 1};
                const double t0 = bench::now_s();
                const RenderResult r = scene.render(cam, o);
                resolve(scene, r.pick, cam, p.x, p.y, S);
                return 1000.0 * (bench::now_s() - t0);
            };
            for (int w = 0; w < 2; ++w) click(rows[0], true), click(rows[0], false);
            for (int rep = 0; rep < a.reps; ++rep)
                for (std::size_t i = 0; i < rows.size(); ++i) {
                    PickRow& r = rows[i];
                    const bool only_first = (rep + i) % 2 == 0;
                    const double first = click(r, !only_first), second = click(r, only_first);
                    r.click_only.push_back(only_first ? first : second);
                    r.click_image.push_back(only_first ? second : first);
                }
            // Toggling: in blocks of frames all without or all with a pick (a new pixel each, as hover picking would),
            // the first frame of a block follows a frame of the other kind; the rest follow their own kind.
            std::vector<double> steady_a, steady_b, toggle_a, toggle_b, created_toggle_a, created_toggle_b,
                created_steady;
            for (int block = 0; block < 2 * a.block_pairs; ++block) {
                const bool with = block % 2 == 1;
                for (int k = 0; k < a.block_frames; ++k) {
                    RenderOptions o = plain;
                    if (with)
                        o.pick = PickRegion{rows[std::size_t(k) % rows.size()].x, rows[std::size_t(k) % rows.size()].y,
                                            1, 1};
                    const double t0 = bench::now_s();
                    RenderResult r = scene.render(cam, o);
                    glFinish();
                    if (with) resolve(scene, r.pick, cam, o.pick->x, o.pick->y, S);
                    const double ms = 1000.0 * (bench::now_s() - t0);
                    const double created = double(r.stats.physical_resources);
                    if (block == 0) continue; // the first block follows the A/B loop's last frame
                    if (k == 0)
                        (with ? toggle_b : toggle_a).push_back(ms),
                            (with ? created_toggle_b : created_toggle_a).push_back(created);
                    else
                        (with ? steady_b : steady_a).push_back(ms), created_steady.push_back(created);
                }
            }
            // Where the pick's cost goes: per-pass times (glFinish after each pass), frames without and with a pick, alternating.
            std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> pass_ms;
            std::vector<std::string> pass_order;
            for (int k = 0; k < a.pass_frames; ++k)
                for (const bool with : {false, true}) {
                    RenderOptions o = plain;
                    o.time_passes = true;
                    if (with)
                        o.pick = PickRegion{rows[std::size_t(k) % rows.size()].x, rows[std::size_t(k) % rows.size()].y,
                                            1, 1};
                    const RenderResult r = scene.render(cam, o);
                    glFinish();
                    for (const auto& ps : r.stats.passes) {
                        if (!ps.ran) continue;
                        if (!pass_ms.count(ps.name)) pass_order.push_back(ps.name);
                        (with ? pass_ms[ps.name].second : pass_ms[ps.name].first).push_back(ps.ms);
                    }
                }
            // core::pick: through render_image (its own context; the scene's GPU copy is freed after each call).
            scene.release_gpu();
            for (int i = 0; i < std::min<int>(a.api_picks, int(rows.size())); ++i) {
                PickRow& r = rows[std::size_t(i)];
                core::RenderRequest req;
                req.width = req.height = S;
                req.view = "anterior";
                req.annotations = false;
                core::PickRequest p;
                p.x = r.x;
                p.y = r.y;
                p.threshold = kThreshold;
                const double t0 = bench::now_s();
                const core::PickResult res = core::pick(scene, req, p);
                r.api_ms = 1000.0 * (bench::now_s() - t0);
                r.api_frame_ms = res.frame_ms;
                if (res.visible) {
                    r.api_lps = res.layers[*res.visible].lps;
                    r.api_surface = int(res.layers[*res.visible].surface) - 1;
                    r.api_triangle = res.layers[*res.visible].triangle;
                }
            }
            ctx.make_current();
            // VTK through pick_peer.
            std::ostringstream cmd;
            cmd.precision(17);
            const std::string peer_log = a.out + "/pick_peer_" + std::to_string(S) + ".log";
            cmd << "xvfb-run -a -s '-screen 0 " << std::max(S + 64, 1280) << "x" << std::max(S + 64, 1024) << "x24' "
                << a.peer;
            for (std::size_t i = 0; i < files.size(); ++i)
                cmd << " --mesh " << files[i] << " --color " << v3(glm::dvec3(scene.info(ids[i]).color))
                    << " --opacity " << opacity[i];
            cmd << " --eye " << v3(cam.eye) << " --target " << v3(cam.target) << " --up " << v3(cam.up) << " --fov "
                << cam.fov_y_degrees << " --near " << cam.near_plane << " --far " << cam.far_plane << " --size " << S
                << "x" << S << " --background " << v3(glm::dvec3(plain.look.background)) << " --reps " << a.reps
                << " --frames 10";
            for (const auto& r : rows) cmd << " --pixel " << r.x << "," << r.y;
            cmd << " 2>" << peer_log;
            const std::string line = bench::capture(cmd.str());
            std::vector<double> vtk_frames;
            std::vector<double> locator_ms;
            bool have_vtk = false;
            try {
                const auto j = nlohmann::json::parse(line.substr(line.find('{')));
                vtk_frames = j.at("frame_ms_all").get<std::vector<double>>();
                locator_ms = j.at("locator_build_ms").get<std::vector<double>>();
                vtk_renderer = j.at("renderer").get<std::string>();
                const auto& picks = j.at("picks");
                if (picks.size() != rows.size())
                    throw Error("pick_bench", "pick_peer answered a different number of picks");
                for (std::size_t i = 0; i < rows.size(); ++i) {
                    PickRow& r = rows[i];
                    const auto& p = picks[i];
                    if (p.at("x").get<int>() != r.x || p.at("y").get<int>() != r.y)
                        throw Error("pick_bench", "pick_peer's pixels differ");
                    const Ray ray = cam.pixel_ray(r.x + 0.5, r.y + 0.5, S, S);
                    const auto& cp = p.at("cell_picker");
                    r.cp_ms = cp.at("ms").get<double>();
                    r.cp_all = cp.at("ms_all").get<std::vector<double>>();
                    r.cp_surface = cp.at("actor").get<int>();
                    r.cp_cell = cp.at("cell").get<long long>();
                    if (cp.at("hit").get<bool>()) {
                        const auto pt = cp.at("point").get<std::vector<double>>();
                        r.cp_point = glm::dvec3(pt[0], pt[1], pt[2]);
                    }
                    const auto& hs = p.at("selector");
                    r.sel_ms = hs.at("ms").get<double>();
                    r.sel_all = hs.at("ms_all").get<std::vector<double>>();
                    r.sel_surface = hs.at("actor").get<int>();
                    r.sel_cell = hs.at("cell").get<long long>();
                    if (r.sel_surface >= 0 && r.sel_cell >= 0)
                        r.sel_point =
                            ray_on_triangle(written[std::size_t(r.sel_surface)], std::uint32_t(r.sel_cell), ray);
                }
                have_vtk = true;
            } catch (const std::exception& e) {
                std::cerr << "[pick_bench] pick_peer failed (" << e.what() << "): " << line.substr(0, 300) << " (see "
                          << peer_log << ")\n";
            }

            // ---- latency table ----
            // Every sample: picks x repetitions (ours, the selector, the cell picker), frames (VTK's), calls (core::pick).
            std::vector<double> va, vb, vc, vd, ve, vapi, vapi_frame, vcp, vsel;
            for (const auto& r : rows) {
                vd.insert(vd.end(), r.click_only.begin(), r.click_only.end());
                ve.insert(ve.end(), r.click_image.begin(), r.click_image.end());
                va.insert(va.end(), r.a.begin(), r.a.end());
                vb.insert(vb.end(), r.b.begin(), r.b.end());
                vc.insert(vc.end(), r.c.begin(), r.c.end());
                if (r.api_ms) vapi.push_back(*r.api_ms), vapi_frame.push_back(*r.api_frame_ms);
                vcp.insert(vcp.end(), r.cp_all.begin(), r.cp_all.end());
                vsel.insert(vsel.end(), r.sel_all.begin(), r.sel_all.end());
            }
            SizeSummary sum{S, {}};
            sum.latency.push_back({"ours: frame, no pick (a)", stat(va)});
            sum.latency.push_back({"ours: frame with the pick riding on it, to the result (b)", stat(vb)});
            sum.latency.push_back({"ours: the pick's added cost, (b) - (a) of each pair", stat(vc)});
            sum.latency.push_back(
                {"ours: a click in the 3D view: a frame that only picks, to the result (d)", stat(vd)});
            sum.latency.push_back({"ours: the same click reading the colour image back, as before (e)", stat(ve)});
            sum.latency.push_back({"ours: core::pick (API; uploads the scene, a pick-only frame)", stat(vapi)});
            if (have_vtk) {
                sum.latency.push_back({"VTK: frame (Render + WaitForCompletion)", stat(vtk_frames)});
                sum.latency.push_back({"VTK: vtkHardwareSelector::Select, 1 px, cells", stat(vsel)});
                sum.latency.push_back({"VTK: vtkCellPicker::Pick (vtkCellLocator built once)", stat(vcp)});
            }
            std::printf("\n### Latency, %dx%d: %zu triangles, %zu picks x %d repetitions\n\n", S, S, triangles,
                        rows.size(), a.reps);
            std::printf("| method | samples | ms, median | p25 | p75 |\n|---|---:|---:|---:|---:|\n");
            for (const auto& [name, st] : sum.latency)
                if (st.n)
                    std::printf("| %s | %zu | %s | %s | %s |\n", name.c_str(), st.n, fmt_ms(st.median).c_str(),
                                fmt_ms(st.p25).c_str(), fmt_ms(st.p75).c_str());
            std::printf("\ncore::pick's own frame_ms (its pick-only frame): median %.1f ms\n", stat(vapi_frame).median);
            if (have_vtk)
                std::printf("VTK: vtkCellLocator builds %.1f ms (skin) and %.1f ms (bone), once, before the picks\n",
                            locator_ms.size() > 0 ? locator_ms[0] : 0.0, locator_ms.size() > 1 ? locator_ms[1] : 0.0);

            if (!steady_a.empty() && !steady_b.empty()) {
                std::printf("\nIn blocks of %d frames (%d blocks each, alternating): a frame after one of the same "
                            "kind, and the first after "
                            "one of the other kind (ms, median):\n\n",
                            a.block_frames, a.block_pairs);
                std::printf("| frame | after the same kind | first after the other kind | GPU resources created, first "
                            "frame |\n|---|---:|---:|---:|\n");
                std::printf("| no pick | %s | %s | %.0f |\n", fmt_ms(bench::median(steady_a)).c_str(),
                            fmt_ms(bench::median(toggle_a)).c_str(), bench::median(created_toggle_a));
                std::printf("| with a pick | %s | %s | %.0f |\n", fmt_ms(bench::median(steady_b)).c_str(),
                            fmt_ms(bench::median(toggle_b)).c_str(), bench::median(created_toggle_b));
                std::printf(
                    "\nsteady frames create %.0f resources (median); a pick in a run of picking frames adds %.2f ms\n",
                    bench::median(created_steady), bench::median(steady_b) - bench::median(steady_a));
                csv << S << ",-1,-1,steady_frame_no_pick," << bench::median(steady_a) << ",,,,,,,,,\n";
                csv << S << ",-1,-1,steady_frame_with_pick," << bench::median(steady_b) << ",,,,,,,,,\n";
                csv << S << ",-1,-1,toggle_frame_no_pick," << bench::median(toggle_a) << ",,,,,,,,,\n";
                csv << S << ",-1,-1,toggle_frame_with_pick," << bench::median(toggle_b) << ",,,,,,,,,\n";
            }
            if (!pass_order.empty()) {
                std::printf("\nPer pass (time_passes: glFinish after each pass), median of %d frames without and %d "
                            "with a pick:\n\n",
                            a.pass_frames, a.pass_frames);
                std::printf("| pass | ms, no pick | ms, with a pick |\n|---|---:|---:|\n");
                double sum0 = 0, sum1 = 0;
                for (const auto& name : pass_order) {
                    const auto& [v0, v1] = pass_ms[name];
                    const double m0 = bench::median(v0), m1 = bench::median(v1);
                    sum0 += m0;
                    sum1 += m1;
                    std::printf("| %s | %s | %s |\n", name.c_str(), v0.empty() ? "-" : fmt_ms(m0).c_str(),
                                v1.empty() ? "-" : fmt_ms(m1).c_str());
                }
                std::printf("| sum of medians | %.2f | %.2f |\n", sum0, sum1);
                for (const auto& name : pass_order) {
                    const auto& [v0, v1] = pass_ms[name];
                    if (!v0.empty())
                        csv << S << ",-1,-1,pass_no_pick:" << name << "," << bench::median(v0) << ",,,,,,,,,\n";
                    if (!v1.empty())
                        csv << S << ",-1,-1,pass_with_pick:" << name << "," << bench::median(v1) << ",,,,,,,,,\n";
                }
            }
            // ---- agreement ----
            struct Agree {
                std::string name, against;
                std::array<int, 3> returns{0, 0, 0}; // skin, bone, none
                int same_triangle = 0, compared = 0;
                std::vector<double> dist;
            };
            Agree ag_vis{"ours, visible layer (threshold 0.5)", "reference, visible crossing (same rule)"},
                ag_first{"ours, first layer", "reference, first crossing"},
                ag_api{"ours, core::pick visible layer", "reference, visible crossing (same rule)"},
                ag_cp{"vtkCellPicker point", "reference, first crossing"},
                ag_sel{"vtkHardwareSelector cell (ray meets it)", "reference, first crossing"};
            const auto tally = [](Agree& g, int surface, std::optional<std::uint32_t> tri, std::optional<glm::dvec3> p,
                                  const Hit* ref) {
                g.returns[surface >= 0 && surface < 2 ? std::size_t(surface) : 2]++;
                if (!ref || !p) return;
                ++g.compared;
                if (tri && surface == ref->surface && *tri == ref->triangle) ++g.same_triangle;
                g.dist.push_back(glm::length(*p - ref->lps));
            };
            std::vector<double> ours_vs_vtk;
            for (const auto& r : rows) {
                const Hit* first = r.ref.empty() ? nullptr : &r.ref.front();
                const Hit* ref_vis = r.ref_visible ? &*r.ref_visible : nullptr;
                const Layer* vis = r.ours.visible ? &r.ours.layers[*r.ours.visible] : nullptr;
                tally(ag_vis, vis ? vis->surface : -1, vis ? std::optional<std::uint32_t>(vis->triangle) : std::nullopt,
                      vis ? std::optional<glm::dvec3>(vis->lps) : std::nullopt, ref_vis);
                const Layer* fl = r.ours.layers.empty() ? nullptr : &r.ours.layers.front();
                tally(ag_first, fl ? fl->surface : -1, fl ? std::optional<std::uint32_t>(fl->triangle) : std::nullopt,
                      fl ? std::optional<glm::dvec3>(fl->lps) : std::nullopt, first);
                if (r.api_ms) tally(ag_api, r.api_surface, r.api_triangle, r.api_lps, ref_vis);
                if (have_vtk) {
                    tally(ag_cp, r.cp_point ? r.cp_surface : -1,
                          r.cp_cell >= 0 ? std::optional<std::uint32_t>(std::uint32_t(r.cp_cell)) : std::nullopt,
                          r.cp_point, first);
                    tally(ag_sel, r.sel_surface,
                          r.sel_cell >= 0 ? std::optional<std::uint32_t>(std::uint32_t(r.sel_cell)) : std::nullopt,
                          r.sel_point, first);
                    if (vis && r.cp_point) ours_vs_vtk.push_back(glm::length(vis->lps - *r.cp_point));
                }
            }
            std::printf("\n### What each returns, %dx%d, against a double-precision ray cast of the written meshes\n\n",
                        S, S);
            std::printf(
                "| method | against | skin / bone / none | same triangle | max distance mm | median distance mm |\n"
                "|---|---|---:|---:|---:|---:|\n");
            for (const Agree* g : {&ag_vis, &ag_first, &ag_api, &ag_cp, &ag_sel}) {
                if (g->returns[0] + g->returns[1] + g->returns[2] == 0) continue;
                const Stat d = stat(g->dist);
                std::printf("| %s | %s | %d / %d / %d | %d of %d | %s | %s |\n", g->name.c_str(), g->against.c_str(),
                            g->returns[0], g->returns[1], g->returns[2], g->same_triangle, g->compared,
                            d.n ? fmt_dist(d.max).c_str() : "-", d.n ? fmt_dist(d.median).c_str() : "-");
            }
            if (!ours_vs_vtk.empty()) {
                const Stat d = stat(ours_vs_vtk);
                std::printf("\nours (visible layer) to vtkCellPicker's point: median %.2f mm, min %.2f, max %.2f "
                            "(different surfaces: see below)\n",
                            d.median, d.min, d.max);
            }
            // ---- per pick ----
            std::printf("\n#### Per pick, %dx%d\n\n", S, S);
            std::printf(
                "| pixel | reference: first, visible | ours, visible: LPS mm | Δ ref | ours first Δ ref | "
                "vtkCellPicker: LPS mm | Δ ref "
                "first | ours to VTK mm | selector: surface, Δ ref first | ms (b) | (c) | selector | cell picker |\n"
                "|---|---|---|---:|---:|---|---:|---:|---|---:|---:|---:|---:|\n");
            for (const auto& r : rows) {
                const Hit* first = r.ref.empty() ? nullptr : &r.ref.front();
                const Layer* vis = r.ours.visible ? &r.ours.layers[*r.ours.visible] : nullptr;
                const Layer* fl = r.ours.layers.empty() ? nullptr : &r.ours.layers.front();
                std::printf("| %d,%d | %s, %s | %s %s | %s | %s | ", r.x, r.y,
                            first ? surface_name(first->surface).c_str() : "none",
                            r.ref_visible ? surface_name(r.ref_visible->surface).c_str() : "none",
                            vis ? surface_name(vis->surface).c_str() : "none", vis ? fmt_lps(vis->lps).c_str() : "",
                            vis && r.ref_visible ? fmt_dist(glm::length(vis->lps - r.ref_visible->lps)).c_str() : "-",
                            fl && first ? fmt_dist(glm::length(fl->lps - first->lps)).c_str() : "-");
                if (have_vtk)
                    std::printf("%s %s | %s | %s | %s, %s | ", surface_name(r.cp_point ? r.cp_surface : -1).c_str(),
                                r.cp_point ? fmt_lps(*r.cp_point).c_str() : "",
                                r.cp_point && first ? fmt_dist(glm::length(*r.cp_point - first->lps)).c_str() : "-",
                                r.cp_point && vis ? fmt_dist(glm::length(*r.cp_point - vis->lps)).c_str() : "-",
                                surface_name(r.sel_surface).c_str(),
                                r.sel_point && first ? fmt_dist(glm::length(*r.sel_point - first->lps)).c_str() : "-");
                else
                    std::printf("- | - | - | - | ");
                std::printf("%.1f | %.2f | %.1f | %.3f |\n", bench::median(r.b), bench::median(r.c), r.sel_ms, r.cp_ms);
            }

            // ---- CSV ----
            const auto row_out = [&](const PickRow& r, const std::string& method, std::optional<double> ms, int surface,
                                     std::optional<std::uint32_t> tri, std::optional<glm::dvec3> p, const char* against,
                                     const Hit* ref) {
                csv << S << "," << r.x << "," << r.y << "," << method << ",";
                if (ms) csv << *ms;
                csv << "," << (surface >= -1 ? surface_name(surface) : "") << ",";
                if (tri) csv << *tri;
                csv << ",";
                if (p)
                    csv << p->x << "," << p->y << "," << p->z;
                else
                    csv << ",,";
                csv << "," << against << ",";
                if (ref)
                    csv << surface_name(ref->surface) << "," << ref->triangle << ",";
                else
                    csv << ",,";
                if (ref && p) csv << glm::length(*p - ref->lps);
                csv << "\n";
            };
            for (const auto& r : rows) {
                const Hit* first = r.ref.empty() ? nullptr : &r.ref.front();
                const Hit* ref_vis = r.ref_visible ? &*r.ref_visible : nullptr;
                const Layer* vis = r.ours.visible ? &r.ours.layers[*r.ours.visible] : nullptr;
                const Layer* fl = r.ours.layers.empty() ? nullptr : &r.ours.layers.front();
                row_out(r, "ours_frame", bench::median(r.a), -2, std::nullopt, std::nullopt, "", nullptr);
                row_out(r, "ours_frame_with_pick", bench::median(r.b), vis ? vis->surface : -1,
                        vis ? std::optional<std::uint32_t>(vis->triangle) : std::nullopt,
                        vis ? std::optional<glm::dvec3>(vis->lps) : std::nullopt, "visible", ref_vis);
                row_out(r, "ours_pick_added", bench::median(r.c), -2, std::nullopt, std::nullopt, "", nullptr);
                row_out(r, "ours_first_layer", std::nullopt, fl ? fl->surface : -1,
                        fl ? std::optional<std::uint32_t>(fl->triangle) : std::nullopt,
                        fl ? std::optional<glm::dvec3>(fl->lps) : std::nullopt, "first", first);
                if (r.api_ms)
                    row_out(r, "ours_core_pick", *r.api_ms, r.api_surface, r.api_triangle, r.api_lps, "visible",
                            ref_vis);
                if (have_vtk) {
                    row_out(r, "vtk_hardware_selector", r.sel_ms, r.sel_surface,
                            r.sel_cell >= 0 ? std::optional<std::uint32_t>(std::uint32_t(r.sel_cell)) : std::nullopt,
                            r.sel_point, "first", first);
                    row_out(r, "vtk_cell_picker", r.cp_ms, r.cp_point ? r.cp_surface : -1,
                            r.cp_cell >= 0 ? std::optional<std::uint32_t>(std::uint32_t(r.cp_cell)) : std::nullopt,
                            r.cp_point, "first", first);
                }
            }
            if (have_vtk) csv << S << ",-1,-1,vtk_frame," << bench::median(vtk_frames) << ",,,,,,,,,\n";
            summaries.push_back(std::move(sum));
        }
        csv.close();
        std::printf("\nmeshes: %zu triangles, written and read back %s; ours: %s; VTK: %s; %.0f s in all\n", triangles,
                    same_as_ours ? "bit-identical" : "DIFFERENT (the reference uses the written ones)",
                    gl_renderer.c_str(), vtk_renderer.c_str(), bench::now_s() - t_start);

        // ---- plot: one group of bars per method, one bar per image size (median, IQR bars), log scale ----
        const char* const short_names[] = {
            "ours: frame (a)", "ours: frame + pick (b)", "ours: pick added (c)", "ours: core::pick",
            "VTK: frame",      "VTK: HW selector",       "VTK: cell picker"};
        std::ofstream gp(a.out + "/pick_latency.gp");
        gp << "set terminal pngcairo size 900,560\nset output '" << a.out << "/pick_latency.png'\n"
           << "set title 'Pick latency, head CT (skin 0.3 over bone); " << gl_renderer << "' noenhanced\n"
           << "set logscale y\nset yrange [0.05:*]\nset ylabel 'ms (median; bars: p25-p75; values below 0.05 drawn at "
              "0.05)'\n"
           << "set style data histogram\nset style histogram errorbars gap 1 lw 1\nset style fill solid 0.7 border -1\n"
           << "set xtics rotate by -25 noenhanced\nset grid ytics\nset key top left\nplot";
        for (std::size_t i = 0; i < summaries.size(); ++i)
            gp << (i ? "," : "") << " '-' using 2:3:4" << (i ? "" : ":xtic(1)") << " title '" << summaries[i].size
               << "x" << summaries[i].size << "'";
        gp << "\n";
        for (const auto& sm : summaries) {
            for (std::size_t k = 0; k < sm.latency.size() && k < 7; ++k) {
                const Stat& st = sm.latency[k].second;
                const auto c = [](double v) { return std::max(v, 0.05); };
                gp << "\"" << short_names[k] << "\" " << (st.n ? c(st.median) : 0.05) << " "
                   << (st.n ? c(st.p25) : 0.05) << " " << (st.n ? c(st.p75) : 0.05) << "\n";
            }
            gp << "e\n";
        }
        gp.close();
        if (std::system(("gnuplot " + a.out + "/pick_latency.gp").c_str()) == 0)
            std::printf("\nwrote %s/pick_latency.png\n", a.out.c_str());
    } catch (const std::exception& e) {
        std::cerr << "pick_bench: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
