// Internal: columns for XML diagnostics. tinyxml2 reports the line of an element but no column,
// so the locator scans the source text once and maps elements, attributes and characters inside
// attribute values to line:column (1-based, counted in bytes as gcc does).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <tinyxml2.h>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal::detail {

class XmlLocator {
 public:
  /// `text` must outlive the locator and be the exact text `doc` was parsed from.
  XmlLocator(std::string_view text, std::string file);

  /// Call once after a successful parse: pairs the document's elements (pre-order) with the start
  /// tags found in the text, keeping each offset in the element's user data (no lookup table).
  void index(tinyxml2::XMLDocument& doc);

  [[nodiscard]] const std::string& file() const noexcept { return file_; }
  /// The '<' of the element's start tag.
  [[nodiscard]] SourceLocation element(const tinyxml2::XMLElement* e) const;
  /// The attribute's name; the element when the attribute is absent.
  [[nodiscard]] SourceLocation attribute(const tinyxml2::XMLElement* e, std::string_view name) const;
  /// The character at `decoded_offset` (0-based, in the value after entity decoding) of the
  /// attribute's value; the element when the attribute is absent.
  [[nodiscard]] SourceLocation attribute_value(const tinyxml2::XMLElement* e, std::string_view name,
                                               std::size_t decoded_offset = 0) const;
  /// The first non-blank byte of a line (for parser errors that only know the line).
  [[nodiscard]] SourceLocation line(int line_number) const;
  [[nodiscard]] SourceLocation offset(std::size_t byte_offset) const;

 private:
  struct AttrPos {
    std::size_t name = 0;
    std::size_t value = 0;  ///< first byte after the opening quote
  };
  [[nodiscard]] std::size_t find_attribute(std::size_t tag, std::string_view name, AttrPos& pos) const;
  [[nodiscard]] std::size_t element_offset(const tinyxml2::XMLElement* e, bool& found) const;

  std::string_view text_;
  std::string file_;
  std::vector<std::size_t> line_starts_;
};

}  // namespace tripodal::detail
