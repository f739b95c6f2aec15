// Internal: the XML document behind the net loaders (native format and PNML). tinyxml2 parses the
// text (the common document, without references, CDATA or a DOCTYPE, is read in one pass by the
// plain reader instead, to the same tree: tinyxml2's DOM was half a net's load, issue 42); this
// adds what diagnostics need and tinyxml2 does not keep: the byte offset of every
// element and attribute (so each diagnostic can name LINE:COL), names and values as views with
// their lengths, and the few XML 1.0 well-formedness rules tinyxml2 lets through.
//
// Refused, at the offending byte: invalid UTF-8 and control characters, an unknown entity or a
// bare '&', '<' inside an attribute value, a second root element, text outside the root, encodings
// other than UTF-8 and ISO-8859-1 (the latter is decoded to UTF-8 first). Every other
// well-formedness error is tinyxml2's, located at the line it names.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "large_buffer.hpp"

namespace tinyxml2 {
class XMLDocument;
}

namespace tripodal::detail {

class XmlDocument;

/// Names (of elements and attributes) are short and mostly differ in length or first byte: this
/// settles those inline and calls memcmp only for the rest, where `==` calls it every time.
[[nodiscard]] inline bool same_name(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() && (a.empty() || (a[0] == b[0] && a.compare(b) == 0));
}

struct XmlAttribute {
  std::string_view name;
  /// As tinyxml2 decodes it: references replaced, CR LF and CR turned into LF.
  std::string_view value;
  std::uint32_t name_offset = 0;   ///< source offset of the name
  std::uint32_t value_offset = 0;  ///< source offset of the first byte after the opening quote
  std::uint32_t value_end = 0;     ///< source offset of the closing quote
};

class XmlElement {
 public:
  [[nodiscard]] std::string_view name() const noexcept { return name_; }
  [[nodiscard]] std::span<const XmlAttribute> attributes() const noexcept;
  [[nodiscard]] const XmlAttribute* find_attribute(std::string_view name) const noexcept;
  /// The decoded value of an attribute; nullopt when the element has none of that name.
  [[nodiscard]] std::optional<std::string_view> attribute(std::string_view name) const noexcept;
  /// Child elements in document order, optionally only those of a given name.
  [[nodiscard]] const XmlElement* first_child() const noexcept;
  [[nodiscard]] const XmlElement* first_child(std::string_view name) const noexcept;
  [[nodiscard]] const XmlElement* next_sibling() const noexcept;
  [[nodiscard]] const XmlElement* next_sibling(std::string_view name) const noexcept;
  /// The character data directly inside the element (text and CDATA sections between its
  /// children, concatenated, references decoded), blanks at both ends removed.
  [[nodiscard]] std::string_view text() const noexcept { return text_; }
  /// Source offset of the '<' of the start tag, and its 1-based line and byte column.
  [[nodiscard]] std::uint32_t offset() const noexcept { return offset_; }
  [[nodiscard]] int line() const noexcept { return static_cast<int>(line_); }
  [[nodiscard]] int column() const noexcept { return static_cast<int>(column_); }

 private:
  friend class XmlDocument;
  friend class XmlTreeBuilder;
  friend class XmlPlainReader;
  static constexpr std::uint32_t kNone = 0xFFFFFFFFU;

  const XmlDocument* doc_ = nullptr;
  std::string_view name_;
  std::string_view text_;
  std::uint32_t first_attribute_ = 0;
  std::uint32_t attribute_count_ = 0;
  std::uint32_t first_child_ = kNone;
  std::uint32_t next_sibling_ = kNone;
  std::uint32_t offset_ = 0;
  std::uint32_t line_ = 0;
  std::uint32_t column_ = 0;
};

/// The first well-formedness error of a document: where and what.
struct XmlError {
  std::size_t offset = 0;
  std::string message;
};

/// A parsed document. Views into the source and into the document's own copies of what tinyxml2
/// decoded (its DOM is released at the end of parse()): the text given to parse() must outlive it. Not copyable or movable
/// (elements point back at it).
class XmlDocument {
 public:
  XmlDocument();
  XmlDocument(const XmlDocument&) = delete;
  XmlDocument& operator=(const XmlDocument&) = delete;
  XmlDocument(XmlDocument&&) = delete;
  XmlDocument& operator=(XmlDocument&&) = delete;
  ~XmlDocument();

