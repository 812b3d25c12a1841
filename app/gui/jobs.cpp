#include "app/gui/jobs.hpp"

#include <QProgressDialog>
#include <QThread>
#include <QTimer>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <string>

namespace iso::gui {

struct Jobs::Job {
    QThread* thread = nullptr;
    QProgressDialog* dialog = nullptr; // null: quiet
    QTimer* timer = nullptr;
    QString title;
    Options options;
    std::atomic<double> fraction{0.0};
    std::atomic<bool> cancel{false}, abandoned{false};
    std::mutex stage_mutex;
    std::string stage;
    std::exception_ptr error;
    std::function<void(std::exception_ptr)> done;
};

Jobs::Jobs(QWidget* window) : window_(window) {}

Jobs::~Jobs() { wait_all(true); }

int Jobs::quiet_running() const {
    return int(std::count_if(running_.begin(), running_.end(), [](const auto& j) { return j->options.quiet; }));
}

void Jobs::run(const QString& title, std::function<void(const ProgressFn&)> work,
               std::function<void(std::exception_ptr)> done, Options options) {
    auto job = std::make_shared<Job>();
    job->title = title;
    job->options = options;
    job->done = std::move(done);
    Job* j = job.get();
    // The core calls this on the worker; returning false makes it throw iso::Cancelled.
    ProgressFn progress = [j](double f, std::string_view stage) {
        j->fraction = f;
        {
            std::lock_guard lock(j->stage_mutex);
            j->stage = stage;
        }
        return !j->cancel.load();
    };
    job->thread = QThread::create([j, work = std::move(work), progress] {
        try {
            work(progress);
        } catch (...) {
            j->error = std::current_exception();
        }
    });
    if (!options.quiet) {
        job->dialog = new QProgressDialog(title, "Cancel", 0, 1000, window_);
        job->dialog->setObjectName("progress");
        job->dialog->setWindowModality(Qt::WindowModal);
        job->dialog->setAutoClose(false);
        job->dialog->setAutoReset(false);
        job->dialog->setMinimumDuration(300);
        job->dialog->setValue(0);
        connect(job->dialog, &QProgressDialog::canceled, this, [this, j] { cancel_pressed(j); });
        job->timer = new QTimer(this);
        connect(job->timer, &QTimer::timeout, this, [j] {
            if (j->abandoned) return;
            std::string stage;
            {
                std::lock_guard lock(j->stage_mutex);
                stage = j->stage;
            }
            j->dialog->setValue(int(std::clamp(j->fraction.load(), 0.0, 1.0) * 1000));
            if (!j->cancel && !stage.empty()) j->dialog->setLabelText(j->title + "\n" + QString::fromStdString(stage));
        });
        job->timer->start(50);
        current_ = job;
    }
    connect(job->thread, &QThread::finished, this, [this, job] { finish(job); });
    running_.push_back(job);
    job->thread->start();
}

void Jobs::cancel_pressed(Job* j) {
    j->cancel = true;
    if (!j->options.abandonable) {
        j->dialog->setLabelText(j->title + "\ncancelling...");
        return;
    }
    // The core's load reports no progress for most formats, so it cannot
    // stop early: the window stops waiting and drops the result.
    j->abandoned = true;
    if (current_.get() == j) current_.reset();
    QObject::disconnect(j->dialog, nullptr, this, nullptr);
    j->dialog->hide();
    if (message) message(j->title + ": cancelled");
}

void Jobs::finish(const std::shared_ptr<Job>& job) {
    std::erase(running_, job);
    if (job->timer) {
        job->timer->stop();
        job->timer->deleteLater();
    }
    if (job->dialog) {
        QObject::disconnect(job->dialog, nullptr, this, nullptr);
        job->dialog->hide();
        job->dialog->deleteLater();
    }
    job->thread->deleteLater();
    if (job->abandoned) return;
    if (current_ == job) current_.reset();
    job->done(job->error);
}

void Jobs::wait_all(bool cancel, bool quiet_only) {
    // Workers still running (an abandoned load, an extraction) finish before
    // what they may read goes; extractions stop at their next progress call.
    const auto running = running_;
    for (auto& j : running) {
        if (quiet_only && !j->options.quiet) continue;
        std::erase(running_, j);
        if (cancel) j->cancel = true;
        QObject::disconnect(j->thread, nullptr, this, nullptr);
        j->thread->wait();
        delete j->thread;
        if (j->timer) j->timer->deleteLater();
        if (j->dialog) {
            j->dialog->hide();
            j->dialog->deleteLater();
        }
    }
    if (!quiet_only) current_.reset();
}

} // namespace iso::gui
