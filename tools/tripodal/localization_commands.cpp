// `tripodal localization eval` and `tripodal map build`: the scan-matching localizer and the map
// builder run on recorded logs (CARMEN logs or tripodal traces), scored against the logs' corrected
// laser poses (docs/localization.md has the figures and the commands that made them).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <optional>
#include <ostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cli_tool.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/navi/map_builder.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/scan_matching_localizer.hpp"
#include "tripodal/navi/trajectory_metrics.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_reader.hpp"

namespace tripodal::tool {
namespace {

using namespace cli;
using navi::OccupancyGrid;

constexpr std::string_view kExitCodes = "exit codes: 0 ok, 1 bad input, 2 bad command line, 3 I/O error";

// One scan of a log with the odometry read before it and, in the corrected logs, the reference pose.
struct LoggedScan {
  LaserScan scan;
  Pose2D odom;
  Pose2D reference;
  bool has_reference = false;
};

struct Log {
  std::string name;
  std::vector<LoggedScan> scans;
  bool has_odometry = false;
  /// False when the log holds no odometry worth the name (none, or odometry that repeats the
  /// previous pose): the tools then warn, and figures "on odometry" are not given.
  bool odometry_usable = true;
  std::string odometry_note;  ///< what the odometry is (the importer's word for a CARMEN log)

