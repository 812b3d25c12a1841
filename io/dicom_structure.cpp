// The walk itself (see dicom_structure.hpp for why and what). Written by hand
// because no library on this machine checks a file without the very decoders
// that assert: vtk-dicom's parser and GDCM's reader are what we protect.
// vtk-dicom's own tables are used for what a VR is (vtkDICOMVR) and for the
// VR of public tags (vtkDICOMDictionary), so the two agree on both.
#include "io/dicom_structure.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include <vtkDICOMDictEntry.h>
#include <vtkDICOMDictionary.h>
#include <vtkDICOMTag.h>
#include <vtkDICOMVR.h>

#include "io/error.hpp"

namespace iso {
namespace {

constexpr std::uint32_t kUndefined = 0xffffffffu;
constexpr std::uint16_t kItemGroup = 0xfffe;
constexpr std::uint16_t kItem = 0xe000, kItemEnd = 0xe00d, kSequenceEnd = 0xe0dd;
// vtk-dicom copies an undefined-length value (other than the pixel data) into
// one buffer whose size must stay below 2^32 - 1 (its assertion).
constexpr std::uint64_t kMaxCopiedValue = 0xfffffff0u;

// The file's bytes: memory, or a file read through a window (values are
// skipped by arithmetic, so only element headers are read).
class Bytes {
public:
    explicit Bytes(std::span<const std::uint8_t> mem) : mem_(mem), size_(mem.size()) {}
    Bytes(std::ifstream& f, std::uint64_t size, const std::string& name) : file_(&f), size_(size), name_(name) {}
    std::uint64_t size() const { return size_; }
    // n <= 64 bytes at `at`; the caller has checked at + n <= size().
    void get(std::uint64_t at, std::uint8_t* out, std::size_t n) {
        if (!file_) {
            std::memcpy(out, mem_.data() + at, n);
            return;
        }
        if (at < window_at_ || at + n > window_at_ + window_.size()) fill(at);
        std::memcpy(out, window_.data() + (at - window_at_), n);
    }

private:
    void fill(std::uint64_t at) {
        constexpr std::uint64_t kWindow = 1 << 16;
        window_.resize(std::size_t(std::min(kWindow, size_ - at)));
        window_at_ = at;
        file_->clear();
        file_->seekg(std::streamoff(at));
        file_->read(reinterpret_cast<char*>(window_.data()), std::streamsize(window_.size()));
        if (std::uint64_t(file_->gcount()) != window_.size()) throw Error(name_, "cannot read the file (read failed)");
    }
    std::span<const std::uint8_t> mem_;
    std::ifstream* file_ = nullptr;
    std::uint64_t size_ = 0;
    std::string name_;
    std::vector<std::uint8_t> window_;
    std::uint64_t window_at_ = 0;
};

struct Encoding {
    bool big = false;
    bool implicit = false;
};

// One element's header as vtk-dicom's decoder reads it.
struct Head {
    std::uint64_t at = 0, value = 0; // where the tag and the value start
    std::uint16_t group = 0, element = 0;
    std::uint32_t vl = 0;
    vtkDICOMVR vr;            // as written (explicit VR); invalid when implicit
    bool vr_fallback = false; // explicit VR file, VR bytes not text: read as implicit
};

std::string hex4(unsigned v) {
    char b[8];
    std::snprintf(b, sizeof b, "%04X", v & 0xffffu);
    return b;
}

std::string tag_text(std::uint16_t g, std::uint16_t e) { return "(" + hex4(g) + "," + hex4(e) + ")"; }

bool printable(std::uint8_t c) { return c >= 0x20 && c < 0x7f; }

class Walker {
public:
    Walker(Bytes& b, std::string name) : b_(b), name_(std::move(name)) {}
    DicomStructure run();

private:
    [[noreturn]] void fail(std::uint64_t at, const std::string& why) const {
        throw Error(name_, "malformed DICOM at byte " + std::to_string(at) + ": " + why);
    }
    std::uint16_t u16(std::uint64_t at, bool big) {
        std::uint8_t p[2];
        b_.get(at, p, 2);
        return big ? std::uint16_t(p[0] << 8 | p[1]) : std::uint16_t(p[1] << 8 | p[0]);
    }
    std::uint32_t u32(std::uint64_t at, bool big) {
        std::uint8_t p[4];
        b_.get(at, p, 4);
        return big ? std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3]
                   : std::uint32_t(p[3]) << 24 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[1]) << 8 | p[0];
    }
    Head head(std::uint64_t at, std::uint64_t end, Encoding enc);
    std::uint64_t meta(std::uint64_t at);
    void choose_encoding(std::uint64_t at);
    std::uint64_t value(const Head& h, std::uint64_t end, Encoding enc, int depth, bool top, const char* in);
    bool looks_like_sequence(const Head& h, Encoding enc);
    std::uint64_t elements(std::uint64_t at, std::uint64_t end, bool delimited, Encoding enc, int depth, bool top,
                           const char* in);
    std::uint64_t items(std::uint64_t at, std::uint32_t vl, std::uint64_t end, Encoding enc, int depth, const char* in);
    std::uint64_t fragments(std::uint64_t at, std::uint64_t end, Encoding enc, const char* in);

