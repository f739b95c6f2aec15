#include "net_reader.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <set>
#include <span>
#include <stdexcept>

#include "tripodal/core/registry.hpp"

namespace tripodal::detail {

namespace {

std::string join_names(const std::vector<VariableDecl>& decls) {
  std::string out;
  for (const auto& d : decls) {
    if (!out.empty()) out += ", ";
    out += d.name;
  }
  return out.empty() ? std::string("none") : out;
}

// "; did you mean 'x'?" when one of `known` is close to `name` (registry.hpp's closest_name, the
// helper the profile errors use), else nothing.
std::string did_you_mean(std::string_view name, const std::vector<std::string>& known) {
  const auto close = closest_name(name, known);
  return close ? "; did you mean '" + *close + "'?" : std::string();
}

std::vector<std::string> names_of(const std::vector<VariableDecl>& decls) {
  std::vector<std::string> out;
  out.reserve(decls.size());
  for (const auto& d : decls) out.push_back(d.name);
  return out;
}

std::string declared_list(const PetriNet& net) {
  return "declared parameters: " + join_names(net.parameters) + "; facts: " + join_names(net.facts);
}

bool is_ident_char(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.';
}

// Offset of the first whole-word occurrence of `word` in `text` outside string literals.
std::size_t find_identifier(std::string_view text, std::string_view word) {
  char quote = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quote != 0) {
      if (c == quote) quote = 0;
      continue;
    }
    if (c == '\'' || c == '"') {
      quote = c;
      continue;
    }
    if (text.substr(i, word.size()) == word && (i == 0 || !is_ident_char(text[i - 1])) &&
        (i + word.size() >= text.size() || !is_ident_char(text[i + word.size()]))) {
      return i;
    }
  }
  return 0;
}

std::string type_name(ValueType t) { return std::string(to_string(t)); }

void read_guard(const ReadContext& ctx, const XmlElement* e, Transition& t, const PetriNet& net,
                const std::string& text) {
  try {
    Guard g = Guard::parse(text);
    bool ok = true;
    const auto& ids = g.identifiers();
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const VariableDecl* decl = net.find_parameter(ids[i]);
      if (decl == nullptr) decl = net.find_fact(ids[i]);
      if (decl == nullptr) {
        std::vector<std::string> names = names_of(net.parameters);
        for (auto& f : names_of(net.facts)) names.push_back(std::move(f));
        ctx.error_at_value(e, "guard",
                           "unknown parameter '" + ids[i] + "' in guard of transition '" + t.id + "' (" +
                               declared_list(net) + ")" + did_you_mean(ids[i], names),
                           find_identifier(text, ids[i]));
        ok = false;
        continue;
      }
      const auto expected = g.expected_type(i);
      if (expected && *expected != decl->type) {
        ctx.error_at_value(e, "guard", "guard of transition '" + t.id + "' uses '" + ids[i] + "' as a " +
                                           type_name(*expected) + ", but it is declared " + type_name(decl->type),
                           find_identifier(text, ids[i]));
        ok = false;
      }
    }
    if (ok) t.guard = std::move(g);
  } catch (const GuardSyntaxError& err) {
    ctx.error_at_value(e, "guard", std::string("guard of transition '") + t.id + "' does not parse: " + err.what(),
                       static_cast<std::size_t>(std::max(1, err.column()) - 1));
  }
}

