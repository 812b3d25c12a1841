// UTF-8 to code points for the overlay's text. Labels come from files
// (Slicer markups, sessions) and the user, so any byte sequence must decode
// to something drawable without reading past the end: what is not
// well-formed UTF-8 becomes U+FFFD, one per maximal ill-formed subpart as
// Unicode 15 (section 3.9, "U+FFFD Substitution of Maximal Subparts") and
// the WHATWG Encoding standard recommend.
#pragma once

#include <string>
#include <string_view>

namespace iso::text {

inline constexpr char32_t kReplacement = 0xFFFD;

// Code points of `utf8`: overlong forms, surrogates (U+D800..U+DFFF), values
// above U+10FFFF, stray continuation bytes and sequences cut short (also by
// the end of the string) each give one U+FFFD. Reads only utf8[0, size()).
std::u32string decode_utf8(std::string_view utf8);

} // namespace iso::text
