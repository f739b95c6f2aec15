// The Robot Knowledge Management System's store (paper, section 4): what the HRI module of the
// deliberate layer answers from. Entries (keywords, question forms, an answer with {provider}
// placeholders, an optional task command for the planner) are kept in an XML file (configs/hri/,
// schema configs/hri/rkms.xsd, docs/hri.md) that carries a version number for concurrent edits.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal {

/// One piece of knowledge: "who are you?" -> "I am Jinny, ...".
struct KnowledgeEntry {
  std::string id;     ///< unique in the base: letters, digits, '_', '-', '.'
  std::string topic;  ///< a few words offered when an utterance is not understood ("the weather")
  std::vector<std::string> keywords;   ///< words or short phrases that point at this entry
  std::vector<std::string> questions;  ///< question forms, as a visitor would ask them
  /// What the robot says; "{name}" is replaced by the value of the provider `name` ({time},
  /// {battery}, {weather}); "{{" and "}}" stand for braces.
  std::string answer;
  /// A task command handed to the planner after answering ("guide me to node 1"); empty for none.
  std::string action;
  SourceLocation where;  ///< the <entry> element, when loaded from a file

  friend bool operator==(const KnowledgeEntry& a, const KnowledgeEntry& b) {
    return a.id == b.id && a.topic == b.topic && a.keywords == b.keywords && a.questions == b.questions &&
           a.answer == b.answer && a.action == b.action;
  }
};

/// A placeholder of an answer: the provider's name and where it starts in the answer (bytes).
struct AnswerPlaceholder {
  std::string name;
  std::size_t offset = 0;
};

/// The placeholders of an answer text in order, or the error ("unclosed '{' at byte 12").
struct PlaceholderScan {
  std::vector<AnswerPlaceholder> placeholders;
  std::string error;
  std::size_t error_offset = 0;
};
[[nodiscard]] PlaceholderScan scan_placeholders(std::string_view answer);

/// A problem of one field of an entry: `field` is "id", "topic", "keywords[2]", "questions[0]",
/// "answer" or "action", so an editor can put the message beside the field that is wrong.
struct KnowledgeFieldError {
  std::string field;
  std::string message;
  friend bool operator==(const KnowledgeFieldError&, const KnowledgeFieldError&) = default;
};

/// The rules the loader (and configs/hri/rkms.xsd) apply to an entry, however it was made: an id
/// of letters, digits, '_', '-', '.'; a topic; at least one keyword or question, none empty and no
/// keyword holding a comma; an answer with well-formed placeholders. Empty when the entry is valid.
[[nodiscard]] std::vector<KnowledgeFieldError> knowledge_entry_errors(const KnowledgeEntry& entry);

/// Thrown by KnowledgeBase::save when the file changed since this copy was loaded: the version
/// on disk is not the one the copy was read at. The file is left as it was.
class StaleVersionError : public std::runtime_error {
 public:
  StaleVersionError(const std::string& file, std::uint64_t expected, std::uint64_t found);
  [[nodiscard]] std::uint64_t expected() const noexcept { return expected_; }
  [[nodiscard]] std::uint64_t found() const noexcept { return found_; }

 private:
  std::uint64_t expected_;
  std::uint64_t found_;
};

class KnowledgeBase {
 public:
  /// Reads a knowledge file; throws ConfigError listing every problem at FILE:LINE:COL (malformed
  /// XML, unknown elements or attributes, missing or duplicate ids, empty answers, bad placeholders).
  static KnowledgeBase load(const std::filesystem::path& file);
  static KnowledgeBase load_from_string(std::string_view xml, std::string_view name);

  [[nodiscard]] const std::vector<KnowledgeEntry>& entries() const noexcept { return entries_; }
  [[nodiscard]] const KnowledgeEntry* find(std::string_view id) const noexcept;
  /// The version this copy was loaded at (or last saved as); 0 for a new base.
  [[nodiscard]] std::uint64_t version() const noexcept { return version_; }
  [[nodiscard]] const std::string& robot() const noexcept { return robot_; }
  void set_robot(std::string robot) { robot_ = std::move(robot); }

  /// Adds `entry`, or replaces the entry of the same id. Throws std::invalid_argument (saying
  /// what is wrong, field by field: knowledge_entry_errors) for an entry the loader would refuse;
  /// the base is then unchanged.
  void put(KnowledgeEntry entry);
  /// Removes the entry `id`; false when there is none.
  bool remove(std::string_view id);

  /// The base as a knowledge file (the format load reads), with `version`.
  [[nodiscard]] std::string to_xml(std::uint64_t version) const;

  /// Writes the base to `file` as version() + 1, atomically: a temporary file in the same folder
  /// is written, flushed to disk and renamed over `file`, so a crash leaves the old file or the
  /// new one, never half of one. Savers of the same file are serialised by a lock file
  /// (`file`.lock). Refuses with StaleVersionError, writing nothing, when `file` exists with a
  /// version other than version() (someone saved since this copy was read); a missing file is
  /// version 0. Throws ConfigError when the file on disk cannot be read, std::system_error when
  /// it cannot be written, std::invalid_argument (naming the entry, the field and the character's
  /// place, writing nothing) when a text is not one XML can hold (find_xml_text_fault). On success
  /// version() is the new version.
  void save(const std::filesystem::path& file);

 private:
  std::vector<KnowledgeEntry> entries_;
  std::uint64_t version_ = 0;
  std::string robot_;
};

}  // namespace tripodal
