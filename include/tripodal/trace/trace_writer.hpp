// Records a run as a tripodal trace (docs/trace-format.md): appends framed, checksummed records to a
// file as they arrive, so a recording never has to fit in memory and a killed recorder loses at
// most the records not yet flushed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace {

struct TraceWriterOptions {
  /// Flush the file to the OS after this many records (0: only when the stream buffer fills, on
  /// flush() and on close()). Flushed records survive a crash of the recording process.
  std::uint32_t flush_every_records = 256;
};

/// Appends records to a new trace file. Not thread-safe: one writer per thread, or serialise calls.
class TraceWriter final {
 public:
  /// Creates (or truncates) `path` and writes the file header. Throws TraceIoError.
  explicit TraceWriter(const std::filesystem::path& path, TraceWriterOptions options = {});
  /// Writes the header to `out` (which the writer owns from now on); `name` is used in messages.
  TraceWriter(std::unique_ptr<std::ostream> out, std::string name, TraceWriterOptions options = {});
  ~TraceWriter();  ///< closes, swallowing I/O errors; call close() to see them
  TraceWriter(const TraceWriter&) = delete;
  TraceWriter& operator=(const TraceWriter&) = delete;

  /// Declares a channel and writes its declaration record. Throws std::invalid_argument when `name`
  /// is empty, longer than 65535 bytes, or already declared; std::length_error past 65535 channels.
  ChannelId add_channel(std::string_view name, ChannelKind kind);

  /// Appends one record. Throws std::invalid_argument when `channel` is not declared or carries
  /// another kind, TraceIoError when the file cannot be written.
  /// The typed overloads avoid copying a reading into a RecordData.
  void write(ChannelId channel, const RecordData& data);
  void write(ChannelId channel, const LaserScan& reading);
  void write(ChannelId channel, const OdometryReading& reading);
  void write(ChannelId channel, const SonarReading& reading);
  void write(ChannelId channel, const InfraredReading& reading);
  void write(ChannelId channel, const BumperReading& reading);
  void write(ChannelId channel, const BatteryReading& reading);
  void write(ChannelId channel, const GyroReading& reading);
  void write(ChannelId channel, const CommandRecord& command);
  void write(ChannelId channel, const EventRecord& event);

  /// Pushes buffered records to the OS. Throws TraceIoError.
  void flush();
  /// Flushes and closes the file; later writes throw std::logic_error. Throws TraceIoError.
  void close();

  [[nodiscard]] const std::vector<ChannelInfo>& channels() const noexcept { return channels_; }
  [[nodiscard]] std::uint64_t records_written() const noexcept { return records_; }
  [[nodiscard]] std::uint64_t bytes_written() const noexcept { return bytes_; }

 private:
  template <typename T>
  void write_record(ChannelId channel, const T& data);
  void write_frame();  // frames body_ (length, length check, body, CRC-32) and writes it
  void check_open() const;

  std::unique_ptr<std::ostream> out_;
  std::string name_;
  TraceWriterOptions options_;
  std::vector<ChannelInfo> channels_;
  std::vector<std::uint8_t> body_;  // reused between records: no allocation once it is large enough
  std::uint64_t records_ = 0;
  std::uint64_t bytes_ = 0;
  std::uint32_t since_flush_ = 0;
};

}  // namespace tripodal::trace
