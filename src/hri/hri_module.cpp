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

RetrievalOptions retrieval_options(const TaskLibrary& tasks) {
  RetrievalOptions o;
  o.extra_vocabulary = command_vocabulary(tasks);
  // Politeness the command path strips must survive the typo correction.
  for (const char* w : {"please", "could", "would", "will", "can", "you", "jinny", "hey", "hello", "like"}) {
    o.extra_vocabulary.emplace_back(w);
  }
  return o;
}

// Polite openings and closings around a command ("could you please guide me to node 1"): the
// task templates are written without them.
std::vector<std::string> without_politeness(std::vector<std::string> ws) {
  static const std::array<std::vector<std::string_view>, 12> leads = {{
      {"let", "s"},
      {"let", "us"},
      {"i", "would", "like", "you", "to"},
      {"i", "want", "you", "to"},
      {"can", "you"},
      {"could", "you"},
      {"would", "you"},
      {"will", "you"},
      {"please"},
      {"jinny"},
      {"hey"},
      {"ok"},
  }};
  bool stripped = true;
  while (stripped && !ws.empty()) {
    stripped = false;
    for (const auto& lead : leads) {
      if (ws.size() > lead.size() && std::equal(lead.begin(), lead.end(), ws.begin())) {
        ws.erase(ws.begin(), ws.begin() + static_cast<std::ptrdiff_t>(lead.size()));
        stripped = true;
      }
    }
  }
  while (ws.size() > 1 && (ws.back() == "please" || ws.back() == "jinny" || ws.back() == "now")) ws.pop_back();
  return ws;
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

std::string display_text(const InternalState& state) {
  std::string out = state.task.empty() ? "idle" : "task " + state.task + ": " + (state.task_state.empty() ? "running" : state.task_state);
  out += state.process.empty() ? " | no process" : " | process " + state.process;
  out += state.fault.empty() ? " | no fault" : " | fault: " + state.fault;
  return out;
}

HriReply HriModule::handle_button(std::string_view button) {
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
      index_(base, retrieval_options(tasks)) {
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
  const std::string typed = typed_form(heard.words);
  return remember("heard", heard.words, classify(typed));
}

HriReply HriModule::handle(std::string_view utterance) {
  HriReply reply = classify(utterance);
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

HriReply HriModule::classify(std::string_view utterance) {
  HriReply reply;
  reply.kind = HriReply::Kind::refused_input;
  // Checked before anything reads the words: a huge or binary input costs nothing more.
  if (utterance.size() > options_.max_utterance_bytes) {
    reply.text = "Sorry, that is too long for me. Please ask me in a sentence or two.";
    return reply;
  }
  if (!hri::is_text(utterance)) {
    reply.text = "Sorry, I can only understand words. Please type or say your question again.";
    return reply;
  }
  const std::string corrected = index_.correct(utterance);
  if (corrected.empty()) {
    reply.text = "I did not catch anything. How can I help you?";
    return reply;
  }

  // A command input: the planner understands it, or it starts with a command's verb.
  // The words as typed first: typo correction knows only the base's and the commands' words, and
  // could bend a slot's value ("carry the kettle ...") towards one of them.
  const Understanding as_typed = tasks_.understand(joined(without_politeness(hri::words(utterance))), knowledge_);
  if (as_typed.understood) return command(as_typed);
  const std::vector<std::string> command_words = without_politeness(hri::words(corrected));
  const Understanding u = tasks_.understand(joined(command_words), knowledge_);
  if (u.understood) return command(u);

  const Retrieval r = index_.search(utterance);
  const bool confident = !r.hits.empty() && r.hits.front().confidence >= options_.confidence_threshold;
  const bool starts_like_command = !command_words.empty() && std::find(command_words_.begin(), command_words_.end(),
                                                                       command_words.front()) != command_words_.end();
  const bool action_covers = !r.hits.empty() && r.hits.front().confidence >= options_.command_confidence_threshold &&
                             !entries_[r.hits.front().entry].action.empty();
  if (!u.task.empty() || (starts_like_command && !action_covers)) {
    reply.kind = HriReply::Kind::task_refused;
    reply.task = u.task;
    reply.text = plain_refusal(u.explanation);
    return reply;
  }

  // A reaction input: answered from the RKMS.
  if (confident) return answer(entries_[r.hits.front().entry], r.hits.front().confidence);

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
