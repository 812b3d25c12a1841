// The VTK program behind tests/bench/aa_peer.hpp: VTK 9.1 drawing the same
// meshes (linear RGB colours, opacities), camera and image size with each of
// its anti-aliasing settings, and its own reference for them, the same scene
// drawn `factor` times larger in each direction and box-filtered down in
// linear light. VTK renders through X here (Debian's VTK 9.1 has no EGL):
// run under xvfb-run.
//
//   aa_peer_vtk --mesh a.ply --color R,G,B --opacity A [--mesh ...] --eye X,Y,Z --target X,Y,Z --up X,Y,Z
//               --fov DEG --near MM --far MM --size WxH --background R,G,B
//               [--configs none,fxaa,msaa4,msaa8,reference] [--factor 8] [--reps 5] [--warmup 2] [--flat 0|1]
//               [--peel 1|0] --out DIR
//
// Writes DIR/<config>.png (RGBA8, sRGB, rows from the top, as iso::Image)
// and prints one JSON line per configuration: the median and quartiles of
// ms per frame (Render, WaitForCompletion and the read-back of the pixels),
// the samples the window asked for and has, whether depth peeling drew the
// translucent surfaces (--peel 1, the default: converged dual depth peeling,
// as oit_peer's reference; --peel 0: VTK's weighted-blended OIT), the renderer.
//
// Colour: VTK shades the colours it is given (linear RGB, as ours) and blends
// and resolves multisamples in its framebuffer, which offscreen is plain
// RGBA8: the pixels read back are linear light, 8 bits, and are encoded to
// sRGB here (so the darks carry 8-bit linear quantisation: up to 13/255 in
// sRGB below linear 1/255; the reference averages it away). Measured with
// VTK 9.1 under Xvfb (llvmpipe): a flat colour 0.9, 0.6, 0.3 and the
// background 0.08, 0.09, 0.11 read back as 230, 153, 76 and 20, 23, 28, also
// with UseSRGBColorSpace on (GetUsingSRGBColorSpace then says true, of the
// X window's visual, not of the framebuffer drawn into), so it is not asked
// for. The background's alpha reads 0 (alpha bit planes); the images are
// written opaque, as ours.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkUnsignedCharArray.h>

#include "io/color.hpp"
#include "io/image.hpp"
#include "vtk_peer.hpp"

using iso::vtk_peer::quantile;

namespace {

struct Args {
    iso::vtk_peer::Scene sc;
    std::vector<std::string> configs{"none", "fxaa", "msaa4", "msaa8", "reference"};
    int factor = 8, reps = 5, warmup = 2;
    bool flat = false, peel = true;
    std::string out;
};

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> v;
    std::stringstream in(s);
    for (std::string t; std::getline(in, t, ',');)
        if (!t.empty()) v.push_back(t);
    return v;
}

bool parse(int argc, char** argv, Args& a) {
    for (int i = 1; i < argc; ++i) {
        const std::string k = argv[i];
        if (i + 1 >= argc) {
            std::cerr << "aa_peer_vtk: " << k << " needs a value\n";
            return false;
        }
        const std::string v = argv[++i];
        bool ok = true;
        if (a.sc.option(k, v, ok)) {
        } else if (k == "--configs") {
            a.configs = split(v);
        } else if (k == "--factor") {
            a.factor = std::stoi(v);
            ok = a.factor >= 1 && a.factor <= 16;
        } else if (k == "--reps") {
            a.reps = std::max(1, std::stoi(v));
        } else if (k == "--warmup") {
            a.warmup = std::max(0, std::stoi(v));
        } else if (k == "--flat") {
            a.flat = v == "1";
        } else if (k == "--peel") {
            a.peel = v == "1";
        } else if (k == "--out") {
            a.out = v;
        } else {
            ok = false;
        }
        if (!ok) {
            std::cerr << "aa_peer_vtk: bad option " << k << " " << v << "\n";
            return false;
        }
    }
    if (a.sc.surfaces.empty() || a.out.empty()) {
        std::cerr << "aa_peer_vtk: needs --mesh and --out\n";
        return false;
    }
    return true;
}

// One configuration: its multisamples, FXAA, and the factor its window is larger by.
struct Config {
    std::string name;
    int samples = 0, factor = 1;
    bool fxaa = false;
};

Config config(const std::string& name, int reference_factor) {
    Config c{name};
    if (name == "fxaa")
        c.fxaa = true;
    else if (name.rfind("msaa", 0) == 0)
        c.samples = std::stoi(name.substr(4));
    else if (name == "reference")
        c.factor = reference_factor;
    else if (name != "none")
        throw iso::Error("aa_peer_vtk", "unknown configuration '" + name + "'");
    return c;
}

// The pixels of the window's framebuffer, RGBA8 from the top row.
std::vector<unsigned char> read_back(vtkRenderWindow* win, int w, int h) {
    vtkNew<vtkUnsignedCharArray> rgba;
    win->GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, rgba, 0);
    std::vector<unsigned char> px(std::size_t(w) * std::size_t(h) * 4);
    for (int y = 0; y < h; ++y) // GL rows run bottom-up
        std::copy_n(rgba->GetPointer(0) + std::size_t(y) * std::size_t(w) * 4, std::size_t(w) * 4,
                    px.data() + std::size_t(h - 1 - y) * std::size_t(w) * 4);
    return px;
}

