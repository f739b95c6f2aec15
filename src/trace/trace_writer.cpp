#include "tripodal/trace/trace_writer.hpp"

#include <stdexcept>

#include "codec.hpp"

namespace tripodal::trace {

TraceWriter::TraceWriter(const std::filesystem::path& path, TraceWriterOptions options)
    : TraceWriter(
          [&] {
            auto f = std::make_unique<std::ofstream>(path, std::ios::binary | std::ios::trunc);
            if (!f->is_open()) throw TraceIoError(path.string() + ": cannot open the trace for writing");
            return f;
          }(),
          path.string(), options) {}

TraceWriter::TraceWriter(std::unique_ptr<std::ostream> out, std::string name, TraceWriterOptions options)
    : out_(std::move(out)), name_(std::move(name)), options_(options) {
  std::vector<std::uint8_t> header(detail::kMagic.begin(), detail::kMagic.end());
  detail::ByteWriter w(header);
  w.u16(detail::kFormatVersion);
  w.u16(0);  // flags, reserved
  w.u32(detail::crc32(header.data(), header.size()));
  out_->write(reinterpret_cast<const char*>(header.data()), static_cast<std::streamsize>(header.size()));
  if (!*out_) throw TraceIoError(name_ + ": cannot write the trace header");
  bytes_ = header.size();
  body_.reserve(4096);
}

TraceWriter::~TraceWriter() {
  try {
    close();
  } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw; close() reports
  }
}

void TraceWriter::check_open() const {
  if (!out_) throw std::logic_error(name_ + ": trace writer is closed");
}

ChannelId TraceWriter::add_channel(std::string_view name, ChannelKind kind) {
  check_open();
  if (name.empty() || name.size() > 0xFFFF) {
    throw std::invalid_argument(name_ + ": a channel name must have 1 to 65535 bytes");
  }
  if (!is_valid(kind)) throw std::invalid_argument(name_ + ": invalid channel kind");
  for (const auto& c : channels_) {
    if (c.name == name) throw std::invalid_argument(name_ + ": channel '" + std::string(name) + "' is already declared");
  }
  if (channels_.size() > 0xFFFF) throw std::length_error(name_ + ": a trace holds at most 65536 channels");
  ChannelInfo info{static_cast<ChannelId>(channels_.size()), kind, std::string(name)};
  body_.clear();
  detail::encode_declaration(info, body_);
  write_frame();
  channels_.push_back(std::move(info));
  return channels_.back().id;
}

template <typename T>
void TraceWriter::write_record(ChannelId channel, const T& data) {
  check_open();
  constexpr ChannelKind kKind = detail::kind_for<T>();
  if (channel >= channels_.size()) {
    throw std::invalid_argument(name_ + ": channel " + std::to_string(channel) + " is not declared");
  }
  if (channels_[channel].kind != kKind) {
    throw std::invalid_argument(name_ + ": channel '" + channels_[channel].name + "' carries " +
                                std::string(to_string(channels_[channel].kind)) + " records, not " +
                                std::string(to_string(kKind)));
  }
  body_.clear();
  detail::encode(channel, data, body_);
  write_frame();
  ++records_;
  if (options_.flush_every_records != 0 && ++since_flush_ >= options_.flush_every_records) flush();
}

void TraceWriter::write(ChannelId channel, const RecordData& data) {
  std::visit([&](const auto& r) { write_record(channel, r); }, data);
}
void TraceWriter::write(ChannelId channel, const LaserScan& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const OdometryReading& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const SonarReading& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const InfraredReading& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const BumperReading& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const BatteryReading& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const GyroReading& reading) { write_record(channel, reading); }
void TraceWriter::write(ChannelId channel, const CommandRecord& command) { write_record(channel, command); }
void TraceWriter::write(ChannelId channel, const EventRecord& event) { write_record(channel, event); }

void TraceWriter::write_frame() {
  if (body_.size() > 0xFFFFFFFFu - 64) throw std::length_error(name_ + ": record too large for a trace");
  const auto length = static_cast<std::uint32_t>(body_.size());
  std::array<std::uint8_t, 12> frame{};
  const std::uint32_t crc = detail::crc32(body_.data(), body_.size());
  const std::uint32_t fields[3] = {length, ~length, crc};
  for (std::size_t f = 0; f < 3; ++f) {
    for (std::size_t i = 0; i < 4; ++i) frame[f * 4 + i] = static_cast<std::uint8_t>(fields[f] >> (8 * i));
  }
  // Head, body, tail in that order: a recorder killed mid-record leaves a frame the reader sees as
  // a truncated tail, never as a whole record.
  out_->write(reinterpret_cast<const char*>(frame.data()), 8);
  out_->write(reinterpret_cast<const char*>(body_.data()), static_cast<std::streamsize>(body_.size()));
  out_->write(reinterpret_cast<const char*>(frame.data() + 8), 4);
  if (!*out_) throw TraceIoError(name_ + ": write failed at byte " + std::to_string(bytes_));
  bytes_ += 12 + body_.size();
}

void TraceWriter::flush() {
  check_open();
  out_->flush();
  since_flush_ = 0;
  if (!*out_) throw TraceIoError(name_ + ": flush failed");
}

void TraceWriter::close() {
  if (!out_) return;
  out_->flush();
  const bool ok = static_cast<bool>(*out_);
  if (auto* file = dynamic_cast<std::ofstream*>(out_.get())) file->close();
  const bool closed_ok = ok && static_cast<bool>(*out_);
  out_.reset();
  if (!closed_ok) throw TraceIoError(name_ + ": could not flush and close the trace");
}

}  // namespace tripodal::trace
