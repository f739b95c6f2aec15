// MCAP conformance: the record lists of the public MCAP conformance suite (tests/data/mcap-conformance,
// MIT), each rebuilt into its file; the reader must pass its CRC checks (which proves the rebuilt
// bytes are the suite's) and return exactly the listed records, field by field.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <zlib.h>

#include "tripodal/trace/mcap.hpp"

using namespace tripodal::trace;
using nlohmann::json;

namespace {

const std::filesystem::path kDir = std::filesystem::path(TRIPODAL_TEST_DATA_DIR) / "mcap-conformance";

struct Out {
  std::vector<std::uint8_t> b;
  void le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void str(const std::string& s) {
    le(s.size(), 4);
    b.insert(b.end(), s.begin(), s.end());
  }
  void raw(const std::vector<std::uint8_t>& v) { b.insert(b.end(), v.begin(), v.end()); }
};

std::uint64_t num(const json& fields, const char* name) { return std::stoull(fields.at(name).get<std::string>()); }
std::string text(const json& fields, const char* name) { return fields.at(name).get<std::string>(); }
std::vector<std::uint8_t> data(const json& fields, const char* name) {
  std::vector<std::uint8_t> v;
  for (const auto& x : fields.at(name)) v.push_back(static_cast<std::uint8_t>(std::stoul(x.get<std::string>())));
  return v;
}
std::vector<std::uint8_t> string_map(const json& m) {
  Out o;
  for (const auto& [k, v] : m.items()) {
    o.str(k);
    o.str(v.get<std::string>());
  }
  return o.b;
}
std::vector<std::uint8_t> id_map(const json& m) {
  Out o;
  for (const auto& [k, v] : m.items()) {
    o.le(std::stoull(k), 2);
    o.le(std::stoull(v.get<std::string>()), 8);
  }
  return o.b;
}

// The record's fields as a map (the lists give [name, value] pairs).
json fields_of(const json& record) {
  json f = json::object();
  for (const auto& pair : record.at("fields")) f[pair.at(0).get<std::string>()] = pair.at(1);
  return f;
}

std::vector<std::uint8_t> rebuild(const json& records) {
  Out file;
  file.raw({0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});
  for (const auto& r : records) {
    const std::string type = r.at("type");
    const json f = fields_of(r);
    Out o;
    std::uint8_t op = 0;
    if (type == "Header") {
      op = 0x01;
      o.str(text(f, "profile"));
      o.str(text(f, "library"));
    } else if (type == "Footer") {
      op = 0x02;
      o.le(num(f, "summary_start"), 8);
      o.le(num(f, "summary_offset_start"), 8);
      o.le(num(f, "summary_crc"), 4);
    } else if (type == "Schema") {
      op = 0x03;
      o.le(num(f, "id"), 2);
      o.str(text(f, "name"));
      o.str(text(f, "encoding"));
      const auto d = data(f, "data");
      o.le(d.size(), 4);
      o.raw(d);
    } else if (type == "Channel") {
      op = 0x04;
      o.le(num(f, "id"), 2);
      o.le(num(f, "schema_id"), 2);
      o.str(text(f, "topic"));
      o.str(text(f, "message_encoding"));
      const auto m = string_map(f.at("metadata"));
      o.le(m.size(), 4);
      o.raw(m);
    } else if (type == "Message") {
      op = 0x05;
      o.le(num(f, "channel_id"), 2);
      o.le(num(f, "sequence"), 4);
      o.le(num(f, "log_time"), 8);
      o.le(num(f, "publish_time"), 8);
      o.raw(data(f, "data"));
    } else if (type == "Attachment") {
      op = 0x09;
      o.le(num(f, "log_time"), 8);
      o.le(num(f, "create_time"), 8);
      o.str(text(f, "name"));
      o.str(text(f, "media_type"));
      const auto d = data(f, "data");
      o.le(d.size(), 8);
      o.raw(d);
      // The lists leave the attachment CRC out: it is the CRC-32 of the fields before it.
      o.le(::crc32(0, o.b.data(), static_cast<uInt>(o.b.size())), 4);
    } else if (type == "AttachmentIndex") {
      op = 0x0A;
      for (const char* n : {"offset", "length", "log_time", "create_time", "data_size"}) o.le(num(f, n), 8);
      o.str(text(f, "name"));
      o.str(text(f, "media_type"));
    } else if (type == "Statistics") {
      op = 0x0B;
      o.le(num(f, "message_count"), 8);
      o.le(num(f, "schema_count"), 2);
      for (const char* n : {"channel_count", "attachment_count", "metadata_count", "chunk_count"}) o.le(num(f, n), 4);
      o.le(num(f, "message_start_time"), 8);
      o.le(num(f, "message_end_time"), 8);
      const auto m = id_map(f.at("channel_message_counts"));
      o.le(m.size(), 4);
      o.raw(m);
    } else if (type == "Metadata") {
      op = 0x0C;
      o.str(text(f, "name"));
      const auto m = string_map(f.at("metadata"));
      o.le(m.size(), 4);
      o.raw(m);
    } else if (type == "MetadataIndex") {
      op = 0x0D;
      o.le(num(f, "offset"), 8);
      o.le(num(f, "length"), 8);
      o.str(text(f, "name"));
    } else if (type == "SummaryOffset") {
      op = 0x0E;
      o.le(num(f, "group_opcode"), 1);
      o.le(num(f, "group_start"), 8);
      o.le(num(f, "group_length"), 8);
    } else if (type == "DataEnd") {
      op = 0x0F;
      o.le(num(f, "data_section_crc"), 4);
    } else {
      FAIL("no builder for record type " << type);
    }
    file.b.push_back(op);
    file.le(o.b.size(), 8);
    file.raw(o.b);
  }
  file.raw({0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});
  return file.b;
}

// What the reader returned, in the lists' terms, for the fields every list names.
void check_fields(const mcap::Record& got, const json& f) {
  std::visit(
      [&](const auto& r) {
        using T = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<T, mcap::Header>) {
          CHECK(r.profile == text(f, "profile"));
          CHECK(r.library == text(f, "library"));
        } else if constexpr (std::is_same_v<T, mcap::Footer>) {
          CHECK(r.summary_start == num(f, "summary_start"));
          CHECK(r.summary_offset_start == num(f, "summary_offset_start"));
          CHECK(r.summary_crc == num(f, "summary_crc"));
        } else if constexpr (std::is_same_v<T, mcap::Schema>) {
          CHECK(r.id == num(f, "id"));
          CHECK(r.name == text(f, "name"));
          CHECK(r.data == data(f, "data"));
        } else if constexpr (std::is_same_v<T, mcap::Channel>) {
          CHECK(r.id == num(f, "id"));
          CHECK(r.schema_id == num(f, "schema_id"));
          CHECK(r.topic == text(f, "topic"));
          CHECK(r.metadata.size() == f.at("metadata").size());
        } else if constexpr (std::is_same_v<T, mcap::Message>) {
          CHECK(r.channel_id == num(f, "channel_id"));
          CHECK(r.sequence == num(f, "sequence"));
          CHECK(r.log_time == num(f, "log_time"));
          CHECK(r.publish_time == num(f, "publish_time"));
          CHECK(r.data == data(f, "data"));
        } else if constexpr (std::is_same_v<T, mcap::Attachment>) {
          CHECK(r.name == text(f, "name"));
          CHECK(r.media_type == text(f, "media_type"));
          CHECK(r.data == data(f, "data"));
        } else if constexpr (std::is_same_v<T, mcap::AttachmentIndex>) {
          CHECK(r.offset == num(f, "offset"));
          CHECK(r.length == num(f, "length"));
          CHECK(r.data_size == num(f, "data_size"));
        } else if constexpr (std::is_same_v<T, mcap::Statistics>) {
          CHECK(r.message_count == num(f, "message_count"));
          CHECK(r.channel_count == num(f, "channel_count"));
          CHECK(r.channel_message_counts.size() == f.at("channel_message_counts").size());
        } else if constexpr (std::is_same_v<T, mcap::Metadata>) {
          CHECK(r.name == text(f, "name"));
          CHECK(r.metadata.at("foo") == "bar");
        } else if constexpr (std::is_same_v<T, mcap::MetadataIndex>) {
          CHECK(r.offset == num(f, "offset"));
          CHECK(r.name == text(f, "name"));
        } else if constexpr (std::is_same_v<T, mcap::SummaryOffset>) {
          CHECK(r.group_opcode == num(f, "group_opcode"));
          CHECK(r.group_start == num(f, "group_start"));
          CHECK(r.group_length == num(f, "group_length"));
        } else if constexpr (std::is_same_v<T, mcap::DataEnd>) {
          CHECK(r.data_section_crc == num(f, "data_section_crc"));
        }
      },
      got.body);
}

}  // namespace

