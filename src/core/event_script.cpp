#include "tripodal/core/event_script.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>

namespace tripodal {

namespace {

struct Token {
  std::string text;
  int column = 0;  // from 1
  bool quoted = false;
};

bool is_name_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_'; }
bool is_name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '-' || c == '/';
}

// The index of the first character that makes `s` not a name; nullopt when it is one.
std::optional<std::size_t> bad_name_char(std::string_view s) {
  if (s.empty() || !is_name_start(s[0])) return 0;
  for (std::size_t i = 1; i < s.size(); ++i) {
    if (!is_name_char(s[i])) return i;
  }
  return std::nullopt;
}

class LineParser {
 public:
  LineParser(SourceFile source, int line, Diagnostics& diagnostics)
      : source_(source), line_(line), diagnostics_(diagnostics) {}

  SourceLocation at(int column) const { return SourceLocation{source_, line_, column}; }
  void error(int column, std::string message) { diagnostics_.error(at(column), std::move(message)); }

  // Splits into tokens, stopping at a '#' outside quotes. Returns false on an unterminated quote.
  bool tokenize(std::string_view text, std::vector<Token>& out) {
    std::size_t i = 0;
    while (i < text.size()) {
      const char c = text[i];
      if (c == ' ' || c == '\t' || c == '\r') {
        ++i;
        continue;
      }
      if (c == '#') break;
      Token tok;
      tok.column = static_cast<int>(i) + 1;
      if (c == '"' || c == '\'') {
        const std::size_t close = text.find(c, i + 1);
        if (close == std::string_view::npos) {
          error(tok.column, std::string("unterminated string: missing closing ") + c);
          return false;
        }
        tok.text = std::string(text.substr(i + 1, close - i - 1));
        tok.quoted = true;
        i = close + 1;
        if (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\r' && text[i] != '#') {
          error(static_cast<int>(i) + 1, "expected a space after the closing quote");
          return false;
        }
      } else {
        const std::size_t start = i;
        while (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\r' && text[i] != '#') ++i;
        tok.text = std::string(text.substr(start, i - start));
      }
      out.push_back(std::move(tok));
    }
    return true;
  }

  bool check_name(const Token& tok, const char* what) {
    if (tok.quoted) {
      error(tok.column, std::string(what) + " must not be quoted");
      return false;
    }
    if (const auto bad = bad_name_char(tok.text)) {
      error(tok.column + static_cast<int>(*bad),
            std::string("invalid character '") + tok.text[*bad] + "' in " + what + " '" + tok.text +
                "' (names start with a letter or '_' and contain letters, digits, '_', '.', '-', '/')");
      return false;
    }
    return true;
  }

 private:
  SourceFile source_;
  int line_;
  Diagnostics& diagnostics_;
};

}  // namespace

EventScript parse_event_script(std::string_view text, std::string_view source) {
  EventScript script;
  script.source = std::string(source);
  Diagnostics diagnostics;
  double previous_s = 0.0;
  int previous_line = 0;
  int line_no = 0;
  const SourceFile file(source);  // interned once, not per line
  std::vector<Token> tokens;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t eol = std::min(text.find('\n', pos), text.size());
    const std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    LineParser p(file, line_no, diagnostics);
    tokens.clear();
    if (!p.tokenize(line, tokens) || tokens.empty()) continue;

    const Token& time_tok = tokens[0];
    double seconds = 0.0;
    const char* first = time_tok.text.data();
    const char* last = first + time_tok.text.size();
    const auto [end, ec] = std::from_chars(first, last, seconds);
    if (time_tok.quoted || ec != std::errc() || end != last || !std::isfinite(seconds)) {
      p.error(time_tok.column, "expected a time in seconds at the start of the line, got '" + time_tok.text + "'");
      continue;
    }
    if (seconds < 0.0) {
      p.error(time_tok.column, "time " + time_tok.text + " is negative");
      continue;
    }
    if (seconds < previous_s) {
      std::ostringstream msg;
      msg << "time " << time_tok.text << " is earlier than " << previous_s << " on line " << previous_line
          << "; times must be ascending";
      p.error(time_tok.column, msg.str());
      continue;
    }
    if (tokens.size() < 2) {
      p.error(time_tok.column + static_cast<int>(time_tok.text.size()),
              "expected an event name or 'set NAME VALUE' after the time");
      continue;
    }
    ScriptEntry entry;
    entry.time = time_from_seconds(seconds);
    entry.where = p.at(time_tok.column);
    std::size_t expected_tokens = 2;
    if (tokens[1].text == "set" && !tokens[1].quoted) {
      expected_tokens = 4;
      if (tokens.size() < 3) {
        p.error(tokens[1].column + 3, "expected a fact name after 'set'");
        continue;
      }
      if (!p.check_name(tokens[2], "fact name")) continue;
      if (tokens.size() < 4) {
        p.error(tokens[2].column + static_cast<int>(tokens[2].text.size()),
                "expected a value after the fact name '" + tokens[2].text + "'");
        continue;
      }
      entry.kind = ScriptEntry::Kind::set_fact;
      entry.name = tokens[2].text;
      entry.name_where = p.at(tokens[2].column);
      entry.value_text = tokens[3].text;
      entry.value_quoted = tokens[3].quoted;
      entry.value_where = p.at(tokens[3].column);
    } else {
      if (!p.check_name(tokens[1], "event name")) continue;
      entry.kind = ScriptEntry::Kind::event;
      entry.name = tokens[1].text;
      entry.name_where = p.at(tokens[1].column);
    }
    if (tokens.size() > expected_tokens) {
      p.error(tokens[expected_tokens].column, "unexpected '" + tokens[expected_tokens].text + "' at the end of the " +
                                                  (entry.kind == ScriptEntry::Kind::event ? "event" : "set") +
                                                  " line (comments start with '#')");
      continue;
    }
    previous_s = seconds;
    previous_line = line_no;
    script.entries.push_back(std::move(entry));
  }
  if (diagnostics.has_errors()) throw ConfigError(std::move(diagnostics));
  return script;
}

EventScript load_event_script(const std::filesystem::path& file) {
  return parse_event_script(read_config_file(file), file.string());
}

}  // namespace tripodal
