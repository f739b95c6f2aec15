// The located XML reader's two paths (src/core/xml_document.hpp): the plain one-pass reader takes
// the common document, tinyxml2 the rest and every error. For any input both must agree: the
// same verdict, the same error at the same offset, or the same tree element by element (names,
// offsets, texts, attributes and their source offsets). A difference is a finding.
#include "tripodal_core_internal/xml_document.hpp"

#include <string>
#include <utility>
#include <vector>

#include "../fuzz_target.hpp"

namespace {

std::string describe(const tripodal::detail::XmlElement* e) {
  return e == nullptr ? std::string("(none)") : std::string(e->name()) + " at offset " + std::to_string(e->offset());
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  using namespace tripodal::detail;
  const std::string_view text = fuzz::as_text(bytes);
  XmlDocument plain;
  XmlDocument reference;
  const bool plain_ok = plain.parse(text);
  const bool reference_ok = reference.parse(text, /*plain_reader=*/false);
  fuzz::require(plain_ok == reference_ok, "both readers give the same verdict",
                plain_ok ? reference.error().message : plain.error().message);
  if (!plain_ok) {
    fuzz::require(plain.error().offset == reference.error().offset && plain.error().message == reference.error().message,
                  "both readers report the same error at the same offset",
                  plain.error().message + " / " + reference.error().message);
    return;
  }
  fuzz::require(plain.element_count() == reference.element_count(), "both trees have as many elements");
  std::vector<std::pair<const XmlElement*, const XmlElement*>> pending{{plain.root(), reference.root()}};
  while (!pending.empty()) {
    const auto [a, b] = pending.back();
    pending.pop_back();
    fuzz::require((a == nullptr) == (b == nullptr), "both trees have the same shape", describe(a) + " / " + describe(b));
    if (a == nullptr) continue;
    const bool same = a->name() == b->name() && a->offset() == b->offset() && a->line() == b->line() &&
                      a->column() == b->column() && a->text() == b->text() && a->attributes().size() == b->attributes().size();
    fuzz::require(same, "each element is read alike", describe(a) + " / " + describe(b));
    for (std::size_t i = 0; i < a->attributes().size(); ++i) {
      const XmlAttribute& x = a->attributes()[i];
      const XmlAttribute& y = b->attributes()[i];
      fuzz::require(x.name == y.name && x.value == y.value && x.name_offset == y.name_offset &&
                        x.value_offset == y.value_offset && x.value_end == y.value_end,
                    "each attribute is read alike", describe(a) + ", attribute " + std::string(x.name));
    }
    pending.emplace_back(a->next_sibling(), b->next_sibling());
    pending.emplace_back(a->first_child(), b->first_child());
  }
}
