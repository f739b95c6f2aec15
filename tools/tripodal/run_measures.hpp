// What `tripodal run` measures a run by: the simulator's ground truth, the floor a cleaning can
// reach, a dose plan's up-front estimate, the processes and recoveries of the task, and the figures
// of the report (sections, disinfection). Internal to the tool (tools/tripodal), between the
// driver (run_task.cpp) and the report (report_json.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "run_outputs.hpp"
#include "run_task.hpp"
#include "tripodal/board/board_firmware.hpp"
#include "tripodal/core/geometry.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/planner/planner.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#ifdef TRIPODAL_HAVE_DDS
#include "tripodal/dds/dds_hardware.hpp"
#endif

namespace tripodal::app {

// The cells of the room a cleaning footprint can reach at all: within `reach_m` (half the cleaning
// width; for the UV dose, the lamp's reach) of a cell where the robot can stand (clearance >= its
// radius) connected to its start.
std::vector<char> reachable_area(const Navigation& nav, navi::PathPlanner& planner, const std::vector<std::string>& sections,
                                 Pose2D start, double reach_m);

// What a dose-planned disinfection of these sections will take, for the up-front check: each
// section's coverage path as it will be planned, at its lane speeds, its turns at the cleaning
// behavior's yaw rate, the way between sections at the lane speed; the charge from the board's
// currents (the lamp and the boards all along, the atomizer while the tank lasts, the motors at
// the duty of the speed).
struct DoseEstimate {
  double time_s = 0.0;
  double charge_ah = 0.0;
  double path_m = 0.0;
};
DoseEstimate estimate_dose(navi::CCoveragePlanner& cov, const navi::CSectionSplitter& splitter,
                           const std::vector<std::string>& sections, navi::Point2D from, const board::FirmwareConfig& fw);

// "PrCleaning(section=A)": a process step as the report names it.
std::string step_text(const ProcessStep& s);

// Collects the processes and recoveries of the task for the report.
class ReportObserver final : public TaskObserver {
 public:
  std::vector<std::string> processes, recoveries;
  std::string current;  // the process running now, for the progress bar
  void on_process_started(const ProcessRecord& p) override { current = step_text(p.step); }
  void on_process_succeeded(const ProcessRecord& p) override { add(p, "succeeded"); }
  void on_process_failed(const ProcessRecord& p) override { add(p, "failed: " + p.message); }
  void on_recovery(const RecoveryRecord& r) override { recoveries.push_back(fixed(to_seconds(r.time), 3) + " " + r.reason); }

 private:
  void add(const ProcessRecord& p, const std::string& how) {
    processes.push_back(fixed(to_seconds(p.started), 3) + "-" + fixed(to_seconds(p.finished.value_or(p.started)), 3) + " " +
                        p.run + " " + step_text(p.step) + " " + how);
    current.clear();
  }
};

// The dose of each reachable cell (the dose map is on the world's grid, the reachable cells on the
// robot's map: matched by the cell centre), the tank, and both sides of the link.
DisinfectionFigures disinfection_figures(sim::SimBoardHardware& hw, const std::vector<char>& reachable,
                                         const std::vector<char>& lamp_floor, const navi::OccupancyGrid& grid,
                                         double target_j_m2);

// The report's figures of the floor and the path, the same on the simulator (run_task.cpp) and on
// devices (run_devices.cpp): the reachable cells and of them those cleaned, the coverage, the
// reachable area, the figures of the whole path and of its cleaning part.
void set_floor_figures(RunResult& res, const Navigation& nav, const std::vector<char>& reachable,
                       const navi::CleanedCells& cleaned, const std::vector<navi::Point2D>& path_all,
                       const std::vector<navi::Point2D>& path_cleaning);
// Of the reachable cells, those cleaned.
[[nodiscard]] std::size_t cleaned_reachable(const std::vector<char>& reachable, const navi::CleanedCells& cleaned);

// The sections the current plan of `planner` names (its steps' `section` parameters), in order.
std::vector<std::string> plan_sections(const CPlanner& planner);

// The planned paths of the three patterns over the room's sections (same grid and width): the
// report's comparison. None without a splitter and a coverage planner.
std::vector<SectionFigures> section_figures(const Navigation& nav, const std::vector<std::string>& sections);

// What a run measures itself by: the simulator's ground truth, in this process, or in the
// sim-server's, as its lock-step answers carry it (before the first: the world's start).
class GroundTruth {
 public:
  GroundTruth(CHardware* hw, Pose2D start) : start_(start) {
    if (auto* s = dynamic_cast<sim::SimulatorSources*>(hw)) {
      sources_ = s;
      local_ = &s->simulation();
    }
#ifdef TRIPODAL_HAVE_DDS
    remote_ = dynamic_cast<const dds::DdsHardware*>(hw);
#endif
  }
  [[nodiscard]] const sim::Simulator* local() const noexcept {
    return local_;
  }
  /// Any thread: the pose the hardware published after its last advance.
  [[nodiscard]] Pose2D pose() const {
    if (sources_ != nullptr) return sources_->true_pose(Time{}).value_or(start_);
#ifdef TRIPODAL_HAVE_DDS
    if (remote_ != nullptr && remote_->truth()) return remote_->truth()->map_from_base;
#endif
    return start_;
  }
  [[nodiscard]] double distance_m() const {
    if (local_ != nullptr) return local_->distance_m();
#ifdef TRIPODAL_HAVE_DDS
    if (remote_ != nullptr && remote_->truth()) return remote_->truth()->distance_m;
#endif
    return 0.0;
  }
  [[nodiscard]] std::size_t collisions() const {
    if (local_ != nullptr) return local_->collisions();
#ifdef TRIPODAL_HAVE_DDS
    if (remote_ != nullptr && remote_->truth()) return remote_->truth()->collisions;
#endif
    return 0;
  }
  /// Of the body, absolute (rad): the simulator's own, or summed from the poses sampled here.
  [[nodiscard]] double rotation_rad() const {
    return local_ != nullptr ? local_->rotation_rad() : sampled_rotation_rad_;
  }
  void sample() {
    const Pose2D p = pose();
    sampled_rotation_rad_ += std::abs(wrap_angle(p.theta_rad - last_.theta_rad));
    last_ = p;
  }

 private:
  Pose2D start_;
  Pose2D last_ = start_;
  double sampled_rotation_rad_ = 0.0;
  const sim::Simulator* local_ = nullptr;
  const sim::SimulatorSources* sources_ = nullptr;
#ifdef TRIPODAL_HAVE_DDS
  const dds::DdsHardware* remote_ = nullptr;
#endif
};

}  // namespace tripodal::app
