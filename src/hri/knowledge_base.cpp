#include "tripodal/hri/knowledge_base.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <system_error>
#include <utility>

#include "tripodal/core/xml_text.hpp"
#include "tripodal_core_internal/xml_document.hpp"
#include "tripodal_core_internal/xml_locator.hpp"

namespace tripodal {

namespace {

using detail::XmlAttribute;
using detail::XmlDocument;
using detail::XmlElement;
using detail::XmlLocator;

bool id_char(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
         c == '.';
}

std::string trimmed(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

std::vector<std::string> split_keywords(std::string_view text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? text.size() : comma;
    std::string k = trimmed(text.substr(start, end - start));
    if (!k.empty()) out.push_back(std::move(k));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

struct Reader {
  const XmlLocator& at;
  Diagnostics& d;

  void check_attributes(const XmlElement* e, std::initializer_list<std::string_view> allowed) const {
    for (const XmlAttribute& a : e->attributes()) {
      if (std::find(allowed.begin(), allowed.end(), a.name) != allowed.end()) continue;
      std::string list;
      for (const auto n : allowed) list += (list.empty() ? "" : ", ") + std::string(n);
      d.error(at.attribute(e, a.name), "unknown attribute '" + std::string(a.name) + "' on <" + std::string(e->name()) +
                                           ">; expected " + (list.empty() ? std::string("none") : "one of: " + list));
    }
  }

  // An element that holds text only (keywords, question, answer, action).
  std::string text_of(const XmlElement* e) const {
    check_attributes(e, {});
    for (const XmlElement* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      d.error(at.element(c), "unexpected element <" + std::string(c->name()) + "> inside <" + std::string(e->name()) +
                                 ">; expected text only");
    }
    return std::string(e->text());
  }

  std::optional<KnowledgeEntry> entry(const XmlElement* e) const {
    check_attributes(e, {"id", "topic"});
    const std::size_t errors_before = d.error_count();
    KnowledgeEntry entry;
    entry.where = at.element(e);
    if (const auto id = e->attribute("id")) {
      entry.id = std::string(*id);
      if (entry.id.empty() || !std::all_of(entry.id.begin(), entry.id.end(), id_char)) {
        d.error(at.attribute_value(e, "id"), "entry id '" + entry.id + "': expected letters, digits, '_', '-' or '.'");
      }
    } else {
      d.error(at.element(e), "<entry> has no id attribute; expected id=\"...\"");
    }
    if (const auto topic = e->attribute("topic")) {
      entry.topic = trimmed(*topic);
      if (entry.topic.empty()) d.error(at.attribute_value(e, "topic"), "entry '" + entry.id + "': the topic is empty; expected a few words");
    } else {
      d.error(at.element(e), "entry '" + entry.id + "' has no topic attribute; expected topic=\"...\"");
    }
    if (!e->text().empty()) d.error(at.element(e), "unexpected text in <entry> '" + entry.id + "'; expected elements only");
    const XmlElement* answer = nullptr;
    const XmlElement* keywords = nullptr;
    const XmlElement* action = nullptr;
    for (const XmlElement* c = e->first_child(); c != nullptr; c = c->next_sibling()) {
      const std::string_view name = c->name();
      const auto once = [&](const XmlElement*& seen) {
        if (seen != nullptr) {
          d.error(at.element(c), "entry '" + entry.id + "' has a second <" + std::string(name) + ">; expected at most one");
          return false;
        }
        seen = c;
        return true;
      };
      if (name == "keywords") {
        if (once(keywords)) {
          const std::string text = text_of(c);
          entry.keywords = split_keywords(text);
          if (entry.keywords.empty()) d.error(at.element(c), "entry '" + entry.id + "': <keywords> is empty; expected words separated by commas");
        }
      } else if (name == "question") {
        std::string q = text_of(c);
        if (q.empty()) d.error(at.element(c), "entry '" + entry.id + "': <question> is empty; expected a question form");
        entry.questions.push_back(std::move(q));
      } else if (name == "answer") {
        if (once(answer)) {
          entry.answer = text_of(c);
          if (entry.answer.empty()) {
            d.error(at.element(c), "entry '" + entry.id + "': <answer> is empty; expected what the robot says");
          } else {
            const PlaceholderScan scan = scan_placeholders(entry.answer);
            if (!scan.error.empty()) d.error(at.element(c), "entry '" + entry.id + "': answer: " + scan.error);
          }
        }
      } else if (name == "action") {
        if (once(action)) {
          entry.action = text_of(c);
          if (entry.action.empty()) d.error(at.element(c), "entry '" + entry.id + "': <action> is empty; expected a task command such as \"guide me to node 1\"");
        }
      } else {
        d.error(at.element(c), "unknown element <" + std::string(name) + "> in <entry>; expected one of: keywords, question, answer, action");
      }
    }
    if (answer == nullptr) d.error(at.element(e), "entry '" + entry.id + "' has no <answer>; expected one");
    if (keywords == nullptr && entry.questions.empty()) {
      d.error(at.element(e), "entry '" + entry.id + "' has neither <keywords> nor <question>; expected at least one");
    }
    if (d.error_count() != errors_before) return std::nullopt;
    return entry;
  }
};

std::optional<std::uint64_t> parse_version(std::string_view text) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty()) return std::nullopt;
  return v;
}

KnowledgeBase parse(std::string_view text, std::string_view name, std::uint64_t& version) {
  Diagnostics d;
  XmlDocument doc;
  const XmlLocator at(doc, SourceFile(name));
  if (!doc.parse(text)) {
    d.error(at.offset(doc.error().offset), "malformed XML: " + doc.error().message);
    throw ConfigError(std::move(d));
  }
  const XmlElement* root = doc.root();
  if (root == nullptr) throw ConfigError(SourceLocation{std::string(name), 1, 1}, "no root element; expected <knowledge>");
  if (root->name() != "knowledge") {
    throw ConfigError(at.element(root), "root element <" + std::string(root->name()) + ">; expected <knowledge>");
  }
  const Reader r{at, d};
  r.check_attributes(root, {"version", "robot", "xmlns:xsi", "xsi:noNamespaceSchemaLocation"});
  KnowledgeBase base;
  version = 0;
  if (const auto v = root->attribute("version")) {
    if (const auto parsed = parse_version(*v)) {
      version = *parsed;
    } else {
      d.error(at.attribute_value(root, "version"), "version '" + std::string(*v) + "': expected a whole number 0 or more");
    }
  }
  if (const auto robot = root->attribute("robot")) base.set_robot(std::string(*robot));
  if (!root->text().empty()) d.error(at.element(root), "unexpected text in <knowledge>; expected <entry> elements");
  std::vector<KnowledgeEntry> entries;
  for (const XmlElement* e = root->first_child(); e != nullptr; e = e->next_sibling()) {
    if (e->name() != "entry") {
      d.error(at.element(e), "unknown element <" + std::string(e->name()) + "> in <knowledge>; expected <entry>");
      continue;
    }
    auto entry = r.entry(e);
    if (!entry) continue;
    const auto first = std::find_if(entries.begin(), entries.end(), [&](const KnowledgeEntry& x) { return x.id == entry->id; });
    if (first != entries.end()) {
      d.error(at.attribute_value(e, "id"), "duplicate entry id '" + entry->id + "'; ids must be unique");
      d.note(first->where, "entry '" + entry->id + "' first defined here");
      continue;
    }
    entries.push_back(std::move(*entry));
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  for (auto& e : entries) base.put(std::move(e));
  return base;
}

}  // namespace

std::vector<KnowledgeFieldError> knowledge_entry_errors(const KnowledgeEntry& e) {
  std::vector<KnowledgeFieldError> out;
  const std::string who = "entry '" + e.id + "'";
  if (e.id.empty()) {
    out.push_back({"id", "an entry needs an id: letters, digits, '_', '-' or '.'"});
  } else if (!std::all_of(e.id.begin(), e.id.end(), id_char)) {
    out.push_back({"id", "entry id '" + e.id + "': expected letters, digits, '_', '-' or '.'"});
  }
  if (trimmed(e.topic).empty()) out.push_back({"topic", who + ": the topic is empty; expected a few words"});
  if (e.keywords.empty() && e.questions.empty()) {
    out.push_back({"keywords", who + " has neither keywords nor questions; expected at least one"});
  }
  for (std::size_t i = 0; i < e.keywords.size(); ++i) {
    const std::string& k = e.keywords[i];
    if (trimmed(k).empty() || k.find(',') != std::string::npos) {
      out.push_back({"keywords[" + std::to_string(i) + "]", who + ": keyword '" + k + "' is empty or holds a comma"});
    }
  }
  for (std::size_t i = 0; i < e.questions.size(); ++i) {
    if (trimmed(e.questions[i]).empty()) out.push_back({"questions[" + std::to_string(i) + "]", who + ": a question is empty"});
  }
  if (trimmed(e.answer).empty()) {
    out.push_back({"answer", who + ": the answer is empty; expected what the robot says"});
  } else {
    const PlaceholderScan scan = scan_placeholders(e.answer);
    if (!scan.error.empty()) out.push_back({"answer", who + ": answer: " + scan.error});
  }
  return out;
}

PlaceholderScan scan_placeholders(std::string_view answer) {
  PlaceholderScan scan;
  std::size_t i = 0;
  while (i < answer.size()) {
    const char c = answer[i];
    if (c == '{' && i + 1 < answer.size() && answer[i + 1] == '{') {
      i += 2;
      continue;
    }
    if (c == '}') {
      if (i + 1 < answer.size() && answer[i + 1] == '}') {
        i += 2;
        continue;
      }
      scan.error = "'}' at byte " + std::to_string(i) + " closes nothing; write '}}' for a brace";
      scan.error_offset = i;
      return scan;
    }
    if (c != '{') {
      ++i;
      continue;
    }
    const std::size_t close = answer.find('}', i + 1);
    if (close == std::string_view::npos) {
      scan.error = "unclosed '{' at byte " + std::to_string(i) + "; expected {provider} or '{{' for a brace";
      scan.error_offset = i;
      return scan;
    }
    const std::string_view name = answer.substr(i + 1, close - i - 1);
    const bool ok = !name.empty() && std::all_of(name.begin(), name.end(), [](char ch) {
      return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_';
    });
    if (!ok) {
      scan.error = "placeholder '{" + std::string(name) + "}' at byte " + std::to_string(i) +
                   ": expected a provider name of lower-case letters, digits and '_'";
      scan.error_offset = i;
      return scan;
    }
    scan.placeholders.push_back({std::string(name), i});
    i = close + 1;
  }
  return scan;
}

StaleVersionError::StaleVersionError(const std::string& file, std::uint64_t expected, std::uint64_t found)
    : std::runtime_error(file + ": stale version: this copy was read at version " + std::to_string(expected) +
                         " but the file is at version " + std::to_string(found) +
                         "; reload it and apply the change again (nothing was written)"),
      expected_(expected),
      found_(found) {}

KnowledgeBase KnowledgeBase::load(const std::filesystem::path& file) {
  const std::string text = read_config_file(file);
  return load_from_string(text, file.string());
}

KnowledgeBase KnowledgeBase::load_from_string(std::string_view xml, std::string_view name) {
  std::uint64_t version = 0;
  KnowledgeBase base = parse(xml, name, version);
  base.version_ = version;
  return base;
}

const KnowledgeEntry* KnowledgeBase::find(std::string_view id) const noexcept {
  const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const KnowledgeEntry& e) { return e.id == id; });
  return it == entries_.end() ? nullptr : &*it;
}

