#include "xml_document.hpp"

#include <tinyxml2.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>

namespace tripodal::detail {

namespace {

struct ParseFailure {
  std::size_t offset = 0;
  std::string message;
};

bool is_xml_char(std::uint32_t cp) noexcept {
  return cp == 0x9 || cp == 0xA || cp == 0xD || (cp >= 0x20 && cp <= 0xD7FF) || (cp >= 0xE000 && cp <= 0xFFFD) ||
         (cp >= 0x10000 && cp <= 0x10FFFF);
}

bool is_blank(char c) noexcept { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

std::size_t utf8_length(std::uint32_t cp) noexcept { return cp < 0x80 ? 1 : cp < 0x800 ? 2 : cp < 0x10000 ? 3 : 4; }

std::string byte_text(unsigned char b) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  return std::string("0x") + kHex[b >> 4] + kHex[b & 15];
}

// Whether 32 bytes are all printable ASCII, tab, LF or CR: a reduction without branches, which
// the compiler vectorises. Only the blocks it flags are looked at one character at a time.
bool plain_block(const unsigned char* p) noexcept {
  unsigned char odd = 0;
  for (int k = 0; k < 32; ++k) {
    const unsigned char b = p[k];
    // Bitwise, not short-circuit: one vector compare per term.
    odd |= static_cast<unsigned char>((static_cast<unsigned char>(b - 0x20) >= 0x60) & (b != '\t') & (b != '\n') &
                                      (b != '\r'));
  }
  return odd == 0;
}

// The offset past the character at p[i]; throws at a control character or invalid UTF-8.
std::size_t check_character(const unsigned char* p, std::size_t n, std::size_t i) {
  const unsigned char b = p[i];
  if (b < 0x80) {
    if (b < 0x20 && b != '\t' && b != '\n' && b != '\r') {
      throw ParseFailure{i, "control character " + byte_text(b) + " is not allowed in XML"};
    }
    return i + 1;
  }
  std::size_t len = 0;
  std::uint32_t cp = 0;
  if (b >= 0xC2 && b <= 0xDF) {
    len = 2;
    cp = b & 0x1FU;
  } else if (b >= 0xE0 && b <= 0xEF) {
    len = 3;
    cp = b & 0x0FU;
  } else if (b >= 0xF0 && b <= 0xF4) {
    len = 4;
    cp = b & 0x07U;
  } else {
    throw ParseFailure{i, "invalid UTF-8: byte " + byte_text(b) +
                              " cannot start a character (save the file as UTF-8, or declare encoding=\"ISO-8859-1\")"};
  }
  if (i + len > n) throw ParseFailure{i, "invalid UTF-8: the file ends inside a character"};
  for (std::size_t k = 1; k < len; ++k) {
    const unsigned char c = p[i + k];
    if ((c & 0xC0U) != 0x80U) {
      throw ParseFailure{i, "invalid UTF-8: byte " + byte_text(b) + " is not followed by a continuation byte"};
    }
    cp = (cp << 6) | (c & 0x3FU);
  }
  const bool overlong = (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000);
  if (overlong || !is_xml_char(cp)) throw ParseFailure{i, "invalid UTF-8: not a valid XML character"};
  return i + len;
}

// tinyxml2 passes every byte through: invalid UTF-8 and control characters would reach names and
// values unnoticed (and a NUL would end its parse early), so they are refused before it runs.
void check_characters(std::string_view s) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = 0;
  while (i < n) {
    if (i + 32 <= n && plain_block(p + i)) {
      i += 32;
      continue;
    }
    const std::size_t stop = std::min(n, i + 32);
    while (i < stop) i = check_character(p, n, i);
  }
}

std::string lower_ascii(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

// Whether the XML declaration names ISO-8859-1; refuses UTF-16 and the encodings not read.
// tinyxml2 ignores the declaration's encoding, so it is looked at here.
bool declared_latin1(std::string_view s) {
  if (s.starts_with("\xFE\xFF") || s.starts_with("\xFF\xFE")) {
    throw ParseFailure{0, "UTF-16 is not supported: save the file as UTF-8"};
  }
  const std::size_t start = s.starts_with("\xEF\xBB\xBF") ? 3 : 0;
  if (s.compare(start, 5, "<?xml") != 0) return false;
  const std::size_t end = s.find("?>", start);
  if (end == std::string_view::npos) return false;  // an unclosed declaration: tinyxml2 refuses it
  const std::size_t key = s.substr(0, end).find("encoding", start);
  if (key == std::string_view::npos) return false;
  std::size_t i = key + 8;
  while (i < end && (is_blank(s[i]) || s[i] == '=')) ++i;
  if (i >= end || (s[i] != '"' && s[i] != '\'')) return false;  // tinyxml2 refuses the declaration
  const std::size_t close = s.find(s[i], i + 1);
  if (close == std::string_view::npos || close > end) return false;
  const std::string_view name = s.substr(i + 1, close - i - 1);
  const std::string lower = lower_ascii(name);
  if (lower == "utf-8" || lower == "utf8" || lower == "us-ascii" || lower == "ascii") return false;
  if (lower == "iso-8859-1" || lower == "iso8859-1" || lower == "latin1" || lower == "latin-1") return true;
  throw ParseFailure{i + 1, "encoding '" + std::string(name) +
                                "' is not supported: save the file as UTF-8 (ISO-8859-1 is read too)"};
}

std::string latin1_to_utf8(std::string_view s) {
  std::string out;
  out.reserve(s.size() + s.size() / 8);
  for (const char c : s) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x80) {
      out += c;
    } else {
      out += static_cast<char>(0xC0 | (b >> 6));
      out += static_cast<char>(0x80 | (b & 0x3F));
    }
  }
  return out;
}

