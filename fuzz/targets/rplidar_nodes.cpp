// The RPLIDAR A1's SCAN stream (docs/lidar.md): any bytes at all go through the streaming
// NodeDecoder and the ScanAssembler. Properties: the nodes found do not depend on how the stream is
// cut into reads; every byte is accounted for; every node delivered passes its checks and
// re-encodes to five bytes that decode to it; a scan's ranges are within [range_min, range_max] or
// +infinity, and it has its configured beam count.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "../fuzz_target.hpp"
#include "tripodal/board/rplidar_protocol.hpp"

namespace {

namespace rp = tripodal::board::rplidar;

std::vector<rp::Node> decode(rp::NodeDecoder& decoder, tripodal::fuzz::Bytes bytes, std::size_t chunk) {
  std::vector<rp::Node> nodes;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    decoder.feed(bytes.subspan(i, std::min(chunk, bytes.size() - i)), [&](const rp::Node& n) { nodes.push_back(n); });
  }
  return nodes;
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  if (bytes.empty()) return;
  rp::NodeDecoder whole;
  const std::vector<rp::Node> nodes = decode(whole, bytes, bytes.size());
  rp::NodeDecoder pieces;
  const std::vector<rp::Node> again = decode(pieces, bytes, 1 + bytes[0] % 13);
  fuzz::require(nodes == again, "the nodes found do not depend on the reads' sizes");
  const rp::NodeDecoderStats& s = whole.stats();
  fuzz::require(s.bytes == bytes.size(), "every byte fed is counted");
  fuzz::require(s.nodes == nodes.size(), "every node delivered is counted");
  fuzz::require(s.nodes * rp::kNodeBytes + s.skipped_bytes <= s.bytes, "nodes and skipped bytes come from the bytes fed");
  fuzz::require(s.resyncs <= s.errors, "sync is found again at most once per loss");

  rp::ScanAssemblerConfig config;
  config.beams = 8 + bytes[0] % 64;
  config.min_nodes = 1;
  rp::ScanAssembler assembler(config);
  Time t{};
  for (const rp::Node& n : nodes) {
    std::array<std::uint8_t, rp::kNodeBytes> out{};
    rp::encode_node(n, out);
    fuzz::require(rp::check_node(out) == rp::NodeCheck::ok, "a delivered node passes its checks");
    fuzz::require(rp::decode_node(out) == n, "a node re-encodes to itself");
    t += std::chrono::microseconds(500);
    if (assembler.add(n, t)) {
      const LaserScan& scan = assembler.scan();
      fuzz::require(scan.ranges_m.size() == config.beams, "a scan has its configured beams");
      for (const float r : scan.ranges_m) {
        fuzz::require(std::isinf(r) || (r >= config.range_min_m - 1e-6 && r <= config.range_max_m + 1e-6),
                      "a range is a return or none");
      }
    }
  }
}
