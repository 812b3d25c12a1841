// Shows an image drawn elsewhere (another context, another thread) in the
// current context's framebuffer: uploaded to a texture and blitted, rows
// flipped (Image rows run top-down, GL's bottom-up). The desktop app's 3D
// view shows the still frames its render thread draws this way. No GL
// header here: Qt's widgets include this next to their own GL headers.
#pragma once

#include <memory>

#include "io/image.hpp"

namespace iso::gl {

class ImagePresenter {
public:
    ImagePresenter();
    ~ImagePresenter(); // release() first, with the context current
    // Draws `img` (8-bit RGBA, as RenderResult::image) into GL framebuffer
    // `framebuffer` at its lower-left corner, byte for byte (no colour
    // conversion). Throws iso::Error for another kind of image.
    void present(const Image& img, unsigned framebuffer);
    // The same, stretched over width x height pixels of the framebuffer
    // (linear filtering): a frame drawn at a reduced size while the camera moves.
    void present(const Image& img, unsigned framebuffer, int width, int height);
    // Frees the texture and framebuffer, with the context they were made in current.
    void release();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace iso::gl
