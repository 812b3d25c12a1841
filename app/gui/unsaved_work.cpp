// MainWindow's guard of unsaved work (docs/gui.md "Unsaved work", docs/sessions.md
// "Recovery file"): the title's "*" from the undo stack's clean state, the
// Save / Discard / Cancel question before quitting or opening something
// else, autosave to the recovery file and the offer to restore it at start.
// Member functions of MainWindow kept out of main_window.cpp; the session
// format and its atomic write are the core's (renderer/core/session.hpp).
#include <QCloseEvent>
#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QMessageBox>
#include <QPushButton>
#include <QStandardPaths>
#include <QStatusBar>
#include <QThread>
#include <QTimer>
#include <QUndoStack>

#include <cstdlib>
#include <filesystem>

#include "app/gui/main_window.hpp"
#include "io/error.hpp"
#include "io/image.hpp"
#include "renderer/core/session.hpp"

namespace iso::gui {

namespace {
constexpr int kAutosaveMs = 60000;

QString error_text(std::exception_ptr e) {
    try {
        std::rethrow_exception(e);
    } catch (const std::exception& ex) {
        return QString::fromStdString(ex.what());
    } catch (...) {
        return "unknown error";
    }
}
} // namespace

bool MainWindow::modified() const { return !undo_->isClean(); }

QString MainWindow::recovery_path() {
    return QDir(QStandardPaths::writableLocation(QStandardPaths::AppConfigLocation)).filePath("recovery.isoscope.json");
}

void MainWindow::watch_unsaved_work() {
    autosave_timer_ = new QTimer(this);
    autosave_timer_->setInterval(kAutosaveMs);
    if (const char* ms = std::getenv("ISOSCOPE_AUTOSAVE_MS"); ms && std::atoi(ms) > 0)
        autosave_timer_->setInterval(std::atoi(ms));
    connect(autosave_timer_, &QTimer::timeout, this, [this] { autosave(); });
    connect(undo_, &QUndoStack::cleanChanged, this, [this](bool clean) {
        setWindowModified(!clean);
        clean ? autosave_timer_->stop() : autosave_timer_->start();
    });
    connect(undo_, &QUndoStack::indexChanged, this, [this] { edited_since_autosave_ = true; });
}

void MainWindow::set_autosave_interval(int ms) { autosave_timer_->setInterval(std::max(ms, 1)); }

void MainWindow::autosave() {
    if (!modified() || !edited_since_autosave_ || autosave_thread_ || busy() || path_.isEmpty()) return;
    edited_since_autosave_ = false;
    auto session = std::make_shared<core::Session>(current_session());
    if (input_hash_.first == session->input) session->input_sha256 = input_hash_.second;
    auto error = std::make_shared<std::exception_ptr>();
    const QString path = recovery_path();
    QDir().mkpath(QFileInfo(path).absolutePath());
    // On a worker: the input's SHA-256 (once per input) may take a while for a
    // large DICOM folder. save_session writes a temporary file beside the
    // recovery file and renames it into place: a kill leaves the old one or the new one.
    autosave_thread_ = QThread::create([session, error, p = path.toStdString()] {
        try {
            if (session->input_sha256.empty()) session->input_sha256 = sha256_of_path(session->input);
            core::save_session(*session, p);
        } catch (...) {
            *error = std::current_exception();
        }
    });
    connect(autosave_thread_, &QThread::finished, this, [this, session, error, path] {
        autosave_thread_->deleteLater();
        autosave_thread_ = nullptr;
        if (*error) {
            edited_since_autosave_ = true; // try again next time
            statusBar()->showMessage("Autosave failed: " + error_text(*error));
            return;
        }
        input_hash_ = {session->input, session->input_sha256};
        ++autosaves_;
        // Saved or undone to the saved state meanwhile: nothing to recover.
        if (!modified()) remove_recovery_file();
    });
    autosave_thread_->start();
}

void MainWindow::wait_for_autosave() {
    if (!autosave_thread_) return;
    QObject::disconnect(autosave_thread_, nullptr, this, nullptr);
    autosave_thread_->wait();
    delete autosave_thread_;
    autosave_thread_ = nullptr;
}

void MainWindow::remove_recovery_file() {
    std::error_code ec;
    std::filesystem::remove(recovery_path().toStdString(), ec);
}

void MainWindow::ask_to_save(const QString& doing, std::function<void()> proceed) {
    if (!modified()) {
        proceed();
        return;
    }
    if (findChild<QMessageBox*>("unsaved")) return; // asking already
    auto* box = new QMessageBox(QMessageBox::Warning, "Unsaved changes",
                                "The surfaces or measurements changed since the session was last saved or "
                                "opened.\nSave them as a session before " +
                                    doing + "?",
                                QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, this);
    box->setObjectName("unsaved");
    box->setDefaultButton(QMessageBox::Save);
    box->setAttribute(Qt::WA_DeleteOnClose);
    connect(box, &QMessageBox::finished, this, [this, box, doing, proceed](int) {
        const auto answer = box->standardButton(box->clickedButton());
        if (answer == QMessageBox::Discard) {
            // Not worth recovering any more; while the window still shows it, the next autosave writes it again.
            wait_for_autosave();
            remove_recovery_file();
            edited_since_autosave_ = true;
            proceed();
        } else if (answer == QMessageBox::Save) {
            const QString start = session_path_.isEmpty() ? QDir::home().filePath("session.isoscope.json") : "";
            const QString path = session_path_.isEmpty() ? QFileDialog::getSaveFileName(this, "Save session", start,
                                                                                        "isoscope sessions (*.json)")
                                                         : session_path_;
            if (path.isEmpty()) return; // no file chosen: as Cancel
            save_session(path, proceed);
        } else {
            statusBar()->showMessage(doing.left(1).toUpper() + doing.mid(1) + ": cancelled");
        }
    });
    box->open(); // window-modal, not exec(): the event loop (and tests) go on
}

void MainWindow::closeEvent(QCloseEvent* e) {
    if (!closing_ && modified()) {
        e->ignore();
        ask_to_save("quitting", [this] {
            closing_ = true;
            // Queued: the question's box is still being closed.
            QTimer::singleShot(0, this, [this] { close(); });
        });
        return;
    }
    // A clean exit: nothing to recover.
    closing_ = false;
    autosave_timer_->stop();
    wait_for_autosave();
    remove_recovery_file();
    QMainWindow::closeEvent(e);
}

void MainWindow::offer_recovery(std::function<void()> otherwise) {
    const QString path = recovery_path();
    if (!QFileInfo::exists(path)) {
        if (otherwise) otherwise();
        return;
    }
    const auto restore = [this, path] { open_session(path, true); };
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
                                QMessageBox::NoButton, this);
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
