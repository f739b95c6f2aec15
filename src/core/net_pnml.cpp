// PNML import and export: ISO/IEC 15909-2 (2009) place/transition nets, and the older JARP
// dialect (no <page>, labels in <value>). tripodal's extensions travel in
// <toolspecific tool="tripodal" version="1"> using the native format's attribute syntax; what a
// P/T net cannot express is refused with a located error, never read as something else.
#include <map>
#include <set>
#include <unordered_map>

#include "net_formats.hpp"

namespace tripodal::detail {

namespace {

constexpr std::string_view kTool = "tripodal";
constexpr std::string_view kIsoPtNet = "http://www.pnml.org/version-2009/grammar/ptnet";

bool is_pt_net_type(std::string_view type) {
  return type == kIsoPtNet || type == "http://www.pnml.org/version-2009/grammar/ptnet.pntd" || type == "PTNet" ||
         type == "P/T net" || type == "http://www.informatik.hu-berlin.de/top/pntd/ptNetb";
}

// Labels that only colored / high-level / timed nets have: refused rather than ignored.
bool is_foreign_annotation(std::string_view name) {
  return name == "type" || name == "hlinitialMarking" || name == "hlinscription" || name == "condition" ||
         name == "declaration" || name == "declarations" || name == "structure";
}

struct RawArc {
  const XmlElement* e = nullptr;
  std::string source;
  std::string target;
  Tokens weight = 1;
  ArcKind kind = ArcKind::normal;
  bool tripodal_read = false;  ///< half of a read arc exported as a self-loop
  bool consumed = false;
};

class PnmlReader {
 public:
  PnmlReader(const ReadContext& ctx, PetriNet& net) : ctx_(ctx), net_(net) {}

  void read_net(const XmlElement* e) {
    check_attributes(ctx_, e, {"id", "type"});
    if (auto id = required(ctx_, e, "id")) net_.id = *id;
    const auto type = optional_attr(e, "type");
    if (!type) {
      ctx_.error(e, "missing attribute 'type' on <net>: expected a place/transition net type such as '" +
                        std::string(kIsoPtNet) + "'");
    } else if (!is_pt_net_type(*type)) {
      ctx_.error_at_value(e, "type", "net type '" + std::string(*type) +
                                         "' is not a place/transition net; tripodal reads P/T nets only (" +
                                         std::string(kIsoPtNet) + " or JARP's PTNet)");
      return;
    }
    // The net's tripodal extension declares the parameters guards refer to: read it first.
    for (const auto* c = e->first_child("toolspecific"); c != nullptr; c = c->next_sibling("toolspecific")) {
      if (const auto* ext = tripodal_extension(c, "net")) read_net_extension(ext);
    }
    read_container(e, true);
    if (net_.name.empty()) net_.name = net_.id;  // as in the native format
    resolve_arcs();
  }

 private:
  // The single child element of a tripodal toolspecific block, when it is one and its version is
  // supported; nullptr for other tools (which are allowed to say anything).
  const XmlElement* tripodal_extension(const XmlElement* ts, std::string_view expected) {
    check_attributes(ctx_, ts, {"tool", "version"});
    if (optional_attr(ts, "tool").value_or("") != kTool) return nullptr;
    const auto version = optional_attr(ts, "version");
    if (!version) {
      ctx_.error(ts, "missing attribute 'version' on <toolspecific tool=\"tripodal\">");
      return nullptr;
    }
    if (*version != kFormatVersion) {
      ctx_.error_at_value(ts, "version", "tripodal extension version '" + std::string(*version) +
                                             "' is not supported: this build reads version " + std::string(kFormatVersion));
      return nullptr;
    }
    const XmlElement* found = nullptr;
    for (const auto* c = ts->first_child(); c != nullptr; c = c->next_sibling()) {
      if (found != nullptr || std::string_view(c->name()) != expected) {
        unknown_element(ctx_, c, "toolspecific", expected);
        continue;
      }
      found = c;
    }
    if (found == nullptr) ctx_.error(ts, "empty tripodal extension: expected <" + std::string(expected) + ">");
    return found;
  }

