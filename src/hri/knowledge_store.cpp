#include "tripodal/hri/knowledge_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <system_error>
#include <utility>

#include <nlohmann/json.hpp>

#include "text.hpp"
#include "tripodal/core/xml_text.hpp"

namespace tripodal {

namespace {

using nlohmann::json;

std::string trimmed(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

// An XML reader turns "\r\n" and a lone "\r" into "\n": the store does it first, so what it
// keeps is what a reload of the file gives back.
std::string multi_line(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\r') {
      out += '\n';
      if (i + 1 < s.size() && s[i + 1] == '\n') ++i;
    } else {
      out += s[i];
    }
  }
  return trimmed(out);
}

KnowledgeEntry normalised(KnowledgeEntry e) {
  e.topic = trimmed(e.topic);
  for (auto& k : e.keywords) k = trimmed(k);
  for (auto& q : e.questions) q = multi_line(q);
  e.answer = multi_line(e.answer);
  e.action = trimmed(e.action);
  e.where = {};
  return e;
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

json entry_json(const KnowledgeEntry& e) {
  return json{{"id", e.id}, {"topic", e.topic}, {"keywords", e.keywords}, {"questions", e.questions}, {"answer", e.answer}, {"action", e.action}};
}

// The history file is read back field by field with the types checked (json::value() throws on a
// field of another type): a line someone edited by hand is skipped, it cannot stop the store.
std::optional<std::string> text_of(const json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return std::string();
  if (!it->is_string()) return std::nullopt;
  return it->get<std::string>();
}

bool texts_of(const json& j, const char* key, std::vector<std::string>& out) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return true;
  if (!it->is_array()) return false;
  for (const json& v : *it) {
    if (!v.is_string()) return false;
    out.push_back(v.get<std::string>());
  }
  return true;
}

std::optional<KnowledgeEntry> entry_from_json(const json& j) {
  if (!j.is_object()) return std::nullopt;
  KnowledgeEntry e;
  const auto id = text_of(j, "id"), topic = text_of(j, "topic"), answer = text_of(j, "answer"), action = text_of(j, "action");
  if (!id || !topic || !answer || !action || !texts_of(j, "keywords", e.keywords) || !texts_of(j, "questions", e.questions)) {
    return std::nullopt;
  }
  e.id = *id;
  e.topic = *topic;
  e.answer = *answer;
  e.action = *action;
  return e;
}

std::string utc(std::chrono::system_clock::time_point t) {
  const std::time_t tt = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return {buf, n};
}

std::optional<KnowledgeChange::Kind> kind_of(std::string_view s) {
  if (s == "add") return KnowledgeChange::Kind::add;
  if (s == "edit") return KnowledgeChange::Kind::edit;
  if (s == "delete") return KnowledgeChange::Kind::remove;
  return std::nullopt;
}

void append_line(const std::filesystem::path& file, const std::string& line) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), "cannot open " + file.string());
  std::size_t written = 0;
  int err = 0;
  while (written < line.size()) {
    const ssize_t n = ::write(fd, line.data() + written, line.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    written += static_cast<std::size_t>(n);
  }
  if (err == 0 && ::fsync(fd) != 0) err = errno;
  ::close(fd);
  if (err != 0) throw std::system_error(err, std::generic_category(), "cannot append to " + file.string());
}

// Bytes of a field, a line's worth of text: no line breaks or tabs (ids, topics, keywords and
// actions are written in attributes or on one line, and read back trimmed).
void check_text(std::vector<KnowledgeFieldError>& out, const std::string& field, std::string_view text, std::size_t max_bytes,
                bool lines_allowed) {
  if (text.size() > max_bytes) {
    out.push_back({field, field + " is " + std::to_string(text.size()) + " bytes long; expected at most " + std::to_string(max_bytes)});
    return;
  }
  // XML's characters, so nothing the store accepts can fail to save or to load again.
  if (const auto fault = find_xml_text_fault(text, true)) {
    out.push_back({field, field + " is not text: " + describe(*fault) + "; expected UTF-8 without control characters"});
    return;
  }
  if (!lines_allowed && text.find_first_of("\t\r\n") != std::string_view::npos) {
    out.push_back({field, field + " holds a line break or a tab; expected one line"});
  }
}

}  // namespace

