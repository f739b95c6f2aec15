#include "xml_locator.hpp"

namespace tripodal::detail {

SourceLocation XmlLocator::offset(std::size_t byte_offset) const {
  const auto lc = doc_.line_column(byte_offset);
  return SourceLocation{file_, lc.line, lc.column};
}

SourceLocation XmlLocator::attribute(const XmlElement* e, std::string_view name) const {
  const XmlAttribute* a = e->find_attribute(name);
  return a == nullptr ? element(e) : offset(a->name_offset);
}

SourceLocation XmlLocator::attribute_value(const XmlElement* e, std::string_view name,
                                           std::size_t decoded_offset) const {
  const XmlAttribute* a = e->find_attribute(name);
  return a == nullptr ? element(e) : offset(doc_.value_source_offset(*a, decoded_offset));
}

}  // namespace tripodal::detail
