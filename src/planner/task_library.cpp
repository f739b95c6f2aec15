#include "tripodal/planner/task_library.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <set>

#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal {

namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// Words of a command: whitespace separated, commas as their own token, final punctuation dropped.
std::vector<std::string> tokenize(std::string_view text) {
  std::vector<std::string> out;
  std::string current;
  auto flush = [&] {
    while (!current.empty() && (current.back() == '.' || current.back() == '!' || current.back() == '?')) current.pop_back();
    if (!current.empty()) out.push_back(current);
    current.clear();
  };
  for (const char c : text) {
    if (std::isspace(static_cast<unsigned char>(c)) != 0) {
      flush();
    } else if (c == ',' || c == ';') {
      flush();
      out.emplace_back(",");
    } else {
      current += c;
    }
  }
  flush();
  return out;
}

// ---------------------------------------------------------------- loading

class Loader {
 public:
  Loader(std::string file, const TaskLoadOptions& options) : options_(options), r_(std::move(file), diags_) {}

  std::vector<TaskTemplate> load(const YAML::Node& root) {
    std::vector<TaskTemplate> out;
    if (!r_.expect_keys(root, {"tasks"}, "the task templates file")) throw ConfigError(diags_);
    const YAML::Node tasks = r_.require(root, "tasks", "the task templates file", "a list of task templates");
    if (!tasks) throw ConfigError(diags_);
    if (r_.expect_list(tasks, "'tasks'")) {
      std::set<std::string> names;
      for (const auto& t : tasks) {
        TaskTemplate tt = load_template(t);
        if (!tt.name.empty() && !names.insert(tt.name).second) {
          diags_.error(tt.where, "duplicate task name '" + tt.name + "'");
        }
        out.push_back(std::move(tt));
      }
    }
    if (diags_.has_errors()) throw ConfigError(diags_);
    return out;
  }

 private:
  std::string scalar(const YAML::Node& n, const std::string& what) { return r_.text(n, what).value_or(""); }

  TaskTemplate load_template(const YAML::Node& t) {
    TaskTemplate tt;
    tt.where = r_.at(t);
    if (!r_.expect_keys(t, {"name", "description", "commands", "plan"}, "a task template")) return tt;
    if (const YAML::Node name = r_.require(t, "name", "a task template", "the task's name")) tt.name = scalar(name, "'name'");
    if (t["description"]) tt.description = scalar(t["description"], "'description'");

    std::set<std::string> captured_everywhere;
    bool first_pattern = true;
    const YAML::Node commands = t["commands"];
    if (!commands || !commands.IsSequence() || commands.size() == 0) {
      diags_.error(commands ? r_.at(commands) : tt.where,
                   "task '" + tt.name + "' needs 'commands': a list of command patterns such as \"clean [the] room {room}\"");
    } else {
      for (const auto& c : commands) {
        CommandPattern p = parse_pattern(c);
        std::set<std::string> slots;
        for (const auto& tok : p.tokens) {
          if (tok.kind == PatternToken::Kind::slot || tok.kind == PatternToken::Kind::list_slot) slots.insert(tok.text);
        }
        if (first_pattern) {
          captured_everywhere = slots;
          first_pattern = false;
        } else {
          std::set<std::string> both;
          std::set_intersection(captured_everywhere.begin(), captured_everywhere.end(), slots.begin(), slots.end(),
                                std::inserter(both, both.begin()));
          captured_everywhere = both;
        }
        tt.commands.push_back(std::move(p));
      }
    }

    const YAML::Node plan = t["plan"];
    if (!plan || !plan.IsSequence() || plan.size() == 0) {
      diags_.error(plan ? r_.at(plan) : tt.where, "task '" + tt.name + "' needs 'plan': a list of process modules");
    } else {
      for (const auto& n : plan) tt.plan.push_back(parse_node(n, captured_everywhere, true));
    }
    return tt;
  }

