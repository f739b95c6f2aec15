// Scores of an estimated trajectory against a reference one, for the localization and mapping
// tools (tools/tripodal/localization_commands.cpp): the relative errors of Kümmerle et al. 2009
// and the whole path's error. Written so that they cannot flatter: a log whose time stamps are
// unusable has no "pairs N s apart" (pairs by travel are given instead), an empty set of pairs is
// "no pairs", never 0, and global consistency is scored beside the short pairs.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "tripodal/core/geometry.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::navi {

/// Translational and rotational errors of a set of poses or pairs.
class PoseErrors {
 public:
  void add(const Pose2D& estimate, const Pose2D& reference);
  [[nodiscard]] std::size_t count() const noexcept { return m_.size(); }
  [[nodiscard]] bool empty() const noexcept { return m_.empty(); }
  /// Precondition for the four below: !empty().
  [[nodiscard]] double mean_m() const;
  [[nodiscard]] double p95_m() const;
  [[nodiscard]] double mean_rad() const;
  [[nodiscard]] double p95_rad() const;
  /// "0.031 m (p95 0.075), 0.44 deg (p95 1.20), 909 pairs", or "no pairs" when empty.
  [[nodiscard]] std::string format(const char* unit = "pairs") const;

 private:
  std::vector<double> m_, rad_;
};

/// Whether a log's scan stamps can measure time between scans. Unusable: fewer than two scans,
/// all equal, more than 5 % of the steps not advancing (repeated values, or steps backwards that
/// an importer clamped), or a jump of over 100 times the median step and over a day (a wrap). A
/// shorter hole leaves them usable (pairs_by_time refuses the pairs across it).
struct StampCheck {
  bool usable = false;
  std::string why;  ///< empty when usable
};
[[nodiscard]] StampCheck check_stamps(const std::vector<Time>& stamps);

/// Index pairs (i, j), i < j.
using PosePairs = std::vector<std::pair<std::size_t, std::size_t>>;

[[nodiscard]] PosePairs consecutive_pairs(std::size_t n);
/// For each scan i, the first scan j at least gap_s later, kept when it is at most 1.5 gap_s later
/// (a pair across a hole in the log is no "gap_s apart" pair). Empty when the stamps are unusable:
/// check them first.
[[nodiscard]] PosePairs pairs_by_time(const std::vector<Time>& stamps, double gap_s);
/// For each scan i, the first scan j whose reference path is at least gap_m longer, kept when at
/// most 1.5 gap_m longer: needs no stamps.
[[nodiscard]] PosePairs pairs_by_travel(const std::vector<Pose2D>& reference, double gap_m);

/// Kümmerle et al. 2009: the motion between the two poses of each pair as estimated, against the
/// reference's. Precondition: estimate and reference of the same size, pairs within it.
[[nodiscard]] PoseErrors relative_errors(const std::vector<Pose2D>& estimate, const std::vector<Pose2D>& reference,
                                         const PosePairs& pairs);
/// Every pose against the reference, the two frames joined at the first pose.
[[nodiscard]] PoseErrors errors_from_start(const std::vector<Pose2D>& estimate, const std::vector<Pose2D>& reference);
/// Every pose against the reference after the rigid motion that best aligns the estimated
/// positions on the reference's (least squares): an offset at the start is not counted, a path
/// bent on the way is.
[[nodiscard]] PoseErrors errors_aligned(const std::vector<Pose2D>& estimate, const std::vector<Pose2D>& reference);

}  // namespace tripodal::navi
