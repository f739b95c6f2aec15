// Task templates of the deliberate layer: how a command in plain words ("clean the room 3211",
// "carry the document box from room 2111 to 2133") becomes a Plan of process modules. Templates
// are configuration (YAML); the planner matches a command against their patterns, binds the
// slots, expands foreach loops with the robot's knowledge (rooms, sections) and substitutes
// parameters. A command that is not understood yields an explanation, never a plan.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/planner/plan.hpp"

namespace tripodal {

/// What the planner may ask the rest of the robot while expanding a template: the items of a
/// named list for an argument, e.g. sections("3211") from the section splitter, or rooms("") from
/// the map's regions.
class TaskKnowledge {
 public:
  struct ListResult {
    bool ok = false;
    std::vector<std::string> items;
    std::string error;  ///< when !ok: e.g. "unknown room '3299' (known: 2111, 2133, 3211)"
  };
  virtual ~TaskKnowledge() = default;
  [[nodiscard]] virtual ListResult list(std::string_view function, std::string_view argument) const = 0;
  /// Every argument `function` knows ("node" -> 0, 1, 2), for telling a user what is possible
  /// (the HRI's refusals); empty when the knowledge cannot enumerate them.
  [[nodiscard]] virtual std::vector<std::string> known(std::string_view /*function*/) const { return {}; }
};

/// One word of a command pattern: a literal ("clean"), an optional literal ("[the]"), a slot
/// capturing one word ("{room}") or a list slot capturing one or more ("{rooms...}").
struct PatternToken {
  enum class Kind { word, optional_word, slot, list_slot };
  Kind kind = Kind::word;
  std::string text;  ///< the word (lower case) or the slot name
};

struct CommandPattern {
  std::string text;
  std::vector<PatternToken> tokens;
  SourceLocation where;
};

/// A plan element of a template: a process with parameter templates ("{room}", "{section}.entry"),
/// a foreach over a list ("{rooms}" or "sections({room})") with a body, or a parallel group of
/// processes.
struct TemplateNode {
  enum class Kind { process, foreach, parallel };
  Kind kind = Kind::process;
  std::string process;
  std::vector<BindingParam> params;
  std::string variable;   ///< foreach
  std::string list_expr;  ///< foreach
  std::vector<TemplateNode> body;  ///< foreach body; parallel branches
  SourceLocation where;
};

struct TaskTemplate {
  std::string name;
  std::string description;
  std::vector<CommandPattern> commands;
  std::vector<TemplateNode> plan;
  SourceLocation where;
};

/// The answer to a command.
struct Understanding {
  bool understood = false;
  std::string task;                           ///< template name
  std::map<std::string, std::string> slots;   ///< captured words
  Plan plan;                                  ///< when understood
  std::string explanation;  ///< when not: what was understood, what was expected, what is possible
};

struct TaskLoadOptions {
  /// When set, a process name the predicate rejects is an error ("unknown process 'PrCleening'").
  std::function<bool(std::string_view)> is_known_process;
};

class TaskLibrary {
 public:
  /// Loads templates from a YAML file (format in docs/planner.md); throws ConfigError listing
  /// every error with file:line:col.
  static TaskLibrary load(const std::filesystem::path& file, const TaskLoadOptions& options = {});
  static TaskLibrary load_from_string(std::string_view yaml, std::string_view name,
                                      const TaskLoadOptions& options = {});

  [[nodiscard]] const std::vector<TaskTemplate>& templates() const noexcept { return templates_; }

  /// Matches `command` (case-insensitive, punctuation tolerant) and expands the first template
  /// that matches. Never throws for a bad command: the explanation says what went wrong.
  [[nodiscard]] Understanding understand(std::string_view command, const TaskKnowledge& knowledge) const;

  /// Every accepted command form, for help texts: "clean [the] room {room}", ...
  [[nodiscard]] std::vector<std::string> command_forms() const;

 private:
  std::vector<TaskTemplate> templates_;
};

}  // namespace tripodal