// Checks the reference that starts at s[amp] == '&' (within s, which ends where its text or value
// ends) and returns its end and the bytes it decodes to. tinyxml2 keeps an unknown entity or a
// bare '&' as literal text, where XML 1.0 refuses the document.
std::size_t check_reference(std::string_view s, std::size_t amp, std::size_t& decoded_bytes) {
  const std::size_t semi = s.find(';', amp + 1);
  // Names and numbers are short; a far ';' means the '&' was meant literally.
  if (semi == std::string_view::npos || semi - amp > 12 || semi == amp + 1) {
    throw ParseFailure{amp, "'&' does not start a reference: write &amp; for a literal '&'"};
  }
  const std::string_view body = s.substr(amp + 1, semi - amp - 1);
  decoded_bytes = 1;
  if (body[0] == '#') {
    std::uint32_t cp = 0;
    const bool hex = body.size() > 1 && body[1] == 'x';
    const std::string_view digits = body.substr(hex ? 2 : 1);
    bool ok = !digits.empty();
    for (const char c : digits) {
      std::uint32_t v = 0;
      if (c >= '0' && c <= '9') v = static_cast<std::uint32_t>(c - '0');
      else if (hex && c >= 'a' && c <= 'f') v = static_cast<std::uint32_t>(c - 'a' + 10);
      else if (hex && c >= 'A' && c <= 'F') v = static_cast<std::uint32_t>(c - 'A' + 10);
      else ok = false;
      cp = cp * (hex ? 16 : 10) + v;
      if (!ok || cp > 0x10FFFF) {
        ok = false;
        break;
      }
    }
    if (!ok || !is_xml_char(cp)) {
      throw ParseFailure{amp, "character reference '&" + std::string(body) + ";' is not a valid XML character"};
    }
    decoded_bytes = utf8_length(cp);
  } else if (body != "lt" && body != "gt" && body != "amp" && body != "apos" && body != "quot") {
    throw ParseFailure{amp, "unknown entity '&" + std::string(body) +
                                ";': XML knows &lt; &gt; &amp; &apos; &quot; and character references such as &#160;"};
  }
  return semi + 1;
}

void check_references(std::string_view s, std::size_t from, std::size_t to) {
  const std::string_view region = s.substr(0, to);
  std::size_t decoded = 0;
  for (std::size_t amp = region.find('&', from); amp != std::string_view::npos; amp = region.find('&', amp + 1)) {
    check_reference(region, amp, decoded);
  }
}

std::size_t line_start_offset(std::string_view s, int line) {
  std::size_t at = 0;
  for (int l = 1; l < line && at < s.size(); ++l) {
    const std::size_t nl = s.find('\n', at);
    if (nl == std::string_view::npos) return s.size();
    at = nl + 1;
  }
  return at;
}

bool is_name_char(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == ':' ||
         c == '.' || c == '-' || static_cast<unsigned char>(c) >= 0x80;
}

// --- markup, as tinyxml2 recognises it ----------------------------------------------------
//
// A '<!' other than a comment or CDATA ends at the first '>', and '<?' at the first '?>', as in
// tinyxml2: the start tags found so are tinyxml2's elements, in the same order.

// What ends a run of bytes in a start tag, one table look-up per byte.
enum : unsigned char { kBlank = 1, kEndsName = 2, kInValue = 4, kQuote = 8 };
constexpr std::array<unsigned char, 256> kClass = [] {
  std::array<unsigned char, 256> t{};
  for (const char c : {' ', '\t', '\n', '\r'}) t[static_cast<unsigned char>(c)] = kBlank | kEndsName;
  for (const char c : {'=', '/', '>'}) t[static_cast<unsigned char>(c)] = kEndsName;
  for (const char c : {'<', '&', '\r'}) t[static_cast<unsigned char>(c)] |= kInValue;
  for (const char c : {'"', '\''}) t[static_cast<unsigned char>(c)] = kQuote;
  return t;
}();
unsigned char class_of(char c) noexcept { return kClass[static_cast<unsigned char>(c)]; }

std::size_t skip_blanks(std::string_view s, std::size_t i) noexcept {
  while (i < s.size() && (class_of(s[i]) & kBlank) != 0) ++i;
  return i;
}

std::size_t past(std::string_view s, std::string_view end, std::size_t from) noexcept {
  const std::size_t k = s.find(end, from);
  return k == std::string_view::npos ? s.size() : k + end.size();
}

// For markup other than a start tag at s[lt] == '<': the offset past it. npos for a start tag.
std::size_t other_markup_end(std::string_view s, std::size_t lt) noexcept {
  const char next = lt + 1 < s.size() ? s[lt + 1] : '\0';
  if (next != '!' && next != '?' && next != '/') return std::string_view::npos;  // the common case
  if (s.compare(lt, 4, "<!--") == 0) return past(s, "-->", lt + 4);
  if (s.compare(lt, 9, "<![CDATA[") == 0) return past(s, "]]>", lt + 9);
  if (s.compare(lt, 2, "<?") == 0) return past(s, "?>", lt + 2);
  if (s.compare(lt, 2, "<!") == 0 || s.compare(lt, 2, "</") == 0) return past(s, ">", lt + 2);
  return std::string_view::npos;
}

