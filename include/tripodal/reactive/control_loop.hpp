// A control loop of the reactive layer: every sampling period it runs resources -> behaviors ->
// behavior coordinator -> controller. The process supervisor activates and deactivates behaviors
// from its own thread; the loop applies those changes at the start of a cycle and reports behavior
// outcomes back as events. On a robot a LoopRunner drives it on its own thread at absolute
// deadlines; in simulation Robot::run_until steps it on the caller's thread at simulated time.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/controllers/controller.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/reactive/periodic_runner.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal {

/// Identifies an activation: slot index and generation (a reused slot gets a new generation).
struct BehaviorHandle {
  std::uint32_t slot = 0;
  std::uint32_t generation = 0;
  friend bool operator==(const BehaviorHandle&, const BehaviorHandle&) = default;
};

/// What the loop reports to the process supervisor. The strings view storage that lives as long
/// as the loop (the behavior's manifest, the coordinator's input names, string literals).
struct LoopEvent {
  enum class Kind : std::uint8_t {
    behavior_succeeded,    ///< post done_event_name(behavior): "<BehaviorName>.done"
    behavior_failed,       ///< post failed_event_name(behavior): "<BehaviorName>.failed", with reason
    controller_fault,      ///< the controller reported hardware_fault: "<loop>.controller_fault"
    controller_recovered,  ///< the next cycle without a fault: "<loop>.controller_recovered"
    behavior_signal,       ///< a running behavior raised an event (CBehavior::signal): its name, in `reason`
  };
  Kind kind = Kind::behavior_succeeded;
  Time stamp{};
  BehaviorHandle handle;
  std::string_view behavior;  ///< behavior type name, e.g. "BhGoToPose"
  std::string_view input;     ///< coordinator input it was bound to
  std::string_view reason;    ///< failure reason
  std::string_view loop;      ///< the loop's name
  /// The net event name: "<behavior>.done", "<behavior>.failed", "<loop>.controller_fault",
  /// "<loop>.controller_recovered", a signal's own name ("cliff").
  [[nodiscard]] std::string event_name() const;
};

struct ControlLoopOptions {
  std::string name = "reactive";
  Duration period{std::chrono::milliseconds(10)};  ///< nominal sampling period, > 0
  std::size_t max_behaviors = 16;      ///< simultaneously active behaviors
  std::size_t max_path_points = 4096;  ///< NavigationData::path capacity
  std::size_t event_capacity = 256;    ///< events kept until the supervisor collects them
};

/// The result of one cycle.
struct CycleReport {
  Time now{};
  CoordinatorOutput coordinator;
  ControlStatus controller_status = ControlStatus::ok;
  std::uint32_t active_behaviors = 0;
};

/// One control loop. Threading: step() runs on one thread (the loop's). activate(),
/// deactivate(), set_navigation(), set_lock() and collect_events() may be called from any other
/// thread; they take a mutex that step() only try-locks, so a cycle never waits: a change made
/// while a cycle runs takes effect at the next cycle. Steady-state cycles allocate nothing.
class ControlLoop final {
 public:
  /// The loop owns `coordinator` and `controller` (nullptr: no controller; the fused command is
  /// only reported). `resources` must outlive the loop and not change after construction.
  ControlLoop(ControlLoopOptions options, ResourceTable& resources, CBehaviorCoordinator coordinator,
              std::unique_ptr<CController> controller);
  ~ControlLoop();
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  // --- supervisor side (any thread) -------------------------------------------------------

