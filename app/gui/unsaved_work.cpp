#include "app/gui/unsaved_work.hpp"

#include <QDir>
#include <QFileInfo>
#include <QMainWindow>
#include <QMessageBox>
#include <QPushButton>
#include <QStandardPaths>
#include <QTimer>

#include <cstdlib>
#include <filesystem>
#include <memory>

#include "app/gui/app_context.hpp"
#include "app/gui/files.hpp"
#include "app/gui/jobs.hpp"
#include "io/image.hpp"
#include "renderer/core/session.hpp"

namespace iso::gui {

namespace {
constexpr int kAutosaveMs = 60000;
}

UnsavedWork::UnsavedWork(AppContext& context, Files& files)
    : QObject(&context.window), context_(context), files_(files) {
    timer_ = new QTimer(this);
    timer_->setInterval(kAutosaveMs);
    if (const char* ms = std::getenv("ISOSCOPE_AUTOSAVE_MS"); ms && std::atoi(ms) > 0)
        timer_->setInterval(std::atoi(ms));
    connect(timer_, &QTimer::timeout, this, [this] { autosave(); });
    // Any change of the workspace may be unsaved work; none left: nothing to recover.
    observer_ = context_.workspace.observe([this](core::Parts parts) {
        if (parts & core::kEditedParts) edited_since_autosave_ = true;
        if (context_.workspace.modified()) {
            if (!timer_->isActive()) timer_->start();
            return;
        }
        timer_->stop();
        if (core::has(parts, core::Part::File) && !core::has(parts, core::Part::Data)) { // saved: it goes
            wait_for_autosave();
            remove_recovery_file();
        }
    });
    // Discarded: not worth recovering any more; while the window still shows
    // it, the next autosave writes it again.
    files_.discarded = [this] {
        wait_for_autosave();
        remove_recovery_file();
        edited_since_autosave_ = true;
    };
}

UnsavedWork::~UnsavedWork() { context_.workspace.unobserve(observer_); }

QString UnsavedWork::recovery_path() {
    return QDir(QStandardPaths::writableLocation(QStandardPaths::AppConfigLocation)).filePath("recovery.isoscope.json");
}

void UnsavedWork::set_autosave_interval(int ms) { timer_->setInterval(std::max(ms, 1)); }

void UnsavedWork::autosave() {
    const core::Workspace& w = context_.workspace;
    if (!w.modified() || !edited_since_autosave_ || writing_ || context_.busy() || !w.has_data()) return;
    edited_since_autosave_ = false;
    auto session = std::make_shared<core::Session>(w.session());
    if (input_hash_.first == session->input) session->input_sha256 = input_hash_.second;
    const QString path = recovery_path();
    QDir().mkpath(QFileInfo(path).absolutePath());
    // A quiet job: the input's SHA-256 (once per input) may take a while for
    // a large DICOM folder. save_session writes a temporary file beside the
    // recovery file and renames it into place: a kill leaves the old one or the new one.
    writing_ = true;
    context_.jobs.run(
        "Autosave",
        [session, p = path.toStdString()](const ProgressFn&) {
            if (session->input_sha256.empty()) session->input_sha256 = sha256_of_path(session->input);
            core::save_session(*session, p);
        },
        [this, session](std::exception_ptr e) {
            writing_ = false;
            if (e) {
                edited_since_autosave_ = true; // try again next time
                try {
                    std::rethrow_exception(e);
                } catch (const std::exception& ex) {
                    context_.status(QString("Autosave failed: ") + ex.what());
                }
                return;
            }
            input_hash_ = {session->input, session->input_sha256};
            ++autosaves_;
            // Saved or undone to the saved state meanwhile: nothing to recover.
            if (!context_.workspace.modified()) remove_recovery_file();
        },
        Jobs::Options{false, true});
}

void UnsavedWork::wait_for_autosave() {
    if (!writing_) return;
    context_.jobs.wait_all(false, true);
    writing_ = false;
}

void UnsavedWork::remove_recovery_file() {
    std::error_code ec;
    std::filesystem::remove(recovery_path().toStdString(), ec);
}

bool UnsavedWork::may_close(std::function<void()> close_again) {
    if (!closing_ && context_.workspace.modified()) {
        files_.ask_to_save("quitting", [this, close_again] {
            closing_ = true;
            // Queued: the question's box is still being closed.
            QTimer::singleShot(0, this, close_again);
        });
        return false;
    }
    // A clean exit: nothing to recover.
    closing_ = false;
    timer_->stop();
    wait_for_autosave();
    remove_recovery_file();
    return true;
}

void UnsavedWork::offer_recovery(std::function<void()> otherwise) {
    const QString path = recovery_path();
    if (!QFileInfo::exists(path)) {
        if (otherwise) otherwise();
        return;
    }
    const auto restore = [this, path] { files_.open_session(path, true); };
    const auto discard = [this, otherwise] {
        remove_recovery_file();
        if (otherwise) otherwise();
    };
    const QByteArray answer = qgetenv("ISOSCOPE_RECOVERY");
    if (answer == "restore" || answer == "discard") {
        answer == "restore" ? restore() : discard();
        return;
    }
    auto* box = new QMessageBox(QMessageBox::Question, "Recover unsaved work",
                                "isoscope ended without saving its last changes (a crash or a kill). A copy was "
                                "saved in\n" +
                                    path + "\nRestore it, or discard it?",
                                QMessageBox::NoButton, &context_.window);
    box->setObjectName("recovery");
    auto* restore_button = box->addButton("Restore", QMessageBox::AcceptRole);
    restore_button->setObjectName("restore");
    auto* discard_button = box->addButton(QMessageBox::Discard);
    discard_button->setObjectName("discard");
    box->setDefaultButton(restore_button);
    box->setAttribute(Qt::WA_DeleteOnClose);
    connect(box, &QMessageBox::finished, this, [box, restore_button, discard_button, restore, discard, otherwise](int) {
        if (box->clickedButton() == restore_button)
            restore();
        else if (box->clickedButton() == discard_button)
            discard();
        else if (otherwise) // closed without an answer: the file stays, offered again next time
            otherwise();
    });
    box->open();
}

} // namespace iso::gui