void read_binding_params(const ReadContext& ctx, const XmlElement* e, std::vector<BindingParam>& params,
                         const PetriNet& net, std::string_view owner) {
  std::set<std::string, std::less<>> seen;
  for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
    if (std::string_view(c->name()) != "param") {
      unknown_element(ctx, c, e->name(), "param");
      continue;
    }
    check_attributes(ctx, c, {"name", "value"});
    check_no_text(ctx, c);
    auto name = required(ctx, c, "name");
    auto value = optional_attr(c, "value");
    if (!value) {
      ctx.error(c, "missing attribute 'value' on <param>");
    }
    if (!name || !value) continue;
    if (!seen.emplace(*name).second) {
      ctx.error_at_value(c, "name", "duplicate parameter '" + std::string(*name) + "' for " + std::string(owner));
      continue;
    }
    if (!value->empty() && (*value)[0] == '$') {
      const std::string ref(value->substr(1));
      if (net.find_parameter(ref) == nullptr) {
        const auto close = closest_name(ref, names_of(net.parameters));
        ctx.error_at_value(c, "value",
                           "unknown parameter '$" + ref + "' passed to " + std::string(owner) +
                               " (declared parameters: " + join_names(net.parameters) + ")" +
                               (close ? "; did you mean '$" + *close + "'?" : std::string()));
        continue;
      }
    }
    params.push_back(BindingParam{std::string(*name), std::string(*value), ctx.loc.element(c)});
  }
}

}  // namespace

void ReadContext::error(const XmlElement* e, const std::string& message) const {
  diags.error(loc.element(e), message);
}
void ReadContext::error_at_attribute(const XmlElement* e, std::string_view attr,
                                     const std::string& message) const {
  diags.error(loc.attribute(e, attr), message);
}
void ReadContext::error_at_value(const XmlElement* e, std::string_view attr, const std::string& message,
                                 std::size_t decoded_offset) const {
  diags.error(loc.attribute_value(e, attr, decoded_offset), message);
}

namespace {

void unknown_attribute(const ReadContext& ctx, const XmlElement* e, std::string_view name,
                       std::span<const std::string_view> allowed) {
  std::string list;
  for (const auto& s : allowed) {
    if (!list.empty()) list += ", ";
    list += s;
  }
  ctx.error_at_attribute(e, name,
                         "unknown attribute '" + std::string(name) + "' on <" + std::string(e->name()) +
                             ">; expected one of: " + list);
}

}  // namespace

void check_attributes(const ReadContext& ctx, const XmlElement* e,
                      std::initializer_list<std::string_view> allowed) {
  for (const XmlAttribute& a : e->attributes()) {
    if (std::none_of(allowed.begin(), allowed.end(), [&](std::string_view n) { return same_name(n, a.name); })) {
      unknown_attribute(ctx, e, a.name, std::span<const std::string_view>(allowed.begin(), allowed.size()));
    }
  }
}

void read_attributes(const ReadContext& ctx, const XmlElement* e, std::span<const std::string_view> names,
                     std::span<const XmlAttribute*> found) {
  for (const XmlAttribute& a : e->attributes()) {
    std::size_t k = 0;
    while (k < names.size() && !same_name(names[k], a.name)) ++k;
    if (k < names.size()) {
      found[k] = &a;
    } else {
      unknown_attribute(ctx, e, a.name, names);
    }
  }
}

void unknown_element(const ReadContext& ctx, const XmlElement* e, std::string_view parent,
                     std::string_view expected) {
  ctx.error(e, "unknown element <" + std::string(e->name()) + "> in <" + std::string(parent) +
                   ">; expected " + (expected.empty() ? std::string("no child elements") : "one of: " + std::string(expected)));
}

void check_no_text(const ReadContext& ctx, const XmlElement* e) {
  if (!e->text().empty()) {
    ctx.error(e, "unexpected text in <" + std::string(e->name()) + ">; values are written as attributes");
  }
}

std::string trimmed_text(const XmlElement* e) { return std::string(e->text()); }

void report_missing(const ReadContext& ctx, const XmlElement* e, std::string_view attr, bool present) {
  if (!present) {
    ctx.error(e, "missing attribute '" + std::string(attr) + "' on <" + std::string(e->name()) + ">");
  } else {
    ctx.error_at_attribute(e, attr, "empty attribute '" + std::string(attr) + "' on <" + std::string(e->name()) + ">");
  }
}

