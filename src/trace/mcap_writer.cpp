// The MCAP writer of mcap.hpp: chunked messages (none or zstd), MessageIndex after each chunk, and a
// summary section (schemas, channels, statistics, chunk and metadata indexes) with offsets and CRCs.
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <stdexcept>

#include "tripodal/trace/mcap.hpp"

namespace tripodal::trace::mcap {

namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

std::uint32_t crc_of(std::uint32_t crc, const std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const std::size_t step = std::min<std::size_t>(n, 1u << 30);
    crc = static_cast<std::uint32_t>(::crc32(crc, p, static_cast<uInt>(step)));
    p += step;
    n -= step;
  }
  return crc;
}

// Builds one record body in little endian.
struct Out {
  Bytes b;
  void u8(std::uint8_t v) { b.push_back(v); }
  void u16(std::uint16_t v) { put(v, 2); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void put(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
  }
  void raw(const std::uint8_t* p, std::size_t n) { b.insert(b.end(), p, p + n); }
  void string_map(const StringMap& m) {
    Out inner;
    for (const auto& [k, v] : m) {
      inner.str(k);
      inner.str(v);
    }
    u32(static_cast<std::uint32_t>(inner.b.size()));
    raw(inner.b.data(), inner.b.size());
  }
  void id_map(const std::map<std::uint16_t, std::uint64_t>& m) {
    u32(static_cast<std::uint32_t>(m.size() * 10));
    for (const auto& [k, v] : m) {
      u16(k);
      u64(v);
    }
  }
};

void frame(Bytes& dst, Opcode op, const Bytes& body) {
  Out o;
  o.u8(static_cast<std::uint8_t>(op));
  o.u64(body.size());
  dst.insert(dst.end(), o.b.begin(), o.b.end());
  dst.insert(dst.end(), body.begin(), body.end());
}

}  // namespace

struct Writer::Impl {
  std::unique_ptr<std::ostream> out;
  std::string name;
  WriterOptions options;
  std::uint64_t pos = 0;
  std::uint32_t data_crc = 0;
  bool closed = false;

  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  Bytes chunk;  // records of the open chunk
  std::uint64_t chunk_start = 0, chunk_end = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index;
  std::vector<ChunkIndex> chunk_indexes;
  std::vector<MetadataIndex> metadata_indexes;
  Statistics stats;
  std::vector<bool> schema_in_chunk, channel_in_chunk;

