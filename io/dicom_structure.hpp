// A bounds-checked walk of a DICOM file's element structure, made before
// vtk-dicom or GDCM reads the file (io/dicom.cpp).
//
// Why our own walk: Debian builds vtk-dicom and GDCM with their assertions
// on, and vtk-dicom asserts (aborting the process) when a value length that
// nothing checked against the file's size reaches an allocation: a 443-byte
// file whose length field says 4 GiB kills isoscope. The walk refuses such
// a file with an iso::Error naming it and the byte offset, so the library
// only ever sees files whose every length fits.
//
// What is checked: the preamble and "DICM", the file meta information
// (explicit VR little endian, or implicit where the file says so, as
// vtk-dicom reads it), the transfer syntax's byte order and VR encoding,
// every element's VR (explicit VR files) and length against what is left of
// its item, sequence and file, sequences and items of defined and undefined
// length with their delimiters, nesting depth (at most 64), and encapsulated
// pixel data (fragment items of defined length, ended by a sequence
// delimiter). Element boundaries follow vtk-dicom's decoder where the
// standard leaves room (group lengths in implicit VR, elements whose VR bytes
// are not text read as implicit, a UN value being implicit little endian),
// so the walk and the library agree on where every element starts.
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace iso {

// What the walk saw (the tests read it; the reader needs only the verdict).
struct DicomStructure {
    std::string transfer_syntax; // from the file meta information; "" without one
    bool big_endian = false, implicit_vr = false;
    std::uint64_t elements = 0; // data elements and items, nested ones included
    int depth = 0;              // deepest sequence nesting
    bool pixel_data = false;    // a top-level (7FE0,0010)
    bool encapsulated = false;  // ... in fragments
};

// Deepest sequence nesting accepted.
inline constexpr int kDicomMaxDepth = 64;

// Walks the file; throws iso::Error(path, "malformed DICOM at byte N: ...")
// for a structure the libraries must not see, or "cannot read" for I/O.
DicomStructure check_dicom_structure(const std::string& path);
// The same over bytes in memory; errors name `name`.
DicomStructure check_dicom_structure(std::span<const std::uint8_t> bytes, const std::string& name);

} // namespace iso