std::optional<Tokens> parse_count(const ReadContext& ctx, const XmlElement* e, std::string_view attr,
                                  std::string_view text, Tokens minimum, std::string_view what) {
  std::uint64_t v = 0;
  const bool digits = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  const bool ok = digits && ec == std::errc() && ptr == text.data() + text.size() &&
                  v <= std::numeric_limits<Tokens>::max() && v >= minimum;
  if (!ok) {
    const std::string expected = minimum == 0 ? "a whole number >= 0" : "a whole number >= " + std::to_string(minimum);
    const bool non_positive = minimum > 0 && (text == "0" || (!text.empty() && text[0] == '-'));
    // Located only now: a valid count costs no line lookup.
    ctx.diags.error(attr.empty() ? ctx.loc.element(e) : ctx.loc.attribute_value(e, attr),
                    std::string(non_positive ? "non-positive " : "bad ") + std::string(what) + " '" +
                               std::string(text) + "': expected " + expected);
    return std::nullopt;
  }
  return static_cast<Tokens>(v);
}

std::optional<Duration> parse_delay_text(std::string_view text, std::string& error) {
  std::size_t i = 0;
  while (i < text.size() && ((text[i] >= '0' && text[i] <= '9') || text[i] == '.' || text[i] == '-' || text[i] == '+')) ++i;
  const std::string_view number = text.substr(0, i);
  std::string_view unit = text.substr(i);
  while (!unit.empty() && unit.front() == ' ') unit.remove_prefix(1);
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(number.data(), number.data() + number.size(), v);
  if (number.empty() || ec != std::errc() || ptr != number.data() + number.size() || !std::isfinite(v)) {
    error = "bad delay '" + std::string(text) + "': expected a number and a unit, e.g. '2s' or '500ms'";
    return std::nullopt;
  }
  if (v < 0.0 || number.front() == '-') {
    error = "negative delay '" + std::string(text) + "': a delay is a duration >= 0";
    return std::nullopt;
  }
  double scale = 0.0;
  if (unit == "ns") scale = 1e-9;
  else if (unit == "us") scale = 1e-6;
  else if (unit == "ms") scale = 1e-3;
  else if (unit == "s") scale = 1.0;
  else if (unit == "min") scale = 60.0;
  else if (unit == "h") scale = 3600.0;
  if (scale == 0.0) {
    error = unit.empty() ? "delay '" + std::string(text) + "' has no unit: write e.g. '" + std::string(number) +
                               "s' or '" + std::string(number) + "ms' (units: ns, us, ms, s, min, h)"
                         : "unknown unit '" + std::string(unit) + "' in delay '" + std::string(text) +
                               "': expected ns, us, ms, s, min or h";
    return std::nullopt;
  }
  const double seconds = v * scale;
  if (seconds > 1e9) {
    error = "delay '" + std::string(text) + "' is too long (more than 1e9 s)";
    return std::nullopt;
  }
  return from_seconds(seconds);
}

bool is_valid_name(std::string_view name) noexcept {
  if (name.empty()) return false;
  const auto letter = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  if (!letter(name[0])) return false;
  return std::all_of(name.begin(), name.end(), [&](char c) {
    return letter(c) || (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '/';
  });
}

void read_declaration(const ReadContext& ctx, const XmlElement* e, PetriNet& net, bool fact) {
  check_attributes(ctx, e, {"name", "type", "default", "description"});
  check_no_text(ctx, e);
  for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
    unknown_element(ctx, c, e->name(), "");
  }
  const auto name = required(ctx, e, "name");
  const auto type_text = required(ctx, e, "type");
  if (name && !is_valid_name(*name)) {
    ctx.error_at_value(e, "name", "bad name '" + std::string(*name) + "': expected a letter or '_' then letters, digits, '_', '.', '-', '/'");
    return;
  }
  std::optional<ValueType> type;
  if (type_text) {
    type = parse_value_type(*type_text);
    if (!type) ctx.error_at_value(e, "type", "unknown type '" + std::string(*type_text) + "': expected boolean, number or string");
  }
  if (!name || !type) return;
  if (net.find_parameter(*name) != nullptr || net.find_fact(*name) != nullptr) {
    ctx.error_at_value(e, "name", "duplicate declaration of '" + std::string(*name) + "'");
    return;
  }
  VariableDecl d;
  d.name = *name;
  d.type = *type;
  d.description = optional_attr(e, "description").value_or("");
  d.where = ctx.loc.element(e);
  if (const auto def = optional_attr(e, "default")) {
    d.default_value = parse_value(*type, *def);
    if (!d.default_value) {
      ctx.error_at_value(e, "default", "default '" + std::string(*def) + "' of '" + std::string(*name) + "' is not a " + type_name(*type));
      return;
    }
  }
  (fact ? net.facts : net.parameters).push_back(std::move(d));
}