  /// Parses `text` (UTF-8; ISO-8859-1 when its XML declaration says so). Returns false at the
  /// first error, described by error(); the tree is then empty. The common document is read in
  /// one pass without tinyxml2's DOM (the plain reader); the rest, and every error, through
  /// tinyxml2. `plain_reader` false: tinyxml2 always (tests compare the two).
  bool parse(std::string_view text, bool plain_reader = true);

  [[nodiscard]] const XmlElement* root() const noexcept { return elements_.empty() ? nullptr : &elements_[0]; }
  [[nodiscard]] const XmlError& error() const noexcept { return error_; }
  /// The text offsets refer to: the text given to parse(), or its UTF-8 decoding when the file
  /// was declared ISO-8859-1 and had bytes beyond ASCII.
  [[nodiscard]] std::string_view source() const noexcept { return text_; }
  [[nodiscard]] std::size_t element_count() const noexcept { return elements_.size(); }
  /// Whether the last successful parse was the plain reader's (no tinyxml2 DOM built).
  [[nodiscard]] bool read_plain() const noexcept { return read_plain_; }

  struct LineColumn {
    int line = 1;
    int column = 1;
  };
  /// 1-based line and byte column (as gcc counts) of a source offset.
  [[nodiscard]] LineColumn line_column(std::size_t offset) const;
  /// The source offset of the character that produced byte `decoded_offset` of the attribute's
  /// decoded value (an entity reference is one character); value_end past the last one.
  [[nodiscard]] std::size_t value_source_offset(const XmlAttribute& attribute, std::size_t decoded_offset) const;

 private:
  friend class XmlElement;
  friend class XmlTreeBuilder;
  friend class XmlPlainReader;

  void clear();

  std::unique_ptr<tinyxml2::XMLDocument> xml_;
  std::string latin1_decoded_;  // the source, when it had to be decoded from ISO-8859-1
  std::string_view text_;
  std::vector<XmlElement, LargeBufferAllocator<XmlElement>> elements_;
  std::vector<XmlAttribute, LargeBufferAllocator<XmlAttribute>> attributes_;
  std::deque<std::string> joined_;  // texts of several pieces (around children, CDATA); stable addresses
  std::string owned_;               // decoded values and texts copied out of tinyxml2's buffer before its DOM goes
  mutable std::vector<std::size_t> line_starts_;  // built on the first line_column() call
  XmlError error_;
  bool read_plain_ = false;
};

// Inline: the readers walk every element through these.
inline const XmlElement* XmlElement::first_child() const noexcept {
  return first_child_ == kNone ? nullptr : &doc_->elements_[first_child_];
}
inline const XmlElement* XmlElement::next_sibling() const noexcept {
  return next_sibling_ == kNone ? nullptr : &doc_->elements_[next_sibling_];
}
inline std::span<const XmlAttribute> XmlElement::attributes() const noexcept {
  return {doc_->attributes_.data() + first_attribute_, attribute_count_};
}
inline const XmlAttribute* XmlElement::find_attribute(std::string_view name) const noexcept {
  for (const XmlAttribute& a : attributes()) {
    if (same_name(a.name, name)) return &a;
  }
  return nullptr;
}
inline std::optional<std::string_view> XmlElement::attribute(std::string_view name) const noexcept {
  const XmlAttribute* a = find_attribute(name);
  if (a == nullptr) return std::nullopt;
  return a->value;
}

}  // namespace tripodal::detail
