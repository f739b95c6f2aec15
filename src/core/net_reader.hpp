// Internal: reading the parts of a net that the native XML format and the tripodal extension of
// PNML (<toolspecific tool="tripodal">) share: node attributes, bindings, declarations, guards,
// delays. Every problem becomes a located diagnostic; reading always continues.
#pragma once

#include <array>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "xml_document.hpp"

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/core/petri_net.hpp"
#include "xml_locator.hpp"

namespace tripodal::detail {

inline constexpr std::string_view kFormatVersion = "1";

struct ReadContext {
  const XmlLocator& loc;
  Diagnostics& diags;
  const LoadOptions& options;

  void error(const XmlElement* e, const std::string& message) const;
  void error_at_attribute(const XmlElement* e, std::string_view attr, const std::string& message) const;
  void error_at_value(const XmlElement* e, std::string_view attr, const std::string& message,
                      std::size_t decoded_offset = 0) const;
};

/// Reports every attribute not in `allowed`.
void check_attributes(const ReadContext& ctx, const XmlElement* e,
                      std::initializer_list<std::string_view> allowed);
/// Attribute values found by read_attributes(), by position in the list of names asked for.
/// Pointers, not optionals: an array of them is cleared in a few stores, where an array of
/// 24-byte optional<string_view> is cleared with a slow `rep stos` on every element read.
template <std::size_t N>
struct AttributeValues {
  std::array<const XmlAttribute*, N> found{};
  /// The value of the k-th name; nullopt when the element does not have it.
  [[nodiscard]] std::optional<std::string_view> operator[](std::size_t k) const noexcept {
    return found[k] == nullptr ? std::nullopt : std::optional<std::string_view>(found[k]->value);
  }
};
/// One pass over the element's attributes: found[i] gets the attribute named names[i] (left
/// nullptr when absent); every other attribute is reported as check_attributes does.
void read_attributes(const ReadContext& ctx, const XmlElement* e, std::span<const std::string_view> names,
                     std::span<const XmlAttribute*> found);
/// "unknown element <x> in <parent>; expected one of: ...".
void unknown_element(const ReadContext& ctx, const XmlElement* e, std::string_view parent,
                     std::string_view expected);
/// Reports an element's non-blank text content (the formats keep everything in attributes).
void check_no_text(const ReadContext& ctx, const XmlElement* e);

/// Reports a required attribute missing or empty (the cold half of required()).
void report_missing(const ReadContext& ctx, const XmlElement* e, std::string_view attr, bool present);
/// The check on a value already read (read_attributes): missing or empty is reported, nullopt.
/// Inline: the readers check several attributes of every element.
inline std::optional<std::string_view> required(const ReadContext& ctx, const XmlElement* e, std::string_view attr,
                                                std::optional<std::string_view> value) {
  if (value && !value->empty()) [[likely]] return value;
  report_missing(ctx, e, attr, value.has_value());
  return std::nullopt;
}
/// A required attribute's value (a view into the document); reports it missing (or empty) and
/// returns nullopt.
inline std::optional<std::string_view> required(const ReadContext& ctx, const XmlElement* e, std::string_view attr) {
  return required(ctx, e, attr, e->attribute(attr));
}
/// An optional attribute's value (a view into the document); nullopt when absent.
inline std::optional<std::string_view> optional_attr(const XmlElement* e, std::string_view attr) {
  return e->attribute(attr);
}

/// A decimal count: tokens/capacity (min 0) or weight (min 1). Reports bad text at the value of
/// attribute `attr` of `e`, or at `e` itself when `attr` is empty (PNML labels).
std::optional<Tokens> parse_count(const ReadContext& ctx, const XmlElement* e, std::string_view attr,
                                  std::string_view text, Tokens minimum, std::string_view what);
/// "2s", "500ms", "1.5min": number and unit (ns, us, ms, s, min, h), not negative.
std::optional<Duration> parse_delay_text(std::string_view text, std::string& error);
/// A name that events, parameters and behaviors may use: letter or '_' first, then letters,
/// digits, '_', '.', '-', '/'.
bool is_valid_name(std::string_view name) noexcept;

/// <parameter>/<fact name type default description/>; appends to net.parameters / net.facts.
void read_declaration(const ReadContext& ctx, const XmlElement* e, PetriNet& net, bool fact);

/// Place attributes other than id (name, description, tokens, capacity, outcome, message) and
/// the <behavior>/<process> children. `net` gives the declared parameters for "$param" checks.
void read_place_details(const ReadContext& ctx, const XmlElement* e, Place& place, const PetriNet& net,
                        bool allow_tokens_and_name);
/// Transition attributes other than id (name, description, event, guard, delay, priority).
void read_transition_details(const ReadContext& ctx, const XmlElement* e, Transition& t,
                             const PetriNet& net, bool allow_name);
/// "normal" | "read" | "inhibitor".
std::optional<ArcKind> parse_arc_kind(std::string_view text) noexcept;
[[nodiscard]] std::string_view to_string(ArcKind kind) noexcept;

/// Connects the ends of an arc after every node was read: unknown node, two places, two
/// transitions, a read/inhibitor arc leaving a transition. Returns false after reporting.
bool add_checked_arc(const ReadContext& ctx, const XmlElement* e, PetriNet& net, std::string_view from,
                     std::string_view to, Tokens weight, ArcKind kind);

/// The element's text content with blanks trimmed ("" when none).
std::string trimmed_text(const XmlElement* e);

}  // namespace tripodal::detail