  void read_net_extension(const XmlElement* e) {
    check_attributes(ctx_, e, {"level", "description"});
    check_no_text(ctx_, e);
    net_.description = optional_attr(e, "description").value_or("");
    if (auto level = optional_attr(e, "level")) {
      if (*level == "high") net_.level = NetLevel::high;
      else if (*level == "low") net_.level = NetLevel::low;
      else ctx_.error_at_value(e, "level", "unknown level '" + std::string(*level) + "': expected low or high");
    }
    for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view n = c->name();
      if (n == "parameter" || n == "fact") read_declaration(ctx_, c, net_, n == "fact");
      else unknown_element(ctx_, c, "net", "parameter, fact");
    }
  }

  // A label's value: <text> (ISO) or <value> (JARP).
  std::optional<std::pair<std::string, const XmlElement*>> label_value(const XmlElement* label) {
    const XmlElement* value = nullptr;
    for (const auto* c = label->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view n = c->name();
      if (n == "text" || n == "value") {
        if (value != nullptr) ctx_.error(c, "label <" + std::string(label->name()) + "> has more than one value");
        value = c;
      } else if (n != "graphics" && n != "toolspecific") {
        unknown_element(ctx_, c, label->name(), "text, value, graphics, toolspecific");
      }
    }
    if (value == nullptr) {
      ctx_.error(label, "label <" + std::string(label->name()) + "> has no <text> (or JARP <value>)");
      return std::nullopt;
    }
    return std::make_pair(trimmed_text(value), value);
  }

  std::optional<std::string> claim_id(const XmlElement* e) {
    auto id = required(ctx_, e, "id");
    if (!id) return std::nullopt;
    const auto [it, inserted] = ids_.emplace(*id, ctx_.loc.element(e));
    if (!inserted) {
      ctx_.error_at_value(e, "id", "duplicate id '" + std::string(*id) + "' (first defined at " + it->second.str() + ")");
      return std::nullopt;
    }
    return std::string(*id);
  }

  void read_container(const XmlElement* e, bool is_net) {
    for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view n = c->name();
      if (n == "place") read_place(c);
      else if (n == "transition") read_transition(c);
      else if (n == "arc") read_arc(c);
      else if (n == "page") {
        check_attributes(ctx_, c, {"id"});
        claim_id(c);
        read_container(c, false);
      } else if (n == "name") {
        if (is_net) {
          if (auto v = label_value(c)) net_.name = v->first;
        } else {
          label_value(c);
        }
      } else if (n == "toolspecific") {
        if (!is_net) tripodal_extension(c, "");  // only validates: a page carries no tripodal data
      } else if (n == "graphics") {
      } else if (n == "referencePlace" || n == "referenceTransition") {
        ctx_.error(c, "<" + std::string(n) + "> is not supported: flatten reference nodes before importing");
      } else if (is_foreign_annotation(n)) {
        ctx_.error(c, "<" + std::string(n) + "> belongs to colored/high-level nets, which tripodal cannot represent");
      } else {
        unknown_element(ctx_, c, e->name(), "page, place, transition, arc, name, graphics, toolspecific");
      }
    }
  }

