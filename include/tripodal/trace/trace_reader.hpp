// Reads a tripodal trace (docs/trace-format.md) one record at a time through a small buffer, so a
// multi-hour trace streams; corruption is reported with its byte offset, a cut-off tail as a status.
#pragma once

#include <cstdint>
#include <filesystem>
#include <istream>
#include <memory>
#include <string>
#include <vector>

#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace {

struct TraceReaderOptions {
  /// Size of the read buffer. Records larger than it are still read (into the record's storage).
  std::size_t buffer_bytes = 64 * 1024;
  /// Largest record body accepted; a larger length field is reported as corruption.
  std::uint32_t max_record_bytes = 64u * 1024u * 1024u;
};

/// How reading ended (or that it has not yet ended).
enum class ReadState {
  kReading,    ///< more records may follow
  kEnd,        ///< clean end of file after a whole record
  kTruncated,  ///< the file ends inside a record: the recorder was stopped mid-write
};

class TraceReader final {
 public:
  /// Opens `path` and checks the file header. Throws TraceIoError when the file cannot be opened,
  /// TraceFormatError (with the offset) on a bad magic, a wrong version or a damaged header.
  explicit TraceReader(const std::filesystem::path& path, TraceReaderOptions options = {});
  /// Reads from `in` (owned from now on); `name` is used in messages.
  TraceReader(std::unique_ptr<std::istream> in, std::string name, TraceReaderOptions options = {});
  ~TraceReader();
  TraceReader(const TraceReader&) = delete;
  TraceReader& operator=(const TraceReader&) = delete;

  /// Reads the next data record into `record` (channel declarations are absorbed into channels()).
  /// Returns false at the end: state() then tells a clean end from a truncated tail. Throws
  /// TraceFormatError naming the byte offset on a checksum mismatch or an undecodable record;
  /// after a throw the reader is finished.
  bool next(TraceRecord& record);

  [[nodiscard]] ReadState state() const noexcept { return state_; }
  /// For kTruncated: "FILE: truncated at byte N (...)": the last whole record ends at N.
  [[nodiscard]] const std::string& warning() const noexcept { return warning_; }
  /// Offset of the first byte after the last whole record read.
  [[nodiscard]] std::uint64_t offset() const noexcept { return offset_; }
  [[nodiscard]] std::uint16_t format_version() const noexcept { return version_; }
  /// Channels declared so far (a trace declares each channel before its first record).
  [[nodiscard]] const std::vector<ChannelInfo>& channels() const noexcept { return channels_; }
  /// The channel with this id; throws std::out_of_range when it is not declared.
  [[nodiscard]] const ChannelInfo& channel(ChannelId id) const;
  [[nodiscard]] const std::string& name() const noexcept { return name_; }

 private:
  void read_header();
  std::size_t read_bytes(std::uint8_t* dst, std::size_t n);  // short only at end of file
  [[noreturn]] void fail(std::uint64_t offset, const std::string& what);

  std::unique_ptr<std::istream> in_;
  std::string name_;
  TraceReaderOptions options_;
  std::vector<char> stream_buffer_;  // installed as the stream's buffer for file input
  std::vector<std::uint8_t> body_;
  std::vector<ChannelInfo> channels_;
  std::vector<int> channel_index_;  // channel id -> index in channels_, -1 when undeclared
  std::uint64_t offset_ = 0;
  std::uint16_t version_ = 0;
  ReadState state_ = ReadState::kReading;
  std::string warning_;
};

}  // namespace tripodal::trace