    Bytes& b_;
    std::string name_;
    DicomStructure out_;
    Encoding enc_;
};

// The header at `at` (8 bytes available before `end`, checked by the caller).
Head Walker::head(std::uint64_t at, std::uint64_t end, Encoding enc) {
    Head h;
    h.at = at;
    h.group = u16(at, enc.big);
    h.element = u16(at + 2, enc.big);
    if (enc.implicit || h.group == kItemGroup) {
        h.vl = u32(at + 4, enc.big);
        // vtk-dicom reads an implicit group length as 4 bytes whatever its VL says.
        if (h.element == 0x0000) h.vl = 4;
        h.value = at + 8;
        return h;
    }
    std::uint8_t vr[2];
    b_.get(at + 4, vr, 2);
    h.vr = vtkDICOMVR(vr);
    if (!h.vr.IsValid()) {
        if (printable(vr[0]) && printable(vr[1]))
            fail(at, "element " + tag_text(h.group, h.element) + " has an unknown VR '" + std::string(1, char(vr[0])) +
                         std::string(1, char(vr[1])) + "'");
        // Not text: vtk-dicom reads this one element as implicit VR.
        h.vr_fallback = true;
        h.vl = u32(at + 4, enc.big);
        h.value = at + 8;
        return h;
    }
    if (h.vr.HasLongVL()) {
        if (end - at < 12) fail(at, "element " + tag_text(h.group, h.element) + "'s header is cut short");
        h.vl = u32(at + 8, enc.big);
        h.value = at + 12;
    } else {
        h.vl = u16(at + 6, enc.big);
        h.value = at + 8;
    }
    return h;
}

// The file meta information (group 0002), read as vtk-dicom reads it: explicit
// VR little endian unless the first VR is not one, bounded by the group
// length (wrapping as its 32-bit sum does) and by the group changing.
std::uint64_t Walker::meta(std::uint64_t at) {
    if (b_.size() - at < 8 || u16(at, false) != 0x0002) return at;
    std::uint8_t vr[2];
    b_.get(at + 4, vr, 2);
    const Encoding enc{false, !vtkDICOMVR(vr).IsValid()};
    std::uint32_t limit = kUndefined;
    if (u16(at + 2, false) == 0x0000 && u16(at + 6, false) == 4 && b_.size() - at >= 12)
        limit = u32(at + 8, false) + 12u;
    std::uint64_t pos = at;
    while (limit == kUndefined || pos - at < limit) {
        if (b_.size() - pos < 8 || u16(pos, false) != 0x0002) break;
        const Head h = head(pos, b_.size(), enc);
        const std::uint64_t next = value(h, b_.size(), enc, 0, false, "the file"); // checks the length
        if (h.element == 0x0010) {
            if ((h.vr.IsValid() && h.vr != vtkDICOMVR::UI) || h.vl == kUndefined || h.vl > 256)
                fail(pos, "TransferSyntaxUID (0002,0010) is not a UID");
            std::string ts(h.vl, '\0');
            for (std::uint32_t i = 0; i < h.vl; ++i) b_.get(h.value + i, reinterpret_cast<std::uint8_t*>(&ts[i]), 1);
            // As vtk-dicom's AsString: up to the first NUL, spaces trimmed.
            ts = ts.substr(0, ts.find('\0'));
            ts.erase(0, ts.find_first_not_of(' '));
            ts.erase(ts.find_last_not_of(' ') + 1);
            out_.transfer_syntax = ts;
        }
        pos = next;
    }
    return pos;
}