std::vector<KnowledgeFieldError> validate_knowledge_entry(const KnowledgeEntry& e, const KnowledgeLimits& limits) {
  std::vector<KnowledgeFieldError> out;
  // Size and bytes first: the loader's rules below read the text, which must be text to be read.
  check_text(out, "id", e.id, limits.max_id_bytes, false);
  check_text(out, "topic", e.topic, limits.max_topic_bytes, false);
  if (e.keywords.size() > limits.max_keywords) {
    out.push_back({"keywords", std::to_string(e.keywords.size()) + " keywords; expected at most " + std::to_string(limits.max_keywords)});
  } else {
    for (std::size_t i = 0; i < e.keywords.size(); ++i) {
      check_text(out, "keywords[" + std::to_string(i) + "]", e.keywords[i], limits.max_keyword_bytes, false);
    }
  }
  if (e.questions.size() > limits.max_questions) {
    out.push_back({"questions", std::to_string(e.questions.size()) + " questions; expected at most " + std::to_string(limits.max_questions)});
  } else {
    for (std::size_t i = 0; i < e.questions.size(); ++i) {
      check_text(out, "questions[" + std::to_string(i) + "]", e.questions[i], limits.max_question_bytes, true);
    }
  }
  check_text(out, "answer", e.answer, limits.max_answer_bytes, true);
  check_text(out, "action", e.action, limits.max_action_bytes, false);
  if (!out.empty()) return out;
  return knowledge_entry_errors(e);
}

std::string_view to_string(KnowledgeChange::Kind kind) noexcept {
  switch (kind) {
    case KnowledgeChange::Kind::add: return "add";
    case KnowledgeChange::Kind::edit: return "edit";
    case KnowledgeChange::Kind::remove: return "delete";
  }
  return "?";
}

std::string_view to_string(KnowledgeEdit::Status status) noexcept {
  switch (status) {
    case KnowledgeEdit::Status::ok: return "ok";
    case KnowledgeEdit::Status::invalid: return "invalid";
    case KnowledgeEdit::Status::not_found: return "not_found";
    case KnowledgeEdit::Status::exists: return "exists";
    case KnowledgeEdit::Status::stale: return "stale";
    case KnowledgeEdit::Status::failed: return "failed";
  }
  return "?";
}

KnowledgeStore::KnowledgeStore(std::filesystem::path file, KnowledgeStoreOptions options)
    : file_(std::move(file)), options_(std::move(options)) {
  if (options_.history_file.empty()) options_.history_file = file_.string() + ".history";
  if (!options_.now) options_.now = [] { return std::chrono::system_clock::now(); };
  const std::lock_guard lock(mutex_);
  load_locked();
}

void KnowledgeStore::load_locked() {
  KnowledgeBase base = KnowledgeBase::load(file_);
  std::vector<KnowledgeChange> history;
  if (std::ifstream in(options_.history_file); in) {
    std::string line;
    while (std::getline(in, line)) {
      const json j = json::parse(line, nullptr, false);
      if (j.is_discarded() || !j.is_object() || !j.contains("version") || !j["version"].is_number_unsigned()) continue;
      const auto op = text_of(j, "op"), time = text_of(j, "time"), author = text_of(j, "author"), id = text_of(j, "id");
      if (!op || !time || !author || !id) continue;
      const auto kind = kind_of(*op);
      if (!kind) continue;
      KnowledgeChange c;
      c.version = j["version"].get<std::uint64_t>();
      c.time_utc = *time;
      c.author = *author;
      c.kind = *kind;
      c.id = *id;
      bool readable = true;
      for (const auto& [key, slot] : {std::pair{"before", &c.before}, std::pair{"after", &c.after}}) {
        const auto it = j.find(key);
        if (it == j.end() || it->is_null()) continue;
        *slot = entry_from_json(*it);
        readable = readable && slot->has_value();
      }
      if (!readable) continue;
      history.push_back(std::move(c));
    }
  }
  // Entry versions from the history, when it tells the story of this very file; otherwise
  // (edited by hand since) every entry counts as changed at the file's version: an editor holding
  // an older version is then refused, never wrongly let through.
  std::vector<std::pair<std::string, std::uint64_t>> versions;
  const bool history_fits = !history.empty() && history.back().version == base.version();
  const std::uint64_t unrecorded = history_fits ? history.front().version - 1 : base.version();
  for (const KnowledgeEntry& e : base.entries()) {
    std::uint64_t v = unrecorded;
    if (history_fits) {
      for (const KnowledgeChange& c : history) {
        if (c.id == e.id && c.kind != KnowledgeChange::Kind::remove) v = c.version;
      }
    }
    versions.emplace_back(e.id, v);
  }
  base_ = std::move(base);
  entry_versions_ = std::move(versions);
  history_ = std::move(history);
}

void KnowledgeStore::reload() {
  const std::lock_guard lock(mutex_);
  load_locked();
}

void KnowledgeStore::set_validator(std::function<std::vector<KnowledgeFieldError>(const KnowledgeEntry&)> validator) {
  const std::lock_guard lock(mutex_);
  validator_ = std::move(validator);
}

std::uint64_t KnowledgeStore::version() const {
  const std::lock_guard lock(mutex_);
  return base_.version();
}