// `px` (w x h, linear light) box-filtered by `f` into an opaque sRGB image of w/f x h/f.
iso::Image downsample(const std::vector<unsigned char>& px, int w, int h, int f) {
    iso::Image img;
    img.width = w / f;
    img.height = h / f;
    img.channels = 4;
    img.bytes.resize(std::size_t(img.width) * std::size_t(img.height) * 4);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int j = 0; j < f; ++j)
                    for (int i = 0; i < f; ++i) {
                        const unsigned char v =
                            px[(std::size_t(y * f + j) * std::size_t(w) + std::size_t(x * f + i)) * 4 + std::size_t(c)];
                        sum += v / 255.0;
                    }
                const double enc = iso::srgb_from_linear(sum / double(f * f));
                auto* out = &img.bytes[(std::size_t(y) * std::size_t(img.width) + std::size_t(x)) * 4];
                out[c] = static_cast<unsigned char>(std::lround(std::clamp(enc, 0.0, 1.0) * 255.0));
                out[3] = 255;
            }
    return img;
}

struct Result {
    iso::Image image;
    std::vector<double> ms;
    int samples_asked = 0, samples_window = 0;
    bool peeled = false;
    std::string renderer;
};

// Draws the scene once per frame with configuration `c`, warm-up frames
// first; each timed frame is Render, WaitForCompletion and the read-back.
Result render(const Args& a, const Config& c) {
    iso::vtk_peer::Scene sc = a.sc;
    sc.W *= c.factor;
    sc.H *= c.factor;
    const auto view = iso::vtk_peer::make_view(sc);
    bool translucent = false;
    for (std::size_t i = 0; i < view->actors.size(); ++i) {
        auto* p = view->actors[i]->GetProperty();
        translucent = translucent || sc.surfaces[i].opacity < 1;
        if (!a.flat) continue;
        p->SetAmbient(1.0); // flat: a fragment is its colour (the camera check)
        p->SetDiffuse(0.0);
        p->SetSpecular(0.0);
    }
    vtkOpenGLRenderer* ren = view->ren;
    if (translucent && a.peel) { // converged dual depth peeling, as oit_peer's reference
        ren->SetUseDepthPeeling(true);
        ren->SetMaximumNumberOfPeels(100);
        ren->SetOcclusionRatio(0.0);
    }
    ren->SetUseFXAA(c.fxaa);
    vtkRenderWindow* win = view->win;
    win->SetMultiSamples(c.samples);
    Result r;
    std::vector<unsigned char> px;
    using clock = std::chrono::steady_clock;
    for (int f = 0; f < a.warmup + a.reps; ++f) {
        view->cam->SetClippingRange(sc.near_plane, sc.far_plane);
        const auto t0 = clock::now();
        win->Render();
        win->WaitForCompletion();
        px = read_back(win, sc.W, sc.H);
        if (f >= a.warmup) r.ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
    }
    const int* size = win->GetSize();
    if (size[0] != sc.W || size[1] != sc.H)
        throw iso::Error("aa_peer_vtk " + c.name, "the window is " + std::to_string(size[0]) + "x" +
                                                      std::to_string(size[1]) + ", not the " + std::to_string(sc.W) +
                                                      "x" + std::to_string(sc.H) + " asked for");
    r.samples_asked = c.samples;
    r.samples_window = win->GetMultiSamples();
    r.peeled = ren->GetLastRenderingUsedDepthPeeling();
    r.renderer = iso::vtk_peer::renderer_name(win);
    r.image = downsample(px, sc.W, sc.H, c.factor);
    return r;
}

} // namespace

int main(int argc, char** argv) {
    Args a;
    if (!parse(argc, argv, a)) return 2;
    try {
        vtkOutputWindow::GetInstance()->SetDisplayModeToAlwaysStdErr();
        for (const auto& name : a.configs) {
            const Config c = config(name, a.factor);
            Result r;
            try {
                r = render(a, c);
            } catch (const std::exception& e) { // the others may still draw
                std::printf("{\"config\": \"%s\", \"error\": \"%s\"}\n", name.c_str(), e.what());
                std::fflush(stdout);
                continue;
            }
            const std::string png = a.out + "/" + name + ".png";
            iso::save_image(r.image, png);
            std::printf("{\"config\": \"%s\", \"ms_median\": %.4f, \"ms_p25\": %.4f, \"ms_p75\": %.4f, "
                        "\"samples_asked\": %d, \"samples_window\": %d, \"fxaa\": %s, \"factor\": %d, "
                        "\"peeled\": %s, \"renderer\": \"%s\", \"png\": \"%s\"}\n",
                        name.c_str(), quantile(r.ms, 0.5), quantile(r.ms, 0.25), quantile(r.ms, 0.75), r.samples_asked,
                        r.samples_window, c.fxaa ? "true" : "false", c.factor, r.peeled ? "true" : "false",
                        r.renderer.c_str(), png.c_str());
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::cerr << "aa_peer_vtk: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
