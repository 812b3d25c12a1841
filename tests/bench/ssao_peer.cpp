// The peer for the AO benchmark: VTK 9.1's screen-space ambient occlusion
// (vtkSSAOPass) on the same meshes, camera and image size, read back as the
// raw AO factor. VTK renders through X here: run under xvfb-run.
//
//   ssao_peer --mesh a.ply [--mesh b.ply] --eye X,Y,Z --target X,Y,Z --up X,Y,Z --fov DEG
//             --near MM --far MM --size WxH --radius MM --bias MM --kernel N [--blur 0|1]
//             [--frames 20] [--warmup 3] --out ao.exr
// Prints one JSON line: median (and quartiles of) ms per frame with SSAO,
// and the median without it, on the same window.
//
// The AO term is isolated in the pixel by drawing white surfaces lit by
// ambient light only (ambient 1, diffuse 0, specular 0; a light stays on
// because the SSAO pass applies only where the mapper shades normals):
// vtkSSAOPass multiplies the shaded colour by its occlusion factor.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderer.h>
#include <vtkOutputWindow.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkRenderStepsPass.h>
#include <vtkRenderWindow.h>
#include <vtkSSAOPass.h>

#include "io/error.hpp"
#include "io/image.hpp"
#include "io/mesh.hpp"
#include "io/vtk_mesh.hpp"
#include "vtk_peer.hpp"

using iso::vtk_peer::quantile;
using iso::vtk_peer::vec3;

