// `tripodal run --record`: the run's readings, commands and life cycle into an MCAP file. Internal
// to the tool (tools/tripodal), used by the driver (run_task.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/trace/mcap.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_recorder.hpp"
#include "tripodal/trace/trace_writer.hpp"

namespace tripodal::app {

/// writes as the run goes, so a long run holds no readings in memory), which becomes MCAP at the
/// end through the trace kit's exporter, so that the file replays as a trace and opens in any MCAP
/// tool. The life cycle (task, processes, every firing) goes to the "events" channel.
class RunRecording {
 public:
  RunRecording(const std::filesystem::path& mcap, const Robot& robot)
      : mcap_(mcap), trace_path_(with_parent_folder(mcap.string() + ".trace.partial")), writer_(trace_path_), recorder_(writer_) {
    const ResourceTable& table = robot.resources();
    for (std::size_t i = 0; i < table.size(); ++i) {
      try {
        recorder_.watch(table.at(i));
      } catch (const std::invalid_argument&) {
        ++unrecorded_;  // a reading the trace format does not carry (joints, buttons ...)
      }
    }
    recorder_.record_commands("cmd");
    recorder_.record_events("events");
  }
  RunRecording(const RunRecording&) = delete;
  RunRecording& operator=(const RunRecording&) = delete;
  ~RunRecording() {
    std::error_code ignored;
    std::filesystem::remove(trace_path_, ignored);
  }

  void record(Time now, Robot& robot, const LifecycleRecorder& life) {
    recorder_.record(now);
    const CoordinatorOutput& fused = robot.behavior_loop().coordinator().output();
    recorder_.record_command(fused.stamp, fused.command, fused.winner);
    for (; noted_ < life.entries().size(); ++noted_) {
      const LifecycleEntry& e = life.entries()[noted_];
      recorder_.record_event(e.time, e.text);
    }
  }

  /// Writes the MCAP file; returns how many messages it holds.
  std::uint64_t finish() {
    writer_.close();
    trace::TraceReader reader(trace_path_);
    trace::mcap::Writer out(mcap_);
    trace::export_trace_to_mcap(reader, out);
    return out.messages_written();
  }

  [[nodiscard]] std::size_t unrecorded_resources() const noexcept { return unrecorded_; }

 private:
  // As --out does, the file's folder is made when missing (its failure is the writer's to report).
  static std::filesystem::path with_parent_folder(std::filesystem::path file) {
    std::error_code ignored;
    if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ignored);
    return file;
  }

  std::filesystem::path mcap_;
  std::filesystem::path trace_path_;
  trace::TraceWriter writer_;
  trace::TraceRecorder recorder_;
  std::size_t noted_ = 0;
  std::size_t unrecorded_ = 0;
};

}  // namespace tripodal::app
