// The native XML format of configuration nets: reader and writer (docs/net-format.md).
#include <array>
#include <charconv>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "net_formats.hpp"

namespace tripodal::detail {

namespace {

constexpr std::string_view kNetChildren = "parameter, fact, place, transition, arc";
// How many nodes or arcs ahead the net's id index is prefetched: enough for a memory access to
// land while the elements in between are read (about 50 ns each).
constexpr std::size_t kPrefetchAhead = 8;

}  // namespace

PetriNet read_native(const XmlElement* root, const ReadContext& ctx) {
  PetriNet net;
  net.where = ctx.loc.element(root);
  check_attributes(ctx, root, {"id", "name", "description", "level", "version", "xmlns:xsi",
                               "xsi:noNamespaceSchemaLocation"});
  check_no_text(ctx, root);
  if (auto id = required(ctx, root, "id")) net.id = *id;
  net.name = optional_attr(root, "name").value_or(net.id);  // like nodes: the name defaults to the id
  net.description = optional_attr(root, "description").value_or("");
  if (auto level = optional_attr(root, "level")) {
    if (*level == "low") net.level = NetLevel::low;
    else if (*level == "high") net.level = NetLevel::high;
    else ctx.error_at_value(root, "level", "unknown level '" + std::string(*level) + "': expected low or high");
  }
  if (auto version = optional_attr(root, "version"); version && *version != kFormatVersion) {
    ctx.error_at_value(root, "version", "format version '" + std::string(*version) + "' is not supported: this build reads version " +
                                            std::string(kFormatVersion));
  }

  // One pass sorts the children: declarations are read at once (guards and "$param" bindings
  // are checked against them wherever they appear), then places, transitions and arcs in turn.
  std::vector<const XmlElement*> places;
  std::vector<const XmlElement*> transitions;
  std::vector<const XmlElement*> arcs;
  for (const auto* c = root->first_child(); c != nullptr; c = c->next_sibling()) {
    const std::string_view n = c->name();
    if (n == "arc") arcs.push_back(c);
    else if (n == "place") places.push_back(c);
    else if (n == "transition") transitions.push_back(c);
    else if (n == "parameter" || n == "fact") read_declaration(ctx, c, net, n == "fact");
    else unknown_element(ctx, c, "net", kNetChildren);
  }

  // A node joins the net as soon as its id is read, and its details are then read into it where
  // it lies: the net's own index finds a duplicate id (and its first definition) in the same
  // look-up that adds the node, and no node is built aside and moved in. A node that cannot be
  // added (no id, or a duplicate) is still read, into a scratch node, for the errors it holds.
  const auto duplicate = [&](const XmlElement* e, std::string_view id) {
    const SourceLocation* first = net.find_node_where(id);
    ctx.error_at_value(e, "id", "duplicate id '" + std::string(id) + "' (first defined at " +
                                    (first != nullptr ? first->str() : std::string("?")) + ")");
  };
  net.reserve(places.size(), transitions.size());  // no reallocation while the nodes arrive
  // `add` creates the node in the net; `scratch` (built once: most nodes are added) takes one
  // that cannot be added.
  const auto read_nodes = [&](const std::vector<const XmlElement*>& elements, auto add, auto& scratch, auto details) {
    for (std::size_t i = 0; i < elements.size(); ++i) {
      if (i + kPrefetchAhead < elements.size()) {
        if (auto ahead = elements[i + kPrefetchAhead]->attribute("id")) net.prefetch_node(*ahead);
      }
      const XmlElement* c = elements[i];
      const auto id = required(ctx, c, "id");
      std::remove_reference_t<decltype(scratch)>* node = nullptr;
      if (id) {
        try {
          node = &add(*id, ctx.loc.element(c));
        } catch (const std::invalid_argument&) {
          duplicate(c, *id);
        }
      }
      if (node == nullptr) {
        scratch = {};
        scratch.id = id.value_or(std::string_view());
        scratch.where = ctx.loc.element(c);
        node = &scratch;
      }
      details(ctx, c, *node, net, true);
    }
  };
  Place scratch_place;
  Transition scratch_transition;
  read_nodes(places, [&](std::string_view id, SourceLocation where) -> Place& { return net.new_place(id, where); },
             scratch_place, read_place_details);
  read_nodes(transitions,
             [&](std::string_view id, SourceLocation where) -> Transition& { return net.new_transition(id, where); },
             scratch_transition, read_transition_details);
  static constexpr std::array<std::string_view, 4> kArcAttributes{"source", "target", "weight", "kind"};
  for (std::size_t i = 0; i < arcs.size(); ++i) {
    if (i + kPrefetchAhead < arcs.size()) {
      const XmlElement* ahead = arcs[i + kPrefetchAhead];
      if (auto from = ahead->attribute("source")) net.prefetch_node(*from);
      if (auto to = ahead->attribute("target")) net.prefetch_node(*to);
    }
    const XmlElement* c = arcs[i];
    AttributeValues<kArcAttributes.size()> attr;
    read_attributes(ctx, c, kArcAttributes, attr.found);
    check_no_text(ctx, c);
    for (const auto* g = c->first_child(); g != nullptr; g = g->next_sibling()) unknown_element(ctx, g, "arc", "");
    const auto source = required(ctx, c, "source", attr[0]);
    const auto target = required(ctx, c, "target", attr[1]);
    std::optional<Tokens> weight = 1;
    if (const auto& w = attr[2]) weight = parse_count(ctx, c, "weight", *w, 1, "weight");
    std::optional<ArcKind> kind = ArcKind::normal;
    if (const auto& k = attr[3]) {
      kind = parse_arc_kind(*k);
      if (!kind) ctx.error_at_value(c, "kind", "unknown arc kind '" + std::string(*k) + "': expected normal, read or inhibitor");
    }
    if (source && target && weight && kind) add_checked_arc(ctx, c, net, *source, *target, *weight, *kind);
  }
  return net;
}

std::string xml_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\n': out += "&#10;"; break;
      case '\r': out += "&#13;"; break;
      case '\t': out += "&#9;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string value_text(const Value& v) {
  if (const auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const auto* d = std::get_if<double>(&v)) {
    char buf[64];
    const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, *d);
    return ec == std::errc() ? std::string(buf, ptr) : std::to_string(*d);
  }
  return std::get<std::string>(v);
}

