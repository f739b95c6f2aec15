// The SQLite3 storage of rosbag2 (the default before ROS 2 Iron): table topics (id, name, type,
// serialization_format, ...) and table messages (id, topic_id, timestamp, data); tables schema and
// metadata (newer bags) are not needed to read the messages.
#include "rosbag_sqlite.hpp"

#include <sqlite3.h>

#include <map>
#include <memory>
#include <set>

namespace tripodal::trace::detail {

namespace {

struct DbCloser {
  void operator()(sqlite3* db) const noexcept { sqlite3_close(db); }
};
struct StmtCloser {
  void operator()(sqlite3_stmt* s) const noexcept { sqlite3_finalize(s); }
};
using Db = std::unique_ptr<sqlite3, DbCloser>;
using Stmt = std::unique_ptr<sqlite3_stmt, StmtCloser>;

struct Topic {
  std::string name, type, encoding;
};

std::string fs_absolute(const std::filesystem::path& file) {
  std::error_code ec;
  const auto abs = std::filesystem::absolute(file, ec);
  return ec ? file.string() : abs.string();
}

std::string text(sqlite3_stmt* s, int col) {
  const auto* p = sqlite3_column_text(s, col);
  return p == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(p),
                                                    static_cast<std::size_t>(sqlite3_column_bytes(s, col)));
}

}  // namespace

void for_each_db3_message(const std::filesystem::path& file, const std::function<void(const BagMessage&)>& visit,
                          BagImportReport& report) {
  const std::string name = file.string();
  if (!std::filesystem::is_regular_file(file)) throw TraceIoError(name + ": no such file");
  // immutable=1: a closed bag is only read, so SQLite takes no locks and writes no -shm/-wal files
  // beside it (a WAL-mode bag in a read-only folder, or in the source tree, stays untouched).
  std::string uri = "file:";
  for (const char c : fs_absolute(file)) {
    if (c == '%' || c == '?' || c == '#') {
      static constexpr char kHex[] = "0123456789ABCDEF";
      uri += '%';
      uri += kHex[static_cast<unsigned char>(c) >> 4];
      uri += kHex[static_cast<unsigned char>(c) & 15];
    } else {
      uri += c;
    }
  }
  uri += "?immutable=1";
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(uri.c_str(), &raw, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
  Db db(raw);
  if (rc != SQLITE_OK) throw TraceIoError(name + ": cannot open as SQLite3: " + sqlite3_errstr(rc));
  const auto prepare = [&](const char* sql, const std::string& what) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db.get(), sql, -1, &s, nullptr) != SQLITE_OK) {
      Stmt guard(s);
      throw BagFormatError(name + ": " + what + ": " + sqlite3_errmsg(db.get()));
    }
    return Stmt(s);
  };

  std::set<std::string> tables;
  {
    Stmt s = prepare("SELECT name FROM sqlite_master WHERE type = 'table'", "not a SQLite3 database");
    while (sqlite3_step(s.get()) == SQLITE_ROW) tables.insert(text(s.get(), 0));
  }
  for (const char* required : {"topics", "messages"}) {
    if (tables.count(required) == 0) {
      std::string list;
      for (const auto& t : tables) list += (list.empty() ? "" : ", ") + t;
      throw BagFormatError(name + ": no table '" + required + "': not a rosbag2 SQLite3 bag (tables: " +
                           (list.empty() ? "none" : list) + ")");
    }
  }

  // Newer bags (rosbag2 schema 3 and later) say which ROS release wrote them.
  if (tables.count("schema") != 0) {
    Stmt s = prepare("SELECT schema_version, ros_distro FROM schema", "table schema");
    if (sqlite3_step(s.get()) == SQLITE_ROW) {
      report.storage_metadata["schema_version"] = text(s.get(), 0);
      report.storage_metadata["ros_distro"] = text(s.get(), 1);
    }
  }

  std::map<std::int64_t, Topic> topics;
  {
    Stmt s = prepare("SELECT id, name, type, serialization_format FROM topics", "table topics");
    int step = 0;
    while ((step = sqlite3_step(s.get())) == SQLITE_ROW) {
      const std::int64_t id = sqlite3_column_int64(s.get(), 0);
      Topic t{text(s.get(), 1), text(s.get(), 2), text(s.get(), 3)};
      report.topic_types[t.name] = t.type;
      topics[id] = std::move(t);
    }
    if (step != SQLITE_DONE) throw BagFormatError(name + ": table topics: " + sqlite3_errmsg(db.get()));
  }

  Stmt s = prepare("SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id", "table messages");
  int step = 0;
  while ((step = sqlite3_step(s.get())) == SQLITE_ROW) {
    const std::int64_t row = sqlite3_column_int64(s.get(), 0);
    const std::int64_t topic_id = sqlite3_column_int64(s.get(), 1);
    const auto it = topics.find(topic_id);
    if (it == topics.end()) {
      throw BagFormatError(name + ": table messages, row id " + std::to_string(row) + ": topic_id " +
                           std::to_string(topic_id) + " is not in table topics");
    }
    const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(s.get(), 3));
    const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(s.get(), 3));
    const Topic& t = it->second;
    ++report.messages;
    ++report.topic_messages[t.name];
    visit(BagMessage{t.name, t.type, t.encoding, sqlite3_column_int64(s.get(), 2),
                     std::span<const std::uint8_t>(blob, blob == nullptr ? 0 : bytes), name,
                     static_cast<std::uint64_t>(row), false, 0});
  }
  if (step != SQLITE_DONE) throw BagFormatError(name + ": table messages: " + sqlite3_errmsg(db.get()));
}

}  // namespace tripodal::trace::detail
