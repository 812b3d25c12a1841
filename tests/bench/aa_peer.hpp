// VTK's anti-aliasing as peers for a whole-image benchmark: the same meshes,
// colours, opacities, camera and size drawn by VTK 9.1 without
// anti-aliasing, with FXAA, with 4x and 8x multisampling, and VTK's own
// reference, the scene drawn 8x8 times larger and box-filtered down in
// linear light. VTK renders through X (Debian's VTK 9.1 has no EGL), so the
// drawing is done by the program aa_peer_vtk run under xvfb-run as a child
// process (the peers of the other benchmarks run the same way); this module
// writes the meshes for it, runs it and reads its images back. Plus the
// check that VTK's camera is ours (check_camera) and the image error of
// tests/bench/image_error.hpp that the benchmark prints.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "io/image.hpp"
#include "io/mesh.hpp"
#include "renderer/frame/camera.hpp"

namespace iso::bench {

// A mesh to draw (LPS mm), its colour in linear RGB and its opacity.
// `file`: the mesh already written as a file VTK reads through load_mesh
// (.ply, .vtp, .stl): used as it is, so that a 10M-triangle mesh is not
// written again for every call; empty: written to the work folder.
struct PeerMesh {
    const Mesh* mesh = nullptr;
    glm::vec3 color{0.9f};
    float opacity = 1.0f;
    std::string file;
};

// One configuration as VTK drew it: RGBA8, sRGB, opaque, rows from the top
// (as iso::Image and our renderer's colour image).
struct PeerImage {
    std::string name; // "none", "fxaa", "msaa4", "msaa8", "reference"
    Image image;
    double ms = 0;                 // median per frame of `reps`: Render, WaitForCompletion, read-back
    double ms_p25 = 0, ms_p75 = 0; // the quartiles
    int samples_asked = 0;         // SetMultiSamples
    int samples_window = 0;        // GetMultiSamples afterwards: VTK clamps to what GL offers
    bool peeled = false;           // dual depth peeling drew the translucent surfaces
    long differ_from_none = -1;    // pixels whose RGB differs from "none"'s (-1: "none" not drawn)
    std::string renderer;          // GL renderer of VTK's context
};

struct AaPeerOptions {
    std::vector<std::string> configs{"none", "fxaa", "msaa4", "msaa8", "reference"};
    int reference_factor = 8;                  // the reference's window is this many times larger in x and y
    int warmup = 2;                            // frames before the timed ones (shaders compile on first use)
    glm::vec3 background{0.08f, 0.09f, 0.11f}; // linear RGB; FrameLook's default
    bool flat = false;                         // ambient 1, diffuse 0, specular 0: a fragment is its colour
    // Translucent surfaces: converged dual depth peeling (100 peels,
    // occlusion ratio 0, as oit_peer's reference); false: VTK's
    // weighted-blended OIT, its default without peeling.
    bool depth_peeling = true;
    std::string work_dir; // meshes, images, VTK's logs kept here; empty: a temporary folder, removed
    std::string peer;     // the aa_peer_vtk program; empty: the one built with this
};

// Renders the meshes with VTK in each configuration, `reps` timed frames
// each after the warm-up, one aa_peer_vtk process per configuration (so a
// setting that crashes VTK takes only itself down). VTK draws in linear
// light into a plain RGBA8 framebuffer; the peer encodes the pixels to sRGB
// and box-filters the reference in linear light (aa_peer_vtk.cpp).
// Throws iso::Error when a configuration fails and `failed` is null; else
// that configuration is left out and its error (with VTK's output) added to
// `failed`.
//
// Found with VTK 9.1 under Xvfb on llvmpipe (Mesa, GL_MAX_SAMPLES 4):
// - SetMultiSamples(8) gets 4 (samples_window 4): msaa8 is msaa4 there.
// - Multisampling works for opaque surfaces (edges differ from "none"),
//   but with dual depth peeling the translucent surfaces vanish from the
//   image (peeled still says true); with depth_peeling false (weighted-
//   blended OIT) they are drawn. Look at the images of a translucent scene.
std::vector<PeerImage> render_vtk_aa(const std::vector<PeerMesh>& meshes, const Camera& cam, int W, int H, int reps,
                                     const AaPeerOptions& opt = {}, std::vector<std::string>* failed = nullptr);

// Do VTK and we see the same thing from `cam`? One mesh drawn flat by both
// without anti-aliasing: a pixel is covered where it is not the background.
struct CameraCheck {
    std::size_t pixels = 0, ours = 0, vtk = 0; // covered pixels of each
    std::size_t disagree = 0;                  // covered in one and not the other
    double agreement = 0;                      // 1 - disagree / pixels
    double iou = 0;                            // covered in both / covered in either
    bool ok = false;                           // agreement > 0.99
    Image ours_image, vtk_image;
};
CameraCheck check_camera(const Mesh& mesh, const Camera& cam, int W, int H, const std::string& work_dir = "");

} // namespace iso::bench
