// CARMEN logs (docs/trace-format.md): an imported log gives a trace that reads cleanly to its end
// with one record per scan, odometry reading and laser pose the report counts; a rejected log has
// every error at FILE:LINE:COL.
#include <memory>
#include <sstream>

#include "../fuzz_target.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/trace_reader.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  using namespace tripodal::trace;
  // The writer owns (and on close() destroys) its stream; the buffer stays ours.
  std::stringbuf text;
  auto sink = std::make_unique<std::ostream>(&text);
  CarmenImportReport report;
  std::string trace;
  {
    TraceWriter writer(std::move(sink), "fuzz.trace");
    std::istringstream in{std::string(fuzz::as_text(bytes))};
    try {
      report = import_carmen_log(in, "fuzz.log", writer);
    } catch (const ConfigError& e) {
      fuzz::require_located(e, "fuzz.log");
      return;
    }
    writer.close();
  }
  trace = text.str();
  TraceReader reader(std::make_unique<std::istringstream>(std::move(trace)), "fuzz.trace");
  TraceRecord record;
  std::uint64_t records = 0;
  while (reader.next(record)) ++records;
  fuzz::require(reader.state() == ReadState::kEnd, "an imported trace reads to a clean end");
  fuzz::require(records == report.laser_scans + report.odometry_readings + report.laser_poses,
                "the imported trace has one record per converted message");
}
