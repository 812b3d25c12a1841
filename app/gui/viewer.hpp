// The 3D view of `isoscope view`: our renderer inside a QOpenGLWidget.
// Presentation only: the scene comes from the core API.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <QOpenGLWidget>

#include "io/mesh.hpp"
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

class Viewer : public QOpenGLWidget {
public:
    explicit Viewer(std::vector<ViewerMesh> meshes, PatientView view, QWidget* parent = nullptr);
    ~Viewer() override;
    int frames() const { return frames_; }

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
    std::unique_ptr<Renderer> renderer_;
    std::unique_ptr<Annotations> annotations_;
    Camera camera_;
    QPoint last_;
    int frames_ = 0;
};

} // namespace iso::gui