  /// Activates `behavior` with `params` bound to the coordinator input `input` (empty: the
  /// behavior's name). Parameters are resolved and on_activate() runs on the caller's thread;
  /// the behavior joins the loop at its next cycle. A behavior already bound to that input is
  /// replaced. Throws ConfigError for bad parameters (located at `where`), std::invalid_argument
  /// for an input the coordinator does not have or when every slot is taken; ConfigError when the
  /// behavior writes a command channel the coordinator does not have (or of another type).
  BehaviorHandle activate(std::unique_ptr<CBehavior> behavior, const ParameterValues& params,
                          std::string_view input = {}, const SourceLocation& where = {});
  /// Removes the behavior at its next cycle; false for an unknown or stale handle.
  bool deactivate(BehaviorHandle handle);
  /// Removes whatever behavior is bound to `input`; false when none.
  bool deactivate(std::string_view input);
  /// Navigation data for the next cycles. The path is copied only when navi.path_id differs from
  /// the last one given (false when it exceeds max_path_points: then it is truncated).
  bool set_navigation(const NavigationData& navi);
  /// What the path-following behaviors reported in the last cycle that handed it over; a report
  /// of the end of a path stays until the next report (the behavior that made it has finished).
  [[nodiscard]] NavigationFeedback navigation_feedback() const;
  /// Holds the changes made from now on (activations, deactivations, navigation, locks) until
  /// release_changes(), so that a loop running on another thread applies the changes of one
  /// supervision step together (a behavior never starts with the previous step's path).
  void hold_changes();
  void release_changes();
  /// hold_changes() for a scope.
  class ChangeBatch {
   public:
    explicit ChangeBatch(ControlLoop& loop) : loop_(loop) { loop_.hold_changes(); }
    ~ChangeBatch() { loop_.release_changes(); }
    ChangeBatch(const ChangeBatch&) = delete;
    ChangeBatch& operator=(const ChangeBatch&) = delete;

   private:
    ControlLoop& loop_;
  };
  /// A lock message for the coordinator, stamped `stamp` (see CoordinatorLockConfig).
  void set_lock(std::string_view lock, bool engaged, Time stamp);
  /// Moves the events reported since the last call into `out` (appends).
  void collect_events(std::vector<LoopEvent>& out);
  /// The status of an activation as last seen by the loop; nullopt for an unknown handle.
  [[nodiscard]] std::optional<BehaviorStatus> status(BehaviorHandle handle) const;

  // --- loop side (the loop's thread) ------------------------------------------------------

  /// One cycle at `now`: apply pending changes, poll resources, step behaviors, fuse, control.
  /// noexcept and allocation-free in steady state.
  const CycleReport& step(Time now) noexcept;
  [[nodiscard]] const CycleReport& last_cycle() const noexcept { return report_; }

  /// The odometry resource the loop publishes the controller's odometry to after each cycle
  /// (nullptr: none). Set before the loop runs.
  void set_odometry_output(OdometryResource* odometry) noexcept { odometry_out_ = odometry; }
  /// The channels (the hardware's) the loop writes the coordinator's fused channels into after
  /// each cycle, for the hardware to apply (nullptr: none). They must be the coordinator's
  /// channels in its order (std::invalid_argument otherwise). Set before the loop runs.
  void set_command_output(CommandChannels* channels);

  [[nodiscard]] const ControlLoopOptions& options() const noexcept { return options_; }
  [[nodiscard]] const std::string& name() const noexcept { return options_.name; }
  [[nodiscard]] Duration period() const noexcept { return options_.period; }
  /// Direct access for the loop's thread and for tests between cycles.
  [[nodiscard]] CBehaviorCoordinator& coordinator() noexcept { return coordinator_; }
  [[nodiscard]] CController* controller() noexcept { return controller_.get(); }
  [[nodiscard]] const ResourceTable& resources() const noexcept { return resources_; }
  [[nodiscard]] std::uint64_t cycles() const noexcept { return cycles_.load(std::memory_order_relaxed); }
  /// Changes not applied because the supervisor held the mutex during a cycle's try-lock.
  [[nodiscard]] std::uint64_t deferred_applies() const noexcept { return deferred_.load(std::memory_order_relaxed); }

 private:
  // The coordinator's channels a behavior's declared writes go to, by declaration index.
  struct ChannelBinding {
    std::array<ChannelId, kMaxBehaviorChannels> ids{};
    std::uint8_t count = 0;
  };
  struct Slot {
    std::unique_ptr<CBehavior> behavior;
    InputId input = 0;
    ChannelBinding channels;
    std::uint32_t generation = 0;
    BehaviorStatus last_status = BehaviorStatus::idle;
    bool active = false;
  };
  struct PendingActivation {
    std::unique_ptr<CBehavior> behavior;
    InputId input = 0;
    std::uint32_t slot = 0;
    std::uint32_t generation = 0;
    ChannelBinding channels;
  };
  struct PendingLock {
    LockId lock = 0;
    bool engaged = false;
    Time stamp{};
  };

