// The MCAP reader of mcap.hpp: streams the file record by record, expands chunks (none, zstd, lz4),
// checks the CRCs the file carries and every length before it allocates.
#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>

#include "tripodal/trace/mcap.hpp"

namespace tripodal::trace::mcap {

namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::size_t kRecordHeaderBytes = 9;  // opcode + uint64 length

std::uint32_t crc32_update(std::uint32_t crc, const std::uint8_t* p, std::size_t n) {
  // zlib's crc32 takes a uInt length: feed large spans in pieces.
  while (n > 0) {
    const std::size_t step = std::min<std::size_t>(n, 1u << 30);
    crc = static_cast<std::uint32_t>(::crc32(crc, p, static_cast<uInt>(step)));
    p += step;
    n -= step;
  }
  return crc;
}

std::uint64_t le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// Reads the fields of one record body; every read is checked against the body's end.
class Fields {
 public:
  Fields(const std::uint8_t* p, std::size_t n, const char* record) : p_(p), n_(n), record_(record) {}
  std::uint8_t u8() { return *need(1, "uint8"); }
  std::uint16_t u16() { const auto* p = need(2, "uint16"); return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
  std::uint32_t u32() {
    const auto* p = need(4, "uint32");
    return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
           static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
  }
  std::uint64_t u64() { return le64(need(8, "uint64")); }
  std::string str() {
    const std::uint32_t n = u32();
    const auto* p = need(n, "string");
    return std::string(reinterpret_cast<const char*>(p), n);
  }
  Bytes bytes32() {
    const std::uint32_t n = u32();
    const auto* p = need(n, "bytes");
    return Bytes(p, p + n);
  }
  StringMap string_map() {
    Fields sub = sub_fields(u32(), "map");
    StringMap m;
    while (!sub.done()) {
      std::string k = sub.str();
      m[std::move(k)] = sub.str();
    }
    return m;
  }
  std::map<std::uint16_t, std::uint64_t> id_map() {
    Fields sub = sub_fields(u32(), "map");
    std::map<std::uint16_t, std::uint64_t> m;
    while (!sub.done()) {
      const std::uint16_t k = sub.u16();
      m[k] = sub.u64();
    }
    return m;
  }
  Fields sub_fields(std::uint64_t n, const char* what) {
    const auto* p = need(n, what);
    return Fields(p, static_cast<std::size_t>(n), record_);
  }
  const std::uint8_t* need(std::uint64_t n, const char* what) {
    if (n > n_ - pos_) {
      throw std::out_of_range(std::string(record_) + " record: " + what + " field of " + std::to_string(n) +
                              " bytes runs past the record's end (" + std::to_string(n_ - pos_) + " bytes left)");
    }
    const auto* p = p_ + pos_;
    pos_ += static_cast<std::size_t>(n);
    return p;
  }
  [[nodiscard]] bool done() const noexcept { return pos_ == n_; }
  [[nodiscard]] std::size_t pos() const noexcept { return pos_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  const char* record_;
};

}  // namespace

const char* to_string(Opcode op) noexcept {
  switch (op) {
    case Opcode::kHeader: return "Header";
    case Opcode::kFooter: return "Footer";
    case Opcode::kSchema: return "Schema";
    case Opcode::kChannel: return "Channel";
    case Opcode::kMessage: return "Message";
    case Opcode::kChunk: return "Chunk";
    case Opcode::kMessageIndex: return "MessageIndex";
    case Opcode::kChunkIndex: return "ChunkIndex";
    case Opcode::kAttachment: return "Attachment";
    case Opcode::kAttachmentIndex: return "AttachmentIndex";
    case Opcode::kStatistics: return "Statistics";
    case Opcode::kMetadata: return "Metadata";
    case Opcode::kMetadataIndex: return "MetadataIndex";
    case Opcode::kSummaryOffset: return "SummaryOffset";
    case Opcode::kDataEnd: return "DataEnd";
  }
  return "Unknown";
}

namespace {
bool known(std::uint8_t op) { return op >= 0x01 && op <= 0x0F; }
}  // namespace

Reader::Reader(const std::filesystem::path& path, ReaderOptions options)
    : name_(path.string()), options_(options) {
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file) throw TraceIoError(name_ + ": cannot open the file");
  in_ = std::move(file);
  in_->seekg(0, std::ios::end);
  size_ = static_cast<std::uint64_t>(in_->tellg());
  in_->seekg(0);
}

Reader::Reader(std::unique_ptr<std::istream> in, std::string name, ReaderOptions options)
    : in_(std::move(in)), name_(std::move(name)), options_(options) {
  in_->seekg(0, std::ios::end);
  const auto end = in_->tellg();
  size_ = end < 0 ? 0 : static_cast<std::uint64_t>(end);
  in_->seekg(0);
}

Reader::~Reader() = default;

void Reader::fail(std::uint64_t offset, const std::string& what) const { throw TraceFormatError(name_, offset, what); }

void Reader::truncated(std::uint64_t record_offset, const std::string& what) {
  state_ = State::kTruncated;
  warning_ = name_ + ": truncated at byte " + std::to_string(record_offset) + " (" + what + "): the " +
             std::to_string(size_ - record_offset) + " bytes from there on are lost, and with no Footer the "
             "summary (statistics, chunk and attachment indexes); every whole record before that byte was read";
}

bool Reader::read_exact(std::uint8_t* dst, std::size_t n) {
  in_->read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
  return static_cast<std::size_t>(in_->gcount()) == n;
}

bool Reader::next(Record& record) {
  if (state_ != State::kReading) return false;
  if (in_chunk_) {
    if (next_in_chunk(record)) return true;
    in_chunk_ = false;
    if (partial_chunk_) {
      state_ = State::kTruncated;
      return false;
    }
  }
  if (pos_ == 0) {
    std::array<std::uint8_t, 8> magic{};
    if (size_ < magic.size() || !read_exact(magic.data(), magic.size()) || magic != kMagic) {
      fail(0, "not an MCAP file (no magic \\x89MCAP0\\r\\n)");
    }
    data_crc_ = crc32_update(0, magic.data(), magic.size());
    pos_ = magic.size();
  }
  if (footer_seen_) {
    std::array<std::uint8_t, 8> magic{};
    if (size_ - pos_ < magic.size() || !read_exact(magic.data(), magic.size()) || magic != kMagic) {
      fail(pos_, "no closing magic after the Footer");
    }
    state_ = State::kEnd;
    return false;
  }
  const std::uint64_t at = pos_;
  if (size_ - pos_ < kRecordHeaderBytes) {
    truncated(at, size_ == pos_ ? "the file ends after a whole record" : "the file ends inside a record's opcode and length");
    return false;
  }
  std::array<std::uint8_t, kRecordHeaderBytes> head{};
  if (!read_exact(head.data(), head.size())) throw TraceIoError(name_ + ": read error at byte " + std::to_string(at));
  const std::uint8_t op = head[0];
  const std::uint64_t length = le64(head.data() + 1);
  const char* op_name = known(op) ? to_string(static_cast<Opcode>(op)) : "user or unknown";
  if (length > options_.max_record_bytes) {
    fail(at, std::string(op_name) + " record declares " + std::to_string(length) + " bytes, more than the " +
                 std::to_string(options_.max_record_bytes) + " a record may have (corrupt length?)");
  }
  if (length > size_ - pos_ - kRecordHeaderBytes) {
    const std::string what = std::string("the ") + op_name + " record there declares " + std::to_string(length) +
                             " bytes, only " + std::to_string(size_ - pos_ - kRecordHeaderBytes) + " follow";
    truncated(at, what);
    if (op == static_cast<std::uint8_t>(Opcode::kChunk)) {
      // A recorder killed while writing a chunk: the whole records at its start are still there.
      const std::uint64_t recovered = recover_chunk(at);
      if (recovered > 0) {
        warning_ += "; " + std::to_string(recovered) + " whole records were recovered from the start of that Chunk";
        partial_chunk_ = true;
        record.opcode = Opcode::kChunk;
        record.offset = at;
        record.chunk_offset = 0;
        record.in_chunk = false;
        record.body = partial_;
        ++counts_[Opcode::kChunk];
        state_ = State::kReading;  // until the recovered records are read
        return true;
      }
    }
    return false;
  }
  body_.resize(static_cast<std::size_t>(length));
  if (!read_exact(body_.data(), body_.size())) throw TraceIoError(name_ + ": read error at byte " + std::to_string(at));
  pos_ += kRecordHeaderBytes + length;

  if (op == static_cast<std::uint8_t>(Opcode::kDataEnd)) {
    data_crc_open_ = false;
  } else if (data_crc_open_) {
    data_crc_ = crc32_update(data_crc_, head.data(), head.size());
    data_crc_ = crc32_update(data_crc_, body_.data(), body_.size());
  }

  record.offset = at;
  record.chunk_offset = 0;
  record.in_chunk = false;
  if (!known(op)) {
    record.opcode = static_cast<Opcode>(op);
    record.body = Unknown{op, length};
    ++counts_[record.opcode];
    return true;
  }
  record.opcode = static_cast<Opcode>(op);
  ++counts_[record.opcode];
  if (record.opcode == Opcode::kChunk) {
    Chunk chunk;
    load_chunk(body_, at, chunk);
    record.body = std::move(chunk);
    return true;
  }
  parse(record.opcode, body_, at, record.body);
  if (record.opcode == Opcode::kDataEnd) {
    const auto& end = std::get<DataEnd>(record.body);
    if (options_.check_crcs && end.data_section_crc != 0 && end.data_section_crc != data_crc_) {
      fail(at, "DataEnd: data section CRC-32 " + std::to_string(end.data_section_crc) + " does not match the " +
                   std::to_string(data_crc_) + " computed");
    }
  } else if (record.opcode == Opcode::kFooter) {
    check_summary_crc(std::get<Footer>(record.body), at);
    footer_seen_ = true;
  } else if (record.opcode == Opcode::kAttachment) {
    const auto& a = std::get<Attachment>(record.body);
    if (options_.check_crcs && a.crc != 0) {
      // The CRC covers the fields before it: 8 + 8 + 4 + name + 4 + media type + 8 + data.
      const std::size_t covered = 8 + 8 + 4 + a.name.size() + 4 + a.media_type.size() + 8 + a.data.size();
      const std::uint32_t crc = crc32_update(0, body_.data(), covered);
      if (crc != a.crc) {
        fail(at, "Attachment '" + a.name + "': CRC-32 " + std::to_string(a.crc) + " does not match the " +
                     std::to_string(crc) + " computed");
      }
    }
  }
  return true;
}

void Reader::check_summary_crc(const Footer& footer, std::uint64_t footer_offset) {
  if (!options_.check_crcs || footer.summary_crc == 0) return;
  const std::uint64_t start = footer.summary_start != 0 ? footer.summary_start : footer_offset;
  const std::uint64_t end = footer_offset + kRecordHeaderBytes + 8 + 8;  // up to the summary_crc field
  if (start > footer_offset) fail(footer_offset, "Footer: summary_start " + std::to_string(start) + " is after the Footer");
  std::uint32_t crc = 0;
  in_->clear();
  in_->seekg(static_cast<std::streamoff>(start));
  std::vector<std::uint8_t> block(std::size_t{64} * 1024);
  for (std::uint64_t left = end - start; left > 0;) {
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(left, block.size()));
    if (!read_exact(block.data(), n)) throw TraceIoError(name_ + ": read error in the summary");
    crc = crc32_update(crc, block.data(), n);
    left -= n;
  }
  in_->seekg(static_cast<std::streamoff>(pos_));
  if (crc != footer.summary_crc) {
    fail(footer_offset, "Footer: summary CRC-32 " + std::to_string(footer.summary_crc) + " does not match the " +
                            std::to_string(crc) + " computed from byte " + std::to_string(start));
  }
}

