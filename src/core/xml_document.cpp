// One pass over the source with an explicit stack of open elements (no recursion, so depth is
// bounded by memory only). Scanning leans on memchr for the long runs (text up to the next '<',
// attribute values up to their quote) and on a byte-class table for names. Values and text are
// views into the source unless a reference, a CR or a Latin-1 byte forces a decoded copy.
#include "xml_document.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace tripodal::detail {

namespace {

enum : std::uint8_t {
  kNameStart = 1,  // may start a name
  kNameChar = 2,   // may continue a name
  kSpace = 4,      // XML white space: space, tab, LF, CR
  kTextSpecial = 8,  // needs decoding inside text: & CR
};

constexpr std::array<std::uint8_t, 256> make_classes() {
  std::array<std::uint8_t, 256> t{};
  for (int c = 0; c < 256; ++c) {
    std::uint8_t k = 0;
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
    // Bytes >= 0x80 are parts of UTF-8 sequences; XML allows most non-ASCII letters in names.
    if (letter || c == '_' || c == ':' || c >= 0x80) k |= kNameStart | kNameChar;
    if ((c >= '0' && c <= '9') || c == '-' || c == '.') k |= kNameChar;
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') k |= kSpace;
    if (c == '&' || c == '\r') k |= kTextSpecial;
    t[static_cast<std::size_t>(c)] = k;
  }
  return t;
}
constexpr std::array<std::uint8_t, 256> kClass = make_classes();

inline std::uint8_t cls(char c) noexcept { return kClass[static_cast<unsigned char>(c)]; }

constexpr std::uint64_t kOnes = 0x0101010101010101ULL;

// Eight bytes with the first at the lowest bits, whatever the machine's byte order, so that the
// lowest flagged bit below names the first flagged byte.
inline std::uint64_t load8(const void* p) noexcept {
  std::uint64_t w = 0;
  std::memcpy(&w, p, 8);
  if constexpr (std::endian::native == std::endian::big) w = __builtin_bswap64(w);
  return w;
}
constexpr std::uint64_t kHigh = 0x8080808080808080ULL;

// Bit tricks on eight bytes at once. Both may also flag a byte above a true hit (a borrow moves
// up), never below one and never miss one: the lowest flagged byte is always a true hit.
constexpr std::uint64_t zero_bytes(std::uint64_t w) noexcept { return (w - kOnes) & ~w & kHigh; }
constexpr std::uint64_t bytes_below(std::uint64_t w, std::uint8_t n) noexcept { return (w - kOnes * n) & ~w & kHigh; }

// Exact per-byte tests (no borrow crosses a byte): the high bit of each byte of the result is set
// where the byte equals `c` / is an ASCII byte below 0x20.
constexpr std::uint64_t kLow7 = 0x7F7F7F7F7F7F7F7FULL;
constexpr std::uint64_t bytes_equal(std::uint64_t w, std::uint8_t c) noexcept {
  const std::uint64_t t = w ^ (kOnes * c);
  return ~(((t & kLow7) + kLow7) | t | kLow7);
}
constexpr std::uint64_t ascii_controls(std::uint64_t w) noexcept {
  return ~(((w & kLow7) + kOnes * 0x60) | w) & kHigh;
}

// From `from`, the offset of the first byte that ends or complicates an attribute value: its
// closing `quote`, or a byte the value cannot keep as it is ('&', '<', a tab/LF/CR, any byte
// >= 0x80 in an ISO-8859-1 document); s.size() when there is none. One pass: most values have
// none of the latter, and their closing quote is found by the same scan.
std::size_t first_quote_or_special(std::string_view s, std::size_t from, char quote, bool latin1) noexcept {
  const std::size_t n = s.size();
  std::size_t i = from;
#if defined(__SSE2__)
  {
    // Sixteen bytes at a time. "Below 0x20" is an unsigned test, done as a signed one on bytes
    // with the top bit flipped; in Latin-1 the flip is left out, so that the signed test also
    // catches every byte >= 0x80.
    const auto* p = reinterpret_cast<const __m128i*>(s.data());
    const __m128i q = _mm_set1_epi8(quote);
    const __m128i amp = _mm_set1_epi8('&');
    const __m128i lt = _mm_set1_epi8('<');
    const __m128i flip = _mm_set1_epi8(static_cast<char>(latin1 ? 0x00 : 0x80));
    const __m128i limit = _mm_set1_epi8(static_cast<char>(latin1 ? 0x20 : 0xA0));
    for (; i + 16 <= n; i += 16) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(reinterpret_cast<const char*>(p) + i));
      const __m128i hit = _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi8(v, q), _mm_cmpeq_epi8(v, amp)),
                                       _mm_or_si128(_mm_cmpeq_epi8(v, lt), _mm_cmplt_epi8(_mm_xor_si128(v, flip), limit)));
      const auto mask = static_cast<unsigned>(_mm_movemask_epi8(hit));
      if (mask != 0) return i + static_cast<std::size_t>(std::countr_zero(mask));
    }
  }
