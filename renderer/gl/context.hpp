// A headless OpenGL 4.5 core context through EGL: the NVIDIA device platform
// when present (EGL_EXT_platform_device), else Mesa's surfaceless platform
// (llvmpipe on machines without a GPU). Rendering goes to framebuffer
// objects; there is no window. GL functions come through libepoxy, which
// works with EGL and GLX contexts alike (the Qt widget uses the same code).
#pragma once

#include <memory>
#include <string>

namespace iso::gl {

struct ContextInfo {
    std::string platform;  // "device" or "surfaceless"
    std::string vendor, renderer, version, glsl;
    bool debug = false;
};

class HeadlessContext {
public:
    // Throws iso::Error when no GL 4.5 core context can be made.
    // `debug`: a debug context with GL_KHR_debug messages routed to stderr
    // (default: on in debug builds).
    explicit HeadlessContext(bool debug = default_debug());
    ~HeadlessContext();
    HeadlessContext(const HeadlessContext&) = delete;
    HeadlessContext& operator=(const HeadlessContext&) = delete;

    void make_current();
    const ContextInfo& info() const { return info_; }

    static bool default_debug();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    ContextInfo info_;
};

// Installs a GL_KHR_debug callback on the current context that prints
// errors and warnings to stderr (performance/other notes are dropped).
void install_debug_output();

} // namespace iso::gl
