#include <catch2/catch.hpp>
#include <sstream>

#include <zlib.h>

#include "trace_test_util.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace tripodal::trace;
using namespace tripodal::trace::test;
using namespace std::chrono_literals;

namespace {

// Writes one record of every kind, each on its own channel, plus a second laser channel.
std::vector<RecordData> write_sample(const std::filesystem::path& path) {
  TraceWriter w(path);
  const auto records = one_of_each(time_from_ns(1'700'000'000'000'000'000));
  std::vector<ChannelId> ids;
  for (const auto& r : records) {
    ids.push_back(w.add_channel("ch_" + std::string(to_string(kind_of(r))), kind_of(r)));
  }
  for (std::size_t i = 0; i < records.size(); ++i) w.write(ids[i], records[i]);
  w.close();
  return records;
}

std::vector<TraceRecord> read_everything(TraceReader& r) {
  std::vector<TraceRecord> out;
  TraceRecord rec;
  while (r.next(rec)) out.push_back(rec);
  return out;
}

}  // namespace

TEST_CASE("every reading kind survives a write/read round trip") {
  TempFile file("roundtrip");
  const auto written = write_sample(file.path());
  TraceReader reader(file.path());
  CHECK(reader.format_version() == 1);
  const auto read = read_everything(reader);
  CHECK(reader.state() == ReadState::kEnd);
  CHECK(reader.warning().empty());
  REQUIRE(read.size() == written.size());
  for (std::size_t i = 0; i < read.size(); ++i) {
    INFO("record " << i << " of kind " << to_string(kind_of(written[i])));
    CHECK(read[i].data == written[i]);
    CHECK(reader.channel(read[i].channel).kind == kind_of(written[i]));
    CHECK(reader.channel(read[i].channel).name == "ch_" + std::string(to_string(kind_of(written[i]))));
  }
  CHECK(reader.channels().size() == 9);
  CHECK(reader.offset() == std::filesystem::file_size(file.path()));
}

TEST_CASE("a NaN range keeps its bits") {
  TempFile file("nan");
  LaserScan scan = sample_scan(Time{5ms}, 10);
  scan.ranges_m[3] = std::nanf("");
  {
    TraceWriter w(file.path());
    w.write(w.add_channel("front_laser", ChannelKind::kLaser), scan);
  }
  TraceReader r(file.path());
  TraceRecord rec;
  REQUIRE(r.next(rec));
  const auto& got = std::get<LaserScan>(rec.data);
  CHECK(std::isnan(got.ranges_m[3]));
  CHECK(got.ranges_m[4] == scan.ranges_m[4]);
}

TEST_CASE("several channels of the same kind keep their names") {
  TempFile file("channels");
  {
    TraceWriter w(file.path());
    const auto front = w.add_channel("front_laser", ChannelKind::kLaser);
    const auto rear = w.add_channel("rear_laser", ChannelKind::kLaser);
    w.write(front, sample_scan(Time{1ms}, 4));
    w.write(rear, sample_scan(Time{2ms}, 6));
    // A channel can be declared in the middle of a recording.
    const auto late = w.add_channel("late_odom", ChannelKind::kOdometry);
    w.write(late, OdometryReading{Time{3ms}, {}, {}});
  }
  TraceReader r(file.path());
  const auto recs = read_everything(r);
  REQUIRE(recs.size() == 3);
  CHECK(r.channel(recs[0].channel).name == "front_laser");
  CHECK(std::get<LaserScan>(recs[0].data).ranges_m.size() == 4);
  CHECK(r.channel(recs[1].channel).name == "rear_laser");
  CHECK(std::get<LaserScan>(recs[1].data).ranges_m.size() == 6);
  CHECK(r.channel(recs[2].channel).name == "late_odom");
}

