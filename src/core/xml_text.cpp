#include "tripodal/core/xml_text.hpp"

#include <array>
#include <cstdio>

namespace tripodal {

std::optional<XmlTextFault> find_xml_text_fault(std::string_view text, bool refuse_discouraged_controls) noexcept {
  std::size_t i = 0, chars = 0;
  const auto fault = [&](std::uint32_t cp, bool invalid) { return XmlTextFault{i, chars, cp, invalid}; };
  while (i < text.size()) {
    const auto b = static_cast<unsigned char>(text[i]);
    if (b < 0x80) {
      if ((b < 0x20 && b != '\t' && b != '\n' && b != '\r') || (refuse_discouraged_controls && b == 0x7F)) return fault(b, false);
      ++i;
      ++chars;
      continue;
    }
    std::size_t len = 0;
    std::uint32_t cp = 0;
    if ((b & 0xE0U) == 0xC0U) {
      len = 2;
      cp = b & 0x1FU;
    } else if ((b & 0xF0U) == 0xE0U) {
      len = 3;
      cp = b & 0x0FU;
    } else if ((b & 0xF8U) == 0xF0U) {
      len = 4;
      cp = b & 0x07U;
    } else {
      return fault(b, true);
    }
    if (i + len > text.size()) return fault(b, true);
    for (std::size_t k = 1; k < len; ++k) {
      const auto c = static_cast<unsigned char>(text[i + k]);
      if ((c & 0xC0U) != 0x80U) return fault(b, true);
      cp = (cp << 6U) | (c & 0x3FU);
    }
    static constexpr std::array<std::uint32_t, 5> kLeast = {0, 0, 0x80, 0x800, 0x10000};
    // Overlong forms, surrogates (a UTF-16 half is no character) and code points beyond Unicode.
    if (cp < kLeast[len] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return fault(b, true);
    if (cp == 0xFFFE || cp == 0xFFFF || (refuse_discouraged_controls && cp <= 0x9F)) return fault(cp, false);
    i += len;
    ++chars;
  }
  return std::nullopt;
}

std::string describe(const XmlTextFault& fault) {
  char what[32];
  if (fault.invalid_utf8) {
    std::snprintf(what, sizeof what, "byte 0x%02X", static_cast<unsigned>(fault.code_point));
  } else {
    std::snprintf(what, sizeof what, "U+%04X", static_cast<unsigned>(fault.code_point));
  }
  return std::string(what) + " at character " + std::to_string(fault.char_offset) + " (byte " + std::to_string(fault.byte_offset) + ") " +
         (fault.invalid_utf8 ? "is not UTF-8" : "is not a character XML allows");
}

}  // namespace tripodal
