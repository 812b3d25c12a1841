// isoscope command-line interface. Parses arguments, calls the core API,
// prints. No algorithms live here.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include <filesystem>

#include "io/atomic_file.hpp"
#include <QApplication>
#include <QImage>
#include <QSurfaceFormat>
#include <QTimer>

#include "app/gui/viewer.hpp"
#include "renderer/core/api.hpp"

namespace {

std::string human_bytes(double b) {
    const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int u = 0;
    while (b >= 1024.0 && u < 4) { b /= 1024.0; ++u; }
    std::ostringstream os;
    os << std::fixed << std::setprecision(u ? 1 : 0) << b << ' ' << unit[u];
    return os.str();
}

void print_info(const nlohmann::json& j, std::ostream& os) {
    os << "source:    " << j["source"].get<std::string>() << "\n";
    os << "format:    " << j["format"].get<std::string>() << " (" << j["storage"].get<std::string>() << ")\n";
    os << "dims:      " << j["dims"][0] << " x " << j["dims"][1] << " x " << j["dims"][2] << "\n";
    os << "type:      " << j["type"].get<std::string>() << "\n";
    os << std::setprecision(6);
    os << "spacing:   " << j["spacing"][0].get<double>() << " x " << j["spacing"][1].get<double>() << " x "
       << j["spacing"][2].get<double>() << " mm\n";
    os << "range:     [" << j["range"][0].get<double>() << ", " << j["range"][1].get<double>() << "]\n";
    os << "memory:    " << human_bytes(j["memory_bytes"].get<double>()) << "\n";
    os << "index -> LPS (mm):\n";
    for (const auto& row : j["index_to_lps"]) {
        os << "  ";
        for (const auto& x : row) os << std::setw(12) << std::fixed << std::setprecision(5) << x.get<double>() << ' ';
        os << "\n";
    }
    os << std::defaultfloat;
    const auto& m = j["metadata"];
    for (const char* key : {"modality", "patient_name", "patient_id", "series_uid", "series_description"})
        if (!m[key].get<std::string>().empty()) os << key << ": " << m[key].get<std::string>() << "\n";
    if (j.contains("series")) {
        os << "series in " << j["source"].get<std::string>() << ":\n";
        int i = 0;
        for (const auto& s : j["series"]) {
            os << (i == j["selected_series"].get<int>() ? " *" : "  ") << "[" << i << "] "
               << s["modality"].get<std::string>() << " #" << s["number"] << " " << s["dims"][0] << "x"
               << s["dims"][1] << "x" << s["dims"][2] << " (" << s["files"] << " files) "
               << s["description"].get<std::string>() << "  " << s["uid"].get<std::string>() << "\n";
            ++i;
        }
    }
    for (const auto& w : j["warnings"]) os << "warning: " << w.get<std::string>() << "\n";
}

// A progress bar on stderr when it is a terminal; silent otherwise.
iso::ProgressFn progress_bar() {
    if (!isatty(STDERR_FILENO)) return {};
    return [last = -1](double f, std::string_view stage) mutable {
        int pct = static_cast<int>(f * 100.0 + 0.5);
        if (pct == last) return true;
        last = pct;
        const int width = 30, filled = pct * width / 100;
        std::fprintf(stderr, "\r%-24.*s [%.*s%*s] %3d%%", static_cast<int>(stage.size()), stage.data(), filled,
                     "##############################", width - filled, "", pct);
        if (pct >= 100) std::fputc('\n', stderr);
        std::fflush(stderr);
        return true;
    };
}

// The core names operations and settings in its errors; on the command line
// they are flags.
std::string cli_message(const iso::Error& e) {
    static const std::pair<std::string, std::string> flags[] = {
        {"patient view", "--view"},
        {"AOV", "--aov"},
        {"ao AOV", "--aov ao"},
        {"ambient occlusion", "--ao"},
        {"ambient occlusion reference", "--ao reference"},
        {"ambient occlusion frames", "--ao-frames"},
        {"smoothing factor", "--smooth"},
        {"decimation fraction", "--decimate"},
    };
    std::string where = e.where();
    const std::string cone = "cone AO setting ";
    if (where.rfind(cone, 0) == 0) where = "--ao-" + where.substr(cone.size());
    for (const auto& [core, flag] : flags)
        if (where == core) where = flag;
    return where.empty() ? e.reason() : where + ": " + e.reason();
}

// Opens the input of `render` and `view`: a mesh, or a volume and its
// isosurfaces (--iso required).
void open_input(iso::core::Scene& scene, const std::string& input, const std::string& series, const std::vector<double>& isos,
                const std::string& command) {
    iso::LoadOptions lo;
    lo.series = series;
    lo.progress = progress_bar();
    scene.open(input, lo);
    if (!scene.has_volume()) return;
    for (const auto& w : scene.volume().meta.warnings) std::cerr << "warning: " << w << "\n";
    if (isos.empty()) throw iso::Error("isoscope " + command, input + " is a volume: give --iso V (repeatable)");
    for (const auto id : scene.add_isosurfaces(isos, {}, {}, progress_bar()))
        for (const auto& w : scene.mesh(id).warnings) std::cerr << "warning: " << scene.info(id).name << ": " << w << "\n";
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"isoscope: inspect CT volumes, reconstruct and render isosurfaces"};
    app.set_version_flag("--version", std::string("isoscope ") + iso::core::version());
    app.require_subcommand(1);