  void emit(const Bytes& bytes, bool data_section = true) {
    out->write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!*out) throw TraceIoError(name + ": write error at byte " + std::to_string(pos));
    if (data_section) data_crc = crc_of(data_crc, bytes.data(), bytes.size());
    pos += bytes.size();
  }
  static Bytes schema_record(const Schema& s) {
    Out o;
    o.u16(s.id);
    o.str(s.name);
    o.str(s.encoding);
    o.u32(static_cast<std::uint32_t>(s.data.size()));
    o.raw(s.data.data(), s.data.size());
    Bytes r;
    frame(r, Opcode::kSchema, o.b);
    return r;
  }
  static Bytes channel_record(const Channel& c) {
    Out o;
    o.u16(c.id);
    o.u16(c.schema_id);
    o.str(c.topic);
    o.str(c.message_encoding);
    o.string_map(c.metadata);
    Bytes r;
    frame(r, Opcode::kChannel, o.b);
    return r;
  }

  void flush_chunk() {
    if (chunk.empty()) return;
    Bytes packed;
    std::string compression;
    if (options.compression == Compression::kZstd) {
      packed.resize(ZSTD_compressBound(chunk.size()));
      const std::size_t n = ZSTD_compress(packed.data(), packed.size(), chunk.data(), chunk.size(), 3);
      if (ZSTD_isError(n) != 0u) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      packed.resize(n);
      compression = "zstd";
    } else if (options.compression == Compression::kLz4) {
      throw std::invalid_argument("MCAP writer: lz4 chunks are read, not written (use zstd or none)");
    } else {
      packed = chunk;
    }
    Out o;
    o.u64(chunk_start);
    o.u64(chunk_end);
    o.u64(chunk.size());
    o.u32(crc_of(0, chunk.data(), chunk.size()));
    o.str(compression);
    o.u64(packed.size());
    o.raw(packed.data(), packed.size());
    Bytes record;
    frame(record, Opcode::kChunk, o.b);
    ChunkIndex index;
    index.message_start_time = chunk_start;
    index.message_end_time = chunk_end;
    index.chunk_start_offset = pos;
    index.chunk_length = record.size();
    index.compression = compression;
    index.compressed_size = packed.size();
    index.uncompressed_size = chunk.size();
    emit(record);
    const std::uint64_t index_start = pos;
    for (const auto& [channel, entries] : chunk_index) {
      Out m;
      m.u16(channel);
      m.u32(static_cast<std::uint32_t>(entries.size() * 16));
      for (const auto& [t, off] : entries) {
        m.u64(t);
        m.u64(off);
      }
      Bytes r;
      frame(r, Opcode::kMessageIndex, m.b);
      index.message_index_offsets[channel] = pos;
      emit(r);
    }
    index.message_index_length = pos - index_start;
    chunk_indexes.push_back(std::move(index));
    ++stats.chunk_count;
    chunk.clear();
    chunk_index.clear();
    schema_in_chunk.assign(schema_in_chunk.size(), false);
    channel_in_chunk.assign(channel_in_chunk.size(), false);
  }

  void close() {
    if (closed) return;
    closed = true;
    flush_chunk();
    Out end;
    end.u32(data_crc);
    Bytes r;
    frame(r, Opcode::kDataEnd, end.b);
    emit(r, false);

    // The summary: one group per record kind, each listed by a SummaryOffset.
    const std::uint64_t summary_start = pos;
    Bytes summary;
    std::vector<SummaryOffset> groups;
    const auto group = [&](Opcode op, const std::function<void()>& fill) {
      const std::size_t before = summary.size();
      fill();
      if (summary.size() > before) {
        groups.push_back(SummaryOffset{static_cast<std::uint8_t>(op), summary_start + before, summary.size() - before});
      }
    };
    group(Opcode::kSchema, [&] {
      for (const auto& s : schemas) {
        const Bytes b = schema_record(s);
        summary.insert(summary.end(), b.begin(), b.end());
      }
    });
    group(Opcode::kChannel, [&] {
      for (const auto& c : channels) {
        const Bytes b = channel_record(c);
        summary.insert(summary.end(), b.begin(), b.end());
      }
    });
    group(Opcode::kStatistics, [&] {
      Out o;
      o.u64(stats.message_count);
      o.u16(static_cast<std::uint16_t>(schemas.size()));
      o.u32(static_cast<std::uint32_t>(channels.size()));
      o.u32(0);
      o.u32(static_cast<std::uint32_t>(metadata_indexes.size()));
      o.u32(stats.chunk_count);
      o.u64(stats.message_count == 0 ? 0 : stats.message_start_time);
      o.u64(stats.message_end_time);
      o.id_map(stats.channel_message_counts);
      frame(summary, Opcode::kStatistics, o.b);
    });
    group(Opcode::kChunkIndex, [&] {
      for (const auto& c : chunk_indexes) {
        Out o;
        o.u64(c.message_start_time);
        o.u64(c.message_end_time);
        o.u64(c.chunk_start_offset);
        o.u64(c.chunk_length);
        o.id_map(c.message_index_offsets);
        o.u64(c.message_index_length);
        o.str(c.compression);
        o.u64(c.compressed_size);
        o.u64(c.uncompressed_size);
        frame(summary, Opcode::kChunkIndex, o.b);
      }
    });
    group(Opcode::kMetadataIndex, [&] {
      for (const auto& m : metadata_indexes) {
        Out o;
        o.u64(m.offset);
        o.u64(m.length);
        o.str(m.name);
        frame(summary, Opcode::kMetadataIndex, o.b);
      }
    });
    const std::uint64_t summary_offset_start = summary_start + summary.size();
    for (const auto& g : groups) {
      Out o;
      o.u8(g.group_opcode);
      o.u64(g.group_start);
      o.u64(g.group_length);
      frame(summary, Opcode::kSummaryOffset, o.b);
    }
    Out footer;
    footer.u64(summary_start);
    footer.u64(summary_offset_start);
    Bytes tail;
    frame(tail, Opcode::kFooter, [&] {
      Bytes b = footer.b;
      b.resize(b.size() + 4);
      return b;
    }());
    // The summary CRC covers the summary and the Footer up to its summary_crc field.
    std::uint32_t crc = crc_of(0, summary.data(), summary.size());
    crc = crc_of(crc, tail.data(), tail.size() - 4);
    for (int i = 0; i < 4; ++i) tail[tail.size() - 4 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(crc >> (8 * i));
    emit(summary, false);
    emit(tail, false);
    emit(Bytes(kMagic, kMagic + 8), false);
    out->flush();
    if (!*out) throw TraceIoError(name + ": write error");
  }
};

