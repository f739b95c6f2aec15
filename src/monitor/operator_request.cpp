#include "operator_request.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <iterator>
#include <utility>

#include "tripodal/core/xml_text.hpp"

namespace tripodal::monitor {

namespace {

using nlohmann::json;
using B = OperatorBudgets;

// --- the schema, as data ------------------------------------------------------------------------

constexpr std::array<std::string_view, 4> kMapActions = {"begin", "end", "status", "save"};

constexpr FieldSpec kTask[] = {
    {.name = "text", .type = FieldType::text, .required = true, .what = "the task in plain words", .max_bytes = B::kMaxTaskTextBytes,
     .non_empty = true, .rule = TextRule::one_line},
};
constexpr FieldSpec kDrive[] = {
    {.name = "stop", .type = FieldType::boolean, .what = "true stops driving by hand"},
    // Bounds of a hand on a joystick; the controller's limits apply after the coordinator.
    {.name = "vx", .type = FieldType::number, .what = "forward speed, m/s", .min = -1.0, .max = 1.0},
    {.name = "vy", .type = FieldType::number, .what = "sideways speed, m/s", .min = -1.0, .max = 1.0},
    {.name = "wz", .type = FieldType::number, .what = "turn rate, rad/s", .min = -2.0, .max = 2.0},
};
constexpr FieldSpec kAck[] = {
    {.name = "text", .type = FieldType::text, .what = "a note for the life cycle", .max_bytes = B::kMaxAckTextBytes,
     .rule = TextRule::one_line},
};
constexpr FieldSpec kNet[] = {
    {.name = "run", .type = FieldType::text, .required = true, .what = "a running process's run id", .max_bytes = B::kMaxRunBytes,
     .non_empty = true, .rule = TextRule::one_line},
};
constexpr FieldSpec kReload[] = {
    {.name = "run", .type = FieldType::text, .required = true, .what = "a running process's run id", .max_bytes = B::kMaxRunBytes,
     .non_empty = true, .rule = TextRule::one_line},
    {.name = "xml", .type = FieldType::text, .required = true, .what = "its edited net", .max_bytes = B::kMaxNetXmlBytes},
};
constexpr FieldSpec kMap[] = {
    {.name = "action", .type = FieldType::text, .required = true, .what = "begin, end, status or save", .max_bytes = 16,
     .choices = kMapActions},
    {.name = "name", .type = FieldType::text, .what = "save: the map's file name (letters, digits, '_', '-' or '.', not starting with '.')",
     .max_bytes = B::kMaxMapNameBytes, .non_empty = true, .rule = TextRule::file_name},
};
constexpr FieldSpec kBreakpoint[] = {
    {.name = "place", .type = FieldType::text, .required = true, .what = "a place id or name (NET.PLACE for one net)",
     .max_bytes = B::kMaxBreakpointBytes, .non_empty = true, .rule = TextRule::one_line},
    {.name = "on", .type = FieldType::boolean, .what = "true sets it (the default), false clears it"},
};
constexpr FieldSpec kEntry[] = {
    {.name = "id", .type = FieldType::text, .what = "the entry's id"},
    {.name = "topic", .type = FieldType::text, .what = "a few words"},
    {.name = "keywords", .type = FieldType::text_list, .what = "words that point at the entry", .max_items = B::kMaxListItems},
    {.name = "questions", .type = FieldType::text_list, .what = "question forms", .max_items = B::kMaxListItems},
    {.name = "answer", .type = FieldType::text, .what = "what the robot says"},
    {.name = "action", .type = FieldType::text, .what = "a task command after answering"},
};
constexpr FieldSpec kAuthor = {.name = "author", .type = FieldType::text, .what = "who asks (free text)", .max_bytes = B::kMaxAuthorBytes,
                               .rule = TextRule::one_line};
constexpr FieldSpec kRkmsList[] = {
    {.name = "query", .type = FieldType::text, .what = "words every entry listed contains", .max_bytes = B::kMaxQueryBytes},
};
constexpr FieldSpec kRkmsGet[] = {
    {.name = "id", .type = FieldType::text, .required = true, .what = "an entry id", .max_bytes = B::kMaxIdBytes, .non_empty = true,
     .rule = TextRule::one_line},
};
constexpr FieldSpec kRkmsAdd[] = {
    {.name = "entry", .type = FieldType::object, .required = true, .what = "an object with id, topic, keywords, questions, answer, action",
     .members = kEntry},
    kAuthor,
};
constexpr FieldSpec kRkmsEdit[] = {
    {.name = "id", .type = FieldType::text, .what = "the entry edited (default: the entry's id)", .max_bytes = B::kMaxIdBytes,
     .non_empty = true, .rule = TextRule::one_line},
    {.name = "version", .type = FieldType::count, .required = true, .what = "the entry's version you edited (from rkms.list)", .min = 0.0,
     .max = 9007199254740992.0},
    {.name = "entry", .type = FieldType::object, .required = true, .what = "an object with id, topic, keywords, questions, answer, action",
     .members = kEntry},
    kAuthor,
};
constexpr FieldSpec kRkmsDelete[] = {
    {.name = "id", .type = FieldType::text, .required = true, .what = "an entry id", .max_bytes = B::kMaxIdBytes, .non_empty = true,
     .rule = TextRule::one_line},
    {.name = "version", .type = FieldType::count, .required = true, .what = "the entry's version you read (from rkms.list)", .min = 0.0,
     .max = 9007199254740992.0},
    kAuthor,
};
constexpr FieldSpec kRkmsHistory[] = {
    {.name = "limit", .type = FieldType::count, .what = "the newest changes to send", .min = 1.0, .max = static_cast<double>(B::kMaxHistoryLimit)},
};
constexpr FieldSpec kAsk[] = {
    {.name = "text", .type = FieldType::text, .required = true, .what = "what the visitor typed", .max_bytes = B::kMaxAskTextBytes},
    {.name = "speak", .type = FieldType::boolean, .what = "true: the answer as audio too"},
};

constexpr OpSpec kOps[] = {
    {"task", "a task in plain words", kTask},
    {"pause", "hold the run", {}},
    {"resume", "go on", {}},
    {"cancel", "cancel the task", {}},
    {"drive", "drive by hand (repeat while held)", kDrive},
    {"ack", "acknowledge a fault", kAck},
    {"net", "the XML of a running process net", kNet},
    {"reload", "reload an edited process net", kReload},
    {"map", "live mapping", kMap},
    {"breakpoint", "set or clear a breakpoint on a place", kBreakpoint},
    {"rkms.list", "the knowledge entries", kRkmsList},
    {"rkms.get", "one knowledge entry", kRkmsGet},
    {"rkms.add", "add a knowledge entry", kRkmsAdd},
    {"rkms.edit", "edit a knowledge entry", kRkmsEdit},
    {"rkms.delete", "delete a knowledge entry", kRkmsDelete},
    {"rkms.history", "the knowledge base's changes", kRkmsHistory},
    {"touch", "the touch screen's questions", {}},
    {"ask", "a visitor's question", kAsk},
};

// --- checking -----------------------------------------------------------------------------------

std::string_view type_name(const json& v) noexcept {
  switch (v.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float: return "a number";
    case json::value_t::string: return "a string";
    case json::value_t::array: return "an array";
    case json::value_t::object: return "an object";
    default: return "something else";
  }
}

std::string number_text(double v) {
  if (std::floor(v) == v && std::fabs(v) < 1e15) return std::to_string(static_cast<long long>(v));
  return json(v).dump();
}

// A name a client chose, fit to be quoted in an answer and a log: short, one line of text, no quote.
bool plain_name(std::string_view s) noexcept {
  return !s.empty() && s.size() <= 64 && !find_xml_text_fault(s, true) && s.find_first_of("\t\r\n'") == std::string_view::npos;
}

// An unknown field as the errors name it: as sent when plain, otherwise described (a key may be
// empty or 60 KB of anything).
std::string shown_name(const std::string& key) {
  if (plain_name(key)) return key;
  return key.empty() ? std::string("(empty name)") : "(a name of " + std::to_string(key.size()) + " bytes)";
}

bool file_name(std::string_view s) noexcept {
  return !s.empty() && s.front() != '.' && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '.';
  });
}