    std::string info_path, info_series;
    bool info_json = false;
    auto* info = app.add_subcommand("info", "Describe a volume: dimensions, type, spacing, range, index->LPS affine");
    info->add_option("path", info_path, "Volume file or DICOM folder")->required();
    info->add_option("--series", info_series, "DICOM series to load: index in the listing or SeriesInstanceUID");
    info->add_flag("--json", info_json, "Print one JSON object");

    std::string mesh_in, mesh_out, mesh_series;
    std::vector<double> mesh_isos, mesh_label_values;
    bool mesh_labels = false;
    iso::PostProcessOptions post;
    int mesh_threads = 0, mesh_chunk = 32;
    auto* mesh = app.add_subcommand("mesh", "Extract isosurfaces (or label surfaces) and write them in LPS mm");
    mesh->add_option("input", mesh_in, "Volume file or DICOM folder")->required();
    mesh->add_option("--iso", mesh_isos, "Iso value (repeat for several surfaces, e.g. --iso -500 --iso 300)")
        ->allow_extra_args(false);
    mesh->add_flag("--labels", mesh_labels, "Label map: one surface per label");
    mesh->add_option("--label", mesh_label_values, "With --labels: only these labels (repeatable)")
        ->allow_extra_args(false);
    mesh->add_option("--smooth", post.smooth, "Windowed-sinc smoothing factor, 0..1 (Slicer's scale)")->check(CLI::Range(0.0, 1.0));
    mesh->add_option("--decimate", post.decimate, "Fraction of triangles to remove, 0..<1")->check(CLI::Range(0.0, 0.999));
    mesh->add_flag("--largest", post.keep_largest, "Keep only the largest connected component");
    mesh->add_option("--series", mesh_series, "DICOM series to load: index or SeriesInstanceUID");
    mesh->add_option("--threads", mesh_threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
    mesh->add_option("--chunk", mesh_chunk, "Chunk size in cells per side")->check(CLI::Range(2, 1024));
    mesh->add_option("-o,--output", mesh_out, "Output .stl, .ply, .obj or .vtp (several surfaces: NAME-iso<V>.ext)")->required();

    // Cone-AO tunables, shared by `render` and `view`.
    auto add_cone_options = [](CLI::App* cmd, iso::ConeAoSettings& c) {
        cmd->add_option("--ao-cones", c.cones, "Cones over the hemisphere (cone AO)")->check(CLI::Range(1, 64));
        cmd->add_option("--ao-spheres", c.spheres, "Spheres per cone (cone AO)")->check(CLI::Range(1, 32));
        cmd->add_option("--ao-samples", c.samples, "Poisson-disk columns per sphere (cone AO)")->check(CLI::Range(1, 64));
        cmd->add_option("--ao-strength", c.strength, "AO = 1 - strength * occlusion (cone AO)")->check(CLI::Range(0.0, 4.0));
        cmd->add_option("--ao-layers", c.layers, "Slicemap depth: 128 z-voxels per layer, 1..8 (cone AO)")->check(CLI::Range(1, 8));
        cmd->add_option("--ao-grid", c.grid_scale, "Slicemap texels per image pixel, 0.125..2 (cone AO)")->check(CLI::Range(0.125, 2.0));
        cmd->add_option("--ao-jitter", c.jitter_sets, "Jitter distributions chosen per pixel by a screen hash (cone AO)")
            ->check(CLI::Range(1, 64));
        cmd->add_option("--ao-persistence", c.persistence,
                        "Sphere combination along a cone: 0 independent absorbers, 1 one solid (cone AO)")
            ->check(CLI::Range(0.0, 1.0));
        cmd->add_option("--ao-ray-weight", c.ray_weight,
                        "Sphere occlusion: 0 occupied volume fraction, 1 blocked-ray fraction of a cutting plane (cone AO)")
            ->check(CLI::Range(0.0, 1.0));
        cmd->add_option("--ao-resolution", c.resolution,
                        "Cone-pass pixels per image pixel, 0.25..1; below 1 a bilateral upsampling follows (cone AO)")
            ->check(CLI::Range(0.25, 1.0));
        cmd->add_option("--ao-guard", c.guard,
                        "Largest guard band around the view, fraction of the viewport per side, for occluders just off screen; 0 none (cone AO)")
            ->check(CLI::Range(0.0, 0.5));
    };

    std::string r_in, r_out, r_view = "anterior", r_size = "1024x1024", r_aov, r_series;
    std::vector<double> r_isos;
    float r_scale = 1.0f;
    bool r_stats = false, r_no_annotations = false, r_transparent = false;
    auto* render = app.add_subcommand("render", "Render surfaces of a volume (or a mesh) to an annotated image");
    render->add_option("input", r_in, "Volume file, DICOM folder, or mesh (.stl .ply .obj .vtp)")->required();
    render->add_option("--iso", r_isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    render->add_option("--view", r_view, "anterior, posterior, left, right, superior or inferior");
    render->add_option("--size", r_size, "Image size WxH (default 1024x1024)");
    render->add_option("--scale", r_scale, "Scale of text, lines and glyphs (e.g. 2 for a 2x export)")->check(CLI::Range(0.1, 20.0));
    render->add_option("--aov", r_aov, "Write a buffer instead of the colour image: depth, normal, id or ao (EXR)");
    std::string r_ao = "off";
    double r_ao_radius = 10.0;
    int r_ao_rays = 1024;
    iso::ConeAoSettings r_cone;
    int r_ao_frames = 1;
    std::string r_cache;
    render->add_option("--ao", r_ao, "Ambient occlusion: off, cone (cone tracing), or reference (Embree ray tracing; with --aov ao)");
    render->add_option("--ao-radius", r_ao_radius, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    render->add_option("--ao-rays", r_ao_rays, "Rays per pixel for --ao reference")->check(CLI::Range(1, 1 << 20));
    add_cone_options(render, r_cone);
    render->add_option("--ao-frames", r_ao_frames, "Still frames accumulated with new jitter sets (cone AO)")->check(CLI::Range(1, 4096));
    render->add_option("--ao-cache", r_cache, "Folder caching AO references ('-': none; default ~/.cache/isoscope)");
    render->add_flag("--no-annotations", r_no_annotations, "No scale bar, orientation letters or labels");
    render->add_flag("--transparent", r_transparent, "Transparent background");
    render->add_flag("--stats", r_stats, "Print per-pass statistics");
    render->add_option("--series", r_series, "DICOM series to load: index or SeriesInstanceUID");
    render->add_option("-o,--output", r_out, "Output .png, .tif or .exr")->required();

    std::string v_in, v_view = "anterior", v_shot, v_series;
    std::vector<double> v_isos;
    auto* view = app.add_subcommand("view", "Open a window showing the surfaces (mouse: orbit, pan, zoom; keys a p l r s i: views)");
    view->add_option("input", v_in, "Volume file, DICOM folder, or mesh")->required();
    view->add_option("--iso", v_isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    view->add_option("--view", v_view, "Initial view: anterior, posterior, left, right, superior or inferior");
    view->add_option("--series", v_series, "DICOM series to load: index or SeriesInstanceUID");
    view->add_option("--screenshot", v_shot, "Save the first converged frame to this PNG and quit (tests)");
    std::string v_ao = "cone";
    iso::gui::ViewerOptions v_opt;
    view->add_option("--ao", v_ao, "Ambient occlusion: cone (default) or off; key O toggles it")->check(CLI::IsMember({"cone", "off"}));
    view->add_option("--ao-radius", v_opt.cone.radius_mm, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    add_cone_options(view, v_opt.cone);
    view->add_option("--ao-frames", v_opt.still_frames, "Still frames accumulated with new jitter sets while nothing moves")
        ->check(CLI::Range(1, 4096));

    CLI11_PARSE(app, argc, argv);

    try {
        if (*info) {
            iso::LoadOptions opt;
            opt.series = info_series;
            opt.progress = progress_bar();
            const auto v = iso::core::open_volume(info_path, opt);
            const auto j = iso::core::describe(v);
            if (info_json)
                std::cout << j.dump(2) << "\n";
            else
                print_info(j, std::cout);
        }
        if (*mesh) {
            if (mesh_isos.empty() && !mesh_labels) throw iso::Error("isoscope mesh", "give --iso V (repeatable) or --labels");
            if (!mesh_isos.empty() && mesh_labels) throw iso::Error("isoscope mesh", "--iso and --labels exclude each other");
            namespace fs = std::filesystem;
            const fs::path out(mesh_out);
            if (!iso::is_mesh_path(mesh_out))
                throw iso::Error(mesh_out, "unsupported mesh format (write " + iso::mesh_extensions_text() + ")");
            iso::check_writable_destination(mesh_out); // fail before the long part
            iso::LoadOptions lo;
            lo.series = mesh_series;
            lo.progress = progress_bar();
            iso::core::Scene scene;
            if (scene.open(mesh_in, lo) != 0) throw iso::Error(mesh_in, "is a mesh; isoscope mesh extracts surfaces from volumes");
            for (const auto& w : scene.volume().meta.warnings) std::cerr << "warning: " << w << "\n";
            iso::ExtractOptions eo;
            eo.threads = mesh_threads;
            eo.chunk_size = mesh_chunk;
            const auto ids = mesh_labels ? scene.add_label_surfaces(mesh_label_values, eo, post, progress_bar())
                                         : scene.add_isosurfaces(mesh_isos, eo, post, progress_bar());
            const std::string ext = out.extension().string();
            for (const auto id : ids) {
                const auto& s = scene.info(id);
                std::string path = mesh_out;
                if (ids.size() > 1) {
                    char suffix[64];
                    std::snprintf(suffix, sizeof suffix, mesh_labels ? "-label%g" : "-iso%g", s.value);
                    path = (out.parent_path() / (out.stem().string() + suffix + ext)).string();
                }
                const auto& m = scene.mesh(id);
                for (const auto& w : m.warnings) std::cerr << "warning: " << s.name << ": " << w << "\n";
                scene.export_mesh(id, path);
                const auto st = iso::mesh_stats(m);
                std::cout << s.name << ": " << st.triangles << " triangles, " << st.vertices << " vertices, area "
                          << st.area << " mm^2, volume " << st.volume << " mm^3 -> " << path << "\n";
            }
        }
        if (*view) {
            const auto initial = iso::patient_view_from_name(v_view);
            iso::validate(v_opt.cone); // before the long part
            iso::core::Scene scene;
            open_input(scene, v_in, v_series, v_isos, "view");
            QSurfaceFormat fmt;
            fmt.setVersion(4, 5);
            fmt.setProfile(QSurfaceFormat::CoreProfile);
            fmt.setDepthBufferSize(24);
            QSurfaceFormat::setDefaultFormat(fmt);
            int qargc = 1;
            char* qargv[] = {argv[0], nullptr};
            QApplication qapp(qargc, qargv);
            v_opt.ao = v_ao == "cone";
            iso::gui::Viewer w(scene, initial, v_opt);
            w.setWindowTitle(QString::fromStdString("isoscope - " + v_in));
            w.resize(800, 600);
            w.show();
            if (!v_shot.empty()) {
                // Grab once the picture has converged (the first frame without
                // AO; all still frames with it), then quit.
                QTimer poll;
                QObject::connect(&poll, &QTimer::timeout, [&] {
                    if (!w.converged()) return;
                    poll.stop();
                    if (!w.grabFramebuffer().save(QString::fromStdString(v_shot))) {
                        std::cerr << "isoscope: error: " << v_shot << ": cannot save the screenshot\n";
                        qapp.exit(1);
                        return;
                    }
                    qapp.exit(0);
                });
                poll.start(50);
                return qapp.exec();
            }
            return qapp.exec();
        }
        if (*render) {
            iso::core::RenderRequest req;
            req.isos = r_isos;
            req.series = r_series;
            req.view = r_view;
            if (std::sscanf(r_size.c_str(), "%dx%d", &req.width, &req.height) != 2 || req.width < 1 || req.height < 1)
                throw iso::Error("--size", "expected WxH, e.g. 1920x1080, got '" + r_size + "'");
            req.scale = r_scale;
            req.aov_ao = r_aov == "ao";
            req.aov = req.aov_ao ? iso::Aov::None : iso::aov_from_name(r_aov);
            req.ao = r_ao;
            req.ao_radius_mm = r_ao_radius;
            req.ao_rays = r_ao_rays;
            req.cone = r_cone;
            req.ao_frames = r_ao_frames;
            req.cache_dir = r_cache;
            req.annotations = !r_no_annotations;
            req.transparent = r_transparent;
            req.time_passes = r_stats;
            req.progress = progress_bar();
            iso::check_writable_destination(r_out);
            iso::core::Scene scene;
            open_input(scene, r_in, r_series, r_isos, "render");
            const auto out = iso::core::render_image(scene, req);
            iso::core::export_image(out.image, out.meta, r_out);
            std::cout << "rendered " << out.image.width << "x" << out.image.height << " (" << out.gl_renderer << ") -> " << r_out << "\n";
            if (r_stats) {
                std::cout << std::left << std::setw(12) << "pass" << std::setw(8) << "ran" << std::setw(12) << "ms" << "created\n";
                double total = 0;
                for (const auto& p : out.stats.passes) {
                    std::cout << std::setw(12) << p.name << std::setw(8) << (p.ran ? "yes" : "culled") << std::setw(12) << std::fixed
                              << std::setprecision(2) << p.ms << human_bytes(double(p.bytes_created)) << "\n";
                    total += p.ms;
                }
                std::cout << "total " << total << " ms; " << out.stats.physical_resources << " textures, peak "
                          << human_bytes(double(out.stats.peak_bytes)) << "\n";
            }
        }
    } catch (const iso::Error& e) {
        std::cerr << "isoscope: error: " << cli_message(e) << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "isoscope: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
