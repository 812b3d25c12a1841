// The DICOM structure walk (io/dicom_structure.hpp): real files in every
// transfer syntax pass; files built here byte by byte with one fault each are
// refused with the offset and the reason; and whatever the walk accepts,
// vtk-dicom's own parser reads without an error (the two agree on where
// elements start).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkNew.h>

#include "io/dicom_structure.hpp"
#include "io/error.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::error_of;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

const std::string kCorpus = std::string(ISOSCOPE_SOURCE_DIR) + "/tests/fuzz/corpus/dicom/";
const std::string kExplicitLE = "1.2.840.10008.1.2.1", kImplicitLE = "1.2.840.10008.1.2";

// Elements written byte by byte, little or big endian.
struct Bytes {
    std::string b;
    bool big = false;
    Bytes& u16(unsigned v) {
        const char lo = char(v & 0xff), hi = char((v >> 8) & 0xff);
        b += big ? std::string{hi, lo} : std::string{lo, hi};
        return *this;
    }
    Bytes& u32(std::uint32_t v) { return big ? u16(v >> 16).u16(v & 0xffff) : u16(v & 0xffff).u16(v >> 16); }
    Bytes& tag(unsigned g, unsigned e) { return u16(g).u16(e); }
    // An explicit VR element; long VRs get the reserved bytes and a 32-bit length.
    Bytes& el(unsigned g, unsigned e, const std::string& vr, const std::string& value, std::uint32_t vl) {
        tag(g, e);
        b += vr;
        const bool long_vl = vr == "OB" || vr == "OW" || vr == "SQ" || vr == "UN" || vr == "UT" || vr == "OF";
        if (long_vl)
            u16(0).u32(vl);
        else
            u16(vl);
        b += value;
        return *this;
    }
    Bytes& el(unsigned g, unsigned e, const std::string& vr, const std::string& value) {
        return el(g, e, vr, value, std::uint32_t(value.size()));
    }
    Bytes& implicit(unsigned g, unsigned e, const std::string& value, std::uint32_t vl) {
        tag(g, e).u32(vl);
        b += value;
        return *this;
    }
    Bytes& implicit(unsigned g, unsigned e, const std::string& value) {
        return implicit(g, e, value, std::uint32_t(value.size()));
    }
    Bytes& item(std::uint32_t vl) { return tag(0xfffe, 0xe000).u32(vl); }
    Bytes& item_end() { return tag(0xfffe, 0xe00d).u32(0); }
    Bytes& seq_end() { return tag(0xfffe, 0xe0dd).u32(0); }
};

// Preamble, "DICM" and the file meta information naming `ts`, then `dataset`.
std::string part10(const std::string& ts, const std::string& dataset) {
    std::string uid = ts;
    if (uid.size() % 2) uid += '\0';
    Bytes meta;
    meta.el(0x0002, 0x0001, "OB", std::string("\0\1", 2)).el(0x0002, 0x0010, "UI", uid);
    Bytes gl;
    gl.tag(0x0002, 0x0000);
    gl.b += "UL";
    gl.u16(4).u32(std::uint32_t(meta.b.size()));
    return std::string(128, '\0') + "DICM" + gl.b + meta.b + dataset;
}

// A small explicit VR little endian data set with pixel data.
Bytes image_elements() {
    Bytes d;
    d.el(0x0008, 0x0060, "CS", "CT").el(0x0028, 0x0010, "US", std::string("\2\0", 2));
    d.el(0x0028, 0x0011, "US", std::string("\2\0", 2));
    return d;
}

std::string walk_error(const std::string& bytes) {
    return error_of([&] {
        check_dicom_structure(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "mem.dcm");
    });
}

DicomStructure walk(const std::string& bytes) {
    return check_dicom_structure(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "mem");
}

// vtk-dicom's parser reads what the walk accepted without an error.
void expect_vtk_dicom_reads(const std::string& bytes) {
    TempDir tmp;
    const std::string f = tmp / "a.dcm";
    iso::test::write_file(f, bytes);
    vtkNew<vtkDICOMParser> p;
    vtkNew<vtkDICOMMetaData> md;
    p->SetMetaData(md);
    p->SetFileName(f.c_str());
    p->Update();
    EXPECT_EQ(p->GetErrorCode(), 0u);
}

} // namespace