TEST_CASE("the writer refuses records its channel does not carry") {
  TempFile file("contract");
  TraceWriter w(file.path());
  const auto odom = w.add_channel("odom", ChannelKind::kOdometry);
  CHECK_THROWS_WITH(w.write(odom, sample_scan(Time{0ms}, 3)), Catch::Contains("carries odometry records, not laser"));
  CHECK_THROWS_WITH(w.write(ChannelId{7}, OdometryReading{}), Catch::Contains("channel 7 is not declared"));
  CHECK_THROWS_WITH(w.add_channel("odom", ChannelKind::kLaser), Catch::Contains("'odom' is already declared"));
  CHECK_THROWS_AS(w.add_channel("", ChannelKind::kLaser), std::invalid_argument);
  w.close();
  CHECK_THROWS_AS(w.write(odom, OdometryReading{}), std::logic_error);
}

TEST_CASE("a trace larger than the reader's buffer streams through it") {
  TempFile file("stream");
  constexpr int kScans = 2000;  // ~2.9 MB with 360 beams and intensities
  {
    TraceWriter w(file.path(), TraceWriterOptions{.flush_every_records = 0});
    const auto laser = w.add_channel("front_laser", ChannelKind::kLaser);
    const auto odom = w.add_channel("odom", ChannelKind::kOdometry);
    for (int i = 0; i < kScans; ++i) {
      w.write(laser, sample_scan(time_from_ns(i * 100'000'000LL), 360));
      w.write(odom, OdometryReading{time_from_ns(i * 100'000'000LL + 1), Pose2D{0.01 * i, 0, 0}, {}});
    }
    CHECK(w.records_written() == 2 * kScans);
  }
  const auto size = std::filesystem::file_size(file.path());
  REQUIRE(size > 2'000'000);
  // A 4 KiB buffer, smaller than a single scan record (~2.9 KB + framing): records straddle refills.
  TraceReader r(file.path(), TraceReaderOptions{.buffer_bytes = 4096});
  TraceRecord rec;
  int scans = 0;
  int odoms = 0;
  while (r.next(rec)) {
    if (const auto* s = std::get_if<LaserScan>(&rec.data)) {
      CHECK(s->stamp == time_from_ns(scans * 100'000'000LL));
      CHECK(s->ranges_m.back() == sample_scan(Time{0ms}, 360).ranges_m.back());
      ++scans;
    } else {
      CHECK(std::get<OdometryReading>(rec.data).pose.x_m == 0.01 * odoms);
      ++odoms;
    }
  }
  CHECK(r.state() == ReadState::kEnd);
  CHECK(scans == kScans);
  CHECK(odoms == kScans);
  CHECK(r.offset() == size);
}

TEST_CASE("reading an empty trace ends cleanly") {
  TempFile file("empty");
  { TraceWriter w(file.path()); }
  CHECK(std::filesystem::file_size(file.path()) == 16);
  TraceReader r(file.path());
  TraceRecord rec;
  CHECK_FALSE(r.next(rec));
  CHECK(r.state() == ReadState::kEnd);
}

TEST_CASE("header errors name the byte offset") {
  TempFile file("header");
  write_sample(file.path());
  auto bytes = read_all(file.path());
  TempFile bad("header_bad");

  SECTION("not a trace") {
    const std::string text = "FLASER 180 1.0 2.0\n";
    write_all(bad.path(), std::vector<std::uint8_t>(text.begin(), text.end()), text.size());
    CHECK_THROWS_WITH(TraceReader(bad.path()), Catch::Contains("byte 0: not a tripodal trace (bad magic bytes)"));
  }
  SECTION("wrong version") {
    bytes[8] = 2;
    write_all(bad.path(), bytes, bytes.size());
    CHECK_THROWS_WITH(TraceReader(bad.path()),
                      Catch::Contains("byte 8: trace format version 2 is not supported (this reader reads version 1)"));
  }
  SECTION("damaged header") {
    bytes[11] ^= 0x40;
    write_all(bad.path(), bytes, bytes.size());
    CHECK_THROWS_WITH(TraceReader(bad.path()), Catch::Contains("byte 12: trace header checksum mismatch"));
  }
  SECTION("file shorter than the header") {
    write_all(bad.path(), bytes, 10);
    CHECK_THROWS_WITH(TraceReader(bad.path()), Catch::Contains("byte 10: file ends inside the 16-byte trace header"));
  }
  SECTION("missing file") {
    CHECK_THROWS_AS(TraceReader(bad.path().string() + ".nope"), TraceIoError);
  }
}

