// PNML import and export: ISO/IEC 15909-2 (2009) place/transition nets, and the older JARP
// dialect (no <page>, labels in <value>). tripodal's extensions travel in
// <toolspecific tool="tripodal" version="1"> using the native format's attribute syntax; what a
// P/T net cannot express is refused with a located error, never read as something else.
#include <functional>
#include <set>
#include <unordered_map>

#include "net_formats.hpp"

namespace tripodal::detail {

namespace {

constexpr std::string_view kTool = "tripodal";
constexpr std::size_t kPrefetchAhead = 8;  // arcs ahead whose ends are prefetched
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

// PNML ids (pages, places, transitions, arcs) share one name space. An open-addressing table
// of (hash, element) pairs, 8 bytes a slot, at most half full: one hash and usually one probe per
// id, no allocation per id; the id itself is compared (read back from the element) only when the
// 32-bit hashes agree. (A std::unordered_map<std::string, SourceLocation> made a node, a string
// and a location per id: a third of a 10,000-place PNML load.)
class IdTable {
 public:
  /// `root`: the document's first element (the elements lie in one array after it).
  explicit IdTable(const XmlElement* root) : root_(root) {}
  void reserve(std::size_t ids) {
    while ((ids + 1) * 2 > slots_.size()) grow();
  }
  /// The element that first claimed `id`; nullptr when `id` is new (it is then `e`'s).
  const XmlElement* claim(std::string_view id, const XmlElement* e) {
    if ((size_ + 1) * 2 > slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    const auto hash = static_cast<std::uint32_t>(std::hash<std::string_view>{}(id));
    for (std::size_t i = hash & mask;; i = (i + 1) & mask) {
      Slot& slot = slots_[i];
      if (slot.element == 0) {
        slot = Slot{hash, static_cast<std::uint32_t>(e - root_) + 1};
        ++size_;
        return nullptr;
      }
      if (slot.hash != hash) continue;
      const XmlElement* first = root_ + (slot.element - 1);
      if (first->attribute("id") == id) return first;
    }
  }

 private:
  struct Slot {
    std::uint32_t hash = 0;
    std::uint32_t element = 0;  ///< 0: empty; else the element's index + 1
  };
  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.empty() ? 1024 : old.size() * 2, Slot{});
    const std::size_t mask = slots_.size() - 1;
    for (const Slot& slot : old) {
      if (slot.element == 0) continue;
      std::size_t i = slot.hash & mask;
      while (slots_[i].element != 0) i = (i + 1) & mask;
      slots_[i] = slot;
    }
  }
  const XmlElement* root_;
  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

// A (source, target) pair of ids, for the halves of read arcs.
struct IdPairHash {
  std::size_t operator()(const std::pair<std::string_view, std::string_view>& p) const noexcept {
    const std::size_t h = std::hash<std::string_view>{}(p.first);
    return h ^ (std::hash<std::string_view>{}(p.second) + 0x9E3779B97F4A7C15ULL + (h << 6) + (h >> 2));
  }
};

// The places, transitions and other elements with ids (arcs, pages) under a net or page, nested
// pages included: the net and the id table reserve room for them once.
struct NodeCounts {
  std::size_t places = 0;
  std::size_t transitions = 0;
  std::size_t others = 0;
};
void count_nodes(const XmlElement* e, NodeCounts& counts) {
  for (const auto* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
    const std::string_view n = c->name();
    if (n == "arc")
      ++counts.others;
    else if (n == "place")
      ++counts.places;
    else if (n == "transition")
      ++counts.transitions;
    else if (n == "page") {
      ++counts.others;
      count_nodes(c, counts);
    }
  }
}

struct RawArc {
  const XmlElement* e = nullptr;
  std::string_view source;  // views into the document
  std::string_view target;
  Tokens weight = 1;
  ArcKind kind = ArcKind::normal;
  bool tripodal_read = false;  ///< half of a read arc exported as a self-loop
  bool consumed = false;
};

class PnmlReader {
 public:
  PnmlReader(const ReadContext& ctx, PetriNet& net, const XmlElement* root) : ctx_(ctx), net_(net), ids_(root) {}

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
    NodeCounts counts;
    count_nodes(e, counts);
    net_.reserve(counts.places, counts.transitions);
    ids_.reserve(counts.places + counts.transitions + counts.others);
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
  // A view into the document (its text is already trimmed).
  std::optional<std::pair<std::string_view, const XmlElement*>> label_value(const XmlElement* label) {
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
    return std::make_pair(value->text(), value);
  }