void read_place_details(const ReadContext& ctx, const XmlElement* e, Place& place, const PetriNet& net,
                        bool allow_tokens_and_name) {
  // One pass over the attributes. PNML's <toolspecific> place carries only the last four.
  static constexpr std::array<std::string_view, 7> kNames{"id",       "name",    "tokens", "description",
                                                          "capacity", "outcome", "message"};
  enum { kId, kName, kTokens, kDescription, kCapacity, kOutcome, kMessage };
  AttributeValues<kNames.size()> attr;
  const std::size_t first = allow_tokens_and_name ? kId : kDescription;
  read_attributes(ctx, e, std::span(kNames).subspan(first), std::span(attr.found).subspan(first));
  if (const auto& n = attr[kName]; n && !n->empty()) place.name = *n;  // else the id, as add_place() sets
  if (const auto& t = attr[kTokens]) {
    if (auto v = parse_count(ctx, e, "tokens", *t, 0, "token count")) place.initial_tokens = *v;
  }
  check_no_text(ctx, e);
  if (const auto& d = attr[kDescription]) place.description = *d;
  if (const auto& c = attr[kCapacity]) {
    if (auto v = parse_count(ctx, e, "capacity", *c, 1, "capacity")) {
      place.capacity = *v;
      if (place.initial_tokens > *v) {
        ctx.error_at_value(e, "capacity", "place '" + place.id + "' starts with " + std::to_string(place.initial_tokens) +
                                              " tokens, more than its capacity " + std::to_string(*v));
        place.capacity.reset();
      }
    }
  }
  if (const auto& o = attr[kOutcome]) {
    if (*o == "success") place.outcome = Outcome::success;
    else if (*o == "fault") place.outcome = Outcome::fault;
    else if (*o == "none") place.outcome = Outcome::none;
    else ctx.error_at_value(e, "outcome", "unknown outcome '" + std::string(*o) + "': expected success or fault");
  }
  if (const auto& m = attr[kMessage]) {
    if (place.outcome != Outcome::fault) {
      ctx.error_at_attribute(e, "message", "a message belongs to a fault place (outcome=\"fault\") only");
    } else {
      place.fault_message = *m;
    }
  }
  for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
    const std::string_view kind = c->name();
    if (kind != "behavior" && kind != "process") {
      unknown_element(ctx, c, e->name(), "behavior, process");
      continue;
    }
    check_attributes(ctx, c, {"name"});
    check_no_text(ctx, c);
    const auto name = required(ctx, c, "name");
    if (!name) continue;
    if (!is_valid_name(*name)) {
      ctx.error_at_value(c, "name", "bad " + std::string(kind) + " name '" + std::string(*name) + "'");
      continue;
    }
    if (place.behavior || place.process) {
      ctx.error(c, "place '" + place.id + "' already binds a " + (place.behavior ? "behavior" : "process") +
                       "; a place binds at most one behavior or process");
      continue;
    }
    const bool behavior = kind == "behavior";
    const auto& known = behavior ? ctx.options.is_known_behavior : ctx.options.is_known_process;
    if (known && !known(*name)) {
      const auto& names = behavior ? ctx.options.behavior_names : ctx.options.process_names;
      ctx.error_at_value(
          c, "name",
          "unknown " + std::string(kind) + " '" + std::string(*name) + "'" + did_you_mean(*name, names));
    }
    std::vector<BindingParam> params;
    read_binding_params(ctx, c, params, net, std::string(kind) + " " + std::string(*name));
    if (behavior) place.behavior = BehaviorBinding{std::string(*name), std::move(params)};
    else place.process = ProcessRef{std::string(*name), std::move(params)};
  }
}

