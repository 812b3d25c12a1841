// The decoder follows the table of well-formed byte sequences (Unicode 15,
// table 3-7): the second byte's range depends on the first, which is what
// rules out overlong forms and surrogates without decoding first.
#include "renderer/text/utf8.hpp"

#include <cstdint>

namespace iso::text {

namespace {

// The sequence length a lead byte starts (0: not a lead byte) and the range
// its second byte must lie in; every later byte is 0x80..0xBF.
struct Lead {
    int length;
    std::uint8_t lo, hi;
};
Lead lead(std::uint8_t b) {
    if (b >= 0xC2 && b <= 0xDF) return {2, 0x80, 0xBF};
    if (b == 0xE0) return {3, 0xA0, 0xBF}; // no overlong 3-byte forms
    if (b == 0xED) return {3, 0x80, 0x9F}; // no surrogates
    if (b >= 0xE1 && b <= 0xEF) return {3, 0x80, 0xBF};
    if (b == 0xF0) return {4, 0x90, 0xBF}; // no overlong 4-byte forms
    if (b == 0xF4) return {4, 0x80, 0x8F}; // nothing above U+10FFFF
    if (b >= 0xF1 && b <= 0xF3) return {4, 0x80, 0xBF};
    return {0, 0, 0}; // 0x80..0xC1 (continuations, overlong 2-byte leads), 0xF5..0xFF
}

} // namespace

std::u32string decode_utf8(std::string_view s) {
    std::u32string out;
    out.reserve(s.size());
    std::size_t i = 0;
    while (i < s.size()) {
        const auto b0 = static_cast<std::uint8_t>(s[i]);
        if (b0 < 0x80) {
            out.push_back(b0);
            ++i;
            continue;
        }
        const Lead l = lead(b0);
        if (l.length == 0) {
            out.push_back(kReplacement);
            ++i;
            continue;
        }
        char32_t cp = b0 & (0xFF >> (l.length + 1));
        std::size_t k = 1;
        for (; k < std::size_t(l.length) && i + k < s.size(); ++k) {
            const auto b = static_cast<std::uint8_t>(s[i + k]);
            const bool ok = k == 1 ? (b >= l.lo && b <= l.hi) : (b >= 0x80 && b <= 0xBF);
            if (!ok) break;
            cp = (cp << 6) | (b & 0x3F);
        }
        // A maximal subpart that is not a whole sequence is one U+FFFD; the
        // byte that broke it starts the next round.
        out.push_back(k == std::size_t(l.length) ? cp : kReplacement);
        i += k;
    }
    return out;
}

} // namespace iso::text