void Reader::load_chunk(const Bytes& body, std::uint64_t offset, Chunk& chunk) {
  const std::uint8_t* records = nullptr;
  try {
    Fields f(body.data(), body.size(), "Chunk");
    chunk.message_start_time = f.u64();
    chunk.message_end_time = f.u64();
    chunk.uncompressed_size = f.u64();
    chunk.uncompressed_crc = f.u32();
    chunk.compression = f.str();
    chunk.compressed_size = f.u64();
    records = f.need(chunk.compressed_size, "records");
  } catch (const std::out_of_range& e) {
    fail(offset, e.what());
  }
  if (chunk.uncompressed_size > options_.max_record_bytes) {
    fail(offset, "Chunk declares " + std::to_string(chunk.uncompressed_size) + " uncompressed bytes, more than the " +
                     std::to_string(options_.max_record_bytes) + " a chunk may have (corrupt size?)");
  }
  const auto n = static_cast<std::size_t>(chunk.uncompressed_size);
  const auto packed = static_cast<std::size_t>(chunk.compressed_size);
  if (chunk.compression.empty()) {
    if (packed != n) {
      fail(offset, "uncompressed Chunk holds " + std::to_string(packed) + " bytes of records but declares " +
                       std::to_string(n));
    }
    chunk_.assign(records, records + n);
  } else if (chunk.compression == "zstd") {
    // A zstd frame that declares its content size must declare this one: checked before allocating.
    const unsigned long long framed = ZSTD_getFrameContentSize(records, packed);
    if (framed == ZSTD_CONTENTSIZE_ERROR) fail(offset, "Chunk: the zstd data is not a zstd frame");
    if (framed != ZSTD_CONTENTSIZE_UNKNOWN && framed != n) {
      fail(offset, "Chunk: the zstd frame holds " + std::to_string(framed) + " bytes, the chunk declares " +
                       std::to_string(n));
    }
    chunk_.resize(n);
    const std::size_t got = ZSTD_decompress(chunk_.data(), n, records, packed);
    if (ZSTD_isError(got) != 0u) fail(offset, std::string("Chunk: zstd: ") + ZSTD_getErrorName(got));
    if (got != n) {
      fail(offset, "Chunk: zstd gave " + std::to_string(got) + " bytes, the chunk declares " + std::to_string(n));
    }
  } else if (chunk.compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)) != 0u) {
      throw std::bad_alloc();
    }
    chunk_.resize(n);
    std::size_t out = 0;
    std::size_t in = 0;
    std::size_t status = 1;
    while (status != 0 && in < packed) {
      std::size_t dst = n - out;
      std::size_t src = packed - in;
      status = LZ4F_decompress(ctx, chunk_.data() + out, &dst, records + in, &src, nullptr);
      if (LZ4F_isError(status) != 0u) {
        const std::string error = LZ4F_getErrorName(status);
        LZ4F_freeDecompressionContext(ctx);
        fail(offset, "Chunk: lz4: " + error);
      }
      out += dst;
      in += src;
      if (dst == 0 && src == 0) break;  // no progress: the output is full or the input ends
    }
    LZ4F_freeDecompressionContext(ctx);
    if (status != 0 || out != n) {
      fail(offset, "Chunk: lz4 gave " + std::to_string(out) + " bytes" + (status != 0 ? " and an unfinished frame" : "") +
                       ", the chunk declares " + std::to_string(n));
    }
  } else {
    fail(offset, "Chunk: unknown compression '" + chunk.compression + "' (this reader knows '', 'zstd' and 'lz4')");
  }
  if (options_.check_crcs && chunk.uncompressed_crc != 0) {
    const std::uint32_t crc = crc32_update(0, chunk_.data(), chunk_.size());
    if (crc != chunk.uncompressed_crc) {
      fail(offset, "Chunk: CRC-32 " + std::to_string(chunk.uncompressed_crc) + " of the uncompressed records does "
                   "not match the " + std::to_string(crc) + " computed");
    }
  }
  chunk_pos_ = 0;
  chunk_file_offset_ = offset;
  in_chunk_ = true;
}