TEST(DicomStructure, RealFilesInEveryTransferSyntaxPass) {
    for (int i = 1; i <= 3; ++i) {
        const auto s = check_dicom_structure(iso::test::data("dicom-mr-forearm/1-" + std::to_string(i) + ".dcm"));
        EXPECT_EQ(s.transfer_syntax, kExplicitLE);
        EXPECT_TRUE(s.pixel_data);
        EXPECT_FALSE(s.encapsulated);
        EXPECT_GE(s.depth, 1); // the Siemens headers hold sequences
        EXPECT_GT(s.elements, 150u);
    }
    struct Case {
        const char* file;
        const char* ts;
        bool big, implicit, encapsulated;
    } cases[] = {
        {"mr32.dcm", "1.2.840.10008.1.2.1", false, false, false},
        {"mr32-implicit.dcm", "1.2.840.10008.1.2", false, true, false},
        {"mr32-bigendian.dcm", "1.2.840.10008.1.2.2", true, false, false},
        {"mr32-jpeg.dcm", "1.2.840.10008.1.2.4.70", false, false, true},
        {"mr32-jpeg-lossy.dcm", "1.2.840.10008.1.2.4.51", false, false, true},
        {"mr32-j2k.dcm", "1.2.840.10008.1.2.4.90", false, false, true},
        {"mr32-jpegls.dcm", "1.2.840.10008.1.2.4.80", false, false, true},
        {"mr32-rle.dcm", "1.2.840.10008.1.2.5", false, false, true},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.file);
        const auto s = check_dicom_structure(kCorpus + c.file);
        EXPECT_EQ(s.transfer_syntax, c.ts);
        EXPECT_EQ(s.big_endian, c.big);
        EXPECT_EQ(s.implicit_vr, c.implicit);
        EXPECT_TRUE(s.pixel_data);
        EXPECT_EQ(s.encapsulated, c.encapsulated);
        EXPECT_GE(s.depth, 1);
    }
    // Deflated: refused by name, with what to do about it.
    const std::string e = error_of([] { check_dicom_structure(kCorpus + "mr32-deflated.dcm"); });
    EXPECT_NE(e.find("Deflated"), std::string::npos) << e;
    EXPECT_NE(e.find("mr32-deflated.dcm"), std::string::npos) << e;
}

TEST(DicomStructure, TheFileThatAbortedVtkDicomIsRefusedWithItsOffset) {
    // 443 bytes whose file meta information runs into a value of undefined
    // length holding garbage: vtk-dicom copied it into a buffer whose size it
    // took from a length field of ~4 GiB, and asserted (issue 42).
    const std::string f = std::string(ISOSCOPE_SOURCE_DIR) +
                          "/tests/fuzz/regressions/dicom/crash-dicom-crash-314510707ba2abecdd6ccdea964749af198ea78c";
    const std::string e = error_of([&] { check_dicom_structure(f); });
    EXPECT_NE(
        e.find(f + ": malformed DICOM at byte 279: expected an item (FFFE,E000) in a sequence, found (FFFF,FFFF)"),
        std::string::npos)
        << e;
}

TEST(DicomStructure, LengthsMustFitTheirFileItemAndSequence) {
    Bytes d = image_elements();
    d.el(0x0010, 0x0010, "PN", "Doe^J ", 100);
    std::string e = walk_error(part10(kExplicitLE, d.b));
    EXPECT_NE(e.find("mem.dcm: malformed DICOM at byte "), std::string::npos) << e;
    EXPECT_NE(e.find("(0010,0010) claims 100 bytes, but only 6 remain in the file"), std::string::npos) << e;

    // Exactly fitting is fine, and vtk-dicom agrees.
    Bytes ok = image_elements();
    ok.el(0x0010, 0x0010, "PN", "Doe^J ").el(0x7fe0, 0x0010, "OW", std::string(8, '\7'));
    const auto s = walk(part10(kExplicitLE, ok.b));
    EXPECT_TRUE(s.pixel_data);
    expect_vtk_dicom_reads(part10(kExplicitLE, ok.b));

    // An element longer than its item, inside a sequence of defined length.
    Bytes inner;
    inner.el(0x0008, 0x0100, "SH", "T-D0 ", 40);
    Bytes item;
    item.item(std::uint32_t(inner.b.size())).b += inner.b;
    Bytes sq = image_elements();
    sq.el(0x0008, 0x1032, "SQ", item.b);
    e = walk_error(part10(kExplicitLE, sq.b));
    EXPECT_NE(e.find("(0008,0100) claims 40 bytes, but only 5 remain in its item"), std::string::npos) << e;

    // An item longer than its sequence.
    Bytes long_item = image_elements();
    Bytes it;
    it.item(64).b += std::string(8, '\0');
    long_item.el(0x0008, 0x1032, "SQ", it.b);
    e = walk_error(part10(kExplicitLE, long_item.b));
    EXPECT_NE(e.find("an item claims 64 bytes, but only 8 remain in its sequence"), std::string::npos) << e;
}