  [[nodiscard]] std::vector<Pose2D> references() const {
    std::vector<Pose2D> r;
    r.reserve(scans.size());
    for (const LoggedScan& s : scans) r.push_back(s.reference);
    return r;
  }
  [[nodiscard]] std::vector<Time> stamps() const {
    std::vector<Time> t;
    t.reserve(scans.size());
    for (const LoggedScan& s : scans) t.push_back(s.scan.stamp);
    return t;
  }
};

// Where every figure's reference comes from: named in the tools' output beside the figures.
constexpr std::string_view kReferenceNote =
    "the log's corrected laser poses (a SLAM result, not ground truth)";

bool is_carmen(const std::filesystem::path& p) {
  const std::string s = p.filename().string();
  auto ends = [&](std::string_view e) { return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0; };
  return ends(".log") || ends(".log.gz") || ends(".clf") || ends(".clf.gz");
}

// Reads the laser channel, the odometry channel and the laser poses of a trace; a CARMEN log is
// imported to a temporary trace first (the importer's located errors pass through), and so is a
// rosbag2 bag (docs/rosbag.md: /scan and /odom, or /tf's odom -> base_link, become the laser and
// odometry channels named here; other topics keep their names, so --laser-channel front_laser
// reads /front_laser).
Log read_log(const std::filesystem::path& file, const std::string& laser_channel, const std::string& odom_channel,
             const std::string& pose_channel) {
  Log log;
  log.name = file.filename().string();
  std::filesystem::path trace_path = file;
  std::filesystem::path temp;
  std::optional<trace::CarmenImportReport> imported;
  if (is_carmen(file)) {
    temp = std::filesystem::temp_directory_path() /
           ("tripodal_localization_" + std::to_string(::getpid()) + "_" + file.filename().string() + ".trp");
    trace::TraceWriter w(temp, trace::TraceWriterOptions{.flush_every_records = 0});
    trace::CarmenImportOptions o;
    o.laser_channel = laser_channel;
    o.odometry_channel = odom_channel;
    o.laser_pose_channel = pose_channel;
    imported = trace::import_carmen_log(file, w, o);
    w.close();
    trace_path = temp;
  }
  struct Cleanup {
    std::filesystem::path p;
    ~Cleanup() {
      std::error_code ec;
      if (!p.empty()) std::filesystem::remove(p, ec);
    }
  } cleanup{temp};
  std::optional<trace::TraceSource> bag;
  if (!imported && trace::is_rosbag(file)) {
    trace::BagImportOptions bo;
    bo.topic_channels["/scan"] = laser_channel;
    bo.topic_channels["/odom"] = odom_channel;
    bo.topic_channels["/tf"] = odom_channel;
    bag.emplace(file, bo);
    trace_path = bag->trace();
  }
  trace::TraceReader reader(trace_path);
  trace::TraceRecord rec;
  Pose2D odom;
  while (reader.next(rec)) {
    const std::string& channel = reader.channel(rec.channel).name;
    if (const auto* scan = std::get_if<LaserScan>(&rec.data); scan != nullptr && channel == laser_channel) {
      log.scans.push_back({*scan, odom, {}, false});
    } else if (const auto* o = std::get_if<OdometryReading>(&rec.data); o != nullptr) {
      if (channel == odom_channel) {
        odom = o->pose;
        log.has_odometry = true;
      } else if (channel == pose_channel && !log.scans.empty() && !log.scans.back().has_reference) {
        log.scans.back().reference = o->pose;
        log.scans.back().has_reference = true;
      }
    }
  }
  if (reader.state() == trace::ReadState::kTruncated) {
    throw ConfigError(SourceLocation{file.string(), 0, 0}, reader.warning() + ": the trace is cut off");
  }
  if (log.scans.empty()) {
    throw ConfigError(SourceLocation{file.string(), 0, 0}, "no scans on the laser channel '" + laser_channel + "'");
  }
  if (!log.has_odometry && !imported) {
    throw ConfigError(SourceLocation{file.string(), 0, 0}, "no odometry on the channel '" + odom_channel + "'");
  }
  if (imported) {
    log.odometry_note = imported->odometry_note();
    log.odometry_usable = imported->odometry != trace::CarmenOdometry::kNone;
  } else {
    // A trace: the same test as the importer's, odometry that stays still while the reference moves
    std::size_t moving = 0, still = 0;
    for (std::size_t i = 1; i < log.scans.size(); ++i) {
      const LoggedScan &a = log.scans[i - 1], &b = log.scans[i];
      if (!a.has_reference || !b.has_reference) continue;
      const Pose2D moved = compose(inverse(a.reference), b.reference);
      if (std::hypot(moved.x_m, moved.y_m) < 0.05 && std::abs(wrap_angle(moved.theta_rad)) < 0.05) continue;
      ++moving;
      const Pose2D odo = compose(inverse(a.odom), b.odom);
      if (odo.x_m == 0.0 && odo.y_m == 0.0 && odo.theta_rad == 0.0) ++still;
    }
    log.odometry_usable = !(moving >= 3 && 2 * still > moving);
    log.odometry_note = log.odometry_usable ? "odometry as recorded in the trace"
                                            : "no odometry in this trace: it repeats the previous pose (" +
                                                  std::to_string(still) + " of " + std::to_string(moving) +
                                                  " moving scans without odometry motion)";
  }
  return log;
}

bool all_referenced(const Log& log) {
  return std::all_of(log.scans.begin(), log.scans.end(), [](const LoggedScan& s) { return s.has_reference; });
}

// Adds seeded noise to the odometry's increments: relative sigma on the distance travelled and on
// the turn, plus heading noise growing with the distance (sigma * 0.2 rad per metre).
std::vector<Pose2D> noisy_odometry(const Log& log, double sigma, std::uint64_t seed) {
  std::vector<Pose2D> out;
  out.reserve(log.scans.size());
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  for (std::size_t i = 0; i < log.scans.size(); ++i) {
    if (i == 0 || sigma <= 0.0) {
      out.push_back(i == 0 ? log.scans[0].odom : compose(out.back(), compose(inverse(log.scans[i - 1].odom), log.scans[i].odom)));
      continue;
    }
    Pose2D d = compose(inverse(log.scans[i - 1].odom), log.scans[i].odom);
    const double dist = std::hypot(d.x_m, d.y_m);
    const double scale = 1.0 + sigma * n(rng);
    d.x_m *= scale;
    d.y_m *= scale;
    d.theta_rad += sigma * std::abs(d.theta_rad) * n(rng) + sigma * 0.2 * dist * n(rng);
    out.push_back(compose(out.back(), d));
  }
  return out;
}

// The bounds of the reference poses (or the odometry) grown by the range the map should hold.
void extent(const std::vector<Pose2D>& poses, double margin_m, Point2D& lower, Point2D& upper) {
  lower = {1e300, 1e300};
  upper = {-1e300, -1e300};
  for (const Pose2D& p : poses) {
    lower = {std::min(lower.x_m, p.x_m), std::min(lower.y_m, p.y_m)};
    upper = {std::max(upper.x_m, p.x_m), std::max(upper.y_m, p.y_m)};
  }
  lower = {std::floor(lower.x_m - margin_m), std::floor(lower.y_m - margin_m)};
  upper = {std::ceil(upper.x_m + margin_m), std::ceil(upper.y_m + margin_m)};
}

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

using navi::PoseErrors;

OccupancyGrid reference_map(const Log& log, double resolution_m, double max_range_m) {
  std::vector<Pose2D> ref;
  for (const LoggedScan& s : log.scans) ref.push_back(s.reference);
  Point2D lo, hi;
  extent(ref, std::min(max_range_m, 20.0), lo, hi);
  navi::MapBuilderOptions o;
  o.resolution_m = resolution_m;
  o.max_range_m = max_range_m;
  navi::MapBuilder b(lo, hi, o);
  for (const LoggedScan& s : log.scans) b.insert(s.scan, s.reference);
  return b.grid();
}

struct EvalArgs {
  std::vector<std::filesystem::path> logs;
  double resolution_m = 0.05;
  double max_range_m = 30.0;
  double odom_noise = 0.0;
  std::uint64_t seed = 1;
  int global_trials = 10;
  int global_max_scans = 50;
  std::filesystem::path trajectory;  // CSV of the tracking run (one log only)
  std::string laser_channel = "front_laser", odom_channel = "odom", pose_channel = "laser_pose";
};

// The tools' times are the process's CPU time, not wall time: the machines these run on are
// shared, and a starved process's wall time says nothing about the code (issue 41).
std::clock_t cpu_now() noexcept {
  return std::clock();
}
double ms_since(std::clock_t t0) noexcept {
  return 1000.0 * static_cast<double>(cpu_now() - t0) / static_cast<double>(CLOCKS_PER_SEC);
}

int eval_one(const EvalArgs& a, const std::filesystem::path& file, std::ostream& out) {
  const Log log = read_log(file, a.laser_channel, a.odom_channel, a.pose_channel);
  if (!all_referenced(log)) {
    throw ConfigError(SourceLocation{file.string(), 0, 0},
                      "some scans have no reference pose on the channel '" + a.pose_channel +
                          "': a corrected log is needed to score against");
  }
  const OccupancyGrid map = reference_map(log, a.resolution_m, a.max_range_m);
  const std::vector<Pose2D> odom = noisy_odometry(log, a.odom_noise, a.seed);
  out.unsetf(std::ios::floatfield);
  out << std::setprecision(6) << log.name << ": " << log.scans.size() << " scans, map " << map.width() << " x " << map.height() << " cells of "
      << map.resolution_m() << " m, odometry noise " << a.odom_noise << "\n";
  out << "  odometry:      " << log.odometry_note << "\n";
  out << "  reference:     " << kReferenceNote << "; errors per scan, mean (p95)\n";
  if (!log.odometry_usable) {
    out << "  WARNING: no odometry in this log: tracking predicts no motion between scans, and a scan that moved\n"
           "  farther than the search window is matched wherever it fits best\n";
  }

  // Tracking from the first reference pose, on the odometry.
  navi::ScanMatchingLocalizerOptions lo;
  lo.initial_pose = log.scans[0].reference;
  lo.matcher.max_range_m = a.max_range_m;
  // A log's odometry is continuous; an excerpt keeps a scan in ten, metres apart.
  lo.odometry_reset_m = 0.0;
  std::ofstream csv;
  if (!a.trajectory.empty()) {
    csv.open(a.trajectory);
    if (!csv) throw std::runtime_error(a.trajectory.string() + ": cannot be written");
    csv << "scan,ref_x_m,ref_y_m,ref_theta_rad,x_m,y_m,theta_rad,quality,localized\n";
  }
  // recover: as the robot would, a global search on every scan while lost (PrGlobalLocalization)
  auto track = [&](bool recover, std::ostream* trajectory) {
    navi::CScanMatchingLocalizer loc(lo);
    loc.set_map(map);
    std::vector<ModuleEvent> events;
    PoseErrors e;
    double ms = 0.0;
    for (std::size_t i = 0; i < log.scans.size(); ++i) {
      const auto t0 = cpu_now();
      loc.step(log.scans[i].scan, odom[i], log.scans[i].scan.stamp, events);
      if (recover && !loc.localized()) loc.relocalize();
      ms += ms_since(t0);
      const Pose2D& r = log.scans[i].reference;
      const Pose2D& p = loc.estimate();
      if (trajectory != nullptr) {
        *trajectory << i << ',' << r.x_m << ',' << r.y_m << ',' << r.theta_rad << ',' << p.x_m << ',' << p.y_m << ','
                    << p.theta_rad << ',' << loc.last_match().quality << ',' << (loc.localized() ? 1 : 0) << '\n';
      }
      e.add(p, r);
    }
    int lost = 0;
    for (const ModuleEvent& ev : events) lost += ev.name == "localizer.lost" ? 1 : 0;
    out << e.format("scans");
    const std::uint64_t unreliable = loc.unreliable_scans();
    out << "; localizer.lost " << lost << " times; " << unreliable << " scans unreliable; " << std::setprecision(2)
        << ms / static_cast<double>(log.scans.size()) << " ms CPU per scan\n";
    // the localizer's own word on its estimate, printed where a reader looks for the figures
    if (lost > 0 || 20 * unreliable > log.scans.size()) {
      out << "  WARNING: the localizer judged " << unreliable << " of " << log.scans.size()
          << " scans unreliable and was lost " << lost << " times: its estimate there is not to be trusted\n";
    }
  };
  out << "  tracking:      ";
  track(false, csv.is_open() ? &csv : nullptr);
  out << "  + recovery:    ";
  track(true, nullptr);
  PoseErrors dead;
  Pose2D dead_pose = log.scans[0].reference;
  for (std::size_t i = 0; i < log.scans.size(); ++i) {
    if (i > 0) dead_pose = compose(dead_pose, compose(inverse(odom[i - 1]), odom[i]));
    dead.add(dead_pose, log.scans[i].reference);
  }
  out << "  odometry only: " << (log.odometry_usable ? dead.format("scans") : std::string("none (no odometry)"))
      << " (dead reckoning from the first reference pose)\n";

  // Global localization from unknown starts spread over the log.
  int converged = 0, wrong = 0;
  std::vector<double> scans_needed, search_ms;
  for (int t = 0; t < a.global_trials; ++t) {
    const std::size_t k0 = log.scans.size() * static_cast<std::size_t>(t) / static_cast<std::size_t>(a.global_trials);
    navi::ScanMatchingLocalizerOptions go = lo;
    go.start_global = true;
    go.initial_pose = {};
    navi::CScanMatchingLocalizer g(go);
    g.set_map(map);
    std::vector<ModuleEvent> ev;
    bool done = false, accepted_wrong = false;
    for (std::size_t i = k0; i < log.scans.size() && i < k0 + static_cast<std::size_t>(a.global_max_scans); ++i) {
      const auto t0 = cpu_now();
      g.step(log.scans[i].scan, odom[i], log.scans[i].scan.stamp, ev);
      if (!g.localized()) g.relocalize();  // PrGlobalLocalization: a search on every scan while lost
      search_ms.push_back(ms_since(t0));
      const Pose2D& ref = log.scans[i].reference;
      const double err = std::hypot(g.estimate().x_m - ref.x_m, g.estimate().y_m - ref.y_m);
      if (g.localized() && err > 1.0) accepted_wrong = true;
      if (g.localized() && err < 0.3) {
        converged += 1;
        scans_needed.push_back(static_cast<double>(i - k0 + 1));
        done = true;
        break;
      }
    }
    if (!done && accepted_wrong) ++wrong;
  }
  out << "  global:        " << converged << "/" << a.global_trials << " starts converged (within 0.3 m), " << wrong
      << " settled on a wrong place; scans to converge mean " << std::setprecision(1) << mean(scans_needed) << " (max "
      << (scans_needed.empty() ? 0.0 : *std::max_element(scans_needed.begin(), scans_needed.end())) << "); " << std::fixed
      << std::setprecision(0) << mean(search_ms) << " ms CPU per scan while searching\n";
  out.unsetf(std::ios::floatfield);
  return kOk;
}

// Runs a command's body, mapping its failures to the tools' exit codes: located input errors
// (the log's, the trace's, the options') to 1, files that cannot be read or written to 3.
template <class Body>
int guarded(std::string_view command, std::ostream& err, Body&& body) {
  try {
    body();
  } catch (const trace::TraceIoError& e) {
    err << command << ": " << e.what() << '\n';
    return kIoError;
  } catch (const trace::TraceFormatError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const std::runtime_error& e) {
    err << command << ": " << e.what() << '\n';
    return kIoError;
  }
  return kOk;
}

int localization_eval(const EvalArgs& a, std::ostream& out, std::ostream& err) {
  for (const auto& f : a.logs) {
    if (!std::filesystem::exists(f)) {
      err << "tripodal localization eval: " << f.string() << ": no such file\n";
      return kIoError;
    }
  }
  return guarded("tripodal localization eval", err, [&] {
    for (const auto& f : a.logs) eval_one(a, f, out);
  });
}

struct BuildArgs {
  std::filesystem::path trace;
  std::filesystem::path out;
  double resolution_m = 0.05;
  double max_range_m = 30.0;
  double gap_s = 10.0;
  double gap_m = 5.0;
  bool loop_closure = navi::LoopClosureOptions{}.enabled;
  double closure_quality = navi::LoopClosureOptions{}.min_quality;
  double recovery_margin = navi::MapBuilderOptions{}.recovery_margin;
  double fallback_share = navi::MapBuilderOptions{}.fallback_share;
  std::filesystem::path trajectory;  // CSV: scan by scan, the match as made, the final pose, the reference
  std::string laser_channel = "front_laser", odom_channel = "odom", pose_channel = "laser_pose";
};

int map_build(const BuildArgs& a, std::ostream& out, std::ostream& err) {
  if (!std::filesystem::exists(a.trace)) {
    err << "tripodal map build: " << a.trace.string() << ": no such file\n";
    return kIoError;
  }
  return guarded("tripodal map build", err, [&] {
    const Log log = read_log(a.trace, a.laser_channel, a.odom_channel, a.pose_channel);
    std::vector<Pose2D> odom;
    odom.reserve(log.scans.size());
    for (const LoggedScan& s : log.scans) odom.push_back(s.odom);
    // the map frame is the odometry frame at the first scan
    std::vector<Pose2D> rel;
    rel.reserve(odom.size());
    for (const Pose2D& p : odom) rel.push_back(compose(inverse(odom[0]), p));
    Point2D lo, hi;
    // odometry drifts: a generous margin keeps the corrected path inside the grid
    extent(rel, std::min(a.max_range_m, 20.0) + 10.0, lo, hi);
    navi::MapBuilderOptions o;
    o.resolution_m = a.resolution_m;
    o.max_range_m = a.max_range_m;
    o.matcher.max_range_m = a.max_range_m;
    o.loop.enabled = a.loop_closure;
    o.loop.min_quality = a.closure_quality;
    o.recovery_margin = a.recovery_margin;
    o.fallback_share = a.fallback_share;
    navi::MapBuilder b(lo, hi, o);
    std::ostringstream rows;  // the matches as made; the final poses are known only at the end
    const auto t0 = cpu_now();
    for (const LoggedScan& s : log.scans) {
      const navi::MappingHealth before = b.health();
      const Pose2D p = b.add(s.scan, s.odom);
      if (!a.trajectory.empty()) {
        const navi::MappingHealth& h = b.health();
        rows << (h.scans - 1) << ',' << p.x_m << ',' << p.y_m << ',' << p.theta_rad << ',' << b.last_quality() << ','
             << (h.weak - before.weak) << ',' << (h.recovered - before.recovered) << ',' << (h.unreliable - before.unreliable)
             << '\n';
      }
    }
    const double ms = ms_since(t0);
    // scored on the poses as the graph places them at the end (a closure moves past poses too)
    const std::vector<Pose2D> est = b.trajectory();
    if (!a.trajectory.empty()) {
      std::ofstream csv(a.trajectory);
      if (!csv) throw std::runtime_error(a.trajectory.string() + ": cannot be written");
      csv << "scan,x_m,y_m,theta_rad,quality,weak,recovered,unreliable,final_x_m,final_y_m,final_theta_rad,ref_x_m,ref_y_m,ref_"
             "theta_rad\n";
      std::istringstream made(rows.str());
      std::string row;
      for (std::size_t i = 0; i < est.size() && std::getline(made, row); ++i) {
        csv << row << ',' << est[i].x_m << ',' << est[i].y_m << ',' << est[i].theta_rad;
        const LoggedScan& s = log.scans[i];
        if (s.has_reference)
          csv << ',' << s.reference.x_m << ',' << s.reference.y_m << ',' << s.reference.theta_rad;
        else
          csv << ",,,";
        csv << '\n';
      }
    }
    const OccupancyGrid g = b.grid();
    navi::save_map(g, a.out);
    out << log.name << ": " << log.scans.size() << " scans mapped in " << std::fixed << std::setprecision(1) << ms / 1000.0
        << " s CPU (" << std::setprecision(2) << ms / static_cast<double>(log.scans.size()) << " ms per scan); map " << g.width()
        << " x " << g.height() << " cells written to " << a.out.string() << "\n";
    const navi::LoopClosureStats& loop = b.loop_stats();
    out << "  loop closure: " << (o.loop.enabled ? "" : "off; ") << loop.keyframes << " key scans, " << loop.attempts
        << " local matches tried (refused: " << loop.weak << " weak, " << loop.implausible << " beyond the drift, "
        << loop.disagreeing << " not confirmed by the scans before, " << loop.ambiguous << " ambiguous), " << loop.closures
        << " closures kept (" << loop.settled << " within their own noise: no solve), " << loop.rejected
        << " dropped by the graph, " << loop.solves << " graph solves\n";
    const navi::MappingHealth& health = b.health();
    out << "  self-check: " << health.weak << " scans matched far below the recent median, " << health.recovered
        << " of them re-matched globally (an odometry jump), " << health.unreliable << " left unreliable\n";
    // the odometry fallback: where most matches were untrusted, the map is the odometry's
    out << "  odometry fallback: " << health.in_fallback << " scans while most of the last " << o.fallback_scans
        << " matches were untrusted, " << health.odometry_only << " of them mapped on the odometry alone\n";
    if (20 * health.unreliable > health.scans) {
      out << "  WARNING: " << health.unreliable << " of " << health.scans
          << " scans were mapped on matches the builder does not trust: the map may be wrong there\n";
    }
    out << "  odometry: " << log.odometry_note << "\n";
    if (!log.odometry_usable) {
      out << "  WARNING: no odometry in this log: every scan is predicted where the previous one was, and the map\n"
             "  is scan matching alone; no figure below is \"on odometry\"\n";
    }
    if (all_referenced(log)) {
      const std::vector<Pose2D> ref = log.references();
      const navi::StampCheck stamps = navi::check_stamps(log.stamps());
      auto line = [&](const std::string& what, const navi::PoseErrors& mapping, const navi::PoseErrors& odometry,
                      const char* unit = "pairs") {
        out << "    " << what << ": mapping " << mapping.format(unit);
        if (log.odometry_usable) out << "; odometry " << odometry.format(unit);
        out << "\n";
      };
      out << "  errors vs " << kReferenceNote << ", mean (p95):\n";
      out << "  relative (Kuemmerle et al. 2009):\n";
      const navi::PosePairs consecutive = navi::consecutive_pairs(ref.size());
      line("consecutive scans", navi::relative_errors(est, ref, consecutive), navi::relative_errors(odom, ref, consecutive));
      std::ostringstream gap_s, gap_m;
      gap_s << "scans " << a.gap_s << " s apart";
      gap_m << "scans " << a.gap_m << " m of travel apart";
      if (stamps.usable) {
        const navi::PosePairs by_time = navi::pairs_by_time(log.stamps(), a.gap_s);
        line(gap_s.str(), navi::relative_errors(est, ref, by_time), navi::relative_errors(odom, ref, by_time));
      } else {
        out << "    " << gap_s.str() << ": no pairs (time stamps unusable: " << stamps.why << ")\n";
      }
      const navi::PosePairs by_travel = navi::pairs_by_travel(ref, a.gap_m);
      line(gap_m.str(), navi::relative_errors(est, ref, by_travel), navi::relative_errors(odom, ref, by_travel));
      out << "  whole path (global consistency):\n";
      line("frames joined at the first scan", navi::errors_from_start(est, ref), navi::errors_from_start(odom, ref), "scans");
      line("after the best rigid alignment", navi::errors_aligned(est, ref), navi::errors_aligned(odom, ref), "scans");
    }
  });
}

void channel_options(CLI::App& cmd, std::string& laser, std::string& odom, std::string& pose) {
  cmd.add_option("--laser-channel", laser, "NAME: the laser channel")->capture_default_str();
  cmd.add_option("--odom-channel", odom, "NAME: the odometry channel")->capture_default_str();
  cmd.add_option("--pose-channel", pose, "NAME: the reference (corrected) laser poses")->capture_default_str();
}

cli::Action setup_eval(CLI::App& cmd) {
  auto a = std::make_shared<EvalArgs>();
  cmd.add_option("LOG", a->logs, "corrected CARMEN logs (.log, .log.gz) or traces with laser poses")->required();
  cmd.add_option("--resolution", a->resolution_m, "M: cell side of the reference map")->capture_default_str()->check(positive_number());
  cmd.add_option("--max-range", a->max_range_m, "M: returns beyond are ignored")->capture_default_str()->check(positive_number());
  cmd.add_option("--odom-noise", a->odom_noise, "SIGMA: relative noise added to the odometry's increments")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd.add_option("--seed", a->seed, "N: seed of the odometry noise")->check(cli::whole_number())->capture_default_str();
  cmd.add_option("--global-trials", a->global_trials, "N: unknown starts spread over the log")->capture_default_str()->check(positive_count());
  cmd.add_option("--global-max-scans", a->global_max_scans, "N: scans a start may take to converge")
      ->capture_default_str()
      ->check(positive_count());
  cmd.add_option("--trajectory", a->trajectory, "FILE: CSV of the tracking run, scan by scan (last log)")
      ->check(cli::writable_file());
  channel_options(cmd, a->laser_channel, a->odom_channel, a->pose_channel);
  return [a](std::ostream& out, std::ostream& err) { return localization_eval(*a, out, err); };
}

cli::Action setup_build(CLI::App& cmd) {
  auto a = std::make_shared<BuildArgs>();
  cmd.add_option("TRACE", a->trace, "a trace, a CARMEN log (.log, .log.gz) or a rosbag2 bag (MCAP, db3) with laser and odometry")
      ->required();
  cmd.add_option("--out", a->out, "MAP.yaml: the map_server map to write (and MAP.pgm beside it)")
      ->required()
      ->check(cli::writable_file());
  cmd.add_option("--resolution", a->resolution_m, "M: cell side")->capture_default_str()->check(positive_number());
  cmd.add_option("--max-range", a->max_range_m, "M: returns beyond are not mapped")->capture_default_str()->check(positive_number());
  cmd.add_option("--gap", a->gap_s, "S: time between the far pairs of the relative errors")->capture_default_str()->check(positive_number());
  cmd.add_option("--gap-m", a->gap_m, "M: reference travel between the pairs counted by distance (needs no time stamps)")
      ->capture_default_str()->check(positive_number());
  cmd.add_option("--recovery-margin", a->recovery_margin,
                 "Q: a match this far below the recent median is re-matched globally (0: never)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cmd.add_option("--fallback-share", a->fallback_share,
                 "S: above this share of untrusted matches among the last 20, map on the odometry alone (1: never)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1.0));
  cmd.add_option("--trajectory", a->trajectory,
                 "FILE: CSV of the matches, scan by scan, as made and as the graph places them at the end")
      ->check(cli::writable_file());
  cmd.add_flag("--loop-closure,!--no-loop-closure", a->loop_closure,
               "keep a pose graph of key scans and close loops (the default; docs/localization.md)");
  cmd.add_option("--closure-quality", a->closure_quality, "Q: the match quality a closure needs, in (0, 1]")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1.0));
  channel_options(cmd, a->laser_channel, a->odom_channel, a->pose_channel);
  return [a](std::ostream& out, std::ostream& err) { return map_build(*a, out, err); };
}

constexpr std::string_view kEvalDescription =
    "Scores the scan-matching localizer on corrected logs: a map is built from the logs' corrected laser\n"
    "poses (the reference), the localizer runs from the first reference pose on the odometry, and its\n"
    "error against the reference is reported (mean and 95th percentile); then global localization from\n"
    "unknown starts spread over the log: how many converge, and in how many scans.";
constexpr std::string_view kBuildDescription =
    "Builds an occupancy grid from the laser and odometry of a trace (scan-to-map matching with the\n"
    "localizer's matcher) and writes it as a map_server map. When the trace holds reference poses\n"
    "(the corrected CARMEN logs), prints the relative errors of Kuemmerle et al. 2009 against them.";

}  // namespace

TRIPODAL_CLI_COMMAND("localization", "eval", "score the scan-matching localizer on corrected logs", kEvalDescription,
                     kExitCodes, &setup_eval);
TRIPODAL_CLI_COMMAND("map", "build", "build a map_server map from a trace's laser and odometry", kBuildDescription,
                     kExitCodes, &setup_build);

}  // namespace tripodal::tool
