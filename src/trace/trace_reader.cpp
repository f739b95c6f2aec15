#include "tripodal/trace/trace_reader.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "codec.hpp"

namespace tripodal::trace {

namespace {

std::uint32_t le32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

constexpr std::size_t kBodyChunkBytes = std::size_t{1} << 20;

std::string hex32(std::uint32_t v) {
  std::ostringstream s;
  s << "0x" << std::hex << v;
  return s.str();
}

}  // namespace

TraceReader::TraceReader(const std::filesystem::path& path, TraceReaderOptions options)
    : name_(path.string()), options_(options) {
  auto file = std::make_unique<std::ifstream>();
  // The stream reads through our buffer, so its size is the reader's memory footprint (plus the
  // largest record).
  stream_buffer_.resize(std::max<std::size_t>(options_.buffer_bytes, 64));
  file->rdbuf()->pubsetbuf(stream_buffer_.data(), static_cast<std::streamsize>(stream_buffer_.size()));
  file->open(path, std::ios::binary);
  if (!file->is_open()) throw TraceIoError(name_ + ": cannot open the trace for reading");
  in_ = std::move(file);
  read_header();
}

TraceReader::TraceReader(std::unique_ptr<std::istream> in, std::string name, TraceReaderOptions options)
    : in_(std::move(in)), name_(std::move(name)), options_(options) {
  read_header();
}

TraceReader::~TraceReader() = default;

void TraceReader::fail(std::uint64_t offset, const std::string& what) {
  state_ = ReadState::kEnd;
  throw TraceFormatError(name_, offset, what);
}

std::size_t TraceReader::read_bytes(std::uint8_t* dst, std::size_t n) {
  in_->read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
  const auto got = static_cast<std::size_t>(in_->gcount());
  if (got < n && in_->bad()) throw TraceIoError(name_ + ": read error near byte " + std::to_string(offset_ + got));
  return got;
}

void TraceReader::read_header() {
  std::array<std::uint8_t, detail::kFileHeaderBytes> h{};
  const std::size_t got = read_bytes(h.data(), h.size());
  const std::size_t magic_got = std::min(got, detail::kMagic.size());
  for (std::size_t i = 0; i < magic_got; ++i) {
    if (h[i] != detail::kMagic[i]) fail(i, "not a tripodal trace (bad magic bytes)");
  }
  if (got < h.size()) {
    fail(got, "file ends inside the " + std::to_string(h.size()) + "-byte trace header (" + std::to_string(got) +
                  " bytes)");
  }
  version_ = static_cast<std::uint16_t>(h[8] | h[9] << 8);
  if (version_ != detail::kFormatVersion) {
    fail(8, "trace format version " + std::to_string(version_) + " is not supported (this reader reads version " +
                std::to_string(detail::kFormatVersion) + ")");
  }
  const std::uint32_t stored = le32(h.data() + 12);
  const std::uint32_t computed = detail::crc32(h.data(), 12);
  if (stored != computed) {
    fail(12, "trace header checksum mismatch (stored " + hex32(stored) + ", computed " + hex32(computed) + ")");
  }
  const auto flags = static_cast<std::uint16_t>(h[10] | h[11] << 8);
  if (flags != 0) fail(10, "unknown trace header flags " + hex32(flags));
  offset_ = h.size();
}

const ChannelInfo& TraceReader::channel(ChannelId id) const {
  if (id >= channel_index_.size() || channel_index_[id] < 0) {
    throw std::out_of_range(name_ + ": channel " + std::to_string(id) + " is not declared");
  }
  return channels_[static_cast<std::size_t>(channel_index_[id])];
}

bool TraceReader::next(TraceRecord& record) {
  while (state_ == ReadState::kReading) {
    const std::uint64_t frame_at = offset_;
    std::array<std::uint8_t, detail::kFrameHeadBytes> head{};
    const std::size_t got = read_bytes(head.data(), head.size());
    if (got == 0) {
      state_ = ReadState::kEnd;
      return false;
    }
    if (got < head.size()) {
      state_ = ReadState::kTruncated;
      warning_ = name_ + ": truncated at byte " + std::to_string(frame_at) + " (the file ends " + std::to_string(got) +
                 " bytes into a record frame header)";
      return false;
    }
    const std::uint32_t length = le32(head.data());
    if (le32(head.data() + 4) != ~length) fail(frame_at, "corrupt record frame (length check mismatch)");
    if (length < detail::kBodyHeadBytes || length > options_.max_record_bytes) {
      fail(frame_at, "record length " + std::to_string(length) + " outside [" + std::to_string(detail::kBodyHeadBytes) +
                         ", " + std::to_string(options_.max_record_bytes) + "]");
    }
    // The body grows as its bytes arrive, so a length field that promises more than the file
    // holds costs at most one chunk beyond what the file has.
    const std::size_t want = length + detail::kFrameTailBytes;
    std::size_t body_got = 0;
    body_.clear();
    while (body_got < want) {
      const std::size_t step = std::min<std::size_t>(want - body_got, kBodyChunkBytes);
      body_.resize(body_got + step);
      const std::size_t got_now = read_bytes(body_.data() + body_got, step);
      body_got += got_now;
      if (got_now < step) break;
    }
    if (body_got < want) {
      state_ = ReadState::kTruncated;
      warning_ = name_ + ": truncated at byte " + std::to_string(frame_at) + " (a record of " +
                 std::to_string(length + detail::kFrameHeadBytes + detail::kFrameTailBytes) + " bytes has only " +
                 std::to_string(got + body_got) + ")";
      return false;
    }
    const std::uint32_t stored = le32(body_.data() + length);
    const std::uint32_t computed = detail::crc32(body_.data(), length);
    if (stored != computed) {
      fail(frame_at, "record checksum mismatch (stored " + hex32(stored) + ", computed " + hex32(computed) + ")");
    }
    const std::uint64_t body_at = frame_at + detail::kFrameHeadBytes;
    try {
      detail::ByteReader in(body_.data(), length);
      const std::uint8_t type = in.u8();
      const ChannelId channel = in.u16();
      const Time stamp = time_from_ns(in.i64());
      if (type == detail::kChannelDeclaration) {
        // Stamped 0 by the format, so that a trace re-writes to its own bytes.
        if (to_ns(stamp) != 0) {
          throw detail::DecodeError{3, "channel declaration stamped " + std::to_string(to_ns(stamp)) +
                                           " (declarations are stamped 0)"};
        }
        const std::size_t kind_at = in.position();
        const auto kind = static_cast<ChannelKind>(in.u8());
        if (!is_valid(kind)) {
          throw detail::DecodeError{kind_at, "unknown channel kind " + std::to_string(static_cast<int>(kind))};
        }
        std::string channel_name = in.str16("channel name");
        if (in.remaining() != 0) throw detail::DecodeError{in.position(), "unexpected bytes after a channel declaration"};
        if (channel_name.empty()) throw detail::DecodeError{kind_at + 1, "empty channel name"};
        if (channel < channel_index_.size() && channel_index_[channel] >= 0) {
          throw detail::DecodeError{1, "channel " + std::to_string(channel) + " is declared twice"};
        }
        if (channel_index_.size() <= channel) channel_index_.resize(static_cast<std::size_t>(channel) + 1, -1);
        channel_index_[channel] = static_cast<int>(channels_.size());
        channels_.push_back(ChannelInfo{channel, kind, std::move(channel_name)});
        offset_ = frame_at + detail::kFrameHeadBytes + body_.size();
        continue;
      }
      const auto kind = static_cast<ChannelKind>(type);
      if (!is_valid(kind)) throw detail::DecodeError{0, "unknown record type " + std::to_string(type)};
      if (channel >= channel_index_.size() || channel_index_[channel] < 0) {
        throw detail::DecodeError{1, "record on undeclared channel " + std::to_string(channel)};
      }
      const ChannelInfo& info = channels_[static_cast<std::size_t>(channel_index_[channel])];
      if (info.kind != kind) {
        throw detail::DecodeError{0, std::string(to_string(kind)) + " record on " + std::string(to_string(info.kind)) +
                                         " channel '" + info.name + "'"};
      }
      detail::decode_payload(kind, stamp, in, record.data);
      record.channel = channel;
      record.offset = frame_at;
    } catch (const detail::DecodeError& e) {
      fail(body_at + e.position, e.what);
    }
    offset_ = frame_at + detail::kFrameHeadBytes + body_.size();
    return true;
  }
  return false;
}

}  // namespace tripodal::trace
