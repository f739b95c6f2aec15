// Internal: the readers and writers behind load_net / save_net, one pair per format.
#pragma once

#include <optional>
#include <string>

#include "xml_document.hpp"

#include "net_reader.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal::detail {

/// Native XML (docs/net-format.md). The root element must be <net>. Returns the net even when
/// errors were reported (the caller decides by the diagnostics).
PetriNet read_native(const XmlElement* root, const ReadContext& ctx);
/// PNML: ISO/IEC 15909-2 P/T nets (with <page>) and the JARP dialect (no <page>, <value> labels).
PetriNet read_pnml(const XmlElement* root, const ReadContext& ctx);

/// XML attribute/text escaping shared by the writers and the DOT writer's HTML-like labels.
std::string xml_escape(std::string_view text);
/// The value as written in a file: true/false, shortest round-trip number, raw string.
std::string value_text(const Value& v);
/// A delay in the largest unit that keeps it exact: "5s", "500ms", "250us", "7ns".
std::string delay_text(Duration d);

std::string write_native(const PetriNet& net);
/// Throws ConfigError when the net cannot be written as a P/T net.
std::string write_pnml(const PetriNet& net);

/// Attributes (with a leading space each) that describe a place / transition beyond id, name and
/// tokens, in the native format's syntax; the PNML writer reuses them inside <toolspecific>.
std::string place_detail_attributes(const Place& p);
std::string transition_detail_attributes(const Transition& t);
/// <behavior>/<process> child of a place, indented by `indent`; empty when none.
std::string binding_elements(const Place& p, const std::string& indent);
std::string declaration_elements(const PetriNet& net, const std::string& indent);

}  // namespace tripodal::detail
