// How a view's drag frames keep pace (the desktop app's 3D view; docs/gui.md,
// "A drag's frames"): each drag frame's time decides the size and the level
// of detail of the next ones, as VTK's interactive image sample distance and
// desired update rate do. Headless, so that the rule is tested without a window.
#pragma once

#include <cstdint>

namespace iso::core {

class DragPacing {
public:
    // The aim: a drag frame in at most this long (14 frames a second).
    static constexpr double kAimMs = 70.0;
    // The coarsest drag frames: 4 times LodSettings::moving_error_px. At 8
    // the 1024^3 phantom's half-size drag frames drew its coarsest stand-in
    // (38 647 triangles, a 2.8 mm grid), whose thin outer wall closed into
    // holes the user saw through; at 4 the 147 026-triangle one (1.4 mm).
    static constexpr double kMaxCoarsen = 4.0;
    // Still frames slower than this speak for a massive scene: a drag
    // starts paced (start), and the frame thread draws a plain frame of the
    // view first after a drag (app/gui/still_frames.cpp).
    static constexpr double kSlowStillMs = 400.0;

    // The next drag frames' size, as a fraction of the view's (1 or 0.5),
    // and their level-of-detail bound, times LodSettings::moving_error_px
    // (1, 2 or 4: where massive surfaces are drawn by their stand-ins,
    // lod::Proxy).
    double scale() const { return scale_; }
    double coarsen() const { return coarsen_; }

    // A drag frame asked for as `request` took `ms` (at half size:
    // `reduced`). Slower than the aim at full size: half the size, counted
    // as three times as fast (the 1024^3 phantom's stand-in: 257 -> 78 ms).
    // Still over 1.5 times too slow: the bound times the power of two
    // nearest the square root of what is left, at least 2 (the triangles
    // drawn go about with the bound's inverse square), up to kMaxCoarsen. Faster than
    // 15 ms at half size: the bound comes back a step at a time, then the
    // full size. Frames asked for before the last change are ignored (they
    // arrive after it); `newest` is the newest request asked for so far.
    void frame(std::uint64_t request, double ms, bool reduced, std::uint64_t newest);
    // A drag over a massive surface starts, the view's still frames taking
    // `still_ms` each: over kSlowStillMs, it starts as if a drag frame had taken
    // as long (the first drag frames over a 32 M-triangle surface took
    // 1.3-2.1 s each at full size and detail). The caller asks only where
    // the still frames' time speaks for the drag's (not for ray-traced AO
    // or a volume over a small scene).
    void start(double still_ms, std::uint64_t newest);

private:
    void slow(double ms, bool reduced, std::uint64_t newest);
    double scale_ = 1.0, coarsen_ = 1.0;
    std::uint64_t changed_at_ = 0; // the newest request when the size or the bound last changed
};

} // namespace iso::core
