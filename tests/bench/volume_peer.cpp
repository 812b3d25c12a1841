// The VTK program behind tests/bench/volume_bench.cpp: VTK 9.1's
// vtkGPUVolumeRayCastMapper drawing the benchmark's volume (raw int16, its
// index -> LPS placement as origin, spacing and direction matrix), transfer
// function, camera and image size, composite, unshaded, one image per sample
// distance asked for, then frames of a rotation. VTK renders through X here
// (Debian's VTK 9.1 has no EGL): run under xvfb-run.
//
//   volume_peer --raw F --dims X,Y,Z --origin X,Y,Z --spacing X,Y,Z --direction D00,...,D22
//               --tf "v,a,r,g,b;..." --eye X,Y,Z --target X,Y,Z --up X,Y,Z --fov DEG --near MM --far MM
//               --size WxH --background R,G,B --steps MM,MM,... [--reps 5] [--warmup 2]
//               [--rotate FRAMES] [--rotate-step MM] [--rotate-degrees 10] --out DIR
//
// The transfer function's colours are given in linear RGB (the benchmark
// converts its sRGB points): VTK interpolates between the points in the
// space it is given and blends in its RGBA8 framebuffer without any sRGB
// conversion, so linear colours make its compositing the stated model's
// (emission-absorption in linear light); the pixels read back are linear
// light in 8 bits and are encoded to sRGB here (aa_peer_vtk.cpp measured
// that VTK 9.1 offscreen under Xvfb writes the values it blends as they are).
// Opacity: VTK's scalar opacity is per SetScalarOpacityUnitDistance, set to
// 1 mm, so a point's opacity is per mm as ours.
//
// A still frame is timed as Render, WaitForCompletion and the read-back of
// the pixels; rotation frames without the read-back.
// Prints one JSON line per step ({"step_mm", "ms_median", "ms_p25",
// "ms_p75", "png", "renderer", "direction_honoured"}) and, with --rotate, one
// for the rotation at --rotate-step with AutoAdjustSampleDistances off and
// one with VTK's interactive setting (AutoAdjustSampleDistances on, the
// window's desired update rate 15 frames/s, as vtkRenderWindowInteractor
// asks while the user drags).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <vtkCamera.h>
#include <vtkColorTransferFunction.h>
#include <vtkGPUVolumeRayCastMapper.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderer.h>
#include <vtkOutputWindow.h>
#include <vtkPiecewiseFunction.h>
#include <vtkPointData.h>
#include <vtkRenderWindow.h>
#include <vtkShortArray.h>
#include <vtkUnsignedCharArray.h>
#include <vtkVolume.h>
#include <vtkVolumeProperty.h>

#include "io/color.hpp"
#include "io/image.hpp"
#include "vtk_peer.hpp"

using iso::vtk_peer::quantile;