#endif
  const std::uint64_t high_mask = latin1 ? kHigh : 0;
  for (; i + 8 <= n; i += 8) {
    const std::uint64_t w = load8(s.data() + i);
    const std::uint64_t hit = bytes_below(w, 0x20) | zero_bytes(w ^ (kOnes * '&')) | zero_bytes(w ^ (kOnes * '<')) |
                              zero_bytes(w ^ (kOnes * static_cast<unsigned char>(quote))) | (w & high_mask);
    if (hit != 0) return i + static_cast<std::size_t>(std::countr_zero(hit) >> 3);
  }
  for (; i < n; ++i) {
    const auto b = static_cast<unsigned char>(s[i]);
    if (s[i] == quote || b < 0x20 || b == '&' || b == '<' || (latin1 && b >= 0x80)) return i;
  }
  return n;
}

/// Thrown inside the parser at the first error; parse() turns it into XmlError.
struct ParseFailure {
  std::size_t offset;
  std::string message;
};

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

bool is_xml_char(std::uint32_t cp) noexcept {
  return cp == 0x9 || cp == 0xA || cp == 0xD || (cp >= 0x20 && cp <= 0xD7FF) || (cp >= 0xE000 && cp <= 0xFFFD) ||
         (cp >= 0x10000 && cp <= 0x10FFFF);
}

std::string byte_text(unsigned char b) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  return std::string("0x") + kHex[b >> 4] + kHex[b & 15];
}

std::string lower_ascii(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

// The end of a reference starting at s[i] == '&' and what it stands for; throws on a malformed
// or unknown one. `latin1` does not matter here: references name Unicode code points.
std::size_t decode_reference(std::string_view s, std::size_t i, std::string& out) {
  const std::size_t semi = s.find(';', i + 1);
  // Names and numbers are short; a far ';' means the '&' was meant literally.
  if (semi == std::string_view::npos || semi - i > 12 || semi == i + 1) {
    throw ParseFailure{i, "'&' does not start a reference: write &amp; for a literal '&'"};
  }
  const std::string_view body = s.substr(i + 1, semi - i - 1);
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
      else {
        ok = false;
        break;
      }
      cp = cp * (hex ? 16 : 10) + v;
      if (cp > 0x10FFFF) {
        ok = false;
        break;
      }
    }
    if (!ok || !is_xml_char(cp)) {
      throw ParseFailure{i, "character reference '&" + std::string(body) + ";' is not a valid XML character"};
    }
    append_utf8(out, cp);
  } else if (body == "lt") {
    out += '<';
  } else if (body == "gt") {
    out += '>';
  } else if (body == "amp") {
    out += '&';
  } else if (body == "apos") {
    out += '\'';
  } else if (body == "quot") {
    out += '"';
  } else {
    throw ParseFailure{i, "unknown entity '&" + std::string(body) +
                              ";': XML knows &lt; &gt; &amp; &apos; &quot; and character references such as &#160;"};
  }
  return semi + 1;
}

struct SourceCounts {
  std::size_t tags = 0;    // '<': an upper bound of the elements
  std::size_t equals = 0;  // '=': an upper bound of the attributes
};

// From `i`, skips whole blocks of plain bytes (printable ASCII, tab, LF, CR) while counting their
// '<' and '='; returns where a block holds something else (or too few bytes remain).
std::size_t skip_plain_words(const unsigned char* p, std::size_t n, std::size_t i, SourceCounts& counts) noexcept {
  for (; i + 8 <= n; i += 8) {
    const std::uint64_t w = load8(p + i);
    // Most words have no byte below 0x20 at all: tab, LF and CR are looked for only then.
    std::uint64_t controls = ascii_controls(w);
    if (controls != 0) controls &= ~(bytes_equal(w, '\t') | bytes_equal(w, '\n') | bytes_equal(w, '\r'));
    const std::uint64_t odd = (w & kHigh) | controls;
    // The plain bytes before the first odd one are counted and skipped too.
    const std::uint64_t keep = odd == 0 ? ~0ULL : (1ULL << (std::countr_zero(odd) & ~7)) - 1;
    // Each match is 0x80 in its byte: shifted to 1 and summed into the top byte (no popcount
    // instruction in the baseline x86-64 set).
    counts.tags += static_cast<std::size_t>((((bytes_equal(w, '<') & keep) >> 7) * kOnes) >> 56);
    counts.equals += static_cast<std::size_t>((((bytes_equal(w, '=') & keep) >> 7) * kOnes) >> 56);
    if (odd != 0) return i + static_cast<std::size_t>(std::countr_zero(odd) >> 3);
  }
  return i;
}