  std::optional<std::string_view> claim_id(const XmlElement* e) {
    auto id = required(ctx_, e, "id");
    if (!id) return std::nullopt;
    if (const XmlElement* first = ids_.claim(*id, e)) {
      ctx_.error_at_value(e, "id",
                          "duplicate id '" + std::string(*id) + "' (first defined at " + ctx_.loc.element(first).str() + ")");
      return std::nullopt;
    }
    return id;
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
          if (auto v = label_value(c)) net_.name.assign(v->first);
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
        if (auto v = label_value(c)) p.name.assign(v->first);
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
        if (auto v = label_value(c)) t.name.assign(v->first);
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
          if (auto v = label_value(c)) text = std::string(v->first);
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
    arcs_.push_back(arc);
  }

  // Arcs may name nodes declared later (or on another page): connected after everything is read.
  void resolve_arcs() {
    // The transition -> place halves of read arcs, by (source, target).
    std::unordered_map<std::pair<std::string_view, std::string_view>, std::vector<std::size_t>, IdPairHash> returns;
    for (std::size_t i = 0; i < arcs_.size(); ++i) {
      const RawArc& b = arcs_[i];
      if (b.tripodal_read && b.kind == ArcKind::normal) returns[{b.source, b.target}].push_back(i);
    }
    for (std::size_t i = 0; i < arcs_.size(); ++i) {
      if (i + kPrefetchAhead < arcs_.size()) {  // the net's id index outgrows the caches (net_xml.cpp)
        net_.prefetch_node(arcs_[i + kPrefetchAhead].source);
        net_.prefetch_node(arcs_[i + kPrefetchAhead].target);
      }
      RawArc& a = arcs_[i];
      if (a.consumed) continue;
      if (!a.tripodal_read) {
        add_checked_arc(ctx_, a.e, net_, a.source, a.target, a.weight, a.kind);
        continue;
      }
      // A read arc travels as the self-loop p -> t -> p (its meaning for every other P/T tool);
      // both halves carry the tripodal mark and fold back into one read arc.
      if (a.kind != ArcKind::normal) {
        ctx_.error(a.e, "tripodal read arc '" + std::string(a.source) + "' -> '" + std::string(a.target) +
                            "' must not also be an inhibitor or read arc");
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
        ctx_.error(a.e, "tripodal read arc '" + std::string(a.source) + "' -> '" + std::string(a.target) +
                            "' has no matching arc '" + std::string(a.target) + "' -> '" + std::string(a.source) +
                            "' of weight " + std::to_string(a.weight));
        continue;
      }
      back->consumed = true;
      a.consumed = true;
      add_checked_arc(ctx_, a.e, net_, a.source, a.target, a.weight, ArcKind::read);
    }
    for (const auto& a : arcs_) {
      if (a.tripodal_read && !a.consumed && net_.find_transition(a.source) && a.kind == ArcKind::normal) {
        ctx_.error(a.e, "tripodal read arc '" + std::string(a.source) + "' -> '" + std::string(a.target) +
                            "' has no matching arc '" + std::string(a.target) + "' -> '" + std::string(a.source) + "'");
      }
    }
  }

  const ReadContext& ctx_;
  PetriNet& net_;
  IdTable ids_;
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
  PnmlReader(ctx, net, root).read_net(net_element);
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