// From `from` in an attribute value: the offset of its closing `quote`, or of an earlier byte the
// value's scan must look at ('<', '&', CR), or of the last block of fewer than 16 bytes. Sixteen
// bytes per step where SSE2 is there (every x86-64): values are most of a net's bytes.
std::size_t quote_or_markup(std::string_view s, std::size_t from, char quote) noexcept {
#if defined(__SSE2__)
  const __m128i quotes = _mm_set1_epi8(quote);
  const __m128i lt = _mm_set1_epi8('<');
  const __m128i amp = _mm_set1_epi8('&');
  const __m128i cr = _mm_set1_epi8('\r');
  while (from + 16 <= s.size()) {
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s.data() + from));
    const __m128i hit = _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi8(b, quotes), _mm_cmpeq_epi8(b, lt)),
                                     _mm_or_si128(_mm_cmpeq_epi8(b, amp), _mm_cmpeq_epi8(b, cr)));
    const auto mask = static_cast<unsigned>(_mm_movemask_epi8(hit));
    if (mask != 0) return from + static_cast<std::size_t>(__builtin_ctz(mask));
    from += 16;
  }
#else
  (void)quote;
#endif
  return from;
}

struct RawAttribute {
  std::string_view name;
  std::size_t name_offset = 0;
  std::size_t value_offset = 0;            // past the opening quote
  std::size_t value_end = 0;               // the closing quote
  std::size_t first_lt = std::string_view::npos;  // the first '<' inside the value
  bool decoded = false;                    // has a '&' or a CR: tinyxml2's value differs from the text
};

// Reads the start tag at s[lt] == '<': its name, then each attribute, handed to `on_attribute`.
// Returns the offset past the tag. A malformed attribute (no '=', no quote: tinyxml2 refuses it)
// becomes a ParseFailure at the byte where the '=' or the quote was expected.
template <class OnAttribute>
std::size_t read_start_tag(std::string_view s, std::size_t lt, std::string_view& name, OnAttribute&& on_attribute) {
  const std::size_t n = s.size();
  const auto name_end = [&](std::size_t p) {
    while (p < n && (class_of(s[p]) & kEndsName) == 0) ++p;
    return p;
  };
  std::size_t p = skip_blanks(s, lt + 1);
  const std::size_t first = p;
  p = name_end(p);
  name = s.substr(first, p - first);
  while (true) {
    p = skip_blanks(s, p);
    if (p >= n || s[p] == '>') return std::min(n, p + 1);
    if (s[p] == '/') {
      ++p;
      continue;
    }
    RawAttribute a;
    a.name_offset = p;
    p = name_end(p);
    a.name = s.substr(a.name_offset, p - a.name_offset);
    p = skip_blanks(s, p);
    if (p >= n || s[p] != '=') {
      throw ParseFailure{p, "attribute '" + std::string(a.name) + "' of <" + std::string(name) + "> has no value: expected '='"};
    }
    p = skip_blanks(s, p + 1);
    if (p >= n || (s[p] != '"' && s[p] != '\'')) {
      throw ParseFailure{p, "the value of attribute '" + std::string(a.name) + "' must be in quotes"};
    }
    // One pass over the value finds its end and what the caller checks.
    const char quote = s[p];
    std::size_t q = quote_or_markup(s, p + 1, quote);
    for (; q < n; ++q) {
      if ((class_of(s[q]) & (kInValue | kQuote)) == 0) [[likely]] continue;
      if (s[q] == quote) break;
      if (s[q] == '<') a.first_lt = std::min(a.first_lt, q);
      else if (s[q] != '"' && s[q] != '\'') a.decoded = true;
    }
    a.value_offset = p + 1;
    a.value_end = q;
    on_attribute(a);
    p = a.value_end + 1;
  }
}

// tinyxml2 names the element it could not close: the first end tag at its level is the culprit.
ParseFailure mismatched_end_tag(std::string_view s, std::size_t open_at, const std::string& opened_at) {
  std::string_view open;
  std::size_t i = read_start_tag(s, open_at, open, [](const RawAttribute&) {});
  int depth = 0;
  while ((i = s.find('<', i)) != std::string_view::npos) {
    const std::size_t lt = i;
    if (std::size_t end = other_markup_end(s, lt); end != std::string_view::npos) {
      if (s.compare(lt, 2, "</") == 0 && depth-- == 0) {
        const std::size_t first = lt + 2;
        std::size_t last = first;
        while (last < s.size() && !is_blank(s[last]) && s[last] != '>') ++last;
        return ParseFailure{lt, "end tag </" + std::string(s.substr(first, last - first)) +
                                    "> does not match the open element <" + std::string(open) + "> (" + opened_at + ")"};
      }
      i = end;
      continue;
    }
    std::string_view name;
    i = read_start_tag(s, lt, name, [](const RawAttribute&) {});
    if (s[i - 2] != '/') ++depth;
  }
  return ParseFailure{open_at, "element <" + std::string(open) + "> is never closed: expected </" + std::string(open) +
                                   "> before the end of the file"};
}

// tinyxml2 refuses an attribute without saying which: the first duplicate or malformed one.
ParseFailure bad_attribute(std::string_view s, std::size_t tag_at) {
  std::string_view element;
  std::vector<std::string_view> seen;
  try {
    read_start_tag(s, tag_at, element, [&](const RawAttribute& a) {
      if (std::find(seen.begin(), seen.end(), a.name) != seen.end()) {
        throw ParseFailure{a.name_offset, "duplicate attribute '" + std::string(a.name) + "' on <" + std::string(element) + ">"};
      }
      seen.push_back(a.name);
    });
  } catch (ParseFailure& failure) {
    return std::move(failure);
  }
  return ParseFailure{tag_at, "bad attribute in the start tag of <" + std::string(element) + ">"};
}

