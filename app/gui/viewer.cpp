#include "app/gui/viewer.hpp"

#include <QKeyEvent>
#include <QMouseEvent>
#include <QTimer>
#include <QWheelEvent>

#include "renderer/render/overlay.hpp"
#include "renderer/render/renderer.hpp"

namespace iso::gui {

Viewer::Viewer(std::vector<ViewerMesh> meshes, PatientView view, ViewerOptions options, QWidget* parent)
    : QOpenGLWidget(parent), meshes_(std::move(meshes)), initial_view_(view), options_(options),
      annotations_(std::make_unique<Annotations>()) {
    setFocusPolicy(Qt::StrongFocus);
    setMinimumSize(320, 240);
}

Viewer::~Viewer() {
    makeCurrent(); // GL objects are released with the widget's context current
    renderer_.reset();
    doneCurrent();
}

void Viewer::initializeGL() {
    renderer_ = std::make_unique<Renderer>();
    for (const auto& m : meshes_) {
        SceneObject o;
        o.name = m.name;
        o.color = {m.r, m.g, m.b};
        renderer_->add(m.mesh, o);
    }
    meshes_.clear(); // on the GPU now
    camera_.set_view(initial_view_, renderer_->bounds());
}

void Viewer::paintGL() {
    const qreal dpr = devicePixelRatioF();
    const int w = std::max(1, int(width() * dpr)), h = std::max(1, int(height() * dpr));
    camera_.fit_planes(renderer_->bounds());
    RenderOptions opt;
    opt.width = w;
    opt.height = h;
    opt.scale = float(dpr);
    opt.annotations = annotations_.get();
    opt.present = true;
    opt.target_framebuffer = defaultFramebufferObject();
    opt.ao = options_.ao;
    opt.ao_settings = options_.cone;
    const auto r = renderer_->render(camera_, opt);
    ++frames_;
    ao_frames_ = options_.ao ? r.ao_frames : 0;
    // Progressive AO: while the camera and the scene stay still, keep
    // drawing so new jitter sets accumulate and the noise averages out; any
    // interaction restarts the accumulation (the renderer sees the change).
    if (options_.ao && ao_frames_ < options_.still_frames) QTimer::singleShot(0, this, [this] { update(); });
}

void Viewer::mousePressEvent(QMouseEvent* e) { last_ = e->pos(); }

void Viewer::mouseMoveEvent(QMouseEvent* e) {
    const QPoint d = e->pos() - last_;
    last_ = e->pos();
    if (e->buttons() & Qt::LeftButton)
        camera_.orbit(-0.4 * d.x(), -0.4 * d.y());
    else if (e->buttons() & (Qt::RightButton | Qt::MiddleButton))
        camera_.pan(double(d.x()) / height(), double(d.y()) / height());
    update();
}

void Viewer::wheelEvent(QWheelEvent* e) {
    camera_.zoom(std::pow(1.0015, e->angleDelta().y()));
    update();
}

void Viewer::keyPressEvent(QKeyEvent* e) {
    static const std::pair<int, PatientView> keys[] = {{Qt::Key_A, PatientView::Anterior}, {Qt::Key_P, PatientView::Posterior},
                                                       {Qt::Key_L, PatientView::Left},     {Qt::Key_R, PatientView::Right},
                                                       {Qt::Key_S, PatientView::Superior}, {Qt::Key_I, PatientView::Inferior}};
    if (e->key() == Qt::Key_O) { // ambient occlusion on / off
        options_.ao = !options_.ao;
        update();
        return;
    }
    for (auto [k, v] : keys)
        if (e->key() == k) {
            camera_.set_view(v, renderer_->bounds());
            update();
            return;
        }
    QOpenGLWidget::keyPressEvent(e);
}

} // namespace iso::gui