int main(int argc, char** argv) {
    std::vector<std::string> meshes;
    double eye[3], target[3], up[3], fov = 30, near_plane = 1, far_plane = 1000, radius = 0.5, bias = 0.01;
    bool have_eye = false, have_target = false, have_up = false;
    int W = 512, H = 512, kernel = 32, blur = 1, frames = 20, warmup = 3;
    std::string out;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::cerr << "ssao_peer: " << a << " needs a value\n";
            return 2;
        }
        const std::string v = argv[++i];
        if (a == "--mesh")
            meshes.push_back(v);
        else if (a == "--eye")
            have_eye = vec3(v, eye);
        else if (a == "--target")
            have_target = vec3(v, target);
        else if (a == "--up")
            have_up = vec3(v, up);
        else if (a == "--fov")
            fov = std::stod(v);
        else if (a == "--near")
            near_plane = std::stod(v);
        else if (a == "--far")
            far_plane = std::stod(v);
        else if (a == "--size") {
            if (std::sscanf(v.c_str(), "%dx%d", &W, &H) != 2 || W < 1 || H < 1) {
                std::cerr << "ssao_peer: --size: expected WxH, got '" << v << "'\n";
                return 2;
            }
        } else if (a == "--radius")
            radius = std::stod(v);
        else if (a == "--bias")
            bias = std::stod(v);
        else if (a == "--kernel")
            kernel = std::stoi(v);
        else if (a == "--blur")
            blur = std::stoi(v);
        else if (a == "--frames")
            frames = std::stoi(v);
        else if (a == "--warmup")
            warmup = std::stoi(v);
        else if (a == "--out")
            out = v;
        else {
            std::cerr << "ssao_peer: unknown option " << a << "\n";
            return 2;
        }
    }
    if (meshes.empty() || !have_eye || !have_target || !have_up || out.empty()) {
        std::cerr << "ssao_peer: needs --mesh, --eye, --target, --up and --out\n";
        return 2;
    }
    try {
        vtkOutputWindow::GetInstance()->SetDisplayModeToAlwaysStdErr();
        vtkNew<vtkOpenGLRenderer> ren;
        ren->SetBackground(0, 0, 0);
        for (const auto& path : meshes) {
            const iso::Mesh m = iso::load_mesh(path);
            auto pd = iso::to_polydata(m, false);
            vtkNew<vtkPolyDataNormals> normals;
            normals->SetInputData(pd);
            normals->SplittingOff();
            normals->ConsistencyOn();
            vtkNew<vtkPolyDataMapper> mapper;
            mapper->SetInputConnection(normals->GetOutputPort());
            mapper->ScalarVisibilityOff();
            vtkNew<vtkActor> actor;
            actor->SetMapper(mapper);
            actor->GetProperty()->SetColor(1, 1, 1);
            actor->GetProperty()->SetAmbient(1.0);
            actor->GetProperty()->SetDiffuse(0.0);
            actor->GetProperty()->SetSpecular(0.0);
            ren->AddActor(actor);
        }
        vtkCamera* cam = ren->GetActiveCamera();
        cam->SetPosition(eye);
        cam->SetFocalPoint(target);
        cam->SetViewUp(up);
        cam->SetViewAngle(fov);
        cam->SetClippingRange(near_plane, far_plane);
        vtkNew<vtkRenderWindow> win;
        win->SetMultiSamples(0);
        win->SetSize(W, H);
        win->AddRenderer(ren);
        win->SetOffScreenRendering(1);

        vtkNew<vtkRenderStepsPass> basic;
        vtkNew<vtkSSAOPass> ssao;
        ssao->SetDelegatePass(basic);
        ssao->SetRadius(radius);
        ssao->SetBias(bias);
        ssao->SetKernelSize(static_cast<unsigned>(kernel));
        ssao->SetBlur(blur != 0);

        using clock = std::chrono::steady_clock;
        auto time_frames = [&](int n) {
            std::vector<double> ms;
            for (int f = 0; f < n; ++f) {
                cam->SetClippingRange(near_plane, far_plane);
                const auto t0 = clock::now();
                win->Render();
                win->WaitForCompletion();
                ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
            }
            return ms;
        };
        // Alternate with and without SSAO so machine drift cancels.
        std::vector<double> with, without;
        ren->SetPass(ssao);
        time_frames(warmup);
        ren->SetPass(basic);
        time_frames(warmup);
        for (int round = 0; round < 2; ++round) {
            ren->SetPass(ssao);
            const auto a = time_frames((frames + 1) / 2);
            with.insert(with.end(), a.begin(), a.end());
            ren->SetPass(basic);
            const auto b = time_frames((frames + 1) / 2);
            without.insert(without.end(), b.begin(), b.end());
        }
        ren->SetPass(ssao);
        cam->SetClippingRange(near_plane, far_plane);
        win->Render();
        win->WaitForCompletion();
        int* sz = win->GetSize();
        if (sz[0] != W || sz[1] != H)
            throw iso::Error("ssao_peer", "window is " + std::to_string(sz[0]) + "x" + std::to_string(sz[1]));
        vtkNew<vtkFloatArray> rgba;
        win->GetRGBAPixelData(0, 0, W - 1, H - 1, 0, rgba, 0);
        std::vector<float> z(std::size_t(W) * std::size_t(H));
        win->GetZbufferData(0, 0, W - 1, H - 1, z.data());
        iso::Image img;
        img.width = W;
        img.height = H;
        img.channels = 1;
        img.is_float = true;
        img.floats.resize(std::size_t(W) * std::size_t(H));
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const std::size_t src = std::size_t(y) * std::size_t(W) + std::size_t(x); // bottom-up
                const std::size_t dst = std::size_t(H - 1 - y) * std::size_t(W) + std::size_t(x);
                img.floats[dst] =
                    z[src] >= 1.0f ? std::numeric_limits<float>::quiet_NaN() : rgba->GetValue(vtkIdType(src * 4));
            }
        iso::save_image(img, out);
        const std::string renderer = iso::vtk_peer::renderer_name(win);
        std::printf("{\"ms_median\": %.4f, \"ms_p25\": %.4f, \"ms_p75\": %.4f, \"ms_plain_median\": %.4f, "
                    "\"renderer\": \"%s\", "
                    "\"width\": %d, \"height\": %d, \"kernel\": %d, \"radius\": %.9g, \"bias\": %.9g, \"blur\": %d}\n",
                    quantile(with), quantile(with, 0.25), quantile(with, 0.75), quantile(without), renderer.c_str(), W,
                    H, kernel, radius, bias, blur);
    } catch (const std::exception& e) {
        std::cerr << "ssao_peer: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
