#include "tripodal/hri/hri_module.hpp"

#include <algorithm>
#include <array>

#include "text.hpp"

namespace tripodal {

std::string_view to_string(HriReply::Kind kind) noexcept {
  switch (kind) {
    case HriReply::Kind::answered: return "answered";
    case HriReply::Kind::task_started: return "task_started";
    case HriReply::Kind::task_refused: return "task_refused";
    case HriReply::Kind::not_understood: return "not_understood";
    case HriReply::Kind::refused_input: return "refused_input";
    case HriReply::Kind::confirm_task: return "confirm_task";
    case HriReply::Kind::task_cancelled: return "task_cancelled";
  }
  return "unknown";
}

namespace {

std::vector<std::string> command_vocabulary(const TaskLibrary& tasks) {
  std::vector<std::string> out;
  for (const auto& form : tasks.command_forms()) {
    for (const auto& w : hri::words(form)) {
      out.push_back(w);
    }
  }
  return out;
}

// A yes-or-no question: it opens with an auxiliary ("are you ...", "is there ..."). "can you",
// "could you", "would you" and "will you" are the polite form of a request and do not count; a
// question word ("what will you show me") is HriModule::is_question's, asked about first.
bool asks_rather_than_requests(const std::vector<std::string>& ws) {
  static constexpr std::array<std::string_view, 8> kOpenings = {"are", "is", "am", "was", "were", "does", "did", "have"};
  return !ws.empty() && std::find(kOpenings.begin(), kOpenings.end(), ws.front()) != kOpenings.end();
}

RetrievalOptions retrieval_options(const TaskLibrary& tasks, std::shared_ptr<const Lexicon> lexicon) {
  RetrievalOptions o;
  o.lexicon = std::move(lexicon);
  o.extra_vocabulary = command_vocabulary(tasks);
  // Politeness the command path strips must survive the typo correction.
  for (const auto& opening : hri::polite_openings()) o.extra_vocabulary.insert(o.extra_vocabulary.end(), opening.begin(), opening.end());
  for (const auto& closing : hri::polite_closings()) o.extra_vocabulary.emplace_back(closing);
  return o;
}

std::string joined(const std::vector<std::string>& ws) {
  std::string out;
  for (const auto& w : ws) out += (out.empty() ? "" : " ") + w;
  return out;
}

}  // namespace

std::string plain_refusal(std::string_view explanation) {
  std::string e(explanation.substr(0, explanation.find(". Possible commands:")));
  const std::string_view cannot_plan = " but cannot plan it: ";
  if (const auto at = e.find(cannot_plan); at != std::string::npos && e.rfind("understood the task '", 0) == 0) {
    const std::size_t name_start = std::string_view("understood the task '").size();
    const std::string task = e.substr(name_start, e.find('\'', name_start) - name_start);
    return "Sorry, I cannot do the " + task + " task: " + e.substr(at + cannot_plan.size()) + ".";
  }
  // "not understood: "X"; understood "guide me to" (as in "..."), then "kitchen" where "node" was expected"
  std::string detail;
  if (const auto semi = e.find("\"; "); semi != std::string::npos) detail = e.substr(semi + 3);
  if (const auto as_in = detail.find(" (as in \""); as_in != std::string::npos) {
    const auto close = detail.find("\")", as_in);
    if (close != std::string::npos) detail.erase(as_in, close + 2 - as_in);
  }
  if (detail.rfind("understood ", 0) == 0) detail = "I understood " + detail.substr(11);
  if (detail.rfind("nothing matched at the start", 0) == 0) detail = "I know no command that starts like that" + detail.substr(28);
  if (const auto w = detail.find(" where "); w != std::string::npos) {
    const auto was = detail.find(" was expected", w);
    if (was != std::string::npos) {
      detail = detail.substr(0, w) + " where I expected " + detail.substr(w + 7, was - w - 7) + detail.substr(was + 13);
    }
  }
  return detail.empty() ? "Sorry, I did not understand that command." : "Sorry, I did not understand that command: " + detail + ".";
}

namespace {

// "0, 1 or 2".
std::string spoken_list(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i == 0 ? "" : i + 1 == items.size() ? " or " : ", ") + items[i];
  return out;
}

// The "(known: 0, 1, 2)" a TaskKnowledge's refusal ends with (task_library.hpp's convention).
std::vector<std::string> known_in(std::string_view explanation) {
  std::vector<std::string> out;
  const auto at = explanation.rfind("(known: ");
  if (at == std::string_view::npos) return out;
  const auto end = explanation.find(')', at);
  if (end == std::string_view::npos) return out;
  std::string_view rest = explanation.substr(at + 8, end - at - 8);
  while (!rest.empty()) {
    const auto comma = rest.find(", ");
    out.emplace_back(rest.substr(0, comma));
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 2);
  }
  return out;
}

}  // namespace