// tinyxml2 reports a line and, for most errors, the element it was reading: the error is placed at
// that element's '<' when it is on the line, else at the line's first non-blank character.
ParseFailure tinyxml2_failure(const tinyxml2::XMLDocument& xml, std::string_view s) {
  const std::string_view what = xml.ErrorStr();
  std::string element;
  if (const std::size_t k = what.find("XMLElement name="); k != std::string_view::npos) {
    element = std::string(what.substr(k + 16));
  }
  const std::size_t line_start = line_start_offset(s, std::max(1, xml.ErrorLineNum()));
  const std::size_t line_end = std::min(s.size(), s.find('\n', line_start));
  const std::string_view line = s.substr(line_start, line_end - line_start);
  std::size_t at = line_start;
  while (at < line_end && is_blank(s[at])) ++at;
  if (!element.empty()) {
    const std::string open = "<" + element;
    for (std::size_t k = line.find(open); k != std::string_view::npos; k = line.find(open, k + 1)) {
      if (k + open.size() >= line.size() || !is_name_char(line[k + open.size()])) {
        at = line_start + k;
        break;
      }
    }
  }
  const bool at_element = !element.empty() && s.compare(at, element.size() + 1, "<" + element) == 0;
  if (at_element && xml.ErrorID() == tinyxml2::XML_ERROR_MISMATCHED_ELEMENT) {
    const std::size_t column = at - line_start + 1;
    return mismatched_end_tag(s, at, "line " + std::to_string(xml.ErrorLineNum()) + ", column " + std::to_string(column));
  }
  if (at_element && xml.ErrorID() == tinyxml2::XML_ERROR_PARSING_ATTRIBUTE) return bad_attribute(s, at);
  if (xml.ErrorID() == tinyxml2::XML_ERROR_EMPTY_DOCUMENT) return ParseFailure{s.size(), "empty document: expected a root element"};
  if (xml.ErrorID() == tinyxml2::XML_ERROR_PARSING) {
    // tinyxml2 says this for a '<' that starts no markup, and for an element never closed (on the
    // line of its start tag, unnamed).
    for (std::size_t k = line.find('<'); k != std::string_view::npos; k = line.find('<', k + 1)) {
      const char next = k + 1 < line.size() ? line[k + 1] : ' ';
      if (next != '/' && next != '!' && next != '?' && (!is_name_char(next) || (next >= '0' && next <= '9') ||
                                                        next == '.' || next == '-')) {
        return ParseFailure{line_start + k, "'<' is not followed by an element name: write &lt; for a literal '<'"};
      }
    }
    for (std::size_t k = line.find('<'); k != std::string_view::npos; k = line.find('<', k + 1)) {
      if (other_markup_end(s, line_start + k) != std::string_view::npos) continue;
      return mismatched_end_tag(s, line_start + k,
                                "line " + std::to_string(xml.ErrorLineNum()) + ", column " + std::to_string(k + 1));
    }
  }
  const std::string tag = "<" + element + ">";
  std::string message;
  switch (xml.ErrorID()) {
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT:
      message = "element " + tag + " is never closed: its end tag </" + element + "> is missing or another end tag comes first";
      break;
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE:
      message = "bad attribute in the start tag of " + tag + ": a duplicate name, a missing '=' or an unquoted value";
      break;
    case tinyxml2::XML_ERROR_PARSING_ELEMENT:
      message = element.empty() ? "a tag that is not well-formed (an attribute name that is not a name?)"
                                : "the tags of " + tag + " are not well-formed (unterminated, or '/' not followed by '>')";
      break;
    case tinyxml2::XML_ERROR_PARSING_TEXT:
      message = "text after the root element, or an element that is never closed before the end of the file";
      break;
    case tinyxml2::XML_ERROR_PARSING_CDATA: message = "unterminated CDATA section: expected ']]>'"; break;
    case tinyxml2::XML_ERROR_PARSING_COMMENT: message = "unterminated comment: expected '-->'"; break;
    case tinyxml2::XML_ERROR_PARSING_DECLARATION:
      message = "a '<?...?>' that is unterminated or inside the root element (tinyxml2 reads them before and after it only)";
      break;
    case tinyxml2::XML_ERROR_PARSING_UNKNOWN: message = "unterminated '<!...>': expected '>'"; break;
    case tinyxml2::XML_ERROR_PARSING: message = "markup that is not well-formed (an end tag without a name?)"; break;
    case tinyxml2::XML_ELEMENT_DEPTH_EXCEEDED:
      message = "elements nested more than " + std::to_string(TINYXML2_MAX_ELEMENT_DEPTH) + " levels deep";
      break;
    default: message = std::string(what); break;
  }
  return ParseFailure{at, std::move(message)};
}

}  // namespace

// --- XmlElement ---------------------------------------------------------------------------

const XmlElement* XmlElement::first_child(std::string_view name) const noexcept {
  const XmlElement* c = first_child();
  while (c != nullptr && !same_name(c->name_, name)) c = c->next_sibling();
  return c;
}

const XmlElement* XmlElement::next_sibling(std::string_view name) const noexcept {
  const XmlElement* c = next_sibling();
  while (c != nullptr && !same_name(c->name_, name)) c = c->next_sibling();
  return c;
}

// --- the tree -------------------------------------------------------------------------------

