#include "hri_ops.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "tripodal/monitor/wire.hpp"

namespace tripodal::monitor {

namespace {

using nlohmann::json;

constexpr std::size_t kTouchQuestions = 8;

json entry_json(const KnowledgeEntry& e) {
  return json{{"id", e.id}, {"topic", e.topic}, {"keywords", e.keywords}, {"questions", e.questions}, {"answer", e.answer}, {"action", e.action}};
}

json versioned_json(const VersionedEntry& v) {
  json j = entry_json(v.entry);
  j["version"] = v.version;
  return j;
}

// The entry of a request, each field checked for its JSON type; a wrong type is named like the
// store names its fields, so the page puts it at the same place.
std::optional<KnowledgeEntry> entry_from(const json& j, std::vector<KnowledgeFieldError>& errors) {
  if (!j.is_object()) {
    errors.push_back({"entry", "expected \"entry\": an object with id, topic, keywords, questions, answer, action"});
    return std::nullopt;
  }
  KnowledgeEntry e;
  const auto text = [&](const char* field, std::string& out) {
    if (!j.contains(field) || j[field].is_null()) return;
    if (!j[field].is_string()) {
      errors.push_back({field, std::string(field) + ": expected a string"});
      return;
    }
    out = j[field].get<std::string>();
  };
  const auto list = [&](const char* field, std::vector<std::string>& out) {
    if (!j.contains(field) || j[field].is_null()) return;
    if (!j[field].is_array()) {
      errors.push_back({field, std::string(field) + ": expected an array of strings"});
      return;
    }
    for (std::size_t i = 0; i < j[field].size(); ++i) {
      const json& v = j[field][i];
      if (!v.is_string()) {
        errors.push_back({std::string(field) + "[" + std::to_string(i) + "]", std::string(field) + "[" + std::to_string(i) + "]: expected a string"});
        continue;
      }
      out.push_back(v.get<std::string>());
    }
  };
  text("id", e.id);
  text("topic", e.topic);
  list("keywords", e.keywords);
  list("questions", e.questions);
  text("answer", e.answer);
  text("action", e.action);
  if (!errors.empty()) return std::nullopt;
  return e;
}

json errors_json(const std::vector<KnowledgeFieldError>& errors) {
  json out = json::array();
  for (const auto& e : errors) out.push_back({{"field", e.field}, {"message", e.message}});
  return out;
}

int http_status(KnowledgeEdit::Status s) {
  switch (s) {
    case KnowledgeEdit::Status::ok: return 200;
    case KnowledgeEdit::Status::invalid: return 400;
    case KnowledgeEdit::Status::not_found: return 404;
    case KnowledgeEdit::Status::exists:
    case KnowledgeEdit::Status::stale: return 409;
    case KnowledgeEdit::Status::failed: return 500;
  }
  return 500;
}

HriOpResult edit_result(const KnowledgeEdit& r) {
  json j{{"status", std::string(to_string(r.status))}, {"version", r.version}};
  if (r.ok()) {
    j["message"] = r.message;
    j["entry_version"] = r.entry_version;
  } else {
    j["error"] = r.message;
    if (!r.errors.empty()) j["errors"] = errors_json(r.errors);
    if (r.status == KnowledgeEdit::Status::stale) {
      j["entry_version"] = r.entry_version;
      j["current"] = r.current ? entry_json(*r.current) : json(nullptr);
    }
  }
  return {http_status(r.status), std::move(j)};
}

HriOpResult bad(std::string message) { return {400, json{{"error", std::move(message)}}}; }

std::optional<std::uint64_t> version_of(const json& body) {
  if (!body.contains("version") || !body["version"].is_number_unsigned()) return std::nullopt;
  return body["version"].get<std::uint64_t>();
}

std::string author_of(const json& body) {
  return body.contains("author") && body["author"].is_string() ? body["author"].get<std::string>() : std::string();
}

json change_json(const KnowledgeChange& c) {
  return json{{"version", c.version},
              {"time", c.time_utc},
              {"author", c.author},
              {"op", std::string(to_string(c.kind))},
              {"id", c.id},
              {"before", c.before ? entry_json(*c.before) : json(nullptr)},
              {"after", c.after ? entry_json(*c.after) : json(nullptr)}};
}

}  // namespace


bool is_hri_op(std::string_view op) noexcept {
  return op == "rkms.list" || op == "rkms.get" || op == "rkms.add" || op == "rkms.edit" || op == "rkms.delete" ||
         op == "rkms.history" || op == "touch" || op == "ask";
}

HriOpResult handle_hri_op(HriService* hri, std::string_view op, const json& body, const std::function<void(std::string)>& note) {
  if (hri == nullptr) {
    return {404, json{{"error", std::string(op) + ": this robot has no HRI knowledge store (a module of the robot implementing "
                                                  "tripodal::HriService, docs/hri.md)"}}};
  }
  KnowledgeStore& store = hri->knowledge_store();
  if (op == "rkms.list") {
    std::string query;
    if (body.contains("query")) {
      if (!body["query"].is_string()) return bad("rkms.list: \"query\" must be a string");
      query = body["query"].get<std::string>();
      if (query.size() > 200) return bad("rkms.list: \"query\" is " + std::to_string(query.size()) + " bytes; expected at most 200");
    }
    json entries = json::array();
    for (const VersionedEntry& v : store.search(query)) entries.push_back(versioned_json(v));
    return {200, json{{"version", store.version()}, {"file", store.file().filename().string()}, {"entries", std::move(entries)}}};
  }
  if (op == "rkms.get") {
    if (!body.contains("id") || !body["id"].is_string()) return bad("rkms.get: expected \"id\": an entry id");
    const auto v = store.get(body["id"].get<std::string>());
    if (!v) return {404, json{{"error", "rkms.get: there is no entry '" + body["id"].get<std::string>() + "'"}}};
    return {200, json{{"version", store.version()}, {"entry", versioned_json(*v)}}};
  }
  if (op == "rkms.history") {
    std::size_t limit = 0;
    if (body.contains("limit")) {
      if (!body["limit"].is_number_unsigned()) return bad("rkms.history: \"limit\" must be a whole number");
      limit = body["limit"].get<std::size_t>();
    }
    json changes = json::array();
    for (const KnowledgeChange& c : store.history(limit)) changes.push_back(change_json(c));
    return {200, json{{"version", store.version()}, {"changes", std::move(changes)}}};
  }
  if (op == "rkms.add" || op == "rkms.edit") {
    std::vector<KnowledgeFieldError> errors;
    auto entry = entry_from(body.contains("entry") ? body["entry"] : json(nullptr), errors);
    if (!entry) {
      HriOpResult r = bad(std::string(op) + ": the entry is not valid; nothing was saved");
      r.body["status"] = "invalid";
      r.body["errors"] = errors_json(errors);
      return r;
    }
    KnowledgeEdit r;
    if (op == "rkms.add") {
      r = store.add(*entry, author_of(body));
    } else {
      const auto version = version_of(body);
      if (!version) return bad("rkms.edit: expected \"version\": the entry's version you edited (from rkms.list)");
      const std::string id = body.contains("id") && body["id"].is_string() ? body["id"].get<std::string>() : entry->id;
      if (entry->id.empty()) entry->id = id;  // the entry of the id the request names
      r = store.edit(id, *entry, *version, author_of(body));
    }
    const bool changed = r.ok() && r.message.find("unchanged") == std::string::npos;
    if (changed) note("rkms: " + r.message + " by " + (author_of(body).empty() ? std::string("operator") : author_of(body)));
    return edit_result(r);
  }
  if (op == "rkms.delete") {
    if (!body.contains("id") || !body["id"].is_string()) return bad("rkms.delete: expected \"id\": an entry id");
    const auto version = version_of(body);
    if (!version) return bad("rkms.delete: expected \"version\": the entry's version you read (from rkms.list)");
    const KnowledgeEdit r = store.remove(body["id"].get<std::string>(), *version, author_of(body));
    if (r.ok()) note("rkms: " + r.message + " by " + (author_of(body).empty() ? std::string("operator") : author_of(body)));
    return edit_result(r);
  }
  if (op == "touch") {
    // The big buttons: the first question form of the first entries that have one.
    json questions = json::array();
    for (const VersionedEntry& v : store.entries()) {
      if (questions.size() >= kTouchQuestions) break;
      if (!v.entry.questions.empty()) questions.push_back(v.entry.questions.front());
    }
    return {200, json{{"robot", store.base().robot()}, {"voice", hri->voice() != nullptr}, {"questions", std::move(questions)}}};
  }
  // ask
  if (!body.contains("text") || !body["text"].is_string()) return bad("ask: expected \"text\": what the visitor typed");
  const HriReply reply = hri->ask(body["text"].get<std::string>());
  json j{{"kind", std::string(to_string(reply.kind))},
         {"text", reply.text},
         {"entry", reply.entry_id},
         {"task", reply.task},
         {"confidence", reply.confidence},
         {"topics", reply.closest_topics},
         {"voice", hri->voice() != nullptr}};
  if (reply.kind == HriReply::Kind::task_started || (reply.kind == HriReply::Kind::answered && !reply.task.empty())) note("hri: touch screen: task " + reply.task + " started");
  if (body.contains("speak") && body["speak"].is_boolean() && body["speak"].get<bool>()) {
    if (SpeechSynthesizer* voice = hri->voice()) {
      try {
        j["audio"] = base64(wav_bytes(voice->synthesize(reply.text)));
      } catch (const std::exception& e) {
        j["voice_error"] = std::string("the voice failed: ") + e.what();
      }
    }
  }
  return {200, std::move(j)};
}

}  // namespace tripodal::monitor