#if defined(__SSE2__)
std::size_t skip_plain(const unsigned char* p, std::size_t n, std::size_t i, SourceCounts& counts) noexcept {
  const __m128i zero = _mm_setzero_si128();
  const __m128i below = _mm_set1_epi8(0x20);
  const __m128i tab = _mm_set1_epi8('\t');
  const __m128i lf = _mm_set1_epi8('\n');
  const __m128i cr = _mm_set1_epi8('\r');
  const __m128i lt = _mm_set1_epi8('<');
  const __m128i eq = _mm_set1_epi8('=');
  // Matches are counted per byte lane (a compare gives -1, subtracted) and summed every 255
  // blocks, before a lane can overflow.
  __m128i tags = zero;
  __m128i equals = zero;
  int pending = 0;
  const auto flush = [&] {
    const __m128i t = _mm_sad_epu8(tags, zero);
    const __m128i e = _mm_sad_epu8(equals, zero);
    counts.tags += static_cast<std::size_t>(_mm_cvtsi128_si32(t) + _mm_cvtsi128_si32(_mm_srli_si128(t, 8)));
    counts.equals += static_cast<std::size_t>(_mm_cvtsi128_si32(e) + _mm_cvtsi128_si32(_mm_srli_si128(e, 8)));
    tags = zero;
    equals = zero;
    pending = 0;
  };
  for (; i + 16 <= n; i += 16) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + i));
    // Signed: true for the bytes below 0x20 and for every byte >= 0x80.
    const __m128i odd = _mm_cmplt_epi8(v, below);
    if (_mm_movemask_epi8(odd) != 0) {
      const __m128i allowed = _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi8(v, tab), _mm_cmpeq_epi8(v, lf)), _mm_cmpeq_epi8(v, cr));
      const auto bad = static_cast<unsigned>(_mm_movemask_epi8(_mm_andnot_si128(allowed, odd)));
      if (bad != 0) {
        // The plain bytes before the first odd one are counted and skipped too.
        const unsigned before = (1U << std::countr_zero(bad)) - 1;
        counts.tags += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(v, lt))) & before));
        counts.equals += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(v, eq))) & before));
        i += static_cast<std::size_t>(std::countr_zero(bad));
        break;
      }
    }
    tags = _mm_sub_epi8(tags, _mm_cmpeq_epi8(v, lt));
    equals = _mm_sub_epi8(equals, _mm_cmpeq_epi8(v, eq));
    if (++pending == 255) flush();
  }
  flush();
  // Fewer than 16 bytes left: words of eight, as on machines without SSE2.
  return i + 16 > n && i < n ? skip_plain_words(p, n, i, counts) : i;
}
#else
std::size_t skip_plain(const unsigned char* p, std::size_t n, std::size_t i, SourceCounts& counts) noexcept {
  return skip_plain_words(p, n, i, counts);
}
#endif

// Checks that the source is UTF-8 (any byte for ISO-8859-1) without control characters other than
// tab, LF and CR, and counts what the tree will need room for. Blocks of plain bytes are checked
// and counted whole; the byte loop below decides the rest, one character at a time.
SourceCounts validate_and_count(std::string_view s, bool latin1) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  SourceCounts counts;
  std::size_t i = 0;
  while (i < n) {
    i = skip_plain(p, n, i, counts);
    if (i >= n) break;
    const unsigned char b = p[i];
    counts.tags += b == '<' ? 1 : 0;
    counts.equals += b == '=' ? 1 : 0;
    if (b < 0x80) {
      if (b < 0x20 && b != '\t' && b != '\n' && b != '\r') {
        throw ParseFailure{i, "control character " + byte_text(b) + " is not allowed in XML"};
      }
      ++i;
      continue;
    }
    if (latin1) {
      ++i;
      continue;
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
    if (overlong || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF) || cp == 0xFFFE || cp == 0xFFFF) {
      throw ParseFailure{i, "invalid UTF-8: not a valid XML character"};
    }
    i += len;
  }
  return counts;
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

// --- parser -------------------------------------------------------------------------------

class XmlParser {
 public:
  XmlParser(XmlDocument& doc, std::string_view text) : d_(doc), s_(text), n_(text.size()) {}

  void run() {
    if (n_ >= std::numeric_limits<std::uint32_t>::max()) throw ParseFailure{0, "document too large (4 GiB or more)"};
    if (starts_with(0, "\xEF\xBB\xBF")) p_ = 3;
    if (starts_with(0, "\xFE\xFF") || starts_with(0, "\xFF\xFE")) {
      throw ParseFailure{0, "UTF-16 is not supported: save the file as UTF-8"};
    }
    if (starts_with(p_, "<?xml") && p_ + 5 < n_ && (cls(s_[p_ + 5]) & kSpace) != 0) declaration();
    // Every element starts with '<' and every attribute has '=': reserving that many (an upper
    // bound) spares the copies of growing vectors of tens of thousands of entries.
    const SourceCounts counts = validate_and_count(s_, d_.latin1_);
    d_.elements_.reserve(counts.tags);
    d_.attributes_.reserve(counts.equals);
    misc(true);
    if (p_ >= n_) throw ParseFailure{p_, "empty document: expected a root element"};
    content();
    misc(false);
    if (p_ < n_) {
      if (s_[p_] == '<' && p_ + 1 < n_ && (cls(s_[p_ + 1]) & kNameStart) != 0) {
        throw ParseFailure{p_, "a second root element: a document has exactly one root element"};
      }
      throw ParseFailure{p_, "text after the root element"};
    }
    locate_elements();
  }