// Builds the document's flat tree from what tinyxml2 parsed. tinyxml2 keeps a line per node but no
// column and nothing for attributes, so one pass over the source finds every start tag and
// attribute (in document order, as tinyxml2 read them) and checks, on the way, what tinyxml2
// accepts and XML 1.0 does not: bad references, '<' in values, content outside the root.
class XmlTreeBuilder {
 public:
  XmlTreeBuilder(XmlDocument& doc, const tinyxml2::XMLDocument& xml) : d_(doc), xml_(xml), s_(doc.text_) {}

  void run() {
    const tinyxml2::XMLElement* root = xml_.RootElement();
    if (root == nullptr) throw ParseFailure{s_.size(), "empty document: expected a root element"};
    scan();
    walk(root);
    own_borrowed();
  }

 private:
  void scan() {
    const std::size_t n = s_.size();
    std::size_t i = s_.starts_with("\xEF\xBB\xBF") ? 3 : 0;
    std::size_t depth = 0;
    bool root_seen = false;
    while (i < n) {
      const std::size_t lt = std::min(n, s_.find('<', i));
      if (depth == 0) check_blank_outside_root(i, lt, root_seen);
      check_references(s_, i, lt);
      if (lt >= n) break;
      i = other_markup_end(s_, lt);
      if (i != std::string_view::npos) {
        if (s_[lt + 1] == '/') --depth;
        continue;
      }
      if (depth == 0 && root_seen) {
        throw ParseFailure{lt, "a second root element: a document has exactly one root element"};
      }
      i = start_tag(lt);
      root_seen = true;
      if (s_[i - 2] != '/') ++depth;
    }
  }

  // tinyxml2 keeps text between markup outside the root (and makes text of what follows the
  // first '>' of a DOCTYPE's internal subset).
  void check_blank_outside_root(std::size_t from, std::size_t to, bool root_seen) const {
    for (std::size_t k = from; k < to; ++k) {
      if (is_blank(s_[k])) continue;
      throw ParseFailure{k, s_[k] == ']' && !root_seen ? "a DOCTYPE with an internal subset ('[...]') is not supported"
                            : root_seen             ? "text after the root element"
                                                    : "text before the root element"};
    }
  }

  std::size_t start_tag(std::size_t lt) {
    Tag tag;
    tag.offset = static_cast<std::uint32_t>(lt);
    tag.first_attribute = static_cast<std::uint32_t>(d_.attributes_.size());
    const std::size_t end = read_start_tag(s_, lt, tag.name, [&](const RawAttribute& raw) {
      if (raw.first_lt != std::string_view::npos) {
        throw ParseFailure{raw.first_lt, "'<' in the value of attribute '" + std::string(raw.name) +
                                             "': write &lt; for a literal '<'"};
      }
      if (raw.decoded) check_references(s_, raw.value_offset, raw.value_end);
      XmlAttribute& a = d_.attributes_.emplace_back();
      a.name = raw.name;
      a.name_offset = static_cast<std::uint32_t>(raw.name_offset);
      a.value_offset = static_cast<std::uint32_t>(raw.value_offset);
      a.value_end = static_cast<std::uint32_t>(raw.value_end);
      // The common value needs no decoding: the text is tinyxml2's value, and its view is kept.
      if (!raw.decoded) a.value = s_.substr(raw.value_offset, raw.value_end - raw.value_offset);
    });
    tag.attribute_count = static_cast<std::uint32_t>(d_.attributes_.size()) - tag.first_attribute;
    tags_.push_back(tag);
    return end;
  }

  // Pre-order, as the scan found the tags: the k-th element is the k-th start tag.
  void walk(const tinyxml2::XMLElement* root) {
    d_.elements_.reserve(tags_.size());
    struct Open {
      std::uint32_t index;
      std::uint32_t last_child;
    };
    std::vector<Open> open;
    const tinyxml2::XMLElement* x = root;
    while (x != nullptr) {
      const std::uint32_t index = add(x);
      if (!open.empty()) {
        Open& parent = open.back();
        if (parent.last_child == XmlElement::kNone) d_.elements_[parent.index].first_child_ = index;
        else d_.elements_[parent.last_child].next_sibling_ = index;
        parent.last_child = index;
      }
      if (const tinyxml2::XMLElement* child = x->FirstChildElement()) {
        open.push_back(Open{index, XmlElement::kNone});
        x = child;
        continue;
      }
      while (x != root && x->NextSiblingElement() == nullptr) {
        x = x->Parent()->ToElement();
        open.pop_back();
      }
      x = x == root ? nullptr : x->NextSiblingElement();
    }
  }

