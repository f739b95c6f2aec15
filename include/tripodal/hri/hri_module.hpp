// The HRI module of the deliberate layer (paper, section 4, CHri): every user input is a
// *reaction input*, answered by the HRI alone from the RKMS knowledge base, or a *command input*,
// handed to the planner as a task; when the planner refuses, its reason is spoken back in plain
// words. Inputs that are empty, too long or not text get a polite refusal and nothing runs.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/hri/answer_providers.hpp"
#include "tripodal/hri/knowledge_base.hpp"
#include "tripodal/hri/knowledge_index.hpp"
#include "tripodal/hri/speech.hpp"
#include "tripodal/planner/task_library.hpp"

namespace tripodal {

struct HriOptions {
  /// Below this confidence (KnowledgeIndex's coverage of the utterance) the HRI says it did not
  /// understand and offers the closest topics.
  double confidence_threshold = 0.5;
  /// An input that starts like a command ("take me to ...") but that the planner refuses is
  /// answered from the RKMS instead only when an entry with an action covers it this well
  /// ("take me to PSR-2"); otherwise the planner's refusal is spoken ("take me to node").
  double command_confidence_threshold = 0.75;
  /// How many topics a "did not understand" offers.
  std::size_t offered_topics = 3;
  /// The longest utterance considered (bytes); a longer one is refused unread.
  std::size_t max_utterance_bytes = 500;
  /// A recognised utterance less sure than this (SpeechRecognizer::Result::confidence) is not
  /// acted on: "Sorry, I did not catch that." A recognizer with a closed language model hears
  /// any sound as one of its sentences; the posterior is low when the sound was something else.
  double min_recognition_confidence = 0.002;
  /// When the recognizer's best sentence is not understood, its alternatives at most this much
  /// less likely (natural log of the path score ratio) are tried in order, and the first one
  /// understood is acted on. 0 turns the n-best list off.
  double max_alternative_log_gap = 1.0;
  /// No task without consent: a task from speech starts at once only when the command was parsed
  /// whole (every word of what was heard accounted for by the command grammar: no typo correction,
  /// not from the recognizer's alternatives, not an RKMS entry's action) and heard at least this
  /// surely (SpeechRecognizer::Result::confidence). Any other task from speech is asked about
  /// first: 'Did you say "..."? Please say yes or no.', carried out on a yes (confirm_task, then
  /// task_started or answered; task_cancelled on a no); any other input drops the question. A robot
  /// must not drive off on a misheard question. 0 never asks.
  double confirm_heard_tasks_below = 0.5;
  /// The planner's list of the places a visitor can be guided to ("node": TaskKnowledge::known, or
  /// the "(known: ...)" of the planner's refusal), and how a refusal offers them: "I can guide you
  /// to node 0, 1 or 2."
  std::string places_list = "node";
  std::string places_offer = "guide you to node";
  /// LED buttons (Table 3): each button's name and the request a press stands for ("hello" ->
  /// "Introduce yourself."). A press is handled as that input was typed.
  std::map<std::string, std::string, std::less<>> buttons;
  /// English lexical knowledge for the matcher (KnowledgeIndex): the system's WordNet and word
  /// list by default; null matches words only as the base has them.
  std::shared_ptr<const Lexicon> lexicon = Lexicon::system();
};

/// The robot's internal state as the HRI displays it to the visitor and the operator (paper,
/// section 4): the current task and its state, the process running, the last fault. Set by the
/// robot program from the planner's life cycle; read by the demo and the monitor.
struct InternalState {
  std::string task;        ///< "guide" ("" when idle)
  std::string task_state;  ///< "running", "succeeded", "failed", "cancelled"
  std::string process;     ///< "PrAutoMove(goal=node1)" ("" when none runs)
  std::string fault;       ///< the last fault message ("path blocked"; "" when none)
  friend bool operator==(const InternalState&, const InternalState&) = default;
};

/// One line for a display: "task guide: running | process PrAutoMove(goal=node1) | no fault".
[[nodiscard]] std::string display_text(const InternalState& state);

/// What the HRI did with one input.
struct HriReply {
  enum class Kind {
    answered,         ///< a reaction input answered from the RKMS (entry; maybe a task too)
    task_started,     ///< a command input the planner accepted
    task_refused,     ///< a command input the planner refused (text says why)
    not_understood,   ///< nothing matched well enough (text offers the closest topics)
    refused_input,    ///< empty, too long or not text: nothing ran
    confirm_task,     ///< a task heard with too little confidence: asked about (task; entry for an answer), not started
    task_cancelled,   ///< the visitor said no to the task asked about
  };
  Kind kind = Kind::not_understood;
  std::string text;      ///< what the robot says
  std::string entry_id;  ///< answered: the RKMS entry
  std::string task;      ///< the task the planner started (also for an entry's action); confirm_task: the one asked about
  Plan plan;             ///< when a task started
  double confidence = 0.0;
  std::vector<std::string> closest_topics;  ///< not_understood
};

[[nodiscard]] std::string_view to_string(HriReply::Kind kind) noexcept;

/// The last input the HRI handled and what it said, for its display (the monitor's HRI panel).
struct HriExchange {
  /// "typed" (handle), "heard" (handle_heard: the words recognised) or "button" (handle_button).
  std::string source;
  /// What came in: the text, the words heard, the button's name. An input the HRI refused unread
  /// (too long, not text) is described instead ("(1048576 bytes: too long)"), never copied.
  std::string input;
  HriReply::Kind kind = HriReply::Kind::not_understood;
  std::string reply;  ///< what the robot said
  std::string entry;  ///< the RKMS entry that answered ("" when none)
  std::string task;   ///< the task started or refused ("" when none)
  friend bool operator==(const HriExchange&, const HriExchange&) = default;
};

/// Everything the HRI displays: the robot's internal state and the last exchange.
struct HriDisplay {
  InternalState state;
  std::optional<HriExchange> last;  ///< none before the first input
};

/// Where accepted tasks go: the planner of the running robot. Returns an empty string when the
/// task started, otherwise the reason it could not (spoken back).
using TaskStarter = std::function<std::string(const Understanding&)>;

/// One input at a time (the HRI's own thread or the robot's deliberate loop): not thread-safe.
class HriModule {
 public:
  /// `tasks`, `knowledge` and `providers` must outlive the module; the base is indexed now (a
  /// changed base needs a new module). Throws ConfigError, at each entry's location, when an
  /// answer names a provider that `providers` does not have.
  HriModule(const KnowledgeBase& base, const TaskLibrary& tasks, const TaskKnowledge& knowledge,
            const AnswerProviders& providers, TaskStarter start_task, HriOptions options = {});