 private:
  // Per open element: its index, its last child so far, and its character data so far.
  struct Open {
    std::uint32_t element = 0;
    std::uint32_t last_child = XmlElement::kNone;
    bool has_text = false;
    bool owned = false;        // text lives in `buffer`, not in a view
    std::string_view text;     // with leading blanks removed
    std::string buffer;
    std::string gap;           // blank chunks after the last non-blank one
  };

  [[nodiscard]] bool starts_with(std::size_t at, std::string_view what) const noexcept {
    return at + what.size() <= n_ && s_.compare(at, what.size(), what) == 0;
  }

  // The scanning loops work on local copies: a char read may alias any member, so a loop over
  // s_[p_] would reload s_ and p_ from memory at every byte.
  [[nodiscard]] std::size_t space_end(std::size_t from) const noexcept {
    const char* s = s_.data();
    const std::size_t n = n_;
    while (from < n && (cls(s[from]) & kSpace) != 0) ++from;
    return from;
  }
  void skip_space() noexcept { p_ = space_end(p_); }

  std::string_view name_at(std::size_t at) const noexcept {
    const char* s = s_.data();
    const std::size_t n = n_;
    std::size_t e = at;
    if (e < n && (cls(s[e]) & kNameStart) != 0) {
      ++e;
      while (e < n && (cls(s[e]) & kNameChar) != 0) ++e;
    }
    return {s + at, e - at};
  }

  std::string_view intern(std::string_view raw) {
    if (!d_.latin1_) [[likely]] return raw;
    return intern_latin1(raw);
  }
  std::string_view intern_latin1(std::string_view raw) {
    if (std::none_of(raw.begin(), raw.end(), [](char c) { return static_cast<unsigned char>(c) >= 0x80; })) return raw;
    std::string out;
    for (const char c : raw) append_utf8(out, static_cast<unsigned char>(c));
    return d_.decoded_.emplace_back(std::move(out));
  }

  std::string opened_at(const XmlElement& e) const {
    const auto lc = d_.line_column(e.offset_);
    return "<" + std::string(e.name_) + "> (line " + std::to_string(lc.line) + ", column " + std::to_string(lc.column) +
           ")";
  }

  // <?xml version="1.0" encoding="..." standalone="..."?>
  void declaration() {
    const std::size_t start = p_;
    const std::size_t end = s_.find("?>", p_);
    if (end == std::string_view::npos) throw ParseFailure{start, "unterminated XML declaration: expected '?>'"};
    std::size_t i = p_ + 5;
    bool version = false;
    while (i < end) {
      while (i < end && (cls(s_[i]) & kSpace) != 0) ++i;
      if (i >= end) break;
      const std::string_view key = name_at(i);
      if (key.empty()) throw ParseFailure{i, "malformed XML declaration: expected version, encoding or standalone"};
      std::size_t j = i + key.size();
      while (j < end && (cls(s_[j]) & kSpace) != 0) ++j;
      if (j >= end || s_[j] != '=') throw ParseFailure{j, "malformed XML declaration: expected '=' after '" + std::string(key) + "'"};
      ++j;
      while (j < end && (cls(s_[j]) & kSpace) != 0) ++j;
      if (j >= end || (s_[j] != '"' && s_[j] != '\'')) {
        throw ParseFailure{j, "malformed XML declaration: the value of '" + std::string(key) + "' must be quoted"};
      }
      const std::size_t close = s_.find(s_[j], j + 1);
      if (close == std::string_view::npos || close > end) {
        throw ParseFailure{j, "malformed XML declaration: unterminated value of '" + std::string(key) + "'"};
      }
      const std::string_view value = s_.substr(j + 1, close - j - 1);
      if (key == "version") {
        version = true;
        if (value.size() < 3 || value.substr(0, 2) != "1.") {
          throw ParseFailure{j + 1, "XML version '" + std::string(value) + "' is not supported: expected 1.0"};
        }
      } else if (key == "encoding") {
        const std::string enc = lower_ascii(value);
        if (enc == "iso-8859-1" || enc == "latin1" || enc == "latin-1" || enc == "iso8859-1") {
          d_.latin1_ = true;
        } else if (enc != "utf-8" && enc != "utf8" && enc != "us-ascii" && enc != "ascii") {
          throw ParseFailure{j + 1, "encoding '" + std::string(value) +
                                        "' is not supported: save the file as UTF-8 (ISO-8859-1 is read too)"};
        }
      } else if (key != "standalone") {
        throw ParseFailure{i, "malformed XML declaration: unknown pseudo-attribute '" + std::string(key) + "'"};
      }
      i = close + 1;
    }
    if (!version) throw ParseFailure{start, "malformed XML declaration: 'version' is required"};
    p_ = end + 2;
  }