  CommandPattern parse_pattern(const YAML::Node& n) {
    CommandPattern p;
    p.where = r_.at(n);
    p.text = scalar(n, "a command pattern");
    std::set<std::string> seen;
    for (const auto& word : tokenize(p.text)) {
      PatternToken tok;
      if (word.size() >= 2 && word.front() == '{' && word.back() == '}') {
        std::string name = word.substr(1, word.size() - 2);
        tok.kind = PatternToken::Kind::slot;
        if (name.size() > 3 && name.compare(name.size() - 3, 3, "...") == 0) {
          tok.kind = PatternToken::Kind::list_slot;
          name.resize(name.size() - 3);
        }
        if (name.empty() || !std::all_of(name.begin(), name.end(), [](unsigned char c) { return std::isalnum(c) != 0 || c == '_'; })) {
          diags_.error(p.where, "bad slot '" + word + "' in \"" + p.text + "\": expected {name} or {name...}");
        }
        if (!seen.insert(name).second) diags_.error(p.where, "slot {" + name + "} appears twice in \"" + p.text + "\"");
        tok.text = std::move(name);
      } else if (word.size() >= 2 && word.front() == '[' && word.back() == ']') {
        tok.kind = PatternToken::Kind::optional_word;
        tok.text = lower(word.substr(1, word.size() - 2));
      } else if (word.find_first_of("{}[]") != std::string::npos) {
        diags_.error(p.where, "bad word '" + word + "' in \"" + p.text + "\": braces and brackets must enclose a whole word");
      } else {
        tok.text = lower(word);
      }
      p.tokens.push_back(std::move(tok));
    }
    if (p.tokens.empty()) diags_.error(p.where, "empty command pattern");
    return p;
  }

  // Checks that every {name} in `text` is bound.
  void check_refs(const std::string& text, const std::set<std::string>& bound, const SourceLocation& at) {
    std::size_t pos = 0;
    while ((pos = text.find('{', pos)) != std::string::npos) {
      const std::size_t end = text.find('}', pos);
      if (end == std::string::npos) {
        diags_.error(at, "unclosed '{' in \"" + text + "\"");
        return;
      }
      const std::string name = text.substr(pos + 1, end - pos - 1);
      if (bound.count(name) == 0) {
        std::string known;
        for (const auto& b : bound) known += (known.empty() ? "" : ", ") + b;
        diags_.error(at, "'{" + name + "}' is not captured by every command of the task nor bound by a foreach (bound here: " +
                             (known.empty() ? std::string("none") : known) + ")");
      }
      pos = end + 1;
    }
  }

  TemplateNode parse_process(const YAML::Node& key, const YAML::Node& value, const std::set<std::string>& bound) {
    TemplateNode node;
    node.kind = TemplateNode::Kind::process;
    node.where = r_.at(key);
    node.process = key.Scalar();  // parse_node has checked that the key is text
    if (options_.is_known_process && !options_.is_known_process(node.process)) {
      diags_.error(node.where, "unknown process '" + node.process + "'");
    }
    if (value.IsMap()) {
      for (const auto& kv : value) {
        const auto name = r_.key(kv.first, "the parameters of '" + node.process + "'");
        if (!name) continue;
        BindingParam param{*name, scalar(kv.second, "parameter '" + *name + "'"), r_.at(kv.second)};
        check_refs(param.value, bound, param.where);
        node.params.push_back(std::move(param));
      }
    } else if (!value.IsNull()) {
      r_.expect_map(value, "the parameters of '" + node.process + "'");
    }
    return node;
  }

  TemplateNode parse_node(const YAML::Node& n, const std::set<std::string>& bound, bool allow_groups) {
    if (!n.IsMap() || n.size() != 1) {
      diags_.error(r_.at(n), "a plan step must be a map with one key: a process name, 'foreach' or 'parallel'");
      return {};
    }
    const auto kv = *n.begin();
    const auto key_text = r_.key(kv.first, "a plan step (a process name, 'foreach' or 'parallel')");
    if (!key_text) return {};
    const std::string& key = *key_text;
    if (key == "foreach" || key == "parallel") {
      if (!allow_groups) {
        diags_.error(r_.at(kv.first), "'" + key + "' is not allowed inside a parallel group");
        return {};
      }
    }
    if (key == "foreach") {
      TemplateNode node;
      node.kind = TemplateNode::Kind::foreach;
      node.where = r_.at(kv.first);
      const YAML::Node spec = kv.second;
      if (!spec.IsMap() || !spec["var"] || !spec["in"] || !spec["do"]) {
        diags_.error(node.where, "'foreach' needs 'var', 'in' and 'do', e.g. {var: section, in: \"sections({room})\", do: [...]}");
        return node;
      }
      node.variable = scalar(spec["var"], "'var'");
      node.list_expr = scalar(spec["in"], "'in'");
      check_refs(node.list_expr, bound, r_.at(spec["in"]));
      if (bound.count(node.variable) != 0) {
        diags_.error(r_.at(spec["var"]), "foreach variable '" + node.variable + "' hides a slot of the same name");
      }
      std::set<std::string> inner = bound;
      inner.insert(node.variable);
      if (r_.expect_list(spec["do"], "'do' (the plan steps)")) {
        for (const auto& s : spec["do"]) node.body.push_back(parse_node(s, inner, true));
      }
      return node;
    }
    if (key == "parallel") {
      TemplateNode node;
      node.kind = TemplateNode::Kind::parallel;
      node.where = r_.at(kv.first);
      if (!kv.second.IsSequence() || kv.second.size() < 2) {
        diags_.error(node.where, "'parallel' needs a list of at least two processes");
        return node;
      }
      for (const auto& s : kv.second) node.body.push_back(parse_node(s, bound, false));
      return node;
    }
    return parse_process(kv.first, kv.second, bound);
  }