TEST_CASE("mcap conformance: each listed file, rebuilt, passes the CRC checks and reads as listed",
          "[trace][rosbag][mcap]") {
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kDir)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    SECTION(entry.path().filename().string()) {
      std::ifstream in(entry.path());
      const json expected = json::parse(in).at("records");
      const auto bytes = rebuild(expected);
      mcap::Reader reader(std::make_unique<std::istringstream>(std::string(bytes.begin(), bytes.end())),
                          entry.path().filename().string());
      std::vector<mcap::Record> got;
      mcap::Record r;
      while (reader.next(r)) got.push_back(r);  // a CRC that does not match throws here
      CHECK(reader.state() == mcap::State::kEnd);
      REQUIRE(got.size() == expected.size());
      for (std::size_t i = 0; i < got.size(); ++i) {
        INFO("record " << i);
        CHECK(mcap::to_string(got[i].opcode) == expected[i].at("type").get<std::string>());
        check_fields(got[i], fields_of(expected[i]));
      }
    }
  }
  CHECK(files == 6);
}

TEST_CASE("mcap conformance: a rebuilt file whose bytes differ from the suite's fails its CRC check",
          "[trace][rosbag][mcap]") {
  std::ifstream in(kDir / "OneMessage-rch-rsh-st-sum.json");
  json records = json::parse(in).at("records");
  // Change the message's log time: the file still parses, but no longer matches the listed CRCs.
  for (auto& r : records) {
    if (r.at("type") == "Message") r["fields"][2][1] = "3";
  }
  const auto bytes = rebuild(records);
  mcap::Reader reader(std::make_unique<std::istringstream>(std::string(bytes.begin(), bytes.end())), "changed.mcap");
  mcap::Record r;
  CHECK_THROWS_WITH(
      [&] {
        while (reader.next(r)) {
        }
      }(),
      Catch::Contains("changed.mcap: byte ") && Catch::Contains("DataEnd: data section CRC-32 "));
}