namespace {

struct Args {
    std::string raw, out;
    int dims[3] = {0, 0, 0};
    double origin[3] = {0, 0, 0}, spacing[3] = {1, 1, 1}, direction[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::vector<std::vector<double>> tf; // value, opacity, r, g, b (linear)
    double eye[3] = {0, 0, 0}, target[3] = {0, 0, 0}, up[3] = {0, 0, 1}, background[3] = {0, 0, 0};
    double fov = 30, near_plane = 1, far_plane = 1000, rotate_step = 1, rotate_degrees = 10;
    int W = 512, H = 512, reps = 5, warmup = 2, rotate = 0;
    std::vector<double> steps;
};

std::vector<double> numbers(const std::string& s, char sep = ',') {
    std::vector<double> v;
    std::stringstream in(s);
    for (std::string t; std::getline(in, t, sep);)
        if (!t.empty()) v.push_back(std::stod(t));
    return v;
}

bool fill(const std::string& s, double* out, std::size_t n) {
    const auto v = numbers(s);
    if (v.size() != n) return false;
    std::copy(v.begin(), v.end(), out);
    return true;
}

bool option(Args& a, const std::string& k, const std::string& v) {
    if (k == "--raw")
        a.raw = v;
    else if (k == "--out")
        a.out = v;
    else if (k == "--dims") {
        double d[3];
        if (!fill(v, d, 3)) return false;
        for (int i = 0; i < 3; ++i) a.dims[i] = int(d[i]);
    } else if (k == "--origin")
        return fill(v, a.origin, 3);
    else if (k == "--spacing")
        return fill(v, a.spacing, 3);
    else if (k == "--direction")
        return fill(v, a.direction, 9);
    else if (k == "--tf") {
        std::stringstream in(v);
        for (std::string p; std::getline(in, p, ';');) {
            a.tf.push_back(numbers(p));
            if (a.tf.back().size() != 5) return false;
        }
    } else if (k == "--eye")
        return fill(v, a.eye, 3);
    else if (k == "--target")
        return fill(v, a.target, 3);
    else if (k == "--up")
        return fill(v, a.up, 3);
    else if (k == "--background")
        return fill(v, a.background, 3);
    else if (k == "--fov")
        a.fov = std::stod(v);
    else if (k == "--near")
        a.near_plane = std::stod(v);
    else if (k == "--far")
        a.far_plane = std::stod(v);
    else if (k == "--size")
        return std::sscanf(v.c_str(), "%dx%d", &a.W, &a.H) == 2 && a.W > 0 && a.H > 0;
    else if (k == "--steps")
        a.steps = numbers(v);
    else if (k == "--reps")
        a.reps = std::max(1, std::stoi(v));
    else if (k == "--warmup")
        a.warmup = std::max(0, std::stoi(v));
    else if (k == "--rotate")
        a.rotate = std::max(0, std::stoi(v));
    else if (k == "--rotate-step")
        a.rotate_step = std::stod(v);
    else if (k == "--rotate-degrees")
        a.rotate_degrees = std::stod(v);
    else
        return false;
    return true;
}

// The window's pixels (linear light, 8 bits) as an opaque sRGB image from the top row.
iso::Image read_back(vtkRenderWindow* win, int w, int h) {
    vtkNew<vtkUnsignedCharArray> rgba;
    win->GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, rgba, 0);
    iso::Image img;
    img.width = w;
    img.height = h;
    img.channels = 4;
    img.bytes.resize(std::size_t(w) * std::size_t(h) * 4);
    for (int y = 0; y < h; ++y) // GL rows run bottom-up
        for (int x = 0; x < w; ++x) {
            const unsigned char* in = rgba->GetPointer(0) + (std::size_t(y) * std::size_t(w) + std::size_t(x)) * 4;
            auto* out = &img.bytes[(std::size_t(h - 1 - y) * std::size_t(w) + std::size_t(x)) * 4];
            for (int c = 0; c < 3; ++c)
                out[c] = static_cast<unsigned char>(
                    std::lround(std::clamp(iso::srgb_from_linear(in[c] / 255.0), 0.0, 1.0) * 255.0));
            out[3] = 255;
        }
    return img;
}

struct View {
    vtkNew<vtkImageData> image;
    vtkNew<vtkShortArray> values;
    vtkNew<vtkGPUVolumeRayCastMapper> mapper;
    vtkNew<vtkVolumeProperty> property;
    vtkNew<vtkPiecewiseFunction> opacity;
    vtkNew<vtkColorTransferFunction> color;
    vtkNew<vtkVolume> volume;
    vtkNew<vtkOpenGLRenderer> ren;
    vtkNew<vtkRenderWindow> win;
};

void load(const Args& a, View& v) {
    const std::size_t n = std::size_t(a.dims[0]) * std::size_t(a.dims[1]) * std::size_t(a.dims[2]);
    v.values->SetNumberOfValues(vtkIdType(n));
    std::ifstream in(a.raw, std::ios::binary);
    in.read(reinterpret_cast<char*>(v.values->GetPointer(0)), std::streamsize(n * 2));
    if (!in) throw iso::Error("volume_peer", "cannot read " + std::to_string(n * 2) + " bytes from " + a.raw);
    v.image->SetDimensions(a.dims);
    v.image->SetOrigin(a.origin);
    v.image->SetSpacing(a.spacing);
    v.image->SetDirectionMatrix(a.direction);
    v.image->GetPointData()->SetScalars(v.values);
}

void setup(const Args& a, View& v) {
    load(a, v);
    for (const auto& p : a.tf) {
        v.opacity->AddPoint(p[0], p[1]);
        v.color->AddRGBPoint(p[0], p[2], p[3], p[4]);
    }
    v.opacity->ClampingOn(); // constant beyond the ends, as ours
    v.color->ClampingOn();
    v.color->SetColorSpaceToRGB(); // straight lines between the (linear) colours given
    v.property->SetScalarOpacity(v.opacity);
    v.property->SetColor(v.color);
    v.property->SetScalarOpacityUnitDistance(1.0); // opacity per mm
    v.property->SetInterpolationTypeToLinear();
    v.property->ShadeOff();
    v.mapper->SetInputData(v.image);
    v.mapper->SetBlendModeToComposite();
    v.mapper->AutoAdjustSampleDistancesOff();
    v.mapper->LockSampleDistanceToInputSpacingOff();
    v.mapper->SetUseJittering(0);
    v.mapper->SetImageSampleDistance(1.0);
    v.volume->SetMapper(v.mapper);
    v.volume->SetProperty(v.property);
    v.ren->AddVolume(v.volume);
    v.ren->SetBackground(a.background);
    vtkCamera* cam = v.ren->GetActiveCamera();
    cam->SetPosition(a.eye);
    cam->SetFocalPoint(a.target);
    cam->SetViewUp(a.up);
    cam->SetViewAngle(a.fov);
    v.win->SetMultiSamples(0);
    v.win->SetAlphaBitPlanes(1);
    v.win->SetSize(a.W, a.H);
    v.win->AddRenderer(v.ren);
    v.win->SetOffScreenRendering(1);
}

// Render + WaitForCompletion, ms.
double frame(vtkRenderWindow* win) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    win->Render();
    win->WaitForCompletion();
    return std::chrono::duration<double, std::milli>(clock::now() - t0).count();
}

