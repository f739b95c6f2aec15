#include "yaml_reader.hpp"

#include <fmt/format.h>

#include <yaml-cpp/eventhandler.h>

#include <cmath>
#include <sstream>
#include <unordered_map>

namespace tripodal::yaml {

namespace {

std::string joined(KeyList items, std::string_view separator) {
  std::string out;
  for (std::string_view s : items) {
    if (!out.empty()) out += separator;
    out += s;
  }
  return out;
}

// yaml-cpp's own conversion, but never an exception and never a non-finite number: "nan" and
// ".inf" are valid YAML floats that no configuration value means.
std::optional<double> finite(const YAML::Node& node) {
  double v = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || !std::isfinite(v)) return std::nullopt;
  return v;
}

// YAML says a mapping's keys are unique, but yaml-cpp keeps both pairs and `map["k"]` answers the
// first: a profile that sets `period_s` twice would run with the value its author did not read
// last. The parser's events see every key where it is written (an alias is one event, so a
// document of aliases is scanned in its length, never expanded).
class DuplicateKeys final : public YAML::EventHandler {
 public:
  DuplicateKeys(const std::string& file, Diagnostics& d) : file_(file), d_(d) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override { leaf(); }
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override { leaf(); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    if (in_key_position()) {
      const auto [first, inserted] = frames_.back().keys.try_emplace(value, mark);
      if (!inserted) {
        d_.error(located(mark), fmt::format("duplicate key '{}' (first at {}:{}:{}); a key may appear once in a map", value, file_,
                                            first->second.line + 1, first->second.column + 1));
      }
    }
    leaf();
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    frames_.push_back({});
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    frames_.push_back({true, 0, {}});
  }
  void OnMapEnd() override { close(); }

 private:
  struct Frame {
    bool map = false;
    std::size_t children = 0;  // in a map, keys and values alternate: an even count is a key next
    std::unordered_map<std::string, YAML::Mark> keys;
  };
  [[nodiscard]] bool in_key_position() const { return !frames_.empty() && frames_.back().map && frames_.back().children % 2 == 0; }
  void leaf() {
    if (!frames_.empty()) ++frames_.back().children;
  }
  void close() {
    frames_.pop_back();
    leaf();
  }
  [[nodiscard]] SourceLocation located(const YAML::Mark& m) const { return {file_, m.line + 1, m.column + 1}; }

  const std::string& file_;
  Diagnostics& d_;
  std::vector<Frame> frames_;
};

}  // namespace

std::string read_file(const std::filesystem::path& file) { return read_config_file(file); }

YAML::Node parse(std::string_view text, const std::string& file) {
  try {
    std::string owned(text);
    YAML::Node root = YAML::Load(owned);
    // The document parsed: now its keys, every duplicate at once, each with both places.
    std::istringstream in(std::move(owned));
    YAML::Parser parser(in);
    Diagnostics d;
    DuplicateKeys keys(file, d);
    parser.HandleNextDocument(keys);
    if (d.has_errors()) throw ConfigError(std::move(d));
    return root;
  } catch (const YAML::Exception& e) {
    throw ConfigError(SourceLocation{file, e.mark.line + 1, e.mark.column + 1}, "YAML syntax error: " + e.msg);
  }
}

std::string kind(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map: return "a map";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Scalar: return "'" + node.Scalar() + "'";
    case YAML::NodeType::Null: return "nothing";
    case YAML::NodeType::Undefined: break;
  }
  return "nothing";
}

SourceLocation Reader::at(const YAML::Node& node) const {
  const YAML::Mark m = node.Mark();
  // Only a document with no node at all (an empty file) has no position: its start is where to
  // write the missing content (found by fuzz_robot_profile: an empty profile was reported unlocated).
  if (m.line < 0) return {file_, 1, 1};
  return {file_, m.line + 1, m.column + 1};
}

void Reader::error(const YAML::Node& node, std::string message) { d_.error(at(node), std::move(message)); }

bool Reader::expect_map(const YAML::Node& node, std::string_view what) {
  if (node.IsMap()) return true;
  error(node, fmt::format("{}: expected a map, got {}", what, kind(node)));
  return false;
}

bool Reader::expect_list(const YAML::Node& node, std::string_view what) {
  if (node.IsSequence()) return true;
  error(node, fmt::format("{}: expected a list, got {}", what, kind(node)));
  return false;
}

bool Reader::expect_keys(const YAML::Node& map, KeyList allowed, std::string_view what) {
  if (!expect_map(map, what)) return false;
  for (const auto& kv : map) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : kind(kv.first);
    bool known = false;
    for (std::string_view a : allowed) known = known || a == key;
    if (!known) error(kv.first, fmt::format("unknown key '{}' in {}; expected one of: {}", key, what, joined(allowed, ", ")));
  }
  return true;
}

