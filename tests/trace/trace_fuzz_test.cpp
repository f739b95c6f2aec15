#include <algorithm>
// Randomised damage to a small trace: the reader must never crash (the suite also runs under
// AddressSanitizer and UBSan) and must end every read with records plus either a clean end, a
// truncation status at a whole-record boundary, or an error that names a byte offset in the file.
#include <catch2/catch.hpp>
#include <random>

#include "trace_test_util.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace tripodal::trace;
using namespace tripodal::trace::test;

namespace {

struct Outcome {
  std::size_t records = 0;
  ReadState state = ReadState::kReading;
  bool error = false;
  std::uint64_t error_offset = 0;
  std::string message;
};

// True when `message` contains "byte N: " (the located form of every TraceFormatError).
bool located(const std::string& message) {
  for (std::size_t at = message.find("byte "); at != std::string::npos; at = message.find("byte ", at + 1)) {
    std::size_t i = at + 5;
    const std::size_t digits = i;
    while (i < message.size() && message[i] >= '0' && message[i] <= '9') ++i;
    if (i > digits && message.compare(i, 2, ": ") == 0) return true;
  }
  return false;
}

Outcome read_damaged(const std::filesystem::path& path) {
  Outcome o;
  try {
    TraceReader r(path);
    TraceRecord rec;
    while (r.next(rec)) ++o.records;
    o.state = r.state();
    o.message = r.warning();
  } catch (const TraceFormatError& e) {
    o.error = true;
    o.error_offset = e.offset();
    o.message = e.what();
  }
  return o;
}

std::vector<std::uint8_t> small_trace(const std::filesystem::path& path, std::vector<std::uint64_t>& ends) {
  {
    TraceWriter w(path);
    const auto records = one_of_each(time_from_ns(123456789));
    for (const auto& r : records) {
      const auto id = w.add_channel(std::string(to_string(kind_of(r))), kind_of(r));
      w.write(id, r);
    }
  }
  // Offsets where a whole data record ends: the valid truncation points.
  TraceReader r(path);
  TraceRecord rec;
  while (r.next(rec)) ends.push_back(r.offset());
  return read_all(path);  // ~4.5 KB: small enough to cut at every offset
}

}  // namespace

TEST_CASE("truncating a trace at every offset gives records and a located status") {
  TempFile file("fuzz_src");
  std::vector<std::uint64_t> ends;
  const auto bytes = small_trace(file.path(), ends);
  TempFile cut("fuzz_cut");
  for (std::size_t n = 0; n <= bytes.size(); ++n) {
    write_all(cut.path(), bytes, n);
    const Outcome o = read_damaged(cut.path());
    INFO("cut at " << n << ": " << o.message);
    if (n < 16) {
      // Inside the header: an error naming where the file ended (or a magic mismatch can't happen).
      REQUIRE(o.error);
      CHECK(o.error_offset == n);
      continue;
    }
    REQUIRE_FALSE(o.error);
    // Exactly the records that end at or before the cut are read.
    const auto whole = static_cast<std::size_t>(std::count_if(ends.begin(), ends.end(), [&](auto e) { return e <= n; }));
    CHECK(o.records == whole);
    if (n == bytes.size()) {
      CHECK(o.state == ReadState::kEnd);
    } else if (std::find(ends.begin(), ends.end(), n) != ends.end()) {
      CHECK(o.state == ReadState::kEnd);  // cut exactly after a record: indistinguishable from a clean end
    } else {
      CHECK((o.state == ReadState::kTruncated || o.state == ReadState::kEnd));
      if (o.state == ReadState::kTruncated) CHECK_THAT(o.message, Catch::Contains("truncated at byte"));
    }
  }
}

TEST_CASE("random byte damage never crashes and is located") {
  TempFile file("fuzz_src2");
  std::vector<std::uint64_t> ends;
  const auto original = small_trace(file.path(), ends);
  TempFile bad("fuzz_bad");
  std::mt19937_64 rng(20261122);  // seeded: a failure repeats exactly
  std::uniform_int_distribution<std::size_t> pos(0, original.size() - 1);
  std::uniform_int_distribution<int> flips(1, 4);
  std::uniform_int_distribution<int> byte(0, 255);
  int errors = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    auto bytes = original;
    const int k = flips(rng);
    std::size_t first = bytes.size();
    for (int i = 0; i < k; ++i) {
      const std::size_t p = pos(rng);
      bytes[p] = static_cast<std::uint8_t>(byte(rng));
      first = std::min(first, p);
    }
    const std::size_t keep = trial % 3 == 0 ? pos(rng) : bytes.size();  // also cut some
    write_all(bad.path(), bytes, keep);
    const Outcome o = read_damaged(bad.path());
    INFO("trial " << trial << ": " << o.message);
    if (o.error) {
      ++errors;
      CHECK(located(o.message));
      CHECK(o.error_offset <= keep);
    }
    // Never more records than the file held; records before the first damaged byte are all read.
    CHECK(o.records <= ends.size());
    const auto intact = static_cast<std::size_t>(
        std::count_if(ends.begin(), ends.end(), [&](auto e) { return e <= std::min(first, keep); }));
    CHECK(o.records >= intact);
  }
  CHECK(errors > 1000);  // the damage is detected, not silently read as data
}
