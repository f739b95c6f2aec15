// MCAP, the container of rosbag2 bags since ROS 2 Iron (the open MCAP specification, version 0):
// a record-by-record reader that checks every CRC present and refuses bad input with the file and
// the record's byte offset, and a writer with chunks (uncompressed or zstd), a summary section and
// CRCs. Sits under rosbag.hpp, which turns the CDR messages it carries into trace records.
#pragma once

#include <cstdint>
#include <filesystem>
#include <istream>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace::mcap {

/// The record opcodes of the specification; 0x80-0xFF are user records (skipped and counted).
enum class Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};
/// "Header", "Footer", ... as the specification names the record; "Unknown" for other values.
[[nodiscard]] const char* to_string(Opcode op) noexcept;

using Bytes = std::vector<std::uint8_t>;
using StringMap = std::map<std::string, std::string>;

struct Header { std::string profile, library; };
struct Footer { std::uint64_t summary_start = 0, summary_offset_start = 0; std::uint32_t summary_crc = 0; };
struct Schema { std::uint16_t id = 0; std::string name, encoding; Bytes data; };
struct Channel { std::uint16_t id = 0, schema_id = 0; std::string topic, message_encoding; StringMap metadata; };
struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;  ///< ns
  Bytes data;
};
/// The chunk's own fields; its records are returned one by one after it (McapRecord::chunk_offset).
struct Chunk {
  std::uint64_t message_start_time = 0, message_end_time = 0, uncompressed_size = 0, compressed_size = 0;
  std::uint32_t uncompressed_crc = 0;
  std::string compression;
};
struct MessageIndex { std::uint16_t channel_id = 0; std::vector<std::pair<std::uint64_t, std::uint64_t>> records; };
struct ChunkIndex {
  std::uint64_t message_start_time = 0, message_end_time = 0, chunk_start_offset = 0, chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0, uncompressed_size = 0;
};
struct Attachment {
  std::uint64_t log_time = 0, create_time = 0;
  std::string name, media_type;
  Bytes data;
  std::uint32_t crc = 0;
};
struct AttachmentIndex {
  std::uint64_t offset = 0, length = 0, log_time = 0, create_time = 0, data_size = 0;
  std::string name, media_type;
};
struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0, attachment_count = 0, metadata_count = 0, chunk_count = 0;
  std::uint64_t message_start_time = 0, message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};
struct Metadata { std::string name; StringMap metadata; };
struct MetadataIndex { std::uint64_t offset = 0, length = 0; std::string name; };
struct SummaryOffset { std::uint8_t group_opcode = 0; std::uint64_t group_start = 0, group_length = 0; };
struct DataEnd { std::uint32_t data_section_crc = 0; };
/// A user record (opcode 0x80-0xFF) or one a later version of the specification may add: skipped.
struct Unknown { std::uint8_t opcode = 0; std::uint64_t length = 0; };

using RecordBody = std::variant<Header, Footer, Schema, Channel, Message, Chunk, MessageIndex, ChunkIndex, Attachment,
                                AttachmentIndex, Statistics, Metadata, MetadataIndex, SummaryOffset, DataEnd, Unknown>;

struct Record {
  Opcode opcode = Opcode::kHeader;
  /// Byte offset of the record in the file; for a record inside a chunk, that of the chunk.
  std::uint64_t offset = 0;
  /// For a record inside a chunk: its offset in the chunk's uncompressed records (else 0).
  std::uint64_t chunk_offset = 0;
  bool in_chunk = false;
  RecordBody body;
};

struct ReaderOptions {
  /// The largest record (or uncompressed chunk) accepted; a larger length is refused before any
  /// allocation, as corruption: a real bag's chunks are a few MiB.
  std::uint64_t max_record_bytes = std::uint64_t{1} << 30;
  bool check_crcs = true;
};

/// How reading ended (or that it has not yet ended); as the trace reader's ReadState.
enum class State { kReading, kEnd, kTruncated };