std::uint64_t Reader::recover_chunk(std::uint64_t offset) {
  Bytes rest(static_cast<std::size_t>(size_ - pos_ - kRecordHeaderBytes));
  in_->seekg(static_cast<std::streamoff>(pos_ + kRecordHeaderBytes));
  if (!read_exact(rest.data(), rest.size())) return 0;
  Chunk& chunk = partial_;
  const std::uint8_t* packed = nullptr;
  std::size_t packed_size = 0;
  try {
    Fields f(rest.data(), rest.size(), "Chunk");
    chunk.message_start_time = f.u64();
    chunk.message_end_time = f.u64();
    chunk.uncompressed_size = f.u64();
    chunk.uncompressed_crc = f.u32();
    chunk.compression = f.str();
    chunk.compressed_size = f.u64();
    packed_size = static_cast<std::size_t>(std::min<std::uint64_t>(chunk.compressed_size, rest.size() - f.pos()));
    packed = f.need(packed_size, "records");
  } catch (const std::out_of_range&) {
    return 0;
  }
  if (chunk.uncompressed_size > options_.max_record_bytes) return 0;
  chunk_.clear();
  if (chunk.compression.empty()) {
    chunk_.assign(packed, packed + packed_size);
  } else if (chunk.compression == "zstd") {
    // Streamed, so that the cut-off frame gives what it holds.
    ZSTD_DStream* z = ZSTD_createDStream();
    chunk_.resize(static_cast<std::size_t>(chunk.uncompressed_size));
    ZSTD_inBuffer in{packed, packed_size, 0};
    ZSTD_outBuffer out{chunk_.data(), chunk_.size(), 0};
    while (in.pos < in.size && out.pos < out.size) {
      const std::size_t rc = ZSTD_decompressStream(z, &out, &in);
      if (ZSTD_isError(rc) != 0u) break;
    }
    ZSTD_freeDStream(z);
    chunk_.resize(out.pos);
  } else if (chunk.compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)) != 0u) return 0;
    chunk_.resize(static_cast<std::size_t>(chunk.uncompressed_size));
    std::size_t dst = chunk_.size();
    std::size_t src = packed_size;
    if (LZ4F_isError(LZ4F_decompress(ctx, chunk_.data(), &dst, packed, &src, nullptr)) != 0u) dst = 0;
    LZ4F_freeDecompressionContext(ctx);
    chunk_.resize(dst);
  }
  // Keep the whole records only.
  std::size_t end = 0;
  std::uint64_t whole = 0;
  while (chunk_.size() - end >= kRecordHeaderBytes) {
    const std::uint64_t length = le64(chunk_.data() + end + 1);
    if (length > chunk_.size() - end - kRecordHeaderBytes) break;
    end += kRecordHeaderBytes + static_cast<std::size_t>(length);
    ++whole;
  }
  chunk_.resize(end);
  pos_ = size_;
  chunk_pos_ = 0;
  chunk_file_offset_ = offset;
  in_chunk_ = whole > 0;
  return whole;
}

