#include "renderer/gl/present.hpp"

#include "io/error.hpp"
#include "renderer/gl/objects.hpp"

namespace iso::gl {

struct ImagePresenter::Impl {
    Texture texture;
    Framebuffer source;
};

ImagePresenter::ImagePresenter() : impl_(std::make_unique<Impl>()) {}

ImagePresenter::~ImagePresenter() {
    // Without a current context the names cannot be freed here: leave them
    // to the context's destruction rather than delete another context's.
    impl_->texture.release();
    impl_->source.release();
}

void ImagePresenter::present(const Image& img, unsigned framebuffer) {
    present(img, framebuffer, img.width, img.height);
}

void ImagePresenter::present(const Image& img, unsigned framebuffer, int width, int height) {
    if (img.is_float || img.channels != 4 || img.width < 1 || img.height < 1 ||
        img.bytes.size() != std::size_t(img.width) * std::size_t(img.height) * 4)
        throw Error("present image", "not an 8-bit RGBA image of its stated size");
    Impl& im = *impl_;
    if (!im.texture || im.texture.width() != img.width || im.texture.height() != img.height) {
        im.texture = Texture::create_2d(GL_RGBA8, img.width, img.height);
        if (!im.source) im.source = Framebuffer::create();
        im.source.attach(GL_COLOR_ATTACHMENT0, im.texture);
        im.source.check();
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glTextureSubImage2D(im.texture.id(), 0, 0, 0, img.width, img.height, GL_RGBA, GL_UNSIGNED_BYTE, img.bytes.data());
    glDisable(GL_SCISSOR_TEST);
    // The image's first row is the top: blit it to the destination's top row.
    const bool same = width == img.width && height == img.height;
    glBlitNamedFramebuffer(im.source.id(), GLuint(framebuffer), 0, 0, img.width, img.height, 0, height, width, 0,
                           GL_COLOR_BUFFER_BIT, same ? GL_NEAREST : GL_LINEAR);
}

void ImagePresenter::release() {
    impl_->source.reset();
    impl_->texture.reset();
}

} // namespace iso::gl
