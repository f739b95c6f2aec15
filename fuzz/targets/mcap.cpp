// MCAP files (docs/rosbag.md): any input reads record by record to a clean end, a truncation
// warning, or a TraceFormatError naming the file and a byte inside it; no input allocates more
// than a record's declared size after that size was checked against the bytes present. Every
// message is also handed to each CDR decoder, which must refuse bad bytes the same way.
#include <memory>
#include <sstream>
#include <string>

#include "../fuzz_target.hpp"
#include "tripodal/trace/cdr.hpp"
#include "tripodal/trace/mcap.hpp"

namespace {

template <typename T>
void try_decode(const std::vector<std::uint8_t>& data) {
  using namespace tripodal::trace;
  try {
    (void)ros::decode_cdr<T>(data, "fuzz.cdr", 0);
  } catch (const TraceFormatError& e) {
    tripodal::fuzz::require(std::string(e.what()).rfind("fuzz.cdr: byte ", 0) == 0, "a CDR refusal names its byte",
                            e.what());
    tripodal::fuzz::require(e.offset() <= data.size(), "the refused byte is inside the message", e.what());
  }
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal::trace;
  mcap::ReaderOptions options;
  options.max_record_bytes = 1u << 24;  // keeps libFuzzer's memory limit out of the way
  try {
    mcap::Reader reader(std::make_unique<std::istringstream>(std::string(tripodal::fuzz::as_text(bytes))), "fuzz.mcap",
                        options);
    mcap::Record record;
    while (reader.next(record)) {
      tripodal::fuzz::require(record.offset < bytes.size(), "a record starts inside the file");
      if (const auto* m = std::get_if<mcap::Message>(&record.body)) {
        try_decode<ros::LaserScan>(m->data);
        try_decode<ros::Odometry>(m->data);
        try_decode<ros::TFMessage>(m->data);
        try_decode<ros::String>(m->data);
      }
    }
    if (reader.state() == mcap::State::kTruncated) {
      tripodal::fuzz::require(reader.warning().rfind("fuzz.mcap: truncated at byte ", 0) == 0,
                              "a truncation names its byte", reader.warning());
    }
  } catch (const TraceFormatError& e) {
    tripodal::fuzz::require(std::string(e.what()).rfind("fuzz.mcap: byte ", 0) == 0, "a refusal names the file and byte",
                            e.what());
    tripodal::fuzz::require(e.offset() <= bytes.size(), "the refused record is inside the file", e.what());
  }
}