std::string HriModule::refusal(const Understanding& u) const {
  std::vector<std::string> places = knowledge_.known(options_.places_list);
  if (places.empty()) places = known_in(u.explanation);
  const std::string offer = places.empty() ? std::string() : " I can " + options_.places_offer + " " + spoken_list(places) + ".";
  if (!u.task.empty()) {
    // Understood, not plannable: a place that does not exist, or the planner's own reason.
    if (const auto slot = u.slots.find(options_.places_list); slot != u.slots.end() && !places.empty() &&
                                                              std::find(places.begin(), places.end(), slot->second) == places.end()) {
      return "Sorry, there is no " + options_.places_list + " " + slot->second + " here." + offer;
    }
    return plain_refusal(u.explanation);
  }
  return "Sorry, I did not understand that request." + offer;
}

std::string display_text(const InternalState& state) {
  std::string out = state.task.empty() ? "idle" : "task " + state.task + ": " + (state.task_state.empty() ? "running" : state.task_state);
  out += state.process.empty() ? " | no process" : " | process " + state.process;
  out += state.fault.empty() ? " | no fault" : " | fault: " + state.fault;
  return out;
}

HriReply HriModule::handle_button(std::string_view button) {
  asked_.reset();
  const auto it = options_.buttons.find(button);
  if (it == options_.buttons.end()) {
    HriReply reply;
    reply.kind = HriReply::Kind::not_understood;
    reply.text = "Sorry, that button does nothing here.";
    return remember("button", std::string(button.substr(0, 64)), std::move(reply));
  }
  return remember("button", it->first, classify(it->second));
}

std::vector<std::string> HriModule::buttons() const {
  std::vector<std::string> out;
  for (const auto& [name, request] : options_.buttons) out.push_back(name);
  return out;
}