/// Reads an MCAP file record by record, expanding chunks (the Chunk record comes first, then its
/// records with in_chunk set). Checks the magic at both ends, the chunk, data-section, summary and
/// attachment CRCs (where not 0), every length against the bytes left. A file cut short (a
/// recorder killed: no footer) ends with state() kTruncated after the last whole record — for a
/// chunk cut short, after the whole records its first bytes decompress to — and warning() says
/// what is lost. Every refusal throws TraceFormatError naming the file and the
/// byte offset of the record.
class Reader final {
 public:
  explicit Reader(const std::filesystem::path& path, ReaderOptions options = {});
  Reader(std::unique_ptr<std::istream> in, std::string name, ReaderOptions options = {});
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// The next record; false at the end (state() tells a clean end from a truncated file).
  bool next(Record& record);

  [[nodiscard]] State state() const noexcept { return state_; }
  [[nodiscard]] const std::string& warning() const noexcept { return warning_; }
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  /// Records of each opcode seen so far, those inside chunks included.
  [[nodiscard]] const std::map<Opcode, std::uint64_t>& counts() const noexcept { return counts_; }

 private:
  bool next_in_chunk(Record& record);
  bool read_exact(std::uint8_t* dst, std::size_t n);
  void parse(Opcode op, const Bytes& body, std::uint64_t offset, RecordBody& out) const;
  void load_chunk(const Bytes& body, std::uint64_t offset, Chunk& chunk);
  std::uint64_t recover_chunk(std::uint64_t offset);  // whole records at the start of a cut chunk
  void check_summary_crc(const Footer& footer, std::uint64_t footer_offset);
  void truncated(std::uint64_t record_offset, const std::string& what);
  [[noreturn]] void fail(std::uint64_t offset, const std::string& what) const;

  std::unique_ptr<std::istream> in_;
  std::string name_;
  ReaderOptions options_;
  std::uint64_t size_ = 0;  // of the file
  std::uint64_t pos_ = 0;   // bytes consumed
  std::uint32_t data_crc_ = 0;  // CRC-32 of the bytes before DataEnd
  bool data_crc_open_ = true;
  Bytes body_;
  Bytes chunk_;  // the uncompressed records of the current chunk
  std::uint64_t chunk_pos_ = 0;
  std::uint64_t chunk_file_offset_ = 0;
  bool in_chunk_ = false;
  bool footer_seen_ = false;
  bool partial_chunk_ = false;  // the chunk being read was cut short: the file ends after it
  Chunk partial_;
  State state_ = State::kReading;
  std::string warning_;
  std::map<Opcode, std::uint64_t> counts_;
};

enum class Compression { kNone, kZstd, kLz4 };

struct WriterOptions {
  Compression compression = Compression::kZstd;
  /// A chunk is closed once its uncompressed records pass this size.
  std::size_t chunk_bytes = 1 << 20;
  std::string profile = "ros2";
  std::string library = "tripodal";
};

/// Writes an MCAP file: Header, chunks (each followed by its MessageIndex records), DataEnd with
/// the data-section CRC, a summary (schemas, channels, statistics, chunk indexes, metadata
/// indexes), SummaryOffset records and a Footer with the summary CRC. Not thread-safe.
class Writer final {
 public:
  explicit Writer(const std::filesystem::path& path, WriterOptions options = {});
  Writer(std::unique_ptr<std::ostream> out, std::string name, WriterOptions options = {});
  ~Writer();  ///< closes, swallowing I/O errors; call close() to see them
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Returns the new schema's id (1, 2, ...).
  std::uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  /// Returns the new channel's id (0, 1, ...). Throws std::invalid_argument for an unknown schema.
  std::uint16_t add_channel(const std::string& topic, const std::string& message_encoding, std::uint16_t schema_id,
                            const StringMap& metadata = {});
  /// Appends a message (times in ns). Throws std::invalid_argument for an unknown channel.
  void write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time, const Bytes& data,
             std::uint32_t sequence = 0);
  /// A Metadata record (rosbag2 stores its bag metadata as one named "rosbag2").
  void write_metadata(const std::string& name, const StringMap& metadata);
  /// Writes the last chunk, the summary and the footer. Throws TraceIoError.
  void close();

  [[nodiscard]] std::uint64_t messages_written() const noexcept { return messages_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint64_t messages_ = 0;
};

}  // namespace tripodal::trace::mcap
