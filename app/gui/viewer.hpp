// The 3D view of `isoscope view`: our renderer inside a QOpenGLWidget.
// Presentation only: the scene comes from the core API.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <QOpenGLWidget>

#include "io/mesh.hpp"
#include "renderer/render/cone_ao.hpp"
#include "renderer/scene/camera.hpp"

namespace iso {
class Renderer;
struct Annotations;
}

namespace iso::gui {

struct ViewerMesh {
    Mesh mesh;
    std::string name;
    float r, g, b;
};

struct ViewerOptions {
    bool ao = true;          // cone-traced AO (key O toggles it)
    ConeAoSettings cone;     // its settings
    int still_frames = 16;   // while nothing moves, this many frames accumulate new jitter sets
};

class Viewer : public QOpenGLWidget {
public:
    explicit Viewer(std::vector<ViewerMesh> meshes, PatientView view, ViewerOptions options = {}, QWidget* parent = nullptr);
    ~Viewer() override;
    int frames() const { return frames_; }
    // True once the picture stopped changing: AO off, or its still frames
    // all accumulated.
    bool converged() const { return frames_ > 0 && (!options_.ao || ao_frames_ >= options_.still_frames); }
    int ao_frames() const { return ao_frames_; }

protected:
    void initializeGL() override;
    void paintGL() override;
    void mousePressEvent(QMouseEvent* e) override;
    void mouseMoveEvent(QMouseEvent* e) override;
    void wheelEvent(QWheelEvent* e) override;
    void keyPressEvent(QKeyEvent* e) override;

private:
    std::vector<ViewerMesh> meshes_;
    PatientView initial_view_;
    ViewerOptions options_;
    std::unique_ptr<Renderer> renderer_;
    std::unique_ptr<Annotations> annotations_;
    Camera camera_;
    QPoint last_;
    int frames_ = 0;
    int ao_frames_ = 0;
};

} // namespace iso::gui