TEST_CASE("a corrupt record is reported with its offset after the records before it") {
  TempFile file("corrupt");
  write_sample(file.path());
  auto bytes = read_all(file.path());
  // Find the offset of the third data record by reading the intact file.
  std::vector<std::uint64_t> offsets;
  {
    TraceReader r(file.path());
    TraceRecord rec;
    while (r.next(rec)) offsets.push_back(rec.offset);
  }
  REQUIRE(offsets.size() == 9);
  TempFile bad("corrupt_bad");

  SECTION("a flipped payload byte fails the checksum") {
    bytes[offsets[2] + 8 + 20] ^= 0x01;
    write_all(bad.path(), bytes, bytes.size());
    TraceReader r(bad.path());
    TraceRecord rec;
    CHECK(r.next(rec));
    CHECK(r.next(rec));
    CHECK_THROWS_WITH(r.next(rec), Catch::Contains("byte " + std::to_string(offsets[2]) + ": record checksum mismatch"));
    CHECK_FALSE(r.next(rec));  // finished after the error
  }
  SECTION("a flipped length byte fails the length check") {
    bytes[offsets[1]] ^= 0x10;
    write_all(bad.path(), bytes, bytes.size());
    TraceReader r(bad.path());
    TraceRecord rec;
    CHECK(r.next(rec));
    CHECK_THROWS_WITH(r.next(rec), Catch::Contains("byte " + std::to_string(offsets[1]) +
                                                   ": corrupt record frame (length check mismatch)"));
  }
}

TEST_CASE("a trace cut inside a record reads up to the last whole record") {
  TempFile file("trunc");
  write_sample(file.path());
  const auto bytes = read_all(file.path());
  std::vector<std::uint64_t> offsets;
  {
    TraceReader r(file.path());
    TraceRecord rec;
    while (r.next(rec)) offsets.push_back(rec.offset);
  }
  TempFile cut("trunc_cut");
  // Cut 5 bytes into the body of the fifth data record: four whole records remain.
  write_all(cut.path(), bytes, offsets[4] + 13);
  TraceReader r(cut.path());
  TraceRecord rec;
  int n = 0;
  while (r.next(rec)) ++n;
  CHECK(n == 4);
  CHECK(r.state() == ReadState::kTruncated);
  CHECK_THAT(r.warning(), Catch::Contains("truncated at byte " + std::to_string(offsets[4])));
  CHECK(r.offset() == offsets[4]);
}

TEST_CASE("a recorder killed mid-write leaves a readable trace") {
  TempFile file("killed");
  // The writer's stream is flushed every 2 records; we copy the file as it is on disk while the
  // writer is still open, as if the process had been killed at that moment.
  TraceWriter w(file.path(), TraceWriterOptions{.flush_every_records = 2});
  const auto odom = w.add_channel("odom", ChannelKind::kOdometry);
  for (int i = 0; i < 5; ++i) w.write(odom, OdometryReading{time_from_ns(i), Pose2D{1.0 * i, 0, 0}, {}});
  TempFile snapshot("killed_snapshot");
  const auto on_disk = read_all(file.path());
  write_all(snapshot.path(), on_disk, on_disk.size());
  TraceReader r(snapshot.path());
  TraceRecord rec;
  int n = 0;
  while (r.next(rec)) CHECK(std::get<OdometryReading>(rec.data).pose.x_m == 1.0 * n++);
  CHECK(n == 4);  // records 0-3 were flushed, record 4 still sits in the stream buffer
  CHECK(r.state() == ReadState::kEnd);
}