  std::uint32_t add(const tinyxml2::XMLElement* x) {
    const auto index = static_cast<std::uint32_t>(d_.elements_.size());
    // tinyxml2 parses a copy of the text in place: its element is the scanned tag when its name
    // lies at the same offset in that copy (the root's fixes the distance) and ends where the
    // scanned name ends, with a NUL. A comparison of addresses, not of the bytes.
    const char* name = x->Name();
    const auto at = reinterpret_cast<std::uintptr_t>(name);
    if (index == 0 && !tags_.empty()) copy_distance_ = at - reinterpret_cast<std::uintptr_t>(tags_[0].name.data());
    if (index >= tags_.size() || at - copy_distance_ != reinterpret_cast<std::uintptr_t>(tags_[index].name.data()) ||
        name[tags_[index].name.size()] != '\0' || (index == 0 && tags_[0].name != name)) {
      // Only markup tinyxml2 reads differently from XML 1.0 can get here.
      throw ParseFailure{index < tags_.size() ? tags_[index].offset : s_.size(),
                         "element <" + std::string(name) + "> cannot be located in the text"};
    }
    const Tag& tag = tags_[index];
    XmlElement& e = d_.elements_.emplace_back();
    e.doc_ = &d_;
    e.name_ = tag.name;
    e.offset_ = tag.offset;
    // tinyxml2 counts the line; the column is the distance back to the line's start.
    e.line_ = static_cast<std::uint32_t>(x->GetLineNum());
    std::size_t line_start = tag.offset;
    while (line_start > 0 && s_[line_start - 1] != '\n') --line_start;
    e.column_ = static_cast<std::uint32_t>(tag.offset - line_start + 1);
    // The scan listed the attributes; tinyxml2 must have read as many (the element's name agreed,
    // so the same ones), and gives the values that needed decoding.
    e.first_attribute_ = tag.first_attribute;
    e.attribute_count_ = tag.attribute_count;
    std::uint32_t k = tag.first_attribute;
    const std::uint32_t end = tag.first_attribute + tag.attribute_count;
    const tinyxml2::XMLAttribute* a = x->FirstAttribute();
    for (; a != nullptr && k < end; a = a->Next(), ++k) {
      if (d_.attributes_[k].value.data() == nullptr) {
        d_.attributes_[k].value = a->Value();
        borrowed_.push_back(&d_.attributes_[k].value);
      }
    }
    if (a != nullptr || k != end) {
      throw ParseFailure{tag.offset, "the attributes of <" + std::string(name) + "> cannot be located in the text"};
    }
    e.text_ = text_of(x);
    if (text_borrowed_) borrowed_.push_back(&e.text_);
    return index;
  }

  // Copies what still points into tinyxml2's buffer (decoded values, single text pieces) into one
  // string of the document's, so its DOM can go at once: a large net's nodes are then built in
  // the memory the DOM gave back, not in fresh pages (100,000 places: 40 MB less touched).
  void own_borrowed() {
    std::size_t bytes = 0;
    for (const std::string_view* v : borrowed_) bytes += v->size();
    d_.owned_.reserve(bytes);  // no reallocation below: the views into it stay valid
    for (std::string_view* v : borrowed_) {
      const std::size_t at = d_.owned_.size();
      d_.owned_.append(*v);
      *v = std::string_view(d_.owned_).substr(at, v->size());
    }
  }

  // The direct text and CDATA pieces, joined, blanks at both ends trimmed. One piece (a PNML
  // <text>) is a view into tinyxml2's buffer until own_borrowed copies it.
  std::string_view text_of(const tinyxml2::XMLElement* x) {
    std::string_view first;
    std::string* joined = nullptr;
    for (const tinyxml2::XMLNode* c = x->FirstChild(); c != nullptr; c = c->NextSibling()) {
      if (c->ToText() == nullptr) continue;
      const std::string_view piece = c->Value();
      if (first.data() == nullptr) {
        first = piece;
      } else {
        if (joined == nullptr) joined = &d_.joined_.emplace_back(first);
        *joined += piece;
      }
    }
    std::string_view text = joined != nullptr ? std::string_view(*joined) : first;
    while (!text.empty() && is_blank(text.front())) text.remove_prefix(1);
    while (!text.empty() && is_blank(text.back())) text.remove_suffix(1);
    text_borrowed_ = joined == nullptr && !text.empty();
    return text;
  }

  struct Tag {
    std::string_view name;
    std::uint32_t offset = 0;
    std::uint32_t first_attribute = 0;
    std::uint32_t attribute_count = 0;
  };

  XmlDocument& d_;
  const tinyxml2::XMLDocument& xml_;
  std::string_view s_;
  std::vector<Tag> tags_;
  std::vector<std::string_view*> borrowed_;  // views into tinyxml2's buffer (own_borrowed)
  std::uintptr_t copy_distance_ = 0;         // tinyxml2's copy of the text less the text, in bytes (add)
  bool text_borrowed_ = false;               // the latest text_of's view is into tinyxml2's buffer
};

// --- the plain reader -----------------------------------------------------------------------

// The common document read in one pass over the text, without tinyxml2's DOM (its parse and
// teardown were half of a net's load): the prolog's XML declaration, comments, elements whose
// names and attribute names are ASCII XML names, quoted values and at most one text piece per
// element, none with a reference or a CR, properly nested. At anything else (a reference, CDATA,
// a DOCTYPE, a processing instruction, UTF-8 names, text in pieces, and every error) it gives up
// and the document goes through tinyxml2 as before: the same tree, the same errors at the same
// places. What it accepts is a subset of what tinyxml2 accepts, tree for tree (xml_document_test:
// "the plain reader and tinyxml2 build the same tree").
class XmlPlainReader {
 public:
  explicit XmlPlainReader(XmlDocument& doc) : d_(doc), s_(doc.text_) {}

