// A headless OpenGL 4.5 core context through EGL: the NVIDIA device platform
// when present (EGL_EXT_platform_device), else Mesa's surfaceless platform
// (llvmpipe on machines without a GPU). Rendering goes to framebuffer
// objects; there is no window. GL functions come through libepoxy, which
// works with EGL and GLX contexts alike (the Qt widget uses the same code).
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace iso::gl {

struct ContextInfo {
    std::string platform; // "device" or "surfaceless"
    std::string vendor, renderer, version, glsl;
    bool debug = false;
};

class HeadlessContext {
public:
    // Throws iso::Error when no GL 4.5 core context can be made.
    // `debug`: a debug context whose GL_KHR_debug messages go to debug_log()
    // (default: on in debug builds, or with ISOSCOPE_GL_DEBUG set).
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

// Makes a headless context current for its lifetime and then makes current
// again whatever EGL context the thread had before (none: none), so that
// the next caller may be another thread (the desktop app renders exports on
// worker threads) and a caller's own context is left as it was. Without an
// argument it uses one context for the whole process, made on first use.
class ScopedCurrent {
public:
    // null: the process's shared context.
    explicit ScopedCurrent(HeadlessContext* ctx = nullptr);
    ~ScopedCurrent();
    ScopedCurrent(const ScopedCurrent&) = delete;
    ScopedCurrent& operator=(const ScopedCurrent&) = delete;

private:
    void* display_;
    void* draw_;
    void* read_;
    void* context_;
};

// What the GL_KHR_debug callback of a debug context saw, for the whole
// process (all debug contexts report here). Tests read and reset it after
// each test (tests/gl/gl_test.hpp); the CLI and the viewer keep today's
// behaviour: errors and warnings echoed to stderr (set_echo).
class DebugLog {
public:
    static constexpr std::size_t kKept = 16; // messages kept, newest last

    // Messages of type GL_DEBUG_TYPE_ERROR since the last clear().
    std::size_t errors() const;
    // The last kKept messages (notifications excluded) since the last
    // clear(), as "GL error (id N): text" or "GL warning (...)", "GL note (...)".
    std::vector<std::string> messages() const;
    void clear();
    // Echo errors and warnings (undefined behaviour, deprecated, portability)
    // to stderr as they arrive; on by default.
    void set_echo(bool on);
    bool echo() const;

    // Called by the debug callback (GLenum values as unsigned).
    void record(unsigned type, unsigned id, unsigned severity, const std::string& text);

private:
    mutable std::mutex mutex_;
    std::size_t errors_ = 0;
    std::deque<std::string> messages_;
    bool echo_ = true;
};

DebugLog& debug_log();

// Installs the GL_KHR_debug callback (into debug_log()) on the current
// context when it is a debug context; does nothing otherwise.
void install_debug_output();

} // namespace iso::gl