namespace {

// An event "SOURCE.KIND" whose source is a behavior or a process bound in this net must be one
// that source posts (BhX.done / BhX.failed; PLACE.success / PLACE.fault for a place running a
// process); a source that is not bound here but is close to one that is, and is written like one
// (Bh.../Pr..., or an event .success/.fault), is a typo. Module events (localizer.lost,
// board.battery_low) are left alone: the net cannot know them.
void check_event_source(const ReadContext& ctx, const XmlElement* e, const std::string& event,
                        const PetriNet& net) {
  const auto dot = event.rfind('.');
  if (dot == std::string::npos || dot == 0) return;
  const std::string source = event.substr(0, dot);
  const std::string kind = event.substr(dot + 1);
  std::vector<std::string> sources;
  std::vector<std::string> known_events;
  const std::vector<std::string>* kinds_of_source = nullptr;
  static const std::vector<std::string> behavior_kinds{"done", "failed"};
  static const std::vector<std::string> process_kinds{"success", "fault"};
  for (const Place& p : net.places()) {
    const std::string* name = p.behavior ? &p.behavior->behavior : (p.process ? &p.id : nullptr);
    if (name == nullptr) continue;
    const auto& kinds = p.behavior ? behavior_kinds : process_kinds;
    if (*name == source) kinds_of_source = &kinds;
    sources.push_back(*name);
    for (const auto& k : kinds) known_events.push_back(*name + "." + k);
  }
  if (kinds_of_source != nullptr) {
    if (std::find(kinds_of_source->begin(), kinds_of_source->end(), kind) != kinds_of_source->end()) return;
    std::vector<std::string> own;
    for (const auto& k : *kinds_of_source) own.push_back(source + "." + k);
    ctx.error_at_value(e, "event",
                       "unknown event '" + event + "': '" + source + "' posts " + own[0] + " and " + own[1] +
                           did_you_mean(event, own));
    return;
  }
  // Behaviors and processes are named Bh... and Pr...; a process's events are its place's
  // (P1.success). Other sources are modules.
  const auto prefixed = [&](char a, char b) {
    return source.size() > 2 && (source[0] == a || source[0] == a - 'a' + 'A') &&
           (source[1] == b || source[1] == b - 'a' + 'A');
  };
  const bool looks_bound = prefixed('b', 'h') || prefixed('p', 'r') || kind == "success" || kind == "fault";
  if (!looks_bound) return;
  if (const auto close = closest_name(source, sources)) {
    const auto event_close = closest_name(*close + "." + kind, known_events);
    ctx.error_at_value(e, "event",
                       "unknown event '" + event + "': no place of net '" + net.id + "' binds '" + source +
                           "'; did you mean '" + (event_close ? *event_close : *close + "." + kind) + "'?");
  }
}

}  // namespace

