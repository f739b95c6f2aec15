// XML 1.0's characters (core area, under every area that saves text): whether a text can be
// written into an XML document and read back, and where it cannot. The knowledge store refuses an
// entry that fails it (with the place) before anything is saved, and so does the monitor's
// operator request layer for every string a request carries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace tripodal {

/// The first character of a text that XML 1.0 does not allow.
struct XmlTextFault {
  std::size_t byte_offset = 0;  ///< where its bytes start
  std::size_t char_offset = 0;  ///< the characters (code points) before it
  /// The character; for bytes that are not UTF-8 (`invalid_utf8`), the first of them.
  std::uint32_t code_point = 0;
  bool invalid_utf8 = false;  ///< a byte that starts no character, a cut or overlong sequence, a surrogate
};

/// The first fault of `text`: invalid UTF-8 (including encoded surrogates, overlong forms and code
/// points beyond U+10FFFF), a control character other than tab, line feed and carriage return,
/// U+FFFE or U+FFFF (XML 1.0's Char production). With `refuse_discouraged_controls`, DEL and the C1
/// controls (U+007F..U+009F, which XML allows but discourages) too. nullopt: the text is fine.
[[nodiscard]] std::optional<XmlTextFault> find_xml_text_fault(std::string_view text,
                                                              bool refuse_discouraged_controls = false) noexcept;

/// "U+FFFE at character 3 (byte 5) is not a character XML allows" or "byte 0xFF at character 0
/// (byte 0) is not UTF-8".
[[nodiscard]] std::string describe(const XmlTextFault& fault);

}  // namespace tripodal