  void apply_pending() noexcept;
  [[nodiscard]] ChannelBinding bind_channels(const CBehavior& behavior, const SourceLocation& where) const;
  [[nodiscard]] std::string exported_channels() const;
  bool deactivate_locked(BehaviorHandle handle);
  void push_event(const LoopEvent& event) noexcept;
  void retire(Slot& slot) noexcept;

  ControlLoopOptions options_;
  ResourceTable& resources_;
  CBehaviorCoordinator coordinator_;
  std::unique_ptr<CController> controller_;
  OdometryResource* odometry_out_ = nullptr;
  CommandChannels* channels_out_ = nullptr;
  BaseCapabilities base_;

  // Loop-thread state.
  std::vector<Slot> slots_;
  NavigationData navi_;
  std::vector<Pose2D> path_;
  NavigationFeedback feedback_;
  SafetyFeedback safety_;  // the last fusion's safety override, for the behavior that won it
  CycleReport report_;
  bool controller_faulted_ = false;
  std::vector<LoopEvent> local_events_;  // ring buffer of events not yet handed over
  std::size_t local_head_ = 0, local_count_ = 0;
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<std::uint64_t> deferred_{0};
  std::atomic<Time::rep> last_now_{0};

  // Shared state, guarded by mutex_ (the loop only try-locks it).
  mutable std::mutex mutex_;
  std::vector<PendingActivation> pending_activations_;
  struct PendingDeactivation {
    std::uint32_t slot = 0;
    std::uint32_t generation = 0;
  };
  std::vector<PendingDeactivation> pending_deactivations_;
  std::vector<PendingLock> pending_locks_;
  bool navi_dirty_ = false;
  bool path_dirty_ = false;
  int holding_ = 0;  // hold_changes() depth
  NavigationData navi_shared_;
  std::vector<Pose2D> path_shared_;
  NavigationFeedback feedback_shared_;
  std::vector<std::unique_ptr<CBehavior>> retired_;  // destroyed on the supervisor's side
  std::vector<LoopEvent> events_out_;
  // The supervisor's view of each slot.
  std::vector<std::uint32_t> slot_generation_;
  std::vector<InputId> slot_input_;
  std::vector<char> slot_used_;
  std::vector<BehaviorStatus> slot_status_;  // as last reported by the loop, for slot_generation_
};

/// Runs a ControlLoop on its own thread at absolute deadlines of `clock` (a PeriodicRunner whose
/// cycle is the loop's step), with its period error, overruns and deadline faults.
class LoopRunner final {
 public:
  LoopRunner(ControlLoop& loop, const Clock& clock, LoopTimingOptions options = {});
  ~LoopRunner() = default;  ///< stops the thread (the runner's destructor)
  LoopRunner(const LoopRunner&) = delete;
  LoopRunner& operator=(const LoopRunner&) = delete;

  /// Starts the thread; the first deadline is one period after now. Throws std::logic_error when
  /// already running.
  void start() { runner_.start(); }
  /// Stops after the current cycle and joins.
  void stop() noexcept { runner_.stop(); }
  [[nodiscard]] bool running() const noexcept { return runner_.running(); }
  /// Whether SCHED_FIFO was granted (false when not asked or not permitted).
  [[nodiscard]] bool realtime_granted() const noexcept { return runner_.realtime_granted(); }
  /// Statistics; read them after stop() (the loop thread writes them while running).
  [[nodiscard]] const LoopStatistics& statistics() const noexcept { return runner_.statistics(); }
  [[nodiscard]] PeriodicRunner& runner() noexcept { return runner_; }

 private:
  PeriodicRunner runner_;
};

}  // namespace tripodal
