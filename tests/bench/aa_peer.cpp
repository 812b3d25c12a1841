#include "aa_peer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <unistd.h>

#include "bench_util.hpp"
#include "io/color.hpp"
#include "io/error.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"

namespace iso::bench {

namespace {

std::string v3(const glm::dvec3& v) {
    std::ostringstream s;
    s.precision(17);
    s << v.x << "," << v.y << "," << v.z;
    return s.str();
}

std::string work_folder(const std::string& asked) {
    static int serial = 0;
    const std::filesystem::path dir =
        asked.empty() ? std::filesystem::temp_directory_path() /
                            ("aa_peer-" + std::to_string(::getpid()) + "-" + std::to_string(serial++))
                      : std::filesystem::path(asked);
    std::filesystem::create_directories(dir);
    return dir.string();
}

// The scene's part of aa_peer_vtk's command line: meshes (written to `dir`
// unless given as files), colours, opacities, camera, size, background.
std::string scene_arguments(const std::vector<PeerMesh>& meshes, const Camera& cam, int W, int H,
                            const AaPeerOptions& opt, const std::string& dir) {
    std::ostringstream cmd;
    cmd.precision(17);
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        std::string file = meshes[i].file;
        if (file.empty()) {
            if (!meshes[i].mesh) throw Error("render_vtk_aa", "mesh " + std::to_string(i) + " has no mesh and no file");
            file = dir + "/mesh" + std::to_string(i) + ".ply";
            save_mesh(*meshes[i].mesh, file);
        }
        cmd << " --mesh '" << file << "' --color " << v3(glm::dvec3(meshes[i].color)) << " --opacity "
            << meshes[i].opacity;
    }
    cmd << " --eye " << v3(cam.eye) << " --target " << v3(cam.target) << " --up " << v3(cam.up) << " --fov "
        << cam.fov_y_degrees << " --near " << cam.near_plane << " --far " << cam.far_plane << " --size " << W << "x"
        << H << " --background " << v3(glm::dvec3(opt.background)) << " --flat " << (opt.flat ? 1 : 0) << " --peel "
        << (opt.depth_peeling ? 1 : 0);
    return cmd.str();
}

PeerImage peer_image(const nlohmann::json& j) {
    PeerImage p;
    p.name = j.at("config").get<std::string>();
    p.image = load_image(j.at("png").get<std::string>());
    p.ms = j.at("ms_median").get<double>();
    p.ms_p25 = j.at("ms_p25").get<double>();
    p.ms_p75 = j.at("ms_p75").get<double>();
    p.samples_asked = j.at("samples_asked").get<int>();
    p.samples_window = j.at("samples_window").get<int>();
    p.peeled = j.at("peeled").get<bool>();
    p.renderer = j.at("renderer").get<std::string>();
    return p;
}

} // namespace

