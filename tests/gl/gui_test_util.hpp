// Shared by the desktop app's tests (tests/gl/main_window_test.cpp,
// tests/gl/gui_*_test.cpp): each program's outer test starts the same
// program again under xvfb-run (run_inner_under_xvfb), whose inner tests
// drive the widgets in-process with QTest (make_app). Expected values come
// from the core API, not from the window's own state.
#pragma once

#include <QApplication>
#include <QElapsedTimer>
#include <QImage>
#include <QSurfaceFormat>
#include <QTest>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/test_util.hpp"

namespace iso::test {

inline bool wait_until(const std::function<bool()>& ready, int timeout_ms) {
    QElapsedTimer t;
    t.start();
    while (!ready()) {
        if (t.elapsed() > timeout_ms) return false;
        QTest::qWait(20);
    }
    return true;
}

// Pixels brighter than black: the picture shows something, not an empty frame.
inline double lit_fraction(const QImage& img) {
    if (img.isNull()) return 0;
    const QImage g = img.convertToFormat(QImage::Format_Grayscale8);
    std::size_t lit = 0;
    for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x) lit += g.constScanLine(y)[x] > 20;
    return double(lit) / double(g.width() * g.height());
}

// The outer test: runs this program again under xvfb-run with `inner_env`
// set and only `filter`'s tests; expects `tests` of them to pass, none skipped.
// Skips when xvfb-run is missing.
inline void run_inner_under_xvfb(const char* inner_env, const std::string& filter, int tests = 1) {
    if (std::getenv(inner_env)) GTEST_SKIP() << "already inside xvfb-run";
    if (run_command("command -v xvfb-run").exit_code != 0) GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
    const auto r = run_command(std::string(inner_env) + "=1 xvfb-run -a -s '-screen 0 1600x1200x24' " + self +
                                   " --gtest_filter='" + filter + "'",
                               true);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    // It ran (a skip inside would also exit 0).
    EXPECT_NE(r.out.find("[  PASSED  ] " + std::to_string(tests) + " test"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("SKIPPED"), std::string::npos) << r.out;
}

// The inner tests' application: GL 4.5 core surfaces, settings (recent
// files) in `config_dir`, not the user's. Keep it while the test runs and
// let it go before the test ends (one per process: Qt allows one at a time;
// a static one would outlive Qt's own statics).
inline std::unique_ptr<QApplication> make_app(const std::string& name, const std::filesystem::path& config_dir) {
    ::setenv("XDG_CONFIG_HOME", config_dir.c_str(), 1);
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
    static int argc = 1;
    static std::string arg0;
    arg0 = name;
    static char* argv[2] = {nullptr, nullptr};
    argv[0] = arg0.data();
    auto app = std::make_unique<QApplication>(argc, argv);
    QApplication::setOrganizationName("isoscope-test");
    QApplication::setApplicationName(QString::fromStdString(name));
    return app;
}

// The test's output folder for screenshots: build/test_output/<name>.
inline std::filesystem::path output_dir(const std::string& name) {
    const auto out = std::filesystem::path(ISOSCOPE_BINARY_DIR) / "test_output" / name;
    std::filesystem::create_directories(out);
    return out;
}

} // namespace iso::test
