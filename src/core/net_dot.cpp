#include "tripodal/core/net_dot.hpp"

#include <stdexcept>

#include "net_formats.hpp"  // xml_escape: an HTML-like label is XML text

namespace tripodal {

namespace {

// A DOT double-quoted string: quotes and backslashes escaped; "\n" stays a DOT line break.
std::string dot_quoted(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

// The tokens as the paper draws them: dots for a few, a number beyond.
std::string token_text(Tokens n) {
  if (n == 0) return {};
  if (n > 4) return std::to_string(n);
  std::string out;
  for (Tokens k = 0; k < n; ++k) out += k == 2 ? "\n\xE2\x97\x8F" : "\xE2\x97\x8F";  // U+25CF BLACK CIRCLE
  return out;
}

std::string seconds_text(Duration d) { return format_seconds(d, kExactDigits) + " s"; }

}  // namespace

std::string net_to_dot(const PetriNet& net, std::span<const Tokens> marking, const DotOptions& options) {
  const auto& places = net.places();
  if (!marking.empty() && marking.size() != places.size()) {
    throw std::invalid_argument("marking has " + std::to_string(marking.size()) + " entries for " +
                                std::to_string(places.size()) + " places");
  }
  std::string out = "digraph " + dot_quoted(net.id.empty() ? "net" : net.id) + " {\n";
  out += "  graph [rankdir=TB, nodesep=0.7, ranksep=0.5, forcelabels=true, fontname=\"Helvetica\"";
  if (!net.description.empty()) out += ", label=" + dot_quoted(net.description) + ", labelloc=t";
  out += "];\n";
  out += "  node [fontname=\"Helvetica\", fontsize=11];\n  edge [arrowsize=0.7];\n";
  // The drawing carries the ids (as the paper's figures do); the descriptions go to a legend table
  // beside it, like the paper's tables, so long texts do not pile up over the arcs.
  for (std::size_t i = 0; i < places.size(); ++i) {
    const Place& p = places[i];
    const Tokens tokens = marking.empty() ? p.initial_tokens : marking[i];
    std::string xlabel = p.name;
    if (p.capacity) xlabel += " (" + std::to_string(*p.capacity) + ")";
    out += "  " + dot_quoted(p.id) + " [shape=circle, fixedsize=true, width=0.5, label=" + dot_quoted(token_text(tokens)) +
           ", xlabel=" + dot_quoted(xlabel);
    if (p.outcome != Outcome::none) out += ", peripheries=2";
    if (p.outcome == Outcome::fault) out += ", color=\"#b00000\"";
    if (p.behavior || p.process) out += ", style=filled, fillcolor=\"#eef3ff\"";
    out += "];\n";
  }
  for (const auto& t : net.transitions()) {
    std::string xlabel = t.name;
    if (!t.event.empty()) xlabel += " [" + t.event + "]";
    if (t.guard) xlabel += "\nif " + t.guard->text();
    if (t.delay.count() != 0) xlabel += "\nafter " + seconds_text(t.delay);
    if (t.priority != 0) xlabel += "\npriority " + std::to_string(t.priority);
    out += "  " + dot_quoted(t.id) +
           " [shape=box, style=filled, fillcolor=black, label=\"\", width=0.45, height=0.07, fixedsize=true, xlabel=" +
           dot_quoted(xlabel) + "];\n";
  }
  for (const auto& t : net.transitions()) {
    const auto weight = [](Tokens w) { return w > 1 ? "label=" + dot_quoted(std::to_string(w)) : std::string(); };
    const auto more = [&](Tokens w) { return w > 1 ? ", " + weight(w) : std::string(); };
    for (const auto& a : t.inputs) out += "  " + dot_quoted(places[a.place].id) + " -> " + dot_quoted(t.id) + " [" + weight(a.weight) + "];\n";
    for (const auto& a : t.outputs) out += "  " + dot_quoted(t.id) + " -> " + dot_quoted(places[a.place].id) + " [" + weight(a.weight) + "];\n";
    for (const auto& a : t.reads) {
      out += "  " + dot_quoted(places[a.place].id) + " -> " + dot_quoted(t.id) + " [style=dashed, arrowhead=none" + more(a.weight) + "];\n";
    }
    for (const auto& a : t.inhibitors) {
      out += "  " + dot_quoted(places[a.place].id) + " -> " + dot_quoted(t.id) + " [arrowhead=odot" + more(a.weight) + "];\n";
    }
  }
  if (options.descriptions) {
    std::string rows;
    const auto row = [&](const std::string& id, const std::string& text) {
      if (text.empty()) return;
      rows += "<TR><TD ALIGN=\"LEFT\">" + detail::xml_escape(id) + "</TD><TD ALIGN=\"LEFT\">" + detail::xml_escape(text) + "</TD></TR>";
    };
    for (const auto& p : places) {
      std::string text = p.description;
      if (p.behavior) text += (text.empty() ? "" : " ") + std::string("[behavior ") + p.behavior->behavior + "]";
      if (p.process) text += (text.empty() ? "" : " ") + std::string("[process ") + p.process->process + "]";
      if (p.outcome == Outcome::fault && !p.fault_message.empty()) text += " [fault: " + p.fault_message + "]";
      row(p.name, text);
    }
    for (const auto& t : net.transitions()) row(t.name, t.description);
    if (!rows.empty()) {
      out += "  legend [shape=plaintext, fontsize=10, label=<<TABLE BORDER=\"0\" CELLBORDER=\"1\" CELLSPACING=\"0\" "
             "CELLPADDING=\"3\"><TR><TD COLSPAN=\"2\"><B>Description</B></TD></TR>" +
             rows + "</TABLE>>];\n";
    }
  }
  return out + "}\n";
}

}  // namespace tripodal