YAML::Node Reader::require(const YAML::Node& map, std::string_view key, std::string_view what,
                           std::string_view expected) {
  YAML::Node value = map[std::string(key)];
  if (!value) error(map, fmt::format("{}: missing '{}' ({})", what, key, expected));
  return value;
}

std::optional<std::string> Reader::key(const YAML::Node& key, std::string_view what) {
  if (key.IsScalar()) return key.Scalar();
  error(key, fmt::format("{}: a key must be text, got {}", what, kind(key)));
  return std::nullopt;
}

std::optional<std::string> Reader::text(const YAML::Node& node, std::string_view what, bool non_empty) {
  if (!node.IsScalar() || (non_empty && node.Scalar().empty())) {
    error(node, fmt::format("{}: expected {}, got {}", what, non_empty ? "a non-empty text" : "text",
                            node.IsScalar() ? std::string("an empty text") : kind(node)));
    return std::nullopt;
  }
  return node.Scalar();
}

std::optional<double> Reader::number(const YAML::Node& node, std::string_view what) {
  if (auto v = finite(node)) return v;
  error(node, fmt::format("{}: expected a number, got {}", what, kind(node)));
  return std::nullopt;
}

std::optional<double> Reader::positive(const YAML::Node& node, std::string_view what) {
  const auto v = finite(node);
  if (v && *v > 0.0) return v;
  error(node, fmt::format("{}: expected a number > 0, got {}", what, kind(node)));
  return std::nullopt;
}

std::optional<double> Reader::seconds(const YAML::Node& node, std::string_view what, double min_s, double max_s) {
  const auto v = finite(node);
  if (v && *v >= min_s && *v <= max_s) return v;
  error(node, fmt::format("{}: expected seconds from {:g} to {:g}, got {}", what, min_s, max_s, kind(node)));
  return std::nullopt;
}

std::optional<double> Reader::non_negative(const YAML::Node& node, std::string_view what) {
  const auto v = finite(node);
  if (v && *v >= 0.0) return v;
  error(node, fmt::format("{}: expected a number >= 0, got {}", what, kind(node)));
  return std::nullopt;
}

std::optional<std::int64_t> Reader::integer(const YAML::Node& node, std::string_view what, std::int64_t lo,
                                            std::int64_t hi) {
  const auto v = finite(node);
  if (v && *v == std::floor(*v) && *v >= static_cast<double>(lo) && *v <= static_cast<double>(hi)) {
    return static_cast<std::int64_t>(*v);
  }
  error(node, fmt::format("{}: expected a whole number from {} to {}, got {}", what, lo, hi, kind(node)));
  return std::nullopt;
}

std::optional<bool> Reader::boolean(const YAML::Node& node, std::string_view what) {
  bool v = false;
  if (node.IsScalar()) {
    if (node.Scalar() == "1" || node.Scalar() == "0") return node.Scalar() == "1";
    if (YAML::convert<bool>::decode(node, v)) return v;
  }
  error(node, fmt::format("{}: expected true or false, got {}", what, kind(node)));
  return std::nullopt;
}

std::optional<std::string> Reader::choice(const YAML::Node& node, std::string_view what, KeyList choices) {
  if (node.IsScalar()) {
    for (std::string_view c : choices) {
      if (node.Scalar() == c) return node.Scalar();
    }
  }
  error(node, fmt::format("{}: expected one of {}; got {}", what, joined(choices, ", "), kind(node)));
  return std::nullopt;
}

std::optional<std::vector<std::string>> Reader::names(const YAML::Node& node, std::string_view what) {
  if (!node.IsSequence()) {
    error(node, fmt::format("{}: expected a list of names, got {}", what, kind(node)));
    return std::nullopt;
  }
  std::vector<std::string> out;
  bool ok = true;
  for (const auto& item : node) {
    auto s = text(item, what, true);
    ok = ok && s.has_value();
    if (s) out.push_back(std::move(*s));
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<std::vector<double>> Reader::numbers(const YAML::Node& node, std::string_view what,
                                                   std::size_t min_count, std::size_t max_count,
                                                   std::string_view shape) {
  if (!node.IsSequence() || node.size() < min_count || node.size() > max_count) {
    error(node, fmt::format("{}: expected {}, got {}", what, shape,
                            node.IsSequence() ? fmt::format("a list of {} items", node.size()) : kind(node)));
    return std::nullopt;
  }
  std::vector<double> out;
  bool ok = true;
  for (const auto& item : node) {
    auto v = number(item, what);
    ok = ok && v.has_value();
    out.push_back(v.value_or(0.0));
  }
  if (!ok) return std::nullopt;
  return out;
}

}  // namespace tripodal::yaml