bool Reader::next_in_chunk(Record& record) {
  if (chunk_pos_ == chunk_.size()) return false;
  const std::uint64_t at = chunk_pos_;
  const auto where = [&] { return "in the Chunk, at its byte " + std::to_string(at) + ": "; };
  if (chunk_.size() - chunk_pos_ < kRecordHeaderBytes) {
    fail(chunk_file_offset_, where() + "a record's opcode and length run past the chunk's end");
  }
  const std::uint8_t op = chunk_[at];
  const std::uint64_t length = le64(chunk_.data() + at + 1);
  if (length > chunk_.size() - chunk_pos_ - kRecordHeaderBytes) {
    fail(chunk_file_offset_, where() + "a record of " + std::to_string(length) + " bytes runs past the chunk's end");
  }
  record.offset = chunk_file_offset_;
  record.chunk_offset = at;
  record.in_chunk = true;
  record.opcode = static_cast<Opcode>(op);
  ++counts_[record.opcode];
  const std::size_t start = static_cast<std::size_t>(at) + kRecordHeaderBytes;
  chunk_pos_ = start + length;
  if (!known(op)) {
    record.body = Unknown{op, length};
    return true;
  }
  if (record.opcode == Opcode::kChunk) fail(chunk_file_offset_, where() + "a Chunk inside a Chunk");
  Bytes inner(chunk_.begin() + static_cast<std::ptrdiff_t>(start),
              chunk_.begin() + static_cast<std::ptrdiff_t>(start + length));
  try {
    parse(record.opcode, inner, chunk_file_offset_, record.body);
  } catch (const TraceFormatError& e) {
    fail(chunk_file_offset_, where() + std::string(e.what()).substr(name_.size() + 2));
  }
  return true;
}

