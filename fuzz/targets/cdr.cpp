// CDR messages (docs/rosbag.md): every decoder of cdr.hpp either decodes the bytes or refuses them
// with a TraceFormatError at a byte inside the message; a decoded message re-encodes to bytes that
// decode to the same message (little endian) — the decoders and encoders agree field by field.
#include <string>

#include "../fuzz_target.hpp"
#include "tripodal/trace/cdr.hpp"

namespace {

template <typename T>
void check(tripodal::fuzz::Bytes bytes) {
  using namespace tripodal::trace;
  T m;
  try {
    m = ros::decode_cdr<T>(bytes, "fuzz.cdr", 0);
  } catch (const TraceFormatError& e) {
    tripodal::fuzz::require(std::string(e.what()).rfind("fuzz.cdr: byte ", 0) == 0, "a refusal names its byte", e.what());
    tripodal::fuzz::require(e.offset() <= bytes.size(), "the refused byte is inside the message", e.what());
    return;
  }
  const auto again = ros::encode_cdr(m);
  const T back = ros::decode_cdr<T>(again, "re-encoded", 0);
  // NaN != NaN: compare the re-encoded bytes instead of the values.
  tripodal::fuzz::require(ros::encode_cdr(back) == again, "decode(encode(m)) re-encodes to the same bytes");
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal::trace::ros;
  if (bytes.empty()) return;
  // The first byte picks the type, so one corpus covers every decoder.
  const auto body = bytes.subspan(1);
  switch (bytes[0] % 10) {
    case 0: check<LaserScan>(body); break;
    case 1: check<Odometry>(body); break;
    case 2: check<Imu>(body); break;
    case 3: check<JointState>(body); break;
    case 4: check<Twist>(body); break;
    case 5: check<TwistStamped>(body); break;
    case 6: check<TFMessage>(body); break;
    case 7: check<Clock>(body); break;
    case 8: check<OccupancyGrid>(body); break;
    default: check<String>(body); break;
  }
}
