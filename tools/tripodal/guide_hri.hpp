// GuideHri, the HRI the guide robot's program runs on its Hri module (hri/hri_robot_module.hpp,
// docs/guide.md), the same for the scripted visit and the monitor's touch and RKMS pages.
// Application layer, not installed.
#pragma once

#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/hri/answer_providers.hpp"
#include "tripodal/hri/hri_robot_module.hpp"
#include "tripodal/hri/hri_service.hpp"
#include "tripodal/hri/knowledge_store.hpp"
#include "tripodal/planner/planner.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/processes/module.hpp"

namespace tripodal {
class Robot;
}

namespace tripodal::app {

/// The words of the task's first command form with the slots the HRI understood: what the robot's
/// planner is told ("guide me to node 1").
[[nodiscard]] std::string command_text(const TaskLibrary& tasks, const Understanding& understanding);

/// The guide robot's HRI as the robot program runs it, on the scripted visit and under the monitor
/// alike: a StoreBackedHri over the Hri module's knowledge store (an edit on the /rkms page is
/// answered from at once), the hall's nodes for the planner (the module's answers from where the
/// robot stands), the hall's local providers ({time}, {battery}, {weather}: there is no internet),
/// command inputs handed to the robot's planner, and the internal state it displays, kept from the
/// planner's life cycle. One thread: the robot's (ask, update, module).
class GuideHri final : private TaskObserver {
 public:
  struct Options {
    /// The battery's state of charge, 0..1 ("unknown" outside).
    std::function<double()> battery_charge;
    /// The robot's voice for the touch page's spoken answers (nullptr: none).
    std::unique_ptr<SpeechSynthesizer> voice;
  };
  /// `robot` and `clock` must outlive this object; it observes the robot's planner until destroyed.
  /// Throws ConfigError when the tasks file does not load or an answer names a provider the hall
  /// lacks.
  GuideHri(Robot& robot, CHri& hri, const Clock& clock, const std::filesystem::path& tasks_file, Options options);
  ~GuideHri() override;
  GuideHri(const GuideHri&) = delete;
  GuideHri& operator=(const GuideHri&) = delete;

  /// What the monitor's RKMS and touch pages reach (RobotMonitor::set_hri).
  [[nodiscard]] StoreBackedHri& service() noexcept { return *service_; }
  /// The module as of the store's version, its internal state up to date (spoken and button inputs).
  [[nodiscard]] HriModule& module();
  [[nodiscard]] const TaskLibrary& tasks() const noexcept { return tasks_; }
  [[nodiscard]] const AnswerProviders& providers() const noexcept { return providers_; }

  /// Between periods: the internal state to the display, and the explanations the HRI speaks for
  /// the PrExplain runs started since (each handled as its topic asked, so the RKMS answers it).
  [[nodiscard]] std::vector<HriReply> update();
  /// The task the planner started for the inputs since the last call ("" when none).
  [[nodiscard]] std::string take_started_task() { return std::exchange(started_task_, {}); }
  /// How the last task ended ("succeeded", "failed"; "" while it runs or none ended since the
  /// last clear_task_end()).
  [[nodiscard]] const std::string& last_task_end() const noexcept { return last_task_end_; }
  void clear_task_end() noexcept { last_task_end_.clear(); }
  [[nodiscard]] const InternalState& state() const noexcept { return state_; }
  /// The processes run, "12.300-40.100 X0 PrAutoMove(goal=node1) succeeded".
  [[nodiscard]] const std::vector<std::string>& processes() const noexcept { return processes_; }

 private:
  class Hall;
  void on_task_started(const TaskReport& task, const Plan& plan, Time now) override;
  void on_process_started(const ProcessRecord& p) override;
  void on_process_succeeded(const ProcessRecord& p) override;
  void on_process_failed(const ProcessRecord& p) override;
  void on_task_succeeded(const TaskReport& task) override;
  void on_task_failed(const TaskReport& task) override;
  void finished(const ProcessRecord& p, const std::string& how);
  void ended(const std::string& how);

  Robot& robot_;
  TaskLibrary tasks_;
  std::unique_ptr<Hall> hall_;
  AnswerProviders providers_;
  std::unique_ptr<StoreBackedHri> service_;
  std::string started_task_;
  InternalState state_;
  std::deque<std::string> explain_;  // topics of the PrExplain runs started, to be spoken
  std::vector<std::string> processes_;
  std::string last_task_end_;
};

}  // namespace tripodal::app