  const TaskLoadOptions& options_;
  Diagnostics diags_;
  yaml::Reader r_;
};

std::vector<TaskTemplate> load_templates(const std::string& text, const std::string& name, const TaskLoadOptions& options) {
  return yaml::guarded(name, [&] { return Loader(name, options).load(yaml::parse(text, name)); });
}

// ---------------------------------------------------------------- matching

struct MatchState {
  std::size_t furthest = 0;     // furthest command token reached
  std::string expected;         // what the pattern wanted there
};

bool match(const std::vector<PatternToken>& pat, std::size_t pi, const std::vector<std::string>& words, std::size_t wi,
           std::map<std::string, std::vector<std::string>>& slots, MatchState& st) {
  auto note = [&](const std::string& what) {
    if (wi > st.furthest || (wi == st.furthest && st.expected.empty())) {
      st.furthest = wi;
      st.expected = what;
    }
  };
  if (pi == pat.size()) {
    if (wi == words.size()) return true;
    note("the end of the command");
    return false;
  }
  const PatternToken& tok = pat[pi];
  switch (tok.kind) {
    case PatternToken::Kind::word:
      if (wi < words.size() && lower(words[wi]) == tok.text) return match(pat, pi + 1, words, wi + 1, slots, st);
      note("\"" + tok.text + "\"");
      return false;
    case PatternToken::Kind::optional_word:
      if (wi < words.size() && lower(words[wi]) == tok.text && match(pat, pi + 1, words, wi + 1, slots, st)) return true;
      return match(pat, pi + 1, words, wi, slots, st);
    case PatternToken::Kind::slot:
      if (wi < words.size() && words[wi] != ",") {
        slots[tok.text] = {words[wi]};
        if (match(pat, pi + 1, words, wi + 1, slots, st)) return true;
        slots.erase(tok.text);
        return false;
      }
      note("a " + tok.text);
      return false;
    case PatternToken::Kind::list_slot: {
      // Greedy: the longest run of words that still lets the rest of the pattern match.
      for (std::size_t end = words.size(); end > wi; --end) {
        std::vector<std::string> run(words.begin() + static_cast<std::ptrdiff_t>(wi), words.begin() + static_cast<std::ptrdiff_t>(end));
        if (run.front() == "," || run.back() == ",") continue;
        slots[tok.text] = std::move(run);
        if (match(pat, pi + 1, words, end, slots, st)) return true;
        slots.erase(tok.text);
      }
      note("one or more " + tok.text);
      return false;
    }
  }
  return false;
}

std::string join(const std::vector<std::string>& words, const char* sep) {
  std::string out;
  for (const auto& w : words) {
    if (!out.empty() && w != ",") out += sep;
    out += w;
  }
  return out;
}

// A list slot's words as items: split on commas and "and".
std::vector<std::string> items_of(const std::vector<std::string>& words) {
  std::vector<std::string> items;
  std::string current;
  for (const auto& w : words) {
    if (w == "," || lower(w) == "and") {
      if (!current.empty()) items.push_back(current);
      current.clear();
    } else {
      current += (current.empty() ? "" : " ") + w;
    }
  }
  if (!current.empty()) items.push_back(current);
  return items;
}

std::string substitute(const std::string& text, const std::map<std::string, std::string>& vars) {
  std::string out;
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t open = text.find('{', pos);
    if (open == std::string::npos) break;
    const std::size_t close = text.find('}', open);
    if (close == std::string::npos) break;
    out += text.substr(pos, open - pos);
    const auto it = vars.find(text.substr(open + 1, close - open - 1));
    out += it != vars.end() ? it->second : text.substr(open, close - open + 1);
    pos = close + 1;
  }
  out += text.substr(pos);
  return out;
}

class Expander {
 public:
  Expander(const TaskKnowledge& knowledge, const std::map<std::string, std::vector<std::string>>& lists)
      : knowledge_(knowledge), lists_(lists) {}

  bool expand(const std::vector<TemplateNode>& nodes, const std::map<std::string, std::string>& vars, Plan& plan) {
    for (const auto& node : nodes) {
      switch (node.kind) {
        case TemplateNode::Kind::process:
          plan.stages.push_back(PlanStage{{make_step(node, vars)}});
          break;
        case TemplateNode::Kind::parallel: {
          PlanStage stage;
          for (const auto& b : node.body) stage.steps.push_back(make_step(b, vars));
          plan.stages.push_back(std::move(stage));
          break;
        }
        case TemplateNode::Kind::foreach: {
          std::vector<std::string> items;
          if (!list(node.list_expr, vars, items)) return false;
          for (const auto& item : items) {
            auto inner = vars;
            inner[node.variable] = item;
            if (!expand(node.body, inner, plan)) return false;
          }
          break;
        }
      }
    }
    return true;
  }

