#include "app/gui/load_warnings.hpp"

#include <QMessageBox>
#include <QStyle>

namespace iso::gui {

LoadWarnings::LoadWarnings(QWidget* parent) : QToolButton(parent) {
    setObjectName("load_warnings");
    setAutoRaise(true);
    setToolButtonStyle(Qt::ToolButtonTextBesideIcon);
    setIcon(style()->standardIcon(QStyle::SP_MessageBoxWarning));
    setToolTip("What opening the data warned about");
    hide();
    connect(this, &QToolButton::clicked, this, &LoadWarnings::show_list);
}

void LoadWarnings::set(const QString& source, const std::vector<std::string>& warnings) {
    source_ = source;
    warnings_.clear();
    for (const auto& w : warnings) warnings_ << QString::fromStdString(w);
    const auto n = warnings_.size();
    setText(QString("%1 load warning%2").arg(n).arg(n == 1 ? "" : "s"));
    setToolTip("Opening " + source + " said:\n- " + warnings_.join("\n- ") + "\n(click to list them)");
    setVisible(n > 0);
}

void LoadWarnings::show_list() {
    if (warnings_.isEmpty()) return;
    auto* box = new QMessageBox(QMessageBox::Warning, "Load warnings",
                                "Opening " + source_ + " said:", QMessageBox::Close, window());
    box->setObjectName("load_warnings_list");
    box->setAttribute(Qt::WA_DeleteOnClose);
    box->setInformativeText("- " + warnings_.join("\n- "));
    box->setTextInteractionFlags(Qt::TextSelectableByMouse);
    box->open(); // window-modal, not exec(): the event loop (and tests) go on
}

} // namespace iso::gui