TEST_CASE("a checksum-valid record with a bad payload is refused, located") {
  // Builds frames by hand so the CRC matches and only the decoder can catch the problem.
  TempFile file("payload");
  {
    TraceWriter w(file.path());
    w.add_channel("odom", ChannelKind::kOdometry);
  }
  auto bytes = read_all(file.path());
  const std::size_t record_at = bytes.size();
  // Body: type 1 (laser) on channel 0, which is an odometry channel.
  std::vector<std::uint8_t> body = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const auto frame = [&](const std::vector<std::uint8_t>& b) {
    std::vector<std::uint8_t> out;
    const auto len = static_cast<std::uint32_t>(b.size());
    for (std::uint32_t v : {len, ~len}) {
      for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    out.insert(out.end(), b.begin(), b.end());
    // CRC-32 computed bitwise here, independently of the library's table.
    std::uint32_t crc = 0xFFFFFFFFu;
    for (auto byte : b) {
      crc ^= byte;
      for (int k = 0; k < 8; ++k) crc = (crc & 1u) != 0 ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
    }
    crc = ~crc;
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(crc >> (8 * i)));
    return out;
  };
  SECTION("wrong kind for the channel") {
    const auto f = frame(body);
    bytes.insert(bytes.end(), f.begin(), f.end());
    write_all(file.path(), bytes, bytes.size());
    TraceReader r(file.path());
    TraceRecord rec;
    CHECK_THROWS_WITH(r.next(rec), Catch::Contains("byte " + std::to_string(record_at + 8) +
                                                   ": laser record on odometry channel 'odom'"));
  }
  SECTION("payload shorter than an odometry reading") {
    body[0] = 2;
    body.insert(body.end(), 20, 0);
    const auto f = frame(body);
    bytes.insert(bytes.end(), f.begin(), f.end());
    write_all(file.path(), bytes, bytes.size());
    TraceReader r(file.path());
    TraceRecord rec;
    // 11 + 16 bytes hold two f64 fields; the third starts at body byte 27.
    CHECK_THROWS_WITH(r.next(rec), Catch::Contains("byte " + std::to_string(record_at + 8 + 27) +
                                                   ": record ends inside a field (f64 needs 8 bytes, 4 left)"));
  }
  SECTION("undeclared channel") {
    body[0] = 2;
    body[1] = 9;
    body.insert(body.end(), 48, 0);
    const auto f = frame(body);
    bytes.insert(bytes.end(), f.begin(), f.end());
    write_all(file.path(), bytes, bytes.size());
    TraceReader r(file.path());
    TraceRecord rec;
    CHECK_THROWS_WITH(r.next(rec), Catch::Contains("record on undeclared channel 9"));
  }
}

TEST_CASE("a length field promising more than the file holds reads as a truncated tail") {
  // The reader grows a record's buffer as its bytes arrive, so this 24-byte file does not cost
  // the 60 MiB its frame announces.
  TempFile file("long_frame");
  { TraceWriter w(file.path()); }
  auto bytes = read_all(file.path());
  const std::uint32_t length = 60u << 20;
  for (const std::uint32_t v : {length, ~length}) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  bytes.insert(bytes.end(), {1, 2, 3});
  write_all(file.path(), bytes, bytes.size());
  TraceReader r(file.path());
  TraceRecord rec;
  CHECK_FALSE(r.next(rec));
  CHECK(r.state() == ReadState::kTruncated);
  CHECK_THAT(r.warning(), Catch::Contains("truncated at byte 16 (a record of 62914572 bytes has only 11)"));
}

TEST_CASE("a channel declaration stamped other than 0 is refused, located at its stamp") {
  // The format stamps declarations 0; fuzz_trace's re-write property (a trace re-writes to its
  // own bytes) failed on declarations with other stamps until the reader refused them.
  TempFile file("decl_stamp");
  { TraceWriter w(file.path()); }
  auto bytes = read_all(file.path());
  std::vector<std::uint8_t> body = {0, 0, 0, 5, 0, 0, 0, 0, 0, 0, 0, static_cast<std::uint8_t>(ChannelKind::kEvent), 1, 0, 'e'};
  const auto length = static_cast<std::uint32_t>(body.size());
  const std::uint32_t crc = static_cast<std::uint32_t>(crc32(0L, body.data(), static_cast<unsigned>(body.size())));
  for (const std::uint32_t v : {length, ~length}) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  bytes.insert(bytes.end(), body.begin(), body.end());
  for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(crc >> (8 * i)));
  write_all(file.path(), bytes, bytes.size());
  TraceReader r(file.path());
  TraceRecord rec;
  CHECK_THROWS_WITH(r.next(rec), Catch::Contains("byte 27: channel declaration stamped 5 (declarations are stamped 0)"));
}