void read_transition_details(const ReadContext& ctx, const XmlElement* e, Transition& t, const PetriNet& net,
                             bool allow_name) {
  // One pass over the attributes. PNML's <toolspecific> transition carries only the last five.
  static constexpr std::array<std::string_view, 7> kNames{"id", "name", "description", "event", "guard", "delay",
                                                          "priority"};
  enum { kId, kName, kDescription, kEvent, kGuard, kDelay, kPriority };
  AttributeValues<kNames.size()> attr;
  const std::size_t first = allow_name ? kId : kDescription;
  read_attributes(ctx, e, std::span(kNames).subspan(first), std::span(attr.found).subspan(first));
  if (const auto& n = attr[kName]; n && !n->empty()) t.name = *n;  // else the id, as add_transition() sets
  check_no_text(ctx, e);
  for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
    unknown_element(ctx, c, e->name(), "");
  }
  if (const auto& d = attr[kDescription]) t.description = *d;
  if (const auto& ev = attr[kEvent]) {
    if (!is_valid_name(*ev)) {
      ctx.error_at_value(e, "event", "bad event name '" + std::string(*ev) +
                                         "': expected a letter or '_' then letters, digits, '_', '.', '-', '/'");
    } else {
      t.event = *ev;
      check_event_source(ctx, e, t.event, net);
    }
  }
  if (const auto& g = attr[kGuard]) read_guard(ctx, e, t, net, std::string(*g));
  if (const auto& d = attr[kDelay]) {
    std::string err;
    if (auto v = parse_delay_text(*d, err)) t.delay = *v;
    else ctx.error_at_value(e, "delay", err + " (transition '" + t.id + "')");
  }
  if (const auto& p = attr[kPriority]) {
    int v = 0;
    const auto [ptr, ec] = std::from_chars(p->data(), p->data() + p->size(), v);
    if (p->empty() || ec != std::errc() || ptr != p->data() + p->size()) {
      ctx.error_at_value(e, "priority", "bad priority '" + std::string(*p) + "': expected an integer");
    } else {
      t.priority = v;
    }
  }
}

std::optional<ArcKind> parse_arc_kind(std::string_view text) noexcept {
  if (text == "normal") return ArcKind::normal;
  if (text == "read") return ArcKind::read;
  if (text == "inhibitor") return ArcKind::inhibitor;
  return std::nullopt;
}

std::string_view to_string(ArcKind kind) noexcept {
  switch (kind) {
    case ArcKind::normal: return "normal";
    case ArcKind::read: return "read";
    case ArcKind::inhibitor: return "inhibitor";
  }
  return "normal";
}

bool add_checked_arc(const ReadContext& ctx, const XmlElement* e, PetriNet& net, std::string_view from,
                     std::string_view to, Tokens weight, ArcKind kind) {
  // The common case costs the net's own look-ups only; the diagnosis below runs after a refusal.
  try {
    net.add_arc(from, to, weight, kind, ctx.loc.element(e));
    return true;
  } catch (const std::invalid_argument&) {
  }
  const auto fp = net.find_place(from);
  const auto ft = net.find_transition(from);
  const auto tp = net.find_place(to);
  const auto tt = net.find_transition(to);
  bool ok = true;
  std::vector<std::string> nodes;
  if ((!fp && !ft) || (!tp && !tt)) {
    for (const Place& p : net.places()) nodes.push_back(p.id);
    for (const Transition& t : net.transitions()) nodes.push_back(t.id);
  }
  if (!fp && !ft) {
    ctx.error_at_value(e, "source",
                       "arc from unknown node '" + std::string(from) + "'" + did_you_mean(from, nodes));
    ok = false;
  }
  if (!tp && !tt) {
    ctx.error_at_value(e, "target",
                       "arc to unknown node '" + std::string(to) + "'" + did_you_mean(to, nodes));
    ok = false;
  }
  if (!ok) return false;
  if (fp && tp) {
    ctx.error(e, "arc between two places '" + std::string(from) + "' and '" + std::string(to) +
                     "': an arc connects a place and a transition");
    return false;
  }
  if (ft && tt) {
    ctx.error(e, "arc between two transitions '" + std::string(from) + "' and '" + std::string(to) +
                     "': an arc connects a place and a transition");
    return false;
  }
  if (ft && kind != ArcKind::normal) {
    ctx.error(e, "a " + std::string(to_string(kind)) + " arc goes from a place to a transition, not from transition '" +
                     std::string(from) + "' to place '" + std::string(to) + "'");
    return false;
  }
  ctx.error(e, "arc '" + std::string(from) + "' -> '" + std::string(to) + "' is refused");  // unreachable: add_arc refuses only the above
  return false;
}

}  // namespace tripodal::detail
