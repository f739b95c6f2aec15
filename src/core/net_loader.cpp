#include "tripodal/core/net_loader.hpp"

#include <cstdint>
#include <fstream>
#include <sstream>

#include "net_formats.hpp"
#include "xml_locator.hpp"

namespace tripodal {

namespace {

bool has_extension(std::string_view name, std::string_view ext) {
  if (name.size() < ext.size()) return false;
  const auto tail = name.substr(name.size() - ext.size());
  for (std::size_t i = 0; i < ext.size(); ++i) {
    const char c = tail[i];
    const char lower = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    if (lower != ext[i]) return false;
  }
  return true;
}

// tinyxml2's ErrorStr() reads "Error=XML_ERROR_X ErrorID=n (0xn) Line number=n: detail"; keep the
// part an author can use.
std::string xml_error_message(const tinyxml2::XMLDocument& doc) {
  std::string what;
  switch (doc.ErrorID()) {
    case tinyxml2::XML_ERROR_EMPTY_DOCUMENT: what = "empty document: expected a root element"; break;
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT: what = "end tag does not match the open element"; break;
    case tinyxml2::XML_ERROR_PARSING_ELEMENT: what = "cannot parse element (unclosed tag, bad name or missing end tag)"; break;
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE: what = "cannot parse attribute (missing quote or '=', or duplicate attribute)"; break;
    case tinyxml2::XML_ERROR_PARSING_TEXT: what = "cannot parse text (unescaped '<' or '&'?)"; break;
    case tinyxml2::XML_ERROR_PARSING_CDATA: what = "unterminated CDATA section"; break;
    case tinyxml2::XML_ERROR_PARSING_COMMENT: what = "unterminated comment"; break;
    case tinyxml2::XML_ERROR_PARSING_DECLARATION: what = "cannot parse the XML declaration"; break;
    case tinyxml2::XML_ERROR_PARSING_UNKNOWN: what = "cannot parse a <!...> declaration"; break;
    case tinyxml2::XML_ERROR_PARSING: what = "cannot parse the document (text after the root element?)"; break;
    default: what = doc.ErrorName(); break;
  }
  const std::string full = doc.ErrorStr() != nullptr ? doc.ErrorStr() : "";
  const auto ln = full.find("Line number=");
  if (ln != std::string::npos) {
    const auto colon = full.find(": ", ln);
    if (colon != std::string::npos) what += " (" + full.substr(colon + 2) + ")";
  }
  return "malformed XML: " + what;
}

}  // namespace

void structural_warnings(const PetriNet& net, Diagnostics& diagnostics) {
  // Over-approximation of markable places: a transition may become enabled once every place it
  // consumes from or reads is markable; then its output places are markable. A worklist keeps it
  // linear in the size of the net whatever the declaration order.
  const auto& places = net.places();
  const auto& transitions = net.transitions();
  std::vector<bool> markable(places.size(), false);
  std::vector<bool> fireable(transitions.size(), false);
  std::vector<std::size_t> missing(transitions.size(), 0);  // needed places not yet markable
  std::vector<std::vector<std::uint32_t>> needed_by(places.size());
  std::vector<PlaceIndex> work;
  for (std::size_t t = 0; t < transitions.size(); ++t) {
    for (const auto* arcs : {&transitions[t].inputs, &transitions[t].reads}) {
      for (const auto& a : *arcs) {
        needed_by[a.place].push_back(static_cast<std::uint32_t>(t));
        ++missing[t];
      }
    }
  }
  const auto mark = [&](PlaceIndex p) {
    if (!markable[p]) {
      markable[p] = true;
      work.push_back(p);
    }
  };
  const auto fire = [&](std::size_t t) {
    fireable[t] = true;
    for (const auto& a : transitions[t].outputs) mark(a.place);
  };
  for (std::size_t i = 0; i < places.size(); ++i) {
    if (places[i].initial_tokens > 0) mark(static_cast<PlaceIndex>(i));
  }
  for (std::size_t t = 0; t < transitions.size(); ++t) {
    if (missing[t] == 0) fire(t);
  }
  while (!work.empty()) {
    const PlaceIndex p = work.back();
    work.pop_back();
    // A place counted once per arc: several arcs from one place decrement once each.
    for (const auto t : needed_by[p]) {
      if (--missing[t] == 0 && !fireable[t]) fire(t);
    }
  }
  for (std::size_t i = 0; i < places.size(); ++i) {
    if (markable[i]) continue;
    diagnostics.warning(places[i].where, "place '" + places[i].id +
                                             "' can never be marked: it has no initial tokens and no transition that "
                                             "can fire puts tokens into it");
  }
  for (std::size_t t = 0; t < transitions.size(); ++t) {
    if (fireable[t]) continue;
    std::string blocked;
    const auto& tr = transitions[t];
    for (const auto* arcs : {&tr.inputs, &tr.reads}) {
      for (const auto& a : *arcs) {
        if (markable[a.place]) continue;
        if (!blocked.empty()) blocked += ", ";
        blocked += places[a.place].id;
      }
    }
    diagnostics.warning(tr.where, "transition '" + tr.id + "' can never be enabled: place(s) " + blocked +
                                      " can never be marked");
  }
}

std::optional<PetriNet> load_net_from_string(std::string_view text, std::string_view name, Diagnostics& diagnostics,
                                             const LoadOptions& options) {
  const std::size_t errors_before = diagnostics.error_count();
  detail::XmlLocator locator(text, std::string(name));
  tinyxml2::XMLDocument doc(true, tinyxml2::PRESERVE_WHITESPACE);
  if (doc.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) {
    diagnostics.error(locator.line(doc.ErrorLineNum()), xml_error_message(doc));
    return std::nullopt;
  }
  locator.index(doc);
  const detail::ReadContext ctx{locator, diagnostics, options};
  const tinyxml2::XMLElement* root = doc.RootElement();
  if (root == nullptr) {
    diagnostics.error(locator.line(1), "malformed XML: no root element");
    return std::nullopt;
  }
  NetFormat format = options.format;
  if (format == NetFormat::automatic) {
    if (has_extension(name, ".pnml") || std::string_view(root->Name()) == "pnml") format = NetFormat::pnml;
    else format = NetFormat::native_xml;
  }
  const std::string_view expected_root = format == NetFormat::pnml ? "pnml" : "net";
  if (std::string_view(root->Name()) != expected_root) {
    ctx.error(root, "unexpected root element <" + std::string(root->Name()) + ">: expected <" +
                        std::string(expected_root) + ">" +
                        (format == NetFormat::pnml ? " (a PNML file)" : " (a tripodal net, docs/net-format.md)"));
    return std::nullopt;
  }
  PetriNet net = format == NetFormat::pnml ? detail::read_pnml(root, ctx) : detail::read_native(root, ctx);
  if (diagnostics.error_count() != errors_before) return std::nullopt;
  if (options.structural_warnings) structural_warnings(net, diagnostics);
  return net;
}

std::optional<PetriNet> load_net(const std::filesystem::path& file, Diagnostics& diagnostics,
                                 const LoadOptions& options) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    diagnostics.error(SourceLocation{file.string(), 0, 0}, "cannot open file");
    return std::nullopt;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    diagnostics.error(SourceLocation{file.string(), 0, 0}, "cannot read file");
    return std::nullopt;
  }
  return load_net_from_string(buffer.str(), file.string(), diagnostics, options);
}

PetriNet load_net_or_throw(const std::filesystem::path& file, const LoadOptions& options) {
  Diagnostics diagnostics;
  auto net = load_net(file, diagnostics, options);
  if (!net) throw ConfigError(std::move(diagnostics));
  return std::move(*net);
}

std::string net_to_string(const PetriNet& net, NetFormat format) {
  return format == NetFormat::pnml ? detail::write_pnml(net) : detail::write_native(net);
}

void save_net(const PetriNet& net, const std::filesystem::path& file) {
  const NetFormat format = has_extension(file.string(), ".pnml") ? NetFormat::pnml : NetFormat::native_xml;
  const std::string text = net_to_string(net, format);
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot open file for writing");
  out << text;
  out.flush();
  if (!out) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot write file");
}

}  // namespace tripodal