class Checker {
 public:
  explicit Checker(std::string_view op) : op_(op) {}

  void object(const json& body, std::span<const FieldSpec> fields, const std::string& prefix) {
    for (const auto& item : body.items()) {
      const std::string& key = item.key();  // (not a structured binding: a lambda below names it)
      const json& value = item.value();
      const auto spec = std::find_if(fields.begin(), fields.end(), [&](const FieldSpec& f) { return f.name == key; });
      if (spec == fields.end()) {
        if (prefix.empty() && key == "op") continue;
        std::string known;
        for (const FieldSpec& f : fields) known += (known.empty() ? "" : ", ") + std::string(f.name);
        fail(prefix + shown_name(key), known.empty() ? "unknown; op '" + std::string(op_) + "' takes no fields"
                                         : "unknown; expected " + known);
        continue;
      }
      field(value, *spec, prefix + key);
    }
    for (const FieldSpec& f : fields) {
      if (f.required && !body.contains(std::string(f.name))) fail(prefix + std::string(f.name), "missing; expected \"" + std::string(f.name) + "\": " + std::string(f.what));
    }
  }

  std::vector<RequestFieldError> errors;

 private:
  void fail(const std::string& path, const std::string& why) {
    errors.push_back({path, "field '" + path + "' of op '" + std::string(op_) + "': " + why});
  }
  void expected(const std::string& path, std::string_view want, const json& got) {
    fail(path, "expected " + std::string(want) + ", got " + std::string(type_name(got)));
  }