// Whether the mapper placed the volume by its direction matrix: the bounds
// VTK reports for the volume against those of the eight corners placed by
// origin + direction * (index * spacing).
bool direction_honoured(const Args& a, View& v) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (int c = 0; c < 8; ++c) {
        const double ijk[3] = {(c & 1) ? a.dims[0] - 1.0 : 0.0, (c & 2) ? a.dims[1] - 1.0 : 0.0,
                               (c & 4) ? a.dims[2] - 1.0 : 0.0};
        for (int r = 0; r < 3; ++r) {
            double p = a.origin[r];
            for (int k = 0; k < 3; ++k) p += a.direction[r * 3 + k] * ijk[k] * a.spacing[k];
            lo[r] = std::min(lo[r], p);
            hi[r] = std::max(hi[r], p);
        }
    }
    const double* b = v.volume->GetBounds();
    bool ok = true;
    for (int r = 0; r < 3; ++r) ok = ok && std::abs(b[2 * r] - lo[r]) < 1e-6 && std::abs(b[2 * r + 1] - hi[r]) < 1e-6;
    return ok;
}

void still_frames(const Args& a, View& v) {
    for (std::size_t s = 0; s < a.steps.size(); ++s) {
        v.mapper->SetSampleDistance(float(a.steps[s]));
        std::vector<double> ms;
        iso::Image img;
        for (int f = 0; f < a.warmup + a.reps; ++f) {
            v.ren->GetActiveCamera()->SetClippingRange(a.near_plane, a.far_plane);
            const auto t0 = std::chrono::steady_clock::now();
            v.win->Render();
            v.win->WaitForCompletion();
            img = read_back(v.win, a.W, a.H); // timed, as the benchmark's frames read theirs back
            const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            if (f >= a.warmup) ms.push_back(t);
        }
        const int* size = v.win->GetSize();
        if (size[0] != a.W || size[1] != a.H) throw iso::Error("volume_peer", "the window is not the size asked for");
        const std::string png = a.out + "/vtk_step" + std::to_string(s) + ".png";
        iso::save_image(img, png);
        std::printf("{\"kind\": \"still\", \"step_mm\": %.6f, \"ms_median\": %.4f, \"ms_p25\": %.4f, \"ms_p75\": "
                    "%.4f, \"png\": \"%s\", \"renderer\": \"%s\", \"direction_honoured\": %s}\n",
                    a.steps[s], quantile(ms, 0.5), quantile(ms, 0.25), quantile(ms, 0.75), png.c_str(),
                    iso::vtk_peer::renderer_name(v.win).c_str(), direction_honoured(a, v) ? "true" : "false");
        std::fflush(stdout);
    }
}

