#include "renderer/gl/context.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "io/error.hpp"

namespace iso::gl {

struct HeadlessContext::Impl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
};

bool HeadlessContext::default_debug() {
#ifdef NDEBUG
    return std::getenv("ISOSCOPE_GL_DEBUG") != nullptr;
#else
    return true;
#endif
}

namespace {

const char* egl_error_name(EGLint e) {
    switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: return "EGL error";
    }
}

bool has_extension(const char* list, const char* name) {
    if (!list) return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    return false;
}

// Displays to try, best first: each GPU the device platform lists (skipping
// Mesa's software device, which surfaceless gives us anyway), then surfaceless.
std::vector<std::pair<EGLDisplay, const char*>> candidate_displays() {
    std::vector<std::pair<EGLDisplay, const char*>> out;
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (has_extension(client, "EGL_EXT_platform_device") && has_extension(client, "EGL_EXT_device_enumeration")) {
        EGLDeviceEXT devices[16];
        EGLint n = 0;
        if (eglQueryDevicesEXT(16, devices, &n)) {
            for (EGLint i = 0; i < n; ++i) {
                const char* ext = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
                if (has_extension(ext, "EGL_MESA_device_software")) continue;
                EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
                if (d != EGL_NO_DISPLAY) out.emplace_back(d, "device");
            }
        }
    }
    if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (d != EGL_NO_DISPLAY) out.emplace_back(d, "surfaceless");
    }
    return out;
}

// An EGL display is one per process (eglGetPlatformDisplayEXT returns the
// same handle to every caller), and eglTerminate on it ends every context
// made on it, another thread's included: the frame thread's context died
// when a one-off render on a worker ended. The contexts made here count
// their display's users and the last one terminates it.
std::mutex& display_mutex() {
    static std::mutex m;
    return m;
}
std::map<EGLDisplay, int>& display_users() {
    static std::map<EGLDisplay, int> users;
    return users;
}
bool initialize_display(EGLDisplay d, EGLint& major, EGLint& minor) {
    std::lock_guard lock(display_mutex());
    if (!eglInitialize(d, &major, &minor)) return false;
    ++display_users()[d];
    return true;
}
void release_display(EGLDisplay d) {
    std::lock_guard lock(display_mutex());
    auto& users = display_users();
    if (--users[d] > 0) return;
    users.erase(d);
    eglTerminate(d);
}

} // namespace

HeadlessContext::HeadlessContext(bool debug) : impl_(std::make_unique<Impl>()) {
    std::string tried;
    for (auto [display, platform] : candidate_displays()) {
        EGLint major = 0, minor = 0;
        if (!initialize_display(display, major, minor)) {
            tried += std::string(platform) + ": eglInitialize failed (" + egl_error_name(eglGetError()) + "); ";
            continue;
        }
        if (!eglBindAPI(EGL_OPENGL_API)) {
            tried += std::string(platform) + ": no desktop OpenGL; ";
            release_display(display);
            continue;
        }
        const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  4,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_CONTEXT_OPENGL_DEBUG,
                                  debug ? EGL_TRUE : EGL_FALSE,
                                  EGL_NONE};
        EGLContext ctx = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
        if (ctx == EGL_NO_CONTEXT) {
            tried += std::string(platform) + ": no GL 4.5 core context (" + egl_error_name(eglGetError()) + "); ";
            release_display(display);
            continue;
        }
        if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
            tried += std::string(platform) + ": eglMakeCurrent failed; ";
            eglDestroyContext(display, ctx);
            release_display(display);
            continue;
        }
        impl_->display = display;
        impl_->context = ctx;
        info_.platform = platform;
        info_.vendor = reinterpret_cast<const char*>(glGetString(GL_VENDOR));
        info_.renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        info_.version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
        info_.glsl = reinterpret_cast<const char*>(glGetString(GL_SHADING_LANGUAGE_VERSION));
        info_.debug = debug;
        if (debug) install_debug_output();
        return;
    }
    throw Error("OpenGL", "cannot create a headless OpenGL 4.5 core context through EGL (" +
                              (tried.empty() ? std::string("no EGL platform found") : tried) +
                              "). Install libegl-mesa0 and libgl1-mesa-dri (./setup.sh).");
}