  void field(const json& v, const FieldSpec& f, const std::string& path) {
    switch (f.type) {
      case FieldType::boolean:
        if (!v.is_boolean()) expected(path, "a boolean", v);
        return;
      case FieldType::number: {
        if (!v.is_number()) return expected(path, "a number", v);
        const double x = v.get<double>();
        if (!(x >= f.min && x <= f.max)) fail(path, "expected a number from " + number_text(f.min) + " to " + number_text(f.max) + ", got " + v.dump());
        return;
      }
      case FieldType::count: {
        if (!v.is_number()) return expected(path, "a whole number", v);
        const bool whole = v.is_number_unsigned() || (v.is_number_integer() && v.get<std::int64_t>() >= 0);
        const double x = v.get<double>();
        if (!whole || !(x >= f.min && x <= f.max)) {
          fail(path, "expected a whole number from " + number_text(f.min) + " to " + number_text(f.max) + ", got " + v.dump());
        }
        return;
      }
      case FieldType::text:
        if (!v.is_string()) return expected(path, "a string", v);
        text(v.get_ref<const std::string&>(), f, path);
        return;
      case FieldType::text_list:
        if (!v.is_array()) return expected(path, "an array of strings", v);
        if (f.max_items > 0 && v.size() > f.max_items) {
          return fail(path, std::to_string(v.size()) + " items; expected at most " + std::to_string(f.max_items));
        }
        for (std::size_t i = 0; i < v.size(); ++i) {
          const std::string item = path + "[" + std::to_string(i) + "]";
          if (!v[i].is_string()) {
            expected(item, "a string", v[i]);
            continue;
          }
          text(v[i].get_ref<const std::string&>(), f, item);
        }
        return;
      case FieldType::object:
        if (!v.is_object()) return expected(path, "an object", v);
        object(v, f.members, path + ".");
        return;
    }
  }

  void text(const std::string& s, const FieldSpec& f, const std::string& path) {
    if (f.max_bytes > 0 && s.size() > f.max_bytes) {
      return fail(path, std::to_string(s.size()) + " bytes; expected at most " + std::to_string(f.max_bytes));
    }
    // Every string may end in a log line, the life cycle or a saved file: XML's characters only.
    if (const auto fault = find_xml_text_fault(s, true)) return fail(path, "not text: " + describe(*fault));
    if (f.non_empty && s.empty()) return fail(path, "empty; expected \"" + std::string(f.name) + "\": " + std::string(f.what));
    if (f.rule == TextRule::one_line && s.find_first_of("\t\r\n") != std::string::npos) {
      return fail(path, "holds a line break or a tab at byte " + std::to_string(s.find_first_of("\t\r\n")) + "; expected one line");
    }
    if (f.rule == TextRule::file_name && !file_name(s)) {
      return fail(path, "expected \"" + std::string(f.name) + "\": " + std::string(f.what) + ", got " + json(s).dump());
    }
    if (!f.choices.empty() && std::find(f.choices.begin(), f.choices.end(), s) == f.choices.end()) {
      return fail(path, "expected \"" + std::string(f.name) + "\": " + std::string(f.what) + ", got " + json(s).dump());
    }
  }

  std::string_view op_;
};

// --- typed values from a checked body (types are known to be right here) --------------------------

std::string text_or(const json& j, const char* key, std::string fallback = {}) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::move(fallback);
}
bool bool_or(const json& j, const char* key, bool fallback) {
  const auto it = j.find(key);
  return it != j.end() && it->is_boolean() ? it->get<bool>() : fallback;
}
double number_or(const json& j, const char* key, double fallback) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}
std::uint64_t count_or(const json& j, const char* key, std::uint64_t fallback) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number_integer() ? it->get<std::uint64_t>() : fallback;
}
std::vector<std::string> texts_of(const json& j, const char* key) {
  std::vector<std::string> out;
  const auto it = j.find(key);
  if (it == j.end() || !it->is_array()) return out;
  for (const json& v : *it) out.push_back(v.get<std::string>());
  return out;
}
EntryFields entry_of(const json& j) {
  EntryFields e;
  e.id = text_or(j, "id");
  e.topic = text_or(j, "topic");
  e.keywords = texts_of(j, "keywords");
  e.questions = texts_of(j, "questions");
  e.answer = text_or(j, "answer");
  e.action = text_or(j, "action");
  return e;
}