std::string delay_text(Duration d) {
  const auto ns = d.count();
  if (ns % 1'000'000'000 == 0) return std::to_string(ns / 1'000'000'000) + "s";
  if (ns % 1'000'000 == 0) return std::to_string(ns / 1'000'000) + "ms";
  if (ns % 1'000 == 0) return std::to_string(ns / 1'000) + "us";
  return std::to_string(ns) + "ns";
}

namespace {
std::string attr(std::string_view name, std::string_view value) {
  std::string out = " ";
  out += name;
  out += "=\"";
  out += xml_escape(value);
  out += '"';
  return out;
}
}  // namespace

std::string place_detail_attributes(const Place& p) {
  std::string out;
  if (!p.description.empty()) out += attr("description", p.description);
  if (p.capacity) out += attr("capacity", std::to_string(*p.capacity));
  if (p.outcome == Outcome::success) out += attr("outcome", "success");
  if (p.outcome == Outcome::fault) {
    out += attr("outcome", "fault");
    if (!p.fault_message.empty()) out += attr("message", p.fault_message);
  }
  return out;
}

std::string transition_detail_attributes(const Transition& t) {
  std::string out;
  if (!t.description.empty()) out += attr("description", t.description);
  if (!t.event.empty()) out += attr("event", t.event);
  if (t.guard) out += attr("guard", t.guard->text());
  if (t.delay.count() != 0) out += attr("delay", delay_text(t.delay));
  if (t.priority != 0) out += attr("priority", std::to_string(t.priority));
  return out;
}

std::string binding_elements(const Place& p, const std::string& indent) {
  const std::string* name = nullptr;
  const std::vector<BindingParam>* params = nullptr;
  const char* kind = nullptr;
  if (p.behavior) {
    kind = "behavior";
    name = &p.behavior->behavior;
    params = &p.behavior->params;
  } else if (p.process) {
    kind = "process";
    name = &p.process->process;
    params = &p.process->params;
  } else {
    return {};
  }
  std::string out = indent + "<" + kind + attr("name", *name);
  if (params->empty()) return out + "/>\n";
  out += ">\n";
  for (const auto& bp : *params) out += indent + "  <param" + attr("name", bp.name) + attr("value", bp.value) + "/>\n";
  return out + indent + "</" + kind + ">\n";
}

std::string declaration_elements(const PetriNet& net, const std::string& indent) {
  std::string out;
  const auto one = [&](const char* kind, const VariableDecl& d) {
    out += indent + "<" + kind + attr("name", d.name) + attr("type", to_string(d.type));
    if (d.default_value) out += attr("default", value_text(*d.default_value));
    if (!d.description.empty()) out += attr("description", d.description);
    out += "/>\n";
  };
  for (const auto& d : net.parameters) one("parameter", d);
  for (const auto& d : net.facts) one("fact", d);
  return out;
}

std::string write_native(const PetriNet& net) {
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<net";
  out += attr("id", net.id.empty() ? std::string("net") : net.id);
  if (!net.name.empty() && net.name != net.id) out += attr("name", net.name);
  out += attr("level", net.level == NetLevel::high ? "high" : "low");
  out += attr("version", kFormatVersion);
  if (!net.description.empty()) out += attr("description", net.description);
  out += ">\n";
  out += declaration_elements(net, "  ");
  for (const auto& p : net.places()) {
    out += "  <place" + attr("id", p.id);
    if (p.name != p.id) out += attr("name", p.name);
    if (p.initial_tokens != 0) out += attr("tokens", std::to_string(p.initial_tokens));
    out += place_detail_attributes(p);
    const std::string bindings = binding_elements(p, "    ");
    out += bindings.empty() ? "/>\n" : ">\n" + bindings + "  </place>\n";
  }
  for (const auto& t : net.transitions()) {
    out += "  <transition" + attr("id", t.id);
    if (t.name != t.id) out += attr("name", t.name);
    out += transition_detail_attributes(t) + "/>\n";
  }
  for (const auto& t : net.transitions()) {
    const auto arc = [&](const std::string& from, const std::string& to, const ArcRef& a, ArcKind kind) {
      out += "  <arc" + attr("source", from) + attr("target", to);
      if (a.weight != 1) out += attr("weight", std::to_string(a.weight));
      if (kind != ArcKind::normal) out += attr("kind", to_string(kind));
      out += "/>\n";
    };
    for (const auto& a : t.inputs) arc(net.place(a.place).id, t.id, a, ArcKind::normal);
    for (const auto& a : t.reads) arc(net.place(a.place).id, t.id, a, ArcKind::read);
    for (const auto& a : t.inhibitors) arc(net.place(a.place).id, t.id, a, ArcKind::inhibitor);
    for (const auto& a : t.outputs) arc(t.id, net.place(a.place).id, a, ArcKind::normal);
  }
  return out + "</net>\n";
}

}  // namespace tripodal::detail
