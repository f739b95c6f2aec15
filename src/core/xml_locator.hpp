// Internal: source locations for diagnostics about a parsed XML document: the element's '<', an
// attribute's name, a character inside an attribute's value (1-based line and byte column, as
// gcc counts).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "tripodal/core/diagnostic.hpp"
#include "xml_document.hpp"

namespace tripodal::detail {

class XmlLocator {
 public:
  /// `doc` must outlive the locator.
  XmlLocator(const XmlDocument& doc, SourceFile file) : doc_(doc), file_(file) {}

  [[nodiscard]] const std::string& file() const noexcept { return file_.str(); }
  /// The '<' of the element's start tag.
  [[nodiscard]] SourceLocation element(const XmlElement* e) const {
    return SourceLocation{file_, e->line(), e->column()};
  }
  /// The attribute's name; the element when the attribute is absent.
  [[nodiscard]] SourceLocation attribute(const XmlElement* e, std::string_view name) const;
  /// The character that produced byte `decoded_offset` (0-based) of the attribute's decoded value
  /// (an entity reference is one character); the element when the attribute is absent.
  [[nodiscard]] SourceLocation attribute_value(const XmlElement* e, std::string_view name,
                                               std::size_t decoded_offset = 0) const;
  [[nodiscard]] SourceLocation offset(std::size_t byte_offset) const;

 private:
  const XmlDocument& doc_;
  SourceFile file_;  // interned once per document: locating an element does not allocate
};

}  // namespace tripodal::detail