  // Comments, processing instructions and white space around the root (and one DOCTYPE before it).
  void misc(bool before_root) {
    bool doctype_seen = false;
    for (;;) {
      skip_space();
      if (p_ >= n_) return;
      if (starts_with(p_, "<!--")) {
        comment();
      } else if (starts_with(p_, "<?")) {
        processing_instruction();
      } else if (before_root && starts_with(p_, "<!DOCTYPE")) {
        if (doctype_seen) throw ParseFailure{p_, "a second DOCTYPE"};
        doctype_seen = true;
        doctype();
      } else if (before_root && s_[p_] != '<') {
        throw ParseFailure{p_, "text before the root element"};
      } else {
        return;
      }
    }
  }

  // XML 1.0 forbids "--" inside a comment, so the first "--" must be the one that ends it.
  void comment() {
    const std::size_t dashes = s_.find("--", p_ + 4);
    if (dashes == std::string_view::npos || s_.find("-->", dashes) == std::string_view::npos) {
      throw ParseFailure{p_, "unterminated comment: expected '-->'"};
    }
    if (dashes + 2 >= n_ || s_[dashes + 2] != '>') {
      throw ParseFailure{dashes, "'--' is not allowed inside a comment: end the comment with '-->' first"};
    }
    p_ = dashes + 3;
  }

  void processing_instruction() {
    const std::string_view target = name_at(p_ + 2);
    if (target.empty()) throw ParseFailure{p_, "'<?' not followed by a processing instruction name"};
    if (lower_ascii(target) == "xml") {
      throw ParseFailure{p_, "an XML declaration is allowed only at the very start of the file"};
    }
    const std::size_t end = s_.find("?>", p_ + 2);
    if (end == std::string_view::npos) throw ParseFailure{p_, "unterminated processing instruction: expected '?>'"};
    p_ = end + 2;
  }

  // <!DOCTYPE name ExternalID? [internal subset]? >: skipped. Quotes are literals both outside
  // and inside the subset; inside it, comments and processing instructions are skipped whole
  // (a quote or bracket in them means nothing), and ']' ends the subset.
  void doctype() {
    const std::size_t start = p_;
    const auto unterminated = [&] { return ParseFailure{start, "unterminated DOCTYPE"}; };
    const auto skip_quoted = [&](std::size_t i) {
      const std::size_t close = s_.find(s_[i], i + 1);
      if (close == std::string_view::npos) throw unterminated();
      return close + 1;
    };
    std::size_t i = p_ + 9;
    while (i < n_ && s_[i] != '[' && s_[i] != '>') i = (s_[i] == '"' || s_[i] == '\'') ? skip_quoted(i) : i + 1;
    if (i < n_ && s_[i] == '[') {
      ++i;
      for (;;) {
        if (i >= n_) throw unterminated();
        if (s_[i] == ']') {
          ++i;
          break;
        }
        std::string_view end;
        if (s_.compare(i, 4, "<!--") == 0) end = "-->";
        else if (s_.compare(i, 2, "<?") == 0) end = "?>";
        if (!end.empty()) {
          const std::size_t close = s_.find(end, i + 2);
          if (close == std::string_view::npos) throw unterminated();
          i = close + end.size();
        } else if (s_[i] == '"' || s_[i] == '\'') {
          i = skip_quoted(i);
        } else {
          ++i;
        }
      }
      while (i < n_ && (cls(s_[i]) & kSpace) != 0) ++i;
    }
    if (i >= n_ || s_[i] != '>') throw unterminated();
    p_ = i + 1;
  }

  std::uint32_t new_element(std::size_t at, std::string_view name) {
    const auto index = static_cast<std::uint32_t>(d_.elements_.size());
    XmlElement& e = d_.elements_.emplace_back();
    e.doc_ = &d_;
    e.name_ = intern(name);
    e.offset_ = static_cast<std::uint32_t>(at);
    e.first_attribute_ = static_cast<std::uint32_t>(d_.attributes_.size());
    if (depth_ > 0) {
      Open& parent = stack_[depth_ - 1];
      if (parent.last_child == XmlElement::kNone) {
        d_.elements_[parent.element].first_child_ = index;
      } else {
        d_.elements_[parent.last_child].next_sibling_ = index;
      }
      parent.last_child = index;
    }
    return index;
  }

  void push(std::uint32_t element) {
    if (depth_ == stack_.size()) stack_.emplace_back();
    Open& o = stack_[depth_++];
    o.element = element;
    o.last_child = XmlElement::kNone;
    o.has_text = false;
    o.owned = false;
    o.text = {};
    o.buffer.clear();
    o.gap.clear();
  }

