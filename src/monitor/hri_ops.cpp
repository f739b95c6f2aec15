#include "hri_ops.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <utility>
#include <variant>
#include <vector>

#include "wire.hpp"

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


bool is_hri_op(const OperatorCommand& command) noexcept {
  return std::holds_alternative<RkmsListRequest>(command) || std::holds_alternative<RkmsGetRequest>(command) ||
         std::holds_alternative<RkmsAddRequest>(command) || std::holds_alternative<RkmsEditRequest>(command) ||
         std::holds_alternative<RkmsDeleteRequest>(command) || std::holds_alternative<RkmsHistoryRequest>(command) ||
         std::holds_alternative<TouchRequest>(command) || std::holds_alternative<AskRequest>(command);
}

namespace {

std::string who(const std::string& author) { return author.empty() ? std::string("operator") : author; }

KnowledgeEntry knowledge_entry(const EntryFields& f) {
  KnowledgeEntry e;
  e.id = f.id;
  e.topic = f.topic;
  e.keywords = f.keywords;
  e.questions = f.questions;
  e.answer = f.answer;
  e.action = f.action;
  return e;
}

struct HriOps {
  HriService& hri;
  KnowledgeStore& store;
  const std::function<void(std::string)>& note;

  HriOpResult operator()(const RkmsListRequest& r) const {
    json entries = json::array();
    for (const VersionedEntry& v : store.search(r.query)) entries.push_back(versioned_json(v));
    return {200, json{{"version", store.version()}, {"file", store.file().filename().string()}, {"entries", std::move(entries)}}};
  }
  HriOpResult operator()(const RkmsGetRequest& r) const {
    const auto v = store.get(r.id);
    if (!v) return {404, json{{"error", "rkms.get: there is no entry '" + r.id + "'"}}};
    return {200, json{{"version", store.version()}, {"entry", versioned_json(*v)}}};
  }
  HriOpResult operator()(const RkmsHistoryRequest& r) const {
    // The newest changes first, as many as the limit and the answer's byte budget allow (a change
    // holds two entries of up to ~45 KB each): a long history never makes an answer the server
    // cannot send.
    const std::vector<KnowledgeChange> all = store.history(r.limit);
    std::vector<json> newest;
    std::size_t bytes = 0;
    for (auto it = all.rbegin(); it != all.rend(); ++it) {
      json c = change_json(*it);
      const std::size_t size = c.dump().size() + 1;
      if (bytes + size > OperatorBudgets::kMaxHistoryAnswerBytes) break;
      bytes += size;
      newest.push_back(std::move(c));
    }
    const std::size_t omitted = all.size() - newest.size();
    json changes = json::array();
    for (auto it = newest.rbegin(); it != newest.rend(); ++it) changes.push_back(std::move(*it));
    return {200, json{{"version", store.version()}, {"changes", std::move(changes)}, {"omitted", omitted}}};
  }
  HriOpResult operator()(const RkmsAddRequest& r) const { return changed(store.add(knowledge_entry(r.entry), r.author), r.author); }
  HriOpResult operator()(const RkmsEditRequest& r) const {
    KnowledgeEntry entry = knowledge_entry(r.entry);
    if (entry.id.empty()) entry.id = r.id;  // the entry of the id the request names
    return changed(store.edit(r.id, std::move(entry), r.version, r.author), r.author);
  }
  HriOpResult operator()(const RkmsDeleteRequest& r) const { return changed(store.remove(r.id, r.version, r.author), r.author); }
  HriOpResult operator()(const TouchRequest&) const {
    // The big buttons: the first question form of the first entries that have one.
    json questions = json::array();
    for (const VersionedEntry& v : store.entries()) {
      if (questions.size() >= kTouchQuestions) break;
      if (!v.entry.questions.empty()) questions.push_back(v.entry.questions.front());
    }
    return {200, json{{"robot", store.base().robot()}, {"voice", hri.voice() != nullptr}, {"questions", std::move(questions)}}};
  }
  HriOpResult operator()(const AskRequest& r) const {
    const HriReply reply = hri.ask(r.text);
    json j{{"kind", std::string(to_string(reply.kind))},
           {"text", reply.text},
           {"entry", reply.entry_id},
           {"task", reply.task},
           {"confidence", reply.confidence},
           {"topics", reply.closest_topics},
           {"voice", hri.voice() != nullptr}};
    if (reply.kind == HriReply::Kind::task_started || (reply.kind == HriReply::Kind::answered && !reply.task.empty())) {
      note("hri: touch screen: task " + reply.task + " started");
    }
    if (r.speak) {
      if (SpeechSynthesizer* voice = hri.voice()) {
        try {
          j["audio"] = base64(wav_bytes(voice->synthesize(reply.text)));
        } catch (const std::exception& e) {
          j["voice_error"] = std::string("the voice failed: ") + e.what();
        }
      }
    }
    return {200, std::move(j)};
  }
  template <class Other>
  HriOpResult operator()(const Other&) const {
    return {500, json{{"error", "not an HRI op"}}};
  }

  HriOpResult changed(const KnowledgeEdit& r, const std::string& author) const {
    if (r.ok() && r.message.find("unchanged") == std::string::npos) note("rkms: " + r.message + " by " + who(author));
    return edit_result(r);
  }
};

}  // namespace

HriOpResult handle_hri_op(HriService* hri, std::string_view op, const OperatorCommand& command, const std::function<void(std::string)>& note) {
  if (hri == nullptr) {
    return {404, json{{"error", std::string(op) + ": this robot has no HRI knowledge store (a module of the robot implementing "
                                                  "tripodal::HriService, docs/hri.md)"}}};
  }
  return std::visit(HriOps{*hri, hri->knowledge_store(), note}, command);
}

}  // namespace tripodal::monitor