  /// Classifies and handles one typed or recognised input. Never throws for any input.
  HriReply handle(std::string_view utterance);
  /// A spoken input: below min_recognition_confidence it is not understood ("Sorry, I did not
  /// catch that. Could you say it again?"); otherwise its words, in typed form ("node one" ->
  /// "node 1"), are handled as typed, unless they are not understood and one of the recognizer's
  /// alternatives within max_alternative_log_gap is: then the first such alternative is.
  HriReply handle_heard(const SpeechRecognizer::Result& heard);

  /// An LED button was pressed: handled as the request HriOptions::buttons binds to it; an
  /// unbound button is not understood ("Sorry, that button does nothing here.").
  HriReply handle_button(std::string_view button);
  /// The names of the bound buttons, for a display or a page.
  [[nodiscard]] std::vector<std::string> buttons() const;

  /// The robot's internal state the HRI displays (set by the robot program). Like every method,
  /// on the HRI's thread: a monitor on another thread copies it there (e.g. between periods).
  void set_internal_state(InternalState state) { state_ = std::move(state); }
  [[nodiscard]] const InternalState& internal_state() const noexcept { return state_; }
  /// display_text(internal_state()).
  [[nodiscard]] std::string status() const { return display_text(state_); }
  /// The last input handled (handle, handle_heard, handle_button) and the reply; none before.
  [[nodiscard]] const std::optional<HriExchange>& last_exchange() const noexcept { return last_; }
  /// The internal state and the last exchange. A module indexed anew for an edited base takes
  /// them over from the one it replaces (restore_display), so the display does not blink.
  [[nodiscard]] HriDisplay display() const { return {state_, last_}; }
  void restore_display(HriDisplay display) {
    state_ = std::move(display.state);
    last_ = std::move(display.last);
  }

  [[nodiscard]] const KnowledgeIndex& index() const noexcept { return index_; }

 private:
  // What an input is, decided without acting on it (so that a recogniser's alternatives can be
  // weighed), then carried out: a task started, an answer given.
  struct Decision {
    enum class What { refuse_input, command, refuse_command, answer, not_understood } what = What::not_understood;
    std::string text;             // refuse_input, refuse_command: what to say
    Understanding understanding;  // command, refuse_command
    Retrieval retrieval;          // answer, not_understood
    bool whole = false;           // command: parsed from the words as given, every one accounted for
    [[nodiscard]] bool understood() const noexcept { return what == What::command || what == What::answer; }
  };
  [[nodiscard]] Decision decide(std::string_view utterance) const;
  HriReply carry_out(const Decision& decision);
  HriReply classify(std::string_view utterance) { return carry_out(decide(utterance)); }
  // confirm_task: 'Did you say "words"? Please say yes or no.', remembering what was asked about.
  HriReply ask_about(Decision chosen, std::string_view words, double confidence);
  // Starts with a question word ("what", "where", "how", ...): a question, not a request.
  [[nodiscard]] static bool is_question(std::string_view utterance);
  // The visitor's answer to a confirm_task question: a reply when `words` say yes or no; nullopt
  // (and the question dropped) otherwise.
  std::optional<HriReply> answer_to_question(std::string_view words);
  HriReply remember(std::string source, std::string input, HriReply reply);
  HriReply answer(const KnowledgeEntry& entry, double confidence);
  HriReply command(const Understanding& understanding);
  [[nodiscard]] std::string fill(std::string_view answer) const;
  // What a refused command is told: what does not exist, and what the robot can do instead.
  [[nodiscard]] std::string refusal(const Understanding& understanding) const;

  std::vector<KnowledgeEntry> entries_;
  const TaskLibrary& tasks_;
  const TaskKnowledge& knowledge_;
  const AnswerProviders& providers_;
  TaskStarter start_task_;
  HriOptions options_;
  KnowledgeIndex index_;
  std::vector<std::string> command_words_;  // the first word of each command form ("guide", "clean")
  InternalState state_;
  std::optional<HriExchange> last_;
  // What a confirm_task asked about: a command, or an answer whose entry starts a task.
  std::optional<Decision> asked_;
};

/// The planner's explanation of a refused command in plain words, for speaking: "I cannot do
/// that: ..." without the list of command forms.
[[nodiscard]] std::string plain_refusal(std::string_view explanation);

}  // namespace tripodal
