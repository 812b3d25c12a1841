// How a volume is shown by ray casting (docs/volume.md): its transfer
// function, the mode, the sample step, and the clip region that cuts
// surfaces and volume alike. The stated model, which the GPU passes, the CPU
// reference (reference.hpp) and outside checks all follow:
//  - the volume occupies its index box [0, n-1] per axis, values trilinear
//    between voxel centres, nothing outside the box;
//  - the transfer function is piecewise linear in the value between its
//    points (constant beyond the first and last), colours given as sRGB hex
//    and interpolated in linear light;
//  - opacity is per millimetre of path: a segment of L mm at opacity a
//    transmits (1 - a)^L; emission-absorption composited front to back in
//    linear light with translucent surfaces at their depths, an opaque
//    surface ending the ray.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace iso {

struct TfPoint {
    double value = 0;
    double opacity = 0;            // per mm, 0..1
    std::string color = "#ffffff"; // sRGB hex, as given
    bool operator==(const TfPoint&) const = default;
};

class TransferFunction {
public:
    TransferFunction() = default;
    // Points in increasing value (equal values allowed: a step). Throws
    // iso::Error("transfer function", ...) for none, a value out of order or
    // not finite, an opacity outside [0, 1], a colour that is not #rrggbb.
    explicit TransferFunction(std::vector<TfPoint> points);
    // "value:opacity:#rrggbb,..." (e.g. "150:0:#c08040,400:0.2:#fff0e0").
    static TransferFunction parse(const std::string& text);
    // The text parse() reads: values and opacities with the digits needed to read them back.
    std::string text() const;

    const std::vector<TfPoint>& points() const { return points_; }
    bool empty() const { return points_.empty(); }
    glm::dvec3 linear_color(std::size_t i) const { return linear_[i]; } // point i's colour in linear light
    // Linear RGB and opacity per mm at value v.
    glm::dvec4 at(double v) const;
    // The largest opacity over values [lo, hi] (a trilinear sample between
    // samples in that range never leaves it).
    double max_opacity(double lo, double hi) const;
    bool operator==(const TransferFunction& o) const { return points_ == o.points_; }

private:
    std::vector<TfPoint> points_;
    std::vector<glm::dvec3> linear_; // points' colours in linear light
};

// Named CT presets (values in HU): "bone", "vessels", "skin", "soft tissue".
std::vector<std::string> transfer_function_presets();
// A preset by name, else the text parsed as a transfer function; throws
// iso::Error naming both readings when neither works.
TransferFunction transfer_function_from(const std::string& preset_or_text);

enum class VolumeMode { Composite, Mip, Minip };
const char* volume_mode_name(VolumeMode m);                // "composite", "mip", "minip"
VolumeMode volume_mode_from_name(const std::string& name); // throws iso::Error

// How the composite march integrates between samples (docs/volume.md):
// pre-integrated segments (preintegration.hpp; the default), or each
// sample's classification held over its step (the stated model's sampling,
// which the CPU reference marches at a fine step).
enum class VolumeIntegration { Preintegrated, Sampled };
const char* volume_integration_name(VolumeIntegration i);                // "preintegrated", "sampled"
VolumeIntegration volume_integration_from_name(const std::string& name); // throws iso::Error

// A half-space kept by clipping: points p with dot(normal, p) >= offset (LPS mm).
struct ClipPlane {
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double offset = 0;
    bool operator==(const ClipPlane&) const = default;
};

// A crop: an axis-aligned LPS box and planes; what lies outside any of them
// is cut, surfaces and volume alike.
struct Clip {
    std::optional<std::pair<glm::dvec3, glm::dvec3>> box; // LPS min, max
    std::vector<ClipPlane> planes;
    bool active() const { return box || !planes.empty(); }
    bool keeps(const glm::dvec3& p) const;
    // The box's six faces and the planes, as half-spaces (the shaders' form).
    std::vector<ClipPlane> half_spaces() const;
    // "box=x0,y0,z0,x1,y1,z1" or "plane=px,py,pz,nx,ny,nz" (a point and the
    // normal of the side kept), added to this clip; throws iso::Error.
    void add(const std::string& text);
    std::string text() const; // the add() texts, separated by "; "
    bool operator==(const Clip&) const = default;
};
constexpr int kMaxClipHalfSpaces = 16; // the box's 6 and up to 10 planes

// The volume in a frame.
struct VolumeLook {
    bool enabled = false;
    TransferFunction tf;
    VolumeMode mode = VolumeMode::Composite;
    // Sample step in units of the smallest voxel spacing: when still, and
    // while the camera moves (RenderOptions::moving).
    double step = 0.5;
    double moving_step = 2.0;
    VolumeIntegration integration = VolumeIntegration::Preintegrated;
    // Gradient shading (central differences); FrameLook::flat_shading turns it off.
    bool shading = true;
    // Skip chunks whose value range the transfer function maps to zero
    // opacity (off: for checks that the skipping changes nothing).
    bool skip_empty = true;
    bool operator==(const VolumeLook&) const = default;
};
// Throws iso::Error naming the setting.
void validate(const VolumeLook& v);

// Texels of the transfer function's tables (preintegration.hpp) over its points' values.
constexpr int kTransferTableTexels = 4096;
// The value between two of those texels (0: the function has one value).
double transfer_table_texel(const TransferFunction& tf);
// The gradient magnitude (value per mm) at which gradient shading is full:
// a twentieth of the transfer function's value span per voxel of
// `min_spacing` mm, so homogeneous regions keep their colour (the GPU march
// and the CPU reference alike).
double gradient_reference(const TransferFunction& tf, double min_spacing);

// Per chunk of a range index (one min and max per chunk): 1 where the
// transfer function gives some sample in the chunk a non-zero opacity (or,
// for MIP/MinIP, always: every sample counts), 0 where marching it adds
// nothing. The range is widened by one texel of the tables each way: the
// march reads them interpolated between texels, so a chunk is empty only
// where every texel it can read is.
std::vector<unsigned char> occupied_chunks(const VolumeLook& v, std::span<const double> mins,
                                           std::span<const double> maxs);

} // namespace iso
