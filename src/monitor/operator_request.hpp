// Internal (monitor area): the operator's requests (the JSON body of POST /api/command) read into
// typed values by one validating layer, before anything reaches the robot. The schema is data
// (request_schema(): op -> fields with type, required, range, length, count), the parser follows it
// (types, ranges, lengths, counts, unknown fields, text XML can hold) and refuses with the field
// named, so RobotMonitor and the HRI ops only ever see requests of the right shape. The budgets of
// what an operator can make the robot keep are named here and listed in docs/monitor.md ("Budgets").
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

namespace tripodal::monitor {

/// What an operator can make the robot keep or build, bounded (docs/monitor.md, "Budgets").
struct OperatorBudgets {
  static constexpr std::size_t kMaxTaskTextBytes = 500;       ///< task: text (the HRI's utterance limit)
  /// ask: text. Above the HRI's own limit (HriOptions::max_utterance_bytes, 500), which
  /// answers a visitor's overlong input with a refused_input reply the touch page shows.
  static constexpr std::size_t kMaxAskTextBytes = 4000;
  static constexpr std::size_t kMaxAckTextBytes = 500;        ///< ack: the note's text
  static constexpr std::size_t kMaxAckNotesKept = 100;        ///< ack notes with a text kept in a run's life cycle
  static constexpr std::size_t kMaxBreakpoints = 64;          ///< breakpoints set at once
  static constexpr std::size_t kMaxBreakpointBytes = 256;     ///< breakpoint: place
  static constexpr std::size_t kMaxRunBytes = 128;            ///< net, reload: run
  static constexpr std::size_t kMaxNetXmlBytes = 1U << 20U;   ///< reload: xml
  static constexpr std::size_t kMaxMapNameBytes = 64;         ///< map: name
  static constexpr std::size_t kMaxQueryBytes = 200;          ///< rkms.list: query
  static constexpr std::size_t kMaxIdBytes = 64;              ///< rkms.get, rkms.edit, rkms.delete: id
  static constexpr std::size_t kMaxAuthorBytes = 64;          ///< rkms.add, rkms.edit, rkms.delete: author
  static constexpr std::size_t kMaxListItems = 256;           ///< entry: keywords, questions (the store's own limit is lower)
  static constexpr std::size_t kDefaultHistoryLimit = 50;     ///< rkms.history without a limit
  static constexpr std::size_t kMaxHistoryLimit = 200;        ///< rkms.history: limit
  /// rkms.history: the newest changes that fit in this many bytes of JSON are sent (the server
  /// lets a client queue at most 8 MiB); the answer says how many were left out.
  static constexpr std::size_t kMaxHistoryAnswerBytes = 4U << 20U;
};

// --- the schema ---------------------------------------------------------------------------------

enum class FieldType : std::uint8_t {
  boolean,    ///< true or false
  number,     ///< a finite number within [min, max]
  count,      ///< a whole number >= 0 within [min, max]
  text,       ///< a string: text XML can hold (no control characters but tab, LF, CR), at most max_bytes
  text_list,  ///< an array of at most max_items texts
  object,     ///< an object whose fields are `members` (the same rules, unknown fields refused)
};

enum class TextRule : std::uint8_t {
  free,       ///< line breaks and tabs allowed
  one_line,   ///< no tab, line feed or carriage return (it becomes one line of a log)
  file_name,  ///< letters, digits, '_', '-', '.', not starting with '.' (never a folder)
};

struct FieldSpec {
  std::string_view name;
  FieldType type = FieldType::text;
  bool required = false;
  std::string_view what;  ///< for a person: what the field is
  double min = 0.0, max = 0.0;                ///< number, count
  std::size_t max_bytes = 0;                  ///< text, text_list items (0: no limit of its own)
  std::size_t max_items = 0;                  ///< text_list
  bool non_empty = false;                     ///< text
  TextRule rule = TextRule::free;             ///< text, text_list items
  std::span<const std::string_view> choices;  ///< text: one of these (empty: any)
  std::span<const FieldSpec> members;         ///< object
};

struct OpSpec {
  std::string_view op;
  std::string_view what;
  std::span<const FieldSpec> fields;
};

/// Every op the console and the RKMS pages send, with its fields. Fields not listed (other than
/// "op") are refused with their name.
[[nodiscard]] std::span<const OpSpec> request_schema() noexcept;
[[nodiscard]] const OpSpec* find_op(std::string_view op) noexcept;

// --- typed requests -----------------------------------------------------------------------------

struct TaskRequest { std::string text; };
struct PauseRequest {};
struct ResumeRequest {};
struct CancelRequest {};
struct DriveRequest {
  bool stop = false;
  double vx_m_s = 0.0, vy_m_s = 0.0, wz_rad_s = 0.0;
};
struct AckRequest { std::string text; };
struct NetRequest { std::string run; };
struct ReloadRequest { std::string run, xml; };
struct MapRequest {
  enum class Action { begin, end, status, save };
  Action action = Action::status;
  std::string name;  ///< save: a bare file name
};
struct BreakpointRequest {
  std::string place;
  bool on = true;
};
/// An RKMS entry as a request gives it (the hri area's KnowledgeEntry without its location); kept
/// apart so this layer depends on no area but core (its fuzz target builds alone).
struct EntryFields {
  std::string id, topic;
  std::vector<std::string> keywords, questions;
  std::string answer, action;
};
struct RkmsListRequest { std::string query; };
struct RkmsGetRequest { std::string id; };
struct RkmsAddRequest {
  EntryFields entry;
  std::string author;
};
struct RkmsEditRequest {
  std::string id;  ///< the entry's id when the request names none
  std::uint64_t version = 0;
  EntryFields entry;
  std::string author;
};
struct RkmsDeleteRequest {
  std::string id;
  std::uint64_t version = 0;
  std::string author;
};
struct RkmsHistoryRequest { std::size_t limit = OperatorBudgets::kDefaultHistoryLimit; };
struct TouchRequest {};
struct AskRequest {
  std::string text;
  bool speak = false;
};

using OperatorCommand =
    std::variant<TaskRequest, PauseRequest, ResumeRequest, CancelRequest, DriveRequest, AckRequest, NetRequest, ReloadRequest, MapRequest,
                 BreakpointRequest, RkmsListRequest, RkmsGetRequest, RkmsAddRequest, RkmsEditRequest, RkmsDeleteRequest, RkmsHistoryRequest,
                 TouchRequest, AskRequest>;

/// One thing wrong with a request: `field` is its path ("stop", "entry.keywords[1]"; "op" for the
/// op, "" for the body itself), `message` says the op, the field, what was expected and what came.
struct RequestFieldError {
  std::string field;
  std::string message;
};

/// A request read: `command` when it is valid, else every error found (in the body's order).
struct ParsedRequest {
  std::string op;  ///< as sent, when it was a string
  std::optional<OperatorCommand> command;
  std::vector<RequestFieldError> errors;
};

/// Reads a request body. Never throws for any input (but std::bad_alloc).
[[nodiscard]] ParsedRequest parse_operator_request(std::string_view body);

/// The 400 answer of a refused request: {"error": the first message, "field": its field,
/// "errors": [{"field", "message"}...], "status": "invalid"}. An entry's fields are named in
/// "errors" as the knowledge store names them ("keywords[1]"), so the RKMS page shows them beside
/// the field; "field" has the whole path ("entry.keywords[1]").
[[nodiscard]] nlohmann::json refusal_json(const ParsedRequest& parsed);

}  // namespace tripodal::monitor
