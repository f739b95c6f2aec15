#include "xml_locator.hpp"

#include <algorithm>
#include <cstdint>

namespace tripodal::detail {

namespace {

bool is_name_start(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':' ||
         static_cast<unsigned char>(c) >= 0x80;
}
bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// Offsets of every start tag's '<', in document order, skipping comments, CDATA, processing
// instructions, declarations and quoted attribute values (which may contain '<' or '>').
std::vector<std::size_t> start_tags(std::string_view s) {
  std::vector<std::size_t> out;
  std::size_t i = 0;
  const auto skip_past = [&](std::string_view end) {
    const auto p = s.find(end, i);
    i = p == std::string_view::npos ? s.size() : p + end.size();
  };
  while (i < s.size()) {
    const auto lt = s.find('<', i);
    if (lt == std::string_view::npos) break;
    i = lt + 1;
    if (s.substr(lt, 4) == "<!--") {
      skip_past("-->");
    } else if (s.substr(lt, 9) == "<![CDATA[") {
      skip_past("]]>");
    } else if (s.substr(lt, 2) == "<?") {
      skip_past("?>");
    } else if (i < s.size() && (s[i] == '!' || s[i] == '/')) {
      skip_past(">");
    } else if (i < s.size() && is_name_start(s[i])) {
      out.push_back(lt);
      char quote = 0;
      while (i < s.size()) {
        const char c = s[i++];
        if (quote != 0) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '>') {
          break;
        }
      }
    }
  }
  return out;
}

void preorder(tinyxml2::XMLNode* node, std::vector<tinyxml2::XMLElement*>& out) {
  for (auto* child = node->FirstChild(); child != nullptr; child = child->NextSibling()) {
    if (auto* e = child->ToElement()) {
      out.push_back(e);
      preorder(e, out);
    }
  }
}

}  // namespace

XmlLocator::XmlLocator(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {
  line_starts_.push_back(0);
  for (std::size_t i = 0; i < text_.size(); ++i) {
    if (text_[i] == '\n') line_starts_.push_back(i + 1);
  }
}

void XmlLocator::index(tinyxml2::XMLDocument& doc) {
  std::vector<tinyxml2::XMLElement*> elems;
  preorder(&doc, elems);
  const auto tags = start_tags(text_);
  const std::size_t n = std::min(elems.size(), tags.size());
  for (std::size_t k = 0; k < n; ++k) {
    // A mismatch means the scan and tinyxml2 disagree about this text; such elements fall back to
    // the start of their line rather than pointing somewhere wrong.
    if (offset(tags[k]).line != elems[k]->GetLineNum()) break;
    // Offset + 1, so that null user data means "not located".
    elems[k]->SetUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(tags[k] + 1)));
  }
}

SourceLocation XmlLocator::offset(std::size_t byte_offset) const {
  const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), byte_offset);
  const auto line_index = static_cast<std::size_t>(it - line_starts_.begin()) - 1;
  return SourceLocation{file_, static_cast<int>(line_index + 1),
                        static_cast<int>(byte_offset - line_starts_[line_index] + 1)};
}

SourceLocation XmlLocator::line(int line_number) const {
  if (line_number < 1) line_number = 1;
  const auto index = std::min(static_cast<std::size_t>(line_number - 1), line_starts_.size() - 1);
  std::size_t p = line_starts_[index];
  while (p < text_.size() && (text_[p] == ' ' || text_[p] == '\t')) ++p;
  if (p >= text_.size() || text_[p] == '\n' || text_[p] == '\r') p = line_starts_[index];
  return offset(p);
}

std::size_t XmlLocator::element_offset(const tinyxml2::XMLElement* e, bool& found) const {
  const auto stored = reinterpret_cast<std::uintptr_t>(e->GetUserData());
  found = stored != 0;
  return found ? static_cast<std::size_t>(stored - 1) : 0;
}

SourceLocation XmlLocator::element(const tinyxml2::XMLElement* e) const {
  bool found = false;
  const auto off = element_offset(e, found);
  return found ? offset(off) : line(e->GetLineNum());
}

std::size_t XmlLocator::find_attribute(std::size_t tag, std::string_view name, AttrPos& pos) const {
  std::size_t i = tag + 1;
  while (i < text_.size() && !is_space(text_[i]) && text_[i] != '>' && text_[i] != '/') ++i;
  while (i < text_.size()) {
    while (i < text_.size() && is_space(text_[i])) ++i;
    if (i >= text_.size() || text_[i] == '>' || text_[i] == '/') return std::string_view::npos;
    const std::size_t name_start = i;
    while (i < text_.size() && !is_space(text_[i]) && text_[i] != '=' && text_[i] != '>') ++i;
    const auto attr_name = text_.substr(name_start, i - name_start);
    while (i < text_.size() && is_space(text_[i])) ++i;
    if (i >= text_.size() || text_[i] != '=') return std::string_view::npos;
    ++i;
    while (i < text_.size() && is_space(text_[i])) ++i;
    if (i >= text_.size() || (text_[i] != '"' && text_[i] != '\'')) return std::string_view::npos;
    const char quote = text_[i++];
    const std::size_t value_start = i;
    while (i < text_.size() && text_[i] != quote) ++i;
    if (attr_name == name) {
      pos = AttrPos{name_start, value_start};
      return name_start;
    }
    ++i;
  }
  return std::string_view::npos;
}

SourceLocation XmlLocator::attribute(const tinyxml2::XMLElement* e, std::string_view name) const {
  bool found = false;
  const auto tag = element_offset(e, found);
  AttrPos pos;
  if (!found || find_attribute(tag, name, pos) == std::string_view::npos) return element(e);
  return offset(pos.name);
}

SourceLocation XmlLocator::attribute_value(const tinyxml2::XMLElement* e, std::string_view name,
                                           std::size_t decoded_offset) const {
  bool found = false;
  const auto tag = element_offset(e, found);
  AttrPos pos;
  if (!found || find_attribute(tag, name, pos) == std::string_view::npos) return element(e);
  // Walk the raw value: an entity reference (&amp;, &#39;) is one decoded character.
  std::size_t raw = pos.value;
  for (std::size_t k = 0; k < decoded_offset && raw < text_.size(); ++k) {
    if (text_[raw] == '&') {
      const auto semi = text_.find(';', raw);
      raw = (semi == std::string_view::npos || semi - raw > 10) ? raw + 1 : semi + 1;
    } else {
      ++raw;
    }
  }
  return offset(std::min(raw, text_.empty() ? std::size_t{0} : text_.size() - 1));
}

}  // namespace tripodal::detail