  // Reads the start tag at p_ ('<' then a name start); true when it was an empty-element tag.
  bool start_tag() {
    const std::size_t at = p_;
    const std::string_view name = name_at(p_ + 1);
    const std::uint32_t index = new_element(at, name);
    p_ += 1 + name.size();
    std::uint32_t count = 0;
    for (;;) {
      const std::size_t before_space = p_;
      skip_space();
      if (p_ >= n_) throw ParseFailure{at, "unterminated start tag <" + std::string(name) + ">: expected '>'"};
      const char c = s_[p_];
      if (c == '>') {
        ++p_;
        finish_attributes(index, count);
        return false;
      }
      if (c == '/') {
        if (p_ + 1 >= n_ || s_[p_ + 1] != '>') {
          throw ParseFailure{p_, "expected '>' after '/' in the start tag of <" + std::string(name) + ">"};
        }
        p_ += 2;
        finish_attributes(index, count);
        return true;
      }
      if ((cls(c) & kNameStart) == 0) {
        throw ParseFailure{p_, "unexpected '" + std::string(1, c) + "' in the start tag of <" + std::string(name) +
                                   ">: expected an attribute, '>' or '/>'"};
      }
      if (p_ == before_space) {
        throw ParseFailure{p_, "missing white space before an attribute in the start tag of <" + std::string(name) + ">"};
      }
      attribute(name, index, count);
      ++count;
    }
  }

  void attribute(std::string_view element_name, std::uint32_t element, std::uint32_t count) {
    const std::size_t name_at_offset = p_;
    const std::string_view raw_name = name_at(p_);
    p_ += raw_name.size();
    const std::string_view name = intern(raw_name);
    if (count > 0) check_unique(name, name_at_offset, element_name, element, count);
    skip_space();
    if (p_ >= n_ || s_[p_] != '=') {
      throw ParseFailure{p_ < n_ ? p_ : name_at_offset, "attribute '" + std::string(raw_name) + "' of <" +
                                                             std::string(element_name) + "> has no value: expected '='"};
    }
    ++p_;
    skip_space();
    if (p_ >= n_ || (s_[p_] != '"' && s_[p_] != '\'')) {
      throw ParseFailure{p_ < n_ ? p_ : name_at_offset,
                         "the value of attribute '" + std::string(raw_name) + "' must be in quotes"};
    }
    const char quote = s_[p_];
    const std::size_t value_start = p_ + 1;
    std::size_t value_end = first_quote_or_special(s_, value_start, quote, d_.latin1_);
    const bool special = value_end < n_ && s_[value_end] != quote;
    if (special) {
      const void* found = std::memchr(s_.data() + value_end, quote, n_ - value_end);
      value_end = found == nullptr ? n_ : static_cast<std::size_t>(static_cast<const char*>(found) - s_.data());
    }
    if (value_end >= n_) {
      throw ParseFailure{p_, "unterminated value of attribute '" + std::string(raw_name) + "': missing closing " +
                                 (quote == '"' ? "'\"'" : "\"'\"")};
    }
    const std::string_view raw = s_.substr(value_start, value_end - value_start);
    if (special) {
      if (const auto lt = raw.find('<'); lt != std::string_view::npos) {
        throw ParseFailure{value_start + lt, "'<' in the value of attribute '" + std::string(raw_name) +
                                                 "': write &lt; for a literal '<'"};
      }
    }
    XmlAttribute& a = d_.attributes_.emplace_back();
    a.name = name;
    a.value = special ? std::string_view(d_.decoded_.emplace_back(decode(raw, value_start, Content::attribute))) : raw;
    a.name_offset = static_cast<std::uint32_t>(name_at_offset);
    a.value_offset = static_cast<std::uint32_t>(value_start);
    a.value_end = static_cast<std::uint32_t>(value_end);
    p_ = value_end + 1;
  }

  // Each name as it is read, so that the first duplicate in document order is the one reported.
  // A few attributes: a linear scan; more: a set of the names seen (built once the count passes
  // the linear limit, so a huge start tag costs linear time, not quadratic).
  void check_unique(std::string_view name, std::size_t at, std::string_view element_name, std::uint32_t element,
                    std::uint32_t count) {
    const XmlAttribute* prior = d_.attributes_.data() + d_.elements_[element].first_attribute_;
    bool duplicate = false;
    if (count < kLinearDuplicateCheck) {
      for (std::uint32_t k = 0; k < count && !duplicate; ++k) duplicate = same_name(prior[k].name, name);
    } else {
      if (count == kLinearDuplicateCheck) {
        names_seen_.clear();
        for (std::uint32_t k = 0; k < count; ++k) names_seen_.insert(prior[k].name);
      }
      duplicate = !names_seen_.insert(name).second;
    }
    if (duplicate) {
      throw ParseFailure{at, "duplicate attribute '" + std::string(name) + "' on <" + std::string(element_name) + ">"};
    }
  }