HeadlessContext::~HeadlessContext() {
    if (impl_ && impl_->display != EGL_NO_DISPLAY) {
        eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (impl_->context != EGL_NO_CONTEXT) eglDestroyContext(impl_->display, impl_->context);
        release_display(impl_->display);
    }
}

void HeadlessContext::make_current() {
    if (!eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context))
        throw Error("OpenGL", std::string("eglMakeCurrent failed: ") + egl_error_name(eglGetError()));
}

namespace {
HeadlessContext& shared_context() {
    static HeadlessContext shared; // one per process, made (and made current) on first use
    return shared;
}
} // namespace

// The caller's context is recorded before the shared one is made: making it
// makes it current.
ScopedCurrent::ScopedCurrent(HeadlessContext* ctx)
    : display_(eglGetCurrentDisplay()), draw_(eglGetCurrentSurface(EGL_DRAW)), read_(eglGetCurrentSurface(EGL_READ)),
      context_(eglGetCurrentContext()) {
    (ctx ? *ctx : shared_context()).make_current();
}

ScopedCurrent::~ScopedCurrent() {
    if (context_ != EGL_NO_CONTEXT)
        eglMakeCurrent(display_, draw_, read_, context_);
    else if (eglGetCurrentContext() != EGL_NO_CONTEXT)
        eglMakeCurrent(eglGetCurrentDisplay(), EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

std::size_t DebugLog::errors() const {
    std::lock_guard lock(mutex_);
    return errors_;
}

std::vector<std::string> DebugLog::messages() const {
    std::lock_guard lock(mutex_);
    return {messages_.begin(), messages_.end()};
}

void DebugLog::clear() {
    std::lock_guard lock(mutex_);
    errors_ = 0;
    messages_.clear();
}

void DebugLog::set_echo(bool on) {
    std::lock_guard lock(mutex_);
    echo_ = on;
}

bool DebugLog::echo() const {
    std::lock_guard lock(mutex_);
    return echo_;
}

void DebugLog::record(unsigned type, unsigned id, unsigned severity, const std::string& text) {
    // Notifications (e.g. buffer placement hints) are noise.
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
    const bool error = type == GL_DEBUG_TYPE_ERROR;
    const bool warning = type == GL_DEBUG_TYPE_UNDEFINED_BEHAVIOR || type == GL_DEBUG_TYPE_DEPRECATED_BEHAVIOR ||
                         type == GL_DEBUG_TYPE_PORTABILITY;
    const std::string line = std::string("GL ") +
                             (error     ? "error"
                              : warning ? "warning"
                                        : "note") +
                             " (id " + std::to_string(id) + "): " + text;
    std::lock_guard lock(mutex_);
    errors_ += error;
    messages_.push_back(line);
    if (messages_.size() > kKept) messages_.pop_front();
    if (echo_ && (error || warning)) std::fprintf(stderr, "%s\n", line.c_str());
}

DebugLog& debug_log() {
    static DebugLog log;
    return log;
}

namespace {
void GLAPIENTRY on_debug_message(GLenum, GLenum type, GLuint id, GLenum severity, GLsizei length, const GLchar* message,
                                 const void*) {
    debug_log().record(type, id, severity,
                       length >= 0 ? std::string(message, std::size_t(length)) : std::string(message));
}
} // namespace

void install_debug_output() {
    GLint flags = 0;
    glGetIntegerv(GL_CONTEXT_FLAGS, &flags);
    if (!(flags & GL_CONTEXT_FLAG_DEBUG_BIT)) return;
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(on_debug_message, nullptr);
}

} // namespace iso::gl