HriModule::HriModule(const KnowledgeBase& base, const TaskLibrary& tasks, const TaskKnowledge& knowledge,
                     const AnswerProviders& providers, TaskStarter start_task, HriOptions options)
    : entries_(base.entries()),
      tasks_(tasks),
      knowledge_(knowledge),
      providers_(providers),
      start_task_(std::move(start_task)),
      options_(std::move(options)),
      index_(base, retrieval_options(tasks, options_.lexicon)) {
  Diagnostics d;
  std::string available;
  for (const auto& n : providers_.names()) available += (available.empty() ? "" : ", ") + n;
  for (const auto& e : entries_) {
    for (const auto& p : scan_placeholders(e.answer).placeholders) {
      if (providers_.find(p.name) == nullptr) {
        d.error(e.where, "entry '" + e.id + "': the answer names {" + p.name + "}, which no provider gives; providers: " +
                             (available.empty() ? std::string("none") : available));
      }
    }
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  for (const auto& form : tasks_.command_forms()) {
    const auto ws = hri::words(form);
    if (!ws.empty() && std::find(command_words_.begin(), command_words_.end(), ws.front()) == command_words_.end()) {
      command_words_.push_back(ws.front());
    }
  }
}

std::string HriModule::fill(std::string_view answer) const {
  std::string out;
  std::size_t i = 0;
  while (i < answer.size()) {
    const char c = answer[i];
    if ((c == '{' || c == '}') && i + 1 < answer.size() && answer[i + 1] == c) {
      out += c;
      i += 2;
      continue;
    }
    if (c == '{') {
      const std::size_t close = answer.find('}', i);
      if (close != std::string_view::npos) {
        const AnswerProvider* p = providers_.find(answer.substr(i + 1, close - i - 1));
        out += p != nullptr ? p->value() : std::string("unknown");
        i = close + 1;
        continue;
      }
    }
    out += c;
    ++i;
  }
  return out;
}

HriReply HriModule::command(const Understanding& understanding) {
  HriReply reply;
  const std::string why = start_task_ ? start_task_(understanding) : std::string("no planner is connected");
  if (!why.empty()) {
    reply.kind = HriReply::Kind::task_refused;
    reply.task = understanding.task;
    reply.text = "Sorry, I cannot start the " + understanding.task + " task now: " + why + ".";
    return reply;
  }
  reply.kind = HriReply::Kind::task_started;
  reply.task = understanding.task;
  reply.plan = understanding.plan;
  reply.confidence = 1.0;
  reply.text = "All right, I am starting the " + understanding.task + " task.";
  return reply;
}

HriReply HriModule::answer(const KnowledgeEntry& entry, double confidence) {
  HriReply reply;
  reply.kind = HriReply::Kind::answered;
  reply.entry_id = entry.id;
  reply.confidence = confidence;
  reply.text = fill(entry.answer);
  if (!entry.action.empty()) {
    const Understanding u = tasks_.understand(entry.action, knowledge_);
    if (!u.understood) {
      reply.text += " " + plain_refusal(u.explanation);
    } else if (const std::string why = start_task_ ? start_task_(u) : std::string("no planner is connected"); !why.empty()) {
      reply.text += " But I cannot do it now: " + why + ".";
    } else {
      reply.task = u.task;
      reply.plan = u.plan;
    }
  }
  return reply;
}

HriReply HriModule::handle_heard(const SpeechRecognizer::Result& heard) {
  if (!heard.words.empty() && heard.confidence < options_.min_recognition_confidence) {
    HriReply reply;
    reply.kind = HriReply::Kind::not_understood;
    reply.confidence = heard.confidence;
    reply.text = "Sorry, I did not catch that. Could you say it again?";
    return remember("heard", heard.words, std::move(reply));
  }
  if (auto reply = answer_to_question(heard.words)) return remember("heard", heard.words, std::move(*reply));
  Decision chosen = decide(typed_form(heard.words));
  std::string words = heard.words;
  bool from_alternative = false;
  // Only a command is taken from the alternatives: the task grammar is strict, so a sentence
  // misheard into a full command is rare, while retrieval finds some entry in almost anything.
  // Never for a command heard whole that names what does not exist: "node seven" must not become
  // the guide to node one an alternative heard.
  const bool names_unknown = chosen.what == Decision::What::refuse_command && !chosen.understanding.task.empty();
  if (!chosen.understood() && !names_unknown) {
    for (const auto& alt : heard.alternatives) {
      if (alt.log_score < -options_.max_alternative_log_gap) continue;
      if (Decision d = decide(typed_form(alt.words)); d.what == Decision::What::command) {
        chosen = std::move(d);
        words = alt.words;
        from_alternative = true;
        break;
      }
    }
  }
  // A task heard unsurely (a command, or an answer whose entry starts one) waits for a yes.
  const bool starts_task = chosen.what == Decision::What::command ||
                           (chosen.what == Decision::What::answer && !entries_[chosen.retrieval.hits.front().entry].action.empty());
  const bool consented = chosen.what == Decision::What::command && chosen.whole && !from_alternative &&
                         heard.confidence >= options_.confirm_heard_tasks_below;
  if (starts_task && options_.confirm_heard_tasks_below > 0.0 && !consented) {
    return remember("heard", words, ask_about(std::move(chosen), typed_form(words), heard.confidence));
  }
  return remember("heard", words, carry_out(chosen));
}

HriReply HriModule::ask_about(Decision chosen, std::string_view words, double confidence) {
  HriReply reply;
  reply.kind = HriReply::Kind::confirm_task;
  if (chosen.what == Decision::What::command) {
    reply.task = chosen.understanding.task;
  } else {
    const KnowledgeEntry& e = entries_[chosen.retrieval.hits.front().entry];
    reply.entry_id = e.id;
    reply.task = tasks_.understand(e.action, knowledge_).task;
  }
  reply.confidence = confidence;
  reply.text = "Did you say \"" + std::string(words) + "\"? Please say yes or no.";
  asked_ = std::move(chosen);
  return reply;
}

bool HriModule::is_question(std::string_view utterance) {
  const auto ws = hri::words(utterance);
  static constexpr std::array<std::string_view, 9> kAsking = {"what", "where", "who", "whom", "which", "why", "when", "how", "whats"};
  return !ws.empty() && std::find(kAsking.begin(), kAsking.end(), ws.front()) != kAsking.end();
}

std::optional<HriReply> HriModule::answer_to_question(std::string_view input) {
  if (!asked_) return std::nullopt;
  const Decision asked = std::move(*asked_);
  asked_.reset();
  switch (hri::yes_or_no(hri::without_politeness(hri::words(input)))) {
    case hri::Answer::yes:
      return carry_out(asked);
    case hri::Answer::no: {
      HriReply reply;
      reply.kind = HriReply::Kind::task_cancelled;
      reply.text = "All right, I will not do that.";
      if (asked.what == Decision::What::command) reply.task = asked.understanding.task;
      return reply;
    }
    case hri::Answer::neither:
      break;
  }
  return std::nullopt;
}

HriReply HriModule::handle(std::string_view utterance) {
  const bool readable = utterance.size() <= options_.max_utterance_bytes && hri::is_text(utterance);
  if (!readable) asked_.reset();  // refused unread: not an answer, and the question is dropped
  std::optional<HriReply> answered = readable ? answer_to_question(utterance) : std::nullopt;
  HriReply reply;
  if (answered) {
    reply = std::move(*answered);
  } else if (Decision d = decide(utterance); d.what == Decision::What::answer && is_question(utterance) &&
                                             !entries_[d.retrieval.hits.front().entry].action.empty()) {
    // A question is not a request: an entry that would start a task ("what will you show me" ->
    // the visit to PSR-1) asks first, even typed.
    reply = ask_about(std::move(d), utterance, 1.0);
  } else {
    reply = carry_out(d);
  }
  // What the display may show of the input: the text itself, unless it was refused unread.
  std::string shown = utterance.size() > options_.max_utterance_bytes ? "(" + std::to_string(utterance.size()) + " bytes: too long)"
                      : !hri::is_text(utterance)                       ? "(" + std::to_string(utterance.size()) + " bytes: not text)"
                                                                       : std::string(utterance);
  return remember("typed", std::move(shown), std::move(reply));
}

HriReply HriModule::remember(std::string source, std::string input, HriReply reply) {
  last_ = HriExchange{std::move(source), std::move(input), reply.kind, reply.text, reply.entry_id, reply.task};
  return reply;
}

HriModule::Decision HriModule::decide(std::string_view utterance) const {
  Decision d;
  d.what = Decision::What::refuse_input;
  // Checked before anything reads the words: a huge or binary input costs nothing more.
  if (utterance.size() > options_.max_utterance_bytes) {
    d.text = "Sorry, that is too long for me. Please ask me in a sentence or two.";
    return d;
  }
  if (!hri::is_text(utterance)) {
    d.text = "Sorry, I can only understand words. Please type or say your question again.";
    return d;
  }
  const std::string corrected = index_.correct(utterance);
  if (corrected.empty()) {
    d.text = "I did not catch anything. How can I help you?";
    return d;
  }

  // A command input: the planner understands it, or it starts with a command's verb.
  // The words as typed first: typo correction knows only the base's and the commands' words, and
  // could bend a slot's value ("carry the kettle ...") towards one of them.
  d.what = Decision::What::command;
  // The grammar's own wording first ("explain this robot"), then the visitor's rephrased
  // (fillers, politeness and tails stripped: "um jinny could you take us to node one please").
  const std::vector<std::string> literal_words = hri::words(utterance);
  std::vector<std::string> typed_words = literal_words;
  d.understanding = tasks_.understand(joined(literal_words), knowledge_);
  if (!d.understanding.understood) {
    typed_words = hri::command_phrasing(literal_words);
    d.understanding = tasks_.understand(joined(typed_words), knowledge_);
  }
  d.whole = d.understanding.understood;
  if (d.understanding.understood) return d;
  // A request naming a place that does not exist is refused, never bent towards a known one,
  // unless an entry that starts a task is about it by name ("i would like to see the cleaning
  // robot": the visit to PSR-2).
  if (!d.understanding.task.empty()) {
    Retrieval r = index_.search(utterance);
    if (!r.hits.empty() && r.hits.front().confidence >= options_.command_confidence_threshold &&
        !entries_[r.hits.front().entry].action.empty()) {
      d.what = Decision::What::answer;
      d.retrieval = std::move(r);
      return d;
    }
    d.what = Decision::What::refuse_command;
    d.text = refusal(d.understanding);
    return d;
  }
  d.understanding = tasks_.understand(joined(hri::command_phrasing(hri::words(corrected))), knowledge_);
  if (d.understanding.understood) return d;

  d.retrieval = index_.search(utterance);
  // A question is no request: "are you a robot?" may rank a visit's entry first ("I will take you
  // to the cleaning robot"), and answering it would start the visit. A question is answered from
  // the entries that start nothing.
  if (asks_rather_than_requests(literal_words) && !d.retrieval.hits.empty() &&
      !entries_[d.retrieval.hits.front().entry].action.empty()) {
    auto& hits = d.retrieval.hits;
    hits.erase(std::remove_if(hits.begin(), hits.end(), [&](const RetrievalHit& h) { return !entries_[h.entry].action.empty(); }),
               hits.end());
  }
  // Starting a task asks for more than answering: an entry that starts one answers only when it
  // covers the utterance as surely as a command that starts like one ("see you next time" shares
  // "see" and "time" with "I want to see PSR-1" and started the guide).
  if (!d.retrieval.hits.empty() && !entries_[d.retrieval.hits.front().entry].action.empty() &&
      d.retrieval.hits.front().confidence < options_.command_confidence_threshold) {
    auto& hits = d.retrieval.hits;
    hits.erase(std::remove_if(hits.begin(), hits.end(),
                              [&](const RetrievalHit& h) {
                                return !entries_[h.entry].action.empty() && h.confidence < options_.command_confidence_threshold;
                              }),
               hits.end());
  }
  const Retrieval& r = d.retrieval;
  const bool confident = !r.hits.empty() && r.hits.front().confidence >= options_.confidence_threshold;
  // The verb as typed: a correction that made one ("cook pasta" -> "look") is no command.
  const bool starts_like_command = !typed_words.empty() && std::find(command_words_.begin(), command_words_.end(),
                                                                     typed_words.front()) != command_words_.end();
  const bool action_covers = !r.hits.empty() && r.hits.front().confidence >= options_.command_confidence_threshold &&
                             !entries_[r.hits.front().entry].action.empty();
  if (!d.understanding.task.empty() || (starts_like_command && !action_covers)) {
    d.what = Decision::What::refuse_command;
    d.text = refusal(d.understanding);
    return d;
  }
  // A reaction input: answered from the RKMS.
  d.what = confident ? Decision::What::answer : Decision::What::not_understood;
  return d;
}

HriReply HriModule::carry_out(const Decision& d) {
  HriReply reply;
  const Retrieval& r = d.retrieval;
  switch (d.what) {
    case Decision::What::refuse_input:
      reply.kind = HriReply::Kind::refused_input;
      reply.text = d.text;
      return reply;
    case Decision::What::command:
      return command(d.understanding);
    case Decision::What::refuse_command:
      reply.kind = HriReply::Kind::task_refused;
      reply.task = d.understanding.task;
      reply.text = d.text;
      return reply;
    case Decision::What::answer:
      return answer(entries_[r.hits.front().entry], r.hits.front().confidence);
    case Decision::What::not_understood:
      break;
  }

  reply.kind = HriReply::Kind::not_understood;
  reply.confidence = r.hits.empty() ? 0.0 : r.hits.front().confidence;
  for (const auto& hit : r.hits) {
    const std::string& topic = entries_[hit.entry].topic;
    if (reply.closest_topics.size() >= options_.offered_topics) break;
    if (std::find(reply.closest_topics.begin(), reply.closest_topics.end(), topic) == reply.closest_topics.end()) {
      reply.closest_topics.push_back(topic);
    }
  }
  for (const auto& e : entries_) {
    if (reply.closest_topics.size() >= options_.offered_topics) break;
    if (std::find(reply.closest_topics.begin(), reply.closest_topics.end(), e.topic) == reply.closest_topics.end()) {
      reply.closest_topics.push_back(e.topic);
    }
  }
  reply.text = "Sorry, I did not understand that.";
  if (!reply.closest_topics.empty()) {
    reply.text += " I can tell you about ";
    for (std::size_t i = 0; i < reply.closest_topics.size(); ++i) {
      if (i > 0) reply.text += i + 1 == reply.closest_topics.size() ? " or " : ", ";
      reply.text += reply.closest_topics[i];
    }
    reply.text += ".";
  }
  return reply;
}

}  // namespace tripodal