// Frames of a rotation about the view-up axis through the focal point,
// the clipping range reset each frame (as the interactor does).
void rotation(const Args& a, View& v, bool interactive) {
    vtkCamera* cam = v.ren->GetActiveCamera();
    cam->SetPosition(a.eye);
    cam->SetFocalPoint(a.target);
    cam->SetViewUp(a.up);
    v.mapper->SetSampleDistance(float(a.rotate_step));
    v.mapper->SetAutoAdjustSampleDistances(interactive ? 1 : 0);
    if (interactive) v.win->SetDesiredUpdateRate(15.0);
    frame(v.win); // warm: the new sample distance's first frame
    std::vector<double> ms;
    float isd_max = 0; // the image sample distance the frames used at most (> 1: fewer rays than pixels)
    for (int f = 0; f < a.rotate; ++f) {
        cam->Azimuth(a.rotate_degrees);
        cam->OrthogonalizeViewUp();
        v.ren->ResetCameraClippingRange();
        ms.push_back(frame(v.win));
        isd_max = std::max(isd_max, v.mapper->GetImageSampleDistance());
    }
    std::printf(
        "{\"kind\": \"%s\", \"step_mm\": %.6f, \"frames\": %d, \"ms_median\": %.4f, \"ms_p5\": %.4f, \"ms_p95\": %.4f, "
        "\"image_sample_distance_max\": %.3f}\n",
        interactive ? "rotate_interactive" : "rotate", a.rotate_step, a.rotate, quantile(ms, 0.5), quantile(ms, 0.05),
        quantile(ms, 0.95), double(isd_max));
    std::fflush(stdout);
    v.mapper->AutoAdjustSampleDistancesOff();
    v.mapper->SetImageSampleDistance(1.0);
}

} // namespace

int main(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string k = argv[i];
        bool ok = i + 1 < argc;
        try {
            ok = ok && option(a, k, argv[i + 1]);
        } catch (const std::exception&) {
            ok = false;
        }
        if (!ok) {
            std::cerr << "volume_peer: bad option " << k << "\n";
            return 2;
        }
        ++i;
    }
    if (a.raw.empty() || a.out.empty() || a.tf.empty() || a.dims[0] <= 0) {
        std::cerr << "volume_peer: needs --raw, --dims, --tf and --out\n";
        return 2;
    }
    try {
        vtkOutputWindow::GetInstance()->SetDisplayModeToAlwaysStdErr();
        View v;
        setup(a, v);
        still_frames(a, v);
        if (a.rotate > 0) {
            rotation(a, v, false);
            rotation(a, v, true);
        }
    } catch (const std::exception& e) {
        std::printf("{\"error\": \"%s\"}\n", e.what());
        std::cerr << "volume_peer: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