  void finish_attributes(std::uint32_t element, std::uint32_t count) { d_.elements_[element].attribute_count_ = count; }

  enum class Content { attribute, text, cdata };

  // Decodes a raw value or text piece: references (not in CDATA), CR LF and lone CR as one line
  // end, Latin-1 bytes to UTF-8. In an attribute value every line end, tab or LF becomes a space
  // (XML 1.0 section 3.3.3); in text a line end becomes LF.
  std::string decode(std::string_view raw, std::size_t source_offset, Content content) {
    const bool attribute = content == Content::attribute;
    std::string out;
    out.reserve(raw.size());
    for (std::size_t i = 0; i < raw.size();) {
      const char c = raw[i];
      if (c == '&' && content != Content::cdata) {
        try {
          i = decode_reference(raw, i, out);
        } catch (ParseFailure& f) {
          f.offset += source_offset;
          throw;
        }
      } else if (c == '\r') {
        out += attribute ? ' ' : '\n';
        i += (i + 1 < raw.size() && raw[i + 1] == '\n') ? 2 : 1;
      } else if (attribute && (c == '\t' || c == '\n')) {
        out += ' ';
        ++i;
      } else if (d_.latin1_ && static_cast<unsigned char>(c) >= 0x80) {
        append_utf8(out, static_cast<unsigned char>(c));
        ++i;
      } else {
        out += c;
        ++i;
      }
    }
    return out;
  }

  void add_text(std::string_view raw, std::size_t source_offset, bool cdata) {
    if (!cdata) {
      if (const std::size_t k = raw.find("]]>"); k != std::string_view::npos) {
        throw ParseFailure{source_offset + k, "']]>' is not allowed in text: write ']]&gt;'"};
      }
    }
    Open& o = stack_[depth_ - 1];
    bool blank = true;
    bool special = false;
    for (const char c : raw) {
      const std::uint8_t k = cls(c);
      if ((k & kSpace) == 0) blank = false;
      if ((k & kTextSpecial) != 0 || (d_.latin1_ && static_cast<unsigned char>(c) >= 0x80)) special = true;
    }
    if (!cdata && !special && blank) {
      if (o.has_text) o.gap.append(raw);  // blanks between two pieces of text are kept
      return;
    }
    // References are decoded (and so checked) even in text nobody reads: a bad one is an error.
    if (special) {
      add_decoded(o, decode(raw, source_offset, cdata ? Content::cdata : Content::text));
    } else {
      add_view(o, raw);
    }
  }

  void add_view(Open& o, std::string_view piece) {
    if (o.has_text) return append(o, piece);
    const std::size_t first = first_non_blank(piece);
    if (first == piece.size()) return;
    o.text = piece.substr(first);
    o.has_text = true;
  }

  void add_decoded(Open& o, const std::string& piece) {
    if (o.has_text) return append(o, piece);
    const std::size_t first = first_non_blank(piece);
    if (first == piece.size()) return;
    o.buffer.assign(piece, first);
    o.owned = true;
    o.has_text = true;
  }

  // A piece after earlier text: from now on the text lives in the buffer, with the blanks between.
  static void append(Open& o, std::string_view piece) {
    if (!o.owned) {
      o.buffer.assign(o.text);
      o.owned = true;
    }
    o.buffer += o.gap;
    o.gap.clear();
    o.buffer += piece;
  }

  static std::size_t first_non_blank(std::string_view s) noexcept {
    std::size_t i = 0;
    while (i < s.size() && (cls(s[i]) & kSpace) != 0) ++i;
    return i;
  }

  void close_top() {
    Open& o = stack_[--depth_];
    XmlElement& e = d_.elements_[o.element];
    if (!o.has_text) return;
    if (o.owned) {
      std::string& kept = d_.decoded_.emplace_back(std::move(o.buffer));
      std::size_t end = kept.size();
      while (end > 0 && (cls(kept[end - 1]) & kSpace) != 0) --end;
      kept.resize(end);
      e.text_ = kept;
      o.buffer = std::string();
    } else {
      std::string_view t = o.text;
      while (!t.empty() && (cls(t.back()) & kSpace) != 0) t.remove_suffix(1);
      e.text_ = t;
    }
  }

