// Tripodal traces (docs/trace-format.md): what reads re-writes to a trace that reads to the same
// records and re-writes byte-identically (a fixed point); a canonical trace (channels numbered in
// declaration order, as TraceWriter numbers them) re-writes to its own bytes. A rejected trace
// names its byte offset.
#include <memory>
#include <sstream>
#include <vector>

#include "../fuzz_target.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_writer.hpp"

namespace {

struct Rewrite {
  std::string bytes;        // the re-written trace
  std::uint64_t read_to = 0;  // offset after the last whole record of the input
  bool canonical = true;    // channel ids were 0, 1, 2... in declaration order
  bool ok = false;          // the input read without a format error
};

Rewrite rewrite(std::string input) {
  using namespace tripodal;
  using namespace tripodal::trace;
  Rewrite out;
  // The writer owns (and on close() destroys) its stream; the buffer stays ours.
  std::stringbuf text;
  auto sink = std::make_unique<std::ostream>(&text);
  {
    TraceWriter writer(std::move(sink), "rewrite");
    try {
      TraceReader reader(std::make_unique<std::istringstream>(std::move(input)), "fuzz.trace");
      TraceRecord record;
      std::size_t declared = 0;
      std::vector<ChannelId> ids;  // input channel id -> output channel id
      const auto declare = [&] {
        for (; declared < reader.channels().size(); ++declared) {
          const ChannelInfo& c = reader.channels()[declared];
          if (c.id != declared) out.canonical = false;
          if (ids.size() <= c.id) ids.resize(c.id + 1u);
          ids[c.id] = writer.add_channel(c.name, c.kind);
        }
      };
      while (reader.next(record)) {
        declare();
        writer.write(ids[record.channel], record.data);
      }
      declare();
      out.read_to = reader.offset();
      out.ok = true;
    } catch (const TraceFormatError& e) {
      const std::string what = e.what();
      tripodal::fuzz::require(what.find("fuzz.trace") != std::string::npos && what.find("byte ") != std::string::npos,
                              "a trace format error names the file and the byte", what);
    }
    writer.close();
  }
  out.bytes = text.str();
  return out;
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  const std::string input(tripodal::fuzz::as_text(bytes));
  const Rewrite first = rewrite(input);
  if (!first.ok) return;
  if (first.canonical) {
    tripodal::fuzz::require(first.bytes == input.substr(0, first.read_to),
                            "a canonical trace re-writes to its own bytes");
  }
  const Rewrite second = rewrite(first.bytes);
  tripodal::fuzz::require(second.ok && second.bytes == first.bytes, "a re-written trace is a fixed point");
}