OperatorCommand command_of(std::string_view op, const json& b) {
  if (op == "task") return TaskRequest{text_or(b, "text")};
  if (op == "pause") return PauseRequest{};
  if (op == "resume") return ResumeRequest{};
  if (op == "cancel") return CancelRequest{};
  if (op == "drive") return DriveRequest{bool_or(b, "stop", false), number_or(b, "vx", 0.0), number_or(b, "vy", 0.0), number_or(b, "wz", 0.0)};
  if (op == "ack") return AckRequest{text_or(b, "text")};
  if (op == "net") return NetRequest{text_or(b, "run")};
  if (op == "reload") return ReloadRequest{text_or(b, "run"), text_or(b, "xml")};
  if (op == "map") {
    const std::string a = text_or(b, "action");
    const auto action = a == "begin" ? MapRequest::Action::begin
                        : a == "end" ? MapRequest::Action::end
                        : a == "save" ? MapRequest::Action::save
                                      : MapRequest::Action::status;
    return MapRequest{action, text_or(b, "name")};
  }
  if (op == "breakpoint") return BreakpointRequest{text_or(b, "place"), bool_or(b, "on", true)};
  if (op == "rkms.list") return RkmsListRequest{text_or(b, "query")};
  if (op == "rkms.get") return RkmsGetRequest{text_or(b, "id")};
  if (op == "rkms.add") return RkmsAddRequest{entry_of(b.at("entry")), text_or(b, "author")};
  if (op == "rkms.edit") {
    RkmsEditRequest r{text_or(b, "id"), count_or(b, "version", 0), entry_of(b.at("entry")), text_or(b, "author")};
    if (r.id.empty()) r.id = r.entry.id;
    return r;
  }
  if (op == "rkms.delete") return RkmsDeleteRequest{text_or(b, "id"), count_or(b, "version", 0), text_or(b, "author")};
  if (op == "rkms.history") return RkmsHistoryRequest{static_cast<std::size_t>(count_or(b, "limit", B::kDefaultHistoryLimit))};
  if (op == "touch") return TouchRequest{};
  return AskRequest{text_or(b, "text"), bool_or(b, "speak", false)};
}

std::string op_names() {
  std::string out;
  for (std::size_t i = 0; i < std::size(kOps); ++i) {
    out += (i == 0 ? "" : i + 1 == std::size(kOps) ? " or " : ", ") + std::string(kOps[i].op);
  }
  return out;
}

}  // namespace

std::span<const OpSpec> request_schema() noexcept { return kOps; }

const OpSpec* find_op(std::string_view op) noexcept {
  for (const OpSpec& s : kOps) {
    if (s.op == op) return &s;
  }
  return nullptr;
}

ParsedRequest parse_operator_request(std::string_view body) {
  ParsedRequest out;
  const json j = json::parse(body, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    out.errors.push_back({"", "body: expected a JSON object with a string \"op\""});
    return out;
  }
  const auto op = j.find("op");
  if (op == j.end() || !op->is_string()) {
    out.errors.push_back({"op", "field 'op': expected a string naming the op (" + op_names() + "), got " +
                                    (op == j.end() ? std::string("nothing") : std::string(type_name(*op)))});
    return out;
  }
  out.op = op->get<std::string>();
  const OpSpec* spec = find_op(out.op);
  if (spec == nullptr) {
    // Named as sent when it is a short line of text; what a client sends may be anything.
    out.errors.push_back({"op", "unknown op '" + shown_name(out.op) + "': expected " + op_names()});
    return out;
  }
  Checker checker(spec->op);
  checker.object(j, spec->fields, "");
  if (!checker.errors.empty()) {
    out.errors = std::move(checker.errors);
    return out;
  }
  // The one rule across fields: a map is saved under a name.
  if (spec->op == "map" && j.at("action") == "save" && !j.contains("name")) {
    out.errors.push_back({"name", "field 'name' of op 'map': missing; expected \"name\": " + std::string(kMap[1].what)});
    return out;
  }
  out.command = command_of(spec->op, j);
  return out;
}

json refusal_json(const ParsedRequest& parsed) {
  json errors = json::array();
  for (const RequestFieldError& e : parsed.errors) {
    // The RKMS page puts an entry's errors beside its fields, named as the store names them.
    const bool entry_field = e.field.starts_with("entry.");
    const std::string field = entry_field ? e.field.substr(6) : e.field;
    std::string message = e.message;
    if (entry_field) message = field + ": " + message.substr(message.find("': ") + 3);
    errors.push_back({{"field", field}, {"message", message}});
  }
  json out{{"error", parsed.errors.empty() ? std::string("refused") : parsed.errors.front().message},
           {"field", parsed.errors.empty() ? std::string() : parsed.errors.front().field},
           {"status", "invalid"},
           {"errors", std::move(errors)}};
  return out;
}

}  // namespace tripodal::monitor