TEST(DicomStructure, SequencesNeedTheirDelimitersAndItems) {
    Bytes inner;
    inner.el(0x0008, 0x0100, "SH", "T-D0");
    // Undefined-length sequence and item, properly delimited: accepted.
    Bytes good = image_elements();
    good.el(0x0008, 0x1032, "SQ", "", 0xffffffffu).item(0xffffffffu).b += inner.b;
    good.item_end().seq_end();
    good.el(0x0010, 0x0010, "PN", "Doe^J ");
    const auto s = walk(part10(kExplicitLE, good.b));
    EXPECT_EQ(s.depth, 1);
    expect_vtk_dicom_reads(part10(kExplicitLE, good.b));

    // No item delimiter before the end of the file.
    Bytes open = image_elements();
    open.el(0x0008, 0x1032, "SQ", "", 0xffffffffu).item(0xffffffffu).b += inner.b;
    std::string e = walk_error(part10(kExplicitLE, open.b));
    EXPECT_NE(e.find("no item delimiter"), std::string::npos) << e;

    // Something other than an item in a sequence.
    Bytes stray = image_elements();
    stray.el(0x0008, 0x1032, "SQ", "", 0xffffffffu).b += inner.b;
    stray.seq_end();
    e = walk_error(part10(kExplicitLE, stray.b));
    EXPECT_NE(e.find("expected an item (FFFE,E000) in a sequence, found (0008,0100)"), std::string::npos) << e;

    // Items of a defined-length sequence that do not fill it.
    Bytes it;
    it.item(std::uint32_t(inner.b.size())).b += inner.b;
    Bytes gap = image_elements();
    gap.el(0x0008, 0x1032, "SQ", it.b + std::string(4, '\0'));
    e = walk_error(part10(kExplicitLE, gap.b));
    EXPECT_NE(e.find("do not add up to its length"), std::string::npos) << e;

    // An item tag at the top level.
    Bytes top = image_elements();
    top.item(0);
    e = walk_error(part10(kExplicitLE, top.b));
    EXPECT_NE(e.find("item outside a sequence"), std::string::npos) << e;
}

TEST(DicomStructure, NestingIsBoundedAt64Levels) {
    auto nested = [](int levels) {
        Bytes d = image_elements();
        for (int i = 0; i < levels; ++i) d.el(0x0040, 0xa730, "SQ", "", 0xffffffffu).item(0xffffffffu);
        d.el(0x0040, 0xa160, "UT", "x ");
        for (int i = 0; i < levels; ++i) d.item_end().seq_end();
        return part10(kExplicitLE, d.b);
    };
    EXPECT_EQ(walk(nested(kDicomMaxDepth)).depth, kDicomMaxDepth);
    expect_vtk_dicom_reads(nested(kDicomMaxDepth));
    const std::string e = walk_error(nested(kDicomMaxDepth + 1));
    EXPECT_NE(e.find("nested deeper than 64 levels"), std::string::npos) << e;
}

TEST(DicomStructure, EncapsulatedPixelDataIsFragmentsThenADelimiter) {
    const std::string jpeg = "1.2.840.10008.1.2.4.70";
    auto with_fragments = [&](const std::function<void(Bytes&)>& frags) {
        Bytes d = image_elements();
        d.el(0x7fe0, 0x0010, "OB", "", 0xffffffffu);
        frags(d);
        return part10(jpeg, d.b);
    };
    const std::string good = with_fragments([](Bytes& d) {
        d.item(0);                                                 // the basic offset table, empty
        d.item(6).b += std::string("\xff\xd8\x00\x01\xff\xd9", 6); // one fragment
        d.seq_end();
    });
    const auto s = walk(good);
    EXPECT_TRUE(s.encapsulated);
    expect_vtk_dicom_reads(good);
    std::string e = walk_error(with_fragments([](Bytes& d) { d.item(0).item(0xffffffffu).seq_end(); }));
    EXPECT_NE(e.find("a fragment of undefined length"), std::string::npos) << e;
    e = walk_error(with_fragments([](Bytes& d) { d.item(0).item(0xfffffff0u).b += "ab"; }));
    EXPECT_NE(e.find("a fragment claims 4294967280 bytes, but only 2 remain in the file"), std::string::npos) << e;
    e = walk_error(with_fragments([](Bytes& d) { d.item(0).item(2).b += "ab"; }));
    EXPECT_NE(e.find("encapsulated data has no sequence delimiter"), std::string::npos) << e;
    e = walk_error(with_fragments([](Bytes& d) { d.el(0x0008, 0x0100, "SH", "T-D0").seq_end(); }));
    EXPECT_NE(e.find("expected a fragment item"), std::string::npos) << e;
}