  void read_place(const XmlElement* e) {
    check_attributes(ctx_, e, {"id"});
    Place p;
    const auto id = claim_id(e);
    p.id = id.value_or("");
    p.where = ctx_.loc.element(e);
    const XmlElement* ext = nullptr;
    for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view n = c->name();
      if (n == "name") {
        if (auto v = label_value(c)) p.name = v->first;
      } else if (n == "initialMarking") {
        if (auto v = label_value(c)) {
          if (auto tokens = parse_count(ctx_, v->second, "", v->first, 0, "token count")) {
            p.initial_tokens = *tokens;
          }
        }
      } else if (n == "toolspecific") {
        if (const auto* x = tripodal_extension(c, "place")) ext = x;
      } else if (n == "graphics") {
      } else if (is_foreign_annotation(n)) {
        ctx_.error(c, "place '" + p.id + "' has <" + std::string(n) +
                          ">: colored/high-level places cannot be represented as a P/T net");
      } else {
        ctx_.error(c, "unknown label <" + std::string(n) + "> on place '" + p.id +
                          "': tripodal cannot represent it (expected name, initialMarking, graphics, toolspecific)");
      }
    }
    if (ext != nullptr) read_place_details(ctx_, ext, p, net_, false);
    if (id) net_.add_place(std::move(p));
  }

  void read_transition(const XmlElement* e) {
    check_attributes(ctx_, e, {"id"});
    Transition t;
    const auto id = claim_id(e);
    t.id = id.value_or("");
    t.where = ctx_.loc.element(e);
    for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view n = c->name();
      if (n == "name") {
        if (auto v = label_value(c)) t.name = v->first;
      } else if (n == "toolspecific") {
        if (const auto* x = tripodal_extension(c, "transition")) read_transition_details(ctx_, x, t, net_, false);
      } else if (n == "graphics") {
      } else if (is_foreign_annotation(n)) {
        ctx_.error(c, "transition '" + t.id + "' has <" + std::string(n) +
                          ">: colored/high-level transitions cannot be represented as a P/T net");
      } else {
        ctx_.error(c, "unknown label <" + std::string(n) + "> on transition '" + t.id +
                          "': tripodal cannot represent it (expected name, graphics, toolspecific)");
      }
    }
    if (id) net_.add_transition(std::move(t));
  }

  // "normal" / "inhibitor" / "read" / "test"; nullopt (after an error) for anything else.
  std::optional<ArcKind> arc_type(const XmlElement* where, std::string_view attr, std::string_view text) {
    if (text == "normal") return ArcKind::normal;
    if (text == "inhibitor") return ArcKind::inhibitor;
    if (text == "read" || text == "test") return ArcKind::read;
    const std::string message = "unknown arc type '" + std::string(text) +
                                "': tripodal represents normal, inhibitor and read (test) arcs only";
    if (attr.empty()) ctx_.error(where, message);
    else ctx_.error_at_value(where, attr, message);
    return std::nullopt;
  }

  void read_arc(const XmlElement* e) {
    check_attributes(ctx_, e, {"id", "source", "target", "type"});
    RawArc arc;
    arc.e = e;
    bool ok = claim_id(e).has_value();
    const auto source = required(ctx_, e, "source");
    const auto target = required(ctx_, e, "target");
    ok = ok && source && target;
    if (auto type = optional_attr(e, "type")) {
      const auto kind = arc_type(e, "type", *type);
      ok = ok && kind;
      if (kind) arc.kind = *kind;
    }
    for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view n = c->name();
      if (n == "inscription") {
        if (auto v = label_value(c)) {
          const auto w = parse_count(ctx_, v->second, "", v->first, 1, "weight");
          ok = ok && w;
          if (w) arc.weight = *w;
        } else {
          ok = false;
        }
      } else if (n == "type") {
        // <type><text>inhibitor</text></type> and PIPE's <type value="inhibitor"/>.
        std::optional<std::string> text;
        if (const auto value = optional_attr(c, "value")) text = std::string(*value);
        if (!text) {
          if (auto v = label_value(c)) text = v->first;
        }
        const auto kind = text ? arc_type(c, "", *text) : std::nullopt;
        ok = ok && kind;
        if (kind) arc.kind = *kind;
      } else if (n == "toolspecific") {
        if (const auto* x = tripodal_extension(c, "arc")) {
          check_attributes(ctx_, x, {"kind"});
          const std::string_view kind = optional_attr(x, "kind").value_or("");
          if (kind == "read") arc.tripodal_read = true;
          else ctx_.error_at_value(x, "kind", "unknown tripodal arc kind '" + std::string(kind) + "': expected read");
        }
      } else if (n == "graphics") {
      } else if (is_foreign_annotation(n)) {
        ctx_.error(c, "arc has <" + std::string(n) + ">: colored/high-level arcs cannot be represented as a P/T net");
        ok = false;
      } else {
        ctx_.error(c, "unknown label <" + std::string(n) +
                          "> on arc: tripodal cannot represent it (expected inscription, type, graphics, toolspecific)");
        ok = false;
      }
    }
    if (!ok) return;
    arc.source = *source;
    arc.target = *target;
    arcs_.push_back(std::move(arc));
  }

  // Arcs may name nodes declared later (or on another page): connected after everything is read.
  void resolve_arcs() {
    // The transition -> place halves of read arcs, by (source, target).
    std::map<std::pair<std::string, std::string>, std::vector<std::size_t>> returns;
    for (std::size_t i = 0; i < arcs_.size(); ++i) {
      const RawArc& b = arcs_[i];
      if (b.tripodal_read && b.kind == ArcKind::normal) returns[{b.source, b.target}].push_back(i);
    }
    for (std::size_t i = 0; i < arcs_.size(); ++i) {
      RawArc& a = arcs_[i];
      if (a.consumed) continue;
      if (!a.tripodal_read) {
        add_checked_arc(ctx_, a.e, net_, a.source, a.target, a.weight, a.kind);
        continue;
      }
      // A read arc travels as the self-loop p -> t -> p (its meaning for every other P/T tool);
      // both halves carry the tripodal mark and fold back into one read arc.
      if (a.kind != ArcKind::normal) {
        ctx_.error(a.e, "tripodal read arc '" + a.source + "' -> '" + a.target + "' must not also be an inhibitor or read arc");
        continue;
      }
      if (!net_.find_place(a.source)) {
        // Unknown source: reported here. A transition source: the return half, matched below.
        if (!net_.find_transition(a.source)) add_checked_arc(ctx_, a.e, net_, a.source, a.target, a.weight, a.kind);
        continue;
      }
      RawArc* back = nullptr;
      const auto candidates = returns.find({a.target, a.source});
      if (candidates != returns.end()) {
        for (const std::size_t k : candidates->second) {
          RawArc& b = arcs_[k];
          if (!b.consumed && b.weight == a.weight) {
            back = &b;
            break;
          }
        }
      }
      if (back == nullptr) {
        ctx_.error(a.e, "tripodal read arc '" + a.source + "' -> '" + a.target + "' has no matching arc '" + a.target +
                            "' -> '" + a.source + "' of weight " + std::to_string(a.weight));
        continue;
      }
      back->consumed = true;
      a.consumed = true;
      add_checked_arc(ctx_, a.e, net_, a.source, a.target, a.weight, ArcKind::read);
    }
    for (const auto& a : arcs_) {
      if (a.tripodal_read && !a.consumed && net_.find_transition(a.source) && a.kind == ArcKind::normal) {
        ctx_.error(a.e, "tripodal read arc '" + a.source + "' -> '" + a.target + "' has no matching arc '" + a.target +
                            "' -> '" + a.source + "'");
      }
    }
  }

  const ReadContext& ctx_;
  PetriNet& net_;
  std::unordered_map<std::string, SourceLocation> ids_;  // hashed: one look-up per element of a large net
  std::vector<RawArc> arcs_;
};

