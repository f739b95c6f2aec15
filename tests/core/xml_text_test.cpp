// XML 1.0's characters (tripodal/core/xml_text.hpp): what every saved text must be, and where a
// text is not.
#include "tripodal/core/xml_text.hpp"

#include <catch2/catch.hpp>

#include <string>

using namespace tripodal;

TEST_CASE("find_xml_text_fault accepts what XML 1.0 holds", "[core][xml]") {
  CHECK_FALSE(find_xml_text_fault(""));
  CHECK_FALSE(find_xml_text_fault("plain text\twith tab\nlines\r\n"));
  CHECK_FALSE(find_xml_text_fault("caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80"));  // é, €, an emoji (4 bytes)
  CHECK_FALSE(find_xml_text_fault("\xEF\xBF\xBD"));                              // U+FFFD, the last before the two
  CHECK_FALSE(find_xml_text_fault("\xF4\x8F\xBF\xBF"));                          // U+10FFFF
  CHECK_FALSE(find_xml_text_fault("\x7F \xC2\x85"));  // DEL and NEL: allowed, only discouraged ...
  CHECK(find_xml_text_fault("\x7F", true));            // ... refused when asked
  CHECK(find_xml_text_fault("\xC2\x85", true));
}

TEST_CASE("find_xml_text_fault finds the first character XML 1.0 forbids, by character and byte", "[core][xml]") {
  const auto at = [](const std::string& text) {
    const auto f = find_xml_text_fault(text);
    REQUIRE(f.has_value());
    return describe(*f);
  };
  CHECK(at("ab\xEF\xBF\xBE") == "U+FFFE at character 2 (byte 2) is not a character XML allows");
  CHECK(at("\xC3\xA9\xEF\xBF\xBF") == "U+FFFF at character 1 (byte 2) is not a character XML allows");
  CHECK(at(std::string("a\0b", 3)) == "U+0000 at character 1 (byte 1) is not a character XML allows");
  CHECK(at("x\x1B[31m") == "U+001B at character 1 (byte 1) is not a character XML allows");
  CHECK(at("\xED\xA0\x80") == "byte 0xED at character 0 (byte 0) is not UTF-8");       // a lone surrogate, encoded
  CHECK(at("ok\xFF") == "byte 0xFF at character 2 (byte 2) is not UTF-8");
  CHECK(at("\xC0\xAF") == "byte 0xC0 at character 0 (byte 0) is not UTF-8");           // overlong '/'
  CHECK(at("\xE2\x82") == "byte 0xE2 at character 0 (byte 0) is not UTF-8");           // cut short
  CHECK(at("\xF4\x90\x80\x80") == "byte 0xF4 at character 0 (byte 0) is not UTF-8");   // beyond U+10FFFF
  const auto f = find_xml_text_fault("\xC3\xA9\xC3\xA9\xEF\xBF\xBE");
  REQUIRE(f);
  CHECK(f->char_offset == 2);
  CHECK(f->byte_offset == 4);
  CHECK(f->code_point == 0xFFFE);
  CHECK_FALSE(f->invalid_utf8);
}
