#include "tripodal/core/net_loader.hpp"

#include <cstdint>
#include <fstream>

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

}  // namespace

std::vector<bool> structurally_markable(const PetriNet& net) {
  // Over-approximation of markable places: a transition may become enabled once every place it
  // consumes from or reads is markable; then its output places are markable. A worklist keeps it
  // linear in the size of the net whatever the declaration order.
  const auto& places = net.places();
  const auto& transitions = net.transitions();
  std::vector<bool> markable(places.size(), false);
  std::vector<bool> fireable(transitions.size(), false);
  std::vector<std::uint32_t> missing(transitions.size(), 0);  // needed places not yet markable
  // needed_by[needed_begin[p] .. needed_begin[p + 1]): the transitions consuming or reading p,
  // one entry per arc (flat arrays: a net of 10,000 places is one allocation, not 10,000).
  std::vector<std::uint32_t> needed_begin(places.size() + 1, 0);
  for (const auto& tr : transitions) {
    for (const auto* arcs : {&tr.inputs, &tr.reads}) {
      for (const auto& a : *arcs) ++needed_begin[a.place + 1];
    }
  }
  for (std::size_t p = 0; p < places.size(); ++p) needed_begin[p + 1] += needed_begin[p];
  std::vector<std::uint32_t> needed_by(needed_begin.back());
  {
    std::vector<std::uint32_t> fill(needed_begin.begin(), needed_begin.end() - 1);
    for (std::size_t t = 0; t < transitions.size(); ++t) {
      for (const auto* arcs : {&transitions[t].inputs, &transitions[t].reads}) {
        for (const auto& a : *arcs) {
          needed_by[fill[a.place]++] = static_cast<std::uint32_t>(t);
          ++missing[t];
        }
      }
    }
  }
  std::vector<PlaceIndex> work;
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
    for (std::uint32_t i = needed_begin[p]; i < needed_begin[p + 1]; ++i) {
      const std::uint32_t t = needed_by[i];
      if (--missing[t] == 0 && !fireable[t]) fire(t);
    }
  }
  return markable;
}

void structural_warnings(const PetriNet& net, Diagnostics& diagnostics) {
  const auto& places = net.places();
  const auto& transitions = net.transitions();
  const std::vector<bool> markable = structurally_markable(net);
  // A transition can fire in the over-approximation exactly when every place it needs is markable.
  const auto fireable = [&](const Transition& tr) {
    for (const auto* arcs : {&tr.inputs, &tr.reads}) {
      for (const auto& a : *arcs) {
        if (!markable[a.place]) return false;
      }
    }
    return true;
  };
  for (std::size_t i = 0; i < places.size(); ++i) {
    if (markable[i]) continue;
    diagnostics.warning(places[i].where, "place '" + places[i].id +
                                             "' can never be marked: it has no initial tokens and no transition that "
                                             "can fire puts tokens into it");
  }
  for (const auto& tr : transitions) {
    if (fireable(tr)) continue;
    std::string blocked;
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
  detail::XmlDocument doc;
  detail::XmlLocator locator(doc, SourceFile(name));
  if (!doc.parse(text)) {
    diagnostics.error(locator.offset(doc.error().offset), "malformed XML: " + doc.error().message);
    return std::nullopt;
  }
  const detail::ReadContext ctx{locator, diagnostics, options, {}};
  const detail::XmlElement* root = doc.root();
  NetFormat format = options.format;
  if (format == NetFormat::automatic) {
    if (has_extension(name, ".pnml") || root->name() == "pnml") format = NetFormat::pnml;
    else format = NetFormat::native_xml;
  }
  const std::string_view expected_root = format == NetFormat::pnml ? "pnml" : "net";
  if (root->name() != expected_root) {
    ctx.error(root, "unexpected root element <" + std::string(root->name()) + ">: expected <" +
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
  std::string text;
  try {
    text = read_config_file(file);
  } catch (const ConfigError& e) {
    diagnostics.append(e.diagnostics());
    return std::nullopt;
  }
  return load_net_from_string(text, file.string(), diagnostics, options);
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