Writer::Writer(const std::filesystem::path& path, WriterOptions options)
    : Writer(
          [&] {
            auto f = std::make_unique<std::ofstream>(path, std::ios::binary | std::ios::trunc);
            if (!*f) throw TraceIoError(path.string() + ": cannot create the file");
            return f;
          }(),
          path.string(), std::move(options)) {}

Writer::Writer(std::unique_ptr<std::ostream> out, std::string name, WriterOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->out = std::move(out);
  impl_->name = std::move(name);
  impl_->options = std::move(options);
  impl_->emit(Bytes(kMagic, kMagic + 8));
  Out h;
  h.str(impl_->options.profile);
  h.str(impl_->options.library);
  Bytes r;
  frame(r, Opcode::kHeader, h.b);
  impl_->emit(r);
}

Writer::~Writer() {
  try {
    close();
  } catch (...) {  // NOLINT(bugprone-empty-catch): documented: close() reports errors
  }
}

std::uint16_t Writer::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  Schema s;
  s.id = static_cast<std::uint16_t>(impl_->schemas.size() + 1);
  s.name = name;
  s.encoding = encoding;
  s.data.assign(data.begin(), data.end());
  impl_->schemas.push_back(std::move(s));
  impl_->schema_in_chunk.push_back(false);
  return impl_->schemas.back().id;
}

std::uint16_t Writer::add_channel(const std::string& topic, const std::string& message_encoding, std::uint16_t schema_id,
                                  const StringMap& metadata) {
  if (schema_id == 0 || schema_id > impl_->schemas.size()) {
    throw std::invalid_argument("MCAP writer: channel '" + topic + "' names schema " + std::to_string(schema_id) +
                                ", which was not added");
  }
  Channel c;
  c.id = static_cast<std::uint16_t>(impl_->channels.size());
  c.schema_id = schema_id;
  c.topic = topic;
  c.message_encoding = message_encoding;
  c.metadata = metadata;
  impl_->channels.push_back(std::move(c));
  impl_->channel_in_chunk.push_back(false);
  return impl_->channels.back().id;
}

void Writer::write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time, const Bytes& data,
                   std::uint32_t sequence) {
  Impl& w = *impl_;
  if (w.closed) throw std::logic_error("MCAP writer: write after close");
  if (channel_id >= w.channels.size()) {
    throw std::invalid_argument("MCAP writer: channel " + std::to_string(channel_id) + " was not added");
  }
  // Each chunk is readable alone: it repeats the schema and channel its messages need.
  const Channel& c = w.channels[channel_id];
  if (!w.schema_in_chunk[c.schema_id - 1u]) {
    const Bytes r = Impl::schema_record(w.schemas[c.schema_id - 1u]);
    w.chunk.insert(w.chunk.end(), r.begin(), r.end());
    w.schema_in_chunk[c.schema_id - 1u] = true;
  }
  if (!w.channel_in_chunk[channel_id]) {
    const Bytes r = Impl::channel_record(c);
    w.chunk.insert(w.chunk.end(), r.begin(), r.end());
    w.channel_in_chunk[channel_id] = true;
  }
  if (w.chunk_index.empty()) {
    w.chunk_start = log_time;
    w.chunk_end = log_time;
  }
  w.chunk_start = std::min(w.chunk_start, log_time);
  w.chunk_end = std::max(w.chunk_end, log_time);
  w.chunk_index[channel_id].emplace_back(log_time, w.chunk.size());
  Out o;
  o.u16(channel_id);
  o.u32(sequence);
  o.u64(log_time);
  o.u64(publish_time);
  o.raw(data.data(), data.size());
  frame(w.chunk, Opcode::kMessage, o.b);
  if (w.stats.message_count == 0) {
    w.stats.message_start_time = log_time;
    w.stats.message_end_time = log_time;
  }
  w.stats.message_start_time = std::min(w.stats.message_start_time, log_time);
  w.stats.message_end_time = std::max(w.stats.message_end_time, log_time);
  ++w.stats.message_count;
  ++w.stats.channel_message_counts[channel_id];
  ++messages_;
  if (w.chunk.size() >= w.options.chunk_bytes) w.flush_chunk();
}

void Writer::write_metadata(const std::string& name, const StringMap& metadata) {
  Impl& w = *impl_;
  if (w.closed) throw std::logic_error("MCAP writer: write after close");
  w.flush_chunk();  // metadata sits between chunks, never inside one
  Out o;
  o.str(name);
  o.string_map(metadata);
  Bytes r;
  frame(r, Opcode::kMetadata, o.b);
  w.metadata_indexes.push_back(MetadataIndex{w.pos, r.size(), name});
  w.emit(r);
}

void Writer::close() { impl_->close(); }

}  // namespace tripodal::trace::mcap