std::string attr(std::string_view name, std::string_view value) {
  return " " + std::string(name) + "=\"" + xml_escape(value) + "\"";
}

std::string label(const std::string& indent, std::string_view name, const std::string& text) {
  return indent + "<" + std::string(name) + "><text>" + xml_escape(text) + "</text></" + std::string(name) + ">\n";
}

std::string toolspecific(const std::string& indent, const std::string& body) {
  return indent + "<toolspecific tool=\"tripodal\" version=\"" + std::string(kFormatVersion) + "\">\n" + body + indent +
         "</toolspecific>\n";
}

}  // namespace

PetriNet read_pnml(const XmlElement* root, const ReadContext& ctx) {
  PetriNet net;
  net.where = ctx.loc.element(root);
  check_attributes(ctx, root, {"xmlns"});
  const XmlElement* net_element = nullptr;
  for (const auto* c = root->first_child(); c != nullptr; c = c->next_sibling()) {
    if (std::string_view(c->name()) != "net") {
      unknown_element(ctx, c, "pnml", "net");
    } else if (net_element != nullptr) {
      ctx.error(c, "a second <net>: tripodal reads one net per file");
    } else {
      net_element = c;
    }
  }
  if (net_element == nullptr) {
    ctx.error(root, "no <net> in the PNML document");
    return net;
  }
  net.where = ctx.loc.element(net_element);
  PnmlReader(ctx, net).read_net(net_element);
  return net;
}