std::vector<PeerImage> render_vtk_aa(const std::vector<PeerMesh>& meshes, const Camera& cam, int W, int H, int reps,
                                     const AaPeerOptions& opt, std::vector<std::string>* failed) {
    if (meshes.empty()) throw Error("render_vtk_aa", "no meshes");
    const std::string dir = work_folder(opt.work_dir);
    // A folder of our own goes when done (a large mesh written as PLY is hundreds of MiB); the caller's stays.
    struct Cleanup {
        std::string dir;
        ~Cleanup() {
            std::error_code ec;
            if (!dir.empty()) std::filesystem::remove_all(dir, ec);
        }
    } cleanup{opt.work_dir.empty() ? dir : std::string()};
    const std::string scene = scene_arguments(meshes, cam, W, H, opt, dir);
    const std::string peer = opt.peer.empty() ? std::string(ISOSCOPE_AA_PEER) : opt.peer;
    std::vector<PeerImage> out;
    // One process per configuration: a setting that crashes VTK takes only itself down.
    for (const auto& config : opt.configs) {
        // An X screen that holds the window, as the other peers' (the reference's is `factor` times larger).
        const int f = config == "reference" ? opt.reference_factor : 1;
        std::ostringstream cmd;
        cmd << "xvfb-run -a -s '-screen 0 " << std::max(W * f + 64, 1280) << "x" << std::max(H * f + 64, 1024)
            << "x24' '" << peer << "'" << scene << " --configs " << config << " --factor " << opt.reference_factor
            << " --reps " << std::max(1, reps) << " --warmup " << opt.warmup << " --out '" << dir << "' 2>'" << dir
            << "/" << config << ".log'";
        const std::string text = capture(cmd.str());
        std::string why;
        try {
            const auto brace = text.find('{');
            if (brace == std::string::npos) throw Error(config, "no result");
            const auto j = nlohmann::json::parse(text.substr(brace, text.find('\n', brace) - brace));
            if (j.contains("error")) throw Error(config, j.at("error").get<std::string>());
            out.push_back(peer_image(j));
        } catch (const std::exception& e) {
            std::ifstream log(dir + "/" + config + ".log");
            std::stringstream err;
            err << log.rdbuf();
            why = config + ": " + e.what() + "; stdout: " + text + "; stderr: " + err.str().substr(0, 2000);
        }
        if (!why.empty() && failed) failed->push_back(why);
        if (!why.empty() && !failed) throw Error("render_vtk_aa", why);
    }
    const PeerImage* none = nullptr;
    for (const auto& p : out)
        if (p.name == "none") none = &p;
    for (auto& p : out)
        if (none && p.image.bytes.size() == none->image.bytes.size()) {
            p.differ_from_none = 0;
            for (std::size_t i = 0; i < p.image.bytes.size(); i += 4)
                p.differ_from_none += !std::equal(p.image.bytes.begin() + std::ptrdiff_t(i),
                                                  p.image.bytes.begin() + std::ptrdiff_t(i + 3),
                                                  none->image.bytes.begin() + std::ptrdiff_t(i));
        }
    return out;
}

namespace {

// Pixels that are not the background (by more than 2/255 in a channel): the coverage mask.
std::vector<bool> covered(const Image& img, glm::vec3 background_linear) {
    const glm::ivec3 bg(int(std::lround(srgb_from_linear(background_linear.r) * 255)),
                        int(std::lround(srgb_from_linear(background_linear.g) * 255)),
                        int(std::lround(srgb_from_linear(background_linear.b) * 255)));
    std::vector<bool> m(std::size_t(img.width) * std::size_t(img.height));
    for (std::size_t p = 0; p < m.size(); ++p) {
        const std::uint8_t* px = &img.bytes[p * std::size_t(img.channels)];
        m[p] = std::abs(px[0] - bg.r) > 2 || std::abs(px[1] - bg.g) > 2 || std::abs(px[2] - bg.b) > 2;
    }
    return m;
}

} // namespace

CameraCheck check_camera(const Mesh& mesh, const Camera& cam, int W, int H, const std::string& work_dir) {
    // Ours: flat (albedo only), no AO, no annotations; the planes fitted to the mesh as render_image does.
    core::Scene scene;
    core::SurfaceInfo info;
    info.name = "camera check";
    info.color = {0.9f, 0.6f, 0.3f};
    scene.add_mesh(mesh, info);
    core::RenderRequest req;
    req.camera = cam;
    req.width = W;
    req.height = H;
    req.look.flat_shading = true;
    req.annotations = false;
    const core::RenderOutput ours = core::render_image(scene, req);
    AaPeerOptions opt;
    opt.configs = {"none"};
    opt.flat = true;
    opt.warmup = 0;
    opt.background = req.look.background;
    opt.work_dir = work_dir;
    const auto vtk = render_vtk_aa({{&mesh, info.color, 1.0f, ""}}, ours.camera, W, H, 1, opt);
    CameraCheck c;
    c.ours_image = ours.image;
    c.vtk_image = vtk.at(0).image;
    const auto a = covered(c.ours_image, opt.background), b = covered(c.vtk_image, opt.background);
    std::size_t both = 0, either = 0;
    for (std::size_t p = 0; p < a.size(); ++p) {
        c.ours += a[p];
        c.vtk += b[p];
        c.disagree += a[p] != b[p];
        both += a[p] && b[p];
        either += a[p] || b[p];
    }
    c.pixels = a.size();
    c.agreement = 1.0 - double(c.disagree) / double(std::max<std::size_t>(c.pixels, 1));
    c.iou = either ? double(both) / double(either) : 1.0;
    c.ok = c.agreement > 0.99;
    return c;
}

} // namespace iso::bench
