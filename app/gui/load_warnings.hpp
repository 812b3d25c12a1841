// What loading said: a button in the status bar, shown only when the data
// just opened came with warnings (a DICOM folder's unreadable files skipped,
// missing slices filled in, a scout, NaN voxels, what the decoder said ...),
// "N load warning(s)", with every warning in its tooltip; a click lists them
// in a dialog. Presentation only: the warnings are the reader's
// (io/volume.hpp Metadata::warnings).
#pragma once

#include <string>
#include <vector>

#include <QToolButton>

namespace iso::gui {

class LoadWarnings : public QToolButton {
public:
    explicit LoadWarnings(QWidget* parent = nullptr);
    // The warnings of what was opened from `source`; none hides the button.
    void set(const QString& source, const std::vector<std::string>& warnings);
    const QStringList& warnings() const { return warnings_; }
    // Opens the dialog that lists them (what a click does).
    void show_list();

private:
    QString source_;
    QStringList warnings_;
};

} // namespace iso::gui
