// The RKMS's administration store (hri area, deliberate layer): the knowledge file of a robot
// edited while the robot runs — add, edit, delete entries, each change validated, saved atomically
// (KnowledgeBase::save), versioned per entry so a stale edit is refused, and recorded in a history.
// The monitor's web administration (docs/monitor.md) is one client of it; it needs no web server.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/hri/knowledge_base.hpp"

namespace tripodal {

/// Bounds on what an editor may put in an entry (bytes of UTF-8). The loader has none; these keep
/// a typing accident or a hostile client from growing the robot's knowledge file without bound.
struct KnowledgeLimits {
  std::size_t max_id_bytes = 64;
  std::size_t max_topic_bytes = 200;
  std::size_t max_keywords = 64;
  std::size_t max_keyword_bytes = 100;
  std::size_t max_questions = 64;
  std::size_t max_question_bytes = 500;
  std::size_t max_answer_bytes = 4000;
  std::size_t max_action_bytes = 500;
  std::size_t max_author_bytes = 64;
};

/// The loader's rules (knowledge_entry_errors) and more, for an entry that comes from an editor:
/// every field is UTF-8 text without control characters (line breaks and tabs allowed in answers
/// and questions: they survive the XML file), within `limits`. Empty when valid.
[[nodiscard]] std::vector<KnowledgeFieldError> validate_knowledge_entry(const KnowledgeEntry& entry,
                                                                        const KnowledgeLimits& limits = {});

/// An entry with the version of the base at which it was last added or edited.
struct VersionedEntry {
  KnowledgeEntry entry;
  std::uint64_t version = 0;
};

/// One change of the history.
struct KnowledgeChange {
  enum class Kind { add, edit, remove };
  std::uint64_t version = 0;  ///< the base's version the change made (the file's version="...")
  std::string time_utc;       ///< "2026-11-26T14:05:00Z"
  std::string author;         ///< who asked for it (free text the client gives; "operator" by default)
  Kind kind = Kind::add;
  std::string id;
  std::optional<KnowledgeEntry> before;  ///< edit, remove
  std::optional<KnowledgeEntry> after;   ///< add, edit
};
[[nodiscard]] std::string_view to_string(KnowledgeChange::Kind kind) noexcept;

/// What a change request came to.
struct KnowledgeEdit {
  enum class Status {
    ok,
    invalid,    ///< the entry breaks a rule: `errors`, field by field; nothing changed
    not_found,  ///< edit or delete of an id the base does not have
    exists,     ///< add of an id the base already has
    stale,      ///< based on a version that is not the entry's (or the file changed on disk)
    failed,     ///< the file could not be written: the old file and the store are unchanged
  };
  Status status = Status::ok;
  std::string message;                       ///< for a person: what happened, what to do
  std::vector<KnowledgeFieldError> errors;   ///< invalid
  std::uint64_t version = 0;                 ///< the base's version now
  std::uint64_t entry_version = 0;           ///< ok: the entry's new version; stale: its version now
  std::optional<KnowledgeEntry> current;     ///< stale: the entry as it is now (none if deleted)
  [[nodiscard]] bool ok() const noexcept { return status == Status::ok; }
};
[[nodiscard]] std::string_view to_string(KnowledgeEdit::Status status) noexcept;

struct KnowledgeStoreOptions {
  KnowledgeLimits limits;
  /// The history: one JSON object a line, appended and flushed after each saved change. Empty:
  /// the knowledge file's path with ".history" added (jinny.xml.history).
  std::filesystem::path history_file;
  /// The time stamped on changes (the wall clock by default; tests inject theirs).
  std::function<std::chrono::system_clock::time_point()> now;
};

/// Thread-safe: every method takes the store's lock, so the robot's HRI may read while the web
/// administration writes. A change is applied to a copy, saved, and only then becomes the store's
/// state: a refused or failed change leaves both the file and the store as they were.
class KnowledgeStore {
 public:
  /// Loads `file` (ConfigError, located, when it does not load) and its history. Each entry's
  /// version is the version of the last change to it in the history; when the history does not
  /// end at the file's version (the file was edited by hand), every entry gets the file's version.
  /// A history line that does not parse (a crash in the middle of an append) is skipped.
  explicit KnowledgeStore(std::filesystem::path file, KnowledgeStoreOptions options = {});

  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }
  [[nodiscard]] const std::filesystem::path& history_file() const noexcept { return options_.history_file; }
  [[nodiscard]] const KnowledgeLimits& limits() const noexcept { return options_.limits; }
  /// The base's version: the version="..." of the file, one more at each saved change.
  [[nodiscard]] std::uint64_t version() const;
  /// A copy of the base as it is now (for indexing it).
  [[nodiscard]] KnowledgeBase base() const;
  [[nodiscard]] std::vector<VersionedEntry> entries() const;
  [[nodiscard]] std::optional<VersionedEntry> get(std::string_view id) const;
  /// The entries whose id, topic, keywords, questions, answer or action contain every word of
  /// `query` (case-insensitive); all entries for an empty query. In the base's order.
  [[nodiscard]] std::vector<VersionedEntry> search(std::string_view query) const;

  /// Adds a new entry. `exists` when the id is taken.
  KnowledgeEdit add(KnowledgeEntry entry, std::string_view author);
  /// Replaces entry `id` by `entry` (same id: an id is not renamed, delete and add instead), when
  /// `based_on` is the entry's version; otherwise `stale` with the entry as it is now.
  KnowledgeEdit edit(std::string_view id, KnowledgeEntry entry, std::uint64_t based_on, std::string_view author);
  /// Deletes entry `id` when `based_on` is its version.
  KnowledgeEdit remove(std::string_view id, std::uint64_t based_on, std::string_view author);

  /// The changes, oldest first; the last `limit` of them when `limit` > 0.
  [[nodiscard]] std::vector<KnowledgeChange> history(std::size_t limit = 0) const;

  /// A check of the robot's own on top of validate_knowledge_entry (StoreBackedHri refuses an
  /// answer naming a provider the robot lacks). Called under the store's lock: it must not call
  /// back into the store.
  void set_validator(std::function<std::vector<KnowledgeFieldError>(const KnowledgeEntry&)> validator);

  /// Reads the file again (after someone edited it by hand). Throws ConfigError when it does not
  /// load; the store is then unchanged.
  void reload();

 private:
  KnowledgeEdit commit(KnowledgeBase next, KnowledgeChange change);
  void load_locked();
  [[nodiscard]] std::uint64_t entry_version_locked(std::string_view id) const;

  std::filesystem::path file_;
  KnowledgeStoreOptions options_;
  mutable std::mutex mutex_;
  KnowledgeBase base_;
  std::vector<std::pair<std::string, std::uint64_t>> entry_versions_;  // id -> version, any order
  std::vector<KnowledgeChange> history_;
  std::function<std::vector<KnowledgeFieldError>(const KnowledgeEntry&)> validator_;
};

}  // namespace tripodal