KnowledgeBase KnowledgeStore::base() const {
  const std::lock_guard lock(mutex_);
  return base_;
}

std::uint64_t KnowledgeStore::entry_version_locked(std::string_view id) const {
  for (const auto& [name, v] : entry_versions_) {
    if (name == id) return v;
  }
  return base_.version();
}

std::vector<VersionedEntry> KnowledgeStore::entries() const {
  const std::lock_guard lock(mutex_);
  std::vector<VersionedEntry> out;
  out.reserve(base_.entries().size());
  for (const KnowledgeEntry& e : base_.entries()) out.push_back({e, entry_version_locked(e.id)});
  return out;
}

std::optional<VersionedEntry> KnowledgeStore::get(std::string_view id) const {
  const std::lock_guard lock(mutex_);
  const KnowledgeEntry* e = base_.find(id);
  if (e == nullptr) return std::nullopt;
  return VersionedEntry{*e, entry_version_locked(id)};
}

std::vector<VersionedEntry> KnowledgeStore::search(std::string_view query) const {
  std::vector<std::string> terms;
  const std::string q = lower(query);
  std::size_t i = 0;
  while (i < q.size()) {
    const std::size_t b = q.find_first_not_of(" \t\r\n", i);
    if (b == std::string::npos) break;
    const std::size_t e = std::min(q.find_first_of(" \t\r\n", b), q.size());
    terms.push_back(q.substr(b, e - b));
    i = e;
  }
  const std::lock_guard lock(mutex_);
  std::vector<VersionedEntry> out;
  for (const KnowledgeEntry& e : base_.entries()) {
    std::string all = e.id + '\n' + e.topic + '\n' + e.answer + '\n' + e.action;
    for (const auto& k : e.keywords) all += '\n' + k;
    for (const auto& qf : e.questions) all += '\n' + qf;
    all = lower(all);
    const bool match = std::all_of(terms.begin(), terms.end(), [&](const std::string& t) { return all.find(t) != std::string::npos; });
    if (match) out.push_back({e, entry_version_locked(e.id)});
  }
  return out;
}

std::vector<KnowledgeChange> KnowledgeStore::history(std::size_t limit) const {
  const std::lock_guard lock(mutex_);
  if (limit == 0 || limit >= history_.size()) return history_;
  return {history_.end() - static_cast<std::ptrdiff_t>(limit), history_.end()};
}

namespace {

KnowledgeEdit refusal(KnowledgeEdit::Status status, std::string message, std::uint64_t version) {
  KnowledgeEdit r;
  r.status = status;
  r.message = std::move(message);
  r.version = version;
  return r;
}

std::string author_of(std::string_view author, const KnowledgeLimits& limits) {
  std::string a = trimmed(author);
  // Who asked is free text from a client: kept printable and short, it cannot break the log.
  if (a.empty() || a.size() > limits.max_author_bytes || !hri::is_text(a) || a.find_first_of("\t\r\n") != std::string::npos) {
    return "operator";
  }
  return a;
}

}  // namespace

KnowledgeEdit KnowledgeStore::add(KnowledgeEntry entry, std::string_view author) {
  entry = normalised(std::move(entry));
  const std::lock_guard lock(mutex_);
  auto errors = validate_knowledge_entry(entry, options_.limits);
  if (errors.empty() && validator_) errors = validator_(entry);
  if (!errors.empty()) {
    KnowledgeEdit r = refusal(KnowledgeEdit::Status::invalid, "the entry is not valid; nothing was saved", base_.version());
    r.errors = std::move(errors);
    return r;
  }
  if (base_.find(entry.id) != nullptr) {
    KnowledgeEdit r = refusal(KnowledgeEdit::Status::exists, "an entry '" + entry.id + "' exists already; edit it or choose another id",
                              base_.version());
    r.errors.push_back({"id", "the id '" + entry.id + "' is taken"});
    return r;
  }
  KnowledgeBase next = base_;
  KnowledgeChange change;
  change.kind = KnowledgeChange::Kind::add;
  change.id = entry.id;
  change.author = author_of(author, options_.limits);
  change.after = entry;
  next.put(std::move(entry));
  return commit(std::move(next), std::move(change));
}