  // True with the tree built; false (the tree left to the caller to clear) to go through tinyxml2.
  bool run() {
    const std::size_t n = s_.size();
    std::size_t i = s_.starts_with("\xEF\xBB\xBF") ? 3 : 0;
    if (s_.compare(i, 5, "<?xml") == 0) {
      const std::size_t end = s_.find("?>", i + 5);
      if (end == std::string_view::npos) return false;
      i = end + 2;
    }
    if (!misc(i)) return false;
    if (i >= n) return false;  // empty: tinyxml2 says so
    // The elements, from the root's start tag to its end tag.
    while (true) {
      if (s_[i] != '<') {
        if (open_.empty()) return false;
        // Most text between tags is indentation: skipped here without a search for the '<'.
        std::size_t j = i;
        while (j < n && is_blank(s_[j])) ++j;
        if (j < n && s_[j] == '<') {
          i = j;
          continue;
        }
        const std::size_t lt = s_.find('<', j);
        if (lt == std::string_view::npos) return false;
        if (!text(i, lt)) return false;
        i = lt;
        continue;
      }
      const char next = i + 1 < n ? s_[i + 1] : '\0';
      if (next == '/') {
        if (open_.empty()) return false;
        const std::string_view name = d_.elements_[open_.back().index].name_;
        if (s_.compare(i + 2, name.size(), name) != 0 || i + 2 + name.size() >= n || s_[i + 2 + name.size()] != '>') return false;
        i += name.size() + 3;
        open_.pop_back();
        if (open_.empty()) break;
      } else if (next == '!') {
        if (s_.compare(i, 4, "<!--") != 0) return false;  // CDATA, DOCTYPE
        const std::size_t end = s_.find("-->", i + 4);
        if (end == std::string_view::npos) return false;
        i = end + 3;
      } else {
        if (open_.empty() && !d_.elements_.empty()) return false;  // a second root
        // Deep nesting is left to tinyxml2, which refuses it past its limit (well below: safe).
        if (open_.size() >= static_cast<std::size_t>(TINYXML2_MAX_ELEMENT_DEPTH) / 2) return false;
        bool empty = false;
        i = start_tag(i, empty);
        if (i == std::string_view::npos) return false;
        if (empty && open_.empty()) break;  // <root/>
      }
      if (i >= n) return false;  // inside the root at the end
    }
    return misc(i) && i == n;
  }

 private:
  // One table look-up per byte of a name (names are a third of a document's bytes): bit 1 a
  // name's first byte, bit 2 any later one.
  static constexpr std::array<std::uint8_t, 256> kNameBytes = [] {
    std::array<std::uint8_t, 256> t{};
    for (int c = 0; c < 256; ++c) {
      const bool start = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':';
      const bool later = start || (c >= '0' && c <= '9') || c == '.' || c == '-';
      t[static_cast<std::size_t>(c)] = static_cast<std::uint8_t>((start ? 1U : 0U) | (later ? 2U : 0U));
    }
    return t;
  }();
  static bool name_start(char c) noexcept { return (kNameBytes[static_cast<unsigned char>(c)] & 1U) != 0; }
  static bool name_char(char c) noexcept { return (kNameBytes[static_cast<unsigned char>(c)] & 2U) != 0; }
  // The end of the ASCII name at s_[p], or p when none starts there.
  std::size_t name_end(std::size_t p) const noexcept {
    if (p >= s_.size() || !name_start(s_[p])) return p;
    ++p;
    while (p < s_.size() && name_char(s_[p])) ++p;
    return p;
  }

  // Blanks and comments outside the root; false at anything else but a start tag or the end.
  bool misc(std::size_t& i) const {
    while (true) {
      i = skip_blanks(s_, i);
      if (i >= s_.size()) return true;
      if (s_.compare(i, 4, "<!--") == 0) {
        const std::size_t end = s_.find("-->", i + 4);
        if (end == std::string_view::npos) return false;
        i = end + 3;
        continue;
      }
      if (s_[i] != '<' || !name_start(i + 1 < s_.size() ? s_[i + 1] : '\0')) return false;
      return d_.elements_.empty();  // before the root; after it, tinyxml2 names the second root
    }
  }

  // A text piece of the open element: blanks only (tinyxml2 makes no node of them), or its one
  // text, trimmed, without references or CRs.
  bool text(std::size_t from, std::size_t to) {
    std::size_t first = from;
    while (first < to && is_blank(s_[first])) ++first;
    if (first == to) return true;
    XmlElement& e = d_.elements_[open_.back().index];
    if (e.text_.data() != nullptr) return false;  // a second piece: joined by the tinyxml2 path
    std::size_t last = to;
    while (is_blank(s_[last - 1])) --last;
    const std::string_view piece = s_.substr(first, last - first);
    if (piece.find('&') != std::string_view::npos || piece.find('\r') != std::string_view::npos) return false;
    e.text_ = piece;
    return true;
  }

  // The start tag at s_[lt] == '<': the element joins the tree; npos to give up.
  std::size_t start_tag(std::size_t lt, bool& empty) {
    const std::size_t n = s_.size();
    const std::size_t name_to = name_end(lt + 1);
    if (name_to == lt + 1) return std::string_view::npos;
    const auto index = static_cast<std::uint32_t>(d_.elements_.size());
    XmlElement& e = d_.elements_.emplace_back();
    e.doc_ = &d_;
    e.name_ = s_.substr(lt + 1, name_to - lt - 1);
    e.offset_ = static_cast<std::uint32_t>(lt);
    advance_line(lt);
    e.line_ = line_;
    e.column_ = static_cast<std::uint32_t>(lt - line_start_ + 1);
    e.first_attribute_ = static_cast<std::uint32_t>(d_.attributes_.size());
    if (!open_.empty()) {
      Open& parent = open_.back();
      if (parent.last_child == XmlElement::kNone)
        d_.elements_[parent.index].first_child_ = index;
      else
        d_.elements_[parent.last_child].next_sibling_ = index;
      parent.last_child = index;
    }
    std::size_t p = name_to;
    while (true) {
      if (p >= n) return std::string_view::npos;
      if (s_[p] == '>') {
        open_.push_back(Open{index, XmlElement::kNone});
        ++p;
        break;
      }
      if (s_[p] == '/') {
        if (p + 1 >= n || s_[p + 1] != '>') return std::string_view::npos;
        empty = true;
        p += 2;
        break;
      }
      if (!is_blank(s_[p])) return std::string_view::npos;  // an attribute right after a value
      p = skip_blanks(s_, p);
      if (p >= n || s_[p] == '>' || s_[p] == '/') continue;
      const std::size_t name_at = p;
      p = name_end(p);
      if (p == name_at) return std::string_view::npos;
      const std::string_view name = s_.substr(name_at, p - name_at);
      p = skip_blanks(s_, p);
      if (p >= n || s_[p] != '=') return std::string_view::npos;
      p = skip_blanks(s_, p + 1);
      if (p >= n || (s_[p] != '"' && s_[p] != '\'')) return std::string_view::npos;
      const char quote = s_[p];
      std::size_t q = quote_or_markup(s_, p + 1, quote);
      while (q < n && s_[q] != quote && s_[q] != '<' && s_[q] != '&' && s_[q] != '\r') ++q;
      if (q >= n || s_[q] != quote) return std::string_view::npos;  // to be decoded, or refused
      for (std::size_t k = e.first_attribute_; k < d_.attributes_.size(); ++k) {
        if (same_name(d_.attributes_[k].name, name)) return std::string_view::npos;  // tinyxml2 refuses it
      }
      XmlAttribute& a = d_.attributes_.emplace_back();
      a.name = name;
      a.value = s_.substr(p + 1, q - p - 1);
      a.name_offset = static_cast<std::uint32_t>(name_at);
      a.value_offset = static_cast<std::uint32_t>(p + 1);
      a.value_end = static_cast<std::uint32_t>(q);
      ++e.attribute_count_;
      p = q + 1;
    }
    return p;
  }

