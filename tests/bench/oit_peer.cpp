// The peer for the transparency benchmark: VTK 9.1 drawing the same meshes,
// colours, opacities, camera and image size with its weighted-blended OIT
// (its default for translucent geometry) or dual depth peeling (a number of
// peels, 0 = until converged). Flat shading as ours: ambient 1, diffuse 0,
// specular 0, so a fragment is its colour. VTK blends the colours it is
// given in framebuffer space: they are passed linear, and the image is read
// back linear (8 bits). VTK renders through X here: run under xvfb-run.
//
//   oit_peer --mesh a.ply --color R,G,B --opacity A [--mesh ... ...] --eye X,Y,Z --target X,Y,Z --up X,Y,Z
//            --fov DEG --near MM --far MM --size WxH --background R,G,B --mode wboit|peel [--peels N]
//            [--frames 10] [--warmup 2] --out image.png
// Prints one JSON line: median and quartiles of ms per frame, the renderer.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkUnsignedCharArray.h>

#include "io/image.hpp"
#include "vtk_peer.hpp"

using iso::vtk_peer::quantile;

int main(int argc, char** argv) {
    iso::vtk_peer::Scene sc;
    int peels = 4, frames = 10, warmup = 2;
    std::string mode = "wboit", out;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::cerr << "oit_peer: " << a << " needs a value\n";
            return 2;
        }
        const std::string v = argv[++i];
        bool ok = true;
        if (!sc.option(a, v, ok)) {
            if (a == "--mode")
                ok = (mode = v, v == "wboit" || v == "peel");
            else if (a == "--peels")
                peels = std::stoi(v);
            else if (a == "--frames")
                frames = std::stoi(v);
            else if (a == "--warmup")
                warmup = std::stoi(v);
            else if (a == "--out")
                out = v;
            else
                ok = false;
        }
        if (!ok) {
            std::cerr << "oit_peer: bad option " << a << " " << v << "\n";
            return 2;
        }
    }
    if (sc.surfaces.empty() || out.empty()) {
        std::cerr << "oit_peer: needs --mesh and --out\n";
        return 2;
    }
    const int W = sc.W, H = sc.H;
    try {
        vtkOutputWindow::GetInstance()->SetDisplayModeToAlwaysStdErr();
        const auto view = iso::vtk_peer::make_view(sc);
        for (const auto& actor : view->actors) { // flat: a fragment is its colour
            auto* p = actor->GetProperty();
            p->SetAmbient(1.0);
            p->SetDiffuse(0.0);
            p->SetSpecular(0.0);
            p->BackfaceCullingOff();
        }
        vtkOpenGLRenderer* ren = view->ren;
        if (mode == "peel") {
            ren->SetUseDepthPeeling(true);
            ren->SetMaximumNumberOfPeels(peels);
            ren->SetOcclusionRatio(0.0);
        } else {
            ren->SetUseDepthPeeling(false);
            // VTK 9.1 draws translucent geometry with its weighted-blended
            // OIT pass (McGuire and Bavoil) whenever depth peeling is off.
        }
        vtkRenderWindow* win = view->win;
        const std::vector<double> ms = iso::vtk_peer::timed_frames(*view, sc, warmup, frames, "oit_peer");
        vtkNew<vtkUnsignedCharArray> rgb;
        win->GetPixelData(0, 0, W - 1, H - 1, 0, rgb, 0);
        iso::Image img;
        img.width = W;
        img.height = H;
        img.channels = 4;
        img.bytes.resize(std::size_t(W) * std::size_t(H) * 4);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const std::size_t src = (std::size_t(y) * std::size_t(W) + std::size_t(x)) * 3; // bottom-up
                const std::size_t dst = (std::size_t(H - 1 - y) * std::size_t(W) + std::size_t(x)) * 4;
                for (int c = 0; c < 3; ++c)
                    img.bytes[dst + std::size_t(c)] = rgb->GetValue(vtkIdType(src + std::size_t(c)));
                img.bytes[dst + 3] = 255;
            }
        iso::save_image(img, out);
        const std::string renderer = iso::vtk_peer::renderer_name(win);
        std::printf("{\"ms_median\": %.4f, \"ms_p25\": %.4f, \"ms_p75\": %.4f, \"renderer\": \"%s\", \"mode\": \"%s\", "
                    "\"peels\": %d}\n",
                    quantile(ms, 0.5), quantile(ms, 0.25), quantile(ms, 0.75), renderer.c_str(), mode.c_str(), peels);
    } catch (const std::exception& e) {
        std::cerr << "oit_peer: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
