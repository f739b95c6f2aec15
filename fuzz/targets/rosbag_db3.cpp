// rosbag2 SQLite3 bags (docs/rosbag.md): any file either converts (every message counted, every
// record written reads back) or is refused with an error naming the file; never a crash. SQLite
// reads from a file, so each input is written to one (named after the process, in the temp folder).
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "../fuzz_target.hpp"
#include "tripodal/trace/rosbag.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal::trace;
  namespace fs = std::filesystem;
  static const fs::path file = fs::temp_directory_path() / ("tripodal_fuzz_" + std::to_string(::getpid()) + ".db3");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    const auto text = tripodal::fuzz::as_text(bytes);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
  std::stringbuf trace;
  try {
    TraceWriter writer(std::make_unique<std::ostream>(&trace), "fuzz.trace");
    const BagImportReport report = import_rosbag(file, writer);
    writer.close();
    std::uint64_t counted = 0;
    for (const auto& [topic, n] : report.topic_messages) counted += n;
    tripodal::fuzz::require(counted == report.messages, "every message is counted on its topic");
    TraceReader reader(std::make_unique<std::istringstream>(trace.str()), "fuzz.trace");
    TraceRecord record;
    std::uint64_t records = 0;
    while (reader.next(record)) ++records;
    tripodal::fuzz::require(records == report.records_written, "the trace holds every record written");
  } catch (const BagFormatError& e) {
    tripodal::fuzz::require(std::string(e.what()).find(file.string()) == 0, "a refusal names the file", e.what());
  } catch (const TraceFormatError& e) {
    tripodal::fuzz::require(std::string(e.what()).find(file.string()) == 0, "a refusal names the file", e.what());
  } catch (const TraceIoError& e) {
    tripodal::fuzz::require(std::string(e.what()).find(file.string()) == 0, "an I/O error names the file", e.what());
  }
}