void KnowledgeBase::put(KnowledgeEntry entry) {
  const std::vector<KnowledgeFieldError> problems = knowledge_entry_errors(entry);
  if (!problems.empty()) {
    std::string text;
    for (const auto& p : problems) text += (text.empty() ? "" : "; ") + p.message;
    throw std::invalid_argument(text);
  }
  const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const KnowledgeEntry& e) { return e.id == entry.id; });
  if (it != entries_.end()) {
    *it = std::move(entry);
  } else {
    entries_.push_back(std::move(entry));
  }
}

bool KnowledgeBase::remove(std::string_view id) {
  const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const KnowledgeEntry& e) { return e.id == id; });
  if (it == entries_.end()) return false;
  entries_.erase(it);
  return true;
}

namespace {

void escape_into(std::string& out, std::string_view text, bool attribute) {
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"':
        if (attribute) {
          out += "&quot;";
        } else {
          out += c;
        }
        break;
      // Line breaks inside an attribute would be normalised to spaces by a reader.
      case '\n':
        out += attribute ? "&#10;" : "\n";
        break;
      default: out += c;
    }
  }
}

}  // namespace

std::string KnowledgeBase::to_xml(std::uint64_t version) const {
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<knowledge version=\"" + std::to_string(version) + "\"";
  if (!robot_.empty()) {
    out += " robot=\"";
    escape_into(out, robot_, true);
    out += "\"";
  }
  out += ">\n";
  for (const auto& e : entries_) {
    out += "  <entry id=\"";
    escape_into(out, e.id, true);
    out += "\" topic=\"";
    escape_into(out, e.topic, true);
    out += "\">\n";
    if (!e.keywords.empty()) {
      out += "    <keywords>";
      for (std::size_t i = 0; i < e.keywords.size(); ++i) {
        if (i > 0) out += ", ";
        escape_into(out, e.keywords[i], false);
      }
      out += "</keywords>\n";
    }
    for (const auto& q : e.questions) {
      out += "    <question>";
      escape_into(out, q, false);
      out += "</question>\n";
    }
    out += "    <answer>";
    escape_into(out, e.answer, false);
    out += "</answer>\n";
    if (!e.action.empty()) {
      out += "    <action>";
      escape_into(out, e.action, false);
      out += "</action>\n";
    }
    out += "  </entry>\n";
  }
  out += "</knowledge>\n";
  return out;
}