  std::string error;

 private:
  static ProcessStep make_step(const TemplateNode& node, const std::map<std::string, std::string>& vars) {
    ProcessStep step{node.process, {}};
    for (const auto& p : node.params) step.params.push_back({p.name, substitute(p.value, vars), p.where});
    return step;
  }

  // "{rooms}" (a list slot) or "function({slot})" (asked of the knowledge).
  bool list(const std::string& expr, const std::map<std::string, std::string>& vars, std::vector<std::string>& items) {
    if (expr.size() > 2 && expr.front() == '{' && expr.back() == '}') {
      const auto it = lists_.find(expr.substr(1, expr.size() - 2));
      if (it != lists_.end()) {
        items = items_of(it->second);
        return true;
      }
      items = {substitute(expr, vars)};
      return true;
    }
    const std::size_t open = expr.find('(');
    if (open == std::string::npos || expr.back() != ')') {
      error = "cannot expand '" + expr + "': expected {list} or function({slot})";
      return false;
    }
    const std::string fn = expr.substr(0, open);
    const std::string arg = substitute(expr.substr(open + 1, expr.size() - open - 2), vars);
    auto result = knowledge_.list(fn, arg);
    if (!result.ok) {
      error = result.error.empty() ? fn + "(" + arg + ") is not known" : result.error;
      return false;
    }
    if (result.items.empty()) {
      error = fn + "(" + arg + ") is empty: nothing to do";
      return false;
    }
    items = std::move(result.items);
    return true;
  }

  const TaskKnowledge& knowledge_;
  const std::map<std::string, std::vector<std::string>>& lists_;
};

}  // namespace

TaskLibrary TaskLibrary::load(const std::filesystem::path& file, const TaskLoadOptions& options) {
  TaskLibrary lib;
  lib.templates_ = load_templates(yaml::read_file(file), file.string(), options);
  return lib;
}

TaskLibrary TaskLibrary::load_from_string(std::string_view yaml, std::string_view name, const TaskLoadOptions& options) {
  TaskLibrary lib;
  lib.templates_ = load_templates(std::string(yaml), std::string(name), options);
  return lib;
}

std::vector<std::string> TaskLibrary::command_forms() const {
  std::vector<std::string> out;
  for (const auto& t : templates_) {
    for (const auto& c : t.commands) out.push_back(c.text);
  }
  return out;
}

Understanding TaskLibrary::understand(std::string_view command, const TaskKnowledge& knowledge) const {
  Understanding u;
  const std::vector<std::string> words = tokenize(command);
  MatchState best;
  std::string best_form;
  for (const auto& t : templates_) {
    for (const auto& pattern : t.commands) {
      std::map<std::string, std::vector<std::string>> slots;
      MatchState st;
      if (match(pattern.tokens, 0, words, 0, slots, st)) {
        u.task = t.name;
        std::map<std::string, std::string> vars;
        for (const auto& [k, v] : slots) vars[k] = join(v, " ");
        u.slots = vars;
        Plan plan;
        plan.task = t.name;
        plan.command = std::string(command);
        Expander expander(knowledge, slots);
        if (!expander.expand(t.plan, vars, plan)) {
          u.explanation = "understood the task '" + t.name + "' but cannot plan it: " + expander.error;
          return u;
        }
        u.plan = std::move(plan);
        u.understood = true;
        return u;
      }
      if (st.furthest > best.furthest || best_form.empty()) {
        best = st;
        best_form = pattern.text;
      }
    }
  }
  std::string text = "not understood: \"" + std::string(command) + "\"";
  if (words.empty()) {
    text += " (no words)";
  } else if (!best_form.empty()) {
    const std::vector<std::string> ok(words.begin(), words.begin() + static_cast<std::ptrdiff_t>(best.furthest));
    text += best.furthest == 0 ? "; nothing matched at the start"
                               : "; understood \"" + join(ok, " ") + "\" (as in \"" + best_form + "\")";
    text += best.furthest < words.size() ? ", then \"" + words[best.furthest] + "\" where " + best.expected + " was expected"
                                         : ", then the command ended where " + best.expected + " was expected";
  }
  text += ". Possible commands:";
  for (const auto& form : command_forms()) text += "\n  " + form;
  u.explanation = text;
  return u;
}

}  // namespace tripodal