// The data set's encoding, chosen as vtk-dicom chooses it.
void Walker::choose_encoding(std::uint64_t at) {
    const std::string& ts = out_.transfer_syntax;
    if (ts.empty()) {
        if (b_.size() - at < 8) return;
        std::uint8_t p[6];
        b_.get(at, p, 6);
        enc_.big = p[0] == 0x00 && p[1] == 0x08;
        enc_.implicit = !vtkDICOMVR(p + 4).IsValid();
    } else if (ts == "1.2.840.10008.1.2" || ts == "1.2.840.10008.1.20" || ts == "1.2.840.113619.5.2") {
        enc_.implicit = true;
    } else if (ts == "1.2.840.10008.1.2.2") {
        enc_.big = true;
    } else if (ts == "1.2.840.10008.1.2.1.99") {
        throw Error(name_, "the Deflated Explicit VR Little Endian transfer syntax (1.2.840.10008.1.2.1.99) is not "
                           "supported; convert the file, e.g. with 'gdcmconv --raw' or 'dcmconv +te'");
    }
    out_.big_endian = enc_.big;
    out_.implicit_vr = enc_.implicit;
}

DicomStructure Walker::run() {
    std::uint64_t at = 0;
    std::uint8_t magic[4];
    if (b_.size() >= 132 && (b_.get(128, magic, 4), std::memcmp(magic, "DICM", 4) == 0))
        at = 132;
    else if (b_.size() >= 4 && (b_.get(0, magic, 4), std::memcmp(magic, "DICM", 4) == 0))
        at = 4;
    at = meta(at);
    choose_encoding(at);
    elements(at, b_.size(), false, enc_, 0, true, "the file");
    return out_;
}

// A value of defined length that vtk-dicom may decode as a sequence although
// nothing says SQ (implicit VR, explicit UN, a VR fallback): the dictionary's
// VR where it knows the (public) tag, else whether an item tag comes first.
// The pixel data groups are never sequences to vtk-dicom.
bool Walker::looks_like_sequence(const Head& h, Encoding enc) {
    if ((h.group & 0xff01u) == 0x7f00u || h.vl < 4) return false;
    if (h.group % 2 == 0) {
        const vtkDICOMDictEntry e = vtkDICOMDictionary::FindDictEntry(vtkDICOMTag(h.group, h.element));
        if (e.IsValid()) return e.GetVR() == vtkDICOMVR::SQ;
    }
    return u16(h.value, enc.big) == kItemGroup && u16(h.value + 2, enc.big) == kItem;
}

// Checks one element's value (its header read) and returns where the next
// element starts. `end` is where its item, sequence or the file ends.
std::uint64_t Walker::value(const Head& h, std::uint64_t end, Encoding enc, int depth, bool top, const char* in) {
    ++out_.elements;
    const bool pixels = h.group == 0x7fe0 && h.element == 0x0010;
    const bool pixel_group = top && (h.group & 0xff01u) == 0x7f00u && h.element != 0;
    if (top && pixels) out_.pixel_data = true;
    const std::string what = "element " + tag_text(h.group, h.element);
    // An explicit UN holds implicit little endian (DICOM PS3.5 6.2.2), as vtk-dicom reads it.
    const Encoding inner = (h.vr == vtkDICOMVR::UN) ? Encoding{false, true} : enc;
    if (h.vl != kUndefined) {
        if (h.vl > end - h.value)
            fail(h.at, what + " claims " + std::to_string(h.vl) + " bytes, but only " + std::to_string(end - h.value) +
                           " remain in " + in + " (truncated or corrupt)");
        if (h.vr == vtkDICOMVR::SQ || ((!h.vr.IsValid() || h.vr == vtkDICOMVR::UN) && looks_like_sequence(h, inner)))
            items(h.value, h.vl, h.value + h.vl, inner, depth + 1, in);
        return h.value + h.vl;
    }
    if (h.vr_fallback) fail(h.at, what + " has neither a VR nor a defined length");
    std::uint64_t next;
    const bool implicit = !h.vr.IsValid();
    if (h.vr == vtkDICOMVR::OB || h.vr == vtkDICOMVR::OW || (implicit && pixels)) {
        if (top && pixels) out_.encapsulated = true;
        next = fragments(h.value, end, enc, in);
    } else if (h.vr == vtkDICOMVR::SQ || h.vr == vtkDICOMVR::UN || implicit) {
        next = items(h.value, kUndefined, end, inner, depth + 1, in);
    } else {
        fail(h.at, what + " (VR " + h.vr.GetText() +
                       ") has an undefined length, which only sequences and "
                       "encapsulated data may have");
    }
    if (!pixel_group && next - h.value > kMaxCopiedValue) fail(h.at, what + " holds 4 GiB or more");
    return next;
}