std::string write_pnml(const PetriNet& net) {
  std::set<std::string, std::less<>> used;
  for (const auto& p : net.places()) used.insert(p.id);
  for (const auto& t : net.transitions()) used.insert(t.id);
  const auto fresh = [&](std::string base) {
    while (used.count(base) != 0) base += '_';
    used.insert(base);
    return base;
  };
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                    "<pnml xmlns=\"http://www.pnml.org/version-2009/grammar/pnml\">\n";
  out += "  <net" + attr("id", net.id.empty() ? std::string("net") : net.id) + attr("type", kIsoPtNet) + ">\n";
  if (!net.name.empty()) out += label("    ", "name", net.name);
  {
    std::string body = "      <net" + attr("level", net.level == NetLevel::high ? "high" : "low");
    if (!net.description.empty()) body += attr("description", net.description);
    const std::string decls = declaration_elements(net, "        ");
    body += decls.empty() ? "/>\n" : ">\n" + decls + "      </net>\n";
    out += toolspecific("    ", body);
  }
  out += "    <page" + attr("id", fresh("page0")) + ">\n";
  const std::string in = "      ";
  for (const auto& p : net.places()) {
    out += in + "<place" + attr("id", p.id) + ">\n";
    out += label(in + "  ", "name", p.name);
    if (p.initial_tokens != 0) out += label(in + "  ", "initialMarking", std::to_string(p.initial_tokens));
    const std::string details = place_detail_attributes(p);
    const std::string bindings = binding_elements(p, in + "      ");
    if (!details.empty() || !bindings.empty()) {
      out += toolspecific(in + "  ", in + "    <place" + details +
                                         (bindings.empty() ? "/>\n" : ">\n" + bindings + in + "    </place>\n"));
    }
    out += in + "</place>\n";
  }
  for (const auto& t : net.transitions()) {
    out += in + "<transition" + attr("id", t.id) + ">\n";
    out += label(in + "  ", "name", t.name);
    const std::string details = transition_detail_attributes(t);
    if (!details.empty()) out += toolspecific(in + "  ", in + "    <transition" + details + "/>\n");
    out += in + "</transition>\n";
  }
  const auto arc = [&](const std::string& from, const std::string& to, Tokens weight, ArcKind kind) {
    out += in + "<arc" + attr("id", fresh("a" + std::to_string(used.size()))) + attr("source", from) + attr("target", to);
    if (kind == ArcKind::inhibitor) out += attr("type", "inhibitor");
    const bool plain = weight == 1 && kind != ArcKind::read;
    if (plain) {
      out += "/>\n";
      return;
    }
    out += ">\n";
    if (weight != 1) out += label(in + "  ", "inscription", std::to_string(weight));
    if (kind == ArcKind::read) out += toolspecific(in + "  ", in + "    <arc kind=\"read\"/>\n");
    out += in + "</arc>\n";
  };
  for (const auto& t : net.transitions()) {
    for (const auto& a : t.inputs) arc(net.place(a.place).id, t.id, a.weight, ArcKind::normal);
    for (const auto& a : t.reads) {
      arc(net.place(a.place).id, t.id, a.weight, ArcKind::read);
      arc(t.id, net.place(a.place).id, a.weight, ArcKind::read);
    }
    for (const auto& a : t.inhibitors) arc(net.place(a.place).id, t.id, a.weight, ArcKind::inhibitor);
    for (const auto& a : t.outputs) arc(t.id, net.place(a.place).id, a.weight, ArcKind::normal);
  }
  out += "    </page>\n  </net>\n</pnml>\n";
  return out;
}

}  // namespace tripodal::detail