namespace {

// A file descriptor closed on every path.
class Fd {
 public:
  explicit Fd(int fd) noexcept : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int get() const noexcept { return fd_; }
  int release() noexcept { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

[[noreturn]] void throw_errno(const std::string& what) {
  throw std::system_error(errno, std::generic_category(), what);
}

std::uint64_t version_on_disk(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return 0;
  const std::string text = read_config_file(file);
  XmlDocument doc;
  const XmlLocator at(doc, SourceFile(file.string()));
  if (!doc.parse(text)) throw ConfigError(at.offset(doc.error().offset), "malformed XML: " + doc.error().message);
  if (doc.root() == nullptr) return 0;
  const auto v = doc.root()->attribute("version");
  if (!v) return 0;
  const auto parsed = parse_version(*v);
  if (!parsed) throw ConfigError(at.attribute_value(doc.root(), "version"), "version '" + std::string(*v) + "': expected a whole number 0 or more");
  return *parsed;
}

// The file is XML: a text XML cannot hold (U+FFFE, a control character, bytes that are not UTF-8)
// would be written and then refused by every reader, so it is refused before anything is written.
void check_saveable(const std::string& robot, const std::vector<KnowledgeEntry>& entries) {
  const auto check = [](const std::string& where, std::string_view text) {
    if (const auto fault = find_xml_text_fault(text)) {
      throw std::invalid_argument("knowledge base: " + where + ": " + describe(*fault) + "; nothing was saved");
    }
  };
  check("the robot's name", robot);
  for (const KnowledgeEntry& e : entries) {
    const std::string entry = "entry '" + e.id + "'";
    check(entry + " id", e.id);
    check(entry + " topic", e.topic);
    for (std::size_t i = 0; i < e.keywords.size(); ++i) check(entry + " keywords[" + std::to_string(i) + "]", e.keywords[i]);
    for (std::size_t i = 0; i < e.questions.size(); ++i) check(entry + " questions[" + std::to_string(i) + "]", e.questions[i]);
    check(entry + " answer", e.answer);
    check(entry + " action", e.action);
  }
}

}  // namespace

void KnowledgeBase::save(const std::filesystem::path& file) {
  check_saveable(robot_, entries_);
  const std::string lock_path = file.string() + ".lock";
  const Fd lock(::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644));
  if (lock.get() < 0) throw_errno("cannot open the lock file " + lock_path);
  while (::flock(lock.get(), LOCK_EX) != 0) {
    if (errno != EINTR) throw_errno("cannot lock " + lock_path);
  }
  // Under the lock: no other saver can move the version between this check and the rename.
  const std::uint64_t found = version_on_disk(file);
  if (found != version_) throw StaleVersionError(file.string(), version_, found);

  const std::string text = to_xml(version_ + 1);
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  const std::filesystem::path tmp = dir / ("." + file.filename().string() + ".tmp." + std::to_string(::getpid()));
  {
    Fd out(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
    if (out.get() < 0) throw_errno("cannot create " + tmp.string());
    std::size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = ::write(out.get(), text.data() + written, text.size() - written);
      if (n < 0) {
        if (errno == EINTR) continue;
        const int err = errno;
        ::unlink(tmp.c_str());
        throw std::system_error(err, std::generic_category(), "cannot write " + tmp.string());
      }
      written += static_cast<std::size_t>(n);
    }
    // The data must be on disk before the rename makes it the file, or a crash could leave an
    // empty file under the real name.
    if (::fsync(out.get()) != 0 || ::close(out.release()) != 0) {
      const int err = errno;
      ::unlink(tmp.c_str());
      throw std::system_error(err, std::generic_category(), "cannot flush " + tmp.string());
    }
  }
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::system_error(err, std::generic_category(), "cannot rename " + tmp.string() + " to " + file.string());
  }
  // The rename itself is durable once the folder is flushed.
  const Fd dir_fd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir_fd.get() >= 0) (void)::fsync(dir_fd.get());
  version_ += 1;
}

}  // namespace tripodal