// The elements of the file, an item of defined length (up to `end`) or a
// delimited item (up to its item delimiter); returns where they end.
std::uint64_t Walker::elements(std::uint64_t at, std::uint64_t end, bool delimited, Encoding enc, int depth, bool top,
                               const char* in) {
    std::uint64_t pos = at;
    for (;;) {
        if (pos == end && !delimited) return end;
        if (end - pos < 8) {
            // vtk-dicom ignores a few trailing bytes after the last element.
            if (top) return end;
            fail(pos, delimited
                          ? std::string("an item of undefined length has no item delimiter before the end of ") + in
                          : "an element's header crosses the end of its item");
        }
        const Head h = head(pos, end, enc);
        if (h.group == kItemGroup) {
            if (h.element == kItemEnd && delimited) return h.value;
            // An item delimiter closing an item of defined length is tolerated.
            if (h.element == kItemEnd && !top && h.value == end) return end;
            fail(pos, "unexpected " + tag_text(h.group, h.element) +
                          (h.element == kItem ? " item outside a sequence" : " delimiter"));
        }
        pos = value(h, end, enc, depth, top, in);
    }
}

// A sequence's items, of length `vl` or up to its sequence delimiter.
// `in` names what holds the sequence when its length is undefined.
std::uint64_t Walker::items(std::uint64_t at, std::uint32_t vl, std::uint64_t end, Encoding enc, int depth,
                            const char* in) {
    if (depth > kDicomMaxDepth) fail(at, "sequences nested deeper than " + std::to_string(kDicomMaxDepth) + " levels");
    out_.depth = std::max(out_.depth, depth);
    const bool defined = vl != kUndefined;
    const std::uint64_t send = defined ? at + vl : end;
    std::uint64_t pos = at;
    for (;;) {
        if (defined && pos == send) return send;
        if (send - pos < 8)
            fail(pos,
                 defined
                     ? "a sequence's items do not add up to its length"
                     : std::string("a sequence of undefined length has no sequence delimiter before the end of ") + in);
        const std::uint16_t g = u16(pos, enc.big), e = u16(pos + 2, enc.big);
        const std::uint32_t il = u32(pos + 4, enc.big);
        if (g == kItemGroup && e == kSequenceEnd) {
            // A delimiter is tolerated at the very end of a sequence of defined length.
            if (!defined || pos + 8 == send) return pos + 8;
            fail(pos, "a sequence delimiter inside a sequence of defined length");
        }
        if (g != kItemGroup || e != kItem)
            fail(pos, "expected an item (FFFE,E000) in a sequence, found " + tag_text(g, e));
        ++out_.elements;
        if (il == kUndefined) {
            pos = elements(pos + 8, send, true, enc, depth, false, defined ? "its sequence" : in);
        } else {
            if (il > send - (pos + 8))
                fail(pos, "an item claims " + std::to_string(il) + " bytes, but only " +
                              std::to_string(send - pos - 8) + " remain in its sequence");
            pos = elements(pos + 8, pos + 8 + il, false, enc, depth, false, "its item");
        }
    }
}

// Encapsulated data: fragment items of defined length, then a sequence delimiter.
std::uint64_t Walker::fragments(std::uint64_t at, std::uint64_t end, Encoding enc, const char* in) {
    std::uint64_t pos = at;
    for (;;) {
        if (end - pos < 8)
            fail(pos, std::string("encapsulated data has no sequence delimiter before the end of ") + in);
        const std::uint16_t g = u16(pos, enc.big), e = u16(pos + 2, enc.big);
        const std::uint32_t il = u32(pos + 4, enc.big);
        if (g == kItemGroup && e == kSequenceEnd) return pos + 8;
        if (g != kItemGroup || e != kItem)
            fail(pos, "expected a fragment item (FFFE,E000) in encapsulated data, found " + tag_text(g, e));
        if (il == kUndefined) fail(pos, "a fragment of undefined length in encapsulated data");
        if (il > end - (pos + 8))
            fail(pos, "a fragment claims " + std::to_string(il) + " bytes, but only " + std::to_string(end - pos - 8) +
                          " remain in " + in + " (truncated or corrupt)");
        ++out_.elements;
        pos += 8 + std::uint64_t(il);
    }
}

} // namespace

DicomStructure check_dicom_structure(std::span<const std::uint8_t> bytes, const std::string& name) {
    Bytes b(bytes);
    return Walker(b, name).run();
}

DicomStructure check_dicom_structure(const std::string& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw Error(path, "cannot read the file (" + ec.message() + ")");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path, "cannot open the file");
    Bytes b(f, size, path);
    return Walker(b, path).run();
}

} // namespace iso