  // Lines counted up to `offset` (offsets only grow): tinyxml2's line of the element's '<'.
  void advance_line(std::size_t offset) noexcept {
    while (true) {
      const void* nl = std::memchr(s_.data() + line_scanned_, '\n', offset - line_scanned_);
      if (nl == nullptr) break;
      line_start_ = static_cast<std::size_t>(static_cast<const char*>(nl) - s_.data()) + 1;
      line_scanned_ = line_start_;
      ++line_;
    }
    line_scanned_ = offset;
  }

  struct Open {
    std::uint32_t index;
    std::uint32_t last_child;
  };
  XmlDocument& d_;
  std::string_view s_;
  std::vector<Open> open_;
  std::uint32_t line_ = 1;
  std::size_t line_start_ = 0;
  std::size_t line_scanned_ = 0;
};

// --- XmlDocument --------------------------------------------------------------------------

XmlDocument::XmlDocument()
    : xml_(std::make_unique<tinyxml2::XMLDocument>(/*processEntities=*/true, tinyxml2::PRESERVE_WHITESPACE)) {}

XmlDocument::~XmlDocument() = default;

void XmlDocument::clear() {
  xml_->Clear();
  latin1_decoded_.clear();
  owned_.clear();
  elements_.clear();
  attributes_.clear();
  joined_.clear();
  line_starts_.clear();
  error_ = {};
  read_plain_ = false;
}

bool XmlDocument::parse(std::string_view text, bool plain_reader) {
  clear();
  text_ = text;
  try {
    if (text.size() >= std::numeric_limits<std::uint32_t>::max()) throw ParseFailure{0, "document too large (4 GiB or more)"};
    if (declared_latin1(text) &&
        std::any_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) >= 0x80; })) {
      latin1_decoded_ = latin1_to_utf8(text);
      text_ = latin1_decoded_;
    }
    check_characters(text_);
    if (plain_reader) {
      if (XmlPlainReader(*this).run()) {
        read_plain_ = true;
        return true;
      }
      elements_.clear();
      attributes_.clear();
    }
    if (xml_->Parse(text_.data(), text_.size()) != tinyxml2::XML_SUCCESS) throw tinyxml2_failure(*xml_, text_);
    XmlTreeBuilder(*this, *xml_).run();
    xml_->Clear();  // everything kept is in text_, owned_ and joined_ now
    return true;
  } catch (ParseFailure& failure) {
    // The tree goes; the text stays, since the error's offset refers to it.
    xml_->Clear();
    elements_.clear();
    attributes_.clear();
    joined_.clear();
    error_ = XmlError{failure.offset, std::move(failure.message)};
    return false;
  }
}

XmlDocument::LineColumn XmlDocument::line_column(std::size_t offset) const {
  if (line_starts_.empty()) {
    line_starts_.push_back(0);
    for (std::size_t i = 0; i < text_.size(); ++i) {
      if (text_[i] == '\n') line_starts_.push_back(i + 1);
    }
  }
  offset = std::min(offset, text_.size());
  const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), offset);
  const auto index = static_cast<std::size_t>(it - line_starts_.begin()) - 1;
  return LineColumn{static_cast<int>(index + 1), static_cast<int>(offset - line_starts_[index] + 1)};
}

std::size_t XmlDocument::value_source_offset(const XmlAttribute& a, std::size_t decoded_offset) const {
  const std::string_view value = text_.substr(0, a.value_end);
  std::size_t produced = 0;
  std::size_t i = a.value_offset;
  while (i < a.value_end) {
    const std::size_t start = i;
    std::size_t width = 1;
    if (value[i] == '&') {
      try {
        i = check_reference(value, i, width);
      } catch (const ParseFailure&) {
        return start;  // cannot happen on a parsed document
      }
    } else if (value[i] == '\r' && i + 1 < a.value_end && value[i + 1] == '\n') {
      i += 2;  // tinyxml2 turns CR LF into one LF
    } else {
      ++i;
    }
    if (decoded_offset < produced + width) return start;
    produced += width;
  }
  return a.value_end;
}

}  // namespace tripodal::detail