  // The root element and everything inside it.
  void content() {
    if (s_[p_] != '<' || p_ + 1 >= n_ || (cls(s_[p_ + 1]) & kNameStart) == 0) {
      throw ParseFailure{p_, "expected the root element"};
    }
    if (!start_tag()) push(static_cast<std::uint32_t>(d_.elements_.size() - 1));
    while (depth_ > 0) {
      // Between two tags there is mostly a line end and indentation: skipped inline, and only
      // kept when it falls between two pieces of text (blanks before any text are not text).
      std::size_t lt = space_end(p_);
      if (lt < n_ && s_[lt] == '<') {
        if (lt > p_ && stack_[depth_ - 1].has_text) add_text(s_.substr(p_, lt - p_), p_, false);
      } else {
        const void* found = std::memchr(s_.data() + lt, '<', n_ - lt);
        if (found == nullptr) {
          const XmlElement& open = d_.elements_[stack_[depth_ - 1].element];
          throw ParseFailure{open.offset_, "element <" + std::string(open.name_) + "> is never closed: expected </" +
                                               std::string(open.name_) + "> before the end of the file"};
        }
        lt = static_cast<std::size_t>(static_cast<const char*>(found) - s_.data());
        add_text(s_.substr(p_, lt - p_), p_, false);
      }
      p_ = lt;
      const char next = lt + 1 < n_ ? s_[lt + 1] : '\0';
      if (next == '/') {
        end_tag();
      } else if ((cls(next) & kNameStart) != 0) {
        if (!start_tag()) push(static_cast<std::uint32_t>(d_.elements_.size() - 1));
      } else if (starts_with(p_, "<!--")) {
        comment();
      } else if (starts_with(p_, "<![CDATA[")) {
        const std::size_t end = s_.find("]]>", p_ + 9);
        if (end == std::string_view::npos) throw ParseFailure{p_, "unterminated CDATA section: expected ']]>'"};
        add_text(s_.substr(p_ + 9, end - p_ - 9), p_ + 9, true);
        p_ = end + 3;
      } else if (next == '?') {
        processing_instruction();
      } else if (next == '!') {
        throw ParseFailure{p_, "unexpected '<!' inside an element (a DOCTYPE belongs before the root element)"};
      } else {
        throw ParseFailure{p_, "'<' is not followed by an element name: write &lt; for a literal '<'"};
      }
    }
  }

  void end_tag() {
    const std::size_t at = p_;
    const std::string_view name = name_at(p_ + 2);
    const XmlElement& open = d_.elements_[stack_[depth_ - 1].element];
    if (name.empty()) throw ParseFailure{at, "'</' is not followed by an element name"};
    p_ += 2 + name.size();
    skip_space();
    if (p_ >= n_ || s_[p_] != '>') throw ParseFailure{at, "unterminated end tag </" + std::string(name) + ">: expected '>'"};
    ++p_;
    if (intern(name) != open.name_) {
      throw ParseFailure{at, "end tag </" + std::string(name) + "> does not match the open element " +
                                 opened_at(open)};
    }
    close_top();
  }

  // Lines and columns of every element in one forward walk (elements are in document order).
  void locate_elements() {
    std::size_t cursor = 0;
    std::uint32_t line = 1;
    std::size_t line_start = 0;
    for (XmlElement& e : d_.elements_) {
      const std::size_t target = e.offset_;
      while (cursor < target) {
        const void* nl = std::memchr(s_.data() + cursor, '\n', target - cursor);
        if (nl == nullptr) break;
        cursor = static_cast<std::size_t>(static_cast<const char*>(nl) - s_.data()) + 1;
        line_start = cursor;
        ++line;
      }
      cursor = target;
      e.line_ = line;
      e.column_ = static_cast<std::uint32_t>(target - line_start + 1);
    }
  }

  static constexpr std::uint32_t kLinearDuplicateCheck = 16;

  XmlDocument& d_;
  std::string_view s_;
  std::size_t n_;
  std::size_t p_ = 0;
  std::vector<Open> stack_;
  std::size_t depth_ = 0;
  std::unordered_set<std::string_view> names_seen_;  // attribute names of a start tag with many
};

// --- XmlDocument --------------------------------------------------------------------------

bool XmlDocument::parse(std::string_view text) {
  text_ = text;
  elements_.clear();
  attributes_.clear();
  decoded_.clear();
  line_starts_.clear();
  error_ = XmlError{};
  latin1_ = false;
  try {
    XmlParser(*this, text).run();
    return true;
  } catch (const ParseFailure& f) {
    error_ = XmlError{std::min(f.offset, text.size()), f.message};
  }
  elements_.clear();
  attributes_.clear();
  decoded_.clear();
  return false;
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
  std::size_t produced = 0;
  std::size_t i = a.value_offset;
  std::string unit;
  while (i < a.value_end) {
    const std::size_t start = i;
    const char c = text_[i];
    std::size_t width = 1;
    if (c == '&') {
      unit.clear();
      try {
        i = decode_reference(text_.substr(0, a.value_end), i, unit);
      } catch (const ParseFailure&) {
        return start;  // cannot happen on a parsed document
      }
      width = unit.size();
    } else if (c == '\r' && i + 1 < a.value_end && text_[i + 1] == '\n') {
      i += 2;
    } else if (latin1_ && static_cast<unsigned char>(c) >= 0x80) {
      width = 2;
      ++i;
    } else {
      ++i;
    }
    if (decoded_offset < produced + width) return start;
    produced += width;
  }
  return a.value_end;
}

}  // namespace tripodal::detail