TEST(DicomStructure, VrsAndUndefinedLengthsAreRefusedWhereTheStandardHasNone) {
    Bytes bad_vr = image_elements();
    bad_vr.el(0x0010, 0x0010, "ZZ", "Doe^J ");
    std::string e = walk_error(part10(kExplicitLE, bad_vr.b));
    EXPECT_NE(e.find("(0010,0010) has an unknown VR 'ZZ'"), std::string::npos) << e;

    // VR bytes that are not text: vtk-dicom reads that one element as implicit
    // VR (some old writers did this); so does the walk.
    Bytes fallback = image_elements();
    fallback.tag(0x0010, 0x0020).u32(4).b += "1234";
    fallback.el(0x0010, 0x0030, "DA", "20091018");
    EXPECT_NO_THROW(walk(part10(kExplicitLE, fallback.b)));
    expect_vtk_dicom_reads(part10(kExplicitLE, fallback.b));

    // Only sequences and encapsulated data may have an undefined length.
    Bytes undefined = image_elements();
    undefined.el(0x0040, 0xa160, "UT", "", 0xffffffffu).seq_end();
    e = walk_error(part10(kExplicitLE, undefined.b));
    EXPECT_NE(e.find("(0040,A160) (VR UT) has an undefined length"), std::string::npos) << e;
}

TEST(DicomStructure, ImplicitVrFollowsVtkDicomsReading) {
    Bytes d;
    // A group length whose VL is wrong: vtk-dicom reads 4 bytes, whatever it says.
    d.implicit(0x0008, 0x0000, std::string(4, '\0'), 0x12345678);
    d.implicit(0x0008, 0x0060, "CT");
    // A sequence in implicit VR (the dictionary says SQ), undefined lengths.
    d.implicit(0x0008, 0x1032, "", 0xffffffffu).item(0xffffffffu).implicit(0x0008, 0x0100, "T-D0");
    d.item_end().seq_end();
    // A private element whose value starts like an item is walked as a sequence.
    Bytes priv;
    priv.item(8).implicit(0x0029, 0x0010, "");
    d.implicit(0x0029, 0x1010, priv.b);
    d.implicit(0x7fe0, 0x0010, std::string(8, '\1'));
    const auto s = walk(part10(kImplicitLE, d.b));
    EXPECT_TRUE(s.implicit_vr);
    EXPECT_TRUE(s.pixel_data);
    EXPECT_EQ(s.depth, 1);
    expect_vtk_dicom_reads(part10(kImplicitLE, d.b));

    // The private "sequence" with an item that overruns it.
    Bytes bad;
    Bytes over;
    over.item(12).implicit(0x0029, 0x0010, "");
    bad.implicit(0x0029, 0x1010, over.b);
    const std::string e = walk_error(part10(kImplicitLE, bad.b));
    EXPECT_NE(e.find("an item claims 12 bytes, but only 8 remain in its sequence"), std::string::npos) << e;
}

TEST(DicomStructure, BigEndianAndFilesWithoutMetaInformation) {
    Bytes be;
    be.big = true;
    be.el(0x0008, 0x0060, "CS", "CT").el(0x0010, 0x0010, "PN", "Doe^J ");
    be.el(0x7fe0, 0x0010, "OW", std::string(8, '\2'));
    const auto s = walk(part10("1.2.840.10008.1.2.2", be.b));
    EXPECT_TRUE(s.big_endian);
    EXPECT_TRUE(s.pixel_data);
    // A bare big endian data set (no preamble, no meta): guessed from (0008,...).
    const auto bare = walk(be.b);
    EXPECT_TRUE(bare.big_endian);
    EXPECT_EQ(bare.transfer_syntax, "");
    Bytes cut = be;
    cut.b.resize(cut.b.size() - 3);
    const std::string e = walk_error(cut.b);
    EXPECT_NE(e.find("(7FE0,0010) claims 8 bytes, but only 5 remain"), std::string::npos) << e;
    // A few trailing bytes after the last element are ignored, as vtk-dicom does.
    EXPECT_NO_THROW(walk(part10(kExplicitLE, image_elements().b + std::string(5, '\0'))));
}

TEST(DicomStructure, FileErrorsNameTheFile) {
    TempDir tmp;
    const std::string e = error_of([&] { check_dicom_structure(tmp / "missing.dcm"); });
    EXPECT_NE(e.find("missing.dcm: cannot read the file"), std::string::npos) << e;
}
