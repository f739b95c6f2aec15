// The monitor's operator requests (src/monitor/operator_request.hpp, docs/monitor.md): any bytes as
// the body of POST /api/command, read by the one layer that checks every console and RKMS request.
// Properties: nothing throws; a refused request names a field in each error and its answer is JSON
// that serialises; an accepted one is an op of the schema, typed as that op, with every budget the
// robot keeps (task, ack and breakpoint texts, runs, history limit) held and its texts XML's.
#include "tripodal_monitor_internal/operator_request.hpp"

#include <string>
#include <string_view>
#include <variant>

#include "../fuzz_target.hpp"
#include "tripodal/core/xml_text.hpp"

namespace {

using namespace tripodal;
using namespace tripodal::monitor;

void require_text(const std::string& s, std::size_t max_bytes, std::string_view what) {
  fuzz::require(s.size() <= max_bytes, what, "over its budget");
  fuzz::require(!find_xml_text_fault(s, true).has_value(), what, "is not XML text");
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using B = OperatorBudgets;
  const ParsedRequest p = parse_operator_request(fuzz::as_text(bytes));
  if (!p.command) {
    fuzz::require(!p.errors.empty(), "a refused request says why");
    for (const RequestFieldError& e : p.errors) {
      fuzz::require(!e.message.empty(), "every error has a message");
      fuzz::require(e.field.empty() ? e.message.starts_with("body:") : (e.message.starts_with("field '" + e.field + "'") || e.message.starts_with("unknown op")),
                    "every error names its field", e.message);
    }
    const std::string answer = refusal_json(p).dump();  // throws on text that is not UTF-8
    fuzz::require(answer.find("\"field\"") != std::string::npos, "the answer names the field");
    return;
  }
  fuzz::require(p.errors.empty(), "an accepted request has no errors");
  const auto schema = request_schema();
  const OpSpec* spec = find_op(p.op);
  fuzz::require(spec != nullptr, "an accepted op is in the schema", p.op);
  fuzz::require(static_cast<std::size_t>(spec - schema.data()) == p.command->index(), "the command is typed as its op", p.op);
  std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, TaskRequest>) require_text(c.text, B::kMaxTaskTextBytes, "task text");
        if constexpr (std::is_same_v<T, AckRequest>) require_text(c.text, B::kMaxAckTextBytes, "ack text");
        if constexpr (std::is_same_v<T, BreakpointRequest>) {
          require_text(c.place, B::kMaxBreakpointBytes, "breakpoint place");
          fuzz::require(!c.place.empty(), "a breakpoint names a place");
        }
        if constexpr (std::is_same_v<T, NetRequest>) require_text(c.run, B::kMaxRunBytes, "net run");
        if constexpr (std::is_same_v<T, ReloadRequest>) require_text(c.xml, B::kMaxNetXmlBytes, "reload xml");
        if constexpr (std::is_same_v<T, DriveRequest>) {
          fuzz::require(c.vx_m_s >= -1.0 && c.vx_m_s <= 1.0 && c.vy_m_s >= -1.0 && c.vy_m_s <= 1.0 && c.wz_rad_s >= -2.0 && c.wz_rad_s <= 2.0,
                        "drive speeds within a hand's bounds");
        }
        if constexpr (std::is_same_v<T, MapRequest>) {
          fuzz::require(c.action != MapRequest::Action::save || (!c.name.empty() && c.name.size() <= B::kMaxMapNameBytes &&
                                                                 c.name.front() != '.' && c.name.find('/') == std::string::npos),
                        "a map is saved under a bare name");
        }
        if constexpr (std::is_same_v<T, RkmsHistoryRequest>) {
          fuzz::require(c.limit >= 1 && c.limit <= B::kMaxHistoryLimit, "the history limit holds");
        }
        if constexpr (std::is_same_v<T, RkmsAddRequest> || std::is_same_v<T, RkmsEditRequest>) {
          require_text(c.entry.answer, B::kMaxNetXmlBytes, "entry answer");
          for (const std::string& k : c.entry.keywords) require_text(k, B::kMaxNetXmlBytes, "entry keyword");
          fuzz::require(c.entry.keywords.size() <= B::kMaxListItems, "entry lists hold");
        }
      },
      *p.command);
}