void Reader::parse(Opcode op, const Bytes& body, std::uint64_t offset, RecordBody& out) const {
  // Fields past those read are padding a later version of the specification may fill: ignored.
  try {
    Fields f(body.data(), body.size(), to_string(op));
    switch (op) {
      case Opcode::kHeader: {
        Header h;
        h.profile = f.str();
        h.library = f.str();
        out = std::move(h);
        break;
      }
      case Opcode::kFooter: {
        Footer r;
        r.summary_start = f.u64();
        r.summary_offset_start = f.u64();
        r.summary_crc = f.u32();
        out = r;
        break;
      }
      case Opcode::kSchema: {
        Schema s;
        s.id = f.u16();
        s.name = f.str();
        s.encoding = f.str();
        s.data = f.bytes32();
        if (s.id == 0) throw std::out_of_range("Schema record: id 0 is reserved (no schema)");
        out = std::move(s);
        break;
      }
      case Opcode::kChannel: {
        Channel c;
        c.id = f.u16();
        c.schema_id = f.u16();
        c.topic = f.str();
        c.message_encoding = f.str();
        c.metadata = f.string_map();
        out = std::move(c);
        break;
      }
      case Opcode::kMessage: {
        Message m;
        m.channel_id = f.u16();
        m.sequence = f.u32();
        m.log_time = f.u64();
        m.publish_time = f.u64();
        const std::size_t n = body.size() - f.pos();
        const auto* p = f.need(n, "data");
        m.data.assign(p, p + n);
        out = std::move(m);
        break;
      }
      case Opcode::kMessageIndex: {
        MessageIndex m;
        m.channel_id = f.u16();
        Fields sub = f.sub_fields(f.u32(), "records");
        while (!sub.done()) {
          const std::uint64_t t = sub.u64();
          m.records.emplace_back(t, sub.u64());
        }
        out = std::move(m);
        break;
      }
      case Opcode::kChunkIndex: {
        ChunkIndex c;
        c.message_start_time = f.u64();
        c.message_end_time = f.u64();
        c.chunk_start_offset = f.u64();
        c.chunk_length = f.u64();
        c.message_index_offsets = f.id_map();
        c.message_index_length = f.u64();
        c.compression = f.str();
        c.compressed_size = f.u64();
        c.uncompressed_size = f.u64();
        out = std::move(c);
        break;
      }
      case Opcode::kAttachment: {
        Attachment a;
        a.log_time = f.u64();
        a.create_time = f.u64();
        a.name = f.str();
        a.media_type = f.str();
        const std::uint64_t n = f.u64();
        const auto* p = f.need(n, "data");
        a.data.assign(p, p + n);
        a.crc = f.u32();
        out = std::move(a);
        break;
      }
      case Opcode::kAttachmentIndex: {
        AttachmentIndex a;
        a.offset = f.u64();
        a.length = f.u64();
        a.log_time = f.u64();
        a.create_time = f.u64();
        a.data_size = f.u64();
        a.name = f.str();
        a.media_type = f.str();
        out = std::move(a);
        break;
      }
      case Opcode::kStatistics: {
        Statistics s;
        s.message_count = f.u64();
        s.schema_count = f.u16();
        s.channel_count = f.u32();
        s.attachment_count = f.u32();
        s.metadata_count = f.u32();
        s.chunk_count = f.u32();
        s.message_start_time = f.u64();
        s.message_end_time = f.u64();
        s.channel_message_counts = f.id_map();
        out = std::move(s);
        break;
      }
      case Opcode::kMetadata: {
        Metadata m;
        m.name = f.str();
        m.metadata = f.string_map();
        out = std::move(m);
        break;
      }
      case Opcode::kMetadataIndex: {
        MetadataIndex m;
        m.offset = f.u64();
        m.length = f.u64();
        m.name = f.str();
        out = std::move(m);
        break;
      }
      case Opcode::kSummaryOffset: {
        SummaryOffset s;
        s.group_opcode = f.u8();
        s.group_start = f.u64();
        s.group_length = f.u64();
        out = s;
        break;
      }
      case Opcode::kDataEnd: {
        DataEnd d;
        d.data_section_crc = f.u32();
        out = d;
        break;
      }
      case Opcode::kChunk: break;  // load_chunk
    }
  } catch (const std::out_of_range& e) {
    fail(offset, e.what());
  }
}

}  // namespace tripodal::trace::mcap