KnowledgeEdit KnowledgeStore::edit(std::string_view id, KnowledgeEntry entry, std::uint64_t based_on, std::string_view author) {
  entry = normalised(std::move(entry));
  const std::lock_guard lock(mutex_);
  const KnowledgeEntry* old = base_.find(id);
  if (old == nullptr) return refusal(KnowledgeEdit::Status::not_found, "there is no entry '" + std::string(id) + "' (deleted?)", base_.version());
  const std::uint64_t now = entry_version_locked(id);
  if (based_on != now) {
    KnowledgeEdit r = refusal(KnowledgeEdit::Status::stale,
                              "entry '" + std::string(id) + "' was changed since you read it (you edited version " + std::to_string(based_on) +
                                  ", it is now at version " + std::to_string(now) + "); nothing was saved: reload it and apply your change again",
                              base_.version());
    r.entry_version = now;
    r.current = *old;
    return r;
  }
  auto errors = validate_knowledge_entry(entry, options_.limits);
  if (entry.id != id) errors.insert(errors.begin(), {"id", "an entry's id is not renamed ('" + std::string(id) + "' to '" + entry.id + "'): delete it and add a new one"});
  if (errors.empty() && validator_) errors = validator_(entry);
  if (!errors.empty()) {
    KnowledgeEdit r = refusal(KnowledgeEdit::Status::invalid, "the entry is not valid; nothing was saved", base_.version());
    r.errors = std::move(errors);
    return r;
  }
  if (entry == *old) {
    KnowledgeEdit r = refusal(KnowledgeEdit::Status::ok, "entry '" + std::string(id) + "' is unchanged; nothing to save", base_.version());
    r.entry_version = now;
    return r;
  }
  KnowledgeBase next = base_;
  KnowledgeChange change;
  change.kind = KnowledgeChange::Kind::edit;
  change.id = entry.id;
  change.author = author_of(author, options_.limits);
  change.before = *old;
  change.after = entry;
  next.put(std::move(entry));
  return commit(std::move(next), std::move(change));
}

KnowledgeEdit KnowledgeStore::remove(std::string_view id, std::uint64_t based_on, std::string_view author) {
  const std::lock_guard lock(mutex_);
  const KnowledgeEntry* old = base_.find(id);
  if (old == nullptr) return refusal(KnowledgeEdit::Status::not_found, "there is no entry '" + std::string(id) + "' (deleted already?)", base_.version());
  const std::uint64_t now = entry_version_locked(id);
  if (based_on != now) {
    KnowledgeEdit r = refusal(KnowledgeEdit::Status::stale,
                              "entry '" + std::string(id) + "' was changed since you read it (you read version " + std::to_string(based_on) +
                                  ", it is now at version " + std::to_string(now) + "); it was not deleted",
                              base_.version());
    r.entry_version = now;
    r.current = *old;
    return r;
  }
  KnowledgeBase next = base_;
  KnowledgeChange change;
  change.kind = KnowledgeChange::Kind::remove;
  change.id = std::string(id);
  change.author = author_of(author, options_.limits);
  change.before = *old;
  next.remove(id);
  return commit(std::move(next), std::move(change));
}

KnowledgeEdit KnowledgeStore::commit(KnowledgeBase next, KnowledgeChange change) {
  // `next` was copied at the store's version, so its save refuses when the file moved on (someone
  // edited it by hand): the store must be reloaded before it overwrites that.
  try {
    next.save(file_);
  } catch (const StaleVersionError& e) {
    return refusal(KnowledgeEdit::Status::stale, std::string(e.what()) + " (the file was changed outside this store)", base_.version());
  } catch (const std::exception& e) {
    return refusal(KnowledgeEdit::Status::failed, std::string("the knowledge file could not be saved; it is unchanged: ") + e.what(),
                   base_.version());
  }
  base_ = std::move(next);
  change.version = base_.version();
  change.time_utc = utc(options_.now());
  const bool removed = change.kind == KnowledgeChange::Kind::remove;
  entry_versions_.erase(std::remove_if(entry_versions_.begin(), entry_versions_.end(), [&](const auto& p) { return p.first == change.id; }),
                        entry_versions_.end());
  if (!removed) entry_versions_.emplace_back(change.id, change.version);

  KnowledgeEdit r;
  r.status = KnowledgeEdit::Status::ok;
  r.version = base_.version();
  r.entry_version = removed ? 0 : change.version;
  r.message = "entry '" + change.id + "' " + (removed ? "deleted" : change.kind == KnowledgeChange::Kind::add ? "added" : "saved") +
              " as version " + std::to_string(change.version);
  const json line{{"version", change.version},
                  {"time", change.time_utc},
                  {"author", change.author},
                  {"op", std::string(to_string(change.kind))},
                  {"id", change.id},
                  {"before", change.before ? entry_json(*change.before) : json(nullptr)},
                  {"after", change.after ? entry_json(*change.after) : json(nullptr)}};
  try {
    append_line(options_.history_file, line.dump() + "\n");
  } catch (const std::exception& e) {
    // The change is in the file already; the history keeps it in memory and says what was lost.
    r.message += "; its history record could not be written: " + std::string(e.what());
  }
  history_.push_back(std::move(change));
  return r;
}

}  // namespace tripodal
