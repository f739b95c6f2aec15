#include "tripodal/board/board_link.hpp"

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

namespace tripodal::board {

BoardLink::BoardLink(ByteStream& stream, const LinkConfig& config)
    : stream_(stream),
      config_(config),
      protocol_(config.protocol ? config.protocol : resolve_protocol_profile("", {})),
      profile_(*protocol_),
      decoder_(profile_.frame, FrameSide::responses) {
  const std::string expected(to_string(profile_.frame.checksum));
  for (std::size_t k = 0; k < kChecksumKindCount; ++k) {
    const auto kind = static_cast<ChecksumKind>(k);
    mismatch_text_[k] = fmt::format("protocol profile {} expects {}, the board's frames fit {}{}", profile_.name, expected,
                                    kind == ChecksumKind::sum8 ? "an " : "", to_string(kind));
  }
  const LengthRule other = profile_.frame.length_rule == LengthRule::cmd_payload ? LengthRule::type_cmd_payload : LengthRule::cmd_payload;
  mismatch_text_[kChecksumKindCount] =
      fmt::format("protocol profile {} reads a request's Length as {}, the board's frames fit Length = {}", profile_.name,
                  to_string(profile_.frame.length_rule), to_string(other));
  mismatch_text_[kChecksumKindCount + 1] =
      fmt::format("the board refuses the checksum of requests framed by protocol profile {} (Length = {}), while its own frames "
                  "pass {}: it reads Length as {}, or computes another checksum",
                  profile_.name, to_string(profile_.frame.length_rule), expected, to_string(other));
}

// Two pieces of the same evidence name the mismatch: one could be line noise.
void BoardLink::check_dialect() noexcept {
  const DecoderStats& s = decoder_.stats();
  for (std::size_t k = 0; k < kChecksumKindCount; ++k) {
    if (s.fits[k] >= 2 && dialect_mismatch_.empty()) {
      dialect_mismatch_ = mismatch_text_[k];
      ++stats_.dialect_mismatches;
    }
  }
  if (s.fits_other_length_rule >= 2 && dialect_mismatch_.empty()) {
    dialect_mismatch_ = mismatch_text_[kChecksumKindCount];
    ++stats_.dialect_mismatches;
  }
  if (refused_checksums_ >= 2 && dialect_mismatch_.empty()) {
    dialect_mismatch_ = mismatch_text_[kChecksumKindCount + 1];
    ++stats_.dialect_mismatches;
  }
}

bool BoardLink::queue(Command cmd, std::span<const std::uint8_t> payload) noexcept {
  if (queue_size_ == queue_.size() || payload.size() > queue_[0].payload.size() || !profile_.has(cmd)) return false;
  ActuatorCommand& c = queue_[(queue_head_ + queue_size_) % queue_.size()];
  c.cmd = cmd;
  c.size = static_cast<std::uint8_t>(payload.size());
  if (!payload.empty()) std::memcpy(c.payload.data(), payload.data(), payload.size());
  ++queue_size_;
  return true;
}

bool BoardLink::take_link_lost() noexcept {
  const bool lost = lost_pending_;
  lost_pending_ = false;
  return lost;
}

void BoardLink::fail_stream(Time now) noexcept {
  while (outstanding_size_ > 0) miss(now);
  // The device is gone or misconfigured: lost now, whatever max_missed allows (nothing more is
  // sent, so nothing more would be missed), and SYNC again once it is reopened.
  lose(now);
  stream_failed_ = true;
  next_reopen_ = now;
}

// The port's settings are the link's too: a line switched to canonical mode or echo under the
// host swallows or mirrors bytes for good, so the port is reopened and configured again.
void BoardLink::check_port(Time now) noexcept {
  check_port_now_ = false;
  next_port_check_ = now + config_.port_check_period;
  ++stats_.port_checks;
  const std::string_view fault = stream_.check();
  if (fault.empty()) return;
  last_port_fault_ = fault;
  if (fault == kDeviceGone || fault == kConnectionGone) {
    ++stats_.port_failures;
  } else {
    ++stats_.settings_changed;
  }
  fail_stream(now);
}

void BoardLink::cycle(Time now, WheelSpeeds speeds) noexcept {
  if (!stream_failed_ && (check_port_now_ || now >= next_port_check_)) check_port(now);
  if (stream_failed_) {
    // The device went away (unplugged, the board's process killed): every outstanding request
    // is missed; the device is opened again now and then, and the link resynchronises with SYNC.
    while (outstanding_size_ > 0) miss(now);
    if (now < next_reopen_) return;
    next_reopen_ = now + config_.reopen_period;
    if (!stream_.reopen()) return;
    stream_failed_ = false;
    decoder_.reset();
    ++stats_.reopens;
  }
  receive(now);
  while (outstanding_size_ > 0 && now - outstanding_[0].sent >= config_.response_timeout) miss(now);
  if (outstanding_size_ > 0) return;  // still waiting within the period: one exchange at a time

  if (!synchronised_) {
    (void)send(Command::sync, {}, now, false);
    return;
  }
  std::array<std::uint8_t, 4> p{};
  ByteWriter w(p);
  pack(w, speeds);
  (void)send(Command::drive, w.written(), now, false);
  // At most one other request per period, so the exchange fits the line (docs/board-protocol.md).
  if (queue_size_ > 0) {
    const ActuatorCommand& c = queue_[queue_head_];
    (void)send(c.cmd, std::span<const std::uint8_t>(c.payload.data(), c.size), now, true);
  } else if (now >= next_battery_) {
    next_battery_ = now + config_.battery_period;
    (void)send(Command::battery, {}, now, false);
  } else if (now >= next_tank_) {
    next_tank_ = now + config_.tank_period;
    (void)send(Command::liquid_level, {}, now, false);
  } else if (now >= next_ranges_) {
    next_ranges_ = now + config_.ranges_period / 2;
    ranges_toggle_ = !ranges_toggle_;
    (void)send(ranges_toggle_ ? Command::ultrasonic : Command::infrared, {}, now, false);
  }
}

bool BoardLink::send(Command cmd, std::span<const std::uint8_t> payload, Time now, bool actuator) noexcept {
  if (outstanding_size_ == outstanding_.size()) return false;
  const std::optional<std::uint8_t> id = profile_.id(cmd);
  if (!id) return false;  // the board's dialect has no such command: the poll is skipped
  // A board whose layouts differ from the host's: the payload in the board's layout.
  std::array<std::uint8_t, kMaxLength> staged{};
  if (const CommandSpec* spec = profile_.spec(cmd); spec != nullptr && spec->request_transcoded) {
    const std::ptrdiff_t t = transcode(builtin_command(cmd).request, spec->request, payload, staged);
    if (t < 0) return false;
    payload = std::span<const std::uint8_t>(staged.data(), static_cast<std::size_t>(t));
  }
  const std::size_t n = encode_request(*id, payload, tx_, profile_.frame);
  if (n == 0) return false;
  if (cmd == Command::sync && n <= sync_frame_.size()) {
    std::memcpy(sync_frame_.data(), tx_.data(), n);
    sync_size_ = n;
  }
  if (!stream_.write(std::span<const std::uint8_t>(tx_.data(), n))) {
    miss(now);
    return false;
  }
  outstanding_[outstanding_size_++] = Outstanding{cmd, now, actuator};
  ++stats_.requests;
  stats_.bytes_sent += n;
  return true;
}

void BoardLink::receive(Time now) noexcept {
  while (true) {
    // Deadline 0 (passed): take what has arrived, never wait in the control loop.
    const std::ptrdiff_t n = stream_.read(rx_, Time{});
    if (n < 0) {
      ++stats_.port_failures;
      fail_stream(now);
      return;
    }
    if (n == 0) return;
    stats_.bytes_received += static_cast<std::uint64_t>(n);
    decoder_.feed(std::span<const std::uint8_t>(rx_.data(), static_cast<std::size_t>(n)),
                  [&](const FrameView& f) { on_frame(f, now); });
    check_dialect();
  }
}

void BoardLink::on_frame(const FrameView& frame, Time now) noexcept {
  const std::optional<Response> r = parse_response(frame.body);
  if (!r || outstanding_size_ == 0) return;  // nothing asked: stray bytes
  const Outstanding front = outstanding_[0];
  const bool echo = front.cmd == Command::sync && profile_.sync_echo && frame.bytes.size() == sync_size_ &&
                    std::equal(frame.bytes.begin(), frame.bytes.end(), sync_frame_.begin());
  const bool is_error = r->resp == profile_.error_resp;
  const bool matches = echo || r->resp == profile_.id(front.cmd) || is_error;
  if (!matches) {
    // The front's response never came (this one answers a later request). No re-scan: the
    // decoder is mid-feed.
    miss(now, false);
    if (outstanding_size_ > 0) on_frame(frame, now);
    return;
  }
  std::copy(outstanding_.begin() + 1, outstanding_.begin() + static_cast<std::ptrdiff_t>(outstanding_size_), outstanding_.begin());
  --outstanding_size_;
  const Duration rtt = now - front.sent;
  stats_.last_round_trip = rtt;
  stats_.max_round_trip = std::max(stats_.max_round_trip, rtt);
  stats_.total_round_trip += rtt;
  if (is_error) {
    ++stats_.error_responses;
    check_port_now_ = true;
    if (front.actuator) ++stats_.retries;  // stays queued: sent again next period
    const std::optional<ErrorCode> code = r->payload.empty() ? std::nullopt : profile_.error_of(r->payload[0]);
    // A checksum error on a request we framed: noise, or a board of another dialect.
    refused_checksums_ = code == ErrorCode::checksum ? refused_checksums_ + 1 : 0;
    check_dialect();
    // The board's watchdog tripped (it stopped the motors and wants SYNC), or too many errors.
    if (code == ErrorCode::not_synchronised && synchronised_) ++stats_.watchdog_trips;
    if (code == ErrorCode::not_synchronised || ++consecutive_missed_ >= config_.max_missed) lose(now);
    return;
  }
  refused_checksums_ = 0;
  // A board whose layouts differ from the host's (order, types, scales): into the host's layout.
  std::span<const std::uint8_t> payload = r->payload;
  const CommandSpec* spec = profile_.spec(front.cmd);
  if (spec != nullptr && spec->response_transcoded && !echo) {
    const std::ptrdiff_t n = transcode(spec->response, builtin_command(front.cmd).response, payload, transcoded_);
    payload = n < 0 ? std::span<const std::uint8_t>{} : std::span<const std::uint8_t>(transcoded_.data(), static_cast<std::size_t>(n));
  }
  ++stats_.responses;
  consecutive_missed_ = 0;
  if (front.actuator && queue_size_ > 0) {
    queue_head_ = (queue_head_ + 1) % queue_.size();
    --queue_size_;
  }
  switch (front.cmd) {
    case Command::sync:
      if (!synchronised_) {
        ++stats_.resyncs;
        synced_at_ = now;
      }
      synchronised_ = true;
      break;
    case Command::drive:
      if (const auto d = unpack_drive(payload)) {
        drive_ = *d;
        drive_stamp_ = now;
        has_drive_ = true;
      }
      break;
    case Command::battery:
      if (const auto b = unpack_battery(payload)) {
        battery_ = *b;
        has_battery_ = true;
      }
      break;
    case Command::liquid_level:
      if (payload.size() == 2) {
        tank_percent_ = payload[0];
        tank_empty_ = payload[1] != 0;
        has_tank_ = true;
      }
      break;
    case Command::ultrasonic: {
      ByteReader rd(payload);
      ultrasonic_count_ = std::min<std::size_t>(rd.u8(), kMaxUltrasonic);
      for (std::size_t i = 0; i < ultrasonic_count_; ++i) ultrasonic_[i] = rd.u16();
      if (rd.failed()) ultrasonic_count_ = 0;
      break;
    }
    case Command::infrared: {
      ByteReader rd(payload);
      cliff_count_ = std::min<std::size_t>(rd.u8(), kMaxInfrared);
      infrared_count_ = cliff_count_ + std::min<std::size_t>(rd.u8(), kMaxInfrared);
      for (std::size_t i = 0; i < infrared_count_; ++i) infrared_[i] = rd.u16();
      if (rd.failed()) infrared_count_ = cliff_count_ = 0;
      break;
    }
    default: break;
  }
}

void BoardLink::miss(Time now, bool rescan) noexcept {
  if (outstanding_size_ > 0) {
    if (outstanding_[0].actuator) ++stats_.retries;  // stays queued
    std::copy(outstanding_.begin() + 1, outstanding_.begin() + static_cast<std::ptrdiff_t>(outstanding_size_), outstanding_.begin());
    --outstanding_size_;
  }
  ++stats_.missed;
  check_port_now_ = true;
  // A frame cut short by the loss would hold up the next one: give it up and re-scan.
  if (rescan && decoder_.partial()) (void)decoder_.abandon_partial();
  // One stall, one miss: the requests in flight time out together (DRIVE and a poll each
  // period, and the late answers that then arrive out of order), and counting each would lose
  // the link after little more than one response_timeout whatever max_missed says.
  if (consecutive_missed_ > 0 && now - last_counted_miss_ < config_.response_timeout) return;
  last_counted_miss_ = now;
  if (++consecutive_missed_ >= config_.max_missed) lose(now);
}

void BoardLink::lose(Time now) noexcept {
  consecutive_missed_ = 0;
  if (!synchronised_) return;  // already lost: SYNC until the board answers
  synchronised_ = false;
  lost_pending_ = true;
  lost_at_ = now;
  ++stats_.link_losses;
}

}  // namespace tripodal::board
